//! The data of the figures, drawn by [`crate::report::plots`]: the paper's figures from a replay and the
//! generator's truth ([`write_figures`]); the report's figures of any log from its [`Timeline`]
//! ([`timeline_figures`]); the Monte Carlo statistics over time ([`monte_carlo_figure`]).

use crate::replay::Step;
use crate::report::html::Figure;
use crate::report::plots::{self, Band, CorrelationPanel, Curve, Lane, Panel, Series, PALETTE};
use crate::report::timeline::{Bucket, Timeline};
use crate::report::{errors_arcsec, percent_error, residual_arcsec, truth_index};
use crate::sim::scenario::{Row, RowTruth};
use crate::study::monte_carlo::Summary;
use estimator_core::correlation::{products, ROLL_SIN};
use estimator_core::installation::Angles;
use estimator_core::units::{rad_to_arcsec, RAD_PER_DEG};
use estimator_core::{Attitude, Estimate, Real, Status};
use plotters::style::RGBColor;
use std::path::{Path, PathBuf};

/// Time span of the Fig. 3 analogue, s.
pub const FIG3_SPAN_S: f64 = 20_000.0;

/// `(time_s, percent)` of each error, for every row with an estimate (Figs. 2 and 4).
pub fn percent_curves(steps: &[Step], truth: &[RowTruth], interval_s: f64) -> [Vec<(f64, f64)>; 4] {
    let mut curves: [Vec<(f64, f64)>; 4] = Default::default();
    let mut held: Option<Estimate> = None;
    for step in steps {
        if let Ok(o) = &step.result {
            held = o.estimate;
        }
        let Some(k) = truth_index(step.time_s, interval_s, truth.len()) else {
            continue;
        };
        let x = &truth[k].errors_arcsec;
        if let Some(e) = errors_arcsec(held.as_ref(), x) {
            for i in 0..4 {
                curves[i].push((step.time_s, percent_error(e[i], x[i])));
            }
        }
    }
    curves
}

/// Heading, roll and pitch errors over time, arcsec: before compensation (the oscillation of
/// eq (2) put in) and after it.
pub struct AttitudeCurves {
    /// Heading, roll and pitch error before compensation: the oscillation of eq (2) put in.
    pub before: [Curve; 3],
    /// Heading, roll and pitch error left after compensation.
    pub after: [Curve; 3],
}

/// Attitude error of eq (2) before (the oscillation put in) and after compensation, arcsec
/// (Figs. 7 and 8).
pub fn attitude_curves(
    rows: &[Row],
    steps: &[Step],
    truth: &[RowTruth],
    interval_s: f64,
) -> AttitudeCurves {
    let mut before: [Vec<(f64, f64)>; 3] = Default::default();
    let mut after: [Vec<(f64, f64)>; 3] = Default::default();
    for (row, step) in rows.iter().zip(steps) {
        let (Ok(out), Some(k)) = (
            &step.result,
            truth_index(step.time_s, interval_s, truth.len()),
        ) else {
            continue;
        };
        let res = residual_arcsec(row, &out.corrected, &truth[k]);
        for a in 0..3 {
            before[a].push((step.time_s, truth[k].oscillation_deg[a] * 3600.0));
            after[a].push((step.time_s, res[a]));
        }
    }
    AttitudeCurves { before, after }
}

/// Fig. 3: for the roll as logged, and split with the truth into the true roll, the oscillatory
/// roll and the rest (low-frequency errors + noise), the
/// cumulative correlation with sin(rho) of eq (8) and its moving average over one rotation period
/// (`window` samples) of eq (11), arcsec. Uses the core's correlation products. `rows` are the
/// logged rows (lost rows missing); each takes its truth by its time (`interval_s` apart).
pub fn correlation_panels(
    rows: &[Row],
    truth: &[RowTruth],
    interval_s: f64,
    window: usize,
) -> Vec<CorrelationPanel> {
    let names = [
        "roll as logged (sum of the three below)",
        "true roll",
        "oscillatory roll (installation errors)",
        "low-frequency errors + noise",
    ];
    let mut sums = [0.0f64; 4];
    let mut corr: [Curve; 4] = Default::default();
    let with_truth = rows.iter().filter_map(|row| {
        truth_index(row.time_s, interval_s, truth.len()).map(|k| (row, &truth[k]))
    });
    for (n, (row, tr)) in with_truth.enumerate() {
        let rad = |deg: f64| (deg * RAD_PER_DEG) as Real;
        let lat = row.latitude_deg * RAD_PER_DEG;
        let angles = Angles::new(
            rad(estimator_core::units::wrap_deg(row.rotation_deg)),
            rad(estimator_core::units::wrap_deg(row.platform_deg)),
            (lat.sin() as Real, lat.cos() as Real),
        );
        let true_roll = tr.true_attitude_deg[1];
        let osc_roll = tr.oscillation_deg[1];
        let rest_roll = row.roll_deg - true_roll - osc_roll;
        for (c, roll_deg) in [row.roll_deg, true_roll, osc_roll, rest_roll]
            .into_iter()
            .enumerate()
        {
            let p = products(
                &Attitude {
                    heading_rad: 0.0,
                    roll_rad: rad(roll_deg),
                    pitch_rad: 0.0,
                },
                &angles,
            )[ROLL_SIN];
            sums[c] += p as f64;
            corr[c].push((row.time_s, rad_to_arcsec(sums[c] / (n + 1) as f64)));
        }
    }
    names
        .iter()
        .zip(corr)
        .map(|(name, c)| {
            let avg = moving_average(&c, window);
            (name.to_string(), c, avg)
        })
        .collect()
}

/// Moving average of the values over `window` points, from the first full window on.
pub fn moving_average(points: &[(f64, f64)], window: usize) -> Vec<(f64, f64)> {
    let window = window.max(1);
    let mut out = Vec::with_capacity(points.len());
    let mut sum = 0.0;
    for (i, &(t, v)) in points.iter().enumerate() {
        sum += v;
        if i >= window {
            sum -= points[i - window].1;
        }
        if i + 1 >= window {
            out.push((t, sum / window as f64));
        }
    }
    out
}

/// Writes every figure of one scenario into `dir`; `replays` are (method name, steps), the
/// first is the method whose corrected attitude goes into Figs. 7-8. Returns the files written.
pub fn write_figures(
    dir: &Path,
    rows: &[Row],
    truth: &[RowTruth],
    x_arcsec: &[f64; 4],
    interval_s: f64,
    window: usize,
    replays: &[(&str, &[Step])],
) -> anyhow::Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    for (name, steps) in replays {
        let fig = if *name == "traditional" {
            "fig2"
        } else {
            "fig4"
        };
        let path = dir.join(format!("{fig}_percent_error_{name}.png"));
        plots::percent_error_figure(
            &path,
            &format!("Absolute percentage error, {name} method"),
            &percent_curves(steps, truth, interval_s),
        )?;
        written.push(path);
    }
    let lat = rows.first().map_or(0.0, |r| r.latitude_deg) * RAD_PER_DEG;
    // The first 20000 s: the stage where eq (11)'s averaging matters.
    let n3 = rows.iter().take_while(|r| r.time_s <= FIG3_SPAN_S).count();
    let path = dir.join("fig3_correlation.png");
    plots::correlation_figure(
        &path,
        &correlation_panels(&rows[..n3], truth, interval_s, window),
        x_arcsec[2] * lat.cos() / 2.0,
    )?;
    written.push(path);
    if let Some((name, steps)) = replays.first() {
        let AttitudeCurves { before, after } = attitude_curves(rows, steps, truth, interval_s);
        let span = before
            .iter()
            .flatten()
            .map(|p| p.1.abs())
            .fold(10.0, f64::max)
            * 1.1;
        let path = dir.join("fig7_attitude_error_before.png");
        plots::attitude_error_figure(
            &path,
            "Attitude error of eq (2) before compensation",
            &before,
            span,
        )?;
        written.push(path);
        // At its own scale, from the first estimate on (before it nothing is removed, and at
        // Fig. 7's scale what is left is a flat line at 0): the 99th percentile of what is left;
        // the first estimates' larger errors are drawn at the axis and marked.
        let first_estimate_s = steps
            .iter()
            .find(|s| s.result.as_ref().is_ok_and(|o| o.estimate.is_some()))
            .map_or(f64::INFINITY, |s| s.time_s);
        let mut left: Vec<f64> = after
            .iter()
            .flatten()
            .filter(|p| p.0 >= first_estimate_s)
            .map(|p| p.1.abs())
            .collect();
        left.sort_by(f64::total_cmp);
        let after_span = left
            .get(left.len() * 99 / 100)
            .copied()
            .unwrap_or(1.0)
            .max(1.0)
            * 1.2;
        let path = dir.join(format!("fig8_attitude_error_after_{name}.png"));
        plots::attitude_error_figure(
            &path,
            &format!("Attitude error after compensation ({name}; running estimate; Fig. 7's scale is +-{span:.0} arcsec)"),
            &after,
            after_span,
        )?;
        written.push(path);
        // The same after the first 10 % of the run, at a scale that shows the residual.
        let t_end = rows.last().map_or(0.0, |r| r.time_s);
        let late: [Vec<(f64, f64)>; 3] =
            after.map(|c| c.into_iter().filter(|p| p.0 >= 0.1 * t_end).collect());
        let late_span = late.iter().flatten().map(|p| p.1.abs()).fold(1.0, f64::max) * 1.1;
        let path = dir.join(format!("fig8_attitude_error_after_{name}_zoom.png"));
        plots::attitude_error_figure(
            &path,
            &format!(
                "Attitude error after compensation ({name}), from {:.0} s",
                0.1 * t_end
            ),
            &late,
            late_span,
        )?;
        written.push(path);
    }
    Ok(written)
}

/// What a figure of [`write_figures`] shows, from its file name.
pub fn caption_of(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let what = if name.starts_with("fig2_") || name.starts_with("fig4_") {
        "Absolute percentage error of eq (7) over time (the paper's Figs. 2 and 4)"
    } else if name.starts_with("fig3_") {
        "Correlation values of eq (8) and their one-period averages of eq (11) (the paper's Fig. 3)"
    } else if name.starts_with("fig7_") {
        "Attitude error of eq (2) before compensation (the paper's Fig. 7)"
    } else if name.ends_with("_zoom.png") {
        "Attitude error after compensation from a tenth of the run on, at its own scale (the paper's Fig. 8)"
    } else if name.starts_with("fig8_") {
        "Attitude error after compensation (the paper's Fig. 8)"
    } else {
        "Figure"
    };
    what.to_string()
}

/// Names of x1..x4.
const X_NAMES: [&str; 4] = ["x1", "x2", "x3", "x4"];
/// Names of the attitude axes and of the correlation channels.
const AXES: [&str; 3] = ["heading", "roll", "pitch"];
const CHANNELS: [&str; 4] = ["pitch x sin", "pitch x cos", "roll x sin", "roll x cos"];
const GREY: RGBColor = RGBColor(120, 120, 120);

/// Half way to white.
fn lighter(c: RGBColor) -> RGBColor {
    RGBColor(c.0 / 2 + 128, c.1 / 2 + 128, c.2 / 2 + 128)
}

/// A symmetric range around 0 holding `values` (at least `floor`), 10 % more.
fn symmetric_range(values: impl Iterator<Item = f64>, floor: f64) -> (f64, f64) {
    let m = values
        .filter(|v| v.is_finite())
        .fold(floor, |m, v| m.max(v.abs()))
        * 1.1;
    (-m, m)
}

/// The report's plots of one run, written into `dir`: the estimates with their 1-sigma, the
/// error against the truth (when there is one), the status timeline, the attitude before and
/// after compensation with its zooms, and the filter's residuals (when the replay has them).
/// `period_s` is the rotation period, for the zoom on the last two periods.
pub fn timeline_figures(
    dir: &Path,
    tl: &Timeline,
    method: &str,
    period_s: Option<f64>,
) -> anyhow::Result<Vec<Figure>> {
    let buckets: Vec<&Bucket> = tl.buckets().collect();
    let mut figures = Vec::new();
    let x_range = (
        tl.first_time_s.unwrap_or(0.0),
        tl.last_time_s.unwrap_or(1.0),
    );
    let time_panel = |title: String, y_label: &str, y_range: (f64, f64), log_y: bool| Panel {
        title,
        x_label: "time, s".into(),
        y_label: y_label.into(),
        y_range,
        log_y,
        ..Panel::default()
    };

    // Estimates with 1-sigma bands, one panel per error.
    if tl.first_estimate_s.is_some() {
        let with_estimate: Vec<(
            f64,
            crate::report::timeline::EstimateArcsec,
            Option<[f64; 4]>,
        )> = buckets
            .iter()
            .filter_map(|b| b.estimate.map(|e| (b.t1_s, e, b.truth_x_arcsec)))
            .collect();
        let last = with_estimate.last().map(|p| p.1);
        let t_first = with_estimate.first().map_or(0.0, |p| p.0);
        let t_last = with_estimate.last().map_or(1.0, |p| p.0);
        let settled_from = t_first + 0.25 * (t_last - t_first);
        let panels: Vec<Panel> = (0..4)
            .map(|i| {
                let final_x = last.map_or(0.0, |e| e.x[i]);
                let final_sigma = last.map_or(1.0, |e| e.sigma[i]);
                // The scale of the settled estimate (its last three quarters, its truth): the first
                // estimates and their wide 1-sigma are cut at the axis and marked.
                let mut lo = final_x - (5.0 * final_sigma).max(5.0);
                let mut hi = final_x + (5.0 * final_sigma).max(5.0);
                for (t, e, truth) in &with_estimate {
                    if *t >= settled_from {
                        lo = lo.min(e.x[i]);
                        hi = hi.max(e.x[i]);
                    }
                    if let Some(x) = truth {
                        lo = lo.min(x[i]);
                        hi = hi.max(x[i]);
                    }
                }
                let pad = 0.1 * (hi - lo);
                let mut p = time_panel(
                    format!("{} estimate, arcsec ({method})", X_NAMES[i]),
                    "arcsec",
                    (lo - pad, hi + pad),
                    false,
                );
                p.bands.push(Band {
                    label: "estimate ± 1-sigma".into(),
                    color: PALETTE[i],
                    points: with_estimate
                        .iter()
                        .map(|(t, e, _)| (*t, e.x[i] - e.sigma[i], e.x[i] + e.sigma[i]))
                        .collect(),
                });
                p.series.push(Series {
                    label: "estimate".into(),
                    color: PALETTE[i],
                    points: with_estimate.iter().map(|(t, e, _)| (*t, e.x[i])).collect(),
                });
                if tl.has_truth {
                    let truth: Vec<(f64, f64)> = with_estimate
                        .iter()
                        .filter_map(|(t, _, x)| x.map(|x| (*t, x[i])))
                        .collect();
                    p.series.push(Series {
                        label: "truth".into(),
                        color: plotters::style::BLACK,
                        points: truth,
                    });
                }
                p
            })
            .collect();
        let path = dir.join("estimates.png");
        plots::draw_png(&path, &panels, 1000, 260)?;
        figures.push(Figure {
            path,
            caption: "The estimates of x1..x4 with their reported 1-sigma band over time".into(),
        });
    }

    // The error against the truth: arcsec and percent (eq (7)), log scales.
    if tl.has_truth && tl.first_estimate_s.is_some() {
        /// At a bucket's last row: time, error, truth, reported 1-sigma (arcsec).
        struct Judged {
            t: f64,
            error: [f64; 4],
            truth: [f64; 4],
            sigma: [f64; 4],
        }
        let errors: Vec<Judged> = buckets
            .iter()
            .filter_map(|b| {
                Some(Judged {
                    t: b.t1_s,
                    error: b.error_arcsec?,
                    truth: b.truth_x_arcsec?,
                    sigma: b.estimate?.sigma,
                })
            })
            .collect();
        let mut arcsec = time_panel(
            format!("Error against the truth, |estimate - truth|, arcsec ({method})"),
            "arcsec",
            (1e-3, 1e4),
            true,
        );
        let mut percent = time_panel(
            format!("Absolute percentage error (eq 7) ({method})"),
            "%",
            (1e-3, 1e3),
            true,
        );
        for i in 0..4 {
            arcsec.series.push(Series {
                label: X_NAMES[i].into(),
                color: PALETTE[i],
                points: errors.iter().map(|e| (e.t, e.error[i].abs())).collect(),
            });
            percent.series.push(Series {
                label: X_NAMES[i].into(),
                color: PALETTE[i],
                points: errors
                    .iter()
                    .filter(|e| e.truth[i] != 0.0)
                    .map(|e| (e.t, crate::report::percent_error(e.error[i], e.truth[i])))
                    .collect(),
            });
        }
        arcsec.series.push(Series {
            label: "2-sigma reported, largest of the four".into(),
            color: GREY,
            points: errors
                .iter()
                .map(|e| (e.t, 2.0 * e.sigma.iter().fold(0.0f64, |m, s| m.max(*s))))
                .collect(),
        });
        let path = dir.join("error.png");
        plots::draw_png(&path, &[arcsec, percent], 1000, 360)?;
        figures.push(Figure {
            path,
            caption: "The error of each estimate against the truth file, in arcsec and in percent"
                .into(),
        });
    }

    // Status timeline: one lane per status of the core, then what happened to the rows.
    let spans = |hit: &dyn Fn(&Bucket) -> bool| -> Vec<(f64, f64)> {
        let mut out: Vec<(f64, f64)> = Vec::new();
        for b in buckets.iter().filter(|b| hit(b)) {
            match out.last_mut() {
                Some(last) if b.t0_s - last.1 <= (b.t1_s - b.t0_s).max(1e-9) * 1.01 => {
                    last.1 = b.t1_s
                }
                _ => out.push((b.t0_s, b.t1_s)),
            }
        }
        out
    };
    let mut lanes: Vec<Lane> = Status::ALL
        .iter()
        .enumerate()
        .map(|(k, status)| Lane {
            name: status.name().into(),
            color: PALETTE[k % PALETTE.len()],
            spans: spans(&|b: &Bucket| b.saw(*status)),
            ticks: vec![],
        })
        .collect();
    let red = RGBColor(200, 30, 30);
    lanes.push(Lane {
        name: "rejected rows".into(),
        color: red,
        spans: spans(&|b: &Bucket| b.rejected > 0),
        ticks: vec![],
    });
    lanes.push(Lane {
        name: "lost samples (gaps)".into(),
        color: GREY,
        spans: spans(&|b: &Bucket| b.lost_samples > 0),
        ticks: vec![],
    });
    if tl.knows_restarts {
        lanes.push(Lane {
            name: "window restarts".into(),
            color: red,
            spans: spans(&|b: &Bucket| b.window_restarts > 0),
            ticks: vec![],
        });
    }
    lanes.push(Lane {
        name: "clock steps".into(),
        color: red,
        spans: spans(&|b: &Bucket| b.clock_steps > 0),
        ticks: vec![],
    });
    let path = dir.join("status.png");
    plots::lanes_figure(
        &path,
        &format!("Status over time ({method})"),
        &lanes,
        x_range,
    )?;
    figures.push(Figure {
        path,
        caption: "What the estimator reported row by row (one lane per status), and the rows rejected, the samples lost, the restarts of the moving average and the clock steps".into(),
    });

    // Attitude before and after compensation.
    let tail: Vec<&crate::report::timeline::TailRow> = {
        let all: Vec<_> = tl.tail().collect();
        let end = all.last().map_or(0.0, |r| r.time_s);
        let span = 2.0 * period_s.unwrap_or(960.0 / 2.0);
        all.into_iter().filter(|r| r.time_s >= end - span).collect()
    };
    let envelope_bands =
        |pick: &dyn Fn(&Bucket) -> Option<crate::report::timeline::Envelope<3>>,
         from_s: f64|
         -> Vec<Band> {
            (0..3)
                .map(|a| Band {
                    label: AXES[a].into(),
                    color: PALETTE[a],
                    points: buckets
                        .iter()
                        .filter(|b| b.t0_s >= from_s)
                        .map(|b| {
                            pick(b).map_or((f64::NAN, f64::NAN, f64::NAN), |e| {
                                (0.5 * (b.t0_s + b.t1_s), e.min[a], e.max[a])
                            })
                        })
                        .collect(),
                })
                .collect()
        };
    let band_range = |bands: &[Band], floor: f64| {
        symmetric_range(
            bands
                .iter()
                .flat_map(|b| b.points.iter().flat_map(|p| [p.1, p.2])),
            floor,
        )
    };
    let first_estimate_s = tl.first_estimate_s.unwrap_or(x_range.0);
    let mut panels = Vec::new();
    if tl.has_truth {
        let before = envelope_bands(&|b| b.before_arcsec, f64::NEG_INFINITY);
        let mut p = time_panel(
            "Attitude error of eq (2) before compensation (envelope), arcsec".into(),
            "arcsec",
            band_range(&before, 1.0),
            false,
        );
        p.bands = before;
        panels.push(p);
        let after = envelope_bands(&|b| b.after_arcsec, first_estimate_s);
        // The scale of the last three quarters from the first estimate on: what is left once the
        // estimate has settled; the first estimates' larger errors are cut at the axis.
        let settled_s = first_estimate_s + 0.25 * (x_range.1 - first_estimate_s);
        let settled: Vec<Band> = after
            .iter()
            .map(|b| Band {
                points: b
                    .points
                    .iter()
                    .copied()
                    .filter(|p| p.0 >= settled_s)
                    .collect(),
                ..b.clone()
            })
            .collect();
        let mut p = time_panel(
            "After compensation from the first estimate (envelope; scale of its last 3/4), arcsec"
                .to_string(),
            "arcsec",
            band_range(&settled, 0.01),
            false,
        );
        p.bands = after;
        panels.push(p);
        let mut p = time_panel(
            "After compensation, the last two rotation periods, every row, arcsec".into(),
            "arcsec",
            (0.0, 0.0),
            false,
        );
        for a in 0..3 {
            p.series.push(Series {
                label: AXES[a].into(),
                color: PALETTE[a],
                points: tail
                    .iter()
                    .filter_map(|r| r.after_arcsec.map(|v| (r.time_s, v[a])))
                    .collect(),
            });
        }
        p.y_range = symmetric_range(
            p.series.iter().flat_map(|s| s.points.iter().map(|q| q.1)),
            0.1,
        );
        panels.push(p);
    } else {
        let removed = envelope_bands(&|b| b.removed_arcsec, f64::NEG_INFINITY);
        let mut p = time_panel(
            format!("Oscillation removed by the compensation (eq 2, running estimate; envelope), arcsec ({method})"),
            "arcsec",
            band_range(&removed, 1.0),
            false,
        );
        p.bands = removed;
        panels.push(p);
        let mut p = time_panel(
            "The same, the last two rotation periods, every row, arcsec".into(),
            "arcsec",
            (0.0, 0.0),
            false,
        );
        for a in 0..3 {
            p.series.push(Series {
                label: AXES[a].into(),
                color: PALETTE[a],
                points: tail
                    .iter()
                    .map(|r| (r.time_s, r.removed_arcsec[a]))
                    .collect(),
            });
        }
        p.y_range = symmetric_range(
            p.series.iter().flat_map(|s| s.points.iter().map(|q| q.1)),
            1.0,
        );
        panels.push(p);
    }
    let path = dir.join("attitude.png");
    plots::draw_png(&path, &panels, 1000, 330)?;
    figures.push(Figure {
        path,
        caption: if tl.has_truth {
            "The attitude error of eq (2) before and after compensation, and zooms on what is left".into()
        } else {
            "No truth file: the attitude error itself is unknown; this is the oscillation the compensation removed".into()
        },
    });

    // The filter's residuals.
    if tl.has_residuals {
        let bands: Vec<Band> = (0..4)
            .map(|c| Band {
                label: CHANNELS[c].into(),
                color: PALETTE[c],
                points: buckets
                    .iter()
                    .map(|b| {
                        b.residual_arcsec
                            .map_or((f64::NAN, f64::NAN, f64::NAN), |e| {
                                (0.5 * (b.t0_s + b.t1_s), e.min[c], e.max[c])
                            })
                    })
                    .collect(),
            })
            .collect();
        // Their mean over about one rotation period (the buckets it spans), as the filter's
        // residual check averages them: a drift or a model mismatch moves it off 0.
        let span_s = period_s.unwrap_or(480.0);
        let means: Vec<Series> = (0..4)
            .map(|c| {
                let mut points = Vec::new();
                let mut window: std::collections::VecDeque<(f64, f64, u64)> = Default::default();
                for b in &buckets {
                    let Some(e) = b.residual_arcsec else {
                        window.clear();
                        points.push((f64::NAN, f64::NAN));
                        continue;
                    };
                    window.push_back((b.t1_s, e.sum[c], e.rows));
                    while window.front().is_some_and(|f| f.0 < b.t1_s - span_s) {
                        window.pop_front();
                    }
                    // Only once the mean spans a whole period (after the start and each restart).
                    if window.front().is_some_and(|f| f.0 > b.t1_s - 0.9 * span_s) {
                        points.push((f64::NAN, f64::NAN));
                        continue;
                    }
                    let (sum, rows) = window
                        .iter()
                        .fold((0.0, 0u64), |(s, n), w| (s + w.1, n + w.2));
                    points.push((b.t1_s, sum / rows.max(1) as f64));
                }
                Series {
                    label: format!("{} mean over a period", CHANNELS[c]),
                    color: PALETTE[c],
                    points,
                }
            })
            .collect();
        // The scale of the second half: the first windows' sway residuals are cut and marked.
        let mid = 0.5 * (x_range.0 + x_range.1);
        let range = symmetric_range(
            bands.iter().flat_map(|b| {
                b.points
                    .iter()
                    .filter(|p| p.0 >= mid)
                    .flat_map(|p| [p.1, p.2])
            }),
            0.01,
        );
        let mut p = time_panel(format!("Post-fit residuals z - H x of the correlation channels (envelope), arcsec ({method})"), "arcsec", range, false);
        p.bands = bands;
        let mean_range = symmetric_range(
            means
                .iter()
                .flat_map(|s| s.points.iter().filter(|p| p.0 >= mid).map(|p| p.1)),
            0.01,
        );
        let mut m = time_panel(
            "Their mean over one rotation period, arcsec".into(),
            "arcsec",
            mean_range,
            false,
        );
        m.series = means;
        let path = dir.join("residuals.png");
        plots::draw_png(&path, &[p, m], 1000, 330)?;
        figures.push(Figure {
            path,
            caption: "What eq (2) with the current estimate leaves unexplained in each window's correlations, and its mean over a period: noise around 0 when the model holds".into(),
        });
    }
    Ok(figures)
}

/// The Monte Carlo statistics over time: the median, 95th percentile and largest absolute error of
/// each of x1..x4 over the runs (log scale), and the share of errors within twice their reported
/// 1-sigma (about 95 % when the 1-sigma is honest).
pub fn monte_carlo_figure(path: &Path, s: &Summary) -> anyhow::Result<()> {
    let mut errors = Panel {
        title:
            "Absolute error, arcsec, from the first estimate: median (thick), p95, largest (grey)"
                .into(),
        x_label: "time, s".into(),
        y_label: "arcsec".into(),
        y_range: (1e-3, 1e4),
        log_y: true,
        ..Panel::default()
    };
    let over_time = |f: &dyn Fn(usize) -> f64| -> Vec<(f64, f64)> {
        s.times_s
            .iter()
            .enumerate()
            .map(|(k, t)| (*t, f(k)))
            .collect()
    };
    // A statistic over runs of which too many have no estimate yet is infinite: not drawn (the
    // line starts at the first estimate), rather than marked beyond the axis.
    let estimated = |points: Vec<(f64, f64)>| -> Vec<(f64, f64)> {
        points.into_iter().filter(|(_, v)| v.is_finite()).collect()
    };
    for i in 0..4 {
        errors.series.push(Series {
            label: format!("{} median", X_NAMES[i]),
            color: PALETTE[i],
            points: estimated(over_time(&|k| s.median_abs_error_arcsec[k][i])),
        });
        errors.series.push(Series {
            label: format!("{} p95", X_NAMES[i]),
            color: lighter(PALETTE[i]),
            points: estimated(over_time(&|k| s.p95_abs_error_arcsec[k][i])),
        });
    }
    errors.series.push(Series {
        label: "largest of the four".into(),
        color: GREY,
        points: estimated(over_time(&|k| {
            s.max_abs_error_arcsec[k]
                .iter()
                .fold(0.0f64, |m, v| m.max(*v))
        })),
    });
    let coverage = Panel {
        title: "Errors within twice their reported 1-sigma, % of (run, error) pairs".into(),
        x_label: "time, s".into(),
        y_label: "%".into(),
        y_range: (0.0, 100.0),
        log_y: false,
        series: vec![
            Series {
                label: "within 2-sigma".into(),
                color: PALETTE[1],
                points: over_time(&|k| 100.0 * s.coverage_2sigma[k]),
            },
            Series {
                label: "95 % (an honest 1-sigma)".into(),
                color: GREY,
                points: over_time(&|_| 95.0),
            },
        ],
        bands: vec![],
    };
    plots::draw_png(path, &[errors, coverage], 1000, 400)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_average_of_ramp() {
        let pts: Vec<(f64, f64)> = (0..5).map(|i| (i as f64, i as f64)).collect();
        assert_eq!(
            moving_average(&pts, 3),
            vec![(2.0, 1.0), (3.0, 2.0), (4.0, 3.0)]
        );
    }
}
