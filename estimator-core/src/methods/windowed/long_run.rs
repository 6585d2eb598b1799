//! The long-run variance of a channel pair's residuals: what the 1-sigma of a constant estimated
//! over correlated residuals needs.
//!
//! The filter averages the windows' measurements as if their noise were white: after `N` entries
//! its variance of an error is about `q / N` for a per-product variance `q` (docs/method.md,
//! "Noise of an overlapping-window measurement"). What the residuals hold beyond white
//! noise (the slow heel and trim that the correlation turns into a ripple near the rotation
//! frequency, the errors of filled and missing samples, the sway's leak through the windows, a
//! disturbance that lasts) averages down otherwise, and the variance of the filter's estimate is
//! the residuals' long-run variance over `N`, not `q / N`.
//!
//! # Batch means whose batches grow with the log
//! The residuals, averaged over batches of `B` updates, have a variance `s_b^2` about their mean;
//! `B s_b^2` estimates the long-run variance of everything correlated over less than `B`. Over the
//! model's variance of a batch mean of white products (`q / b (1 - a / (3 b))`, `a` and `b` the
//! shorter and the longer of the window and the batch, in entries: a trapezoid's sum of squared
//! weights), it is the factor by which the filter's covariance understates the error: the
//! **long-run noise scale**.
//!
//! The batches double in length as the log goes on ([`SLOTS`] of them at most; when all are full,
//! the oldest two are dropped and the others merged in neighbouring pairs, so that the batches
//! cover the more recent part of the log, not the filter's own settling at its start): a batch stays a fixed share of the log, so that whatever lasts less
//! than a share of it (a ripple of hours, the sway's leak that falls like `1 / N` rather than
//! `1 / sqrt(N)`) is averaged in the batches as it is in the estimate, and the scale follows what
//! is left of it. A ripple of period `P_r` leaves an error of at most `A P_r / (pi t)` after `t`;
//! batches of `t / SLOTS` give it a 1-sigma of about twice that. The first batch is one period.
//!
//! The batches' squares are taken about zero: a mean that persists (a drift's lag, a bias the model
//! cannot explain, such as a cadence of lost rows that leaves the same leak every period) is an
//! error of the estimate as much as what scatters. Their lag-one correlation is taken about their
//! mean, once [`CENTRED_FROM`] batches are complete (see below).
//!
//! # What chance gives
//! Over `n` batches the scale of white residuals is a chi-square's mean, about 1 give or take
//! `sqrt(2 / n)`: taken as it is, the larger of it and the residual power's scale would make the
//! 1-sigma of a clean log too large by that chance alone (docs/uncertainty.md has the coverage
//! this gives). The scale is therefore taken less
//! [`CHANCE_SIGMAS`] times `sqrt(2 / n)`: a scale that only chance raised above the model's
//! leaves the 1-sigma to the residual power's, while one that a heel raises tens or thousands of
//! times above it loses nothing that matters.

use crate::math::Compare;
use crate::Real;

/// Batches kept; when all are full they are merged in neighbouring pairs.
pub const SLOTS: usize = 8;

/// Batches from which their squares are taken about their mean (and their lag-one correlation
/// counts).
pub const CENTRED_FROM: u32 = 3;

/// Bounds of the batches' lag-one correlation in the long-run factor `(1 + rho) / (1 - rho)`:
/// batches that alternate (the sway's leak, which averages out faster than white noise) count as
/// fewer than independent ones, but not below a third; a ripple many batches long at most 19.
pub const MIN_CORRELATION: Real = -0.5;
/// Upper bound of the batches' lag-one correlation (see [`MIN_CORRELATION`]).
pub const MAX_CORRELATION: Real = 0.9;

/// Standard deviations of the batch means' scale under white residuals that are taken as chance
/// (one-sided 95 %).
pub const CHANCE_SIGMAS: Real = 1.64;

/// The long-run statistics of one pair's residuals.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LongRun {
    /// Each batch's sum of residuals per channel, rad; the first `full` are complete, the next is
    /// the one being filled.
    sums_rad: [[Real; 2]; SLOTS],
    /// Complete batches.
    full: u32,
    /// Updates in the batch being filled.
    updates: u32,
    /// Updates a batch takes (0 until the first update sets it to one period's).
    length: u32,
    /// The long-run noise scale of the complete batches (0 until one is complete).
    scale: Real,
}

impl LongRun {
    /// Nothing learned.
    pub const NEW: LongRun = LongRun {
        sums_rad: [[0.0; 2]; SLOTS],
        full: 0,
        updates: 0,
        length: 0,
        scale: 0.0,
    };

    /// The long-run noise scale: the factor by which the filter's covariance understates the
    /// variance of its estimate (0 until a batch is complete).
    pub fn scale(&self) -> Real {
        self.scale
    }

    /// Complete batches.
    pub fn batches(&self) -> u32 {
        self.full
    }

    /// Adds one update's post-fit residuals, rad. `first_length` is the length of the first
    /// batch, updates (one period's); `window_entries` the window's entries and `q_rad2` the
    /// per-product variance of the model, for the batch mean's model variance.
    pub fn add(
        &mut self,
        residual_rad: [Real; 2],
        first_length: u32,
        window_entries: u32,
        q_rad2: Real,
    ) {
        if self.length == 0 {
            self.length = first_length.max(1);
        }
        let slot = (self.full as usize).min(SLOTS - 1);
        for k in 0..2 {
            self.sums_rad[slot][k] += residual_rad[k];
        }
        self.updates = self.updates.saturating_add(1);
        if self.updates < self.length {
            return;
        }
        self.updates = 0;
        self.full = (self.full + 1).min(SLOTS as u32);
        self.scale = self.scale_of_batches(window_entries, q_rad2);
        if self.full as usize == SLOTS {
            // The oldest two batches dropped, the others merged in neighbouring pairs: a third as
            // many batches, twice as long, of the more recent three quarters of the span (the
            // first batches hold the filter's own settling, which the estimate has outgrown).
            for i in 0..(SLOTS - 2) / 2 {
                for k in 0..2 {
                    self.sums_rad[i][k] = self.sums_rad[2 * i + 2][k] + self.sums_rad[2 * i + 3][k];
                }
            }
            for s in &mut self.sums_rad[(SLOTS - 2) / 2..] {
                *s = [0.0; 2];
            }
            self.full = ((SLOTS - 2) / 2) as u32;
            self.length = self.length.saturating_mul(2);
        }
    }

    /// The scale of the complete batches: the larger of the two channels' variance of a batch
    /// mean (about their mean, or zero while few) over the model's.
    #[cold]
    #[inline(never)]
    fn scale_of_batches(&self, window_entries: u32, q_rad2: Real) -> Real {
        let n = (self.full as usize).min(SLOTS);
        if n == 0 || !(q_rad2 > 0.0) {
            return 0.0;
        }
        let inv_length = 1.0 / self.length as Real;
        // A pair's update is every other entry: a batch spans twice its updates in entries.
        let entries = 2.0 * self.length as Real;
        let w = window_entries.max(1) as Real;
        let (a, b) = if entries < w {
            (entries, w)
        } else {
            (w, entries)
        };
        let model = q_rad2 / b * (1.0 - a / (3.0 * b));
        let mut scale: Real = 0.0;
        let centred = self.full >= CENTRED_FROM;
        for k in 0..2 {
            let mut sum = 0.0;
            for s in &self.sums_rad[..n] {
                sum += s[k] * inv_length;
            }
            let mean = if centred { sum / n as Real } else { 0.0 };
            let (mut square, mut lag) = (0.0, 0.0);
            let mut previous: Option<Real> = None;
            for s in &self.sums_rad[..n] {
                let d = s[k] * inv_length - mean;
                square += d * d;
                if let Some(p) = previous {
                    lag += d * p;
                }
                previous = Some(d);
            }
            // About zero: a mean that persists (a bias the model cannot explain) counts too.
            let variance = ((square + n as Real * mean * mean) / n as Real).larger(0.0);
            // A long sum of batches of lag-one correlation rho has the variance of
            // (1 + rho) / (1 - rho) independent ones (see the module doc).
            let factor = if centred && square > 0.0 {
                let rho = (lag / square)
                    .larger(MIN_CORRELATION)
                    .smaller(MAX_CORRELATION);
                (1.0 + rho) / (1.0 - rho)
            } else {
                1.0
            };
            scale = scale.larger(variance * factor / model);
        }
        // Less what chance gives white residuals over `n` batches ([`CHANCE_SIGMAS`] standard
        // deviations of a chi-square's mean, `sqrt(2 / n)`): a scale that only chance raised
        // above the model's stays with the power's (see the module doc).
        (scale - CHANCE_SIGMAS * crate::math::sqrt(2.0 / n as Real)).larger(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn normal(state: &mut u64) -> Real {
        // Sum of 12 uniforms: a unit normal, near enough.
        let mut s = 0.0;
        for _ in 0..12 {
            *state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            s += (*state >> 11) as f64 / (1u64 << 53) as f64;
        }
        (s - 6.0) as Real
    }

    /// Residuals whose batch means have the model's variance give a scale of about 1; a constant
    /// (a bias) its square over the model's variance; a ripple shown by the first batches a scale
    /// that falls as the batches outgrow its period.
    #[test]
    fn the_scale_follows_what_lasts_less_than_a_batch() {
        // A window of 480 entries; batches of 240 updates (one period). A residual of per-update
        // variance v gives a batch mean of v / 240, the model's q / 480 (2/3) when
        // v = q (2/3) 240 / 480 / (1/240)...: take independent residuals of variance
        // q (2/3) / 480 * 240 so that a batch mean of 240 has the model's variance.
        let q = 1.0e-8;
        let sd = ((q * (2.0 / 3.0) / 480.0 * 240.0) as f64).sqrt() as Real;
        let mut white = LongRun::NEW;
        let mut state = 12345u64;
        for _ in 0..(240 * 7) {
            white.add(
                [normal(&mut state) * sd, normal(&mut state) * sd],
                240,
                480,
                q,
            );
        }
        assert!(
            (0.3..3.0).contains(&white.scale()),
            "white: {}",
            white.scale()
        );
        // A bias the residuals keep counts in full: its square over the model's variance (less
        // what chance gives white residuals over the batches).
        let mut lag = LongRun::NEW;
        for _ in 0..(240 * 7) {
            lag.add([1.0e-4, -2.0e-4], 240, 480, q);
        }
        // At least the first batches' (one period's) value: later batches are longer, their
        // model variance smaller, and the same bias's share larger.
        let model = q / 480.0 * (2.0 / 3.0);
        // (Rounding aside: the batch means are sums of a few hundred terms.)
        let chance = CHANCE_SIGMAS * libm::sqrt(2.0 / f64::from(lag.batches())) as Real;
        let expected = 4.0e-8 / model * (1.0 - 1e-6) - chance;
        assert!(
            lag.scale() >= expected,
            "a constant: {} (at least {expected})",
            lag.scale()
        );
        let ripple = |updates: u32| {
            let mut r = LongRun::NEW;
            for k in 0..updates {
                let v = 1.0e-4 * libm::sin(k as f64 * 2.0 * core::f64::consts::PI / 1000.0) as Real;
                r.add([v, v], 240, 480, q);
            }
            r.scale()
        };
        let (early, late) = (ripple(240 * 7), ripple(240 * 7 * 16));
        assert!(early > 100.0, "ripple, early: {early}");
        assert!(late < early / 10.0, "ripple, late: {late} (early {early})");
    }
}
