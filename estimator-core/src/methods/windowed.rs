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
pub mod long_run;
pub mod pair;
pub mod start;
pub mod turn_hold;

use crate::config::Config;
use crate::correlation::{
    Measurement, ReferenceFilter, FULL_WEIGHT, HEEL_STATE, ROLL_PAIR, STATES, TURN_RATE_UNIT_RAD_S,
};
use crate::gap_fill::{FillVariance, GridSample};
use crate::kalman::{ConstantStateKalman, KalmanError};
use crate::math::{wrap_pi, Compare};
use crate::moving_average::CorrelationWindow;
use crate::Real;
use change::{persistence_blocks, Alarm, BlockContext, ChangeDetector};
use pair::{channels, Pair, ResidualStats};

/// The prior 1-sigma of the heel state ([`crate::correlation::HEEL_STATE`]), rad: a heel of 10 deg
/// per deg/s of turn rate.
pub const HEEL_PRIOR_SIGMA_RAD: Real = 0.01;

/// The low-passed rate of turn beyond which the ship turns enough for its heel in turns to be
/// learned, in units of [`TURN_RATE_UNIT_RAD_S`] (0.029 deg/s): far above what eq (2)'s heading
/// oscillation left in the heading gives (about 0.001 deg/s), far below a course change or an
/// autopilot's yawing.
pub const TURN_EXCITATION: Real = 0.5;

/// The 1-sigma x3 and x4 go back to when the heel in turns starts to be learned, rad (200
/// arcsec: a course weave's heel leaks into them by hundreds of arcsec).
pub const HEEL_FORGET_SIGMA_RAD: Real = 1.0e-3;

/// A heel at the unit rate of turn beyond which the first turn channel's measurement makes x3,
/// x4 be learned again, rad (1.5 s of heel per rad/s of turn; one window's measurement of no heel
/// at sea scatters by a few 1e-4).
pub const HEEL_SIGNIFICANT_RAD: Real = 1.0e-3;

/// The heel state's variance below which the correlation channels update it too, rad^2: a heel
/// known to 2e-5 rad (4 arcsec) at the unit rate of turn.
pub const HEEL_LEARNED_VARIANCE_RAD2: Real = 4.0e-10;

/// The prior 1-sigma of each state: the configuration's for x1..x4; for the heel in turns,
/// [`HEEL_PRIOR_SIGMA_RAD`] once the ship has turned (`turning`), else 0: until then the heel
/// state is held at 0 (a rate of turn that is only the rest of eq (2)'s heading oscillation is
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

/// The heel state's 1-sigma while it is held at 0, rad: next to nothing (0.002 arcsec of roll at a
/// brisk turn), but not zero, so that the covariance stays positive definite.
pub const HEEL_HELD_SIGMA_RAD: Real = 1.0e-9;

/// Whether the heel state is being learned (its variance above the held one's).
fn heel_learned(p: Real) -> bool {
    p > 4.0 * HEEL_HELD_SIGMA_RAD * HEEL_HELD_SIGMA_RAD
}
use start::StartTaper;
use turn_hold::{TurnHold, TurnVerdict, ROLL_HOLD_SIGMAS};

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
    /// The 4-state filter of x1..x4.
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

/// What became of a window's measurement in an update of its pair.
#[derive(Clone, Copy, Debug)]
struct Outcome {
    /// The filter took some channel of it.
    applied: bool,
    /// It was held out, by the innovation gate or the change detector's hold: its residuals
    /// still go on to the change detector.
    held_out: bool,
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
    // Inlined, so that `Estimator::init_in` writes it into its place: called, it was built on
    // the stack and copied (22 KB of stack in the C library's `rins_estimator_init`).
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

    /// Each error's reported 1-sigma, rad, as its pair last refreshed it.
    fn reported_sigma_rad(&self) -> [Real; 4] {
        let [p, r] = &self.pairs;
        [
            p.reported_sigma_rad[0],
            p.reported_sigma_rad[1],
            r.reported_sigma_rad[0],
            r.reported_sigma_rad[1],
        ]
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

    /// Updates the filter with the window's measurement, if the window is full and has new
    /// entries. `interval` is the sample interval, s, `fill_variance` a filled single sample's
    /// error variance of roll and of pitch ([`crate::gap_fill::GapFiller::single_fill_variance`]).
    /// Returns the change of the errors this update declared, if any (see [`change`]).
    pub fn update(
        &mut self,
        config: &Config,
        interval: Real,
        fill_variance: FillVariance,
    ) -> Option<Alarm> {
        let alarm = self.update_filter(config, interval, fill_variance);
        self.report = self.estimate_now();
        alarm
    }

    /// The estimate to report now: the filter's, or, while the first windows' bumps go on, the
    /// one held at the end of the last bump (none before the first ends).
    pub(crate) fn estimate_now(&self) -> Option<MethodEstimate> {
        if !self.start.holds() {
            return self.live_estimate();
        }
        self.start.has_held().then_some(MethodEstimate {
            x_rad: [
                self.held_x_rad[0],
                self.held_x_rad[1],
                self.held_x_rad[2],
                self.held_x_rad[3],
            ],
            sigma_rad: self.reported_sigma_rad(),
            mismatch: false,
            relearning: false,
        })
    }

    /// [`Windowed::update`] but for the report: the random walk since the last update, the pair
    /// whose turn it is takes the window's measurement ([`Windowed::apply_measurement`]), and its
    /// residuals go on to the checks ([`Windowed::average_residuals`]) and to the change detector.
    // Called once, on the step's path.
    #[inline(always)]
    fn update_filter(
        &mut self,
        config: &Config,
        interval: Real,
        fill_variance: FillVariance,
    ) -> Option<Alarm> {
        if !self.window.is_full() || self.entries_since_update == 0 {
            return None;
        }
        let pair = usize::from(self.next_pair.min(1));
        let m = self.window.sums().measurement_of(pair)?;
        self.next_pair = 1 - pair as u8;
        let bin = self.window.bin() as Real;
        self.predict(config, interval, bin);
        self.weigh_product_noise(config, bin, fill_variance);
        if core::mem::take(&mut self.clean_state_due) && !self.change.holding() {
            self.keep_clean_state();
        }
        if self.pairs[pair].relearning {
            if self.relearn_from_block(pair, &m.rows, &m.z, interval * bin) {
                self.refresh_report(config, 0);
                self.refresh_report(config, 1);
            }
            return None;
        }
        // Each pair takes every other window, so each of its updates carries two entries' worth;
        // the first windows come with the weights of [`start`].
        let weight = self.start.weight(
            self.window.newest_number(),
            self.window.first_number(),
            self.window.len() as u32,
            self.window.bin(),
            self.updates == 0,
        );
        let mut r = 0.5 * self.pairs[pair].product_variance_rad2;
        // The turn channel's, at full weight from the first window on: the heel it learns is what
        // the first windows need to tell x3, x4 from the heel of a course weave.
        let r_full = r;
        if weight.value < 1.0 {
            // A window of weight 0 (at the ends of a bump) adds next to nothing, but is taken as
            // every window is: one update a step.
            r /= weight.value.larger(start::MIN_WEIGHT);
        }
        let detecting = config.change_detection_step_rad > 0.0;
        let horizon = self.residual_horizon();
        let gate = (detecting
            && self.pairs[pair].spread_count >= (horizon / RESIDUAL_PERIODS as u32).max(1))
        .then_some(GATE_SIGMAS);
        let outcome = self.apply_measurement(pair, &m, r, r_full, gate);
        self.report_at_bump_end(config, pair, weight.ends_bump);
        if !(outcome.applied || outcome.held_out) {
            return None;
        }
        if outcome.applied {
            self.updates = self.updates.saturating_add(1);
        }
        let settled = !self.start.holds();
        let residual = self.average_residuals(config, pair, &m, outcome.applied, settled, horizon);
        let (alarm, tested) = if detecting && settled {
            self.pairs[pair].learn_spread(horizon, residual, outcome.held_out);
            self.detect_change(config, pair, residual, &m.rows, interval * bin)
        } else {
            (None, false)
        };
        // A block's test is the costliest part of an update: after it, the pair's report waits
        // for the pair's next update, two windows later (a change declared has refreshed both).
        if !(tested || self.start.holds()) {
            self.refresh_report(config, pair);
        }
        alarm
    }

    /// The prediction over the entries since the last update (`bin` samples of `interval` s
    /// each): each pair's errors take the configured random walk times the pair's drift share
    /// (see "Learning the noise and the drift" in the module doc); the heel state takes none.
    // Called once, on the step's path.
    #[inline(always)]
    fn predict(&mut self, config: &Config, interval: Real, bin: Real) {
        let elapsed_s = interval * bin * self.entries_since_update as Real;
        self.changed_entries = self
            .changed_entries
            .saturating_sub(self.entries_since_update);
        self.entries_since_update = 0;
        let q = config.drift_rad_per_sqrt_s * config.drift_rad_per_sqrt_s * elapsed_s;
        let (qp, qr) = (
            q * self.pairs[0].stats.drift_share,
            q * self.pairs[1].stats.drift_share,
        );
        self.kf.predict(&[qp, qp, qr, qr, 0.0]);
    }

    /// Each pair's per-product variance for the window now, rad^2: the configured noise over the
    /// `bin` samples of an entry, raised by the share of weight the window lacks and by its
    /// filled samples' interpolation error (see "Filled samples and bins" in the module doc).
    // Called once, on the step's path.
    #[inline(always)]
    fn weigh_product_noise(&mut self, config: &Config, bin: Real, fill_variance: FillVariance) {
        let sums = self.window.sums();
        let filled = sums.fill_weight as Real / (sums.count as Real * bin * bin);
        let mut r0 = config.measurement_sigma_rad * config.measurement_sigma_rad / bin;
        // Entries left out or weighted down near lost rows: the window carries their share less
        // information (its weight over that of a full window of full-weight entries).
        let full = (self.window.len() as u32).saturating_mul(u32::from(FULL_WEIGHT));
        if sums.weight < full && sums.weight > 0 {
            r0 *= full as Real / sums.weight as Real;
        }
        self.pairs[0].product_variance_rad2 = r0 + 0.5 * filled * fill_variance.pitch_rad2;
        self.pairs[1].product_variance_rad2 = r0 + 0.5 * filled * fill_variance.roll_rad2;
    }

    /// The filter takes the window's measurement `m` for `pair`, each channel of variance `r`
    /// (the turn channel's `r_full`), gated at `gate` standard deviations when it is set; or holds
    /// it out while a change may be building up ([`change`]) or a turn the heel state does not
    /// explain is in the window ([`turn_hold`]).
    // Called once, on the step's path.
    #[inline(always)]
    fn apply_measurement(
        &mut self,
        pair: usize,
        m: &Measurement,
        r: Real,
        r_full: Real,
        gate: Option<Real>,
    ) -> Outcome {
        let mut outcome = Outcome {
            applied: false,
            held_out: false,
        };
        let turn = if pair == ROLL_PAIR {
            self.test_turn(m, gate.is_some())
        } else {
            TurnVerdict::default()
        };
        if self.change.holding() {
            // A change may be building up: the filter waits.
            outcome.held_out = true;
        } else if turn.held {
            // The window holds a turn the heel state does not explain: the roll pair waits until
            // it has left the window, from the copy of before it began to pull.
            if turn.started {
                self.restore_clean_state();
            }
        } else {
            if pair == ROLL_PAIR
                && self.turning
                && self.updates > 0
                && !self.start.holds()
                && !heel_learned(self.kf.covariance()[(HEEL_STATE, HEEL_STATE)])
                && m.turn_row[HEEL_STATE] > 0.0
            {
                self.weigh_heel_evidence(m);
            }
            if pair == ROLL_PAIR {
                outcome.applied |= self.update_turn_channel(m, r_full);
            }
            let channels = self.update_channels(pair, m, r, gate);
            outcome.applied |= channels.applied;
            outcome.held_out |= channels.held_out;
        }
        outcome
    }

    /// The turn channel's update, with the roll pair once the heel in turns is learned: it
    /// learns the heel (see "Heel in turns" in the module doc of [`crate::correlation`]) and
    /// only it, x1..x4 taken as they are. Its products are roll times the rate of turn, whose
    /// mean square is the row's last term. Returns whether the filter took it.
    // Called once, on the step's path.
    #[inline(always)]
    fn update_turn_channel(&mut self, m: &Measurement, r_full: Real) -> bool {
        let heel_variance = self.kf.covariance()[(HEEL_STATE, HEEL_STATE)];
        if !(m.turn_row[HEEL_STATE] > 0.0 && heel_learned(heel_variance)) {
            return false;
        }
        // The channel's terms in x1..x4 taken at their estimates, their uncertainty added to the
        // measurement's: a measurement of the heel alone, which moves the other states only
        // through their covariance with it.
        let x = self.kf.state();
        let p = self.kf.covariance();
        let mut z = m.turn_z;
        let mut r_turn = 2.0 * r_full * m.turn_row[HEEL_STATE];
        for j in 0..HEEL_STATE {
            z -= m.turn_row[j] * x[j];
            r_turn += m.turn_row[j] * m.turn_row[j] * p[(j, j)];
        }
        let mut h = [0.0; STATES];
        h[HEEL_STATE] = m.turn_row[HEEL_STATE];
        if self.kf.update(&h, z, r_turn).is_ok() {
            self.add_roll_information(&h, r_turn);
            return true;
        }
        false
    }

    /// The two channels of `pair` update the filter in turn, each of variance `r`, gated at
    /// `gate` standard deviations of its learned spread when it is set.
    // Called once, on the step's path.
    #[inline(always)]
    fn update_channels(
        &mut self,
        pair: usize,
        m: &Measurement,
        r: Real,
        gate: Option<Real>,
    ) -> Outcome {
        let mut outcome = Outcome {
            applied: false,
            held_out: false,
        };
        // Until the turn channel has learned the heel, the channels only consider it: its
        // uncertainty widens the others', its estimate stays (over a window or two, a course
        // weave near the rotation's frequency cannot tell it from x3, x4).
        let mut all_but_heel = [true; STATES];
        all_but_heel[HEEL_STATE] = false;
        let learned = self.kf.covariance()[(HEEL_STATE, HEEL_STATE)] < HEEL_LEARNED_VARIANCE_RAD2;
        let updated = (!learned).then_some(&all_but_heel);
        // A heel held at its negligible variance (no turn has shown one) is left out of the
        // update: x1..x4 alone, at two thirds of the cost.
        let heel_active = heel_learned(self.kf.covariance()[(HEEL_STATE, HEEL_STATE)]);
        for k in 0..2 {
            // The channel from its pair and rank, not read back from an array: below 4 as the
            // optimiser sees it (no bound check left in the C library's step).
            let ch = 2 * (pair & 1) + k;
            let gate = gate.map(|g| (self.pairs[pair].spread_rad2[k], g));
            let result = if heel_active {
                self.kf
                    .update_masked(&m.rows[ch], m.z[ch], r, gate, updated)
            } else {
                self.kf
                    .update_leading::<HEEL_STATE>(&m.rows[ch], m.z[ch], r, gate, updated)
            };
            match result {
                Ok(_) => {
                    outcome.applied = true;
                    if pair == ROLL_PAIR {
                        self.add_roll_information(&m.rows[ch], r);
                    }
                }
                Err(KalmanError::Gated) => {
                    outcome.held_out = true;
                    self.gated = self.gated.saturating_add(1);
                }
                Err(_) => {}
            }
        }
        outcome
    }

    /// At the end of one of the first windows' bumps ([`start`]), the estimate to hold until the
    /// next bump ends: the filter's now, with this pair's report, and the other pair's at its
    /// next update (a window of weight 0 too: the next bump's first), one report a step as
    /// always (not refreshed in between).
    // Called once, on the step's path.
    #[inline(always)]
    fn report_at_bump_end(&mut self, config: &Config, pair: usize, ends_bump: bool) {
        if ends_bump {
            let x = self.kf.state();
            self.held_x_rad = (*x).into();
            self.refresh_report(config, pair);
            self.held_report_due = self.start.holds();
        } else if core::mem::take(&mut self.held_report_due) {
            self.refresh_report(config, pair);
        }
    }

    /// The residual bookkeeping after an update of `pair` with window `m` (`applied`: the filter
    /// took some channel of it; `settled`: the first windows' bumps are over): the pair's
    /// residual average and the check, the learned noise and drift, the long-run batches.
    /// Returns the pair's two post-fit residuals, rad.
    ///
    /// What the filter held out (the gate, the detector's hold) stays out of the residual
    /// averages: the check and the learned noise and drift are about the data the filter took;
    /// the detector sees everything. So do the windows of the first bumps ([`start`]): the filter
    /// has taken a few windows, most of them at a fraction of their weight, and a window's
    /// residual is then mostly its sway, which would inflate the learned noise.
    // Called once, on the step's path.
    #[inline(always)]
    fn average_residuals(
        &mut self,
        config: &Config,
        pair: usize,
        m: &Measurement,
        applied: bool,
        settled: bool,
        horizon: u32,
    ) -> [Real; 2] {
        let residual = self.pairs[pair].average_residuals(
            pair,
            horizon,
            &m.rows,
            &m.z,
            self.kf.state().as_slice(),
            applied && settled,
        );
        if self.change.holding() {
            self.entries_since_hold = 0;
        }
        if applied && settled {
            let (bin, len) = (self.window.bin(), self.window.len());
            self.pairs[pair].learn_noise_and_drift(config, bin, len, horizon);
        }
        // The first batch a quarter of a period of the pair's updates, from the first update on
        // ([`long_run`]); the windows that hold what the filter held out are left out of it as
        // they were of the filter.
        if applied && self.entries_since_hold >= self.window.len() as u32 {
            let len = self.window.len() as u32;
            let q = self.pairs[pair].product_variance_rad2;
            self.pairs[pair]
                .long_run
                .add(residual, (len / 16).max(1), len, q);
        }
        residual
    }

    /// Whether the heel in turns is to be learned: the turn channel's measurement of it (x1..x4
    /// taken at their estimates), averaged over a period of the roll pair's updates, is beyond
    /// [`HEEL_SIGNIFICANT_RAD`]. Then it starts to be learned (its prior covariance), and x3 and
    /// x4, which the roll channels gave with the heel taken as none, are learned again with it
    /// ([`HEEL_FORGET_SIGMA_RAD`]): a course weave near the rotation's frequency leaks its heel
    /// into them by hundreds of arcsec. A ship that turns without heeling is never given the
    /// state: its estimate would only scatter the roll channels' residuals.
    #[cold]
    #[inline(never)]
    fn weigh_heel_evidence(&mut self, m: &Measurement) {
        let x = self.kf.state();
        let mut z = m.turn_z;
        for j in 0..HEEL_STATE {
            z -= m.turn_row[j] * x[j];
        }
        let heel = z / m.turn_row[HEEL_STATE];
        let n = (self.window.len() as u32 / 2).max(1);
        self.heel_evidence.1 = self.heel_evidence.1.saturating_add(1).min(n);
        let alpha = 1.0 / self.heel_evidence.1 as Real;
        self.heel_evidence.0 += alpha * (heel - self.heel_evidence.0);
        if self.heel_evidence.1 < n || self.heel_evidence.0.abs() <= HEEL_SIGNIFICANT_RAD {
            return;
        }
        let mut which = [false; STATES];
        let mut sigma = [HEEL_FORGET_SIGMA_RAD; STATES];
        which[HEEL_STATE] = true;
        which[2] = true;
        which[3] = true;
        sigma[HEEL_STATE] = HEEL_PRIOR_SIGMA_RAD;
        self.kf.forget(&which, &sigma);
        self.forget_roll_information(&which);
    }

    /// The turn hold's verdict on the roll pair's update of window `m` ([`turn_hold`]); none
    /// while the heading does not change. `spread_known`: the roll channels' spreads are learned
    /// (as for the innovation gate).
    fn test_turn(&mut self, m: &Measurement, spread_known: bool) -> TurnVerdict {
        if !(m.turn_row[HEEL_STATE] > 0.0) {
            return TurnVerdict::default();
        }
        let x = self.kf.state().as_slice();
        let innovation =
            |row: &[Real; STATES], z: Real| row.iter().zip(x).fold(z, |e, (h, xj)| e - h * xj);
        let mut roll_beyond = false;
        if spread_known {
            let [a, b] = channels(ROLL_PAIR);
            for (k, ch) in [a, b].into_iter().enumerate() {
                let e = innovation(&m.rows[ch], m.z[ch]);
                let bound =
                    ROLL_HOLD_SIGMAS * ROLL_HOLD_SIGMAS * self.pairs[ROLL_PAIR].spread_rad2[k];
                roll_beyond |= e * e > bound;
            }
        }
        let turn = innovation(&m.turn_row, m.turn_z);
        self.turn_hold.test(
            turn,
            roll_beyond,
            self.window.newest_number(),
            self.window.len() as u32,
        )
    }

    /// The residual average's horizon, in updates of a pair: [`RESIDUAL_PERIODS`] periods of
    /// windows, each pair taking every other one (the count of a pair's residual average
    /// saturates there).
    #[inline(always)]
    fn residual_horizon(&self) -> u32 {
        (RESIDUAL_PERIODS * self.window.len() / 2) as u32
    }

    /// The model's variance of a block mean of the change detector for blocks of `block` entries,
    /// rad^2 ([`change::block_variance_factor`]).
    fn block_floor_rad2(&self, pair: usize, block: u32) -> Real {
        let len = self.window.len().max(1) as u32;
        self.pairs[pair.min(1)].product_variance_rad2 * change::block_variance_factor(len, block)
            / len as Real
    }

    /// Passes the pair's residuals to the change detector; when it declares a change, the errors
    /// that changed are learned again (see "Changes of the errors" in the module doc). Returns the
    /// change declared, if any, and whether a block ended (and was tested).
    // Called once, on the step's path.
    #[inline(always)]
    fn detect_change(
        &mut self,
        config: &Config,
        pair: usize,
        residual: [Real; 2],
        rows: &[[Real; STATES]; 4],
        entry_s: Real,
    ) -> (Option<Alarm>, bool) {
        // A pair is 0 or 1; said so, the indexing below needs no bounds check (no panic path).
        let pair = pair.min(1);
        let holding = self.change.holding();
        self.pairs[pair].block_held &= holding;
        // A block's updates of a pair: half its entries.
        let block_entries = change::block_entries(self.window.len() as u32, entry_s);
        let Some(block) = self
            .change
            .accumulate(pair, residual, (block_entries / 2).max(1))
        else {
            return (None, false);
        };
        // Kept for learning the errors again, should a change be declared while the filter holds.
        let p = &mut self.pairs[pair];
        p.last_block.held = p.block_held;
        if p.block_held {
            let [a, b] = channels(pair);
            p.last_block.rad = block;
            p.last_block.rows = [rows[a], rows[b]];
        }
        p.block_held = true;
        let len = self.window.len() as u32;
        let horizon = self.residual_horizon().max(1);
        let ctx = BlockContext {
            persistence_blocks: persistence_blocks(len, block_entries, entry_s),
            floor_rad2: self.block_floor_rad2(pair, block_entries),
            step_rad: config.change_detection_step_rad,
            settled: self.pairs[pair].stats.count >= horizon,
            armed: self.pairs.iter().all(|p| p.stats.count >= horizon),
            max_widening_rad: config.prior_sigma_rad,
            blocks_per_half_period: change::blocks_per_half_period(len, block_entries),
        };
        let was_holding = self.change.holding();
        let alarm = self.change.test(pair, block, self.pairs[pair].gains, &ctx);
        // Kept at the next update: this one has the block's work already.
        self.clean_state_due |= alarm.is_none() && pair == 1 && !self.change.holding();
        if self.change.holding() && !was_holding {
            // The block that started the hold was taken: back to before it. Each pair's report
            // follows at its next update without a block's test (the other pair's block ends at
            // its next update, so some three windows on); refreshing the other pair's here too
            // took a hold's first step to 5,050 instructions on a lossy 360 s log.
            self.restore_clean_state();
        }
        let Some(mut alarm) = alarm else {
            return (None, true);
        };
        // The roll channels carry the leakage of x1 and x2: a change of those can hide a change
        // of x3 or x4 on their channels (their shifts cancel), so x3 and x4 are learned again
        // with any change. The pitch channels see x1 and x2 alone.
        if alarm.changed[0] || alarm.changed[1] {
            alarm.changed[2] = true;
            alarm.changed[3] = true;
        }
        self.relearn(config, &alarm.changed);
        (Some(alarm), true)
    }

    /// Keeps a copy of the filter and its residual statistics ([`CleanState`]).
    /// Field by field, in place: a whole `CleanState` built first took its size again on the
    /// stack (at a restore, on top of the image's parts).
    fn keep_clean_state(&mut self) {
        let c = &mut self.clean;
        c.kf.clone_from(&self.kf);
        c.roll_information = self.roll_information;
        for (kept, p) in c.stats.iter_mut().zip(&self.pairs) {
            *kept = p.stats;
        }
    }

    /// Goes back to the copy of [`Windowed::keep_clean_state`].
    fn restore_clean_state(&mut self) {
        let c = &self.clean;
        self.kf = c.kf.clone();
        self.roll_information = c.roll_information;
        for (p, kept) in self.pairs.iter_mut().zip(&c.stats) {
            p.stats = *kept;
        }
    }

    /// Starts learning the errors `changed` again: their covariance back to the prior, the
    /// residual check of their pairs (polluted by the step) back to its start and the long
    /// averages of the noise and the drift down to the weight of one horizon (see "Changes of the
    /// errors" in the module doc), the detector's blocks started over; both pairs' updates then
    /// wait for one block of residuals against the estimate held now
    /// ([`Windowed::relearn_from_block`]: a pair updated from a single window would take that
    /// window's sway for the change, and through the leakage of x1, x2 into the roll channels the
    /// roll pair's update would move a forgotten x1 or x2). The other errors, and the statistics
    /// of a pair whose channels showed nothing, keep what they learnt.
    fn relearn(&mut self, config: &Config, changed: &[bool; 4]) {
        // Back to before the change began to pull at the filter: through the leakage of x1, x2
        // into the roll channels, the errors that did not change were pulled too.
        self.restore_clean_state();
        self.clean_state_due = false;
        let prior = prior_sigma_rad(config, true);
        let forget: [bool; STATES] =
            core::array::from_fn(|i| changed.get(i).copied().unwrap_or(false));
        self.kf.forget(&forget, &prior);
        self.forget_roll_information(&forget);
        let horizon = self.residual_horizon();
        for (pair, p) in self.pairs.iter_mut().enumerate() {
            let [a, b] = channels(pair);
            if changed[a] || changed[b] {
                p.stats.relearn(horizon);
            }
        }
        self.held_x_rad = (*self.kf.state()).into();
        self.changed_entries = self.window.len() as u32;
        self.change.restart_blocks();
        for p in &mut self.pairs {
            p.relearning = true;
            p.block_held = true;
        }
        self.refresh_report(config, 0);
        self.refresh_report(config, 1);
    }

    /// An update of a pair while the errors are learned again. Its last block of residuals, when
    /// the filter held through all of it, was formed against the estimate the filter went back to
    /// and holds now, and (a change being declared only after a run longer than a passing
    /// disturbance) from windows wholly after the change began: it is applied at once. Otherwise
    /// the residuals against the estimate held now are summed over one more block first. Applied
    /// as one measurement per channel, of the learned variance of a block mean over the pair's
    /// noise scale (in the filter's units, see "Changes of the errors" in the module doc): with
    /// the prior's covariance the filter takes the changed errors from it, as from a window at a
    /// cold start but with the block's far smaller sway; the pair updates from windows again from
    /// then on.
    /// Returns whether the block was applied (the filter changed).
    fn relearn_from_block(
        &mut self,
        pair: usize,
        rows: &[[Real; STATES]; 4],
        z: &[Real; 4],
        entry_s: Real,
    ) -> bool {
        // A pair is 0 or 1; said so, the indexing below needs no bounds check (no panic path).
        let pair = pair.min(1);
        let held = self.held_x_rad;
        let fit = |row: &[Real; STATES]| -> Real { (0..STATES).map(|i| row[i] * held[i]).sum() };
        let block_entries = change::block_entries(self.window.len() as u32, entry_s);
        let chs = channels(pair);
        let (block, rows) = if self.pairs[pair].last_block.held {
            let last = &mut self.pairs[pair].last_block;
            last.held = false;
            (last.rad, last.rows)
        } else {
            let pair_rows = [rows[chs[0]], rows[chs[1]]];
            let residual = [
                z[chs[0]] - fit(&pair_rows[0]),
                z[chs[1]] - fit(&pair_rows[1]),
            ];
            let Some(block) = self
                .change
                .accumulate(pair, residual, (block_entries / 2).max(1))
            else {
                return false;
            };
            (block, pair_rows)
        };
        let floor = self.block_floor_rad2(pair, block_entries);
        let mut applied = false;
        let p = &mut self.pairs[pair];
        for (k, ch) in chs.into_iter().enumerate() {
            let target = block[k] + fit(&rows[k]);
            applied |= self
                .kf
                .update(
                    &rows[k],
                    target,
                    self.change.block_variance(ch, floor) / p.stats.noise_scale,
                )
                .is_ok();
            p.gains[k] = rows[k][ch].abs();
        }
        if applied {
            self.updates = self.updates.saturating_add(1);
        }
        p.relearning = false;
        true
    }

    /// Refreshes what is reported of the errors of `pair` (after its update, or after anything
    /// that changed the filter): [`Pair::refresh_report`] with the filter's variance of the pair's
    /// errors and the change detector's widening. Once per update of the pair, not every step:
    /// the other pair's report is at most one update old.
    fn refresh_report(&mut self, config: &Config, pair: usize) {
        // A pair is 0 or 1; said so, the indexing below needs no bounds check (no panic path).
        let pair = pair.min(1);
        let [a, b] = channels(pair);
        let widening = self.change.widening_rad();
        let scaled = [self.scaled_variance(a), self.scaled_variance(b)];
        self.pairs[pair].refresh_report(
            config,
            self.window.bin(),
            self.window.len(),
            scaled,
            [widening[a], widening[b]],
        );
    }

    /// The variance of error `i`, each pair's share of the filter's covariance rescaled by that
    /// pair's noise scale: `lambda_pitch (P_ii - C_ii) + lambda_roll C_ii`, `C = P I P` the roll
    /// pair's share (`I` its information, [`Windowed::roll_information`]), within `[0, P_ii]`; at
    /// least the error's own pair's scale times `P_ii`.
    fn scaled_variance(&self, i: usize) -> Real {
        let i = i.min(STATES - 1);
        let p = self.kf.covariance();
        let p_ii = p[(i, i)].larger(0.0);
        // p_i' I p_i, p_i = P's column i, from I's upper triangle.
        let info = &self.roll_information;
        let mut roll_share: Real = 0.0;
        for j in 0..STATES {
            let pj = p[(j, i)];
            let mut v: Real = 0.5 * info[j][j] * pj;
            for k in j + 1..STATES {
                v += info[j][k] * p[(k, i)];
            }
            roll_share += 2.0 * pj * v;
        }
        let roll_share = roll_share.larger(0.0).smaller(p_ii);
        let (pitch, roll) = (self.pairs[0].noise_scale(), self.pairs[1].noise_scale());
        // Never below the error's own pair's scale times its variance: a roll pair quieter than
        // the pitch pair does not make x1, x2 surer than their own channels' noise says.
        let own = if i < 2 { pitch } else { roll };
        (pitch * (p_ii - roll_share) + roll * roll_share).larger(own * p_ii)
    }

    /// Adds a roll measurement's information `h h' / r` to [`Windowed::roll_information`].
    fn add_roll_information(&mut self, h: &[Real; STATES], r: Real) {
        if !(r > 0.0) {
            return;
        }
        let inv_r = 1.0 / r;
        // The upper triangle only: what reads it reads that (the lower one stays as it was).
        for j in 0..STATES {
            let hj = h[j] * inv_r;
            for k in j..STATES {
                self.roll_information[j][k] += hj * h[k];
            }
        }
    }

    /// Forgets the roll pair's information on the states `which` (as the filter forgets them).
    fn forget_roll_information(&mut self, which: &[bool; STATES]) {
        for j in 0..STATES {
            if which[j] {
                for k in 0..STATES {
                    self.roll_information[j][k] = 0.0;
                    self.roll_information[k][j] = 0.0;
                }
            }
        }
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

    /// The filter's estimate now (see [`Windowed::estimate`]).
    fn live_estimate(&self) -> Option<MethodEstimate> {
        if self.updates == 0 {
            return None;
        }
        // Flag only with a full horizon of residuals: the first windows carry sway residuals of
        // tens of arcsec that the average has not yet taken down (their widening of the 1-sigma
        // stays: it is conservative).
        let horizon = self.residual_horizon();
        let mismatch = self.pairs.iter().any(|p| p.mismatch.iter().any(|m| *m))
            && self.pairs.iter().all(|p| p.stats.count >= horizon);
        let x = self.kf.state();
        Some(MethodEstimate {
            x_rad: [x[0], x[1], x[2], x[3]],
            sigma_rad: self.reported_sigma_rad(),
            mismatch,
            relearning: self.changed_entries > 0 || self.pairs.iter().any(|p| p.relearning),
        })
    }
}
