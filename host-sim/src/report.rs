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
//! - Attitude error before and after compensation: the oscillation of eq (2) put into the log
//!   (truth) versus what is left of it after the core's correction:
//!   `residual = oscillation_in - (raw attitude - corrected attitude)`. The true attitude, the
//!   low-frequency errors and the noise cancel out of this difference exactly.

use crate::replay::Step;
use crate::scenario::{Row, RowTruth};
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Estimate, Output, SampleError};

/// Times of the accuracy table, s.
pub const REPORT_TIMES_S: [f64; 4] = [20_000.0, 45_000.0, 86_400.0, 172_800.0];
/// Settling thresholds.
pub const PERCENT_THRESHOLD: f64 = 0.5;
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
        }
    }

    /// One row: its time, the estimate on board, and the true errors at that time (arcsec).
    /// Rows with a non-finite time or out of order are ignored.
    pub fn observe(&mut self, time_s: f64, estimate: Option<&Estimate>, truth_arcsec: &[f64; 4]) {
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
        }
    }
}

/// Accuracy at one report time.
#[derive(Clone, Debug, PartialEq)]
pub struct AccuracyAt {
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
    pub points: Vec<AccuracyAt>,
    /// Per error: first time after which it stays within 0.5 % (10 arcsec for a true error of 0);
    /// `None`: not within at the end.
    pub within_percent_from_s: [Option<f64>; 4],
    /// Per error: first time after which it stays within 10 arcsec.
    pub within_arcsec_from_s: [Option<f64>; 4],
    /// The estimator's status at the last accepted row, where the caller recorded it.
    pub final_status: Option<estimator_core::Status>,
}

impl Accuracy {
    /// The latest of the four settling times (all errors within), `None` if one never settles.
    pub fn all_within_percent_from_s(&self) -> Option<f64> {
        latest(&self.within_percent_from_s)
    }
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
    pub from_s: f64,
    pub to_s: f64,
    pub rows: usize,
    pub before_arcsec: [f64; 3],
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
    pub fn new(from_s: f64) -> Self {
        RmsAccumulator {
            from_s,
            to_s: from_s,
            rows: 0,
            before: [0.0; 3],
            after: [0.0; 3],
        }
    }

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
    /// added to the log's time stamps (its `--time-offset`), taken off before matching.
    Generated {
        rows: &'a [Row],
        truth: &'a [RowTruth],
        time_offset_s: f64,
    },
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
    pub fn new(truth: TruthRows<'a>) -> Self {
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
            tracker: Tracker::new(&REPORT_TIMES_S),
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
        self.tracker
            .observe(row.time_s - offset_s, self.held.as_ref(), &truth_errors);
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

/// Evaluates a replay of `rows` (the log as read) against the generator's rows and truth.
pub fn evaluate(
    rows: &[Row],
    steps: &[Step],
    generated_rows: &[Row],
    truth: &[RowTruth],
    interval_s: f64,
) -> Report {
    let mut builder = ReportBuilder::new(TruthRows::Generated {
        rows: generated_rows,
        truth,
        time_offset_s: 0.0,
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
        t.observe(0.0, None, &truth);
        t.observe(1.0, None, &truth);
        // Errors 1, -2.5, 0.5, 10 arcsec against 1-sigma 1, 1, 0.2, 4: within 2 sigma is x1 only
        // (1 <= 2; 2.5 > 2, 0.5 > 0.4, 10 > 8); within 3 sigma all four.
        t.observe(
            2.0,
            Some(&est_sigma(
                [101.0, -102.5, 200.5, 1010.0],
                [1.0, 1.0, 0.2, 4.0],
            )),
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
        t.observe(0.0, None, &truth);
        t.observe(1.0, Some(&est([130.0, -100.0, 200.0, 1000.0])), &truth);
        t.observe(2.0, Some(&est([100.2, -100.0, 200.0, 1003.0])), &truth);
        // 3 s missing: the 4 s report time is taken at 5 s's predecessor (2 s)
        t.observe(5.0, Some(&est([101.0, -100.0, 200.0, 1012.0])), &truth);
        t.observe(6.0, Some(&est([100.1, -100.0, 200.0, 1001.0])), &truth);
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
        t.observe(0.0, Some(&est([100.0, 100.0, 100.0, 100.0])), &truth);
        t.observe(1.0, Some(&est([100.0, 100.0, 100.0, 120.0])), &truth);
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
        t.observe(0.0, Some(&est([100.0, 0.0, 200.0, 3.0])), &truth);
        t.observe(1.0, Some(&est([100.0, 0.0, 200.0, 3.0])), &truth);
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
            crate::rotation_scheme::RotationScheme::Continuous,
            crate::rotation_scheme::RotationScheme::Reciprocating,
        ] {
            let mut p = crate::scenario::ScenarioParams::new(crate::scenario::ScenarioKind::Sea, 3);
            p.duration_s = 2000.0;
            p.scheme = scheme;
            let g = crate::scenario::generate(&p);
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
    fn truth_index_matches_grid() {
        assert_eq!(truth_index(3.0, 1.0, 10), Some(3));
        assert_eq!(truth_index(3.5, 1.0, 10), None);
        assert_eq!(truth_index(10.0, 1.0, 10), None);
        assert_eq!(truth_index(f64::NAN, 1.0, 10), None);
    }
}
