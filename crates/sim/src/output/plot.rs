//! SVG plots shared by every run type: line plots (a quantity against time or distance) and
//! track plots (x east, y north, equal scales). Each returns the SVG as a string, so it can be
//! written as a file or inlined into an HTML report.

use coopnav_moos::palette;
use plotters::prelude::*;
use thiserror::Error;

#[derive(Debug, Error)]
#[error("cannot draw plot '{title}': {message}")]
pub struct PlotError {
    title: String,
    message: String,
}

impl PlotError {
    /// Drawing the plot titled `title` failed with `e` (for plots drawn beside these, e.g. heat maps).
    pub(crate) fn new(title: &str, e: &dyn std::fmt::Display) -> Self {
        PlotError { title: title.to_string(), message: e.to_string() }
    }
}

/// One named line on a plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// A vehicle's colour (`coopnav_moos::palette`); by default a colour by the series'
    /// position, so every line differs.
    pub colour: Option<palette::Rgb>,
    /// Dashed rather than solid: how a plot tells an estimate from the truth of the same vehicle.
    pub dashed: bool,
}

impl Series {
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points, colour: None, dashed: false }
    }

    /// Draws in survey AUV `k`'s colour (`coopnav_moos::palette`), so one vehicle's series match
    /// each other and the replay page.
    pub fn colour(mut self, k: usize) -> Self {
        self.colour = Some(palette::vehicle(k));
        self
    }

    /// Draws in the CNA's colour, as the replay page does.
    pub fn cna(mut self) -> Self {
        self.colour = Some(palette::CNA);
        self
    }

    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
}

/// Axis labels and title of a plot.
#[derive(Debug, Clone, Copy)]
pub struct Labels<'a> {
    pub title: &'a str,
    pub x: &'a str,
    pub y: &'a str,
}

const SIZE: (u32, u32) = (900, 600);
/// Height of the plotting area in pixels (the figure less caption, margins and x labels).
const PLOT_HEIGHT_PX: f64 = 600.0 - 40.0 - 24.0 - 40.0;
/// Height of one legend row, and of the legend box's padding, in pixels.
const LEGEND_ROW_PX: f64 = 20.0;

/// A line plot of every series against a shared x axis.
pub fn line_svg(labels: Labels, series: &[Series]) -> Result<String, PlotError> {
    let (x, y) = bounds(series);
    draw(labels, series, x, with_legend_headroom(y, series))
}

/// A track plot (y north against x east) with equal metres per pixel on both axes.
pub fn track_svg(labels: Labels, series: &[Series]) -> Result<String, PlotError> {
    let (x, y) = bounds(series);
    let (mut x, mut y) = (x, with_legend_headroom(y, series));
    let aspect = f64::from(SIZE.0) / f64::from(SIZE.1);
    let (w, h) = (x.1 - x.0, y.1 - y.0);
    if w / h < aspect {
        let grow = (h * aspect - w) / 2.0;
        x = (x.0 - grow, x.1 + grow);
    } else {
        let grow = (w / aspect - h) / 2.0;
        y = (y.0 - grow, y.1 + grow);
    }
    draw(labels, series, x, y)
}

/// Range of all finite points with a 5 % margin (and a unit span when degenerate).
fn bounds(series: &[Series]) -> ((f64, f64), (f64, f64)) {
    let finite = series.iter().flat_map(|s| s.points.iter()).filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x, mut y) = ((f64::INFINITY, f64::NEG_INFINITY), (f64::INFINITY, f64::NEG_INFINITY));
    for p in finite {
        x = (x.0.min(p.0), x.1.max(p.0));
        y = (y.0.min(p.1), y.1.max(p.1));
    }
    (padded(x), padded(y))
}

/// Raises the top of the y range so the legend (upper right) sits above every line instead of
/// covering one.
fn with_legend_headroom((lo, hi): (f64, f64), series: &[Series]) -> (f64, f64) {
    if !has_legend(series) {
        return (lo, hi);
    }
    let legend_px = LEGEND_ROW_PX * (series.len() as f64 + 1.0);
    let fraction = (legend_px / PLOT_HEIGHT_PX).min(0.75);
    (lo, hi + (hi - lo) * fraction / (1.0 - fraction))
}

fn has_legend(series: &[Series]) -> bool {
    series.len() > 1 || series.iter().any(|s| !s.name.is_empty())
}

fn padded((lo, hi): (f64, f64)) -> (f64, f64) {
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = if hi > lo { hi - lo } else { 1.0 };
    (lo - 0.05 * span, hi + 0.05 * span)
}

fn draw(labels: Labels, series: &[Series], x: (f64, f64), y: (f64, f64)) -> Result<String, PlotError> {
    let fail = |e: &dyn std::fmt::Display| PlotError::new(labels.title, e);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(labels.title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x.0..x.1, y.0..y.1)
            .map_err(|e| fail(&e))?;
        chart.configure_mesh().x_desc(labels.x).y_desc(labels.y).draw().map_err(|e| fail(&e))?;
        for (i, s) in series.iter().enumerate() {
            let colour = match s.colour {
                Some((r, g, b)) => RGBColor(r, g, b).to_rgba(),
                None => Palette99::pick(i).to_rgba(),
            };
            let style = colour.stroke_width(2);
            let points = s.points.iter().copied();
            let drawn = if s.dashed {
                chart.draw_series(DashedLineSeries::new(points, 6, 4, style))
            } else {
                chart.draw_series(LineSeries::new(points, style))
            };
            let dashed = s.dashed;
            drawn.map_err(|e| fail(&e))?.label(s.name.as_str()).legend(move |(lx, ly)| {
                let sample = if dashed { vec![(lx, ly), (lx + 6, ly)] } else { vec![(lx, ly), (lx + 18, ly)] };
                PathElement::new(sample, style)
            });
        }
        if has_legend(series) {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    Ok(svg)
}

/// One row of an interval plot: a label, a mean and its interval, and whether it is good news
/// (green) or not (red).
#[derive(Debug, Clone, PartialEq)]
pub struct Interval {
    pub label: String,
    pub mean: f64,
    pub low: f64,
    pub high: f64,
    pub good: bool,
}

/// One horizontal interval per row against a zero line, labelled beside it: how paired
/// differences and their confidence intervals are shown. The axis spans at most ±200 (a wider
/// interval is clipped at the edge).
pub fn intervals_svg(title: &str, x_desc: &str, intervals: &[Interval]) -> Result<String, PlotError> {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let mut svg = String::new();
    {
        let rows = intervals.len().max(1);
        let height = (60 + 14 * rows) as u32;
        let root = SVGBackend::with_string(&mut svg, (900, height)).into_drawing_area();
        let e = |e: &dyn std::fmt::Display| PlotError::new(title, e);
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let lo = intervals.iter().map(|c| c.low).fold(0.0, f64::min).max(-200.0);
        let hi = intervals.iter().map(|c| c.high).fold(0.0, f64::max).min(200.0);
        let pad = 0.05 * (hi - lo).max(1.0);
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(260)
            .build_cartesian_2d((lo - pad)..(hi + pad), 0.0..rows as f64)
            .map_err(|x| e(&x))?;
        chart.configure_mesh().y_labels(0).x_desc(x_desc).draw().map_err(|x| e(&x))?;
        chart.draw_series(LineSeries::new([(0.0, 0.0), (0.0, rows as f64)], BLACK)).map_err(|x| e(&x))?;
        // One label per interval, beside it (the mesh's own labels thin out to "nice" ticks).
        let label_style = TextStyle::from(("sans-serif", 11).into_font()).pos(Pos::new(HPos::Right, VPos::Center));
        for (i, c) in intervals.iter().enumerate() {
            let y = (rows - 1 - i) as f64 + 0.5;
            let (px, py) = chart.backend_coord(&(lo - pad, y));
            root.draw(&Text::new(c.label.clone(), (px - 8, py), label_style.clone())).map_err(|x| e(&x))?;
            let colour = if c.good { GREEN } else { RED };
            let clip = |v: f64| v.clamp(lo - pad, hi + pad);
            chart
                .draw_series(LineSeries::new([(clip(c.low), y), (clip(c.high), y)], colour.stroke_width(2)))
                .map_err(|x| e(&x))?;
            chart.draw_series([Circle::new((clip(c.mean), y), 3, colour.filled())]).map_err(|x| e(&x))?;
        }
        root.present().map_err(|x| e(&x))?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_plot_contains_title_and_legend() {
        let s =
            [Series::new("auv-1", vec![(0.0, 1.0), (10.0, 2.0)]), Series::new("auv-2", vec![(0.0, 3.0), (10.0, 1.0)])];
        let svg = line_svg(Labels { title: "error vs time", x: "t [s]", y: "error [m]" }, &s).unwrap();
        assert!(svg.starts_with("<svg"));
        for text in ["error vs time", "auv-1", "auv-2", "t [s]"] {
            assert!(svg.contains(text), "missing {text}");
        }
    }

    /// The legend box's bottom edge and the highest point of any data line, in SVG pixels (y down).
    fn legend_bottom_and_data_top(svg: &str) -> (f64, f64) {
        // The legend background is the one semi-transparent rectangle.
        let legend = svg.split("<rect").find(|r| r.contains("opacity=\"0.8\"")).expect("a legend box");
        let attr = |name: &str| -> f64 {
            legend.split(&format!(" {name}=\"")).nth(1).and_then(|v| v.split('"').next()).unwrap().parse().unwrap()
        };
        // Data lines are drawn 2 px wide (axes and ticks 1 px); legend samples sit inside the box.
        let data_ys = svg
            .split("<polyline")
            .filter(|p| p.contains("stroke-width=\"2\""))
            .filter_map(|p| p.split("points=\"").nth(1)?.split('"').next())
            .flat_map(|pts| pts.split_whitespace())
            .filter_map(|xy| {
                Some((xy.split(',').next()?.parse::<f64>().ok()?, xy.split(',').nth(1)?.parse::<f64>().ok()?))
            })
            .filter(|&(x, _)| x < attr("x"))
            .map(|(_, y)| y);
        (attr("y") + attr("height"), data_ys.fold(f64::INFINITY, f64::min))
    }

    #[test]
    fn the_legend_sits_above_every_line() {
        let s: Vec<Series> =
            (0..6).map(|k| Series::new(format!("auv{k}"), vec![(0.0, 0.0), (10.0, 9.0 + k as f64)])).collect();
        let labels = Labels { title: "t", x: "x", y: "y" };
        for svg in [line_svg(labels, &s).unwrap(), track_svg(labels, &s).unwrap()] {
            let (legend_bottom, data_top) = legend_bottom_and_data_top(&svg);
            assert!(legend_bottom < data_top, "legend bottom {legend_bottom} px covers data reaching {data_top} px");
        }
    }

    #[test]
    fn a_series_can_share_a_colour_and_be_dashed() {
        let s = [
            Series::new("auv0 true", vec![(0.0, 0.0), (1.0, 1.0)]).colour(3),
            Series::new("auv0 estimated", vec![(0.0, 0.1), (1.0, 1.1)]).colour(3).dashed(),
        ];
        let svg = line_svg(Labels { title: "t", x: "x", y: "y" }, &s).unwrap();
        let (r, g, b) = palette::vehicle(3);
        let hex = format!("#{r:02X}{g:02X}{b:02X}");
        assert!(svg.matches(&hex).count() >= 4, "both series and both legend samples in {hex}");
        assert!(svg.matches("<polyline").count() > 2, "the dashed series is drawn as several segments");
    }

    #[test]
    fn track_plot_survives_degenerate_and_empty_input() {
        let labels = Labels { title: "tracks", x: "east [m]", y: "north [m]" };
        assert!(track_svg(labels, &[Series::new("still", vec![(5.0, 5.0)])]).is_ok());
        assert!(track_svg(labels, &[]).is_ok());
        assert!(line_svg(labels, &[Series::new("nan", vec![(f64::NAN, 1.0)])]).is_ok());
    }
}
