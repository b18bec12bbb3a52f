//! Pre-deployment scenario files (TOML): the CNA start pose, its platform (`[platform]`), the
//! planner (`[policy.planner]`, the closed loop's dialect: `coopnav_plan::PlannerSpec`) and each
//! survey AUV's a-priori track (a lawnmower description or a CSV file). Parsed with
//! `deny_unknown_fields` and validated before anything runs; errors name the file and the field.

use super::tracks::{load_track_csv, TrackLoadError};
pub use crate::scenario::file::ScenarioError;
use crate::scenario::file::{self as scenario_file, Problems};
use coopnav_core::validation::CheckFields;
use coopnav_core::{CompassDeg, DepthProfile, Heading, Lawnmower, Track, Vec3};
use coopnav_plan::auto::{CnaFact, MissionFacts};
use coopnav_plan::predeploy::Mission;
use coopnav_plan::{CnaKind, CnaPose, PlannerSpec, Platform};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The example scenario embedded in the binary.
pub const EXAMPLE: &str = include_str!("example.toml");

/// The whole file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    pub cna: CnaStart,
    /// The CNA as a vehicle (speed, decision period, turn limit, ASC or AUV).
    pub platform: Platform,
    pub policy: PlanPolicies,
    #[serde(default)]
    pub mission: MissionSection,
    pub auv: Vec<AuvSpec>,
    /// The site's geodetic origin (`scenario::site`; a site grid is `simulate`'s, refused here).
    #[serde(default, skip_serializing_if = "super::site::Site::is_empty")]
    pub site: super::site::Site,
}

/// CNA start pose (docs/models.md#hudson-start). Heading in compass degrees, as everywhere in files.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CnaStart {
    pub x: f64,
    pub y: f64,
    #[serde(default)]
    pub depth: f64,
    pub heading_compass_deg: f64,
    #[serde(default)]
    pub pitch_deg: f64,
}

/// The policy table of a pre-deployment file: Hudson's planner, as a closed-loop scenario's
/// `[policy.planner]` writes it (`coopnav_plan::PlannerSpec`; the pre-deployment planner has
/// no filters to read, so its cost is Hudson's).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanPolicies {
    pub planner: PlannerSpec,
}

/// Mission time span; by default from 0 to the end of the shortest survey track.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MissionSection {
    pub start_time: Option<f64>,
    pub end_time: Option<f64>,
}

/// One survey AUV.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AuvSpec {
    pub name: String,
    /// Initial radial and tangential errors, m (absent: the planner's `cost.sigma0`, `cost.eps0`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sigma0: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eps0: Option<f64>,
    pub lawnmower: Option<LawnmowerSpec>,
    /// CSV with columns t,x,y,z (relative paths are relative to the scenario file).
    pub track_csv: Option<PathBuf>,
}

/// A lawnmower in file units (compass heading).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LawnmowerSpec {
    pub origin: (f64, f64),
    pub lane_heading_compass_deg: f64,
    pub lane_length: f64,
    pub spacing: f64,
    pub lanes: usize,
    pub speed: f64,
    pub depth: DepthProfile,
}

impl CheckFields for LawnmowerSpec {
    fn check_fields(&self, prefix: &str, p: &mut coopnav_core::validation::Problems) {
        p.finite(&format!("{prefix}origin[0]"), self.origin.0);
        p.finite(&format!("{prefix}origin[1]"), self.origin.1);
        p.finite(&format!("{prefix}lane_heading_compass_deg"), self.lane_heading_compass_deg);
        p.positive(&format!("{prefix}lane_length"), self.lane_length);
        p.finite(&format!("{prefix}spacing"), self.spacing);
        if self.lanes == 0 {
            p.push(format!("{prefix}lanes"), "0", ">= 1");
        }
        p.positive(&format!("{prefix}speed"), self.speed);
        match self.depth {
            DepthProfile::Constant { depth } => p.finite(&format!("{prefix}depth.depth"), depth),
            DepthProfile::Sinusoid { mean, amplitude, period } => {
                p.finite(&format!("{prefix}depth.mean"), mean);
                p.finite(&format!("{prefix}depth.amplitude"), amplitude);
                p.positive(&format!("{prefix}depth.period"), period);
            }
        }
    }
}

impl LawnmowerSpec {
    pub fn to_lawnmower(&self) -> Lawnmower {
        Lawnmower {
            origin: self.origin,
            lane_heading: Heading::from(CompassDeg(self.lane_heading_compass_deg)),
            lane_length: self.lane_length,
            spacing: self.spacing,
            lanes: self.lanes,
            speed: self.speed,
            depth: self.depth,
        }
    }
}

/// Sampling interval of generated lawnmower tracks, s (linear between samples, exact on lanes).
pub(crate) const LAWNMOWER_DT: f64 = 1.0;

impl Scenario {
    /// Parses TOML text and checks every field that needs no track file; `file` names it in
    /// messages.
    pub fn parse(text: &str, file: &Path) -> Result<Self, ScenarioError> {
        let scenario = Self::read(text, file)?;
        scenario.validate(file)?;
        Ok(scenario)
    }

    /// [`Scenario::parse`] without the validation; positions in latitude/longitude are placed on
    /// the plane at `site.origin` (`scenario::site`).
    pub fn read(text: &str, file: &Path) -> Result<Self, ScenarioError> {
        super::moved::refuse_old_form(text, file, &[&super::moved::PLAN])?;
        match super::site::resolved(text, file, &toml::Value::Table(toml::Table::new()))? {
            Some(tree) => scenario_file::parse_tree(tree, file, |_, _| Ok(())),
            None => scenario_file::parse(text, file, |_, _| Ok(())),
        }
    }

    pub fn load(file: &Path) -> Result<Self, ScenarioError> {
        Self::parse(&scenario_file::read_scenario_text(file, false)?, file)
    }

    /// Checks the planner settings, the CNA pose, the mission span and each AUV's settings, and
    /// reports every bad field at once (the track files and the mission span they allow are
    /// checked by [`Scenario::build`]).
    pub fn validate(&self, file: &Path) -> Result<(), ScenarioError> {
        let mut p = Problems::new(file);
        if self.site.bathymetry.is_some() {
            p.push("site.bathymetry", "a grid", "none: the pre-deployment planner takes no bathymetry");
        }
        self.validate_planner(&mut p);
        let c = &self.cna;
        for (name, v) in [
            ("cna.x", c.x),
            ("cna.y", c.y),
            ("cna.depth", c.depth),
            ("cna.heading_compass_deg", c.heading_compass_deg),
            ("cna.pitch_deg", c.pitch_deg),
        ] {
            p.finite(name, v);
        }
        for (name, t) in [("mission.start_time", self.mission.start_time), ("mission.end_time", self.mission.end_time)]
        {
            if let Some(t) = t {
                p.finite(name, t);
            }
        }
        if self.auv.is_empty() {
            p.push("auv", "no [[auv]]", "at least one [[auv]]");
        }
        for (i, a) in self.auv.iter().enumerate() {
            let (sigma0, eps0) = self.initial_errors(a);
            p.positive(&format!("auv[{i}].sigma0"), sigma0);
            p.positive(&format!("auv[{i}].eps0"), eps0);
            match (&a.lawnmower, &a.track_csv) {
                (Some(m), None) => m.check_fields(&format!("auv[{i}].lawnmower."), &mut p),
                (None, Some(_)) => {}
                (lawnmower, _) => p.push(
                    format!("auv[{i}].lawnmower/track_csv"),
                    if lawnmower.is_some() { "both" } else { "neither" },
                    "exactly one of [auv.lawnmower] or track_csv",
                ),
            }
        }
        p.finish()
    }

    /// The planner's own checks, named as the file names them; its cost must be Hudson's.
    fn validate_planner(&self, p: &mut Problems) {
        let spec = &self.policy.planner;
        if spec.estimator_cost().is_some() {
            p.push(
                "policy.planner.cost.kind",
                "estimator",
                "\"hudson\" (the pre-deployment planner has no survey-AUV filters to read)",
            );
        }
        spec.check(&self.platform, &self.facts(), 0.0, "policy.planner.", p);
    }

    /// What the planner's rule would read of this mission (unused under Hudson's cost; the
    /// spec's checks take it).
    fn facts(&self) -> MissionFacts {
        let cna = match self.platform.cna {
            CnaKind::Asc {} => CnaFact::Asc,
            CnaKind::Auv { .. } => CnaFact::Auv { nav_diffusion_m2_s: 0.0 },
        };
        MissionFacts { n_auvs: self.auv.len(), cna, adcp_current: [0.0, 0.0], filters_estimate_current: false }
    }

    /// AUV `a`'s initial σ₀ and ε₀: its own, else the planner's.
    fn initial_errors(&self, a: &AuvSpec) -> (f64, f64) {
        let cost = self.policy.planner.hudson_cost();
        (a.sigma0.unwrap_or(cost.sigma0), a.eps0.unwrap_or(cost.eps0))
    }

    /// Validates everything and builds the mission (tracks read relative to `base_dir`).
    pub fn build(&self, file: &Path, base_dir: &Path) -> Result<Mission, ScenarioError> {
        self.validate(file)?;
        let planner = self.policy.planner.config(&self.platform, &self.facts(), 0.0);
        let tracks = self
            .auv
            .iter()
            .enumerate()
            .map(|(i, a)| Self::track(i, a, file, base_dir))
            .collect::<Result<Vec<_>, _>>()?;
        let data_start = tracks.iter().map(Track::start_time).fold(f64::NEG_INFINITY, f64::max);
        let data_end = tracks.iter().map(Track::end_time).fold(f64::INFINITY, f64::min);
        let start_time = self.mission.start_time.unwrap_or(data_start.max(0.0));
        let end_time = self.mission.end_time.unwrap_or(data_end);
        if !(start_time.is_finite() && end_time.is_finite() && start_time + planner.motion.tau <= end_time) {
            let value = format!("start_time {start_time} s, end_time {end_time} s");
            return Err(ScenarioError::invalid(
                file,
                "mission",
                value,
                format!("start_time + tau <= end_time (survey data covers {data_start}..{data_end} s)"),
            ));
        }
        let c = &self.cna;
        Ok(Mission {
            planner,
            cna: CnaPose {
                pos: Vec3::new(c.x, c.y, c.depth),
                heading: Heading::from(CompassDeg(c.heading_compass_deg)),
                pitch: c.pitch_deg.to_radians(),
            },
            names: self.auv.iter().map(|a| a.name.clone()).collect(),
            tracks,
            sigma0: self.auv.iter().map(|a| self.initial_errors(a).0).collect(),
            eps0: self.auv.iter().map(|a| self.initial_errors(a).1).collect(),
            start_time,
            end_time,
        })
    }

    /// AUV `i`'s track (CSV paths relative to `base_dir`).
    fn track(i: usize, a: &AuvSpec, file: &Path, base_dir: &Path) -> Result<Track, ScenarioError> {
        let track_err = |cause| ScenarioError::Track { file: file.to_path_buf(), index: i, cause };
        match (&a.lawnmower, &a.track_csv) {
            (Some(m), _) => m
                .to_lawnmower()
                .track(LAWNMOWER_DT)
                .map_err(|e| track_err(TrackLoadError::Track { path: PathBuf::from("<lawnmower>"), source: e })),
            (None, Some(path)) => load_track_csv(&base_dir.join(path)).map_err(track_err),
            (None, None) => Err(ScenarioError::invalid(
                file,
                format!("auv[{i}].lawnmower/track_csv"),
                "neither",
                "exactly one of [auv.lawnmower] or track_csv",
            )),
        }
    }
}
