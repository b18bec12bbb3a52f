//! SVG figures of the HBL tools: the buoy-grid heat map (drawn here: the shared plots have no
//! colour maps), and true vs estimated tracks and error against along-path position x_rel (drawn
//! with the shared [`crate::plot`] line and track plots).

use super::grid::GridCell;
use super::profile::ProfileBin;
use super::world::TraceRow;
use crate::plot::{line_svg, track_svg, Labels, Series};
use plotters::prelude::*;

pub use crate::plot::PlotError;

/// Colour of `v` on a blue (low) → red (high) ramp over [lo, hi].
fn ramp(v: f64, lo: f64, hi: f64) -> RGBColor {
    let f = if hi > lo { ((v - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.0 };
    RGBColor((40.0 + 215.0 * f) as u8, (60.0 + 80.0 * (1.0 - (2.0 * f - 1.0).abs())) as u8, (255.0 * (1.0 - f)) as u8)
}

/// Heat map of mean zone error per buoy cell (`spacing` = cell size in m).
pub fn heat_map(cells: &[GridCell], spacing: f64) -> Result<String, PlotError> {
    const TITLE: &str = "Mean AUV zone error by buoy position";
    let err = |e: &dyn std::fmt::Display| PlotError::new(TITLE, e);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let (xs, ys): (Vec<f64>, Vec<f64>) = cells.iter().map(|c| (c.x, c.y)).unzip();
        let lo = cells.iter().map(|c| c.zone_error.mean).fold(f64::INFINITY, f64::min);
        let hi = cells.iter().map(|c| c.zone_error.mean).fold(f64::NEG_INFINITY, f64::max);
        let h = spacing / 2.0;
        let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("{TITLE} ({lo:.2}–{hi:.2} m, blue = low)"), ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(min(&xs) - h..max(&xs) + h, min(&ys) - h..max(&ys) + h)
            .map_err(|e| err(&e))?;
        chart.configure_mesh().x_desc("buoy x (m, along path)").y_desc("buoy y (m)").draw().map_err(|e| err(&e))?;
        chart
            .draw_series(cells.iter().map(|c| {
                Rectangle::new([(c.x - h, c.y - h), (c.x + h, c.y + h)], ramp(c.zone_error.mean, lo, hi).filled())
            }))
            .map_err(|e| err(&e))?;
    }
    Ok(svg)
}

/// True and estimated AUV tracks, the ship and (when there is one) the buoy.
pub fn tracks(rows: &[TraceRow]) -> Result<String, PlotError> {
    let line =
        |f: fn(&TraceRow) -> Option<[f64; 2]>| rows.iter().filter_map(f).map(|p| (p[0], p[1])).collect::<Vec<_>>();
    let mut series = vec![
        Series::new("AUV true", line(|r| Some(r.auv_true))),
        Series::new("AUV estimated", line(|r| Some(r.auv_est))),
        Series::new("ship", line(|r| Some(r.ship_true))),
    ];
    let buoy = line(|r| r.buoy_true);
    if !buoy.is_empty() {
        series.push(Series::new("buoy", buoy));
    }
    track_svg(Labels { title: "AUV true vs estimated track, ship and buoy", x: "east (m)", y: "north (m)" }, &series)
}

const X_REL: &str = "x_rel (m, + = behind the ship)";

/// The measurement zone's ends as vertical lines from 0 to `top`.
fn zone_edges(zone: (f64, f64), top: f64) -> [Series; 2] {
    let edge = |x: f64| vec![(x, 0.0), (x, top)];
    [Series::new("zone start", edge(zone.0)), Series::new("zone end", edge(zone.1))]
}

/// AUV position error against x_rel, with the measurement zone's ends marked by vertical lines.
pub fn error_vs_xrel(rows: &[TraceRow], zone: (f64, f64)) -> Result<String, PlotError> {
    let top = rows.iter().map(|r| r.error).fold(1.0, f64::max);
    let mut series = vec![Series::new("error", rows.iter().map(|r| (r.x_rel, r.error)).collect())];
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
    use crate::hbl::{run, Scenario};
    use coopnav_nav::cycle::Configuration;

    fn rows(c: Configuration) -> (Scenario, Vec<TraceRow>) {
        let sc = Scenario::table5(c);
        let (_, trace) = run(&sc, &sc.resolved_cycle().unwrap(), 1, true);
        (sc, trace.unwrap().rows)
    }

    /// Whether the SVG has a text element reading exactly `name` (a legend entry).
    fn legend(svg: &str, name: &str) -> bool {
        svg.contains(&format!(">\n{name}\n</text>"))
    }

    #[test]
    fn tracks_name_each_vehicle_and_leave_out_a_missing_buoy() {
        let (_, hbl) = rows(Configuration::HblTwo);
        assert!(hbl.iter().any(|r| r.buoy_true.is_some()));
        let svg = tracks(&hbl).unwrap();
        assert!(["AUV true", "AUV estimated", "ship", "buoy"].iter().all(|n| legend(&svg, n)), "{svg}");
        let (_, msbl) = rows(Configuration::Msbl);
        assert!(msbl.iter().all(|r| r.buoy_true.is_none()));
        let svg = tracks(&msbl).unwrap();
        assert!(legend(&svg, "ship") && !legend(&svg, "buoy"));
    }

    #[test]
    fn error_plot_marks_the_zone() {
        let (sc, rows) = rows(Configuration::HblOne);
        let svg = error_vs_xrel(&rows, (sc.geometry.zone_min, sc.geometry.zone_max)).unwrap();
        assert!(legend(&svg, "zone start") && legend(&svg, "zone end") && svg.contains("x_rel"));
    }
}
