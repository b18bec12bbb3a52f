//! Pre-deployment scenario files (TOML): the CNA start pose, the planner settings and each survey
//! AUV's a-priori track (a lawnmower description or a CSV file). Parsed with
//! `deny_unknown_fields` and validated before anything runs; errors name the file and the field.

use super::tracks::{load_track_csv, TrackLoadError};
use crate::scenario_file;
pub use crate::scenario_file::ScenarioError;
use coopnav_core::{CompassDeg, DepthProfile, Heading, Lawnmower, Track, Vec3};
use coopnav_plan::{
    CnaPose, DistanceLimits, ErrorModel, MotionConfig, PenaltyCase, PenaltyFn, PenaltyPair, PlannerConfig, SearchConfig,
};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The example scenario embedded in the binary.
pub const EXAMPLE: &str = include_str!("example.toml");

/// The whole file.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    pub cna: CnaStart,
    pub planner: PlannerSection,
    #[serde(default)]
    pub mission: MissionSection,
    pub auv: Vec<AuvSpec>,
}

/// CNA start pose (A12). Heading in compass degrees, as everywhere in files.
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

/// Planner settings (see `coopnav_plan::PlannerConfig`).
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannerSection {
    pub look_ahead: usize,
    pub penalty: PenaltySpec,
    pub motion: MotionConfig,
    #[serde(default)]
    pub error: ErrorModel,
    #[serde(default)]
    pub limits: DistanceLimits,
    /// Pre-deployment planning is offline: no deadline unless asked for, so runs are repeatable.
    #[serde(default = "offline_search")]
    pub search: SearchConfig,
}

fn offline_search() -> SearchConfig {
    SearchConfig { deadline: coopnav_plan::Deadline::None, ..SearchConfig::default() }
}

/// A Table 5.2 case, or a custom primary/look-ahead pair.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PenaltySpec {
    pub case: Option<String>,
    pub primary: Option<PenaltyFn>,
    pub look_ahead: Option<PenaltyFn>,
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
    /// Initial radial and tangential errors, m (Table 5.1: 1 m).
    #[serde(default = "one")]
    pub sigma0: f64,
    #[serde(default = "one")]
    pub eps0: f64,
    pub lawnmower: Option<LawnmowerSpec>,
    /// CSV with columns t,x,y,z (relative paths are relative to the scenario file).
    pub track_csv: Option<PathBuf>,
}

fn one() -> f64 {
    1.0
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

/// A validated, ready-to-run pre-deployment mission.
#[derive(Debug, Clone)]
pub struct Mission {
    pub planner: PlannerConfig,
    pub cna: CnaPose,
    pub names: Vec<String>,
    pub tracks: Vec<Track>,
    pub sigma0: Vec<f64>,
    pub eps0: Vec<f64>,
    pub start_time: f64,
    pub end_time: f64,
}

/// Sampling interval of generated lawnmower tracks, s (linear between samples, exact on lanes).
pub(crate) const LAWNMOWER_DT: f64 = 1.0;

impl Scenario {
    /// Parses TOML text and checks every field that needs no track file; `file` names it in
    /// messages.
    pub fn parse(text: &str, file: &Path) -> Result<Self, ScenarioError> {
        scenario_file::parse(text, file, Self::validate)
    }

    pub fn load(file: &Path) -> Result<Self, ScenarioError> {
        scenario_file::load(file, Self::validate)
    }

    /// Checks the planner settings, the CNA pose and each AUV's settings (the track files and the
    /// mission span they allow are checked by [`Scenario::build`]).
    pub fn validate(&self, file: &Path) -> Result<(), ScenarioError> {
        self.planner_config(file)?
            .validate()
            .map_err(|cause| ScenarioError::Planner { file: file.to_path_buf(), cause })?;
        let c = &self.cna;
        if ![c.x, c.y, c.depth, c.heading_compass_deg, c.pitch_deg].iter().all(|v| v.is_finite()) {
            let value = format!(
                "{{ x = {}, y = {}, depth = {}, heading_compass_deg = {}, pitch_deg = {} }}",
                c.x, c.y, c.depth, c.heading_compass_deg, c.pitch_deg
            );
            return Err(ScenarioError::invalid(
                file,
                "cna",
                value,
                "finite numbers for x, y, depth, heading_compass_deg and pitch_deg",
            ));
        }
        if self.auv.is_empty() {
            return Err(ScenarioError::invalid(file, "auv", "no [[auv]]", "at least one [[auv]]"));
        }
        for (i, a) in self.auv.iter().enumerate() {
            for (name, v) in [("sigma0", a.sigma0), ("eps0", a.eps0)] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(ScenarioError::invalid(file, format!("auv[{i}].{name}"), v.to_string(), "> 0 m"));
                }
            }
            Self::source(i, a, file)?;
        }
        Ok(())
    }

    /// Validates everything and builds the mission (tracks read relative to `base_dir`).
    pub fn build(&self, file: &Path, base_dir: &Path) -> Result<Mission, ScenarioError> {
        self.validate(file)?;
        let planner = self.planner_config(file)?;
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
            sigma0: self.auv.iter().map(|a| a.sigma0).collect(),
            eps0: self.auv.iter().map(|a| a.eps0).collect(),
            start_time,
            end_time,
        })
    }

    fn planner_config(&self, file: &Path) -> Result<PlannerConfig, ScenarioError> {
        let p = &self.planner;
        Ok(PlannerConfig {
            look_ahead: p.look_ahead,
            motion: p.motion,
            error: p.error,
            cost: coopnav_plan::CostSpec::Hudson,
            limits: p.limits,
            penalties: self.penalties(file)?,
            search: p.search,
        })
    }

    fn penalties(&self, file: &Path) -> Result<PenaltyPair, ScenarioError> {
        let p = &self.planner.penalty;
        match (&p.case, p.primary, p.look_ahead) {
            (Some(id), None, None) => PenaltyCase::from_id(id).map(PenaltyCase::penalties).ok_or_else(|| {
                let ids: Vec<&str> = PenaltyCase::ALL.iter().map(|c| c.id()).collect();
                ScenarioError::invalid(file, "planner.penalty.case", format!("'{id}'"), ids.join(", "))
            }),
            (None, Some(primary), Some(look_ahead)) => Ok(PenaltyPair { primary, look_ahead }),
            _ => Err(ScenarioError::invalid(
                file,
                "planner.penalty",
                given(p),
                "either case = \"<Table 5.2 case>\" or both primary and look_ahead",
            )),
        }
    }

    /// AUV `i`'s track source, checked: exactly one of a sound lawnmower or a track CSV.
    fn source<'a>(i: usize, a: &'a AuvSpec, file: &Path) -> Result<TrackSource<'a>, ScenarioError> {
        let invalid = |f: &str, value: String, allowed: &str| {
            ScenarioError::invalid(file, format!("auv[{i}].{f}"), value, allowed)
        };
        match (&a.lawnmower, &a.track_csv) {
            (Some(m), None) => {
                if !(m.speed.is_finite() && m.speed > 0.0) {
                    return Err(invalid("lawnmower.speed", m.speed.to_string(), "> 0 m/s"));
                }
                if !(m.lane_length.is_finite() && m.lane_length > 0.0) || m.lanes == 0 || !m.spacing.is_finite() {
                    let value = format!("lane_length {}, lanes {}, spacing {}", m.lane_length, m.lanes, m.spacing);
                    return Err(invalid("lawnmower", value, "lane_length > 0 m, lanes >= 1 and spacing finite"));
                }
                match m.depth {
                    DepthProfile::Sinusoid { period, .. } if period.is_nan() || period <= 0.0 => {
                        Err(invalid("lawnmower.depth.period", period.to_string(), "> 0 s"))
                    }
                    _ => Ok(TrackSource::Lawnmower(m)),
                }
            }
            (None, Some(path)) => Ok(TrackSource::Csv(path)),
            (lawnmower, _) => {
                let value = if lawnmower.is_some() { "both" } else { "neither" };
                Err(invalid("lawnmower/track_csv", value.into(), "exactly one of [auv.lawnmower] or track_csv"))
            }
        }
    }

    /// AUV `i`'s track (CSV paths relative to `base_dir`).
    fn track(i: usize, a: &AuvSpec, file: &Path, base_dir: &Path) -> Result<Track, ScenarioError> {
        let track_err = |cause| ScenarioError::Track { file: file.to_path_buf(), index: i, cause };
        match Self::source(i, a, file)? {
            TrackSource::Lawnmower(m) => m
                .to_lawnmower()
                .track(LAWNMOWER_DT)
                .map_err(|e| track_err(TrackLoadError::Track { path: PathBuf::from("<lawnmower>"), source: e })),
            TrackSource::Csv(path) => load_track_csv(&base_dir.join(path)).map_err(track_err),
        }
    }
}

/// Which of a penalty's keys a file gave, e.g. "case and primary".
fn given(p: &PenaltySpec) -> String {
    let keys: Vec<&str> =
        [("case", p.case.is_some()), ("primary", p.primary.is_some()), ("look_ahead", p.look_ahead.is_some())]
            .into_iter()
            .filter_map(|(k, set)| set.then_some(k))
            .collect();
    if keys.is_empty() {
        "none of case, primary, look_ahead".into()
    } else {
        keys.join(" and ")
    }
}

/// Where an AUV's a-priori track comes from.
enum TrackSource<'a> {
    Lawnmower(&'a LawnmowerSpec),
    Csv(&'a Path),
}
