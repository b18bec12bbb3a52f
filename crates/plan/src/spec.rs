//! The planner's specification as every front end writes it: [`PlannerSpec`], one table per
//! planner instance (a scenario's `[policy.planner]`, `[policy.planner-estimator]`, a
//! pre-deployment file's `[policy.planner]`, Python's dict), with its tree, distance limits,
//! penalty, deadline, search, mission-long horizon and cost, each default written once here. The
//! cost is a tagged kind with its own parameters: Hudson's error model ([`HudsonCost`]) or the
//! estimator-aware cost ([`EstimatorCost`]), whose every setting is an optional override of the
//! planner's rule for the mission ([`crate::auto::for_mission`]). The vehicle's facts (speed,
//! decision period, turn limit, kind) are a separate [`Platform`]; [`PlannerSpec::config`] joins
//! the two into the [`PlannerConfig`] the search runs.

use crate::auto::{self, EstimatorSettings, MissionFacts};
use crate::error_model::{BearingMode, CostMode, ErrorModel};
use crate::estimator::Aggregate;
use crate::horizon::HorizonSpec;
use crate::motion::{CnaKind, MotionConfig};
use crate::penalty::{PenaltyCase, PenaltyFn, PenaltyPair};
use crate::planner::{Algorithm, CostSpec, Deadline, DistanceLimits, PlannerConfig, SearchConfig};
use crate::true_error::TruthSpec;
use crate::PlanError;
use coopnav_core::validation::{CheckFields, Problem, Problems};
use serde::{Deserialize, Serialize};

/// A of Hudson's planner when its table sets none (Hudson 2012, Table 5.1's five headings).
pub const HUDSON_HEADING_OPTIONS: usize = 5;
/// L of Hudson's planner when its table sets none (the closed-loop evaluation's five levels).
pub const HUDSON_LOOK_AHEAD: usize = 5;
/// The Table 5.2 case a planner flies when neither its table nor its rule names one.
pub const DEFAULT_PENALTY_CASE: PenaltyCase = PenaltyCase::C1;

/// The CNA as a vehicle: what it is and how it moves, apart from how it plans.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Platform {
    /// Transit speed s, m/s (> 0).
    pub speed: f64,
    /// Decision period τ, s (> 0).
    pub tau: f64,
    /// Turn-rate limit ψ̇max, degrees per second (Table 5.1: 4).
    #[serde(default = "default_turn_rate")]
    pub max_turn_rate_deg_s: f64,
    /// An ASC or an AUV CNA with its pitch options.
    pub cna: CnaKind,
}

fn default_turn_rate() -> f64 {
    4.0
}

impl Platform {
    /// The motion options with `heading_options` headings per level.
    pub fn motion(&self, heading_options: usize) -> MotionConfig {
        MotionConfig {
            speed: self.speed,
            tau: self.tau,
            heading_options,
            max_turn_rate_deg_s: self.max_turn_rate_deg_s,
            cna: self.cna,
        }
    }
}

/// The look-ahead tree. Every key absent: Hudson's cost takes [`HUDSON_HEADING_OPTIONS`] and
/// [`HUDSON_LOOK_AHEAD`], every level's pitch options and the thesis's pitch model; the
/// estimator-aware cost takes the rule's values for the mission.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TreeSpec {
    /// A: heading options per level (≥ 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heading_options: Option<usize>,
    /// L: look-ahead levels (the tree has L + 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub look_ahead: Option<usize>,
    /// With an AUV CNA, how many levels offer the pitch options, from level 0 (≥ 1; deeper
    /// levels hold the pitch). Fewer pitch levels make a deeper look-ahead affordable
    /// ([`CnaKind::Auv`]'s `pitch_levels`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pitch_levels: Option<usize>,
    /// With an AUV CNA, model each step as the engine flies it: starting level, its pitch cut at
    /// the limit and its depth at the depth limits ([`CnaKind::Auv`]'s `level_off`); false is the
    /// thesis's model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub level_off: Option<bool>,
}

impl TreeSpec {
    fn is_empty(&self) -> bool {
        *self == TreeSpec::default()
    }
}

/// The distance penalties: a Table 5.2 case by its id, or a custom primary/look-ahead pair.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PenaltySpec {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub case: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub primary: Option<PenaltyFn>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub look_ahead: Option<PenaltyFn>,
}

impl PenaltySpec {
    /// A Table 5.2 case.
    pub fn case(case: PenaltyCase) -> Self {
        PenaltySpec { case: Some(case.id().to_string()), primary: None, look_ahead: None }
    }

    /// The penalty pair, or the problem with the keys given (field names relative to `prefix`).
    pub fn pair(&self, prefix: &str) -> Result<PenaltyPair, Problem> {
        match (&self.case, self.primary, self.look_ahead) {
            (Some(id), None, None) => PenaltyCase::from_id(id).map(PenaltyCase::penalties).ok_or_else(|| {
                let ids: Vec<&str> = PenaltyCase::ALL.iter().map(|c| c.id()).collect();
                let allowed = format!("a Table 5.2 case: {}", ids.join(", "));
                Problem { field: format!("{prefix}case"), value: format!("'{id}'"), allowed }
            }),
            (None, Some(primary), Some(look_ahead)) => Ok(PenaltyPair { primary, look_ahead }),
            _ => {
                let keys: Vec<&str> = [
                    ("case", self.case.is_some()),
                    ("primary", self.primary.is_some()),
                    ("look_ahead", self.look_ahead.is_some()),
                ]
                .into_iter()
                .filter_map(|(k, set)| set.then_some(k))
                .collect();
                let given =
                    if keys.is_empty() { "none of case, primary, look_ahead".into() } else { keys.join(" and ") };
                let trimmed = prefix.strip_suffix('.').unwrap_or(prefix).to_string();
                let allowed = "either case = \"<Table 5.2 case>\" or both primary and look_ahead".into();
                Err(Problem { field: trimmed, value: given, allowed })
            }
        }
    }

    /// The Table 5.2 case this names (None: a custom pair or an unknown id).
    pub fn preset(&self) -> Option<PenaltyCase> {
        self.case.as_deref().and_then(PenaltyCase::from_id)
    }
}

/// How the tree is searched (the decision's time budget is [`PlannerSpec::deadline`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchSpec {
    #[serde(default)]
    pub algorithm: Algorithm,
    /// Search the top tree levels with rayon (default false: a closed loop runs its missions on
    /// the threads, one decision on one; the decision is the same either way).
    #[serde(default)]
    pub parallel: bool,
    /// See [`SearchConfig::parallel_after_nodes`].
    #[serde(default = "parallel_after_nodes")]
    pub parallel_after_nodes: u64,
    /// See [`SearchConfig::parallel_after_us`].
    #[serde(default = "parallel_after_us")]
    pub parallel_after_us: u64,
    /// See [`SearchConfig::tie_tolerance`].
    #[serde(default = "tie_tolerance")]
    pub tie_tolerance: f64,
}

fn parallel_after_nodes() -> u64 {
    SearchConfig::default().parallel_after_nodes
}
fn parallel_after_us() -> u64 {
    SearchConfig::default().parallel_after_us
}
fn tie_tolerance() -> f64 {
    SearchConfig::default().tie_tolerance
}

impl Default for SearchSpec {
    fn default() -> Self {
        SearchSpec {
            algorithm: Algorithm::default(),
            parallel: false,
            parallel_after_nodes: parallel_after_nodes(),
            parallel_after_us: parallel_after_us(),
            tie_tolerance: tie_tolerance(),
        }
    }
}

/// Hudson's error model (Hudson 2012, eq. 1) and the modelled errors it starts from.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HudsonCost {
    /// Velocity-estimate error α, m²/s (Table 5.1: 0.1).
    #[serde(default = "alpha")]
    pub alpha: f64,
    /// The line of sight's angle between pings ([`BearingMode`]).
    #[serde(default)]
    pub bearing: BearingMode,
    /// What each AUV's term counts ([`CostMode`]).
    #[serde(default)]
    pub terms: CostMode,
    /// Initial modelled σ₀ and ε₀, m (Table 5.1: 1 m).
    #[serde(default = "one")]
    pub sigma0: f64,
    #[serde(default = "one")]
    pub eps0: f64,
    /// Model lost pings in the tracked error (expected value over the success likelihood);
    /// false = the thesis's behaviour (every ping assumed received).
    #[serde(default)]
    pub model_lost_pings: bool,
}

fn alpha() -> f64 {
    ErrorModel::default().alpha
}
fn one() -> f64 {
    1.0
}

impl Default for HudsonCost {
    fn default() -> Self {
        HudsonCost {
            alpha: alpha(),
            bearing: BearingMode::default(),
            terms: CostMode::default(),
            sigma0: one(),
            eps0: one(),
            model_lost_pings: false,
        }
    }
}

impl HudsonCost {
    pub fn error_model(&self) -> ErrorModel {
        ErrorModel { alpha: self.alpha, bearing: self.bearing, cost: self.terms }
    }
}

/// How the estimator-aware planner's model of each AUV's filter covariance moves between that
/// AUV's status reports.
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

/// The estimator cost's `truth`: a truth model, or the word `"covariance"` (the filters' covariance).
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

/// The estimator-aware cost (the `estimator` module; docs/models.md#estimator-cost). Every
/// optional key absent takes the planner's rule's value for the mission
/// ([`auto::for_mission`]); a key set overrides it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EstimatorCost {
    /// How the AUVs' terms are joined into a level's cost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aggregate: Option<Aggregate>,
    /// k_b: the range bias assumed, m of 1-σ per km of range (estimator step 4). The filters' own
    /// sound-speed term is 1000·σ_c/c (2 m/km for their default σ_c = 3 m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bias_per_km: Option<f64>,
    /// Also price the range bias the water's sound-speed profile causes between the CNA's depth
    /// and each AUV's, against the speed the filters convert at (`BiasTable`; invented,
    /// docs/models.md#estimator-cost).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bias_profile: Option<bool>,
    /// Know the schedule: beyond a slant range set by each AUV's slot timing no ping reaches it
    /// (half-duplex; invented, docs/models.md#closed-loop-schedule).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slot_reach: Option<bool>,
    /// H: levels of cost-to-go at each leaf (estimator step 6; 0 = none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub terminal_levels: Option<f64>,
    /// p_u: success probability that makes a ping useful for the reach cost-to-go (estimator
    /// step 7; 0 = none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reach_success: Option<f64>,
    /// Add the CNA's own horizontal variance to each ping's range variance (estimator step 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cna_variance: Option<bool>,
    /// A truth model: score the AUVs' expected true error under their filters' gains
    /// (`true_error`); `"covariance"`: the filters' covariance instead.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub truth: Option<TruthChoice>,
    /// The water current the filters do not model, east and north, m/s (estimator step 1b).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unmodelled_current: Option<[f64; 2]>,
    /// The water current, east and north (m/s), for filters that estimate it (`current_states`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub current: Option<[f64; 2]>,
    /// m of step 1b: levels over which the unmodelled current's drift builds up unseen (≥ 0;
    /// [`crate::EstimatorSpec`]'s default). Written only when set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drift_levels: Option<f64>,
    /// What the planner's model of an AUV's covariance takes between its reports.
    #[serde(default, skip_serializing_if = "EstimatorTracking::is_expected_pings")]
    pub tracking: EstimatorTracking,
}

impl EstimatorCost {
    /// m of step 1b: the file's, else the estimator's default.
    pub fn drift_levels(&self) -> f64 {
        self.drift_levels.unwrap_or(crate::EstimatorSpec::default().drift_levels)
    }
}

/// What a planner minimises, with its own parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PlannerCost {
    Hudson(HudsonCost),
    Estimator(EstimatorCost),
}

/// One planner: its tree, limits, penalty, deadline, search, horizon and cost.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannerSpec {
    #[serde(default, skip_serializing_if = "TreeSpec::is_empty")]
    pub tree: TreeSpec,
    /// CNA–AUV distance limits, m (Table 5.1: 100 and 1000).
    #[serde(default)]
    pub limits: DistanceLimits,
    /// Absent: case [`DEFAULT_PENALTY_CASE`], or with the estimator cost the rule's case.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub penalty: Option<PenaltySpec>,
    /// The time budget of one decision (default: τ − 1 s, the thesis's real-time budget).
    #[serde(default)]
    pub deadline: Deadline,
    #[serde(default)]
    pub search: SearchSpec,
    /// The mission-long horizon above the tree (`horizon` module), with the estimator cost only;
    /// absent: on with its defaults.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizon: Option<HorizonSpec>,
    pub cost: PlannerCost,
}

impl PlannerSpec {
    /// Hudson's planner with every default.
    pub fn hudson() -> Self {
        PlannerSpec::with_cost(PlannerCost::Hudson(HudsonCost::default()))
    }

    /// The estimator-aware planner with every setting from the rule.
    pub fn estimator() -> Self {
        PlannerSpec::with_cost(PlannerCost::Estimator(EstimatorCost::default()))
    }

    fn with_cost(cost: PlannerCost) -> Self {
        PlannerSpec {
            tree: TreeSpec::default(),
            limits: DistanceLimits::default(),
            penalty: None,
            deadline: Deadline::default(),
            search: SearchSpec::default(),
            horizon: None,
            cost,
        }
    }

    /// The Hudson cost's parameters (the defaults under the estimator cost, whose closed-loop
    /// adapter still tracks Hudson's modelled error for its statistics).
    pub fn hudson_cost(&self) -> HudsonCost {
        match self.cost {
            PlannerCost::Hudson(h) => h,
            PlannerCost::Estimator(_) => HudsonCost::default(),
        }
    }

    /// The estimator cost's parameters, None under Hudson's.
    pub fn estimator_cost(&self) -> Option<&EstimatorCost> {
        match &self.cost {
            PlannerCost::Estimator(e) => Some(e),
            PlannerCost::Hudson(_) => None,
        }
    }

    /// The horizon layer the planner runs (None: none; Hudson's cost never has one).
    pub fn horizon(&self) -> Option<HorizonSpec> {
        match self.cost {
            PlannerCost::Estimator(_) => Some(self.horizon.unwrap_or_default()).filter(|h| h.enabled),
            PlannerCost::Hudson(_) => None,
        }
    }

    /// With the estimator cost, its settings for the mission `facts`: the rule's
    /// ([`auto::for_mission`]), each replaced by the key this spec sets (the tree's A, L, pitch
    /// levels and level-off, the penalty's case, the cost's own keys). None under Hudson's cost.
    pub fn estimator_settings(&self, facts: &MissionFacts) -> Option<EstimatorSettings> {
        let c = self.estimator_cost()?;
        let rule = auto::for_mission(facts);
        let t = &self.tree;
        Some(EstimatorSettings {
            heading_options: t.heading_options.unwrap_or(rule.heading_options),
            look_ahead: t.look_ahead.unwrap_or(rule.look_ahead),
            pitch_levels: t.pitch_levels.or(rule.pitch_levels),
            aggregate: c.aggregate.unwrap_or(rule.aggregate),
            bias_per_km: c.bias_per_km.unwrap_or(rule.bias_per_km),
            bias_profile: c.bias_profile.unwrap_or(rule.bias_profile),
            level_off: t.level_off.unwrap_or(rule.level_off),
            slot_reach: c.slot_reach.unwrap_or(rule.slot_reach),
            terminal_levels: c.terminal_levels.unwrap_or(rule.terminal_levels),
            reach_success: c.reach_success.unwrap_or(rule.reach_success),
            penalty_case: match &self.penalty {
                Some(p) => p.preset(),
                None => rule.penalty_case,
            },
            cna_variance: c.cna_variance.unwrap_or(rule.cna_variance),
            truth: c.truth.map_or(rule.truth, TruthChoice::model),
            unmodelled_current: c.unmodelled_current.unwrap_or(rule.unmodelled_current),
            current: c.current.unwrap_or(rule.current),
        })
    }

    /// The search's configuration on `platform` for the mission `facts`, whose survey spans
    /// `survey_extent_m` (the diagonal of the box around every AUV's plan). The cost is left as
    /// Hudson's: the estimator cost needs the filters' range noise, which its caller knows.
    /// The penalties: this spec's; else, with the estimator cost, the rule's case, or none (case
    /// "2") where the horizon takes over from them ([`HorizonSpec::replaces_distance_penalties`]);
    /// else [`DEFAULT_PENALTY_CASE`]. An unknown case falls back to the default (`check_fields`
    /// refuses it).
    pub fn config(&self, platform: &Platform, facts: &MissionFacts, survey_extent_m: f64) -> PlannerConfig {
        let settings = self.estimator_settings(facts);
        let t = &self.tree;
        let (heading_options, look_ahead) = match &settings {
            Some(s) => (s.heading_options, s.look_ahead),
            None => (t.heading_options.unwrap_or(HUDSON_HEADING_OPTIONS), t.look_ahead.unwrap_or(HUDSON_LOOK_AHEAD)),
        };
        let mut motion = platform.motion(heading_options);
        if let CnaKind::Auv { pitch_levels, level_off, .. } = &mut motion.cna {
            match &settings {
                Some(s) => (*pitch_levels, *level_off) = (s.pitch_levels, s.level_off),
                None => {
                    *pitch_levels = t.pitch_levels.or(*pitch_levels);
                    *level_off = t.level_off.unwrap_or(*level_off);
                }
            }
        }
        let penalties = match (&self.penalty, &settings) {
            (Some(p), _) => p.pair("").unwrap_or_else(|_| DEFAULT_PENALTY_CASE.penalties()),
            (None, Some(s)) => match s.penalty_case {
                Some(case) => case.penalties(),
                None if self
                    .horizon()
                    .is_some_and(|h| h.replaces_distance_penalties(survey_extent_m, &self.limits)) =>
                {
                    PenaltyCase::C2.penalties()
                }
                None => DEFAULT_PENALTY_CASE.penalties(),
            },
            (None, None) => DEFAULT_PENALTY_CASE.penalties(),
        };
        let s = &self.search;
        PlannerConfig {
            look_ahead,
            motion,
            error: self.hudson_cost().error_model(),
            cost: CostSpec::Hudson,
            limits: self.limits,
            penalties,
            search: SearchConfig {
                algorithm: s.algorithm,
                parallel: s.parallel,
                parallel_after_nodes: s.parallel_after_nodes,
                parallel_after_us: s.parallel_after_us,
                deadline: self.deadline,
                tie_tolerance: s.tie_tolerance,
            },
        }
    }

    /// Every bad setting at once, named by its path in this spec (`tree.look_ahead`) and, for
    /// the vehicle's, in [`Platform`] (`platform.speed`).
    pub fn validate(&self, platform: &Platform, facts: &MissionFacts, survey_extent_m: f64) -> Result<(), PlanError> {
        let mut p = Problems::new();
        self.check(platform, facts, survey_extent_m, "", &mut p);
        Ok(p.finish()?)
    }

    /// [`PlannerSpec::validate`]'s checks, each field named after `prefix`.
    pub fn check(
        &self,
        platform: &Platform,
        facts: &MissionFacts,
        survey_extent_m: f64,
        prefix: &str,
        p: &mut Problems,
    ) {
        let field = |name: &str| format!("{prefix}{name}");
        if let Some(penalty) = &self.penalty {
            if let Err(problem) = penalty.pair(&field("penalty.")) {
                p.push(problem.field, problem.value, problem.allowed);
            }
            if let Some(pair) = penalty.primary.zip(penalty.look_ahead) {
                PenaltyPair { primary: pair.0, look_ahead: pair.1 }.check_fields(&field("penalty."), p);
            }
        }
        if self.tree.pitch_levels == Some(0) {
            p.push(field("tree.pitch_levels"), "0", ">= 1 (or absent: every level)");
        }
        match self.cost {
            PlannerCost::Hudson(h) => {
                p.non_negative(&field("cost.alpha"), h.alpha);
                p.positive(&field("cost.sigma0"), h.sigma0);
                p.non_negative(&field("cost.eps0"), h.eps0);
                if self.horizon.is_some() {
                    p.push(
                        field("horizon"),
                        "a table",
                        "none with cost.kind = \"hudson\" (the horizon serves the estimator cost)",
                    );
                }
            }
            PlannerCost::Estimator(c) => {
                let prefix = field("cost.");
                if let Some(h) = c.terminal_levels {
                    p.non_negative(&format!("{prefix}terminal_levels"), h);
                }
                if let Some(p_u) = c.reach_success {
                    p.probability(&format!("{prefix}reach_success"), p_u);
                }
                if let Some(k_b) = c.bias_per_km {
                    p.non_negative(&format!("{prefix}bias_per_km"), k_b);
                }
                for (key, current) in [("unmodelled_current", c.unmodelled_current), ("current", c.current)] {
                    if let Some([east, north]) = current {
                        p.finite(&format!("{prefix}{key}[0]"), east);
                        p.finite(&format!("{prefix}{key}[1]"), north);
                    }
                }
                if let Some(m) = c.drift_levels {
                    p.non_negative(&format!("{prefix}drift_levels"), m);
                }
                if let Some(truth) = c.truth.and_then(TruthChoice::model) {
                    truth.check_fields(&format!("{prefix}truth."), p);
                }
            }
        }
        if let Some(h) = &self.horizon {
            h.check_fields(&field("horizon."), p);
        }
        if let Err(PlanError::Invalid(found)) = self.config(platform, facts, survey_extent_m).validate() {
            for bad in found.0 {
                // The penalties, the error model and the cost are checked above, by their own names.
                let Some(name) = spec_field(&bad.field) else { continue };
                p.push(name.replace("{prefix}", prefix), bad.value, bad.allowed);
            }
        }
    }
}

/// Where a [`PlannerConfig`] setting sits in a spec and its platform (`{prefix}` stands for the
/// spec's own prefix); None for what the spec checks by its own names.
fn spec_field(field: &str) -> Option<String> {
    let name = match field {
        "look_ahead" => "{prefix}tree.look_ahead".to_string(),
        "motion.heading_options" => "{prefix}tree.heading_options".to_string(),
        "limits" => "{prefix}limits".to_string(),
        f if f.starts_with("penalties.") || f.starts_with("error.") || f.starts_with("cost.") => return None,
        f => match f.strip_prefix("search.") {
            Some(rest) if rest.starts_with("deadline") => format!("{{prefix}}{rest}"),
            Some(rest) => format!("{{prefix}}search.{rest}"),
            None => format!("platform.{}", f.strip_prefix("motion.").unwrap_or(f)),
        },
    };
    Some(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::auto::CnaFact;

    fn asc(n: usize) -> MissionFacts {
        MissionFacts { n_auvs: n, cna: CnaFact::Asc, adcp_current: [0.05, 0.0], filters_estimate_current: false }
    }

    fn platform() -> Platform {
        Platform { speed: 2.0, tau: 30.0, max_turn_rate_deg_s: 4.0, cna: CnaKind::Asc {} }
    }

    fn read(text: &str) -> Result<PlannerSpec, String> {
        toml::from_str(text).map_err(|e| e.to_string())
    }

    /// An empty Hudson table is Hudson's planner with every default, written once: A = 5, L = 5,
    /// case 1, τ − 1 s, one thread, α = 0.1, σ₀ = ε₀ = 1.
    #[test]
    fn an_empty_hudson_table_is_every_default() {
        let spec = read("cost = { kind = \"hudson\" }").unwrap();
        assert_eq!(spec, PlannerSpec::hudson());
        let cfg = spec.config(&platform(), &asc(3), 0.0);
        assert_eq!((cfg.motion.heading_options, cfg.look_ahead), (5, 5));
        assert_eq!(cfg.penalties, PenaltyCase::C1.penalties());
        assert_eq!(cfg.search.deadline, Deadline::TauMinus { margin_s: 1.0 });
        assert!(!cfg.search.parallel);
        assert_eq!(cfg.error, ErrorModel::default());
        assert_eq!((spec.hudson_cost().sigma0, spec.hudson_cost().eps0), (1.0, 1.0));
        assert_eq!(spec.estimator_settings(&asc(3)), None);
        assert_eq!(spec.horizon(), None);
    }

    /// With the estimator cost and no key set, the settings are the rule's; each key set
    /// replaces one, the rest stay the rule's.
    #[test]
    fn the_estimator_cost_takes_the_rule_unless_a_key_overrides_it() {
        let spec = read("cost = { kind = \"estimator\" }").unwrap();
        assert_eq!(spec.estimator_settings(&asc(8)), Some(auto::for_mission(&asc(8))));
        let cfg = spec.config(&platform(), &asc(8), 0.0);
        assert_eq!((cfg.motion.heading_options, cfg.look_ahead), (21, 2));
        assert_eq!(cfg.penalties, PenaltyCase::C3.penalties(), "the rule's case at N = 8");
        let spec = read(
            "tree = { look_ahead = 3 }\npenalty = { case = \"4\" }\n\
             cost = { kind = \"estimator\", aggregate = \"worst_auv\", truth = \"covariance\" }",
        )
        .unwrap();
        let s = spec.estimator_settings(&asc(8)).unwrap();
        let rule = auto::for_mission(&asc(8));
        assert_eq!((s.look_ahead, s.heading_options), (3, rule.heading_options));
        assert_eq!((s.aggregate, s.truth, s.penalty_case), (Aggregate::WorstAuv, None, Some(PenaltyCase::C4)));
        assert_eq!((s.terminal_levels, s.bias_per_km), (rule.terminal_levels, rule.bias_per_km));
        assert_eq!(spec.config(&platform(), &asc(8), 0.0).penalties, PenaltyCase::C4.penalties());
    }

    /// Without a penalty of its own or of the rule, the estimator's tree drops the distance
    /// penalties where the horizon takes over (a survey wider than twice the maximum distance),
    /// and keeps case 1 otherwise or with the horizon off.
    #[test]
    fn the_horizon_replaces_the_penalties_only_on_wide_surveys() {
        let spec = PlannerSpec::estimator();
        assert_eq!(spec.config(&platform(), &asc(3), 2500.0).penalties, PenaltyCase::C2.penalties());
        assert_eq!(spec.config(&platform(), &asc(3), 1500.0).penalties, PenaltyCase::C1.penalties());
        let off = read("horizon = { enabled = false }\ncost = { kind = \"estimator\" }").unwrap();
        assert_eq!(off.horizon(), None);
        assert_eq!(off.config(&platform(), &asc(3), 2500.0).penalties, PenaltyCase::C1.penalties());
        let hudson = PlannerSpec::hudson();
        assert_eq!(hudson.config(&platform(), &asc(3), 2500.0).penalties, PenaltyCase::C1.penalties());
    }

    /// Unknown keys, unknown cost kinds and a missing cost are refused, each naming the key.
    #[test]
    fn unknown_keys_and_kinds_are_refused() {
        let e = read("tree = { depth = 3 }\ncost = { kind = \"hudson\" }").unwrap_err();
        assert!(e.contains("unknown field `depth`") && e.contains("heading_options"), "{e}");
        let e = read("cost = { kind = \"fisher\" }").unwrap_err();
        assert!(e.contains("fisher") && e.contains("hudson") && e.contains("estimator"), "{e}");
        let e = read("cost = { kind = \"hudson\", aggregate = \"trace_sum\" }").unwrap_err();
        assert!(e.contains("aggregate"), "an estimator key under Hudson's cost: {e}");
        let e = read("limits = { min = 1.0, max = 2.0 }").unwrap_err();
        assert!(e.contains("cost"), "{e}");
    }

    /// Every bad field is named by its path in the spec, with what is allowed.
    #[test]
    fn bad_fields_are_named_by_their_path() {
        let spec = read(
            "tree = { heading_options = 1, look_ahead = 70, pitch_levels = 0 }\npenalty = { case = \"zz\" }\n\
             deadline = { kind = \"tau_minus\", margin_s = 40.0 }\ncost = { kind = \"hudson\", sigma0 = -1.0 }",
        )
        .unwrap();
        let e = spec.validate(&platform(), &asc(3), 0.0).unwrap_err().to_string();
        for field in
            ["tree.heading_options = 1", "tree.look_ahead = 70", "tree.pitch_levels = 0", "penalty.case = 'zz'"]
        {
            assert!(e.contains(&format!("field {field}")), "{field}: {e}");
        }
        assert!(e.contains("deadline.margin_s") && e.contains("cost.sigma0"), "{e}");
        assert!(e.contains("a Table 5.2 case: 1, 2a"), "{e}");
        let both =
            read("penalty = { case = \"1\", primary = { kind = \"none\" } }\ncost = { kind = \"hudson\" }").unwrap();
        let e = both.validate(&platform(), &asc(3), 0.0).unwrap_err().to_string();
        assert!(e.contains("field penalty = case and primary"), "{e}");
        let horizon = read("horizon = { segments = 9 }\ncost = { kind = \"hudson\" }").unwrap();
        let e = horizon.validate(&platform(), &asc(3), 0.0).unwrap_err().to_string();
        assert!(e.contains("field horizon = ") && e.contains("horizon.segments = 9"), "{e}");
        let bad = read("cost = { kind = \"estimator\", reach_success = 1.5, current = [nan, 0.0] }").unwrap();
        let e = bad.validate(&platform(), &asc(3), 0.0).unwrap_err().to_string();
        assert!(e.contains("cost.reach_success = 1.5") && e.contains("cost.current[0]"), "{e}");
        PlannerSpec::estimator().validate(&platform(), &asc(8), 0.0).unwrap();
    }

    /// A spec written out reads back as itself, and only what was set is written.
    #[test]
    fn a_spec_round_trips_writing_only_what_was_set() {
        let text = "tree = { look_ahead = 3 }\ncost = { kind = \"estimator\", tracking = \"reports_only\" }";
        let spec = read(text).unwrap();
        let written = toml::to_string(&spec).unwrap();
        assert_eq!(read(&written).unwrap(), spec);
        assert!(!written.contains("heading_options") && !written.contains("aggregate"), "{written}");
        let custom = "penalty = { primary = { kind = \"none\" }, look_ahead = { kind = \"doubling\" } }\n\
                      cost = { kind = \"hudson\", alpha = 0.2, bearing = \"slant3d\" }";
        let spec = read(custom).unwrap();
        assert_eq!(read(&toml::to_string(&spec).unwrap()).unwrap(), spec);
        let cfg = spec.config(&platform(), &asc(3), 0.0);
        assert_eq!(cfg.penalties, PenaltyPair { primary: PenaltyFn::None {}, look_ahead: PenaltyFn::Doubling {} });
        assert_eq!((cfg.error.alpha, cfg.error.bearing), (0.2, BearingMode::Slant3d));
    }
}
