//! The first estimate: the weights the first windows enter the filter with, and when their
//! estimate is reported.
//!
//! # Why weights
//! After `N` equally weighted windows of one period `W` (boxcars), the filter's weight on the
//! products is the trapezoid `g = rect_W * rect_N`, whose kinks let a sway of angular frequency `w`
//! through by `|G(w)| / G(0) <= 4 / (w^2 W N)` for `w N >> 1`: nothing long after the start, but
//! the first estimate is due within 1.25 periods, after a few tens of windows.
//!
//! # Bumps
//! So the first windows enter with the weights of a bump: the `k`-th window of a bump of `L`
//! windows with `w(u) = 30 u^2 (1 - u)^2`, `u = k / L` (its variance `r / w`). Its mean is 1, the
//! information of equal weights; it is zero with a zero slope at both ends, so `g = rect_W * w` has
//! a continuous second derivative and the leakage falls like `1 / w^4`. A bump's newest windows
//! carry most of its weight until it ends, so its estimate is reported at its end and held until
//! the next ends. The bumps double until they span a quarter of a period of windows; then the
//! weights rise to 1 over twice the last bump's length (`3 u^2 - 2 u^3`: a step would be a kink of
//! `g`), the estimate reported at every update from the last bump's end on.
//!
//! # The first bump's length
//! It ends when the first estimate is due: when the newest entry is 1.25 periods from the window's
//! first, less the rows not yet turned into entries ([`ROWS_BEHIND`]); at least a sixteenth of a
//! period, at most a quarter; the rows behind counted in bins for a window of bins that holds
//! the samples gathered while the period was learned (binned as the expected period needs,
//! [`crate::moving_average::CorrelationWindow::expect_bin`]). A window of bins emptied when the
//! period came (it needs other bins) has no earlier samples: its first bump is a sixteenth.
//!
//! # Restarts
//! A window restarted during the bumps begins them again at its next full window, the estimate
//! held meanwhile. A checkpoint keeps whether the bumps go on and the estimate held (two bits of
//! the windowed method's flag byte), so a restore in the bumps does the same, and one after them
//! (the rise included) takes equal weights at once.
//!
//! The derivation: docs/method.md, "The first windows"; what the first estimate is worth:
//! docs/real-logs.md, "The rotation pattern" (pinned by `host-sim/tests/replay/gap_logs.rs`).

use crate::gap_fill::DELAY;
use crate::time_grid::LEARNING_STAMPS;
use crate::Real;

/// What the start needs of the window: its entries in a full window, its samples per entry, and
/// whether a window of bins holds the samples gathered while the period was learned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Entries in a full window.
    pub len: u32,
    /// Samples per entry.
    pub bin: u32,
    /// Whether its entries go back to before the period was known.
    pub from_learning: bool,
}

impl Layout {
    /// A window of one sample an entry (entries from the first row on).
    pub const fn samples(len: u32) -> Layout {
        Layout {
            len,
            bin: 1,
            from_learning: true,
        }
    }
}

/// Rows the estimator has not turned into window entries when a row arrives: the filler's delay
/// and the stamps the grid's interval and phase are learned from ([`LEARNING_STAMPS`]).
pub const ROWS_BEHIND: u32 = DELAY + LEARNING_STAMPS as u32;

/// The smallest weight a window is taken with (a bump's ends are 0): its variance 65,536 times a
/// window's.
pub const MIN_WEIGHT: Real = 1.0 / 65_536.0;

/// Where the windows' weights stand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StartTaper {
    /// No window taken since the filter started afresh: the first full window begins the bumps
    /// (or, for a filter restored with windows taken, equal weights).
    Fresh,
    /// The window restarted during the bumps: its next full window begins them again. `held`:
    /// a bump had ended (its estimate is held).
    Restarted {
        /// Whether a bump had ended (its estimate is held).
        held: bool,
    },
    /// In a bump: the window numbers of the first bump's first window and of this bump's, this
    /// bump's length in windows, and whether a bump has ended (its estimate is held).
    Bumps {
        /// The window number of the first bump's first window.
        first: u32,
        /// The window number of this bump's first window.
        start: u32,
        /// This bump's length, windows.
        len: u32,
        /// Whether a bump has ended (its estimate is held).
        held: bool,
    },
    /// After the bumps, the weights rising to 1 over `len` windows from window `start`, the
    /// estimate reported at every update.
    Rise {
        /// The window number the rise starts from.
        start: u32,
        /// The rise's length, windows.
        len: u32,
    },
    /// Equal weights, the estimate reported at every update.
    Done,
}

/// A window's weight and whether its estimate is to be reported.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weight {
    /// In `[0, 1.875]` in a bump, `[0, 1]` in the rise, then 1: the window's variance is divided
    /// by it.
    pub value: Real,
    /// This window ends a bump: the estimate after it is the one to report until the next does.
    pub ends_bump: bool,
}

impl StartTaper {
    /// The weight of a bump at `k` of `len` windows: `30 u^2 (1 - u)^2`, `u = k / len`.
    pub fn bump(k: u32, len: u32) -> Real {
        let u = k as Real / len.max(1) as Real;
        let v = u * (1.0 - u);
        30.0 * v * v
    }

    /// The weight at `k` of a rise of `len` windows from 0 to 1: `3 u^2 - 2 u^3`, `u = k / len`.
    pub fn rise(k: u32, len: u32) -> Real {
        let u = k as Real / len.max(1) as Real;
        u * u * (3.0 - 2.0 * u)
    }

    /// The length of the first bump, windows, for a window of `len` entries of `bin` samples whose
    /// first entry is number `first`, first full at number `newest`; `from_learning` when a window
    /// of bins holds the samples gathered while the period was learned (see the module doc).
    pub fn first_bump_len(first: u32, newest: u32, len: u32, bin: u32, from_learning: bool) -> u32 {
        let behind = ROWS_BEHIND.div_ceil(bin.max(1));
        let due = first.wrapping_add(len + len / 4).wrapping_sub(behind);
        // A due number already passed wraps to a huge number: the shortest bump, as with a window
        // of bins that starts empty when its period is known.
        let left = if bin > 1 && !from_learning {
            0
        } else {
            due.wrapping_sub(newest)
        };
        let left = if left > len { 0 } else { left };
        left.min(len / 4).max(len / 16).max(1)
    }

    /// Whether the estimate reported is the one held at the end of the last bump (none before
    /// the first ends).
    #[inline]
    pub fn holds(&self) -> bool {
        matches!(
            self,
            StartTaper::Bumps { .. } | StartTaper::Restarted { .. }
        )
    }

    /// Whether a bump has ended, while the bumps go on: there is an estimate held.
    pub fn has_held(&self) -> bool {
        matches!(
            self,
            StartTaper::Bumps { held: true, .. } | StartTaper::Restarted { held: true }
        )
    }

    /// The window restarted: bumps begin again at its next full window.
    pub fn restart(&mut self) {
        if let StartTaper::Bumps { held, .. } = *self {
            *self = StartTaper::Restarted { held };
        }
    }

    /// The weight of the window numbered `newest` of a full window of `len` entries of `bin`
    /// samples whose first entry is numbered `first`; `cold` when the filter has taken no window
    /// yet.
    // On the step's path: the usual case (done) inlined, the start out of line.
    #[inline]
    pub fn weight(&mut self, newest: u32, first: u32, window: Layout, cold: bool) -> Weight {
        if let StartTaper::Done = self {
            return Weight {
                value: 1.0,
                ends_bump: false,
            };
        }
        self.weight_at_start(newest, first, window, cold)
    }

    /// [`StartTaper::weight`] before the weights are done.
    #[inline(never)]
    fn weight_at_start(&mut self, newest: u32, first: u32, window: Layout, cold: bool) -> Weight {
        let Layout {
            len,
            bin,
            from_learning,
        } = window;
        let (value, ends_bump) = match *self {
            StartTaper::Fresh if !cold => {
                *self = StartTaper::Done;
                (1.0, false)
            }
            // A bump's first window has weight 0.
            StartTaper::Fresh | StartTaper::Restarted { .. } => {
                *self = StartTaper::Bumps {
                    first: newest,
                    start: newest,
                    len: Self::first_bump_len(first, newest, len, bin, from_learning),
                    held: self.has_held(),
                };
                (0.0, false)
            }
            StartTaper::Bumps {
                first: begun,
                start,
                len: bump,
                ..
            } => {
                let k = newest.wrapping_sub(start);
                if k < bump {
                    (Self::bump(k, bump), false)
                } else {
                    // This window ends the bump (a run of lost rows may have skipped past its
                    // end): its weight is 0, and it begins the next bump, twice as long, until
                    // the bumps span a quarter of a period; then the rise, over twice the last
                    // bump.
                    let next = bump.saturating_mul(2);
                    *self = if newest.wrapping_sub(begun) >= len / 4 {
                        StartTaper::Rise {
                            start: newest,
                            len: next,
                        }
                    } else {
                        StartTaper::Bumps {
                            first: begun,
                            start: newest,
                            len: next,
                            held: true,
                        }
                    };
                    (0.0, true)
                }
            }
            StartTaper::Rise { start, len: rise } => {
                let k = newest.wrapping_sub(start);
                if k < rise {
                    (Self::rise(k, rise), false)
                } else {
                    *self = StartTaper::Done;
                    (1.0, false)
                }
            }
            StartTaper::Done => (1.0, false),
        };
        Weight { value, ends_bump }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bump_has_mean_one_and_is_zero_at_its_ends() {
        for len in [8u32, 24, 45, 90] {
            let sum: Real = (0..len).map(|k| StartTaper::bump(k, len)).sum();
            assert!((sum / len as Real - 1.0).abs() < 0.02, "{len}: {sum}");
            assert_eq!(StartTaper::bump(0, len), 0.0);
            // Zero slope at the ends: the first window's weight is of order 1/len^2.
            assert!(StartTaper::bump(1, len) <= 30.0 / (len * len) as Real);
            assert!(StartTaper::bump(len - 1, len) <= 30.0 / (len * len) as Real);
        }
    }

    #[test]
    fn the_first_bump_ends_when_the_first_estimate_is_due() {
        // A 480-entry window from entry 0, first full at 492: due at 600 - ROWS_BEHIND.
        assert_eq!(
            StartTaper::first_bump_len(0, 492, 480, 1, true),
            600 - ROWS_BEHIND - 492
        );
        // Known late: a sixteenth of a period; early: at most a quarter.
        assert_eq!(StartTaper::first_bump_len(0, 440, 360, 1, true), 22);
        assert_eq!(StartTaper::first_bump_len(0, 280, 360, 1, true), 90);
        assert_eq!(StartTaper::first_bump_len(0, 1000, 360, 1, true), 22);
        // Bins from the period on (the window emptied when it came): a sixteenth. Bins that hold
        // the samples gathered while it was learned: due 1.25 periods from the first, the rows
        // behind counted in bins (at 10 Hz, 8 samples a bin: 600 entries a period, first full at
        // 610, due at 750 less the rows behind in bins, rounded up).
        assert_eq!(StartTaper::first_bump_len(0, 720, 720, 2, false), 45);
        assert_eq!(
            StartTaper::first_bump_len(0, 610, 600, 8, true),
            750 - ROWS_BEHIND.div_ceil(8) - 610
        );
    }

    #[test]
    fn bumps_double_until_a_quarter_period_then_the_weights_rise() {
        let mut t = StartTaper::Fresh;
        let mut ends = std::vec::Vec::new();
        let mut n = 400u32;
        // First entry 0, 360 entries, first full at 400: due at 410, ten windows: a sixteenth (22).
        loop {
            let w = t.weight(n, 0, Layout::samples(360), true);
            if w.ends_bump {
                assert_eq!(w.value, 0.0);
                ends.push(n - 400);
            }
            if let StartTaper::Rise { len, .. } = t {
                assert_eq!(len, 176);
                break;
            }
            assert!(t.holds());
            n += 1;
        }
        assert_eq!(ends, [22, 66, 154]);
        // Then the weights rise to 1 over twice the last bump's length, reported at every window.
        assert!(!t.holds());
        let w = t.weight(n + 88, 0, Layout::samples(360), true).value;
        assert!((w - 0.5).abs() < 1e-6, "{w}");
        assert_eq!(t.weight(n + 176, 0, Layout::samples(360), true).value, 1.0);
        assert_eq!(t, StartTaper::Done);
    }

    #[test]
    fn a_restored_filter_takes_equal_weights_and_a_restart_begins_the_bumps_again() {
        let mut t = StartTaper::Fresh;
        assert_eq!(t.weight(500, 0, Layout::samples(360), false).value, 1.0);
        assert_eq!(t, StartTaper::Done);
        let mut t = StartTaper::Fresh;
        t.weight(400, 0, Layout::samples(360), true);
        t.restart();
        assert_eq!(t, StartTaper::Restarted { held: false });
        assert!(t.holds() && !t.has_held());
        assert_eq!(t.weight(900, 500, Layout::samples(360), false).value, 0.0);
        assert!(matches!(
            t,
            StartTaper::Bumps {
                first: 900,
                held: false,
                ..
            }
        ));
        // After a bump ended, its estimate stays held through a restart.
        for n in 901..=922 {
            t.weight(n, 500, Layout::samples(360), false);
        }
        assert!(t.has_held());
        t.restart();
        assert_eq!(t, StartTaper::Restarted { held: true });
    }
}
