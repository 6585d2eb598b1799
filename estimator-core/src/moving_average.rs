//! The averaging of eq (11): a moving average over one rotation period.
//!
//! Two windows live here: [`CorrelationWindow`], the windowed method's (the exact sums of the
//! correlation of [`crate::correlation`] over one period of any rotation pattern), and
//! [`WindowAverage`], a plain moving average of a few channels, which the paper's method applies
//! to its running correlation (eq 11 as printed).
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

use heapless::Deque;

use crate::correlation::{CorrelationSums, QuantizedSample};
use crate::gap_fill::GridSample;
use crate::installation::Angles;
use crate::math::{round, sin_cos, wrap_pi};
use crate::Real;

/// Fixed-point counts per unit.
pub const COUNTS_PER_UNIT: Real = (1u64 << 30) as Real;
/// Largest magnitude a stored value may have; larger values are clamped.
pub const MAX_MAGNITUDE: Real = 1.999_999;

/// `CH` channels averaged over the same window of up to `CAP` samples.
#[derive(Clone, Debug, PartialEq)]
pub struct WindowAverage<const CH: usize, const CAP: usize> {
    /// The samples in the window, oldest first (at most `len`).
    ring: Deque<[i32; CH], CAP>,
    /// The exact sums of the samples in `ring`, per channel.
    sums: [i64; CH],
    len: usize,
}

impl<const CH: usize, const CAP: usize> WindowAverage<CH, CAP> {
    /// A window of `len` samples, `1 <= len <= CAP` (clamped into that range).
    pub fn new(len: usize) -> Self {
        WindowAverage {
            ring: Deque::new(),
            sums: [0; CH],
            len: len.clamp(1, CAP.max(1)),
        }
    }

    /// Rounds a value to fixed point, clamping it to +-[`MAX_MAGNITUDE`]. NaN becomes 0 (callers
    /// never pass NaN: samples are checked before they get here).
    pub fn quantize(value: Real) -> i32 {
        let v = if value.is_nan() {
            0.0
        } else {
            value.clamp(-MAX_MAGNITUDE, MAX_MAGNITUDE)
        };
        round(v * COUNTS_PER_UNIT) as i32
    }

    /// Adds one sample of every channel, dropping the oldest once the window is full.
    pub fn push(&mut self, values: &[Real; CH]) {
        if self.is_full() {
            if let Some(oldest) = self.ring.pop_front() {
                for ch in 0..CH {
                    self.sums[ch] -= i64::from(oldest[ch]);
                }
            }
        }
        let q: [i32; CH] = core::array::from_fn(|ch| Self::quantize(values[ch]));
        // `len <= CAP` and the window was not full: there is room.
        if self.ring.push_back(q).is_ok() {
            for ch in 0..CH {
                self.sums[ch] += i64::from(q[ch]);
            }
        }
    }

    /// True once the window holds `len` samples.
    pub fn is_full(&self) -> bool {
        self.ring.len() >= self.len
    }

    /// Window length in samples.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Samples currently in the window.
    pub fn filled(&self) -> usize {
        self.ring.len()
    }

    /// Back to the state of [`WindowAverage::new`]`(len)`, in place: no `CAP x CH` temporary on
    /// the stack (13 KB for the default estimator), which a microcontroller's stack may not hold.
    pub fn reset(&mut self, len: usize) {
        self.clear();
        self.len = len.clamp(1, CAP.max(1));
    }

    /// Forgets every sample (after a long gap or a rotation fault).
    pub fn clear(&mut self) {
        self.ring.clear();
        self.sums = [0; CH];
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
        self.ring.iter().map(move |v| v[ch.min(CH - 1)])
    }
}

/// The moving average of the windowed method: the last `len` entries of exactly one rotation
/// period, as the exact [`CorrelationSums`] of their fixed-point inputs.
///
/// The ring holds each entry's inputs ([`QuantizedSample`], 28 bytes: roll, pitch, the sines and
/// cosines, and the low-passed references) rather than its 28 products; the products of the entry that leaves the window are
/// formed again from them, exactly as they were when it came in, and subtracted.
///
/// # Bins
/// When one period holds more samples than the ring's capacity (a 10 Hz log, a long period),
/// consecutive samples are averaged into bins of `bin` samples (roll, pitch, latitude, the
/// references, and the angles as offsets from the bin's first sample), and each bin is one entry: the window still
/// spans one period (exactly, when `bin` divides the period; the nearest whole number of bins
/// otherwise). Averaging within a bin slightly low-passes the sway (it helps) and the oscillation
/// of eq (2) (a relative error of about `(w_r b dt)^2 / 24`, 1e-5 for 5 samples of 0.1 s at 480 s).
/// Its measured cost is in docs/real-logs.md (Bins).
#[derive(Clone, Debug, PartialEq)]
pub struct CorrelationWindow<const CAP: usize> {
    /// The entries in the window, oldest first (at most `len`).
    ring: Deque<Entry, CAP>,
    /// The exact sums of the entries in `ring`.
    sums: CorrelationSums,
    /// Entries in a full window.
    len: usize,
    /// Samples per entry.
    bin: u32,
    partial: Bin,
}

/// One entry of the window: a sample's (or a bin's) fixed-point inputs and how many of its samples
/// were filled. Packed to 30 bytes rather than padded to 32, which keeps the default estimator's
/// 720 entries, and so its state, within 24 KiB; its fields are read by value, never by reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C, packed(2))]
pub struct Entry {
    pub sample: QuantizedSample,
    pub fill_weight: u16,
}

/// A bin being filled.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Bin {
    pub count: u32,
    pub roll_rad: Real,
    pub pitch_rad: Real,
    pub latitude_rad: Real,
    /// Sum of the low-passed references.
    pub reference: [Real; 4],
    /// The first sample's rotation and rotation-minus-platform angles, and the sums of the offsets
    /// from them.
    pub rotation0_rad: Real,
    pub rotation_offset_rad: Real,
    pub rotation_minus_platform0_rad: Real,
    pub rotation_minus_platform_offset_rad: Real,
    pub fill_weight: u32,
}

impl Bin {
    /// Nothing in it.
    pub const ZERO: Bin = Bin {
        count: 0,
        roll_rad: 0.0,
        pitch_rad: 0.0,
        latitude_rad: 0.0,
        reference: [0.0; 4],
        rotation0_rad: 0.0,
        rotation_offset_rad: 0.0,
        rotation_minus_platform0_rad: 0.0,
        rotation_minus_platform_offset_rad: 0.0,
        fill_weight: 0,
    };
}

/// How one period is held by the window: samples per entry and entries in a full window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WindowLayout {
    pub samples_per_entry: u32,
    pub entries: usize,
}

impl WindowLayout {
    /// How a period of `period_samples` is held by a ring of `capacity` entries. One sample per
    /// entry when the period fits; otherwise the smallest bin that divides the period into at most
    /// `capacity` entries, or, when none does within twice the smallest possible bin, that
    /// smallest bin and the nearest whole number of entries.
    pub fn for_period(period_samples: u32, capacity: usize) -> WindowLayout {
        let capacity = capacity.max(2) as u32;
        let period = period_samples.max(2);
        if period <= capacity {
            return WindowLayout {
                samples_per_entry: 1,
                entries: period as usize,
            };
        }
        let smallest = period.div_ceil(capacity);
        for bin in smallest..=2 * smallest {
            if period.is_multiple_of(bin) && period / bin <= capacity {
                return WindowLayout {
                    samples_per_entry: bin,
                    entries: (period / bin) as usize,
                };
            }
        }
        let entries = ((period + smallest / 2) / smallest).clamp(2, capacity);
        WindowLayout {
            samples_per_entry: smallest,
            entries: entries as usize,
        }
    }
}

impl<const CAP: usize> CorrelationWindow<CAP> {
    /// An empty window of one entry per sample over `len` entries (set by [`Self::configure`]).
    pub const fn new() -> Self {
        CorrelationWindow {
            ring: Deque::new(),
            sums: CorrelationSums::ZERO,
            len: if CAP > 1 { CAP } else { 1 },
            bin: 1,
            partial: Bin::ZERO,
        }
    }

    /// Back to [`Self::new`], in place (no `CAP`-sized temporary on the stack).
    pub fn reset(&mut self) {
        self.len = CAP.max(1);
        self.bin = 1;
        self.clear();
    }

    /// Sets the window to one period of `period_samples` and empties it.
    pub fn configure(&mut self, period_samples: u32) {
        let layout = WindowLayout::for_period(period_samples, CAP);
        self.bin = layout.samples_per_entry;
        self.len = layout.entries.clamp(1, CAP.max(1));
        self.clear();
    }

    /// Forgets every entry and the bin being filled (after a gap or a rotation fault).
    pub fn clear(&mut self) {
        self.ring.clear();
        self.sums = CorrelationSums::default();
        self.partial = Bin::default();
    }

    /// Entries in a full window.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Samples per entry.
    pub fn bin(&self) -> u32 {
        self.bin
    }

    /// True once the window holds `len` entries.
    pub fn is_full(&self) -> bool {
        self.ring.len() >= self.len
    }

    /// Entries in the window.
    pub fn filled(&self) -> usize {
        self.ring.len()
    }

    /// The running sums.
    pub fn sums(&self) -> &CorrelationSums {
        &self.sums
    }

    /// The entries in the window, oldest first.
    pub fn entries(&self) -> impl Iterator<Item = Entry> + '_ {
        self.ring.iter().copied()
    }

    /// Adds one sample with its low-passed references; returns true when it completed an entry
    /// (every sample, without bins).
    pub fn push(&mut self, s: &GridSample, reference: &[Real; 4]) -> bool {
        if self.bin <= 1 {
            self.push_entry(
                QuantizedSample::new(s.roll_rad, s.pitch_rad, &s.angles, reference),
                s.fill_weight,
            );
            return true;
        }
        let b = &mut self.partial;
        if b.count == 0 {
            *b = Bin {
                rotation0_rad: s.rotation_rad,
                rotation_minus_platform0_rad: s.rotation_minus_platform_rad,
                ..Bin::default()
            };
        }
        b.count += 1;
        b.roll_rad += s.roll_rad;
        b.pitch_rad += s.pitch_rad;
        b.latitude_rad += s.latitude_rad;
        for ch in 0..4 {
            b.reference[ch] += reference[ch];
        }
        b.rotation_offset_rad += wrap_pi(s.rotation_rad - b.rotation0_rad);
        b.rotation_minus_platform_offset_rad +=
            wrap_pi(s.rotation_minus_platform_rad - b.rotation_minus_platform0_rad);
        b.fill_weight += u32::from(s.fill_weight);
        if b.count < self.bin {
            return false;
        }
        let n = b.count as Real;
        let rotation = wrap_pi(b.rotation0_rad + b.rotation_offset_rad / n);
        let rotation_minus_platform =
            wrap_pi(b.rotation_minus_platform0_rad + b.rotation_minus_platform_offset_rad / n);
        let angles = Angles::from_rotation(
            rotation,
            rotation_minus_platform,
            sin_cos(b.latitude_rad / n),
        );
        let q = QuantizedSample::new(
            b.roll_rad / n,
            b.pitch_rad / n,
            &angles,
            &b.reference.map(|r| r / n),
        );
        let weight = b.fill_weight.min(u32::from(u16::MAX)) as u16;
        self.partial = Bin::default();
        self.push_entry(q, weight);
        true
    }

    fn push_entry(&mut self, sample: QuantizedSample, fill_weight: u16) {
        if self.is_full() {
            // Read in place, then dropped: one copy of the packed entry fewer than popping it.
            if let Some(oldest) = self.ring.front() {
                let (q, w) = (oldest.sample, oldest.fill_weight);
                self.sums.subtract(&q, w);
            }
            self.ring.pop_front();
        }
        // `len <= CAP` and the window is not full: there is room.
        if self
            .ring
            .push_back(Entry {
                sample,
                fill_weight,
            })
            .is_ok()
        {
            self.sums.add(&sample, fill_weight);
        }
    }
}

impl<const CAP: usize> Default for CorrelationWindow<CAP> {
    fn default() -> Self {
        Self::new()
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
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let r = ((state >> 33) as f64 / (1u64 << 31) as f64 - 0.5) as Real;
            let sway = 0.05 * libm::sin(i as f64 * 1.047) as Real;
            w.push(&[sway + 1e-3 * r, -0.3 + r]);
        }
        for ch in 0..2 {
            let direct: i64 = w.window_counts(ch).map(i64::from).sum();
            assert_eq!(direct, w.sums()[ch], "channel {ch} drifted");
        }
        let direct_mean: f64 = w
            .window_counts(0)
            .map(|c| c as f64 / (1u64 << 30) as f64)
            .sum::<f64>()
            / 480.0;
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
