//! Ships on a fixed track (Gill's support ship, Gill 2013, §2.4.1): a surface vehicle that
//! drives a straight line at constant speed under a look-ahead path controller and broadcasts its
//! state as mini-packets from two outrigger modems (port and starboard, Gill 2013, §2.4.2). The spec
//! (`[[ships]]`), the pilot and their validation live here; the engine's ship is in
//! `engine/vehicles.rs`.

use super::minipacket::check_zone;
use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::{wrap_pi, CompassDeg, Heading};
use coopnav_nav::codec::Zone;
use coopnav_nav::{Outriggers, SurfaceParams};
use serde::{Deserialize, Serialize};

/// One `[[ships]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShipSpec {
    /// Nominal start on the track, m (the survey frame: x east, y north).
    pub x: f64,
    pub y: f64,
    /// Direction of the track through the start, compass degrees.
    pub heading_compass_deg: f64,
    /// Speed over ground, m/s (Gill: 1.30).
    pub speed: f64,
    #[serde(default)]
    pub pilot: Pilot,
    /// Scatter of the true start about the nominal one (Gill's §5.3 values by default).
    #[serde(default)]
    pub start_scatter: StartScatter,
    #[serde(default)]
    pub outriggers: Outriggers,
    /// What its broadcasts measure: DGPS position, speed and heading noise (Gill 2013, §2.4.1;
    /// docs/models.md#gill-sensor-noise).
    #[serde(default)]
    pub sensors: ShipSensors,
    /// Quantisation zone of its East/North mini-packets.
    pub zone: Zone,
    /// The ship filter every survey AUV runs from its broadcasts (Gill 2013, §2.2.2; coefficients
    /// invented, docs/models.md#gill-coefficients).
    #[serde(default = "SurfaceParams::ship")]
    pub filter: SurfaceParams,
}

/// Look-ahead path controller (a MOOS-style virtual waypoint; the thesis's controller is not
/// given): a heading-rate command towards the point `lookahead_m` ahead on the track. Gains
/// invented (docs/models.md#gill-scenario).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Pilot {
    pub lookahead_m: f64,
    pub heading_gain: f64,
    pub max_rate_deg_s: f64,
}

impl Default for Pilot {
    fn default() -> Self {
        Pilot { lookahead_m: 10.0, heading_gain: 1.0, max_rate_deg_s: 4.0 }
    }
}

impl Pilot {
    /// Heading-rate command (rad/s) for a vehicle at `offset` m left of a track of math heading
    /// `track`, heading `psi`.
    pub fn rate(&self, offset: f64, track: f64, psi: f64) -> f64 {
        let desired = track + (-offset).atan2(self.lookahead_m);
        let max = self.max_rate_deg_s.to_radians();
        (self.heading_gain * wrap_pi(desired - psi)).clamp(-max, max)
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StartScatter {
    pub position_sd_m: f64,
    pub speed_sd: f64,
    pub heading_sd_deg: f64,
}

impl Default for StartScatter {
    fn default() -> Self {
        StartScatter { position_sd_m: 4.0, speed_sd: 0.05, heading_sd_deg: 0.1f64.to_degrees() }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShipSensors {
    pub gps_sd_m: f64,
    pub speed_sd: f64,
    pub heading_sd_deg: f64,
}

impl Default for ShipSensors {
    fn default() -> Self {
        ShipSensors { gps_sd_m: 0.1, speed_sd: 0.02, heading_sd_deg: 0.5 }
    }
}

/// Most ships a scenario may have.
pub const MAX_SHIPS: usize = 4;

impl ShipSpec {
    /// Math heading of the track.
    pub fn track(&self) -> f64 {
        Heading::from(CompassDeg(self.heading_compass_deg)).radians()
    }
}

impl CheckFields for ShipSpec {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let mut need =
            |field: &str, v: f64, ok: bool, allowed: &str| p.require(&format!("{prefix}{field}"), v, ok, allowed);
        for (field, v) in [("x", self.x), ("y", self.y), ("heading_compass_deg", self.heading_compass_deg)] {
            need(field, v, true, "a finite number");
        }
        need("speed", self.speed, self.speed > 0.0 && self.speed <= 6.0, "0 < speed <= 6 m/s");
        let pilot = &self.pilot;
        need("pilot.lookahead_m", pilot.lookahead_m, pilot.lookahead_m > 0.0, "a finite number > 0");
        need("pilot.heading_gain", pilot.heading_gain, pilot.heading_gain > 0.0, "a finite number > 0");
        need("pilot.max_rate_deg_s", pilot.max_rate_deg_s, pilot.max_rate_deg_s > 0.0, "a finite number > 0");
        let s = &self.start_scatter;
        let ranges = [
            ("start_scatter.position_sd_m", s.position_sd_m, 100.0),
            ("start_scatter.speed_sd", s.speed_sd, 1.0),
            ("start_scatter.heading_sd_deg", s.heading_sd_deg, 90.0),
            ("sensors.gps_sd_m", self.sensors.gps_sd_m, 100.0),
            ("sensors.speed_sd", self.sensors.speed_sd, 1.0),
            ("sensors.heading_sd_deg", self.sensors.heading_sd_deg, 90.0),
        ];
        for (field, v, max) in ranges {
            need(field, v, (0.0..=max).contains(&v), &format!("0..={max}"));
        }
        let o = &self.outriggers;
        need("outriggers.separation", o.separation, (0.0..=100.0).contains(&o.separation), "0..=100 m");
        need("outriggers.along_offset", o.along_offset, o.along_offset.abs() <= 100.0, "within ±100 m");
        need("outriggers.depth", o.depth, (0.0..=100.0).contains(&o.depth), "0..=100 m");
        check_zone(&format!("{prefix}zone."), &self.zone, p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn the_pilot_turns_back_towards_the_track_and_holds_it() {
        let pilot = Pilot::default();
        // On the track and on its heading: no command; off it, the command is limited.
        assert_eq!(pilot.rate(0.0, PI, PI), 0.0);
        assert_eq!(pilot.rate(100.0, 0.0, 0.0).abs(), 4f64.to_radians());
        // Left of an eastward track, the pilot turns right (negative rate).
        assert!(pilot.rate(5.0, 0.0, 0.0) < 0.0);
        assert!(pilot.rate(-5.0, 0.0, 0.0) > 0.0);
        // A westward track (math π): 5 m left of it is south; the pilot turns right, to the north.
        assert!(pilot.rate(5.0, PI, PI) < 0.0);
    }

    #[test]
    fn bad_ship_fields_are_named() {
        let text = "x = 121.0\ny = 0.0\nheading_compass_deg = 270.0\nspeed = 0.0\n\
                    zone = { east = { origin = -183.8, resolution = 1.6 }, north = { origin = -53.6, resolution = 0.0 } }\n\
                    outriggers = { depth = -1.0 }";
        let ship: ShipSpec = toml::from_str(text).unwrap();
        let fields = ship.validate("ships[0].").unwrap_err().fields();
        assert_eq!(fields, ["ships[0].speed", "ships[0].outriggers.depth", "ships[0].zone.north.resolution"]);
        let typo = toml::from_str::<ShipSpec>(&text.replace("speed = 0.0", "sped = 1.3")).unwrap_err().to_string();
        assert!(typo.contains("sped"), "{typo}");
    }
}
