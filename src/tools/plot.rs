//! Log-log scatter-and-line figures, written as SVG and as PNG (plotters). Text is drawn with a
//! font compiled into the binary (epaint_default_fonts' Hack), so a PNG looks the same
//! on a machine without fonts.

use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Points of one colour, with a legend entry.
#[derive(Clone, Debug, PartialEq)]
pub struct PointGroup {
    /// Legend text.
    pub label: String,
    /// Index into the palette.
    pub colour: usize,
    /// (x, y), both positive.
    pub points: Vec<(f64, f64)>,
}

/// A polyline through points (in order); grey when it has no colour.
#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    /// Index into the palette, or `None` for a neutral grey.
    pub colour: Option<usize>,
    /// (x, y), both positive.
    pub points: Vec<(f64, f64)>,
}

/// A log-log figure: lines under coloured points, with a legend of the point groups.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// Caption.
    pub title: String,
    /// Horizontal axis description.
    pub x_label: String,
    /// Vertical axis description.
    pub y_label: String,
    /// Lines, drawn first.
    pub lines: Vec<Line>,
    /// Points, drawn over the lines, one legend entry per group.
    pub groups: Vec<PointGroup>,
}

/// Pixel size of both outputs.
pub const SIZE: (u32, u32) = (900, 600);

/// Ten colours that stay apart on white (Tableau 10); groups past ten reuse them.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

const FONT: &str = "sans-serif";

/// Registers the built-in font for plotters' text layout (once per process).
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The bytes are a valid TrueType font shipped by epaint_default_fonts; registering
        // cannot fail for them, and text without a font would fail loudly at the first label.
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::HACK_REGULAR);
    });
}

/// The range [lo, hi] of positive values, widened by a quarter decade each side (a whole decade
/// around a single value) so that no point sits on the frame.
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) =
        values.filter(|v| *v > 0.0 && v.is_finite()).fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if lo > hi {
        return 0.1..10.0;
    }
    let pad = if hi / lo < 1.01 { 10f64.powf(0.5) } else { 10f64.powf(0.25) };
    lo / pad..hi * pad
}

/// Tick positions on a log axis over `r`: 1-2-5 in each decade (1-1.5-2-3-5-7 over a narrow
/// range, powers of ten over a wide one), so that every axis has a few labelled ticks.
fn log_ticks(r: &std::ops::Range<f64>) -> Vec<f64> {
    let (e0, e1) = (r.start.log10().floor() as i32, r.end.log10().ceil() as i32);
    let ticks = |mantissas: &[f64]| -> Vec<f64> {
        (e0..=e1).flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e))).filter(|v| r.contains(v)).collect()
    };
    let t = ticks(&[1.0, 2.0, 5.0]);
    if t.len() > 12 {
        ticks(&[1.0])
    } else if t.len() < 3 {
        ticks(&[1.0, 1.5, 2.0, 3.0, 5.0, 7.0])
    } else {
        t
    }
}

/// Three significant digits without trailing zeros: 0.0123, 1.5, 250.
fn tick(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

fn draw<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, fig: &Figure) -> std::result::Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let all = || fig.groups.iter().flat_map(|g| &g.points).chain(fig.lines.iter().flat_map(|l| &l.points));
    let (xr, yr) = (log_range(all().map(|p| p.0)), log_range(all().map(|p| p.1)));
    let (xt, yt) = (log_ticks(&xr), log_ticks(&yr));
    let mut chart = ChartBuilder::on(root)
        .caption(&fig.title, (FONT, 20))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(xr.log_scale().with_key_points(xt), yr.log_scale().with_key_points(yt))
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc(&fig.x_label)
        .y_desc(&fig.y_label)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style((FONT, 14))
        .axis_desc_style((FONT, 16))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    for line in &fig.lines {
        let style = match line.colour {
            Some(c) => PALETTE[c % PALETTE.len()].stroke_width(2),
            None => RGBColor(150, 150, 150).stroke_width(1),
        };
        chart.draw_series(LineSeries::new(line.points.iter().copied(), style)).map_err(err)?;
    }
    for g in &fig.groups {
        let colour = PALETTE[g.colour % PALETTE.len()];
        chart
            .draw_series(g.points.iter().map(|&p| Circle::new(p, 5, colour.filled())))
            .map_err(err)?
            .label(&g.label)
            .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FONT, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(180, 180, 180))
        .draw()
        .map_err(err)?;
    root.present().map_err(err)
}

/// Writes `fig` as an SVG file.
pub fn write_svg(fig: &Figure, path: &Path) -> Result<()> {
    register_font();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw(&root, fig).map_err(|e| Error::output(path, e))?;
    }
    crate::files::write_bytes(path, svg.as_bytes())
}

/// Writes `fig` as an 8-bit RGB PNG file.
pub fn write_png(fig: &Figure, path: &Path) -> Result<()> {
    register_font();
    let (w, h) = SIZE;
    let mut rgb = vec![0u8; w as usize * h as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, fig).map_err(|e| Error::output(path, e))?;
    }
    crate::files::write_png(path, w, h, &rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_readable_on_narrow_and_wide_log_ranges() {
        assert_eq!(log_ticks(&(0.3..30.0)), [0.5, 1.0, 2.0, 5.0, 10.0, 20.0]);
        assert_eq!(log_ticks(&(0.9..1.6)), [1.0, 1.5]);
        assert_eq!(log_ticks(&(0.85..2.5)), [1.0, 1.5, 2.0]);
        assert_eq!(log_ticks(&(5e-7..2e2)).len(), 9);
        assert_eq!(
            (tick(0.012345), tick(1.5), tick(250.0), tick(2.0)),
            ("0.0123".into(), "1.5".into(), "250".into(), "2".into())
        );
    }

    #[test]
    fn ranges_keep_every_point_off_the_frame() {
        let r = log_range([0.01, 1.0, -1.0, 0.0, f64::NAN].into_iter());
        assert!(r.start < 0.01 && r.end > 1.0 && r.start > 0.0);
        let single = log_range([2.0].into_iter());
        assert!(single.start < 2.0 && single.end > 2.0);
        assert_eq!(log_range(std::iter::empty()), 0.1..10.0);
    }
}
