//! Accuracy of a replay against the truth: the accuracy table of the `estimate` and `run` commands.
//! Each log row is judged as it comes ([`ReportBuilder`]) into a [`Report`]; the parts:
//!
//! - Absolute percentage error of eq (7): `|x_hat - x| / |x| * 100`, and absolute error in arcsec,
//!   at [`accuracy::REPORT_TIMES_S`] (those inside the run; "at T" = the estimate on board at the last row
//!   with `time_s <= T`).
//! - Settling times: the first time after which an error stays within 0.5 % (resp. 10 arcsec) until
//!   the end of the run; rows without an estimate count as outside. A true error of 0 has no
//!   percentage error: it is judged in arcsec only (its "within 0.5 %" is "within 10 arcsec").
//! - Each log row is judged against the truth row nearest in time ([`ReportBuilder`]), so logs
//!   starting at any time, shifted or jittered, are judged against the right truth.
//! - Honesty of the reported 1-sigma, row by row ([`honesty::Honesty`]): over every row from the first
//!   estimate on, the share of rows where some of the four |error| exceeds 2, 3 and 5 times its
//!   1-sigma, and the largest |error| / 1-sigma. The rows from a true change of the errors
//!   (`errors_step`) are left out until 2,000 s after the estimator first reports
//!   `errors_changed` from then on (2,000 s after the change if it never does): while it relearns,
//!   its 1-sigma is of the errors before. Rows without an estimate after the first (a restart
//!   before the next one) are counted apart, not in the shares.
//! - Attitude error before and after compensation: the oscillation of eq (2) put into the log
//!   (truth) versus what is left of it after the core's correction:
//!   `residual = oscillation_in - (raw attitude - corrected attitude)`. The true attitude, the
//!   low-frequency errors and the noise cancel out of this difference exactly
//!   ([`attitude_rms`]).
//!
//! [`tables`] puts them in text. What `--report DIR` writes is in the parts: [`timeline`] (the bounded record of a replay or a
//! stream), [`figures`] (the data of each picture) drawn by [`plots`], and [`pages`] (what each
//! command's `report.html` says) written by [`html`].

pub mod accuracy;
pub mod attitude_rms;
pub mod figures;
pub mod honesty;
pub mod html;
pub mod pages;
pub mod plots;
pub mod tables;
pub mod timeline;

use crate::formats::truth_file::LogTruth;
use crate::replay::Step;
use crate::sim::scenario::{Row, RowTruth};
use accuracy::{Accuracy, Tracker, REPORT_TIMES_S};
use attitude_rms::{oscillation_deg, residual_arcsec, AttitudeRms, RmsAccumulator};
use estimator_core::{Estimate, Output, SampleError};

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

#[cfg(test)]
mod tests {
    use super::accuracy::*;
    use super::honesty::*;
    use super::tables::*;
    use super::*;
    use estimator_core::units::arcsec_to_rad;
    use estimator_core::{Real, Status};

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
