//! Log-log line plots written as PNG and SVG (plotters), for the convergence figures and the
//! error-against-time study. Text is drawn with the bundled DejaVu Sans, so no system fonts are
//! needed.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::error::Result;

/// One polyline with its legend entry.
#[derive(Clone, Debug)]
pub struct Line {
    /// Legend text.
    pub label: String,
    /// Points (x, y), both positive.
    pub points: Vec<(f64, f64)>,
    /// Index into the palette.
    pub color: usize,
    /// Dashed instead of solid.
    pub dashed: bool,
}

/// One log-log chart.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Caption above the chart.
    pub caption: String,
    /// x-axis description.
    pub x_label: String,
    /// y-axis description.
    pub y_label: String,
    /// The lines.
    pub lines: Vec<Line>,
    /// Points to mark with a ring (e.g. a Pareto front), joined by a black step line.
    pub front: Vec<(f64, f64)>,
}

/// Panels in a grid, row by row.
#[derive(Clone, Debug)]
pub struct Figure {
    /// The panels.
    pub panels: Vec<Panel>,
    /// Panels per row.
    pub columns: usize,
}

/// Ten colours that stay apart (Matplotlib's "tab10").
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

const PANEL_WIDTH: u32 = 840;
const PANEL_HEIGHT: u32 = 620;

static FONT: Once = Once::new();

pub(crate) fn register_font() {
    FONT.call_once(|| {
        let bytes: &'static [u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
        // The bundled font is a valid TrueType file; a failure here is a build defect.
        plotters::style::register_font("sans-serif", FontStyle::Normal, bytes)
            .unwrap_or_else(|_| panic!("bundled DejaVuSans.ttf is not a valid font"));
    });
}

/// Writes `figure` as `<stem>.png` and `<stem>.svg`; returns the two paths.
pub fn write_figure(figure: &Figure, stem: &Path) -> Result<Vec<PathBuf>> {
    register_font();
    if let Some(dir) = stem.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let (rows, columns) = grid(figure);
    let size = (PANEL_WIDTH * columns as u32, PANEL_HEIGHT * rows as u32);
    let png = PathBuf::from(format!("{}.png", stem.display()));
    let svg = PathBuf::from(format!("{}.svg", stem.display()));
    draw(BitMapBackend::new(&png, size).into_drawing_area(), figure)?;
    draw(SVGBackend::new(&svg, size).into_drawing_area(), figure)?;
    Ok(vec![png, svg])
}

pub(crate) fn plot_error<E: std::fmt::Display>(e: E) -> crate::error::Error {
    std::io::Error::other(format!("plotting: {e}")).into()
}

/// A log range covering `values` with a little room on both sides.
fn log_range(values: impl Iterator<Item = f64>) -> Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !lo.is_finite() {
        return 0.1..10.0;
    }
    let (lo, hi) = if hi / lo < 10.0 { (lo / 3.0, hi * 3.0) } else { (lo / 1.6, hi * 1.6) };
    lo..hi
}

/// (rows, columns) of the figure's grid.
fn grid(figure: &Figure) -> (usize, usize) {
    let columns = figure.columns.clamp(1, figure.panels.len().max(1));
    (figure.panels.len().div_ceil(columns).max(1), columns)
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, figure: &Figure) -> Result<()> {
    root.fill(&WHITE).map_err(plot_error)?;
    let areas = root.split_evenly(grid(figure));
    for (area, panel) in areas.iter().zip(&figure.panels) {
        draw_panel(area, panel)?;
    }
    root.present().map_err(plot_error)
}

/// A tick label: plain decimals from 0.01 to 100000, powers of ten otherwise.
fn tick(v: f64) -> String {
    if (0.01..100_000.0).contains(&v.abs()) {
        let text = format!("{v:.3}");
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.0e}")
    }
}

/// Share of a panel's width given to its legend.
const LEGEND_SHARE: f64 = 0.36;

fn draw_panel<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, panel: &Panel) -> Result<()> {
    let width = area.dim_in_pixel().0;
    let (plot_area, legend_area) =
        area.split_horizontally((f64::from(width) * (1.0 - LEGEND_SHARE)) as u32);
    let all = || panel.lines.iter().flat_map(|l| l.points.iter().copied());
    let x = log_range(all().map(|p| p.0));
    let y = log_range(all().map(|p| p.1));
    let mut chart = ChartBuilder::on(&plot_area)
        .caption(&panel.caption, ("sans-serif", 15))
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(x.log_scale(), y.log_scale())
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc(&panel.x_label)
        .y_desc(&panel.y_label)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 14))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(plot_error)?;
    let mut legend: Vec<(String, ShapeStyle, bool)> = Vec::new();
    for line in &panel.lines {
        let color = PALETTE[line.color % PALETTE.len()];
        let style = color.stroke_width(2);
        if line.dashed {
            chart
                .draw_series(DashedLineSeries::new(line.points.clone(), 8, 5, style))
                .map_err(plot_error)?;
        } else {
            chart.draw_series(LineSeries::new(line.points.clone(), style)).map_err(plot_error)?;
        }
        chart
            .draw_series(line.points.iter().map(|&p| Circle::new(p, 3, color.filled())))
            .map_err(plot_error)?;
        legend.push((line.label.clone(), style, line.dashed));
    }
    if !panel.front.is_empty() {
        let mut front = panel.front.clone();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut steps = Vec::with_capacity(2 * front.len());
        for (k, &(t, e)) in front.iter().enumerate() {
            if k > 0 {
                steps.push((t, front[k - 1].1));
            }
            steps.push((t, e));
        }
        let style = BLACK.stroke_width(1);
        chart.draw_series(LineSeries::new(steps, style)).map_err(plot_error)?;
        chart
            .draw_series(front.iter().map(|&p| Circle::new(p, 7, BLACK.stroke_width(2))))
            .map_err(plot_error)?;
        legend.push(("Pareto front (ringed)".into(), style, false));
    }
    draw_legend(&legend_area, &legend)
}

/// The legend in its own strip right of the chart: a line sample and the label per entry.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, ShapeStyle, bool)],
) -> Result<()> {
    let font = ("sans-serif", 12).into_font();
    for (k, (label, style, dashed)) in entries.iter().enumerate() {
        let y = 40 + 18 * k as i32;
        let segments: Vec<(i32, i32)> =
            if *dashed { vec![(0, 8), (13, 21)] } else { vec![(0, 21)] };
        for (a, b) in segments {
            area.draw(&PathElement::new(vec![(4 + a, y), (4 + b, y)], *style))
                .map_err(plot_error)?;
        }
        area.draw(&Text::new(label.clone(), (32, y - 7), font.clone())).map_err(plot_error)?;
    }
    Ok(())
}
