//! Our method (the default): one filter of x1..x4 and the heel in turns, fed by the four
//! correlation channels of [`crate::correlation`], each averaged over a moving window of exactly
//! one rotation period ([`crate::moving_average::CorrelationWindow`]).
//!
//! What holds, and why (the derivation, with the paper's equations, is in docs/method.md, "The
//! windowed method in full"; what the 1-sigma covers is measured in docs/uncertainty.md):
//!
//! - **Measurement** `z = H x + v`, `H` eq (2)'s rows pushed through the same correlation and
//!   averaging over the angles observed in the window: eq (11) applied to the product, the
//!   increment of the correlation integral over one whole period. A constant attitude error
//!   cancels, there is no `a0 / (w_r t)` transient, and the leakage of x1, x2 into the roll
//!   channels is modelled exactly instead of eq (12)'s `1/t` term.
//! - **One update a step** (`windowed/update.rs`): the pitch pair (x1, x2) and the roll pair (x3,
//!   x4) take every other window in turn, each with half the per-product variance `r`. `r` is the
//!   per-product variance, not the window mean's: consecutive windows share all but one entry, so
//!   the sequence carries no more information than the raw products.
//! - **Consistency** ([`pair`]): each channel's post-fit residual is averaged over
//!   [`RESIDUAL_PERIODS`] periods; what is beyond its noise widens the 1-sigma and reports
//!   `model_mismatch`. From those residual means each pair learns its noise scale (which rescales
//!   its share of the covariance) and its drift share (how much of the configured random walk its
//!   errors take), see [`LONG_HORIZONS`], [`BIAS_SHARE_NOISE`], [`BIAS_SHARE_DRIFT`].
//! - **Changes of the errors** ([`change`], `windowed/relearn.rs`): residual blocks are tested
//!   for a step; the filter holds while one builds up and learns the changed errors again once it
//!   is declared, from the clean copy ([`CleanState`]) kept before the change began to pull.
//! - **The first windows** ([`start`]) enter with the weights of smooth bumps; **turns** are
//!   learned ([`heel`]) or held ([`turn_hold`]); a channel whose innovation is beyond
//!   [`GATE_SIGMAS`] of its learned spread is left out.
//! - **Report** (`windowed/report.rs`): the estimate and each error's 1-sigma, refreshed once per
//!   update of a pair; [`Windowed::estimate`] returns it without computing.
//!
//! The state's layout is the checkpoint's (`windowed/checkpoint.rs`): a field added here is a field
//! of the image.

pub mod change;
pub(crate) mod checkpoint;
pub mod heel;
pub mod long_run;
pub mod pair;
mod relearn;
mod report;
pub mod start;
pub mod turn_hold;
mod update;

use crate::config::Config;
use crate::correlation::{ReferenceFilter, STATES, TURN_RATE_UNIT_RAD_S};
use crate::gap_fill::GridSample;
use crate::kalman::ConstantStateKalman;
use crate::math::{wrap_pi, Compare};
use crate::moving_average::{CorrelationWindow, WindowLayout};
use crate::Real;
use change::ChangeDetector;
use heel::{HEEL_HELD_SIGMA_RAD, HEEL_PRIOR_SIGMA_RAD, TURN_EXCITATION};
use pair::{Pair, ResidualStats};
use start::StartTaper;
use turn_hold::TurnHold;

/// The prior 1-sigma of each state: the configuration's for x1..x4; for the heel in turns,
/// [`HEEL_PRIOR_SIGMA_RAD`] once the ship has turned (`turning`), else [`HEEL_HELD_SIGMA_RAD`]:
/// until then the heel state is held at 0 (a rate of turn that is only the rest of eq (2)'s heading
/// oscillation is locked to the rotation, and would trade the heel for x3, x4).
fn prior_sigma_rad(config: &Config, turning: bool) -> [Real; STATES] {
    let p = config.prior_sigma_rad;
    let heel = if turning {
        HEEL_PRIOR_SIGMA_RAD
    } else {
        HEEL_HELD_SIGMA_RAD
    };
    [p, p, p, p, heel]
}

/// Time constant of the residual average, in rotation periods.
pub const RESIDUAL_PERIODS: usize = 4;

/// Time constant of the long averages of the residual mean (its mean and its power), in multiples
/// of the residual average's horizon (see docs/method.md, "Learning the noise and the drift").
pub const LONG_HORIZONS: u32 = 32;

/// Bias share at and below which the residual mean is taken as noise (no drift: the random walk
/// is switched off), and at and above which as a persistent bias (the full random walk of
/// `Config::drift_rad_per_sqrt_s`). Between them the random walk's variance rises linearly.
pub const BIAS_SHARE_NOISE: Real = 0.35;
/// Bias share at and above which the residual mean is taken as a persistent bias (see
/// [`BIAS_SHARE_NOISE`]).
pub const BIAS_SHARE_DRIFT: Real = 0.7;

/// Innovation gate, in standard deviations of a window's residual (see "Innovation gate" in
/// docs/method.md).
pub const GATE_SIGMAS: Real = 8.0;

/// Time constant of the learned spread of the residuals, in horizons of the residual average.
pub const SPREAD_HORIZONS: u32 = 2;

/// A residual enters the learned spread clipped at this many of its standard deviations.
pub const SPREAD_CLIP_SIGMAS: Real = 3.0;

/// Smallest noise scale applied to the reported 1-sigma (the data may be quieter than
/// `Config::measurement_sigma_rad` says, but not without bound).
pub const MIN_NOISE_SCALE: Real = 1.0 / 16.0;

/// State of the windowed method.
#[derive(Clone, Debug, PartialEq)]
pub struct Windowed<const CAP: usize> {
    /// The moving window of the correlation sums.
    window: CorrelationWindow<CAP>,
    /// The low-pass of the correlation references.
    reference: ReferenceFilter,
    /// The filter of x1..x4 and the heel in turns.
    kf: ConstantStateKalman<Real, STATES>,
    /// Measurement steps applied so far.
    updates: u32,
    /// Window entries added since the last update.
    entries_since_update: u32,
    /// The channel pair the next update takes: 0 pitch (x1, x2), 1 roll (x3, x4).
    next_pair: u8,
    /// What each channel pair learned beside the filter ([`pair`]): pitch, roll.
    pairs: [Pair; 2],
    /// The roll pair's share of the filter's covariance (symmetric; its upper triangle
    /// `[j][k]`, `j <= k`, is kept, the lower one is not used): carried through every update
    /// with that update's gain, the roll measurements' noise joining it
    /// ([`crate::kalman::carry_share`]); its noise scale rescales it (`windowed/report.rs`).
    roll_share: [[Real; STATES]; STATES],
    /// How the estimate moves with the heel in turns while the heel state is held at none
    /// (`S = d x / d k`, rad per rad of heel at the unit rate of turn), carried through the
    /// updates while the report considers the heel ([`Windowed::heel_to_consider`], taken into
    /// `considering_heel` at each update), and widening its 1-sigma meanwhile.
    /// Not kept by a checkpoint: after a restore it starts again from 0 with the turn
    /// channel's evidence, and what the heel moved the estimate by before the restore is not
    /// considered (a restore within the first period of turning is the case it leaves out).
    heel_sensitivity: [Real; STATES],
    /// Whether this update considers the heel ([`Windowed::heel_to_consider`]).
    considering_heel: bool,
    /// The detector of changes of the errors ([`change`]).
    change: ChangeDetector,
    /// The estimate when the change was declared, rad: the residuals of that block are formed
    /// against it; while the first windows' bumps go on ([`start`]), the estimate held at the end
    /// of the last bump.
    held_x_rad: [Real; STATES],
    /// Window entries still to come in the period after a change was declared, while which the
    /// status says so (not kept by a checkpoint).
    changed_entries: u32,
    /// Channel measurements held out by the innovation gate.
    gated: u32,
    /// Window entries since the filter last held its updates (saturating).
    entries_since_hold: u32,
    /// Whether the clean state is to be kept at the next update.
    clean_state_due: bool,
    /// The filter and its residual statistics at the end of the last block of the roll pair that
    /// did not hold it (see [`change`]): what they knew before a change or a passing disturbance
    /// began to pull at them.
    clean: CleanState,
    /// The first windows' weights ([`start`]; a checkpoint keeps whether their bumps go on and
    /// whether one has ended, not where they stand).
    start: StartTaper,
    /// The grid index and heading of the last sample pushed, for the rate of turn (not kept by a
    /// checkpoint: the window restarts).
    last_heading: Option<(u32, Real, Option<Real>)>,
    /// The ship has turned since the start (its low-passed rate of turn beyond
    /// [`TURN_EXCITATION`]): the heel in turns is learned once the first windows' bumps are over.
    turning: bool,
    /// The turn channel's measurement of the heel while it is not yet learned: its running mean
    /// over a period of the roll pair's updates, rad, and the updates in it.
    heel_evidence: (Real, u32),
    /// Whether the roll pair waits for a turn to leave the window ([`turn_hold`]; not kept by a
    /// checkpoint).
    turn_hold: TurnHold,
    /// The estimate reported ([`Windowed::estimate_now`] after each update).
    report: Option<MethodEstimate>,
    /// A bump has just ended: the other pair's report is to be refreshed at the next update (not
    /// kept by a checkpoint: after a restore it waits for the next bump's end).
    held_report_due: bool,
}

/// A copy of what a change or a passing disturbance pulls at before the change detector sees it:
/// the filter and each pair's residual statistics learned alongside it.
#[derive(Clone, Debug, PartialEq)]
pub struct CleanState {
    kf: ConstantStateKalman<Real, STATES>,
    stats: [ResidualStats; 2],
    roll_share: [[Real; STATES]; STATES],
    heel_sensitivity: [Real; STATES],
}

impl CleanState {
    /// A filter of zeros (see [`Windowed::unconfigured`]).
    const UNCONFIGURED: CleanState = CleanState {
        kf: ConstantStateKalman::from_parts([0.0; STATES], [[0.0; STATES]; STATES]),
        stats: [ResidualStats::UNCONFIGURED; 2],
        roll_share: [[0.0; STATES]; STATES],
        heel_sensitivity: [0.0; STATES],
    };
}

/// The estimate of one step: x1..x4, their 1-sigma, whether the model is inconsistent and
/// whether errors are being learned again after a change.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MethodEstimate {
    /// x1..x4, rad.
    pub x_rad: [Real; 4],
    /// Their 1-sigma, rad.
    pub sigma_rad: [Real; 4],
    /// Whether a channel's residual mean is beyond the residual check's bound (the status
    /// `model_mismatch`).
    pub mismatch: bool,
    /// Within one period of a declared change of the errors, or still learning them again
    /// ([`change`]).
    pub relearning: bool,
}

impl<const CAP: usize> Windowed<CAP> {
    /// The moving-average window of the correlation products.
    pub fn window(&self) -> &CorrelationWindow<CAP> {
        &self.window
    }

    /// The Kalman filter of x1..x4.
    pub fn filter(&self) -> &ConstantStateKalman<Real, STATES> {
        &self.kf
    }

    /// Measurement updates applied so far.
    pub fn updates(&self) -> u32 {
        self.updates
    }

    /// An empty window and a filter of zeros: what an estimator holds before
    /// [`crate::Estimator::init_in`] resets it to a configuration.
    // Inlined, so that `Estimator::init_in` writes it into its place: called, it would be built
    // on the stack and copied, and the state is tens of KB (the C library's
    // `rins_estimator_init` runs on the caller's stack).
    #[inline(always)]
    pub(crate) fn unconfigured() -> Self {
        Windowed {
            window: CorrelationWindow::new(),
            reference: ReferenceFilter::NEW,
            kf: ConstantStateKalman::from_parts([0.0; STATES], [[0.0; STATES]; STATES]),
            updates: 0,
            entries_since_update: 0,
            next_pair: 0,
            pairs: [Pair::UNCONFIGURED; 2],
            roll_share: [[0.0; STATES]; STATES],
            heel_sensitivity: [0.0; STATES],
            considering_heel: false,
            change: ChangeDetector::NEW,
            held_x_rad: [0.0; STATES],
            changed_entries: 0,
            gated: 0,
            entries_since_hold: u32::MAX,
            clean_state_due: false,
            clean: CleanState::UNCONFIGURED,
            start: StartTaper::Fresh,
            last_heading: None,
            turning: false,
            heel_evidence: (0.0, 0),
            turn_hold: TurnHold::NEW,
            report: None,
            held_report_due: false,
        }
    }

    /// Fresh state: empty window, prior covariance.
    pub fn new(config: &Config) -> Self {
        let mut w = Self::unconfigured();
        w.reset(config);
        w
    }

    /// Back to the state of [`Windowed::new`], in place (the window's ring is not copied). The
    /// one place that says what a fresh state is.
    pub fn reset(&mut self, config: &Config) {
        self.window.reset();
        self.reference = ReferenceFilter::default();
        let sigma = prior_sigma_rad(config, false);
        let mean = config.prior.map_or([0.0; 4], |p| p.x_rad);
        self.kf = match config.prior {
            Some(p) => ConstantStateKalman::with_mean(
                [mean[0], mean[1], mean[2], mean[3], 0.0],
                [
                    p.sigma_rad[0],
                    p.sigma_rad[1],
                    p.sigma_rad[2],
                    p.sigma_rad[3],
                    sigma[4],
                ],
            ),
            None => ConstantStateKalman::new(sigma),
        };
        self.updates = 0;
        self.entries_since_update = 0;
        self.next_pair = 0;
        self.pairs = [Pair::new(config); 2];
        if let Some(p) = config.prior {
            self.pairs[0].reported_sigma_rad = [p.sigma_rad[0], p.sigma_rad[1]];
            self.pairs[1].reported_sigma_rad = [p.sigma_rad[2], p.sigma_rad[3]];
        }
        self.roll_share = [[0.0; STATES]; STATES];
        self.heel_sensitivity = [0.0; STATES];
        self.considering_heel = false;
        self.change = ChangeDetector::NEW;
        self.held_x_rad = [mean[0], mean[1], mean[2], mean[3], 0.0];
        self.changed_entries = 0;
        self.gated = 0;
        self.entries_since_hold = u32::MAX;
        self.clean_state_due = false;
        self.keep_clean_state();
        self.start = StartTaper::Fresh;
        self.last_heading = None;
        self.turning = false;
        self.heel_evidence = (0.0, 0);
        self.turn_hold = TurnHold::NEW;
        self.report = None;
        self.held_report_due = false;
    }
    /// Channel measurements the innovation gate held out so far.
    pub fn gated(&self) -> u32 {
        self.gated
    }

    /// The learned mean square of each channel's residual, rad^2 (0 until learned).
    pub fn residual_spread_rad2(&self) -> [Real; 4] {
        let [p, r] = &self.pairs;
        [
            p.spread_rad2[0],
            p.spread_rad2[1],
            r.spread_rad2[0],
            r.spread_rad2[1],
        ]
    }

    /// Each pair's residual level (the larger of its two channels' residual means, rad) and its
    /// noise scale ([`pair::Pair::noise_scale`]): pitch pair (x1, x2) first, then roll (x3, x4).
    pub fn pair_levels(&self) -> ([Real; 2], [Real; 2]) {
        let level = |p: &Pair| p.stats.mean_rad[0].abs().larger(p.stats.mean_rad[1].abs());
        let [p, r] = &self.pairs;
        ([level(p), level(r)], [p.noise_scale(), r.noise_scale()])
    }

    /// The detector of changes of the errors.
    pub fn change_detector(&self) -> &ChangeDetector {
        &self.change
    }

    /// While the period is being learned, bins the window as a period of `period_samples` would
    /// ([`CorrelationWindow::expect_bin`]), so that the samples gathered meanwhile stay when it
    /// comes.
    pub fn expect_period(&mut self, period_samples: u32) {
        self.window
            .expect_bin(WindowLayout::for_period(period_samples, CAP).samples_per_entry);
    }

    /// Sets the window to one period of the rotation pattern.
    pub fn configure(&mut self, period_samples: u32) {
        self.window.configure(period_samples);
        self.entries_since_update = 0;
        self.change.restart_blocks();
        for p in &mut self.pairs {
            p.block_held = true;
            p.last_block.held = false;
        }
    }

    /// Adds one sample of weight `weight` to the window (its references low-passed on the way,
    /// with stage gain `reference_alpha`: [`ReferenceFilter::alpha`]); returns how many old
    /// entries the window removed.
    pub fn push(
        &mut self,
        sample: &GridSample,
        reference_alpha: Real,
        interval: Real,
        weight: u8,
    ) -> u32 {
        // The rate of turn at the sample: the heading's difference since the last sample pushed
        // is the rate half an interval before (over the rows lost in between, the mean rate);
        // extrapolated to the sample from the difference before, when both are one interval.
        let (turn_rate_rad_s, difference) = match self.last_heading {
            Some((index, heading, previous)) if sample.index != index => {
                let steps = sample.index.wrapping_sub(index);
                let d = wrap_pi(sample.heading_rad - heading) / (steps as Real * interval);
                match previous {
                    Some(p) if steps == 1 => (1.5 * d - 0.5 * p, Some(d)),
                    _ => (d, (steps == 1).then_some(d)),
                }
            }
            _ => (0.0, None),
        };
        self.last_heading = Some((sample.index, sample.heading_rad, difference));
        let turn_rate = turn_rate_rad_s * (1.0 / TURN_RATE_UNIT_RAD_S);
        let reference = self
            .reference
            .filter(&sample.angles, turn_rate, reference_alpha);
        if reference.turn.abs() > TURN_EXCITATION {
            // The ship turns: its heel in turns is to be learned (from the next roll update).
            self.turning = true;
        }
        let pushed = self.window.push(sample, &reference, turn_rate, weight);
        if pushed.completed {
            self.entries_since_update = self.entries_since_update.saturating_add(1);
            self.entries_since_hold = self.entries_since_hold.saturating_add(1);
        }
        pushed.removed
    }

    /// The residual average's horizon, in updates of a pair: [`RESIDUAL_PERIODS`] periods of
    /// windows, each pair taking every other one (the count of a pair's residual average
    /// saturates there).
    #[inline(always)]
    fn residual_horizon(&self) -> u32 {
        (RESIDUAL_PERIODS * self.window.len() / 2) as u32
    }

    /// The rotation pattern was forgotten (a new one is being learned): the window lets go of the
    /// old period and of its entries, and keeps the samples from now on, up to its capacity, until
    /// the new period is known ([`CorrelationWindow::configure`]). Until then it is never full, so
    /// the filter takes no measurement of a window whose length is not one period.
    pub fn forget_period(&mut self) {
        if self.window.is_configured() {
            self.window.reset();
            self.entries_since_update = 0;
            self.start.restart();
            self.turn_hold.end();
        }
    }

    /// Restarts the moving average.
    pub fn restart_window(&mut self) {
        self.window.clear();
        self.entries_since_update = 0;
        self.start.restart();
        self.turn_hold.end();
    }

    /// Current estimate, 1-sigma (the filter's, widened by the residual check) and whether the
    /// residual check reports a model mismatch, once updated; while the first windows' bumps go
    /// on, the estimate at the end of the last bump ([`start`]).
    // On the step's path: inlined although the firmware inlines little (.cargo/config.toml).
    #[inline]
    pub fn estimate(&self, _config: &Config) -> Option<MethodEstimate> {
        self.report
    }
}
