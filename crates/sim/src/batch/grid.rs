//! The buoy-location grid (Gill 2013, §2.3.1 and §3.1.1; the thesis's Fig. 13 is lost, so its
//! optimal region is recomputed): a zero-drift Monte Carlo per candidate
//! buoy position north of the path, the region within a tolerance of the best cell, and CSV
//! output (the SVG heat map is in [`crate::output::hbl_plot`]). The caller says how one cell runs (on the
//! engine: [`engine_cell`]).

use crate::models::buoy::Drift as EngineDrift;
use crate::observe::stats::Stats;
use crate::observe::zone::{zone_monte_carlo, ZoneError, ZoneSpec};
use crate::scenario::Scenario as EngineScenario;
use coopnav_core::validation::{InvalidFields, Problems};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Grid extent and sampling. Defaults: the 200 m path, 0–100 m north, 10 m spacing, 250 runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GridSpec {
    pub x: [f64; 2],
    pub y: [f64; 2],
    pub spacing: f64,
    pub runs_per_cell: usize,
}

impl Default for GridSpec {
    fn default() -> Self {
        GridSpec { x: [-79.0, 121.0], y: [0.0, 100.0], spacing: 10.0, runs_per_cell: 250 }
    }
}

#[derive(Debug, Error)]
pub enum GridError {
    #[error("grid spec: {0}")]
    Fields(#[from] InvalidFields),
    #[error(transparent)]
    Zone(#[from] ZoneError),
    #[error("grid: the scenario has no buoy to place")]
    NoBuoy,
    #[error("grid cell x = {x} m, y = {y} m: {source}")]
    Cell { x: f64, y: f64, source: Box<GridError> },
    #[error("grid CSV: {0}")]
    Csv(#[from] csv::Error),
}

impl GridSpec {
    /// Checks each field; the grid's size is checked against the work limits by
    /// `coopnav_sim::batch::work::hbl_grid`.
    pub fn validate(&self) -> Result<(), GridError> {
        let mut p = Problems::new();
        p.positive("spacing", self.spacing);
        for (axis, [lo, hi]) in [("x", self.x), ("y", self.y)] {
            p.finite(&format!("{axis}[0]"), lo);
            p.require(&format!("{axis}[1]"), hi, hi >= lo, &format!("a finite number ≥ {axis}[0]"));
        }
        if self.runs_per_cell < 2 {
            p.push("runs_per_cell", self.runs_per_cell.to_string(), "≥ 2 (a cell's Monte Carlo needs 2 runs)");
        }
        Ok(p.finish()?)
    }
    /// The last index of an axis (its points are lo + i·step, i = 0..=n), as a float so that a
    /// huge count is checked before anything is allocated.
    fn axis_last(lo: f64, hi: f64, step: f64) -> f64 {
        ((hi - lo) / step + 1e-9).floor()
    }
    fn axis(lo: f64, hi: f64, step: f64) -> Vec<f64> {
        let n = Self::axis_last(lo, hi, step) as usize;
        (0..=n).map(|i| lo + i as f64 * step).collect()
    }
    /// The number of cells [`GridSpec::cells`] would hold, computed without building them.
    pub fn cell_count(&self) -> f64 {
        let points = |r: [f64; 2]| Self::axis_last(r[0], r[1], self.spacing) + 1.0;
        points(self.x) * points(self.y)
    }
    pub fn xs(&self) -> Vec<f64> {
        Self::axis(self.x[0], self.x[1], self.spacing)
    }
    pub fn ys(&self) -> Vec<f64> {
        Self::axis(self.y[0], self.y[1], self.spacing)
    }
    /// Cells in row-major order (y outer, x inner).
    pub fn cells(&self) -> Vec<[f64; 2]> {
        let xs = self.xs();
        self.ys().into_iter().flat_map(|y| xs.iter().map(move |&x| [x, y])).collect()
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GridCell {
    pub x: f64,
    pub y: f64,
    pub zone_error: Stats,
}

/// The zone-error statistics of one cell's Monte Carlo, the buoy placed at the cell.
pub type CellMonteCarlo<'a> = dyn Fn([f64; 2]) -> Result<Stats, GridError> + Sync + 'a;

/// Runs `cell` at every cell of `spec`, in row-major order; `progress` receives the number of
/// finished cells.
pub fn buoy_grid(
    spec: &GridSpec,
    progress: &(dyn Fn(u64) + Sync),
    cell: &CellMonteCarlo,
) -> Result<Vec<GridCell>, GridError> {
    spec.validate()?;
    let mut out = Vec::new();
    for (i, [x, y]) in spec.cells().into_iter().enumerate() {
        let zone_error = cell([x, y]).map_err(|e| GridError::Cell { x, y, source: Box::new(e) })?;
        out.push(GridCell { x, y, zone_error });
        progress(i as u64 + 1);
    }
    Ok(out)
}

/// The grid's runs end once the AUV is past the zone, or at the former HBL loop's cap of 400 s:
/// a buoy on the path near the AUV's start can pull the AUV's filter into the mirror solution and
/// the AUV, steering on it, off the path, so it reaches the zone late (cell (−79, 10) m, run 82
/// of the full grid, did not by Table 5's 130 s). The lane is long enough for 400 s.
pub const GRID_MIN_DURATION_S: f64 = 400.0;
pub const GRID_MIN_LANE_M: f64 = 360.0;

/// Gives `sc` at least [`GRID_MIN_DURATION_S`] and a lane of at least [`GRID_MIN_LANE_M`]
/// (revalidate it after).
pub fn lengthen_for_grid(sc: &mut EngineScenario) {
    sc.duration_s = sc.duration_s.max(GRID_MIN_DURATION_S);
    sc.fleet.lane_length = sc.fleet.lane_length.max(GRID_MIN_LANE_M);
}

/// A cell on the engine: scenario `base` with its buoy 0 moored at the cell (its zone as the
/// file gives it), `runs` runs from `seed`, scored in `zone`.
pub fn engine_cell(
    base: &EngineScenario,
    zone: ZoneSpec,
    runs: usize,
    seed: u64,
) -> Result<impl Fn([f64; 2]) -> Result<Stats, GridError> + Sync + '_, GridError> {
    if base.buoys.is_empty() {
        return Err(GridError::NoBuoy);
    }
    Ok(move |[x, y]: [f64; 2]| {
        let mut sc = base.clone();
        sc.buoys[0].x = x;
        sc.buoys[0].y = y;
        sc.buoys[0].drift = EngineDrift::Moored;
        Ok(zone_monte_carlo(&sc, zone, runs, seed).map_err(ZoneError::from)?.summary(seed)?.zone_error)
    })
}

/// Cells whose mean error is within `tolerance` (fraction) of the best cell's.
pub fn optimal_region(cells: &[GridCell], tolerance: f64) -> Vec<GridCell> {
    let best = cells.iter().map(|c| c.zone_error.mean).fold(f64::INFINITY, f64::min);
    cells.iter().filter(|c| c.zone_error.mean <= best * (1.0 + tolerance)).copied().collect()
}

pub fn write_csv<W: std::io::Write>(out: W, cells: &[GridCell]) -> Result<(), GridError> {
    let mut w = csv::Writer::from_writer(out);
    w.write_record(["x", "y", "runs", "mean_zone_error", "sd", "se"])?;
    for c in cells {
        let s = c.zone_error;
        w.write_record([c.x, c.y, s.n as f64, s.mean, s.sd, s.se].map(|v| v.to_string()))?;
    }
    w.flush().map_err(csv::Error::from)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_cover_the_box() {
        let g = GridSpec { x: [0.0, 20.0], y: [0.0, 10.0], spacing: 10.0, runs_per_cell: 2 };
        assert_eq!(g.cells(), vec![[0.0, 0.0], [10.0, 0.0], [20.0, 0.0], [0.0, 10.0], [10.0, 10.0], [20.0, 10.0]]);
        assert_eq!(g.cell_count(), 6.0);
        assert_eq!(GridSpec { spacing: 0.001, ..g.clone() }.cell_count(), 20_001.0 * 10_001.0);
        let bad = GridSpec { spacing: 0.0, ..g.clone() };
        assert!(bad.validate().unwrap_err().to_string().contains("spacing"));
        let bad = GridSpec { runs_per_cell: 1, ..g };
        assert!(bad.validate().unwrap_err().to_string().contains("runs_per_cell"));
    }

    #[test]
    fn optimal_region_tolerance() {
        let s = |m| Stats { n: 2, mean: m, sd: 0.0, se: 0.0 };
        let cells = [
            GridCell { x: 0.0, y: 0.0, zone_error: s(1.0) },
            GridCell { x: 1.0, y: 0.0, zone_error: s(1.05) },
            GridCell { x: 2.0, y: 0.0, zone_error: s(2.0) },
        ];
        assert_eq!(optimal_region(&cells, 0.1).len(), 2);
    }

    #[test]
    fn an_engine_grid_names_the_cell_whose_runs_never_reached_the_zone_and_needs_a_buoy() {
        let text = include_str!("../../../../scenarios/gill-table5-hbl-two.toml");
        let mut sc = EngineScenario::parse(text, std::path::Path::new("gill-table5-hbl-two.toml")).unwrap();
        sc.duration_s = 20.0; // the AUV meets the ship's zone after about 80 s
        let spec = GridSpec { x: [0.0, 0.0], y: [50.0, 50.0], spacing: 10.0, runs_per_cell: 2 };
        let err = {
            let cell = engine_cell(&sc, ZoneSpec::table5(), 2, 1).unwrap();
            buoy_grid(&spec, &|_| {}, &cell).unwrap_err().to_string()
        };
        assert!(err.contains("x = 0 m, y = 50 m") && err.contains("never entered"), "{err}");
        sc.buoys.clear();
        assert!(matches!(engine_cell(&sc, ZoneSpec::table5(), 2, 1), Err(GridError::NoBuoy)));
    }
}
