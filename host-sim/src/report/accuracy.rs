//! The accuracy table's numbers, followed row by row ([`Tracker`]): the percentage error of
//! eq (7) and the absolute error at the report times, and the settling times.

use crate::report::honesty::{Honesty, HonestyTracker};
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Estimate, Status};

/// Times of the accuracy table, s.
pub const REPORT_TIMES_S: [f64; 4] = [20_000.0, 45_000.0, 86_400.0, 172_800.0];

/// Settling threshold of the absolute percentage error, %.
pub const PERCENT_THRESHOLD: f64 = 0.5;

/// Settling threshold of the absolute error, arcsec.
pub const ARCSEC_THRESHOLD: f64 = 10.0;

/// The estimate's reported 1-sigma, arcsec, per error; `None` without an estimate.
pub fn sigmas_arcsec(estimate: Option<&Estimate>) -> Option<[f64; 4]> {
    estimate.map(|e| e.sigma_rad.map(|s| rad_to_arcsec(s as f64)))
}

/// Estimate minus truth, arcsec, per error; `None` without an estimate.
pub fn errors_arcsec(estimate: Option<&Estimate>, truth_arcsec: &[f64; 4]) -> Option<[f64; 4]> {
    estimate.map(|e| core::array::from_fn(|i| rad_to_arcsec(e.x_rad[i] as f64) - truth_arcsec[i]))
}

/// Eq (7): absolute percentage error; `None` for a true error of 0 (judged in arcsec only).
pub fn percent_of(error_arcsec: f64, truth_arcsec: f64) -> Option<f64> {
    (truth_arcsec != 0.0).then(|| percent_error(error_arcsec, truth_arcsec))
}

/// Eq (7): absolute percentage error; infinite for a true error of 0 and a non-zero estimate error
/// (for plots; reports use [`percent_of`]).
pub fn percent_error(error_arcsec: f64, truth_arcsec: f64) -> f64 {
    if error_arcsec == 0.0 {
        0.0
    } else {
        (error_arcsec / truth_arcsec).abs() * 100.0
    }
}

/// Follows the estimate row by row and keeps what the accuracy table needs.
#[derive(Clone, Debug)]
pub struct Tracker {
    times_s: Vec<f64>,
    /// Estimate error, truth and reported 1-sigma (all arcsec) at each of `times_s`, once reached.
    at: Vec<Option<Held>>,
    /// Per error: time of the first row of the current run of rows within the threshold
    /// (`None` while outside).
    within_percent_since: [Option<f64>; 4],
    within_arcsec_since: [Option<f64>; 4],
    last_time_s: f64,
    last: Option<Held>,
    next_time: usize,
    honesty: HonestyTracker,
}

/// What the tracker keeps of the estimate on board: error, truth, reported 1-sigma, arcsec.
type Held = ([f64; 4], [f64; 4], [f64; 4]);

impl Tracker {
    /// A tracker reporting at `times_s` (ascending).
    pub fn new(times_s: &[f64]) -> Tracker {
        Tracker {
            times_s: times_s.to_vec(),
            at: vec![None; times_s.len()],
            within_percent_since: [None; 4],
            within_arcsec_since: [None; 4],
            last_time_s: f64::NEG_INFINITY,
            last: None,
            next_time: 0,
            honesty: HonestyTracker::default(),
        }
    }

    /// The tracker of a log whose errors change at `at_s` (the truth's `errors_step`), s on the
    /// rows' time: [`Honesty`] leaves the rows of the change out.
    pub fn with_errors_step(mut self, at_s: Option<f64>) -> Tracker {
        self.honesty.step_at_s = at_s.filter(|t| t.is_finite());
        self
    }

    /// One row: its time, the estimate on board, the status the estimator reported for it (`None`
    /// for a rejected row) and the true errors at that time (arcsec). Rows with a non-finite time
    /// or out of order are ignored.
    pub fn observe(
        &mut self,
        time_s: f64,
        estimate: Option<&Estimate>,
        status: Option<Status>,
        truth_arcsec: &[f64; 4],
    ) {
        if !time_s.is_finite() || time_s <= self.last_time_s {
            return;
        }
        // Report times passed between the previous row and this one take the previous row's state.
        while self.next_time < self.times_s.len() && self.times_s[self.next_time] < time_s {
            self.at[self.next_time] = self.last;
            self.next_time += 1;
        }
        self.last_time_s = time_s;
        let err = errors_arcsec(estimate, truth_arcsec);
        self.honesty
            .observe(time_s, err.zip(sigmas_arcsec(estimate)).as_ref(), status);
        self.last = err
            .zip(sigmas_arcsec(estimate))
            .map(|(e, sigma)| (e, *truth_arcsec, sigma));
        for i in 0..4 {
            let (in_pct, in_as) = match err {
                Some(e) => {
                    let in_as = e[i].abs() <= ARCSEC_THRESHOLD;
                    (
                        percent_of(e[i], truth_arcsec[i]).map_or(in_as, |p| p <= PERCENT_THRESHOLD),
                        in_as,
                    )
                }
                None => (false, false),
            };
            let update = |since: &mut Option<f64>, inside: bool| {
                if !inside {
                    *since = None;
                } else if since.is_none() {
                    *since = Some(time_s);
                }
            };
            update(&mut self.within_percent_since[i], in_pct);
            update(&mut self.within_arcsec_since[i], in_as);
        }
        if self.next_time < self.times_s.len() && self.times_s[self.next_time] == time_s {
            self.at[self.next_time] = self.last;
            self.next_time += 1;
        }
    }

    /// The summary. A report time counts as inside the run when it is at most one `interval_s`
    /// after the last row (a 172800 s log ends at 172799 s).
    pub fn finish(&self, interval_s: f64) -> Accuracy {
        let mut points = Vec::new();
        for (k, &t) in self.times_s.iter().enumerate() {
            if t > self.last_time_s + interval_s {
                break;
            }
            let state = if k < self.next_time {
                self.at[k]
            } else {
                self.last
            };
            points.push(AccuracyAt {
                time_s: t,
                error_arcsec: state.map(|s| s.0),
                sigma_arcsec: state.map(|s| s.2),
                percent: state.map(|(e, x, _)| core::array::from_fn(|i| percent_of(e[i], x[i]))),
            });
        }
        Accuracy {
            points,
            within_percent_from_s: self.within_percent_since,
            within_arcsec_from_s: self.within_arcsec_since,
            final_status: None,
            honesty: self.honesty.finish(),
        }
    }
}

/// Accuracy at one report time.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyAt {
    /// The report time, s.
    pub time_s: f64,
    /// Estimate minus truth, arcsec; `None` without an estimate.
    pub error_arcsec: Option<[f64; 4]>,
    /// The estimate's reported 1-sigma, arcsec; `None` without an estimate.
    pub sigma_arcsec: Option<[f64; 4]>,
    /// Absolute percentage error; `None` inside for a true error of 0.
    pub percent: Option<[Option<f64>; 4]>,
}

impl AccuracyAt {
    /// How many of the four errors lie within `k` times their reported 1-sigma (0 without an
    /// estimate).
    pub fn within_sigmas(&self, k: f64) -> usize {
        match (self.error_arcsec, self.sigma_arcsec) {
            (Some(e), Some(s)) => (0..4).filter(|&i| e[i].abs() <= k * s[i]).count(),
            _ => 0,
        }
    }
}

/// The accuracy table's numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct Accuracy {
    /// The accuracy at each report time inside the run.
    pub points: Vec<AccuracyAt>,
    /// Per error: first time after which it stays within 0.5 % (10 arcsec for a true error of 0);
    /// `None`: not within at the end.
    pub within_percent_from_s: [Option<f64>; 4],
    /// Per error: first time after which it stays within 10 arcsec.
    pub within_arcsec_from_s: [Option<f64>; 4],
    /// The estimator's status at the last accepted row, where the caller recorded it.
    pub final_status: Option<estimator_core::Status>,
    /// How honest the reported 1-sigma was, row by row.
    pub honesty: Honesty,
}

impl Accuracy {
    /// The latest of the four settling times (all errors within), `None` if one never settles.
    pub fn all_within_percent_from_s(&self) -> Option<f64> {
        latest(&self.within_percent_from_s)
    }

    /// The latest of the four settling times within 10 arcsec (all errors within), `None` if one
    /// never settles.
    pub fn all_within_arcsec_from_s(&self) -> Option<f64> {
        latest(&self.within_arcsec_from_s)
    }
}

fn latest(v: &[Option<f64>; 4]) -> Option<f64> {
    v.iter()
        .try_fold(f64::NEG_INFINITY, |m, t| t.map(|t| m.max(t)))
}
