//! Pre-deployment scenario files (TOML): the CNA start pose, the planner settings and each survey
//! AUV's a-priori track (a lawnmower description or a CSV file). Parsed with
//! `deny_unknown_fields` and validated before anything runs; errors name the file and the field.

use super::tracks::{load_track_csv, TrackLoadError};
use coopnav_core::{CompassDeg, DepthProfile, Heading, Lawnmower, Track, Vec3};
use coopnav_plan::{CnaPose, DistanceLimits, ErrorModel, MotionConfig, PenaltyCase, PenaltyFn, PenaltyPair, PlanError, PlannerConfig, SearchConfig};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The example scenario embedded in the binary.
pub const EXAMPLE: &str = include_str!("example.toml");

#[derive(Debug, Error)]
pub enum ScenarioError {
    #[error("cannot read scenario {file}: {source}")]
    Read { file: PathBuf, source: std::io::Error },
    #[error("scenario {file}: {message}")]
    Parse { file: PathBuf, message: String },
    #[error("scenario {file}: field {field}: {message}")]
    Invalid { file: PathBuf, field: String, message: String },
    #[error("scenario {file}: {source}")]
    Planner { file: PathBuf, source: PlanError },
    #[error("scenario {file}: auv[{index}] track: {source}")]
    Track { file: PathBuf, index: usize, source: TrackLoadError },
}

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
const LAWNMOWER_DT: f64 = 1.0;

impl Scenario {
    /// Parses TOML text; `file` is used in messages.
    pub fn parse(text: &str, file: &Path) -> Result<Self, ScenarioError> {
        toml::from_str(text).map_err(|e| ScenarioError::Parse { file: file.to_path_buf(), message: e.to_string() })
    }

    pub fn load(file: &Path) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(file).map_err(|source| ScenarioError::Read { file: file.to_path_buf(), source })?;
        Self::parse(&text, file)
    }

    /// Validates everything and builds the mission (tracks read relative to `base_dir`).
    pub fn build(&self, file: &Path, base_dir: &Path) -> Result<Mission, ScenarioError> {
        let invalid = |field: &str, message: String| ScenarioError::Invalid { file: file.to_path_buf(), field: field.into(), message };
        let planner = PlannerConfig {
            look_ahead: self.planner.look_ahead,
            motion: self.planner.motion,
            error: self.planner.error,
            limits: self.planner.limits,
            penalties: self.penalties().map_err(|m| invalid("planner.penalty", m))?,
            search: self.planner.search,
        };
        planner.validate().map_err(|source| ScenarioError::Planner { file: file.to_path_buf(), source })?;
        let c = &self.cna;
        if ![c.x, c.y, c.depth, c.heading_compass_deg, c.pitch_deg].iter().all(|v| v.is_finite()) {
            return Err(invalid("cna", "x, y, depth, heading_compass_deg and pitch_deg must be finite numbers".into()));
        }
        if self.auv.is_empty() {
            return Err(invalid("auv", "at least one [[auv]] is needed".into()));
        }
        let mut tracks = Vec::with_capacity(self.auv.len());
        for (i, a) in self.auv.iter().enumerate() {
            for (name, v) in [("sigma0", a.sigma0), ("eps0", a.eps0)] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(invalid(&format!("auv[{i}].{name}"), format!("must be > 0 m, got {v}")));
                }
            }
            tracks.push(self.track(i, a, file, base_dir)?);
        }
        let data_start = tracks.iter().map(Track::start_time).fold(f64::NEG_INFINITY, f64::max);
        let data_end = tracks.iter().map(Track::end_time).fold(f64::INFINITY, f64::min);
        let start_time = self.mission.start_time.unwrap_or(data_start.max(0.0));
        let end_time = self.mission.end_time.unwrap_or(data_end);
        if !(start_time.is_finite() && end_time.is_finite() && start_time + planner.motion.tau <= end_time) {
            return Err(invalid("mission", format!("start_time {start_time} s + tau must not pass end_time {end_time} s (survey data covers {data_start}..{data_end} s)")));
        }
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

    fn penalties(&self) -> Result<PenaltyPair, String> {
        let p = &self.planner.penalty;
        match (&p.case, p.primary, p.look_ahead) {
            (Some(id), None, None) => PenaltyCase::from_id(id).map(PenaltyCase::penalties).ok_or_else(|| {
                let ids: Vec<&str> = PenaltyCase::ALL.iter().map(|c| c.id()).collect();
                format!("unknown case '{id}'; allowed: {}", ids.join(", "))
            }),
            (None, Some(primary), Some(look_ahead)) => Ok(PenaltyPair { primary, look_ahead }),
            _ => Err("give either case = \"<Table 5.2 case>\" or both primary and look_ahead".into()),
        }
    }

    fn track(&self, i: usize, a: &AuvSpec, file: &Path, base_dir: &Path) -> Result<Track, ScenarioError> {
        let field = |f: &str| format!("auv[{i}].{f}");
        let invalid = |f: &str, message: String| ScenarioError::Invalid { file: file.to_path_buf(), field: field(f), message };
        let track_err = |source| ScenarioError::Track { file: file.to_path_buf(), index: i, source };
        match (&a.lawnmower, &a.track_csv) {
            (Some(m), None) => {
                if !(m.speed.is_finite() && m.speed > 0.0) {
                    return Err(invalid("lawnmower.speed", format!("must be > 0 m/s, got {}", m.speed)));
                }
                if !(m.lane_length.is_finite() && m.lane_length > 0.0) || m.lanes == 0 || !m.spacing.is_finite() {
                    return Err(invalid("lawnmower", "lane_length must be > 0 m, lanes >= 1 and spacing finite".into()));
                }
                if let DepthProfile::Sinusoid { period, .. } = m.depth {
                    if !(period > 0.0) {
                        return Err(invalid("lawnmower.depth.period", format!("must be > 0 s, got {period}")));
                    }
                }
                m.to_lawnmower().track(LAWNMOWER_DT).map_err(|e| track_err(TrackLoadError::Track { path: PathBuf::from("<lawnmower>"), source: e }))
            }
            (None, Some(path)) => load_track_csv(&base_dir.join(path)).map_err(track_err),
            _ => Err(invalid("lawnmower/track_csv", "give exactly one of [auv.lawnmower] or track_csv".into())),
        }
    }
}
