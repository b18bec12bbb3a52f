//! The look-ahead planner as a closed-loop CNA policy (Hudson 2012, Sec. 4.2, underway mode;
//! docs/models.md#hudson-prediction): it keeps its own modelled error state per survey AUV (eq. 1, stepped at every
//! ping from the CNA's pose and the AUV's *predicted* position), plans over the AUVs the CNA has
//! heard from, and records the decisions' deadline misses and the tree levels reached.
//! Under the estimator-aware cost it also keeps a model of each AUV's filter covariance
//! ([`CovarianceTracker`]), stepped by the same expected EKF update the planner scores with.

use crate::policy::{CnaCommand, CnaPolicy, PolicyContext, ReportedCov};
use coopnav_core::{Track, Vec3};
use coopnav_plan::current_states::{
    current_ping, current_prediction, CurrentGrowth, CurrentPingNoise, CurrentState, CurrentStates,
};
use coopnav_plan::true_error::{true_error_prediction, true_error_step, Growth, PingNoise, TrueState};
use coopnav_plan::{
    expected_posterior, AuvError, AuvEstimate, AuvForecast, CostSpec, CurrentInput, Decision, ErrorModel, HorizonSpec,
    LinkModel, LookAheadPlanner, PlanError, PlanInput, PlannerConfig, RangeNoise, SurveyInput, TrueError, TruthInput,
    TruthSpec,
};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// The planner's error model (eq. 1) tracked per AUV between decisions.
#[derive(Debug, Clone)]
pub struct ErrorTracker {
    model: ErrorModel,
    tau: f64,
    sigma0: f64,
    eps0: f64,
    errors: Vec<Option<AuvError>>,
}

impl ErrorTracker {
    pub fn new(n: usize, model: ErrorModel, tau: f64, sigma0: f64, eps0: f64) -> Self {
        ErrorTracker { model, tau, sigma0, eps0, errors: vec![None; n] }
    }

    /// A ping from `cna` at AUV `k` (at `auv`), received with probability `p_received` (1 = the
    /// thesis's assumption that every ping arrives). The first ping starts the model (docs/models.md#hudson-start); a
    /// ping counts as the expected value over reception: received → eq. 1, lost → ε² + ατ.
    pub fn ping(&mut self, k: usize, cna: &Vec3, auv: &Vec3, p_received: f64) {
        let m = self.model;
        let next = match self.errors[k] {
            None => m.initial(self.sigma0, self.eps0, cna, auv),
            Some(prev) => {
                let got = m.step(&prev, m.los([cna.x, cna.y, cna.z], [auv.x, auv.y, auv.z]), self.tau);
                let p = p_received.clamp(0.0, 1.0);
                let lost = prev.eps2 + m.alpha * self.tau;
                AuvError { eps2: p * got.eps2 + (1.0 - p) * lost, ..got }
            }
        };
        self.errors[k] = Some(next);
    }

    /// No ping this period (no CNA, or the AUV unknown): ε² grows by ατ.
    pub fn silent(&mut self, k: usize) {
        if let Some(e) = self.errors[k].as_mut() {
            e.eps2 += self.model.alpha * self.tau;
        }
    }

    pub fn error(&self, k: usize) -> Option<&AuvError> {
        self.errors[k].as_ref()
    }

    /// Modelled total error √(σ² + ε²) of AUV `k`, m.
    pub fn total(&self, k: usize) -> Option<f64> {
        self.error(k).map(AuvError::total)
    }
}

/// The CNA's model of each survey AUV's horizontal filter covariance. The AUVs report their
/// filter's covariance in every status message; at each decision the model starts from the
/// newest report it has not used yet, grown by the filter's process noise q over the report's
/// age (the filter's own prediction), else from its previous value grown by q·τ; then, unless it
/// counts reports only ([`CovarianceTracker::reports_only`]), it takes the expected range update of
/// this period's ping (`coopnav_plan::expected_posterior`). Before any report it starts at the
/// filter's initial covariance.
#[derive(Debug, Clone)]
pub struct CovarianceTracker {
    start: AuvEstimate,
    tau: f64,
    noise: RangeNoise,
    covs: Vec<Option<[f64; 3]>>,
    /// Growth rate per axis each AUV's estimate is planned with, m²/s.
    rates: Vec<f64>,
    /// Send time of the newest report each AUV's model was restarted from.
    used: Vec<f64>,
    /// Some: pings are never credited ([`CovarianceTracker::reports_only`]).
    unheard: Option<UnheardGrowth>,
    /// Some: the true-error moments are tracked too ([`CovarianceTracker::with_truth`]).
    truth: Option<TruthTracker>,
}

/// The CNA's model of each survey AUV's TRUE error moments (S, C of `coopnav_plan::true_error`),
/// stepped at every ping by the same recursion the true-error cost scores with, with the gain of
/// the tracked filter covariance. Reports cannot restart it (an AUV does not know its true error):
/// an AUV starts, when first known at time t, at S = (σ₀² + q_t·t)·I (σ₀ its launch position
/// error) and C = 0. When the CNA's own variance falls (a fix), its new error is independent of
/// the old one, so every C restarts at 0. Invented (docs/models.md#true-error-cost). Under a current
/// the filters do not model (`current`, m/s) each error also carries the mean −c·t
/// since launch, less what the pings took off it (`true_error` step 1).
#[derive(Debug, Clone)]
struct TruthTracker {
    spec: TruthSpec,
    launch_variance: f64,
    current: [f64; 2],
    errors: Vec<Option<(f64, TrueError)>>,
    cna_variance: f64,
}

impl TruthTracker {
    /// AUV `k`'s moments at time `t` before this period's ping: grown by the true drift (and
    /// shifted by the unmodelled current) since they were last stepped, or their start.
    fn grown(&self, k: usize, t: f64) -> TrueError {
        let (since, start) = match self.errors[k] {
            Some((since, e)) => (since, e),
            None => (0.0, TrueError { s: [self.launch_variance, 0.0, self.launch_variance], ..TrueError::default() }),
        };
        let dt = (t - since).max(0.0);
        let growth =
            Growth { filter: 0.0, truth: self.spec.drift_m2_s * dt, cna: 0.0, shift: self.current.map(|c| -c * dt) };
        true_error_prediction(&TrueState { p: [0.0; 3], truth: start, v: 0.0 }, growth).truth
    }

    /// The CNA's own variance at this decision; a fall restarts every C.
    fn set_cna_variance(&mut self, v: f64) {
        if v < self.cna_variance {
            for (_, e) in self.errors.iter_mut().flatten() {
                e.c = [0.0; 4];
            }
        }
        self.cna_variance = v;
    }

    /// A ping at time `t` from `cna` at AUV `k` (at `auv`), received with probability `p`, under
    /// the filter covariance `prior` grown by `grow` per axis.
    fn ping(&mut self, k: usize, t: f64, (prior, grow): ([f64; 3], f64), link: (&Vec3, &Vec3, f64), noise: RangeNoise) {
        let (cna, auv, p) = link;
        let state = TrueState { p: prior, truth: self.grown(k, t), v: self.cna_variance };
        let growth = Growth { filter: grow, truth: 0.0, cna: 0.0, shift: [0.0; 2] };
        let ping_noise = PingNoise { filter: noise, filter_cna_variance: 0.0, truth: self.spec.range_noise };
        let next = true_error_step(&state, growth, [cna.x, cna.y, cna.z], [auv.x, auv.y, auv.z], &ping_noise, |_| p);
        self.errors[k] = Some((t, next.truth));
    }

    /// No ping credited: the moments only grow.
    fn silent(&mut self, k: usize, t: f64) {
        if self.errors[k].is_some() {
            self.errors[k] = Some((t, self.grown(k, t)));
        }
    }
}

/// The CNA's model of each survey AUV's filter and true error when the filters estimate the water
/// current (`coopnav_plan::current_states`): stepped at every ping by the same recursion the
/// current-states cost scores with, from launch (t = 0), every ping counted with its expected
/// arrival. Reports do not restart it (they carry the position covariance only, not the
/// current's). Invented (docs/models.md#current-states-cost).
#[derive(Debug, Clone)]
struct CurrentTracker {
    spec: CurrentStates,
    /// The filters' position noise q_f and the truth's drift q_t per axis, m²/s.
    q_filter: f64,
    q_truth: f64,
    filter_noise: RangeNoise,
    truth_noise: RangeNoise,
    start: CurrentState,
    states: Vec<Option<(f64, CurrentState)>>,
}

impl CurrentTracker {
    /// AUV `k`'s state at `t` before this period's ping: grown since it was last stepped, or launch.
    fn grown(&self, k: usize, t: f64) -> CurrentState {
        let (since, state) = self.states[k].unwrap_or((0.0, self.start));
        current_prediction(&state, &CurrentGrowth::over(&self.spec, t - since, self.q_filter, self.q_truth))
    }

    /// A ping at `t` from `cna` to AUV `k` at `auv`, arriving with probability `p`, the CNA's
    /// own variance `v`.
    fn ping(&mut self, k: usize, t: f64, (cna, auv, p): (&Vec3, &Vec3, f64), v: f64) {
        let (filter, truth) = (self.filter_noise, self.truth_noise);
        let next = current_ping(
            &self.grown(k, t),
            [cna.x, cna.y, cna.z],
            [auv.x, auv.y, auv.z],
            |r, hh| CurrentPingNoise { filter: filter.variance(r), truth: truth.variance(r) + v * hh },
            |_| p,
        );
        self.states[k] = Some((t, next));
    }

    fn silent(&mut self, k: usize, t: f64) {
        if self.states[k].is_some() {
            self.states[k] = Some((t, self.grown(k, t)));
        }
    }

    /// AUV `k`'s state at `t` (stepped, or grown from launch for an AUV never pinged).
    fn state(&self, k: usize, t: f64) -> CurrentState {
        match self.states[k] {
            Some((since, s)) if since == t => s,
            _ => self.grown(k, t),
        }
    }
}

/// How the filter of an AUV not heard from since launch predicts its horizontal position
/// covariance per axis with no range: the position integrates an unobserved current (initial
/// variance P_c, (m/s)²; noise density q_c, (m/s)²/s; both 0 without a current state). With a
/// random-walk current P(t) = P₀ + q·t + P_c·t² + q_c·t³/3. With a Gauss–Markov current of
/// correlation time T (`model.correlation_time_s`), writing e = exp(−t/T), the initial current
/// contributes P_c·T²·(1 − e)² and the driven one q_c·T²·(t − 2T(1 − e) + T(1 − e²)/2) (the
/// integrated Ornstein–Uhlenbeck process; both tend to the random walk's terms as T → ∞). The
/// rate dP/dt (q + 2·P_c·T·e(1 − e) + q_c·T²·(1 − e)² with the decay; q + 2·P_c·t + q_c·t²
/// without) is what the planner grows it by. The speed, heading and compass-bias states are left
/// out: the AUV's sensors observe them, the current they cannot. Invented; the filter's prediction
/// is Gill 2013, §2.2.1's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UnheardGrowth {
    pub current_p0: f64,
    pub current_q: f64,
    /// The current's correlation time T, s; None: a random walk.
    pub current_correlation_s: Option<f64>,
}

impl UnheardGrowth {
    /// (P(t) − P₀, dP/dt) per axis at `t` seconds after launch, for process noise `q`.
    fn at(&self, q: f64, t: f64) -> (f64, f64) {
        let t = t.max(0.0);
        let (p_c, q_c) = (self.current_p0, self.current_q);
        let (current, rate) = match self.current_correlation_s {
            None => (p_c * t * t + q_c * t * t * t / 3.0, 2.0 * p_c * t + q_c * t * t),
            Some(tc) => {
                let e = (-t / tc).exp();
                let driven = tc * tc * (t - 2.0 * tc * (1.0 - e) + 0.5 * tc * (1.0 - e * e));
                let grown = p_c * tc * tc * (1.0 - e).powi(2) + q_c * driven;
                (grown, 2.0 * p_c * tc * e * (1.0 - e) + q_c * tc * tc * (1.0 - e).powi(2))
            }
        };
        (q * t + current, q + rate)
    }
}

impl CovarianceTracker {
    pub fn new(n: usize, start: AuvEstimate, tau: f64, noise: RangeNoise) -> Self {
        CovarianceTracker {
            start,
            tau,
            noise,
            covs: vec![None; n],
            rates: vec![start.process_noise; n],
            used: vec![f64::NEG_INFINITY; n],
            unheard: None,
            truth: None,
        }
    }

    /// Tracks the AUVs' true-error moments too (`TruthTracker`), each starting from a launch
    /// position variance `launch_variance` per axis, m², under the water current `current` (m/s)
    /// the filters do not model.
    pub fn with_truth(mut self, spec: TruthSpec, launch_variance: f64, current: [f64; 2]) -> Self {
        let n = self.covs.len();
        self.truth = Some(TruthTracker { spec, launch_variance, current, errors: vec![None; n], cna_variance: 0.0 });
        self
    }

    /// The CNA's own horizontal variance at this decision (the true-error moments' v).
    pub fn set_cna_variance(&mut self, v: f64) {
        if let Some(truth) = self.truth.as_mut() {
            truth.set_cna_variance(v);
        }
    }

    /// AUV `k`'s true-error moments, once known (with [`CovarianceTracker::with_truth`]).
    pub fn true_error(&self, k: usize) -> Option<TrueError> {
        self.truth.as_ref().and_then(|truth| truth.errors[k].map(|(_, e)| e))
    }

    /// The CNA's own variance the true-error moments were last stepped with, m².
    pub fn cna_variance(&self) -> f64 {
        self.truth.as_ref().map_or(0.0, |truth| truth.cna_variance)
    }

    /// Counts reports only (`[policy.planner-estimator]` `cost.tracking = "reports_only"`): a ping teaches the model
    /// nothing until the AUV's report shows it; an AUV never heard from grows from launch (t = 0)
    /// as `unheard` says.
    pub fn reports_only(mut self, unheard: UnheardGrowth) -> Self {
        self.unheard = Some(unheard);
        self
    }

    /// AUV `k`'s covariance before this period's ping at time `t`, and the growth still to add.
    fn prior(&mut self, k: usize, t: f64, reported: Option<ReportedCov>) -> Option<([f64; 3], f64)> {
        let q = self.start.process_noise;
        match reported.filter(|r| r.t > self.used[k]) {
            Some(r) => {
                self.used[k] = r.t;
                Some((r.cov, q * (t - r.t).max(0.0)))
            }
            None => self.covs[k].map(|c| (c, q * self.tau)),
        }
    }

    /// A ping at time `t` from `cna` at AUV `k` (at `auv`), received with probability
    /// `p_received`; `reported` is the AUV's newest covariance report.
    pub fn ping(&mut self, k: usize, t: f64, reported: Option<ReportedCov>, link: (&Vec3, &Vec3, f64)) {
        if self.unheard.is_some() {
            return self.predict(k, t, reported);
        }
        let (cna, auv, p_received) = link;
        let p = p_received.clamp(0.0, 1.0);
        let prior = self.prior(k, t, reported);
        if let Some(truth) = self.truth.as_mut() {
            truth.ping(k, t, prior.unwrap_or((self.start.cov, 0.0)), (cna, auv, p), self.noise);
        }
        self.covs[k] = Some(match prior {
            None => self.start.cov,
            Some((prior, grow)) => {
                expected_posterior(&prior, grow, [cna.x, cna.y, cna.z], [auv.x, auv.y, auv.z], &self.noise, 0.0, |_| p)
            }
        });
    }

    /// Reports only: the filter's prediction from the newest report, or from launch; the true
    /// error grows (a ping is not credited to it either).
    fn predict(&mut self, k: usize, t: f64, reported: Option<ReportedCov>) {
        if let Some(truth) = self.truth.as_mut() {
            truth.errors[k] = Some((t, truth.grown(k, t)));
        }
        let never_heard = self.used[k] == f64::NEG_INFINITY && reported.is_none();
        match self.unheard.filter(|_| never_heard) {
            Some(growth) => {
                let (grown, rate) = growth.at(self.start.process_noise, t);
                let [a, b, c] = self.start.cov;
                self.covs[k] = Some([a + grown, b, c + grown]);
                self.rates[k] = rate;
            }
            None => {
                self.rates[k] = self.start.process_noise;
                let ([a, b, c], grow) = self.prior(k, t, reported).unwrap_or((self.start.cov, 0.0));
                self.covs[k] = Some([a + grow, b, c + grow]);
            }
        }
    }

    /// No ping this period: the covariance only grows (from a newer report if there is one).
    pub fn silent(&mut self, k: usize, t: f64, reported: Option<ReportedCov>) {
        if let Some(truth) = self.truth.as_mut() {
            truth.silent(k, t);
        }
        if let Some(([a, b, c], grow)) = self.prior(k, t, reported) {
            self.covs[k] = Some([a + grow, b, c + grow]);
        }
    }

    pub fn estimate(&self, k: usize) -> Option<AuvEstimate> {
        self.covs[k].map(|cov| AuvEstimate { cov, process_noise: self.rates[k] })
    }

    /// AUV `k`'s modelled state at `t` for the horizon layer, known or not: its estimate, else
    /// its filter's covariance grown from launch with no range (its process noise, or as
    /// `reports_only`'s `unheard` says); and its true-error moments, else their launch value grown
    /// to `t` (with the tracked truth only).
    fn survey_state(&self, k: usize, t: f64) -> (AuvEstimate, Option<TrueError>) {
        let estimate = self.estimate(k).unwrap_or_else(|| {
            let q = self.start.process_noise;
            let (grown, rate) = self.unheard.map_or((q * t.max(0.0), q), |u| u.at(q, t));
            let [a, b, c] = self.start.cov;
            AuvEstimate { cov: [a + grown, b, c + grown], process_noise: rate }
        });
        let truth = self.truth.as_ref().map(|truth| truth.errors[k].map_or_else(|| truth.grown(k, t), |(_, e)| e));
        (estimate, truth)
    }
}

/// How the planner's decisions went.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct PlannerStats {
    pub decisions: u64,
    /// Decisions whose search stopped at the deadline before the full depth.
    pub deadline_misses: u64,
    pub levels_requested: usize,
    /// Shallowest and mean tree depth completed.
    pub min_levels_searched: usize,
    pub mean_levels_searched: f64,
    /// Decisions the planner could not make (no forecast): the CNA held position.
    pub failures: u64,
    /// Decisions taken before any AUV was known (the CNA held position).
    pub waiting: u64,
}

/// The success likelihood the planner assumes for a ping over a given slant distance.
pub type PingLikelihood = Box<dyn Likelihood>;

/// A ping likelihood that can be copied (a forked mission copies its planner); every `Clone`
/// closure is one.
pub trait Likelihood: Fn(f64) -> f64 + Send {
    fn clone_box(&self) -> PingLikelihood;
}

impl<F: Fn(f64) -> f64 + Send + Clone + 'static> Likelihood for F {
    fn clone_box(&self) -> PingLikelihood {
        Box::new(self.clone())
    }
}

impl Clone for PingLikelihood {
    fn clone(&self) -> Self {
        // The boxed closure's own copy (the box itself is a `Likelihood` too).
        (**self).clone_box()
    }
}

/// The ping likelihood as the planner's link model.
pub(crate) struct LikelihoodLink<'a>(pub &'a PingLikelihood);

impl LinkModel for LikelihoodLink<'_> {
    fn success(&self, slant_range_m: f64) -> f64 {
        (self.0)(slant_range_m).clamp(0.0, 1.0)
    }
}

/// The underway look-ahead planner behind [`CnaPolicy`].
#[derive(Clone)]
pub struct PlannerPolicy {
    planner: LookAheadPlanner,
    tracker: ErrorTracker,
    /// The filters' covariances, under the estimator-aware cost only.
    covariances: Option<CovarianceTracker>,
    lost_pings: Option<PingLikelihood>,
    /// Whether the planner is given the CNA's own variance (else 0: broadcasts taken as exact).
    cna_variance: bool,
    /// Per AUV (fleet order), the slant range beyond which no broadcast reaches it (its own slot
    /// starts first: `Scenario::slot_reach_m`); empty: the link alone decides.
    slot_reach: Vec<f64>,
    stats: PlannerStats,
    levels_total: u64,
    /// The newest decision's search result (None: it held, waiting or failing).
    last: Option<Decision>,
    /// Every survey AUV's mission plan (fleet order), what the horizon layer follows for an AUV
    /// the CNA has not heard from; None: no horizon layer.
    plans: Option<Arc<[Track]>>,
    /// The filters' current states, under the current-states cost only.
    current: Option<CurrentTracker>,
}

/// The survey as the horizon layer sees it: the AUVs the CNA has heard from as their reports
/// predict them, the others along their mission plans.
struct Survey<'a> {
    fleet: &'a dyn AuvForecast,
    known: &'a [bool],
    plans: &'a [Track],
}

impl AuvForecast for Survey<'_> {
    fn n_auvs(&self) -> usize {
        self.plans.len()
    }
    fn position(&self, k: usize, t: f64) -> Option<Vec3> {
        if self.known[k] {
            self.fleet.position(k, t)
        } else {
            Some(self.plans[k].at(t))
        }
    }
}

/// The AUVs of a forecast that are known, renumbered 0..m.
struct Known<'a> {
    inner: &'a dyn AuvForecast,
    index: &'a [usize],
}

impl AuvForecast for Known<'_> {
    fn n_auvs(&self) -> usize {
        self.index.len()
    }
    fn position(&self, k: usize, t: f64) -> Option<Vec3> {
        self.inner.position(*self.index.get(k)?, t)
    }
}

impl PlannerPolicy {
    /// `n` survey AUVs; `lost_pings` = Some(likelihood) models lost pings, None is the thesis.
    /// `filters` (the AUVs' initial covariance and process noise, and the range noise they
    /// assume) is required by the estimator-aware cost and ignored by Hudson's.
    pub fn new(
        cfg: PlannerConfig,
        n: usize,
        sigma0: f64,
        eps0: f64,
        lost_pings: Option<PingLikelihood>,
        filters: Option<(AuvEstimate, RangeNoise)>,
    ) -> Result<Self, PlanError> {
        let tracker = ErrorTracker::new(n, cfg.error, cfg.motion.tau, sigma0, eps0);
        let covariances = match (cfg.cost, filters) {
            (CostSpec::Hudson, _) => None,
            (CostSpec::Estimator(_), Some((start, noise))) => {
                Some(CovarianceTracker::new(n, start, cfg.motion.tau, noise))
            }
            (CostSpec::Estimator(_), None) => {
                return Err(PlanError::Input("the estimator-aware cost needs the AUVs' filter settings".into()))
            }
        };
        let stats = PlannerStats {
            levels_requested: cfg.look_ahead + 1,
            min_levels_searched: usize::MAX,
            ..PlannerStats::default()
        };
        // Only the estimator-aware cost reads the link (sampling it costs a few thousand calls).
        let planner = match (&lost_pings, cfg.cost) {
            (Some(f), CostSpec::Estimator(_)) => LookAheadPlanner::with_link(cfg, &LikelihoodLink(f))?,
            _ => LookAheadPlanner::new(cfg)?,
        };
        Ok(PlannerPolicy {
            planner,
            tracker,
            covariances,
            lost_pings,
            cna_variance: true,
            slot_reach: Vec::new(),
            stats,
            levels_total: 0,
            plans: None,
            current: None,
            last: None,
        })
    }

    /// Plans on filters that estimate the water current (`coopnav_plan::current_states`), with the
    /// true-error cost's `truth` and the AUVs' launch position variance; no effect under Hudson's
    /// cost or without the true-error cost.
    pub fn with_current_states(mut self, spec: CurrentStates, truth: TruthSpec, launch_variance: f64) -> Self {
        let Some(c) = self.covariances.as_ref() else { return self };
        let CostSpec::Estimator(e) = self.planner.config().cost else { return self };
        if e.truth.is_none() {
            return self;
        }
        let n = c.covs.len();
        self.current = Some(CurrentTracker {
            spec,
            q_filter: c.start.process_noise,
            q_truth: truth.drift_m2_s,
            filter_noise: c.noise,
            truth_noise: truth.range_noise,
            start: CurrentState::launch(&spec, c.start.cov, launch_variance),
            states: vec![None; n],
        });
        self.planner = self.planner.clone().with_current_states(spec);
        self
    }

    /// The mission-long horizon layer (coopnav_plan `horizon`) over every AUV, those not heard
    /// from along `plans` (their mission plans, fleet order); no effect under Hudson's cost or
    /// with `spec.enabled = false`.
    pub fn with_horizon(mut self, spec: HorizonSpec, plans: Vec<Track>) -> Result<Self, PlanError> {
        if self.covariances.is_some() && spec.enabled {
            self.planner = self.planner.with_horizon(spec)?;
            self.plans = Some(plans.into());
        }
        Ok(self)
    }

    /// The estimator-aware cost's range bias from a known sound-speed profile (`BiasTable`).
    pub fn with_bias(mut self, table: coopnav_plan::BiasTable) -> Self {
        self.planner = self.planner.with_bias(table);
        self
    }

    /// The estimator-aware cost and its covariance model credit no ping beyond AUV k's
    /// `reach[k]` (fleet order); no effect under Hudson's cost.
    pub fn with_slot_reach(mut self, reach: Vec<f64>) -> Self {
        if self.covariances.is_some() {
            self.slot_reach = reach;
        }
        self
    }

    /// The planner scores every broadcast position as exact (the CNA's own variance left out).
    pub fn without_cna_variance(mut self) -> Self {
        self.cna_variance = false;
        self
    }

    /// The true-error cost's model of the AUVs' true errors (`CovarianceTracker::with_truth`);
    /// no effect under Hudson's cost.
    pub fn with_truth(mut self, spec: TruthSpec, launch_variance: f64, current: [f64; 2]) -> Self {
        self.covariances = self.covariances.map(|c| c.with_truth(spec, launch_variance, current));
        self
    }

    /// The estimator-aware cost's covariance model counts reports only
    /// ([`CovarianceTracker::reports_only`]); no effect under Hudson's cost.
    pub fn with_reports_only(mut self, unheard: UnheardGrowth) -> Self {
        self.covariances = self.covariances.map(|c| c.reports_only(unheard));
        self
    }

    pub fn stats(&self) -> PlannerStats {
        let mut s = self.stats.clone();
        let planned = s.decisions - s.failures - s.waiting;
        s.mean_levels_searched = if planned > 0 { self.levels_total as f64 / planned as f64 } else { 0.0 };
        if s.min_levels_searched == usize::MAX {
            s.min_levels_searched = 0;
        }
        s
    }

    pub fn tracker(&self) -> &ErrorTracker {
        &self.tracker
    }

    /// The newest decision's search result: the option chosen, its cost, the levels searched
    /// (None: that decision held position).
    pub fn last_decision(&self) -> Option<&Decision> {
        self.last.as_ref()
    }

    /// The planner's configuration (its motion options among it).
    pub fn config(&self) -> &PlannerConfig {
        self.planner.config()
    }

    /// The decision under the 2-state costs: the horizon layer (if any) over every AUV, those not
    /// heard from along their plans.
    fn decide_on_moments(
        &self,
        input: &PlanInput,
        truth: Option<&TruthInput>,
        (ctx, n, known): (&PolicyContext, usize, &[usize]),
    ) -> Result<Decision, PlanError> {
        match (&self.plans, &self.covariances) {
            (Some(plans), Some(c)) => {
                let mut heard = vec![false; n];
                known.iter().for_each(|&k| heard[k] = true);
                let states: Vec<(AuvEstimate, Option<TrueError>)> = (0..n).map(|k| c.survey_state(k, ctx.t)).collect();
                let all_estimates: Vec<AuvEstimate> = states.iter().map(|s| s.0).collect();
                let all_truth: Vec<TrueError> = states.iter().filter_map(|s| s.1).collect();
                let survey_truth = truth
                    .filter(|_| all_truth.len() == n)
                    .map(|t| TruthInput { errors: &all_truth, cna_variance: t.cna_variance });
                let forecast = Survey { fleet: ctx.fleet, known: &heard, plans };
                let plan = PlanInput {
                    estimates: &all_estimates,
                    forecast: &forecast,
                    slot_reach_m: &self.slot_reach,
                    ..*input
                };
                let survey = SurveyInput { plan: &plan, truth: survey_truth.as_ref() };
                self.planner.decide_with_survey(input, truth, survey)
            }
            _ => self.planner.decide_with_truth(input, truth),
        }
    }
}

impl CnaPolicy for PlannerPolicy {
    fn name(&self) -> &'static str {
        if self.covariances.is_some() {
            "planner-estimator"
        } else {
            "planner"
        }
    }

    /// Called right after the CNA's broadcast at `ctx.t`: first the broadcast's effect on the
    /// modelled errors, then the next decision.
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        self.stats.decisions += 1;
        self.last = None;
        let n = ctx.fleet.n_auvs();
        if let Some(c) = self.covariances.as_mut() {
            c.set_cna_variance(ctx.cna_variance);
        }
        let mut known = Vec::with_capacity(n);
        for k in 0..n {
            match ctx.fleet.position(k, ctx.t) {
                Some(p) => {
                    let range = (p - ctx.cna.pos).norm();
                    let likelihood = self.lost_pings.as_ref().map_or(1.0, |f| f(range));
                    self.tracker.ping(k, &ctx.cna.pos, &p, likelihood);
                    let beyond = self.slot_reach.get(k).is_some_and(|&reach| range >= reach);
                    let arrives = if beyond { 0.0 } else { likelihood };
                    if let Some(c) = self.covariances.as_mut() {
                        c.ping(k, ctx.t, ctx.reported(k), (&ctx.cna.pos, &p, arrives));
                    }
                    if let Some(c) = self.current.as_mut() {
                        c.ping(k, ctx.t, (&ctx.cna.pos, &p, arrives), ctx.cna_variance);
                    }
                    known.push(k);
                }
                None => {
                    self.tracker.silent(k);
                    if let Some(c) = self.covariances.as_mut() {
                        c.silent(k, ctx.t, ctx.reported(k));
                    }
                    if let Some(c) = self.current.as_mut() {
                        c.silent(k, ctx.t);
                    }
                }
            }
        }
        if known.is_empty() {
            self.stats.waiting += 1;
            return CnaCommand::Hold;
        }
        let errors: Vec<AuvError> = known.iter().filter_map(|&k| self.tracker.error(k).copied()).collect();
        let estimates: Vec<AuvEstimate> =
            self.covariances.as_ref().map_or(Vec::new(), |c| known.iter().filter_map(|&k| c.estimate(k)).collect());
        let true_errors: Vec<TrueError> =
            self.covariances.as_ref().map_or(Vec::new(), |c| known.iter().filter_map(|&k| c.true_error(k)).collect());
        // Only a tracker with the true-error moments has them (one per known AUV).
        let truth = self
            .covariances
            .as_ref()
            .filter(|_| !true_errors.is_empty())
            .map(|c| TruthInput { errors: &true_errors, cna_variance: c.cna_variance() });
        let forecast = Known { inner: ctx.fleet, index: &known };
        let slot_reach: Vec<f64> = known.iter().filter_map(|&k| self.slot_reach.get(k).copied()).collect();
        let input = PlanInput {
            t: ctx.t,
            cna: ctx.cna,
            errors: &errors,
            estimates: &estimates,
            cna_variance: if self.cna_variance { ctx.cna_variance } else { 0.0 },
            forecast: &forecast,
            slot_reach_m: &slot_reach,
        };
        let decided = match (&self.current, &self.covariances) {
            (Some(current), Some(c)) => {
                let states: Vec<CurrentState> = known.iter().map(|&k| current.state(k, ctx.t)).collect();
                let v = ctx.cna_variance;
                let here = CurrentInput { states: &states, cna_variance: v };
                match &self.plans {
                    Some(plans) => {
                        let mut heard = vec![false; n];
                        known.iter().for_each(|&k| heard[k] = true);
                        let all_estimates: Vec<AuvEstimate> = (0..n).map(|k| c.survey_state(k, ctx.t).0).collect();
                        let all_states: Vec<CurrentState> = (0..n).map(|k| current.state(k, ctx.t)).collect();
                        let forecast = Survey { fleet: ctx.fleet, known: &heard, plans };
                        let plan = PlanInput {
                            estimates: &all_estimates,
                            forecast: &forecast,
                            slot_reach_m: &self.slot_reach,
                            ..input
                        };
                        let survey = CurrentInput { states: &all_states, cna_variance: v };
                        self.planner.decide_on_current_states(&input, &here, Some((&plan, &survey)))
                    }
                    None => self.planner.decide_on_current_states(&input, &here, None),
                }
            }
            _ => self.decide_on_moments(&input, truth.as_ref(), (ctx, n, &known)),
        };
        match decided {
            Ok(d) => {
                if d.levels_searched < d.levels_requested {
                    self.stats.deadline_misses += 1;
                }
                self.stats.min_levels_searched = self.stats.min_levels_searched.min(d.levels_searched);
                self.levels_total += d.levels_searched as u64;
                self.last = Some(d);
                CnaCommand::GoTo(d.next.pos)
            }
            Err(e) => {
                tracing::warn!(t = ctx.t, error = %e, "planner could not decide; the CNA holds");
                self.stats.failures += 1;
                CnaCommand::Hold
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_core::Heading;
    use coopnav_plan::{
        CnaKind, CnaPose, Deadline, DistanceLimits, FnForecast, MotionConfig, PenaltyCase, SearchConfig,
    };

    fn cfg() -> PlannerConfig {
        PlannerConfig {
            look_ahead: 2,
            motion: MotionConfig {
                speed: 2.0,
                tau: 30.0,
                heading_options: 5,
                max_turn_rate_deg_s: 4.0,
                cna: CnaKind::Asc {},
            },
            error: ErrorModel::default(),
            cost: coopnav_plan::CostSpec::Hudson,
            limits: DistanceLimits::default(),
            penalties: PenaltyCase::C1.penalties(),
            search: SearchConfig { deadline: Deadline::None, parallel: false, ..SearchConfig::default() },
        }
    }

    /// The context of decision `step` (τ = 30 s) from `cna`.
    fn at_step<'a>(step: u32, cna: CnaPose, fleet: &'a dyn AuvForecast) -> PolicyContext<'a> {
        let t = 30.0 * f64::from(step);
        PolicyContext { t, tau: 30.0, cna, speed: 2.0, fleet, reported: &[], cna_variance: 1.0 }
    }

    #[test]
    fn plans_over_known_auvs_and_tracks_their_errors() {
        let mut p = PlannerPolicy::new(cfg(), 2, 1.0, 1.0, None, None).unwrap();
        // AUV 1 never heard from: the planner still plans for AUV 0.
        let fleet = FnForecast { n: 2, f: |k: usize, t: f64| (k == 0).then(|| Vec3::new(300.0, 1.5 * t, 20.0)) };
        let cna = CnaPose { pos: Vec3::new(0.0, 0.0, 0.0), heading: Heading::from_radians(0.0), pitch: 0.0 };
        for step in 0..4 {
            assert!(matches!(p.decide(&at_step(step, cna, &fleet)), CnaCommand::GoTo(_)));
        }
        assert!(p.tracker().total(0).unwrap() > 1.0);
        assert!(p.tracker().total(1).is_none());
        let s = p.stats();
        assert_eq!((s.decisions, s.deadline_misses, s.failures, s.min_levels_searched), (4, 0, 0, 3));
    }

    #[test]
    fn lost_pings_grow_the_modelled_error() {
        let (m, c, a) = (ErrorModel::default(), Vec3::zeros(), Vec3::new(100.0, 0.0, 0.0));
        let (mut sure, mut lossy) = (ErrorTracker::new(1, m, 30.0, 1.0, 1.0), ErrorTracker::new(1, m, 30.0, 1.0, 1.0));
        for i in 0..10 {
            let ang = i as f64;
            let auv = Vec3::new(100.0 * ang.cos(), 100.0 * ang.sin(), 0.0);
            sure.ping(0, &c, &auv, 1.0);
            lossy.ping(0, &c, &auv, 0.3);
        }
        assert!(lossy.total(0).unwrap() > sure.total(0).unwrap());
        let mut silent = ErrorTracker::new(1, m, 30.0, 1.0, 1.0);
        silent.ping(0, &c, &a, 1.0);
        silent.silent(0);
        assert!((silent.error(0).unwrap().eps2 - (1.0 + 3.0)).abs() < 1e-12);
    }

    #[test]
    fn the_estimator_planner_tracks_covariances_and_needs_the_filter_settings() {
        let est = PlannerConfig { cost: CostSpec::Estimator(coopnav_plan::EstimatorSpec::default()), ..cfg() };
        assert!(PlannerPolicy::new(est, 2, 1.0, 1.0, None, None).is_err());
        let start = AuvEstimate { cov: [16.0, 0.0, 16.0], process_noise: 0.1 };
        let mut p = PlannerPolicy::new(est, 2, 1.0, 1.0, None, Some((start, RangeNoise::default()))).unwrap();
        assert_eq!(p.name(), "planner-estimator");
        let fleet = FnForecast { n: 2, f: |k: usize, t: f64| Some(Vec3::new(300.0 + 200.0 * k as f64, 1.5 * t, 20.0)) };
        let cna = CnaPose { pos: Vec3::new(0.0, 0.0, 0.0), heading: Heading::from_radians(0.0), pitch: 0.0 };
        for step in 0..4 {
            assert!(matches!(p.decide(&at_step(step, cna, &fleet)), CnaCommand::GoTo(_)));
        }
        // Three pings after the start: the radial variance collapses, the trace falls below 2·16.
        let c = p.covariances.as_ref().unwrap().estimate(0).unwrap().cov;
        assert!(c[0] + c[2] < 32.0, "{c:?}");
        // A lost ping is pure growth: q·τ per axis.
        let mut t = CovarianceTracker::new(1, start, 30.0, RangeNoise::default());
        let (cna, auv) = (Vec3::zeros(), Vec3::new(100.0, 0.0, 0.0));
        t.ping(0, 0.0, None, (&cna, &auv, 1.0));
        t.ping(0, 30.0, None, (&cna, &auv, 0.0));
        assert_eq!(t.estimate(0).unwrap().cov, [19.0, 0.0, 19.0]);
        t.silent(0, 60.0, None);
        assert_eq!(t.estimate(0).unwrap().cov, [22.0, 0.0, 22.0]);
        // A report restarts the model from the filter's own covariance, grown by q over its age
        // (10 s: 1 m² per axis), once: the same report is not used twice.
        let report = ReportedCov { t: 80.0, cov: [50.0, 5.0, 2.0] };
        t.silent(0, 90.0, Some(report));
        assert_eq!(t.estimate(0).unwrap().cov, [51.0, 5.0, 3.0]);
        t.silent(0, 120.0, Some(report));
        assert_eq!(t.estimate(0).unwrap().cov, [54.0, 5.0, 6.0]);
        // A lost ping after a report: pure growth from the report.
        t.ping(0, 150.0, Some(ReportedCov { t: 140.0, cov: [4.0, 0.0, 9.0] }), (&cna, &auv, 0.0));
        assert_eq!(t.estimate(0).unwrap().cov, [5.0, 0.0, 10.0]);
    }

    /// An AUV beyond its slot reach is pinged in vain: its modelled covariance only grows (q·τ
    /// per axis and decision), where an AUV as far with no reach limit gets the pings' updates;
    /// the reach is the estimator's only (Hudson's planner ignores it).
    #[test]
    fn no_ping_is_credited_beyond_an_auvs_slot_reach() {
        let est = PlannerConfig { cost: CostSpec::Estimator(coopnav_plan::EstimatorSpec::default()), ..cfg() };
        let start = AuvEstimate { cov: [16.0, 0.0, 16.0], process_noise: 0.1 };
        let filters = Some((start, RangeNoise::default()));
        let policy =
            |reach: Vec<f64>| PlannerPolicy::new(est, 2, 1.0, 1.0, None, filters).unwrap().with_slot_reach(reach);
        let (mut reached, mut cut) = (policy(vec![f64::INFINITY; 2]), policy(vec![f64::INFINITY, 250.0]));
        let fleet = FnForecast { n: 2, f: |k: usize, t: f64| Some(Vec3::new(300.0 * (k + 1) as f64, 1.5 * t, 20.0)) };
        let cna = CnaPose { pos: Vec3::new(0.0, 0.0, 0.0), heading: Heading::from_radians(0.0), pitch: 0.0 };
        for step in 0..4 {
            reached.decide(&at_step(step, cna, &fleet));
            cut.decide(&at_step(step, cna, &fleet));
        }
        let cov = |p: &PlannerPolicy, k: usize| p.covariances.as_ref().unwrap().estimate(k).unwrap().cov;
        // AUV 1, 600 m away, beyond 250 m: three decisions of growth after the start.
        assert_eq!(cov(&cut, 1), [25.0, 0.0, 25.0]);
        assert!(cov(&reached, 1)[0] + cov(&reached, 1)[2] < 32.0, "{:?}", cov(&reached, 1));
        // AUV 0 has no reach limit in either.
        assert_eq!(cov(&cut, 0), cov(&reached, 0));
        let hudson = PlannerPolicy::new(cfg(), 2, 1.0, 1.0, None, None).unwrap().with_slot_reach(vec![0.0; 2]);
        assert!(hudson.slot_reach.is_empty());
    }

    /// One AUV's tracker with true-error moments: its filter's process noise, the truth's drift
    /// 0.05 m²/s and ranges σ 1 m, the CNA's diffusion and the unmodelled current.
    fn truth_tracker(process_noise: f64, cna_diffusion_m2_s: f64, current: [f64; 2]) -> CovarianceTracker {
        let start = AuvEstimate { cov: [16.0, 0.0, 16.0], process_noise };
        let range_noise = RangeNoise { sigma_m: 1.0, per_km_m: 0.0 };
        let spec = TruthSpec { drift_m2_s: 0.05, range_noise, cna_diffusion_m2_s };
        CovarianceTracker::new(1, start, 30.0, RangeNoise::default()).with_truth(spec, 1.0, current)
    }

    /// Under a current the filters do not model (0.1 m/s east), an AUV first known at 600 s has
    /// drifted 60 m west of its estimate on average; a sure range from the east takes that off.
    #[test]
    fn the_true_error_moments_carry_the_unmodelled_currents_mean() {
        let mut t = truth_tracker(0.1, 0.0, [0.1, 0.0]);
        let (cna, auv) = (Vec3::new(300.0, 0.0, 0.0), Vec3::zeros());
        t.ping(0, 600.0, None, (&cna, &auv, 0.0));
        let e = t.true_error(0).unwrap();
        assert_eq!((e.m, e.s), ([-60.0, 0.0], [31.0 + 3600.0, 0.0, 31.0]));
        t.ping(0, 630.0, None, (&cna, &auv, 1.0));
        let e = t.true_error(0).unwrap();
        assert!(e.m[0].abs() < 1.0 && e.m[1] == 0.0 && e.s[0] < 10.0, "{e:?}");
    }

    #[test]
    fn the_true_error_moments_start_at_launch_inherit_the_cnas_offset_and_forget_it_at_a_fix() {
        let mut t = truth_tracker(2.0, 0.01, [0.0; 2]);
        let (cna, auv) = (Vec3::zeros(), Vec3::new(300.0, 0.0, 0.0));
        // First known at 600 s by a lost ping: σ₀² + q_t·t = 1 + 30 per axis, no correlation yet.
        t.set_cna_variance(4.0);
        t.ping(0, 600.0, None, (&cna, &auv, 0.0));
        assert_eq!(t.true_error(0).unwrap(), TrueError { s: [31.0, 0.0, 31.0], c: [0.0; 4], m: [0.0; 2] });
        // No ping for 30 s: the true drift only (0.05 · 30 = 1.5 m² per axis), not the filter's q.
        t.silent(0, 630.0, None);
        assert_eq!(t.true_error(0).unwrap().s, [32.5, 0.0, 32.5]);
        // A sure ping from the west with the CNA off by σ_c² = 4 m²: the filter (P̃ = 16 + 2·30 +
        // 2·30 ≫ R) moves the east error almost onto the range's: S_ee ≈ R_t + σ_c², C_ee ≈ σ_c².
        t.ping(0, 660.0, None, (&cna, &auv, 1.0));
        let e = t.true_error(0).unwrap();
        assert!((e.s[0] - 5.0).abs() < 0.2 && (e.s[2] - 34.0).abs() < 1e-9, "{e:?}");
        assert!((e.c[0] - 4.0).abs() < 0.1 && e.c[1] == 0.0 && e.c[3] == 0.0, "{e:?}");
        // The CNA's fix: its new error is independent of the old one, so C restarts; S is kept.
        t.set_cna_variance(1.0);
        let fixed = t.true_error(0).unwrap();
        assert_eq!((fixed.s, fixed.c), (e.s, [0.0; 4]));
        assert_eq!(t.cna_variance(), 1.0);
    }

    #[test]
    fn the_true_error_planner_needs_its_moments() {
        let truth = TruthSpec {
            drift_m2_s: 0.03,
            range_noise: RangeNoise { sigma_m: 1.8, per_km_m: 0.0 },
            cna_diffusion_m2_s: 0.01,
        };
        let spec = coopnav_plan::EstimatorSpec { truth: Some(truth), ..coopnav_plan::EstimatorSpec::default() };
        let est = PlannerConfig { cost: CostSpec::Estimator(spec), ..cfg() };
        let start = AuvEstimate { cov: [16.0, 0.0, 16.0], process_noise: 0.1 };
        let fleet = FnForecast { n: 2, f: |k: usize, t: f64| Some(Vec3::new(300.0 + 200.0 * k as f64, 1.5 * t, 20.0)) };
        let cna = CnaPose { pos: Vec3::new(0.0, 0.0, 0.0), heading: Heading::from_radians(0.0), pitch: 0.0 };
        let filters = Some((start, RangeNoise::default()));
        let mut with = PlannerPolicy::new(est, 2, 1.0, 1.0, None, filters).unwrap().with_truth(truth, 1.0, [0.0; 2]);
        let mut without = PlannerPolicy::new(est, 2, 1.0, 1.0, None, filters).unwrap();
        for step in 0..3 {
            assert!(matches!(with.decide(&at_step(step, cna, &fleet)), CnaCommand::GoTo(_)));
            assert!(matches!(without.decide(&at_step(step, cna, &fleet)), CnaCommand::Hold));
        }
        assert_eq!((with.stats().failures, without.stats().failures), (0, 3));
    }

    /// The closed forms against the filter's own discrete prediction of [position, current] per
    /// axis (x ← x + h·c, c ← φ·c + w, var w = q_c·h, position noise q·h; step 0.1 s), random
    /// walk (φ = 1) and Gauss–Markov (φ = exp(−h/T)); the rate against the step-to-step growth.
    #[test]
    fn an_unheard_auvs_growth_is_its_filters_discrete_prediction() {
        let (q, p_c, q_c, h) = (0.5, 0.09, 2.5e-5, 0.1);
        for correlation in [None, Some(600.0)] {
            let growth = UnheardGrowth { current_p0: p_c, current_q: q_c, current_correlation_s: correlation };
            let phi = correlation.map_or(1.0, |tc: f64| (-h / tc).exp());
            let (mut pxx, mut pxc, mut pcc) = (0.0, 0.0, p_c);
            let mut step = 0u64;
            for t_check in [300.0, 1800.0, 6000.0] {
                let mut before = pxx;
                while (step as f64) * h < t_check - 1e-9 {
                    before = pxx;
                    (pxx, pxc, pcc) =
                        (pxx + 2.0 * h * pxc + h * h * pcc + q * h, phi * (pxc + h * pcc), phi * phi * pcc + q_c * h);
                    step += 1;
                }
                let (grown, rate) = growth.at(q, t_check);
                assert!((grown - pxx).abs() < 2e-3 * pxx, "{correlation:?} t = {t_check}: {grown} against {pxx}");
                let discrete_rate = (pxx - before) / h;
                assert!(
                    (rate - discrete_rate).abs() < 2e-3 * discrete_rate,
                    "{correlation:?}: {rate} against {discrete_rate}"
                );
            }
        }
    }

    #[test]
    fn counting_reports_only_an_unheard_auv_grows_from_launch_as_its_filter_predicts() {
        let start = AuvEstimate { cov: [16.0, 0.0, 16.0], process_noise: 0.5 };
        let growth = UnheardGrowth { current_p0: 0.09, current_q: 3e-5, current_correlation_s: None };
        let mut t = CovarianceTracker::new(1, start, 30.0, RangeNoise::default()).reports_only(growth);
        let (cna, auv) = (Vec3::zeros(), Vec3::new(100.0, 0.0, 0.0));
        // Sure pings from 100 m teach the model nothing: at 600 s after launch the covariance is
        // P₀ + q·t + P_c·t² + q_c·t³/3 = 16 + 300 + 32,400 + 2,160 per axis, rate q + 2·P_c·t + q_c·t².
        for step in 0..=20 {
            t.ping(0, 30.0 * step as f64, None, (&cna, &auv, 1.0));
        }
        let e = t.estimate(0).unwrap();
        let (axis, rate) = (16.0 + 300.0 + 32_400.0 + 2_160.0, 0.5 + 108.0 + 10.8);
        assert!((e.cov[0] - axis).abs() < 1e-6 && (e.cov[2] - axis).abs() < 1e-6 && e.cov[1] == 0.0, "{e:?}");
        assert!((e.process_noise - rate).abs() < 1e-9, "{e:?}");
        // The first report restarts it at the filter's own covariance grown by q over its age, and
        // the next sure ping is not credited either: q·τ more per axis; the rate is q again.
        let report = ReportedCov { t: 620.0, cov: [40.0, 3.0, 25.0] };
        t.ping(0, 630.0, Some(report), (&cna, &auv, 1.0));
        assert_eq!(t.estimate(0).unwrap().cov, [45.0, 3.0, 30.0]);
        t.ping(0, 660.0, Some(report), (&cna, &auv, 1.0));
        assert_eq!(t.estimate(0).unwrap(), AuvEstimate { cov: [60.0, 3.0, 45.0], process_noise: 0.5 });
        // Counting expected pings instead, the same sure pings keep the never-heard AUV small.
        let mut expected = CovarianceTracker::new(1, start, 30.0, RangeNoise::default());
        for step in 0..=20 {
            expected.ping(0, 30.0 * step as f64, None, (&cna, &auv, 1.0));
        }
        let c = expected.estimate(0).unwrap().cov;
        assert!(c[0] + c[2] < 1_000.0, "{c:?}");
    }
}
