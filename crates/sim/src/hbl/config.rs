//! The HBL scenario: every number of the Gill simulation (digest §5), with the digest's
//! reconstructions as defaults, read from TOML (`deny_unknown_fields`) and validated before a run.

use super::log_format::LogFormat;
use coopnav_core::validation::{CheckFields, InvalidFields, Problems};
use coopnav_nav::codec::Zone;
use coopnav_nav::cycle::{Configuration, Cycle, CycleError};
use coopnav_nav::{AuvParams, Outriggers, SurfaceParams};
use serde::{Deserialize, Serialize};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ConfigError {
    #[error("scenario: {0}")]
    Fields(#[from] InvalidFields),
    #[error("scenario: {0}")]
    Cycle(#[from] CycleError),
    #[error("scenario file: {0}")]
    Toml(#[from] toml::de::Error),
    #[error("scenario field 'log.buoy_fix_storage' = {0:?} needs log.geodetic_origin (the rounding happens in latitude/longitude); add `geodetic_origin = {{ lat_deg = ..., lon_deg = ... }}` or use \"f64\"")]
    LogStorage(coopnav_core::LatLonStorage),
}

/// Where the transponder position used for a range is taken (digest §10 A6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TransponderTime {
    Transmit,
    Receive,
}

/// Vehicle paths and the measurement zone (digest §5.1, A16). x is along the path (east),
/// crossing-centred; the AUV goes east, the ship west.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Geometry {
    pub auv_start_x: f64,
    pub ship_start_x: f64,
    pub path_y: f64,
    pub auv_speed: f64,
    pub ship_speed: f64,
    pub zone_min: f64,
    pub zone_max: f64,
    /// The run ends this far past the zone exit (m of x_rel).
    pub end_margin: f64,
    /// Length of the approach window just before the zone (x_rel in [zone_min − approach_m,
    /// zone_min)), where the thesis says HBL has already corrected the perpendicular error and
    /// MSBL has not (digest §7.5, §11; the window length is ours).
    pub approach_m: f64,
}

impl Default for Geometry {
    fn default() -> Self {
        Geometry {
            auv_start_x: -79.0,
            ship_start_x: 121.0,
            path_y: 0.0,
            auv_speed: 0.85,
            ship_speed: 1.30,
            zone_min: -30.0,
            zone_max: 75.0,
            end_margin: 5.0,
            approach_m: 50.0,
        }
    }
}

/// Initial truth scatter about the nominal start (digest §5.3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InitNoise {
    pub position_sd: f64,
    pub speed_sd: f64,
    pub heading_sd_rad: f64,
}

impl Default for InitNoise {
    fn default() -> Self {
        InitNoise { position_sd: 4.0, speed_sd: 0.05, heading_sd_rad: 0.1 }
    }
}

/// Look-ahead path controllers (digest §5.2, A25: gains invented).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Control {
    pub lookahead_m: f64,
    pub heading_gain: f64,
    pub auv_max_rate_deg_s: f64,
    pub ship_max_rate_deg_s: f64,
}

impl Default for Control {
    fn default() -> Self {
        Control { lookahead_m: 10.0, heading_gain: 1.0, auv_max_rate_deg_s: 30.0, ship_max_rate_deg_s: 4.0 }
    }
}

/// Sensor noise (digest §5.4, A12–A13).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Sensors {
    pub speed_sd: f64,
    /// Step SD of the compass-bias random walk over integer headings (deg).
    pub compass_bias_step_deg: f64,
    /// Independent per-degree bias values instead of a random walk.
    pub compass_bias_iid: bool,
    pub compass_white_deg: f64,
    pub yaw_rate_white_deg_s: f64,
    pub dgps_sd: f64,
    pub ship_speed_sd: f64,
    pub ship_heading_sd_deg: f64,
}

impl Default for Sensors {
    fn default() -> Self {
        Sensors {
            speed_sd: 0.05,
            compass_bias_step_deg: 0.047,
            compass_bias_iid: false,
            compass_white_deg: 0.0,
            yaw_rate_white_deg_s: 0.0,
            dgps_sd: 0.1,
            ship_speed_sd: 0.02,
            ship_heading_sd_deg: 0.5,
        }
    }
}

/// Acoustic channel (digest §5.4, §2.4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Acoustic {
    pub p_slightly_long: f64,
    pub p_slightly_short: f64,
    pub p_outlier: f64,
    pub p_drop: f64,
    pub slight_max_m: f64,
    pub outlier_min_m: f64,
    pub outlier_max_m: f64,
    pub sound_speed: f64,
    /// Error of the filter's assumed sound speed (m/s).
    pub filter_sound_speed_bias: f64,
    /// Draw a receiver clock drift rate ~ N(mean, sd) µs/h per run.
    pub clock_drift: bool,
    pub clock_drift_mean_us_h: f64,
    pub clock_drift_sd_us_h: f64,
    pub transponder_time: TransponderTime,
}

impl Default for Acoustic {
    fn default() -> Self {
        Acoustic {
            p_slightly_long: 0.50,
            p_slightly_short: 0.35,
            p_outlier: 0.05,
            p_drop: 0.10,
            slight_max_m: 0.20,
            outlier_min_m: 5.0,
            outlier_max_m: 10.0,
            sound_speed: 1500.0,
            filter_sound_speed_bias: 0.0,
            clock_drift: false,
            clock_drift_mean_us_h: 162.0,
            clock_drift_sd_us_h: 203.0,
            transponder_time: TransponderTime::Transmit,
        }
    }
}

impl Acoustic {
    /// Mean square of the range error of a *received* message under the thesis's mixture
    /// (digest §5.4: uniform "slight" errors and uniform 5–10 m outliers), in m².
    pub fn received_error_mean_square(&self) -> f64 {
        let uniform_sq = |a: f64, b: f64| (a * a + a * b + b * b) / 3.0;
        let received = self.p_slightly_long + self.p_slightly_short + self.p_outlier;
        let sum = (self.p_slightly_long + self.p_slightly_short) * uniform_sq(0.0, self.slight_max_m)
            + self.p_outlier * uniform_sq(self.outlier_min_m, self.outlier_max_m);
        if received > 0.0 {
            sum / received
        } else {
            0.0
        }
    }
}

/// Buoy drift model (digest §5.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Drift {
    /// Moored (the buoy-location optimisation).
    None,
    /// Lake Pend Oreille statistics, linear or circular with equal odds.
    Lake,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Buoy {
    /// Uniform initial-position box [min, max] (digest §5.3, A14: a guess to re-derive).
    pub region_x: [f64; 2],
    pub region_y: [f64; 2],
    /// A fixed initial position instead of the box (grid cells).
    pub fixed: Option<[f64; 2]>,
    pub drift: Drift,
    pub drift_mean: f64,
    pub drift_sd: f64,
    pub circular_fraction: f64,
    pub circular_radius: f64,
    /// SD of the buoy filter's initial position error per axis (digest A17).
    pub init_sd: f64,
    /// Constant offset injected into the buoy's broadcast position (the field GPS failure).
    pub broadcast_bias: [f64; 2],
}

impl Default for Buoy {
    fn default() -> Self {
        Buoy {
            region_x: [-20.0, 60.0],
            region_y: [40.0, 90.0],
            fixed: None,
            drift: Drift::Lake,
            drift_mean: 0.056,
            drift_sd: 0.039,
            circular_fraction: 0.5,
            circular_radius: 200.0,
            init_sd: 4.0,
            broadcast_bias: [0.0, 0.0],
        }
    }
}

/// Broadcast quantisation zones (digest §10 A9).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Quantisation {
    pub ship_resolution: [f64; 2],
    /// East centre of both zones (the path midpoint) and north start of the ship zone.
    pub centre_e: f64,
    pub north_min: f64,
    pub buoy_resolution: [f64; 2],
    /// Centre of the buoy zone; None: the ship zone's layout at the buoy resolution.
    pub buoy_centre: Option<[f64; 2]>,
}

impl Default for Quantisation {
    fn default() -> Self {
        Quantisation {
            ship_resolution: [1.6, 0.6],
            centre_e: 21.0,
            north_min: -53.6,
            buoy_resolution: [1.6, 0.6],
            buoy_centre: None,
        }
    }
}

impl Quantisation {
    pub fn ship_zone(&self) -> Zone {
        Zone::with_resolution(self.centre_e, self.north_min, self.ship_resolution[0], self.ship_resolution[1])
    }
    pub fn buoy_zone(&self) -> Zone {
        let [re, rn] = self.buoy_resolution;
        match self.buoy_centre {
            Some([e, n]) => Zone::centred(e, n, re, rn),
            None => Zone::with_resolution(self.centre_e, self.north_min, re, rn),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Filters {
    pub auv: AuvParams,
    pub ship: SurfaceParams,
    pub buoy: SurfaceParams,
    pub outriggers: Outriggers,
}

impl Default for Filters {
    fn default() -> Self {
        Filters {
            auv: AuvParams::default(),
            ship: SurfaceParams::ship(),
            buoy: SurfaceParams::buoy(),
            outriggers: Outriggers::default(),
        }
    }
}

/// A whole HBL simulation set-up.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Scenario {
    /// Truth and filter step (s). Digest §10 A1.
    pub dt: f64,
    pub max_duration_s: f64,
    pub configuration: Configuration,
    /// Cycle preset (msbl, hbl_short, hbl_long), unless `custom_cycle` is given.
    pub cycle: String,
    pub custom_cycle: Option<Cycle>,
    pub geometry: Geometry,
    pub init: InitNoise,
    pub control: Control,
    pub sensors: Sensors,
    pub acoustic: Acoustic,
    pub buoy: Buoy,
    pub quantisation: Quantisation,
    pub filters: Filters,
    pub log: LogFormat,
}

impl Default for Scenario {
    fn default() -> Self {
        Scenario {
            dt: 0.1,
            max_duration_s: 400.0,
            configuration: Configuration::HblTwo,
            cycle: "hbl_long".into(),
            custom_cycle: None,
            geometry: Geometry::default(),
            init: InitNoise::default(),
            control: Control::default(),
            sensors: Sensors::default(),
            acoustic: Acoustic::default(),
            buoy: Buoy::default(),
            quantisation: Quantisation::default(),
            filters: Filters::default(),
            log: LogFormat::default(),
        }
    }
}

impl Scenario {
    /// The Table 5 set-up for one configuration (MSBL uses the MSBL cycle, digest A8).
    pub fn table5(configuration: Configuration) -> Self {
        let cycle = if configuration == Configuration::Msbl { "msbl" } else { "hbl_long" };
        Scenario { configuration, cycle: cycle.into(), ..Scenario::default() }
    }

    pub fn from_toml(text: &str) -> Result<Self, ConfigError> {
        let s: Scenario = toml::from_str(text)?;
        s.validate()?;
        Ok(s)
    }

    pub fn resolved_cycle(&self) -> Result<Cycle, ConfigError> {
        let c = match &self.custom_cycle {
            Some(c) => c.clone(),
            None => Cycle::preset(&self.cycle)?,
        };
        c.validate()?;
        Ok(c)
    }

    /// Checks every field and reports every bad one at once, each named with its allowed range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let mut p = Problems::new();
        p.require("dt", self.dt, self.dt > 0.0 && self.dt <= 2.0, "in (0, 2] s");
        p.require("max_duration_s", self.max_duration_s, self.max_duration_s > self.dt, "> dt");
        let g = &self.geometry;
        p.require("geometry.auv_speed", g.auv_speed, g.auv_speed > 0.0 && g.auv_speed <= 4.0, "in (0, 4] m/s");
        p.require("geometry.ship_speed", g.ship_speed, g.ship_speed > 0.0 && g.ship_speed <= 4.0, "in (0, 4] m/s");
        p.require(
            "geometry.ship_start_x",
            g.ship_start_x,
            g.ship_start_x > g.auv_start_x,
            "> geometry.auv_start_x (east of it)",
        );
        p.require("geometry.zone_max", g.zone_max, g.zone_max > g.zone_min, "> geometry.zone_min");
        p.non_negative("geometry.end_margin", g.end_margin);
        p.non_negative("geometry.approach_m", g.approach_m);
        p.finite("geometry.auv_start_x", g.auv_start_x);
        p.finite("geometry.zone_min", g.zone_min);
        p.finite("geometry.path_y", g.path_y);
        p.non_negative("init.position_sd", self.init.position_sd);
        p.non_negative("init.speed_sd", self.init.speed_sd);
        p.non_negative("init.heading_sd_rad", self.init.heading_sd_rad);
        let c = &self.control;
        p.positive("control.lookahead_m", c.lookahead_m);
        p.positive("control.heading_gain", c.heading_gain);
        p.positive("control.auv_max_rate_deg_s", c.auv_max_rate_deg_s);
        p.positive("control.ship_max_rate_deg_s", c.ship_max_rate_deg_s);
        let s = &self.sensors;
        for (name, v) in [
            ("sensors.speed_sd", s.speed_sd),
            ("sensors.compass_bias_step_deg", s.compass_bias_step_deg),
            ("sensors.compass_white_deg", s.compass_white_deg),
            ("sensors.yaw_rate_white_deg_s", s.yaw_rate_white_deg_s),
            ("sensors.dgps_sd", s.dgps_sd),
            ("sensors.ship_speed_sd", s.ship_speed_sd),
            ("sensors.ship_heading_sd_deg", s.ship_heading_sd_deg),
        ] {
            p.non_negative(name, v);
        }
        let a = &self.acoustic;
        for (name, v) in [
            ("acoustic.p_slightly_long", a.p_slightly_long),
            ("acoustic.p_slightly_short", a.p_slightly_short),
            ("acoustic.p_outlier", a.p_outlier),
            ("acoustic.p_drop", a.p_drop),
        ] {
            p.probability(name, v);
        }
        let total = a.p_slightly_long + a.p_slightly_short + a.p_outlier + a.p_drop;
        p.require(
            "acoustic.p_* (sum)",
            total,
            (total - 1.0).abs() < 1e-9,
            "p_slightly_long + p_slightly_short + p_outlier + p_drop, which must sum to 1",
        );
        p.non_negative("acoustic.slight_max_m", a.slight_max_m);
        p.non_negative("acoustic.outlier_min_m", a.outlier_min_m);
        p.require(
            "acoustic.outlier_max_m",
            a.outlier_max_m,
            a.outlier_max_m >= a.outlier_min_m,
            "≥ acoustic.outlier_min_m",
        );
        p.require(
            "acoustic.sound_speed",
            a.sound_speed,
            a.sound_speed >= 1300.0 && a.sound_speed <= 1700.0,
            "in [1300, 1700] m/s",
        );
        let cf = a.sound_speed + a.filter_sound_speed_bias;
        p.require(
            "acoustic.filter_sound_speed_bias",
            a.filter_sound_speed_bias,
            (1300.0..=1700.0).contains(&cf),
            "sound_speed + bias in [1300, 1700] m/s",
        );
        p.finite("acoustic.clock_drift_mean_us_h", a.clock_drift_mean_us_h);
        p.non_negative("acoustic.clock_drift_sd_us_h", a.clock_drift_sd_us_h);
        let b = &self.buoy;
        p.require(
            "buoy.region_x[1]",
            b.region_x[1],
            b.region_x[1] >= b.region_x[0] && b.region_x[0].is_finite(),
            "≥ buoy.region_x[0]",
        );
        p.require(
            "buoy.region_y[1]",
            b.region_y[1],
            b.region_y[1] >= b.region_y[0] && b.region_y[0].is_finite(),
            "≥ buoy.region_y[0]",
        );
        if let Some([x, y]) = b.fixed {
            p.finite("buoy.fixed[0]", x);
            p.finite("buoy.fixed[1]", y);
        }
        p.non_negative("buoy.drift_mean", b.drift_mean);
        p.non_negative("buoy.drift_sd", b.drift_sd);
        p.probability("buoy.circular_fraction", b.circular_fraction);
        p.positive("buoy.circular_radius", b.circular_radius);
        p.non_negative("buoy.init_sd", b.init_sd);
        p.finite("buoy.broadcast_bias[0]", b.broadcast_bias[0]);
        p.finite("buoy.broadcast_bias[1]", b.broadcast_bias[1]);
        let q = &self.quantisation;
        for (name, v) in [
            ("quantisation.ship_resolution[0]", q.ship_resolution[0]),
            ("quantisation.ship_resolution[1]", q.ship_resolution[1]),
            ("quantisation.buoy_resolution[0]", q.buoy_resolution[0]),
            ("quantisation.buoy_resolution[1]", q.buoy_resolution[1]),
        ] {
            p.positive(name, v);
        }
        p.finite("quantisation.centre_e", q.centre_e);
        p.finite("quantisation.north_min", q.north_min);
        if let Some([e, n]) = q.buoy_centre {
            p.finite("quantisation.buoy_centre[0]", e);
            p.finite("quantisation.buoy_centre[1]", n);
        }
        self.filters.auv.check_fields("filters.auv.", &mut p);
        self.filters.ship.check_fields("filters.ship.", &mut p);
        self.filters.buoy.check_fields("filters.buoy.", &mut p);
        self.filters.outriggers.check_fields("filters.outriggers.", &mut p);
        p.finish()?;
        self.log.validate()?;
        self.resolved_cycle()?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_toml_overrides() {
        Scenario::default().validate().unwrap();
        let s = Scenario::from_toml(
            "configuration = 'msbl'\ncycle = 'msbl'\n[acoustic]\np_drop = 0.2\np_slightly_long = 0.4\n",
        )
        .unwrap();
        assert_eq!(s.configuration, Configuration::Msbl);
        assert_eq!(s.acoustic.p_drop, 0.2);
    }

    /// The AUV filter's default timing noise is matched to this simulator's range-error mixture
    /// (see `coopnav_nav::RangeNoise`); the two defaults must not drift apart.
    #[test]
    fn default_range_noise_matches_the_channel() {
        let rms = Acoustic::default().received_error_mean_square().sqrt();
        let noise = Filters::default().auv.range_noise;
        let filter = noise.sound_speed * noise.sigma_time;
        assert!((filter - rms).abs() < 0.01 * rms, "filter σ at zero range {filter} m vs channel RMS {rms} m");
    }

    #[test]
    fn bad_scenarios_name_the_field() {
        let e = |t: &str| Scenario::from_toml(t).unwrap_err().to_string();
        assert!(e("dt = -1.0\n").contains("field dt = -1"));
        assert!(e("[acoustic]\np_drop = 0.5\n").contains("sum to 1"));
        assert!(e("[geometry]\nauv_speed = 9.0\n").contains("geometry.auv_speed"));
        assert!(e("[buoy]\nregion_y = [50.0, 10.0]\n").contains("buoy.region_y[1]"));
        assert!(e("[filters.auv]\nsigma_speed = 0.0\n").contains("filters.auv.sigma_speed"));
        assert!(e("cycle = 'weekly'\n").contains("weekly"));
        assert!(e("[geometry]\nspeed = 1.0\n").contains("speed"));
        assert!(e("configuration = 'hbl_three'\n").contains("hbl_three"));
    }
}
