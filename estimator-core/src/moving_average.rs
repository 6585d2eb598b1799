//! The averaging of eq (11): a moving average over one rotation period.
//!
//! A boxcar of exactly one rotation period (480 samples of 1 s) passes the constant part of a signal
//! and blocks every component at a whole multiple of 1/480 Hz: the rotation harmonics of the
//! correlation products (`sin 2 rho`, `cos 2 rho`, and a constant error times `sin rho`). It also
//! divides a component at frequency f by about `pi f T` (T = 480 s), which is what takes the sway
//! (periods 6-14 s) down by a factor of 200-600 per window.
//!
//! The samples are stored as fixed-point `i32` (2^30 counts per unit, resolution 9.3e-10 rad =
//! 0.0002 arcsec, range +-2) and the running sums as exact `i64`. Adding the new sample and
//! subtracting the oldest is then exact, so the running sum never drifts, however long the run
//! (a floating-point running sum accumulates rounding as a random walk: 0.3 arcsec after two days
//! in `f32`). Each value is rounded once, on the way in.

use crate::math::round;
use crate::Real;

/// Fixed-point counts per unit.
pub const COUNTS_PER_UNIT: Real = (1u64 << 30) as Real;
/// Largest magnitude a stored value may have; larger values are clamped.
pub const MAX_MAGNITUDE: Real = 1.999_999;

/// `CH` channels averaged over the same window of up to `CAP` samples.
#[derive(Clone, Debug, PartialEq)]
pub struct WindowAverage<const CH: usize, const CAP: usize> {
    pub(crate) ring: [[i32; CH]; CAP],
    pub(crate) sums: [i64; CH],
    pub(crate) len: usize,
    pub(crate) head: usize,
    pub(crate) filled: usize,
}

impl<const CH: usize, const CAP: usize> WindowAverage<CH, CAP> {
    /// A window of `len` samples, `1 <= len <= CAP` (clamped into that range).
    pub fn new(len: usize) -> Self {
        WindowAverage {
            ring: [[0; CH]; CAP],
            sums: [0; CH],
            len: len.clamp(1, CAP.max(1)),
            head: 0,
            filled: 0,
        }
    }

    /// Rounds a value to fixed point, clamping it to +-[`MAX_MAGNITUDE`]. NaN becomes 0 (callers
    /// never pass NaN: samples are checked before they get here).
    pub fn quantize(value: Real) -> i32 {
        let v = if value.is_nan() { 0.0 } else { value.clamp(-MAX_MAGNITUDE, MAX_MAGNITUDE) };
        round(v * COUNTS_PER_UNIT) as i32
    }

    /// Adds one sample of every channel, dropping the oldest once the window is full.
    pub fn push(&mut self, values: &[Real; CH]) {
        let slot = self.head;
        let full = self.filled == self.len;
        for ch in 0..CH {
            let q = Self::quantize(values[ch]);
            if full {
                self.sums[ch] -= i64::from(self.ring[slot][ch]);
            }
            self.ring[slot][ch] = q;
            self.sums[ch] += i64::from(q);
        }
        self.head = if slot + 1 >= self.len { 0 } else { slot + 1 };
        if !full {
            self.filled += 1;
        }
    }

    /// True once the window holds `len` samples.
    pub fn is_full(&self) -> bool {
        self.filled == self.len
    }

    /// Window length in samples.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Samples currently in the window.
    pub fn filled(&self) -> usize {
        self.filled
    }

    /// Back to the state of [`WindowAverage::new`]`(len)`, in place: no `CAP x CH` temporary on
    /// the stack (13 KB for the default estimator), which a microcontroller's stack may not hold.
    pub fn reset(&mut self, len: usize) {
        self.ring.fill([0; CH]);
        self.clear();
        self.len = len.clamp(1, CAP.max(1));
    }

    /// Forgets every sample (after a long gap or a rotation fault).
    pub fn clear(&mut self) {
        self.sums = [0; CH];
        self.head = 0;
        self.filled = 0;
    }

    /// The mean of each channel over the full window, or `None` while it fills.
    pub fn means(&self) -> Option<[Real; CH]> {
        if !self.is_full() {
            return None;
        }
        let scale = COUNTS_PER_UNIT * self.len as Real;
        let mut out = [0.0; CH];
        for ch in 0..CH {
            out[ch] = self.sums[ch] as Real / scale;
        }
        Some(out)
    }

    /// The exact running sums (fixed-point counts), for tests and checkpoints.
    pub fn sums(&self) -> &[i64; CH] {
        &self.sums
    }

    /// The stored samples of channel `ch` over the window, oldest first (fixed-point counts).
    pub fn window_counts(&self, ch: usize) -> impl Iterator<Item = i32> + '_ {
        let start = if self.is_full() { self.head } else { 0 };
        (0..self.filled).map(move |i| self.ring[(start + i) % self.len][ch.min(CH - 1)])
    }
}


#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_days_of_running_sums_equal_the_direct_sum_of_the_window() {
        let mut w: WindowAverage<2, 480> = WindowAverage::new(480);
        let mut state: u64 = 12345;
        for i in 0..172_800u64 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let r = ((state >> 33) as f64 / (1u64 << 31) as f64 - 0.5) as Real;
            let sway = 0.05 * libm::sin(i as f64 * 1.047) as Real;
            w.push(&[sway + 1e-3 * r, -0.3 + r]);
        }
        for ch in 0..2 {
            let direct: i64 = w.window_counts(ch).map(i64::from).sum();
            assert_eq!(direct, w.sums()[ch], "channel {ch} drifted");
        }
        let direct_mean: f64 =
            w.window_counts(0).map(|c| c as f64 / (1u64 << 30) as f64).sum::<f64>() / 480.0;
        let mean = w.means().unwrap()[0] as f64;
        assert!((mean - direct_mean).abs() < 1e-7 * direct_mean.abs().max(1e-3));
    }

    #[test]
    fn blocks_whole_rotation_harmonics() {
        let n = 480;
        let mut w: WindowAverage<3, 480> = WindowAverage::new(n);
        for k in 0..(3 * n + 17) {
            let rho = 2.0 * core::f64::consts::PI * k as f64 / n as f64;
            w.push(&[
                (0.01 * libm::sin(rho)) as Real,
                (0.01 * libm::cos(2.0 * rho) + 0.002) as Real,
                (0.01 * libm::sin(5.0 * rho + 0.3)) as Real,
            ]);
        }
        let m = w.means().unwrap();
        assert!(m[0].abs() < 1e-9, "{}", m[0]);
        assert!((m[1] - 0.002).abs() < 1e-9, "{}", m[1]);
        assert!(m[2].abs() < 1e-9, "{}", m[2]);
    }

    #[test]
    fn fills_then_reports_and_clears() {
        let mut w: WindowAverage<1, 8> = WindowAverage::new(4);
        for v in [1.0, 2.0, 3.0] {
            w.push(&[v as Real * 0.1]);
            assert!(w.means().is_none());
        }
        w.push(&[0.4]);
        assert!((w.means().unwrap()[0] - 0.25).abs() < 1e-7);
        w.push(&[0.5]);
        assert!((w.means().unwrap()[0] - 0.35).abs() < 1e-7);
        w.clear();
        assert!(w.means().is_none());
        assert_eq!(w.filled(), 0);
    }
}
