//! What the windowed method learns of one channel pair beside the filter: the pitch pair (x1, x2)
//! and the roll pair (x3, x4 and the leakage of x1, x2) update the filter in turn, and each keeps
//! its residuals' statistics, its channels' gains and noise, the 1-sigma it reports and what the
//! change detector leaves it to hold. [`super::Windowed`] holds two, indexed by pair
//! ([`crate::correlation::PITCH_PAIR`], [`crate::correlation::ROLL_PAIR`]); a pair's channels are
//! [`channels`] of the four.
//!
//! The derivations (the residual check, the noise scale and the drift share, the report, the
//! learned spread) are in docs/method.md, "The windowed method in full"; this module holds their
//! state and the arithmetic that updates it, one pair at a time.

use crate::config::Config;
use crate::correlation::STATES;
use crate::math::{sqrt, Compare};
use crate::Real;

use super::long_run::LongRun;
use super::{
    BIAS_SHARE_DRIFT, BIAS_SHARE_NOISE, LONG_HORIZONS, MIN_NOISE_SCALE, SPREAD_CLIP_SIGMAS,
    SPREAD_HORIZONS,
};

/// The two channels of `pair` (0 pitch, 1 roll) among the four, in order.
#[inline(always)]
pub const fn channels(pair: usize) -> [usize; 2] {
    [2 * pair, 2 * pair + 1]
}

/// The residual statistics of a pair learned alongside the filter: what goes back with the filter
/// to the clean state while a change builds up (see "Changes of the errors: what the filter does"
/// in docs/method.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResidualStats {
    /// Exponential mean of each channel's post-fit residual, rad.
    pub mean_rad: [Real; 2],
    /// Residuals averaged so far (saturates at the averaging time).
    pub count: u32,
    /// Long exponential mean of each channel's residual mean, rad.
    pub mean_long_rad: [Real; 2],
    /// Each channel's residual mean averaged as `mean_long_rad` is, but with weights that grow
    /// with the residual mean's rank until the long averages' horizon is full (from then on both
    /// are the same running mean): the persistent residual mean now, from which the lag a drift
    /// leaves is read, without the first periods' residual means (the filter's estimate still
    /// converging) weighing as much as the latest, rad.
    pub mean_recent_rad: [Real; 2],
    /// Long exponential mean of each channel's squared residual mean, over the model's variance
    /// of that mean (about 1 when the model holds).
    pub power: [Real; 2],
    /// Residual means averaged into the long averages (saturates at their horizon).
    pub long_count: u32,
    /// The factor applied to the filter's variance in the reported 1-sigma (1 until the long
    /// averages start).
    pub noise_scale: Real,
    /// Share of the configured random walk's variance applied to the pair's errors, in [0, 1]
    /// (1 until the long averages start).
    pub drift_share: Real,
}

impl ResidualStats {
    /// Nothing learned, the defaults applied (scale 1, the full random walk).
    pub const NEW: ResidualStats = ResidualStats {
        mean_rad: [0.0; 2],
        count: 0,
        mean_long_rad: [0.0; 2],
        mean_recent_rad: [0.0; 2],
        power: [0.0; 2],
        long_count: 0,
        noise_scale: 1.0,
        drift_share: 1.0,
    };

    /// All zeros: an estimator not yet reset to a configuration.
    pub const UNCONFIGURED: ResidualStats = ResidualStats {
        noise_scale: 0.0,
        drift_share: 0.0,
        ..ResidualStats::NEW
    };

    /// After a declared change of the pair's errors: the residual check starts afresh, the scale
    /// and the walk go back to their defaults until a full horizon of residuals is averaged again,
    /// and the long averages keep what they learned with the weight of one `horizon` (see
    /// "Changes of the errors: what the filter does", item 3, in docs/method.md).
    pub fn relearn(&mut self, horizon: u32) {
        self.mean_rad = [0.0; 2];
        self.count = 0;
        self.long_count = self.long_count.min(horizon.max(1));
        self.noise_scale = 1.0;
        self.drift_share = 1.0;
    }
}

/// The last block of residuals the change detector formed for a pair, kept for learning the
/// errors again should a change be declared while the filter holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LastBlock {
    /// Each channel's block mean, rad.
    pub rad: [Real; 2],
    /// The rows of the pair's channels at the update that ended it.
    pub rows: [[Real; STATES]; 2],
    /// Whether the filter held through all of it.
    pub held: bool,
}

/// Everything the windowed method keeps of one channel pair.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pair {
    /// The residual statistics learned alongside the filter.
    pub stats: ResidualStats,
    /// Channel gains (diagonal of the rows, about 1/2 for x1, x2 and cos L / 2 for x3, x4) of the
    /// last update, for mapping residuals to x.
    pub gains: [Real; 2],
    /// Per-product variance of the pair's channels at the last update, rad^2 (`r` of "Noise of an
    /// overlapping-window measurement" in docs/method.md, filled samples included).
    pub product_variance_rad2: Real,
    /// The usual spread of each channel's residual, rad^2 (mean square, learned).
    pub spread_rad2: [Real; 2],
    /// Residuals learned into it (saturates at [`SPREAD_HORIZONS`] horizons).
    pub spread_count: u32,
    /// Each error's reported 1-sigma, rad, refreshed with the pair's updates.
    pub reported_sigma_rad: [Real; 2],
    /// Each channel's residual mean beyond the residual check's bound at the pair's last update.
    pub mismatch: [bool; 2],
    /// The pair's updates wait for a block of residuals after a change was declared.
    pub relearning: bool,
    /// The filter has held through every update of the current block so far.
    pub block_held: bool,
    /// The change detector's last block.
    pub last_block: LastBlock,
    /// The long-run variance of the residuals ([`super::long_run`]).
    pub long_run: LongRun,
}

impl Pair {
    /// All zeros: an estimator not yet reset to a configuration.
    pub const UNCONFIGURED: Pair = Pair {
        stats: ResidualStats::UNCONFIGURED,
        gains: [0.0; 2],
        product_variance_rad2: 0.0,
        spread_rad2: [0.0; 2],
        spread_count: 0,
        reported_sigma_rad: [0.0; 2],
        mismatch: [false; 2],
        relearning: false,
        block_held: true,
        last_block: LastBlock {
            rad: [0.0; 2],
            rows: [[0.0; STATES]; 2],
            held: false,
        },
        long_run: LongRun::NEW,
    };

    /// Nothing learned: the gains of a uniform rotation at the equator, the prior's 1-sigma.
    pub fn new(config: &Config) -> Pair {
        Pair {
            stats: ResidualStats::NEW,
            gains: [0.5; 2],
            reported_sigma_rad: [config.prior_sigma_rad; 2],
            ..Pair::UNCONFIGURED
        }
    }

    /// The model's variance of a residual mean, `s_e^2 = r / n` (see "Consistency" in
    /// docs/method.md): `r` the per-product variance at the last update (at least the configured
    /// one), `n` the samples averaged (at least one window of `window_len` entries); entries of
    /// `bin` samples.
    fn residual_mean_variance(&self, config: &Config, bin: u32, window_len: usize) -> Real {
        let sigma2 = config.measurement_sigma_rad * config.measurement_sigma_rad / bin as Real;
        let n = (2 * self.stats.count as usize).max(window_len) as Real;
        self.product_variance_rad2.larger(sigma2) / n
    }

    /// The pair's post-fit residuals against the estimate `x` (returned, rad), averaged into the
    /// residual means when `average` (the count saturating at `horizon` updates); `rows` and `z`
    /// of the pair's channels.
    // Called once, on the step's path.
    #[inline(always)]
    pub fn average_residuals(
        &mut self,
        pair: usize,
        horizon: u32,
        rows: &[[Real; STATES]; 4],
        z: &[Real; 4],
        x: &[Real],
        average: bool,
    ) -> [Real; 2] {
        let count = &mut self.stats.count;
        if average {
            *count = count.saturating_add(1).min(horizon.max(1));
        }
        let alpha = if average { 1.0 / *count as Real } else { 0.0 };
        let mut out = [0.0; 2];
        for (k, ch) in channels(pair).into_iter().enumerate() {
            let fit: Real = (0..STATES).map(|i| rows[ch][i] * x[i]).sum();
            let residual = z[ch] - fit;
            self.stats.mean_rad[k] += alpha * (residual - self.stats.mean_rad[k]);
            self.gains[k] = rows[ch][ch].abs();
            out[k] = residual;
        }
        out
    }

    /// The long averages of the residual means and what they give: the noise scale and the drift
    /// share (see "Learning the noise and the drift" in docs/method.md). Starts once
    /// a full `horizon` of residuals has been averaged.
    // Called once, on the step's path.
    #[inline(always)]
    pub fn learn_noise_and_drift(
        &mut self,
        config: &Config,
        bin: u32,
        window_len: usize,
        horizon: u32,
    ) {
        if self.stats.count < horizon.max(1) {
            return;
        }
        let count = &mut self.stats.long_count;
        let full = LONG_HORIZONS * horizon.max(1);
        let n = count.saturating_add(1);
        *count = n.min(full);
        let alpha = 1.0 / *count as Real;
        // Weights 1, 2, ..., n: the mean of weights growing linearly is updated by 2 / (n + 1).
        let alpha_recent = if n < full {
            2.0 / (n + 1) as Real
        } else {
            alpha
        };
        // The model's variance of a residual mean, s_e^2 = r / n (as in `refresh_report`).
        let sigma2 = config.measurement_sigma_rad * config.measurement_sigma_rad / bin as Real;
        let n = (2 * self.stats.count as usize).max(window_len) as Real;
        let inv_s_e2 = n / self.product_variance_rad2.larger(sigma2);
        let (mut power, mut bias) = (0.0, 0.0);
        let s = &mut self.stats;
        for k in 0..2 {
            let mean = s.mean_rad[k];
            s.mean_long_rad[k] += alpha * (mean - s.mean_long_rad[k]);
            s.mean_recent_rad[k] += alpha_recent * (mean - s.mean_recent_rad[k]);
            s.power[k] += alpha * (mean * mean * inv_s_e2 - s.power[k]);
            power += s.power[k];
            bias += s.mean_long_rad[k] * s.mean_long_rad[k] * inv_s_e2;
        }
        s.noise_scale = power.larger(MIN_NOISE_SCALE);
        let share = if power > 0.0 { bias / power } else { 0.0 };
        s.drift_share = ((share - BIAS_SHARE_NOISE)
            * (1.0 / (BIAS_SHARE_DRIFT - BIAS_SHARE_NOISE)))
            .clamp(0.0, 1.0);
    }

    /// The factor applied to the part of the filter's covariance this pair's noise makes: the
    /// larger of the noise scale (the power of the residual means, which holds what persists in
    /// them) and the long-run noise scale ([`super::long_run`]).
    pub fn noise_scale(&self) -> Real {
        self.stats.noise_scale.larger(self.long_run.scale())
    }

    /// Refreshes what is reported of the pair's errors: each error's 1-sigma, from
    /// `scaled_variance` (the filter's variance of the pair's errors, each pair's share rescaled
    /// by that pair's noise scale) widened by the residual check, the lag and the change
    /// detector's `widening_rad`, and whether its channel's residual mean is beyond the check's
    /// bound (see "Learning the noise and the drift" in docs/method.md).
    pub fn refresh_report(
        &mut self,
        config: &Config,
        bin: u32,
        window_len: usize,
        scaled_variance: [Real; 2],
        widening_rad: [Real; 2],
    ) {
        // The residual mean of a pair averages `count` updates of two entries each, of per-entry
        // variance `r` (filled samples included); without an update yet, the configured sigma.
        let s_e2 = self.residual_mean_variance(config, bin, window_len);
        for k in 0..2 {
            let mean = self.stats.mean_rad[k];
            let mut model = 0.0;
            let mut mismatch = false;
            // Within 2 sigma: nothing to add, no mismatch (the usual case, without a root).
            if mean * mean > 4.0 * s_e2 {
                let s_e = sqrt(s_e2);
                let excess = (mean.abs() - 2.0 * s_e).larger(0.0);
                // A bias b on a channel of gain g means an error of about b/g, but never more than
                // the prior says we could not know anyway: near the pole the gain of x3, x4 is
                // cos L / 2, about 0, and they are unobservable (their filter 1-sigma stays at the
                // prior).
                model = if excess <= 0.0 {
                    0.0
                } else if self.gains[k] > 1e-6 {
                    (excess / self.gains[k]).smaller(config.prior_sigma_rad)
                } else {
                    config.prior_sigma_rad
                };
                mismatch = mean.abs() > 4.0 * s_e;
            }
            // The persistent residual mean now as a state error (a drift's lag), where a drift is seen.
            let lag = if self.stats.drift_share > 0.0 && self.gains[k] > 1e-6 {
                (self.stats.mean_recent_rad[k] / self.gains[k])
                    .abs()
                    .smaller(config.prior_sigma_rad)
            } else {
                0.0
            };
            let m = model.larger(lag).larger(widening_rad[k]);
            self.reported_sigma_rad[k] = sqrt(scaled_variance[k].larger(0.0) + m * m);
            self.mismatch[k] = mismatch;
        }
    }

    /// The usual spread of each channel's residuals: a running mean of the squared residual over
    /// [`SPREAD_HORIZONS`] horizons. A residual the gate held out (`gated`) enters clipped at
    /// [`SPREAD_CLIP_SIGMAS`] and with the weight of a full average, so that a disturbance cannot
    /// widen the gate it is being held out by (see "Innovation gate" in
    /// docs/method.md).
    // Called once, on the step's path.
    #[inline(always)]
    pub fn learn_spread(&mut self, horizon: u32, residual: [Real; 2], gated: bool) {
        let horizon = horizon.max(1);
        let learned = self.spread_count;
        let full = SPREAD_HORIZONS * horizon;
        let count = learned.saturating_add(1).min(full);
        let weight = 1.0 / if gated { full } else { count } as Real;
        for k in 0..2 {
            let e2 = residual[k] * residual[k];
            let e2 = if learned == 0 {
                e2
            } else {
                e2.smaller(SPREAD_CLIP_SIGMAS * SPREAD_CLIP_SIGMAS * self.spread_rad2[k])
            };
            self.spread_rad2[k] += weight * (e2 - self.spread_rad2[k]);
        }
        self.spread_count = count;
    }
}
