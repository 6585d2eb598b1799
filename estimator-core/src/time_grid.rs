//! The sample grid: places each time stamp in its slot on a grid of whole sample intervals
//! anchored in absolute time.
//!
//! The estimator needs only how many intervals lie between two accepted samples (1 for
//! consecutive samples, `n` after `n - 1` lost ones); the stamps pass to the output untouched.
//!
//! # Slots, not steps
//! A recorder that stamps rows on receipt jitters each stamp by up to nearly half an interval:
//! two stamps then lie 0.1 to 1.9 intervals apart, and their step does not tell a lost row from
//! jitter. But once the interval `T` and the phase are known, a stamp lies within half an interval
//! of exactly one slot `t_anchor + k T`: a stamp `e` after the last accepted one is placed
//! `n = round(e / T)` slots on (`n - 1` samples missing), or in the very next slot when it is
//! consistent with it (rows are lost far less often than stamps jitter).
//!
//! # Learning, then following the clock
//! The first [`LEARNING_STAMPS`] stamps are not estimated from: the interval (unless pinned by
//! [`crate::Config::sample_interval_s`]) starts as the median of their steps, each step is classed
//! as one slot or more, and a least-squares line through the stamps against their slots gives the
//! interval and the phase. Then each stamp placed corrects the grid, a line fit updated a stamp at
//! a time with a memory growing from [`TRACKING_START`] to [`TRACKING_MEMORY`] stamps: the grid
//! follows a clock that runs fast or drifts (a pinned interval's copy within
//! [`PINNED_INTERVAL_TOLERANCE`] of it).
//!
//! # Placing a stamp
//! - `n >= 1` slots on: on the grid, `n - 1` samples missing;
//! - twice in a row off its slot on the same side by more than the jitter explains, or over
//!   `u32::MAX` intervals on: a clock jump; over [`CLOCK_STEP_BACK_INTERVALS`] intervals back: a
//!   step back. Either is accepted, counted, re-anchored, and a gap the window cannot bridge;
//! - otherwise at or before the last accepted slot: refused ([`SampleError::TimeNotIncreasing`],
//!   [`SampleError::IrregularTimeStep`]), the grid unchanged.
//!
//! The usual stamp costs one double-precision subtraction (from a base moved every
//! [`REBASE_INTERVALS`]), the rest single precision without division. The derivation (the
//! classing, the tracker's gains, the thresholds) and where the learning can go wrong:
//! docs/real-logs.md, "Time stamps".

mod checkpoint;

use crate::sample::SampleError;

/// Stamps the interval and the phase are learned from (accepted, not estimated from).
pub const LEARNING_STAMPS: usize = 9;
/// The tracking's growing-memory stamp count right after learning.
pub const TRACKING_START: u32 = LEARNING_STAMPS as u32;
/// The tracking's memory, stamps: its gains stop falling here.
pub const TRACKING_MEMORY: u32 = 1024;
/// How far back (in intervals) a stamp must go to be a clock step rather than a repeated row.
pub const CLOCK_STEP_BACK_INTERVALS: f64 = 2.0;
/// How far the interval the grid follows may stray from a pinned one, as a fraction of it.
pub const PINNED_INTERVAL_TOLERANCE: f32 = 0.01;
/// Intervals after which the base time moves up to the grid's phase.
pub const REBASE_INTERVALS: f32 = 1024.0;
/// Largest offset from the grid's phase, in intervals, placed in single precision.
pub const FAST_PATH_INTERVALS: f32 = 4096.0;
/// Stamps a learning offset may reach, s, before learning starts again at the stamp (single
/// precision keeps a millisecond there).
const MAX_LEARNING_OFFSET_S: f64 = 8192.0;

/// The tracking's gains once its memory is full: `2 (2N - 1) / (N (N + 1))` and `6 / (N (N + 1))`.
const HELD_GAINS: (f32, f32) = {
    let n = TRACKING_MEMORY as f32;
    (
        2.0 * (2.0 * n - 1.0) / (n * (n + 1.0)),
        6.0 / (n * (n + 1.0)),
    )
};

/// Where a stamp falls on the grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// One of the stamps the grid is learned from.
    Learning,
    /// `intervals` sample intervals after the previous accepted sample (1: the next sample).
    OnGrid {
        /// Sample intervals since the previous accepted sample.
        intervals: u32,
    },
    /// A clock jump or a clock step backwards: the grid is re-anchored here.
    ClockStep,
}

/// A stamp placed by [`TimeGrid::place`]: where it falls, and what [`TimeGrid::accept`] needs to
/// follow it without computing it again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed {
    /// Where the stamp falls.
    pub placement: Placement,
    /// The stamp less the grid's base time, s (while learning: less the first stamp).
    rel_s: f32,
    /// The stamp less its slot's time, s.
    residual_s: f32,
    /// `rel_s` is exact enough to follow the grid in single precision.
    fast: bool,
    /// Further from its slot than the jitter explains.
    off: bool,
    /// Learning starts again at this stamp.
    restart: bool,
}

impl Placed {
    /// A clock jump or a step backwards found on the long path: re-anchored at the stamp.
    const CLOCK_STEP: Placed = Placed {
        placement: Placement::ClockStep,
        rel_s: 0.0,
        residual_s: 0.0,
        fast: false,
        off: false,
        restart: false,
    };

    fn learning(rel_s: f32, restart: bool) -> Placed {
        Placed {
            placement: Placement::Learning,
            rel_s,
            residual_s: 0.0,
            fast: false,
            off: false,
            restart,
        }
    }
}

/// The grid's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeGrid {
    /// The interval, s: pinned, or learned (refreshed when the base moves).
    interval_s: Option<f64>,
    /// Whether the interval was pinned by the configuration.
    pinned: bool,
    /// The previous accepted stamp, s.
    last_stamp_s: Option<f64>,
    /// The time the grid's offsets are taken from, s: the first learning stamp, then a slot time.
    base_s: f64,
    /// The grid's interval as it follows the clock, s (0 before learning).
    interval32_s: f32,
    /// The slot time of the last accepted stamp less `base_s`, s.
    lead32_s: f32,
    /// The last accepted stamp less `base_s`, s.
    last_rel32_s: f32,
    /// The learning stamps less the first, s; the first `learned` are set.
    stamps_s: [f32; LEARNING_STAMPS],
    /// Learning stamps in (`LEARNING_STAMPS` once the grid is known).
    learned: u32,
    /// The tracking's stamp count (its gains' `m`), at most [`TRACKING_MEMORY`].
    tracked: u32,
    /// Mean square of the residuals of the stamps placed, s^2.
    mean_square32_s2: f32,
    /// The residual of the previous stamp if it was off the grid, s; 0 otherwise.
    pending32_s: f32,
    /// Clock jumps and steps backwards seen.
    clock_steps: u32,
}

impl TimeGrid {
    /// The sample interval, pinned or learned; `None` while it is being learned.
    pub fn interval_s(&self) -> Option<f64> {
        self.interval_s
    }

    /// The sample interval once the grid's phase is known too: stamps are placed on the grid.
    pub fn placing_interval_s(&self) -> Option<f64> {
        self.interval_s.filter(|_| self.ready())
    }

    /// The time stamp of the last accepted sample, s.
    pub fn last_stamp_s(&self) -> Option<f64> {
        self.last_stamp_s
    }

    /// A grid with the interval pinned (`Some`) or to be learned (`None`).
    pub const fn new(pinned_interval_s: Option<f64>) -> TimeGrid {
        TimeGrid {
            interval_s: pinned_interval_s,
            pinned: pinned_interval_s.is_some(),
            last_stamp_s: None,
            base_s: 0.0,
            interval32_s: 0.0,
            lead32_s: 0.0,
            last_rel32_s: 0.0,
            stamps_s: [0.0; LEARNING_STAMPS],
            learned: 0,
            tracked: 0,
            mean_square32_s2: 0.0,
            pending32_s: 0.0,
            clock_steps: 0,
        }
    }

    fn ready(&self) -> bool {
        self.learned as usize >= LEARNING_STAMPS
    }

    /// Where `time_s` falls, or why the stamp is rejected. Changes nothing (see [`TimeGrid::accept`]).
    pub fn place(&self, time_s: f64) -> Result<Placed, SampleError> {
        if !self.ready() {
            return self.place_learning(time_s);
        }
        // The one double-precision operation of the usual stamp.
        let rel64 = time_s - self.base_s;
        let rel = rel64 as f32;
        let t = self.interval32_s;
        let e = rel - self.lead32_s;
        if rel > self.last_rel32_s && e < FAST_PATH_INTERVALS * t {
            let r1 = e - t;
            let (n, r) = if r1.abs() <= 0.5 * t || r1.abs() <= (0.5 + self.widening()) * t {
                (1.0, r1)
            } else {
                // After lost rows (or a stamp far off): one division.
                let n = libm::roundf(e / t);
                (n, e - n * t)
            };
            if n >= 1.0 {
                return Ok(self.on_grid(n as u32, r, rel, true));
            }
        }
        self.place_slow(time_s, rel64)
    }

    /// The long way, in double precision: a long gap, a stamp not after the previous one, or
    /// one in a slot at or before the last.
    fn place_slow(&self, time_s: f64, rel64: f64) -> Result<Placed, SampleError> {
        let t = f64::from(self.interval32_s);
        let last = self.last_stamp_s.unwrap_or(time_s);
        if time_s > last {
            let e = rel64 - f64::from(self.lead32_s);
            let n = libm::round(e / t);
            if n > f64::from(u32::MAX) {
                // Beyond four billion intervals (136 years at 1 Hz) a stamp names no slot (its
                // residual is lost in the rounding): a clock jump, re-anchored at the stamp.
                return Ok(Placed::CLOCK_STEP);
            }
            if n >= 1.0 {
                return Ok(self.on_grid(n as u32, (e - n * t) as f32, rel64 as f32, false));
            }
            let r1 = e - t;
            if r1.abs() <= (0.5 + f64::from(self.widening())) * t {
                return Ok(self.on_grid(1, r1 as f32, rel64 as f32, false));
            }
            return Err(SampleError::IrregularTimeStep);
        }
        // The step back itself, not `last - 2 t`: two stamps near each other subtract exactly,
        // where `last - 2 t` rounds at large stamps (beyond 1.8e16 s, where stamps are 4 s
        // apart, it would refuse a stamp 4 s back as not increasing).
        if last - time_s > CLOCK_STEP_BACK_INTERVALS * t {
            return Ok(Placed::CLOCK_STEP);
        }
        Err(SampleError::TimeNotIncreasing)
    }

    /// A stamp `n` slots on with residual `r`: on the grid, or a clock jump when it and the
    /// previous stamp are both off the grid on the same side.
    fn on_grid(&self, n: u32, r: f32, rel: f32, fast: bool) -> Placed {
        let t = self.interval32_s;
        // Off: |r| > 4 RMS + 0.05 T (+ 3 sigma of the prediction across lost rows), compared
        // squared (no square root on the usual path); never when that tolerance reaches half an
        // interval (jitter that large hides any jump).
        let across = if n > 1 {
            3.0 * libm::sqrtf(self.gap_variance(n))
        } else {
            0.0
        };
        let beyond = r.abs() - 0.05 * t - across;
        let off = beyond > 0.0
            && beyond * beyond > 16.0 * self.mean_square32_s2
            && 16.0 * self.mean_square32_s2 < 0.2025 * t * t;
        let jump = off && self.pending32_s != 0.0 && (self.pending32_s > 0.0) == (r > 0.0);
        Placed {
            placement: if jump {
                Placement::ClockStep
            } else {
                Placement::OnGrid { intervals: n }
            },
            rel_s: rel,
            residual_s: r,
            fast,
            off,
            restart: false,
        }
    }

    /// The variance of the grid's prediction `n` slots on that its interval's uncertainty adds,
    /// s^2: `n^2` times the variance of a least-squares slope through the stamps followed,
    /// `12 RMS^2 / m^3`.
    fn gap_variance(&self, n: u32) -> f32 {
        let m = self.tracked.max(1) as f32;
        let n = n as f32;
        n * n * 12.0 * self.mean_square32_s2 / (m * m * m)
    }

    /// How far, in intervals, beyond half an interval a stamp is still taken for the next slot:
    /// what three times the uncertainty of the grid's prediction (twice the residuals' RMS over
    /// the square root of the stamps it has followed) adds to jitter of 0.45 intervals, at most
    /// 0.4.
    fn widening(&self) -> f32 {
        let m = self.tracked.max(1) as f32;
        let sigma = 2.0 * libm::sqrtf(self.mean_square32_s2 / m);
        (3.0 * sigma / self.interval32_s - 0.05).clamp(0.0, 0.4)
    }

    fn place_learning(&self, time_s: f64) -> Result<Placed, SampleError> {
        let Some(last) = self.last_stamp_s else {
            return Ok(Placed::learning(0.0, true));
        };
        // With the interval pinned, a stamp is judged against it while the phase is learned, as
        // on the grid: far back, a clock step (learning starts again at it); less than half an
        // interval on, a repeated row.
        if let (true, Some(interval)) = (self.pinned, self.interval_s) {
            let dt = time_s - last;
            if dt < -CLOCK_STEP_BACK_INTERVALS * interval {
                return Ok(Placed::learning(0.0, true));
            }
            if dt > 0.0 && dt < 0.5 * interval {
                return Err(SampleError::IrregularTimeStep);
            }
        }
        if !(time_s > last) {
            return Err(SampleError::TimeNotIncreasing);
        }
        let rel = time_s - self.base_s;
        Ok(if self.learned == 0 || rel > MAX_LEARNING_OFFSET_S {
            Placed::learning(0.0, true)
        } else {
            Placed::learning(rel as f32, false)
        })
    }

    /// Records an accepted stamp placed by [`TimeGrid::place`].
    pub fn accept(&mut self, time_s: f64, placed: Placed) {
        self.last_stamp_s = Some(time_s);
        match placed.placement {
            Placement::Learning => {
                if placed.restart {
                    self.base_s = time_s;
                    self.stamps_s = [0.0; LEARNING_STAMPS];
                    self.learned = 1;
                } else if let Some(slot) = self.stamps_s.get_mut(self.learned as usize) {
                    *slot = placed.rel_s;
                    self.learned += 1;
                }
                if self.ready() {
                    self.learn();
                }
            }
            Placement::OnGrid { intervals } => self.follow(time_s, intervals, &placed),
            Placement::ClockStep => {
                self.clock_steps = self.clock_steps.saturating_add(1);
                // Re-anchored at this stamp; after a jump, its slot is where the two stamps off
                // the old grid put the new phase (the mean of their residuals).
                let stamp_less_slot = if placed.off {
                    0.5 * (placed.residual_s - self.pending32_s)
                } else {
                    0.0
                };
                self.base_s = time_s;
                self.lead32_s = -stamp_less_slot;
                self.last_rel32_s = 0.0;
                self.pending32_s = 0.0;
                self.tracked = self.tracked.min(TRACKING_START);
            }
        }
    }

    /// Follows the clock with a stamp placed `n` slots on.
    fn follow(&mut self, time_s: f64, n: u32, placed: &Placed) {
        let r = placed.residual_s;
        let m = self.tracked;
        let (alpha, beta) = if m >= TRACKING_MEMORY {
            HELD_GAINS
        } else {
            let mf = m.max(1) as f32;
            let inv = 1.0 / (mf * (mf + 1.0));
            (2.0 * (2.0 * mf - 1.0) * inv, 6.0 * inv)
        };
        // Across lost rows the prediction is the less certain the longer the gap: the phase moves
        // by the weight of its uncertainty against the stamp's (a Kalman gain).
        let alpha = if n > 1 {
            let v = self.gap_variance(n);
            alpha.max(v / (v + self.mean_square32_s2))
        } else {
            alpha
        };
        // A stamp off the grid moves nothing: it may be the first of a clock jump.
        let alpha = if placed.off { 0.0 } else { alpha };
        let stamp_less_slot = r - alpha * r;
        if placed.fast {
            self.lead32_s = placed.rel_s - stamp_less_slot;
            self.last_rel32_s = placed.rel_s;
        } else {
            self.base_s = time_s - f64::from(stamp_less_slot);
            self.lead32_s = 0.0;
            self.last_rel32_s = stamp_less_slot;
        }
        if placed.off {
            self.pending32_s = r;
            return;
        }
        self.pending32_s = 0.0;
        self.interval32_s += if n == 1 {
            beta * r
        } else {
            beta * r / n as f32
        };
        if let (true, Some(nominal)) = (self.pinned, self.interval_s) {
            // Compared, not `clamp`ed: `clamp`'s check of its bounds is a panic path (and its
            // message's float formatting brings the float formatter into the image:
            // docs/firmware.md, "Measured figures").
            let nominal = nominal as f32;
            let (low, high) = (
                nominal * (1.0 - PINNED_INTERVAL_TOLERANCE),
                nominal * (1.0 + PINNED_INTERVAL_TOLERANCE),
            );
            if self.interval32_s < low {
                self.interval32_s = low;
            } else if self.interval32_s > high {
                self.interval32_s = high;
            }
        }
        let g = if m >= 256 {
            1.0 / 256.0
        } else {
            1.0 / (m.max(1) as f32)
        };
        self.mean_square32_s2 += g * (r * r - self.mean_square32_s2);
        self.tracked = (m + 1).min(TRACKING_MEMORY);
        if self.lead32_s > REBASE_INTERVALS * self.interval32_s {
            self.base_s += f64::from(self.lead32_s);
            self.last_rel32_s -= self.lead32_s;
            self.lead32_s = 0.0;
            if !self.pinned {
                self.interval_s = Some(f64::from(self.interval32_s));
            }
        }
    }

    /// The grid from the learning stamps (docs/real-logs.md, "Time stamps"): the interval, the
    /// phase, the residuals' spread. Learning starts again at the last stamp if they give no
    /// positive interval.
    fn learn(&mut self) {
        let x = &self.stamps_s;
        let mut steps = [0.0f32; LEARNING_STAMPS - 1];
        for (i, s) in steps.iter_mut().enumerate() {
            *s = x[i + 1] - x[i];
        }
        let pinned = match self.interval_s {
            Some(pinned) if self.pinned => Some(pinned as f32),
            _ => None,
        };
        let t0 = pinned.unwrap_or_else(|| median(&mut steps.clone()));
        let mut work = [0.0f32; LEARNING_STAMPS];
        let mut singles = 0;
        // `get_mut` and the bounded count: no index the compiler cannot prove, no panic path.
        for s in steps.iter().filter(|s| **s < 1.5 * t0) {
            if let Some(w) = work.get_mut(singles) {
                *w = (s - t0).abs();
                singles += 1;
            }
        }
        let mad = median(&mut work[..singles.min(LEARNING_STAMPS)]);
        let mut longest_single = (1.1 + 4.5 * mad / t0).clamp(1.25, 2.0);
        let mut k = [0.0f32; LEARNING_STAMPS];
        for i in 1..LEARNING_STAMPS {
            let s = steps[i - 1];
            k[i] = k[i - 1]
                + if s < longest_single * t0 {
                    1.0
                } else {
                    libm::roundf(s / t0).max(1.0)
                };
        }
        let (mut a, mut t) = line(x, &k, pinned);
        for _ in 0..3 {
            if !(t > 0.0 && t.is_finite()) {
                break;
            }
            for i in 0..LEARNING_STAMPS {
                work[i] = (x[i] - a - k[i] * t).abs();
            }
            let jitter = 2.0 * median(&mut work);
            longest_single = (1.05 + 2.2 * jitter / t).clamp(1.25, 2.0);
            let mut k2 = [0.0f32; LEARNING_STAMPS];
            for i in 1..LEARNING_STAMPS {
                k2[i] = if steps[i - 1] < longest_single * t {
                    k2[i - 1] + 1.0
                } else {
                    libm::roundf((x[i] - a) / t).max(k2[i - 1] + 1.0)
                };
            }
            if k2 == k {
                break;
            }
            k = k2;
            (a, t) = line(x, &k, pinned);
        }
        if !(t > 0.0 && t.is_finite() && a.is_finite()) {
            let last = x[LEARNING_STAMPS - 1];
            self.base_s += f64::from(last);
            self.stamps_s = [0.0; LEARNING_STAMPS];
            self.learned = 1;
            return;
        }
        let mut square_sum = 0.0;
        for i in 0..LEARNING_STAMPS {
            let r = x[i] - a - k[i] * t;
            square_sum += r * r;
        }
        self.interval32_s = t;
        if !self.pinned {
            self.interval_s = Some(f64::from(t));
        }
        self.lead32_s = a + k[LEARNING_STAMPS - 1] * t;
        self.last_rel32_s = x[LEARNING_STAMPS - 1];
        self.tracked = TRACKING_START;
        // At least a microsecond of jitter: a clock step's tolerance is never zero.
        self.mean_square32_s2 = (square_sum / LEARNING_STAMPS as f32).max(1e-12);
        self.pending32_s = 0.0;
    }
}

/// The least-squares line `x = a + k t` through the points, `(a, t)`; with the slope `pinned`,
/// only `a` is fitted (the mean of `x - k t`).
fn line(x: &[f32; LEARNING_STAMPS], k: &[f32; LEARNING_STAMPS], pinned: Option<f32>) -> (f32, f32) {
    let n = LEARNING_STAMPS as f32;
    let mk = k.iter().sum::<f32>() / n;
    let mx = x.iter().sum::<f32>() / n;
    if let Some(t) = pinned {
        return (mx - t * mk, t);
    }
    let (mut skk, mut skx) = (0.0f32, 0.0f32);
    for i in 0..LEARNING_STAMPS {
        skk += (k[i] - mk) * (k[i] - mk);
        skx += (k[i] - mk) * (x[i] - mx);
    }
    let t = skx / skk;
    (mx - t * mk, t)
}

/// Median of a small slice, sorted in place (insertion sort); 0 for none.
fn median(v: &mut [f32]) -> f32 {
    for i in 1..v.len() {
        let mut j = i;
        // A pair of neighbours by pattern, not by index: no bound left for the optimiser to prove.
        while let Some([a, b]) = j.checked_sub(1).and_then(|k| v.get_mut(k..=j)) {
            if *a <= *b {
                break;
            }
            core::mem::swap(a, b);
            j -= 1;
        }
    }
    // `get`, not indexing: the optimiser does not prove `n / 2 - 1 < n`, and an index it cannot
    // prove leaves a panic path in the C library.
    let n = v.len();
    let at = |i: usize| v.get(i).copied().unwrap_or(0.0);
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => at(n / 2),
        _ => 0.5 * (at(n / 2 - 1) + at(n / 2)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// A recorder's stamps: sample `k` (of those kept) at `t0 + k T (1 + fast)` plus uniform
    /// jitter of +-`jitter` intervals, from a fixed pseudo-random sequence.
    struct Log {
        /// The generator's true index of each stamp.
        index: Vec<u64>,
        stamp_s: Vec<f64>,
    }

    fn uniform(state: &mut u64) -> f64 {
        // xorshift64*: reproducible, no dependency.
        *state ^= *state >> 12;
        *state ^= *state << 25;
        *state ^= *state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn log(t0: f64, interval_s: f64, jitter: f64, fast: f64, lost: &dyn Fn(u64) -> bool) -> Log {
        let mut state = 0x9E37_79B9_7F4A_7C15u64 ^ (interval_s * 1e6) as u64;
        let mut index = Vec::new();
        let mut stamp_s = Vec::new();
        for k in 0..20_000u64 {
            let j = jitter * (2.0 * uniform(&mut state) - 1.0);
            if lost(k) {
                continue;
            }
            index.push(k);
            stamp_s.push(t0 + (k as f64 + j) * interval_s * (1.0 + fast));
        }
        Log { index, stamp_s }
    }

    fn run(grid: &mut TimeGrid, stamps: &[f64]) -> Vec<Result<Placement, SampleError>> {
        stamps
            .iter()
            .map(|&t| {
                let p = grid.place(t)?;
                grid.accept(t, p);
                Ok(p.placement)
            })
            .collect()
    }

    /// Every stamp after the learning ones placed exactly as many intervals after the previous
    /// one as the generator's indices say, none a clock step.
    fn assert_every_stamp_in_its_slot(log: &Log, placed: &[Result<Placement, SampleError>]) {
        for (i, p) in placed.iter().enumerate() {
            if i < LEARNING_STAMPS {
                assert_eq!(*p, Ok(Placement::Learning), "stamp {i}");
                continue;
            }
            let intervals = (log.index[i] - log.index[i - 1]) as u32;
            assert_eq!(
                *p,
                Ok(Placement::OnGrid { intervals }),
                "stamp {i} (index {})",
                log.index[i]
            );
        }
    }

    /// Rows lost: one here and there, and runs of 2 to 40, none among the learning stamps.
    fn lost(k: u64) -> bool {
        (k > 40 && (k.is_multiple_of(97) || k.is_multiple_of(101)))
            || (k % 1000 >= 500 && k % 1000 < 500 + 2 + (k / 1000) % 39)
    }

    #[test]
    fn stamps_jittered_by_045_of_the_interval_with_lost_rows_and_a_fast_clock_land_in_their_slots()
    {
        for interval_s in [1.0, 0.1] {
            for pinned in [None, Some(interval_s)] {
                let log = log(1.7e9, interval_s, 0.45, 1e-3, &lost);
                let mut grid = TimeGrid::new(pinned);
                let placed = run(&mut grid, &log.stamp_s);
                assert_every_stamp_in_its_slot(&log, &placed);
                assert_eq!(grid.clock_steps, 0);
                // The grid follows the clock: its interval 0.1 % long, its phase a few hundredths
                // of the jitter off.
                let t = f64::from(grid.interval32_s);
                assert!(
                    (t / (interval_s * 1.001) - 1.0).abs() < 2e-5,
                    "{interval_s} {pinned:?}: {t}"
                );
                let rms = f64::from(grid.mean_square32_s2).sqrt() / interval_s;
                assert!(
                    (rms - 0.45 / 3f64.sqrt()).abs() < 0.03,
                    "residual RMS {rms}"
                );
                match pinned {
                    Some(p) => assert_eq!(grid.interval_s(), Some(p)),
                    None => assert!((grid.interval_s().unwrap() / t - 1.0).abs() < 1e-4),
                }
            }
        }
    }

    #[test]
    fn lost_rows_among_the_learning_stamps_are_counted() {
        // Moderate jitter, rows 3, 5 and 6 lost while learning, 12 to 13 just after: while the
        // grid is young a stamp after lost rows may land a slot off (its data go with it: the
        // sample is a second early or late, nothing more); never further, never a clock step or
        // a refused row, and nearly every stamp in its slot.
        let lost_early = |k: u64| k == 3 || k == 5 || k == 6 || (12..14).contains(&k) || lost(k);
        for interval_s in [1.0, 0.1] {
            let log = log(12_345.0, interval_s, 0.2, 1e-3, &lost_early);
            let mut grid = TimeGrid::new(None);
            let placed = run(&mut grid, &log.stamp_s);
            assert_eq!(grid.clock_steps, 0);
            let mut off_slot = 0;
            for (i, p) in placed.iter().enumerate().skip(LEARNING_STAMPS) {
                let intervals = (log.index[i] - log.index[i - 1]) as i64;
                let Ok(Placement::OnGrid { intervals: got }) = p else {
                    panic!("stamp {i}: {p:?}");
                };
                let off = i64::from(*got) - intervals;
                assert!(off.abs() <= 1, "stamp {i}: {off}");
                off_slot += usize::from(off != 0);
            }
            assert!(
                off_slot * 1000 <= placed.len(),
                "{off_slot} of {}",
                placed.len()
            );
        }
    }

    #[test]
    fn a_clock_jump_and_a_clock_step_back_are_each_counted_once() {
        let interval_s = 1.0;
        let mut log = log(1.7e9, interval_s, 0.1, 0.0, &|_| false);
        // +3.7 s from stamp 3000 on, -100 s from stamp 8000 on.
        for (i, t) in log.stamp_s.iter_mut().enumerate() {
            if i >= 3000 {
                *t += 3.7;
            }
            if i >= 8000 {
                *t -= 100.0;
            }
        }
        let mut grid = TimeGrid::new(None);
        let placed = run(&mut grid, &log.stamp_s);
        assert_eq!(grid.clock_steps, 2);
        let steps: Vec<usize> = (0..placed.len())
            .filter(|i| placed[*i] == Ok(Placement::ClockStep))
            .collect();
        // The jump is seen at the second stamp off the grid (the first is placed in its nearest
        // slot); the step back at once.
        assert!(steps[0] == 3000 || steps[0] == 3001, "{steps:?}");
        assert_eq!(steps[1], 8000);
        // Everything else in its slot.
        for (i, p) in placed.iter().enumerate().skip(LEARNING_STAMPS) {
            if steps.contains(&i) || i == 3000 {
                continue;
            }
            assert_eq!(*p, Ok(Placement::OnGrid { intervals: 1 }), "stamp {i}");
        }
        // With jitter of +-0.45 intervals a step back is still seen at once.
        let mut log = log_045_step_back();
        let mut grid = TimeGrid::new(Some(1.0));
        let placed = run(&mut grid, &log.stamp_s);
        assert_eq!(grid.clock_steps, 1);
        assert_eq!(placed[5000], Ok(Placement::ClockStep));
        log.stamp_s.clear();
    }

    fn log_045_step_back() -> Log {
        let mut log = log(1.7e9, 1.0, 0.45, 0.0, &|_| false);
        for t in log.stamp_s.iter_mut().skip(5000) {
            *t -= 100.0;
        }
        log
    }

    #[test]
    fn repeated_and_out_of_order_rows_are_refused_and_change_nothing() {
        let log = log(1.7e9, 0.1, 0.45, 0.0, &|_| false);
        let mut grid = TimeGrid::new(None);
        run(&mut grid, &log.stamp_s[..2000]);
        let before = grid;
        let last = log.stamp_s[1999];
        assert_eq!(grid.place(last), Err(SampleError::TimeNotIncreasing));
        assert_eq!(grid.place(last - 0.01), Err(SampleError::TimeNotIncreasing));
        assert_eq!(
            grid.place(log.stamp_s[1998]),
            Err(SampleError::TimeNotIncreasing)
        );
        // Later than the last stamp, but in its slot (or before it): a stamp of no new slot.
        let slot_of_last = grid.base_s + f64::from(grid.lead32_s);
        let later_in_same_slot = last.max(slot_of_last) + 0.01;
        assert_eq!(
            grid.place(later_in_same_slot).map(|p| p.placement),
            Err(SampleError::IrregularTimeStep)
        );
        assert_eq!(grid, before, "placing changes nothing");
        // During learning too.
        let mut grid = TimeGrid::new(None);
        run(&mut grid, &log.stamp_s[..5]);
        assert_eq!(
            grid.place(log.stamp_s[4]),
            Err(SampleError::TimeNotIncreasing)
        );
        // The next row is placed as usual.
        let mut grid = before;
        assert_eq!(
            run(&mut grid, &log.stamp_s[2000..2001]),
            [Ok(Placement::OnGrid { intervals: 1 })]
        );
    }

    #[test]
    fn long_gaps_on_a_fast_clock_keep_the_slots() {
        // An hour lost at +-0.1 intervals of jitter, a day at +-0.02: the interval followed over
        // the last thousand stamps to a few parts in a million still names the slot after it.
        for (jitter, gap) in [(0.1, 3_600u64), (0.02, 86_400)] {
            let ahead = 5_000u64;
            let stamp = |k: u64, state: &mut u64| {
                1.7e9 + (k as f64 + jitter * (2.0 * uniform(state) - 1.0)) * 1.001
            };
            let mut state = 7u64;
            let mut stamps: Vec<f64> = (0..ahead).map(|k| stamp(k, &mut state)).collect();
            stamps.extend((ahead + gap..ahead + gap + 100).map(|k| stamp(k, &mut state)));
            let mut grid = TimeGrid::new(None);
            let placed = run(&mut grid, &stamps);
            assert_eq!(
                placed[ahead as usize],
                Ok(Placement::OnGrid {
                    intervals: gap as u32 + 1
                }),
                "{gap}"
            );
            for (i, p) in placed.iter().enumerate().skip(ahead as usize + 1) {
                assert_eq!(*p, Ok(Placement::OnGrid { intervals: 1 }), "{gap}: {i}");
            }
            assert_eq!(grid.clock_steps, 0);
        }
    }
}
