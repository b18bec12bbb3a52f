//! Software in the loop, in lockstep: the engine is the world, and the CNA's planner runs outside
//! it as a `coopnav live cna` child process on the bus. Every status the CNA's modem receives
//! (the engine's `on_cna_status` hook) is published on `COOPNAV_CNA_STATUS`; at each decision the
//! world publishes the CNA's fix (`COOPNAV_CNA_FIX`) and its clock (`COOPNAV_CLOCK`), then waits
//! for the child's command and decision record of that decision and steers the CNA by the
//! command. The engine's policy call is the [`RemoteCna`] policy: a plug-in like any other,
//! returning the command the child gave (the engine is not told it is remote).
//!
//! The world checks that the child decided on what it was sent: the record's fix time and its
//! count of statuses applied must be the world's, else the decision is counted in
//! `input_mismatches`. A child that does not answer within the timeout has stopped commanding:
//! the CNA holds its last command, counted in `missed_decisions` and logged. With equal inputs
//! the child's policy is the engine's own code on the same values, so the run's results equal
//! `coopnav simulate`'s with the same seed (the tests compare the run directories).

use crate::auv::LiveError;
use crate::cna::CnaChannels;
use crate::world::{clock_message, decision_index, fix_message, status_message, utime};
use coopnav_core::Vec3;
use coopnav_lcm::messages::{Clock, CnaCommand as CommandMsg, Decision, Message};
use coopnav_lcm::{Schema, Udpm};
use coopnav_sim::engine::{self, CnaStatusHeard, CommsEvent, Faults, Observer, Trace, TraceRow};
use coopnav_sim::observe::metrics::{self, RunResult};
use coopnav_sim::policy::{CnaCommand, CnaPolicy, PlannerStats, Policy, PolicyContext, PolicySpec};
use coopnav_sim::scenario::Scenario;
use serde::Serialize;
use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Command, Stdio};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// How the world runs its child and waits for it.
#[derive(Debug, Clone)]
pub struct SitlOptions {
    pub url: String,
    /// The child: a program and its arguments (`coopnav live cna FILE --clock bus --url URL ...`).
    pub child: Vec<String>,
    /// How long the world waits for one decision before holding the last command.
    pub decision_timeout: Duration,
}

/// What the world saw of its child.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct WorldCounts {
    pub decisions: u64,
    pub statuses_published: u64,
    /// Decisions the child did not answer in time: the CNA held its last command.
    pub missed_decisions: u64,
    /// Decisions whose record shows another fix or another count of statuses than sent.
    pub input_mismatches: u64,
    /// Commands and records that arrived for another decision than the one awaited.
    pub stray_messages: u64,
}

/// A lockstep run: the engine's result and the world's account of its child.
#[derive(Debug, Clone)]
pub struct SitlRun {
    pub result: RunResult,
    pub counts: WorldCounts,
    /// The child's one-line JSON summary, when it printed one.
    pub child_summary: Option<serde_json::Value>,
}

struct Bus {
    lcm: Udpm,
    schema: Schema,
    channels: CnaChannels,
}

impl Bus {
    fn publish(&mut self, channel: &str, payload: &[u8]) {
        if let Err(e) = self.lcm.publish(channel, payload) {
            tracing::error!(channel, error = %e, "publishing to the CNA failed");
        }
    }
}

/// The engine's policy call answered by the child on the bus (see the module doc).
pub struct RemoteCna {
    name: &'static str,
    transmits: bool,
    planner: bool,
    sc: Scenario,
    bus: Arc<Mutex<Bus>>,
    pending: Arc<Mutex<Vec<Vec<u8>>>>,
    counts: Arc<Mutex<WorldCounts>>,
    timeout: Duration,
    last: CnaCommand,
    stats: Option<PlannerStats>,
}

impl RemoteCna {
    /// Waits for the child's command and record of decision `seq`.
    fn await_decision(&self, bus: &mut Bus, seq: i64) -> Option<(CommandMsg, Decision)> {
        let deadline = Instant::now() + self.timeout;
        let (mut command, mut record) = (None, None);
        loop {
            if let (Some(c), Some(d)) = (command, record.clone()) {
                return Some((c, d));
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return None;
            }
            let msg = match bus.lcm.recv_timeout(left) {
                Ok(Some(m)) => m,
                Ok(None) => continue,
                Err(e) => {
                    tracing::error!(error = %e, "receiving from the CNA failed");
                    return None;
                }
            };
            let stray = if msg.channel == bus.channels.command {
                match CommandMsg::decode(&bus.schema, &msg.data) {
                    Ok(c) if c.seq == seq => {
                        command = Some(c);
                        false
                    }
                    _ => true,
                }
            } else if msg.channel == bus.channels.decision {
                match Decision::decode(&bus.schema, &msg.data) {
                    Ok(d) if d.seq == seq => {
                        record = Some(d);
                        false
                    }
                    _ => true,
                }
            } else {
                false
            };
            if stray {
                self.counts.lock().expect("counts").stray_messages += 1;
            }
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
        let bus = self.bus.clone();
        let mut bus = bus.lock().expect("bus");
        let pending = std::mem::take(&mut *self.pending.lock().expect("pending"));
        let status = bus.channels.status.clone();
        for payload in &pending {
            bus.publish(&status, payload);
        }
        let fix = fix_message(&self.sc, ctx);
        let (fix_payload, clock) = (fix.encode(&bus.schema), clock_message(m, ctx.t, ctx.tau).encode(&bus.schema));
        let (Ok(fix_payload), Ok(clock)) = (fix_payload, clock) else {
            tracing::error!(decision = m, "the fix or clock does not encode: the CNA holds its last command");
            return self.last;
        };
        let (fix_channel, clock_channel) = (bus.channels.fix.clone(), bus.channels.clock.clone());
        bus.publish(&fix_channel, &fix_payload);
        bus.publish(&clock_channel, &clock);
        let answer = self.await_decision(&mut bus, m as i64);
        let mut counts = self.counts.lock().expect("counts");
        counts.decisions += 1;
        counts.statuses_published += pending.len() as u64;
        let Some((command, record)) = answer else {
            counts.missed_decisions += 1;
            tracing::warn!(decision = m, "the CNA stopped commanding: it holds its last command");
            return self.last;
        };
        if record.fix_utime != utime(ctx.t) || record.n_status as u64 != counts.statuses_published {
            counts.input_mismatches += 1;
            tracing::warn!(decision = m, ?record, "the CNA decided on other inputs than the world sent");
        }
        if self.planner {
            self.stats = Some(stats_of(&record));
        }
        self.last = if command.has_waypoint {
            CnaCommand::GoTo(Vec3::new(command.waypoint_x, command.waypoint_y, command.waypoint_depth))
        } else {
            CnaCommand::Hold
        };
        self.last
    }
    fn planner_stats(&self) -> Option<PlannerStats> {
        self.stats.clone()
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

/// The run's time series (as `simulate` records it), and every status the CNA's modem received,
/// encoded for the bus and kept until the next decision publishes it.
struct WorldObserver {
    trace: Trace,
    pending: Arc<Mutex<Vec<Vec<u8>>>>,
    schema: Schema,
}

impl Observer for WorldObserver {
    fn on_decision(&mut self, decision: &engine::Decision) {
        self.trace.on_decision(decision);
    }
    fn on_sample(&mut self, t: f64, cna: Vec3, rows: &[TraceRow]) {
        self.trace.on_sample(t, cna, rows);
    }
    fn on_packet(&mut self, event: &CommsEvent) {
        self.trace.on_packet(event);
    }
    fn on_cna_status(&mut self, heard: &CnaStatusHeard) {
        match status_message(heard).encode(&self.schema) {
            Ok(payload) => self.pending.lock().expect("pending").push(payload),
            Err(e) => tracing::error!(error = %e, "a received status does not encode for the bus"),
        }
    }
}

/// The child, listening (it announces on stderr once subscribed).
struct ChildCna {
    child: Child,
    stderr: mpsc::Receiver<String>,
}

impl ChildCna {
    fn start(args: &[String]) -> Result<Self, LiveError> {
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
        let mut me = ChildCna { child, stderr: rx };
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match me.stderr.recv_timeout(left) {
                Ok(line) if line.starts_with("listening:") => return Ok(me),
                Ok(line) => eprintln!("live cna: {line}"),
                Err(_) => {
                    me.kill();
                    return Err(LiveError::Child("live cna did not announce that it listens within 30 s".into()));
                }
            }
        }
    }

    fn kill(&mut self) {
        // Child::kill signals this child's own pid (SIGKILL), which is not yet reaped.
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// Waits for its exit (at most `timeout`, then kills it by pid); its summary line.
    fn finish(mut self, timeout: Duration) -> Result<Option<serde_json::Value>, LiveError> {
        let deadline = Instant::now() + timeout;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) => {
                    for line in self.stderr.try_iter() {
                        eprintln!("live cna: {line}");
                    }
                    let mut out = String::new();
                    if let Some(mut stdout) = self.child.stdout.take() {
                        let _ = stdout.read_to_string(&mut out);
                    }
                    if !status.success() {
                        return Err(LiveError::Child(format!("live cna exited with {status}")));
                    }
                    return Ok(serde_json::from_str(out.trim()).ok());
                }
                Ok(None) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(20)),
                _ => {
                    self.kill();
                    return Err(LiveError::Child(format!("live cna did not stop within {timeout:?}: killed")));
                }
            }
        }
    }
}

/// Runs scenario `sc` (its seed) with the child deciding for policy `policy`; see the module doc.
pub fn run_lockstep(sc: &Scenario, policy: &str, opts: &SitlOptions) -> Result<SitlRun, LiveError> {
    let local = PolicySpec::new(policy, sc)?.build(sc)?;
    let (name, transmits, planner) = match &local {
        Policy::Planner(p) => (p.name(), p.transmits(), true),
        Policy::Baseline(b) => (b.name(), b.transmits(), false),
    };
    let channels = CnaChannels::default();
    let mut lcm = Udpm::new(&opts.url)?;
    lcm.subscribe(&channels.command)?;
    lcm.subscribe(&channels.decision)?;
    let bus = Arc::new(Mutex::new(Bus { lcm, schema: Schema::coopnav(), channels }));
    let child = ChildCna::start(&opts.child)?;
    let pending = Arc::new(Mutex::new(Vec::new()));
    let counts = Arc::new(Mutex::new(WorldCounts::default()));
    let remote = RemoteCna {
        name,
        transmits,
        planner,
        sc: sc.clone(),
        bus: bus.clone(),
        pending: pending.clone(),
        counts: counts.clone(),
        timeout: opts.decision_timeout,
        last: CnaCommand::Hold,
        stats: None,
    };
    let mut policy = Policy::Baseline(Box::new(remote));
    let mut obs = WorldObserver { trace: Trace::default(), pending, schema: Schema::coopnav() };
    let mut result = metrics::run(sc, &mut policy, sc.seed, &Faults::default(), &mut obs);
    result.trace = Some(obs.trace);
    {
        let mut bus = bus.lock().expect("bus");
        let stop = Clock { running: false, ..Clock::default() }.encode(&bus.schema)?;
        let clock = bus.channels.clock.clone();
        bus.publish(&clock, &stop);
    }
    let child_summary = child.finish(Duration::from_secs(30))?;
    let counts = counts.lock().expect("counts").clone();
    Ok(SitlRun { result, counts, child_summary })
}
