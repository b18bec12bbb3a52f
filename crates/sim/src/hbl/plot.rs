//! SVG figures of the HBL tools (plotters, SVG backend, written to strings): the buoy-grid heat
//! map, true vs estimated tracks, and error against along-path position x_rel.

use super::grid::GridCell;
use super::world::TraceRow;
use plotters::prelude::*;
use thiserror::Error;

#[derive(Debug, Error)]
#[error("plot: {0}")]
pub struct PlotError(String);

fn err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError(e.to_string())
}

/// Colour of `v` on a blue (low) → red (high) ramp over [lo, hi].
fn ramp(v: f64, lo: f64, hi: f64) -> RGBColor {
    let f = if hi > lo { ((v - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.0 };
    RGBColor((40.0 + 215.0 * f) as u8, (60.0 + 80.0 * (1.0 - (2.0 * f - 1.0).abs())) as u8, (255.0 * (1.0 - f)) as u8)
}

/// Heat map of mean zone error per buoy cell (`spacing` = cell size in m).
pub fn heat_map(cells: &[GridCell], spacing: f64) -> Result<String, PlotError> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (720, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let (xs, ys): (Vec<f64>, Vec<f64>) = cells.iter().map(|c| (c.x, c.y)).unzip();
        let lo = cells.iter().map(|c| c.zone_error.mean).fold(f64::INFINITY, f64::min);
        let hi = cells.iter().map(|c| c.zone_error.mean).fold(f64::NEG_INFINITY, f64::max);
        let h = spacing / 2.0;
        let min = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let max = |v: &[f64]| v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("Mean AUV zone error by buoy position ({lo:.2}–{hi:.2} m, blue = low)"), ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(min(&xs) - h..max(&xs) + h, min(&ys) - h..max(&ys) + h)
            .map_err(err)?;
        chart.configure_mesh().x_desc("buoy x (m, along path)").y_desc("buoy y (m)").draw().map_err(err)?;
        chart
            .draw_series(cells.iter().map(|c| {
                Rectangle::new([(c.x - h, c.y - h), (c.x + h, c.y + h)], ramp(c.zone_error.mean, lo, hi).filled())
            }))
            .map_err(err)?;
    }
    Ok(svg)
}

/// True and estimated AUV tracks, the ship and the buoy.
pub fn tracks(rows: &[TraceRow]) -> Result<String, PlotError> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 450)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let pts = rows.iter().flat_map(|r| [r.auv_true, r.auv_est, r.ship_true].into_iter().chain(r.buoy_true));
        let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
        for p in pts {
            x0 = x0.min(p[0]);
            x1 = x1.max(p[0]);
            y0 = y0.min(p[1]);
            y1 = y1.max(p[1]);
        }
        let mut chart = ChartBuilder::on(&root)
            .caption("AUV true (black) vs estimated (blue); ship (red); buoy (green)", ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(x0 - 5.0..x1 + 5.0, y0 - 5.0..y1 + 5.0)
            .map_err(err)?;
        chart.configure_mesh().x_desc("east (m)").y_desc("north (m)").draw().map_err(err)?;
        let line = |f: fn(&TraceRow) -> Option<[f64; 2]>| rows.iter().filter_map(f).map(|p| (p[0], p[1])).collect::<Vec<_>>();
        for (data, colour) in [
            (line(|r| Some(r.auv_true)), BLACK),
            (line(|r| Some(r.auv_est)), BLUE),
            (line(|r| Some(r.ship_true)), RED),
            (line(|r| r.buoy_true), GREEN),
        ] {
            chart.draw_series(LineSeries::new(data, &colour)).map_err(err)?;
        }
    }
    Ok(svg)
}

/// AUV position error against x_rel, with the measurement zone marked.
pub fn error_vs_xrel(rows: &[TraceRow], zone: (f64, f64)) -> Result<String, PlotError> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 400)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        let x0 = rows.iter().map(|r| r.x_rel).fold(f64::INFINITY, f64::min).min(zone.0);
        let x1 = rows.iter().map(|r| r.x_rel).fold(f64::NEG_INFINITY, f64::max).max(zone.1);
        let y1 = rows.iter().map(|r| r.error).fold(1.0, f64::max) * 1.1;
        let mut chart = ChartBuilder::on(&root)
            .caption("AUV position error vs x_rel (zone shaded)", ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(45)
            .build_cartesian_2d(x0..x1, 0.0..y1)
            .map_err(err)?;
        chart.configure_mesh().x_desc("x_rel (m, + = behind the ship)").y_desc("error (m)").draw().map_err(err)?;
        chart.draw_series([Rectangle::new([(zone.0, 0.0), (zone.1, y1)], RGBColor(220, 235, 255).filled())]).map_err(err)?;
        chart.draw_series(LineSeries::new(rows.iter().map(|r| (r.x_rel, r.error)), &BLUE)).map_err(err)?;
    }
    Ok(svg)
}
