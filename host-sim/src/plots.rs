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

use anyhow::{anyhow, Context, Result};
use plotters::coord::ranged1d::{AsRangedCoord, Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
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
    pub label: String,
    pub color: RGBColor,
    pub points: Vec<(f64, f64)>,
}

/// One panel: a chart with a title, axis labels and lines.
#[derive(Clone, Debug)]
pub struct Panel {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub y_range: (f64, f64),
    pub log_y: bool,
    pub series: Vec<Series>,
}

/// Colours of x1..x4 (and of heading, roll, pitch).
pub const PALETTE: [RGBColor; 4] = [RGBColor(200, 30, 30), RGBColor(30, 90, 200), RGBColor(20, 150, 60), RGBColor(150, 60, 170)];
pub const BLUE_LINE: RGBColor = RGBColor(30, 90, 200);
pub const RED_LINE: RGBColor = RGBColor(210, 30, 30);

fn x_extent(panel: &Panel) -> (f64, f64) {
    let (lo, hi) = panel
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.0))
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
    if lo < hi {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

fn draw_panel<DB, Y>(area: &DrawingArea<DB, plotters::coord::Shift>, panel: &Panel, y: Y) -> Result<()>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let (x0, x1) = x_extent(panel);
    let (y0, y1) = panel.y_range;
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
    for s in &panel.series {
        let color = s.color;
        let pts = s.points.iter().map(|&(x, v)| (x, v.clamp(y0, y1))).filter(|p| p.1.is_finite());
        chart
            .draw_series(LineSeries::new(pts, color.stroke_width(1)))
            .map_err(|e| anyhow!("plot: {e}"))?
            .label(s.label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
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

/// Draws panels stacked vertically into one PNG of `width` x (`panel_height` x panels).
pub fn draw_png(path: &Path, panels: &[Panel], width: u32, panel_height: u32) -> Result<()> {
    register_font();
    let height = panel_height * panels.len().max(1) as u32;
    let root = BitMapBackend::new(path, (width, height)).into_drawing_area();
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
    root.present().with_context(|| format!("{}:0: cannot write PNG", path.display()))?;
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
        .map(|(i, c)| Series { label: format!("x{}", i + 1), color: PALETTE[i], points: decimate(c.clone(), 4000) })
        .collect();
    let panel = Panel {
        title: title.to_string(),
        x_label: "time, s".into(),
        y_label: "absolute percentage error, %".into(),
        y_range: (1e-3, 1e3),
        log_y: true,
        series,
    };
    draw_png(path, &[panel], 1000, 600)
}

/// Fig. 3: one panel per roll component, each with
/// the correlation value of eq (8) (blue) and its average of eq (11) (red); `target_arcsec` is
/// x3 cos L / 2 drawn on the oscillatory panel.
pub fn correlation_figure(path: &Path, panels: &[CorrelationPanel], target_arcsec: f64) -> Result<()> {
    let span = 3.0 * target_arcsec.abs().max(50.0);
    let out: Vec<Panel> = panels
        .iter()
        .map(|(name, corr, avg)| {
            let mut series = vec![
                Series { label: "correlation value (eq 8)".into(), color: BLUE_LINE, points: decimate(corr.clone(), 6000) },
                Series { label: "average (eq 11)".into(), color: RED_LINE, points: decimate(avg.clone(), 6000) },
            ];
            if name.starts_with("oscillatory") || name.starts_with("roll as logged") {
                let (x0, x1) = (corr.first().map_or(0.0, |p| p.0), corr.last().map_or(1.0, |p| p.0));
                series.push(Series { label: "x3 cos L / 2".into(), color: BLACK, points: vec![(x0, target_arcsec), (x1, target_arcsec)] });
            }
            Panel {
                title: format!("Fig. 3 analogue: {name}"),
                x_label: "time, s".into(),
                y_label: "roll x sin(rho), arcsec".into(),
                y_range: (-span, span),
                log_y: false,
                series,
            }
        })
        .collect();
    draw_png(path, &out, 1000, 330)
}

/// Figs. 7 / 8: attitude error (heading, roll, pitch), arcsec, against time.
pub fn attitude_error_figure(path: &Path, title: &str, curves: &[Vec<(f64, f64)>; 3], y_span_arcsec: f64) -> Result<()> {
    let names = ["heading", "roll", "pitch"];
    let series = curves
        .iter()
        .enumerate()
        .map(|(i, c)| Series { label: names[i].into(), color: PALETTE[i], points: decimate(c.clone(), 20000) })
        .collect();
    let panel = Panel {
        title: title.to_string(),
        x_label: "time, s".into(),
        y_label: "attitude error, arcsec".into(),
        y_range: (-y_span_arcsec, y_span_arcsec),
        log_y: false,
        series,
    };
    draw_png(path, &[panel], 1000, 500)
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
        assert!(with > without + 300, "title adds no pixels: {with} vs {without} bytes");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
