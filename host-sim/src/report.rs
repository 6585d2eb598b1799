//! Accuracy of a replay against the truth: the accuracy table of the `estimate` and `run` commands.
//!
//! - Absolute percentage error of eq (7): `|x_hat - x| / |x| * 100`, and absolute error in arcsec,
//!   at [`REPORT_TIMES_S`] (those inside the run; "at T" = the estimate on board at the last row
//!   with `time_s <= T`).
//! - Settling times: the first time after which an error stays within 0.5 % (resp. 10 arcsec) until
//!   the end of the run; rows without an estimate count as outside. A true error of 0 has no
//!   percentage error: it is judged in arcsec only (its "within 0.5 %" is "within 10 arcsec").
//! - Each log row is judged against the truth row nearest in time ([`ReportBuilder`]), so logs
//!   starting at any time, shifted or jittered, are judged against the right truth.
//! - Honesty of the reported 1-sigma, row by row ([`Honesty`]): over every row from the first
//!   estimate on, the share of rows where some of the four |error| exceeds 2, 3 and 5 times its
//!   1-sigma, and the largest |error| / 1-sigma. The rows from a true change of the errors
//!   (`errors_step`) are left out until 2,000 s after the estimator first reports
//!   `errors_changed` from then on (2,000 s after the change if it never does): while it relearns,
//!   its 1-sigma is of the errors before. Rows without an estimate after the first (a restart
//!   before the next one) are counted apart, not in the shares.
//! - Attitude error before and after compensation: the oscillation of eq (2) put into the log
//!   (truth) versus what is left of it after the core's correction:
//!   `residual = oscillation_in - (raw attitude - corrected attitude)`. The true attitude, the
//!   low-frequency errors and the noise cancel out of this difference exactly.
//!
//! What `--report DIR` writes is in the parts: [`timeline`] (the bounded record of a replay or a
//! stream), [`figures`] (the data of each picture) drawn by [`plots`], and [`pages`] (what each
//! command's `report.html` says) written by [`html`].

pub mod figures;
pub mod html;
pub mod pages;
pub mod plots;
pub mod timeline;

use crate::formats::truth_file::LogTruth;
use crate::replay::Step;
use crate::sim::scenario::{Row, RowTruth};
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Estimate, Method, Output, SampleError, Status};
use serde::Serialize;
use std::io::Write;

/// Label of a method in reports.
pub fn method_label(m: Method) -> &'static str {
    match m {
        Method::Windowed => "ours (windowed)",
        Method::Paper => "paper (literal)",
        Method::Traditional => "traditional",
    }
}

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
struct HonestyTracker {
    step_at_s: Option<f64>,
    started: bool,
    counted: Honesty,
    pending: Honesty,
}

impl HonestyTracker {
    fn observe(
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

    fn finish(&self) -> Honesty {
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

/// `n` with its thousands separated by commas (`19,401`).
pub fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `1 row`, `19,401 rows`.
pub fn rows_text(n: u64) -> String {
    if n == 1 {
        "1 row".into()
    } else {
        format!("{} rows", thousands(n))
    }
}

/// A time in whole seconds with its thousands separated (`2,940 s`).
fn seconds(t: f64) -> String {
    if t.is_finite() && t >= 0.0 {
        format!("{} s", thousands(t.round() as u64))
    } else {
        format!("{t:.0} s")
    }
}

/// A share of rows in percent, with as many decimals as a share above 0 needs to show (`0.3 %`,
/// `0.01 %`); exactly `0 %` for none and `100 %` for all.
pub fn percent_of_rows(count: u64, rows: u64) -> String {
    if rows == 0 {
        return "-".into();
    }
    if count == 0 {
        return "0 %".into();
    }
    if count == rows {
        return "100 %".into();
    }
    let p = 100.0 * count as f64 / rows as f64;
    let decimals = (-p.log10()).ceil().max(1.0) as usize;
    format!("{p:.decimals$} %")
}

/// `3.4 (x3 at 2,940 s)`: the largest |error| / 1-sigma and where (with the run, over runs).
pub fn format_largest(l: &SigmaRatio) -> String {
    let run = l.run.map_or(String::new(), |r| format!("run {r}: "));
    format!(
        "{:.1} ({run}x{} at {})",
        l.ratio,
        l.error,
        seconds(l.time_s)
    )
}

/// The shares beyond 2, 3 and 5 sigma and the largest ratio:
/// `some error beyond 2 sigma on 0.3 %, beyond 3 sigma on 0.01 %, beyond 5 sigma on 0 %; largest
/// |error|/sigma 3.4 (x3 at 2,940 s)`.
pub fn format_honesty_shares(h: &Honesty) -> String {
    let mut s = format!(
        "some error beyond 2 sigma on {}, beyond 3 sigma on {}, beyond 5 sigma on {}",
        percent_of_rows(h.beyond_2_sigma_rows, h.rows),
        percent_of_rows(h.beyond_3_sigma_rows, h.rows),
        percent_of_rows(h.beyond_5_sigma_rows, h.rows),
    );
    if let Some(l) = &h.largest {
        s.push_str(&format!("; largest |error|/sigma {}", format_largest(l)));
    }
    s
}

/// The honesty line of one run (with a line more for rows left out or without an estimate).
pub fn format_honesty(h: &Honesty) -> String {
    if h.rows == 0 {
        return "1-sigma honesty: no row with an estimate to judge\n".into();
    }
    let mut s = format!(
        "1-sigma honesty, {} from the first estimate: {}\n",
        rows_text(h.rows),
        format_honesty_shares(h)
    );
    let mut notes = Vec::new();
    if let (Some([from_s, to_s]), true) = (h.left_out_s, h.rows_left_out > 0) {
        let why = match h.declared_at_s {
            Some(d) => format!("2,000 s after errors_changed at {}", seconds(d)),
            None => "never declared: 2,000 s after the change".to_string(),
        };
        notes.push(format!(
            "{} of the change of the errors left out ({} to {}: {why})",
            rows_text(h.rows_left_out),
            seconds(from_s),
            seconds(to_s),
        ));
    }
    if h.rows_without_estimate > 0 {
        notes.push(format!(
            "{} after the first estimate without one, not judged",
            rows_text(h.rows_without_estimate)
        ));
    }
    if !notes.is_empty() {
        s.push_str(&format!("  {}\n", notes.join("; ")));
    }
    s
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

/// RMS of the attitude error of eq (2) before and after compensation, arcsec, per axis
/// (heading, roll, pitch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AttitudeRms {
    /// Start of the span, s: the rows from this time on are taken.
    pub from_s: f64,
    /// Time of the last row taken, s (`from_s` when none was).
    pub to_s: f64,
    /// Rows taken.
    pub rows: usize,
    /// RMS of the oscillation eq (2) put in, before compensation, arcsec.
    pub before_arcsec: [f64; 3],
    /// RMS of what is left of it after compensation, arcsec.
    pub after_arcsec: [f64; 3],
}

/// Attitude error left after compensation of one accepted row, arcsec (heading, roll, pitch):
/// oscillation put in minus oscillation removed.
pub fn residual_arcsec(
    row: &Row,
    corrected: &estimator_core::Attitude,
    truth: &RowTruth,
) -> [f64; 3] {
    let raw = [row.heading_deg, row.roll_deg, row.pitch_deg];
    let cor = [
        corrected.heading_rad as f64,
        corrected.roll_rad as f64,
        corrected.pitch_rad as f64,
    ]
    .map(|r| r.to_degrees());
    core::array::from_fn(|a| {
        let mut removed_deg = raw[a] - cor[a];
        if a == 0 {
            removed_deg = estimator_core::units::wrap_deg(removed_deg);
        }
        (truth.oscillation_deg[a] - removed_deg) * 3600.0
    })
}

/// Accumulates [`AttitudeRms`] over rows with `time_s >= from_s`.
#[derive(Clone, Debug)]
pub struct RmsAccumulator {
    from_s: f64,
    to_s: f64,
    rows: usize,
    before: [f64; 3],
    after: [f64; 3],
}

impl RmsAccumulator {
    /// An accumulator of the rows from `from_s` on, s.
    pub fn new(from_s: f64) -> Self {
        RmsAccumulator {
            from_s,
            to_s: from_s,
            rows: 0,
            before: [0.0; 3],
            after: [0.0; 3],
        }
    }

    /// Takes one accepted row: its time, s, the attitude error left after compensation
    /// ([`residual_arcsec`]) and its truth. A row before `from_s` is left out.
    pub fn add(&mut self, time_s: f64, residual_arcsec: &[f64; 3], truth: &RowTruth) {
        if time_s.is_nan() || time_s < self.from_s {
            return;
        }
        self.rows += 1;
        self.to_s = time_s;
        #[allow(clippy::needless_range_loop)]
        for a in 0..3 {
            let b = truth.oscillation_deg[a] * 3600.0;
            self.before[a] += b * b;
            self.after[a] += residual_arcsec[a] * residual_arcsec[a];
        }
    }

    /// The RMS over the rows taken.
    pub fn finish(&self) -> AttitudeRms {
        let n = self.rows.max(1) as f64;
        AttitudeRms {
            from_s: self.from_s,
            to_s: self.to_s,
            rows: self.rows,
            before_arcsec: self.before.map(|s| (s / n).sqrt()),
            after_arcsec: self.after.map(|s| (s / n).sqrt()),
        }
    }
}

/// The oscillation eq (2) puts into the attitude of `row` for installation errors `x_arcsec`,
/// deg (heading, roll, pitch), from the core's rows ([`estimator_core::installation::Angles`]).
pub fn oscillation_deg(row: &Row, x_arcsec: &[f64; 4]) -> [f64; 3] {
    use estimator_core::installation::Angles;
    use estimator_core::units::{arcsec_to_rad, wrap_deg, RAD_PER_DEG};
    use estimator_core::Real;
    let rad = |deg: f64| (wrap_deg(deg) * RAD_PER_DEG) as Real;
    let lat = row.latitude_deg * RAD_PER_DEG;
    let angles = Angles::new(
        rad(row.rotation_deg),
        rad(row.platform_deg),
        (lat.sin() as Real, lat.cos() as Real),
    );
    let d = angles.oscillation(&x_arcsec.map(|x| arcsec_to_rad(x) as Real));
    [d.heading_rad, d.roll_rad, d.pitch_rad].map(|r| r as f64 / RAD_PER_DEG)
}

/// The truth a log row was judged against.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TruthAt {
    /// The installation errors in force, arcsec.
    pub errors_arcsec: [f64; 4],
    /// The oscillation of eq (2) in the row's attitude, deg (heading, roll, pitch).
    pub oscillation_deg: [f64; 3],
}

/// Index of the truth row for a log time (the generator writes one row per interval from 0).
pub fn truth_index(time_s: f64, interval_s: f64, len: usize) -> Option<usize> {
    if !time_s.is_finite() || time_s < 0.0 {
        return None;
    }
    let k = (time_s / interval_s).round();
    ((k - time_s / interval_s).abs() < 1e-6 && (k as usize) < len).then_some(k as usize)
}

/// The full report of one replay against the truth.
#[derive(Clone, Debug)]
pub struct Report {
    /// The accuracy table's numbers.
    pub accuracy: Accuracy,
    /// Over the rows from the first estimate to the end (a generated truth only).
    pub rms_from_first_estimate: Option<AttitudeRms>,
    /// Over the last quarter of the truth's time span (a generated truth only).
    pub rms_last_quarter: Option<AttitudeRms>,
}

/// What the rows are judged against.
#[derive(Clone, Copy, Debug)]
pub enum TruthRows<'a> {
    /// Constant installation errors, arcsec (a truth file with `x_arcsec` only): accuracy only.
    Constant([f64; 4]),
    /// The generator's rows and their truth: accuracy against the errors in force, and the
    /// attitude error of eq (2) before and after compensation. `time_offset_s`: what the recorder
    /// added to the log's time stamps (its `--time-offset`), taken off before matching;
    /// `errors_step_at_s`: when the truth's errors change (its `errors_step`), s from the start.
    Generated {
        /// The generator's rows, one per sample instant.
        rows: &'a [Row],
        /// Their truth, in the same order.
        truth: &'a [RowTruth],
        /// What the recorder added to the log's time stamps, s.
        time_offset_s: f64,
        /// When the truth's errors change, s from the start.
        errors_step_at_s: Option<f64>,
    },
}

impl<'a> TruthRows<'a> {
    /// The rows a log is judged against: the truth beside it ([`LogTruth`]), its scenario's rows
    /// when it names one, its errors alone otherwise.
    pub fn of(truth: &'a LogTruth) -> TruthRows<'a> {
        let (file, generated) = (&truth.file, truth.generated.as_ref());
        match generated {
            Some(g) => TruthRows::Generated {
                rows: &g.rows,
                truth: &g.truth,
                time_offset_s: file
                    .params
                    .as_ref()
                    .map_or(0.0, |p| p.recording.time_offset_s),
                errors_step_at_s: file
                    .params
                    .as_ref()
                    .and_then(|p| p.errors_step.map(|step| step.at_s)),
            },
            None => TruthRows::Constant(file.x_arcsec),
        }
    }
}

/// Builds a [`Report`] row by row, as the replay goes: it holds no rows of its own.
#[derive(Clone, Debug)]
pub struct ReportBuilder<'a> {
    truth: TruthRows<'a>,
    tracker: Tracker,
    rms_all: Option<RmsAccumulator>,
    rms_quarter: Option<RmsAccumulator>,
    held: Option<Estimate>,
    /// Index of the generated row nearest the last row's time.
    cursor: usize,
}

impl<'a> ReportBuilder<'a> {
    /// A builder judging rows against `truth`, reporting at [`REPORT_TIMES_S`].
    pub fn new(truth: TruthRows<'a>) -> Self {
        let errors_step_at_s = match truth {
            TruthRows::Constant(_) => None,
            TruthRows::Generated {
                errors_step_at_s, ..
            } => errors_step_at_s,
        };
        let rms_quarter = match truth {
            TruthRows::Constant(_) => None,
            TruthRows::Generated { rows, .. } => {
                let end_s = rows
                    .iter()
                    .map(|r| r.time_s)
                    .filter(|t| t.is_finite())
                    .fold(0.0, f64::max);
                Some(RmsAccumulator::new(0.75 * end_s))
            }
        };
        ReportBuilder {
            truth,
            tracker: Tracker::new(&REPORT_TIMES_S).with_errors_step(errors_step_at_s),
            rms_all: None,
            rms_quarter,
            held: None,
            cursor: 0,
        }
    }

    /// Index of the generated row nearest in time to `time_s` (moves from the last one found).
    fn nearest(&mut self, rows: &[Row], time_s: f64) -> Option<usize> {
        if rows.is_empty() || !time_s.is_finite() {
            return None;
        }
        let d = |k: usize| (rows[k].time_s - time_s).abs();
        let mut k = self.cursor.min(rows.len() - 1);
        while k + 1 < rows.len() && d(k + 1) <= d(k) {
            k += 1;
        }
        while k > 0 && d(k - 1) < d(k) {
            k -= 1;
        }
        self.cursor = k;
        Some(k)
    }

    /// One log row and the estimator's result for it; returns the truth it was judged against.
    pub fn observe(&mut self, row: &Row, result: &Result<Output, SampleError>) -> Option<TruthAt> {
        if let Ok(out) = result {
            self.held = out.estimate;
        }
        let (truth_errors, oscillation_deg) = match self.truth {
            TruthRows::Constant(x) => (x, oscillation_deg(row, &x)),
            TruthRows::Generated {
                rows,
                truth,
                time_offset_s,
                ..
            } => {
                let t = row.time_s - time_offset_s;
                let k = self.nearest(rows, t)?;
                let tr = truth.get(k)?;
                if let Ok(out) = result {
                    if out.estimate.is_some() && self.rms_all.is_none() {
                        self.rms_all = Some(RmsAccumulator::new(t));
                    }
                    let res = residual_arcsec(row, &out.corrected, tr);
                    if let Some(acc) = self.rms_all.as_mut() {
                        acc.add(t, &res, tr);
                    }
                    if let Some(acc) = self.rms_quarter.as_mut() {
                        acc.add(t, &res, tr);
                    }
                }
                (tr.errors_arcsec, tr.oscillation_deg)
            }
        };
        let offset_s = match self.truth {
            TruthRows::Generated { time_offset_s, .. } => time_offset_s,
            TruthRows::Constant(_) => 0.0,
        };
        let status = result.as_ref().ok().map(|out| out.status);
        self.tracker.observe(
            row.time_s - offset_s,
            self.held.as_ref(),
            status,
            &truth_errors,
        );
        Some(TruthAt {
            errors_arcsec: truth_errors,
            oscillation_deg,
        })
    }

    /// The report; `interval_s` is the log's sample interval.
    pub fn finish(&self, interval_s: f64) -> Report {
        Report {
            accuracy: self.tracker.finish(interval_s),
            rms_from_first_estimate: self.rms_all.as_ref().map(RmsAccumulator::finish),
            rms_last_quarter: self.rms_quarter.as_ref().map(RmsAccumulator::finish),
        }
    }
}

/// Evaluates a replay of `rows` (the log as read) against the generator's rows and truth (whose
/// errors change at `errors_step_at_s`, if they do).
pub fn evaluate(
    rows: &[Row],
    steps: &[Step],
    generated_rows: &[Row],
    truth: &[RowTruth],
    errors_step_at_s: Option<f64>,
    interval_s: f64,
) -> Report {
    let mut builder = ReportBuilder::new(TruthRows::Generated {
        rows: generated_rows,
        truth,
        time_offset_s: 0.0,
        errors_step_at_s,
    });
    for (row, step) in rows.iter().zip(steps) {
        builder.observe(row, &step.result);
    }
    builder.finish(interval_s)
}

fn fmt_time(t: Option<f64>) -> String {
    t.map(|t| format!("{t:.0} s"))
        .unwrap_or_else(|| "not within at end".to_string())
}

/// A table's head and rows, as text cells.
pub type Table = (Vec<String>, Vec<Vec<String>>);

/// A table as markdown, one line a row, cells followed by ` | ` as the tool prints them.
pub fn markdown(head: &[String], rows: &[Vec<String>]) -> String {
    let line = |cells: &[String]| format!("| {} |\n", cells.join(" | "));
    let mut s = line(head);
    s.push('|');
    s.push_str(&"---|".repeat(head.len()));
    s.push('\n');
    for r in rows {
        s.push_str(&line(r));
    }
    s
}

/// The accuracy table: per error, the percentage and absolute error at each report time and the
/// settling times.
pub fn accuracy_table(a: &Accuracy) -> Table {
    let mut head = vec!["x".to_string()];
    head.extend(
        a.points
            .iter()
            .map(|p| format!("{:.0} s: % / arcsec", p.time_s)),
    );
    head.push("within 0.5 % from".into());
    head.push("within 10 arcsec from".into());
    let rows = (0..4)
        .map(|i| {
            let mut row = vec![format!("x{}", i + 1)];
            for p in &a.points {
                row.push(match (p.percent, p.error_arcsec) {
                    (Some(pc), Some(e)) => match pc[i] {
                        Some(p) => format!("{p:.3} % / {:.2}", e[i].abs()),
                        None => format!("- / {:.2}", e[i].abs()),
                    },
                    _ => "no estimate".to_string(),
                });
            }
            row.push(fmt_time(a.within_percent_from_s[i]));
            row.push(fmt_time(a.within_arcsec_from_s[i]));
            row
        })
        .collect();
    (head, rows)
}

/// The accuracy table as text (markdown).
pub fn format_accuracy(a: &Accuracy) -> String {
    let (head, rows) = accuracy_table(a);
    markdown(&head, &rows)
}

/// The title of an attitude RMS table.
pub fn rms_title(label: &str, r: &AttitudeRms) -> String {
    format!(
        "attitude error of eq (2), RMS arcsec, {label} ({:.0}-{:.0} s, {} rows)",
        r.from_s, r.to_s, r.rows
    )
}

/// The attitude RMS table: before and after compensation, per axis.
pub fn rms_table(r: &AttitudeRms) -> Table {
    let head = ["", "heading", "roll", "pitch"].map(String::from).to_vec();
    let row = |name: &str, v: &[f64; 3]| {
        vec![
            name.to_string(),
            format!("{:.2}", v[0]),
            format!("{:.2}", v[1]),
            format!("{:.2}", v[2]),
        ]
    };
    (
        head,
        vec![
            row("before compensation", &r.before_arcsec),
            row("after compensation", &r.after_arcsec),
        ],
    )
}

/// The attitude RMS table as text (markdown).
pub fn format_rms(label: &str, r: &AttitudeRms) -> String {
    let (head, rows) = rms_table(r);
    format!("{}:\n{}", rms_title(label, r), markdown(&head, &rows))
}

/// Methods side by side (one line each): largest percentage error of the four at each report
/// time, settling times of all four, attitude RMS after compensation over the last quarter.
pub fn format_side_by_side(reports: &[(&str, &Report)]) -> String {
    let times: Vec<f64> = reports
        .first()
        .map(|(_, r)| r.accuracy.points.iter().map(|p| p.time_s).collect())
        .unwrap_or_default();
    let mut s = String::from("| method | ");
    for t in &times {
        s.push_str(&format!("max % at {t:.0} s | "));
    }
    s.push_str("all within 0.5 % from | all within 10 arcsec from | RMS after, last quarter (heading / roll / pitch arcsec) |\n|---|");
    s.push_str(&"---|".repeat(times.len() + 3));
    s.push('\n');
    for (name, r) in reports {
        s.push_str(&format!("| {name} | "));
        for p in &r.accuracy.points {
            match p.percent {
                Some(pc) => s.push_str(&format!(
                    "{:.3} | ",
                    pc.iter().flatten().fold(0.0f64, |m, v| m.max(*v))
                )),
                None => s.push_str("no estimate | "),
            }
        }
        let rms = r.rms_last_quarter.map_or("-".to_string(), |q| {
            let q = q.after_arcsec;
            format!("{:.2} / {:.2} / {:.2}", q[0], q[1], q[2])
        });
        s.push_str(&format!(
            "{} | {} | {rms} |\n",
            fmt_time(r.accuracy.all_within_percent_from_s()),
            fmt_time(r.accuracy.all_within_arcsec_from_s()),
        ));
    }
    s
}

/// The accuracy of a replay with `method` against the truth as `estimate` and `run` print it:
/// the table, the honesty of the 1-sigma and the attitude error's RMS.
pub fn write_report(w: &mut dyn Write, method: Method, rep: &Report) -> std::io::Result<()> {
    writeln!(w, "\naccuracy against the truth, {}:", method_label(method))?;
    write!(w, "{}", format_accuracy(&rep.accuracy))?;
    write!(w, "{}", format_honesty(&rep.accuracy.honesty))?;
    if let Some(r) = &rep.rms_from_first_estimate {
        write!(w, "{}", format_rms("from the first estimate", r))?;
    }
    if let Some(r) = &rep.rms_last_quarter {
        write!(w, "{}", format_rms("last quarter of the run", r))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use estimator_core::units::arcsec_to_rad;
    use estimator_core::Real;

    fn est(x: [f64; 4]) -> Estimate {
        est_sigma(x, [0.0; 4])
    }

    fn est_sigma(x: [f64; 4], sigma_arcsec: [f64; 4]) -> Estimate {
        Estimate {
            x_rad: x.map(|a| arcsec_to_rad(a) as Real),
            sigma_rad: sigma_arcsec.map(|a| arcsec_to_rad(a) as Real),
        }
    }

    #[test]
    fn tracker_keeps_the_reported_sigma_and_counts_errors_within_two_sigma() {
        let truth = [100.0, -100.0, 200.0, 1000.0];
        let mut t = Tracker::new(&[1.0, 3.0]);
        t.observe(0.0, None, None, &truth);
        t.observe(1.0, None, None, &truth);
        // Errors 1, -2.5, 0.5, 10 arcsec against 1-sigma 1, 1, 0.2, 4: within 2 sigma is x1 only
        // (1 <= 2; 2.5 > 2, 0.5 > 0.4, 10 > 8); within 3 sigma all four.
        t.observe(
            2.0,
            Some(&est_sigma(
                [101.0, -102.5, 200.5, 1010.0],
                [1.0, 1.0, 0.2, 4.0],
            )),
            None,
            &truth,
        );
        let a = t.finish(1.0);
        assert_eq!(a.points[0].sigma_arcsec, None);
        assert_eq!(
            a.points[0].within_sigmas(2.0),
            0,
            "no estimate counts as outside"
        );
        let s = a.points[1].sigma_arcsec.unwrap();
        assert!(
            (s[3] - 4.0).abs() < 1e-4 && (s[2] - 0.2).abs() < 1e-5,
            "{s:?}"
        );
        assert_eq!(a.points[1].within_sigmas(2.0), 1);
        assert_eq!(a.points[1].within_sigmas(3.0), 4);
    }

    #[test]
    fn tracker_settling_and_report_times() {
        let truth = [100.0, -100.0, 200.0, 1000.0];
        let mut t = Tracker::new(&[2.0, 4.0, 10.0]);
        t.observe(0.0, None, None, &truth);
        t.observe(
            1.0,
            Some(&est([130.0, -100.0, 200.0, 1000.0])),
            None,
            &truth,
        );
        t.observe(
            2.0,
            Some(&est([100.2, -100.0, 200.0, 1003.0])),
            None,
            &truth,
        );
        // 3 s missing: the 4 s report time is taken at 5 s's predecessor (2 s)
        t.observe(
            5.0,
            Some(&est([101.0, -100.0, 200.0, 1012.0])),
            None,
            &truth,
        );
        t.observe(
            6.0,
            Some(&est([100.1, -100.0, 200.0, 1001.0])),
            None,
            &truth,
        );
        let a = t.finish(1.0);
        assert_eq!(a.points.len(), 2, "10 s is past the end");
        let e2 = a.points[0].error_arcsec.unwrap();
        assert!((e2[0] - 0.2).abs() < 1e-3 && (e2[3] - 3.0).abs() < 1e-3);
        assert_eq!(a.points[1].error_arcsec, a.points[0].error_arcsec);
        // x1: within 0.5 % (0.5 arcsec) at 2 s, out at 5 s (1.0), back at 6 s.
        assert_eq!(a.within_percent_from_s[0], Some(6.0));
        // x4: within 10 arcsec at 2 s, out at 5 s (12), back at 6 s.
        assert_eq!(a.within_arcsec_from_s[3], Some(6.0));
        assert_eq!(a.within_arcsec_from_s[1], Some(1.0));
        assert_eq!(a.all_within_arcsec_from_s(), Some(6.0));
    }

    #[test]
    fn unsettled_error_reports_none() {
        let truth = [100.0; 4];
        let mut t = Tracker::new(&[]);
        t.observe(0.0, Some(&est([100.0, 100.0, 100.0, 100.0])), None, &truth);
        t.observe(1.0, Some(&est([100.0, 100.0, 100.0, 120.0])), None, &truth);
        let a = t.finish(1.0);
        assert_eq!(
            a.within_arcsec_from_s,
            [Some(0.0), Some(0.0), Some(0.0), None]
        );
        assert_eq!(a.all_within_arcsec_from_s(), None);
    }

    #[test]
    fn a_true_error_of_zero_is_judged_in_arcsec_only() {
        let truth = [100.0, 0.0, 200.0, 0.0];
        let mut t = Tracker::new(&[1.0]);
        t.observe(0.0, Some(&est([100.0, 0.0, 200.0, 3.0])), None, &truth);
        t.observe(1.0, Some(&est([100.0, 0.0, 200.0, 3.0])), None, &truth);
        let a = t.finish(1.0);
        let pc = a.points[0].percent.unwrap();
        assert!(
            pc[0].unwrap() < 1e-5 && pc[2].unwrap() < 1e-5 && pc[1].is_none() && pc[3].is_none(),
            "{pc:?}"
        );
        assert_eq!(
            a.within_percent_from_s,
            [Some(0.0); 4],
            "x4 is 3 arcsec off a true 0: within 10 arcsec"
        );
        let text = format_accuracy(&a);
        assert!(!text.contains("inf") && !text.contains("NaN"), "{text}");
        assert!(text.contains("| x4 | - / 3.00 |"), "{text}");
    }

    fn output(time_s: f64, x: [f64; 4]) -> Result<Output, SampleError> {
        Ok(Output {
            time_s,
            status: estimator_core::Status::Estimating,
            estimate: Some(est(x)),
            corrected: estimator_core::Attitude {
                heading_rad: 0.0,
                roll_rad: 0.0,
                pitch_rad: 0.0,
            },
            health: estimator_core::Health::NONE,
        })
    }

    fn row(time_s: f64) -> Row {
        Row {
            time_s,
            rotation_deg: 0.0,
            platform_deg: 0.0,
            latitude_deg: 40.0,
            heading_deg: 0.0,
            roll_deg: 0.0,
            pitch_deg: 0.0,
        }
    }

    #[test]
    fn rows_are_matched_to_the_truth_nearest_in_time() {
        // A truth whose errors change at 10 s; a log starting at 1000.5 s would find no row on the
        // truth's grid, and a jittered one neither.
        let generated: Vec<Row> = (0..20).map(|k| row(k as f64)).collect();
        let truth: Vec<RowTruth> = (0..20)
            .map(|k| RowTruth {
                true_attitude_deg: [0.0; 3],
                oscillation_deg: [0.0; 3],
                errors_arcsec: if k < 10 { [10.0; 4] } else { [20.0; 4] },
            })
            .collect();
        let mut b = ReportBuilder::new(TruthRows::Generated {
            rows: &generated,
            truth: &truth,
            time_offset_s: 0.0,
            errors_step_at_s: None,
        });
        for (k, jitter) in [
            0.3, -0.2, 0.1, 0.45, -0.4, 0.0, 0.2, -0.1, 0.3, 0.0, 0.2, -0.3, 0.1, 0.0,
        ]
        .iter()
        .enumerate()
        {
            let t = k as f64 + jitter;
            b.observe(
                &row(t),
                &output(
                    t,
                    if t.round() < 10.0 {
                        [10.0; 4]
                    } else {
                        [20.0; 4]
                    },
                ),
            );
        }
        let a = b.finish(1.0).accuracy;
        assert_eq!(
            a.within_percent_from_s[0],
            Some(0.3),
            "every row exact against its nearest truth: {a:?}"
        );
        // Constant truth, any start time.
        let mut c = ReportBuilder::new(TruthRows::Constant([200.0, -150.0, 300.0, 0.0]));
        for k in 0..30_000 {
            let t = 1000.5 + k as f64;
            c.observe(&row(t), &output(t, [200.0, -150.0, 300.0, 0.0]));
        }
        let r = c.finish(1.0);
        assert!(r.rms_last_quarter.is_none());
        assert_eq!(r.accuracy.points.len(), 1);
        assert_eq!(
            r.accuracy.points[0].error_arcsec.map(|e| e
                .map(f64::abs)
                .iter()
                .fold(0.0, |m: f64, v| m.max(*v))
                < 1e-3),
            Some(true)
        );
        assert_eq!(r.accuracy.within_percent_from_s, [Some(1000.5); 4]);
        assert_eq!(r.accuracy.within_arcsec_from_s, [Some(1000.5); 4]);
    }

    #[test]
    fn the_cores_oscillation_of_eq_2_is_the_generators() {
        // The oscillation a constant truth file puts into each row, from the core's rows, against
        // the generator's own eq (2), over a one-way and a reciprocating log.
        for scheme in [
            crate::sim::rotation_scheme::RotationScheme::Continuous,
            crate::sim::rotation_scheme::RotationScheme::Reciprocating,
        ] {
            let mut p = crate::sim::scenario::ScenarioParams::new(
                crate::sim::scenario::ScenarioKind::Sea,
                3,
            );
            p.duration_s = 2000.0;
            p.scheme = scheme;
            let g = crate::sim::scenario::generate(&p);
            for (row, truth) in g.rows.iter().zip(&g.truth) {
                let ours = oscillation_deg(row, &truth.errors_arcsec);
                for (a, (o, t)) in ours.iter().zip(&truth.oscillation_deg).enumerate() {
                    let diff_arcsec = (o - t).abs() * 3600.0;
                    assert!(
                        diff_arcsec < 1e-3,
                        "{scheme:?} t = {}: axis {a} off by {diff_arcsec} arcsec",
                        row.time_s
                    );
                }
            }
        }
    }

    #[test]
    fn honesty_counts_rows_beyond_2_3_and_5_sigma_from_the_first_estimate() {
        let truth = [100.0, -100.0, 200.0, 1000.0];
        let one = [1.0; 4];
        let off = |e: [f64; 4]| est_sigma(core::array::from_fn(|i| truth[i] + e[i]), one);
        let mut t = Tracker::new(&[]);
        t.observe(0.0, None, None, &truth);
        t.observe(1.0, Some(&off([0.5, 0.0, 0.0, 0.0])), None, &truth);
        t.observe(2.0, Some(&off([0.0, 2.5, 0.0, 0.0])), None, &truth);
        t.observe(3.0, Some(&off([0.0, 0.0, -3.5, 0.0])), None, &truth);
        t.observe(4.0, None, None, &truth);
        t.observe(5.0, Some(&off([0.0, 0.0, 0.0, 6.0])), None, &truth);
        t.observe(6.0, Some(&off([1.9, -1.9, 1.9, -1.9])), None, &truth);
        let h = t.finish(1.0).honesty;
        assert_eq!(
            (
                h.rows,
                h.beyond_2_sigma_rows,
                h.beyond_3_sigma_rows,
                h.beyond_5_sigma_rows,
                h.rows_without_estimate,
                h.rows_left_out
            ),
            (5, 3, 2, 1, 1, 0),
            "the row before the first estimate is not counted, the one after without one apart"
        );
        let l = h.largest.unwrap();
        assert_eq!((l.time_s, l.error, l.run), (5.0, 4, None));
        assert!((l.ratio - 6.0).abs() < 1e-3, "{l:?}");
        assert!((h.share_beyond(0) - 0.6).abs() < 1e-12);
        assert_eq!(
            format_honesty(&h),
            "1-sigma honesty, 5 rows from the first estimate: some error beyond 2 sigma on 60.0 %, \
             beyond 3 sigma on 40.0 %, beyond 5 sigma on 20.0 %; largest |error|/sigma 6.0 (x4 at 5 s)\n  \
             1 row after the first estimate without one, not judged\n"
        );
        // Pooled with a second run whose largest ratio is larger: counts add, its run is named.
        let mut pooled = Honesty::default();
        pooled.pool(&h, 0);
        let mut t = Tracker::new(&[]);
        t.observe(2940.0, Some(&off([0.0, 0.0, 8.0, 0.0])), None, &truth);
        pooled.pool(&t.finish(1.0).honesty, 1);
        assert_eq!((pooled.rows, pooled.beyond_5_sigma_rows), (6, 2));
        assert!(format_honesty_shares(&pooled)
            .ends_with("largest |error|/sigma 8.0 (run 1: x3 at 2,940 s)"));
        assert_eq!(Tracker::new(&[]).finish(1.0).honesty, Honesty::default());
    }

    /// Rows 0..6000 s, an estimate from 10 s, errors changing at 100 s: the estimate is 50 sigma
    /// off until 3000 s, then 0.1 sigma; `errors_changed` reported at `declared_s`.
    fn through_a_change(declared_s: Option<f64>) -> Honesty {
        let truth = [100.0, -100.0, 200.0, 1000.0];
        let mut t = Tracker::new(&[]).with_errors_step(Some(100.0));
        for k in 0..6000 {
            let time_s = k as f64;
            let e = if (100.0..3000.0).contains(&time_s) {
                50.0
            } else {
                0.1
            };
            let estimate = est_sigma([truth[0] + e, truth[1], truth[2], truth[3]], [1.0; 4]);
            let status = if declared_s.is_some_and(|d| (d..d + 100.0).contains(&time_s)) {
                Status::ErrorsChanged
            } else {
                Status::Estimating
            };
            t.observe(time_s, (k >= 10).then_some(&estimate), Some(status), &truth);
        }
        t.finish(1.0).honesty
    }

    #[test]
    fn honesty_leaves_out_a_change_of_the_errors_until_2000_s_after_its_declaration() {
        // Declared at 2600 s: 100-4600 s left out (the rows after 2100 s waited for it).
        let h = through_a_change(Some(2600.0));
        assert_eq!(
            (h.rows, h.rows_left_out, h.beyond_2_sigma_rows),
            (90 + 1400, 4500, 0)
        );
        assert_eq!(
            (h.left_out_s, h.declared_at_s),
            (Some([100.0, 4600.0]), Some(2600.0))
        );
        assert!(h.largest.unwrap().ratio < 0.2);
        assert!(
            format_honesty(&h).ends_with(
                "\n  4,500 rows of the change of the errors left out (100 s to 4,600 s: 2,000 s after errors_changed at 2,600 s)\n"
            ),
            "{}",
            format_honesty(&h)
        );
        // Declared at 500 s: 100-2500 s left out; 2500-3000 s counted, 50 sigma off.
        let h = through_a_change(Some(500.0));
        assert_eq!(
            (h.rows, h.rows_left_out, h.beyond_5_sigma_rows),
            (90 + 3500, 2400, 500)
        );
        // Never declared (or only before the change): 100-2100 s left out, the rest counted.
        for declared in [None, Some(0.0)] {
            let h = through_a_change(declared);
            assert_eq!(
                (h.rows, h.rows_left_out, h.beyond_5_sigma_rows),
                (90 + 3900, 2000, 900)
            );
            assert_eq!(
                (h.left_out_s, h.declared_at_s),
                (Some([100.0, 2100.0]), None)
            );
            let l = h.largest.unwrap();
            assert_eq!((l.time_s, l.error), (2100.0, 1));
            assert!(format_honesty(&h)
                .contains("(100 s to 2,100 s: never declared: 2,000 s after the change)"));
        }
    }

    #[test]
    fn shares_of_rows_and_thousands_read_as_printed() {
        assert_eq!(thousands(19_401), "19,401");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1_000_000), "1,000,000");
        assert_eq!(percent_of_rows(0, 19_401), "0 %");
        assert_eq!(percent_of_rows(58, 19_401), "0.3 %");
        assert_eq!(percent_of_rows(2, 19_401), "0.01 %");
        assert_eq!(percent_of_rows(1, 200_000), "0.0005 %");
        assert_eq!(percent_of_rows(7, 7), "100 %");
        assert_eq!(percent_of_rows(0, 0), "-");
    }

    #[test]
    fn truth_index_matches_grid() {
        assert_eq!(truth_index(3.0, 1.0, 10), Some(3));
        assert_eq!(truth_index(3.5, 1.0, 10), None);
        assert_eq!(truth_index(10.0, 1.0, 10), None);
        assert_eq!(truth_index(f64::NAN, 1.0, 10), None);
    }
}
