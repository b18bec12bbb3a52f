//! Software in the loop: the engine is the world, and the CNA's planner (and, with live AUVs,
//! every survey AUV's navigator) runs outside it as `coopnav live` child processes on the bus.
//!
//! # What the world publishes and reads
//! - To the CNA: every status its modem receives (the engine's `on_cna_status` hook) on
//!   `COOPNAV_CNA_STATUS`; at each decision its fix (`COOPNAV_CNA_FIX`), then the world's clock
//!   (`COOPNAV_CLOCK`). It reads the child's command (`COOPNAV_CNA_COMMAND`) and decision record
//!   (`COOPNAV_CNA_DECISION`). The engine's policy call is the [`RemoteCna`] policy: a plug-in
//!   like any other, returning the command the child gave (the engine is not told it is remote).
//! - To live AUV K ([`LiveAuvs`]): its dead-reckoning sensors at every filter step of the
//!   engine (`COOPNAV_AUV{K}_SENSORS`: the speed and compass readings the engine's own filter
//!   took, the true depth) and every usable range it decoded (`COOPNAV_AUV{K}_RANGE`: the
//!   transmit time, the receive time on its clock, the travel time it measured and the
//!   transmitter's position the packet carried). It reads `COOPNAV_AUV{K}_ESTIMATE`.
//!
//! # Lockstep and free running ([`Pace`])
//! - **Lockstep**: the world's clock on the bus; at each decision the world waits for the
//!   child's command and record of that decision and steers the CNA by it. Statuses are
//!   published at the decision that follows them. The world checks that the child decided on
//!   what it was sent (the record's fix time and count of statuses applied), else the decision is
//!   counted in `input_mismatches`. With live AUVs the world also waits, once a mission second,
//!   until every running navigator has published its estimate of the time one reorder window
//!   and a second back (flow control: the bus never holds more than a few seconds of messages).
//!   With equal inputs the child's policy is the engine's own code on the same values, so the
//!   run's results equal `coopnav simulate`'s with the same seed (the tests compare the run
//!   directories).
//! - **Free running at W × wall-clock time**: the world steps mission time t at wall time
//!   t / W after its start (never earlier; a world behind its clock is counted in `late_steps`
//!   and runs on). Statuses are published as they arrive; the clock once a mission second
//!   (not at a step where a decision falls due, whose fix the clock must follow) and at every
//!   decision after its fix. A command is applied when it arrives, at the next step
//!   ([`ScoredMission::steer`]: relative to the fix its decision saw); until then, and when
//!   none comes, the CNA holds its last command. A decision whose command has not arrived when
//!   the next decision falls due is **missed**; a command that arrives after that is **late**
//!   (counted, not applied); two or more missed decisions in a row are a **silence**, reported
//!   with its start and end (a CNA that stopped commanding).
//!
//! In both modes a child that does not answer holds the CNA on its last command; nothing the
//! children do stops the world.
//!
//! # Live AUVs and the run's error
//! With [`LiveAuvs`], one `coopnav live auv --auv K` per survey AUV navigates on the messages
//! above; the engine's own filters still run (they compose the statuses the CNA plans on, as
//! they would from the vehicle's own navigation). The run is **scored on the live estimates**:
//! every sample (each AUV, each mission second t) takes the live navigator's estimate of time
//! t (its `auv_estimate_t` whose `utime` is t's, published one reorder window later) in place of
//! the engine filter's position and covariance, and the run's metrics ([`Score`]: true error,
//! NEES, divergence) are computed again from those rows, in the order the engine reported them.
//! A sample without that estimate (a lost message, a navigator down) takes the newest earlier
//! one (counted in `samples_on_older_estimate`), or, before any, the engine's row (counted in
//! `samples_on_engine_filter`). The counts of ranges applied and the filters' NIS stay the
//! engine filters'. `sitl.json` holds both fleet errors. The live navigator cannot equal the
//! engine's filter bit for bit, even in lockstep: `auv_sensors_t` has no yaw rate (the navigator
//! predicts with none) and carries speed and depth as `f32`; the engine's filter moves a range's
//! transponder by its own motion over the decode delay and applies it at the arrival's end, with
//! the sound speed between the two depths; a surfaced AUV's GPS fixes have no message.
//!
//! # Faults ([`BusFaults`])
//! The world can spoil its own publications to the live AUVs, deterministically by count: drop,
//! duplicate, delay (by mission seconds), swap with the next (reorder) or corrupt (malformed)
//! every n-th message; and kill one navigator at a mission time and start it again later
//! ([`Restart`]: from the vehicle's own navigation then, the engine filter's estimate, as a
//! backseat process restarted at sea takes the frontseat's position). Every fault injected is
//! counted in `sitl.json`; the navigators count what they saw.

use crate::auv::{Channels, LiveConfig, LiveError, Start};
use crate::cna::CnaChannels;
use crate::world::{clock_message, decision_index, fix_message, status_message, utime};
use coopnav_acomms::Rate;
use coopnav_core::{CompassDeg, Heading, Vec3};
use coopnav_lcm::messages::{
    AuvEstimate, AuvSensors, Clock, CnaCommand as CommandMsg, Decision, Message, OwttRange, Position,
};
use coopnav_lcm::{Schema, Udpm};
use coopnav_nav::post::PostConfig;
use coopnav_nav::Gate;
use coopnav_nav::Recoveries;
use coopnav_sim::engine::{
    self, CnaFix, CnaStatusHeard, CommsEvent, DeadReckoning, Faults, FilterStart, LinkArrival, Observer, RangeHeard,
    RangeUpdate, RunEnd, Trace, TraceRow,
};
use coopnav_sim::models::channel::air_time;
use coopnav_sim::models::health::nees_2d;
use coopnav_sim::observe::metrics::{RunResult, Score, ScoredMission};
use coopnav_sim::policy::{CnaCommand, CnaPolicy, PlannerStats, Policy, PolicyContext, PolicySpec};
use coopnav_sim::scenario::Scenario;
use serde::Serialize;
use std::collections::{BTreeMap, VecDeque};
use std::io::{BufRead, BufReader, Read};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// How the world's clock runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pace {
    /// The world waits for each decision (and, with live AUVs, for their estimates).
    Lockstep,
    /// Mission time runs at this many times wall-clock time.
    Warp(f64),
}

/// Faults the world injects into its publications to the live AUVs: every `n`-th message on
/// their channels (counted over all of them, from 1; 0 = never).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct BusFaults {
    pub drop_every: u64,
    pub duplicate_every: u64,
    /// Held back `delay_s` of mission time, then published.
    pub delay_every: u64,
    pub delay_s: f64,
    /// Published after the message that follows it.
    pub reorder_every: u64,
    /// Its bytes spoiled (the type's fingerprint changed), so it does not decode.
    pub malformed_every: u64,
}

/// One live navigator killed at mission time `kill_at_s` and started again at `restart_at_s`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Restart {
    pub auv: usize,
    pub kill_at_s: f64,
    pub restart_at_s: f64,
}

/// The survey AUVs' live navigators.
#[derive(Debug, Clone)]
pub struct LiveAuvs {
    /// The program and its first arguments (`coopnav live auv`); the world adds `DIR/auvK.toml
    /// --auv K --url URL --log DIR/auvK.lcm`.
    pub program: Vec<String>,
    /// Where their configs and LCM logs go.
    pub dir: PathBuf,
    pub faults: BusFaults,
    pub restart: Option<Restart>,
    /// Lockstep: the longest wait for a navigator's estimates before the world runs on.
    pub estimate_timeout: Duration,
}

/// How the world runs its children and waits for them.
#[derive(Debug, Clone)]
pub struct SitlOptions {
    pub url: String,
    /// The CNA child: a program and its arguments (`coopnav live cna FILE --clock bus --url URL ...`).
    pub child: Vec<String>,
    /// Lockstep: how long the world waits for one decision before holding the last command.
    pub decision_timeout: Duration,
    pub pace: Pace,
    pub live_auvs: Option<LiveAuvs>,
}

impl SitlOptions {
    /// Lockstep with the CNA child only.
    pub fn lockstep(url: &str, child: Vec<String>, decision_timeout: Duration) -> Self {
        SitlOptions { url: url.into(), child, decision_timeout, pace: Pace::Lockstep, live_auvs: None }
    }
}

/// What the world saw of its CNA child.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct WorldCounts {
    pub decisions: u64,
    pub statuses_published: u64,
    /// Decisions the child did not answer in time (lockstep: within the timeout; free running:
    /// before the next decision fell due): the CNA held its last command.
    pub missed_decisions: u64,
    /// Free running: commands that arrived after the next decision fell due (not applied).
    pub late_commands: u64,
    /// Decisions whose record shows another fix or another count of statuses than sent
    /// (free running: another fix only, as statuses go out as they arrive).
    pub input_mismatches: u64,
    /// Commands and records that arrived for another decision than the one awaited (lockstep),
    /// or twice, or undecodable.
    pub stray_messages: u64,
    /// Free running: runs of two or more missed decisions in a row, [first, last] decision time
    /// (s): the CNA stopped commanding.
    pub silences: Vec<[f64; 2]>,
    /// Free running: steps the world ran after their wall-clock time by more than one step.
    pub late_steps: u64,
}

/// Latencies of the applied commands (free running).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Latencies {
    pub commands: u64,
    /// Wall time from the clock message of a decision to its command's arrival, ms.
    pub wall_ms_p50: f64,
    pub wall_ms_p99: f64,
    pub wall_ms_max: f64,
    /// Mission time from a decision to the step its command was applied at, s.
    pub mission_s_max: f64,
}

/// What the world did with the live AUVs.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct AuvWorldCounts {
    pub sensors_published: u64,
    /// Negative speed readings of the engine published as 0.
    pub speeds_clamped: u64,
    pub ranges_published: u64,
    pub estimates_received: u64,
    /// Messages not sent because the navigator was down (killed, not yet restarted).
    pub withheld_while_down: u64,
    pub dropped: u64,
    pub duplicated: u64,
    pub delayed: u64,
    /// Delayed messages still held when the mission ended: never sent.
    pub delayed_past_end: u64,
    pub reordered: u64,
    pub malformed: u64,
    /// Lockstep waits for estimates that ran out (the world ran on).
    pub estimate_timeouts: u64,
    pub samples_on_live_estimate: u64,
    pub samples_on_older_estimate: u64,
    pub samples_on_engine_filter: u64,
    pub restarts: u64,
    /// The fleet's mean true error on the engine's own filters (the live-scored one is the
    /// run's `fleet.error.mean`).
    pub engine_fleet_error_mean: f64,
}

/// A run: the engine's result (scored on the live estimates with live AUVs) and the world's
/// account of its children.
#[derive(Debug, Clone)]
pub struct SitlRun {
    pub result: RunResult,
    pub counts: WorldCounts,
    pub latencies: Latencies,
    pub auvs: Option<AuvWorldCounts>,
    /// The CNA child's one-line JSON summary, when it printed one.
    pub child_summary: Option<serde_json::Value>,
    /// Each live navigator's summaries (one per process it ran as), in order.
    pub auv_summaries: Vec<Vec<serde_json::Value>>,
    /// The live navigators' LCM logs, per AUV, one per process.
    pub auv_logs: Vec<Vec<PathBuf>>,
    pub wall_s: f64,
}

/// A decision published and not yet answered (free running).
#[derive(Debug, Clone, Copy)]
struct Outstanding {
    seq: i64,
    t: f64,
    sent: Instant,
    fix_utime: i64,
}

/// Everything the world shares between its loop, its observer and its policy call.
struct World {
    lcm: Udpm,
    schema: Schema,
    channels: CnaChannels,
    auv_channels: Vec<Channels>,
    pace: Pace,
    counts: WorldCounts,
    /// Lockstep: statuses kept until the next decision.
    pending_statuses: Vec<Vec<u8>>,
    /// Lockstep: answers by decision.
    answers: BTreeMap<i64, (Option<CommandMsg>, Option<Decision>)>,
    /// Free running: the newest decision published and not answered, and the command to apply.
    outstanding: Option<Outstanding>,
    answered: Option<Outstanding>,
    to_apply: Option<(CnaCommand, f64)>,
    /// The newest command taken (the CNA holds it), and the planner's tally from its record.
    last: CnaCommand,
    stats: Option<PlannerStats>,
    missed_in_row: Vec<f64>,
    wall_ms: Vec<f64>,
    mission_latency_max: f64,
    /// Live AUVs: per AUV the estimates received by utime, and the newest.
    estimates: Vec<BTreeMap<i64, AuvEstimate>>,
    newest_estimate: Vec<i64>,
    faults: BusFaults,
    auv_counts: AuvWorldCounts,
    sent_to_auvs: u64,
    delayed: VecDeque<(f64, String, Vec<u8>)>,
    reorder_held: Option<(String, Vec<u8>)>,
    down: Option<usize>,
    /// Each AUV's own navigation (the engine filter's estimate) at the latest sample.
    own_nav: Vec<(f64, f64)>,
    /// Mission time each navigator's process started.
    since: Vec<f64>,
    t: f64,
}

fn every(n: u64, i: u64) -> bool {
    n > 0 && i % n == 0
}

impl World {
    fn publish(&mut self, channel: &str, payload: &[u8]) {
        if let Err(e) = self.lcm.publish(channel, payload) {
            tracing::error!(channel, error = %e, "publishing failed");
        }
    }

    /// A message to live AUV `k`, through the fault injector.
    fn to_auv(&mut self, k: usize, channel: String, payload: Vec<u8>) {
        if self.down == Some(k) {
            self.auv_counts.withheld_while_down += 1;
            return;
        }
        self.sent_to_auvs += 1;
        let (i, f) = (self.sent_to_auvs, self.faults);
        if every(f.drop_every, i) {
            self.auv_counts.dropped += 1;
            return;
        }
        if every(f.malformed_every, i) {
            self.auv_counts.malformed += 1;
            let mut bad = payload;
            bad[0] ^= 0xff;
            self.publish(&channel, &bad);
            return;
        }
        if every(f.delay_every, i) {
            self.auv_counts.delayed += 1;
            self.delayed.push_back((self.t + f.delay_s, channel, payload));
            return;
        }
        if every(f.reorder_every, i) && self.reorder_held.is_none() {
            self.auv_counts.reordered += 1;
            self.reorder_held = Some((channel, payload));
            return;
        }
        self.publish(&channel, &payload);
        if every(f.duplicate_every, i) {
            self.auv_counts.duplicated += 1;
            self.publish(&channel, &payload);
        }
        if let Some((c, p)) = self.reorder_held.take() {
            self.publish(&c, &p);
        }
    }

    /// Publishes the delayed messages due by mission time `t`.
    fn release_delayed(&mut self, t: f64) {
        self.t = t;
        while self.delayed.front().is_some_and(|(at, _, _)| *at <= t) {
            let (_, c, p) = self.delayed.pop_front().expect("front checked");
            self.publish(&c, &p);
        }
    }

    /// Receives for at most `timeout` (one message), and files it.
    fn receive(&mut self, timeout: Duration) -> bool {
        match self.lcm.recv_timeout(timeout) {
            Ok(Some(msg)) => {
                self.file(&msg.channel, &msg.data);
                true
            }
            Ok(None) => false,
            Err(e) => {
                tracing::error!(error = %e, "receiving failed");
                false
            }
        }
    }

    /// Files every message already waiting.
    fn drain(&mut self) {
        while self.receive(Duration::ZERO) {}
    }

    fn file(&mut self, channel: &str, data: &[u8]) {
        if channel == self.channels.command {
            match CommandMsg::decode(&self.schema, data) {
                Ok(c) => self.on_command(c),
                Err(_) => self.counts.stray_messages += 1,
            }
        } else if channel == self.channels.decision {
            match Decision::decode(&self.schema, data) {
                Ok(d) => self.on_record(d),
                Err(_) => self.counts.stray_messages += 1,
            }
        } else if let Some(k) = self.auv_channels.iter().position(|c| c.estimate == channel) {
            match AuvEstimate::decode(&self.schema, data) {
                Ok(e) if e.auv as usize == k => {
                    self.auv_counts.estimates_received += 1;
                    self.newest_estimate[k] = self.newest_estimate[k].max(e.utime);
                    self.estimates[k].insert(e.utime, e);
                }
                _ => tracing::warn!(channel, "an estimate that does not decode or names another AUV"),
            }
        }
    }

    fn on_command(&mut self, c: CommandMsg) {
        match self.pace {
            Pace::Lockstep => {
                let slot = self.answers.entry(c.seq).or_default();
                if slot.0.is_some() {
                    self.counts.stray_messages += 1;
                }
                slot.0 = Some(c);
            }
            Pace::Warp(_) => match self.outstanding {
                Some(o) if o.seq == c.seq => {
                    self.wall_ms.push(o.sent.elapsed().as_secs_f64() * 1e3);
                    self.outstanding = None;
                    self.answered = Some(o);
                    self.missed_in_row.clear();
                    let cmd = command_of(&c);
                    self.to_apply = Some((cmd, o.t));
                    self.last = cmd;
                }
                _ => {
                    self.counts.late_commands += 1;
                    tracing::warn!(seq = c.seq, "a command after its next decision fell due: not applied");
                }
            },
        }
    }

    fn on_record(&mut self, d: Decision) {
        match self.pace {
            Pace::Lockstep => {
                let slot = self.answers.entry(d.seq).or_default();
                if slot.1.is_some() {
                    self.counts.stray_messages += 1;
                }
                slot.1 = Some(d);
            }
            Pace::Warp(_) => {
                // The record follows its command: its decision is the one just answered, or
                // still outstanding.
                let expected = [self.answered, self.outstanding].into_iter().flatten().find(|o| o.seq == d.seq);
                if let Some(fix) = expected.map(|o| o.fix_utime) {
                    if d.fix_utime != fix {
                        self.counts.input_mismatches += 1;
                    }
                }
                self.stats = Some(stats_of(&d));
            }
        }
    }

    /// Free running: the decision at `t` falls due; the one before it is missed if unanswered.
    fn close_outstanding(&mut self) {
        if let Some(o) = self.outstanding.take() {
            self.counts.missed_decisions += 1;
            self.missed_in_row.push(o.t);
            tracing::warn!(decision = o.seq, "no command before the next decision: the CNA holds its last command");
            if self.missed_in_row.len() == 2 {
                tracing::warn!(t = self.missed_in_row[0], "the CNA stopped commanding: it holds its last command");
                self.counts.silences.push([self.missed_in_row[0], o.t]);
            } else if self.missed_in_row.len() > 2 {
                if let Some(s) = self.counts.silences.last_mut() {
                    s[1] = o.t;
                }
            }
        }
    }
}

fn command_of(c: &CommandMsg) -> CnaCommand {
    if c.has_waypoint {
        CnaCommand::GoTo(Vec3::new(c.waypoint_x, c.waypoint_y, c.waypoint_depth))
    } else {
        CnaCommand::Hold
    }
}

/// The planner's tally as the child's record carries it.
fn stats_of(d: &Decision) -> PlannerStats {
    let u = |v: i64| u64::try_from(v).unwrap_or(0);
    let z = |v: i32| usize::try_from(v).unwrap_or(0);
    PlannerStats {
        decisions: u(d.decisions),
        deadline_misses: u(d.deadline_misses),
        levels_requested: z(d.levels_requested),
        min_levels_searched: z(d.min_levels_searched),
        mean_levels_searched: d.mean_levels_searched,
        failures: u(d.failures),
        waiting: u(d.waiting),
    }
}

type Shared = Arc<Mutex<World>>;

/// The engine's policy call answered by the child on the bus (see the module doc).
pub struct RemoteCna {
    name: &'static str,
    transmits: bool,
    planner: bool,
    sc: Scenario,
    world: Shared,
    timeout: Duration,
}

impl RemoteCna {
    /// Lockstep: waits for the child's command and record of decision `seq`.
    fn await_decision(&self, w: &mut World, seq: i64) -> Option<(CommandMsg, Decision)> {
        let deadline = Instant::now() + self.timeout;
        loop {
            if let Some((Some(c), Some(d))) = w.answers.get(&seq) {
                let answer = (*c, d.clone());
                w.answers.remove(&seq);
                return Some(answer);
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return None;
            }
            w.receive(left);
        }
    }
}

impl CnaPolicy for RemoteCna {
    fn name(&self) -> &'static str {
        self.name
    }
    fn transmits(&self) -> bool {
        self.transmits
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        let m = decision_index(ctx.t, ctx.tau);
        let world = self.world.clone();
        let mut w = world.lock().expect("world");
        let pending = std::mem::take(&mut w.pending_statuses);
        let status = w.channels.status.clone();
        for payload in &pending {
            w.publish(&status, payload);
        }
        let fix = fix_message(&self.sc, ctx);
        let (fix_payload, clock) = (fix.encode(&w.schema), clock_message(m, ctx.t, ctx.tau).encode(&w.schema));
        let (Ok(fix_payload), Ok(clock)) = (fix_payload, clock) else {
            tracing::error!(decision = m, "the fix or clock does not encode: the CNA holds its last command");
            return w.last;
        };
        let (fix_channel, clock_channel) = (w.channels.fix.clone(), w.channels.clock.clone());
        w.counts.decisions += 1;
        if let Pace::Warp(_) = w.pace {
            w.drain();
            w.close_outstanding();
            w.publish(&fix_channel, &fix_payload);
            w.publish(&clock_channel, &clock);
            w.outstanding =
                Some(Outstanding { seq: m as i64, t: ctx.t, sent: Instant::now(), fix_utime: utime(ctx.t) });
            w.to_apply = None;
            return w.last;
        }
        w.publish(&fix_channel, &fix_payload);
        w.publish(&clock_channel, &clock);
        let answer = self.await_decision(&mut w, m as i64);
        w.counts.statuses_published += pending.len() as u64;
        let Some((command, record)) = answer else {
            w.counts.missed_decisions += 1;
            tracing::warn!(decision = m, "the CNA stopped commanding: it holds its last command");
            return w.last;
        };
        // Answers to earlier decisions that came after their timeout are strays.
        let stale: Vec<i64> = w.answers.range(..m as i64).map(|(s, _)| *s).collect();
        for s in stale {
            w.answers.remove(&s);
            w.counts.stray_messages += 1;
        }
        if record.fix_utime != utime(ctx.t) || record.n_status as u64 != w.counts.statuses_published {
            w.counts.input_mismatches += 1;
            tracing::warn!(decision = m, ?record, "the CNA decided on other inputs than the world sent");
        }
        if self.planner {
            w.stats = Some(stats_of(&record));
        }
        w.last = command_of(&command);
        w.last
    }
    fn planner_stats(&self) -> Option<PlannerStats> {
        if self.planner {
            self.world.lock().expect("world").stats.clone()
        } else {
            None
        }
    }
}

/// One call of the engine that [`Score`] reads, kept to score the run again on the live
/// estimates.
enum Scored {
    Fix { t: f64, fix: Vec3, transmits: bool, forecast: Vec<Option<Vec3>> },
    Sample { t: f64, cna: Vec3, rows: Vec<TraceRow> },
    Range(RangeUpdate),
    Link(LinkArrival),
    End { recoveries: Vec<Recoveries>, finite: bool },
}

/// The run's time series (as `simulate` records it); statuses to the CNA; with live AUVs, their
/// sensors and ranges, and what [`Score`] reads.
struct WorldObserver {
    trace: Trace,
    world: Shared,
    live: bool,
    starts: Vec<Option<FilterStart>>,
    scored: Vec<Scored>,
}

impl WorldObserver {
    fn sensors(&self, dr: &DeadReckoning) -> AuvSensors {
        let compass = CompassDeg::from(Heading::from_radians(dr.heading)).0;
        AuvSensors {
            utime: utime(dr.t),
            auv: dr.auv as i16,
            heading: compass.to_radians(),
            // A speed log reads no negative speed through the water (the engine's Gaussian
            // reading can dip below zero at rest; its own filter takes it as it is).
            speed: dr.speed.max(0.0) as f32,
            depth: dr.truth.z as f32,
            ..AuvSensors::default()
        }
    }
}

impl Observer for WorldObserver {
    fn on_decision(&mut self, decision: &engine::Decision) {
        self.trace.on_decision(decision);
    }
    fn on_sample(&mut self, t: f64, cna: Vec3, rows: &[TraceRow]) {
        self.trace.on_sample(t, cna, rows);
        if self.live {
            self.scored.push(Scored::Sample { t, cna, rows: rows.to_vec() });
            let mut w = self.world.lock().expect("world");
            for r in rows {
                w.own_nav[r.auv] = (r.est_x, r.est_y);
            }
        }
    }
    fn on_packet(&mut self, event: &CommsEvent) {
        self.trace.on_packet(event);
    }
    fn on_cna_status(&mut self, heard: &CnaStatusHeard) {
        let mut w = self.world.lock().expect("world");
        match status_message(heard).encode(&w.schema) {
            Ok(payload) => match w.pace {
                Pace::Lockstep => w.pending_statuses.push(payload),
                Pace::Warp(_) => {
                    let channel = w.channels.status.clone();
                    w.publish(&channel, &payload);
                    w.counts.statuses_published += 1;
                }
            },
            Err(e) => tracing::error!(error = %e, "a received status does not encode for the bus"),
        }
    }
    fn on_filter_start(&mut self, start: &FilterStart) {
        if let Some(s) = self.starts.get_mut(start.auv) {
            *s = Some(*start);
        }
    }
    fn on_dead_reckoning(&mut self, dr: &DeadReckoning) {
        if !self.live {
            return;
        }
        let msg = self.sensors(dr);
        let mut w = self.world.lock().expect("world");
        w.auv_counts.speeds_clamped += u64::from(dr.speed < 0.0);
        let Ok(payload) = msg.encode(&w.schema) else { return };
        let channel = w.auv_channels[dr.auv].sensors.clone();
        w.auv_counts.sensors_published += 1;
        w.to_auv(dr.auv, channel, payload);
    }
    fn on_range(&mut self, r: &RangeHeard) {
        let (true, Some(p)) = (self.live, r.fix) else { return };
        let receive_time = r.t_tx + r.travel_time;
        let msg = OwttRange {
            utime: utime(receive_time),
            src: match r.from {
                coopnav_sim::models::schedule::Owner::Cna => -1,
                coopnav_sim::models::schedule::Owner::Buoy(b) => i8::try_from(100 + b).unwrap_or(i8::MAX),
                _ => i8::MAX,
            },
            transmit_time: r.t_tx,
            receive_time,
            transponder: Position { x: p.x, y: p.y, z: p.z },
            travel_time: r.travel_time,
        };
        let mut w = self.world.lock().expect("world");
        let Ok(payload) = msg.encode(&w.schema) else { return };
        let channel = w.auv_channels[r.auv].range.clone();
        w.auv_counts.ranges_published += 1;
        w.to_auv(r.auv, channel, payload);
    }
    fn on_cna_fix(&mut self, fix: &CnaFix) {
        if self.live {
            self.scored.push(Scored::Fix {
                t: fix.t,
                fix: fix.fix,
                transmits: fix.transmits,
                forecast: fix.forecast.to_vec(),
            });
        }
    }
    fn on_range_update(&mut self, update: &RangeUpdate) {
        // The trace explains the error plot's jumps by the ranges offered, as `simulate`'s does.
        // With live AUVs the outcome recorded is the engine's own filter's on the same range.
        self.trace.on_range_update(update);
        if self.live {
            self.scored.push(Scored::Range(*update));
        }
    }
    fn on_link(&mut self, arrival: &LinkArrival) {
        if self.live {
            self.scored.push(Scored::Link(*arrival));
        }
    }
    fn on_end(&mut self, end: &RunEnd) {
        if self.live {
            self.scored.push(Scored::End { recoveries: end.recoveries.to_vec(), finite: end.finite });
        }
    }
}

/// A child process, listening (it announces on stderr once subscribed).
struct ChildProc {
    name: String,
    child: Child,
    stderr: mpsc::Receiver<String>,
}

impl ChildProc {
    fn start(args: &[String], name: &str) -> Result<Self, LiveError> {
        let (program, rest) = args.split_first().ok_or_else(|| LiveError::Child("no child program".into()))?;
        let mut child = Command::new(program)
            .args(rest)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| LiveError::Child(format!("cannot start {program}: {e}")))?;
        let (tx, rx) = mpsc::channel();
        let err = child.stderr.take().expect("piped");
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().take(100_000) {
                let Ok(line) = line else { break };
                if tx.send(line).is_err() {
                    break;
                }
            }
        });
        let mut me = ChildProc { name: name.to_string(), child, stderr: rx };
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match me.stderr.recv_timeout(left) {
                Ok(line) if line.starts_with("listening:") => return Ok(me),
                Ok(line) => eprintln!("{name}: {line}"),
                Err(_) => {
                    me.kill();
                    return Err(LiveError::Child(format!("{name} did not announce that it listens within 30 s")));
                }
            }
        }
    }

    fn kill(&mut self) {
        // Child::kill signals this child's own pid (SIGKILL), which is not yet reaped.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Asks it to stop (SIGTERM to its own pid).
    fn terminate(&self) {
        // SAFETY: kill(2) on our own child's pid, which is not yet reaped.
        unsafe { libc::kill(self.child.id() as libc::pid_t, libc::SIGTERM) };
    }

    fn exited(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(Some(_)))
    }

    /// Waits for its exit (at most `timeout`, then kills it by pid); its summary line.
    fn finish(mut self, timeout: Duration) -> Result<Option<serde_json::Value>, LiveError> {
        let deadline = Instant::now() + timeout;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => {
                    for line in self.stderr.try_iter().take(50) {
                        eprintln!("{}: {line}", self.name);
                    }
                    let mut out = String::new();
                    if let Some(mut stdout) = self.child.stdout.take() {
                        let _ = stdout.read_to_string(&mut out);
                    }
                    if !status.success() {
                        return Err(LiveError::Child(format!("{} exited with {status}", self.name)));
                    }
                    return Ok(serde_json::from_str(out.trim()).ok());
                }
                Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(20)),
                _ => {
                    self.kill();
                    return Err(LiveError::Child(format!("{} did not stop within {timeout:?}: killed", self.name)));
                }
            }
        }
    }
}

/// The live navigator's config for survey AUV `k` of `sc`, starting at `start`: the engine
/// filter's coefficients and model, its range gate at the top level (post-processing's place),
/// the slant range on the logged depth (the engine's filter ranges in 3-D on the AUV's depth).
///
/// The world reports a range when its packet's arrival ends (as a modem reports it once decoded),
/// up to one packet's air time after its receive time; the reorder window is the default plus the
/// longest air time of the modem's rates, so that no range the world reports is stale.
pub fn live_config(sc: &Scenario, start: Start) -> LiveConfig {
    let mut auv = sc.filter.params.clone();
    let range_gate = std::mem::replace(&mut auv.range_gate, Gate::default());
    let filter = PostConfig { auv, model: sc.filter.model, range_gate, slant_range: true, ..PostConfig::default() };
    let longest_air = Rate::usable().into_iter().map(air_time).fold(0.0, f64::max);
    let window = LiveConfig::default().reorder_window_s + longest_air;
    LiveConfig { filter, start, reorder_window_s: window }
}

/// The live navigators as the world runs them.
struct Navigators {
    opts: LiveAuvs,
    url: String,
    children: Vec<Option<ChildProc>>,
    summaries: Vec<Vec<serde_json::Value>>,
    logs: Vec<Vec<PathBuf>>,
    configs: Vec<LiveConfig>,
    window_s: f64,
}

impl Navigators {
    fn start(&mut self, k: usize) -> Result<(), LiveError> {
        let n = self.logs[k].len();
        let stem = if n == 0 { format!("auv{k}") } else { format!("auv{k}-{n}") };
        let (config, log) = (self.opts.dir.join(format!("{stem}.toml")), self.opts.dir.join(format!("{stem}.lcm")));
        let text =
            toml::to_string(&self.configs[k]).map_err(|e| LiveError::Child(format!("config of AUV {k}: {e}")))?;
        std::fs::write(&config, text).map_err(|e| LiveError::Child(format!("{}: {e}", config.display())))?;
        let mut args = self.opts.program.clone();
        args.push(config.display().to_string());
        for (flag, value) in
            [("--auv", k.to_string()), ("--url", self.url.clone()), ("--log", log.display().to_string())]
        {
            args.extend([flag.to_string(), value]);
        }
        self.children[k] = Some(ChildProc::start(&args, &format!("live auv {k}"))?);
        self.logs[k].push(log);
        Ok(())
    }

    fn kill(&mut self, k: usize) {
        if let Some(mut c) = self.children[k].take() {
            c.kill();
            self.summaries[k].push(serde_json::json!({ "killed": true }));
        }
    }
}

/// Lockstep with live AUVs: waits until every running navigator has published its estimate of
/// `t` less one reorder window and a second.
fn wait_for_estimates(world: &Shared, navs: &Navigators, t: f64, timeout: Duration) {
    let want = utime(t - navs.window_s - 1.0);
    if want <= 0 {
        return;
    }
    let deadline = Instant::now() + timeout;
    let mut w = world.lock().expect("world");
    loop {
        // A navigator started less than a window and a second ago has no estimate to wait for.
        let behind = (0..navs.children.len()).any(|k| {
            navs.children[k].is_some() && w.down != Some(k) && utime(w.since[k]) < want && w.newest_estimate[k] < want
        });
        if !behind {
            return;
        }
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            w.auv_counts.estimate_timeouts += 1;
            tracing::warn!(t, "a live navigator is behind: the world runs on");
            return;
        }
        w.receive(left.min(Duration::from_millis(50)));
    }
}

/// The rows of a sample with every AUV's live estimate of its time in place of the engine's
/// (see the module doc).
fn live_rows(
    rows: &[TraceRow],
    estimates: &[BTreeMap<i64, AuvEstimate>],
    counts: &mut AuvWorldCounts,
) -> Vec<TraceRow> {
    rows.iter()
        .map(|r| {
            let at = utime(r.t);
            let found = estimates[r.auv].range(..=at).next_back().map(|(u, e)| (*u == at, *e));
            let Some((exact, e)) = found else {
                counts.samples_on_engine_filter += 1;
                return *r;
            };
            if exact {
                counts.samples_on_live_estimate += 1;
            } else {
                counts.samples_on_older_estimate += 1;
            }
            let (dx, dy) = (e.x - r.true_x, e.y - r.true_y);
            let [[p_ee, p_en], [_, p_nn]] = e.cov;
            TraceRow {
                est_x: e.x,
                est_y: e.y,
                error: dx.hypot(dy),
                est_sd: (p_ee + p_nn).max(0.0).sqrt(),
                p_ee,
                p_en,
                p_nn,
                nees: nees_2d(dx, dy, p_ee, p_en, p_nn),
                ..*r
            }
        })
        .collect()
}

/// Scores the run again from the recorded calls, each sample's rows on the live estimates.
fn rescore(sc: &Scenario, scored: &[Scored], world: &mut World, trace: &mut Trace) -> Score {
    let mut score = Score::new(sc);
    let mut counts = std::mem::take(&mut world.auv_counts);
    let mut samples: Vec<Vec<TraceRow>> = Vec::new();
    for call in scored {
        match call {
            Scored::Fix { t, fix, transmits, forecast } => {
                score.on_cna_fix(&CnaFix { t: *t, fix: *fix, transmits: *transmits, forecast })
            }
            Scored::Sample { t, cna, rows } => {
                let rows = live_rows(rows, &world.estimates, &mut counts);
                score.on_sample(*t, *cna, &rows);
                samples.push(rows);
            }
            Scored::Range(u) => score.on_range_update(u),
            Scored::Link(a) => score.on_link(a),
            Scored::End { recoveries, finite } => score.on_end(&RunEnd { recoveries, finite: *finite }),
        }
    }
    let live: Vec<TraceRow> = samples.into_iter().flatten().collect();
    if live.len() == trace.rows.len() {
        trace.rows = live;
    }
    world.auv_counts = counts;
    score
}

/// Runs scenario `sc` (its seed) with the child deciding for policy `policy` in lockstep, the
/// engine's own filters navigating the survey AUVs.
pub fn run_lockstep(sc: &Scenario, policy: &str, opts: &SitlOptions) -> Result<SitlRun, LiveError> {
    run(sc, policy, &SitlOptions { pace: Pace::Lockstep, live_auvs: None, ..opts.clone() })
}

/// Runs scenario `sc` (its seed) with the child deciding for policy `policy`; see the module doc.
pub fn run(sc: &Scenario, policy: &str, opts: &SitlOptions) -> Result<SitlRun, LiveError> {
    let started = Instant::now();
    let local = PolicySpec::new(policy, sc)?.build(sc)?;
    let (name, transmits, planner) = match &local {
        Policy::Planner(p) => (p.name(), p.transmits(), true),
        Policy::Baseline(b) => (b.name(), b.transmits(), false),
    };
    let n = sc.fleet.n_auvs;
    let channels = CnaChannels::default();
    let auv_channels: Vec<Channels> = (0..n).map(|k| Channels::for_auv(k as i16)).collect();
    let mut lcm = Udpm::new(&opts.url)?;
    lcm.subscribe(&channels.command)?;
    lcm.subscribe(&channels.decision)?;
    if opts.live_auvs.is_some() {
        for c in &auv_channels {
            lcm.subscribe(&c.estimate)?;
        }
    }
    let world = Arc::new(Mutex::new(World {
        lcm,
        schema: Schema::coopnav(),
        channels,
        auv_channels,
        pace: opts.pace,
        counts: WorldCounts::default(),
        pending_statuses: Vec::new(),
        answers: BTreeMap::new(),
        outstanding: None,
        answered: None,
        to_apply: None,
        last: CnaCommand::Hold,
        stats: None,
        missed_in_row: Vec::new(),
        wall_ms: Vec::new(),
        mission_latency_max: 0.0,
        estimates: vec![BTreeMap::new(); n],
        newest_estimate: vec![i64::MIN; n],
        faults: opts.live_auvs.as_ref().map(|l| l.faults).unwrap_or_default(),
        auv_counts: AuvWorldCounts::default(),
        sent_to_auvs: 0,
        delayed: VecDeque::new(),
        reorder_held: None,
        down: None,
        own_nav: vec![(0.0, 0.0); n],
        since: vec![0.0; n],
        t: 0.0,
    }));
    let remote =
        RemoteCna { name, transmits, planner, sc: sc.clone(), world: world.clone(), timeout: opts.decision_timeout };
    let mut policy = Policy::Baseline(Box::new(remote));
    let mut obs = WorldObserver {
        trace: Trace::default(),
        world: world.clone(),
        live: opts.live_auvs.is_some(),
        starts: vec![None; n],
        scored: Vec::new(),
    };
    let faults = Faults::default();
    let mut mission = ScoredMission::new(sc, &mut policy, sc.seed, &faults, &mut obs);
    let mut navs = match &opts.live_auvs {
        None => None,
        Some(live) => {
            let configs: Vec<LiveConfig> = obs
                .starts
                .iter()
                .map(|s| live_config(sc, s.map_or(Start::default(), |s| Start { e: s.x, n: s.y })))
                .collect();
            let window_s = configs.first().map_or(0.0, |c| c.reorder_window_s);
            let mut navs = Navigators {
                opts: live.clone(),
                url: opts.url.clone(),
                children: (0..n).map(|_| None).collect(),
                summaries: vec![Vec::new(); n],
                logs: vec![Vec::new(); n],
                configs,
                window_s,
            };
            for k in 0..n {
                navs.start(k)?;
            }
            Some(navs)
        }
    };
    let cna = ChildProc::start(&opts.child, "live cna")?;
    let wall0 = Instant::now();
    let mut last_clock_s = -1.0;
    while !mission.done() {
        let t = mission.t();
        if let Some(navs) = navs.as_mut() {
            restart_step(&world, navs, t)?;
        }
        match opts.pace {
            Pace::Warp(warp) => {
                let due = wall0 + Duration::from_secs_f64(t / warp);
                let mut w = world.lock().expect("world");
                if Instant::now() > due + Duration::from_secs_f64(sc.dt / warp) {
                    w.counts.late_steps += 1;
                }
                loop {
                    let left = due.saturating_duration_since(Instant::now());
                    if left.is_zero() {
                        break;
                    }
                    w.receive(left);
                }
                w.drain();
                w.release_delayed(t);
                if t.floor() > last_clock_s && !mission.decides_next() {
                    last_clock_s = t.floor();
                    let m = decision_index(t, sc.comms.tau);
                    if let Ok(clock) = clock_message(m, t, sc.comms.tau).encode(&w.schema) {
                        let channel = w.channels.clock.clone();
                        w.publish(&channel, &clock);
                    }
                }
                if let Some((cmd, t_dec)) = w.to_apply.take() {
                    w.mission_latency_max = w.mission_latency_max.max(t - t_dec);
                    drop(w);
                    mission.steer(cmd, &mut obs);
                }
            }
            Pace::Lockstep => {
                let mut w = world.lock().expect("world");
                w.release_delayed(t);
                drop(w);
                if let (Some(navs), Some(timeout)) =
                    (navs.as_ref(), opts.live_auvs.as_ref().map(|l| l.estimate_timeout))
                {
                    if (t - t.round()).abs() < 1e-6 {
                        wait_for_estimates(&world, navs, t, timeout);
                    }
                }
            }
        }
        mission.step(&mut obs);
    }
    let mut result = mission.finish();
    drop(policy);
    // The last decision's command may still come.
    {
        let mut w = world.lock().expect("world");
        if let Pace::Warp(warp) = opts.pace {
            let deadline = Instant::now() + Duration::from_secs_f64(sc.comms.tau / warp);
            while w.outstanding.is_some() && Instant::now() < deadline {
                w.receive(Duration::from_millis(10));
            }
            w.close_outstanding();
        }
        // Messages held past the mission's end never arrive.
        w.auv_counts.delayed_past_end = w.delayed.len() as u64;
        w.delayed.clear();
        if let Some((c, p)) = w.reorder_held.take() {
            w.publish(&c, &p);
        }
        let stop = Clock { running: false, ..Clock::default() }.encode(&w.schema)?;
        let clock = w.channels.clock.clone();
        w.publish(&clock, &stop);
    }
    let child_summary = cna.finish(Duration::from_secs(30))?;
    let mut auv_summaries = Vec::new();
    let mut auv_logs = Vec::new();
    let mut auv_counts = None;
    if let Some(mut navs) = navs {
        for c in navs.children.iter().flatten() {
            c.terminate();
        }
        // Their last estimates (the reorder buffers flushed) come before they exit.
        let deadline = Instant::now() + Duration::from_secs(30);
        while navs.children.iter_mut().flatten().any(|c| !c.exited()) && Instant::now() < deadline {
            world.lock().expect("world").receive(Duration::from_millis(20));
        }
        world.lock().expect("world").drain();
        for k in 0..n {
            if let Some(c) = navs.children[k].take() {
                if let Some(s) = c.finish(Duration::from_secs(5))? {
                    navs.summaries[k].push(s);
                }
            }
        }
        let mut w = world.lock().expect("world");
        w.auv_counts.engine_fleet_error_mean = result.fleet.error.mean;
        let mut trace = std::mem::take(&mut obs.trace);
        let score = rescore(sc, &obs.scored, &mut w, &mut trace);
        obs.trace = trace;
        let (auvs, fleet) = score.metrics();
        result.auvs = auvs;
        result.fleet = fleet;
        auv_counts = Some(w.auv_counts.clone());
        auv_summaries = navs.summaries;
        auv_logs = navs.logs;
    }
    result.trace = Some(std::mem::take(&mut obs.trace));
    let w = world.lock().expect("world");
    if planner {
        result.planner = w.stats.clone();
    }
    let latencies = latencies(&w);
    Ok(SitlRun {
        result,
        counts: w.counts.clone(),
        latencies,
        auvs: auv_counts,
        child_summary,
        auv_summaries,
        auv_logs,
        wall_s: started.elapsed().as_secs_f64(),
    })
}

fn latencies(w: &World) -> Latencies {
    let mut ms = w.wall_ms.clone();
    ms.sort_by(f64::total_cmp);
    let at = |q: f64| if ms.is_empty() { 0.0 } else { ms[((ms.len() - 1) as f64 * q).round() as usize] };
    Latencies {
        commands: ms.len() as u64,
        wall_ms_p50: at(0.5),
        wall_ms_p99: at(0.99),
        wall_ms_max: at(1.0),
        mission_s_max: w.mission_latency_max,
    }
}

/// Kills and restarts the navigator the options name when mission time `t` reaches its times.
fn restart_step(world: &Shared, navs: &mut Navigators, t: f64) -> Result<(), LiveError> {
    let Some(r) = navs.opts.restart else { return Ok(()) };
    let mut w = world.lock().expect("world");
    if w.down.is_none() && navs.children[r.auv].is_some() && navs.logs[r.auv].len() == 1 && t >= r.kill_at_s {
        tracing::warn!(auv = r.auv, t, "killing the live navigator");
        navs.kill(r.auv);
        w.down = Some(r.auv);
    } else if w.down == Some(r.auv) && t >= r.restart_at_s {
        // Started again where the vehicle's own navigation puts it now, as a backseat process
        // restarted at sea takes the frontseat's position.
        let (e, n) = w.own_nav[r.auv];
        navs.configs[r.auv].start = Start { e, n };
        drop(w);
        navs.start(r.auv)?;
        let mut w = world.lock().expect("world");
        w.down = None;
        w.since[r.auv] = t;
        w.auv_counts.restarts += 1;
    }
    Ok(())
}
