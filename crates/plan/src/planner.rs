//! The planner's public face: configuration, the survey-AUV forecast it reads, the
//! [`Planner`] trait every CNA path planner implements (the closed loop's baselines are
//! `coopnav_sim::policy::CnaPolicy`s instead), and
//! [`LookAheadPlanner`], the receding-horizon tree-search planner of Hudson Ch. 3.
//!
//! Each call plans one decision from the CNA's current pose and the AUVs' current modelled
//! errors; the caller executes it, then updates the errors from the positions that really
//! happened (in pre-deployment mode they are the forecast ones).

use crate::cost_model::{CostModel, HudsonCost, Tangential};
use crate::current_states::{CurrentState, CurrentStates, CurrentStatesCost};
use crate::error_model::{to_arr, AuvError, ErrorModel};
use crate::estimator::{AuvEstimate, BiasTable, EkfCost, EstimatorSpec, LinkModel, LinkTable};
use crate::horizon::{best_order, GoalTerm, HorizonSpec, World};
use crate::motion::{CnaPose, FastOption, FastPose, MotionConfig, MotionOption};
use crate::penalty::PenaltyPair;
use crate::search::{branch_and_bound, Shared};
use crate::tree::{reaches, rest_floors, Tree};
use crate::true_error::{TrueErrorCost, TrueState, TruthInput, TruthSpec};
use crate::{brute, PlanError, SearchOutcome};
use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::Vec3;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// CNA–AUV distance limits, metres (Table 5.1: 100 and 1000).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DistanceLimits {
    pub min: f64,
    pub max: f64,
}

impl Default for DistanceLimits {
    fn default() -> Self {
        DistanceLimits { min: 100.0, max: 1000.0 }
    }
}

/// Which search computes the decision (both give the same decision and cost).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Algorithm {
    #[default]
    BranchAndBound,
    BruteForce,
}

/// The time budget of one decision (docs/models.md#hudson-time-budget).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Deadline {
    /// Search the full depth, however long it takes (deterministic).
    None,
    /// τ minus a margin (seconds): iterative deepening, the deepest completed level wins (levels
    /// are skipped once the full tree surely fits in the budget left: `LookAheadPlanner::run`).
    TauMinus { margin_s: f64 },
    /// A fixed budget in seconds, with iterative deepening.
    Seconds { seconds: f64 },
}

impl Default for Deadline {
    fn default() -> Self {
        Deadline::TauMinus { margin_s: 1.0 }
    }
}

/// How the tree is searched.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchConfig {
    #[serde(default)]
    pub algorithm: Algorithm,
    /// Use rayon over the top levels of the tree (see `parallel_after_nodes`).
    #[serde(default = "yes")]
    pub parallel: bool,
    /// The parallel mode searches on the calling thread first and shares the rest of the tree
    /// among rayon's threads only once it has expanded this many nodes; subtrees it finished are
    /// not searched again. Small trees thus never pay for the threads (0 = share at once).
    /// Invented; chosen with `coopnav bench planner`.
    #[serde(default = "default_parallel_after_nodes")]
    pub parallel_after_nodes: u64,
    /// ... and once this many microseconds have passed since the search began: waking the
    /// threads and enumerating the tasks costs about 0.1 ms, so a tree whose whole search is
    /// shorter than a few of those only loses by sharing. 0 = the node count alone decides.
    /// Invented; chosen with `coopnav bench planner`. Only the node count depends on it (and so on
    /// timing), never the decision or its cost.
    #[serde(default = "default_parallel_after_us")]
    pub parallel_after_us: u64,
    #[serde(default)]
    pub deadline: Deadline,
    /// Relative tolerance of the tie-break: every level-0 option whose minimum path cost is within
    /// `tie_tolerance` × the overall minimum of it ties, and the lowest option index wins (so
    /// mirror-symmetric set-ups are not decided by rounding). Invented: 1e-9.
    #[serde(default = "default_tie_tolerance")]
    pub tie_tolerance: f64,
}

fn yes() -> bool {
    true
}

fn default_tie_tolerance() -> f64 {
    1e-9
}

fn default_parallel_after_nodes() -> u64 {
    2_000
}

fn default_parallel_after_us() -> u64 {
    250
}

impl Default for SearchConfig {
    fn default() -> Self {
        SearchConfig {
            algorithm: Algorithm::default(),
            parallel: true,
            parallel_after_nodes: default_parallel_after_nodes(),
            parallel_after_us: default_parallel_after_us(),
            deadline: Deadline::default(),
            tie_tolerance: default_tie_tolerance(),
        }
    }
}

/// What the planner minimises (Hudson 2012, Ch. 3, eqs. 1 and 3 for Hudson's; `estimator` module for the other).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum CostSpec {
    /// Hudson eq. (1): isotropic tangential growth, parameters in `PlannerConfig::error`.
    #[default]
    Hudson,
    /// The survey AUVs' own EKF covariances ([`PlanInput::estimates`]).
    Estimator(EstimatorSpec),
}

/// Everything the look-ahead planner needs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannerConfig {
    /// Look-ahead levels L (the tree has L + 1 levels).
    pub look_ahead: usize,
    pub motion: MotionConfig,
    #[serde(default)]
    pub error: ErrorModel,
    #[serde(default)]
    pub cost: CostSpec,
    #[serde(default)]
    pub limits: DistanceLimits,
    pub penalties: PenaltyPair,
    #[serde(default)]
    pub search: SearchConfig,
}

/// Largest tree we accept: (A·B)^(L+1) leaves.
pub const MAX_LEAVES: f64 = 1e12;

impl PlannerConfig {
    /// Every bad setting at once (`PlanError::Invalid`), each named by its path in this struct.
    pub fn validate(&self) -> Result<(), PlanError> {
        Ok(CheckFields::validate(self, "")?)
    }

    fn budget(&self) -> Option<Duration> {
        match self.search.deadline {
            Deadline::None => None,
            Deadline::TauMinus { margin_s } => Some(Duration::from_secs_f64(self.motion.tau - margin_s)),
            Deadline::Seconds { seconds } => Some(Duration::from_secs_f64(seconds)),
        }
    }
}

impl CheckFields for PlannerConfig {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        let field = |name: &str| format!("{prefix}{name}");
        self.motion.check_fields(&field("motion."), p);
        let m = self.motion.options().len();
        let leaves = (m as f64).powi(self.look_ahead as i32 + 1);
        if m > 4096 || leaves > MAX_LEAVES || self.look_ahead >= crate::tree::MAX_LEVELS {
            p.push(
                field("look_ahead"),
                format!("{} with {m} options", self.look_ahead),
                "look_ahead <= 63 and (heading_options * pitch_options)^(look_ahead + 1) <= 1e12",
            );
        }
        p.non_negative(&field("error.alpha"), self.error.alpha);
        let DistanceLimits { min, max } = self.limits;
        if !(min.is_finite() && max.is_finite() && min >= 0.0 && min < max) {
            p.push(field("limits"), format!("min {min}, max {max}"), "0 <= min < max (metres)");
        }
        if let CostSpec::Estimator(e) = &self.cost {
            e.check_fields(&field("cost."), p);
        }
        self.penalties.check_fields(&field("penalties."), p);
        let tol = self.search.tie_tolerance;
        p.check(
            &field("search.tie_tolerance"),
            tol,
            |v| (0.0..=1e-3).contains(&v),
            "0 <= tie_tolerance <= 1e-3 (relative)",
        );
        match self.search.deadline {
            Deadline::TauMinus { margin_s } => p.require(
                &field("search.deadline.margin_s"),
                margin_s,
                margin_s >= 0.0 && margin_s < self.motion.tau,
                "0 <= margin_s < motion.tau",
            ),
            Deadline::Seconds { seconds } => p.positive(&field("search.deadline.seconds"), seconds),
            Deadline::None => {}
        }
    }
}

/// Where the survey AUVs will be: position of AUV `k` at time `t`, or `None` past the end of
/// what is known (the horizon is then truncated, docs/models.md#hudson-search).
pub trait AuvForecast {
    fn n_auvs(&self) -> usize;
    fn position(&self, k: usize, t: f64) -> Option<Vec3>;
}

/// A forecast from a closure `(k, t) -> Option<Vec3>`.
pub struct FnForecast<F> {
    pub n: usize,
    pub f: F,
}

impl<F: Fn(usize, f64) -> Option<Vec3>> AuvForecast for FnForecast<F> {
    fn n_auvs(&self) -> usize {
        self.n
    }
    fn position(&self, k: usize, t: f64) -> Option<Vec3> {
        (self.f)(k, t)
    }
}

/// What a policy is asked each τ.
pub struct PlanInput<'a> {
    /// Time of the decision, s.
    pub t: f64,
    pub cna: CnaPose,
    /// Current modelled error of each AUV (same order as the forecast), for Hudson's cost.
    pub errors: &'a [AuvError],
    /// Each AUV's filter covariance (same order), for the estimator-aware cost; may be empty
    /// under Hudson's.
    pub estimates: &'a [AuvEstimate],
    /// The CNA's own horizontal position variance per axis, m² (its GPS σ², or an AUV CNA's
    /// navigation variance); the estimator-aware cost adds it to each ping's range variance.
    pub cna_variance: f64,
    pub forecast: &'a dyn AuvForecast,
    /// Per AUV (same order), the slant range beyond which no ping reaches it whatever the link,
    /// m (its own slot starts before the broadcast has arrived); the estimator-aware cost only.
    /// Empty: no such range.
    pub slot_reach_m: &'a [f64],
}

/// One decision.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Decision {
    /// Index of the chosen option in [`MotionConfig::options`].
    pub option: usize,
    pub motion: MotionOption,
    /// The CNA pose after the step: the next waypoint.
    pub next: CnaPose,
    /// Minimum path cost over the searched tree (penalised). The chosen option's own minimum is
    /// within `SearchConfig::tie_tolerance` of it.
    pub value: f64,
    /// Tree levels requested (L + 1) and completed.
    pub levels_requested: usize,
    pub levels_searched: usize,
    /// Tree nodes evaluated (varies with the thread count under parallel search).
    pub nodes: u64,
}

/// A CNA path planner: anything that plans the CNA's next move each τ from a [`PlanInput`].
pub trait Planner {
    fn name(&self) -> &str;
    fn decide(&mut self, input: &PlanInput) -> Result<Decision, PlanError>;
}

/// The exact receding-horizon look-ahead planner.
#[derive(Debug, Clone)]
pub struct LookAheadPlanner {
    cfg: PlannerConfig,
    link: LinkTable,
    /// The estimator-aware cost's range bias from a known sound-speed profile (step 4).
    bias: Option<BiasTable>,
    /// The mission-long horizon layer over the estimator-aware costs (`horizon`); None: none.
    horizon: Option<HorizonSpec>,
    /// The filters' current states (`current_states`), for [`LookAheadPlanner::decide_on_current_states`].
    current_states: Option<CurrentStates>,
}

/// What the current-states cost starts from at a decision: each AUV's state (the order of
/// `PlanInput::estimates`) and v, the CNA's own true horizontal variance per axis, m².
#[derive(Debug, Clone, Copy)]
pub struct CurrentInput<'a> {
    pub states: &'a [CurrentState],
    pub cna_variance: f64,
}

/// What the horizon layer plans over when it is not the tree's own input: every AUV of the
/// survey (those the CNA has not heard from along their mission plans), their states and, under
/// the true-error cost, their true-error moments.
#[derive(Clone, Copy)]
pub struct SurveyInput<'a> {
    pub plan: &'a PlanInput<'a>,
    pub truth: Option<&'a TruthInput<'a>>,
}

/// The cost-independent part of a tree: predicted AUV positions and the CNA's options.
struct Geometry {
    auv: Vec<[f64; 3]>,
    depth: usize,
    n: usize,
    options: Vec<FastOption>,
    root_options: Vec<usize>,
    root_pose: FastPose,
}

impl LookAheadPlanner {
    /// A planner with a perfect acoustic link.
    pub fn new(cfg: PlannerConfig) -> Result<Self, PlanError> {
        cfg.validate()?;
        Ok(LookAheadPlanner { cfg, link: LinkTable::perfect(), bias: None, horizon: None, current_states: None })
    }

    /// A planner whose estimator-aware cost weights each ping by `link`'s success probability.
    pub fn with_link(cfg: PlannerConfig, link: &dyn LinkModel) -> Result<Self, PlanError> {
        cfg.validate()?;
        Ok(LookAheadPlanner { cfg, link: LinkTable::sample(link)?, bias: None, horizon: None, current_states: None })
    }

    /// The estimator-aware cost's range bias from `table` (the scale error between two depths)
    /// instead of `bias_per_km_m`.
    pub fn with_bias(mut self, table: BiasTable) -> Self {
        self.bias = Some(table);
        self
    }

    /// The mission-long horizon layer (`horizon`) above the estimator-aware costs' trees; a spec
    /// with `enabled = false` is none. Hudson's cost is the thesis's planner and never has it.
    pub fn with_horizon(mut self, spec: HorizonSpec) -> Result<Self, PlanError> {
        Ok(CheckFields::validate(&spec, "horizon.")?).map(|()| {
            self.horizon = spec.enabled.then_some(spec);
            self
        })
    }

    /// The true-error cost on filters that estimate the water current (`current_states`), used by
    /// [`LookAheadPlanner::decide_on_current_states`].
    pub fn with_current_states(mut self, spec: CurrentStates) -> Self {
        self.current_states = Some(spec);
        self
    }

    pub fn config(&self) -> &PlannerConfig {
        &self.cfg
    }

    /// Predicted positions for `depth` levels (fewer when the forecast ends) and the options.
    fn geometry(&self, input: &PlanInput, depth: usize) -> Result<Geometry, PlanError> {
        let cfg = &self.cfg;
        let n = input.forecast.n_auvs();
        let states = match cfg.cost {
            CostSpec::Hudson => input.errors.len(),
            CostSpec::Estimator(_) => input.estimates.len(),
        };
        if n == 0 || states != n {
            return Err(PlanError::Input(format!(
                "{states} error states for {n} forecast AUVs (need one per AUV, at least one)"
            )));
        }
        let mut auv = Vec::with_capacity(n * depth);
        let mut levels = 0;
        'levels: for l in 0..depth {
            let t = input.t + (l + 1) as f64 * cfg.motion.tau;
            let mut row = Vec::with_capacity(n);
            for k in 0..n {
                match input.forecast.position(k, t) {
                    Some(p) => row.push(to_arr(&p)),
                    None => break 'levels,
                }
            }
            auv.extend(row);
            levels += 1;
        }
        if levels == 0 {
            return Err(PlanError::NoForecast { t: input.t + cfg.motion.tau });
        }
        let options = cfg.motion.fast_options();
        let root_pose = FastPose::from_pose(&input.cna);
        // Level 0 keeps only the options that break the AUV-CNA limits least (none, normally):
        // docs/models.md#hudson-motion.
        let violation: Vec<f64> =
            options.iter().map(|o| cfg.motion.limit_violation(&cfg.motion.step(&root_pose, o))).collect();
        let least = violation.iter().cloned().fold(f64::INFINITY, f64::min);
        let root_options = (0..options.len()).filter(|&i| violation[i] <= least).collect();
        Ok(Geometry { auv, depth: levels, n, options, root_options, root_pose })
    }

    fn tree<M: CostModel>(&self, g: Geometry, model: M, root_state: Vec<M::State>, goal: Option<GoalTerm>) -> Tree<M> {
        let cfg = &self.cfg;
        Tree {
            motion: cfg.motion,
            limits: cfg.limits,
            penalties: cfg.penalties,
            all_options: (0..g.options.len()).collect(),
            held_pitch_options: least_pitch(&g.options),
            pitch_levels: cfg.motion.pitch_levels(),
            options: g.options,
            root_options: g.root_options,
            depth: g.depth,
            n: g.n,
            reach: reaches(&g.auv, g.n, cfg.motion.speed * cfg.motion.tau),
            step: cfg.motion.speed * cfg.motion.tau,
            auv: g.auv,
            rest_floor: rest_floors(&model.level_floors(&root_state, g.depth), 1.0 + model.terminal_levels()),
            tie_tolerance: cfg.search.tie_tolerance,
            goal,
            model,
            root_pose: g.root_pose,
            root_state,
        }
    }

    fn hudson_tree(&self, input: &PlanInput, depth: usize) -> Result<Tree<HudsonCost>, PlanError> {
        let g = self.geometry(input, depth)?;
        let model = HudsonCost {
            model: self.cfg.error,
            sigma2: input.errors.iter().map(|e| e.sigma2).collect(),
            alpha_tau: self.cfg.error.alpha * self.cfg.motion.tau,
        };
        let root = input.errors.iter().map(|e| Tangential { eps2: e.eps2, los: e.los }).collect();
        Ok(self.tree(g, model, root, None))
    }

    fn estimator_model(&self, spec: EstimatorSpec, input: &PlanInput) -> Result<EkfCost, PlanError> {
        let motion = (self.cfg.motion.tau, self.cfg.motion.speed, input.cna_variance);
        let mut model = EkfCost::new(spec, input.estimates, motion, self.link.clone())?;
        model.bias = self.bias.clone();
        let reach = input.slot_reach_m;
        if !(reach.is_empty() || reach.len() == input.estimates.len()) {
            return Err(PlanError::Input(format!(
                "{} slot reaches for {} AUVs: give one per AUV, or none",
                reach.len(),
                input.estimates.len()
            )));
        }
        if let Some((k, r)) = reach.iter().enumerate().find(|(_, r)| r.is_nan() || **r < 0.0) {
            return Err(PlanError::Input(format!("AUV {k}: slot reach {r} m is not a range >= 0 (or infinite)")));
        }
        model.slot_reach = reach.to_vec();
        Ok(model)
    }

    fn estimator_tree(
        &self,
        spec: EstimatorSpec,
        input: &PlanInput,
        depth: usize,
        goal: Option<GoalTerm>,
    ) -> Result<Tree<EkfCost>, PlanError> {
        let g = self.geometry(input, depth)?;
        let model = self.estimator_model(spec, input)?;
        let root = input.estimates.iter().map(|e| e.cov).collect();
        Ok(self.tree(g, model, root, goal))
    }

    /// The true-error model and its root states for `input` with the moments `known`.
    fn true_error_model(
        &self,
        (spec, truth): (EstimatorSpec, TruthSpec),
        input: &PlanInput,
        known: &TruthInput,
    ) -> Result<(TrueErrorCost, Vec<TrueState>), PlanError> {
        let n = input.forecast.n_auvs();
        if known.errors.len() != n {
            return Err(PlanError::Input(format!("{} true-error states for {n} forecast AUVs", known.errors.len())));
        }
        let root = TrueErrorCost::root(input.estimates.iter().map(|e| e.cov), known)?;
        Ok((TrueErrorCost::new(self.estimator_model(spec, input)?, truth, self.cfg.motion.tau), root))
    }

    /// The horizon layer's goal for this decision (None without the layer, or when the forecast
    /// cannot place every AUV now): the best visiting order over `survey`'s AUVs under `model`
    /// from `root`, and the tree levels' goal positions.
    fn goal<M: CostModel>(&self, survey: &PlanInput, model: &M, root: &[M::State]) -> Option<GoalTerm> {
        let spec = self.horizon?;
        let motion = &self.cfg.motion;
        let per_segment = ((spec.segment_s / motion.tau).round() as usize).max(1);
        let levels = (per_segment * spec.segments).max(self.cfg.look_ahead + 1);
        let n = survey.forecast.n_auvs();
        let mut auv: Vec<[f64; 3]> = Vec::with_capacity(levels * n);
        for j in 0..levels {
            let t = survey.t + (j + 1) as f64 * motion.tau;
            for k in 0..n {
                // Past the end of what is known the AUV is held where it was last forecast.
                match survey.forecast.position(k, t) {
                    Some(p) => auv.push(to_arr(&p)),
                    None if j > 0 => auv.push(auv[(j - 1) * n + k]),
                    None => return None,
                }
            }
        }
        let step = motion.speed * motion.tau;
        let world = World {
            auv,
            n,
            levels_per_segment: per_segment,
            segments: spec.segments,
            cna: to_arr(&survey.cna.pos),
            step,
            standoff: spec.standoff_m,
        };
        let order = best_order(model, &world, root)?;
        let target = order.targets[0];
        let goal = (0..levels).map(|l| world.auv[l * n + target]).map(|a| [a[0], a[1]]).collect();
        Some(GoalTerm { target, per_metre: spec.weight * order.delay / step, standoff_m: spec.standoff_m, goal })
    }

    fn true_error_tree(
        &self,
        spec: (EstimatorSpec, TruthSpec),
        input: &PlanInput,
        known: &TruthInput,
        (depth, goal): (usize, Option<GoalTerm>),
    ) -> Result<Tree<TrueErrorCost>, PlanError> {
        let g = self.geometry(input, depth)?;
        let (model, root) = self.true_error_model(spec, input, known)?;
        Ok(self.tree(g, model, root, goal))
    }

    fn decision<M: CostModel>(&self, tree: &Tree<M>, out: SearchOutcome, requested: usize) -> Decision {
        let opt = self.cfg.motion.options()[out.root_option];
        let next = self.cfg.motion.step(&tree.root_pose, &tree.options[out.root_option]).to_pose();
        Decision {
            option: out.root_option,
            motion: opt,
            next,
            value: out.value,
            levels_requested: requested,
            levels_searched: tree.depth,
            nodes: out.nodes,
        }
    }

    /// Searches the trees `build(depth)` makes: the full depth when there is no deadline, else
    /// iterative deepening where the deepest level completed before the deadline decides. Once
    /// the whole tree surely fits in what is left of the budget ([`surely_fits`]), the levels
    /// between are skipped and the full depth is searched next: it decides whenever it completes,
    /// as it would have after them, and a deadline it still misses leaves the deepest level
    /// completed before it.
    fn run<M: CostModel>(&self, build: impl Fn(usize) -> Result<Tree<M>, PlanError>) -> Result<Decision, PlanError> {
        let requested = self.cfg.look_ahead + 1;
        let full = build(requested)?;
        let search = |tree: &Tree<M>, shared: &Shared| match self.cfg.search.algorithm {
            Algorithm::BruteForce => brute::brute_force(tree, shared),
            Algorithm::BranchAndBound => branch_and_bound(tree, &self.cfg.search, shared),
        };
        let Some(budget) = self.cfg.budget() else {
            let out = search(&full, &Shared::new(None)).expect("no deadline, no abort");
            return Ok(self.decision(&full, out, requested));
        };
        let deadline = Instant::now() + budget;
        let mut best: Option<Decision> = None;
        let mut nodes = 0;
        let mut depth = 1;
        loop {
            let started = Instant::now();
            let shallower;
            let tree = if depth == full.depth {
                &full
            } else {
                shallower = build(depth)?;
                &shallower
            };
            let Some(out) = search(tree, &Shared::new(Some(deadline))) else { break };
            nodes += out.nodes;
            best = Some(Decision { nodes, ..self.decision(tree, out, requested) });
            if depth == full.depth {
                break;
            }
            let per_node = started.elapsed().as_secs_f64() / out.nodes.max(1) as f64;
            let left = deadline.saturating_duration_since(Instant::now()).as_secs_f64();
            depth = if surely_fits(&full, per_node, left) { full.depth } else { depth + 1 };
        }
        best.ok_or(PlanError::Deadline)
    }
}

/// How much longer than its measured share a node of the full tree may take before a search
/// that was judged to fit misses the deadline anyway ([`surely_fits`]): machine noise.
const FIT_MARGIN: f64 = 10.0;

/// Whether `tree`'s search surely completes in `left` seconds, at `per_node` seconds per node
/// as measured on a shallower tree (its build included): every node of it expanded (no
/// pruning), each node also paying for a bound over at most `depth` levels below, each level
/// about one more expansion, and [`FIT_MARGIN`] on top. The decision never depends on it, only
/// which shallower levels are searched first.
fn surely_fits<M: CostModel>(tree: &Tree<M>, per_node: f64, left: f64) -> bool {
    tree.nodes_above(tree.depth) as f64 * per_node * (1.0 + tree.depth as f64) * FIT_MARGIN < left
}

/// The options with the smallest pitch change (Δφ = 0 with an odd number of pitch options).
fn least_pitch(options: &[FastOption]) -> Vec<usize> {
    let least = options.iter().map(|o| o.dphi.abs()).fold(f64::INFINITY, f64::min);
    (0..options.len()).filter(|&i| options[i].dphi.abs() <= least).collect()
}

impl Planner for LookAheadPlanner {
    fn name(&self) -> &str {
        "look-ahead"
    }

    /// Refused under a true-error cost (`EstimatorSpec::truth`): use
    /// [`LookAheadPlanner::decide_with_truth`].
    fn decide(&mut self, input: &PlanInput) -> Result<Decision, PlanError> {
        self.decide_with_truth(input, None)
    }
}

impl LookAheadPlanner {
    /// One decision; `truth` (each AUV's true-error moments and the CNA's own variance) is what
    /// the true-error cost starts from, required by it and ignored by the other costs.
    pub fn decide_with_truth(&self, input: &PlanInput, truth: Option<&TruthInput>) -> Result<Decision, PlanError> {
        self.decide_with_survey(input, truth, SurveyInput { plan: input, truth })
    }

    /// [`LookAheadPlanner::decide_with_truth`], with the horizon layer (if any) planning over
    /// `survey` instead of the tree's own AUVs.
    pub fn decide_with_survey(
        &self,
        input: &PlanInput,
        truth: Option<&TruthInput>,
        survey: SurveyInput,
    ) -> Result<Decision, PlanError> {
        match (self.cfg.cost, truth) {
            (CostSpec::Hudson, _) => self.run(|depth| self.hudson_tree(input, depth)),
            (CostSpec::Estimator(spec @ EstimatorSpec { truth: None, .. }), _) => {
                let goal = match self.horizon {
                    Some(_) => {
                        let model = self.estimator_model(spec, survey.plan)?;
                        let root: Vec<[f64; 3]> = survey.plan.estimates.iter().map(|e| e.cov).collect();
                        self.goal(survey.plan, &model, &root)
                    }
                    None => None,
                };
                self.run(|depth| self.estimator_tree(spec, input, depth, goal.clone()))
            }
            (CostSpec::Estimator(spec @ EstimatorSpec { truth: Some(t), .. }), Some(known)) => {
                let goal = match (self.horizon, survey.truth) {
                    (Some(_), Some(survey_known)) => {
                        let (model, root) = self.true_error_model((spec, t), survey.plan, survey_known)?;
                        self.goal(survey.plan, &model, &root)
                    }
                    _ => None,
                };
                self.run(|depth| self.true_error_tree((spec, t), input, known, (depth, goal.clone())))
            }
            (CostSpec::Estimator(_), None) => Err(PlanError::Input(
                "the true-error cost (cost.truth) needs each AUV's true-error moments (decide_with_truth)".into(),
            )),
        }
    }
}

impl LookAheadPlanner {
    /// One decision under the true-error cost on filters with current states (`current_states`):
    /// needs `cost.truth` and [`LookAheadPlanner::with_current_states`]. `survey` (its input and
    /// states over every AUV) is what the horizon layer, if any, plans over; None: the tree's own.
    pub fn decide_on_current_states(
        &self,
        input: &PlanInput,
        states: &CurrentInput,
        survey: Option<(&PlanInput, &CurrentInput)>,
    ) -> Result<Decision, PlanError> {
        let (CostSpec::Estimator(spec @ EstimatorSpec { truth: Some(truth), .. }), Some(current)) =
            (self.cfg.cost, self.current_states)
        else {
            return Err(PlanError::Input(
                "the current-states cost needs cost.truth and the filters' current states (with_current_states)".into(),
            ));
        };
        let model = |plan: &PlanInput,
                     known: &CurrentInput|
         -> Result<(CurrentStatesCost, Vec<CurrentState>), PlanError> {
            let n = plan.forecast.n_auvs();
            if known.states.len() != n {
                return Err(PlanError::Input(format!("{} current states for {n} forecast AUVs", known.states.len())));
            }
            CurrentStatesCost::check(known.states)?;
            let filter = self.estimator_model(spec, plan)?;
            let cost = CurrentStatesCost::new(filter, truth, current, self.cfg.motion.tau, known.cna_variance);
            Ok((cost, known.states.to_vec()))
        };
        let goal = match self.horizon {
            Some(_) => {
                let (plan, known) = survey.unwrap_or((input, states));
                let (m, root) = model(plan, known)?;
                self.goal(plan, &m, &root)
            }
            None => None,
        };
        self.run(|depth| {
            let g = self.geometry(input, depth)?;
            let (m, root) = model(input, states)?;
            Ok(self.tree(g, m, root, goal.clone()))
        })
    }
}
