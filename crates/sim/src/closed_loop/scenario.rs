//! The closed-loop scenario file (TOML, `deny_unknown_fields`): the survey fleet and its
//! lawnmowers, the CNA, the acoustic link, sensors and filters, and the planner. Validated
//! before anything runs; every error names the file, the field and what is allowed.

use crate::hbl::config::Sensors;
pub use crate::scenario_file::ScenarioError;
use crate::scenario_file::{self, overlay};
use coopnav_acomms::selector::AdaptiveConfig;
use coopnav_acomms::tl::analytic::Thorp;
use coopnav_acomms::{Rate, SuccessModel};
use coopnav_core::{Bathymetry, CompassDeg, DepthTarget, Heading, Lawnmower, Shelf};
use coopnav_nav::{AuvParams, RangeNoise};
use coopnav_plan::predict::{PredictorConfig, WaypointUse};
use coopnav_plan::{
    CnaKind, Deadline, DistanceLimits, ErrorModel, MotionConfig, PenaltyCase, PlannerConfig, SearchConfig,
};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The embedded default mission (`coopnav simulate` with no scenario, `--example`).
pub const EXAMPLE: &str = include_str!("example.toml");

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Base seed; Monte Carlo run i uses `run_seed(seed, i)`.
    pub seed: u64,
    pub duration_s: f64,
    /// Truth and filter step, s (10 Hz filters: 0.1).
    #[serde(default = "default_dt")]
    pub dt: f64,
    pub fleet: Fleet,
    pub cna: Cna,
    #[serde(default)]
    pub comms: Comms,
    #[serde(default)]
    pub sensors: Sensors,
    /// The survey AUVs' filter; its range noise is also the truth's (plus `comms.extra_range_sd`).
    #[serde(default = "default_filter", deserialize_with = "filter_over_default")]
    pub filter: AuvParams,
    pub planner: Planner,
}

/// The closed loop's channel keeps 0.15 m range noise at zero range (σ_τ = 0.1 ms, the model its
/// reproductions were measured with), not the nav default matched to Gill's outlier mixture.
fn default_filter() -> AuvParams {
    AuvParams { range_noise: RangeNoise { sigma_time: 1e-4, ..RangeNoise::default() }, ..AuvParams::default() }
}

/// A `[filter]` table overrides only the fields it names.
fn filter_over_default<'de, D: serde::Deserializer<'de>>(d: D) -> Result<AuvParams, D::Error> {
    use serde::Deserialize;
    overlay(&default_filter(), toml::Value::deserialize(d)?).map_err(serde::de::Error::custom)
}

fn default_dt() -> f64 {
    0.1
}

/// N survey AUVs, each with its own lawnmower block. Lanes step to the right of the lane heading
/// (east for northward lanes), and block k starts `block_offset` metres right of block k − 1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fleet {
    pub n_auvs: usize,
    pub origin: (f64, f64),
    pub lane_heading_compass_deg: f64,
    pub lane_length: f64,
    pub lane_spacing: f64,
    pub lanes: usize,
    pub block_offset: f64,
    /// Speed through water, m/s.
    pub speed: f64,
    /// Constant depth or height above the seafloor.
    pub depth: DepthTarget,
    /// Flat seafloor depth, m (used unless `shelf` is given).
    #[serde(default = "default_seafloor")]
    pub seafloor_depth: f64,
    /// A sloping synthetic shelf instead of the flat seafloor (altitude targets follow it).
    #[serde(default)]
    pub shelf: Option<Shelf>,
    /// Constant water current (east, north), m/s: true tracks depart from the plan.
    #[serde(default)]
    pub current: (f64, f64),
    /// SD of the initial position fix (GPS before diving), m.
    #[serde(default = "one")]
    pub init_position_sd: f64,
}

fn default_seafloor() -> f64 {
    100.0
}
fn one() -> f64 {
    1.0
}

/// The CNA: an autonomous surface craft with GPS, or (with `auv`) an AUV CNA that changes depth
/// by pitch and broadcasts its own dead-reckoned position estimate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cna {
    pub x: f64,
    pub y: f64,
    pub heading_compass_deg: f64,
    /// Transit speed s, m/s.
    pub speed: f64,
    /// Turn-rate limit of the craft, deg/s (Table 5.1: 4).
    #[serde(default = "default_turn_rate")]
    pub max_turn_rate_deg_s: f64,
    /// GPS position SD of the fix the CNA broadcasts, m (ASC).
    #[serde(default = "one")]
    pub gps_sd: f64,
    /// An AUV CNA instead of an ASC.
    #[serde(default)]
    pub auv: Option<AuvCna>,
}

/// An AUV as the CNA (Hudson's AUV-CNA case: heading and pitch options).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AuvCna {
    /// Pitch options B of the planner (≥ 1).
    pub pitch_options: usize,
    /// Start depth, m.
    pub depth: f64,
    /// Growth of the CNA's own horizontal position-error variance, m²/s per axis (a random walk:
    /// what it broadcasts is its truth plus this error). Invented: no thesis value.
    pub nav_diffusion: f64,
}

fn default_turn_rate() -> f64 {
    4.0
}

/// The acoustic link: TDMA over one period τ (CNA broadcast in slot 0, then one status slot per
/// AUV), fixed WHOI rates per direction, analytic TL and the Table 4/5 success engine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Comms {
    /// Period τ of the CNA's broadcast and of its decisions, s (independent of N).
    pub tau: f64,
    pub cna_rate: Rate,
    /// Fixed rate of the status messages, unless `status_adaptive` is given.
    pub status_rate: Rate,
    /// The Nams adaptive distance-bin selector for the status messages: each AUV picks the rate
    /// from its estimated distance to the CNA; the CNA's next broadcast acknowledges (one bit per
    /// AUV) the statuses it received since its last one.
    pub status_adaptive: Option<AdaptiveConfig>,
    pub tl: Thorp,
    pub success: SuccessModel,
    pub sound_speed: f64,
    /// SD of the true range error per range, m, on top of the filter's modelled noise (0 = the
    /// truth noise equals the filter's model).
    pub extra_range_sd: f64,
}

impl Default for Comms {
    fn default() -> Self {
        Comms {
            tau: 30.0,
            cna_rate: Rate::R0,
            status_rate: Rate::R0,
            status_adaptive: None,
            tl: Thorp::default(),
            success: SuccessModel::default(),
            sound_speed: 1500.0,
            extra_range_sd: 0.0,
        }
    }
}

/// The underway planner (Hudson §3.3, digest A13–A16) and its adapter's options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Planner {
    pub heading_options: usize,
    pub look_ahead: usize,
    /// Table 5.2 penalty case id.
    #[serde(default = "default_case")]
    pub penalty_case: String,
    #[serde(default)]
    pub error: ErrorModel,
    #[serde(default)]
    pub limits: DistanceLimits,
    /// The thesis's real-time budget per decision (τ − margin); fast-time runs rarely reach it.
    #[serde(default)]
    pub deadline: Deadline,
    /// Search the top tree levels with rayon.
    #[serde(default)]
    pub parallel: bool,
    /// Reports needed from an AUV before the CNA plans for it (digest A14).
    #[serde(default = "one_usize")]
    pub start_after_reports: usize,
    /// Thesis option: use at most min(L, 3) reported waypoints (default: all received).
    #[serde(default)]
    pub thesis_waypoints: bool,
    /// Model lost pings in the tracked error (expected value over the success likelihood);
    /// false = the thesis's behaviour (every ping assumed received).
    #[serde(default)]
    pub model_lost_pings: bool,
    /// Initial modelled σ₀ and ε₀, m (Table 5.1: 1 m).
    #[serde(default = "one")]
    pub sigma0: f64,
    #[serde(default = "one")]
    pub eps0: f64,
    #[serde(default)]
    pub predictor: PredictorConfig,
}

fn default_case() -> String {
    PenaltyCase::C1.id().to_string()
}
fn one_usize() -> usize {
    1
}

impl Scenario {
    pub fn example() -> Self {
        toml::from_str(EXAMPLE).expect("the embedded example scenario parses")
    }

    /// Parses and validates TOML text; `file` names it in messages.
    pub fn parse(text: &str, file: &Path) -> Result<Self, ScenarioError> {
        scenario_file::parse(text, file, Self::validate)
    }

    pub fn load(file: &Path) -> Result<Self, ScenarioError> {
        scenario_file::load(file, Self::validate)
    }

    /// Checks every field against its allowed range.
    pub fn validate(&self, file: &Path) -> Result<(), ScenarioError> {
        let bad = |field: &str, value: String, allowed: &str| ScenarioError::invalid(file, field, value, allowed);
        let positive = |field: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(bad(field, v.to_string(), "a finite number > 0"))
            }
        };
        let non_negative = |field: &str, v: f64| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                Err(bad(field, v.to_string(), "a finite number >= 0"))
            }
        };
        positive("duration_s", self.duration_s)?;
        if !(self.dt > 0.0 && self.dt <= 1.0) {
            return Err(bad("dt", self.dt.to_string(), "0 < dt <= 1 s"));
        }
        let f = &self.fleet;
        if !(1..=8).contains(&f.n_auvs) {
            return Err(bad("fleet.n_auvs", f.n_auvs.to_string(), "1..=8"));
        }
        positive("fleet.lane_length", f.lane_length)?;
        positive("fleet.lane_spacing", f.lane_spacing)?;
        if f.lanes == 0 {
            return Err(bad("fleet.lanes", "0".into(), ">= 1"));
        }
        non_negative("fleet.block_offset", f.block_offset)?;
        if !(f.speed > 0.0 && f.speed <= 3.0) {
            return Err(bad("fleet.speed", f.speed.to_string(), "0 < speed <= 3 m/s"));
        }
        positive("fleet.seafloor_depth", f.seafloor_depth)?;
        match f.depth {
            DepthTarget::Depth { depth } if !(depth >= 0.0 && depth < f.seafloor_depth) => {
                return Err(bad("fleet.depth.depth", depth.to_string(), "0 <= depth < fleet.seafloor_depth"))
            }
            DepthTarget::Altitude { altitude } if !(altitude > 0.0 && altitude < f.seafloor_depth) => {
                return Err(bad("fleet.depth.altitude", altitude.to_string(), "0 < altitude < fleet.seafloor_depth"))
            }
            _ => {}
        }
        if let Some(shelf) = &f.shelf {
            Bathymetry::shelf(shelf)
                .map_err(|e| bad("fleet.shelf", e.to_string(), "a valid shelf (extent, spacing, depths > 0)"))?;
            let shallowest = shelf.shallow.min(shelf.deep);
            let clear = match f.depth {
                DepthTarget::Depth { depth } => depth < shallowest,
                DepthTarget::Altitude { altitude } => altitude < shallowest,
            };
            if !clear {
                return Err(bad(
                    "fleet.depth",
                    format!("{:?}", f.depth),
                    "shallower than the shelf's shallowest water",
                ));
            }
        }
        if !(f.current.0.is_finite() && f.current.1.is_finite() && f.current.0.hypot(f.current.1) < f.speed) {
            return Err(bad("fleet.current", format!("{:?}", f.current), "finite, slower than fleet.speed"));
        }
        non_negative("fleet.init_position_sd", f.init_position_sd)?;
        for (field, v) in [
            ("fleet.origin", f.origin.0.abs().max(f.origin.1.abs())),
            ("cna.x", self.cna.x.abs()),
            ("cna.y", self.cna.y.abs()),
        ] {
            if !(v < 10_000.0) {
                return Err(bad(field, v.to_string(), "coordinates within ±10 000 m (status message range ±16 000 m)"));
            }
        }
        // Every survey waypoint must fit the status message's ±16 000 m fields (with room for drift).
        let extent = (0..f.n_auvs)
            .flat_map(|k| self.lawnmower(k).waypoints())
            .map(|(x, y)| x.abs().max(y.abs()))
            .fold(0.0, f64::max);
        if !(extent < 15_000.0) {
            return Err(bad(
                "fleet",
                format!("survey reaching {extent:.0} m from the origin"),
                "every lawnmower within ±15 000 m (status message fields are ±16 000 m)",
            ));
        }
        positive("cna.speed", self.cna.speed)?;
        if let Some(a) = &self.cna.auv {
            if a.pitch_options == 0 {
                return Err(bad("cna.auv.pitch_options", "0".into(), ">= 1"));
            }
            if !(a.depth >= 0.0 && a.depth < 100.0) {
                return Err(bad(
                    "cna.auv.depth",
                    a.depth.to_string(),
                    "0 <= depth < 100 m (the planner's AUV-CNA depth limits)",
                ));
            }
            non_negative("cna.auv.nav_diffusion", a.nav_diffusion)?;
        }
        positive("cna.max_turn_rate_deg_s", self.cna.max_turn_rate_deg_s)?;
        non_negative("cna.gps_sd", self.cna.gps_sd)?;
        let c = &self.comms;
        if !(5.0..=600.0).contains(&c.tau) {
            return Err(bad("comms.tau", c.tau.to_string(), "5..=600 s"));
        }
        if self.dt > c.tau {
            return Err(bad("dt", self.dt.to_string(), "<= comms.tau"));
        }
        for (field, rate) in [("comms.cna_rate", c.cna_rate), ("comms.status_rate", c.status_rate)] {
            if rate.spec().deprecated {
                return Err(bad(field, rate.to_string(), "0, 1, 4 or 5 (rates 2 and 3 are deprecated)"));
            }
        }
        if let Some(a) = &c.status_adaptive {
            a.validate().map_err(|e| bad("comms.status_adaptive", e, "see the message"))?;
        }
        positive("comms.sound_speed", c.sound_speed)?;
        non_negative("comms.extra_range_sd", c.extra_range_sd)?;
        positive("comms.tl.k", c.tl.k)?;
        positive("comms.tl.freq_hz", c.tl.freq_hz)?;
        self.filter.validate("filter.").map_err(|e| bad("filter", e.to_string(), "see the message"))?;
        let p = &self.planner;
        positive("planner.sigma0", p.sigma0)?;
        non_negative("planner.eps0", p.eps0)?;
        if p.start_after_reports == 0 {
            return Err(bad("planner.start_after_reports", "0".into(), ">= 1"));
        }
        if PenaltyCase::from_id(&p.penalty_case).is_none() {
            let ids: Vec<&str> = PenaltyCase::ALL.iter().map(|c| c.id()).collect();
            return Err(bad("planner.penalty_case", p.penalty_case.clone(), &ids.join(", ")));
        }
        self.planner_config().validate().map_err(|e| bad("planner", e.to_string(), "see the message"))?;
        Ok(())
    }

    /// The seafloor: the shelf if given, else a flat bottom at `seafloor_depth`.
    pub fn bathymetry(&self) -> Bathymetry {
        let flat =
            || Bathymetry::new(-20_000.0, -20_000.0, 40_000.0, 40_000.0, 2, 2, vec![self.fleet.seafloor_depth; 4]);
        let grid = match &self.fleet.shelf {
            Some(shelf) => Bathymetry::shelf(shelf),
            None => flat(),
        };
        grid.or_else(|_| flat()).expect("validated scenarios always give a grid")
    }

    /// The look-ahead planner's configuration for this scenario.
    pub fn planner_config(&self) -> PlannerConfig {
        let p = &self.planner;
        PlannerConfig {
            look_ahead: p.look_ahead,
            motion: MotionConfig {
                speed: self.cna.speed,
                tau: self.comms.tau,
                heading_options: p.heading_options,
                max_turn_rate_deg_s: self.cna.max_turn_rate_deg_s,
                cna: self.cna.auv.as_ref().map_or(CnaKind::Asc {}, |a| CnaKind::auv(a.pitch_options)),
            },
            error: p.error,
            cost: coopnav_plan::CostSpec::Hudson,
            limits: p.limits,
            penalties: PenaltyCase::from_id(&p.penalty_case).unwrap_or(PenaltyCase::C1).penalties(),
            search: SearchConfig { parallel: p.parallel, deadline: p.deadline, ..SearchConfig::default() },
        }
    }

    pub fn predictor_config(&self) -> PredictorConfig {
        let mut c = self.planner.predictor;
        if self.planner.thesis_waypoints {
            c.waypoints = WaypointUse::thesis(self.planner.look_ahead);
        }
        c
    }

    /// The lawnmower of survey AUV `k`.
    pub fn lawnmower(&self, k: usize) -> Lawnmower {
        let f = &self.fleet;
        let heading = Heading::from(CompassDeg(f.lane_heading_compass_deg));
        let (ux, uy) = heading.unit();
        let off = k as f64 * f.block_offset;
        Lawnmower {
            origin: (f.origin.0 + uy * off, f.origin.1 - ux * off),
            lane_heading: heading,
            lane_length: f.lane_length,
            spacing: -f.lane_spacing,
            lanes: f.lanes,
            speed: f.speed,
            depth: coopnav_core::DepthProfile::Constant {
                depth: match f.depth {
                    DepthTarget::Depth { depth } => depth,
                    DepthTarget::Altitude { altitude } => f.seafloor_depth - altitude,
                },
            },
        }
    }

    /// The benchmark mission of issue 5: 3 h, 5 survey AUVs on 16-lane blocks (long enough to
    /// keep surveying for the whole 3 h), τ = 30 s, A = 5, L = 5, 10 Hz EKFs.
    pub fn bench() -> Self {
        let mut s = Self::example().with_auvs(5);
        s.duration_s = 3.0 * 3600.0;
        s.fleet.lanes = 16;
        s.fleet.lane_length = 950.0;
        s.fleet.lane_spacing = 50.0;
        s.fleet.block_offset = 850.0;
        s.cna.x = 2100.0;
        (s.planner.heading_options, s.planner.look_ahead, s.comms.tau, s.dt) = (5, 5, 30.0, 0.1);
        s
    }

    /// Copy with N survey AUVs (experiments sweep N).
    pub fn with_auvs(&self, n: usize) -> Self {
        let mut s = self.clone();
        s.fleet.n_auvs = n;
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        Scenario::parse(text, Path::new("s.toml")).unwrap_err().to_string()
    }

    #[test]
    fn example_is_valid_and_the_default_mission() {
        let s = Scenario::parse(EXAMPLE, Path::new("example.toml")).unwrap();
        assert_eq!((s.fleet.n_auvs, s.seed, s.duration_s), (3, 1, 3600.0));
        assert_eq!((s.planner.heading_options, s.planner.look_ahead), (5, 5));
        Scenario::bench().validate(Path::new("bench")).unwrap();
        // The commented-out options of the example are valid too.
        let options =
            EXAMPLE.replace("# status_adaptive", "status_adaptive").replace("# shelf", "shelf").replace("# auv", "auv");
        let s = Scenario::parse(&options, Path::new("options.toml")).unwrap();
        assert!(s.comms.status_adaptive.is_some() && s.fleet.shelf.is_some() && s.cna.auv.is_some());
        let survey_s = Scenario::bench().lawnmower(0).path_length() / 1.5;
        assert!(survey_s >= 3.0 * 3600.0 * 0.95, "bench survey lasts {survey_s} s");
    }

    /// A `[filter]` table changes only what it names: the closed loop's 0.1 ms timing noise
    /// survives it, and a misspelt key is still refused.
    #[test]
    fn partial_filter_tables_keep_the_closed_loop_channel() {
        let plain = Scenario::parse(EXAMPLE, Path::new("e.toml")).unwrap();
        assert_eq!(plain.filter.range_noise.sigma_time, 1e-4);
        let s = Scenario::parse(&format!("{EXAMPLE}\n[filter]\nsigma_speed = 0.2\n"), Path::new("f.toml")).unwrap();
        assert_eq!((s.filter.sigma_speed, s.filter.range_noise.sigma_time), (0.2, 1e-4));
        assert_eq!(s.filter.q, plain.filter.q);
        let e = err(&format!("{EXAMPLE}\n[filter.range_noise]\nsigma_tim = 1e-3\n"));
        assert!(e.contains("sigma_tim"), "{e}");
    }

    #[test]
    fn bad_files_name_the_field() {
        let e = err(&EXAMPLE.replace("n_auvs = 3", "n_auvs = 9"));
        assert!(e.contains("fleet.n_auvs") && e.contains("1..=8") && e.contains("s.toml"), "{e}");
        let e = err(&EXAMPLE.replace("tau = 30.0", "tau = 1.0"));
        assert!(e.contains("comms.tau"), "{e}");
        let e = err(&EXAMPLE.replace("penalty_case = \"1\"", "penalty_case = \"zz\""));
        assert!(e.contains("planner.penalty_case"), "{e}");
        let e = err(&EXAMPLE.replace("seed = 1", "seed = 1\nsurprise = 2"));
        assert!(e.contains("surprise"), "{e}");
        let e = err(&EXAMPLE.replace("cna_rate = 0", "cna_rate = 3"));
        assert!(e.contains("comms.cna_rate"), "{e}");
        let e = err(&EXAMPLE.replace("speed = 1.5", "speed = -1.5"));
        assert!(e.contains("fleet.speed"), "{e}");
        let e = err(&EXAMPLE
            .replace("gps_sd = 1.0", "gps_sd = 1.0\nauv = { pitch_options = 0, depth = 10.0, nav_diffusion = 0.01 }"));
        assert!(e.contains("cna.auv.pitch_options"), "{e}");
        let e = err(&EXAMPLE.replace("lane_length = 800.0", "lane_length = 20000.0"));
        assert!(e.contains("field fleet") && e.contains("15 000"), "{e}");
        let e = err(&EXAMPLE.replace("heading_options = 5", "heading_options = 1"));
        assert!(e.contains("planner") && e.contains("heading_options"), "{e}");
    }
}
