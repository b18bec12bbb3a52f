//! Which CNA policy a closed-loop run uses, by name: the underway planner or one of the
//! baselines of [`crate::policy`], configured from the scenario (survey area, fleet, CNA start).

use super::planner_policy::{LikelihoodLink, PingLikelihood, PlannerPolicy, PlannerStats};
use super::scenario::Scenario;
use crate::policy::{
    Centroid, CentroidStandoff, CnaPolicy, FixedPattern, GreedyFisher, MidpointRelay, NoCna, Rect, TimedWaypoints,
    Trail,
};
use crate::predeploy::runner;
use crate::predeploy::scenario::Mission;
use coopnav_acomms::Receiver;
use coopnav_core::{CompassDeg, Heading, Vec3};
use coopnav_plan::{
    AuvEstimate, CnaKind, CnaPose, CostSpec, Deadline, EstimatorSpec, LinkTable, LookAheadPlanner, PenaltyCase,
    PlanError, RangeNoise,
};
use thiserror::Error;

/// Every policy name, the planners first: `planner` scores with Hudson's model, `planner-estimator`
/// with the survey AUVs' filter covariances (issue 10); `greedy-fisher` is the one-step
/// Fisher-information baseline.
pub const POLICY_NAMES: [&str; 11] = [
    "planner",
    "planner-estimator",
    "none",
    "racetrack",
    "zigzag",
    "centroid",
    "centroid-standoff",
    "trail",
    "relay",
    "open-loop",
    "greedy-fisher",
];

#[derive(Debug, Error)]
pub enum PolicyError {
    #[error("unknown policy '{name}' (allowed: {})", POLICY_NAMES.join(", "))]
    Unknown { name: String },
    #[error("policy {name}: {source}")]
    Plan { name: String, source: PlanError },
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
            Policy::Baseline(_) => None,
        }
    }
}

/// Capture radius of the fixed patterns, m; inset of the racetrack, m; zig-zag legs. Invented.
const CAPTURE_RADIUS: f64 = 20.0;
const RACETRACK_INSET: f64 = 100.0;
const ZIGZAG_LEGS: usize = 4;
/// Trail one AUV this far directly behind it, m (BHV_Trail-style). Invented.
const TRAIL_RANGE: f64 = 150.0;

/// The bounding box of every AUV's lawnmower.
pub fn survey_area(sc: &Scenario) -> Rect {
    let pts: Vec<(f64, f64)> = (0..sc.fleet.n_auvs).flat_map(|k| sc.lawnmower(k).waypoints()).collect();
    let fold = |f: fn(f64, f64) -> f64, init: f64, pick: fn(&(f64, f64)) -> f64| pts.iter().map(pick).fold(init, f);
    Rect {
        min: (fold(f64::min, f64::INFINITY, |p| p.0), fold(f64::min, f64::INFINITY, |p| p.1)),
        max: (fold(f64::max, f64::NEG_INFINITY, |p| p.0), fold(f64::max, f64::NEG_INFINITY, |p| p.1)),
    }
}

/// The CNA's start pose.
pub fn cna_start(sc: &Scenario) -> CnaPose {
    let z = sc.cna.auv.as_ref().map_or(0.0, |a| a.depth);
    CnaPose {
        pos: Vec3::new(sc.cna.x, sc.cna.y, z),
        heading: Heading::from(CompassDeg(sc.cna.heading_compass_deg)),
        pitch: 0.0,
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
        if !POLICY_NAMES.contains(&name) {
            return Err(PolicyError::Unknown { name: name.to_string() });
        }
        let open_loop = match name {
            "open-loop" => Some(open_loop(sc).map_err(|source| PolicyError::Plan { name: name.to_string(), source })?),
            _ => None,
        };
        Ok(PolicySpec { name: name.to_string(), open_loop })
    }

    /// A fresh policy for one run.
    pub fn build(&self, sc: &Scenario) -> Result<Policy, PolicyError> {
        build(&self.name, sc, self.open_loop.as_ref())
    }
}

/// Builds policy `name` for scenario `sc` (`planned`: a precomputed open-loop plan).
fn build(name: &str, sc: &Scenario, planned: Option<&TimedWaypoints>) -> Result<Policy, PolicyError> {
    let n = sc.fleet.n_auvs;
    let plan_err = |source| PolicyError::Plan { name: name.to_string(), source };
    let baseline: Box<dyn CnaPolicy> = match name {
        "planner" | "planner-estimator" => {
            let p = &sc.planner;
            // The estimator-aware cost always weights a ping by the link model; Hudson's planner
            // only when asked (the thesis assumes every ping arrives).
            let estimator = name == "planner-estimator";
            let likelihood = (p.model_lost_pings || estimator).then(|| modem_likelihood(sc));
            let (start, noise) = filter_model(sc);
            let mut cfg = sc.planner_config();
            if estimator {
                cfg.cost = CostSpec::Estimator(EstimatorSpec {
                    range_noise: noise,
                    aggregate: p.estimator_aggregate,
                    bias_per_km_m: p.estimator_bias_per_km.unwrap_or(noise.per_km_m),
                    terminal_levels: p.estimator_terminal_levels,
                    reach_success: p.estimator_reach_success,
                });
                if let Some(case) = p.estimator_penalty_case.as_deref().and_then(PenaltyCase::from_id) {
                    cfg.penalties = case.penalties();
                }
                cfg.look_ahead = p.estimator_look_ahead.unwrap_or(cfg.look_ahead);
                if let CnaKind::Auv { pitch_levels, .. } = &mut cfg.motion.cna {
                    *pitch_levels = p.estimator_pitch_levels;
                }
            }
            let mut policy =
                PlannerPolicy::new(cfg, n, p.sigma0, p.eps0, likelihood, Some((start, noise))).map_err(plan_err)?;
            if !p.estimator_cna_variance {
                policy = policy.without_cna_variance();
            }
            return Ok(Policy::Planner(Box::new(policy)));
        }
        "none" => Box::new(NoCna),
        "racetrack" => Box::new(FixedPattern::racetrack(survey_area(sc), RACETRACK_INSET, CAPTURE_RADIUS)),
        "zigzag" => Box::new(FixedPattern::zigzag(survey_area(sc), ZIGZAG_LEGS, CAPTURE_RADIUS)),
        "centroid" => Box::new(Centroid),
        "centroid-standoff" => Box::new(CentroidStandoff { radius: sc.cna.standoff_radius_m }),
        "trail" => Box::new(Trail { auv: n / 2, range: TRAIL_RANGE, angle: std::f64::consts::PI }),
        "relay" => Box::new(MidpointRelay { base: (sc.cna.x, sc.cna.y), auv: n / 2 }),
        "greedy-fisher" => {
            let link = LinkTable::sample(&LikelihoodLink(&modem_likelihood(sc))).map_err(plan_err)?;
            Box::new(GreedyFisher::new(n, link, filter_model(sc).1))
        }
        "open-loop" => match planned {
            Some(p) => Box::new(p.clone()),
            None => Box::new(open_loop(sc).map_err(plan_err)?),
        },
        _ => return Err(PolicyError::Unknown { name: name.to_string() }),
    };
    Ok(Policy::Baseline(baseline))
}

/// The downlink's success probability over a slant distance, as a real CNA can know it: the
/// modem's rate and success curves and the TL model it is configured with (never the draws).
fn modem_likelihood(sc: &Scenario) -> PingLikelihood {
    let (tl, success, rate) = (sc.comms.tl.assumed(), sc.comms.success.clone(), sc.comms.cna_rate);
    Box::new(move |d: f64| success.p_success(rate, tl.at_distance(d)))
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

/// The pre-deployment plan on the nominal survey tracks (no current, no nav error), flown by time.
fn open_loop(sc: &Scenario) -> Result<TimedWaypoints, PlanError> {
    let mut cfg = sc.planner_config();
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
        sigma0: vec![sc.planner.sigma0; n],
        eps0: vec![sc.planner.eps0; n],
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

/// Receiver type of a link's far end.
pub fn receiver(to_cna: bool) -> Receiver {
    if to_cna {
        Receiver::Barge
    } else {
        Receiver::Iver2
    }
}
