//! The engine's vehicles: a survey AUV (its controller steering on its own estimate, its truth,
//! its filter, its sensors' noise streams and its modem's state), the CNA craft, the
//! transponder buoys (their drift, GPS and clock) and the ships on a fixed track (their pilot,
//! broadcast sensors and clock).

use crate::models::buoy::BuoySpec;
use crate::models::channel::Clock;
use crate::models::filter::Adcp;
use crate::models::finish::Action;
use crate::models::minipacket;
use crate::models::noise::{normal, BuoyMotion, CompassBias};
use crate::models::ship::ShipSpec;
use crate::scenario::start::{auv_launch, Launch};
use crate::scenario::world::Scenario;
use coopnav_acomms::node_report::{NodeReport, VehicleType};
use coopnav_acomms::selector::{RatePolicy, RatePolicySpec};
use coopnav_acomms::Rate;
use coopnav_core::{hypot_within, wrap_pi, Bathymetry, Heading, Iver2, Iver2State, SeedStream, Vec3, Waypoint};
use coopnav_nav::{AuvFilter, AuvModel, AuvParams, Side, StateKind};
use rand_chacha::ChaCha8Rng;

/// Stream ids of one run: the CNA's, a block of ten per survey AUV and one per buoy.
pub mod stream {
    pub const CNA_GPS: u64 = 1;
    pub const CNA_NAV: u64 = 2;
    pub const CNA_CLOCK: u64 = 3;
    pub const AUV_BASE: u64 = 100;
    pub const INIT: u64 = 0;
    pub const SPEED: u64 = 1;
    pub const COMPASS_MAP: u64 = 2;
    pub const COMPASS_WHITE: u64 = 3;
    pub const YAW_RATE: u64 = 4;
    pub const RANGE: u64 = 5;
    pub const DOWNLINK: u64 = 6;
    pub const UPLINK: u64 = 7;
    pub const CLOCK: u64 = 8;
    pub const GPS: u64 = 9;
    pub const BUOY_BASE: u64 = 10_000;
    pub const BUOY_MOTION: u64 = 0;
    pub const BUOY_GPS: u64 = 1;
    pub const BUOY_CLOCK: u64 = 2;
    /// The channel draws (fate and range error) of its broadcasts, at every AUV in turn.
    pub const BUOY_LINK: u64 = 3;
    pub const SHIP_BASE: u64 = 20_000;
    pub const SHIP_INIT: u64 = 0;
    pub const SHIP_SENSORS: u64 = 1;
    pub const SHIP_CLOCK: u64 = 2;
    pub const SHIP_LINK: u64 = 3;
}

/// `rng` replaced by the generator of its own stream id under `streams`: fresh draws from here on
/// that still differ from every other source's.
pub fn redraw(rng: &mut ChaCha8Rng, streams: &SeedStream) {
    *rng = streams.rng(rng.get_stream());
}

/// A survey AUV.
#[derive(Clone)]
pub struct SurveyAuv {
    pub ctrl: Iver2,
    /// True position at the end of the last step, and at its start.
    pub truth: Vec3,
    pub prev: Vec3,
    pub ekf: AuvFilter,
    pub clock: Clock,
    /// Yaw rate measured over the current step (the filter's prediction input).
    pub yaw_measured: f64,
    /// The readings summed since the filter's last step (a decimated filter predicts with their
    /// mean, [`crate::models::filter::FilterRate`]).
    pub yaw_sum: f64,
    compass: CompassBias,
    rng_speed: ChaCha8Rng,
    rng_white: ChaCha8Rng,
    rng_yaw: ChaCha8Rng,
    rng_gps: ChaCha8Rng,
    /// Its acoustic modem.
    pub modem: AuvModem,
    /// Propulsion off (a finished vehicle holding or surfacing).
    adrift: bool,
    /// Its last survey waypoint: where a finished vehicle loiters or holds station.
    pub station: (f64, f64),
}

/// A survey AUV's acoustic modem: its noise streams, its status-rate selector and what it has
/// heard of the CNA.
#[derive(Clone)]
pub struct AuvModem {
    /// The measured travel time's noise.
    pub rng_range: ChaCha8Rng,
    /// Whether a packet to it (the CNA's broadcast) decodes.
    pub rng_down: ChaCha8Rng,
    /// Whether a packet from it (its status) decodes.
    pub rng_up: ChaCha8Rng,
    /// Rate selection for the status messages, and the status slots it still waits to hear about.
    pub selector: Box<dyn RatePolicy>,
    pub unacked: Vec<u64>,
    /// Last CNA position heard (from its broadcast).
    pub cna_heard: Option<Vec3>,
    /// The CNA's broadcasts decoded since its last status (acknowledged in it, when the CNA's
    /// broadcast has a rate policy).
    pub heard_broadcasts: Vec<u64>,
}

/// The filter's model and coefficients with the current the team states ([`Adcp`]): the true
/// current plus the ADCP's error, drawn from `r_init` after the start position (so a scenario
/// without an ADCP draws as before); the file's own without one.
fn stated_current(sc: &Scenario, r_init: &mut ChaCha8Rng) -> (AuvModel, AuvParams) {
    let (mut model, mut params) = (sc.filter.model, sc.filter.params.clone());
    if let Some(Adcp { sd_m_s }) = sc.filter.adcp {
        let (e, n) = sc.fleet.current;
        let stated = [e + sd_m_s * normal(r_init), n + sd_m_s * normal(r_init)];
        match &mut model {
            AuvModel::Current(c) => c.mean = stated,
            AuvModel::Thesis => params.stated_current = stated,
        }
    }
    (model, params)
}

impl SurveyAuv {
    pub fn new(sc: &Scenario, k: usize, streams: &SeedStream, bathy: &Bathymetry) -> Self {
        let rng = |id: u64| streams.rng(stream::AUV_BASE + 10 * k as u64 + id);
        let Launch { waypoints: pts, pos: truth, heading, bottom } = auv_launch(sc, k, bathy);
        let (start, z0) = ((truth.x, truth.y), truth.z);
        let waypoints: Vec<Waypoint> =
            pts.iter().map(|&(x, y)| Waypoint { x, y, target: sc.fleet.depth, speed: sc.fleet.speed }).collect();
        let mut r_init = rng(stream::INIT);
        let sd = sc.fleet.init_position_sd;
        let (ex, ey) = (start.0 + sd * normal(&mut r_init), start.1 + sd * normal(&mut r_init));
        let (model, params) = stated_current(sc, &mut r_init);
        let mut state = Iver2State::at_rest(Vec3::new(ex, ey, z0), Heading::from_radians(heading));
        state.altitude = bottom - z0;
        let s = &sc.sensors;
        SurveyAuv {
            ctrl: Iver2::new(sc.survey_dynamics(), state, waypoints),
            truth,
            prev: truth,
            ekf: AuvFilter::new(&model, 0.0, ex, ey, 0.0, heading, params),
            clock: sc.channel.clocks.draw(&mut rng(stream::CLOCK)),
            yaw_measured: 0.0,
            yaw_sum: 0.0,
            compass: CompassBias::draw(s.compass_bias_step_deg, s.compass_bias_iid, &mut rng(stream::COMPASS_MAP)),
            rng_speed: rng(stream::SPEED),
            rng_white: rng(stream::COMPASS_WHITE),
            rng_yaw: rng(stream::YAW_RATE),
            rng_gps: rng(stream::GPS),
            modem: AuvModem {
                rng_range: rng(stream::RANGE),
                rng_down: rng(stream::DOWNLINK),
                rng_up: rng(stream::UPLINK),
                selector: status_policy(sc, k).build().expect("validated rate policy"),
                unacked: Vec::new(),
                cna_heard: None,
                heard_broadcasts: Vec::new(),
            },
            adrift: false,
            station: pts.last().copied().unwrap_or(start),
        }
    }

    /// Its noise streams from here on drawn from `streams` (each keeps its stream id).
    pub fn redraw(&mut self, streams: &SeedStream) {
        for r in [
            &mut self.rng_speed,
            &mut self.rng_white,
            &mut self.rng_yaw,
            &mut self.rng_gps,
            &mut self.modem.rng_range,
            &mut self.modem.rng_down,
            &mut self.modem.rng_up,
        ] {
            redraw(r, streams);
        }
    }

    /// True velocity over ground in the last step.
    pub fn velocity(&self, dt: f64) -> Vec3 {
        (self.truth - self.prev) * (1.0 / dt)
    }

    /// Applies the finish behaviour's action, then one truth step: the controller steers from
    /// the filter's estimate; the truth moves by the same displacement plus the current.
    pub fn step_truth(&mut self, sc: &Scenario, bathy: &Bathymetry, action: Action) {
        let (ex, ey) = self.ekf.position();
        self.ctrl.state.pos.x = ex;
        self.ctrl.state.pos.y = ey;
        self.adrift = false;
        match action {
            Action::Continue => {}
            Action::Steer(points) => {
                let last = self.ctrl.waypoints().last().copied();
                let (target, speed) = last.map_or((sc.fleet.depth, sc.fleet.speed), |w| (w.target, w.speed));
                let waypoints = points.into_iter().map(|(x, y)| Waypoint { x, y, target, speed }).collect();
                self.ctrl = Iver2::new(self.ctrl.params, self.ctrl.state, waypoints);
            }
            Action::Drift => self.propulsion_off(),
            Action::Ascend(rate) => {
                self.propulsion_off();
                self.ctrl.state.pos.z = (self.ctrl.state.pos.z - rate * sc.dt).max(0.0);
            }
        }
        self.prev = self.truth;
        let before = self.ctrl.state.pos;
        self.ctrl.step(bathy);
        let d = self.ctrl.state.pos - before;
        self.truth.x += d.x + sc.fleet.current.0 * sc.dt;
        self.truth.y += d.y + sc.fleet.current.1 * sc.dt;
        self.truth.z = self.ctrl.state.pos.z;
        self.yaw_measured =
            self.ctrl.state.yaw_rate + sc.sensors.yaw_rate_white_deg_s.to_radians() * normal(&mut self.rng_yaw);
    }

    /// The vehicle stops through the water (an instant stop: the IVER2 model has no coast-down).
    fn propulsion_off(&mut self) {
        let s = &mut self.ctrl.state;
        (s.speed, s.yaw_rate, s.lin_accel, s.vertical_speed) = (0.0, 0.0, 0.0, 0.0);
        self.adrift = true;
    }

    pub fn at_surface(&self) -> bool {
        self.adrift && self.truth.z <= 0.0
    }

    /// One filter step to `t` at heading rate `yaw_rate`: prediction, then the speed and compass
    /// updates; returns the readings (m/s; math heading, rad).
    #[inline]
    pub fn sense(&mut self, sc: &Scenario, t: f64, yaw_rate: f64) -> (f64, f64) {
        let s = &sc.sensors;
        let psi = self.ctrl.state.heading.radians();
        let speed = self.ctrl.state.speed + s.speed_sd * normal(&mut self.rng_speed);
        let heading =
            wrap_pi(psi + self.compass.at(psi) + s.compass_white_deg.to_radians() * normal(&mut self.rng_white));
        self.ekf.dead_reckoning_step(t, yaw_rate, speed, heading);
        (speed, heading)
    }

    /// A GPS fix of the horizontal position (σ `sd` per axis), as a surfaced AUV takes.
    pub fn gps_fix(&mut self, sd: f64) {
        let fix = (self.truth.x + sd * normal(&mut self.rng_gps), self.truth.y + sd * normal(&mut self.rng_gps));
        self.ekf.update_position_fix(fix, sd);
    }

    pub fn finite(&self) -> bool {
        self.ekf.is_finite()
    }

    /// The Appendix C status message from the AUV's own estimate and its next three waypoints.
    pub fn status(&self, k: usize, t: f64) -> NodeReport {
        let (ex, ey) = self.ekf.position();
        let (speed, psi) = self.ekf.speed_heading();
        let next = self.ctrl.next_waypoint();
        let waypoints = self.ctrl.waypoints().iter().skip(next).take(3).map(|w| (w.x, w.y)).collect();
        NodeReport {
            src_id: (k + 1) as u8,
            time_of_day: (t.rem_euclid(86_400.0)) as u32,
            vehicle: VehicleType::Auv,
            x: ex,
            y: ey,
            speed: speed.clamp(-2.0, 9.0),
            heading: Heading::from_radians(psi),
            waypoints,
            front_seat_error: 0,
            front_mode: 0,
            leak: false,
            depth: self.truth.z.clamp(-1.0, 203.0),
            altitude: self.ctrl.state.altitude.clamp(-1.0, 203.0),
            battery: 100.0 * (1.0 - t / 86_400.0).clamp(0.0, 1.0),
        }
    }
}

/// Survey AUV `k`'s status rate policy: the one its schedule slot names, else the comms default
/// (the adaptive selector when `comms.status_adaptive` is given, else `comms.status_rate`).
pub fn status_policy(sc: &Scenario, k: usize) -> RatePolicySpec {
    if let Some(spec) = sc.comms.schedule.status_policy(k) {
        return spec.clone();
    }
    match &sc.comms.status_adaptive {
        Some(cfg) => RatePolicySpec::Adaptive(cfg.clone()),
        None => RatePolicySpec::Fixed { rate: sc.comms.status_rate },
    }
}

pub fn lerp(a: Vec3, b: Vec3, f: f64) -> Vec3 {
    a + (b - a) * f
}

/// The CNA craft: steers to its commanded point at transit speed with a turn-rate limit and holds
/// station on arrival; an AUV CNA also moves towards the commanded depth, pitch-limited.
#[derive(Clone)]
pub struct Craft {
    pub pos: Vec3,
    pub prev: Vec3,
    pub heading: f64,
    pub target: Option<Vec3>,
}

impl Craft {
    pub fn step(&mut self, speed: f64, max_rate: f64, dt: f64) {
        self.prev = self.pos;
        let Some(goal) = self.target else { return };
        // Depth changes at most at the speed's vertical share at the 30° pitch limit (docs/models.md#hudson-motion).
        let dz_max = speed * dt * 0.5;
        self.pos.z += (goal.z - self.pos.z).clamp(-dz_max, dz_max);
        let (dx, dy) = (goal.x - self.pos.x, goal.y - self.pos.y);
        if hypot_within(dx, dy, speed * dt).is_some_and(|dist| dist <= speed * dt) {
            self.pos.x = goal.x;
            self.pos.y = goal.y;
            return;
        }
        let turn = wrap_pi(dy.atan2(dx) - self.heading).clamp(-max_rate * dt, max_rate * dt);
        self.heading = wrap_pi(self.heading + turn);
        self.pos.x += speed * dt * self.heading.cos();
        self.pos.y += speed * dt * self.heading.sin();
    }
}

/// A transponder buoy: where it truly is, what its GPS reads and its modem's clock.
#[derive(Clone)]
pub struct Buoy {
    motion: BuoyMotion,
    depth: f64,
    gps_sd: f64,
    pub rate: Rate,
    pub clock: Clock,
    rng_gps: ChaCha8Rng,
    pub rng_link: ChaCha8Rng,
}

impl Buoy {
    pub fn new(sc: &Scenario, i: usize, streams: &SeedStream) -> Self {
        let spec: &BuoySpec = &sc.buoys[i];
        let rng = |id: u64| streams.rng(stream::BUOY_BASE + 10 * i as u64 + id);
        Buoy {
            motion: spec.motion(&mut rng(stream::BUOY_MOTION)),
            depth: spec.modem_depth_m,
            gps_sd: spec.gps_sd_m,
            rate: spec.rate,
            clock: sc.channel.clocks.draw(&mut rng(stream::BUOY_CLOCK)),
            rng_gps: rng(stream::BUOY_GPS),
            rng_link: rng(stream::BUOY_LINK),
        }
    }

    /// Its noise streams from here on drawn from `streams`.
    pub fn redraw(&mut self, streams: &SeedStream) {
        redraw(&mut self.rng_gps, streams);
        redraw(&mut self.rng_link, streams);
    }

    /// Its transducer's true position at `t`.
    pub fn position(&self, t: f64) -> Vec3 {
        let [x, y] = self.motion.at(t);
        Vec3::new(x, y, self.depth)
    }

    /// The position it broadcasts at `t`: its GPS fix.
    pub fn gps_fix(&mut self, t: f64) -> Vec3 {
        let p = self.position(t);
        let (ex, ey) = (self.gps_sd * normal(&mut self.rng_gps), self.gps_sd * normal(&mut self.rng_gps));
        Vec3::new(p.x + ex, p.y + ey, p.z)
    }
}

/// A ship on its fixed track: its truth (a unicycle its pilot steers back onto the track), what
/// its broadcasts measure, and its modems' clock.
#[derive(Clone)]
pub struct Ship {
    /// True position of its reference point at the end of the last step, and at its start.
    pub pos: Vec3,
    pub prev: Vec3,
    /// True math heading and speed over ground.
    pub psi: f64,
    pub speed: f64,
    pub clock: Clock,
    rng_sensors: ChaCha8Rng,
    pub rng_link: ChaCha8Rng,
}

impl Ship {
    /// Its noise streams from here on drawn from `streams`.
    pub fn redraw(&mut self, streams: &SeedStream) {
        redraw(&mut self.rng_sensors, streams);
        redraw(&mut self.rng_link, streams);
    }

    /// Ship `i` at its nominal start, scattered as its spec says (its own stream).
    pub fn new(sc: &Scenario, i: usize, streams: &SeedStream) -> Self {
        let spec = &sc.ships[i];
        let rng = |id: u64| streams.rng(stream::SHIP_BASE + 10 * i as u64 + id);
        let mut r_init = rng(stream::SHIP_INIT);
        let sd = spec.start_scatter;
        let pos = Vec3::new(
            spec.x + sd.position_sd_m * normal(&mut r_init),
            spec.y + sd.position_sd_m * normal(&mut r_init),
            0.0,
        );
        let speed = spec.speed + sd.speed_sd * normal(&mut r_init);
        let psi = wrap_pi(spec.track() + sd.heading_sd_deg.to_radians() * normal(&mut r_init));
        Ship {
            pos,
            prev: pos,
            psi,
            speed,
            clock: sc.channel.clocks.draw(&mut rng(stream::SHIP_CLOCK)),
            rng_sensors: rng(stream::SHIP_SENSORS),
            rng_link: rng(stream::SHIP_LINK),
        }
    }

    /// One truth step: the pilot's heading-rate command from the true offset off the track.
    pub fn step(&mut self, spec: &ShipSpec, dt: f64) {
        let track = spec.track();
        let (dx, dy) = (self.pos.x - spec.x, self.pos.y - spec.y);
        let left_of_track = -dx * track.sin() + dy * track.cos();
        let rate = spec.pilot.rate(left_of_track, track, self.psi);
        self.prev = self.pos;
        self.psi = wrap_pi(self.psi + rate * dt);
        self.pos.x += dt * self.speed * self.psi.cos();
        self.pos.y += dt * self.speed * self.psi.sin();
    }

    /// The transducer of its `side` modem at fraction `frac` of the last step.
    pub fn modem(&self, spec: &ShipSpec, side: Side, frac: f64) -> Vec3 {
        let p = lerp(self.prev, self.pos, frac);
        spec.outriggers.position(side, p.x, p.y, self.psi)
    }

    /// The value its mini-packet carrying `kind` decodes to: its DGPS position at fraction `frac`
    /// of the last step, its measured speed and heading, quantised (four draws, whatever the kind:
    /// the stream does not depend on the cycle).
    pub fn mini_value(&mut self, spec: &ShipSpec, kind: StateKind, frac: f64) -> f64 {
        let s = &spec.sensors;
        let noise: [f64; 4] = std::array::from_fn(|_| normal(&mut self.rng_sensors));
        let p = lerp(self.prev, self.pos, frac);
        let measured = [p.x + s.gps_sd_m * noise[0], p.y + s.gps_sd_m * noise[1]];
        let speed = self.speed + s.speed_sd * noise[2];
        let psi = self.psi + s.heading_sd_deg.to_radians() * noise[3];
        minipacket::quantised(kind, measured, speed, psi, &spec.zone)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On course and far from its goal, the CNA craft moves speed × dt per step of any length.
    #[test]
    fn the_cna_moves_speed_times_dt() {
        for dt in [0.01, 0.1, 0.2, 0.5, 1.0] {
            let start = Vec3::new(10.0, -20.0, 0.0);
            let mut c = Craft { pos: start, prev: start, heading: 0.3, target: None };
            c.target = Some(Vec3::new(10.0 + 5000.0 * 0.3f64.cos(), -20.0 + 5000.0 * 0.3f64.sin(), 0.0));
            c.step(2.5, 4f64.to_radians(), dt);
            let moved = (c.pos - start).norm();
            assert!((moved - 2.5 * dt).abs() < 1e-9, "dt = {dt}: moved {moved} m");
            assert_eq!(c.prev, start);
        }
    }

    /// A ship on its track at its speed moves speed × dt along the track per step of any length.
    #[test]
    fn a_ship_moves_speed_times_dt() {
        let text =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios/gill-table5-msbl.toml"))
                .expect("the library's Gill scenario");
        let sc = Scenario::parse(&text, std::path::Path::new("gill-table5-msbl.toml")).expect("it parses");
        let streams = SeedStream::new(1);
        for dt in [0.01, 0.1, 0.2, 0.5, 1.0] {
            let mut ship = Ship::new(&sc, 0, &streams);
            let spec = &sc.ships[0];
            (ship.pos, ship.psi, ship.speed) = (Vec3::new(spec.x, spec.y, 0.0), spec.track(), spec.speed);
            let start = ship.pos;
            ship.step(spec, dt);
            let moved = (ship.pos - start).norm();
            assert!((moved - spec.speed * dt).abs() < 1e-9, "dt = {dt}: moved {moved} m");
        }
    }
}
