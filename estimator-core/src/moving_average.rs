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
//! (a floating-point running sum accumulates rounding as a random walk; how much in `f32`:
//! docs/method.md, "Numerics on a Cortex-M4F"). Each value is rounded once, on the way in.

mod bins;

pub use bins::{Bin, WindowLayout};

use heapless::Deque;

use crate::correlation::{CorrelationSums, QuantizedSample, References};
use crate::gap_fill::GridSample;
use crate::math::round;
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
    // On the step's path: inlined although the firmware inlines little (.cargo/config.toml).
    #[inline]
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
    /// the stack (most of the estimator's state), which a microcontroller's stack may not hold.
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

/// The moving average of the windowed method: the entries of exactly one rotation period, as the
/// exact [`CorrelationSums`] of their fixed-point inputs.
///
/// The ring holds each entry's inputs ([`QuantizedSample`], 28 bytes: roll, pitch, the sines and
/// cosines, and the low-passed references; 32 with its number and weights, [`Entry`]) rather than
/// its 28 products; the products of the entry
/// that leaves the window are formed again from them, exactly as they were when it came in, and
/// subtracted.
///
/// # One period of time, not of entries
/// Each entry carries its number on the sample grid (the grid index, or the bin's number with
/// bins), and the window holds the entries of the last `len` numbers: rows lost in a run too long
/// to fill ([`crate::gap_fill`]) are simply absent, and the measurement is built from the entries
/// that are there (`z = row . x` holds for any subset, see [`crate::correlation`]). An entry near
/// such a run comes with a weight below [`crate::correlation::FULL_WEIGHT`] (the taper that keeps
/// the sway out of the sums, [`crate::gap_fill`]), and the sums are weighted.
///
/// # Bounded work a push
/// After a run of lost rows the next entry's number jumps, and the entries of as many numbers
/// leave at once; before the period is known the window holds more than a period (see
/// [`Self::configure`]). Neither is done in one step: a push removes at most
/// [`MAX_REMOVALS_PER_PUSH`] old entries, and until the window is back to one period
/// ([`Self::is_full`] false meanwhile) the filter takes no measurement from it. So no step does
/// more than a few entries' work, whatever the gap.
///
/// # Bins
/// When one period holds more samples than the ring's capacity, consecutive samples are averaged
/// into bins of `bin` samples, each bin one entry of the mean weight of its samples
/// ([`WindowLayout`]; `moving_average/bins.rs`): the window still spans one period (exactly, when
/// `bin` divides the period; the nearest whole number of bins otherwise).
#[derive(Clone, Debug, PartialEq)]
pub struct CorrelationWindow<const CAP: usize> {
    /// The entries in the window, oldest first.
    ring: Deque<Entry, CAP>,
    /// The exact sums of the entries in `ring`.
    sums: CorrelationSums,
    /// Entry numbers in a full window (one period).
    len: usize,
    /// Samples per entry.
    bin: u32,
    /// Samples per entry while the period is being learned ([`Self::expect_bin`]; 1 unless set).
    expected_bin: u32,
    /// Whether `len` is one period of the rotation pattern (set by [`Self::configure`]); before,
    /// the window keeps up to `CAP` entries from the first sample on.
    configured: bool,
    /// The grid index of the first sample since the window was emptied (bins count from it).
    origin: Option<u32>,
    /// The number of the first entry since the window was emptied, and of the newest.
    first: u32,
    newest: Option<u32>,
    /// Whether the window has held exactly one period since it was emptied.
    was_full: bool,
    /// Whether its entries go back to before the period was known (kept by [`Self::configure`]).
    from_learning: bool,
    partial: Bin,
}

/// What a push did: whether it completed an entry, and how many old entries it removed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pushed {
    /// Whether the push completed an entry (every push, without bins).
    pub completed: bool,
    /// Old entries the push removed, at most [`MAX_REMOVALS_PER_PUSH`].
    pub removed: u32,
}

/// Most old entries a push removes (see [`CorrelationWindow`], "Bounded work a push").
pub const MAX_REMOVALS_PER_PUSH: usize = 3;

/// One entry of the window: a sample's (or a bin's) fixed-point inputs, its number on the grid
/// (low 16 bits), its weight and its fill weight in one byte ([`FillCode`]). 32 bytes, aligned
/// like its `i32`s: an entry is copied in and out of the ring by a few word moves (a packed entry
/// would take a byte-wise library copy each way).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Entry {
    /// The sample's (or the bin's) inputs, in fixed point.
    pub sample: QuantizedSample,
    /// The entry's number (grid index, or bin number with bins), low 16 bits.
    pub number: u16,
    /// Its weight in the sums, 0 to [`crate::correlation::FULL_WEIGHT`].
    pub weight: u8,
    /// How much of it was filled ([`crate::gap_fill`]): its fill weight, coded.
    pub fill: FillCode,
}

impl Entry {
    /// An entry of weight 0: its products are all 0 (what [`CorrelationSums::replace`] takes for
    /// the side of a change that has no entry).
    pub const NONE: Entry = Entry {
        sample: QuantizedSample {
            roll: 0,
            pitch: 0,
            sin_rho: 0,
            cos_rho: 0,
            sin_rho_s: 0,
            cos_rho_s: 0,
            sin_lat: 0,
            cos_lat: 0,
            reference: [0; 4],
            turn_rate: 0,
            turn_reference: 0,
        },
        number: 0,
        weight: 0,
        fill: FillCode(0),
    };

    /// The fill weight the sums count for this entry.
    pub fn fill_weight(&self) -> u32 {
        self.fill.weight()
    }
}

/// A fill weight (a filled sample's error variance in units of a single filled sample's, summed
/// over a bin; 0 when nothing was filled) in one byte: exact up to 127, above that rounded up to
/// four significant bits (at most 6.25 % high, never low), saturating at 31,744. Codes 0-127 are
/// the weight itself; code `128 + 16 e + m` is `(16 + m) 2^(e + 3)`. The window's sums count the
/// coded weight, in and out alike, so they stay exact.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FillCode(pub u8);

impl FillCode {
    /// The largest weight a code holds.
    pub const MAX_WEIGHT: u32 = 31 << 10;

    /// The code of the smallest coded weight at or above `weight` (saturating).
    pub fn of(weight: u32) -> FillCode {
        if weight < 128 {
            return FillCode(weight as u8);
        }
        if weight >= Self::MAX_WEIGHT {
            return FillCode(u8::MAX);
        }
        // weight in [2^(b), 2^(b+1)), b >= 7: four significant bits, e = b - 7.
        let e = 31 - weight.leading_zeros() - 7;
        let shift = e + 3;
        let mut m = weight >> shift;
        if weight & ((1 << shift) - 1) != 0 {
            m += 1;
        }
        let (e, m) = if m == 32 { (e + 1, 16) } else { (e, m) };
        FillCode((128 + 16 * e + (m - 16)) as u8)
    }

    /// The weight the code stands for.
    pub fn weight(self) -> u32 {
        let c = u32::from(self.0);
        if c < 128 {
            c
        } else {
            let k = c - 128;
            (16 + (k & 15)) << ((k >> 4) + 3)
        }
    }
}

impl<const CAP: usize> CorrelationWindow<CAP> {
    /// An empty window of one entry per sample, not yet set to a period (it keeps up to `CAP`
    /// entries until [`Self::configure`]).
    pub const fn new() -> Self {
        CorrelationWindow {
            ring: Deque::new(),
            sums: CorrelationSums::ZERO,
            len: if CAP > 1 { CAP } else { 1 },
            bin: 1,
            expected_bin: 1,
            configured: false,
            origin: None,
            first: 0,
            newest: None,
            was_full: false,
            from_learning: false,
            partial: Bin::ZERO,
        }
    }

    /// Back to [`Self::new`], in place (no `CAP`-sized temporary on the stack), but for the bin
    /// expected while the period is learned ([`Self::expect_bin`]), which it takes again.
    pub fn reset(&mut self) {
        self.len = CAP.max(1);
        self.bin = self.expected_bin;
        self.configured = false;
        self.clear();
    }

    /// The samples per entry to bin with while the period is being learned: those of the period
    /// most likely to come, so that when it does, the entries gathered while it was learned stay
    /// (a period that needs another bin empties the window, as any change of bin does). Applied
    /// at once to a window not yet set to a period (emptied), and again at each [`Self::reset`].
    pub fn expect_bin(&mut self, bin: u32) {
        self.expected_bin = bin.max(1);
        if !self.configured && self.bin != self.expected_bin {
            self.bin = self.expected_bin;
            self.clear();
        }
    }

    /// Sets the window to one period of `period_samples`. When the period's layout keeps the
    /// window's samples per entry, the entries kept so far stay (the samples since the first row,
    /// one an entry or in the expected bins while the period was being learned): the window holds
    /// one period as soon as the excess has been removed, a few entries a push. A window already
    /// set to a period with bins, or one whose bin changes, starts empty.
    pub fn configure(&mut self, period_samples: u32) {
        let layout = WindowLayout::for_period(period_samples, CAP);
        let keep = layout.samples_per_entry == self.bin && (self.bin == 1 || !self.configured);
        self.bin = layout.samples_per_entry;
        self.len = layout.entries.clamp(1, CAP.max(1));
        if keep {
            self.from_learning = !self.configured;
        } else {
            self.clear();
        }
        self.configured = true;
    }

    /// Whether the entries go back to the samples gathered while the period was being learned
    /// (kept when the period came, one sample an entry or in the expected bins): the first
    /// estimate is then due 1.25 periods from the first of them ([`crate::methods::windowed`]'s
    /// start). A window emptied since, or set to a period from its first sample, does not.
    pub fn holds_samples_from_learning(&self) -> bool {
        self.from_learning
    }

    /// Forgets every entry and the bin being filled (after a long gap or a rotation fault).
    pub fn clear(&mut self) {
        self.from_learning = false;
        self.ring.clear();
        self.sums = CorrelationSums::default();
        self.partial = Bin::default();
        self.origin = None;
        self.newest = None;
        self.first = 0;
        self.was_full = false;
    }

    /// Entry numbers in a full window.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Samples per entry.
    pub fn bin(&self) -> u32 {
        self.bin
    }

    /// Whether the window is set to one period of the rotation pattern.
    pub fn is_configured(&self) -> bool {
        self.configured
    }

    /// The entry numbers the window spans so far, up to `len`.
    fn span(&self) -> usize {
        match self.newest {
            Some(n) => (n.wrapping_sub(self.first) as usize)
                .saturating_add(1)
                .min(self.len),
            None => 0,
        }
    }

    /// True when the window is set to one period, has spanned a whole one since it was emptied,
    /// and holds no entry older than that period: a measurement can be taken.
    // On the step's path: inlined although the firmware inlines little (.cargo/config.toml).
    #[inline]
    pub fn is_full(&self) -> bool {
        self.configured && self.span() >= self.len && !self.is_over_long()
    }

    /// True once the window has held exactly one period since it was emptied (after a run of lost
    /// rows it may hold a few older entries for a few pushes: still true).
    pub fn has_spanned_a_period(&self) -> bool {
        self.was_full
    }

    /// Whether the window still holds entries older than one period (being removed, a few a push).
    fn is_over_long(&self) -> bool {
        match (self.ring.front(), self.newest) {
            (Some(front), Some(n)) => {
                usize::from((n as u16).wrapping_sub(front.number)) >= self.len
            }
            _ => false,
        }
    }

    /// The entry numbers spanned so far, up to a full window (what [`crate::Holdup`] reports).
    pub fn filled(&self) -> usize {
        self.span()
    }

    /// The number of the first entry since the window was emptied.
    pub fn first_number(&self) -> u32 {
        self.first
    }

    /// The number of the newest entry (0 when empty).
    pub fn newest_number(&self) -> u32 {
        self.newest.unwrap_or(0)
    }

    /// The running sums.
    pub fn sums(&self) -> &CorrelationSums {
        &self.sums
    }

    /// The entries in the window, oldest first.
    pub fn entries(&self) -> impl Iterator<Item = Entry> + '_ {
        self.ring.iter().copied()
    }

    /// Adds one sample with its low-passed references and its weight (0 to
    /// [`crate::correlation::FULL_WEIGHT`]): whether it completed an entry (every sample, without
    /// bins) and how many old entries went. Samples come in grid order; lost ones are simply not
    /// pushed.
    pub fn push(
        &mut self,
        s: &GridSample,
        reference: &References,
        turn_rate: Real,
        weight: u8,
    ) -> Pushed {
        if self.bin <= 1 {
            let q = QuantizedSample::new(s.roll_rad, s.pitch_rad, &s.angles, reference, turn_rate);
            let removed =
                self.push_entry(s.index, q, FillCode::of(u32::from(s.fill_weight)), weight);
            return Pushed {
                completed: true,
                removed,
            };
        }
        self.push_to_bin(s, reference, turn_rate, weight)
    }

    /// Adds an entry, removing up to [`MAX_REMOVALS_PER_PUSH`] entries older than one period (and
    /// the oldest when the ring is full); returns how many went. Every change of the sums is one
    /// call of [`CorrelationSums::replace`]: the first entry removed with the new one, any further
    /// one with an entry of weight 0 (whose products are all 0), and the new one alone, when none
    /// goes, with an entry of weight 0 in its place. One copy of the products' code in the image,
    /// and the same exact sums as adding and subtracting apart.
    fn push_entry(
        &mut self,
        number: u32,
        sample: QuantizedSample,
        fill: FillCode,
        weight: u8,
    ) -> u32 {
        if self.newest.is_none() {
            self.first = number;
        }
        self.newest = Some(number);
        let mut removed = 0;
        let mut new = Some(Entry {
            sample,
            number: number as u16,
            weight,
            fill,
        });
        loop {
            // The oldest goes when it is older than one period (a few a push), or to make room
            // for the new entry in a full ring (only when more than `CAP` numbers are held, before
            // the period is known).
            let old = match self.ring.front() {
                Some(o)
                    if (new.is_some() && self.ring.is_full())
                        || (removed < MAX_REMOVALS_PER_PUSH
                            && usize::from((number as u16).wrapping_sub(o.number)) >= self.len) =>
                {
                    Some(o)
                }
                _ => None,
            };
            // The new entry goes in on the first pass (the ring has room: it was not full, or its
            // oldest goes now).
            let adding = new.take().filter(|_| old.is_some() || !self.ring.is_full());
            let going = old.is_some();
            if !going && adding.is_none() {
                break;
            }
            let (o, a) = (
                old.unwrap_or(&Entry::NONE),
                adding.as_ref().unwrap_or(&Entry::NONE),
            );
            self.sums.replace(
                &o.sample,
                o.fill_weight(),
                o.weight,
                &a.sample,
                a.fill_weight(),
                a.weight,
            );
            self.sums.count =
                (self.sums.count + u32::from(adding.is_some())).saturating_sub(u32::from(going));
            if going {
                self.ring.pop_front();
                removed += 1;
            }
            if let Some(e) = adding {
                // Room was made above: this cannot fail.
                let _ = self.ring.push_back(e);
            }
        }
        if !self.was_full && self.is_full() {
            self.was_full = true;
        }
        removed as u32
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
    use rand_chacha::rand_core::{RngCore, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn two_days_of_running_sums_equal_the_direct_sum_of_the_window() {
        let mut w: WindowAverage<2, 480> = WindowAverage::new(480);
        let mut rng = ChaCha8Rng::seed_from_u64(12345);
        for i in 0..172_800u64 {
            let r = ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 - 0.5) as Real;
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
