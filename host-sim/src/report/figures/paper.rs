//! The paper's figures from a generated run and its truth ([`write_figures`], one function per
//! figure): the percentage error of each method (Figs. 2 and 4), the correlation values and
//! their averages (Fig. 3), and the attitude error before and after compensation (Figs. 7 and 8).

use crate::replay::Step;
use crate::report::accuracy::{errors_arcsec, percent_error};
use crate::report::attitude_rms::residual_arcsec;
use crate::report::plots::{self, CorrelationPanel, Curve};
use crate::report::truth_index;
use crate::sim::scenario::{Row, RowTruth};
use estimator_core::correlation::{products, ROLL_SIN};
use estimator_core::installation::Angles;
use estimator_core::units::{rad_to_arcsec, RAD_PER_DEG};
use estimator_core::{Attitude, Estimate, Real};
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
        written.push(percent_error_figure(dir, name, steps, truth, interval_s)?);
    }
    written.push(correlation_figure(
        dir, rows, truth, x_arcsec, interval_s, window,
    )?);
    if let Some((name, steps)) = replays.first() {
        let curves = attitude_curves(rows, steps, truth, interval_s);
        let (before, span) = attitude_before_figure(dir, &curves)?;
        written.push(before);
        written.push(attitude_after_figure(dir, name, steps, &curves, span)?);
        written.push(attitude_after_zoom_figure(dir, name, rows, curves)?);
    }
    Ok(written)
}

/// Figs. 2 and 4: the absolute percentage error of method `name`'s estimates over time.
fn percent_error_figure(
    dir: &Path,
    name: &str,
    steps: &[Step],
    truth: &[RowTruth],
    interval_s: f64,
) -> anyhow::Result<PathBuf> {
    let fig = if name == "traditional" {
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
    Ok(path)
}

/// Fig. 3: the correlation values of eq (8) and their averages of eq (11) over the first
/// [`FIG3_SPAN_S`], the stage where eq (11)'s averaging matters.
fn correlation_figure(
    dir: &Path,
    rows: &[Row],
    truth: &[RowTruth],
    x_arcsec: &[f64; 4],
    interval_s: f64,
    window: usize,
) -> anyhow::Result<PathBuf> {
    let lat = rows.first().map_or(0.0, |r| r.latitude_deg) * RAD_PER_DEG;
    let n3 = rows.iter().take_while(|r| r.time_s <= FIG3_SPAN_S).count();
    let path = dir.join("fig3_correlation.png");
    plots::correlation_figure(
        &path,
        &correlation_panels(&rows[..n3], truth, interval_s, window),
        x_arcsec[2] * lat.cos() / 2.0,
    )?;
    Ok(path)
}

/// Fig. 7: the attitude error of eq (2) before compensation; returns its file and its scale,
/// arcsec.
fn attitude_before_figure(dir: &Path, curves: &AttitudeCurves) -> anyhow::Result<(PathBuf, f64)> {
    let span = curves
        .before
        .iter()
        .flatten()
        .map(|p| p.1.abs())
        .fold(10.0, f64::max)
        * 1.1;
    let path = dir.join("fig7_attitude_error_before.png");
    plots::attitude_error_figure(
        &path,
        "Attitude error of eq (2) before compensation",
        &curves.before,
        span,
    )?;
    Ok((path, span))
}

/// Fig. 8: the attitude error left after compensation with method `name`'s running estimate, at
/// its own scale from the first estimate on (before it nothing is removed, and at Fig. 7's scale,
/// `fig7_span` arcsec, what is left is a flat line at 0): the 99th percentile of what is left; the
/// first estimates' larger errors are drawn at the axis and marked.
fn attitude_after_figure(
    dir: &Path,
    name: &str,
    steps: &[Step],
    curves: &AttitudeCurves,
    fig7_span: f64,
) -> anyhow::Result<PathBuf> {
    let first_estimate_s = steps
        .iter()
        .find(|s| s.result.as_ref().is_ok_and(|o| o.estimate.is_some()))
        .map_or(f64::INFINITY, |s| s.time_s);
    let mut left: Vec<f64> = curves
        .after
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
        &format!("Attitude error after compensation ({name}; running estimate; Fig. 7's scale is +-{fig7_span:.0} arcsec)"),
        &curves.after,
        after_span,
    )?;
    Ok(path)
}

/// Fig. 8 zoomed: the same after the first 10 % of the run, at a scale that shows the residual.
fn attitude_after_zoom_figure(
    dir: &Path,
    name: &str,
    rows: &[Row],
    curves: AttitudeCurves,
) -> anyhow::Result<PathBuf> {
    let t_end = rows.last().map_or(0.0, |r| r.time_s);
    let late: [Vec<(f64, f64)>; 3] = curves
        .after
        .map(|c| c.into_iter().filter(|p| p.0 >= 0.1 * t_end).collect());
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
    Ok(path)
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
