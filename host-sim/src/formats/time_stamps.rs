//! Time stamps as recorders write them, and whether their interval makes sense for a RINS.
//!
//! # Formats (the log's time column, see `docs/log-format.md`)
//! - `time_s`: seconds, any origin (log start, Unix or GPS seconds), plain decimal or scientific;
//! - `time_ms`: milliseconds, any origin;
//! - `time_utc`: ISO 8601 / RFC 3339 date and time, parsed with the `jiff` crate:
//!   `2024-05-01T12:00:00Z`, `2024-05-01T12:00:00.250+02:00`, `2024-05-01 12:00:00.25` (a space for
//!   the `T`; no offset is read as UTC). It becomes Unix seconds, which the estimates CSV writes in
//!   its `time_s` column.
//!
//! A cell of any time column that is a date and time is read as one (a `time_s` column holding
//! `2024-05-01T12:00:00Z` is read as it means); a number in `time_utc` is read as seconds.
//!
//! # The interval ([`IntervalCheck`])
//! The estimator learns the sample interval from the stamps (the median of the first 8 steps) and
//! accepts any; a RINS logs its attitude every 10 ms to 10 s. Stamps in another unit than their
//! column says give intervals outside that range (1000 "s" for milliseconds in `time_s`), and a
//! `--sample-interval` that contradicts the stamps makes every row a clock step: both are caught
//! after the first 8 steps, before any estimate is made, and told with their likely cause.
//!
//! A log at the navigation rate (100-200 Hz) read with `--bin-interval-s S` is averaged into bins
//! of S s before the estimator sees it (`estimator_core::binning`): its stamps may then step by
//! as little as 5 ms ([`BINNED_INTERVAL_S`]), and by no more than one bin
//! ([`IntervalCheck::binned`]). Without the option a log whose stamps step by 5 to 10 ms is
//! refused with that option named ([`IntervalError::NavigationRate`]).

use jiff::civil::DateTime;
use jiff::tz::TimeZone;
use jiff::Timestamp;

/// What a time column holds by its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimeColumn {
    /// `time_s`: seconds.
    Seconds,
    /// `time_ms`: milliseconds.
    Milliseconds,
    /// `time_utc`: ISO 8601 / RFC 3339 date and time.
    Utc,
}

impl TimeColumn {
    /// The time columns by name, in the order one is chosen when a log has several.
    pub const ALL: [TimeColumn; 3] = [
        TimeColumn::Seconds,
        TimeColumn::Milliseconds,
        TimeColumn::Utc,
    ];

    /// The column's name in a log header.
    pub fn name(self) -> &'static str {
        match self {
            TimeColumn::Seconds => "time_s",
            TimeColumn::Milliseconds => "time_ms",
            TimeColumn::Utc => "time_utc",
        }
    }

    /// Reads one cell (trimmed) as seconds.
    pub fn parse(self, cell: &str) -> Result<f64, String> {
        if looks_like_date(cell) {
            return parse_utc(cell);
        }
        let value: f64 = cell.parse().map_err(|_| {
            if cell.is_empty() {
                "blank cell".to_string()
            } else {
                format!("not a number: {cell:?}")
            }
        })?;
        Ok(match self {
            TimeColumn::Milliseconds => value / 1000.0,
            TimeColumn::Seconds | TimeColumn::Utc => value,
        })
    }
}

/// Whether a cell is a date (`YYYY-MM-DD...`) rather than a number.
fn looks_like_date(cell: &str) -> bool {
    let b = cell.as_bytes();
    b.len() >= 10 && b[..4].iter().all(u8::is_ascii_digit) && b[4] == b'-' && b[7] == b'-'
}

/// An ISO 8601 / RFC 3339 date and time as Unix seconds; without an offset, UTC.
pub fn parse_utc(cell: &str) -> Result<f64, String> {
    let timestamp = match cell.parse::<Timestamp>() {
        Ok(t) => t,
        Err(with_offset) => match cell.parse::<DateTime>() {
            Ok(civil) => TimeZone::UTC
                .to_timestamp(civil)
                .map_err(|e| format!("not a date and time: {cell:?}: {e}"))?,
            Err(_) => return Err(format!("not a date and time: {cell:?}: {with_offset}")),
        },
    };
    Ok(timestamp.as_second() as f64 + f64::from(timestamp.subsec_nanosecond()) * 1e-9)
}

/// A time in Unix seconds as an RFC 3339 UTC date and time to the millisecond, when it lies
/// between 1980 and 2100 (a log's stamps that are Unix or ISO time); `None` otherwise (seconds
/// since the log's start).
pub fn format_utc(unix_s: f64) -> Option<String> {
    const Y1980_S: f64 = 315_532_800.0;
    const Y2100_S: f64 = 4_102_444_800.0;
    if !(Y1980_S..Y2100_S).contains(&unix_s) {
        return None;
    }
    let millis = (unix_s * 1000.0).round() as i64;
    let t = Timestamp::from_millisecond(millis).ok()?;
    Some(format!("{t:.3}"))
}

/// The interval a RINS logs its attitude at, s: 10 ms to 10 s.
pub const PLAUSIBLE_INTERVAL_S: (f64, f64) = (0.01, 10.0);

/// The interval of a log whose rows are binned (`--bin-interval-s`), s: 5 ms (200 Hz, a
/// navigation computer's attitude) to 10 s.
pub const BINNED_INTERVAL_S: (f64, f64) = (0.005, 10.0);

/// How far below 5 ms, relatively, the median step of a 200 Hz log may lie: stamps in Unix
/// seconds carry 0.24 us of rounding (the `f64`'s resolution at 1.7e9 s), a recorder's clock a
/// little of its own.
const NAVIGATION_RATE_TOLERANCE: f64 = 0.01;

/// Steps whose median [`IntervalCheck`] judges.
pub const CHECKED_STEPS: usize = 8;

/// Why the stamps' interval makes no sense.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IntervalError {
    /// The stamps step by more than 10 s or less than 10 ms (5 ms when binned: `shortest_s`),
    /// and another unit explains it.
    #[error(
        "the time stamps step by {interval_s} s (median of the first {CHECKED_STEPS} steps), but a RINS logs every {shortest_s} to 10 s: \
         they look like {unit} ({interval_s} {unit_short} a row is {as_seconds} s){hint}"
    )]
    WrongUnit {
        /// Median of the first [`CHECKED_STEPS`] steps, s, to 4 significant digits.
        interval_s: f64,
        /// Shortest interval accepted, s: 10 ms, or 5 ms when binned.
        shortest_s: f64,
        /// The unit that explains the steps, in words: `milliseconds`, `minutes`, ...
        unit: &'static str,
        /// Its symbol: `ms`, `min`, ...
        unit_short: &'static str,
        /// The median step in seconds, were the stamps in that unit, to 4 significant digits.
        as_seconds: f64,
        /// What to do about it, the end of the message (starting with a space).
        hint: &'static str,
    },
    /// The stamps step by more than 10 s or less than 10 ms (5 ms when binned: `shortest_s`),
    /// and no unit explains it.
    #[error(
        "the time stamps step by {interval_s} s (median of the first {CHECKED_STEPS} steps), but a RINS logs every {shortest_s} to 10 s: \
         {cause}"
    )]
    Implausible {
        /// Median of the first [`CHECKED_STEPS`] steps, s, to 4 significant digits.
        interval_s: f64,
        /// Shortest interval accepted, s: 10 ms, or 5 ms when binned.
        shortest_s: f64,
        /// The likely cause, in words.
        cause: &'static str,
    },
    /// The stamps step by 5 to 10 ms, a navigation computer's rate, and the log is not binned.
    #[error(
        "the time stamps step by {interval_s} s (median of the first {CHECKED_STEPS} steps), but a RINS logs every 0.01 to 10 s \
         to the estimator: attitude at the navigation rate (up to 200 Hz) is averaged into its grid with --bin-interval-s S (0.1 to 10, e.g. 1)"
    )]
    NavigationRate {
        /// Median of the first [`CHECKED_STEPS`] steps, s, to 4 significant digits.
        interval_s: f64,
    },
    /// The stamps of a binned log step by more than one bin: bins would be left empty.
    #[error(
        "the time stamps step by {interval_s} s (median of the first {CHECKED_STEPS} steps), more than --bin-interval-s {bin_s} s: \
         most bins would be empty; give a --bin-interval-s of at least {interval_s} s, or leave it out for a log at the grid's rate"
    )]
    SlowerThanBins {
        /// Median of the first [`CHECKED_STEPS`] steps, s, to 4 significant digits.
        interval_s: f64,
        /// The bin interval (`--bin-interval-s`), s.
        bin_s: f64,
    },
    /// `--sample-interval` says one interval, the stamps another.
    #[error(
        "--sample-interval {pinned_s} s contradicts the log's time stamps, which step by {step_s} s ({which} of the first {CHECKED_STEPS} steps): \
         every row would be off the grid; leave --sample-interval out (the interval is learned) or give {step_s}"
    )]
    ContradictsPinned {
        /// The `--sample-interval`, s.
        pinned_s: f64,
        /// The step that contradicts it, s, to 4 significant digits.
        step_s: f64,
        /// Which step that is: `the shortest` or `the median` of the first [`CHECKED_STEPS`].
        which: &'static str,
    },
}

/// Watches the first steps of a log's stamps (rows as read, in order) and judges their median
/// once [`CHECKED_STEPS`] positive steps are in (see the module doc).
#[derive(Clone, Debug)]
pub struct IntervalCheck {
    pinned_s: Option<f64>,
    /// The bin interval of a binned log, s.
    bin_s: Option<f64>,
    last_s: Option<f64>,
    steps: Vec<f64>,
    done: bool,
}

impl IntervalCheck {
    /// `pinned_s`: the `--sample-interval`, if given.
    pub fn new(pinned_s: Option<f64>) -> IntervalCheck {
        IntervalCheck {
            pinned_s,
            bin_s: None,
            last_s: None,
            steps: Vec::with_capacity(CHECKED_STEPS),
            done: false,
        }
    }

    /// For a log averaged into bins of `bin_s` (`--bin-interval-s`): its stamps may step by 5 ms
    /// to 10 s ([`BINNED_INTERVAL_S`]) but by no more than `bin_s`; the estimator's interval is
    /// the bins', so no pinned interval is checked against the rows.
    pub fn binned(bin_s: f64) -> IntervalCheck {
        IntervalCheck {
            bin_s: Some(bin_s),
            ..IntervalCheck::new(None)
        }
    }

    /// One stamp; an error once the first steps show an interval that makes no sense.
    pub fn observe(&mut self, time_s: f64) -> Result<(), IntervalError> {
        if self.done || !time_s.is_finite() {
            return Ok(());
        }
        let last = self.last_s.replace(time_s);
        if let Some(step) = last.map(|l| time_s - l).filter(|s| *s > 0.0) {
            self.steps.push(step);
        }
        if self.steps.len() < CHECKED_STEPS {
            return Ok(());
        }
        self.done = true;
        self.steps.sort_by(f64::total_cmp);
        let n = self.steps.len();
        let median = 0.5 * (self.steps[n / 2 - 1] + self.steps[n / 2]);
        match self.bin_s {
            None => judge(median, self.steps[0], self.pinned_s),
            Some(bin_s) => judge_binned(median, bin_s),
        }
    }
}

/// Rounds to 4 significant digits for messages (the stamps carry a recorder's clock error).
fn round4(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(3 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}

/// Units a RINS's stamps are mistaken for seconds in: name, symbol, seconds per unit, what to do.
const OTHER_UNITS: [(&str, &str, f64, &str); 6] = [
    ("milliseconds", "ms", 1e-3, " (name the time column time_ms, or divide them by 1000), unless the log was thinned out to one row in many"),
    ("microseconds", "us", 1e-6, " (divide them by 1e6 into a time_s column), unless the log was thinned out to one row in many"),
    ("nanoseconds", "ns", 1e-9, " (divide them by 1e9 into a time_s column), unless the log was thinned out to one row in many"),
    ("minutes", "min", 60.0, " (write seconds in a time_s column)"),
    ("hours", "h", 3600.0, " (write seconds in a time_s column)"),
    ("days", "d", 86_400.0, " (write seconds in a time_s column)"),
];

/// Judges the stamps' steps: their median against the plausible range (a median of 5 to 10 ms,
/// a navigation computer's rate, is told to bin the log: [`IntervalError::NavigationRate`]) and,
/// with the interval pinned, against it: the shortest step (the interval itself, whatever rows are lost) must not be
/// two pinned intervals or more, nor the median (robust to stamps jittered by up to nearly half an
/// interval, whose shortest step may be a tenth of one) below 0.6 of one.
pub fn judge(median_s: f64, shortest_s: f64, pinned_s: Option<f64>) -> Result<(), IntervalError> {
    let interval_s = round4(median_s);
    let (nav_lo, _) = BINNED_INTERVAL_S;
    let (lo, _) = PLAUSIBLE_INTERVAL_S;
    if (nav_lo * (1.0 - NAVIGATION_RATE_TOLERANCE)..lo).contains(&median_s) {
        return Err(IntervalError::NavigationRate { interval_s });
    }
    judge_range(median_s, PLAUSIBLE_INTERVAL_S)?;
    if let Some(pinned_s) = pinned_s {
        if shortest_s > 1.5 * pinned_s {
            return Err(IntervalError::ContradictsPinned {
                pinned_s,
                step_s: round4(shortest_s),
                which: "the shortest",
            });
        }
        if median_s < 0.6 * pinned_s {
            return Err(IntervalError::ContradictsPinned {
                pinned_s,
                step_s: round4(median_s),
                which: "the median",
            });
        }
    }
    Ok(())
}

/// Judges the median step of a log averaged into bins of `bin_s`: within [`BINNED_INTERVAL_S`]
/// (down to 1 % below 5 ms),
/// and at most one bin (a step of a bin and a little more, stamps jittered, still fills most
/// bins; at 1.5 bins and more every other bin would be empty).
pub fn judge_binned(median_s: f64, bin_s: f64) -> Result<(), IntervalError> {
    let (lo, hi) = BINNED_INTERVAL_S;
    if !(lo * (1.0 - NAVIGATION_RATE_TOLERANCE)..=hi).contains(&median_s) {
        judge_range(median_s, BINNED_INTERVAL_S)?;
    }
    if median_s > 1.01 * bin_s {
        return Err(IntervalError::SlowerThanBins {
            interval_s: round4(median_s),
            bin_s,
        });
    }
    Ok(())
}

/// The median step against the range `(lo, hi)`, naming the likely cause when outside.
fn judge_range(median_s: f64, (lo, hi): (f64, f64)) -> Result<(), IntervalError> {
    let interval_s = round4(median_s);
    if !(lo..=hi).contains(&median_s) {
        // The unit that makes the step a RINS's interval, the nearest to the usual 1 s.
        let unit = OTHER_UNITS
            .iter()
            .map(|&(name, short, s_per_unit, hint)| (name, short, median_s * s_per_unit, hint))
            .filter(|&(.., s, _)| (lo..=hi).contains(&s))
            .min_by(|a, b| a.2.log10().abs().total_cmp(&b.2.log10().abs()));
        return Err(match unit {
            Some((unit, unit_short, as_seconds, hint)) => {
                IntervalError::WrongUnit { interval_s, shortest_s: lo, unit, unit_short, as_seconds: round4(as_seconds), hint }
            }
            None if median_s > hi => IntervalError::Implausible {
                interval_s,
                shortest_s: lo,
                cause: "the log may have been thinned out (every n-th row kept), or the time column is not a time",
            },
            None => IntervalError::Implausible {
                interval_s,
                shortest_s: lo,
                cause: "the stamps may have too few digits (rounded), or the time column is not a time",
            },
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_milliseconds_and_utc_stamps_read_as_seconds() {
        assert_eq!(
            TimeColumn::Seconds.parse("1700000000.25"),
            Ok(1_700_000_000.25)
        );
        assert_eq!(
            TimeColumn::Milliseconds.parse("1700000000250"),
            Ok(1_700_000_000.25)
        );
        assert_eq!(TimeColumn::Milliseconds.parse("1500"), Ok(1.5));
        // 2023-11-14T22:13:20Z is Unix 1700000000.
        for cell in [
            "2023-11-14T22:13:20Z",
            "2023-11-14 22:13:20Z",
            "2023-11-14T22:13:20",
            "2023-11-15T00:13:20+02:00",
            "2023-11-14t22:13:20z",
        ] {
            assert_eq!(TimeColumn::Utc.parse(cell), Ok(1_700_000_000.0), "{cell}");
            assert_eq!(
                TimeColumn::Seconds.parse(cell),
                Ok(1_700_000_000.0),
                "a date in time_s: {cell}"
            );
        }
        assert_eq!(
            TimeColumn::Utc.parse("2023-11-14T22:13:20.250Z"),
            Ok(1_700_000_000.25)
        );
        assert_eq!(
            TimeColumn::Utc.parse("12.5"),
            Ok(12.5),
            "a number in time_utc is seconds"
        );
        assert!(TimeColumn::Utc
            .parse("2023-13-14T22:13:20Z")
            .unwrap_err()
            .contains("not a date and time"));
        assert_eq!(TimeColumn::Seconds.parse(""), Err("blank cell".to_string()));
        assert!(TimeColumn::Seconds
            .parse("12:00:00")
            .unwrap_err()
            .contains("not a number"));
    }

    #[test]
    fn utc_is_formatted_for_unix_times_only() {
        assert_eq!(
            format_utc(1_700_000_000.25).as_deref(),
            Some("2023-11-14T22:13:20.250Z")
        );
        assert_eq!(
            format_utc(45_000.0),
            None,
            "seconds since the log's start are no date"
        );
        assert_eq!(format_utc(f64::NAN), None);
    }

    fn check(
        stamps: impl IntoIterator<Item = f64>,
        pinned: Option<f64>,
    ) -> Result<(), IntervalError> {
        let mut c = IntervalCheck::new(pinned);
        stamps.into_iter().try_for_each(|t| c.observe(t))
    }

    #[test]
    fn plausible_intervals_pass_with_lost_rows_and_jitter() {
        assert_eq!(check((0..100).map(f64::from), None), Ok(()));
        assert_eq!(
            check((0..100).map(|k| 1.7e9 + 0.1 * f64::from(k)), Some(0.1)),
            Ok(())
        );
        // Every other row lost (the median is 2 s, the shortest step 1 s), 20 ms of jitter.
        let stamps = (0..100)
            .filter(|k| k % 4 == 0 || k % 4 == 1)
            .map(|k| f64::from(k) + 0.02 * f64::from(k % 2));
        assert_eq!(check(stamps, Some(1.0)), Ok(()));
        assert_eq!(
            check((0..100).map(|k| 10.0 * f64::from(k)), None),
            Ok(()),
            "10 s is the slowest RINS rate"
        );
    }

    #[test]
    fn implausible_intervals_name_their_likely_cause() {
        let ms = check((0..100).map(|k| 1000.0 * f64::from(k)), None).unwrap_err();
        assert!(
            matches!(
                ms,
                IntervalError::WrongUnit {
                    unit: "milliseconds",
                    ..
                }
            ),
            "{ms:?}"
        );
        assert!(
            ms.to_string().contains("step by 1000 s") && ms.to_string().contains("time_ms"),
            "{ms}"
        );
        let us = check((0..100).map(|k| 2e6 * f64::from(k)), None).unwrap_err();
        assert!(
            matches!(
                us,
                IntervalError::WrongUnit {
                    unit: "microseconds",
                    ..
                }
            ),
            "{us:?}"
        );
        let hours = check((0..100).map(|k| f64::from(k) / 3600.0), None).unwrap_err();
        // 1 s in hours is 0.0002778 h; read as minutes it would be 16.7 ms: hours is nearer 1 s.
        assert!(
            matches!(hours, IntervalError::WrongUnit { unit: "hours", .. }),
            "{hours:?}"
        );
        assert!(
            hours.to_string().contains("0.0002778 h a row is 1 s"),
            "{hours}"
        );
        let thinned = check((0..100).map(|k| 60.0 * f64::from(k)), None).unwrap_err();
        assert!(
            thinned.to_string().contains("milliseconds")
                && thinned.to_string().contains("thinned out"),
            "{thinned}"
        );
        let rounded = check((0..100).map(|k| 1e-9 * f64::from(k)), None).unwrap_err();
        assert!(
            matches!(rounded, IntervalError::Implausible { .. })
                && rounded.to_string().contains("too few digits"),
            "{rounded}"
        );
    }

    #[test]
    fn the_navigation_rate_is_read_only_when_binned() {
        // In Unix seconds the steps are 5 ms +- 0.24 us of rounding, their median a little below.
        let rate_200_hz = || (0..100).map(|k| 1.7e9 + 0.005 * f64::from(k));
        let e = check(rate_200_hz(), None).unwrap_err();
        assert_eq!(e, IntervalError::NavigationRate { interval_s: 0.005 });
        assert_eq!(
            check((0..100).map(|k| 0.005 * f64::from(k)), None),
            Err(IntervalError::NavigationRate { interval_s: 0.005 })
        );
        assert!(
            e.to_string().contains("a RINS logs every 0.01 to 10 s")
                && e.to_string().contains("--bin-interval-s"),
            "{e}"
        );
        fn binned(stamps: impl Iterator<Item = f64>, bin_s: f64) -> Result<(), IntervalError> {
            let mut c = IntervalCheck::binned(bin_s);
            stamps.into_iter().try_for_each(|t| c.observe(t))
        }
        assert_eq!(binned(rate_200_hz(), 1.0), Ok(()));
        assert_eq!(binned(rate_200_hz(), 0.1), Ok(()));
        assert_eq!(
            binned((0..100).map(f64::from), 1.0),
            Ok(()),
            "1 Hz in 1 s bins"
        );
        // 400 Hz is below what a binned log may step by; a 2 s log leaves every other 1 s bin empty.
        let fast = binned((0..100).map(|k| 0.0025 * f64::from(k)), 1.0).unwrap_err();
        assert!(
            matches!(fast, IntervalError::Implausible { shortest_s, .. } if shortest_s == 0.005)
                || matches!(fast, IntervalError::WrongUnit { shortest_s, .. } if shortest_s == 0.005),
            "{fast:?}"
        );
        assert!(fast.to_string().contains("every 0.005 to 10 s"), "{fast}");
        let slow = binned((0..100).map(|k| 2.0 * f64::from(k)), 1.0).unwrap_err();
        assert_eq!(
            slow,
            IntervalError::SlowerThanBins {
                interval_s: 2.0,
                bin_s: 1.0
            }
        );
    }

    #[test]
    fn a_pinned_interval_that_contradicts_the_stamps_is_refused() {
        let e = check((0..100).map(f64::from), Some(2.0)).unwrap_err();
        assert_eq!(
            e,
            IntervalError::ContradictsPinned {
                pinned_s: 2.0,
                step_s: 1.0,
                which: "the median"
            }
        );
        assert!(
            e.to_string()
                .starts_with("--sample-interval 2 s contradicts"),
            "{e}"
        );
        assert_eq!(
            check((0..100).map(|k| 1.1 * f64::from(k)), Some(1.0)),
            Ok(()),
            "within the grid's snap"
        );
        // Stamps jittered by +-0.45 of the interval: steps from 0.1 to 1.9 intervals.
        let jittered = (0..100).map(|k| f64::from(k) + 0.45 * if k % 2 == 0 { 1.0 } else { -1.0 });
        assert_eq!(check(jittered, Some(1.0)), Ok(()));
        let half = check((0..100).map(f64::from), Some(0.5)).unwrap_err();
        assert!(
            matches!(half, IntervalError::ContradictsPinned { .. }),
            "every step two pinned intervals: {half:?}"
        );
    }
}
