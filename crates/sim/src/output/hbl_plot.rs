//! SVG figures of the HBL tools: the buoy-grid heat map (drawn here: the shared plots have no
//! colour maps), and true vs estimated tracks and error against along-path position x_rel (drawn
//! with the shared [`super::plot`] line and track plots).

use super::record::PassRow;
use crate::batch::grid::GridCell;
use crate::observe::profile::ProfileBin;
use crate::output::plot::{line_svg, tick_decimals, tick_label, track_svg, Labels, Series};
use crate::output::plot::{AXIS_FONT, SMALL_FONT, TITLE_FONT};
use coopnav_moos::palette;
use plotters::prelude::*;

pub use crate::output::plot::PlotError;

/// Colour of `v` on the colour-blind-safe sequential scale (viridis: dark purple low, yellow
/// high) over [lo, hi].
fn ramp(v: f64, lo: f64, hi: f64) -> RGBColor {
    let f = if hi > lo { (v - lo) / (hi - lo) } else { 0.0 };
    let (r, g, b) = palette::sequential(f);
    RGBColor(r, g, b)
}

/// Quantile of the colour scale's top: cells above it share the top colour, so one outlying
/// cell (a buoy placed where the AUV diverges) does not wash every other cell out to blue.
const SCALE_TOP_QUANTILE: f64 = 0.95;

/// The heat map's colour range: the lowest finite cell to the [`SCALE_TOP_QUANTILE`] quantile
/// (nearest rank), and how many cells lie above that top.
fn colour_range(values: &[f64]) -> ((f64, f64), usize) {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    let (Some(&lo), Some(&max)) = (v.first(), v.last()) else { return ((0.0, 1.0), 0) };
    let rank = ((SCALE_TOP_QUANTILE * v.len() as f64).ceil() as usize).clamp(1, v.len());
    let hi = if v[rank - 1] > lo { v[rank - 1] } else { max };
    ((lo, hi), v.iter().filter(|&&x| x > hi).count())
}

const HEAT_SIZE: (u32, u32) = (900, 480);
const BAR_WIDTH: u32 = 130;

/// Heat map of mean zone error per buoy cell (`spacing` = cell size in m), with a colour bar.
pub fn heat_map(cells: &[GridCell], spacing: f64) -> Result<String, PlotError> {
    const TITLE: &str = "Mean AUV zone error by buoy position";
    let err = |e: &dyn std::fmt::Display| PlotError::new(TITLE, e);
    let means: Vec<f64> = cells.iter().map(|c| c.zone_error.mean).collect();
    let ((lo, hi), above) = colour_range(&means);
    let caption = match above {
        0 => format!("{TITLE} (m)"),
        n => format!("{TITLE} (m; {n} cell(s) above {hi:.2} m in the top colour)"),
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, HEAT_SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let (map_area, bar_area) = root.split_horizontally(HEAT_SIZE.0 - BAR_WIDTH);
        let (xs, ys): (Vec<f64>, Vec<f64>) = cells.iter().map(|c| (c.x, c.y)).unzip();
        let h = spacing / 2.0;
        let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (x, y) = ((min(&xs) - h, max(&xs) + h), (min(&ys) - h, max(&ys) + h));
        let mut chart = ChartBuilder::on(&map_area)
            .caption(caption, ("sans-serif", if above == 0 { TITLE_FONT } else { 18 }))
            .margin(10)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(x.0..x.1, y.0..y.1)
            .map_err(|e| err(&e))?;
        let (xd, yd) = (tick_decimals(x), tick_decimals(y));
        chart
            .configure_mesh()
            .x_desc("buoy x (m, along path)")
            .y_desc("buoy y (m)")
            .x_label_formatter(&|v| tick_label(*v, xd))
            .y_label_formatter(&|v| tick_label(*v, yd))
            .label_style(("sans-serif", SMALL_FONT))
            .axis_desc_style(("sans-serif", AXIS_FONT))
            .draw()
            .map_err(|e| err(&e))?;
        chart
            .draw_series(cells.iter().map(|c| {
                Rectangle::new([(c.x - h, c.y - h), (c.x + h, c.y + h)], ramp(c.zone_error.mean, lo, hi).filled())
            }))
            .map_err(|e| err(&e))?;
        colour_bar(&bar_area, lo, hi).map_err(|e| err(&e))?;
    }
    Ok(svg)
}

/// The ramp from `lo` to `hi` as a vertical bar with its values labelled (m).
fn colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    lo: f64,
    hi: f64,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    const STEPS: usize = 64;
    let top = if hi > lo { hi } else { lo + 1.0 };
    let mut bar = ChartBuilder::on(area)
        .margin_top(44)
        .margin_bottom(58)
        .margin_right(14)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..1.0, lo..top)
        .map_err(|e| e.to_string())?;
    // The bar's plotting area is narrow: plotters' default label size (a share of it) would be
    // about 4 px, so the sizes are set.
    let d = tick_decimals((lo, top));
    bar.configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .disable_x_axis()
        .y_desc("zone error (m)")
        .y_labels(6)
        .y_label_formatter(&|v| tick_label(*v, d))
        .label_style(("sans-serif", SMALL_FONT))
        .axis_desc_style(("sans-serif", AXIS_FONT))
        .draw()
        .map_err(|e| e.to_string())?;
    let step = (top - lo) / STEPS as f64;
    bar.draw_series((0..STEPS).map(|i| {
        let v = lo + step * i as f64;
        Rectangle::new([(0.0, v), (1.0, v + step)], ramp(v + step / 2.0, lo, top).filled())
    }))
    .map_err(|e| e.to_string())?;
    Ok(())
}

/// True and estimated AUV tracks, the ship and (when there is one) the buoy.
pub fn tracks(rows: &[PassRow]) -> Result<String, PlotError> {
    let line =
        |f: fn(&PassRow) -> Option<[f64; 2]>| rows.iter().filter_map(f).map(|p| (p[0], p[1])).collect::<Vec<_>>();
    // The AUV's truth and estimate in its one colour (the estimate dashed), the ship in the CNA's.
    let mut series = vec![
        Series::new("AUV true", line(|r| Some(r.auv_true))).colour(0),
        Series::new("AUV estimated", line(|r| Some(r.auv_est))).colour(0).dashed(),
        Series::new("ship", line(|r| Some(r.ship_true))).cna(),
    ];
    let buoy = line(|r| r.buoy_true);
    if !buoy.is_empty() {
        series.push(Series::new("buoy", buoy).colour(1));
    }
    track_svg(Labels { title: "AUV true vs estimated track, ship and buoy", x: "east (m)", y: "north (m)" }, &series)
}

const X_REL: &str = "x_rel (m, + = behind the ship)";

/// The measurement zone's ends as vertical lines from 0 to `top`.
fn zone_edges(zone: (f64, f64), top: f64) -> [Series; 2] {
    let edge = |x: f64| vec![(x, 0.0), (x, top)];
    [Series::new("zone start", edge(zone.0)).reference(), Series::new("zone end", edge(zone.1)).reference().dashed()]
}

/// AUV position error against x_rel, with the measurement zone's ends marked by vertical lines.
pub fn error_vs_xrel(rows: &[PassRow], zone: (f64, f64)) -> Result<String, PlotError> {
    let top = rows.iter().map(|r| r.error).fold(1.0, f64::max);
    let mut series = vec![Series::new("error", rows.iter().map(|r| (r.x_rel, r.error)).collect()).colour(0)];
    series.extend(zone_edges(zone, top));
    line_svg(Labels { title: "AUV position error vs x_rel", x: X_REL, y: "error (m)" }, &series)
}

/// Monte Carlo mean error, |along-path| and |across-path| components against x_rel.
pub fn profile(bins: &[ProfileBin], zone: (f64, f64)) -> Result<String, PlotError> {
    let top = bins.iter().map(|b| b.error).fold(1.0, f64::max);
    let line = |f: fn(&ProfileBin) -> f64| bins.iter().map(|b| (b.x_rel, f(b))).collect();
    let mut series = vec![
        Series::new("mean error", line(|b| b.error)),
        Series::new("along path", line(|b| b.parallel)),
        Series::new("across path", line(|b| b.perpendicular)),
    ];
    series.extend(zone_edges(zone, top));
    line_svg(Labels { title: "Monte Carlo mean AUV error vs x_rel", x: X_REL, y: "error (m)" }, &series)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observe::zone::ZoneSpec;
    use crate::output::log_format::LogFormat;
    use crate::output::record::record_pass;
    use crate::scenario::hbl::table5_scenario;
    use coopnav_nav::cycle::Configuration;

    fn rows(c: Configuration) -> Vec<PassRow> {
        let sc = table5_scenario(c).unwrap();
        record_pass(&sc, ZoneSpec::table5(), LogFormat::default(), 1).unwrap().0.rows
    }

    /// Whether the SVG has a text element reading exactly `name` (a legend entry).
    fn legend(svg: &str, name: &str) -> bool {
        svg.contains(&format!(">\n{name}\n</text>"))
    }

    #[test]
    fn tracks_name_each_vehicle_and_leave_out_a_missing_buoy() {
        let hbl = rows(Configuration::HblTwo);
        assert!(hbl.iter().any(|r| r.buoy_true.is_some()));
        let svg = tracks(&hbl).unwrap();
        assert!(["AUV true", "AUV estimated", "ship", "buoy"].iter().all(|n| legend(&svg, n)), "{svg}");
        let msbl = rows(Configuration::Msbl);
        assert!(msbl.iter().all(|r| r.buoy_true.is_none()));
        let svg = tracks(&msbl).unwrap();
        assert!(legend(&svg, "ship") && !legend(&svg, "buoy"));
    }

    fn cell(x: f64, mean: f64) -> GridCell {
        GridCell { x, y: 0.0, zone_error: crate::observe::stats::Stats { n: 1, mean, sd: 0.0, se: 0.0 } }
    }

    /// Distinct fill colours of the map's cells (the colour bar's rectangles come after them).
    fn cell_fills(svg: &str, n: usize) -> std::collections::BTreeSet<String> {
        svg.split("<rect")
            .filter(|r| r.contains("fill=\"#") && !r.contains("#FFFFFF"))
            .take(n)
            .filter_map(|r| r.split("fill=\"").nth(1)?.split('"').next().map(str::to_string))
            .collect()
    }

    #[test]
    fn one_outlying_cell_does_not_wash_out_the_heat_map() {
        // 40 ordinary cells from 1 to 2 m and one diverged cell at 100 m.
        let mut cells: Vec<GridCell> = (0..40).map(|i| cell(10.0 * f64::from(i), 1.0 + f64::from(i) / 39.0)).collect();
        cells.push(cell(400.0, 100.0));
        let svg = heat_map(&cells, 10.0).unwrap();
        let distinct = cell_fills(&svg, 40).len();
        assert!(distinct >= 20, "the ordinary cells use only {distinct} colours");
        // Nearest rank of the 95 % quantile of 41 cells is the 39th: the 2 m cell and the outlier lie above.
        assert!(svg.contains("2 cell(s) above 1.97 m") && svg.contains("zone error (m)"), "caption and colour bar");
        // Every text, the colour bar's labels among them, readable at 100 %.
        let sizes: Vec<f64> =
            svg.split("font-size=\"").skip(1).filter_map(|r| r.split('"').next()?.parse().ok()).collect();
        assert!(sizes.len() > 10 && sizes.iter().all(|&px| px >= crate::output::plot::MIN_TEXT_PX), "{sizes:?}");
        // The colour bar labels its top, 1.97 m, at 2 decimals' ticks or fewer, never 4-digit noise.
        assert!(!svg.contains("1.9700"), "bar labels at their precision");
        assert_eq!(colour_range(&[3.0, f64::NAN, 1.0, 2.0]), ((1.0, 3.0), 0));
        assert_eq!(colour_range(&[]), ((0.0, 1.0), 0));
    }

    #[test]
    fn error_plot_marks_the_zone() {
        let rows = rows(Configuration::HblOne);
        let zone = ZoneSpec::table5();
        let svg = error_vs_xrel(&rows, (zone.zone_min, zone.zone_max)).unwrap();
        assert!(legend(&svg, "zone start") && legend(&svg, "zone end") && svg.contains("x_rel"));
    }
}
