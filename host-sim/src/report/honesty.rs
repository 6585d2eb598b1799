//! Honesty of the reported 1-sigma, row by row ([`Honesty`]), with the rows of a true change of
//! the errors left out while the estimator relearns them.

use estimator_core::Status;
use serde::Serialize;

/// How long after a change of the errors, or after the estimator declares it, the rows are left
/// out of [`Honesty`], s.
pub const HONESTY_SETTLE_S: f64 = 2_000.0;

/// The multiples of the reported 1-sigma [`Honesty`] counts rows beyond.
pub const HONESTY_SIGMAS: [f64; 3] = [2.0, 3.0, 5.0];

/// The largest |error| / reported 1-sigma of a set of rows, and where it was.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SigmaRatio {
    /// |error| / 1-sigma (infinite for an error beside a 1-sigma of 0).
    pub ratio: f64,
    /// Time of the row, s (from the log's start, as the truth's).
    pub time_s: f64,
    /// Which error, 1..=4 (x1..x4).
    pub error: usize,
    /// Which run, for statistics over runs (`None` for one run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub run: Option<usize>,
}

/// Honesty of the reported 1-sigma, row by row: over every row from the first estimate on (rows
/// of a change of the errors left out, see [`Tracker::with_errors_step`]), how often some of the
/// four |error| exceeded 2, 3 and 5 times its 1-sigma. For an honest, Gaussian 1-sigma, a single
/// error exceeds 2 sigma on 4.6 % of rows and 3 sigma on 0.27 %; some of four independent errors
/// on 17 % and 1.1 % (fewer when the errors' estimates are correlated).
///
/// [`Tracker::with_errors_step`]: crate::report::accuracy::Tracker::with_errors_step
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Honesty {
    /// Rows judged: with an estimate, from the first estimate on, outside the change's rows.
    pub rows: u64,
    /// Rows judged where some of the four |error| exceeds 2 sigma.
    pub beyond_2_sigma_rows: u64,
    /// ... exceeds 3 sigma.
    pub beyond_3_sigma_rows: u64,
    /// ... exceeds 5 sigma.
    pub beyond_5_sigma_rows: u64,
    /// The largest |error| / 1-sigma over the rows judged.
    pub largest: Option<SigmaRatio>,
    /// Rows after the first estimate without one (e.g. a restart before the next): not judged,
    /// not in the shares.
    pub rows_without_estimate: u64,
    /// Rows left out after a true change of the errors.
    pub rows_left_out: u64,
    /// The span left out, s: from the change to 2,000 s after its declaration (or after the
    /// change, when the estimator never declared it); `None` without a change (and over runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub left_out_s: Option<[f64; 2]>,
    /// When the estimator declared the change (`errors_changed` from the change on), s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub declared_at_s: Option<f64>,
}

impl Honesty {
    /// Share of the rows judged beyond `HONESTY_SIGMAS[k]` sigma (NaN without rows).
    pub fn share_beyond(&self, k: usize) -> f64 {
        let n = [
            self.beyond_2_sigma_rows,
            self.beyond_3_sigma_rows,
            self.beyond_5_sigma_rows,
        ][k];
        if self.rows == 0 {
            f64::NAN
        } else {
            n as f64 / self.rows as f64
        }
    }

    /// Adds `other`'s rows (run `run` of a study): the counts add up, the largest ratio is the
    /// larger; the span left out is per run and dropped.
    pub fn pool(&mut self, other: &Honesty, run: usize) {
        self.rows += other.rows;
        self.beyond_2_sigma_rows += other.beyond_2_sigma_rows;
        self.beyond_3_sigma_rows += other.beyond_3_sigma_rows;
        self.beyond_5_sigma_rows += other.beyond_5_sigma_rows;
        self.rows_without_estimate += other.rows_without_estimate;
        self.rows_left_out += other.rows_left_out;
        self.left_out_s = None;
        self.declared_at_s = None;
        if let Some(l) = other.largest {
            if self.largest.is_none_or(|m| l.ratio > m.ratio) {
                self.largest = Some(SigmaRatio {
                    run: Some(run),
                    ..l
                });
            }
        }
    }

    /// Counts one row with an estimate: its errors and reported 1-sigma, arcsec.
    fn judge(&mut self, time_s: f64, error_arcsec: &[f64; 4], sigma_arcsec: &[f64; 4]) {
        self.rows += 1;
        let beyond = |k: f64| (0..4).any(|i| error_arcsec[i].abs() > k * sigma_arcsec[i]);
        self.beyond_2_sigma_rows += beyond(HONESTY_SIGMAS[0]) as u64;
        self.beyond_3_sigma_rows += beyond(HONESTY_SIGMAS[1]) as u64;
        self.beyond_5_sigma_rows += beyond(HONESTY_SIGMAS[2]) as u64;
        for i in 0..4 {
            let (e, s) = (error_arcsec[i].abs(), sigma_arcsec[i]);
            let ratio = if s > 0.0 {
                e / s
            } else if e == 0.0 {
                0.0
            } else {
                f64::INFINITY
            };
            if self.largest.is_none_or(|m| ratio > m.ratio) {
                self.largest = Some(SigmaRatio {
                    ratio,
                    time_s,
                    error: i + 1,
                    run: None,
                });
            }
        }
    }
}

/// Follows [`Honesty`] row by row without holding rows: the rows after the change's first
/// 2,000 s, while the estimator has not declared it yet, are counted aside; a declaration leaves
/// them out, the end of the log without one takes them in.
#[derive(Clone, Debug, Default)]
pub(super) struct HonestyTracker {
    /// When the truth's errors change, s on the rows' time.
    pub(super) step_at_s: Option<f64>,
    started: bool,
    counted: Honesty,
    pending: Honesty,
}

impl HonestyTracker {
    /// One row: its time, its error and reported 1-sigma (arcsec) when it has an estimate, and
    /// the status the estimator reported for it.
    pub(super) fn observe(
        &mut self,
        time_s: f64,
        held: Option<&([f64; 4], [f64; 4])>,
        status: Option<Status>,
    ) {
        if !self.started {
            if held.is_none() {
                return;
            }
            self.started = true;
        }
        let mut waiting = false;
        if let Some(at_s) = self.step_at_s.filter(|at| time_s >= *at) {
            if self.counted.declared_at_s.is_none() && status == Some(Status::ErrorsChanged) {
                // Declared: what waited is left out with the rest of the change's rows.
                self.counted.declared_at_s = Some(time_s);
                self.counted.rows_left_out +=
                    self.pending.rows + self.pending.rows_without_estimate;
                self.pending = Honesty::default();
            }
            let end_s = self.counted.declared_at_s.unwrap_or(at_s) + HONESTY_SETTLE_S;
            if time_s < end_s {
                self.counted.rows_left_out += 1;
                return;
            }
            // Past the change's first 2,000 s, not declared yet: counted aside until the
            // estimator declares it or the log ends.
            waiting = self.counted.declared_at_s.is_none();
        }
        let into = if waiting {
            &mut self.pending
        } else {
            &mut self.counted
        };
        match held {
            Some((e, s)) => into.judge(time_s, e, s),
            None => into.rows_without_estimate += 1,
        }
    }

    /// The honesty over the rows observed.
    pub(super) fn finish(&self) -> Honesty {
        let mut h = self.counted;
        // Never declared: the rows after the change's first 2,000 s count after all.
        if h.declared_at_s.is_none() {
            h.rows += self.pending.rows;
            h.beyond_2_sigma_rows += self.pending.beyond_2_sigma_rows;
            h.beyond_3_sigma_rows += self.pending.beyond_3_sigma_rows;
            h.beyond_5_sigma_rows += self.pending.beyond_5_sigma_rows;
            h.rows_without_estimate += self.pending.rows_without_estimate;
            if let Some(l) = self.pending.largest {
                if h.largest.is_none_or(|m| l.ratio > m.ratio) {
                    h.largest = Some(l);
                }
            }
        }
        h.left_out_s = self
            .step_at_s
            .filter(|_| self.started)
            .map(|at_s| [at_s, h.declared_at_s.unwrap_or(at_s) + HONESTY_SETTLE_S]);
        h
    }
}
