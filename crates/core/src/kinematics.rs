//! IVER2 vehicle kinematics and waypoint following, ported from the Nams thesis's `vehicle.m`
//! (Nams 2014, Ch. 4 and App. B; eqs. 3–7 rebuilt from that code, see
//! docs/models.md#nams-kinematics): a 0.1 s kinematic step, P/PD loops on yaw, pitch (through depth) and
//! speed, with yaw-rate, pitch-rate, pitch and forward-acceleration limits. Zero roll.
//!
//! Conventions: the thesis works in compass degrees; here heading is the internal math heading
//! (radians, 0 = east, counter-clockwise) and the gains are converted so the motion is the same.
//! Pitch is positive nose-up; depth is positive down. Used by the acomms position estimator (the
//! "shadow simulation") and by the simulators, so it knows nothing about modems.

use crate::bathymetry::Bathymetry;
use crate::validation::{CheckFields, Problems};
use crate::{hypot_within, wrap_pi, Heading, Vec3};
use serde::{Deserialize, Serialize};

/// Depth reference of a waypoint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum DepthTarget {
    /// Fixed depth below the surface, m.
    Depth { depth: f64 },
    /// Height above the seafloor, m (altitude keeping: depth follows the terrain).
    Altitude { altitude: f64 },
}

impl DepthTarget {
    /// The depth this reference asks for where the seafloor is `bottom` m deep (an altitude
    /// deeper than the water gives a negative depth: callers that place a vehicle clamp it).
    pub fn depth_over(self, bottom: f64) -> f64 {
        match self {
            DepthTarget::Depth { depth } => depth,
            DepthTarget::Altitude { altitude } => bottom - altitude,
        }
    }
}

/// A mission waypoint: horizontal position, depth reference and speed through water (m/s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Waypoint {
    pub x: f64,
    pub y: f64,
    pub target: DepthTarget,
    pub speed: f64,
}

/// Constants of the IVER2 model. Defaults are `vehicle.m`'s values (Nams 2014, App. B).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Iver2Params {
    pub timestep: f64,
    /// Forward acceleration limit, m/s².
    pub max_lin_accel: f64,
    /// Pitch-rate clamp, rad/s (thesis: 10 deg/s).
    pub max_pitch_rate: f64,
    /// Yaw-rate clamp, rad/s (thesis: 13 deg/s).
    pub max_yaw_rate: f64,
    /// Yaw acceleration limit, rad/s². Declared but unused in `vehicle.m` (12.9 deg/s²); `None`
    /// keeps the faithful behaviour (docs/models.md#nams-kinematics).
    pub max_yaw_accel: Option<f64>,
    /// Pitch limit, rad. Invented: the thesis uses VectorMap's default, which is lost; 20°
    /// (docs/models.md#nams-kinematics).
    pub max_pitch: f64,
    pub kp_speed: f64,
    pub kd_speed: f64,
    /// Yaw gains: yaw rate (rad/s) per rad of heading error.
    pub kp_yaw: f64,
    pub kd_yaw: f64,
    /// Pitch gains in the thesis's units: deg/s of pitch rate per m of depth error, and per m/s of
    /// vertical speed.
    pub kp_pitch: f64,
    pub kd_pitch: f64,
    /// Waypoint capture radius, m (IVER2 standard 5 m).
    pub waypoint_tolerance: f64,
    /// Fractional slow-down at the full yaw rate (0.2 = 20 %).
    pub turn_slowdown: f64,
}

impl Default for Iver2Params {
    fn default() -> Self {
        Iver2Params {
            timestep: 0.1,
            max_lin_accel: 0.25,
            max_pitch_rate: 10f64.to_radians(),
            max_yaw_rate: 13f64.to_radians(),
            max_yaw_accel: None,
            max_pitch: 20f64.to_radians(),
            kp_speed: 1.0,
            kd_speed: 0.0,
            kp_yaw: 1.0,
            kd_yaw: 0.0,
            kp_pitch: 5.0,
            kd_pitch: 15.0,
            waypoint_tolerance: 5.0,
            turn_slowdown: 0.2,
        }
    }
}

impl CheckFields for Iver2Params {
    /// Every step, limit and gain must be able to drive the model.
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let field = |name: &str| format!("{prefix}{name}");
        for (name, v) in [
            ("timestep", self.timestep),
            ("max_lin_accel", self.max_lin_accel),
            ("max_pitch_rate", self.max_pitch_rate),
            ("max_yaw_rate", self.max_yaw_rate),
            ("max_pitch", self.max_pitch),
            ("waypoint_tolerance", self.waypoint_tolerance),
        ] {
            p.positive(&field(name), v);
        }
        if self.timestep > 10.0 {
            p.push(field("timestep"), self.timestep.to_string(), "a step of at most 10 s");
        }
        p.check(&field("turn_slowdown"), self.turn_slowdown, |v| (0.0..1.0).contains(&v), "a number in [0, 1)");
        if let Some(a) = self.max_yaw_accel {
            p.positive(&field("max_yaw_accel"), a);
        }
        for (name, g) in [
            ("kp_speed", self.kp_speed),
            ("kd_speed", self.kd_speed),
            ("kp_yaw", self.kp_yaw),
            ("kd_yaw", self.kd_yaw),
            ("kp_pitch", self.kp_pitch),
            ("kd_pitch", self.kd_pitch),
        ] {
            p.finite(&field(name), g);
        }
    }
}

/// Kinematic state of one vehicle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Iver2State {
    pub pos: Vec3,
    pub heading: Heading,
    /// Pitch, rad, positive nose-up.
    pub pitch: f64,
    /// Speed through water, m/s.
    pub speed: f64,
    /// Depth rate, m/s, positive down.
    pub vertical_speed: f64,
    pub yaw_rate: f64,
    pub lin_accel: f64,
    /// Height above the seafloor as last sensed, m.
    pub altitude: f64,
    /// Time since mission start, s.
    pub t: f64,
}

impl Iver2State {
    /// At rest at `pos`, pointing along `heading`, at time 0.
    pub fn at_rest(pos: Vec3, heading: Heading) -> Self {
        Iver2State {
            pos,
            heading,
            pitch: 0.0,
            speed: 0.0,
            vertical_speed: 0.0,
            yaw_rate: 0.0,
            lin_accel: 0.0,
            altitude: -1.0,
            t: 0.0,
        }
    }
}

/// An IVER2 following a list of waypoints; it parks (stops moving) once the last is reached.
#[derive(Debug, Clone, PartialEq)]
pub struct Iver2 {
    pub params: Iver2Params,
    pub state: Iver2State,
    waypoints: Vec<Waypoint>,
    next: usize,
}

impl Iver2 {
    pub fn new(params: Iver2Params, state: Iver2State, waypoints: Vec<Waypoint>) -> Self {
        Iver2 { params, state, waypoints, next: 0 }
    }

    /// Index of the waypoint being steered to (== number of waypoints when complete).
    pub fn next_waypoint(&self) -> usize {
        self.next
    }
    pub fn waypoints(&self) -> &[Waypoint] {
        &self.waypoints
    }
    pub fn is_complete(&self) -> bool {
        self.next >= self.waypoints.len()
    }
    /// Replaces the state and the waypoint being steered to (used to reset a shadow vehicle).
    pub fn reset(&mut self, state: Iver2State, next: usize) {
        self.state = state;
        self.next = next.min(self.waypoints.len());
    }

    /// Runs whole kinematic steps until the vehicle's clock reaches `t` (within half a step).
    pub fn advance_to(&mut self, t: f64, bathy: &Bathymetry) {
        let dt = self.params.timestep;
        while self.state.t + 0.5 * dt < t {
            self.step(bathy);
        }
    }

    /// One kinematic step (`vehicle.m` `updatePosition` inner loop, same update order).
    pub fn step(&mut self, bathy: &Bathymetry) {
        let dt = self.params.timestep;
        let p = self.params;
        let Some(wp) = self.waypoints.get(self.next).copied() else {
            self.state.t += dt;
            return;
        };
        let s = &mut self.state;
        let bottom = bathy.depth_at(s.pos.x, s.pos.y);
        s.altitude = bottom - s.pos.z;

        let setpoint = Heading::from_radians((wp.y - s.pos.y).atan2(wp.x - s.pos.x));
        let mut yaw_rate = p.kp_yaw * s.heading.turn_to(setpoint) + p.kd_yaw * s.yaw_rate;
        if let Some(a) = p.max_yaw_accel {
            yaw_rate = yaw_rate.clamp(s.yaw_rate - a * dt, s.yaw_rate + a * dt);
        }
        yaw_rate = yaw_rate.clamp(-p.max_yaw_rate, p.max_yaw_rate);

        let depth_sp = wp.target.depth_over(bottom);
        // The thesis's pitch loop is in degrees: deg/s per metre of depth error and per m/s of
        // the previous step's vertical speed.
        let pitch_rate_deg = (s.pos.z - depth_sp) * p.kp_pitch + p.kd_pitch * s.vertical_speed;
        let pitch_rate = pitch_rate_deg.to_radians().clamp(-p.max_pitch_rate, p.max_pitch_rate);

        let speed_sp = wp.speed * (1.0 - p.turn_slowdown * yaw_rate.abs() / p.max_yaw_rate);
        let lin_accel =
            ((speed_sp - s.speed) * p.kp_speed + s.lin_accel * p.kd_speed).clamp(-p.max_lin_accel, p.max_lin_accel);

        s.speed += lin_accel * dt;
        s.pitch = (s.pitch + pitch_rate * dt).clamp(-p.max_pitch, p.max_pitch);
        let ground = s.pitch.cos() * s.speed;
        s.vertical_speed = -s.pitch.sin() * s.speed;
        s.pos.z = (s.pos.z + s.vertical_speed * dt).max(0.0);
        s.heading = Heading::from_radians(wrap_pi(s.heading.radians() + yaw_rate * dt));
        let (ux, uy) = s.heading.unit();
        s.pos.x += ground * dt * ux;
        s.pos.y += ground * dt * uy;
        s.yaw_rate = yaw_rate;
        s.lin_accel = lin_accel;
        s.t += dt;

        let tolerance = p.waypoint_tolerance;
        if hypot_within(wp.x - s.pos.x, wp.y - s.pos.y, tolerance).is_some_and(|d| d < tolerance) {
            self.next += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bathymetry::Shelf;

    fn flat(depth: f64) -> Bathymetry {
        Bathymetry::new(-5000.0, -5000.0, 10000.0, 10000.0, 2, 2, vec![depth; 4]).unwrap()
    }

    fn wp(x: f64, y: f64) -> Waypoint {
        Waypoint { x, y, target: DepthTarget::Altitude { altitude: 5.0 }, speed: 1.543 }
    }

    #[test]
    fn reaches_cruise_speed_with_limited_acceleration() {
        let b = flat(30.0);
        let mut v = Iver2::new(
            Iver2Params::default(),
            Iver2State::at_rest(Vec3::new(0.0, 0.0, 25.0), Heading::from_radians(0.0)),
            vec![wp(5000.0, 0.0)],
        );
        v.step(&b);
        assert!((v.state.speed - 0.025).abs() < 1e-12, "0.25 m/s² for 0.1 s");
        v.advance_to(60.0, &b);
        assert!((v.state.speed - 1.543).abs() < 1e-3);
        assert!((v.state.t - 60.0).abs() < 1e-6);
        assert!((v.state.pos.z - 25.0).abs() < 0.5, "altitude keeping at 5 m over 30 m");
    }

    /// At cruise, level and on course, one step of any length moves the vehicle speed × dt along
    /// its heading, and its clock by dt.
    #[test]
    fn one_step_moves_speed_times_dt() {
        let b = flat(30.0);
        for dt in [0.01, 0.05, 0.1, 0.2, 0.5, 1.0] {
            let mut state = Iver2State::at_rest(Vec3::new(0.0, 0.0, 25.0), Heading::from_radians(0.0));
            state.speed = 1.543;
            let params = Iver2Params { timestep: dt, ..Iver2Params::default() };
            let mut v = Iver2::new(params, state, vec![wp(5000.0, 0.0)]);
            v.step(&b);
            let moved = v.state.pos.x;
            assert!((moved - 1.543 * dt).abs() < 1e-12, "dt = {dt}: moved {moved} m");
            assert!(v.state.pos.y.abs() < 1e-12 && (v.state.t - dt).abs() < 1e-15, "dt = {dt}");
        }
    }

    #[test]
    fn yaw_rate_is_clamped_and_turns_toward_waypoint() {
        let b = flat(30.0);
        // Waypoint due north, vehicle heading east: a left (counter-clockwise) turn at 13 deg/s.
        let mut v = Iver2::new(
            Iver2Params::default(),
            Iver2State::at_rest(Vec3::new(0.0, 0.0, 25.0), Heading::from_radians(0.0)),
            vec![wp(0.0, 1000.0)],
        );
        v.step(&b);
        assert!((v.state.yaw_rate - 13f64.to_radians()).abs() < 1e-12);
        v.advance_to(30.0, &b);
        assert!((v.state.heading.radians() - std::f64::consts::FRAC_PI_2).abs() < 0.05);
    }

    #[test]
    fn follows_the_terrain_and_completes_the_mission() {
        let b = Bathymetry::shelf(&Shelf::default()).unwrap();
        let wps = vec![wp(300.0, 0.0), wp(300.0, 100.0), wp(0.0, 100.0)];
        let mut v = Iver2::new(
            Iver2Params::default(),
            Iver2State::at_rest(Vec3::new(0.0, 0.0, 20.0), Heading::from_radians(0.0)),
            wps,
        );
        let mut max_alt_err: f64 = 0.0;
        for _ in 0..12000 {
            v.step(&b);
            if v.state.t > 60.0 && !v.is_complete() {
                max_alt_err = max_alt_err.max((v.state.altitude - 5.0).abs());
            }
        }
        assert!(v.is_complete());
        assert!(max_alt_err < 1.0, "altitude error {max_alt_err}");
        assert!((v.state.pos.x - 0.0).abs() < 5.0 && (v.state.pos.y - 100.0).abs() < 5.0);
        let parked = v.state.pos;
        v.step(&b);
        assert_eq!(v.state.pos, parked, "a complete vehicle parks");
    }

    #[test]
    fn bad_params_are_named() {
        let fields = |v: Iver2Params| {
            let mut p = Problems::new();
            v.check_fields("vehicle.", &mut p);
            p.finish().err().map(|e| e.0.into_iter().map(|p| p.field).collect::<Vec<_>>()).unwrap_or_default()
        };
        assert!(fields(Iver2Params::default()).is_empty());
        let bad = Iver2Params {
            timestep: 0.0,
            turn_slowdown: 1.0,
            max_yaw_accel: Some(-1.0),
            kd_pitch: f64::NAN,
            ..Iver2Params::default()
        };
        assert_eq!(
            fields(bad),
            ["vehicle.timestep", "vehicle.turn_slowdown", "vehicle.max_yaw_accel", "vehicle.kd_pitch"]
        );
        assert_eq!(fields(Iver2Params { timestep: 11.0, ..Iver2Params::default() }), ["vehicle.timestep"]);
    }

    #[test]
    fn pitch_stays_within_limit() {
        let b = flat(80.0);
        let mut v = Iver2::new(
            Iver2Params::default(),
            Iver2State::at_rest(Vec3::new(0.0, 0.0, 0.0), Heading::from_radians(0.0)),
            vec![wp(5000.0, 0.0)],
        );
        for _ in 0..3000 {
            v.step(&b);
            assert!(v.state.pitch.abs() <= 20f64.to_radians() + 1e-12);
            assert!(v.state.pos.z >= 0.0);
        }
        assert!((v.state.altitude - 5.0).abs() < 1.0);
    }
}
