//! Our method (the default): one 4-state filter fed by all four correlation channels, each averaged
//! over a moving window of exactly one rotation period.
//!
//! # Measurement
//! Every sample, for the window of the last `W` samples (W = one period of the rotation pattern),
//! the centred correlation of each channel of [`crate::correlation`] is
//!
//! ```text
//! z = H x + v,    H = the same correlation and averaging applied to eq (2)'s rows
//! ```
//!
//! with `H` from the angles observed in that window ([`crate::correlation::CorrelationSums::measurement`]),
//! so any rotation pattern works and a constant attitude offset cancels.
//!
//! This is eq (11) applied to the product itself rather than to the running correlation of eq (8):
//! `mean over [t-W, t]` = `(I(t) - I(t-W)) / W`, the increment of the correlation integral over one
//! whole rotation period. A constant attitude error times `sin rho` sums to exactly zero over a whole
//! period, so there is no `a0 / (w_r t)` start-up transient, and the x1, x2 leakage into the roll
//! channels is a slow term with known coefficients instead of the `1/t` term of eq (12). Those
//! coefficients are averaged over the same window as the products, so the row belongs to the same
//! moment as the measurement: the middle of the window, `t - (W-1)/2` samples.
//!
//! # Pitch and roll in turn
//! The two pitch channels (x1, x2) and the two roll channels (x3, x4 and the leakage of x1, x2)
//! update the filter in turn, each pair every other window, each update with half the per-product
//! variance. By the argument above the information is the same (a pair's window moved by two
//! samples since its last update), and a step costs two scalar Kalman updates instead of four:
//! what keeps the Cortex-M4F's step within its budget.
//!
//! # Filled samples and bins
//! A window with filled samples ([`crate::gap_fill`]) carries their interpolation error: the
//! per-product variance `r` is raised by the window's mean fill variance times 1/2 (the mean square
//! of a reference), with the fill variance measured from the data. With bins of `b` samples
//! ([`crate::moving_average::CorrelationWindow`]), an entry is the mean of `b` samples: `r / b`, and
//! a filled sample's error counts `1 / b^2`. At most one update is made per step: after a filled
//! gap several entries can come at once, and the filter takes the newest window only (its
//! information is then slightly understated, never overstated).
//!
//! # Noise of an overlapping-window measurement
//! Consecutive windows share W-1 of their W samples, so consecutive measurements are almost the same
//! measurement. For a white per-sample product noise of variance `q`, the window mean has variance
//! `q/W`, but its autocorrelation is a triangle W samples long, and the information the whole
//! sequence carries about a constant equals that of the raw products: `N` steps give variance `q/N`,
//! not `q/(W N)`. Feeding every window to the filter with `r = q` (the per-product variance) makes
//! the filter's covariance match that. Using `r = q/W` would make the 1-sigma ~22 times too small.
//!
//! The sway does not average like white noise: its product with `sin rho` has no power near zero
//! frequency, and the sum of the sliding windows weights the raw products by a trapezoid whose
//! ramps are W samples long, so the sway residual falls like `A / (w_y^2 W N)` (about 20/N arcsec
//! for 3 deg at 6 s): negligible after the first few hundred windows.
//!
//! # Consistency: saying so when the model does not hold
//! The covariance only knows the noise it was told about. Effects eq (2) does not contain (errors
//! that drift, coloured attitude noise) bias the measurements without touching `P`, and the 1-sigma
//! would then understate the error many times over. So each channel's post-fit residual
//! `z - H x` is averaged exponentially over `RESIDUAL_PERIODS` rotation periods. Under the model
//! the average is zero-mean noise of 1-sigma `s_e = sigma_m / sqrt(n)` (n the samples averaged, at
//! least one window, at most the averaging time). The part of |mean| above `2 s_e`, divided by the
//! channel's gain (1/2 for x1, x2; cos L / 2 for x3, x4), is added in quadrature to the reported
//! 1-sigma, and a mean beyond `4 s_e`, once a full horizon of residuals has been averaged, is
//! reported as [`crate::Status::ModelMismatch`]. With a
//! consistent model this changes nothing (tested on the paper scenario); with errors drifting at
//! 20 arcsec/day it raises the 1-sigma to the size of the lag (tested in `host-sim`).
//!
//! # Learning the noise and the drift
//! Two numbers of the model are not known in advance: how noisy the products really are
//! (`Config::measurement_sigma_rad` is a default: 10 arcsec of white attitude noise, where a
//! quiet RINS has 5 and coloured noise acts like hundreds), and whether the errors drift
//! (`Config::drift_rad_per_sqrt_s` is a default random walk that caps the filter's memory at
//! about `sqrt(r / q)`, some 5000 s, even when the errors are constant). Both are learned from the
//! residual means the check above already forms, by covariance matching on that sequence: once a
//! full horizon of residuals has been averaged, each update of a pair feeds two long averages
//! per channel, of time constant [`LONG_HORIZONS`] horizons (a plain running mean until then):
//!
//! ```text
//! m_long  = E[m]                  the persistent part of the residual mean m
//! power   = E[m^2 / s_e^2]        s_e^2 = r / n, the model's variance of m (as in the check)
//! ```
//!
//! - **Noise scale** `lambda` = the sum of the pair's two powers (the mean power times 2: an
//!   exponential mean of time constant `n` samples has half the variance `r / n` of an `n`-sample
//!   boxcar, so a power of 1/2 per channel is what the model predicts). The reported variance is
//!   `lambda P_ii + model_i^2`: `P` is the covariance for the configured noise, `lambda` rescales
//!   it to the noise measured (with the sea scenario's 5 arcsec, `lambda` ~ 1/4; with 20 arcsec of
//!   coloured noise, tens). At least [`MIN_NOISE_SCALE`]. The filter itself keeps the configured
//!   `r`: a drift's lag also raises the power, and a larger `r` would lengthen the memory and
//!   the lag with it, a runaway.
//! - **Drift share**: the share of the power that is persistent, `sum m_long^2 / s_e^2` over the
//!   power. Noise, white or coloured, averages out of `m_long` (its share is about 1 /
//!   [`LONG_HORIZONS`] times the horizons `m` stays correlated); a drift's lag does not (share
//!   near 1). The random walk applied to the pair's errors is the configured `q` times
//!   `clamp((share - BIAS_SHARE_NOISE) / (BIAS_SHARE_DRIFT - BIAS_SHARE_NOISE), 0, 1)`: zero for
//!   noise (constant errors: the memory grows without bound and the error keeps falling like
//!   `1 / sqrt(t)`, also under coloured noise, where a short memory loses to the traditional
//!   baseline), the full configured walk for a drift (measured: 20 arcsec/day followed within
//!   2 arcsec, docs/uncertainty.md).
//!
//! - **Lag**: where a drift is seen (share above zero), the persistent residual mean over the
//!   channel's gain, `|m_long| / g`, is the error the filter's lag leaves; the reported 1-sigma
//!   takes the larger of it and the check's widening in quadrature with `lambda P_ii` (measured:
//!   71 % of the errors within 2 sigma at 5000 s under a 20 arcsec/day drift without it, 85 % with
//!   it; clean coverage unchanged at 95-97.5 %).
//!
//! Why this and not a bank of filters with several random-walk levels: a bank multiplies the
//! Kalman updates, the bulk of the step, by its size, and the step on the Cortex-M4F has little
//! room under its budget. This costs per update a dozen multiply-adds on residual
//! means already formed and four divisions (the running-mean weight, the configured `r` per bin,
//! `n / r` and the share), plus a division per error in every estimate (the lag); what each added to the step's maximum
//! on the Cortex-M4F is in docs/uncertainty.md (`host-sim/tests/qemu/qemu_budgets.rs`). The reported 1-sigma (the lag included) is now computed
//! once per update of a pair, for that pair's two errors, not every step for all four (the other
//! pair's is at most one update old; four values more in the checkpoint): what made room for the
//! change detector below. Before the first full horizon both stay at their defaults (scale 1,
//! full walk), so the start is as before.
//!
//! # Changes of the errors
//! A re-installation or a shock moves the errors by a step. The filter, whose memory has grown
//! with the log, would follow it only as fast as the random walk lets it (hours to days); the
//! residual check would say `model_mismatch` and widen the 1-sigma by a part of the step. Instead
//! ([`change`] has the derivation and the thresholds):
//!
//! 1. **Detection**: the pair's residuals, averaged again over blocks of half a period (a quarter
//!    or less at periods over 480 s, at most 240 s), are tested
//!    for a shift of at least half the smallest step (`Config::change_detection_step_rad`, 20
//!    arcsec; 0 turns all of this off) by a log-likelihood ratio summed over a run of blocks, with
//!    the run's long-run variance; a change is declared when the sum reaches 20 and the run has
//!    lasted longer than a passing disturbance can make it (2.5 periods at 480 s).
//! 2. **While a change builds up**: the 1-sigma of the error whose channel shows it is widened by
//!    the block's shift over the gain; once a block is in a run and significant (beyond 3 of its
//!    standard deviations), the filter holds its updates and goes back to the state it had at the
//!    end of the last block that did not hold ([`CleanState`]: the filter and the residual
//!    statistics), so that neither a change nor a passing disturbance (a turn's heel) pulls at it.
//!    A hold never outlasts the persistence: a longer run is a change, or an inconsistency the
//!    filter must work through. What the filter holds out stays out of the residual averages.
//!    Before the blocks are tested (their first 8 periods), a block 10 sigma out holds the filter
//!    alike ([`change`], "Before the first test": a turn's heel).
//! 3. **Learning again**: when a change is declared, the filter goes back to the clean state, the
//!    errors that changed get the prior's covariance ([`ConstantStateKalman::forget`]) and their
//!    pairs' residual check starts afresh; x3 and x4 are learned again with any change of x1
//!    or x2 (through the leakage, a change of x1 or x2 can cancel one of x3 or x4 on their
//!    channels). Each pair then applies one block of residuals against the held estimate as a
//!    single measurement per channel of the learned block variance: the last block, when the
//!    filter held through it (a change is declared after a run longer than a passing disturbance,
//!    so that block saw only windows after the change began), or else the next one. A window at
//!    a cold start carries tens of arcsec of sway; a block, a fraction of an arcsec. The status is
//!    [`crate::Status::ErrorsChanged`] for one period from the declaration.
//!
//!    - **The block's weight.** `P` is the covariance for the configured noise; the errors' is
//!      `lambda P` (the noise scale above). A block mean is measured with its actual variance
//!      `s^2`, so in the filter's units it enters with `s^2 / lambda`: the gain is then
//!      `lambda P h / (lambda h' P h + s^2)`, what the errors' covariance and the block's call for.
//!      With `s^2` alone, a pair that did not change (`lambda` about 1/4 on the sea scenario)
//!      took its block four times too strongly: measured, one log's x2 (unchanged, 1-sigma
//!      0.05 arcsec) moved 0.027 arcsec with the block of a 150 arcsec step of x3, from 0.12 to
//!      0.15 off, and stayed beyond 3 sigma for the rest of the log. A pair that changed has
//!      `lambda` = 1 (below).
//!    - **The noise learned again.** The noise of the data did not change with the errors. The
//!      check's residual average starts afresh (its mean was the step's); the noise scale is 1 and
//!      the random walk the configured one until a full horizon of residuals is averaged again,
//!      as at a cold start, since the residuals of a transition are more than noise. Then the long
//!      averages (the noise scale, the drift share) go on from what they learned before the
//!      change, with the weight of one horizon: what they learned before is the prior of what
//!      they learn after. Started afresh, they learned the noise from the first few residual
//!      means, strongly correlated: measured, after a 150 arcsec step of x1 at a 720 s period one
//!      log's 1-sigma of x1 fell to 0.06 arcsec (0.14 before the step) while x1 was 0.18 to
//!      0.24 off; and on a four-position 360 s rotation x3 was 0.92 off with a 1-sigma of 0.21.
//!
//! # The first windows
//! Until the filter has taken a quarter of a period of windows, the windows enter it with the
//! weights of smooth bumps and the estimate is reported at each bump's end ([`start`] has the
//! derivation): the first estimate, due within 1.25 periods, is then not the sway that a few tens
//! of equally weighted windows let through.
//!
//! # Innovation gate
//! With change detection on, a channel's measurement is left out when its innovation is beyond
//! [`GATE_SIGMAS`] = 8 standard deviations of `h' P h + s`, `s` the learned mean square of that
//! channel's residuals (a running mean over [`SPREAD_HORIZONS`] horizons, learned from the first
//! update, each residual clipped at [`SPREAD_CLIP_SIGMAS`]; one held out enters with the weight of
//! a full average, so a disturbance cannot widen the gate that holds it out). It protects the
//! first hours, before the detector is armed, from a disturbance tens of times the usual residual
//! (a turn of several degrees of heel). At 5 sigma it also held out the tails of the sway's
//! residuals that a cold start needs (p95 at 5,000 s 0.52 instead of 0.40 arcsec on the sea
//! scenario); at 8 it holds out none of them.

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
use crate::moving_average::CorrelationWindow;
use crate::Real;
use change::ChangeDetector;
use heel::{HEEL_HELD_SIGMA_RAD, HEEL_PRIOR_SIGMA_RAD, TURN_EXCITATION};
use pair::{Pair, ResidualStats};
use start::StartTaper;
use turn_hold::TurnHold;

/// The prior 1-sigma of each state: the configuration's for x1..x4; for the heel in turns,
/// [`HEEL_PRIOR_SIGMA_RAD`] once the ship has turned (`turning`), else [`HEEL_HELD_SIGMA_RAD`]:
/// until then the heel state is held at 0 (a rate of turn that is only the rest of eq (2)'s heading oscillation is
/// locked to the rotation, and would trade the heel for x3, x4).
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
/// of the residual average's horizon (see "Learning the noise and the drift" in the module doc).
pub const LONG_HORIZONS: u32 = 32;

/// Bias share at and below which the residual mean is taken as noise (no drift: the random walk
/// is switched off), and at and above which as a persistent bias (the full random walk of
/// `Config::drift_rad_per_sqrt_s`). Between them the random walk's variance rises linearly.
pub const BIAS_SHARE_NOISE: Real = 0.35;
/// Bias share at and above which the residual mean is taken as a persistent bias (see
/// [`BIAS_SHARE_NOISE`]).
pub const BIAS_SHARE_DRIFT: Real = 0.7;

/// Innovation gate, in standard deviations of a window's residual (see "Innovation gate" in the
/// module doc).
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
    /// The information the roll pair's measurements gave the filter, `sum h h' / r` (symmetric;
    /// its upper triangle `[j][k]`, `j <= k`, is kept, the lower one is not used): the roll
    /// pair's share of the filter's covariance is about `P I P`, which its noise scale rescales
    /// (see "The 1-sigma" in the module doc).
    roll_information: [[Real; STATES]; STATES],
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
    roll_information: [[Real; STATES]; STATES],
}

impl CleanState {
    /// A filter of zeros (see [`Windowed::unconfigured`]).
    const UNCONFIGURED: CleanState = CleanState {
        kf: ConstantStateKalman::from_parts([0.0; STATES], [[0.0; STATES]; STATES]),
        stats: [ResidualStats::UNCONFIGURED; 2],
        roll_information: [[0.0; STATES]; STATES],
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
            roll_information: [[0.0; STATES]; STATES],
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
        self.roll_information = [[0.0; STATES]; STATES];
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
