//! The one mission engine. It owns the loop only: every truth step runs the named phases of
//! `phases` in order — decide, advance, transmit, deliver, sense, observe — and reports what
//! it saw to an [`Observer`]; what a run is scored by (its error and link metrics, Hudson's
//! modelled error) are observers too (`crate::observe::metrics`). The vehicles are in `vehicles`, packets in flight and their fate
//! in `inflight`, filter consistency in [`health`]; the models it plugs in (channel truth,
//! schedule, finish behaviour) in [`crate::models`].
//!
//! Today it runs the closed-loop scenario: survey AUVs on lawnmowers with OWTT EKFs, one CNA
//! (ASC or AUV) steered by a [`crate::policy::CnaPolicy`], transponder buoys (moored or
//! drifting) whose position broadcasts the AUVs range to as well, ships on a fixed track, the
//! comms schedule of the scenario. Ships and buoys may send 13-bit mini-packets (Gill's cycles):
//! each survey AUV filters their states from the components and ranges to them (`mini`).
//! Survey AUVs may also address their statuses to each other as Nams's frame 0, with the
//! packet-success tracker, shadow estimates and rate feedback of `peer`.

mod cna_rate;
mod inflight;
mod mini;
pub mod observe;
mod peer;
mod phases;
mod vehicles;

use crate::models::channel::Clock;
use crate::models::filter::RangeSpeed;
use crate::models::peer::StatusFormat;
use crate::models::schedule::Slot;
use crate::models::surfacing::{OwnNav, Step};
use crate::policy::belief;
use crate::policy::registry::Policy;
use crate::policy::{CnaCommand, ReportedCov};
use crate::scenario::start::cna_start;
use crate::scenario::world::Scenario;
use coopnav_acomms::tl::{TlError, TransmissionLoss, TL_CEILING};
use coopnav_core::{Bathymetry, Iver2State, SeedStream, Vec3};
use coopnav_plan::predict::UnderwayPredictor;
use coopnav_plan::AuvForecast;
use inflight::InFlight;
use mini::SurfaceFilters;
pub use observe::{
    BuoyFix, BuoySample, CnaChoice, CnaFix, CnaStatusHeard, CommsEvent, DeadReckoning, Decision, FilterStart,
    LinkArrival, Observer, Phase, PhaseClock, RangeHeard, RangeUpdate, RunEnd, ShadowSample, ShipPose, ShipSample,
    StatusChoice, StatusFrames, StatusSent, Timing, Trace, TraceRow,
};
use peer::{PeerLink, Plans};
use phases::Payload;
use rand_chacha::ChaCha8Rng;
use std::cell::Cell;
use std::sync::Arc;
use std::time::Instant;
use vehicles::{stream, Buoy, Craft, Ship, SurveyAuv};

/// Links forced to lose every packet (failure studies and tests).
#[derive(Debug, Clone, Default)]
pub struct Faults {
    /// AUVs whose packets (both directions) are all lost from `silent_from_s` on.
    pub silent_auvs: Vec<usize>,
    pub silent_from_s: f64,
}

/// The CNA predictors as a forecast, hiding AUVs with fewer than the required reports (Hudson 2012, Sec. 4.2)
/// unless their mission plan stands in (`policy.before_first_report`).
pub struct FleetView<'a> {
    pub predictors: &'a [UnderwayPredictor],
    pub min_reports: usize,
}

impl AuvForecast for FleetView<'_> {
    fn n_auvs(&self) -> usize {
        self.predictors.len()
    }
    fn position(&self, k: usize, t: f64) -> Option<Vec3> {
        self.predictors.get(k)?.planning_position(t, self.min_reports)
    }
}

/// The CNA: its craft, its own navigation, its clock, and what it knows of the fleet.
#[derive(Clone)]
struct Cna {
    craft: Craft,
    /// Its broadcast position minus its truth (GPS error for an ASC, a random walk for an AUV),
    /// drawn at each decision and held over the cycle.
    nav_error: (f64, f64),
    /// What it knows of its own navigation error, and its surfacing cycle (an AUV CNA).
    own: OwnNav,
    rng_gps: ChaCha8Rng,
    rng_nav: ChaCha8Rng,
    clock: Clock,
    predictors: Vec<UnderwayPredictor>,
    /// Status slots received since its last broadcast, per AUV (its one-bit-per-AUV ack).
    acked: Vec<Vec<u64>>,
    /// The newest covariance each AUV reported (the status message's trailer).
    reported: Vec<Option<ReportedCov>>,
    /// Its broadcast's rate policy, when its slot names one.
    rate: Option<cna_rate::CnaRate>,
    /// The last decision's step of its surfacing cycle, its true position and the fix its policy
    /// saw: a command that arrives later ([`Mission::steer`]) steers relative to that fix.
    last_decision: Option<(Step, Vec3, Vec3)>,
}

/// One run's state.
struct Engine<'a> {
    sc: &'a Scenario,
    policy: &'a mut Policy,
    faults: &'a Faults,
    bathy: Bathymetry,
    slots: Vec<Slot>,
    auvs: Vec<SurveyAuv>,
    cna: Cna,
    buoys: Vec<Buoy>,
    ships: Vec<Ship>,
    /// Per survey AUV, its filters of the ships and buoys it hears mini-packets from.
    surface: Vec<SurfaceFilters>,
    /// Per survey AUV, its side of Nams's link (empty unless `comms.status_format` is Nams's).
    peers: Vec<PeerLink>,
    /// Per survey AUV, the channel draws of its statuses at the other survey AUVs.
    peer_draws: Vec<ChaCha8Rng>,
    air: InFlight<Payload>,
    /// How the survey AUVs' filters turn travel times into ranges (`filter.sound_speed`).
    range_speed: RangeSpeed,
    /// The scenario's transmission-loss model, built once for the run.
    tl: Arc<dyn TransmissionLoss>,
    /// Whether a failed transmission-loss lookup was reported (once per run: it repeats per packet).
    tl_failure_reported: Cell<bool>,
    next_decision: u64,
    /// Index of the next slot over the whole run (cycle = index / slots per cycle).
    next_slot: u64,
    status_sent: Vec<u64>,
    /// Whether every survey AUV's filter was finite at every sample.
    finite: bool,
    /// Truth steps per second (the observe phase runs once a second).
    per_second: u64,
}

/// A run its caller steps, and may fork: a copy of the whole state at a step, driven on by
/// another policy (clairvoyant rollouts measure how much any CNA path could gain,
/// `examples/closed_loop_headroom.rs`). A scored run (`observe::metrics::run`) is a `Mission`
/// stepped to its end.
pub struct Mission<'a> {
    engine: Engine<'a>,
    /// The next truth step, and the run's count.
    step: u64,
    steps: u64,
    t_start: Instant,
}

impl<'a> Mission<'a> {
    /// Runs `policy` over scenario `sc` with run seed `seed` (the set-up reported to `obs`), on
    /// the transmission-loss model `tl` when the caller built one (one model shared by an
    /// experiment's many runs, e.g. a BELLHOP grid of its own layout), else on the scenario's
    /// `comms.tl`.
    pub fn new(
        sc: &'a Scenario,
        policy: &'a mut Policy,
        seed: u64,
        faults: &'a Faults,
        tl: Option<Arc<dyn TransmissionLoss>>,
        obs: &mut dyn Observer,
    ) -> Self {
        let engine = Engine::new(sc, policy, seed, faults, tl);
        let t_start = Instant::now();
        for (auv, a) in engine.auvs.iter().enumerate() {
            let ((x, y), (speed, heading)) = (a.ekf.position(), a.ekf.speed_heading());
            obs.on_filter_start(&FilterStart { auv, x, y, speed, heading });
        }
        for (ship, s) in engine.ships.iter().enumerate() {
            obs.on_ship_pose(&ShipPose { t: 0.0, ship, pos: s.pos, heading: s.psi });
        }
        obs.on_phase_end(Phase::Setup);
        let steps = (engine.sc.duration_s / engine.sc.dt).round() as u64;
        Mission { engine, step: 0, steps, t_start }
    }

    pub fn done(&self) -> bool {
        self.step >= self.steps
    }

    /// Time at the start of the next step, s.
    pub fn t(&self) -> f64 {
        self.step as f64 * self.engine.sc.dt
    }

    /// Whether the next step opens with a CNA decision.
    pub fn decides_next(&self) -> bool {
        self.engine.decision_due((self.step + 1) as f64 * self.engine.sc.dt)
    }

    /// One truth step.
    pub fn step(&mut self, obs: &mut dyn Observer) {
        self.engine.step(self.step, obs);
        self.step += 1;
    }

    /// Steers the CNA by `command` now, as its last decision would have had the policy returned
    /// it then (relative to the fix the policy saw; a climbing AUV CNA keeps climbing): a
    /// command that reached the CNA after its decision (a live planner in free-running software
    /// in the loop). Before the first decision it does nothing. Reports the new leg as a decision
    /// at the current time.
    pub fn steer(&mut self, command: CnaCommand, obs: &mut dyn Observer) {
        let Some((step, here, fix)) = self.engine.cna.last_decision else { return };
        let t = self.t();
        let craft = &mut self.engine.cna.craft;
        craft.target = phases::target(step, command, here, fix, craft.pos, craft.target);
        obs.on_decision(&Decision { t, from: craft.pos, to: craft.target });
    }

    /// A copy of this run as it stands, driven by `policy` from here on. `redraw`: None keeps this
    /// run's own future random draws (the copy sees the same noise); Some(seed) draws every noise
    /// source afresh from run seed `seed`. The state drawn at the start (clocks, compass-bias maps,
    /// buoy motion) is kept either way.
    pub fn fork<'b>(&'b self, policy: &'b mut Policy, redraw: Option<u64>) -> Mission<'b> {
        let mut engine = self.engine.fork(policy);
        if let Some(seed) = redraw {
            engine.redraw(&SeedStream::new(seed));
        }
        Mission { engine, step: self.step, steps: self.steps, t_start: Instant::now() }
    }

    /// The policy driving this run.
    pub fn policy(&mut self) -> &mut Policy {
        self.engine.policy
    }

    /// Ends the run after the steps run: reports its end to `obs` and returns its wall time, s.
    pub fn finish(self, obs: &mut dyn Observer) -> f64 {
        let recoveries: Vec<_> = self.engine.auvs.iter().map(|a| a.ekf.recoveries()).collect();
        obs.on_end(&RunEnd { recoveries: &recoveries, finite: self.engine.finite });
        self.t_start.elapsed().as_secs_f64()
    }
}

impl<'a> Engine<'a> {
    fn new(
        sc: &'a Scenario,
        policy: &'a mut Policy,
        seed: u64,
        faults: &'a Faults,
        tl: Option<Arc<dyn TransmissionLoss>>,
    ) -> Self {
        let streams = SeedStream::new(seed);
        let n = sc.fleet.n_auvs;
        let bathy = sc.bathymetry();
        let auvs: Vec<SurveyAuv> = (0..n).map(|k| SurveyAuv::new(sc, k, &streams, &bathy)).collect();
        let start = cna_start(sc);
        let cna = Cna {
            craft: Craft { pos: start.pos, prev: start.pos, heading: start.heading.radians(), target: None },
            nav_error: (0.0, 0.0),
            own: OwnNav::new(sc.cna.navigation.diffusion_m2_s()),
            rng_gps: streams.rng(stream::CNA_GPS),
            rng_nav: streams.rng(stream::CNA_NAV),
            clock: sc.channel.clocks.draw(&mut streams.rng(stream::CNA_CLOCK)),
            predictors: (0..n).map(|k| belief::predictor(sc, k, &bathy)).collect(),
            acked: vec![Vec::new(); n],
            reported: vec![None; n],
            rate: sc
                .comms
                .schedule
                .cna_policy()
                .map(|spec| cna_rate::CnaRate::new(spec, n).expect("validated rate policy")),
            last_decision: None,
        };
        Engine {
            sc,
            policy,
            faults,
            bathy,
            slots: sc.comms.schedule.slots(sc.comms.tau, n, sc.buoys.len()),
            cna,
            buoys: (0..sc.buoys.len()).map(|i| Buoy::new(sc, i, &streams)).collect(),
            ships: (0..sc.ships.len()).map(|i| Ship::new(sc, i, &streams)).collect(),
            surface: (0..n).map(|_| SurfaceFilters::new(sc)).collect(),
            peers: peer_links(sc, &auvs),
            peer_draws: (0..n).map(|k| streams.rng(peer::STREAM_BASE + k as u64)).collect(),
            air: InFlight::new(sc.channel.collisions.capture_margin_db),
            range_speed: sc.filter.range_speed(&sc.channel.sound_speed),
            tl: tl.map_or_else(|| sc.tl_provider(), Ok).unwrap_or_else(|e| {
                // Validation builds the provider first, so this is a scenario built in code.
                tracing::error!(error = %e, "transmission loss unavailable: every packet is lost");
                Arc::new(Unavailable)
            }),
            tl_failure_reported: Cell::new(false),
            auvs,
            next_decision: 0,
            next_slot: 0,
            status_sent: vec![0; n],
            finite: true,
            per_second: ((1.0 / sc.dt).round() as u64).max(1),
        }
    }

    /// This state with `policy` in place of its own (`Mission::fork`).
    fn fork<'b>(&'b self, policy: &'b mut Policy) -> Engine<'b> {
        Engine {
            sc: self.sc,
            policy,
            faults: self.faults,
            bathy: self.bathy.clone(),
            slots: self.slots.clone(),
            auvs: self.auvs.clone(),
            cna: self.cna.clone(),
            buoys: self.buoys.clone(),
            ships: self.ships.clone(),
            surface: self.surface.clone(),
            peers: self.peers.clone(),
            peer_draws: self.peer_draws.clone(),
            air: self.air.clone(),
            range_speed: self.range_speed.clone(),
            tl: Arc::clone(&self.tl),
            tl_failure_reported: self.tl_failure_reported.clone(),
            next_decision: self.next_decision,
            next_slot: self.next_slot,
            status_sent: self.status_sent.clone(),
            finite: self.finite,
            per_second: self.per_second,
        }
    }

    /// Every noise stream from here on drawn from `streams` (`Mission::fork`).
    fn redraw(&mut self, streams: &SeedStream) {
        self.auvs.iter_mut().for_each(|a| a.redraw(streams));
        self.buoys.iter_mut().for_each(|b| b.redraw(streams));
        self.ships.iter_mut().for_each(|s| s.redraw(streams));
        let cna = &mut self.cna;
        for r in self.peer_draws.iter_mut().chain([&mut cna.rng_gps, &mut cna.rng_nav]) {
            vehicles::redraw(r, streams);
        }
    }

    /// One truth step from `step · dt`, phase by phase, each end reported.
    fn step(&mut self, step: u64, obs: &mut dyn Observer) {
        let t = step as f64 * self.sc.dt;
        let t_next = t + self.sc.dt;
        self.decide(t_next, obs);
        obs.on_phase_end(Phase::Decide);
        self.advance(t_next, obs);
        obs.on_phase_end(Phase::Advance);
        self.transmit(t, t_next, obs);
        obs.on_phase_end(Phase::Transmit);
        self.deliver(t_next, obs);
        obs.on_phase_end(Phase::Deliver);
        self.sense(step, t_next, obs);
        obs.on_phase_end(Phase::Sense);
        if (step + 1) % self.per_second == 0 {
            self.observe(t_next, obs);
        }
        obs.on_phase_end(Phase::Observe);
    }

    /// Transmission loss from `a` to `b`, dB; the ceiling (a lost packet) when the model fails,
    /// said once per run so the loss is never silent.
    fn tl_db(&self, a: &Vec3, b: &Vec3) -> f64 {
        self.tl.tl(a, b).unwrap_or_else(|e| {
            if !self.tl_failure_reported.replace(true) {
                tracing::error!(
                    error = %e,
                    from = ?[a.x, a.y, a.z],
                    to = ?[b.x, b.y, b.z],
                    "no transmission loss for a link: its packet is lost (further failures in this run are not reported)"
                );
            }
            TL_CEILING
        })
    }

    fn silent(&self, k: usize, t: f64) -> bool {
        t >= self.faults.silent_from_s && self.faults.silent_auvs.contains(&k)
    }
}

/// Every survey AUV's side of Nams's link, when the statuses are Nams's frame 0.
fn peer_links(sc: &Scenario, auvs: &[SurveyAuv]) -> Vec<PeerLink> {
    let StatusFormat::NamsFrame0 { estimator } = sc.comms.status_format else { return Vec::new() };
    let plans = Plans {
        waypoints: auvs.iter().map(|a| a.ctrl.waypoints().to_vec()).collect(),
        starts: auvs.iter().map(|a| Iver2State::at_rest(a.truth, a.ctrl.state.heading)).collect(),
        target: sc.fleet.depth,
        speed: sc.fleet.speed,
        vehicle: sc.survey_dynamics(),
    };
    (0..auvs.len())
        .map(|k| {
            let rates = vehicles::status_policy(sc, k).rates().unwrap_or_default();
            PeerLink::new(k, &rates, estimator, &plans)
        })
        .collect()
}

/// A transmission-loss model that could not be built: every packet is lost.
struct Unavailable;

impl TransmissionLoss for Unavailable {
    fn tl(&self, _: &Vec3, _: &Vec3) -> Result<f64, TlError> {
        Err(TlError::Invalid("the scenario's transmission-loss model could not be built".into()))
    }
}
