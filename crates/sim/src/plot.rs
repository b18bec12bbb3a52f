//! SVG plots shared by every run type: line plots (a quantity against time or distance) and
//! track plots (x east, y north, equal scales). Each returns the SVG as a string, so it can be
//! written as a file or inlined into an HTML report.

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
}

impl Series {
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series { name: name.into(), points }
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

/// A line plot of every series against a shared x axis.
pub fn line_svg(labels: Labels, series: &[Series]) -> Result<String, PlotError> {
    let (x, y) = bounds(series);
    draw(labels, series, x, y)
}

/// A track plot (y north against x east) with equal metres per pixel on both axes.
pub fn track_svg(labels: Labels, series: &[Series]) -> Result<String, PlotError> {
    let (mut x, mut y) = bounds(series);
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
            let color = Palette99::pick(i).to_rgba();
            chart
                .draw_series(LineSeries::new(s.points.iter().copied(), color.stroke_width(2)))
                .map_err(|e| fail(&e))?
                .label(s.name.as_str())
                .legend(move |(lx, ly)| PathElement::new(vec![(lx, ly), (lx + 18, ly)], color.stroke_width(2)));
        }
        if series.len() > 1 || series.iter().any(|s| !s.name.is_empty()) {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
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

    #[test]
    fn track_plot_survives_degenerate_and_empty_input() {
        let labels = Labels { title: "tracks", x: "east [m]", y: "north [m]" };
        assert!(track_svg(labels, &[Series::new("still", vec![(5.0, 5.0)])]).is_ok());
        assert!(track_svg(labels, &[]).is_ok());
        assert!(line_svg(labels, &[Series::new("nan", vec![(f64::NAN, 1.0)])]).is_ok());
    }
}
