//! Accuracy of a replay against the truth: the accuracy table of the `estimate` and `run` commands.
//!
//! - Absolute percentage error of eq (7): `|x_hat - x| / |x| * 100`, and absolute error in arcsec,
//!   at [`REPORT_TIMES_S`] (those inside the run; "at T" = the estimate on board at the last row
//!   with `time_s <= T`).
//! - Settling times: the first time after which an error stays within 0.5 % (resp. 10 arcsec) until
//!   the end of the run; rows without an estimate count as outside.
//! - Attitude error before and after compensation: the oscillation of eq (2) put into the log
//!   (truth) versus what is left of it after the core's correction:
//!   `residual = oscillation_in - (raw attitude - corrected attitude)`. The true attitude, the
//!   low-frequency errors and the noise cancel out of this difference exactly.

use crate::replay::Step;
use crate::scenario::{Row, RowTruth};
use estimator_core::units::rad_to_arcsec;
use estimator_core::Estimate;

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

/// Eq (7): absolute percentage error; infinite for a true error of 0 and a non-zero estimate error.
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
        self.last = err.zip(sigmas_arcsec(estimate)).map(|(e, sigma)| (e, *truth_arcsec, sigma));
        for i in 0..4 {
            let (in_pct, in_as) = match err {
                Some(e) => (percent_error(e[i], truth_arcsec[i]) <= PERCENT_THRESHOLD, e[i].abs() <= ARCSEC_THRESHOLD),
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
            let state = if k < self.next_time { self.at[k] } else { self.last };
            points.push(AccuracyAt {
                time_s: t,
                error_arcsec: state.map(|s| s.0),
                sigma_arcsec: state.map(|s| s.2),
                percent: state.map(|(e, x, _)| core::array::from_fn(|i| percent_error(e[i], x[i]))),
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
    pub percent: Option<[f64; 4]>,
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
    /// Per error: first time after which it stays within 0.5 %; `None`: not within at the end.
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
    v.iter().try_fold(f64::NEG_INFINITY, |m, t| t.map(|t| m.max(t)))
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
pub fn residual_arcsec(row: &Row, corrected: &estimator_core::Attitude, truth: &RowTruth) -> [f64; 3] {
    let raw = [row.heading_deg, row.roll_deg, row.pitch_deg];
    let cor = [corrected.heading_rad as f64, corrected.roll_rad as f64, corrected.pitch_rad as f64].map(|r| r.to_degrees());
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
        RmsAccumulator { from_s, to_s: from_s, rows: 0, before: [0.0; 3], after: [0.0; 3] }
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

/// Index of the truth row for a log time (the generator writes one row per interval from 0).
pub fn truth_index(time_s: f64, interval_s: f64, len: usize) -> Option<usize> {
    if !time_s.is_finite() || time_s < 0.0 {
        return None;
    }
    let k = (time_s / interval_s).round();
    ((k - time_s / interval_s).abs() < 1e-6 && (k as usize) < len).then_some(k as usize)
}

/// The full report of one replay against a regenerated truth.
#[derive(Clone, Debug)]
pub struct Report {
    pub accuracy: Accuracy,
    /// Over the rows from the first estimate to the end.
    pub rms_from_first_estimate: Option<AttitudeRms>,
    /// Over the last quarter of the run.
    pub rms_last_quarter: AttitudeRms,
}

/// Evaluates a replay of `rows` (the log as read) against the generator's truth rows.
pub fn evaluate(rows: &[Row], steps: &[Step], truth: &[RowTruth], interval_s: f64) -> Report {
    let mut tracker = Tracker::new(&REPORT_TIMES_S);
    let first_estimate_s = steps.iter().find_map(|s| s.result.ok().and_then(|o| o.estimate.map(|_| o.time_s)));
    let end_s = rows.iter().map(|r| r.time_s).filter(|t| t.is_finite()).fold(0.0, f64::max);
    let mut rms_all = first_estimate_s.map(RmsAccumulator::new);
    let mut rms_quarter = RmsAccumulator::new(0.75 * end_s);
    let mut held: Option<Estimate> = None;
    for (row, step) in rows.iter().zip(steps) {
        let Some(k) = truth_index(step.time_s, interval_s, truth.len()) else { continue };
        let tr = &truth[k];
        if let Ok(out) = &step.result {
            held = out.estimate;
            let res = residual_arcsec(row, &out.corrected, tr);
            if let Some(acc) = rms_all.as_mut() {
                acc.add(step.time_s, &res, tr);
            }
            rms_quarter.add(step.time_s, &res, tr);
        }
        tracker.observe(step.time_s, held.as_ref(), &tr.errors_arcsec);
    }
    Report {
        accuracy: tracker.finish(interval_s),
        rms_from_first_estimate: rms_all.map(|a| a.finish()),
        rms_last_quarter: rms_quarter.finish(),
    }
}

fn fmt_time(t: Option<f64>) -> String {
    t.map(|t| format!("{t:.0} s")).unwrap_or_else(|| "not within at end".to_string())
}

/// The accuracy table as text (markdown).
pub fn format_accuracy(a: &Accuracy) -> String {
    let mut s = String::new();
    s.push_str("| x | ");
    for p in &a.points {
        s.push_str(&format!("{:.0} s: % / arcsec | ", p.time_s));
    }
    s.push_str("within 0.5 % from | within 10 arcsec from |\n|---|");
    for _ in &a.points {
        s.push_str("---|");
    }
    s.push_str("---|---|\n");
    for i in 0..4 {
        s.push_str(&format!("| x{} | ", i + 1));
        for p in &a.points {
            match (p.percent, p.error_arcsec) {
                (Some(pc), Some(e)) => s.push_str(&format!("{:.3} % / {:.2} | ", pc[i], e[i].abs())),
                _ => s.push_str("no estimate | "),
            }
        }
        s.push_str(&format!("{} | {} |\n", fmt_time(a.within_percent_from_s[i]), fmt_time(a.within_arcsec_from_s[i])));
    }
    s
}

/// The attitude RMS table as text (markdown).
pub fn format_rms(label: &str, r: &AttitudeRms) -> String {
    let mut s = format!("attitude error of eq (2), RMS arcsec, {label} ({:.0}-{:.0} s, {} rows):\n", r.from_s, r.to_s, r.rows);
    s.push_str("| | heading | roll | pitch |\n|---|---|---|---|\n");
    let f = |v: &[f64; 3]| format!("{:.2} | {:.2} | {:.2}", v[0], v[1], v[2]);
    s.push_str(&format!("| before compensation | {} |\n", f(&r.before_arcsec)));
    s.push_str(&format!("| after compensation | {} |\n", f(&r.after_arcsec)));
    s
}

/// Methods side by side (one line each): largest percentage error of the four at each report
/// time, settling times of all four, attitude RMS after compensation over the last quarter.
pub fn format_side_by_side(reports: &[(&str, &Report)]) -> String {
    let times: Vec<f64> = reports.first().map(|(_, r)| r.accuracy.points.iter().map(|p| p.time_s).collect()).unwrap_or_default();
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
                Some(pc) => s.push_str(&format!("{:.3} | ", pc.iter().fold(0.0f64, |m, v| m.max(*v)))),
                None => s.push_str("no estimate | "),
            }
        }
        let q = &r.rms_last_quarter.after_arcsec;
        s.push_str(&format!(
            "{} | {} | {:.2} / {:.2} / {:.2} |\n",
            fmt_time(r.accuracy.all_within_percent_from_s()),
            fmt_time(r.accuracy.all_within_arcsec_from_s()),
            q[0],
            q[1],
            q[2]
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
        Estimate { x_rad: x.map(|a| arcsec_to_rad(a) as Real), sigma_rad: sigma_arcsec.map(|a| arcsec_to_rad(a) as Real) }
    }

    #[test]
    fn tracker_keeps_the_reported_sigma_and_counts_errors_within_two_sigma() {
        let truth = [100.0, -100.0, 200.0, 1000.0];
        let mut t = Tracker::new(&[1.0, 3.0]);
        t.observe(0.0, None, &truth);
        t.observe(1.0, None, &truth);
        // Errors 1, -2.5, 0.5, 10 arcsec against 1-sigma 1, 1, 0.2, 4: within 2 sigma is x1 only
        // (1 <= 2; 2.5 > 2, 0.5 > 0.4, 10 > 8); within 3 sigma all four.
        t.observe(2.0, Some(&est_sigma([101.0, -102.5, 200.5, 1010.0], [1.0, 1.0, 0.2, 4.0])), &truth);
        let a = t.finish(1.0);
        assert_eq!(a.points[0].sigma_arcsec, None);
        assert_eq!(a.points[0].within_sigmas(2.0), 0, "no estimate counts as outside");
        let s = a.points[1].sigma_arcsec.unwrap();
        assert!((s[3] - 4.0).abs() < 1e-4 && (s[2] - 0.2).abs() < 1e-5, "{s:?}");
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
        assert_eq!(a.within_arcsec_from_s, [Some(0.0), Some(0.0), Some(0.0), None]);
        assert_eq!(a.all_within_arcsec_from_s(), None);
    }

    #[test]
    fn truth_index_matches_grid() {
        assert_eq!(truth_index(3.0, 1.0, 10), Some(3));
        assert_eq!(truth_index(3.5, 1.0, 10), None);
        assert_eq!(truth_index(10.0, 1.0, 10), None);
        assert_eq!(truth_index(f64::NAN, 1.0, 10), None);
    }
}
