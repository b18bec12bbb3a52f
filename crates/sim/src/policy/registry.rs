//! Which CNA policy a closed-loop run uses, by name: the underway planner or one of the
//! baselines of [`crate::policy`], configured from the scenario (survey area, fleet, CNA start).

use super::planner::{LikelihoodLink, PingLikelihood, PlannerPolicy, PlannerStats, UnheardGrowth};
use crate::policy::{
    Centroid, CentroidStandoff, CnaPolicy, FixedPattern, GreedyFisher, MidpointRelay, NoCna, TimedWaypoints, Trail,
};
use crate::scenario::start::cna_start;
use crate::scenario::world::{EstimatorTracking, PlannerLink, Scenario};
use coopnav_acomms::selector::{FixedRate, RatePolicy, RatePolicyError};
use coopnav_acomms::tl::{TlError, TransmissionLoss, TL_CEILING};
use coopnav_core::{Bathymetry, DepthTarget, Vec3};
use coopnav_nav::AuvModel;
use coopnav_plan::current_states::CurrentStates;
use coopnav_plan::predeploy::runner;
use coopnav_plan::predeploy::Mission;
use coopnav_plan::{
    AuvEstimate, CostSpec, Deadline, EstimatorSpec, LinkTable, LookAheadPlanner, PlanError, RangeNoise,
};
use coopnav_plan::{PlannerConfig, PlannerSpec};
use std::sync::Arc;
use thiserror::Error;

/// How a policy is built for one run: from its name (for its errors), the scenario and, for
/// `open-loop`, the plan computed once for the scenario ([`PolicySpec`]).
type Build = fn(&str, &Scenario, Option<&TimedWaypoints>) -> Result<Policy, PolicyError>;

/// Every CNA policy, the planners first, by the name a scenario or a command gives it: the one
/// place a name is written beside what it builds. `planner` scores with Hudson's model,
/// `planner-estimator` with the survey AUVs' filter covariances (docs/models.md#estimator-cost);
/// `greedy-fisher` is the one-step Fisher-information baseline; the rest are the baselines of
/// [`crate::policy`], each with its parameters in its own `[policy.NAME]` table.
const REGISTRY: [(&str, Build); 11] = [
    ("planner", |name, sc, _| planner(name, &sc.policy.planner, sc)),
    ("planner-estimator", |name, sc, _| planner(name, &sc.policy.planner_estimator, sc)),
    ("none", |_, _, _| baseline(NoCna)),
    ("racetrack", |_, sc, _| {
        let r = &sc.policy.racetrack;
        baseline(FixedPattern::racetrack(sc.survey_area(), r.inset_m, r.capture_radius_m))
    }),
    ("zigzag", |_, sc, _| {
        let z = &sc.policy.zigzag;
        baseline(FixedPattern::zigzag(sc.survey_area(), z.legs, z.capture_radius_m))
    }),
    ("centroid", |_, _, _| baseline(Centroid)),
    ("centroid-standoff", |_, sc, _| baseline(CentroidStandoff { radius: sc.policy.centroid_standoff.radius_m })),
    ("trail", |_, sc, _| {
        let t = &sc.policy.trail;
        let angle = std::f64::consts::PI * (t.angle_deg / 180.0);
        baseline(Trail { auv: t.auv.unwrap_or(sc.fleet.n_auvs / 2), range: t.range_m, angle })
    }),
    ("relay", |_, sc, _| {
        baseline(MidpointRelay { base: (sc.cna.x, sc.cna.y), auv: sc.policy.relay.auv.unwrap_or(sc.fleet.n_auvs / 2) })
    }),
    ("open-loop", |name, sc, planned| match planned {
        Some(p) => baseline(p.clone()),
        None => baseline(open_loop(sc).map_err(|source| PolicyError::Plan { name: name.to_string(), source })?),
    }),
    ("greedy-fisher", |name, sc, _| {
        let link_err = |source| PolicyError::Link { name: name.to_string(), source };
        let link = LinkTable::sample(&LikelihoodLink(&modem_likelihood(sc).map_err(link_err)?))
            .map_err(|source| PolicyError::Plan { name: name.to_string(), source })?;
        let g = &sc.policy.greedy_fisher;
        baseline(GreedyFisher::new(sc.fleet.n_auvs, link, filter_model(sc).1, g.candidates, g.sigma_prior_m))
    }),
];

/// Every policy name, in [`REGISTRY`]'s order.
pub const POLICY_NAMES: [&str; REGISTRY.len()] = {
    let mut names = [""; REGISTRY.len()];
    let mut i = 0;
    while i < REGISTRY.len() {
        names[i] = REGISTRY[i].0;
        i += 1;
    }
    names
};

/// The policy whose plan is computed once per scenario ([`PolicySpec`]), not once per run.
const PLANNED_ONCE: &str = "open-loop";

fn baseline(p: impl CnaPolicy + 'static) -> Result<Policy, PolicyError> {
    Ok(Policy::Baseline(Box::new(p)))
}

/// `name`'s entry of [`REGISTRY`].
fn registered(name: &str) -> Result<Build, PolicyError> {
    REGISTRY
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, b)| *b)
        .ok_or_else(|| PolicyError::Unknown { name: name.to_string() })
}

#[derive(Debug, Error)]
pub enum PolicyError {
    #[error("unknown policy '{name}' (allowed: {})", POLICY_NAMES.join(", "))]
    Unknown { name: String },
    #[error("policy {name}: {source}")]
    Plan { name: String, source: PlanError },
    #[error("policy {name}: {source}")]
    Link { name: String, source: LinkError },
}

/// Why the planners' link model could not be built.
#[derive(Debug, Error)]
pub enum LinkError {
    #[error("the policies' link model (policy.link = \"scenario_channel\"): {0}")]
    Channel(#[from] TlError),
    #[error("the CNA slot's rate_policy: {0}")]
    RatePolicy(RatePolicyError),
}

/// A configured CNA policy; the planner is kept visible for its statistics.
pub enum Policy {
    Planner(Box<PlannerPolicy>),
    Baseline(Box<dyn CnaPolicy>),
}

impl Policy {
    pub fn as_policy(&mut self) -> &mut dyn CnaPolicy {
        match self {
            Policy::Planner(p) => p.as_mut(),
            Policy::Baseline(b) => b.as_mut(),
        }
    }
    pub fn planner_stats(&self) -> Option<PlannerStats> {
        match self {
            Policy::Planner(p) => Some(p.stats()),
            Policy::Baseline(b) => b.planner_stats(),
        }
    }
}

/// A checked policy name with whatever it needs precomputed (the open-loop plan), so Monte
/// Carlo runs build their policies cheaply.
#[derive(Debug, Clone)]
pub struct PolicySpec {
    pub name: String,
    open_loop: Option<TimedWaypoints>,
}

impl PolicySpec {
    pub fn new(name: &str, sc: &Scenario) -> Result<Self, PolicyError> {
        registered(name)?;
        let open_loop = match name {
            PLANNED_ONCE => Some(open_loop(sc).map_err(|source| PolicyError::Plan { name: name.to_string(), source })?),
            _ => None,
        };
        Ok(PolicySpec { name: name.to_string(), open_loop })
    }

    /// A fresh policy for one run.
    pub fn build(&self, sc: &Scenario) -> Result<Policy, PolicyError> {
        build(&self.name, sc, self.open_loop.as_ref())
    }
}

/// Deepest CNA or AUV depth the planner's bias table covers, m (deeper holds its last value).
const BIAS_TABLE_DEPTH_M: f64 = 200.0;

/// Builds policy `name` for scenario `sc` from its `[policy.NAME]` table (`planned`: a
/// precomputed open-loop plan).
fn build(name: &str, sc: &Scenario, planned: Option<&TimedWaypoints>) -> Result<Policy, PolicyError> {
    registered(name)?(name, sc, planned)
}

/// The look-ahead search's whole configuration for planner instance `name` (`planner` or
/// `planner-estimator`) on `sc`: its spec's tree, penalties, limits and search on the scenario's
/// platform, and its cost with the settings its table and the rule give (the policy built from
/// it adds what that cost reads of the mission as it flies: `build`).
pub fn planner_config(name: &str, sc: &Scenario) -> Result<PlannerConfig, PolicyError> {
    match name {
        "planner" => Ok(spec_planner_config(&sc.policy.planner, sc)),
        "planner-estimator" => Ok(spec_planner_config(&sc.policy.planner_estimator, sc)),
        _ => Err(PolicyError::Unknown { name: name.to_string() }),
    }
}

fn spec_planner_config(spec: &PlannerSpec, sc: &Scenario) -> PlannerConfig {
    let mut cfg = sc.spec_config(spec);
    if let (Some(e), Some(cost)) = (spec.estimator_settings(&sc.mission_facts()), spec.estimator_cost()) {
        cfg.cost = CostSpec::Estimator(EstimatorSpec {
            range_noise: filter_model(sc).1,
            aggregate: e.aggregate,
            bias_per_km_m: e.bias_per_km,
            terminal_levels: e.terminal_levels,
            reach_success: e.reach_success,
            unmodelled_current: e.unmodelled_current,
            drift_levels: cost.drift_levels(),
            truth: e.truth,
        });
    }
    cfg
}

/// The planner instance `name` from its spec: Hudson's cost, or the estimator-aware cost with
/// the settings its spec and the rule give for this mission, and what that cost reads of the
/// mission (the filters' model, the sound-speed profile, the schedule, the survey plans).
fn planner(name: &str, spec: &PlannerSpec, sc: &Scenario) -> Result<Policy, PolicyError> {
    let n = sc.fleet.n_auvs;
    let plan_err = |source| PolicyError::Plan { name: name.to_string(), source };
    let link_err = |source| PolicyError::Link { name: name.to_string(), source };
    let settings = spec.estimator_settings(&sc.mission_facts());
    let hudson = spec.hudson_cost();
    // The estimator-aware cost always weights a ping by the link model; Hudson's planner only
    // when asked (the thesis assumes every ping arrives).
    let likelihood =
        (hudson.model_lost_pings || settings.is_some()).then(|| modem_likelihood(sc)).transpose().map_err(link_err)?;
    let (start, noise) = filter_model(sc);
    let cfg = spec_planner_config(spec, sc);
    let (Some(e), Some(cost)) = (settings, spec.estimator_cost()) else {
        let policy = PlannerPolicy::new(cfg, n, hudson.sigma0, hudson.eps0, likelihood, Some((start, noise)))
            .map_err(plan_err)?;
        return Ok(Policy::Planner(Box::new(policy.without_cna_variance())));
    };
    let mut policy =
        PlannerPolicy::new(cfg, n, hudson.sigma0, hudson.eps0, likelihood, Some((start, noise))).map_err(plan_err)?;
    if !e.cna_variance {
        policy = policy.without_cna_variance();
    }
    if e.bias_profile {
        // The scale error a range between two depths carries: travel time at the water's
        // harmonic-mean speed, converted at the filters' (the engine's straight-ray model;
        // none where the filters convert with a cast of this water, `filter.sound_speed`).
        let filters = sc.filter.range_speed(&sc.channel.sound_speed);
        let water = &sc.channel.sound_speed;
        let table = coopnav_plan::BiasTable::sample(BIAS_TABLE_DEPTH_M, |z_cna, z_auv| {
            filters.between(z_cna, z_auv) / water.mean_between(z_cna, z_auv) - 1.0
        })
        .map_err(plan_err)?;
        policy = policy.with_bias(table);
    }
    if let Some(truth) = e.truth {
        policy = policy.with_truth(truth, sc.fleet.init_position_sd.powi(2), e.unmodelled_current);
    }
    if e.slot_reach {
        policy = policy.with_slot_reach(sc.slot_reach_m());
    }
    if cost.tracking == EstimatorTracking::ReportsOnly {
        policy = policy.with_reports_only(unheard_growth(sc));
    }
    if let (Some(truth), AuvModel::Current(c)) = (e.truth, sc.filter.model) {
        let spec = CurrentStates {
            p0: c.p0,
            q: c.q / sc.filter.params.step_s,
            correlation_s: c.correlation_time_s,
            water: [e.current[0] - c.mean[0], e.current[1] - c.mean[1]],
        };
        policy = policy.with_current_states(spec, truth, sc.fleet.init_position_sd.powi(2));
    }
    if let Some(horizon) = spec.horizon() {
        let plans = (0..n)
            .map(|k| sc.lawnmower(k).track(1.0))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| plan_err(PlanError::Input(format!("nominal survey track: {e}"))))?;
        policy = policy.with_horizon(horizon, plans).map_err(plan_err)?;
    }
    Ok(Policy::Planner(Box::new(policy)))
}

/// The downlink's success probability over a slant distance, as a real CNA can know it: the
/// modem's success curves over the TL model `policy.link` names (never the draws), at
/// `comms.cna_rate` or, when the CNA's slots name a rate policy, at what that policy sends once it
/// has settled on this link ([`RatePolicy::settled_success`]; the engine's policy decides on the
/// farthest AUV, so for a nearer one this counts a faster rate than it gets, pessimistic where a
/// slower rate carries further).
fn modem_likelihood(sc: &Scenario) -> Result<PingLikelihood, LinkError> {
    let success = sc.comms.success.clone();
    let policy: Box<dyn RatePolicy> = match sc.comms.schedule.cna_policy() {
        Some(spec) => spec.build().map_err(LinkError::RatePolicy)?,
        None => Box::new(FixedRate { rate: sc.comms.cna_rate }),
    };
    let at_tl = move |tl: f64| policy.settled_success(&|rate| success.p_success(rate, tl));
    match sc.policy.link {
        PlannerLink::Assumed => {
            let tl = sc.comms.tl.assumed();
            Ok(Box::new(move |d: f64| at_tl(tl.at_distance(d))))
        }
        PlannerLink::ScenarioChannel => {
            let channel = ChannelSample::new(sc)?;
            Ok(Box::new(move |d: f64| channel.mean(&at_tl, d)))
        }
    }
}

/// The scenario's own TL provider seen from where the CNA pings: from the centre of every survey
/// block at the CNA's start depth, along [`CHANNEL_BEARINGS`] bearings, to an AUV at its mission
/// depth. Invented: the link depends on where the CNA is, but the planner's table
/// depends on distance only, so it gets the mean over these sources and bearings.
#[derive(Clone)]
struct ChannelSample {
    tl: Arc<dyn TransmissionLoss>,
    sources: Vec<Vec3>,
    bathymetry: Bathymetry,
    depth: DepthTarget,
}

/// Bearings per source of [`ChannelSample`] (the default BELLHOP grid's own count). Invented.
const CHANNEL_BEARINGS: usize = 16;

impl ChannelSample {
    fn new(sc: &Scenario) -> Result<Self, TlError> {
        let z = cna_start(sc).pos.z;
        let sources = (0..sc.fleet.n_auvs)
            .map(|k| {
                let corners = sc.lawnmower(k).waypoints();
                let n = corners.len().max(1) as f64;
                let (x, y) = corners.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
                Vec3::new(x / n, y / n, z)
            })
            .collect();
        Ok(ChannelSample { tl: sc.tl_provider()?, sources, bathymetry: sc.bathymetry(), depth: sc.fleet.depth })
    }

    /// The mean of `success(TL)` over every source and bearing at slant distance `d`; a TL the
    /// provider cannot give is the engine's lost packet ([`TL_CEILING`]).
    fn mean(&self, success: impl Fn(f64) -> f64, d: f64) -> f64 {
        let mut sum = 0.0;
        for src in &self.sources {
            for b in 0..CHANNEL_BEARINGS {
                let (s, c) = (std::f64::consts::TAU * b as f64 / CHANNEL_BEARINGS as f64).sin_cos();
                let z = self.receiver_depth(src.x + d * c, src.y + d * s);
                let h = (d * d - (z - src.z).powi(2)).max(0.0).sqrt();
                let rx = Vec3::new(src.x + h * c, src.y + h * s, z);
                sum += success(self.tl.tl(src, &rx).unwrap_or(TL_CEILING));
            }
        }
        sum / (self.sources.len() * CHANNEL_BEARINGS).max(1) as f64
    }

    /// A survey AUV's depth at (x, y): its depth, or the water's depth less its altitude.
    fn receiver_depth(&self, x: f64, y: f64) -> f64 {
        self.depth.depth_over(self.bathymetry.depth_at(x, y)).max(0.0)
    }
}

/// The survey AUVs' filter as the estimator-aware planner models it: the initial horizontal
/// covariance and process noise per second (the filter's per-step Q over its step; the mean of
/// east and north), and its range noise σ² = (c·σ_t)² + floor + (r·σ_c/c)² as σ₀ and k per km.
fn filter_model(sc: &Scenario) -> (AuvEstimate, RangeNoise) {
    let f = &sc.filter.params;
    let q = 0.5 * (f.q[0] + f.q[1]) / f.step_s;
    let n = &f.range_noise;
    let sigma_m = ((n.sound_speed * n.sigma_time).powi(2) + n.floor).sqrt();
    let per_km_m = 1000.0 * n.sigma_sound_speed / n.sound_speed;
    (AuvEstimate { cov: [f.p0[0], 0.0, f.p0[1]], process_noise: q }, RangeNoise { sigma_m, per_km_m })
}

/// How the survey AUVs' filters predict an unheard AUV's position covariance: with the `current`
/// model, the current's initial variance and its random walk per second (per axis); else none.
fn unheard_growth(sc: &Scenario) -> UnheardGrowth {
    match sc.filter.model {
        AuvModel::Current(c) => UnheardGrowth {
            current_p0: c.p0,
            current_q: c.q / sc.filter.params.step_s,
            current_correlation_s: c.correlation_time_s,
        },
        AuvModel::Thesis => UnheardGrowth { current_p0: 0.0, current_q: 0.0, current_correlation_s: None },
    }
}

/// The pre-deployment plan on the nominal survey tracks (no current, no nav error), flown by time.
fn open_loop(sc: &Scenario) -> Result<TimedWaypoints, PlanError> {
    let spec = &sc.policy.open_loop;
    let mut cfg = sc.spec_config(spec);
    cfg.search.deadline = Deadline::None;
    let tracks = (0..sc.fleet.n_auvs)
        .map(|k| sc.lawnmower(k).track(1.0))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| PlanError::Input(format!("nominal survey track: {e}")))?;
    let n = tracks.len();
    let mission = Mission {
        planner: cfg,
        cna: cna_start(sc),
        names: (0..n).map(|k| format!("auv{k}")).collect(),
        tracks,
        sigma0: vec![spec.hudson_cost().sigma0; n],
        eps0: vec![spec.hudson_cost().eps0; n],
        start_time: 0.0,
        end_time: sc.duration_s,
    };
    let mut planner = LookAheadPlanner::new(cfg)?;
    let run = runner::run(&mission, &mut planner, &|_| {}).map_err(|e| PlanError::Input(e.to_string()))?;
    let tau = sc.comms.tau;
    Ok(TimedWaypoints {
        waypoints: run.decisions.iter().enumerate().map(|(i, d)| ((i + 1) as f64 * tau, d.next.pos)).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::world::PlannerLink;

    /// The planners' success likelihood at each distance, under `link`.
    fn likelihood_at(sc: &Scenario, link: PlannerLink, distances: &[f64]) -> Vec<f64> {
        let mut sc = sc.clone();
        sc.policy.link = link;
        let f = modem_likelihood(&sc).unwrap();
        distances.iter().map(|&d| f(d)).collect()
    }

    #[test]
    fn on_the_analytic_tl_the_scenario_channel_is_the_assumed_link() {
        // Every source and bearing lands at the asked slant distance, so the analytic channel's
        // mean is the assumed curve itself.
        let sc = Scenario::example();
        let distances = [100.0, 450.0, 900.0, 1300.0, 2000.0, 3000.0];
        let assumed = likelihood_at(&sc, PlannerLink::Assumed, &distances);
        let channel = likelihood_at(&sc, PlannerLink::ScenarioChannel, &distances);
        for ((d, a), c) in distances.iter().zip(&assumed).zip(&channel) {
            assert!((a - c).abs() < 1e-9, "{d} m: assumed {a}, channel {c}");
        }
        assert!(assumed[0] > 0.75 && assumed[5] < 0.3, "the curve falls over the distances: {assumed:?}");
    }

    #[test]
    fn a_rate_policy_on_the_cnas_slot_sets_the_planners_link() {
        use crate::models::schedule::{Schedule, SlotSpec};
        use coopnav_acomms::{selector::RatePolicySpec, Rate};
        let mut sc = Scenario::example();
        let tl = sc.comms.tl.assumed();
        let distances = [100.0, 900.0, 1300.0, 2000.0];
        let curve = |rate| -> Vec<f64> {
            distances.iter().map(|&d| sc.comms.success.p_success(rate, tl.at_distance(d))).collect()
        };
        let (r0, r5) = (curve(Rate::R0), curve(Rate::R5));
        assert_eq!(sc.comms.cna_rate, Rate::R0);
        assert_eq!(likelihood_at(&sc, PlannerLink::Assumed, &distances), r0, "no policy: comms.cna_rate");
        let on_cna_slot = |policy| Schedule::Tdma {
            slots: vec![SlotSpec {
                who: "cna".into(),
                start_s: 0.0,
                length_s: 10.0,
                message: None,
                rate_policy: Some(policy),
            }],
        };
        sc.comms.schedule = on_cna_slot(RatePolicySpec::Fixed { rate: Rate::R5 });
        assert_eq!(likelihood_at(&sc, PlannerLink::Assumed, &distances), r5);
        sc.comms.schedule = on_cna_slot(RatePolicySpec::Alternating { rates: vec![Rate::R0, Rate::R5] });
        let mean: Vec<f64> = r0.iter().zip(&r5).map(|(a, b)| (a + b) / 2.0).collect();
        for (got, want) in likelihood_at(&sc, PlannerLink::Assumed, &distances).iter().zip(&mean) {
            assert!((got - want).abs() < 1e-12, "alternating: {got} against {want}");
        }
        assert!(r0.iter().zip(&r5).any(|(a, b)| (a - b).abs() > 0.1), "rates 0 and 5 differ: {r0:?} {r5:?}");
    }

    #[test]
    #[cfg_attr(not(bellhop_installed), ignore = "BELLHOP is not installed: run scripts/install-bellhop.sh")]
    fn on_a_bellhop_grid_the_scenario_channel_is_the_grids_link() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/full-stack.toml");
        let sc: Scenario = toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let distances: Vec<f64> = (1..=12).map(|i| 200.0 * i as f64).collect();
        let assumed = likelihood_at(&sc, PlannerLink::Assumed, &distances);
        let channel = likelihood_at(&sc, PlannerLink::ScenarioChannel, &distances);
        for ((d, a), c) in distances.iter().zip(&assumed).zip(&channel) {
            eprintln!("{d:6.0} m  assumed {a:.3}  channel {c:.3}");
        }
        // Measured on this grid (altitude-keeping AUVs over the 30-90 m shelf, the ASC at the
        // surface): both see the modem's plateau close in, but from 1.2 km the assumed Thorp model
        // still gives 0.71-0.39 where the grid's sea gives under 0.02.
        assert!((assumed[0] - channel[0]).abs() < 0.05, "200 m: {} vs {}", assumed[0], channel[0]);
        for i in 5..distances.len() {
            assert!(assumed[i] > 0.3 && channel[i] < 0.1, "{} m: {} vs {}", distances[i], assumed[i], channel[i]);
        }
    }
}
