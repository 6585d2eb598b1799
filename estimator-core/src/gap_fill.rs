//! Lost samples: short gaps filled from their neighbours, longer runs left out with a taper, so
//! that the moving average still cancels the sway.
//!
//! # Why fill, and how
//! The window mean of eq (11) cancels the ship's sway (degrees) only because it sums the sway over
//! whole sway periods: a lost sample left out biases the window's correlation by about `A c / N`
//! (`A` the sway amplitude, `c` the reference, `N` the window). Up to `max_filled_gap_samples`
//! lost in a row are filled: roll and pitch with the Lagrange polynomial through the
//! [`NEIGHBOURS`] present samples on each side (the sway lies far below a 1 s log's Nyquist
//! frequency, where a polynomial of high order through many neighbours is a good band-limited
//! interpolator, unlike a linear or cubic one); the angles, which move slowly at a steady rate,
//! linearly the short way round. The filled reference is used in the measurement and in its row
//! alike, so an error in it is no bias.
//!
//! # Longer runs: left out, with a taper
//! Three or more lost in a row leave the polynomial off by a share of the sway that a regular
//! cadence of losses repeats, and a plain hole leaves a piece of a sway cycle uncancelled. So a
//! longer run is left out of the sums and the rows around it weighted down: a sample's weight is
//! `R(d_before) R(d_after)`, `d` its distance in samples to the nearest lost row of a hole before
//! and after it, `R` the cumulative sum of a Hann window of `2 TAPER_HALF + 1` points
//! ([`TAPER_WEIGHTS`]): 0 next to the hole, 1 after [`TAPER_LEN`] samples. The missing weight is
//! then the hole convolved with a Hann window, whose side lobes leave little of the sway above its
//! first null (a 16 s period at 1 s). The weights enter the measurement and its rows alike
//! ([`crate::correlation::CorrelationSums`]), so nothing is biased; a hole costs about
//! `2 TAPER_HALF` samples of information.
//!
//! A run of an eighth of a rotation period or more (or a clock step) restarts the window instead
//! (the estimator decides, [`crate::estimator`]). The interpolation errors, the taper's spectrum
//! and the figures on lossy logs: docs/real-logs.md, "Lost rows", and docs/gap-study.md.
pub(crate) mod checkpoint;
mod weights;

use heapless::Deque;

use crate::correlation::FULL_WEIGHT;
use crate::installation::Angles;
use crate::math::{sin_cos, wrap_pi};
use crate::Real;

use weights::{lagrange_at_zero, ALL_NEIGHBOURS, CENTRED_WEIGHTS, WITHOUT_NEXT, WITHOUT_PREVIOUS};

/// Present samples used on each side of a lost one.
pub const NEIGHBOURS: usize = 5;
/// Longest gap that can ever be filled (the configuration may choose less).
pub const MAX_FILLABLE_GAP: u32 = 3;
/// Half-length of the Hann window of the taper around holes, samples.
pub const TAPER_HALF: u32 = 15;
/// Samples over which the taper rises from 0 to full weight.
pub const TAPER_LEN: u32 = 2 * TAPER_HALF + 1;
/// The taper's weights at distance `1..=TAPER_LEN` from a lost row of a hole, in units of
/// `FULL_WEIGHT / 64` (64 = full): `R(d) = sum_{j < d} K_j` with `K` the Hann window
/// `sin^2(pi (j + 1) / (2 TAPER_HALF + 2))`, `j = 0..2 TAPER_HALF`, normalised to sum 1, rounded to
/// 64ths (the test `taper_weights_are_the_hann_window_s_cumulative_sum` recomputes them).
pub const TAPER_WEIGHTS: [u8; TAPER_LEN as usize] = [
    0, 0, 1, 1, 2, 3, 5, 7, 9, 12, 15, 19, 22, 26, 30, 34, 38, 42, 45, 49, 52, 55, 57, 59, 61, 62,
    63, 63, 64, 64, 64,
];
/// How far the window runs behind the newest sample: a sample is passed on once its
/// [`TAPER_LEN`] successors are known (received or lost), so that a hole after it has tapered it.
pub const DELAY: u32 = TAPER_LEN;
/// Capacity of the delay line (received samples waiting, and the [`NEIGHBOURS`] passed on last):
/// the delay, the samples a hole leaves waiting (up to the delay again), and margin.
pub const LINE: usize = 80;
/// Samples over which the prediction error of present samples is averaged.
pub const FILL_ERROR_SAMPLES: u32 = 256;
/// The prediction error is measured at every this many grid indices.
pub const FILL_ERROR_EVERY: u32 = 4;
/// How much each further lost neighbour at distance 1..=5 raises the variance of a filled sample
/// (squared ratios of the interpolation errors of a 6 s sway at 1 s, rounded up: one neighbour
/// fewer at distance 1 makes the error 8.7 times larger, at 5 only 2 times).
pub const MISSING_NEIGHBOUR_VARIANCE_FACTOR: [u32; NEIGHBOURS] = [76, 20, 10, 6, 4];

/// One sample on the grid, as the window takes it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSample {
    /// Index on the sample grid.
    pub index: u32,
    /// Roll, rad.
    pub roll_rad: Real,
    /// Pitch, rad.
    pub pitch_rad: Real,
    /// Rotation angle rho of eq (2), rad.
    pub rotation_rad: Real,
    /// Rotation minus platform angle, rad.
    pub rotation_minus_platform_rad: Real,
    /// Latitude, rad.
    pub latitude_rad: Real,
    /// Heading, rad (the ship's turns: [`crate::correlation`], "Heel in turns").
    pub heading_rad: Real,
    /// Trigonometry of the angles.
    pub angles: Angles,
    /// 0 for a received sample; for a filled one, its variance in units of a filled single
    /// sample's ([`MISSING_NEIGHBOUR_VARIANCE_FACTOR`]), saturating.
    pub fill_weight: u16,
}

/// A received sample waiting in the delay line.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Held {
    sample: GridSample,
    /// The window restarts before this sample (a gap too long to bridge, or a clock step).
    restart: bool,
}

/// What the filler passes on: a sample (received or filled), its weight in the window's sums
/// (0 to [`FULL_WEIGHT`]), and whether the window restarts before it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Passed {
    /// The sample, received or filled.
    pub sample: GridSample,
    /// Its weight in the window's sums, 0 to [`FULL_WEIGHT`].
    pub weight: u8,
    /// Whether the window restarts before it.
    pub restart: bool,
}

/// Most holes (runs too long to fill, and restarts) known ahead of the next sample to pass on.
pub const HOLES: usize = 16;

/// The delay line and the fill-error monitor.
#[derive(Clone, Debug, PartialEq)]
pub struct GapFiller {
    /// Received samples in index order: the `history` passed on last (for the fills), then those
    /// waiting.
    line: Deque<Held, LINE>,
    /// How many samples at the front of `line` have been passed on (at most [`NEIGHBOURS`]).
    history: usize,
    /// The first lost row of each hole (or restart) ahead, nearest first.
    holes: Deque<u32, HOLES>,
    /// Lost rows in the holes ahead (stepped over at once when the next sample reaches them).
    hole_rows_ahead: u32,
    /// Lost rows in a row that are filled (the configuration's `max_filled_gap_samples`).
    max_fill: u32,
    /// The newest index received, once any.
    newest: Option<u32>,
    /// The next index to pass on.
    next: u32,
    /// The last lost row of the last hole passed over (for the taper after it).
    hole_end: Option<u32>,
    /// Mean square prediction error of present roll and pitch samples, rad^2, and samples averaged.
    roll_error_rad2: Real,
    pitch_error_rad2: Real,
    error_samples: u32,
    /// Samples dropped because the line was full (rows arriving in runs faster than passed on).
    overflows: u32,
}

/// The taper's factor at distance `d` from a hole's nearest lost row (64 = none).
fn taper(d: u32) -> u32 {
    match d {
        0 => 0,
        d if d <= TAPER_LEN => u32::from(TAPER_WEIGHTS[d as usize - 1]),
        _ => 64,
    }
}

/// The weight of sample `k` near holes: the product of the tapers from the end of the hole behind
/// it (`hole_end`) and from the nearest hole ahead (`holes`, whose holes behind `k` are dropped).
/// Its weight is final once a hole ahead is known (none can come nearer) or [`DELAY`] samples have
/// come (`newest`); `None` until then.
// Called once, on the step's path.
#[inline(always)]
fn tapered_weight(
    holes: &mut Deque<u32, HOLES>,
    hole_end: Option<u32>,
    k: u32,
    newest: u32,
) -> Option<u8> {
    while let Some(&h) = holes.front() {
        if h.wrapping_sub(k).wrapping_sub(1) >= 1 << 31 {
            holes.pop_front();
        } else {
            break;
        }
    }
    let hole_after = holes.front().copied();
    if hole_after.is_none() && newest.wrapping_sub(k) < DELAY {
        return None;
    }
    let d_before = hole_end.map_or(u32::MAX, |e| k.wrapping_sub(e));
    let d_after = hole_after.map_or(u32::MAX, |h| h.wrapping_sub(k));
    Some(((taper(d_before) * taper(d_after) + 32) / 64) as u8)
}

impl Default for GapFiller {
    fn default() -> Self {
        GapFiller::new()
    }
}

impl GapFiller {
    /// An empty delay line, no fill error measured yet.
    pub const fn new() -> Self {
        GapFiller {
            line: Deque::new(),
            history: 0,
            holes: Deque::new(),
            hole_rows_ahead: 0,
            max_fill: 0,
            newest: None,
            next: 0,
            hole_end: None,
            roll_error_rad2: 0.0,
            pitch_error_rad2: 0.0,
            error_samples: 0,
            overflows: 0,
        }
    }
}

/// The error variance of one filled sample, measured online, of roll and of pitch.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FillVariance {
    /// Of roll, rad^2.
    pub roll_rad2: Real,
    /// Of pitch, rad^2.
    pub pitch_rad2: Real,
}

impl GapFiller {
    /// Forgets every pending sample (the fill-error estimate stays: it belongs to the sea state).
    pub fn clear(&mut self) {
        self.line.clear();
        self.history = 0;
        self.holes.clear();
        self.hole_rows_ahead = 0;
        self.newest = None;
        self.hole_end = None;
    }

    /// The variance of a filled single sample of roll and of pitch (0 until measured).
    pub fn single_fill_variance(&self) -> FillVariance {
        FillVariance {
            roll_rad2: self.roll_error_rad2,
            pitch_rad2: self.pitch_error_rad2,
        }
    }

    /// Samples dropped because the delay line was full.
    pub fn overflows(&self) -> u32 {
        self.overflows
    }

    /// Takes a received sample (indices increase; lost ones are skipped). With `restart`, the
    /// window restarts before it (the gap before it is too long to bridge, or the clock stepped).
    /// Runs of up to `max_fill` lost rows are to be filled, longer ones left out.
    pub fn push(&mut self, sample: &GridSample, restart: bool, max_fill: u32) {
        self.max_fill = max_fill;
        match self.newest {
            None => self.next = sample.index,
            Some(n) => {
                let lost = sample.index.wrapping_sub(n).wrapping_sub(1);
                if (restart || lost > max_fill) && !self.holes.is_full() {
                    let _ = self.holes.push_back(n.wrapping_add(1));
                    self.hole_rows_ahead = self.hole_rows_ahead.saturating_add(lost);
                }
            }
        }
        if self.line.is_full() {
            // Rows arrive in runs faster than they are passed on: the oldest goes (a sample
            // passed on, or else the oldest waiting, which becomes lost).
            if self.line.pop_front().is_some() {
                if self.history > 0 {
                    self.history -= 1;
                } else {
                    self.overflows = self.overflows.saturating_add(1);
                }
            }
        }
        let _ = self.line.push_back(Held {
            sample: *sample,
            restart,
        });
        self.newest = Some(sample.index);
    }

    /// How far the samples passed on lag behind the delay, in samples: the rows filled (each
    /// takes a step of its own) since the lag was last made up. The rows of holes ahead do not
    /// count: they are stepped over at once when the next sample reaches them, which makes up
    /// the lag they caused.
    pub fn backlog(&self) -> u32 {
        match self.newest {
            Some(n) if n.wrapping_sub(self.next) < 1 << 31 => n
                .wrapping_sub(self.next)
                .saturating_sub(DELAY - 1)
                .saturating_sub(self.hole_rows_ahead)
                .min(LINE as u32),
            _ => 0,
        }
    }

    /// Passes on the next sample whose weight is known (its [`DELAY`] successors received or
    /// lost, or a hole after it already known): received, or filled when it lies in a run of at
    /// most `max_fill` lost rows (only with `allow_fill`: a fill is the costliest sample). Runs
    /// too long to fill are stepped over. `None` when the next sample must wait.
    pub fn pass_on(&mut self, allow_fill: bool) -> Option<Passed> {
        let newest = self.newest?;
        loop {
            let k = self.next;
            if newest.wrapping_sub(k) >= 1 << 31 {
                return None;
            }
            // The first held sample at or after `k`, and the one before it.
            let pos = self.history;
            let held = self.line.get(pos)?;
            let received = held.sample.index == k;
            if !received && self.is_hole_before(pos, held) {
                // A hole: step over it.
                let index = held.sample.index;
                self.hole_end = Some(index.wrapping_sub(1));
                self.hole_rows_ahead = self.hole_rows_ahead.saturating_sub(index.wrapping_sub(k));
                self.next = index;
                continue;
            }
            // The usual case: a received sample, no hole near it.
            if received
                && self.holes.is_empty()
                && self.hole_end.is_none_or(|e| k.wrapping_sub(e) > TAPER_LEN)
            {
                if newest.wrapping_sub(k) < DELAY {
                    return None;
                }
                let (sample, restart) = (held.sample, held.restart);
                return Some(self.pass_received(k, pos, sample, restart));
            }
            let weight = tapered_weight(&mut self.holes, self.hole_end, k, newest)?;
            let (sample, restart) = if received {
                let (sample, restart) = (held.sample, held.restart);
                self.measure_fill_error(&sample, pos);
                self.history += 1;
                (sample, restart)
            } else if allow_fill {
                (self.fill(k, pos)?, false)
            } else {
                return None;
            };
            if restart {
                self.hole_end = None;
            }
            self.next = k.wrapping_add(1);
            // Keep the last NEIGHBOURS passed on for the fills and the fill-error measure.
            while self.history > NEIGHBOURS {
                self.line.pop_front();
                self.history -= 1;
            }
            return Some(Passed {
                sample,
                weight: weight.min(FULL_WEIGHT),
                restart,
            });
        }
    }

    /// Whether the rows lost before `held`, the sample at `pos` in the line, are a hole to step
    /// over: a run longer than `max_fill` (or with no sample before it), or a restart.
    // Called once, on the step's path.
    #[inline(always)]
    fn is_hole_before(&self, pos: usize, held: &Held) -> bool {
        let before = if pos > 0 {
            self.line.get(pos - 1).map(|h| h.sample.index)
        } else {
            None
        };
        let run = before.map_or(u32::MAX, |b| {
            held.sample.index.wrapping_sub(b).wrapping_sub(1)
        });
        run > self.max_fill || held.restart
    }

    /// Passes on the received sample `k` (at `pos` in the line) at full weight: the usual case,
    /// no hole near it. Measures the fill error on it, and keeps the last [`NEIGHBOURS`] passed
    /// on.
    // Called once, on the step's path.
    #[inline(always)]
    fn pass_received(&mut self, k: u32, pos: usize, sample: GridSample, restart: bool) -> Passed {
        self.measure_fill_error(&sample, pos);
        self.history += 1;
        if restart {
            self.hole_end = None;
        }
        self.next = k.wrapping_add(1);
        if self.history > NEIGHBOURS {
            self.line.pop_front();
            self.history -= 1;
        }
        Passed {
            sample,
            weight: FULL_WEIGHT,
            restart,
        }
    }

    /// Predicts a present sample from its 10 neighbours, when all are present, and averages the
    /// squared prediction error. Every [`FILL_ERROR_EVERY`]th index only: the mean square of a sea
    /// state needs no more, and the step's cost stays low.
    fn measure_fill_error(&mut self, s: &GridSample, pos: usize) {
        if !s.index.is_multiple_of(FILL_ERROR_EVERY) || pos < NEIGHBOURS {
            return;
        }
        // The eleven held samples centred on `s`, in one pass over the ring's (at most two) runs
        // of memory: the line holds increasing indices, so all ten neighbours are present when
        // the first is five before `s` and the last five after. The centre's weight is 0 (adding
        // 0 changes no sum: the same values as the ten terms alone).
        let (mut roll, mut pitch) = (0.0, 0.0);
        let (mut seen, mut first, mut last) = (0usize, 0u32, 0u32);
        self.line
            .iter()
            .skip(pos - NEIGHBOURS)
            .take(2 * NEIGHBOURS + 1)
            .for_each(|h| {
                let w = CENTRED_WEIGHTS.get(seen).copied().unwrap_or(0.0);
                roll += w * h.sample.roll_rad;
                pitch += w * h.sample.pitch_rad;
                if seen == 0 {
                    first = h.sample.index;
                }
                last = h.sample.index;
                seen += 1;
            });
        let n = NEIGHBOURS as u32;
        if seen != 2 * NEIGHBOURS + 1
            || s.index.wrapping_sub(first) != n
            || last.wrapping_sub(s.index) != n
        {
            return;
        }
        self.error_samples = (self.error_samples + 1).min(FILL_ERROR_SAMPLES);
        let a = 1.0 / self.error_samples as Real;
        let (er, ep) = (roll - s.roll_rad, pitch - s.pitch_rad);
        self.roll_error_rad2 += a * (er * er - self.roll_error_rad2);
        self.pitch_error_rad2 += a * (ep * ep - self.pitch_error_rad2);
    }

    /// Fills the lost sample `index` from the present samples within [`NEIGHBOURS`] on each side.
    #[inline(never)]
    fn fill(&self, index: u32, pos: usize) -> Option<GridSample> {
        let mut nodes = [0i32; 2 * NEIGHBOURS];
        let mut values = [(0.0, 0.0); 2 * NEIGHBOURS];
        let mut n = 0;
        let mut before: Option<(i32, &GridSample)> = None;
        let mut after: Option<(i32, &GridSample)> = None;
        // The neighbours present, in one pass over the line (increasing indices): one `o` before
        // `index` sits at most five places before `pos`, one after at most four after it.
        let mut present = 0u32;
        let start = pos.saturating_sub(NEIGHBOURS);
        self.line
            .iter()
            .skip(start)
            .take(pos + NEIGHBOURS - start)
            .for_each(|h| {
                let offset = h.sample.index.wrapping_sub(index) as i32;
                if offset == 0 || offset.unsigned_abs() > NEIGHBOURS as u32 || n >= 2 * NEIGHBOURS {
                    return;
                }
                nodes[n] = offset;
                values[n] = (h.sample.roll_rad, h.sample.pitch_rad);
                n += 1;
                present |= 1 << (offset + NEIGHBOURS as i32);
                if offset < 0 {
                    before = Some((offset, &h.sample));
                } else if after.is_none() {
                    after = Some((offset, &h.sample));
                }
            });
        let (weight, missing) = missing_neighbours(present);
        let ((ob, b), (oa, a)) = (before?, after?);
        let w = match (n, missing) {
            (10, _) => ALL_NEIGHBOURS,
            (9, 1) => WITHOUT_NEXT,
            (9, -1) => WITHOUT_PREVIOUS,
            _ => lagrange_at_zero(&nodes, n),
        };
        let (mut roll, mut pitch) = (0.0, 0.0);
        for (wi, v) in w.iter().zip(values.iter()).take(n) {
            roll += wi * v.0;
            pitch += wi * v.1;
        }
        Some(filled_sample(
            index,
            (roll, pitch),
            (ob, b),
            (oa, a),
            weight,
        ))
    }
}

/// The fill's variance weight (the product of each missing neighbour's factor,
/// [`MISSING_NEIGHBOUR_VARIANCE_FACTOR`], saturating) and the offset of the last neighbour
/// missing (0 when none is), for the neighbours `present` (bit `offset + NEIGHBOURS` set for each
/// offset present). By the bits of the offsets absent, lowest first: as many passes as neighbours
/// missing.
// Called once, in `GapFiller::fill`.
#[inline(always)]
fn missing_neighbours(present: u32) -> (u32, i32) {
    let mut weight = 1u32;
    let mut missing = 0i32;
    let all = ((1u32 << (2 * NEIGHBOURS + 1)) - 1) & !(1 << NEIGHBOURS);
    let mut absent = all & !present;
    while absent != 0 {
        let offset = absent.trailing_zeros() as i32 - NEIGHBOURS as i32;
        absent &= absent - 1;
        let factor = MISSING_NEIGHBOUR_VARIANCE_FACTOR
            .get(offset.unsigned_abs() as usize - 1)
            .copied()
            .unwrap_or(u32::MAX);
        weight = weight.saturating_mul(factor);
        missing = offset;
    }
    (weight, missing)
}

/// The filled sample `index`: its roll and pitch (interpolated from the neighbours), the angles
/// linearly, the short way round, between the nearest present samples `before` and
/// `after` (each with its offset from `index`), and its fill weight `weight` (at most
/// `u16::MAX`).
// Called once, in `GapFiller::fill`.
#[inline(always)]
fn filled_sample(
    index: u32,
    (roll, pitch): (Real, Real),
    (ob, b): (i32, &GridSample),
    (oa, a): (i32, &GridSample),
    weight: u32,
) -> GridSample {
    let f = (-ob) as Real / (oa - ob) as Real;
    let ang = |x: Real, y: Real| wrap_pi(x + wrap_pi(y - x) * f);
    let rotation_rad = ang(b.rotation_rad, a.rotation_rad);
    let rotation_minus_platform_rad =
        ang(b.rotation_minus_platform_rad, a.rotation_minus_platform_rad);
    let latitude_rad = b.latitude_rad + (a.latitude_rad - b.latitude_rad) * f;
    let heading_rad = ang(b.heading_rad, a.heading_rad);
    let lat = if latitude_rad == b.latitude_rad {
        (b.angles.sin_lat, b.angles.cos_lat)
    } else {
        sin_cos(latitude_rad)
    };
    let weight = weight.min(u32::from(u16::MAX)) as u16;
    GridSample {
        index,
        roll_rad: roll,
        pitch_rad: pitch,
        rotation_rad,
        rotation_minus_platform_rad,
        latitude_rad,
        heading_rad,
        angles: Angles::from_rotation(rotation_rad, rotation_minus_platform_rad, lat),
        fill_weight: weight,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The weights from the full set's products equal the products over the nodes present, bit
    /// for bit, for every subset of the ten offsets.
    #[test]
    fn lagrange_weights_from_the_full_set_equal_the_direct_products() {
        for subset in 1u32..1 << (2 * NEIGHBOURS) {
            let mut nodes = [0i32; 2 * NEIGHBOURS];
            let mut n = 0;
            for (bit, x) in (-(NEIGHBOURS as i32)..=NEIGHBOURS as i32)
                .filter(|x| *x != 0)
                .enumerate()
            {
                if subset & (1 << bit) != 0 {
                    nodes[n] = x;
                    n += 1;
                }
            }
            let w = lagrange_at_zero(&nodes, n);
            for i in 0..n {
                let (mut num, mut den) = (1i32, 1i32);
                for m in (0..n).filter(|m| *m != i) {
                    num *= -nodes[m];
                    den *= nodes[i] - nodes[m];
                }
                assert_eq!(
                    w[i].to_bits(),
                    (num as Real / den as Real).to_bits(),
                    "nodes {:?}",
                    &nodes[..n]
                );
            }
        }
    }
    use crate::math::sin_cos;

    #[test]
    fn taper_weights_are_the_hann_window_s_cumulative_sum() {
        let n = TAPER_LEN as usize;
        let k: std::vec::Vec<f64> = (0..n)
            .map(|j| {
                (core::f64::consts::PI * (j + 1) as f64 / (2.0 * TAPER_HALF as f64 + 2.0))
                    .sin()
                    .powi(2)
            })
            .collect();
        let total: f64 = k.iter().sum();
        let mut cumulative = 0.0;
        for (j, w) in k.iter().enumerate() {
            cumulative += w / total;
            assert_eq!(
                TAPER_WEIGHTS[j],
                (64.0 * cumulative).round() as u8,
                "d = {}",
                j + 1
            );
        }
        assert_eq!(u32::from(FULL_WEIGHT), 64);
    }

    fn grid_sample(index: u32) -> GridSample {
        let t = f64::from(index);
        GridSample {
            index,
            roll_rad: (0.05 * libm::sin(t * 1.047)) as Real,
            pitch_rad: (0.01 * libm::cos(t * 0.7)) as Real,
            rotation_rad: 0.0,
            rotation_minus_platform_rad: 0.0,
            latitude_rad: 0.5,
            heading_rad: 0.0,
            angles: Angles::from_rotation(0.0, 0.0, sin_cos(0.5)),
            fill_weight: 0,
        }
    }

    /// Rows 40-49 lost (a hole), 120-121 lost (filled): the hole is stepped over, the samples on
    /// either side weighted by the taper, the pair filled at full weight; one sample passed on a
    /// call, each once its `DELAY` successors are known.
    #[test]
    fn a_run_of_lost_rows_is_stepped_over_with_the_taper_around_it() {
        let mut f = GapFiller::default();
        let mut passed = std::vec::Vec::new();
        for i in (0..200u32).filter(|i| !(40..50).contains(i) && !(120..122).contains(i)) {
            f.push(&grid_sample(i), false, 2);
            while let Some(p) = f.pass_on(true) {
                assert!(
                    i >= p.sample.index + DELAY || p.sample.index < 40,
                    "{} passed at {i}",
                    p.sample.index
                );
                passed.push(p);
            }
        }
        let indices: std::vec::Vec<u32> = passed.iter().map(|p| p.sample.index).collect();
        let expected: std::vec::Vec<u32> =
            (0..200 - DELAY).filter(|i| !(40..50).contains(i)).collect();
        assert_eq!(indices, expected);
        let weight = |i: u32| passed.iter().find(|p| p.sample.index == i).unwrap().weight;
        for d in 1..=TAPER_LEN {
            assert_eq!(
                weight(40 - d),
                TAPER_WEIGHTS[d as usize - 1],
                "{d} before the hole"
            );
            assert_eq!(
                weight(49 + d),
                TAPER_WEIGHTS[d as usize - 1],
                "{d} after the hole"
            );
        }
        assert_eq!(weight(100), FULL_WEIGHT);
        for i in [120, 121] {
            let p = passed.iter().find(|p| p.sample.index == i).unwrap();
            assert!(p.sample.fill_weight > 0 && p.weight == FULL_WEIGHT);
            // Two lost in a row: the fill through the 9 neighbours left of a 6 s sway is 3.4 % of
            // its amplitude off for the first, far less for the second.
            assert!(
                (p.sample.roll_rad - grid_sample(i).roll_rad).abs() < 0.04 * 0.05,
                "filled {i}"
            );
        }
    }
}
