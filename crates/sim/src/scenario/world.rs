//! The closed-loop scenario file (TOML, `deny_unknown_fields`): the survey fleet and its
//! lawnmowers, the CNA, the acoustic link, sensors and filters, and the planner. Validated
//! before anything runs; every error names the file, the field and what is allowed.

use crate::models::buoy::{BuoySpec, MAX_BUOYS};
use crate::models::channel::Channel;
use crate::models::cna_navigation::CnaNavigation;
use crate::models::filter::{FilterRate, FilterSoundSpeed, FilterSpec};
use crate::models::finish::Finish;
pub use crate::models::health::Health;
use crate::models::minipacket;
use crate::models::mower::MowerSpec;
use crate::models::peer::{mask_width, StatusFormat, StatusTo};
use crate::models::schedule::{check_payload, longest_air, Fit, Owner, Schedule};
use crate::models::ship::{ShipSpec, MAX_SHIPS};
use crate::models::tl_spec::TlModel;
pub use crate::scenario::file::ScenarioError;
use crate::scenario::file::{self as scenario_file, overlay, Problem, Problems};
pub use crate::scenario::policies::{BeforeFirstReport, PlannerLink, Policies};
use crate::scenario::site::{self, PathSpec, Site};
use coopnav_acomms::node_report::{BODY_BITS, HEADER_BITS};
use coopnav_acomms::selector::AdaptiveConfig;
use coopnav_acomms::status::CovTrailer;
use coopnav_acomms::{Rate, Receiver, SuccessModel};
use coopnav_core::validation::CheckFields;
use coopnav_core::{Bathymetry, CompassDeg, DepthTarget, Heading, Iver2Params, Lawnmower, Rect, Shelf, SurveyPath};
use coopnav_nav::{AuvModel, AuvParams, RangeNoise};
use coopnav_plan::auto::{CnaFact, EstimatorSettings, MissionFacts};
use coopnav_plan::predict::PredictorConfig;
pub use coopnav_plan::spec::{CovarianceWord, EstimatorTracking, TruthChoice};
use coopnav_plan::{CnaKind, PlannerConfig, PlannerSpec, Platform};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The embedded default mission (`coopnav simulate` with no scenario, `--example`): the
/// library's `scenarios/default.toml`.
pub const EXAMPLE: &str = include_str!("../../../../scenarios/default.toml");

/// The closed-loop benchmark's mission: the library's `scenarios/bench-closed-loop.toml`.
pub const BENCH: &str = include_str!("../../../../scenarios/bench-closed-loop.toml");

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
    /// Transponder buoys (`[[buoys]]`): each broadcasts its position in its own slot.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub buoys: Vec<BuoySpec>,
    /// Ships on a fixed track (`[[ships]]`): each broadcasts its state as mini-packets.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ships: Vec<ShipSpec>,
    #[serde(default)]
    pub comms: Comms,
    /// The acoustic channel as the sea plays it (truth), apart from what `[filter]` assumes.
    #[serde(default)]
    pub channel: Channel,
    #[serde(default)]
    pub sensors: AuvSensors,
    /// The survey AUVs' filter: what it assumes (the truth is `[channel]` and `[sensors]`).
    #[serde(default = "default_filter", deserialize_with = "filter_over_default")]
    pub filter: FilterSpec,
    /// The CNA policies: what the CNA knows of the fleet, and each policy instance's own table
    /// (`[policy.planner]`, `[policy.planner-estimator]`, `[policy.zigzag]`, ...; [`Policies`]).
    /// Absent: every default, `planner-estimator`'s settings from the planner's rule for the mission.
    #[serde(default)]
    pub policy: Policies,
    #[serde(default)]
    pub health: Health,
    /// The site: geodetic origin and bathymetry (`scenario::site`). Written only when given.
    #[serde(default, skip_serializing_if = "Site::is_empty")]
    pub site: Site,
}

/// The survey AUVs' dead-reckoning sensors as they truly are (Gill 2013, §2.4.1 values by default).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AuvSensors {
    /// Speed-through-water noise SD, m/s.
    pub speed_sd: f64,
    /// Step SD of the compass-bias random walk over integer headings, deg.
    pub compass_bias_step_deg: f64,
    /// Independent per-degree bias values instead of a random walk.
    pub compass_bias_iid: bool,
    pub compass_white_deg: f64,
    pub yaw_rate_white_deg_s: f64,
}

impl Default for AuvSensors {
    fn default() -> Self {
        AuvSensors {
            speed_sd: 0.05,
            compass_bias_step_deg: 0.047,
            compass_bias_iid: false,
            compass_white_deg: 0.5,
            yaw_rate_white_deg_s: 0.05,
        }
    }
}

/// The closed loop's channel keeps 0.15 m range noise at zero range (σ_τ = 0.1 ms), not the nav
/// default matched to Gill's outlier mixture.
///
/// Position process noise: Gill's Table 3 Q_E = Q_N = 0.255448 m² was tuned per step of an
/// unknown Δt (docs/models.md#gill-coefficients); read per 0.1 s step it grows σ by 2.55 m²/s per
/// axis, far more than the true dead-reckoning drift, and the filters are conservative (NEES well
/// under its consistent value). A fifth of it, [`CLOSED_LOOP_Q_EN`], keeps the same true error with
/// a NEES nearer consistency; invented (docs/models.md#closed-loop-world), configurable as
/// `[filter] q`.
fn default_filter() -> FilterSpec {
    let thesis = AuvParams::default();
    let q = [CLOSED_LOOP_Q_EN, CLOSED_LOOP_Q_EN, thesis.q[2], thesis.q[3], thesis.q[4]];
    let params = AuvParams { range_noise: RangeNoise { sigma_time: 1e-4, ..RangeNoise::default() }, q, ..thesis };
    FilterSpec {
        model: AuvModel::Thesis,
        params,
        rate: FilterRate::EveryStep,
        sound_speed: FilterSoundSpeed::Constant {},
        adcp: None,
    }
}

/// Position process noise of the closed loop's filters, m² per 0.1 s step: a fifth of Gill's Table 3
/// value, chosen so the default mission's filters are near-consistent (see the scenario's default filter).
pub const CLOSED_LOOP_Q_EN: f64 = 0.2 * 0.255448;

/// A `[filter]` table overrides only the fields it names.
fn filter_over_default<'de, D: serde::Deserializer<'de>>(d: D) -> Result<FilterSpec, D::Error> {
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
    /// What a survey AUV does once its lawnmower is flown.
    #[serde(default)]
    pub finish: Finish,
    /// Each survey AUV's own block (one per AUV; empty: side by side from `origin`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lawnmowers: Vec<MowerSpec>,
    /// Each survey AUV's own waypoints instead of a lawnmower (one per AUV; `fleet.survey` imports
    /// them from `.bhv` or CSV files, `scenario::site`). With them the lawnmower keys above are
    /// unused and may be left out.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub paths: Vec<PathSpec>,
    /// The survey AUVs' IVER2 dynamics (Nams 2014, App. B; default `vehicle.m`'s constants), which
    /// the other vehicles' shadow estimates also fly. The model steps at the scenario's `dt`
    /// ([`Scenario::survey_dynamics`]): `timestep` here may restate it, never differ.
    #[serde(default)]
    pub vehicle: Iver2Params,
}

fn default_seafloor() -> f64 {
    100.0
}
fn one() -> f64 {
    1.0
}

/// The CNA: an autonomous surface craft, or (with `auv`) an AUV CNA that changes depth by pitch;
/// how it knows its own position, and so what position it broadcasts, is its `navigation` model
/// ([`CnaNavigation`]).
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
    /// How it navigates (default: GPS, [`CnaNavigation::default`]).
    #[serde(default)]
    pub navigation: CnaNavigation,
    /// An AUV CNA instead of an ASC.
    #[serde(default)]
    pub auv: Option<AuvCna>,
    /// The water current east and north (m/s) as the CNA's ADCP measures it: a fact a field team
    /// states (not the scenario's `fleet.current`, the truth), read by `planner-estimator`'s rule.
    /// Default [0, 0]: none measured. Written only when set.
    #[serde(default, skip_serializing_if = "coopnav_plan::estimator::is_still")]
    pub adcp_current: [f64; 2],
}

/// An AUV as the CNA (Hudson's AUV-CNA case: heading and pitch options): the vehicle; its
/// navigation is `cna.navigation` (an AUV has no GPS below the surface: `dead-reckoning`, or the
/// counterfactual `exact`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AuvCna {
    /// Pitch options B of the planner (≥ 1).
    pub pitch_options: usize,
    /// Cruise depth: where it starts and what every fixed-path policy holds.
    pub depth: CruiseDepth,
    /// The shallowest depth it works at, m: the planner's depth limit and the top of the cast's
    /// range (climbing for a GPS fix is not work). 0, the default, lets it work at the surface,
    /// where it has its GPS (`models::surfacing`) and is a surface craft in all but speed. Written
    /// only when not 0.
    #[serde(default, skip_serializing_if = "is_surface")]
    pub min_depth_m: f64,
}

fn is_surface(depth: &f64) -> bool {
    *depth == 0.0
}

/// An AUV CNA's cruise depth: metres, or `"cast"`, the fixed depth its CTD cast favours for the
/// fleet ([`Scenario::cna_cruise_depth`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "DepthWord", into = "DepthWord")]
pub enum CruiseDepth {
    Metres(f64),
    Cast,
}

/// How [`CruiseDepth`] is written in a scenario file.
#[derive(Serialize, Deserialize)]
#[serde(untagged)]
enum DepthWord {
    Metres(f64),
    Word(String),
}

const CAST_WORD: &str = "cast";

impl TryFrom<DepthWord> for CruiseDepth {
    type Error = String;
    fn try_from(w: DepthWord) -> Result<Self, String> {
        match w {
            DepthWord::Metres(z) => Ok(CruiseDepth::Metres(z)),
            DepthWord::Word(word) if word == CAST_WORD => Ok(CruiseDepth::Cast),
            DepthWord::Word(word) => Err(format!("`{word}`: expected a depth in metres or \"{CAST_WORD}\"")),
        }
    }
}

impl From<CruiseDepth> for DepthWord {
    fn from(d: CruiseDepth) -> Self {
        match d {
            CruiseDepth::Metres(z) => DepthWord::Metres(z),
            CruiseDepth::Cast => DepthWord::Word(CAST_WORD.into()),
        }
    }
}

/// The most survey AUVs a scenario may have: node-report source ids are 5 bits
/// (`coopnav_acomms::node_report`), and AUV k sends as id k + 1. Below it, the schedule check
/// (`comms.schedule`) says whether N fit in τ.
pub const MAX_SURVEY_AUVS: usize = 31;

/// Spacing of the track points `"cast"` weighs, m.
pub const CAST_SAMPLE_M: f64 = 25.0;

/// Points every `step` m along the polyline through `waypoints`, both ends included.
fn along(waypoints: &[(f64, f64)], step: f64) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = waypoints.first().copied().into_iter().collect();
    for w in waypoints.windows(2) {
        let (dx, dy) = (w[1].0 - w[0].0, w[1].1 - w[0].1);
        let n = ((dx.hypot(dy) / step).ceil() as usize).max(1);
        out.extend((1..=n).map(|i| (w[0].0 + dx * i as f64 / n as f64, w[0].1 + dy * i as f64 / n as f64)));
    }
    out
}

fn default_turn_rate() -> f64 {
    4.0
}

/// The acoustic link: the TDMA schedule over one period τ, fixed WHOI rates per direction (or the
/// adaptive selector for the status messages), analytic TL and the Table 4/5 success engine.
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
    /// Transmission loss as the sea plays it (a named model; without `kind`, analytic).
    #[serde(deserialize_with = "crate::models::tl_spec::kind_defaults_to_analytic")]
    pub tl: TlModel,
    pub success: SuccessModel,
    /// Who transmits when within each cycle of τ.
    pub schedule: Schedule,
    /// Idle time a slot keeps after its packet's air time and longest travel time, s.
    pub slot_guard_s: f64,
    /// Longest range a slot must allow the packet to travel, m.
    pub max_range_m: f64,
    /// Air time of a 13-bit mini-packet, s (see [`minipacket::DEFAULT_AIR_S`]).
    pub mini_packet_air_s: f64,
    /// Who a survey AUV's status is addressed to (`cna` or `cna_and_auvs`).
    pub status_to: StatusTo,
    /// The survey AUVs' modems receiving each other's statuses (Table 5's partial-drop column).
    pub peer_receiver: Receiver,
    /// What a status carries (`{ kind = "node_report" }` or Nams's `{ kind = "nams_frame0", … }`).
    pub status_format: StatusFormat,
}

impl Default for Comms {
    fn default() -> Self {
        Comms {
            tau: 30.0,
            cna_rate: Rate::R0,
            status_rate: Rate::R0,
            status_adaptive: None,
            tl: TlModel::default(),
            success: SuccessModel::default(),
            schedule: Schedule::default(),
            slot_guard_s: 0.1,
            max_range_m: 1000.0,
            mini_packet_air_s: minipacket::DEFAULT_AIR_S,
            status_to: StatusTo::default(),
            peer_receiver: Receiver::Iver2,
            status_format: StatusFormat::default(),
        }
    }
}

/// The fleet's lawnmower keys a file with `fleet.paths` may leave out: the embedded example's.
fn lawnmower_keys() -> toml::Value {
    let example: toml::Table = EXAMPLE.parse().expect("the embedded example scenario parses");
    let fleet = example["fleet"].as_table().expect("the example has a fleet table");
    let keys = ["origin", "lane_heading_compass_deg", "lane_length", "lane_spacing", "lanes", "block_offset"];
    toml::Value::Table(
        fleet.iter().filter(|(k, _)| keys.contains(&k.as_str())).map(|(k, v)| (k.clone(), v.clone())).collect(),
    )
}

impl Scenario {
    pub fn example() -> Self {
        toml::from_str(EXAMPLE).expect("the embedded example scenario parses")
    }

    /// Parses and validates TOML text; `file` names it in messages, and relative file names in
    /// it (`site.bathymetry.file`, `fleet.survey.files`) are relative to its directory.
    pub fn parse(text: &str, file: &Path) -> Result<Self, ScenarioError> {
        let scenario = Self::read(text, file)?;
        scenario.validate(file)?;
        Ok(scenario)
    }

    /// [`Scenario::parse`] without the validation (for callers that check sizes first).
    pub fn read(text: &str, file: &Path) -> Result<Self, ScenarioError> {
        use crate::scenario::moved::{refuse_old_form, CNA_NAVIGATION, SIMULATE};
        refuse_old_form(text, file, &[&SIMULATE, &CNA_NAVIGATION])?;
        match site::resolved(text, file, &lawnmower_keys())? {
            Some(tree) => scenario_file::parse_tree(tree, file, |_, _| Ok(())),
            None => scenario_file::parse(text, file, |_, _| Ok(())),
        }
    }

    pub fn load(file: &Path) -> Result<Self, ScenarioError> {
        Self::parse(&scenario_file::read_scenario_text(file, false)?, file)
    }

    /// The survey AUVs' IVER2 constants with the model stepping at the engine's `dt`: the truth
    /// moves one `dt` per engine step whatever `fleet.vehicle.timestep` held, so that every step
    /// the validator accepts gives the same physics.
    pub fn survey_dynamics(&self) -> Iver2Params {
        Iver2Params { timestep: self.dt, ..self.fleet.vehicle }
    }

    /// Checks every field against its allowed range and reports every bad one at once.
    pub fn validate(&self, file: &Path) -> Result<(), ScenarioError> {
        let mut p = Problems::new(file);
        // The error is sampled every second: a shorter mission has nothing to report.
        p.check(
            "duration_s",
            self.duration_s,
            |v| v >= 1.0,
            "a finite number >= 1 s (the error is sampled every second)",
        );
        p.check("dt", self.dt, |v| v > 0.0 && v <= 1.0, "0 < dt <= 1 s");
        // The survey AUVs' IVER2 model steps at dt (`survey_dynamics`); its own step key may
        // restate dt or keep its default, never name another step.
        let vehicle_step = self.fleet.vehicle.timestep;
        if vehicle_step != self.dt && vehicle_step != Iver2Params::default().timestep {
            let allowed = format!("the scenario's dt ({} s), or leave it out: the survey AUVs step at dt", self.dt);
            p.push("fleet.vehicle.timestep", vehicle_step.to_string(), allowed);
        }
        self.validate_fleet(&mut p);
        self.validate_cna(&mut p);
        self.validate_buoys(&mut p);
        self.validate_ships(&mut p);
        self.validate_comms(&mut p);
        self.validate_sensors(&mut p);
        self.filter.check_fields("filter.", &mut p);
        self.filter.rate.check_fields("filter.", self.dt, &mut p);
        p.check("health.divergence_window_s", self.health.divergence_window_s, |v| v > 0.0, "a finite number > 0");
        self.validate_policies(&mut p);
        if p.is_empty() && !matches!(self.comms.tl, TlModel::Analytic(_)) {
            // The BELLHOP kinds need the program, and a grid is computed (or read from the disk
            // cache) here, once, so that a run never finds it missing.
            if let Err(e) = self.tl_provider() {
                p.push(
                    "comms.tl",
                    e.to_string(),
                    "BELLHOP installed (scripts/install-bellhop.sh) and a grid it can compute",
                );
            }
        }
        p.finish()
    }

    fn validate_fleet(&self, p: &mut Problems) {
        let f = &self.fleet;
        if !(1..=MAX_SURVEY_AUVS).contains(&f.n_auvs) {
            p.push(
                "fleet.n_auvs",
                f.n_auvs.to_string(),
                format!("1..={MAX_SURVEY_AUVS} (the status message's 5-bit source id; the schedule must fit them too)"),
            );
        }
        p.positive("fleet.lane_length", f.lane_length);
        p.positive("fleet.lane_spacing", f.lane_spacing);
        if f.lanes == 0 {
            p.push("fleet.lanes", "0", ">= 1");
        }
        p.non_negative("fleet.block_offset", f.block_offset);
        p.check("fleet.lane_heading_compass_deg", f.lane_heading_compass_deg, |_| true, "a finite number");
        p.check("fleet.speed", f.speed, |v| v > 0.0 && v <= 3.0, "0 < speed <= 3 m/s");
        p.positive("fleet.seafloor_depth", f.seafloor_depth);
        if self.site.bathymetry.is_some() {
            self.validate_site(p);
        } else {
            match f.depth {
                DepthTarget::Depth { depth } => p.check(
                    "fleet.depth.depth",
                    depth,
                    |v| v >= 0.0 && v < f.seafloor_depth,
                    "0 <= depth < fleet.seafloor_depth",
                ),
                DepthTarget::Altitude { altitude } => p.check(
                    "fleet.depth.altitude",
                    altitude,
                    |v| v > 0.0 && v < f.seafloor_depth,
                    "0 < altitude < fleet.seafloor_depth",
                ),
            }
        }
        if let Some(shelf) = &f.shelf {
            if let Err(e) = Bathymetry::shelf(shelf) {
                p.push("fleet.shelf", e.to_string(), "a valid shelf (extent, spacing, depths > 0)");
            }
            let shallowest = shelf.shallow.min(shelf.deep);
            let clear = match f.depth {
                DepthTarget::Depth { depth } => depth < shallowest,
                DepthTarget::Altitude { altitude } => altitude < shallowest,
            };
            if !clear {
                p.push("fleet.depth", format!("{:?}", f.depth), "shallower than the shelf's shallowest water");
            }
        }
        if !(f.current.0.is_finite() && f.current.1.is_finite() && f.current.0.hypot(f.current.1) < f.speed) {
            p.push("fleet.current", format!("{:?}", f.current), "finite, slower than fleet.speed");
        }
        p.non_negative("fleet.init_position_sd", f.init_position_sd);
        f.finish.check_fields("fleet.finish.", p);
        f.vehicle.check_fields("fleet.vehicle.", p);
        if !(f.lawnmowers.is_empty() || f.lawnmowers.len() == f.n_auvs) {
            p.push("fleet.lawnmowers", format!("{} entries", f.lawnmowers.len()), "none, or one per survey AUV");
        }
        for (k, m) in f.lawnmowers.iter().enumerate() {
            m.check_fields(&format!("fleet.lawnmowers[{k}]."), p);
        }
        if !f.paths.is_empty() {
            if f.paths.len() != f.n_auvs {
                p.push("fleet.paths", format!("{} entries", f.paths.len()), "one per survey AUV");
            }
            if !f.lawnmowers.is_empty() {
                p.push("fleet.lawnmowers", "given with fleet.paths", "one of fleet.lawnmowers, fleet.paths");
            }
        }
        for (k, path) in f.paths.iter().enumerate() {
            if path.waypoints.is_empty() {
                p.push(format!("fleet.paths[{k}].waypoints"), "none", "at least one waypoint");
            }
            if let Some((i, w)) = path.waypoints.iter().enumerate().find(|(_, w)| !(w.0.is_finite() && w.1.is_finite()))
            {
                p.push(format!("fleet.paths[{k}].waypoints[{i}]"), format!("{w:?}"), "finite metres");
            }
        }
        for (field, v) in [("fleet.origin[0]", f.origin.0), ("fleet.origin[1]", f.origin.1)] {
            p.check(field, v, |v| v.abs() < 10_000.0, "within ±10 000 m (status message range ±16 000 m)");
        }
        // Every survey waypoint must fit the status message's ±16 000 m fields (with room for drift).
        let extent = (0..f.n_auvs.min(MAX_SURVEY_AUVS))
            .flat_map(|k| self.lawnmower(k).waypoints())
            .map(|(x, y)| x.abs().max(y.abs()))
            .fold(0.0, f64::max);
        if !(extent < 15_000.0) {
            p.push(
                "fleet",
                format!("survey reaching {extent:.0} m from the origin"),
                "every lawnmower within ±15 000 m (status message fields are ±16 000 m)",
            );
        }
    }

    /// A site grid: valid, alone (no shelf), under every survey waypoint, and deep enough along
    /// each survey path for the fleet's depth or altitude.
    fn validate_site(&self, p: &mut Problems) {
        let f = &self.fleet;
        let Some(b) = &self.site.bathymetry else { return };
        if let Err(e) = b.grid.check() {
            p.push("site.bathymetry.grid", e.to_string(), "a valid grid");
            return;
        }
        if f.shelf.is_some() {
            p.push("fleet.shelf", "given with site.bathymetry", "one seafloor: fleet.shelf or site.bathymetry");
        }
        let ((x0, y0), (x1, y1)) = b.grid.bounds();
        for k in 0..f.n_auvs.min(MAX_SURVEY_AUVS) {
            let wps = self.lawnmower(k).waypoints();
            if let Some(w) = wps.iter().find(|w| !(x0..=x1).contains(&w.0) || !(y0..=y1).contains(&w.1)) {
                p.push(
                    format!("site.bathymetry (survey AUV {k})"),
                    format!("waypoint ({:.1}, {:.1}) m", w.0, w.1),
                    format!("inside the grid {} ({x0:.0}..{x1:.0} m east, {y0:.0}..{y1:.0} m north)", b.source),
                );
                continue;
            }
            let shallowest = along(&wps, CAST_SAMPLE_M)
                .into_iter()
                .map(|(x, y)| (b.grid.depth_at(x, y), (x, y)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            let Some((water, at)) = shallowest else { continue };
            let (ok, what) = match f.depth {
                DepthTarget::Depth { depth } => (depth >= 0.0 && depth < water, format!("depth {depth} m")),
                DepthTarget::Altitude { altitude } => {
                    (altitude > 0.0 && altitude < water, format!("altitude {altitude} m"))
                }
            };
            if !ok {
                p.push(
                    "fleet.depth",
                    format!("{what} for survey AUV {k}"),
                    format!("within the water along its path ({water:.1} m deep at ({:.0}, {:.0}) m)", at.0, at.1),
                );
            }
        }
    }

    fn validate_cna(&self, p: &mut Problems) {
        let c = &self.cna;
        for (field, v) in [("cna.x", c.x), ("cna.y", c.y)] {
            p.check(field, v, |v| v.abs() < 10_000.0, "within ±10 000 m (status message range ±16 000 m)");
        }
        p.check("cna.heading_compass_deg", c.heading_compass_deg, |_| true, "a finite number");
        p.positive("cna.speed", c.speed);
        p.positive("cna.max_turn_rate_deg_s", c.max_turn_rate_deg_s);
        c.navigation.check_fields("cna.navigation.", p);
        if c.auv.is_some() && c.navigation.is_gps() {
            p.push(
                "cna.navigation.kind",
                "\"gps\" with cna.auv",
                "\"dead-reckoning\" or \"exact\" for an AUV CNA (no GPS below the surface; it takes its fixes by \
                 navigation.surfacing)",
            );
        }
        if let Some(a) = &c.auv {
            if a.pitch_options == 0 {
                p.push("cna.auv.pitch_options", "0", ">= 1");
            }
            if let CruiseDepth::Metres(z) = a.depth {
                p.check(
                    "cna.auv.depth",
                    z,
                    |v| (0.0..100.0).contains(&v),
                    "0 <= depth < 100 m (the planner's AUV-CNA depth limits), or \"cast\"",
                );
            }
            p.check("cna.auv.min_depth_m", a.min_depth_m, |v| (0.0..100.0).contains(&v), "0 <= min_depth_m < 100 m");
            if let CruiseDepth::Metres(z) = a.depth {
                if z < a.min_depth_m {
                    p.push("cna.auv.depth", z.to_string(), format!(">= cna.auv.min_depth_m ({} m)", a.min_depth_m));
                }
            }
        }
    }

    fn validate_buoys(&self, p: &mut Problems) {
        if self.buoys.len() > MAX_BUOYS {
            p.push("buoys", format!("{} buoys", self.buoys.len()), format!("at most {MAX_BUOYS}"));
        }
        // A buoy's broadcast is a position report.
        let report_bytes = (HEADER_BITS + BODY_BITS).div_ceil(8) as usize;
        for (i, b) in self.buoys.iter().enumerate() {
            b.check_fields(&format!("buoys[{i}]."), p);
            check_payload(&format!("buoys[{i}].rate"), b.rate, report_bytes, p);
            b.filter.check_fields(&format!("buoys[{i}].filter."), p);
        }
    }

    fn validate_ships(&self, p: &mut Problems) {
        if self.ships.len() > MAX_SHIPS {
            p.push("ships", format!("{} ships", self.ships.len()), format!("at most {MAX_SHIPS}"));
        }
        for (i, ship) in self.ships.iter().enumerate() {
            ship.check_fields(&format!("ships[{i}]."), p);
            ship.filter.check_fields(&format!("ships[{i}].filter."), p);
        }
    }

    fn validate_comms(&self, p: &mut Problems) {
        let c = &self.comms;
        p.check("comms.tau", c.tau, |v| (5.0..=600.0).contains(&v), "5..=600 s");
        if self.dt > c.tau {
            p.push("dt", self.dt.to_string(), "<= comms.tau");
        }
        for (field, rate) in [("comms.cna_rate", c.cna_rate), ("comms.status_rate", c.status_rate)] {
            if rate.spec().deprecated {
                p.push(field, rate.to_string(), "0, 1, 4 or 5 (rates 2 and 3 are deprecated)");
            }
        }
        let status_rates: Vec<Rate> = match &c.status_adaptive {
            Some(a) => {
                a.check_fields("comms.status_adaptive.", p);
                Rate::usable().to_vec()
            }
            None => vec![c.status_rate],
        };
        // The status message (node report and covariance trailer), and the CNA's broadcast: its
        // position report with one ack bit per AUV.
        let report_bytes = (HEADER_BITS + BODY_BITS).div_ceil(8) as usize;
        let status_bytes = match c.status_format {
            StatusFormat::NodeReport => report_bytes + CovTrailer::BYTES,
            // Nams's status and its (possibly empty) header in frame 0.
            StatusFormat::NamsFrame0 { estimator } => {
                let rates = (0..self.fleet.n_auvs)
                    .filter_map(|k| c.schedule.status_policy(k).and_then(|s| s.rates().ok()))
                    .chain([status_rates.clone()]);
                let widest = rates.map(|r| mask_width(&r)).max_by_key(|w| w.entry_bits());
                StatusFormat::nams_frame0_bytes(estimator, widest.unwrap_or(coopnav_acomms::tracker::MaskWidth::Narrow))
            }
        };
        if let StatusFormat::NamsFrame0 { .. } = c.status_format {
            for rate in &status_rates {
                if status_bytes > rate.spec().frame_bytes {
                    p.push("comms.status_format", format!("rate {rate}"), "a rate whose frame 0 holds the Nams status");
                }
            }
        }
        let broadcast_bytes = report_bytes + self.fleet.n_auvs.div_ceil(8);
        check_payload("comms.cna_rate", c.cna_rate, broadcast_bytes, p);
        for rate in &status_rates {
            check_payload("comms.status_rate", *rate, status_bytes, p);
        }
        c.tl.check_fields("comms.tl.", p);
        p.non_negative("comms.slot_guard_s", c.slot_guard_s);
        p.positive("comms.max_range_m", c.max_range_m);
        p.check("comms.mini_packet_air_s", c.mini_packet_air_s, |v| v > 0.0 && v <= 10.0, "0 < air time <= 10 s");
        self.channel.range_error.check_fields("channel.range_error.", p);
        self.channel.sound_speed.check_fields("channel.sound_speed.", p);
        self.channel.clocks.check_fields("channel.clocks.", p);
        self.channel.collisions.check_fields("channel.collisions.", p);
        if p.is_empty() {
            let fit = Fit {
                tau: c.tau,
                n_auvs: self.fleet.n_auvs,
                n_buoys: self.buoys.len(),
                n_ships: self.ships.len(),
                cna_air_s: longest_air([c.cna_rate]),
                buoy_air_s: longest_air(self.buoys.iter().map(|b| b.rate)),
                status_air_s: longest_air(status_rates),
                mini_air_s: c.mini_packet_air_s,
                status_bytes,
                travel_s: c.max_range_m / self.channel.sound_speed.slowest(),
                guard_s: c.slot_guard_s,
            };
            c.schedule.check_fields("comms.schedule.", &fit, p);
        }
    }

    fn validate_sensors(&self, p: &mut Problems) {
        let s = &self.sensors;
        p.non_negative("sensors.speed_sd", s.speed_sd);
        p.check("sensors.compass_bias_step_deg", s.compass_bias_step_deg, |v| (0.0..=10.0).contains(&v), "0..=10 deg");
        p.check("sensors.compass_white_deg", s.compass_white_deg, |v| (0.0..=30.0).contains(&v), "0..=30 deg");
        p.check("sensors.yaw_rate_white_deg_s", s.yaw_rate_white_deg_s, |v| (0.0..=10.0).contains(&v), "0..=10 deg/s");
    }

    /// The policies' tables: the baselines' fields, and each planner instance's spec on this
    /// mission's platform and facts, every field named by its path in the file
    /// (`policy.planner-estimator.tree.look_ahead`; the vehicle's facts by their own tables).
    fn validate_policies(&self, p: &mut Problems) {
        let pol = &self.policy;
        pol.check_baselines(self.fleet.n_auvs, p);
        let [east, north] = self.cna.adcp_current;
        p.finite("cna.adcp_current[0]", east);
        p.finite("cna.adcp_current[1]", north);
        let (platform, facts) = (self.platform(), self.mission_facts());
        let mut found: Vec<Problem> = Vec::new();
        for (name, spec) in self.planner_specs() {
            let mut own = coopnav_core::validation::Problems::new();
            spec.check(&platform, &facts, self.survey_extent_m(spec), &format!("policy.{name}."), &mut own);
            for bad in own.finish().err().into_iter().flat_map(|f| f.0) {
                let field = platform_field(&bad.field);
                if !found.iter().any(|f| f.field == field) {
                    found.push(Problem { field, ..bad });
                }
            }
        }
        found.into_iter().for_each(|bad| p.push(bad.field, bad.value, bad.allowed));
        if pol.open_loop.estimator_cost().is_some() {
            p.push(
                "policy.open-loop.cost.kind",
                "estimator",
                "\"hudson\" (the pre-deployment plan is made on the nominal tracks, with no filter to read)",
            );
        }
        if pol.link == PlannerLink::ScenarioChannel && self.comms.tl == TlModel::Bellhop {
            // A direct BELLHOP run per sampled distance and bearing would take hours.
            p.push("policy.link", "scenario_channel", "\"assumed\", or comms.tl of kind analytic or bellhop_grid");
        }
    }

    /// Every planner instance by its policy name.
    pub fn planner_specs(&self) -> [(&'static str, &PlannerSpec); 3] {
        let pol = &self.policy;
        [("planner", &pol.planner), ("planner-estimator", &pol.planner_estimator), ("open-loop", &pol.open_loop)]
    }

    /// The survey's extent for `spec`'s penalty choice, m: the diagonal of the box around every
    /// AUV's plan with the estimator cost (`PlannerSpec::config`), 0 under Hudson's (unused).
    fn survey_extent_m(&self, spec: &PlannerSpec) -> f64 {
        if spec.estimator_cost().is_none() {
            return 0.0;
        }
        self.survey_area().diagonal()
    }

    /// The seafloor: the site's grid if given, else the shelf if given, else a flat bottom at
    /// `seafloor_depth`.
    pub fn bathymetry(&self) -> Bathymetry {
        if let Some(b) = &self.site.bathymetry {
            return b.grid.clone();
        }
        let flat =
            || Bathymetry::new(-20_000.0, -20_000.0, 40_000.0, 40_000.0, 2, 2, vec![self.fleet.seafloor_depth; 4]);
        let grid = match &self.fleet.shelf {
            Some(shelf) => Bathymetry::shelf(shelf),
            None => flat(),
        };
        grid.or_else(|_| flat()).expect("validated scenarios always give a grid")
    }

    /// The CNA's cruise depth, m: 0 for an ASC, `cna.auv.depth` for an AUV, with `"cast"` the
    /// depth in the planner's limits that [`SoundSpeed::least_biased_depth`] picks for the survey
    /// plan's AUV depths (sampled every [`CAST_SAMPLE_M`] along each lawnmower) at the speeds the
    /// filters convert at (`filter.sound_speed`).
    ///
    /// [`SoundSpeed::least_biased_depth`]: crate::models::channel::SoundSpeed::least_biased_depth
    /// Per survey AUV, the slant range beyond which the CNA's broadcast is still arriving when
    /// the AUV's own next slot starts (half-duplex: it hears nothing while it sends), m: the
    /// slowest sound speed of the water times the time from the broadcast's end to that slot;
    /// infinite for an AUV with no slot of its own (the thesis's schedule gives each one).
    pub fn slot_reach_m(&self) -> Vec<f64> {
        let c = &self.comms;
        let slots = c.schedule.slots(c.tau, self.fleet.n_auvs, self.buoys.len());
        let Some(cna) = slots.iter().find(|s| s.owner == Owner::Cna) else {
            return vec![f64::INFINITY; self.fleet.n_auvs];
        };
        let (air, speed) = (longest_air([c.cna_rate]), self.channel.sound_speed.slowest());
        (0..self.fleet.n_auvs)
            .map(|k| {
                let own = slots.iter().filter(|s| s.owner == Owner::Auv(k));
                // Time from the broadcast's start to the AUV's next own slot, in [0, τ) (0: it
                // sends with the broadcast and hears none).
                let gap = own.map(|s| (s.start_s - cna.start_s).rem_euclid(c.tau)).min_by(f64::total_cmp);
                gap.map_or(f64::INFINITY, |g| ((g - air) * speed).max(0.0))
            })
            .collect()
    }

    pub fn cna_cruise_depth(&self) -> f64 {
        match self.cna.auv.as_ref().map(|a| a.depth) {
            None => 0.0,
            Some(CruiseDepth::Metres(z)) => z,
            Some(CruiseDepth::Cast) => {
                let limits = match self.platform().cna {
                    CnaKind::Auv { min_depth, max_depth, .. } => (min_depth, max_depth),
                    CnaKind::Asc {} => (0.0, 0.0),
                };
                let bathy = self.bathymetry();
                let depths: Vec<f64> = (0..self.fleet.n_auvs)
                    .flat_map(|k| along(&self.lawnmower(k).waypoints(), CAST_SAMPLE_M))
                    .map(|(x, y)| self.fleet.depth.depth_over(bathy.depth_at(x, y)))
                    .collect();
                let filters = self.filter.range_speed(&self.channel.sound_speed).conversion();
                self.channel.sound_speed.least_biased_depth(&filters, &depths, limits)
            }
        }
    }

    /// The CNA as a vehicle: its speed and turn limit, the decision period τ, an ASC or an
    /// AUV CNA with its pitch options and shallowest working depth.
    pub fn platform(&self) -> Platform {
        Platform {
            speed: self.cna.speed,
            tau: self.comms.tau,
            max_turn_rate_deg_s: self.cna.max_turn_rate_deg_s,
            cna: self.cna.auv.as_ref().map_or(CnaKind::Asc {}, |a| {
                let mut kind = CnaKind::auv(a.pitch_options);
                if let CnaKind::Auv { min_depth, .. } = &mut kind {
                    *min_depth = a.min_depth_m;
                }
                kind
            }),
        }
    }

    /// Hudson's planner's configuration for this scenario (`[policy.planner]`).
    pub fn planner_config(&self) -> PlannerConfig {
        self.spec_config(&self.policy.planner)
    }

    /// The search configuration `spec` gives on this mission (the cost left as Hudson's:
    /// `PlannerSpec::config`).
    pub fn spec_config(&self, spec: &PlannerSpec) -> PlannerConfig {
        spec.config(&self.platform(), &self.mission_facts(), self.survey_extent_m(spec))
    }

    /// The facts of this mission the planner's rule reads (coopnav_plan `auto`): N, the CNA's
    /// kind and navigation diffusion, the current its ADCP measures, the filters' model.
    pub fn mission_facts(&self) -> MissionFacts {
        MissionFacts {
            n_auvs: self.fleet.n_auvs,
            cna: self
                .cna
                .auv
                .as_ref()
                .map_or(CnaFact::Asc, |_| CnaFact::Auv { nav_diffusion_m2_s: self.cna.navigation.diffusion_m2_s() }),
            adcp_current: self.cna.adcp_current,
            filters_estimate_current: matches!(self.filter.model, AuvModel::Current(_)),
        }
    }

    /// `planner-estimator`'s settings: the rule's for this mission ([`Scenario::mission_facts`],
    /// coopnav_plan `auto::for_mission`), each replaced by the key its table sets. None when its
    /// table names Hudson's cost.
    pub fn estimator_settings(&self) -> Option<EstimatorSettings> {
        self.policy.planner_estimator.estimator_settings(&self.mission_facts())
    }

    /// What each planner instance flies on this mission, as the manifest records it: its search
    /// configuration (tree, motion, penalties, limits, search; the estimator cost's parameters
    /// are the settings beside it) and, with the estimator cost, the settings its table and the
    /// rule chose (`auto::for_mission`).
    pub fn resolved_planners(&self) -> serde_json::Value {
        let planners = self.planner_specs().map(|(name, spec)| {
            let settings = spec.estimator_settings(&self.mission_facts());
            (name, serde_json::json!({ "config": self.spec_config(spec), "estimator_settings": settings }))
        });
        serde_json::Value::Object(planners.into_iter().map(|(k, v)| (k.to_string(), v)).collect())
    }

    pub fn predictor_config(&self) -> PredictorConfig {
        self.policy.predictor
    }

    /// The bounding box of every AUV's survey path.
    pub fn survey_area(&self) -> Rect {
        Rect::around((0..self.fleet.n_auvs).flat_map(|k| self.lawnmower(k).waypoints()))
    }

    /// The survey path of survey AUV `k`: its `fleet.paths` entry if given, else its lawnmower.
    pub fn lawnmower(&self, k: usize) -> SurveyPath {
        let f = &self.fleet;
        let depth = coopnav_core::DepthProfile::Constant {
            depth: match f.depth {
                DepthTarget::Depth { depth } => depth,
                DepthTarget::Altitude { altitude } => f.seafloor_depth - altitude,
            },
        };
        if let Some(p) = f.paths.get(k) {
            return SurveyPath { waypoints: p.waypoints.clone(), speed: f.speed, depth };
        }
        let heading = Heading::from(CompassDeg(f.lane_heading_compass_deg));
        let (ux, uy) = heading.unit();
        let off = k as f64 * f.block_offset;
        let (origin, lane_heading, spacing) = match f.lawnmowers.get(k) {
            Some(m) => (m.origin, Heading::from(CompassDeg(m.lane_heading_compass_deg)), m.spacing(f.lane_spacing)),
            None => ((f.origin.0 + uy * off, f.origin.1 - ux * off), heading, -f.lane_spacing),
        };
        Lawnmower { origin, lane_heading, lane_length: f.lane_length, spacing, lanes: f.lanes, speed: f.speed, depth }
            .into()
    }

    /// The closed-loop benchmark's mission (`coopnav bench closed-loop`), [`BENCH`].
    pub fn bench() -> Self {
        Scenario::parse(BENCH, Path::new("scenarios/bench-closed-loop.toml"))
            .expect("the embedded bench mission is valid")
    }

    /// Copy with N survey AUVs (experiments sweep N).
    pub fn with_auvs(&self, n: usize) -> Self {
        let mut s = self.clone();
        s.fleet.n_auvs = n;
        s
    }
}

/// Where this file states a planner's platform setting (`Scenario::platform` takes them from the
/// CNA and comms tables); every other field is the spec's own, already named by its path.
fn platform_field(field: &str) -> String {
    let file_name = match field {
        "platform.speed" => "cna.speed",
        "platform.tau" => "comms.tau",
        "platform.max_turn_rate_deg_s" => "cna.max_turn_rate_deg_s",
        "platform.cna.pitch_options" => "cna.auv.pitch_options",
        other => return other.to_string(),
    };
    file_name.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::schedule::SlotSpec;
    use coopnav_plan::PenaltyCase;

    fn err(text: &str) -> String {
        Scenario::parse(text, Path::new("s.toml")).unwrap_err().to_string()
    }

    #[test]
    fn example_is_valid_and_the_default_mission() {
        let s = Scenario::parse(EXAMPLE, Path::new("example.toml")).unwrap();
        assert_eq!((s.fleet.n_auvs, s.seed, s.duration_s), (3, 1, 3600.0));
        let hudson = s.planner_config();
        assert_eq!((hudson.motion.heading_options, hudson.look_ahead), (5, 5));
        Scenario::bench().validate(Path::new("bench")).unwrap();
        // The commented-out options of the example are valid too.
        // The AUV CNA's lines replace the ASC's navigation.
        let options = EXAMPLE
            .replace("# status_adaptive", "status_adaptive")
            .replace("# shelf", "shelf")
            .replace("navigation = { kind = \"gps\", sd_m = 1.0 }\n", "")
            .replace("# navigation", "navigation")
            .replace("# auv", "auv");
        let s = Scenario::parse(&options, Path::new("options.toml")).unwrap();
        assert!(s.comms.status_adaptive.is_some() && s.fleet.shelf.is_some() && s.cna.auv.is_some());
        assert!(s.cna.navigation.surfacing().is_some() && s.cna.navigation.diffusion_m2_s() == 0.01);
        let survey_s = Scenario::bench().lawnmower(0).path_length() / 1.5;
        assert!(survey_s >= 3.0 * 3600.0 * 0.95, "bench survey lasts {survey_s} s");
    }

    /// A `[filter]` table changes only what it names: the closed loop's 0.1 ms timing noise
    /// survives it, and a misspelt key is still refused.
    #[test]
    fn partial_filter_tables_keep_the_closed_loop_channel() {
        let plain = Scenario::parse(EXAMPLE, Path::new("e.toml")).unwrap();
        assert_eq!(plain.filter.params.range_noise.sigma_time, 1e-4);
        let s = Scenario::parse(&with_filter_line("sigma_speed = 0.2"), Path::new("f.toml")).unwrap();
        assert_eq!((s.filter.params.sigma_speed, s.filter.params.range_noise.sigma_time), (0.2, 1e-4));
        assert_eq!(s.filter.params.q, plain.filter.params.q);
        assert_eq!(s.filter.params.range_update, plain.filter.params.range_update);
        let e = err(&format!("{EXAMPLE}\n[filter.range_noise]\nsigma_tim = 1e-3\n"));
        assert!(e.contains("sigma_tim"), "{e}");
    }

    /// The example with `line` added to its `[filter]` table.
    fn with_filter_line(line: &str) -> String {
        assert!(EXAMPLE.contains("\n[filter]\n"), "the example has no [filter] table");
        EXAMPLE.replacen("\n[filter]\n", &format!("\n[filter]\n{line}\n"), 1)
    }

    /// A filter's outlier model is checked under its field path, and its keys are spelt out.
    #[test]
    fn a_filters_outlier_model_is_validated_by_field() {
        let bad = err(&with_filter_line("range_outliers = { probability = 1.5, min_m = 5.0, max_m = 2.0 }"));
        assert!(bad.contains("filter.range_outliers.probability = 1.5: allowed a probability in [0, 1)"), "{bad}");
        assert!(bad.contains("filter.range_outliers.max_m = 2: allowed a finite length above min_m"), "{bad}");
        let misspelt = err(&with_filter_line("range_outliers = { probability = 0.05, min_m = 5.0, max = 10.0 }"));
        assert!(misspelt.contains("unknown field `max`") && misspelt.contains("max_m"), "{misspelt}");
        let ok = with_filter_line("range_outliers = { probability = 0.0555, min_m = 5.0, max_m = 10.0 }");
        let s = Scenario::parse(&ok, Path::new("ok.toml")).unwrap();
        assert_eq!(s.filter.params.range_outliers, Some(coopnav_nav::RangeOutliers::GILL));
    }

    /// The filters' own cast is checked as `channel.sound_speed` is, under its own field path.
    #[test]
    fn a_filters_own_cast_is_validated_by_field() {
        let cast = "sound_speed = { kind = \"cast\", points = [[0.0, 1510.0], [0.0, 1200.0]] }";
        let e = err(&with_filter_line(cast));
        assert!(e.contains("filter.sound_speed.points[1][0]") && e.contains("strictly increasing"), "{e}");
        assert!(e.contains("filter.sound_speed.points[1][1]") && e.contains("1300..=1700"), "{e}");
        let empty = err(&with_filter_line("sound_speed = { kind = \"cast\", points = [] }"));
        assert!(empty.contains("filter.sound_speed.points"), "{empty}");
        let ok = with_filter_line("sound_speed = { kind = \"cast\" }");
        Scenario::parse(&ok, Path::new("ok.toml")).unwrap();
    }

    /// NaN, infinite and negative sensor noise, a bad channel model, a bad finish behaviour and a
    /// negative stand-off radius:
    /// every one named with its path in one error, and the sensors' unused keys are refused.
    #[test]
    fn every_bad_field_is_reported_at_once() {
        let text = EXAMPLE
            .replace("speed_sd = 0.05", "speed_sd = nan")
            .replace("compass_white_deg = 0.5", "compass_white_deg = -0.5")
            .replace("yaw_rate_white_deg_s = 0.05", "yaw_rate_white_deg_s = inf")
            .replace("p_outlier = 0.0555", "p_outlier = -0.1")
            .replace("capture_margin_db = 6.0", "capture_margin_db = -1.0")
            .replace("radius_m = 50.0", "radius_m = 0.0")
            .replace("divergence_window_s = 60.0", "divergence_window_s = nan")
            .replace("radius_m = 150.0", "radius_m = -150.0");
        let e = err(&text);
        for field in [
            "sensors.speed_sd",
            "sensors.compass_white_deg",
            "sensors.yaw_rate_white_deg_s",
            "channel.range_error.p_outlier",
            "channel.collisions.capture_margin_db",
            "fleet.finish.radius_m",
            "health.divergence_window_s",
            "policy.centroid-standoff.radius_m",
        ] {
            assert!(e.contains(&format!("field {field} = ")), "{field} missing from: {e}");
        }
        assert!(e.contains("8 bad fields") && e.contains("s.toml"), "{e}");
        let e = err(&EXAMPLE.replace("yaw_rate_white_deg_s = 0.05", "yaw_rate_white_deg_s = 0.05\ndgps_sd = 0.1"));
        assert!(e.contains("dgps_sd"), "{e}");
        let e = err(&EXAMPLE.replace("p_outlier = 0.0555", "p_outliers = 0.0555"));
        assert!(e.contains("p_outliers"), "{e}");
    }

    #[test]
    fn a_survey_auv_model_outside_its_ranges_is_refused_naming_it() {
        let e = err(&EXAMPLE.replacen("[cna]", "[fleet.vehicle]\nmax_yaw_rate = -1.0\n\n[cna]", 1));
        assert!(e.contains("field fleet.vehicle.max_yaw_rate = -1: allowed a finite number > 0"), "{e}");
    }

    /// The example with its `[policy.NAME]` table replaced by `table` (the lines after the header).
    fn with_policy_table(name: &str, table: &str) -> String {
        let header = format!("[policy.{name}]\n");
        let at = EXAMPLE.find(&header).unwrap_or_else(|| panic!("the example has no {header}"));
        let end = EXAMPLE[at + header.len()..].find("\n[").map_or(EXAMPLE.len(), |e| at + header.len() + e + 1);
        format!("{}{header}{table}\n{}", &EXAMPLE[..at], &EXAMPLE[end..])
    }

    /// The estimator's own table is checked on the mission: its tree as the rule and its keys set
    /// it, its cost's fields, each named by its path; a bad field elsewhere is not blamed on it.
    #[test]
    fn the_estimator_planners_own_settings_are_checked() {
        let text = with_policy_table(
            "planner-estimator",
            "tree = { heading_options = 1, look_ahead = 70, pitch_levels = 0 }\npenalty = { case = \"99\" }\n\
             cost = { kind = \"estimator\", terminal_levels = -1.0, bias_per_km = -2.0, reach_success = 1.5, \
             unmodelled_current = [nan, 0.0], drift_levels = -1.0 }",
        );
        let e = err(&text);
        for field in [
            "tree.heading_options = 1",
            "tree.look_ahead = 70",
            "tree.pitch_levels = 0",
            "penalty.case = '99'",
            "cost.terminal_levels",
            "cost.bias_per_km",
            "cost.reach_success",
            "cost.unmodelled_current[0]",
            "cost.drift_levels",
        ] {
            assert!(e.contains(&format!("field policy.planner-estimator.{field}")), "{field}: {e}");
        }
        let ok = with_policy_table(
            "planner-estimator",
            "tree = { look_ahead = 3, heading_options = 7 }\npenalty = { case = \"3\" }\ncost = { kind = \"estimator\" }",
        );
        let other_field_bad =
            err(&ok.replace("tree = { heading_options = 5, look_ahead = 5 }", "tree = { heading_options = 1 }"));
        assert!(
            other_field_bad.contains("policy.planner.tree.heading_options")
                && !other_field_bad.contains("policy.planner-estimator"),
            "a valid estimator tree is blamed for another field: {other_field_bad}"
        );
        let sc = Scenario::parse(&ok, Path::new("s.toml")).unwrap();
        let e = sc.estimator_settings().unwrap();
        assert_eq!((e.penalty_case, e.look_ahead, e.heading_options), (Some(PenaltyCase::C3), 3, 7));
        let too_large = err(&ok.replace("heading_options = 7", "heading_options = 2000"));
        assert!(too_large.contains("policy.planner-estimator.tree.look_ahead = 3 with 2000 options"), "{too_large}");
    }

    /// The rule's tree too large for the mission is named under the estimator's table: A = 21,
    /// L = 2 at N = 8 fits, and a file's L = 9 there does not.
    #[test]
    fn the_rules_tree_is_checked_under_the_estimators_table() {
        let eight = EXAMPLE.replace("n_auvs = 3", "n_auvs = 8").replace("tau = 30.0", "tau = 44.0");
        let sc = Scenario::parse(&eight, Path::new("s.toml")).unwrap();
        assert_eq!(sc.estimator_settings().map(|e| (e.heading_options, e.look_ahead)), Some((21, 2)));
        let deep =
            eight.replace("[policy.planner-estimator]\n", "[policy.planner-estimator]\ntree = { look_ahead = 9 }\n");
        let e = err(&deep);
        assert!(e.contains("field policy.planner-estimator.tree.look_ahead = 9 with 21 options"), "{e}");
    }

    /// An old-form file is refused with every moved key listed once, with its new place.
    #[test]
    fn an_old_form_file_is_refused_listing_every_moved_key() {
        let old = EXAMPLE.replace(
            "[policy]\n",
            "[planner]\nlook_ahead = 5\npenalty_case = \"1\"\nestimator_look_ahead = 3\nlink = \"assumed\"\n\n[policy]\n",
        );
        let e = err(&old);
        assert!(e.contains("s.toml: the old planner form") && e.contains("4 moved key(s)"), "{e}");
        for line in [
            "planner.look_ahead -> policy.planner.tree.look_ahead",
            "planner.penalty_case -> policy.planner.penalty",
            "planner.estimator_look_ahead -> policy.planner-estimator.tree.look_ahead",
            "planner.link -> policy.link",
        ] {
            assert!(e.contains(line), "{line}: {e}");
        }
    }

    /// Hudson's schedule: AUV k sends (k + 1)·τ/(N + 1) after the broadcast starts, so its reach
    /// is that gap less the broadcast's air time, at the water's slowest sound speed; an AUV whose
    /// slot starts with the broadcast hears none at any range.
    #[test]
    fn a_slot_reach_is_the_time_from_the_broadcasts_end_to_the_auvs_own_slot() {
        let mut sc = Scenario::example().with_auvs(8);
        sc.comms.tau = 44.0;
        let (air, speed) = (longest_air([sc.comms.cna_rate]), sc.channel.sound_speed.slowest());
        let reach = sc.slot_reach_m();
        for (k, r) in reach.iter().enumerate() {
            let want = ((k + 1) as f64 * 44.0 / 9.0 - air) * speed;
            assert!((r - want).abs() < 1e-9, "AUV {k}: {r} m, want {want} m");
        }
        assert!(reach[0] > 1000.0 && reach[0] < 3000.0, "the first slot's AUV: {} m", reach[0]);
        let slot = |who: &str, start_s| SlotSpec::packet(who, start_s, 10.0);
        sc.comms.schedule = Schedule::Tdma { slots: vec![slot("cna", 10.0), slot("auv0", 10.0), slot("auv1", 0.0)] };
        sc.comms.tau = 30.0;
        let reach = sc.slot_reach_m();
        assert_eq!(reach[0], 0.0, "sends with the broadcast");
        assert!((reach[1] - (20.0 - air) * speed).abs() < 1e-9, "the next cycle's slot: {}", reach[1]);
        assert!(reach[2..].iter().all(|r| r.is_infinite()), "no slot of their own: {reach:?}");
    }

    #[test]
    fn the_planners_link_is_the_assumed_model_unless_the_file_names_the_scenario_channel() {
        let plain = Scenario::parse(EXAMPLE, Path::new("e.toml")).unwrap();
        assert_eq!(plain.policy.link, PlannerLink::Assumed);
        assert!(!toml::to_string(&plain).unwrap().contains("link"), "the default is not written");
        let with = |link: &str| EXAMPLE.replace("[policy]\n", &format!("[policy]\nlink = \"{link}\"\n"));
        let sc = Scenario::parse(&with("scenario_channel"), Path::new("c.toml")).unwrap();
        assert_eq!(sc.policy.link, PlannerLink::ScenarioChannel);
        let e = err(&with("sonar"));
        assert!(e.contains("sonar") && e.contains("scenario_channel"), "{e}");
        // A direct BELLHOP run per sampled distance is refused before BELLHOP is looked for.
        let direct =
            with("scenario_channel").replace("kind = \"analytic\", k = 1.5, freq_hz = 25000.0", "kind = \"bellhop\"");
        let e = err(&direct);
        assert!(e.contains("policy.link") && e.contains("bellhop_grid") && !e.contains("field comms.tl"), "{e}");
    }

    #[test]
    fn the_estimator_counts_expected_pings_unless_the_file_asks_for_reports_only() {
        let plain = Scenario::parse(EXAMPLE, Path::new("e.toml")).unwrap();
        let tracking = |sc: &Scenario| sc.policy.planner_estimator.estimator_cost().unwrap().tracking;
        assert_eq!(tracking(&plain), EstimatorTracking::ExpectedPings);
        assert!(!toml::to_string(&plain).unwrap().contains("tracking"), "the default is not written");
        let with = |v: &str| {
            with_policy_table("planner-estimator", &format!("cost = {{ kind = \"estimator\", tracking = \"{v}\" }}"))
        };
        let sc = Scenario::parse(&with("reports_only"), Path::new("r.toml")).unwrap();
        assert_eq!(tracking(&sc), EstimatorTracking::ReportsOnly);
        let e = err(&with("hopeful"));
        assert!(e.contains("hopeful") && e.contains("reports_only") && e.contains("expected_pings"), "{e}");
    }

    /// Without `cost.truth` the rule's truth model is scored; a file's model replaces it and
    /// `"covariance"` scores the filters' covariance; the absent key is not written.
    #[test]
    fn the_estimator_scores_the_rules_truth_model_unless_the_file_says_otherwise() {
        let plain = Scenario::parse(EXAMPLE, Path::new("e.toml")).unwrap();
        let truth_key = |sc: &Scenario| sc.policy.planner_estimator.estimator_cost().unwrap().truth;
        assert_eq!(truth_key(&plain), None);
        assert_eq!(plain.estimator_settings().unwrap().truth, Some(coopnav_plan::auto::ASC_TRUTH));
        assert!(!toml::to_string(&plain).unwrap().contains("truth"), "the rule's is not written");
        let with = |v: &str| {
            with_policy_table("planner-estimator", &format!("cost = {{ kind = \"estimator\", truth = {v} }}"))
        };
        let truth = "{ drift_m2_s = 0.03, range_noise = { sigma_m = 1.8, per_km_m = 0.0 }, cna_diffusion_m2_s = 0.01 }";
        let sc = Scenario::parse(&with(truth), Path::new("t.toml")).unwrap();
        let spec = sc.estimator_settings().unwrap().truth.unwrap();
        assert_eq!((spec.drift_m2_s, spec.range_noise.sigma_m, spec.cna_diffusion_m2_s), (0.03, 1.8, 0.01));
        let again = Scenario::parse(&toml::to_string(&sc).unwrap(), Path::new("t.toml")).unwrap();
        assert_eq!(truth_key(&again), Some(TruthChoice::Model(spec)));
        let covariance = Scenario::parse(&with("\"covariance\""), Path::new("c.toml")).unwrap();
        assert_eq!(covariance.estimator_settings().unwrap().truth, None);
        let again = Scenario::parse(&toml::to_string(&covariance).unwrap(), Path::new("c.toml")).unwrap();
        assert_eq!(truth_key(&again), Some(TruthChoice::Cost(CovarianceWord::Covariance)));
        let e = err(&with(&truth.replace("drift_m2_s = 0.03", "drift_m2_s = -0.03")));
        assert!(e.contains("policy.planner-estimator.cost.truth.drift_m2_s") && e.contains(">= 0"), "{e}");
        assert!(Scenario::parse(&with("\"none\""), Path::new("n.toml")).is_err());
    }

    #[test]
    fn an_auv_not_yet_heard_is_ignored_unless_the_file_gives_the_mission_plan() {
        let plain = Scenario::parse(EXAMPLE, Path::new("e.toml")).unwrap();
        assert_eq!(plain.policy.before_first_report, BeforeFirstReport::Ignore);
        let line = "before_first_report = \"ignore\"";
        let planned = EXAMPLE.replace(line, "before_first_report = \"mission_plan\"");
        let sc = Scenario::parse(&planned, Path::new("p.toml")).unwrap();
        assert_eq!(sc.policy.before_first_report, BeforeFirstReport::MissionPlan);
        let e = err(&EXAMPLE.replace(line, "before_first_report = \"guess\""));
        assert!(e.contains("before_first_report") && e.contains("mission_plan") && e.contains("s.toml"), "{e}");
    }

    #[test]
    fn a_schedule_that_cannot_fit_is_refused() {
        let e = err(&EXAMPLE.replace("n_auvs = 3", "n_auvs = 8"));
        assert!(e.contains("comms.schedule.slot 1 (auv0") && e.contains("air time 3.90 s"), "{e}");
        let longer = EXAMPLE.replace("n_auvs = 3", "n_auvs = 8").replace("tau = 30.0", "tau = 44.0");
        Scenario::parse(&longer, Path::new("s.toml")).unwrap();
    }

    #[test]
    fn bad_files_name_the_field() {
        let e = err(&EXAMPLE.replace("n_auvs = 3", "n_auvs = 32"));
        assert!(e.contains("fleet.n_auvs") && e.contains("1..=31") && e.contains("s.toml"), "{e}");
        let e = err(&EXAMPLE.replace("tau = 30.0", "tau = 1.0"));
        assert!(e.contains("comms.tau"), "{e}");
        let e = err(&EXAMPLE.replace("penalty = { case = \"1\" }", "penalty = { case = \"zz\" }"));
        assert!(e.contains("policy.planner.penalty.case"), "{e}");
        let e = err(&EXAMPLE.replace("seed = 1", "seed = 1\nsurprise = 2"));
        assert!(e.contains("surprise"), "{e}");
        let e = err(&EXAMPLE.replace("cna_rate = 0", "cna_rate = 3"));
        assert!(e.contains("comms.cna_rate"), "{e}");
        let e = err(&EXAMPLE.replace("speed = 1.5", "speed = -1.5"));
        assert!(e.contains("fleet.speed"), "{e}");
        let e = err(&EXAMPLE.replace(GPS, &format!("{DEAD_RECKONING}\nauv = {{ pitch_options = 0, depth = 10.0 }}")));
        assert!(e.contains("cna.auv.pitch_options"), "{e}");
        let auv =
            |fields: &str| EXAMPLE.replace(GPS, &format!("{DEAD_RECKONING}\nauv = {{ pitch_options = 1, {fields} }}"));
        let e = err(&auv("depth = 1.0, min_depth_m = 2.0"));
        assert!(e.contains("cna.auv.depth = 1") && e.contains(">= cna.auv.min_depth_m (2 m)"), "{e}");
        let e = err(&auv("depth = 10.0, min_depth_m = -1.0"));
        assert!(e.contains("cna.auv.min_depth_m"), "{e}");
        let e = err(&EXAMPLE.replace("lane_length = 800.0", "lane_length = 20000.0"));
        assert!(e.contains("field fleet") && e.contains("15 000"), "{e}");
        let e = err(&EXAMPLE
            .replace("heading_options = 5", "heading_options = 1")
            .replace("look_ahead = 5 }", "look_ahead = 70 }"));
        assert!(
            e.contains("field policy.planner.tree.heading_options = 1")
                && e.contains("field policy.planner.tree.look_ahead = 70"),
            "{e}"
        );
    }

    /// The example's CNA navigation line, and an AUV CNA's in its place.
    const GPS: &str = "navigation = { kind = \"gps\", sd_m = 1.0 }";
    const DEAD_RECKONING: &str = "navigation = { kind = \"dead-reckoning\", diffusion_m2_s = 0.01 }";

    #[test]
    fn an_auv_cna_broadcasts_its_estimate_unless_the_file_asks_for_the_counterfactual() {
        let auv = |kind: &str| {
            let cna = format!(
                "navigation = {{ kind = \"{kind}\", diffusion_m2_s = 0.01 }}\nauv = {{ pitch_options = 1, depth = 10.0 }}"
            );
            Scenario::parse(&EXAMPLE.replace(GPS, &cna), Path::new("a.toml")).unwrap()
        };
        let plain = auv("dead-reckoning");
        assert_eq!(plain.cna.navigation.broadcast_error((3.0, 4.0)), (3.0, 4.0));
        let exact = auv("exact");
        assert_eq!(exact.cna.navigation.broadcast_error((3.0, 4.0)), (0.0, 0.0));
        assert_eq!(exact.cna.navigation.diffusion_m2_s(), 0.01);
        let again = Scenario::parse(&toml::to_string(&exact).unwrap(), Path::new("a.toml")).unwrap();
        assert_eq!((again.cna.auv, again.cna.navigation), (exact.cna.auv, exact.cna.navigation));
        let e = err(&EXAMPLE.replace(GPS, &format!("{GPS}\nauv = {{ pitch_options = 1, depth = 10.0 }}")));
        assert!(e.contains("cna.navigation.kind") && e.contains("\"dead-reckoning\" or \"exact\""), "{e}");
        let e = err(&EXAMPLE.replace(GPS, "navigation = { kind = \"gps\", sd_m = -1.0 }"));
        assert!(e.contains("cna.navigation.sd_m"), "{e}");
    }

    /// A file in the old CNA form gets every moved key with its new place in one message.
    #[test]
    fn the_old_cna_keys_are_refused_with_their_new_places() {
        let old = EXAMPLE.replace(
            GPS,
            "gps_sd = 1.0\nauv = { pitch_options = 1, depth = 10.0, nav_diffusion = 0.01, broadcasts_truth = true, \
             surfacing = { when = { kind = \"period\", period_s = 900.0 }, fix_time_s = 60.0, gps_sd_m = 1.0 } }",
        );
        let e = err(&old);
        for line in [
            "cna.gps_sd -> cna.navigation = { kind = \"gps\", sd_m }",
            "cna.auv.nav_diffusion -> cna.navigation = { kind = \"dead-reckoning\", diffusion_m2_s }",
            "cna.auv.surfacing -> cna.navigation.surfacing",
            "cna.auv.broadcasts_truth -> cna.navigation = { kind = \"exact\", diffusion_m2_s, surfacing }",
        ] {
            assert!(e.contains(&format!("\n  {line}")), "{line} missing from: {e}");
        }
        assert!(e.contains("4 moved key(s)") && e.contains("cna.navigation"), "{e}");
    }
}
