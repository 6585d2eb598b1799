//! PNG plots (plotters, bitmap backend). Text is drawn with DejaVu Sans embedded in the binary
//! (`assets/DejaVuSans.ttf`, through plotters' `ab_glyph` feature): no system fonts, fontconfig or
//! freetype needed.
//!
//! Analogues of the paper's figures:
//! - Figs. 2 and 4: absolute percentage error (eq 7) of x1..x4 against time, log scale, one file
//!   per method ([`percent_error_figure`]);
//! - Fig. 3: correlation values of eq (8) of the true roll, the oscillatory roll and the
//!   low-frequency errors (plus noise), and their 480 s averages of eq (11) ([`correlation_figure`]);
//! - Figs. 7 and 8: attitude error of eq (2) before and after compensation ([`attitude_error_figure`]).
//!
//! A panel draws lines ([`Series`]) and shaded bands ([`Band`]: a 1-sigma interval, the envelope of
//! an oscillation); a status timeline is drawn by [`lanes_figure`]. Values beyond a panel's axis
//! are drawn at its edge and **marked**: a triangle at the edge where a line leaves the axis
//! (pointing up above it, down below it) and `(beyond the axis: triangles)` after its name in the
//! legend; a band that is cut says `(cut at the axis)`. Every PNG is written through a temporary
//! file beside its target ([`crate::formats::output_file`]).

use anyhow::{anyhow, Context, Result};
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

fn register_font() {
    REGISTER.call_once(|| {
        // The embedded font is valid; if it were not, text would be missing and the test
        // `plots::tests::renders_text` fails.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// `(x, y)` points of one line.
pub type Curve = Vec<(f64, f64)>;
/// A Fig. 3 panel: name, correlation values, their averages.
pub type CorrelationPanel = (String, Curve, Curve);

/// One line of a panel.
#[derive(Clone, Debug)]
pub struct Series {
    /// Name in the legend.
    pub label: String,
    /// Colour of the line.
    pub color: RGBColor,
    /// `(x, y)` points; a NaN is a gap in the line.
    pub points: Vec<(f64, f64)>,
}

/// A shaded band between two curves: `(x, low, high)` points; a point with a non-finite value is
/// a gap in the band.
#[derive(Clone, Debug)]
pub struct Band {
    /// Name in the legend.
    pub label: String,
    /// Colour of the band, drawn translucent.
    pub color: RGBColor,
    /// `(x, low, high)` points.
    pub points: Vec<(f64, f64, f64)>,
}

/// One panel: a chart with a title, axis labels, bands and lines.
#[derive(Clone, Debug, Default)]
pub struct Panel {
    /// Title above the chart.
    pub title: String,
    /// Label of the x axis.
    pub x_label: String,
    /// Label of the y axis.
    pub y_label: String,
    /// Lowest and highest value of the y axis; values beyond it are drawn at its edge and marked.
    pub y_range: (f64, f64),
    /// Whether the y axis is logarithmic.
    pub log_y: bool,
    /// The lines, drawn over the bands.
    pub series: Vec<Series>,
    /// The shaded bands.
    pub bands: Vec<Band>,
}

/// Where a line leaves a panel's axis: `(x, above)` at the first point of each run of points
/// beyond `(y0, y1)` (`above`: beyond `y1`; NaN is a gap, not beyond).
pub fn clip_marks(points: &[(f64, f64)], (y0, y1): (f64, f64)) -> Vec<(f64, bool)> {
    let mut marks = Vec::new();
    let mut outside: Option<bool> = None;
    for &(x, v) in points {
        let now = if v > y1 {
            Some(true)
        } else if v < y0 {
            Some(false)
        } else {
            None
        };
        if let Some(above) = now {
            if outside != Some(above) && x.is_finite() {
                marks.push((x, above));
            }
        }
        outside = now;
    }
    marks
}

/// A line's name in the legend: with `(beyond the axis: triangles)` when it leaves the axis.
pub fn legend_label(series: &Series, y_range: (f64, f64)) -> String {
    if clip_marks(&series.points, y_range).is_empty() {
        series.label.clone()
    } else {
        format!("{} (beyond the axis: triangles)", series.label)
    }
}

/// Whether a band is cut by the axis.
fn band_is_cut(band: &Band, (y0, y1): (f64, f64)) -> bool {
    band.points.iter().any(|&(_, lo, hi)| lo < y0 || hi > y1)
}

/// Triangles drawn at most per line (the first runs beyond the axis; more would hide the line).
const MAX_CLIP_MARKS: usize = 200;

/// Colours of x1..x4 (and of heading, roll, pitch).
pub const PALETTE: [RGBColor; 4] = [
    RGBColor(200, 30, 30),
    RGBColor(30, 90, 200),
    RGBColor(20, 150, 60),
    RGBColor(150, 60, 170),
];
/// Colour of the correlation values of eq (8) in Fig. 3.
pub const BLUE_LINE: RGBColor = RGBColor(30, 90, 200);
/// Colour of their averages of eq (11) in Fig. 3.
pub const RED_LINE: RGBColor = RGBColor(210, 30, 30);

/// The time span of what a panel draws (0 to 1 when it draws nothing).
fn x_extent(panel: &Panel) -> (f64, f64) {
    let (lo, hi) = panel
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .chain(
            panel
                .bands
                .iter()
                .flat_map(|b| b.points.iter().map(|p| p.0)),
        )
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if lo < hi {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

/// Draws one panel on `area`: its title, axes and mesh, its bands, its lines and the legend; `y` is
/// its vertical axis (linear or log).
fn draw_panel<DB, Y>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    panel: &Panel,
    y: Y,
) -> Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let (x0, x1) = x_extent(panel);
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 20))
        .margin(10)
        .margin_right(40)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d::<RangedCoordf64, Y>((x0..x1).into(), y)
        .map_err(|e| anyhow!("plot: {e}"))?;
    chart
        .configure_mesh()
        .x_desc(panel.x_label.as_str())
        .y_desc(panel.y_label.as_str())
        .label_style(("sans-serif", 14))
        .x_label_formatter(&|v| format!("{v:.0}"))
        .draw()
        .map_err(|e| anyhow!("plot: {e}"))?;
    for b in &panel.bands {
        draw_band(&mut chart, b, panel.y_range)?;
    }
    for s in &panel.series {
        draw_line(&mut chart, s, panel.y_range)?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| anyhow!("plot: {e}"))?;
    Ok(())
}

/// A chart of a panel: time across, `Y` (linear or log) up.
type Chart<'a, DB, Y> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>;

/// Draws a band, cut at the axis `y_range`, with its legend entry.
fn draw_band<DB, Y>(chart: &mut Chart<'_, DB, Y>, b: &Band, y_range: (f64, f64)) -> Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64>,
{
    let (y0, y1) = y_range;
    let color = b.color;
    // One polygon per stretch of finite points (a non-finite point is a gap): the low edge
    // forward, the high edge back.
    let polygons: Vec<Vec<(f64, f64)>> = b
        .points
        .split(|p| !(p.0.is_finite() && p.1.is_finite() && p.2.is_finite()))
        .filter(|run| !run.is_empty())
        .map(|run| {
            run.iter()
                .map(|p| (p.0, p.1.clamp(y0, y1)))
                .chain(run.iter().rev().map(|p| (p.0, p.2.clamp(y0, y1))))
                .collect()
        })
        .collect();
    let label = if band_is_cut(b, y_range) {
        format!("{} (cut at the axis)", b.label)
    } else {
        b.label.clone()
    };
    chart
        .draw_series(
            polygons
                .into_iter()
                .map(|polygon| Polygon::new(polygon, color.mix(0.4).filled())),
        )
        .map_err(|e| anyhow!("plot: {e}"))?
        .label(label)
        .legend(move |(x, y)| {
            Rectangle::new([(x, y - 5), (x + 20, y + 5)], color.mix(0.4).filled())
        });
    Ok(())
}

/// Draws a line, cut at the axis `y_range` and marked where it leaves it, with its legend entry.
fn draw_line<DB, Y>(chart: &mut Chart<'_, DB, Y>, s: &Series, y_range: (f64, f64)) -> Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64>,
{
    let (y0, y1) = y_range;
    let color = s.color;
    // A NaN is a gap in the line; values beyond the axis are drawn at its edge.
    let runs: Vec<Vec<(f64, f64)>> = s
        .points
        .split(|p| p.1.is_nan() || !p.0.is_finite())
        .filter(|run| !run.is_empty())
        .map(|run| run.iter().map(|&(x, v)| (x, v.clamp(y0, y1))).collect())
        .collect();
    chart
        .draw_series(
            runs.into_iter()
                .map(|run| PathElement::new(run, color.stroke_width(1))),
        )
        .map_err(|e| anyhow!("plot: {e}"))?
        .label(legend_label(s, y_range))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    let marks = clip_marks(&s.points, y_range);
    chart
        .draw_series(marks.into_iter().take(MAX_CLIP_MARKS).map(|(x, above)| {
            let tip: i32 = if above { -8 } else { 8 };
            EmptyElement::at((x, if above { y1 } else { y0 }))
                + Polygon::new(vec![(0, tip), (-6, 0), (6, 0)], color.filled())
        }))
        .map_err(|e| anyhow!("plot: {e}"))?;
    Ok(())
}

/// Draws panels stacked vertically into one PNG of `width` x (`panel_height` x panels).
pub fn draw_png(path: &Path, panels: &[Panel], width: u32, panel_height: u32) -> Result<()> {
    crate::formats::output_file::write_via_temp(path, |temp| {
        draw_png_at(temp, path, panels, width, panel_height)
    })
}

fn draw_png_at(
    file: &Path,
    path: &Path,
    panels: &[Panel],
    width: u32,
    panel_height: u32,
) -> Result<()> {
    let height = panel_height * panels.len().max(1) as u32;
    let root = BitMapBackend::new(file, (width, height)).into_drawing_area();
    draw_panels(&root, panels)?;
    root.present()
        .with_context(|| format!("{}:0: cannot write PNG", path.display()))?;
    Ok(())
}

/// Draws panels stacked vertically on `root`.
fn draw_panels<DB>(root: &DrawingArea<DB, plotters::coord::Shift>, panels: &[Panel]) -> Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
{
    register_font();
    root.fill(&WHITE).map_err(|e| anyhow!("plot: {e}"))?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    for (area, panel) in areas.iter().zip(panels) {
        let (y0, y1) = panel.y_range;
        if panel.log_y {
            draw_panel(area, panel, (y0..y1).log_scale())?;
        } else {
            draw_panel(area, panel, y0..y1)?;
        }
    }
    Ok(())
}

/// Keeps about `max_points` evenly spaced points.
pub fn decimate(points: Vec<(f64, f64)>, max_points: usize) -> Vec<(f64, f64)> {
    let step = points.len().div_ceil(max_points.max(1)).max(1);
    if step == 1 {
        return points;
    }
    points.into_iter().step_by(step).collect()
}

/// Figs. 2 / 4: percentage error of x1..x4 against time (one panel). `curves[i]` holds
/// `(time_s, percent)` of x(i+1).
pub fn percent_error_figure(path: &Path, title: &str, curves: &[Vec<(f64, f64)>; 4]) -> Result<()> {
    let series = curves
        .iter()
        .enumerate()
        .map(|(i, c)| Series {
            label: format!("x{}", i + 1),
            color: PALETTE[i],
            points: decimate(c.clone(), 4000),
        })
        .collect();
    let panel = Panel {
        title: title.to_string(),
        x_label: "time, s".into(),
        y_label: "absolute percentage error, %".into(),
        y_range: (1e-3, 1e3),
        log_y: true,
        series,
        bands: vec![],
    };
    draw_png(path, &[panel], 1000, 600)
}

/// Fig. 3: one panel per roll component, each with
/// the correlation value of eq (8) (blue) and its average of eq (11) (red); `target_arcsec` is
/// x3 cos L / 2 drawn on the oscillatory panel.
pub fn correlation_figure(
    path: &Path,
    panels: &[CorrelationPanel],
    target_arcsec: f64,
) -> Result<()> {
    let span = 3.0 * target_arcsec.abs().max(50.0);
    let out: Vec<Panel> = panels
        .iter()
        .map(|(name, corr, avg)| {
            let mut series = vec![
                Series {
                    label: "correlation value (eq 8)".into(),
                    color: BLUE_LINE,
                    points: decimate(corr.clone(), 6000),
                },
                Series {
                    label: "average (eq 11)".into(),
                    color: RED_LINE,
                    points: decimate(avg.clone(), 6000),
                },
            ];
            if name.starts_with("oscillatory") || name.starts_with("roll as logged") {
                let (x0, x1) = (
                    corr.first().map_or(0.0, |p| p.0),
                    corr.last().map_or(1.0, |p| p.0),
                );
                series.push(Series {
                    label: "x3 cos L / 2".into(),
                    color: BLACK,
                    points: vec![(x0, target_arcsec), (x1, target_arcsec)],
                });
            }
            Panel {
                title: format!("Fig. 3 analogue: {name}"),
                x_label: "time, s".into(),
                y_label: "roll x sin(rho), arcsec".into(),
                y_range: (-span, span),
                log_y: false,
                series,
                bands: vec![],
            }
        })
        .collect();
    draw_png(path, &out, 1000, 330)
}

/// Figs. 7 / 8: attitude error (heading, roll, pitch), arcsec, against time.
pub fn attitude_error_figure(
    path: &Path,
    title: &str,
    curves: &[Vec<(f64, f64)>; 3],
    y_span_arcsec: f64,
) -> Result<()> {
    let names = ["heading", "roll", "pitch"];
    let series = curves
        .iter()
        .enumerate()
        .map(|(i, c)| Series {
            label: names[i].into(),
            color: PALETTE[i],
            points: decimate(c.clone(), 20000),
        })
        .collect();
    let panel = Panel {
        title: title.to_string(),
        x_label: "time, s".into(),
        y_label: "attitude error, arcsec".into(),
        y_range: (-y_span_arcsec, y_span_arcsec),
        log_y: false,
        series,
        bands: vec![],
    };
    draw_png(path, &[panel], 1000, 500)
}

/// One lane of a timeline: spans `(from, to)` where it holds, drawn as bars, and instants drawn
/// as ticks.
#[derive(Clone, Debug)]
pub struct Lane {
    /// Name on the lane's left.
    pub name: String,
    /// Colour of its bars and ticks.
    pub color: RGBColor,
    /// `(from, to)` times where it holds, s, drawn as bars.
    pub spans: Vec<(f64, f64)>,
    /// Instants, s, drawn as ticks.
    pub ticks: Vec<f64>,
}

/// A timeline: one lane per row, the first at the top, over `x_range` (time, s).
pub fn lanes_figure(path: &Path, title: &str, lanes: &[Lane], x_range: (f64, f64)) -> Result<()> {
    crate::formats::output_file::write_via_temp(path, |temp| {
        register_font();
        let height = 120 + 28 * lanes.len().max(1) as u32;
        let root = BitMapBackend::new(temp, (1000, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| anyhow!("plot: {e}"))?;
        let (x0, x1) = if x_range.0 < x_range.1 {
            x_range
        } else {
            (x_range.0, x_range.0 + 1.0)
        };
        let n = lanes.len().max(1) as f64;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .margin_right(40)
            .x_label_area_size(40)
            .y_label_area_size(190)
            .build_cartesian_2d(x0..x1, 0.0..n)
            .map_err(|e| anyhow!("plot: {e}"))?;
        let names: Vec<String> = lanes.iter().map(|l| l.name.clone()).collect();
        chart
            .configure_mesh()
            .disable_y_mesh()
            .x_desc("time, s")
            .label_style(("sans-serif", 14))
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_labels(lanes.len().max(1) * 2 + 1)
            .y_label_formatter(&|v| {
                // Lane k (from the top) spans (n - k - 1, n - k); its name sits at the middle.
                let k = n - v - 0.5;
                let i = k.round();
                if (k - i).abs() < 1e-6 && i >= 0.0 {
                    names.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .draw()
            .map_err(|e| anyhow!("plot: {e}"))?;
        // Bars at least one pixel wide, so a single row shows.
        let min_width = (x1 - x0) / 1000.0;
        for (k, lane) in lanes.iter().enumerate() {
            let (lo, hi) = (n - k as f64 - 0.85, n - k as f64 - 0.15);
            let color = lane.color;
            chart
                .draw_series(lane.spans.iter().map(|&(a, b)| {
                    Rectangle::new([(a, lo), (b.max(a + min_width), hi)], color.filled())
                }))
                .map_err(|e| anyhow!("plot: {e}"))?;
            chart
                .draw_series(lane.ticks.iter().map(|&t| {
                    PathElement::new(vec![(t, lo - 0.1), (t, hi + 0.1)], color.stroke_width(2))
                }))
                .map_err(|e| anyhow!("plot: {e}"))?;
        }
        root.present()
            .with_context(|| format!("{}:0: cannot write PNG", path.display()))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Text must render: a PNG of a titled panel has many more dark pixels in the title band than
    /// the same chart with an empty title.
    #[test]
    fn renders_text() {
        let dir = std::env::temp_dir().join(format!("host-sim-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let dark_in_title = |title: &str, name: &str| {
            let path = dir.join(name);
            let panel = Panel {
                title: title.into(),
                x_label: String::new(),
                y_label: String::new(),
                y_range: (0.0, 1.0),
                log_y: false,
                series: vec![],
                bands: vec![],
            };
            draw_png(&path, &[panel], 400, 200).unwrap();
            let img = std::fs::read(&path).unwrap();
            assert_eq!(&img[1..4], b"PNG");
            // Decode through plotters' own backend is not available; compare file sizes instead:
            // glyphs add detail that compresses worse than a blank band.
            img.len()
        };
        let with = dark_in_title("WWWWWWWWWWWWWWWW Title text", "with.png");
        let without = dark_in_title("", "without.png");
        assert!(
            with > without + 300,
            "title adds no pixels: {with} vs {without} bytes"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_line_beyond_the_axis_is_marked_where_it_leaves_it() {
        // The paper method's percentage error: thousands of percent at first, inside the axis
        // later, an infinite value (a true error of 0) once.
        let pts = vec![
            (0.0, 5e4),
            (1.0, 2e3),
            (2.0, 50.0),
            (3.0, 0.5),
            (4.0, f64::INFINITY),
            (5.0, 1e-4),
            (6.0, f64::NAN),
            (7.0, 1.0),
        ];
        assert_eq!(
            clip_marks(&pts, (1e-3, 1e3)),
            vec![(0.0, true), (4.0, true), (5.0, false)]
        );
        let series = Series {
            label: "x3".into(),
            color: BLACK,
            points: pts,
        };
        assert_eq!(
            legend_label(&series, (1e-3, 1e3)),
            "x3 (beyond the axis: triangles)"
        );
        assert_eq!(legend_label(&series, (1e-5, f64::INFINITY)), "x3");
        // Drawn: a line wholly above the axis lies along its top edge, and its triangle points up
        // out of the chart, above that edge.
        let color = RGBColor(1, 201, 2);
        let above = Series {
            label: "above".into(),
            color,
            points: (0..50).map(|k| (k as f64, 5.0)).collect(),
        };
        let (w, h) = (400u32, 200u32);
        let mut rgb = vec![0u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
            let panel = Panel {
                title: "t".into(),
                y_range: (-1.0, 1.0),
                series: vec![above],
                ..Panel::default()
            };
            draw_panels(&root, &[panel]).unwrap();
            root.present().unwrap();
        }
        let rows: Vec<u32> = (0..w * h)
            .filter(|i| rgb[(3 * i) as usize..(3 * i + 3) as usize] == [1, 201, 2])
            .map(|i| i / w)
            .collect();
        let mut counts = std::collections::BTreeMap::new();
        rows.iter()
            .for_each(|r| *counts.entry(*r).or_insert(0) += 1);
        let (&edge, _) = counts.iter().max_by_key(|(_, n)| **n).unwrap();
        assert!(
            rows.iter().any(|r| *r + 4 < edge),
            "a triangle above the top edge (row {edge}): {counts:?}"
        );
    }
}
