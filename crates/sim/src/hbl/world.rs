//! One HBL run (digest §5): truth unicycles for the AUV (steering on its *estimated* state) and
//! the ship, the buoy's drift, the sensors, the slot-by-slot acoustic cycle with top-of-second
//! OWTT timing, and the three onboard filters (AUV, ship, buoy) in the order of digest §3.4.
//! Returns the zone metric and, on request, a trace and a post-processing log.

use super::config::{Scenario, TransponderTime};
use super::noise::{draw_reception, normal, stream, BuoyMotion, CompassBias, Reception};
use coopnav_core::{wrap_pi, CompassDeg, Heading, SeedStream, Vec3};
use coopnav_nav::codec::{decode_heading_deg, encode_heading_deg, Zone, SPEED_AXIS};
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

/// Broadcast of `kind` by a vehicle: quantised, then decoded to the box centre as the AUV sees it.
fn broadcast(kind: StateKind, pos: [f64; 2], speed: f64, psi: f64, zone: &Zone) -> f64 {
    match kind {
        StateKind::East => zone.east.decode(zone.east.encode(pos[0]).index),
        StateKind::North => zone.north.decode(zone.north.encode(pos[1]).index),
        StateKind::Speed => SPEED_AXIS.decode(SPEED_AXIS.encode(speed).index),
        StateKind::Heading => {
            let compass = CompassDeg::from(Heading::from_radians(psi)).0;
            Heading::from(CompassDeg(decode_heading_deg(encode_heading_deg(compass)))).radians()
        }
    }
}

/// Runs one simulation with run seed `seed`. `record` keeps a trace and a post-processing log.
pub fn run(sc: &Scenario, cycle: &Cycle, seed: u64, record: bool) -> (RunMetrics, Option<Trace>) {
    let streams = SeedStream::new(seed);
    let rng = |id| streams.rng(id);
    let (mut r_auv0, mut r_ship0, mut r_buoy) = (rng(stream::AUV_INIT), rng(stream::SHIP_INIT), rng(stream::BUOY));
    let (mut r_speed, mut r_white, mut r_rate) = (rng(stream::SPEED), rng(stream::COMPASS_WHITE), rng(stream::YAW_RATE));
    let (mut r_slot, mut r_log) = (rng(stream::SLOTS), rng(stream::LOG));
    let compass = CompassBias::draw(&sc.sensors, &mut rng(stream::COMPASS_MAP));
    let clock_rate = {
        let mut r = rng(stream::CLOCK);
        let a = &sc.acoustic;
        let rate = (a.clock_drift_mean_us_h + a.clock_drift_sd_us_h * normal(&mut r)) * 1e-6 / 3600.0;
        if a.clock_drift {
            rate
        } else {
            0.0
        }
    };
    let g = &sc.geometry;
    let init = &sc.init;
    let scatter = |r: &mut ChaCha8Rng, x: f64, psi: f64, speed: f64| Unicycle {
        x: x + init.position_sd * normal(r),
        y: g.path_y + init.position_sd * normal(r),
        speed: speed + init.speed_sd * normal(r),
        psi: wrap_pi(psi + init.heading_sd_rad * normal(r)),
    };
    let mut auv = scatter(&mut r_auv0, g.auv_start_x, 0.0, g.auv_speed);
    let mut ship = scatter(&mut r_ship0, g.ship_start_x, PI, g.ship_speed);
    let buoy_motion = BuoyMotion::draw(&sc.buoy, &mut r_buoy);
    let b0 = buoy_motion.at(0.0);
    let buoy_init = [b0[0] + sc.buoy.init_sd * normal(&mut r_buoy), b0[1] + sc.buoy.init_sd * normal(&mut r_buoy)];
    let has_buoy = sc.configuration.has_buoy();
    let mut f = Filters {
        auv: AuvEkf::new(0.0, g.auv_start_x, g.path_y, g.auv_speed, 0.0, sc.filters.auv.clone()),
        ship: SurfaceEkf::new(0.0, g.ship_start_x, g.path_y, g.ship_speed, PI, sc.filters.ship.clone()),
        buoy: has_buoy.then(|| SurfaceEkf::new(0.0, buoy_init[0], buoy_init[1], 0.0, FRAC_PI_2, sc.filters.buoy.clone())),
    };
    let assignment = sc.configuration.assign(cycle);
    let (ship_zone, buoy_zone) = (sc.quantisation.ship_zone(), sc.quantisation.buoy_zone());
    let c_true = sc.acoustic.sound_speed;
    let c_filter = c_true + sc.acoustic.filter_sound_speed_bias;
    let (auv_max, ship_max) = (sc.control.auv_max_rate_deg_s.to_radians(), sc.control.ship_max_rate_deg_s.to_radians());

    let mut m = RunMetrics { healthy: true, ..RunMetrics::default() };
    let mut trace = record.then(Trace::default);
    let mut log = |t: f64, record: Record| {
        if let Some(tr) = trace.as_mut() {
            tr.log.push(Entry { t, record });
        }
    };
    log(0.0, Record::Init { e: g.auv_start_x, n: g.path_y, speed: g.auv_speed, compass_deg: 90.0 });
    let mut rows = Vec::new();
    let (mut zone_sum, mut par_sum, mut perp_sum) = (0.0, 0.0, 0.0);
    let (mut buoy_sum, mut buoy_n, mut sat_sum, mut sat_n) = (0.0, 0usize, 0.0, 0usize);
    let mut in_flight: Vec<Flight> = Vec::new();
    let mut slot = 0u64;
    let mut k = 0u64;
    loop {
        let t = k as f64 * sc.dt;
        let t_next = (k + 1) as f64 * sc.dt;
        if t_next > sc.max_duration_s {
            break;
        }
        let (est_psi, est) = (f.auv.state()[3], f.auv.position());
        let auv_rate = steer(est.1, est_psi, g.path_y, 1.0, sc, auv_max);
        let ship_rate = steer(ship.y, ship.psi, g.path_y, -1.0, sc, ship_max);
        let measured_rate = auv_rate + sc.sensors.yaw_rate_white_deg_s.to_radians() * normal(&mut r_rate);
        log(t, Record::YawRate { compass_deg_s: -measured_rate.to_degrees() });
        let (auv_prev, ship_prev) = (auv, ship);
        auv.step(auv_rate, sc.dt);
        ship.step(ship_rate, sc.dt);

        // Transmissions at the top of each slot within [t, t_next).
        while cycle.slot(slot).1 < t_next - 1e-9 {
            let (content, t_tx) = cycle.slot(slot);
            slot += 1;
            let fate = draw_reception(&sc.acoustic, &mut r_slot);
            let noise: [f64; 4] = std::array::from_fn(|_| normal(&mut r_slot));
            let idx = ((slot - 1) % cycle.slots.len() as u64) as usize;
            let (Some(from), Some((vehicle, kind))) = (assignment[idx], content.state()) else { continue };
            let frac = ((t_tx - t) / sc.dt).clamp(0.0, 1.0);
            let (pos_true, speed, psi, zone) = match vehicle {
                Vehicle::Ship => (Unicycle::lerp(&ship_prev, &ship, frac), ship.speed, ship.psi, &ship_zone),
                Vehicle::Buoy => (buoy_motion.at(t_tx), 0.0, 0.0, &buoy_zone),
            };
            let transponder = match from {
                Transmitter::Ship(side) => sc.filters.outriggers.position(side, pos_true[0], pos_true[1], psi),
                Transmitter::Buoy => Vec3::new(pos_true[0], pos_true[1], 0.0),
            };
            let bias = if vehicle == Vehicle::Buoy { sc.buoy.broadcast_bias } else { [0.0, 0.0] };
            let measured = [pos_true[0] + sc.sensors.dgps_sd * noise[0] + bias[0], pos_true[1] + sc.sensors.dgps_sd * noise[1] + bias[1]];
            if vehicle == Vehicle::Buoy {
                sat_sum += zone.saturation_error(pos_true[0], pos_true[1]);
                sat_n += 1;
                log(t_tx, Record::BuoyFix { e: pos_true[0] + 0.1 * normal(&mut r_log), n: pos_true[1] + 0.1 * normal(&mut r_log) });
            }
            let value = broadcast(
                kind,
                measured,
                speed + sc.sensors.ship_speed_sd * noise[2],
                psi + sc.sensors.ship_heading_sd_deg.to_radians() * noise[3],
                zone,
            );
            let Reception::Received(range_error) = fate else { continue };
            // OWTT: the AUV moves during the ~0.1 s flight; one fixed-point iteration suffices.
            let auv_at = |dt_f: f64| {
                let p = Unicycle::lerp(&auv_prev, &auv, frac);
                [p[0] + dt_f * auv.speed * auv.psi.cos(), p[1] + dt_f * auv.speed * auv.psi.sin()]
            };
            let dist = |p: [f64; 2]| (p[0] - transponder.x).hypot(p[1] - transponder.y);
            let tau0 = dist(auv_at(0.0)) / c_true;
            let tau = dist(auv_at(tau0)) / c_true;
            let t_rx = t_tx + tau;
            let travel_time = tau + range_error / c_true + clock_rate * t_rx;
            in_flight.push(Flight { t_tx, t_rx, from, kind, value, travel_time });
        }

        // Receptions up to t_next, in time order: surface filter first, then the range.
        in_flight.sort_by(|a, b| a.t_rx.total_cmp(&b.t_rx));
        let due = in_flight.partition_point(|fl| fl.t_rx <= t_next);
        for fl in in_flight.drain(..due).collect::<Vec<_>>() {
            f.auv.predict_to(fl.t_rx, measured_rate);
            let surface = match fl.from {
                Transmitter::Ship(_) => Some(&mut f.ship),
                Transmitter::Buoy => f.buoy.as_mut(),
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
            m.ranges_received += 1;
            if f.auv.update_range(&meas, None).applied() {
                m.ranges_applied += 1;
            }
            log(fl.t_rx, Record::Range { src: fl.from, travel_time: fl.travel_time });
        }

        f.auv.predict_to(t_next, measured_rate);
        let speed_meas = auv.speed + sc.sensors.speed_sd * normal(&mut r_speed);
        let heading_meas = wrap_pi(auv.psi + compass.at(auv.psi) + sc.sensors.compass_white_deg.to_radians() * normal(&mut r_white));
        f.auv.update_speed(speed_meas);
        f.auv.update_heading(heading_meas);
        log(t_next, Record::Speed(speed_meas));
        log(t_next, Record::Heading { compass_deg: CompassDeg::from(Heading::from_radians(heading_meas)).0 });
        log(t_next, Record::Truth { e: auv.x, n: auv.y });
        log(t_next, Record::ShipFix {
            e: ship.x + sc.sensors.dgps_sd * normal(&mut r_log),
            n: ship.y + sc.sensors.dgps_sd * normal(&mut r_log),
            compass_deg: CompassDeg::from(Heading::from_radians(ship.psi)).0,
        });

        m.healthy &= f.healthy();
        let est = f.auv.position();
        let (de, dn) = (est.0 - auv.x, est.1 - auv.y);
        let error = de.hypot(dn);
        let x_rel = auv.x - ship.x;
        if (g.zone_min..=g.zone_max).contains(&x_rel) {
            zone_sum += error;
            par_sum += de.abs();
            perp_sum += dn.abs();
            m.zone_samples += 1;
        }
        let buoy_true = buoy_motion.at(t_next);
        let buoy_est = f.buoy.as_ref().map(|b| b.position_at(t_next));
        if let Some(b) = buoy_est {
            buoy_sum += (b[0] - buoy_true[0]).hypot(b[1] - buoy_true[1]);
            buoy_n += 1;
        }
        if record {
            let p = f.auv.ekf().p();
            rows.push(TraceRow {
                t: t_next,
                x_rel,
                auv_true: [auv.x, auv.y],
                auv_est: [est.0, est.1],
                auv_sd: [p[(0, 0)].sqrt(), p[(1, 1)].sqrt()],
                ship_true: [ship.x, ship.y],
                ship_est: f.ship.position_at(t_next),
                buoy_true: has_buoy.then_some(buoy_true),
                buoy_est,
                error,
            });
        }
        k += 1;
        if x_rel > g.zone_max + g.end_margin {
            break;
        }
    }
    let n = m.zone_samples as f64;
    if m.zone_samples > 0 {
        m.zone_error = Some(zone_sum / n);
        m.zone_parallel = Some(par_sum / n);
        m.zone_perpendicular = Some(perp_sum / n);
    }
    m.buoy_error = (buoy_n > 0).then(|| buoy_sum / buoy_n as f64);
    m.saturation_error = (sat_n > 0).then(|| sat_sum / sat_n as f64);
    (m.filter_predicts, m.filter_updates) = f.counts();
    if let Some(tr) = trace.as_mut() {
        tr.rows = rows;
    }
    (m, trace)
}
