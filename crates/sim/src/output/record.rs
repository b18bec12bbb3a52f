//! What `coopnav hbl simulate` keeps of one engine run of a Gill pass (Gill 2013, §2.4.1 and §3.3): the
//! zone metric ([`GillZone`]), one [`PassRow`] per second (AUV, ship and buoy truth and the AUV's
//! estimates of them, x_rel: what the plots and the MOOS export read), and the run as a
//! post-processing log (`coopnav_nav::post`): the AUV filter's start, its dead-reckoning readings
//! at every filter step, the ship's DGPS fix at the start and every truth step, each buoy GPS fix as broadcast,
//! and each decoded range from the ship's modems and the buoy.

use super::log_format::LogFormat;
use crate::engine::{
    BuoyFix, BuoySample, DeadReckoning, FilterStart, Observer, RangeHeard, ShipPose, ShipSample, TraceRow,
};
use crate::models::noise::normal;
use crate::models::schedule::Owner;
use crate::observe::metrics::RunResult;
use crate::observe::zone::{zone_run, GillZone, ZoneSpec};
use crate::policy::{PolicyError, PolicySpec};
use crate::scenario::Scenario;
use coopnav_core::{CompassDeg, Heading, SeedStream, Vec3};
use coopnav_nav::cycle::Transmitter;
use coopnav_nav::post::{Entry, Record};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum PassError {
    #[error("the scenario has no ship: a Gill pass is a survey AUV meeting ships[0]")]
    NoShip,
    #[error(transparent)]
    Policy(#[from] PolicyError),
}

/// Runs engine scenario `sc` (its CNA silent) with run seed `seed` and records the pass of survey
/// AUV 0 and ship 0 (and buoy 0, where the schedule has it transmit) in zone `spec`, the log
/// written as `format` says.
pub fn record_pass(
    sc: &Scenario,
    spec: ZoneSpec,
    format: LogFormat,
    seed: u64,
) -> Result<(PassRecorder, RunResult), PassError> {
    let ship = sc.ships.first().ok_or(PassError::NoShip)?;
    let recorder = PassRecorder::new(GillZone::of_scenario(spec, sc), spec, format, ship.sensors.gps_sd_m, seed);
    Ok(zone_run(sc, &PolicySpec::new("none", sc)?, seed, recorder)?)
}

/// The log's own noise stream (the ship fixes' DGPS error), apart from the engine's streams so
/// that recording never shifts the noise the filters see.
const LOG_STREAM: u64 = 90_001;

/// One second of a recorded pass (positions east, north in m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PassRow {
    pub t: f64,
    /// AUV − ship along the path (m; + = the AUV is past the ship).
    pub x_rel: f64,
    pub auv_true: [f64; 2],
    pub auv_est: [f64; 2],
    /// The AUV filter's 1-σ east and north, m.
    pub auv_sd: [f64; 2],
    pub ship_true: [f64; 2],
    /// Where the AUV's filter of the ship puts it.
    pub ship_est: [f64; 2],
    pub buoy_true: Option<[f64; 2]>,
    pub buoy_est: Option<[f64; 2]>,
    pub error: f64,
}

/// Records a pass of survey AUV and ship of `zone` (buoy 0 when there is one) as [`PassRow`]s
/// and log entries, and scores the zone.
pub struct PassRecorder {
    pub zone: GillZone,
    spec: ZoneSpec,
    format: LogFormat,
    /// σ of the logged ship fixes (the ship's GPS), m.
    ship_gps_sd: f64,
    rng: ChaCha8Rng,
    ship_now: Option<ShipSample>,
    buoy_now: Option<BuoySample>,
    /// Time of the AUV's previous filter step (its heading-rate reading covers the step from it).
    last_step_t: f64,
    pub rows: Vec<PassRow>,
    pub log: Vec<Entry>,
}

impl PassRecorder {
    /// For a run with seed `seed`: `zone` scores it, ship fixes are logged with σ `ship_gps_sd`.
    pub fn new(zone: GillZone, spec: ZoneSpec, format: LogFormat, ship_gps_sd: f64, seed: u64) -> Self {
        PassRecorder {
            zone,
            spec,
            format,
            ship_gps_sd,
            rng: SeedStream::new(seed).rng(LOG_STREAM),
            ship_now: None,
            buoy_now: None,
            last_step_t: 0.0,
            rows: Vec::new(),
            log: Vec::new(),
        }
    }

    /// The log in time order (ranges are reported when their packet ends, after later rows).
    pub fn sorted_log(&self) -> Vec<Entry> {
        let mut log = self.log.clone();
        log.sort_by(|a, b| a.t.total_cmp(&b.t));
        log
    }

    fn push(&mut self, t: f64, record: Record) {
        self.log.push(Entry { t, record });
    }

    fn row(&self, ship: &ShipSample, r: &TraceRow) -> PassRow {
        let (auv, _) = self.zone.vehicles();
        let est = |v: &[[f64; 2]]| v.get(auv).copied().unwrap_or([f64::NAN; 2]);
        // The buoy only where the schedule has it transmit (MSBL's file may still list one).
        let buoy = self.buoy_now.as_ref().filter(|_| self.zone.scores_buoy());
        PassRow {
            t: r.t,
            x_rel: self.spec.along(r.true_x - ship.truth.x, r.true_y - ship.truth.y),
            auv_true: [r.true_x, r.true_y],
            auv_est: [r.est_x, r.est_y],
            auv_sd: [r.p_ee.max(0.0).sqrt(), r.p_nn.max(0.0).sqrt()],
            ship_true: [ship.truth.x, ship.truth.y],
            ship_est: est(&ship.estimates),
            buoy_true: buoy.map(|b| [b.truth.x, b.truth.y]),
            buoy_est: buoy.map(|b| est(&b.estimates)),
            error: r.error,
        }
    }
}

impl Observer for PassRecorder {
    fn on_filter_start(&mut self, s: &FilterStart) {
        if s.auv == self.zone.vehicles().0 {
            let compass_deg = CompassDeg::from(Heading::from_radians(s.heading)).0;
            self.push(0.0, Record::Init { e: s.x, n: s.y, speed: s.speed, compass_deg });
        }
    }
    fn on_dead_reckoning(&mut self, dr: &DeadReckoning) {
        if dr.auv != self.zone.vehicles().0 {
            return;
        }
        // The log's heading rate is clockwise (compass), the filter's counter-clockwise.
        self.push(self.last_step_t, Record::YawRate { compass_deg_s: -dr.yaw_rate.to_degrees() });
        self.last_step_t = dr.t;
        self.push(dr.t, Record::Speed(dr.speed));
        self.push(dr.t, Record::Heading { compass_deg: CompassDeg::from(Heading::from_radians(dr.heading)).0 });
        self.push(dr.t, Record::Truth { e: dr.truth.x, n: dr.truth.y });
    }
    fn on_ship_pose(&mut self, p: &ShipPose) {
        if p.ship != self.zone.vehicles().1 {
            return;
        }
        let sd = self.ship_gps_sd;
        let fix = Record::ShipFix {
            e: p.pos.x + sd * normal(&mut self.rng),
            n: p.pos.y + sd * normal(&mut self.rng),
            compass_deg: CompassDeg::from(Heading::from_radians(p.heading)).0,
        };
        self.push(p.t, fix);
    }
    fn on_buoy_fix(&mut self, f: &BuoyFix) {
        if f.buoy == 0 {
            let (e, n) = self.format.stored_buoy_fix(f.fix.x, f.fix.y);
            self.push(f.t, Record::BuoyFix { e, n });
        }
    }
    fn on_range(&mut self, r: &RangeHeard) {
        let (auv, ship) = self.zone.vehicles();
        let src = match r.from {
            Owner::Ship(i, side) if i == ship => Transmitter::Ship(side),
            Owner::Buoy(0) => Transmitter::Buoy,
            // The log format knows one ship's two modems and one buoy.
            _ => return,
        };
        if r.auv == auv {
            // The AUV's clock reads the transmit time (top of the slot) plus the travel time.
            self.push(r.t_tx + r.travel_time, Record::Range { src, travel_time: r.travel_time });
        }
    }
    fn on_ships(&mut self, t: f64, ships: &[Vec3]) {
        self.zone.on_ships(t, ships);
    }
    fn on_ship_samples(&mut self, _t: f64, ships: &[ShipSample]) {
        self.ship_now = ships.get(self.zone.vehicles().1).cloned();
    }
    fn on_buoys(&mut self, t: f64, buoys: &[BuoySample]) {
        self.buoy_now = buoys.first().cloned();
        self.zone.on_buoys(t, buoys);
    }
    fn on_sample(&mut self, t: f64, cna: Vec3, rows: &[TraceRow]) {
        self.zone.on_sample(t, cna, rows);
        let auv = self.zone.vehicles().0;
        if let (Some(ship), Some(r)) = (&self.ship_now, rows.iter().find(|r| r.auv == auv)) {
            let row = self.row(ship, r);
            self.rows.push(row);
        }
    }
    fn stop(&self) -> bool {
        self.zone.stop()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::hbl::table5_scenario;
    use coopnav_nav::cycle::Configuration;

    #[test]
    fn the_log_holds_every_filter_step_and_every_range_the_auv_decoded() {
        let sc = table5_scenario(Configuration::HblTwo).unwrap();
        let (pass, result) = record_pass(&sc, ZoneSpec::table5(), LogFormat::default(), 5).unwrap();
        let count = |f: fn(&Record) -> bool| pass.log.iter().filter(|e| f(&e.record)).count();
        let steps = (sc.duration_s / sc.dt).round() as usize;
        assert_eq!(count(|r| matches!(r, Record::Init { .. })), 1);
        assert_eq!(count(|r| matches!(r, Record::Speed(_))), steps);
        assert_eq!(count(|r| matches!(r, Record::Heading { .. })), steps);
        assert_eq!(count(|r| matches!(r, Record::YawRate { .. })), steps);
        assert_eq!(count(|r| matches!(r, Record::Truth { .. })), steps);
        // A ship fix at the start, so the first range (sent at t = 0) has one.
        assert_eq!(count(|r| matches!(r, Record::ShipFix { .. })), steps + 1);
        // Gill's mixture always leaves a usable range: every decoded ship or buoy packet is logged.
        let a = &result.auvs[0];
        let ranges = count(|r| matches!(r, Record::Range { .. }));
        assert_eq!(ranges as u64, a.downlink.received + a.buoy_link.received);
        assert!(a.ranges_applied <= ranges as u64 && ranges > 20, "{ranges} ranges, {} applied", a.ranges_applied);
        let buoy_ranges = count(|r| matches!(r, Record::Range { src: Transmitter::Buoy, .. }));
        assert!(buoy_ranges > 0 && count(|r| matches!(r, Record::BuoyFix { .. })) >= buoy_ranges);
        // One row a second, whose truth is the logged truth at that time.
        assert_eq!(pass.rows.len(), sc.duration_s as usize);
        let row = pass.rows[9];
        let logged = pass.log.iter().find(|e| (e.t - row.t).abs() < 1e-9 && matches!(e.record, Record::Truth { .. }));
        assert_eq!(logged.map(|e| e.record), Some(Record::Truth { e: row.auv_true[0], n: row.auv_true[1] }));
        // Every range has its transponder's fix at most one step before its transmit time.
        for e in &pass.log {
            let Record::Range { src, travel_time } = e.record else { continue };
            let t_tx = e.t - travel_time;
            let fixed = pass.log.iter().any(|f| {
                let kind = match (src, f.record) {
                    (Transmitter::Ship(_), Record::ShipFix { .. }) | (Transmitter::Buoy, Record::BuoyFix { .. }) => {
                        true
                    }
                    _ => false,
                };
                kind && f.t <= t_tx + 1e-9 && f.t >= t_tx - sc.dt - 1e-9
            });
            assert!(fixed, "the range at {} s ({src:?}) has no fix at its transmit time {t_tx} s", e.t);
        }
        let sorted = pass.sorted_log();
        assert!(sorted.windows(2).all(|w| w[0].t <= w[1].t) && sorted.len() == pass.log.len());
    }
}
