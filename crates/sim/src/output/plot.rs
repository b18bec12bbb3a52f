//! SVG plots shared by every run type: line plots (a quantity against time or distance, with
//! optional marked events), track plots (x east, y north, equal scales) and interval plots (paired
//! differences against zero). Each returns the SVG as a string, so it can be written as a file or
//! inlined into an HTML report. Every text is at least [`MIN_TEXT_PX`] tall and every tick label
//! carries the digits its tick step needs, no more.

use coopnav_moos::palette;
use plotters::coord::ranged1d::{BoldPoints, Ranged};
use plotters::coord::types::RangedCoordf64;
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
    /// A vehicle's colour (`coopnav_moos::palette`); by default the palette's colour of the
    /// series' position, so every line differs.
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

    /// Draws in [`palette::REFERENCE`]: a reference line (a limit, a bound, a zone's edge) rather
    /// than a vehicle or a result.
    pub fn reference(mut self) -> Self {
        self.colour = Some(palette::REFERENCE);
        self
    }

    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
}

/// An event marked on a line plot: a numbered triangle at (x, y), its text on the numbered line
/// under the plot (where no line of the plot crosses it).
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    pub x: f64,
    pub y: f64,
    pub colour: palette::Rgb,
    pub text: String,
}

/// Axis labels and title of a plot.
#[derive(Debug, Clone, Copy)]
pub struct Labels<'a> {
    pub title: &'a str,
    pub x: &'a str,
    pub y: &'a str,
}

/// The smallest text any plot carries, in SVG pixels: readable at 100 % zoom.
pub const MIN_TEXT_PX: f64 = 11.0;
/// Font sizes as plotters takes them: its SVG backend writes a size s as s / 1.24 px, so 14 is
/// 11.3 px on the page (tick labels, legends, row labels, notes), 16 is 12.9 px (axis titles) and
/// 24 is 19.4 px (plot titles).
pub(crate) const SMALL_FONT: u32 = 14;
pub(crate) const AXIS_FONT: u32 = 16;
pub(crate) const TITLE_FONT: u32 = 24;
/// The most tick labels on an axis.
const TICKS: usize = 10;

const SIZE: (u32, u32) = (900, 600);
/// Height of the plotting area in pixels (the figure less caption, margins and x labels).
const PLOT_HEIGHT_PX: f64 = 600.0 - 44.0 - 24.0 - 50.0;
/// Height of one legend row, and of the legend box's padding, in pixels.
const LEGEND_ROW_PX: f64 = 22.0;
/// Height of the strip under a plot that holds its note.
const NOTE_PX: u32 = 24;

/// A line plot of every series against a shared x axis.
pub fn line_svg(labels: Labels, series: &[Series]) -> Result<String, PlotError> {
    line_svg_marked(labels, series, &[], "")
}

/// A line plot of every series with `markers` drawn over the lines, and under the plot `note`
/// (when not empty) and one numbered line per marker: how a plot explains an event it shows.
/// The plot keeps its size; the figure grows by one text row per line.
pub fn line_svg_marked(labels: Labels, series: &[Series], markers: &[Marker], note: &str) -> Result<String, PlotError> {
    let (x, y) = bounds(series);
    draw(labels, series, x, with_legend_headroom(y, series), markers, note)
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
    draw(labels, series, x, y, &[], "")
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

/// How many decimals the tick labels of an axis over `range` need: the fewest that print every
/// tick plotters places there (at most [`TICKS`]) exactly, so 500 reads "500" and 0.25 "0.25".
pub(crate) fn tick_decimals((lo, hi): (f64, f64)) -> usize {
    let ticks = RangedCoordf64::from(lo..hi).key_points(BoldPoints(TICKS));
    (0..=9)
        .find(|&d| {
            let scale = 10f64.powi(d as i32);
            ticks.iter().all(|t| ((t * scale).round() - t * scale).abs() < 1e-6)
        })
        .unwrap_or(9)
}

/// A tick's label at `decimals` decimals (never "-0").
pub(crate) fn tick_label(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-').chars().all(|c| c == '0' || c == '.') {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

fn rgb((r, g, b): palette::Rgb) -> RGBColor {
    RGBColor(r, g, b)
}

fn draw(
    labels: Labels,
    series: &[Series],
    x: (f64, f64),
    y: (f64, f64),
    markers: &[Marker],
    note: &str,
) -> Result<String, PlotError> {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let fail = |e: &dyn std::fmt::Display| PlotError::new(labels.title, e);
    let mut svg = String::new();
    {
        let lines: Vec<(String, String)> = (!note.is_empty())
            .then(|| (String::new(), note.to_string()))
            .into_iter()
            .chain(markers.iter().enumerate().map(|(i, m)| (format!("{}", i + 1), m.text.clone())))
            .collect();
        let below = NOTE_PX * lines.len() as u32;
        let root = SVGBackend::with_string(&mut svg, (SIZE.0, SIZE.1 + below)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let (area, note_area) = root.split_vertically(SIZE.1);
        let mut chart = ChartBuilder::on(&area)
            .caption(labels.title, ("sans-serif", TITLE_FONT))
            .margin(12)
            .x_label_area_size(50)
            .y_label_area_size(75)
            .build_cartesian_2d(x.0..x.1, y.0..y.1)
            .map_err(|e| fail(&e))?;
        let (xd, yd) = (tick_decimals(x), tick_decimals(y));
        chart
            .configure_mesh()
            .x_desc(labels.x)
            .y_desc(labels.y)
            .x_labels(TICKS)
            .y_labels(TICKS)
            .x_label_formatter(&|v| tick_label(*v, xd))
            .y_label_formatter(&|v| tick_label(*v, yd))
            .label_style(("sans-serif", SMALL_FONT))
            .axis_desc_style(("sans-serif", AXIS_FONT))
            .draw()
            .map_err(|e| fail(&e))?;
        for (i, s) in series.iter().enumerate() {
            let colour = rgb(s.colour.unwrap_or_else(|| palette::vehicle(i))).to_rgba();
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
        let small = |h: HPos| TextStyle::from(("sans-serif", SMALL_FONT).into_font()).pos(Pos::new(h, VPos::Center));
        for (i, m) in markers.iter().enumerate() {
            let style = rgb(m.colour).filled();
            chart.draw_series([TriangleMarker::new((m.x, m.y), 8, style)]).map_err(|e| fail(&e))?;
            // The marker's number just above its triangle.
            let (px, py) = chart.backend_coord(&(m.x, m.y));
            let colour = rgb(m.colour);
            let number = TextStyle::from(("sans-serif", SMALL_FONT).into_font().style(FontStyle::Bold))
                .color(&colour)
                .pos(Pos::new(HPos::Center, VPos::Bottom));
            area.draw(&Text::new(format!("{}", i + 1), (px, py - 10), number)).map_err(|e| fail(&e))?;
        }
        if has_legend(series) {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .label_font(("sans-serif", SMALL_FONT))
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()
                .map_err(|e| fail(&e))?;
        }
        for (i, (number, text)) in lines.iter().enumerate() {
            let y = (NOTE_PX as i32) * i as i32 + (NOTE_PX / 2) as i32;
            if !number.is_empty() {
                note_area.draw(&Text::new(number.clone(), (30, y), small(HPos::Right))).map_err(|e| fail(&e))?;
            }
            note_area.draw(&Text::new(text.clone(), (38, y), small(HPos::Left))).map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    Ok(svg)
}

/// One row of an interval plot: a label, a mean and its interval, and whether it is good news
/// (blue) or not (vermillion).
#[derive(Debug, Clone, PartialEq)]
pub struct Interval {
    pub label: String,
    pub mean: f64,
    pub low: f64,
    pub high: f64,
    pub good: bool,
}

/// How far from the rows' median mean, in robust standard deviations, a row's mean may lie and
/// still set the axis.
const BULK_SDS: f64 = 5.0;
/// The widest axis an interval plot draws, either side of zero.
const INTERVAL_AXIS_CAP: f64 = 200.0;
/// Height of one interval row, px.
const ROW_PX: u32 = 26;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

/// The x range an interval plot shows, before padding: zero and every interval of the bulk,
/// capped at ±[`INTERVAL_AXIS_CAP`]. The bulk is every row when there are fewer than three, else
/// the rows whose mean lies within [`BULK_SDS`] robust standard deviations of the median mean (the
/// SD estimated as 1.4826 × the median absolute deviation, and at least the median interval's
/// width), so one far row (a policy that never helps) does not squash the rest to a line.
pub(crate) fn interval_axis(intervals: &[Interval]) -> (f64, f64) {
    let finite: Vec<&Interval> =
        intervals.iter().filter(|c| c.mean.is_finite() && c.low.is_finite() && c.high.is_finite()).collect();
    let bulk: Vec<&Interval> = if finite.len() < 3 {
        finite
    } else {
        let mid = median(&mut finite.iter().map(|c| c.mean).collect::<Vec<_>>());
        let mad = median(&mut finite.iter().map(|c| (c.mean - mid).abs()).collect::<Vec<_>>());
        let width = median(&mut finite.iter().map(|c| c.high - c.low).collect::<Vec<_>>());
        let sd = (1.4826 * mad).max(width);
        finite.into_iter().filter(|c| (c.mean - mid).abs() <= BULK_SDS * sd).collect()
    };
    let lo = bulk.iter().map(|c| c.low).fold(0.0, f64::min).max(-INTERVAL_AXIS_CAP);
    let hi = bulk.iter().map(|c| c.high).fold(0.0, f64::max).min(INTERVAL_AXIS_CAP);
    (lo, hi)
}

/// A row's mean and interval as the comparison table prints them (2 decimals).
fn interval_text(c: &Interval) -> String {
    format!("{:.2} [{:.2}, {:.2}]", c.mean, c.low, c.high)
}

/// One horizontal interval per row against a zero line, its label at the left and its mean and
/// interval printed at the right: how paired differences and their confidence intervals are
/// shown. The axis spans the bulk of the rows ([`interval_axis`]); an interval reaching beyond it
/// is drawn to the edge and ends in a triangle pointing off the axis, and a row whose mean lies
/// beyond it is a triangle at the edge with its mean printed beside; a note under the plot says so.
pub fn intervals_svg(title: &str, x_desc: &str, intervals: &[Interval]) -> Result<String, PlotError> {
    use plotters::style::text_anchor::{HPos, Pos, VPos};
    let mut svg = String::new();
    {
        let rows = intervals.len().max(1);
        let (lo, hi) = interval_axis(intervals);
        let pad = 0.05 * (hi - lo).max(1.0);
        let (x0, x1) = (lo - pad, hi + pad);
        let clipped = intervals.iter().any(|c| c.low < x0 || c.high > x1);
        let height = 100 + ROW_PX * rows as u32 + if clipped { NOTE_PX } else { 0 };
        let root = SVGBackend::with_string(&mut svg, (900, height)).into_drawing_area();
        let e = |e: &dyn std::fmt::Display| PlotError::new(title, e);
        root.fill(&WHITE).map_err(|x| e(&x))?;
        let (area, note_area) = if clipped {
            let (plot, below) = root.split_vertically(height - NOTE_PX);
            (plot, Some(below))
        } else {
            (root.clone(), None)
        };
        let mut chart = ChartBuilder::on(&area)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(48)
            .y_label_area_size(250)
            .right_y_label_area_size(180)
            .build_cartesian_2d(x0..x1, 0.0..rows as f64)
            .map_err(|x| e(&x))?;
        let xd = tick_decimals((x0, x1));
        chart
            .configure_mesh()
            .y_labels(0)
            .x_labels(TICKS)
            .x_label_formatter(&|v| tick_label(*v, xd))
            .label_style(("sans-serif", SMALL_FONT))
            .axis_desc_style(("sans-serif", AXIS_FONT))
            .x_desc(x_desc)
            .draw()
            .map_err(|x| e(&x))?;
        chart.draw_series(LineSeries::new([(0.0, 0.0), (0.0, rows as f64)], BLACK)).map_err(|x| e(&x))?;
        // One label per interval at each side (the mesh's own labels thin out to "nice" ticks).
        let small = |h: HPos| TextStyle::from(("sans-serif", SMALL_FONT).into_font()).pos(Pos::new(h, VPos::Center));
        for (i, c) in intervals.iter().enumerate() {
            let y = (rows - 1 - i) as f64 + 0.5;
            let colour = rgb(if c.good { GOOD } else { BAD });
            let (left, py) = chart.backend_coord(&(x0, y));
            let (right, _) = chart.backend_coord(&(x1, y));
            root.draw(&Text::new(c.label.clone(), (left - 8, py), small(HPos::Right))).map_err(|x| e(&x))?;
            root.draw(&Text::new(interval_text(c), (right + 8, py), small(HPos::Left))).map_err(|x| e(&x))?;
            let clip = |v: f64| v.clamp(x0, x1);
            chart
                .draw_series(LineSeries::new([(clip(c.low), y), (clip(c.high), y)], colour.stroke_width(2)))
                .map_err(|x| e(&x))?;
            if (x0..=x1).contains(&c.mean) {
                chart.draw_series([Circle::new((c.mean, y), 4, colour.filled())]).map_err(|x| e(&x))?;
            }
            // A triangle at each edge the row reaches past, pointing off the axis.
            for (past, edge, dir) in [(c.low < x0, left, -1), (c.high > x1, right, 1)] {
                if !past {
                    continue;
                }
                let tip = (edge + dir * 2, py);
                let base = edge - dir * 10;
                root.draw(&Polygon::new(vec![tip, (base, py - 7), (base, py + 7)], colour.filled()))
                    .map_err(|x| e(&x))?;
            }
            if !(x0..=x1).contains(&c.mean) {
                let (text_x, h) = if c.mean < x0 { (left + 14, HPos::Left) } else { (right - 14, HPos::Right) };
                root.draw(&Text::new(format!("mean {:.2} off the axis", c.mean), (text_x, py), small(h)))
                    .map_err(|x| e(&x))?;
            }
        }
        if let Some(note_area) = note_area {
            let note = "Axis: the rows' bulk (means within 5 robust SDs of their median); \
                        a triangle marks an interval past it (numbers at the right).";
            note_area.draw(&Text::new(note, (14, (NOTE_PX / 2) as i32), small(HPos::Left))).map_err(|x| e(&x))?;
        }
        root.present().map_err(|x| e(&x))?;
    }
    Ok(svg)
}

/// An interval plot's colours: good news in blue, the rest in vermillion (a pair that stays
/// apart under the common colour-vision deficiencies, where green and red do not).
const GOOD: palette::Rgb = (0, 114, 178);
const BAD: palette::Rgb = (213, 94, 0);

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

    /// Every `font-size` in `svg`, px.
    pub(crate) fn font_sizes(svg: &str) -> Vec<f64> {
        svg.split("font-size=\"").skip(1).filter_map(|r| r.split('"').next()?.parse().ok()).collect()
    }

    /// The text of every `<text>` element of `svg`.
    fn texts(svg: &str) -> Vec<String> {
        svg.split("<text")
            .skip(1)
            .filter_map(|t| Some(t.split_once('>')?.1.split("</text>").next()?.trim().to_string()))
            .collect()
    }

    fn differences() -> Vec<Interval> {
        let row = |label: &str, mean: f64, half: f64| Interval {
            label: label.to_string(),
            mean,
            low: mean - half,
            high: mean + half,
            good: mean < 0.0,
        };
        vec![
            row("vs planner", -6.09, 0.8),
            row("vs none", -85.67, 5.27),
            row("vs racetrack", -5.82, 0.83),
            row("vs zigzag", -3.85, 0.38),
            row("vs centroid", -3.90, 0.64),
        ]
    }

    #[test]
    fn every_text_is_readable_at_full_size() {
        let s: Vec<Series> =
            (0..3).map(|k| Series::new(format!("auv{k}"), vec![(0.0, 0.0), (3600.0, 9.0)]).colour(k)).collect();
        let labels = Labels { title: "t", x: "time [s]", y: "error [m]" };
        let marker = Marker { x: 1145.0, y: 8.0, colour: palette::vehicle(2), text: "a jump".into() };
        for svg in [
            line_svg(labels, &s).unwrap(),
            line_svg_marked(labels, &s, &[marker], "a note").unwrap(),
            track_svg(labels, &s).unwrap(),
            intervals_svg("d", "difference, m", &differences()).unwrap(),
            intervals_svg("one row", "difference, m", &differences()[..1]).unwrap(),
        ] {
            let sizes = font_sizes(&svg);
            assert!(sizes.len() > 10, "{} texts", sizes.len());
            let min = sizes.iter().copied().fold(f64::INFINITY, f64::min);
            assert!(min >= MIN_TEXT_PX, "a text {min:.1} px tall");
        }
    }

    #[test]
    fn tick_labels_carry_the_digits_their_step_needs() {
        let labels = Labels { title: "t", x: "x", y: "y" };
        let svg = line_svg(labels, &[Series::new("", vec![(0.0, 0.0), (3600.0, 0.3)])]).unwrap();
        let ticks: Vec<String> = texts(&svg).into_iter().filter(|t| t.parse::<f64>().is_ok()).collect();
        // x every 500 s, y every 0.05.
        for t in ["500", "3500", "0.05", "0.30"] {
            assert!(ticks.iter().any(|x| x == t), "no tick {t} in {ticks:?}");
        }
        assert!(!ticks.iter().any(|t| t == "500.0" || t == "0.3" || t == "0.050" || t.starts_with('-')), "{ticks:?}");
        assert_eq!(tick_label(-0.0001, 2), "0.00");
        assert_eq!(tick_label(-2.5, 1), "-2.5");
    }

    #[test]
    fn one_far_interval_does_not_squash_the_others_and_is_marked() {
        let svg = intervals_svg("d", "difference, m", &differences()).unwrap();
        // The axis is fitted to the four rows near -4 m: its ticks stop short of -10.
        let ticks: Vec<f64> = texts(&svg).iter().filter_map(|t| t.parse().ok()).collect();
        assert!(ticks.iter().all(|&t| t > -10.0), "ticks {ticks:?}");
        assert!(ticks.contains(&-6.0) && ticks.contains(&0.0), "ticks {ticks:?}");
        let t = texts(&svg);
        assert!(t.iter().any(|x| x == "mean -85.67 off the axis"), "{t:?}");
        assert!(t.iter().any(|x| x == "-85.67 [-90.94, -80.40]"), "{t:?}");
        assert!(t.iter().any(|x| x.starts_with("Axis: the rows")), "the note");
        // The one triangle: a polygon at the axis' left edge.
        assert_eq!(svg.matches("<polygon").count(), 1, "one clipped end");
        // Without the far row nothing is clipped: no triangle and no note.
        let rest: Vec<Interval> = differences().into_iter().filter(|c| c.label != "vs none").collect();
        let svg = intervals_svg("d", "difference, m", &rest).unwrap();
        assert_eq!(svg.matches("<polygon").count(), 0);
        assert!(!svg.contains("Axis: the rows"));
        // Two rows set the axis together, however far apart.
        assert_eq!(interval_axis(&differences()[..2]), (-90.94, 0.0));
    }
}
