//! A log's rows at the navigation rate (up to 200 Hz) averaged into the estimator's grid as they
//! are read (`--bin-interval-s S` of `estimate` and `stream`): [`BinnedLines`] wraps the reader's
//! rows and hands on one row per bin of S s, the average of the bin's rows stamped at its centre
//! ([`estimator_core::binning`]), as a navigation computer would send it to the estimator.
//!
//! The rows' stamps are checked as they come ([`IntervalCheck::binned`]: 5 ms to 10 s, at most one
//! bin). Unreadable rows are handed on as the reader gave them (the caller's [`RowFilter`] skips
//! and counts them, or refuses the log); rows the binner refuses (a non-finite or out-of-range
//! value, a stamp not after the last one) are counted ([`BinningSummary::refused`]) and are in no
//! bin. A bin's row is numbered with the line of the last row in it.
//!
//! [`RowFilter`]: crate::formats::log_csv::RowFilter

use crate::formats::log_csv::{LogError, LogLine, LogLines};
use crate::formats::time_stamps::{IntervalCheck, IntervalError};
use crate::replay::summary::significant_4;
use crate::replay::{row_of, sample_of};
use estimator_core::binning::{BinIntervalError, Binner};
use estimator_core::{RejectCounts, RejectReason};

/// What binning did to a log's rows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BinningSummary {
    /// The bin interval, s.
    pub interval_s: f64,
    /// Rows read and given to the binner.
    pub rows: u64,
    /// Bins averaged and handed on.
    pub bins: u64,
    /// Rows the binner refused (non-finite, out of range, time not increasing), by reason: they
    /// are in no bin and have no estimates row.
    pub refused: RejectCounts,
}

impl BinningSummary {
    /// For people: `400000 rows averaged into 2000 bins of 1 s (0 rows refused)`, the reasons of
    /// refused rows named.
    pub fn describe(&self) -> String {
        let refused = self.refused.total();
        let reasons = if refused == 0 {
            String::new()
        } else {
            let named: Vec<String> = RejectReason::ALL
                .iter()
                .filter(|r| self.refused.of(**r) > 0)
                .map(|r| format!("{} {}", r.name(), self.refused.of(*r)))
                .collect();
            format!(": {}", named.join(", "))
        };
        format!(
            "{} rows averaged into {} bins of {} s ({refused} rows refused{reasons})",
            self.rows,
            self.bins,
            significant_4(self.interval_s)
        )
    }
}

/// The rows of `inner` averaged into bins (see the module doc).
pub struct BinnedLines<I> {
    inner: I,
    binner: Binner,
    check: IntervalCheck,
    summary: BinningSummary,
    /// The line of the last row in the bin being filled.
    bin_last_line: usize,
    /// Why the rows stopped early: their stamps' interval.
    interval_error: Option<IntervalError>,
    ended: bool,
}

impl<I> BinnedLines<I> {
    /// Bins of `bin_interval_s`, within [`estimator_core::binning::BIN_INTERVAL_RANGE_S`].
    pub fn new(inner: I, bin_interval_s: f64) -> Result<BinnedLines<I>, BinIntervalError> {
        let binner = Binner::new(bin_interval_s)?;
        Ok(BinnedLines {
            inner,
            binner,
            check: IntervalCheck::binned(bin_interval_s),
            summary: BinningSummary {
                interval_s: bin_interval_s,
                rows: 0,
                bins: 0,
                refused: RejectCounts::ZERO,
            },
            bin_last_line: 0,
            interval_error: None,
            ended: false,
        })
    }

    /// What binning did so far.
    pub fn summary(&self) -> BinningSummary {
        self.summary
    }

    /// The error that ended the rows early, if any: the stamps step by an interval that cannot be
    /// binned. Ask once the rows end.
    pub fn take_interval_error(&mut self) -> Option<IntervalError> {
        self.interval_error.take()
    }

    /// The rows' source.
    pub fn inner(&self) -> &I {
        &self.inner
    }

    /// A bin's average as a row.
    fn bin_line(&mut self, average: &estimator_core::Sample) -> LogLine {
        self.summary.bins += 1;
        LogLine {
            line: self.bin_last_line,
            row: row_of(average),
        }
    }
}

impl<I> Iterator for BinnedLines<I>
where
    I: Iterator<Item = Result<LogLine, LogError>>,
{
    type Item = Result<LogLine, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.ended {
            return None;
        }
        loop {
            let line = match self.inner.next() {
                None => {
                    self.ended = true;
                    let last = self.binner.finish()?;
                    return Some(Ok(self.bin_line(&last)));
                }
                Some(Err(e)) => return Some(Err(e)),
                Some(Ok(line)) => line,
            };
            if let Err(e) = self.check.observe(line.row.time_s) {
                self.interval_error = Some(e);
                self.ended = true;
                return None;
            }
            self.summary.rows += 1;
            match self.binner.push(&sample_of(&line.row)) {
                Err(e) => self.summary.refused.count(e.reason()),
                Ok(None) => self.bin_last_line = line.line,
                Ok(Some(average)) => {
                    let out = self.bin_line(&average);
                    self.bin_last_line = line.line;
                    return Some(Ok(out));
                }
            }
        }
    }
}

impl<I: LogLines> LogLines for BinnedLines<I> {
    fn bytes_read(&self) -> u64 {
        self.inner.bytes_read()
    }
}

/// A log's rows as they come, or averaged into bins (`--bin-interval-s`): what `estimate` and
/// `stream` read.
// One a run, held while it runs: the binned variant's size costs nothing.
#[allow(clippy::large_enum_variant)]
pub enum Lines<I> {
    /// The rows as they come.
    Plain(I),
    /// The rows averaged into bins.
    Binned(BinnedLines<I>),
}

impl<I> Lines<I> {
    /// The rows of `inner`, averaged into bins of `bin_interval_s` when given.
    pub fn new(inner: I, bin_interval_s: Option<f64>) -> Result<Lines<I>, BinIntervalError> {
        Ok(match bin_interval_s {
            Some(bin_s) => Lines::Binned(BinnedLines::new(inner, bin_s)?),
            None => Lines::Plain(inner),
        })
    }

    /// Whether the rows are binned.
    pub fn is_binned(&self) -> bool {
        matches!(self, Lines::Binned(_))
    }

    /// What binning did so far, when binned.
    pub fn binning(&self) -> Option<BinningSummary> {
        match self {
            Lines::Binned(bins) => Some(bins.summary()),
            Lines::Plain(_) => None,
        }
    }

    /// The error that ended binned rows early ([`BinnedLines::take_interval_error`]).
    pub fn take_interval_error(&mut self) -> Option<IntervalError> {
        match self {
            Lines::Binned(bins) => bins.take_interval_error(),
            Lines::Plain(_) => None,
        }
    }
}

impl<I> Iterator for Lines<I>
where
    I: Iterator<Item = Result<LogLine, LogError>>,
{
    type Item = Result<LogLine, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        match self {
            Lines::Plain(rows) => rows.next(),
            Lines::Binned(bins) => bins.next(),
        }
    }
}

impl<I: LogLines> LogLines for Lines<I> {
    fn bytes_read(&self) -> u64 {
        match self {
            Lines::Plain(rows) => rows.bytes_read(),
            Lines::Binned(bins) => bins.bytes_read(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::scenario::Row;

    fn line(line: usize, time_s: f64, roll_deg: f64) -> Result<LogLine, LogError> {
        Ok(LogLine {
            line,
            row: Row {
                time_s,
                rotation_deg: 359.9 + 0.2 * time_s,
                platform_deg: 10.0,
                latitude_deg: 30.0,
                heading_deg: 45.0,
                roll_deg,
                pitch_deg: 1.0,
            },
        })
    }

    #[test]
    fn rows_at_100_hz_come_out_one_a_bin_at_its_centre() {
        // 3.5 s at 100 Hz, rows 2 to 351 of the file; an unreadable row and a NaN among them.
        let mut rows: Vec<Result<LogLine, LogError>> = (0..350u32)
            .map(|k| line(k as usize + 2, f64::from(k) / 100.0, 1.0 + f64::from(k % 2)))
            .collect();
        rows.insert(
            10,
            Err(LogError::unreadable_row(
                std::path::Path::new("x.csv"),
                12,
                "roll_deg: blank cell",
            )),
        );
        rows.insert(20, line(21, 0.195, f64::NAN));
        let mut binned = BinnedLines::new(rows.into_iter(), 1.0).unwrap();
        let out: Vec<Result<LogLine, LogError>> = binned.by_ref().collect();
        assert!(out[0].is_err(), "the unreadable row is handed on");
        let bins: Vec<LogLine> = out.into_iter().filter_map(Result::ok).collect();
        let times: Vec<f64> = bins.iter().map(|l| l.row.time_s).collect();
        assert_eq!(times, [0.5, 1.5, 2.5, 3.5]);
        assert_eq!(
            bins.iter().map(|l| l.line).collect::<Vec<_>>(),
            [101, 201, 301, 351],
            "each bin numbered with its last row's line"
        );
        // The rows' mean times: the centre less half a row's step for the full bins, 3.245 s for
        // the last (3.00 to 3.49 s).
        for (b, mean_time_s) in bins.iter().zip([0.495, 1.495, 2.495, 3.245]) {
            assert!((b.row.roll_deg - 1.5).abs() < 1e-5, "{b:?}");
            // The rotation crosses 360 deg in the first bin: its mean is near 0, not 180.
            let expect = (359.9 + 0.2 * mean_time_s + 180.0f64).rem_euclid(360.0) - 180.0;
            assert!((b.row.rotation_deg - expect).abs() < 1e-4, "{b:?}");
        }
        assert_eq!(
            binned.summary().describe(),
            "351 rows averaged into 4 bins of 1 s (1 rows refused: non_finite 1)"
        );
        assert!(binned.take_interval_error().is_none());
    }

    #[test]
    fn rows_slower_than_the_bins_end_with_the_interval_error() {
        let rows = (0..30u32).map(|k| line(k as usize + 2, 2.0 * f64::from(k), 0.0));
        let mut binned = BinnedLines::new(rows, 1.0).unwrap();
        let out: Vec<_> = binned.by_ref().collect();
        assert!(out.len() < 9, "ended at the ninth row: {}", out.len());
        assert!(matches!(
            binned.take_interval_error(),
            Some(IntervalError::SlowerThanBins { .. })
        ));
        assert!(BinnedLines::new(std::iter::empty::<Result<LogLine, LogError>>(), 0.01).is_err());
    }
}
