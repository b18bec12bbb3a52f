//! One closed-loop run: the survey AUVs' true kinematics (IVER2 steering on their own
//! estimates, pushed by the current), their 10 Hz OWTT EKFs on dead reckoning and on ranges from
//! the CNA's broadcasts, the acoustic link (TL + success draws per packet, the Appendix C status
//! message bit-exactly encoded and decoded), the CNA's predictors and its policy deciding every τ.
//!
//! TDMA over one period τ: the CNA broadcasts at m·τ (independent of N), then AUV j reports at
//! m·τ + (j + 1)·τ/(N + 1). Events are handled at the first truth step at or after their time.

use super::metrics::{AuvMetrics, ErrorStats, FleetMetrics, LinkStats};
use super::planner_policy::{ErrorTracker, PlannerStats};
use super::policies::{cna_start, receiver, tl_between, Policy};
use super::scenario::Scenario;
use crate::hbl::noise::{normal, CompassBias};
use crate::policy::{CnaCommand, PolicyContext};
use coopnav_acomms::node_report::{NodeReport, VehicleType};
use coopnav_acomms::selector::{AdaptiveBins, Choice, FixedRate, Outcome, RatePolicy};
use coopnav_core::{
    wrap_pi, Bathymetry, DepthTarget, Heading, Iver2, Iver2Params, Iver2State, SeedStream, Vec3, Waypoint,
};
use coopnav_nav::{AuvEkf, RangeMeasurement};
use coopnav_plan::predict::{StatusReport, UnderwayPredictor};
use coopnav_plan::{AuvForecast, CnaPose};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::time::{Duration, Instant};

/// Stream ids of one run: the CNA's GPS, and a block of ten per survey AUV.
mod stream {
    pub const CNA_GPS: u64 = 1;
    pub const CNA_NAV: u64 = 2;
    pub const AUV_BASE: u64 = 100;
    pub const INIT: u64 = 0;
    pub const SPEED: u64 = 1;
    pub const COMPASS_MAP: u64 = 2;
    pub const COMPASS_WHITE: u64 = 3;
    pub const YAW_RATE: u64 = 4;
    pub const RANGE: u64 = 5;
    pub const DOWNLINK: u64 = 6;
    pub const UPLINK: u64 = 7;
}

/// Links forced to lose every packet (failure studies and tests).
#[derive(Debug, Clone, Default)]
pub struct Faults {
    /// AUVs whose packets (both directions) are all lost from `silent_from_s` on.
    pub silent_auvs: Vec<usize>,
    pub silent_from_s: f64,
}

/// One row of the time series (every second, per AUV).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TraceRow {
    pub t: f64,
    pub auv: usize,
    pub true_x: f64,
    pub true_y: f64,
    /// True depth, m.
    pub true_z: f64,
    pub est_x: f64,
    pub est_y: f64,
    pub error: f64,
    /// Filter's horizontal 1-σ (√(P_EE + P_NN)), m.
    pub est_sd: f64,
    /// The planner's modelled error, m (empty before the model starts).
    pub modelled: Option<f64>,
    pub cna_x: f64,
    pub cna_y: f64,
    pub distance: f64,
}

/// One packet on the comms timeline.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CommsEvent {
    pub t: f64,
    /// "down" = CNA broadcast to the AUV, "up" = the AUV's status to the CNA.
    pub direction: &'static str,
    pub auv: usize,
    pub received: bool,
}

/// Wall-clock split of a run (not part of the deterministic results).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Timing {
    pub planner_s: f64,
    pub filters_s: f64,
    pub channel_s: f64,
    pub total_s: f64,
}

/// Everything one run produced.
#[derive(Debug, Clone, Serialize)]
pub struct RunResult {
    pub policy: String,
    pub seed: u64,
    pub auvs: Vec<AuvMetrics>,
    pub fleet: FleetMetrics,
    pub planner: Option<PlannerStats>,
    #[serde(skip)]
    pub trace: Option<Trace>,
    #[serde(skip)]
    pub timing: Timing,
}

/// Recorded time series.
#[derive(Debug, Clone, Default)]
pub struct Trace {
    pub rows: Vec<TraceRow>,
    pub comms: Vec<CommsEvent>,
    /// CNA true track (t, x, y) every second.
    pub cna: Vec<(f64, f64, f64)>,
}

/// The CNA predictors as a forecast, hiding AUVs with fewer than the required reports (A14).
pub struct FleetView<'a> {
    pub predictors: &'a [UnderwayPredictor],
    pub min_reports: usize,
}

impl AuvForecast for FleetView<'_> {
    fn n_auvs(&self) -> usize {
        self.predictors.len()
    }
    fn position(&self, k: usize, t: f64) -> Option<Vec3> {
        let p = self.predictors.get(k)?;
        (p.reports_received() >= self.min_reports).then(|| p.position_at(t)).flatten()
    }
}

/// A survey AUV: the controller's believed kinematic state, the truth, the filter and its noise.
struct SurveyAuv {
    ctrl: Iver2,
    truth: Vec3,
    ekf: AuvEkf,
    compass: CompassBias,
    rng_speed: ChaCha8Rng,
    rng_white: ChaCha8Rng,
    rng_yaw: ChaCha8Rng,
    rng_range: ChaCha8Rng,
    rng_down: ChaCha8Rng,
    rng_up: ChaCha8Rng,
    /// Ranges in flight: (receive time, measured travel time, transponder as broadcast).
    pending: Vec<(f64, f64, Vec3)>,
    errors: Vec<f64>,
    distances: Vec<f64>,
    violations: u64,
    modelled: Vec<f64>,
    down: LinkStats,
    up: LinkStats,
    applied: u64,
    /// Rate selection for the status messages, and what it still waits to hear about.
    selector: Box<dyn RatePolicy>,
    /// Own status slots sent since the last CNA broadcast heard.
    unacked: Vec<u64>,
    /// Last CNA position heard (from its broadcast).
    cna_heard: Option<Vec3>,
}

impl SurveyAuv {
    fn new(sc: &Scenario, k: usize, streams: &SeedStream, bathy: &Bathymetry) -> Self {
        let rng = |id: u64| streams.rng(stream::AUV_BASE + 10 * k as u64 + id);
        let lawn = sc.lawnmower(k);
        let pts = lawn.waypoints();
        let start = pts[0];
        let heading = pts.get(1).map_or(0.0, |b| (b.1 - start.1).atan2(b.0 - start.0));
        let waypoints: Vec<Waypoint> =
            pts.iter().map(|&(x, y)| Waypoint { x, y, target: sc.fleet.depth, speed: sc.fleet.speed }).collect();
        let bottom = bathy.depth_at(start.0, start.1);
        let z0 = match sc.fleet.depth {
            DepthTarget::Depth { depth } => depth,
            DepthTarget::Altitude { altitude } => bottom - altitude,
        };
        let truth = Vec3::new(start.0, start.1, z0);
        let mut r_init = rng(stream::INIT);
        let sd = sc.fleet.init_position_sd;
        let (ex, ey) = (start.0 + sd * normal(&mut r_init), start.1 + sd * normal(&mut r_init));
        let mut state = Iver2State::at_rest(Vec3::new(ex, ey, z0), Heading::from_radians(heading));
        state.altitude = bottom - z0;
        SurveyAuv {
            ctrl: Iver2::new(Iver2Params::default(), state, waypoints),
            truth,
            ekf: AuvEkf::new(0.0, ex, ey, 0.0, heading, sc.filter.clone()),
            compass: CompassBias::draw(&sc.sensors, &mut rng(stream::COMPASS_MAP)),
            rng_speed: rng(stream::SPEED),
            rng_white: rng(stream::COMPASS_WHITE),
            rng_yaw: rng(stream::YAW_RATE),
            rng_range: rng(stream::RANGE),
            rng_down: rng(stream::DOWNLINK),
            rng_up: rng(stream::UPLINK),
            pending: Vec::new(),
            errors: Vec::new(),
            distances: Vec::new(),
            violations: 0,
            modelled: Vec::new(),
            down: LinkStats::default(),
            up: LinkStats::default(),
            applied: 0,
            selector: match &sc.comms.status_adaptive {
                Some(cfg) => Box::new(AdaptiveBins::new(cfg.clone()).expect("validated adaptive config")),
                None => Box::new(FixedRate { rate: sc.comms.status_rate }),
            },
            unacked: Vec::new(),
            cna_heard: None,
        }
    }

    /// True velocity over ground: through the water along the heading, plus the current.
    fn ground_velocity(&self, current: (f64, f64)) -> (f64, f64) {
        let (c, s) = self.ctrl.state.heading.unit();
        (self.ctrl.state.speed * c + current.0, self.ctrl.state.speed * s + current.1)
    }

    /// One truth step: the controller steers from the filter's estimate; the truth moves by the
    /// same displacement plus the current. Returns the measured yaw rate.
    fn step_truth(&mut self, sc: &Scenario, bathy: &Bathymetry) -> f64 {
        let (ex, ey) = self.ekf.position();
        self.ctrl.state.pos.x = ex;
        self.ctrl.state.pos.y = ey;
        let before = self.ctrl.state.pos;
        self.ctrl.step(bathy);
        let d = self.ctrl.state.pos - before;
        self.truth.x += d.x + sc.fleet.current.0 * sc.dt;
        self.truth.y += d.y + sc.fleet.current.1 * sc.dt;
        self.truth.z = self.ctrl.state.pos.z;
        self.ctrl.state.yaw_rate + sc.sensors.yaw_rate_white_deg_s.to_radians() * normal(&mut self.rng_yaw)
    }

    /// Filter work up to `t_next`: pending ranges in time order, then speed and compass.
    fn step_filter(&mut self, sc: &Scenario, t_next: f64, yaw_rate: f64) {
        self.pending.sort_by(|a, b| a.0.total_cmp(&b.0));
        let due = self.pending.partition_point(|p| p.0 <= t_next);
        for (t_rx, travel_time, transponder) in self.pending.drain(..due) {
            self.ekf.predict_to(t_rx, yaw_rate);
            let m =
                RangeMeasurement { range: sc.filter.range_noise.sound_speed * travel_time, travel_time, transponder };
            if self.ekf.update_range(&m, Some(self.truth.z)).applied() {
                self.applied += 1;
            }
        }
        self.ekf.predict_to(t_next, yaw_rate);
        let s = &sc.sensors;
        let psi = self.ctrl.state.heading.radians();
        self.ekf.update_speed(self.ctrl.state.speed + s.speed_sd * normal(&mut self.rng_speed));
        self.ekf.update_heading(wrap_pi(
            psi + self.compass.at(psi) + s.compass_white_deg.to_radians() * normal(&mut self.rng_white),
        ));
    }

    fn error(&self) -> f64 {
        let (ex, ey) = self.ekf.position();
        (ex - self.truth.x).hypot(ey - self.truth.y)
    }

    fn healthy(&self) -> bool {
        self.ekf.state().iter().all(|v| v.is_finite()) && self.ekf.ekf().p().iter().all(|v| v.is_finite())
    }

    /// The Appendix C status message from the AUV's own estimate and its next three waypoints.
    fn status(&self, k: usize, t: f64) -> NodeReport {
        let x = self.ekf.state();
        let next = self.ctrl.next_waypoint();
        let waypoints = self.ctrl.waypoints().iter().skip(next).take(3).map(|w| (w.x, w.y)).collect();
        NodeReport {
            src_id: (k + 1) as u8,
            time_of_day: (t.rem_euclid(86_400.0)) as u32,
            vehicle: VehicleType::Auv,
            x: x[0],
            y: x[1],
            speed: x[2].clamp(-2.0, 9.0),
            heading: Heading::from_radians(x[3]),
            waypoints,
            front_seat_error: 0,
            front_mode: 0,
            leak: false,
            depth: self.truth.z.clamp(-1.0, 203.0),
            altitude: self.ctrl.state.altitude.clamp(-1.0, 203.0),
            battery: 100.0 * (1.0 - t / 86_400.0).clamp(0.0, 1.0),
        }
    }
}

/// The CNA craft: steers to its commanded point at transit speed with a turn-rate limit and holds
/// station on arrival; an AUV CNA also moves towards the commanded depth, pitch-limited.
struct Craft {
    pos: Vec3,
    heading: f64,
    target: Option<Vec3>,
}

impl Craft {
    fn step(&mut self, speed: f64, max_rate: f64, dt: f64) {
        let Some(goal) = self.target else { return };
        // Depth changes at most at the speed's vertical share at the 30° pitch limit (digest A5).
        let dz_max = speed * dt * 0.5;
        self.pos.z += (goal.z - self.pos.z).clamp(-dz_max, dz_max);
        let (dx, dy) = (goal.x - self.pos.x, goal.y - self.pos.y);
        let dist = dx.hypot(dy);
        if dist <= speed * dt {
            self.pos.x = goal.x;
            self.pos.y = goal.y;
            return;
        }
        let turn = wrap_pi(dy.atan2(dx) - self.heading).clamp(-max_rate * dt, max_rate * dt);
        self.heading = wrap_pi(self.heading + turn);
        self.pos.x += speed * dt * self.heading.cos();
        self.pos.y += speed * dt * self.heading.sin();
    }
}

/// Resolves a time of day (s) to the absolute time nearest `t_now`.
fn resolve_time(time_of_day: u32, t_now: f64) -> f64 {
    let day = 86_400.0;
    let base = (t_now / day).floor() * day + time_of_day as f64;
    [base - day, base, base + day]
        .into_iter()
        .min_by(|a, b| (a - t_now).abs().total_cmp(&(b - t_now).abs()))
        .unwrap_or(base)
}

/// Runs `policy` over scenario `sc` with run seed `seed`; `record` keeps the time series.
pub fn run(sc: &Scenario, policy: &mut Policy, seed: u64, record: bool, faults: &Faults) -> RunResult {
    let t_start = Instant::now();
    let mut timing = Timing::default();
    let streams = SeedStream::new(seed);
    let n = sc.fleet.n_auvs;
    let bathy = sc.bathymetry();
    let mut auvs: Vec<SurveyAuv> = (0..n).map(|k| SurveyAuv::new(sc, k, &streams, &bathy)).collect();
    let start = cna_start(sc);
    let mut cna = Craft { pos: start.pos, heading: start.heading.radians(), target: None };
    let mut rng_gps = streams.rng(stream::CNA_GPS);
    let mut rng_nav = streams.rng(stream::CNA_NAV);
    // An AUV CNA's own navigation error (random walk); an ASC has GPS instead.
    let mut cna_nav_error = (0.0, 0.0);
    let mut predictors: Vec<UnderwayPredictor> =
        (0..n).map(|_| UnderwayPredictor::new(sc.predictor_config())).collect();
    let cfg = sc.planner_config();
    let mut model = ErrorTracker::new(n, cfg.error, sc.comms.tau, sc.planner.sigma0, sc.planner.eps0);
    let transmits = policy.as_policy().transmits();
    let limits = cfg.limits;
    let tau = sc.comms.tau;
    let steps = (sc.duration_s / sc.dt).round() as u64;
    let per_second = ((1.0 / sc.dt).round() as u64).max(1);
    let max_rate = sc.cna.max_turn_rate_deg_s.to_radians();
    let c_true = sc.comms.sound_speed;
    let mut trace = record.then(Trace::default);
    let mut next_broadcast = 0u64;
    let mut next_status = vec![0u64; n];
    // Status slots the CNA received since its last broadcast (its one-bit-per-AUV acknowledgement).
    let mut acked: Vec<Vec<u64>> = vec![Vec::new(); n];
    let slot = |m: u64, j: usize| m as f64 * tau + (j + 1) as f64 * tau / (n + 1) as f64;
    let silent = |k: usize, t: f64| t >= faults.silent_from_s && faults.silent_auvs.contains(&k);
    let mut healthy = true;

    for step in 0..steps {
        let t = step as f64 * sc.dt;
        let t_next = t + sc.dt;
        // The CNA broadcast and the decision at m·τ.
        if (next_broadcast as f64) * tau < t_next - 1e-9 {
            let t_tx = next_broadcast as f64 * tau;
            next_broadcast += 1;
            let fix = match &sc.cna.auv {
                None => Vec3::new(
                    cna.pos.x + sc.cna.gps_sd * normal(&mut rng_gps),
                    cna.pos.y + sc.cna.gps_sd * normal(&mut rng_gps),
                    cna.pos.z,
                ),
                Some(a) => {
                    let sd = (a.nav_diffusion * if t_tx > 0.0 { tau } else { 0.0 }).sqrt();
                    cna_nav_error =
                        (cna_nav_error.0 + sd * normal(&mut rng_nav), cna_nav_error.1 + sd * normal(&mut rng_nav));
                    Vec3::new(cna.pos.x + cna_nav_error.0, cna.pos.y + cna_nav_error.1, cna.pos.z)
                }
            };
            let t0 = Instant::now();
            for (k, a) in auvs.iter_mut().enumerate() {
                if !transmits {
                    model.silent(k);
                    continue;
                }
                if let Some(p) = predictors[k]
                    .position_at(t_tx)
                    .filter(|_| predictors[k].reports_received() >= sc.planner.start_after_reports)
                {
                    model.ping(k, &fix, &p, 1.0);
                }
                let rx = sc.comms.success.draw(
                    sc.comms.cna_rate,
                    tl_between(sc, &cna.pos, &a.truth),
                    receiver(false),
                    &mut a.rng_down,
                );
                let got = rx.frame0() && !silent(k, t_tx);
                a.down.record(sc.comms.cna_rate.index(), got);
                if let Some(tr) = trace.as_mut() {
                    tr.comms.push(CommsEvent { t: t_tx, direction: "down", auv: k, received: got });
                }
                // Range noise drawn whatever the fate, so packet losses do not shift the stream.
                let noise = normal(&mut a.rng_range);
                if !got {
                    continue;
                }
                // The broadcast acknowledges the statuses the CNA got; the rest of this AUV's
                // unacknowledged ones are resolved as lost.
                let outcomes: Vec<Outcome> =
                    a.unacked.drain(..).map(|slot| Outcome { slot, success: acked[k].contains(&slot) }).collect();
                a.selector.feedback(&outcomes, true);
                a.cna_heard = Some(fix);
                // OWTT: the AUV moves during the flight; one fixed-point iteration suffices.
                let v = a.ground_velocity(sc.fleet.current);
                let at = |dt_f: f64| Vec3::new(a.truth.x + v.0 * dt_f, a.truth.y + v.1 * dt_f, a.truth.z);
                let tt0 = (at(0.0) - cna.pos).norm() / c_true;
                let tt = (at(tt0) - cna.pos).norm() / c_true;
                let sd = (sc.filter.range_noise.variance(tt) + sc.comms.extra_range_sd.powi(2)).sqrt();
                let measured = tt + sd * noise / sc.filter.range_noise.sound_speed;
                a.pending.push((t_tx + tt, measured, fix));
            }
            acked.iter_mut().for_each(Vec::clear);
            timing.channel_s += t0.elapsed().as_secs_f64();
            for (k, a) in auvs.iter_mut().enumerate() {
                if let Some(e) = model.total(k) {
                    a.modelled.push(e);
                }
            }
            let t0 = Instant::now();
            let fleet = FleetView { predictors: &predictors, min_reports: sc.planner.start_after_reports };
            let pose = CnaPose { pos: fix, heading: Heading::from_radians(cna.heading), pitch: 0.0 };
            let ctx = PolicyContext { t: t_tx, tau, cna: pose, speed: sc.cna.speed, fleet: &fleet };
            cna.target = match policy.as_policy().decide(&ctx) {
                // The command is relative to the GPS fix the policy saw.
                CnaCommand::GoTo(p) => Some(Vec3::new(cna.pos.x + p.x - fix.x, cna.pos.y + p.y - fix.y, p.z)),
                CnaCommand::Hold => None,
            };
            timing.planner_s += t0.elapsed().as_secs_f64();
        }
        // Status slots.
        let t0 = Instant::now();
        for (j, a) in auvs.iter_mut().enumerate() {
            let t_tx = slot(next_status[j], j);
            if t_tx >= t_next - 1e-9 {
                continue;
            }
            let slot_id = next_status[j];
            next_status[j] += 1;
            let (ex, ey) = a.ekf.position();
            let distance = a.cna_heard.map(|c| (c.x - ex).hypot(c.y - ey));
            let Choice::Transmit(rate) = a.selector.choose(slot_id, distance) else { continue };
            // Through the wire format: what the CNA gets is the decoded message.
            let bytes = match a.status(j, t_tx).encode() {
                Ok(b) => b,
                Err(e) => {
                    tracing::warn!(t = t_tx, auv = j, error = %e, "status message cannot be encoded; not sent");
                    continue;
                }
            };
            a.unacked.push(slot_id);
            let rx = sc.comms.success.draw(rate, tl_between(sc, &a.truth, &cna.pos), receiver(true), &mut a.rng_up);
            let decoded = (rx.frame0() && !silent(j, t_tx)).then(|| NodeReport::decode(&bytes)).and_then(Result::ok);
            a.up.record(rate.index(), decoded.is_some());
            if let Some(tr) = trace.as_mut() {
                tr.comms.push(CommsEvent { t: t_tx, direction: "up", auv: j, received: decoded.is_some() });
            }
            if let Some(m) = decoded {
                acked[j].push(slot_id);
                predictors[j].receive(StatusReport {
                    t: resolve_time(m.time_of_day, t_tx),
                    pos: Vec3::new(m.x, m.y, m.depth),
                    speed: m.speed,
                    heading: m.heading,
                    waypoints: m.waypoints,
                });
            }
        }
        timing.channel_s += t0.elapsed().as_secs_f64();

        cna.step(sc.cna.speed, max_rate, sc.dt);
        let mut filter_time = Duration::ZERO;
        for a in auvs.iter_mut() {
            let yaw = a.step_truth(sc, &bathy);
            let t0 = Instant::now();
            a.step_filter(sc, t_next, yaw);
            filter_time += t0.elapsed();
        }
        timing.filters_s += filter_time.as_secs_f64();

        if (step + 1) % per_second == 0 {
            for (k, a) in auvs.iter_mut().enumerate() {
                healthy &= a.healthy();
                let e = a.error();
                let d = (a.truth.x - cna.pos.x).hypot(a.truth.y - cna.pos.y);
                a.errors.push(e);
                a.distances.push(d);
                a.violations += u64::from(d < limits.min || d > limits.max);
                if let Some(tr) = trace.as_mut() {
                    let (ex, ey) = a.ekf.position();
                    let p = a.ekf.ekf().p();
                    tr.rows.push(TraceRow {
                        t: t_next,
                        auv: k,
                        true_x: a.truth.x,
                        true_y: a.truth.y,
                        true_z: a.truth.z,
                        est_x: ex,
                        est_y: ey,
                        error: e,
                        est_sd: (p[(0, 0)] + p[(1, 1)]).max(0.0).sqrt(),
                        modelled: model.total(k),
                        cna_x: cna.pos.x,
                        cna_y: cna.pos.y,
                        distance: d,
                    });
                }
            }
            if let Some(tr) = trace.as_mut() {
                tr.cna.push((t_next, cna.pos.x, cna.pos.y));
            }
        }
    }

    let auv_metrics: Vec<AuvMetrics> = auvs.iter().enumerate().map(|(k, a)| metrics(k, a)).collect();
    let pooled: Vec<f64> = auvs.iter().flat_map(|a| a.errors.iter().copied()).collect();
    let modelled: Vec<f64> = auvs.iter().flat_map(|a| a.modelled.iter().copied()).collect();
    timing.total_s = t_start.elapsed().as_secs_f64();
    RunResult {
        policy: policy.as_policy().name().to_string(),
        seed,
        auvs: auv_metrics,
        fleet: FleetMetrics { error: ErrorStats::of(&pooled), modelled_mean: mean(&modelled), healthy },
        planner: policy.planner_stats(),
        trace,
        timing,
    }
}

fn mean(v: &[f64]) -> Option<f64> {
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

fn metrics(k: usize, a: &SurveyAuv) -> AuvMetrics {
    let n = a.distances.len().max(1) as f64;
    AuvMetrics {
        name: format!("auv{k}"),
        error: ErrorStats::of(&a.errors),
        modelled_mean: mean(&a.modelled),
        downlink: a.down,
        ranges_applied: a.applied,
        uplink: a.up,
        distance_mean: a.distances.iter().sum::<f64>() / n,
        distance_min: a.distances.iter().copied().fold(f64::INFINITY, f64::min),
        distance_max: a.distances.iter().copied().fold(0.0, f64::max),
        limit_violation: a.violations as f64 / n,
    }
}
