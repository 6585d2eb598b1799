//! The sample grid: places each time stamp on a grid of whole sample intervals.
//!
//! Real recorders stamp time from their own clocks: Unix or GPS seconds, jitter of tens of
//! milliseconds, dropped rows, now and then a clock step. The estimator needs only how many sample
//! intervals lie between two accepted samples (1 for consecutive samples, `n` after `n - 1` lost
//! ones); the stamps themselves are passed through to the output untouched.
//!
//! # The interval
//! Pinned by [`crate::Config::sample_interval_s`], or learned: the median of the first
//! [`LEARNING_STEPS`] positive time steps (a median, so that lost rows, which double a step, do not
//! move it while fewer than half the rows are lost), then refined to the mean of the last
//! [`REFINEMENT_STEPS`] steps that were one interval long, so that a recorder whose clock runs
//! 0.1 % fast stays on the grid across long gaps. The samples used to learn it are accepted but not
//! estimated from. (Only the grid's snapping uses the refined interval; what the estimator derives
//! from the interval is fixed when estimation starts, see [`crate::estimator::Feed`].)
//!
//! # Placing a stamp
//! With `dt` the step since the previous accepted stamp and `n = round(dt / interval)`:
//! - `n >= 1` and `|dt - n interval| <= interval / 4`: on the grid, `n - 1` samples missing. Jitter
//!   of up to +-10 % of the interval on each stamp (+-20 % on their difference) snaps;
//! - `n >= 1` but further off the grid: a clock jump. Accepted, counted, the grid re-anchored at
//!   this stamp, and treated as a gap the window cannot bridge;
//! - `dt` more than two intervals backwards: a clock step backwards. Accepted, counted,
//!   re-anchored and treated as a gap like a jump;
//! - otherwise (`dt <= 0`, or `0 < dt` below half an interval): a repeated or out-of-order row,
//!   rejected ([`SampleError::TimeNotIncreasing`], [`SampleError::IrregularTimeStep`]).

mod checkpoint;

use crate::sample::SampleError;

/// Positive time steps whose median gives the learned interval.
pub const LEARNING_STEPS: usize = 8;
/// One-interval steps averaged for each refinement of a learned interval (a power of two: the
/// mean is a multiplication, no division on the step's path).
pub const REFINEMENT_STEPS: u32 = 1024;

/// Largest distance of a step from a whole number of intervals that still snaps, in intervals.
pub const SNAP_TOLERANCE: f64 = 0.25;

/// How far back (in intervals) a stamp must go to be a clock step rather than a repeated row.
pub const CLOCK_STEP_BACK_INTERVALS: f64 = 2.0;

/// Where a stamp falls on the grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// The first stamp, or one of the stamps the interval is being learned from.
    Learning,
    /// `intervals` sample intervals after the previous accepted sample (1: the next sample).
    OnGrid { intervals: u32 },
    /// A clock jump or a clock step backwards: the grid is re-anchored here.
    ClockStep,
}

/// The grid's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeGrid {
    /// The interval, s, once pinned or learned.
    interval_s: Option<f64>,
    /// Whether the interval was pinned by the configuration (never refined).
    pinned: bool,
    /// The previous accepted stamp, s.
    last_stamp_s: Option<f64>,
    /// Positive steps seen while learning.
    learning_steps: [f64; LEARNING_STEPS],
    learned: u32,
    /// Sum and count of the one-interval steps of the refinement block being collected.
    step_sum_s: f64,
    steps: u32,
    /// Clock jumps and steps backwards seen.
    clock_steps: u32,
}

impl TimeGrid {
    /// The sample interval, pinned or learned; `None` while it is being learned.
    pub fn interval_s(&self) -> Option<f64> {
        self.interval_s
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
            learning_steps: [0.0; LEARNING_STEPS],
            learned: 0,
            step_sum_s: 0.0,
            steps: 0,
            clock_steps: 0,
        }
    }

    /// Where `time_s` falls, or why the stamp is rejected. Changes nothing (see [`TimeGrid::accept`]).
    pub fn place(&self, time_s: f64) -> Result<Placement, SampleError> {
        let Some(last) = self.last_stamp_s else {
            return Ok(Placement::Learning);
        };
        let dt = time_s - last;
        let Some(interval) = self.interval_s else {
            return if dt > 0.0 {
                Ok(Placement::Learning)
            } else {
                Err(SampleError::TimeNotIncreasing)
            };
        };
        // The usual case, in single precision (the M4F's FPU; f64 is software there): the step
        // and the interval are a few seconds, and a quarter interval of tolerance needs no more
        // than f32's 7 digits. Far from the edge of the tolerance it decides; near it, and for every
        // other case, f64 below.
        let (dt32, interval32) = (dt as f32, interval as f32);
        let off32 = (dt32 - interval32).abs();
        if off32 <= 0.9 * SNAP_TOLERANCE as f32 * interval32 {
            return Ok(Placement::OnGrid { intervals: 1 });
        }
        // Lost rows, the usual way (a gap of up to a day), in single precision when the step is
        // clearly on the grid: within 0.9 of the tolerance of a whole number of intervals. Only
        // for a step clearly longer than one interval plus its tolerance, so that none of the
        // checks below (one interval, a clock step back, a time not increasing) could hold: the
        // same answer as they would give, without their software f64 (some 250 instructions on
        // the Cortex-M4F, the step after every lost row).
        if dt32 > (1.0 + 1.1 * SNAP_TOLERANCE as f32) * interval32 && dt32 < 1.0e5 * interval32 {
            let n32 = libm::roundf(dt32 / interval32);
            if n32 >= 1.0
                && (dt32 - n32 * interval32).abs() <= 0.9 * SNAP_TOLERANCE as f32 * interval32
            {
                return Ok(Placement::OnGrid {
                    intervals: n32 as u32,
                });
            }
        }
        if (dt - interval).abs() <= SNAP_TOLERANCE * interval {
            return Ok(Placement::OnGrid { intervals: 1 });
        }
        if dt < -CLOCK_STEP_BACK_INTERVALS * interval {
            return Ok(Placement::ClockStep);
        }
        if !(dt > 0.0) {
            return Err(SampleError::TimeNotIncreasing);
        }
        let n = libm::round(dt / interval);
        if n < 1.0 {
            return Err(SampleError::IrregularTimeStep);
        }
        if (dt - n * interval).abs() > SNAP_TOLERANCE * interval {
            return Ok(Placement::ClockStep);
        }
        Ok(Placement::OnGrid {
            intervals: if n > u32::MAX as f64 {
                u32::MAX
            } else {
                n as u32
            },
        })
    }

    /// Records an accepted stamp placed by [`TimeGrid::place`].
    pub fn accept(&mut self, time_s: f64, placement: Placement) {
        let previous = self.last_stamp_s.replace(time_s);
        match placement {
            Placement::Learning => {
                if let Some(last) = previous {
                    let k = self.learned as usize;
                    if let Some(slot) = self.learning_steps.get_mut(k) {
                        *slot = time_s - last;
                    }
                    self.learned = self.learned.saturating_add(1);
                    if self.learned as usize >= LEARNING_STEPS {
                        self.interval_s = Some(median(&self.learning_steps));
                    }
                }
            }
            Placement::OnGrid { intervals: 1 } => {
                if let (false, Some(last)) = (self.pinned, previous) {
                    self.step_sum_s += time_s - last;
                    self.steps += 1;
                    if self.steps == REFINEMENT_STEPS {
                        self.interval_s =
                            Some(self.step_sum_s * (1.0 / f64::from(REFINEMENT_STEPS)));
                        self.step_sum_s = 0.0;
                        self.steps = 0;
                    }
                }
            }
            Placement::OnGrid { .. } => {}
            Placement::ClockStep => self.clock_steps = self.clock_steps.saturating_add(1),
        }
    }
}

/// Median of a small array (insertion sort of a copy).
fn median<const N: usize>(values: &[f64; N]) -> f64 {
    let mut v = *values;
    for i in 1..N {
        let mut j = i;
        while j > 0 && v[j - 1] > v[j] {
            v.swap(j - 1, j);
            j -= 1;
        }
    }
    match N {
        0 => 0.0,
        _ if N % 2 == 1 => v[N / 2],
        _ => 0.5 * (v[N / 2 - 1] + v[N / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(grid: &mut TimeGrid, stamps: &[f64]) -> std::vec::Vec<Result<Placement, SampleError>> {
        stamps
            .iter()
            .map(|&t| {
                let p = grid.place(t);
                if let Ok(p) = p {
                    grid.accept(t, p);
                }
                p
            })
            .collect()
    }

    #[test]
    fn learns_the_interval_through_lost_rows_and_jitter_and_snaps_unix_stamps() {
        let mut grid = TimeGrid::new(None);
        let t0 = 1.7e9;
        // 2 s interval, +-0.15 s of jitter, rows 3 and 6 lost.
        let jitter = [
            0.1, -0.15, 0.05, 0.0, 0.12, -0.08, 0.15, -0.1, 0.02, -0.12, 0.07, 0.0, 0.11, -0.03,
        ];
        let stamps: std::vec::Vec<f64> = (0..14)
            .filter(|k| *k != 3 && *k != 6)
            .map(|k| t0 + 2.0 * k as f64 + jitter[k])
            .collect();
        let placed = run(&mut grid, &stamps);
        assert!(placed[..9].iter().all(|p| *p == Ok(Placement::Learning)));
        // The median of 8 steps, two of them doubled by the lost rows and all with +-0.3 s of
        // jitter: within 10 %, well inside the quarter interval that snapping needs.
        let interval = grid.interval_s.unwrap();
        assert!((interval - 2.0).abs() < 0.2, "{interval}");
        assert_eq!(placed[9..], [Ok(Placement::OnGrid { intervals: 1 }); 3]);
        // A stamp 3 intervals on with jitter, then one 2.6 intervals on (a jump), then a repeat.
        let last = *stamps.last().unwrap();
        assert_eq!(
            grid.place(last + 6.1),
            Ok(Placement::OnGrid { intervals: 3 })
        );
        assert_eq!(grid.place(last + 5.2), Ok(Placement::ClockStep));
        assert_eq!(grid.place(last), Err(SampleError::TimeNotIncreasing));
        assert_eq!(grid.place(last + 0.5), Err(SampleError::IrregularTimeStep));
        assert_eq!(grid.place(last - 3600.0), Ok(Placement::ClockStep));
        assert_eq!(grid.place(last - 1.0), Err(SampleError::TimeNotIncreasing));
    }

    #[test]
    fn a_pinned_interval_needs_no_learning_and_is_never_refined() {
        let mut grid = TimeGrid::new(Some(1.0));
        let placed = run(&mut grid, &[10.0, 11.0, 12.02, 13.0, 16.0]);
        assert_eq!(placed[0], Ok(Placement::Learning));
        assert_eq!(placed[4], Ok(Placement::OnGrid { intervals: 3 }));
        assert_eq!(grid.interval_s, Some(1.0));
    }

    #[test]
    fn a_slow_clock_stays_on_the_grid_across_a_long_gap() {
        // The recorder's second is 1.003 s: after learning, a 200-row gap still snaps to 200.
        let mut grid = TimeGrid::new(None);
        let stamps: std::vec::Vec<f64> = (0..2000).map(|k| k as f64 * 1.003).collect();
        run(&mut grid, &stamps);
        assert_eq!(
            grid.place(2199.0 * 1.003),
            Ok(Placement::OnGrid { intervals: 200 })
        );
    }
}
