//! The closed-loop scenario file (TOML, `deny_unknown_fields`): the survey fleet and its
//! lawnmowers, the CNA, the acoustic link, sensors and filters, and the planner. Validated
//! before anything runs; every error names the file, the field and what is allowed.

use crate::models::buoy::{BuoySpec, MAX_BUOYS};
use crate::models::channel::Channel;
use crate::models::filter::{FilterRate, FilterSoundSpeed, FilterSpec};
use crate::models::finish::Finish;
pub use crate::models::health::Health;
use crate::models::minipacket;
use crate::models::mower::MowerSpec;
use crate::models::peer::{mask_width, StatusFormat, StatusTo};
use crate::models::schedule::{longest_air, payload_problem, Fit, Owner, Schedule};
use crate::models::ship::{ShipSpec, MAX_SHIPS};
use crate::models::surfacing::Surfacing;
use crate::models::tl_spec::TlModel;
pub use crate::scenario::file::ScenarioError;
use crate::scenario::file::{self as scenario_file, overlay, Problems};
use crate::scenario::site::{self, PathSpec, Site};
use coopnav_acomms::node_report::{BODY_BITS, HEADER_BITS};
use coopnav_acomms::selector::AdaptiveConfig;
use coopnav_acomms::status::CovTrailer;
use coopnav_acomms::{Rate, Receiver, SuccessModel};
use coopnav_core::validation::CheckFields;
use coopnav_core::{Bathymetry, CompassDeg, DepthTarget, Heading, Iver2Params, Lawnmower, Shelf, SurveyPath};
use coopnav_nav::{AuvModel, AuvParams, RangeNoise};
use coopnav_plan::auto::{self, CnaFact, EstimatorSettings, MissionFacts};
use coopnav_plan::predict::{PredictorConfig, WaypointUse};
use coopnav_plan::{
    Aggregate, CnaKind, Deadline, DistanceLimits, ErrorModel, HorizonSpec, MotionConfig, PenaltyCase, PlanError,
    PlannerConfig, SearchConfig, TruthSpec,
};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The embedded default mission (`coopnav simulate` with no scenario, `--example`): the
/// library's `scenarios/default.toml`.
pub const EXAMPLE: &str = include_str!("../../../../scenarios/default.toml");

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
    /// Absent: every key's default, `planner-estimator`'s from the mission ([`Planner`]).
    #[serde(default)]
    pub planner: Planner,
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
    /// Radius of the `centroid-standoff` baseline's loiter circle around the fleet's centroid, m.
    /// Invented: 150 m, the trail baseline's stand-off.
    #[serde(default = "default_standoff")]
    pub standoff_radius_m: f64,
    /// The water current east and north (m/s) as the CNA's ADCP measures it: a fact a field team
    /// states (not the scenario's `fleet.current`, the truth), read by `planner-estimator`'s rule.
    /// Default [0, 0]: none measured. Written only when set.
    #[serde(default, skip_serializing_if = "coopnav_plan::estimator::is_still")]
    pub adcp_current: [f64; 2],
}

fn default_standoff() -> f64 {
    150.0
}

/// An AUV as the CNA (Hudson's AUV-CNA case: heading and pitch options).
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
    /// Growth of the CNA's own horizontal position-error variance, m²/s per axis (a random walk:
    /// what it broadcasts is its truth plus this error). Invented: no thesis value.
    pub nav_diffusion: f64,
    /// When it climbs for a GPS fix (None: never; [`Surfacing`]).
    #[serde(default)]
    pub surfacing: Option<Surfacing>,
    /// A counterfactual, not a vehicle (`reproduce closed-loop-cna-navigation`): true =
    /// the CNA broadcasts its TRUE position. Its navigation error is still drawn, its σ still grows
    /// and it surfaces as configured; only no range or command carries the error. Default false.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub broadcasts_truth: bool,
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

/// The underway planner (Hudson 2012, Sec. 4.2; docs/models.md#hudson-prediction) and its adapter's options.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Planner {
    /// A of Hudson's planner (default 5, as the evaluation flies it).
    #[serde(default = "five")]
    pub heading_options: usize,
    /// L of Hudson's planner (default 5, as the evaluation flies it).
    #[serde(default = "five")]
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
    /// Reports needed from an AUV before the CNA plans for it (Hudson 2012, Sec. 4.2: two).
    #[serde(default = "one_usize")]
    pub start_after_reports: usize,
    /// What the CNA plans with for an AUV it has fewer than `start_after_reports` reports of.
    /// Written only when not the thesis's default, so existing manifests read as before.
    #[serde(default, skip_serializing_if = "BeforeFirstReport::is_ignore")]
    pub before_first_report: BeforeFirstReport,
    /// Thesis option: use at most min(L, 3) reported waypoints (default: all received).
    #[serde(default)]
    pub thesis_waypoints: bool,
    /// Model lost pings in the tracked error (expected value over the success likelihood);
    /// false = the thesis's behaviour (every ping assumed received).
    #[serde(default)]
    pub model_lost_pings: bool,
    /// Which channel the planners' link model (lost pings, the estimator's link table) is built
    /// on. Written only when not the default, so existing manifests read as before.
    #[serde(default, skip_serializing_if = "PlannerLink::is_assumed")]
    pub link: PlannerLink,
    /// What `planner-estimator`'s model of an AUV's filter covariance takes between that AUV's
    /// reports. Written only when not the default, so existing manifests read as before.
    #[serde(default, skip_serializing_if = "EstimatorTracking::is_expected_pings")]
    pub estimator_tracking: EstimatorTracking,
    /// Initial modelled σ₀ and ε₀, m (Table 5.1: 1 m).
    #[serde(default = "one")]
    pub sigma0: f64,
    #[serde(default = "one")]
    pub eps0: f64,
    #[serde(default)]
    pub predictor: PredictorConfig,
    // `planner-estimator`'s settings: each absent key comes from the planner's rule for the
    // mission (`coopnav_plan::auto::for_mission`, [`Scenario::estimator_settings`]); a key the file
    // sets overrides the rule's value. None is never written.
    /// How `planner-estimator` joins the AUVs' covariances into a level's cost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_aggregate: Option<Aggregate>,
    /// The range bias `planner-estimator` assumes, m of 1-σ per km of range (coopnav_plan
    /// estimator step 4). The filters' own sound-speed term is 1000·σ_c/c (2 m/km for their
    /// default σ_c = 3 m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_bias_per_km: Option<f64>,
    /// `planner-estimator` also prices the range bias `channel.sound_speed` causes, as a CTD cast
    /// the CNA holds: the scale error between the CNA's depth and each AUV's against the speed the
    /// filters convert at (`filter.sound_speed`: none where they convert with the water's own cast),
    /// on top of `estimator_bias_per_km` (coopnav_plan estimator step 4,
    /// `BiasTable`; invented, docs/models.md#estimator-cost). With an AUV CNA and
    /// `estimator_level_off` it lets the planner choose the CNA's depth.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_bias_profile: Option<bool>,
    /// `planner-estimator` models the AUV CNA as the engine flies it: each step starts level, its
    /// pitch is cut at the limit and its depth at the depth limits (coopnav_plan
    /// `CnaKind::Auv::level_off`); false is the thesis's model, where a ±45° pitch step breaks the
    /// 30° limit and so the CNA never changes depth.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_level_off: Option<bool>,
    /// `planner-estimator` knows its schedule: a broadcast still arriving when an AUV's own slot
    /// starts is lost (half-duplex), so beyond a slant range set by the slot's timing
    /// ([`Scenario::slot_reach_m`]) no ping reaches that AUV, whatever the link. Invented
    /// (docs/models.md#closed-loop-schedule): the thesis's link model depends on range only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_slot_reach: Option<bool>,
    /// Levels of cost-to-go `planner-estimator` counts at each leaf (estimator step 6; 0 = none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_terminal_levels: Option<f64>,
    /// The water current the survey AUVs' filters do not model, east and north (m/s):
    /// `planner-estimator` grows each AUV's modelled error along it (coopnav_plan estimator step
    /// 1b; invented, docs/models.md#estimator-cost). The rule takes `cna.adcp_current` for filters
    /// that do not estimate the current.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_unmodelled_current: Option<[f64; 2]>,
    /// Levels over which that current's drift builds up unseen (estimator step 1b's m; default 4).
    #[serde(default = "estimator_drift_levels")]
    pub estimator_drift_levels: f64,
    /// Success probability that makes a ping useful for `planner-estimator`'s reach cost-to-go
    /// (coopnav_plan estimator step 7: each AUV's growth until the CNA is within the range where
    /// the link's success reaches it; 0 = none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_reach_success: Option<f64>,
    /// Table 5.2 penalty case of `planner-estimator` (the rule's "none" is `penalty_case`). Its
    /// cost already prices what Hudson's distance limits stand for (a far ping is lost and noisy,
    /// one from overhead teaches nothing horizontally), so case "2" (no penalties) is an option.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_penalty_case: Option<String>,
    /// L of `planner-estimator`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_look_ahead: Option<usize>,
    /// A of `planner-estimator`, its heading options per level (≥ 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_heading_options: Option<usize>,
    /// With an AUV CNA, how many levels of `planner-estimator`'s tree offer the pitch options, from
    /// level 0 (≥ 1; deeper levels hold the pitch; a number ≥ L: every level). Fewer pitch levels
    /// make a deeper look-ahead affordable (coopnav_plan `CnaKind::Auv::pitch_levels`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_pitch_levels: Option<usize>,
    /// Whether `planner-estimator` adds the CNA's own horizontal variance (GPS σ², or an AUV
    /// CNA's navigation variance since its last fix) to each ping's range variance (coopnav_plan
    /// estimator step 2); false scores every broadcast position as exact.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_cna_variance: Option<bool>,
    /// A truth model: `planner-estimator` scores the AUVs' expected true error under their
    /// filters' gains (coopnav_plan `true_error`; the truth's drift, range noise and the CNA's
    /// diffusion as the CNA believes them); `"covariance"`: the filters' covariance instead.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_truth: Option<TruthChoice>,
    /// The water current east and north (m/s) for filters that estimate the current
    /// (`filter.model = { kind = "current" }`): with a truth model, `planner-estimator` then plans
    /// on those filters' current states, which start from the filters' prior mean (coopnav_plan
    /// `current_states`). The rule takes `cna.adcp_current` for such filters.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub estimator_current: Option<[f64; 2]>,
    /// `planner-estimator`'s mission-long horizon above its tree: which AUV to serve next, valued
    /// over tens of minutes along every AUV's plan (coopnav_plan `horizon`; on by default,
    /// `enabled = false` for none). Written only when not the default.
    #[serde(default, skip_serializing_if = "is_default_horizon")]
    pub horizon: HorizonSpec,
}

fn is_default_horizon(h: &HorizonSpec) -> bool {
    *h == HorizonSpec::default()
}

/// What the CNA knows of a survey AUV before its reports meet the planning start rule (Hudson 2012, Sec. 4.2).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BeforeFirstReport {
    /// Nothing: the planner and every baseline ignore the AUV until then (the thesis's rule).
    /// An AUV whose statuses never reach the CNA is never looked for.
    #[default]
    Ignore,
    /// Its mission plan as the operator knew it before launch (launch point, planned lawnmower
    /// waypoints and speed), followed from t = 0 until the reports take over. An invention, not
    /// in the thesis: a field team knows its AUVs' plans.
    MissionPlan,
}

/// The transmission loss behind the planners' ping success likelihood (`planner.link`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlannerLink {
    /// The analytic model the CNA is configured with (`comms.tl.assumed()`: the default Thorp
    /// model under the BELLHOP kinds), apart from the sea it plays in.
    #[default]
    Assumed,
    /// The scenario's own `comms.tl` provider, averaged over bearings from the survey blocks'
    /// centres (policies `channel_likelihood`). Invented: a team that has modelled
    /// its site's acoustics gives the planner that model. Needs `analytic` or `bellhop_grid`.
    ScenarioChannel,
}

impl PlannerLink {
    fn is_assumed(&self) -> bool {
        *self == PlannerLink::Assumed
    }
}

/// How `planner-estimator`'s model of each AUV's filter covariance moves between that AUV's status
/// reports (`planner.estimator_tracking`; closed loop `CovarianceTracker`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EstimatorTracking {
    /// Every ping counts with the update its success probability under the planner's link model
    /// expects, whether or not the AUV answered.
    #[default]
    ExpectedPings,
    /// Only what the AUV reports counts: between reports, and from launch until the first, the
    /// covariance grows as the AUV's filter predicts it with no range (its process noise, and with
    /// a `current` filter model the unobserved current's variance). Invented: a CNA that never
    /// hears an AUV cannot know its pings reached it, and with `expected_pings` it believes an
    /// AUV it never heard from is the best served.
    ReportsOnly,
}

impl EstimatorTracking {
    fn is_expected_pings(&self) -> bool {
        *self == EstimatorTracking::ExpectedPings
    }
}

impl BeforeFirstReport {
    fn is_ignore(&self) -> bool {
        *self == BeforeFirstReport::Ignore
    }
}

fn estimator_drift_levels() -> f64 {
    coopnav_plan::EstimatorSpec::default().drift_levels
}

/// `planner.estimator_truth`: a truth model, or the word `"covariance"` (the filters' covariance).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum TruthChoice {
    Model(TruthSpec),
    Cost(CovarianceWord),
}

/// The word `"covariance"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum CovarianceWord {
    #[serde(rename = "covariance")]
    Covariance,
}

impl TruthChoice {
    /// The truth model, None for the covariance cost.
    pub fn model(self) -> Option<TruthSpec> {
        match self {
            TruthChoice::Model(t) => Some(t),
            TruthChoice::Cost(_) => None,
        }
    }
}

impl Default for Planner {
    /// The planner of a file with no `[planner]` table: every key's default.
    fn default() -> Self {
        toml::from_str("").expect("an empty [planner] table reads with every default")
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

fn default_case() -> String {
    PenaltyCase::C1.id().to_string()
}
fn one_usize() -> usize {
    1
}
fn five() -> usize {
    5
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
        p.extend(self.filter.rate.problem("filter.", self.dt));
        p.check("health.divergence_window_s", self.health.divergence_window_s, |v| v > 0.0, "a finite number > 0");
        self.validate_planner(&mut p);
        if p.is_empty() && !matches!(self.comms.tl, TlModel::Analytic(_)) {
            // The BELLHOP kinds need the program, and a grid is computed (or read from the disk
            // cache) here, once, so that a run never finds it missing.
            if let Err(e) = self.comms.tl.provider(self) {
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
        p.extend(f.finish.problems("fleet.finish."));
        if let Err(e) = f.vehicle.validate() {
            p.push("fleet.vehicle", e, "the IVER2 model's ranges");
        }
        if !(f.lawnmowers.is_empty() || f.lawnmowers.len() == f.n_auvs) {
            p.push("fleet.lawnmowers", format!("{} entries", f.lawnmowers.len()), "none, or one per survey AUV");
        }
        for (k, m) in f.lawnmowers.iter().enumerate() {
            p.extend(m.problems(&format!("fleet.lawnmowers[{k}].")));
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
        p.non_negative("cna.gps_sd", c.gps_sd);
        p.non_negative("cna.standoff_radius_m", c.standoff_radius_m);
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
            p.non_negative("cna.auv.nav_diffusion", a.nav_diffusion);
            p.check("cna.auv.min_depth_m", a.min_depth_m, |v| (0.0..100.0).contains(&v), "0 <= min_depth_m < 100 m");
            if let CruiseDepth::Metres(z) = a.depth {
                if z < a.min_depth_m {
                    p.push("cna.auv.depth", z.to_string(), format!(">= cna.auv.min_depth_m ({} m)", a.min_depth_m));
                }
            }
            if let Some(s) = &a.surfacing {
                s.validate("cna.auv.surfacing.", p);
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
            p.extend(b.problems(&format!("buoys[{i}].")));
            p.extend(payload_problem(&format!("buoys[{i}].rate"), b.rate, report_bytes));
            b.filter.check_fields(&format!("buoys[{i}].filter."), p);
        }
    }

    fn validate_ships(&self, p: &mut Problems) {
        if self.ships.len() > MAX_SHIPS {
            p.push("ships", format!("{} ships", self.ships.len()), format!("at most {MAX_SHIPS}"));
        }
        for (i, ship) in self.ships.iter().enumerate() {
            p.extend(ship.problems(&format!("ships[{i}].")));
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
                if let Err(e) = a.validate() {
                    p.push("comms.status_adaptive", e, "see the message");
                }
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
        p.extend(payload_problem("comms.cna_rate", c.cna_rate, broadcast_bytes));
        for rate in &status_rates {
            p.extend(payload_problem("comms.status_rate", *rate, status_bytes));
        }
        p.extend(c.tl.problems("comms.tl."));
        p.non_negative("comms.slot_guard_s", c.slot_guard_s);
        p.positive("comms.max_range_m", c.max_range_m);
        p.check("comms.mini_packet_air_s", c.mini_packet_air_s, |v| v > 0.0 && v <= 10.0, "0 < air time <= 10 s");
        p.extend(self.channel.range_error.problems("channel.range_error."));
        p.extend(self.channel.sound_speed.problems("channel.sound_speed."));
        p.extend(self.channel.clocks.problems("channel.clocks."));
        p.extend(self.channel.collisions.problems("channel.collisions."));
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
            p.extend(c.schedule.problems("comms.schedule.", &fit));
        }
    }

    fn validate_sensors(&self, p: &mut Problems) {
        let s = &self.sensors;
        p.non_negative("sensors.speed_sd", s.speed_sd);
        p.check("sensors.compass_bias_step_deg", s.compass_bias_step_deg, |v| (0.0..=10.0).contains(&v), "0..=10 deg");
        p.check("sensors.compass_white_deg", s.compass_white_deg, |v| (0.0..=30.0).contains(&v), "0..=30 deg");
        p.check("sensors.yaw_rate_white_deg_s", s.yaw_rate_white_deg_s, |v| (0.0..=10.0).contains(&v), "0..=10 deg/s");
    }

    /// The planner's own checks of `planner-estimator`'s A and L (the file's or the rule's); its
    /// other fields are reported once, by `planner_config`'s. A tree too large is blamed on the
    /// estimator's L if the file sets it, else on its A if set, else on the mission's N (the rule
    /// chose both).
    fn validate_estimator_tree(&self, p: &mut Problems) {
        let pl = &self.planner;
        let settings = self.estimator_settings();
        let mut cfg = self.planner_config();
        cfg.look_ahead = settings.look_ahead;
        cfg.motion.heading_options = settings.heading_options;
        let Err(PlanError::Invalid(found)) = cfg.validate() else { return };
        let size = if pl.estimator_look_ahead.is_some() || pl.estimator_heading_options.is_none() {
            "look_ahead"
        } else {
            "heading_options"
        };
        for bad in found.0 {
            let own = match bad.field.as_str() {
                "look_ahead" => size,
                "motion.heading_options" if pl.estimator_heading_options.is_some() => "heading_options",
                _ => continue,
            };
            p.push(format!("planner.estimator_{own}"), bad.value, bad.allowed);
        }
    }

    fn validate_planner(&self, p: &mut Problems) {
        let pl = &self.planner;
        p.positive("planner.sigma0", pl.sigma0);
        p.non_negative("planner.eps0", pl.eps0);
        if let Some(h) = pl.estimator_terminal_levels {
            p.non_negative("planner.estimator_terminal_levels", h);
        }
        if let Some(p_u) = pl.estimator_reach_success {
            p.probability("planner.estimator_reach_success", p_u);
        }
        if let Some(k_b) = pl.estimator_bias_per_km {
            p.non_negative("planner.estimator_bias_per_km", k_b);
        }
        for (key, current) in [
            ("planner.estimator_unmodelled_current", pl.estimator_unmodelled_current),
            ("planner.estimator_current", pl.estimator_current),
            ("cna.adcp_current", Some(self.cna.adcp_current)),
        ] {
            if let Some([east, north]) = current {
                p.finite(&format!("{key}[0]"), east);
                p.finite(&format!("{key}[1]"), north);
            }
        }
        p.non_negative("planner.estimator_drift_levels", pl.estimator_drift_levels);
        self.validate_estimator_tree(p);
        if let Some(truth) = pl.estimator_truth.and_then(TruthChoice::model) {
            truth.check_fields("planner.estimator_truth.", p);
        }
        pl.horizon.check_fields("planner.horizon.", p);
        if pl.estimator_pitch_levels == Some(0) {
            p.push("planner.estimator_pitch_levels", "0", ">= 1 (or absent: every level)");
        }
        if pl.start_after_reports == 0 {
            p.push("planner.start_after_reports", "0", ">= 1");
        }
        if pl.link == PlannerLink::ScenarioChannel && self.comms.tl == TlModel::Bellhop {
            // A direct BELLHOP run per sampled distance and bearing would take hours.
            p.push("planner.link", "scenario_channel", "\"assumed\", or comms.tl of kind analytic or bellhop_grid");
        }
        let ids = || PenaltyCase::ALL.iter().map(|c| c.id()).collect::<Vec<&str>>().join(", ");
        if let Some(case) = pl.estimator_penalty_case.as_ref().filter(|c| PenaltyCase::from_id(c).is_none()) {
            p.push("planner.estimator_penalty_case", case.clone(), ids());
        }
        if PenaltyCase::from_id(&pl.penalty_case).is_none() {
            p.push("planner.penalty_case", pl.penalty_case.clone(), ids());
        } else if let Err(e) = self.planner_config().validate() {
            match e {
                PlanError::Invalid(found) => {
                    found.0.into_iter().for_each(|bad| p.push(planner_field(&bad.field), bad.value, bad.allowed))
                }
                other => p.push("planner", other.to_string(), "a valid planner configuration"),
            }
        }
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
                let limits = match self.planner_config().motion.cna {
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
                cna: self.cna.auv.as_ref().map_or(CnaKind::Asc {}, |a| {
                    let mut kind = CnaKind::auv(a.pitch_options);
                    if let CnaKind::Auv { min_depth, .. } = &mut kind {
                        *min_depth = a.min_depth_m;
                    }
                    kind
                }),
            },
            error: p.error,
            cost: coopnav_plan::CostSpec::Hudson,
            limits: p.limits,
            penalties: PenaltyCase::from_id(&p.penalty_case).unwrap_or(PenaltyCase::C1).penalties(),
            search: SearchConfig { parallel: p.parallel, deadline: p.deadline, ..SearchConfig::default() },
        }
    }

    /// The facts of this mission the planner's rule reads (coopnav_plan `auto`): N, the CNA's
    /// kind and navigation diffusion, the current its ADCP measures, the filters' model.
    pub fn mission_facts(&self) -> MissionFacts {
        MissionFacts {
            n_auvs: self.fleet.n_auvs,
            cna: self.cna.auv.as_ref().map_or(CnaFact::Asc, |a| CnaFact::Auv { nav_diffusion_m2_s: a.nav_diffusion }),
            adcp_current: self.cna.adcp_current,
            filters_estimate_current: matches!(self.filter.model, AuvModel::Current(_)),
        }
    }

    /// `planner-estimator`'s settings: the rule's for this mission ([`Scenario::mission_facts`],
    /// coopnav_plan `auto::for_mission`), each replaced by the file's `planner.estimator_*` key
    /// where it sets one (an unknown penalty case is refused by `validate`).
    pub fn estimator_settings(&self) -> EstimatorSettings {
        let p = &self.planner;
        let rule = auto::for_mission(&self.mission_facts());
        EstimatorSettings {
            heading_options: p.estimator_heading_options.unwrap_or(rule.heading_options),
            look_ahead: p.estimator_look_ahead.unwrap_or(rule.look_ahead),
            pitch_levels: p.estimator_pitch_levels.or(rule.pitch_levels),
            aggregate: p.estimator_aggregate.unwrap_or(rule.aggregate),
            bias_per_km: p.estimator_bias_per_km.unwrap_or(rule.bias_per_km),
            bias_profile: p.estimator_bias_profile.unwrap_or(rule.bias_profile),
            level_off: p.estimator_level_off.unwrap_or(rule.level_off),
            slot_reach: p.estimator_slot_reach.unwrap_or(rule.slot_reach),
            terminal_levels: p.estimator_terminal_levels.unwrap_or(rule.terminal_levels),
            reach_success: p.estimator_reach_success.unwrap_or(rule.reach_success),
            penalty_case: match &p.estimator_penalty_case {
                Some(id) => PenaltyCase::from_id(id),
                None => rule.penalty_case,
            },
            cna_variance: p.estimator_cna_variance.unwrap_or(rule.cna_variance),
            truth: p.estimator_truth.map_or(rule.truth, TruthChoice::model),
            unmodelled_current: p.estimator_unmodelled_current.unwrap_or(rule.unmodelled_current),
            current: p.estimator_current.unwrap_or(rule.current),
        }
    }

    pub fn predictor_config(&self) -> PredictorConfig {
        let mut c = self.planner.predictor;
        if self.planner.thesis_waypoints {
            c.waypoints = WaypointUse::thesis(self.planner.look_ahead);
        }
        c
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

    /// The benchmark mission (`coopnav bench closed-loop`): 3 h, 5 survey AUVs on 16-lane blocks (long enough to
    /// keep surveying for the whole 3 h), τ = 30 s, A = 5, L = 5, 10 Hz EKFs. The fleet spans
    /// 4.2 km, so its 5 s slots are planned for ranges up to 2.4 km at rate 1 (3.08 s of air
    /// time); at rate 0 (3.9 s) they hold only 1 km, and longer ranges collide with the next slot.
    /// The CNA knows the AUVs' mission plans (`planner.before_first_report = "mission_plan"`): on
    /// the BELLHOP grid it never hears auv0 and auv1 from its start otherwise, and never looks for
    /// them (docs/evaluation.md has the difference it makes).
    pub fn bench() -> Self {
        let mut s = Self::example().with_auvs(5);
        s.duration_s = 3.0 * 3600.0;
        s.fleet.lanes = 16;
        s.fleet.lane_length = 950.0;
        s.fleet.lane_spacing = 50.0;
        s.fleet.block_offset = 850.0;
        s.cna.x = 2100.0;
        (s.planner.heading_options, s.planner.look_ahead, s.comms.tau, s.dt) = (5, 5, 30.0, 0.1);
        (s.comms.cna_rate, s.comms.status_rate, s.comms.max_range_m) = (Rate::R1, Rate::R1, 2400.0);
        s.planner.before_first_report = BeforeFirstReport::MissionPlan;
        s
    }

    /// Copy with N survey AUVs (experiments sweep N).
    pub fn with_auvs(&self, n: usize) -> Self {
        let mut s = self.clone();
        s.fleet.n_auvs = n;
        s
    }
}

/// Where this file sets each `PlannerConfig` setting (`planner_config` assembles it from the CNA,
/// comms and planner tables; the penalties come from `planner.penalty_case`, a checked preset).
fn planner_field(field: &str) -> String {
    let file_name = match field {
        "motion.speed" => "cna.speed",
        "motion.tau" => "comms.tau",
        "motion.max_turn_rate_deg_s" => "cna.max_turn_rate_deg_s",
        "motion.cna.pitch_options" => "cna.auv.pitch_options",
        _ => {
            let own = field.strip_prefix("motion.").or_else(|| field.strip_prefix("search.")).unwrap_or(field);
            return format!("planner.{own}");
        }
    };
    file_name.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::schedule::SlotSpec;

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
            .replace("standoff_radius_m = 150.0", "standoff_radius_m = -150.0");
        let e = err(&text);
        for field in [
            "sensors.speed_sd",
            "sensors.compass_white_deg",
            "sensors.yaw_rate_white_deg_s",
            "channel.range_error.p_outlier",
            "channel.collisions.capture_margin_db",
            "fleet.finish.radius_m",
            "health.divergence_window_s",
            "cna.standoff_radius_m",
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
        assert!(e.contains("field fleet.vehicle = ") && e.contains("max_yaw_rate"), "{e}");
    }

    /// The default mission without its `planner.estimator_*` lines (tests that write their own).
    fn example_without_estimator_settings() -> String {
        EXAMPLE.lines().filter(|l| !l.starts_with("estimator_")).map(|l| format!("{l}\n")).collect()
    }

    /// Eight AUVs with τ = 30 s leave 3.3 s per slot, less than rate 0's 3.9 s of air time; τ = 44 s fits.
    #[test]
    fn the_estimator_planners_own_settings_are_checked() {
        let example = example_without_estimator_settings();
        let text = example.replace(
            "[planner]\n",
            "[planner]\nestimator_penalty_case = \"99\"\nestimator_look_ahead = 70\nestimator_terminal_levels = -1.0\n\
             estimator_bias_per_km = -2.0\nestimator_reach_success = 1.5\nestimator_pitch_levels = 0\n\
             estimator_unmodelled_current = [nan, 0.0]\nestimator_drift_levels = -1.0\nestimator_heading_options = 1\n",
        );
        let e = err(&text);
        let fields = ["penalty_case", "look_ahead", "terminal_levels", "bias_per_km", "reach_success", "pitch_levels"];
        assert!(e.contains("planner.estimator_heading_options = 1"), "{e}");
        for field in fields.into_iter().chain(["unmodelled_current[0]", "drift_levels"]) {
            assert!(e.contains(&format!("planner.estimator_{field}")), "{field}: {e}");
        }
        let ok = example.replace(
            "[planner]\n",
            "[planner]\nestimator_penalty_case = \"3\"\nestimator_look_ahead = 3\nestimator_heading_options = 7\n",
        );
        let other_field_bad = err(&ok.replace("heading_options = 5", "heading_options = 1"));
        assert!(
            other_field_bad.contains("planner.heading_options") && !other_field_bad.contains("estimator_look_ahead"),
            "a valid estimator look-ahead is blamed for another field: {other_field_bad}"
        );
        let sc = Scenario::parse(&ok, Path::new("s.toml")).unwrap();
        assert_eq!(
            (sc.planner.estimator_penalty_case.as_deref(), sc.planner.estimator_look_ahead),
            (Some("3"), Some(3))
        );
        assert_eq!(sc.planner.estimator_heading_options, Some(7));
        let too_large = err(&ok.replace("estimator_heading_options = 7", "estimator_heading_options = 2000"));
        assert!(too_large.contains("planner.estimator_look_ahead = 3 with 2000 options"), "{too_large}");
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
        assert_eq!(plain.planner.link, PlannerLink::Assumed);
        assert!(!toml::to_string(&plain).unwrap().contains("link"), "the default is not written");
        let with = |link: &str| EXAMPLE.replace("[planner]\n", &format!("[planner]\nlink = \"{link}\"\n"));
        let sc = Scenario::parse(&with("scenario_channel"), Path::new("c.toml")).unwrap();
        assert_eq!(sc.planner.link, PlannerLink::ScenarioChannel);
        let e = err(&with("sonar"));
        assert!(e.contains("sonar") && e.contains("scenario_channel"), "{e}");
        // A direct BELLHOP run per sampled distance is refused before BELLHOP is looked for.
        let direct =
            with("scenario_channel").replace("kind = \"analytic\", k = 1.5, freq_hz = 25000.0", "kind = \"bellhop\"");
        let e = err(&direct);
        assert!(e.contains("planner.link") && e.contains("bellhop_grid") && !e.contains("field comms.tl"), "{e}");
    }

    #[test]
    fn the_estimator_counts_expected_pings_unless_the_file_asks_for_reports_only() {
        let plain = Scenario::parse(EXAMPLE, Path::new("e.toml")).unwrap();
        assert_eq!(plain.planner.estimator_tracking, EstimatorTracking::ExpectedPings);
        assert!(!toml::to_string(&plain).unwrap().contains("estimator_tracking"), "the default is not written");
        let with = |v: &str| EXAMPLE.replace("[planner]\n", &format!("[planner]\nestimator_tracking = \"{v}\"\n"));
        let sc = Scenario::parse(&with("reports_only"), Path::new("r.toml")).unwrap();
        assert_eq!(sc.planner.estimator_tracking, EstimatorTracking::ReportsOnly);
        let e = err(&with("hopeful"));
        assert!(e.contains("hopeful") && e.contains("reports_only") && e.contains("expected_pings"), "{e}");
    }

    /// Without `estimator_truth` the rule's truth model is scored; a file's model replaces it and
    /// `"covariance"` scores the filters' covariance; the absent key is not written.
    #[test]
    fn the_estimator_scores_the_rules_truth_model_unless_the_file_says_otherwise() {
        let plain = Scenario::parse(EXAMPLE, Path::new("e.toml")).unwrap();
        assert_eq!(plain.planner.estimator_truth, None);
        assert_eq!(plain.estimator_settings().truth, Some(auto::ASC_TRUTH));
        assert!(!toml::to_string(&plain).unwrap().contains("estimator_truth"), "the rule's is not written");
        let with = |v: &str| EXAMPLE.replace("[planner]\n", &format!("[planner]\nestimator_truth = {v}\n"));
        let truth = "{ drift_m2_s = 0.03, range_noise = { sigma_m = 1.8, per_km_m = 0.0 }, cna_diffusion_m2_s = 0.01 }";
        let sc = Scenario::parse(&with(truth), Path::new("t.toml")).unwrap();
        let spec = sc.estimator_settings().truth.unwrap();
        assert_eq!((spec.drift_m2_s, spec.range_noise.sigma_m, spec.cna_diffusion_m2_s), (0.03, 1.8, 0.01));
        let again = Scenario::parse(&toml::to_string(&sc).unwrap(), Path::new("t.toml")).unwrap();
        assert_eq!(again.planner.estimator_truth, Some(TruthChoice::Model(spec)));
        let covariance = Scenario::parse(&with("\"covariance\""), Path::new("c.toml")).unwrap();
        assert_eq!(covariance.estimator_settings().truth, None);
        let again = Scenario::parse(&toml::to_string(&covariance).unwrap(), Path::new("c.toml")).unwrap();
        assert_eq!(again.planner.estimator_truth, Some(TruthChoice::Cost(CovarianceWord::Covariance)));
        let e = err(&with(&truth.replace("drift_m2_s = 0.03", "drift_m2_s = -0.03")));
        assert!(e.contains("planner.estimator_truth.drift_m2_s") && e.contains(">= 0"), "{e}");
        assert!(Scenario::parse(&with("\"none\""), Path::new("n.toml")).is_err());
    }

    #[test]
    fn an_auv_not_yet_heard_is_ignored_unless_the_file_gives_the_mission_plan() {
        let plain = Scenario::parse(EXAMPLE, Path::new("e.toml")).unwrap();
        assert_eq!(plain.planner.before_first_report, BeforeFirstReport::Ignore);
        let line = "before_first_report = \"ignore\"";
        let planned = EXAMPLE.replace(line, "before_first_report = \"mission_plan\"");
        let sc = Scenario::parse(&planned, Path::new("p.toml")).unwrap();
        assert_eq!(sc.planner.before_first_report, BeforeFirstReport::MissionPlan);
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
        let auv = |fields: &str| {
            EXAMPLE.replace(
                "gps_sd = 1.0",
                &format!("gps_sd = 1.0\nauv = {{ pitch_options = 1, {fields}, nav_diffusion = 0.01 }}"),
            )
        };
        let e = err(&auv("depth = 1.0, min_depth_m = 2.0"));
        assert!(e.contains("cna.auv.depth = 1") && e.contains(">= cna.auv.min_depth_m (2 m)"), "{e}");
        let e = err(&auv("depth = 10.0, min_depth_m = -1.0"));
        assert!(e.contains("cna.auv.min_depth_m"), "{e}");
        let e = err(&EXAMPLE.replace("lane_length = 800.0", "lane_length = 20000.0"));
        assert!(e.contains("field fleet") && e.contains("15 000"), "{e}");
        let e = err(&EXAMPLE
            .replace("heading_options = 5", "heading_options = 1")
            .replace("look_ahead = 5", "look_ahead = 70"));
        assert!(e.contains("field planner.heading_options = 1") && e.contains("field planner.look_ahead = 70"), "{e}");
    }

    #[test]
    fn an_auv_cna_broadcasts_its_estimate_unless_the_file_asks_for_the_counterfactual() {
        let auv = |extra: &str| {
            let cna = format!("gps_sd = 1.0\nauv = {{ pitch_options = 1, depth = 10.0, nav_diffusion = 0.01{extra} }}");
            Scenario::parse(&EXAMPLE.replace("gps_sd = 1.0", &cna), Path::new("a.toml")).unwrap()
        };
        let plain = auv("");
        assert!(!plain.cna.auv.as_ref().unwrap().broadcasts_truth);
        assert!(!toml::to_string(&plain).unwrap().contains("broadcasts_truth"), "the default is not written");
        let exact = auv(", broadcasts_truth = true");
        assert!(exact.cna.auv.as_ref().unwrap().broadcasts_truth);
        let again = Scenario::parse(&toml::to_string(&exact).unwrap(), Path::new("a.toml")).unwrap();
        assert_eq!(again.cna.auv, exact.cna.auv);
        let cna =
            "gps_sd = 1.0\nauv = { pitch_options = 1, depth = 10.0, nav_diffusion = 0.01, broadcasts_truth = \"yes\" }";
        let e = err(&EXAMPLE.replace("gps_sd = 1.0", cna));
        assert!(e.contains("broadcasts_truth") && e.contains("expected a boolean"), "{e}");
    }
}
