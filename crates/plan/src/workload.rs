//! Standard planning workloads for benchmarks (criterion and `coopnav bench planner`): one
//! decision of the planner on the geometry of Hudson 2012, Sec. 5.2 — N survey AUVs on adjacent lanes `gap`
//! metres apart (500 m in Sec. 5.2; 100 m for the Sec. 5.3 canonical geometry) heading north at
//! 1.5 m/s at 90 m depth, the CNA starting at (140, 0, 0) heading east,
//! τ = 10 s, s = 1.5 m/s, penalty case 1. Invented where the thesis is silent
//! (docs/models.md#hudson-geometry).
//! Under the estimator-aware cost every AUV starts with P = 1 m²·I and q = α/2 per axis (the
//! same trace growth as Hudson's α), over a perfect link or a lossy one ([`PlateauLink`]).
//!
//! [`Workload::standard`] is the one list both the criterion bench and `coopnav bench planner` run.

use crate::planner::Algorithm;
use crate::{
    Aggregate, AuvError, AuvEstimate, CnaKind, CnaPose, CostSpec, Deadline, Decision, DistanceLimits, ErrorModel,
    EstimatorSpec, FnForecast, LinkModel, LookAheadPlanner, MotionConfig, PenaltyCase, PlanError, PlanInput,
    PlannerConfig, RangeNoise, SearchConfig, TrueError, TruthInput, TruthSpec,
};
use coopnav_core::{Heading, Vec3};
use serde::Serialize;

/// One benchmark decision: N AUVs, A heading options, B pitch options (1 = ASC), L look-ahead.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Workload {
    pub n: usize,
    pub a: usize,
    pub b: usize,
    pub l: usize,
    /// East–west gap between neighbouring AUVs, m.
    pub gap: f64,
    pub cost: CostSpec,
    /// A lossy link's success at short range ([`PlateauLink`]; `None`: a perfect link).
    pub link_plateau: Option<f64>,
}

/// A lossy link for the workloads: success = plateau / (1 + (r / 1500 m)⁴). The closed loop's
/// rate-0 curve has a plateau of about 0.8 (`REACH_SUCCESS` in the sim crate's closed-loop
/// experiment); invented shape.
#[derive(Debug, Clone, Copy)]
pub struct PlateauLink(pub f64);

impl LinkModel for PlateauLink {
    fn success(&self, slant_range_m: f64) -> f64 {
        self.0 / (1.0 + (slant_range_m / 1500.0).powi(4))
    }
}

impl Workload {
    /// The standard workloads: Hudson's cost on the thesis's geometries, then the
    /// estimator-aware cost (N = 5, A = 7, L = 5 and L = 7, targets 5 ms and 100 ms), then
    /// with the range bias and cost-to-go the closed-loop evaluation plans with (6 m/km,
    /// H = 10 levels), the evaluation's sloping tree (N = 3, A = 5, L = 5, the sum of σ) over a
    /// lossy link, and last its current grid's: the true-error cost with a 0.05 m/s current the
    /// filters do not model, L = 4 (the sim crate's `CURRENT_TRUTH`; its lower bound cuts nothing
    /// here, so its branch-and-bound prunes on the penalties alone).
    pub fn standard() -> Vec<Workload> {
        let hudson = |n, a, b, l, gap| Workload { n, a, b, l, gap, cost: CostSpec::Hudson, link_plateau: None };
        let cost = CostSpec::Estimator;
        let with = |l, spec| Workload { n: 5, a: 7, b: 1, l, gap: 500.0, cost: cost(spec), link_plateau: None };
        let estimator = |l| with(l, EstimatorSpec::default());
        let biased = EstimatorSpec { bias_per_km_m: 6.0, terminal_levels: 10.0, ..EstimatorSpec::default() };
        let evaluation = EstimatorSpec { aggregate: Aggregate::SigmaSum, ..biased };
        let truth = TruthSpec {
            drift_m2_s: 0.002,
            range_noise: RangeNoise { sigma_m: 1.8, per_km_m: 0.0 },
            cna_diffusion_m2_s: 0.0,
        };
        let true_error = EstimatorSpec { truth: Some(truth), unmodelled_current: [0.05, 0.0], ..evaluation };
        vec![
            hudson(2, 5, 1, 5, 500.0),
            hudson(2, 5, 1, 5, 100.0),
            hudson(5, 7, 1, 7, 500.0),
            hudson(5, 7, 1, 7, 100.0),
            hudson(2, 7, 1, 4, 500.0),
            hudson(2, 5, 3, 3, 500.0),
            hudson(2, 4, 5, 3, 500.0),
            hudson(5, 3, 6, 3, 100.0),
            estimator(5),
            estimator(7),
            with(7, biased),
            Workload { n: 3, a: 5, l: 5, link_plateau: Some(0.8), ..with(5, evaluation) },
            Workload { n: 3, a: 5, l: 4, link_plateau: Some(0.8), ..with(4, true_error) },
        ]
    }

    /// A short name for reports: cost kind (with the estimator's bias and cost-to-go when set)
    /// and the N, A, B, L and gap of the workload, and a lossy link's plateau.
    pub fn name(&self) -> String {
        let kind = match self.cost {
            CostSpec::Hudson => "hudson".to_string(),
            CostSpec::Estimator(e) if e.truth.is_some() => {
                format!("true_error_bias{}_H{}_current{}", e.bias_per_km_m, e.terminal_levels, e.unmodelled_current[0])
            }
            CostSpec::Estimator(e) if e.bias_per_km_m > 0.0 || e.terminal_levels > 0.0 => {
                let sum = if e.aggregate == Aggregate::SigmaSum { "sigma_sum_" } else { "" };
                format!("estimator_{sum}bias{}_H{}", e.bias_per_km_m, e.terminal_levels)
            }
            CostSpec::Estimator(_) => "estimator".to_string(),
        };
        let link = self.link_plateau.map_or(String::new(), |p| format!("_link{p}"));
        format!("{kind}_N{}_A{}_B{}_L{}_gap{}{link}", self.n, self.a, self.b, self.l, self.gap)
    }

    /// The search of a benchmark: `algorithm`, no deadline, on one thread or in the parallel mode
    /// with its default one-thread start (`SearchConfig::parallel_after_nodes`).
    pub fn search(algorithm: Algorithm, parallel: bool) -> SearchConfig {
        SearchConfig { algorithm, parallel, deadline: Deadline::None, ..SearchConfig::default() }
    }

    pub fn config(&self, search: SearchConfig) -> PlannerConfig {
        PlannerConfig {
            look_ahead: self.l,
            motion: MotionConfig {
                speed: 1.5,
                tau: 10.0,
                heading_options: self.a,
                max_turn_rate_deg_s: 4.0,
                cna: if self.b > 1 { CnaKind::auv(self.b) } else { CnaKind::Asc {} },
            },
            error: ErrorModel::default(),
            cost: self.cost,
            limits: DistanceLimits::default(),
            penalties: PenaltyCase::C1.penalties(),
            search,
        }
    }

    /// Leaves of the full tree, (A·B)^(L+1).
    pub fn leaves(&self) -> u64 {
        ((self.a * self.b) as u64).pow(self.l as u32 + 1)
    }

    /// Plans one decision with `search` (e.g. [`Workload::search`]).
    pub fn decide(&self, search: SearchConfig) -> Result<Decision, PlanError> {
        let cfg = self.config(search);
        let gap = self.gap;
        let auv = move |k: usize, t: f64| Vec3::new(gap * k as f64 + 50.0, 1.5 * t, 90.0);
        let cna = CnaPose { pos: Vec3::new(140.0, 0.0, 0.0), heading: Heading::from_radians(0.0), pitch: 0.0 };
        let errors: Vec<AuvError> = (0..self.n).map(|k| cfg.error.initial(1.0, 1.0, &cna.pos, &auv(k, 0.0))).collect();
        let estimate = AuvEstimate { cov: [1.0, 0.0, 1.0], process_noise: 0.5 * cfg.error.alpha };
        let estimates = vec![estimate; self.n];
        let forecast = FnForecast { n: self.n, f: move |k: usize, t: f64| Some(auv(k, t)) };
        let input = PlanInput {
            t: 0.0,
            cna,
            errors: &errors,
            estimates: &estimates,
            cna_variance: 1.0,
            forecast: &forecast,
            slot_reach_m: &[],
        };
        // The true-error cost starts from each AUV's true moments: its filter's P, no mean yet.
        let moments = vec![TrueError { s: estimate.cov, ..TrueError::default() }; self.n];
        let truth = TruthInput { errors: &moments, cna_variance: 1.0 };
        let truth = matches!(self.cost, CostSpec::Estimator(EstimatorSpec { truth: Some(_), .. })).then_some(&truth);
        match self.link_plateau {
            Some(plateau) => LookAheadPlanner::with_link(cfg, &PlateauLink(plateau))?.decide_with_truth(&input, truth),
            None => LookAheadPlanner::new(cfg)?.decide_with_truth(&input, truth),
        }
    }
}
