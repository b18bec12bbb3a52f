//! One HBL run (digest §5): truth unicycles for the AUV (steering on its *estimated* state) and
//! the ship, the buoy's drift, the sensors, the slot-by-slot acoustic cycle with top-of-second
//! OWTT timing, and the three onboard filters (AUV, ship, buoy) in the order of digest §3.4.
//! Returns the zone metric and, on request, a trace and a post-processing log.

use super::config::{Scenario, TransponderTime};
use super::noise::{draw_reception, normal, stream, BuoyMotion, CompassBias, Reception};
use crate::models::minipacket::quantised;
use coopnav_core::{wrap_pi, CompassDeg, Heading, SeedStream, Vec3};
use coopnav_nav::codec::Zone;
use coopnav_nav::cycle::{Cycle, Transmitter, Vehicle};
use coopnav_nav::ekf::is_positive_definite;
use coopnav_nav::post::{Entry, Record};
use coopnav_nav::{AuvEkf, RangeMeasurement, StateKind, SurfaceEkf};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::f64::consts::{FRAC_PI_2, PI};

/// Per-run results.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct RunMetrics {
    /// Mean AUV position error while −30 ≤ x_rel ≤ 75 (None if the AUV never got there).
    pub zone_error: Option<f64>,
    /// Mean |along-path| and |across-path| error components in the zone.
    pub zone_parallel: Option<f64>,
    pub zone_perpendicular: Option<f64>,
    pub zone_samples: usize,
    /// Mean |across-path| error in the approach window before the zone (None if never there).
    pub approach_perpendicular: Option<f64>,
    /// Mean buoy-filter position error over the whole mission.
    pub buoy_error: Option<f64>,
    /// Mean distance from the true buoy to its clamp into the broadcast zone, over buoy slots.
    pub saturation_error: Option<f64>,
    pub ranges_received: u64,
    pub ranges_applied: u64,
    pub filter_predicts: u64,
    pub filter_updates: u64,
    /// Every state finite and every covariance positive definite at every step.
    pub healthy: bool,
}

/// One step of a recorded run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TraceRow {
    pub t: f64,
    pub x_rel: f64,
    pub auv_true: [f64; 2],
    pub auv_est: [f64; 2],
    pub auv_sd: [f64; 2],
    /// True and estimated math heading, estimated compass bias, estimated speed (rad, m/s).
    pub heading: [f64; 2],
    pub bias_est: f64,
    pub speed_est: f64,
    pub ship_true: [f64; 2],
    pub ship_est: [f64; 2],
    pub buoy_true: Option<[f64; 2]>,
    pub buoy_est: Option<[f64; 2]>,
    pub error: f64,
}

#[derive(Debug, Clone, Default)]
pub struct Trace {
    pub rows: Vec<TraceRow>,
    /// The run as a post-processing log (see `coopnav_nav::post`).
    pub log: Vec<Entry>,
}

#[derive(Debug, Clone, Copy)]
struct Unicycle {
    x: f64,
    y: f64,
    psi: f64,
    speed: f64,
}

impl Unicycle {
    fn step(&mut self, rate: f64, dt: f64) {
        self.psi = wrap_pi(self.psi + rate * dt);
        self.x += dt * self.speed * self.psi.cos();
        self.y += dt * self.speed * self.psi.sin();
    }
    fn lerp(a: &Unicycle, b: &Unicycle, f: f64) -> [f64; 2] {
        [a.x + f * (b.x - a.x), a.y + f * (b.y - a.y)]
    }
}

/// Look-ahead path controller (MOOS-style virtual waypoint, digest §5.2): heading-rate command
/// towards the point `lookahead` ahead on the line y = path_y, travelling in `dir` (±1 along x).
fn steer(y: f64, psi: f64, path_y: f64, dir: f64, sc: &Scenario, max_rate: f64) -> f64 {
    let desired = (path_y - y).atan2(dir * sc.control.lookahead_m);
    (sc.control.heading_gain * wrap_pi(desired - psi)).clamp(-max_rate, max_rate)
}

/// An acoustic message in flight.
#[derive(Debug, Clone, Copy)]
struct Flight {
    t_tx: f64,
    t_rx: f64,
    from: Transmitter,
    kind: StateKind,
    /// Decoded broadcast value (E, N, speed in SI; heading in math radians).
    value: f64,
    /// Measured travel time on the AUV clock.
    travel_time: f64,
}

struct Filters {
    auv: AuvEkf,
    ship: SurfaceEkf,
    buoy: Option<SurfaceEkf>,
}

impl Filters {
    fn healthy(&self) -> bool {
        let ok4 = |f: &SurfaceEkf| f.state().iter().all(|v| v.is_finite()) && is_positive_definite(f.ekf().p());
        self.auv.state().iter().all(|v| v.is_finite())
            && is_positive_definite(self.auv.ekf().p())
            && ok4(&self.ship)
            && self.buoy.as_ref().map_or(true, ok4)
    }
    fn counts(&self) -> (u64, u64) {
        let mut c = [self.auv.ekf().counts(), self.ship.ekf().counts()].to_vec();
        if let Some(b) = &self.buoy {
            c.push(b.ekf().counts());
        }
        c.iter().fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
    }
}

/// The random streams a run draws from after initialisation.
struct Streams {
    speed: ChaCha8Rng,
    compass_white: ChaCha8Rng,
    yaw_rate: ChaCha8Rng,
    slots: ChaCha8Rng,
    log: ChaCha8Rng,
}

/// Running sums for the metrics.
#[derive(Default)]
struct Sums {
    zone: f64,
    parallel: f64,
    perpendicular: f64,
    approach_perpendicular: f64,
    approach_n: usize,
    buoy: f64,
    buoy_n: usize,
    saturation: f64,
    saturation_n: usize,
}

/// The whole state of one run between steps.
struct World<'a> {
    sc: &'a Scenario,
    cycle: &'a Cycle,
    assignment: Vec<Option<Transmitter>>,
    ship_zone: Zone,
    buoy_zone: Zone,
    compass: CompassBias,
    buoy_motion: BuoyMotion,
    clock_rate: f64,
    rng: Streams,
    auv: Unicycle,
    ship: Unicycle,
    f: Filters,
    in_flight: Vec<Flight>,
    slot: u64,
    sums: Sums,
    metrics: RunMetrics,
    trace: Option<Trace>,
}

/// Truth of the step being simulated: the vehicles at its start and end.
struct StepTruth {
    t: f64,
    auv_prev: Unicycle,
    ship_prev: Unicycle,
}

impl<'a> World<'a> {
    fn new(sc: &'a Scenario, cycle: &'a Cycle, seed: u64, record: bool) -> Self {
        let streams = SeedStream::new(seed);
        let rng = |id| streams.rng(id);
        let g = &sc.geometry;
        let init = &sc.init;
        let scatter = |id: u64, x: f64, psi: f64, speed: f64| {
            let mut r = rng(id);
            Unicycle {
                x: x + init.position_sd * normal(&mut r),
                y: g.path_y + init.position_sd * normal(&mut r),
                speed: speed + init.speed_sd * normal(&mut r),
                psi: wrap_pi(psi + init.heading_sd_rad * normal(&mut r)),
            }
        };
        let mut r_buoy = rng(stream::BUOY);
        let buoy_motion = BuoyMotion::draw(&sc.buoy, &mut r_buoy);
        let b0 = buoy_motion.at(0.0);
        let buoy_init = [b0[0] + sc.buoy.init_sd * normal(&mut r_buoy), b0[1] + sc.buoy.init_sd * normal(&mut r_buoy)];
        let clock_rate = {
            let a = &sc.acoustic;
            let rate =
                (a.clock_drift_mean_us_h + a.clock_drift_sd_us_h * normal(&mut rng(stream::CLOCK))) * 1e-6 / 3600.0;
            if a.clock_drift {
                rate
            } else {
                0.0
            }
        };
        let f = Filters {
            auv: AuvEkf::new(0.0, g.auv_start_x, g.path_y, g.auv_speed, 0.0, sc.filters.auv.clone()),
            ship: SurfaceEkf::new(0.0, g.ship_start_x, g.path_y, g.ship_speed, PI, sc.filters.ship.clone()),
            buoy: sc
                .configuration
                .has_buoy()
                .then(|| SurfaceEkf::new(0.0, buoy_init[0], buoy_init[1], 0.0, FRAC_PI_2, sc.filters.buoy.clone())),
        };
        let mut w = World {
            sc,
            cycle,
            assignment: sc.configuration.assign(cycle),
            ship_zone: sc.quantisation.ship_zone(),
            buoy_zone: sc.quantisation.buoy_zone(),
            compass: CompassBias::draw(
                sc.sensors.compass_bias_step_deg,
                sc.sensors.compass_bias_iid,
                &mut rng(stream::COMPASS_MAP),
            ),
            buoy_motion,
            clock_rate,
            rng: Streams {
                speed: rng(stream::SPEED),
                compass_white: rng(stream::COMPASS_WHITE),
                yaw_rate: rng(stream::YAW_RATE),
                slots: rng(stream::SLOTS),
                log: rng(stream::LOG),
            },
            auv: scatter(stream::AUV_INIT, g.auv_start_x, 0.0, g.auv_speed),
            ship: scatter(stream::SHIP_INIT, g.ship_start_x, PI, g.ship_speed),
            f,
            in_flight: Vec::new(),
            slot: 0,
            sums: Sums::default(),
            metrics: RunMetrics { healthy: true, ..RunMetrics::default() },
            trace: record.then(Trace::default),
        };
        w.log(0.0, Record::Init { e: g.auv_start_x, n: g.path_y, speed: g.auv_speed, compass_deg: 90.0 });
        w.log_ship_fix(0.0);
        w
    }

    fn log(&mut self, t: f64, record: Record) {
        if let Some(tr) = self.trace.as_mut() {
            tr.log.push(Entry { t, record });
        }
    }

    /// Advances one step k → k+1; false when the run is over.
    fn step(&mut self, k: u64) -> bool {
        let (sc, g) = (self.sc, &self.sc.geometry);
        let (t, t_next) = (k as f64 * sc.dt, (k + 1) as f64 * sc.dt);
        if t_next > sc.max_duration_s {
            return false;
        }
        // The AUV steers on its estimate; the ship's pilot sees the truth.
        let (est, est_psi) = (self.f.auv.position(), self.f.auv.state()[3]);
        let auv_rate = steer(est.1, est_psi, g.path_y, 1.0, sc, sc.control.auv_max_rate_deg_s.to_radians());
        let ship_rate =
            steer(self.ship.y, self.ship.psi, g.path_y, -1.0, sc, sc.control.ship_max_rate_deg_s.to_radians());
        let measured_rate = auv_rate + sc.sensors.yaw_rate_white_deg_s.to_radians() * normal(&mut self.rng.yaw_rate);
        self.log(t, Record::YawRate { compass_deg_s: -measured_rate.to_degrees() });
        let truth = StepTruth { t, auv_prev: self.auv, ship_prev: self.ship };
        self.auv.step(auv_rate, sc.dt);
        self.ship.step(ship_rate, sc.dt);
        while self.cycle.slot(self.slot).1 < t_next - 1e-9 {
            self.transmit(&truth);
        }
        self.receive_due(t_next, measured_rate);
        self.sense(t_next, measured_rate);
        let x_rel = self.score(t_next);
        x_rel <= g.zone_max + g.end_margin
    }

    /// The slot's broadcast: draws its fate and noise (always, for common random numbers),
    /// quantises the state, and puts a received message in flight.
    fn transmit(&mut self, truth: &StepTruth) {
        let sc = self.sc;
        let (content, t_tx) = self.cycle.slot(self.slot);
        let idx = (self.slot % self.cycle.slots.len() as u64) as usize;
        self.slot += 1;
        let fate = draw_reception(&sc.acoustic, &mut self.rng.slots);
        let noise: [f64; 4] = std::array::from_fn(|_| normal(&mut self.rng.slots));
        let (Some(from), Some((vehicle, kind))) = (self.assignment[idx], content.state()) else { return };
        let frac = ((t_tx - truth.t) / sc.dt).clamp(0.0, 1.0);
        let (pos, speed, psi, zone, bias) = match vehicle {
            Vehicle::Ship => (
                Unicycle::lerp(&truth.ship_prev, &self.ship, frac),
                self.ship.speed,
                self.ship.psi,
                self.ship_zone,
                [0.0, 0.0],
            ),
            Vehicle::Buoy => (self.buoy_motion.at(t_tx), 0.0, 0.0, self.buoy_zone, sc.buoy.broadcast_bias),
        };
        let transponder = match from {
            Transmitter::Ship(side) => sc.filters.outriggers.position(side, pos[0], pos[1], psi),
            Transmitter::Buoy => Vec3::new(pos[0], pos[1], 0.0),
        };
        if vehicle == Vehicle::Buoy {
            self.sums.saturation += zone.saturation_error(pos[0], pos[1]);
            self.sums.saturation_n += 1;
            let topside = (pos[0] + 0.1 * normal(&mut self.rng.log), pos[1] + 0.1 * normal(&mut self.rng.log));
            let (e, n) = sc.log.stored_buoy_fix(topside.0, topside.1);
            self.log(t_tx, Record::BuoyFix { e, n });
        }
        let dgps = sc.sensors.dgps_sd;
        let measured = [pos[0] + dgps * noise[0] + bias[0], pos[1] + dgps * noise[1] + bias[1]];
        let value = quantised(
            kind,
            measured,
            speed + sc.sensors.ship_speed_sd * noise[2],
            psi + sc.sensors.ship_heading_sd_deg.to_radians() * noise[3],
            &zone,
        );
        let Reception::Received(range_error) = fate else { return };
        // OWTT: the AUV moves during the ~0.1 s flight; one fixed-point iteration suffices.
        let start = Unicycle::lerp(&truth.auv_prev, &self.auv, frac);
        let (vx, vy) = (self.auv.speed * self.auv.psi.cos(), self.auv.speed * self.auv.psi.sin());
        let c = sc.acoustic.sound_speed;
        let dist = |h: f64| (start[0] + h * vx - transponder.x).hypot(start[1] + h * vy - transponder.y);
        let tau = dist(dist(0.0) / c) / c;
        let t_rx = t_tx + tau;
        let travel_time = tau + range_error / c + self.clock_rate * t_rx;
        self.in_flight.push(Flight { t_tx, t_rx, from, kind, value, travel_time });
    }

    /// Messages arriving by `t_next`, in time order: surface filter first, then the range.
    fn receive_due(&mut self, t_next: f64, measured_rate: f64) {
        let sc = self.sc;
        self.in_flight.sort_by(|a, b| a.t_rx.total_cmp(&b.t_rx));
        let due = self.in_flight.partition_point(|fl| fl.t_rx <= t_next);
        let arrived: Vec<Flight> = self.in_flight.drain(..due).collect();
        let c_filter = sc.acoustic.sound_speed + sc.acoustic.filter_sound_speed_bias;
        for fl in arrived {
            self.f.auv.predict_to(fl.t_rx, measured_rate);
            let surface = match fl.from {
                Transmitter::Ship(_) => Some(&mut self.f.ship),
                Transmitter::Buoy => self.f.buoy.as_mut(),
            };
            let Some(surface) = surface else { continue };
            surface.predict_to(fl.t_tx);
            surface.update(fl.kind, fl.value);
            let mut at = surface.clone();
            if sc.acoustic.transponder_time == TransponderTime::Receive {
                at.predict_to(fl.t_rx);
            }
            let s = at.state();
            let transponder = match fl.from {
                Transmitter::Ship(side) => sc.filters.outriggers.position(side, s[0], s[1], s[3]),
                Transmitter::Buoy => Vec3::new(s[0], s[1], 0.0),
            };
            let meas = RangeMeasurement { range: c_filter * fl.travel_time, travel_time: fl.travel_time, transponder };
            self.metrics.ranges_received += 1;
            if self.f.auv.update_range(&meas, None).applied() {
                self.metrics.ranges_applied += 1;
            }
            // The AUV's clock reads the top of the second plus the measured travel time.
            self.log(fl.t_tx + fl.travel_time, Record::Range { src: fl.from, travel_time: fl.travel_time });
        }
    }

    /// Dead reckoning to the end of the step, then the speed and compass updates.
    fn sense(&mut self, t_next: f64, measured_rate: f64) {
        let s = &self.sc.sensors;
        self.f.auv.predict_to(t_next, measured_rate);
        let speed = self.auv.speed + s.speed_sd * normal(&mut self.rng.speed);
        let white = s.compass_white_deg.to_radians() * normal(&mut self.rng.compass_white);
        let heading = wrap_pi(self.auv.psi + self.compass.at(self.auv.psi) + white);
        self.f.auv.update_speed(speed);
        self.f.auv.update_heading(heading);
        self.log(t_next, Record::Speed(speed));
        self.log(t_next, Record::Heading { compass_deg: CompassDeg::from(Heading::from_radians(heading)).0 });
        self.log(t_next, Record::Truth { e: self.auv.x, n: self.auv.y });
        self.log_ship_fix(t_next);
    }

    /// The ship's pre-quantisation DGPS fix, for post-processing (its own stream: logging
    /// never shifts the noise the filters see).
    fn log_ship_fix(&mut self, t: f64) {
        if self.trace.is_none() {
            return;
        }
        let dgps = self.sc.sensors.dgps_sd;
        let fix = Record::ShipFix {
            e: self.ship.x + dgps * normal(&mut self.rng.log),
            n: self.ship.y + dgps * normal(&mut self.rng.log),
            compass_deg: CompassDeg::from(Heading::from_radians(self.ship.psi)).0,
        };
        self.log(t, fix);
    }

    /// Accumulates the metrics at the end of a step; returns x_rel.
    fn score(&mut self, t_next: f64) -> f64 {
        let g = &self.sc.geometry;
        self.metrics.healthy &= self.f.healthy();
        let est = self.f.auv.position();
        let (de, dn) = (est.0 - self.auv.x, est.1 - self.auv.y);
        let error = de.hypot(dn);
        let x_rel = self.auv.x - self.ship.x;
        if (g.zone_min..=g.zone_max).contains(&x_rel) {
            self.sums.zone += error;
            self.sums.parallel += de.abs();
            self.sums.perpendicular += dn.abs();
            self.metrics.zone_samples += 1;
        } else if (g.zone_min - g.approach_m..g.zone_min).contains(&x_rel) {
            self.sums.approach_perpendicular += dn.abs();
            self.sums.approach_n += 1;
        }
        let buoy_true = self.buoy_motion.at(t_next);
        let buoy_est = self.f.buoy.as_ref().map(|b| b.position_at(t_next));
        if let Some(b) = buoy_est {
            self.sums.buoy += (b[0] - buoy_true[0]).hypot(b[1] - buoy_true[1]);
            self.sums.buoy_n += 1;
        }
        if let Some(tr) = self.trace.as_mut() {
            let p = self.f.auv.ekf().p();
            let x = self.f.auv.state();
            tr.rows.push(TraceRow {
                t: t_next,
                x_rel,
                auv_true: [self.auv.x, self.auv.y],
                auv_est: [est.0, est.1],
                auv_sd: [p[(0, 0)].sqrt(), p[(1, 1)].sqrt()],
                heading: [self.auv.psi, x[3]],
                bias_est: x[4],
                speed_est: x[2],
                ship_true: [self.ship.x, self.ship.y],
                ship_est: self.f.ship.position_at(t_next),
                buoy_true: buoy_est.map(|_| buoy_true),
                buoy_est,
                error,
            });
        }
        x_rel
    }

    fn finish(mut self) -> (RunMetrics, Option<Trace>) {
        let (m, s) = (&mut self.metrics, &self.sums);
        let n = m.zone_samples as f64;
        if m.zone_samples > 0 {
            m.zone_error = Some(s.zone / n);
            m.zone_parallel = Some(s.parallel / n);
            m.zone_perpendicular = Some(s.perpendicular / n);
        }
        m.approach_perpendicular = (s.approach_n > 0).then(|| s.approach_perpendicular / s.approach_n as f64);
        m.buoy_error = (s.buoy_n > 0).then(|| s.buoy / s.buoy_n as f64);
        m.saturation_error = (s.saturation_n > 0).then(|| s.saturation / s.saturation_n as f64);
        (m.filter_predicts, m.filter_updates) = self.f.counts();
        (self.metrics, self.trace)
    }
}

/// Runs one simulation with run seed `seed`. `record` keeps a trace and a post-processing log.
pub fn run(sc: &Scenario, cycle: &Cycle, seed: u64, record: bool) -> (RunMetrics, Option<Trace>) {
    let mut world = World::new(sc, cycle, seed, record);
    let mut k = 0;
    while world.step(k) {
        k += 1;
    }
    world.finish()
}
