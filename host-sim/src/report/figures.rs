//! The report's pictures, one function each, drawn by [`crate::report::plots`]: the paper's
//! figures from a generated run and its truth ([`paper`]), a report page's figures of any log from
//! its timeline ([`report_page`]), and the Monte Carlo statistics over time
//! ([`monte_carlo_figure`]).

pub mod paper;
pub mod report_page;

use crate::report::plots::{self, Panel, Series, PALETTE};
use crate::study::monte_carlo::Summary;
use plotters::style::RGBColor;
use std::path::Path;

/// Names of x1..x4.
const X_NAMES: [&str; 4] = ["x1", "x2", "x3", "x4"];
/// Lines of what is drawn for comparison (a bound, a level).
const GREY: RGBColor = RGBColor(120, 120, 120);

/// Half way to white.
fn lighter(c: RGBColor) -> RGBColor {
    RGBColor(c.0 / 2 + 128, c.1 / 2 + 128, c.2 / 2 + 128)
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
