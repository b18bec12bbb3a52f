//! The CNA's planner on LCM messages: the policy a scenario names (the underway planner by
//! default), built by coopnav-sim's registry from the scenario exactly as `coopnav simulate`
//! builds it, fed what the CNA itself knows, and asked for its next leg every τ. No socket here:
//! [`CnaPlanner::handle`] takes a channel and payload and returns the messages to publish;
//! [`crate::run::run_cna`] does the I/O.
//!
//! # Channels
//! | channel                | type                     | direction |
//! |------------------------|--------------------------|-----------|
//! | `COOPNAV_CNA_FIX`      | `coopnav.cna_fix_t`      | in: the CNA's own fix (GPS on a surface craft, its navigation on an AUV) and its variance |
//! | `COOPNAV_CNA_STATUS`   | `coopnav.status_frame_t` | in: a survey AUV's status its modem received (`src` = the AUV's fleet index) |
//! | `COOPNAV_CLOCK`        | `coopnav.clock_t`        | in, with the bus clock only: the world's time |
//! | `COOPNAV_CNA_COMMAND`  | `coopnav.cna_command_t`  | out: the next leg, every τ |
//! | `COOPNAV_CNA_DECISION` | `coopnav.decision_t`     | out: the decision's record, after its command |
//!
//! # Time
//! Mission time is seconds since the epoch `epoch_utime` (microseconds on the synchronous clock
//! the AUVs' OWTT ranges use; 0 by default). Decision m is at t = m·τ (`comms.tau`), as in the
//! engine; it is taken once the clock — the system clock, or the world's `clock_t` — reaches
//! it. When several fall due at once (a stalled process, a jump of the clock), only the newest
//! is taken and the others are counted as `missed_decisions`.
//!
//! # What each message does
//! - `cna_fix_t`: kept as the CNA's pose for the next decision (position, heading, variance);
//!   no decision is taken before the first one (counted in `no_fix`).
//! - `status_frame_t`: the bytes of a node report with its covariance trailer (the status codec
//!   of coopnav-acomms). Its transmit time is the start of the sending AUV's latest status slot
//!   before its receive time, from the scenario's schedule; the CNA's predictor of that AUV and
//!   its newest reported covariance take it (`coopnav_sim::policy::belief`, the engine's own
//!   reading). The rate feedback and acknowledgements a status carries are the modem's business
//!   and are not read here.
//! - A decision: the policy's `decide` with the same context the engine builds — time, τ, the
//!   fix as the CNA's pose, the scenario's transit speed, the predictors (with
//!   `policy.start_after_reports`), the reported covariances and the fix's variance — then
//!   the command and the record.
//!
//! # Faults
//! A payload that does not decode as its channel's type, a fix that is not finite or has a
//! negative variance, and a status whose bytes do not decode are counted as `malformed`; a
//! status from an AUV outside the fleet as `wrong_source`, one received before the sending
//! AUV's first slot as `unscheduled`, the same status (source, receive time, bytes) twice as a
//! `duplicate`; a status older than the newest one applied from its AUV (reordered or delayed on
//! the bus) as `stale_status`; a clock older than the newest one as `stale_clock`. Each is dropped and logged
//! with `tracing`; none stops the planner.

use crate::auv::LiveError;
use coopnav_core::{Heading, Vec3};
use coopnav_lcm::messages::{Clock, CnaCommand as CommandMsg, CnaFix, Decision, Message, StatusFrame};
use coopnav_lcm::Schema;
use coopnav_plan::predict::UnderwayPredictor;
use coopnav_plan::CnaPose;
use coopnav_sim::engine::FleetView;
use coopnav_sim::models::peer::StatusFormat;
use coopnav_sim::models::schedule::Owner;
use coopnav_sim::policy::{belief, CnaCommand, CnaPolicy, Policy, PolicyContext, PolicySpec, ReportedCov};
use coopnav_sim::scenario::Scenario;
use serde::Serialize;
use std::collections::{BTreeMap, HashSet, VecDeque};
use std::time::Instant;

/// The live CNA's channel names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CnaChannels {
    pub fix: String,
    pub status: String,
    pub clock: String,
    pub command: String,
    pub decision: String,
}

impl Default for CnaChannels {
    fn default() -> Self {
        CnaChannels {
            fix: "COOPNAV_CNA_FIX".into(),
            status: "COOPNAV_CNA_STATUS".into(),
            clock: "COOPNAV_CLOCK".into(),
            command: "COOPNAV_CNA_COMMAND".into(),
            decision: "COOPNAV_CNA_DECISION".into(),
        }
    }
}

/// What happened to every message and decision: nothing is dropped without being counted.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct CnaCounts {
    /// Messages received per channel (every one, before any check).
    pub messages: BTreeMap<String, u64>,
    pub fixes: u64,
    pub statuses_applied: u64,
    pub malformed: u64,
    pub duplicates: u64,
    pub wrong_source: u64,
    pub unscheduled: u64,
    /// Statuses older than the newest one applied from the same AUV (reordered or delayed).
    pub stale_status: u64,
    pub stale_clock: u64,
    pub other_channel: u64,
    pub decisions: u64,
    /// Decisions due before any fix had arrived: none taken.
    pub no_fix: u64,
    /// Decisions that fell due together with a newer one and were not taken.
    pub missed_decisions: u64,
    /// The slowest decision, s of wall time.
    pub max_decision_s: f64,
}

/// One message to publish.
#[derive(Debug, Clone, PartialEq)]
pub struct Outgoing {
    pub channel: String,
    pub payload: Vec<u8>,
}

/// Statuses remembered for the duplicate check.
const DUPLICATE_MEMORY: usize = 4096;

/// The live CNA: its policy and what it knows; see the module doc.
pub struct CnaPlanner {
    schema: Schema,
    channels: CnaChannels,
    policy: Policy,
    tau: f64,
    speed: f64,
    min_reports: usize,
    epoch_utime: i64,
    /// Per survey AUV, the offsets in the cycle (s) of its status slots.
    status_slots: Vec<Vec<f64>>,
    predictors: Vec<UnderwayPredictor>,
    reported: Vec<Option<ReportedCov>>,
    fix: Option<CnaFix>,
    /// The next decision's index, and the newest clock seen.
    next: u64,
    clock_utime: Option<i64>,
    stopped: bool,
    seen: HashSet<(i16, u64, Vec<u8>)>,
    seen_order: VecDeque<(i16, u64, Vec<u8>)>,
    counts: CnaCounts,
}

impl CnaPlanner {
    /// The planner of policy `policy` (a registry name) for scenario `sc`, mission time counted
    /// from `epoch_utime`.
    pub fn new(sc: &Scenario, policy: &str, epoch_utime: i64) -> Result<Self, LiveError> {
        if let StatusFormat::NamsFrame0 { .. } = sc.comms.status_format {
            return Err(LiveError::Unsupported {
                what: "comms.status_format = nams_frame0 (the live CNA reads node reports only)".into(),
            });
        }
        let policy = PolicySpec::new(policy, sc)?.build(sc)?;
        let n = sc.fleet.n_auvs;
        let mut status_slots = vec![Vec::new(); n];
        for slot in sc.comms.schedule.slots(sc.comms.tau, n, sc.buoys.len()) {
            if let Owner::Auv(j) = slot.owner {
                status_slots[j].push(slot.start_s);
            }
        }
        let bathy = sc.bathymetry();
        Ok(CnaPlanner {
            schema: Schema::coopnav(),
            channels: CnaChannels::default(),
            policy,
            tau: sc.comms.tau,
            speed: sc.cna.speed,
            min_reports: sc.policy.start_after_reports,
            epoch_utime,
            status_slots,
            predictors: (0..n).map(|k| belief::predictor(sc, k, &bathy)).collect(),
            reported: vec![None; n],
            fix: None,
            next: 0,
            clock_utime: None,
            stopped: false,
            seen: HashSet::new(),
            seen_order: VecDeque::new(),
            counts: CnaCounts::default(),
        })
    }

    pub fn channels(&self) -> &CnaChannels {
        &self.channels
    }

    pub fn counts(&self) -> &CnaCounts {
        &self.counts
    }

    /// The policy's registry name.
    pub fn policy_name(&self) -> &'static str {
        // `as_policy` needs `&mut`; the name does not change with the state.
        match &self.policy {
            Policy::Planner(p) => p.name(),
            Policy::Baseline(b) => b.name(),
        }
    }

    /// Whether a bus clock said the world stopped (`clock_t.running` false).
    pub fn clock_stopped(&self) -> bool {
        self.stopped
    }

    /// The time (µs on the synchronous clock) decision `m` falls due.
    pub fn due_utime(&self, m: u64) -> i64 {
        self.epoch_utime + (m as f64 * self.tau * 1e6).round() as i64
    }

    /// The next decision's index.
    pub fn next_decision(&self) -> u64 {
        self.next
    }

    /// One received message; returns what to publish (decisions only come from a clock).
    pub fn handle(&mut self, channel: &str, payload: &[u8]) -> Result<Vec<Outgoing>, LiveError> {
        *self.counts.messages.entry(channel.to_string()).or_default() += 1;
        if channel == self.channels.fix {
            self.on_fix(payload);
            Ok(Vec::new())
        } else if channel == self.channels.status {
            self.on_status(payload);
            Ok(Vec::new())
        } else if channel == self.channels.clock {
            match Clock::decode(&self.schema, payload) {
                Ok(c) if !c.running => {
                    self.stopped = true;
                    Ok(Vec::new())
                }
                Ok(c) => self.tick(c.utime),
                Err(e) => {
                    self.malformed(channel, &e.to_string());
                    Ok(Vec::new())
                }
            }
        } else {
            self.counts.other_channel += 1;
            Ok(Vec::new())
        }
    }

    /// The clock reads `utime`: takes the newest decision due by then, if any.
    pub fn tick(&mut self, utime: i64) -> Result<Vec<Outgoing>, LiveError> {
        if self.clock_utime.is_some_and(|c| utime < c) {
            self.counts.stale_clock += 1;
            tracing::warn!(utime, "a clock older than the newest one: dropped");
            return Ok(Vec::new());
        }
        if self.due_utime(self.next) > utime {
            self.clock_utime = Some(utime);
            return Ok(Vec::new());
        }
        // The newest decision due: the largest m with due(m) <= utime.
        let mut m = self.next;
        let step = ((utime - self.due_utime(m)) as f64 / (self.tau * 1e6)).floor().max(0.0) as u64;
        m += step;
        while self.due_utime(m + 1) <= utime {
            m += 1;
        }
        while m > self.next && self.due_utime(m) > utime {
            m -= 1;
        }
        // Decisions due before the first clock was seen are not missed: the process was not up.
        if self.clock_utime.is_some() {
            self.counts.missed_decisions += m - self.next;
        }
        self.next = m + 1;
        self.clock_utime = Some(utime);
        self.decide(m)
    }

    fn malformed(&mut self, channel: &str, why: &str) {
        self.counts.malformed += 1;
        tracing::warn!(channel, why, "malformed message dropped");
    }

    fn on_fix(&mut self, payload: &[u8]) {
        let channel = self.channels.fix.clone();
        match CnaFix::decode(&self.schema, payload) {
            Ok(f) if [f.x, f.y, f.depth, f.heading, f.variance].iter().all(|v| v.is_finite()) && f.variance >= 0.0 => {
                self.counts.fixes += 1;
                self.fix = Some(f);
            }
            Ok(_) => self.malformed(&channel, "a fix not finite or with a negative variance"),
            Err(e) => self.malformed(&channel, &e.to_string()),
        }
    }

    fn on_status(&mut self, payload: &[u8]) {
        let channel = self.channels.status.clone();
        let frame = match StatusFrame::decode(&self.schema, payload) {
            Ok(f) => f,
            Err(e) => return self.malformed(&channel, &e.to_string()),
        };
        let Some(j) = usize::try_from(frame.src).ok().filter(|&j| j < self.predictors.len()) else {
            self.counts.wrong_source += 1;
            tracing::warn!(src = frame.src, "a status from outside the fleet: dropped");
            return;
        };
        let key = (frame.src, frame.receive_time.to_bits(), frame.data.clone());
        if self.seen.contains(&key) {
            self.counts.duplicates += 1;
            return;
        }
        let t_rx = frame.receive_time - self.epoch_utime as f64 / 1e6;
        let Some(t_tx) = self.sent_at(j, t_rx) else {
            self.counts.unscheduled += 1;
            tracing::warn!(auv = j, t_rx, "a status received before the AUV's first slot: dropped");
            return;
        };
        let Some((report, cov)) = belief::read_node_status(&frame.data, t_tx) else {
            return self.malformed(&channel, "the status bytes do not decode as a node report");
        };
        if self.predictors[j].history().last().is_some_and(|newest| report.t < newest.t) {
            // Applied, its covariance would replace the newer report's.
            self.counts.stale_status += 1;
            tracing::warn!(auv = j, t = report.t, "a status older than the AUV's newest one: dropped");
            return;
        }
        self.remember(key);
        self.reported[j] = Some(cov);
        self.predictors[j].receive(report);
        self.counts.statuses_applied += 1;
    }

    fn remember(&mut self, key: (i16, u64, Vec<u8>)) {
        if self.seen_order.len() >= DUPLICATE_MEMORY {
            if let Some(old) = self.seen_order.pop_front() {
                self.seen.remove(&old);
            }
        }
        self.seen.insert(key.clone());
        self.seen_order.push_back(key);
    }

    /// The start of AUV `j`'s latest status slot at or before `t_rx` (mission s), computed as the
    /// engine computes a slot's time (cycle · τ + offset).
    fn sent_at(&self, j: usize, t_rx: f64) -> Option<f64> {
        let tau = self.tau;
        self.status_slots[j]
            .iter()
            .filter_map(|&start| {
                let mut cycle = ((t_rx - start) / tau).floor();
                if cycle < 0.0 {
                    return None;
                }
                let at = |c: f64| (c as u64) as f64 * tau + start;
                if at(cycle) > t_rx {
                    cycle -= 1.0;
                }
                (cycle >= 0.0).then(|| at(cycle))
            })
            .max_by(f64::total_cmp)
    }

    /// Decision `m`: the policy's choice on what the CNA knows now, as a command and a record.
    fn decide(&mut self, m: u64) -> Result<Vec<Outgoing>, LiveError> {
        let Some(fix) = self.fix else {
            self.counts.no_fix += 1;
            tracing::warn!(decision = m, "no fix yet: no decision");
            return Ok(Vec::new());
        };
        let t = m as f64 * self.tau;
        let pos = Vec3::new(fix.x, fix.y, fix.depth);
        let fleet = FleetView { predictors: &self.predictors, min_reports: self.min_reports };
        let ctx = PolicyContext {
            t,
            tau: self.tau,
            cna: CnaPose { pos, heading: Heading::from_radians(fix.heading), pitch: 0.0 },
            speed: self.speed,
            fleet: &fleet,
            reported: &self.reported,
            cna_variance: fix.variance,
        };
        let waiting_before = self.policy.planner_stats().map_or(0, |s| s.waiting);
        let started = Instant::now();
        let command = self.policy.as_policy().decide(&ctx);
        let elapsed_s = started.elapsed().as_secs_f64();
        self.counts.decisions += 1;
        self.counts.max_decision_s = self.counts.max_decision_s.max(elapsed_s);
        let utime = self.due_utime(m);
        let seq = m as i64;
        let msg = match command {
            CnaCommand::GoTo(p) => CommandMsg {
                utime,
                seq,
                has_waypoint: true,
                heading: (p.y - pos.y).atan2(p.x - pos.x),
                waypoint_x: p.x,
                waypoint_y: p.y,
                waypoint_depth: p.z,
                speed: self.speed as f32,
            },
            CnaCommand::Hold => CommandMsg {
                utime,
                seq,
                has_waypoint: false,
                heading: fix.heading,
                waypoint_x: pos.x,
                waypoint_y: pos.y,
                waypoint_depth: pos.z,
                speed: 0.0,
            },
        };
        let mut record = self.record(utime, seq, waiting_before);
        record.elapsed_s = elapsed_s;
        record.fix_utime = fix.utime;
        record.n_status = i32::try_from(self.counts.statuses_applied).unwrap_or(i32::MAX);
        Ok(vec![
            Outgoing { channel: self.channels.command.clone(), payload: msg.encode(&self.schema)? },
            Outgoing { channel: self.channels.decision.clone(), payload: record.encode(&self.schema)? },
        ])
    }

    /// The record of the decision just taken: the planner's options, choice, cost, depth and
    /// tally; a baseline's name only.
    fn record(&self, utime: i64, seq: i64, waiting_before: u64) -> Decision {
        let base = Decision {
            utime,
            seq,
            policy: self.policy_name().to_string(),
            option: -1,
            cost: f64::NAN,
            ..Decision::default()
        };
        let Policy::Planner(p) = &self.policy else {
            return Decision { outcome: Decision::OUTCOME_BASELINE, ..base };
        };
        let stats = p.stats();
        let options = p.config().motion.options();
        let i64_of = |v: u64| i64::try_from(v).unwrap_or(i64::MAX);
        let i32_of = |v: usize| i32::try_from(v).unwrap_or(i32::MAX);
        let mut d = Decision {
            option_turn: options.iter().map(|o| o.dpsi).collect(),
            option_pitch: options.iter().map(|o| o.dphi).collect(),
            levels_requested: i32_of(stats.levels_requested),
            decisions: i64_of(stats.decisions),
            deadline_misses: i64_of(stats.deadline_misses),
            failures: i64_of(stats.failures),
            waiting: i64_of(stats.waiting),
            min_levels_searched: i32_of(stats.min_levels_searched),
            mean_levels_searched: stats.mean_levels_searched,
            ..base
        };
        match p.last_decision() {
            Some(last) => {
                d.outcome = Decision::OUTCOME_PLANNED;
                d.option = i32_of(last.option);
                d.cost = last.value;
                d.levels_searched = i32_of(last.levels_searched);
                d.nodes = i64_of(last.nodes);
            }
            None if stats.waiting > waiting_before => d.outcome = Decision::OUTCOME_WAITING,
            None => d.outcome = Decision::OUTCOME_FAILED,
        }
        d
    }
}
