//! The pictures of a report page, each drawn by a function of its own from the [`Timeline`] of
//! a replayed or streamed log: the estimates with their 1-sigma (`estimates_figure`), the error
//! against the truth (`error_figure`), the status timeline (`status_figure`), the attitude
//! before and after compensation (`attitude_figure`) and the filter's residuals
//! (`residuals_figure`). [`timeline_figures`] draws those the log has.

use super::{GREY, X_NAMES};
use crate::report::html::Figure;
use crate::report::plots::{self, Band, Lane, Panel, Series, PALETTE};
use crate::report::timeline::{Bucket, Envelope, EstimateArcsec, TailRow, Timeline};
use estimator_core::Status;
use plotters::style::RGBColor;
use std::path::Path;

/// What every picture of a page is drawn from.
struct Page<'a> {
    dir: &'a Path,
    tl: &'a Timeline,
    buckets: Vec<&'a Bucket>,
    method: &'a str,
    /// The rotation period, s, for the zoom on the last two periods and the residuals' mean.
    period_s: Option<f64>,
    /// The time span of the log, s.
    x_range: (f64, f64),
}

/// A panel over the log's time.
fn time_panel(title: String, y_label: &str, y_range: (f64, f64), log_y: bool) -> Panel {
    Panel {
        title,
        x_label: "time, s".into(),
        y_label: y_label.into(),
        y_range,
        log_y,
        ..Panel::default()
    }
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
    let page = Page {
        dir,
        tl,
        buckets: tl.buckets().collect(),
        method,
        period_s,
        x_range: (
            tl.first_time_s.unwrap_or(0.0),
            tl.last_time_s.unwrap_or(1.0),
        ),
    };
    let mut figures = Vec::new();
    if tl.first_estimate_s.is_some() {
        figures.push(estimates_figure(&page)?);
    }
    if tl.has_truth && tl.first_estimate_s.is_some() {
        figures.push(error_figure(&page)?);
    }
    figures.push(status_figure(&page)?);
    figures.push(attitude_figure(&page)?);
    if tl.has_residuals {
        figures.push(residuals_figure(&page)?);
    }
    Ok(figures)
}

/// Names of the attitude axes.
const AXES: [&str; 3] = ["heading", "roll", "pitch"];
/// Names of the correlation channels.
const CHANNELS: [&str; 4] = ["pitch x sin", "pitch x cos", "roll x sin", "roll x cos"];
/// Rejected rows, restarts and clock steps in the status timeline.
const RED: RGBColor = RGBColor(200, 30, 30);

/// A symmetric range around 0 holding `values` (at least `floor`), 10 % more.
fn symmetric_range(values: impl Iterator<Item = f64>, floor: f64) -> (f64, f64) {
    let m = values
        .filter(|v| v.is_finite())
        .fold(floor, |m, v| m.max(v.abs()))
        * 1.1;
    (-m, m)
}

/// At a bucket's last row with an estimate: its time, s, the estimate, and the true errors
/// (arcsec) when there is a truth.
type EstimateAt = (f64, EstimateArcsec, Option<[f64; 4]>);

/// `estimates.png`: the estimates with their 1-sigma bands, one panel per error.
fn estimates_figure(page: &Page) -> anyhow::Result<Figure> {
    let with_estimate: Vec<EstimateAt> = page
        .buckets
        .iter()
        .filter_map(|b| b.estimate.map(|e| (b.t1_s, e, b.truth_x_arcsec)))
        .collect();
    let last = with_estimate.last().map(|p| p.1);
    let t_first = with_estimate.first().map_or(0.0, |p| p.0);
    let t_last = with_estimate.last().map_or(1.0, |p| p.0);
    let settled_from = t_first + 0.25 * (t_last - t_first);
    let panels: Vec<Panel> = (0..4)
        .map(|i| estimate_panel(page, i, &with_estimate, last, settled_from))
        .collect();
    let path = page.dir.join("estimates.png");
    plots::draw_png(&path, &panels, 1000, 260)?;
    Ok(Figure {
        path,
        caption: "The estimates of x1..x4 with their reported 1-sigma band over time".into(),
    })
}

/// Error `i`'s panel: its estimate with the 1-sigma band, and its truth.
fn estimate_panel(
    page: &Page,
    i: usize,
    with_estimate: &[EstimateAt],
    last: Option<EstimateArcsec>,
    settled_from: f64,
) -> Panel {
    let final_x = last.map_or(0.0, |e| e.x[i]);
    let final_sigma = last.map_or(1.0, |e| e.sigma[i]);
    // The scale of the settled estimate (its last three quarters, its truth): the first
    // estimates and their wide 1-sigma are cut at the axis and marked.
    let mut lo = final_x - (5.0 * final_sigma).max(5.0);
    let mut hi = final_x + (5.0 * final_sigma).max(5.0);
    for (t, e, truth) in with_estimate {
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
        format!("{} estimate, arcsec ({})", X_NAMES[i], page.method),
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
    if page.tl.has_truth {
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
}

/// `error.png`: the error against the truth, in arcsec (with twice the largest reported 1-sigma)
/// and in percent (eq (7)), log scales.
fn error_figure(page: &Page) -> anyhow::Result<Figure> {
    /// At a bucket's last row: time, error, truth, reported 1-sigma (arcsec).
    struct Judged {
        t: f64,
        error: [f64; 4],
        truth: [f64; 4],
        sigma: [f64; 4],
    }
    let errors: Vec<Judged> = page
        .buckets
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
        format!(
            "Error against the truth, |estimate - truth|, arcsec ({})",
            page.method
        ),
        "arcsec",
        (1e-3, 1e4),
        true,
    );
    let mut percent = time_panel(
        format!("Absolute percentage error (eq 7) ({})", page.method),
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
                .map(|e| {
                    (
                        e.t,
                        crate::report::accuracy::percent_error(e.error[i], e.truth[i]),
                    )
                })
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
    let path = page.dir.join("error.png");
    plots::draw_png(&path, &[arcsec, percent], 1000, 360)?;
    Ok(Figure {
        path,
        caption: "The error of each estimate against the truth file, in arcsec and in percent"
            .into(),
    })
}

/// The spans of consecutive buckets that `hit`, merged where they touch.
fn spans(buckets: &[&Bucket], hit: &dyn Fn(&Bucket) -> bool) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for b in buckets.iter().filter(|b| hit(b)) {
        match out.last_mut() {
            Some(last) if b.t0_s - last.1 <= (b.t1_s - b.t0_s).max(1e-9) * 1.01 => last.1 = b.t1_s,
            _ => out.push((b.t0_s, b.t1_s)),
        }
    }
    out
}

/// `status.png`: one lane per status of the core, then what happened to the rows.
fn status_figure(page: &Page) -> anyhow::Result<Figure> {
    let lane = |name: &str, color: RGBColor, hit: &dyn Fn(&Bucket) -> bool| Lane {
        name: name.into(),
        color,
        spans: spans(&page.buckets, hit),
        ticks: vec![],
    };
    let mut lanes: Vec<Lane> = Status::ALL
        .iter()
        .enumerate()
        .map(|(k, status)| {
            lane(status.name(), PALETTE[k % PALETTE.len()], &|b: &Bucket| {
                b.saw(*status)
            })
        })
        .collect();
    lanes.push(lane("rejected rows", RED, &|b: &Bucket| b.rejected > 0));
    lanes.push(lane("lost samples (gaps)", GREY, &|b: &Bucket| {
        b.lost_samples > 0
    }));
    if page.tl.knows_restarts {
        lanes.push(lane("window restarts", RED, &|b: &Bucket| {
            b.window_restarts > 0
        }));
    }
    lanes.push(lane("clock steps", RED, &|b: &Bucket| b.clock_steps > 0));
    let path = page.dir.join("status.png");
    plots::lanes_figure(
        &path,
        &format!("Status over time ({})", page.method),
        &lanes,
        page.x_range,
    )?;
    Ok(Figure {
        path,
        caption: "What the estimator reported row by row (one lane per status), and the rows rejected, the samples lost, the restarts of the moving average and the clock steps".into(),
    })
}

/// `attitude.png`: the attitude error of eq (2) before and after compensation and a zoom on the
/// last two rotation periods; without a truth, the oscillation the compensation removed.
fn attitude_figure(page: &Page) -> anyhow::Result<Figure> {
    let tail = last_two_periods(page);
    let panels = if page.tl.has_truth {
        attitude_error_panels(page, &tail)
    } else {
        removed_panels(page, &tail)
    };
    let path = page.dir.join("attitude.png");
    plots::draw_png(&path, &panels, 1000, 330)?;
    Ok(Figure {
        path,
        caption: if page.tl.has_truth {
            "The attitude error of eq (2) before and after compensation, and zooms on what is left"
                .into()
        } else {
            "No truth file: the attitude error itself is unknown; this is the oscillation the compensation removed".into()
        },
    })
}

/// The rows kept whole over the last two rotation periods of the log.
fn last_two_periods<'a>(page: &Page<'a>) -> Vec<&'a TailRow> {
    let all: Vec<_> = page.tl.tail().collect();
    let end = all.last().map_or(0.0, |r| r.time_s);
    let span = 2.0 * page.period_s.unwrap_or(960.0 / 2.0);
    all.into_iter().filter(|r| r.time_s >= end - span).collect()
}

/// Each axis's envelope over the buckets from `from_s` on, of the signal `pick` takes.
fn envelope_bands(
    page: &Page,
    pick: &dyn Fn(&Bucket) -> Option<Envelope<3>>,
    from_s: f64,
) -> Vec<Band> {
    (0..3)
        .map(|a| Band {
            label: AXES[a].into(),
            color: PALETTE[a],
            points: page
                .buckets
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
}

/// A symmetric range holding `bands` (at least `floor`).
fn band_range(bands: &[Band], floor: f64) -> (f64, f64) {
    symmetric_range(
        bands
            .iter()
            .flat_map(|b| b.points.iter().flat_map(|p| [p.1, p.2])),
        floor,
    )
}

/// Every row of the last two periods, one line per axis (`points` of an axis), at a symmetric
/// scale of at least `floor`.
fn tail_panel(title: &str, points: &dyn Fn(usize) -> Vec<(f64, f64)>, floor: f64) -> Panel {
    let mut p = time_panel(title.to_string(), "arcsec", (0.0, 0.0), false);
    for a in 0..3 {
        p.series.push(Series {
            label: AXES[a].into(),
            color: PALETTE[a],
            points: points(a),
        });
    }
    p.y_range = symmetric_range(
        p.series.iter().flat_map(|s| s.points.iter().map(|q| q.1)),
        floor,
    );
    p
}

/// With a truth: the attitude error before compensation, after it from the first estimate on,
/// and after it over the last two periods, every row.
fn attitude_error_panels(page: &Page, tail: &[&TailRow]) -> Vec<Panel> {
    let first_estimate_s = page.tl.first_estimate_s.unwrap_or(page.x_range.0);
    let before = envelope_bands(page, &|b| b.before_arcsec, f64::NEG_INFINITY);
    let mut before_panel = time_panel(
        "Attitude error of eq (2) before compensation (envelope), arcsec".into(),
        "arcsec",
        band_range(&before, 1.0),
        false,
    );
    before_panel.bands = before;
    let after = envelope_bands(page, &|b| b.after_arcsec, first_estimate_s);
    // The scale of the last three quarters from the first estimate on: what is left once the
    // estimate has settled; the first estimates' larger errors are cut at the axis.
    let settled_s = first_estimate_s + 0.25 * (page.x_range.1 - first_estimate_s);
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
    let mut after_panel = time_panel(
        "After compensation from the first estimate (envelope; scale of its last 3/4), arcsec"
            .to_string(),
        "arcsec",
        band_range(&settled, 0.01),
        false,
    );
    after_panel.bands = after;
    let zoom = tail_panel(
        "After compensation, the last two rotation periods, every row, arcsec",
        &|a| {
            tail.iter()
                .filter_map(|r| r.after_arcsec.map(|v| (r.time_s, v[a])))
                .collect()
        },
        0.1,
    );
    vec![before_panel, after_panel, zoom]
}

/// Without a truth: the oscillation the compensation removed (the running estimate's eq (2)),
/// and the same over the last two periods, every row.
fn removed_panels(page: &Page, tail: &[&TailRow]) -> Vec<Panel> {
    let removed = envelope_bands(page, &|b| b.removed_arcsec, f64::NEG_INFINITY);
    let mut p = time_panel(
        format!("Oscillation removed by the compensation (eq 2, running estimate; envelope), arcsec ({})", page.method),
        "arcsec",
        band_range(&removed, 1.0),
        false,
    );
    p.bands = removed;
    let zoom = tail_panel(
        "The same, the last two rotation periods, every row, arcsec",
        &|a| {
            tail.iter()
                .map(|r| (r.time_s, r.removed_arcsec[a]))
                .collect()
        },
        1.0,
    );
    vec![p, zoom]
}

/// `residuals.png`: the filter's post-fit residuals of each correlation channel (envelope), and
/// their mean over a rotation period.
fn residuals_figure(page: &Page) -> anyhow::Result<Figure> {
    let bands: Vec<Band> = (0..4)
        .map(|c| Band {
            label: CHANNELS[c].into(),
            color: PALETTE[c],
            points: page
                .buckets
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
    let span_s = page.period_s.unwrap_or(480.0);
    let means: Vec<Series> = (0..4).map(|c| period_mean(page, c, span_s)).collect();
    // The scale of the second half: the first windows' sway residuals are cut and marked.
    let mid = 0.5 * (page.x_range.0 + page.x_range.1);
    let range = symmetric_range(
        bands.iter().flat_map(|b| {
            b.points
                .iter()
                .filter(|p| p.0 >= mid)
                .flat_map(|p| [p.1, p.2])
        }),
        0.01,
    );
    let mut p = time_panel(
        format!(
            "Post-fit residuals z - H x of the correlation channels (envelope), arcsec ({})",
            page.method
        ),
        "arcsec",
        range,
        false,
    );
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
    let path = page.dir.join("residuals.png");
    plots::draw_png(&path, &[p, m], 1000, 330)?;
    Ok(Figure {
        path,
        caption: "What eq (2) with the current estimate leaves unexplained in each window's correlations, and its mean over a period: noise around 0 when the model holds".into(),
    })
}

/// Channel `c`'s residual, its mean over about one rotation period (`span_s`: the buckets it
/// spans), as the filter's residual check averages them: a drift or a model mismatch moves it
/// off 0. Drawn only once the mean spans a whole period (after the start and each restart).
fn period_mean(page: &Page, c: usize, span_s: f64) -> Series {
    let mut points = Vec::new();
    let mut window: std::collections::VecDeque<(f64, f64, u64)> = Default::default();
    for b in &page.buckets {
        let Some(e) = b.residual_arcsec else {
            window.clear();
            points.push((f64::NAN, f64::NAN));
            continue;
        };
        window.push_back((b.t1_s, e.sum[c], e.rows));
        while window.front().is_some_and(|f| f.0 < b.t1_s - span_s) {
            window.pop_front();
        }
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
}
