//! Gill's zone metric (Gill 2013, §2.4.1 and §3.2, Table 5) as an engine [`Observer`]: the survey AUV's true
//! error while it is in the measurement zone relative to the ship, x_rel = (AUV − ship) along the
//! AUV's direction of travel in [zone_min, zone_max], split into along- and across-path parts,
//! the across-path error in the approach window just before the zone, the error profile against
//! x_rel (the thesis's Figs. 16, 19, 21), and, where the schedule has buoy 0 transmit, the AUV's
//! buoy-filter error and the buoy's saturation error over the whole run (Table 4). The engine
//! samples once a second; the former HBL loop scored every 0.1 s step and the saturation at the
//! buoy's slots only.

use super::profile::{add_to_bin, merge_bins, BinSums, ProfileBin};
use crate::engine::Faults;
use crate::engine::{BuoySample, Observer, TraceRow};
use crate::models::schedule::Owner;
use crate::observe::metrics::{run, RunResult};
use crate::observe::stats::Stats;
use crate::policy::{PolicyError, PolicySpec};
use crate::scenario::Scenario;
use coopnav_core::{run_seed, CompassDeg, Heading, Vec3};
use coopnav_nav::codec::Zone;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::{AtomicU64, Ordering};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ZoneError {
    #[error(transparent)]
    Policy(#[from] PolicyError),
    #[error("run {index} (seed {seed}): the AUV never entered the measurement zone within duration_s")]
    NoZone { index: usize, seed: u64 },
}

/// Where the zone is: the AUV's path direction, the x_rel limits, the approach window and the
/// profile's bin width, m; and whether the run ends once the AUV is past the zone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ZoneSpec {
    pub path_compass_deg: f64,
    pub zone_min: f64,
    pub zone_max: f64,
    pub approach_m: f64,
    pub profile_bin_m: f64,
    /// End the run at the first sample past zone_max (only the zone is wanted: a grid cell).
    pub stop_past_zone: bool,
}

impl ZoneSpec {
    /// The component of (dx, dy) along the path direction (x_rel for AUV − ship).
    pub fn along(&self, dx: f64, dy: f64) -> f64 {
        let (ux, uy) = Heading::from(CompassDeg(self.path_compass_deg)).unit();
        dx * ux + dy * uy
    }
    /// The component of (dx, dy) across the path (to its left).
    pub fn across(&self, dx: f64, dy: f64) -> f64 {
        let (ux, uy) = Heading::from(CompassDeg(self.path_compass_deg)).unit();
        -dx * uy + dy * ux
    }

    /// Gill's Table 5 zone (Gill 2013, §2.4.1; docs/models.md#gill-scenario) for an AUV running
    /// east: −30…75 m, 50 m approach,
    /// the profile in 25 m bins.
    pub fn table5() -> Self {
        ZoneSpec {
            path_compass_deg: 90.0,
            zone_min: -30.0,
            zone_max: 75.0,
            approach_m: 50.0,
            profile_bin_m: 25.0,
            stop_past_zone: false,
        }
    }
}

/// The zone figures of one run (None where the AUV never was in the window, or the schedule
/// never has buoy 0 transmit).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ZoneMetrics {
    pub zone_error: Option<f64>,
    pub zone_parallel: Option<f64>,
    pub zone_perpendicular: Option<f64>,
    pub zone_samples: usize,
    pub approach_perpendicular: Option<f64>,
    /// Mean distance from buoy 0 to where the AUV's filter of it puts it, over the run.
    pub buoy_error: Option<f64>,
    /// Mean distance from buoy 0 to its clamp into its broadcast zone, over the run.
    pub saturation_error: Option<f64>,
}

/// Running sum and count of one mean.
#[derive(Debug, Clone, Copy, Default)]
struct Mean {
    sum: f64,
    n: usize,
}

impl Mean {
    fn add(&mut self, v: f64) {
        self.sum += v;
        self.n += 1;
    }
    fn get(&self) -> Option<f64> {
        (self.n > 0).then(|| self.sum / self.n as f64)
    }
}

/// Scores survey AUV `auv` against ship `ship` (and buoy 0, when scored).
pub struct GillZone {
    spec: ZoneSpec,
    auv: usize,
    ship: usize,
    /// Buoy 0's broadcast zone, when its filter and saturation are scored.
    buoy_zone: Option<Zone>,
    /// The ship's true position at the current sample.
    ship_at: Option<Vec3>,
    zone: [Mean; 3],
    approach: Mean,
    buoy: Mean,
    saturation: Mean,
    bins: BinSums,
    past_zone: bool,
}

impl GillZone {
    pub fn new(spec: ZoneSpec, auv: usize, ship: usize) -> Self {
        GillZone {
            spec,
            auv,
            ship,
            buoy_zone: None,
            ship_at: None,
            zone: [Mean::default(); 3],
            approach: Mean::default(),
            buoy: Mean::default(),
            saturation: Mean::default(),
            bins: BinSums::new(),
            past_zone: false,
        }
    }

    /// Also scores buoy 0 (its zone `zone`): the AUV's filter of it and its saturation.
    pub fn with_buoy(self, zone: Zone) -> Self {
        GillZone { buoy_zone: Some(zone), ..self }
    }

    /// For engine scenario `sc`: AUV 0 against ship 0, and buoy 0 where the schedule has it transmit.
    pub fn of_scenario(spec: ZoneSpec, sc: &Scenario) -> Self {
        let zone = GillZone::new(spec, 0, 0);
        let slots = sc.comms.schedule.slots(sc.comms.tau, sc.fleet.n_auvs, sc.buoys.len());
        match sc.buoys.first() {
            Some(b) if slots.iter().any(|s| s.owner == Owner::Buoy(0)) => zone.with_buoy(b.zone()),
            _ => zone,
        }
    }

    /// Whether buoy 0 is scored (the schedule has it transmit).
    pub fn scores_buoy(&self) -> bool {
        self.buoy_zone.is_some()
    }

    /// The scored survey AUV and ship (indices).
    pub fn vehicles(&self) -> (usize, usize) {
        (self.auv, self.ship)
    }

    pub fn metrics(&self) -> ZoneMetrics {
        ZoneMetrics {
            zone_error: self.zone[0].get(),
            zone_parallel: self.zone[1].get(),
            zone_perpendicular: self.zone[2].get(),
            zone_samples: self.zone[0].n,
            approach_perpendicular: self.approach.get(),
            buoy_error: self.buoy.get(),
            saturation_error: self.saturation.get(),
        }
    }

    fn score(&mut self, ship: Vec3, row: &TraceRow) {
        let x_rel = self.spec.along(row.true_x - ship.x, row.true_y - ship.y);
        let (dx, dy) = (row.est_x - row.true_x, row.est_y - row.true_y);
        let (parallel, perpendicular) = (self.spec.along(dx, dy).abs(), self.spec.across(dx, dy).abs());
        let bin = (x_rel / self.spec.profile_bin_m).floor() as i64;
        add_to_bin(self.bins.entry(bin).or_default(), [1.0, row.error, parallel, perpendicular]);
        let s = &self.spec;
        self.past_zone |= x_rel > s.zone_max;
        if (s.zone_min..=s.zone_max).contains(&x_rel) {
            self.zone[0].add(row.error);
            self.zone[1].add(parallel);
            self.zone[2].add(perpendicular);
        } else if (s.zone_min - s.approach_m..s.zone_min).contains(&x_rel) {
            self.approach.add(perpendicular);
        }
    }
}

impl Observer for GillZone {
    fn on_ships(&mut self, _t: f64, ships: &[Vec3]) {
        self.ship_at = ships.get(self.ship).copied();
    }
    fn on_buoys(&mut self, _t: f64, buoys: &[BuoySample]) {
        let (Some(zone), Some(b)) = (self.buoy_zone, buoys.first()) else { return };
        if let Some(est) = b.estimates.get(self.auv) {
            self.buoy.add((est[0] - b.truth.x).hypot(est[1] - b.truth.y));
        }
        self.saturation.add(zone.saturation_error(b.truth.x, b.truth.y));
    }
    fn on_sample(&mut self, _t: f64, _cna: Vec3, rows: &[TraceRow]) {
        if let (Some(ship), Some(row)) = (self.ship_at, rows.iter().find(|r| r.auv == self.auv)) {
            self.score(ship, row);
        }
    }
    fn stop(&self) -> bool {
        self.spec.stop_past_zone && self.past_zone
    }
}

/// What the engine counted in one run for the scored AUV: ranges it decoded (ship and buoy
/// packets), ranges its filter applied, and whether every state stayed finite.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct RunCounts {
    pub ranges_received: u64,
    pub ranges_applied: u64,
    pub healthy: bool,
}

impl RunCounts {
    /// AUV `auv`'s counts in `r`.
    pub fn of(r: &RunResult, auv: usize) -> Self {
        let a = &r.auvs[auv];
        RunCounts {
            ranges_received: a.downlink.received + a.buoy_link.received,
            ranges_applied: a.ranges_applied,
            healthy: r.fleet.healthy,
        }
    }
}

/// A zone Monte Carlo: every run's figures and counts, whether every run was healthy, and the
/// error profile against x_rel over all runs.
#[derive(Debug, Clone)]
pub struct ZoneRuns {
    pub runs: Vec<ZoneMetrics>,
    pub counts: Vec<RunCounts>,
    pub healthy: bool,
    pub profile: Vec<ProfileBin>,
}

/// A zone Monte Carlo's across-run statistics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ZoneSummary {
    pub zone_error: Stats,
    pub zone_parallel: Stats,
    pub zone_perpendicular: Stats,
    pub approach_perpendicular: Option<Stats>,
    pub buoy_error: Option<Stats>,
    pub saturation_error: Option<Stats>,
    /// Every run kept finite states (the engine's health).
    pub all_healthy: bool,
}

impl ZoneRuns {
    /// The statistics over runs seeded `run_seed(base_seed, i)`; an error names the first run
    /// that never reached the zone.
    pub fn summary(&self, base_seed: u64) -> Result<ZoneSummary, ZoneError> {
        if let Some(index) = self.runs.iter().position(|m| m.zone_error.is_none()) {
            return Err(ZoneError::NoZone { index, seed: run_seed(base_seed, index as u64) });
        }
        let of = |f: fn(&ZoneMetrics) -> Option<f64>| {
            let v: Vec<f64> = self.runs.iter().filter_map(f).collect();
            (!v.is_empty()).then(|| Stats::of(&v))
        };
        let every = |f: fn(&ZoneMetrics) -> Option<f64>| Stats::of(&self.runs.iter().filter_map(f).collect::<Vec<_>>());
        Ok(ZoneSummary {
            zone_error: every(|m| m.zone_error),
            zone_parallel: every(|m| m.zone_parallel),
            zone_perpendicular: every(|m| m.zone_perpendicular),
            approach_perpendicular: of(|m| m.approach_perpendicular),
            buoy_error: of(|m| m.buoy_error),
            saturation_error: of(|m| m.saturation_error),
            all_healthy: self.healthy,
        })
    }
}

/// Runs engine scenario `sc` (its CNA silent: policy `none`) with seeds `run_seed(base_seed, i)`
/// and scores it with [`GillZone::of_scenario`]. Runs go in parallel and are merged in index
/// order, so the result does not depend on the thread count.
pub fn zone_monte_carlo(sc: &Scenario, spec: ZoneSpec, runs: usize, base_seed: u64) -> Result<ZoneRuns, PolicyError> {
    zone_monte_carlo_with_progress(sc, spec, runs, base_seed, &|_| {})
}

/// [`zone_monte_carlo`] calling `progress` with the number of finished runs.
pub fn zone_monte_carlo_with_progress(
    sc: &Scenario,
    spec: ZoneSpec,
    runs: usize,
    base_seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<ZoneRuns, PolicyError> {
    let silent = PolicySpec::new("none", sc)?;
    let done = AtomicU64::new(0);
    let per_run: Vec<(ZoneMetrics, RunCounts, BinSums)> = (0..runs as u64)
        .into_par_iter()
        .map(|i| {
            let (zone, result) = zone_run(sc, &silent, run_seed(base_seed, i), GillZone::of_scenario(spec, sc))?;
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok((zone.metrics(), RunCounts::of(&result, zone.auv), zone.bins))
        })
        .collect::<Result<_, PolicyError>>()?;
    let healthy = per_run.iter().all(|r| r.1.healthy);
    let profile = merge_bins(per_run.iter().map(|r| r.2.clone()), spec.profile_bin_m);
    let (runs, counts) = per_run.into_iter().map(|r| (r.0, r.1)).unzip();
    Ok(ZoneRuns { runs, counts, healthy, profile })
}

/// One run of `sc` under `policy` with seed `seed`, scored by `observer` (a [`GillZone`] or an
/// observer that holds one).
pub fn zone_run<O: Observer>(
    sc: &Scenario,
    policy: &PolicySpec,
    seed: u64,
    mut observer: O,
) -> Result<(O, RunResult), PolicyError> {
    let mut policy = policy.build(sc)?;
    let result = run(sc, &mut policy, seed, &Faults::default(), &mut observer);
    Ok((observer, result))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::hbl::table5_scenario;
    use coopnav_nav::cycle::Configuration;

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
            cna_z: 0.0,
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

    #[test]
    fn a_scored_buoy_gives_its_filter_and_saturation_errors_and_the_run_stops_past_the_zone_when_asked() {
        // A 1 m × 1 m zone centred on (0, 0): 128 m to each side.
        let zone = Zone::centred(0.0, 0.0, 1.0, 1.0);
        let spec = ZoneSpec { stop_past_zone: true, ..ZoneSpec::table5() };
        let mut z = GillZone::new(spec, 0, 0).with_buoy(zone);
        // Inside the zone, estimate 3-4-5 m off; then 10 m north of the zone's edge, estimate exact.
        let at = |x: f64, y: f64, est: [f64; 2]| BuoySample { truth: Vec3::new(x, y, 1.0), estimates: vec![est] };
        z.on_buoys(0.0, &[at(0.0, 0.0, [3.0, 4.0])]);
        z.on_buoys(1.0, &[at(0.0, 138.0, [0.0, 138.0])]);
        let m = z.metrics();
        assert_eq!((m.buoy_error, m.saturation_error), (Some(2.5), Some(5.0)));
        let ship = Vec3::new(100.0, 0.0, 0.0);
        z.on_ships(0.0, &[ship]);
        z.on_sample(0.0, Vec3::new(0.0, 0.0, 0.0), &[row(150.0, 150.0, 0.0)]);
        assert!(!z.stop(), "x_rel 50 m is inside the zone");
        z.on_sample(0.0, Vec3::new(0.0, 0.0, 0.0), &[row(180.0, 180.0, 0.0)]);
        assert!(z.stop(), "x_rel 80 m is past it");
        // Unscored, a buoy changes nothing, and without the flag the run goes on.
        let mut plain = GillZone::new(ZoneSpec::table5(), 0, 0);
        plain.on_buoys(0.0, &[at(0.0, 138.0, [3.0, 4.0])]);
        plain.on_ships(0.0, &[ship]);
        plain.on_sample(0.0, Vec3::new(0.0, 0.0, 0.0), &[row(180.0, 180.0, 0.0)]);
        assert_eq!((plain.metrics().buoy_error, plain.metrics().saturation_error, plain.stop()), (None, None, false));
    }

    #[test]
    fn a_run_that_never_reached_the_zone_is_named_in_the_summary() {
        let reached = ZoneMetrics { zone_error: Some(1.0), zone_samples: 3, ..ZoneMetrics::default() };
        let runs = ZoneRuns {
            runs: vec![reached, ZoneMetrics::default()],
            counts: vec![RunCounts::default(); 2],
            healthy: true,
            profile: Vec::new(),
        };
        let err = runs.summary(7).unwrap_err().to_string();
        assert!(err.contains("run 1") && err.contains(&run_seed(7, 1).to_string()), "{err}");
        let ok = ZoneRuns { runs: vec![reached, reached], ..runs };
        assert_eq!(ok.summary(7).unwrap().zone_error.mean, 1.0);
    }

    #[test]
    fn a_zone_monte_carlo_is_identical_on_one_and_two_threads_and_scores_the_heard_buoy() {
        let sc = table5_scenario(Configuration::HblTwo).unwrap();
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| zone_monte_carlo(&sc, ZoneSpec::table5(), 4, 3).unwrap())
        };
        let (one, two) = (on(1), on(2));
        assert_eq!((&one.runs, one.healthy, &one.profile), (&two.runs, two.healthy, &two.profile));
        assert!(one.runs.iter().all(|m| m.zone_samples > 40 && m.buoy_error.is_some()), "{:?}", one.runs);
        // MSBL's cycle never has the buoy transmit: its filter and saturation are not scored.
        let msbl = table5_scenario(Configuration::Msbl).unwrap();
        let runs = zone_monte_carlo(&msbl, ZoneSpec::table5(), 2, 3).unwrap().runs;
        assert!(runs.iter().all(|m| m.buoy_error.is_none() && m.saturation_error.is_none()), "{runs:?}");
    }

    #[test]
    fn the_profile_shows_msbl_keeps_its_across_path_error_longer_than_hbl() {
        let profile = |c| zone_monte_carlo(&table5_scenario(c).unwrap(), ZoneSpec::table5(), 24, 7).unwrap().profile;
        let (msbl, hbl) = (profile(Configuration::Msbl), profile(Configuration::HblTwo));
        let at = |p: &[ProfileBin], x: f64| p.iter().find(|b| (b.x_rel - x).abs() < 1.0).copied().unwrap();
        // 50–75 m before the zone starts (x_rel −87.5 bin centre): HBL has corrected, MSBL not.
        assert!(at(&hbl, -87.5).perpendicular < 0.6 * at(&msbl, -87.5).perpendicular, "{hbl:?}\n{msbl:?}");
        for b in hbl.iter().chain(&msbl) {
            assert!(b.samples > 0 && b.error.is_finite() && b.error + 1e-12 >= b.parallel.max(b.perpendicular));
        }
    }
}
