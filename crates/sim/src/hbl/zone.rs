//! Gill's zone metric (gill digest §5.6, §7.5) as an engine [`Observer`]: the survey AUV's true
//! error while it is in the measurement zone relative to the ship, x_rel = (AUV − ship) along the
//! AUV's direction of travel in [zone_min, zone_max], split into along- and across-path parts,
//! and the across-path error in the approach window just before the zone. The engine samples
//! once a second; the old HBL loop scored every 0.1 s step.

use crate::closed_loop::{run, Faults, PolicyError, PolicySpec, Scenario};
use crate::engine::{Observer, TraceRow};
use coopnav_core::{run_seed, CompassDeg, Heading, Vec3};
use serde::Serialize;

/// Where the zone is: the AUV's path direction, the x_rel limits and the approach window, m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZoneSpec {
    pub path_compass_deg: f64,
    pub zone_min: f64,
    pub zone_max: f64,
    pub approach_m: f64,
}

impl ZoneSpec {
    /// Gill's Table 5 zone (digest §5.1, A16) for an AUV running east: −30…75 m, 50 m approach.
    pub fn table5() -> Self {
        ZoneSpec { path_compass_deg: 90.0, zone_min: -30.0, zone_max: 75.0, approach_m: 50.0 }
    }
}

/// The zone figures of one run (None where the AUV never was in the window).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ZoneMetrics {
    pub zone_error: Option<f64>,
    pub zone_parallel: Option<f64>,
    pub zone_perpendicular: Option<f64>,
    pub zone_samples: usize,
    pub approach_perpendicular: Option<f64>,
}

/// Scores survey AUV `auv` against ship `ship`.
pub struct GillZone {
    spec: ZoneSpec,
    auv: usize,
    ship: usize,
    /// The ship's true position at the current sample.
    ship_at: Option<Vec3>,
    zone: [f64; 3],
    zone_n: usize,
    approach: f64,
    approach_n: usize,
}

impl GillZone {
    pub fn new(spec: ZoneSpec, auv: usize, ship: usize) -> Self {
        GillZone { spec, auv, ship, ship_at: None, zone: [0.0; 3], zone_n: 0, approach: 0.0, approach_n: 0 }
    }

    pub fn metrics(&self) -> ZoneMetrics {
        let mean = |sum: f64, n: usize| (n > 0).then(|| sum / n as f64);
        ZoneMetrics {
            zone_error: mean(self.zone[0], self.zone_n),
            zone_parallel: mean(self.zone[1], self.zone_n),
            zone_perpendicular: mean(self.zone[2], self.zone_n),
            zone_samples: self.zone_n,
            approach_perpendicular: mean(self.approach, self.approach_n),
        }
    }

    fn score(&mut self, ship: Vec3, row: &TraceRow) {
        let (ux, uy) = Heading::from(CompassDeg(self.spec.path_compass_deg)).unit();
        let along = |dx: f64, dy: f64| dx * ux + dy * uy;
        let across = |dx: f64, dy: f64| -dx * uy + dy * ux;
        let x_rel = along(row.true_x - ship.x, row.true_y - ship.y);
        let (dx, dy) = (row.est_x - row.true_x, row.est_y - row.true_y);
        let s = &self.spec;
        if (s.zone_min..=s.zone_max).contains(&x_rel) {
            self.zone[0] += row.error;
            self.zone[1] += along(dx, dy).abs();
            self.zone[2] += across(dx, dy).abs();
            self.zone_n += 1;
        } else if (s.zone_min - s.approach_m..s.zone_min).contains(&x_rel) {
            self.approach += across(dx, dy).abs();
            self.approach_n += 1;
        }
    }
}

impl Observer for GillZone {
    fn on_ships(&mut self, _t: f64, ships: &[Vec3]) {
        self.ship_at = ships.get(self.ship).copied();
    }
    fn on_sample(&mut self, _t: f64, _cna: Vec3, rows: &[TraceRow]) {
        if let (Some(ship), Some(row)) = (self.ship_at, rows.iter().find(|r| r.auv == self.auv)) {
            self.score(ship, row);
        }
    }
}

/// Runs engine scenario `sc` (its CNA silent: policy `none`) with seeds `run_seed(base_seed, i)`
/// and scores survey AUV 0 against ship 0 in `spec`'s zone. Also whether every run was healthy.
pub fn zone_monte_carlo(
    sc: &Scenario,
    spec: ZoneSpec,
    runs: usize,
    base_seed: u64,
) -> Result<(Vec<ZoneMetrics>, bool), PolicyError> {
    let silent = PolicySpec::new("none", sc)?;
    let mut healthy = true;
    let mut metrics = Vec::with_capacity(runs);
    for i in 0..runs as u64 {
        let mut zone = GillZone::new(spec, 0, 0);
        let mut policy = silent.build(sc)?;
        healthy &= run(sc, &mut policy, run_seed(base_seed, i), &Faults::default(), &mut zone).fleet.healthy;
        metrics.push(zone.metrics());
    }
    Ok((metrics, healthy))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(true_x: f64, est_x: f64, est_y: f64) -> TraceRow {
        let (dx, dy) = (est_x - true_x, est_y);
        TraceRow {
            t: 0.0,
            auv: 0,
            true_x,
            true_y: 0.0,
            true_z: 2.0,
            est_x,
            est_y,
            error: dx.hypot(dy),
            est_sd: 1.0,
            p_ee: 1.0,
            p_en: 0.0,
            p_nn: 1.0,
            nees: 0.0,
            modelled: None,
            cna_x: 0.0,
            cna_y: 0.0,
            distance: 0.0,
        }
    }

    #[test]
    fn only_samples_inside_the_zone_count_and_the_approach_keeps_the_across_path_part() {
        let mut z = GillZone::new(ZoneSpec::table5(), 0, 0);
        let ship = Vec3::new(100.0, 0.0, 0.0);
        // x_rel −150 (nowhere), −50 (approach: 3 m across), 0 and 50 (zone: errors 5 and 0.5 m),
        // 90 (past it).
        for (x, ex, ey) in
            [(-50.0, -40.0, 0.0), (50.0, 50.0, 3.0), (100.0, 103.0, 4.0), (150.0, 150.0, 0.5), (190.0, 0.0, 0.0)]
        {
            z.on_ships(0.0, &[ship]);
            z.on_sample(0.0, Vec3::new(0.0, 0.0, 0.0), &[row(x, ex, ey)]);
        }
        let m = z.metrics();
        assert_eq!(
            (m.zone_samples, m.zone_error, m.zone_parallel, m.zone_perpendicular),
            (2, Some(2.75), Some(1.5), Some(2.25))
        );
        assert_eq!(m.approach_perpendicular, Some(3.0));
        // Without a ship nothing is scored.
        let mut none = GillZone::new(ZoneSpec::table5(), 0, 0);
        none.on_sample(0.0, Vec3::new(0.0, 0.0, 0.0), &[row(100.0, 103.0, 4.0)]);
        assert_eq!(none.metrics(), ZoneMetrics::default());
    }
}
