//! The engine's world as a CNA's backseat sees it: the LCM messages a live CNA receives during a
//! simulated mission — its fix at every decision, the world's clock, and every status its modem
//! received — written once here for the software-in-the-loop world (`crate::sitl`) and for
//! recording a mission's inputs ([`record`]: the tests feed them to [`crate::CnaPlanner`] and
//! compare its decisions with the engine's own; the benchmark times them).
//!
//! Times on the bus are mission seconds from epoch 0: a message's `utime` is its mission time in
//! microseconds, rounded; a status's `receive_time` is the end of its arrival at the CNA.

use crate::auv::LiveError;
use crate::cna::CnaChannels;
use coopnav_lcm::messages::{Clock, CnaFix, Message, StatusFrame};
use coopnav_lcm::Schema;
use coopnav_sim::engine::{CnaStatusHeard, Faults, Observer};
use coopnav_sim::observe::metrics::{self, RunResult};
use coopnav_sim::policy::{CnaCommand, CnaPolicy, PlannerStats, Policy, PolicyContext, PolicySpec};
use coopnav_sim::scenario::Scenario;
use std::sync::{Arc, Mutex};

/// Microseconds of a mission time in seconds.
pub fn utime(t: f64) -> i64 {
    (t * 1e6).round() as i64
}

/// The CNA's fix the engine decided on (its pose and variance in the policy's context): GPS for a
/// surface CNA, its navigation for an AUV CNA.
pub fn fix_message(sc: &Scenario, ctx: &PolicyContext) -> CnaFix {
    CnaFix {
        utime: utime(ctx.t),
        x: ctx.cna.pos.x,
        y: ctx.cna.pos.y,
        depth: ctx.cna.pos.z,
        heading: ctx.cna.heading.radians(),
        variance: ctx.cna_variance,
        source: if sc.cna.auv.is_some() { CnaFix::SOURCE_DEAD_RECKONING } else { CnaFix::SOURCE_GPS },
    }
}

/// The world's clock at decision `m` (time `t`, period `tau`).
pub fn clock_message(m: u64, t: f64, tau: f64) -> Clock {
    Clock { utime: utime(t), tick: m as i64, dt: tau, running: true }
}

/// A status the CNA's modem received, as its modem driver publishes it.
pub fn status_message(heard: &CnaStatusHeard) -> StatusFrame {
    StatusFrame {
        utime: utime(heard.t_rx),
        src: heard.auv as i16,
        receive_time: heard.t_rx,
        data: heard.bytes.to_vec(),
    }
}

/// The decision index of a decision at `t` (t = m·τ).
pub fn decision_index(t: f64, tau: f64) -> u64 {
    (t / tau).round() as u64
}

/// One message the CNA received in a recorded mission.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldMessage {
    pub channel: String,
    pub payload: Vec<u8>,
}

/// A mission's CNA inputs in the order the engine produced them, and what the engine decided.
#[derive(Debug, Clone)]
pub struct Recorded {
    pub messages: Vec<WorldMessage>,
    /// Per decision: its index and the engine policy's command.
    pub commands: Vec<(u64, CnaCommand)>,
    /// The engine policy's tally at the end.
    pub stats: Option<PlannerStats>,
    pub result: RunResult,
}

#[derive(Default)]
struct Log {
    messages: Vec<WorldMessage>,
    commands: Vec<(u64, CnaCommand)>,
}

type SharedLog = Arc<Mutex<Log>>;

fn push(log: &SharedLog, channel: &str, payload: Vec<u8>) {
    log.lock().expect("log lock").messages.push(WorldMessage { channel: channel.to_string(), payload });
}

/// The scenario's policy, logging what the CNA knew at each decision (its fix, the clock) and
/// what it chose.
struct Recorder {
    inner: Policy,
    log: SharedLog,
    schema: Schema,
    channels: CnaChannels,
    sc: Scenario,
}

impl CnaPolicy for Recorder {
    fn name(&self) -> &'static str {
        match &self.inner {
            Policy::Planner(p) => p.name(),
            Policy::Baseline(b) => b.name(),
        }
    }
    fn transmits(&self) -> bool {
        match &self.inner {
            Policy::Planner(p) => p.transmits(),
            Policy::Baseline(b) => b.transmits(),
        }
    }
    fn decide(&mut self, ctx: &PolicyContext) -> CnaCommand {
        let m = decision_index(ctx.t, ctx.tau);
        let fix = fix_message(&self.sc, ctx).encode(&self.schema).expect("a fix encodes");
        let clock = clock_message(m, ctx.t, ctx.tau).encode(&self.schema).expect("a clock encodes");
        push(&self.log, &self.channels.fix, fix);
        push(&self.log, &self.channels.clock, clock);
        let command = self.inner.as_policy().decide(ctx);
        self.log.lock().expect("log lock").commands.push((m, command));
        command
    }
    fn planner_stats(&self) -> Option<PlannerStats> {
        self.inner.planner_stats()
    }
}

/// Logs every status the CNA's modem received.
struct StatusTap {
    log: SharedLog,
    schema: Schema,
    channel: String,
}

impl Observer for StatusTap {
    fn on_cna_status(&mut self, heard: &CnaStatusHeard) {
        let payload = status_message(heard).encode(&self.schema).expect("a status frame encodes");
        push(&self.log, &self.channel, payload);
    }
}

/// Runs scenario `sc` with policy `policy` (a registry name) at its seed and records the CNA's
/// inputs and the engine's decisions.
pub fn record(sc: &Scenario, policy: &str) -> Result<Recorded, LiveError> {
    let log = SharedLog::default();
    let channels = CnaChannels::default();
    let inner = PolicySpec::new(policy, sc)?.build(sc)?;
    let recorder = Recorder { inner, log: log.clone(), schema: Schema::coopnav(), channels, sc: sc.clone() };
    let mut tap = StatusTap { log: log.clone(), schema: Schema::coopnav(), channel: CnaChannels::default().status };
    let mut policy = Policy::Baseline(Box::new(recorder));
    let result = metrics::run(sc, &mut policy, sc.seed, &Faults::default(), &mut tap);
    let stats = policy.planner_stats();
    drop(policy);
    let log = std::mem::take(&mut *log.lock().expect("log lock"));
    Ok(Recorded { messages: log.messages, commands: log.commands, stats, result })
}
