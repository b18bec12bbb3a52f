//! What every run is scored by, as observers of the engine: [`Score`] sums each survey AUV's
//! true error, its CNA distance and limit violations, its links, its ranges applied and its
//! filter's health into the run's [`AuvMetrics`] and [`FleetMetrics`], and tracks Hudson's
//! modelled error (the planner's eq. 1 model, Hudson 2012 §3, fed with the CNA's fix and its
//! forecast of each AUV at every decision, whatever the policy). [`run`] is the engine's
//! [`Mission`] stepped to its end with a [`Score`] beside the caller's observer; [`ScoredMission`]
//! is the same run stepped (and forked) by its caller.

use crate::engine::{
    BuoyFix, BuoySample, CnaChoice, CnaFix, CnaStatusHeard, CommsEvent, DeadReckoning, Decision, Faults, FilterStart,
    LinkArrival, Mission, Observer, Phase, RangeHeard, RangeUpdate, RunEnd, ShadowSample, ShipPose, ShipSample,
    StatusChoice, StatusFrames, StatusSent, Trace, TraceRow,
};
use crate::models::health::{self, Health};
use crate::models::metrics::{AuvMetrics, ErrorStats, FleetMetrics, LinkStats};
use crate::models::schedule::Owner;
use crate::policy::planner::{ErrorTracker, PlannerStats};
use crate::policy::registry::Policy;
use crate::policy::CnaCommand;
use crate::scenario::world::Scenario;
use coopnav_acomms::tl::TransmissionLoss;
use coopnav_core::Vec3;
use coopnav_nav::UpdateOutcome;
use coopnav_plan::DistanceLimits;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Everything one run produced (read back by the sweeps, which store each run's results).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RunResult {
    pub policy: String,
    pub seed: u64,
    pub auvs: Vec<AuvMetrics>,
    pub fleet: FleetMetrics,
    pub planner: Option<PlannerStats>,
    /// The recorded time series ([`run_traced`] only).
    #[serde(skip)]
    pub trace: Option<Trace>,
    /// Wall time of the whole run, s (not part of the deterministic results; a
    /// [`crate::engine::PhaseClock`] observer splits it by phase).
    #[serde(skip)]
    pub wall_s: f64,
}

/// Runs `policy` over scenario `sc` with run seed `seed`, reporting to `obs`, scored.
pub fn run(sc: &Scenario, policy: &mut Policy, seed: u64, faults: &Faults, obs: &mut dyn Observer) -> RunResult {
    run_on(sc, policy, seed, faults, None, obs)
}

/// [`run`] on a transmission-loss model the caller built (one model shared by an experiment's many
/// runs, e.g. a BELLHOP grid of its own layout) instead of the scenario's `comms.tl`.
pub fn run_with_tl(
    sc: &Scenario,
    policy: &mut Policy,
    seed: u64,
    tl: Arc<dyn TransmissionLoss>,
    obs: &mut dyn Observer,
) -> RunResult {
    run_on(sc, policy, seed, &Faults::default(), Some(tl), obs)
}

/// [`run`] keeping the whole time series in the result.
pub fn run_traced(sc: &Scenario, policy: &mut Policy, seed: u64, faults: &Faults) -> RunResult {
    let mut trace = Trace::default();
    let mut r = run(sc, policy, seed, faults, &mut trace);
    r.trace = Some(trace);
    r
}

fn run_on(
    sc: &Scenario,
    policy: &mut Policy,
    seed: u64,
    faults: &Faults,
    tl: Option<Arc<dyn TransmissionLoss>>,
    obs: &mut dyn Observer,
) -> RunResult {
    let mut score = Score::new(sc);
    let mut scored = Scored { score: &mut score, inner: obs };
    let mut mission = Mission::new(sc, policy, seed, faults, tl, &mut scored);
    while !mission.done() {
        if scored.stop() {
            break;
        }
        mission.step(&mut scored);
    }
    let wall_s = mission.finish(&mut scored);
    score.result(policy, seed, wall_s)
}

/// A run its caller steps, and may fork (the engine's [`Mission`] with its [`Score`]).
pub struct ScoredMission<'a> {
    mission: Mission<'a>,
    score: Score,
    seed: u64,
}

impl<'a> ScoredMission<'a> {
    /// Runs `policy` over scenario `sc` with run seed `seed` (the set-up reported to `obs`).
    pub fn new(
        sc: &'a Scenario,
        policy: &'a mut Policy,
        seed: u64,
        faults: &'a Faults,
        obs: &mut dyn Observer,
    ) -> Self {
        let mut score = Score::new(sc);
        let mission = Mission::new(sc, policy, seed, faults, None, &mut Scored { score: &mut score, inner: obs });
        ScoredMission { mission, score, seed }
    }

    pub fn done(&self) -> bool {
        self.mission.done()
    }

    /// Time at the start of the next step, s.
    pub fn t(&self) -> f64 {
        self.mission.t()
    }

    /// Whether the next step opens with a CNA decision.
    pub fn decides_next(&self) -> bool {
        self.mission.decides_next()
    }

    /// One truth step.
    pub fn step(&mut self, obs: &mut dyn Observer) {
        self.mission.step(&mut Scored { score: &mut self.score, inner: obs });
    }

    /// Steers the CNA by a command that arrived after its decision (see [`Mission::steer`]).
    pub fn steer(&mut self, command: CnaCommand, obs: &mut dyn Observer) {
        self.mission.steer(command, &mut Scored { score: &mut self.score, inner: obs });
    }

    /// A copy of this run and its score as they stand, driven by `policy` from here on (see
    /// [`Mission::fork`]).
    pub fn fork<'b>(&'b self, policy: &'b mut Policy, redraw: Option<u64>) -> ScoredMission<'b> {
        ScoredMission { mission: self.mission.fork(policy, redraw), score: self.score.clone(), seed: self.seed }
    }

    /// The metrics of the steps run.
    pub fn finish(mut self) -> RunResult {
        let (name, planner) = {
            let policy = self.mission.policy();
            (policy.as_policy().name().to_string(), policy.planner_stats())
        };
        let wall_s = self.mission.finish(&mut self.score);
        let (auvs, fleet) = self.score.metrics();
        RunResult { policy: name, seed: self.seed, auvs, fleet, planner, trace: None, wall_s }
    }
}

/// Per-AUV sums for the run's metrics.
#[derive(Clone, Default)]
struct AuvTally {
    errors: Vec<f64>,
    distances: Vec<f64>,
    violations: u64,
    modelled: Vec<f64>,
    down: LinkStats,
    buoys: LinkStats,
    up: LinkStats,
    applied: u64,
    health: health::Tally,
}

/// The run's metrics and Hudson's modelled error, summed from what the engine reports.
#[derive(Clone)]
pub struct Score {
    limits: DistanceLimits,
    health: Health,
    model: ErrorTracker,
    tallies: Vec<AuvTally>,
    finite: bool,
}

impl Score {
    pub fn new(sc: &Scenario) -> Self {
        let n = sc.fleet.n_auvs;
        // Hudson's modelled error and distance limits as `[policy.planner]` sets them, whichever
        // policy flies.
        let hudson = &sc.policy.planner;
        let cost = hudson.hudson_cost();
        Score {
            limits: hudson.limits,
            health: sc.health.clone(),
            model: ErrorTracker::new(n, cost.error_model(), sc.comms.tau, cost.sigma0, cost.eps0),
            tallies: vec![AuvTally::default(); n],
            finite: true,
        }
    }

    /// Hudson's modelled error of AUV `k` now, m (None before its model starts).
    pub fn modelled(&self, k: usize) -> Option<f64> {
        self.model.total(k)
    }

    /// Every AUV's metrics and the fleet's.
    pub fn metrics(&self) -> (Vec<AuvMetrics>, FleetMetrics) {
        let auvs: Vec<AuvMetrics> = self.tallies.iter().enumerate().map(|(k, a)| metrics(k, a)).collect();
        let pooled: Vec<f64> = self.tallies.iter().flat_map(|a| a.errors.iter().copied()).collect();
        let modelled: Vec<f64> = self.tallies.iter().flat_map(|a| a.modelled.iter().copied()).collect();
        let diverged = auvs.iter().filter(|a| a.health.diverged_at_s.is_some()).count();
        let fleet = FleetMetrics {
            error: ErrorStats::of(&pooled),
            modelled_mean: mean(&modelled),
            healthy: self.finite,
            diverged,
        };
        (auvs, fleet)
    }

    fn result(&self, policy: &mut Policy, seed: u64, wall_s: f64) -> RunResult {
        let (auvs, fleet) = self.metrics();
        let name = policy.as_policy().name().to_string();
        RunResult { policy: name, seed, auvs, fleet, planner: policy.planner_stats(), trace: None, wall_s }
    }
}

impl Observer for Score {
    fn on_cna_fix(&mut self, fix: &CnaFix) {
        for k in 0..self.tallies.len() {
            if !fix.transmits {
                self.model.silent(k);
            } else if let Some(Some(p)) = fix.forecast.get(k) {
                self.model.ping(k, &fix.fix, p, 1.0);
            }
        }
        for (k, tally) in self.tallies.iter_mut().enumerate() {
            if let Some(e) = self.model.total(k) {
                tally.modelled.push(e);
            }
        }
    }

    fn on_sample(&mut self, t: f64, _cna: Vec3, rows: &[TraceRow]) {
        let limits = self.limits;
        for r in rows {
            let tally = &mut self.tallies[r.auv];
            tally.errors.push(r.error);
            tally.distances.push(r.distance);
            tally.violations += u64::from(r.distance < limits.min || r.distance > limits.max);
            tally.health.sample(&self.health, t, r.error, r.est_sd, r.nees);
        }
    }

    fn on_range_update(&mut self, update: &RangeUpdate) {
        let tally = &mut self.tallies[update.auv];
        match update.outcome {
            UpdateOutcome::Applied { nis } => {
                tally.applied += 1;
                tally.health.nis(nis);
            }
            UpdateOutcome::Gated { nis } => tally.health.nis(nis),
            UpdateOutcome::Unusable => {}
        }
    }

    /// A broadcast from the CNA and a status to it count the packets lost in the air as well;
    /// a buoy's position, a ship's or buoy's mini-packet count only sent and received.
    fn on_link(&mut self, a: &LinkArrival) {
        let tally = &mut self.tallies[a.auv];
        match a.from {
            Owner::Cna => tally.down.record_arrival(a.rate, (a.decoded, a.survived), a.received),
            Owner::Auv(_) => tally.up.record_arrival(a.rate, (a.decoded, a.survived), a.received),
            Owner::Ship(..) => tally.down.record(a.rate, a.received),
            Owner::Buoy(_) => tally.buoys.record(a.rate, a.received),
        }
    }

    fn on_end(&mut self, end: &RunEnd) {
        for (tally, recoveries) in self.tallies.iter_mut().zip(end.recoveries) {
            tally.health.recovered(*recoveries);
        }
        self.finite = end.finite;
    }
}

/// The caller's observer behind a [`Score`]: every event goes to the score first, and every
/// sample's rows reach the caller with Hudson's modelled error filled in.
struct Scored<'o> {
    score: &'o mut Score,
    inner: &'o mut dyn Observer,
}

impl Observer for Scored<'_> {
    fn on_decision(&mut self, d: &Decision) {
        self.inner.on_decision(d);
    }
    fn on_sample(&mut self, t: f64, cna: Vec3, rows: &[TraceRow]) {
        self.score.on_sample(t, cna, rows);
        let rows: Vec<TraceRow> =
            rows.iter().map(|r| TraceRow { modelled: self.score.modelled(r.auv), ..*r }).collect();
        self.inner.on_sample(t, cna, &rows);
    }
    fn on_ships(&mut self, t: f64, ships: &[Vec3]) {
        self.inner.on_ships(t, ships);
    }
    fn on_buoys(&mut self, t: f64, buoys: &[BuoySample]) {
        self.inner.on_buoys(t, buoys);
    }
    fn on_ship_samples(&mut self, t: f64, ships: &[ShipSample]) {
        self.inner.on_ship_samples(t, ships);
    }
    fn on_filter_start(&mut self, start: &FilterStart) {
        self.inner.on_filter_start(start);
    }
    fn on_dead_reckoning(&mut self, dr: &DeadReckoning) {
        self.inner.on_dead_reckoning(dr);
    }
    fn on_ship_pose(&mut self, pose: &ShipPose) {
        self.inner.on_ship_pose(pose);
    }
    fn on_buoy_fix(&mut self, fix: &BuoyFix) {
        self.inner.on_buoy_fix(fix);
    }
    fn on_range(&mut self, range: &RangeHeard) {
        self.inner.on_range(range);
    }
    fn on_status_choice(&mut self, choice: &StatusChoice) {
        self.inner.on_status_choice(choice);
    }
    fn on_cna_choice(&mut self, choice: &CnaChoice) {
        self.inner.on_cna_choice(choice);
    }
    fn on_status_sent(&mut self, sent: &StatusSent) {
        self.inner.on_status_sent(sent);
    }
    fn on_status_frames(&mut self, frames: &StatusFrames) {
        self.inner.on_status_frames(frames);
    }
    fn on_shadow(&mut self, sample: &ShadowSample) {
        self.inner.on_shadow(sample);
    }
    fn on_cna_status(&mut self, status: &CnaStatusHeard) {
        self.inner.on_cna_status(status);
    }
    fn on_packet(&mut self, event: &CommsEvent) {
        self.inner.on_packet(event);
    }
    fn on_cna_fix(&mut self, fix: &CnaFix) {
        self.score.on_cna_fix(fix);
        self.inner.on_cna_fix(fix);
    }
    fn on_range_update(&mut self, update: &RangeUpdate) {
        self.score.on_range_update(update);
        self.inner.on_range_update(update);
    }
    fn on_link(&mut self, arrival: &LinkArrival) {
        self.score.on_link(arrival);
        self.inner.on_link(arrival);
    }
    fn on_end(&mut self, end: &RunEnd) {
        self.score.on_end(end);
        self.inner.on_end(end);
    }
    fn on_phase_end(&mut self, phase: Phase) {
        self.inner.on_phase_end(phase);
    }
    fn stop(&self) -> bool {
        self.inner.stop()
    }
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn metrics(k: usize, a: &AuvTally) -> AuvMetrics {
    let n = a.distances.len().max(1) as f64;
    AuvMetrics {
        name: format!("auv{k}"),
        error: ErrorStats::of(&a.errors),
        modelled_mean: mean(&a.modelled),
        downlink: a.down,
        buoy_link: a.buoys,
        ranges_applied: a.applied,
        uplink: a.up,
        distance_mean: a.distances.iter().sum::<f64>() / n,
        distance_min: a.distances.iter().copied().fold(f64::INFINITY, f64::min),
        distance_max: a.distances.iter().copied().fold(0.0, f64::max),
        limit_violation: a.violations as f64 / n,
        health: a.health.summary(),
    }
}
