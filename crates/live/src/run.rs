//! The live processes' loops on LCM UDP multicast. [`run_auv`] runs an [`AuvNavigator`]:
//! subscribes to AUV K's sensors and range channels, hands every message to the navigator and
//! publishes its estimates. [`run_cna`] runs a [`CnaPlanner`]: subscribes to the CNA's fix and
//! status channels (and, on the bus clock, the world's clock), and publishes a command and a
//! decision record whenever a decision falls due — on the system clock, checked at least every
//! 100 ms and at each due time; on the bus clock, at the clock message that reaches it. With a log
//! path, each writes everything received and published to an LCM log (lcm-logger's format,
//! coopnav-lcm's [`LogWriter`]; received events stamped with their arrival time, published ones
//! with their send time, both microseconds since the epoch).
//!
//! Each stops when the stop flag is set (the CLI sets it on SIGINT/SIGTERM), after `duration`, or
//! after `until_idle` without a message on its channels, and the CNA also when the world's clock
//! says it stopped; the navigator then applies what its reorder buffer still holds and publishes
//! those estimates; the log is flushed, and a summary returned with the counts and the process's
//! CPU time (getrusage, user + system).

use crate::auv::{AuvNavigator, Counts, LiveError, Published};
use crate::cna::{CnaCounts, CnaPlanner, Outgoing};
use coopnav_lcm::{LogWriter, Udpm};
use serde::Serialize;
use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

/// How the process runs and when it stops.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Print one line on stderr once subscribed (`listening: ...`), so a supervisor (or a test)
    /// knows when publishing to it starts to count.
    pub announce: bool,
    pub url: String,
    pub log: Option<PathBuf>,
    pub duration: Option<Duration>,
    pub until_idle: Option<Duration>,
    /// Set from outside (a signal handler) to stop.
    pub stop: Arc<AtomicBool>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    Signal,
    Duration,
    Idle,
    /// The world's clock said it stopped (`clock_t.running` false).
    ClockStopped,
}

/// The one-line summary printed at exit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunSummary {
    pub auv: i16,
    pub stopped_by: StopReason,
    #[serde(flatten)]
    pub counts: Counts,
    /// Datagrams the transport dropped as malformed, and messages it could not reassemble.
    pub bad_datagrams: u64,
    pub dropped_fragments: u64,
    pub log_events: u64,
    pub wall_s: f64,
    /// User + system CPU time of the whole process (s).
    pub cpu_s: f64,
}

fn now_utime() -> i64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_micros() as i64)
}

/// This process's user + system CPU time (s).
pub fn cpu_time_s() -> f64 {
    // SAFETY: getrusage writes the struct it is given and nothing else.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) } != 0 {
        return f64::NAN;
    }
    let s = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    s(u.ru_utime) + s(u.ru_stime)
}

struct Log {
    path: String,
    writer: LogWriter<BufWriter<File>>,
    events: u64,
}

impl Log {
    fn write(&mut self, utime: i64, channel: &str, data: &[u8]) -> Result<(), LiveError> {
        self.writer.write(utime, channel, data).map_err(|source| LiveError::Log { path: self.path.clone(), source })?;
        self.events += 1;
        Ok(())
    }
}

/// Where the live CNA's time comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ClockSource {
    /// The machine's clock (synchronised to the AUVs' by GPS/PPS at sea).
    System,
    /// The world's `clock_t` messages (software in the loop).
    Bus,
}

/// The live CNA's one-line summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CnaRunSummary {
    pub policy: &'static str,
    pub clock: ClockSource,
    pub stopped_by: StopReason,
    #[serde(flatten)]
    pub counts: CnaCounts,
    pub bad_datagrams: u64,
    pub dropped_fragments: u64,
    pub log_events: u64,
    pub wall_s: f64,
    pub cpu_s: f64,
}

fn open_log(path: &Option<PathBuf>) -> Result<Option<Log>, LiveError> {
    let Some(path) = path else { return Ok(None) };
    let path_text = path.display().to_string();
    let file = File::create(path).map_err(|e| LiveError::Log { path: path_text.clone(), source: e.into() })?;
    Ok(Some(Log { path: path_text, writer: LogWriter::new(BufWriter::new(file)), events: 0 }))
}

fn close_log(log: Option<Log>) -> Result<u64, LiveError> {
    match log {
        Some(Log { path, writer, events }) => {
            writer.into_inner().map_err(|source| LiveError::Log { path, source })?;
            Ok(events)
        }
        None => Ok(0),
    }
}

/// When the loop stops, from the options and the time of its last input.
fn stop_reason(opts: &RunOptions, start: Instant, last_input: Instant) -> Option<StopReason> {
    let now = Instant::now();
    if opts.stop.load(Ordering::SeqCst) {
        Some(StopReason::Signal)
    } else if opts.duration.is_some_and(|d| now.duration_since(start) >= d) {
        Some(StopReason::Duration)
    } else if opts.until_idle.is_some_and(|d| now.duration_since(last_input) >= d) {
        Some(StopReason::Idle)
    } else {
        None
    }
}

/// How long the loop may wait for a message: at most 100 ms (to see the stop flag), and not
/// past a deadline.
fn wait_budget(opts: &RunOptions, start: Instant, last_input: Instant) -> Duration {
    let mut wait = Duration::from_millis(100);
    if let Some(d) = opts.duration {
        wait = wait.min(d.saturating_sub(start.elapsed()));
    }
    if let Some(d) = opts.until_idle {
        wait = wait.min(d.saturating_sub(last_input.elapsed()));
    }
    wait
}

/// Runs `cna` on the transport until a stop condition; see the module doc.
pub fn run_cna(mut cna: CnaPlanner, opts: &RunOptions, clock: ClockSource) -> Result<CnaRunSummary, LiveError> {
    let start = Instant::now();
    let mut lcm = Udpm::new(&opts.url)?;
    let ch = cna.channels().clone();
    lcm.subscribe(&ch.fix)?;
    lcm.subscribe(&ch.status)?;
    if clock == ClockSource::Bus {
        lcm.subscribe(&ch.clock)?;
    }
    if opts.announce {
        eprintln!(
            "listening: CNA ({}) on {} ({}, {}{}) publishing {}, {}",
            cna.policy_name(),
            opts.url,
            ch.fix,
            ch.status,
            if clock == ClockSource::Bus { format!(", {}", ch.clock) } else { String::new() },
            ch.command,
            ch.decision
        );
    }
    let mut log = open_log(&opts.log)?;
    let publish = |lcm: &mut Udpm, log: &mut Option<Log>, out: Vec<Outgoing>| -> Result<(), LiveError> {
        for o in out {
            lcm.publish(&o.channel, &o.payload)?;
            if let Some(log) = log.as_mut() {
                log.write(now_utime(), &o.channel, &o.payload)?;
            }
        }
        Ok(())
    };
    let mut last_input = Instant::now();
    let stopped_by = loop {
        if let Some(reason) = stop_reason(opts, start, last_input) {
            break reason;
        }
        if cna.clock_stopped() {
            break StopReason::ClockStopped;
        }
        let mut wait = wait_budget(opts, start, last_input);
        if clock == ClockSource::System {
            let due = cna.due_utime(cna.next_decision());
            let to_due = Duration::from_micros(due.saturating_sub(now_utime()).max(0) as u64);
            wait = wait.min(to_due);
        }
        if let Some(msg) = lcm.recv_timeout(wait)? {
            last_input = Instant::now();
            if let Some(log) = log.as_mut() {
                log.write(msg.recv_utime, &msg.channel, &msg.data)?;
            }
            let out = cna.handle(&msg.channel, &msg.data)?;
            publish(&mut lcm, &mut log, out)?;
        }
        if clock == ClockSource::System {
            let out = cna.tick(now_utime())?;
            publish(&mut lcm, &mut log, out)?;
        }
    };
    Ok(CnaRunSummary {
        policy: cna.policy_name(),
        clock,
        stopped_by,
        counts: cna.counts().clone(),
        bad_datagrams: lcm.bad_datagrams(),
        dropped_fragments: lcm.dropped_messages(),
        log_events: close_log(log)?,
        wall_s: start.elapsed().as_secs_f64(),
        cpu_s: cpu_time_s(),
    })
}

/// Runs `nav` on the transport until a stop condition; see the module doc.
pub fn run_auv(mut nav: AuvNavigator, opts: &RunOptions) -> Result<RunSummary, LiveError> {
    let start = Instant::now();
    let mut lcm = Udpm::new(&opts.url)?;
    let channels = nav.channels().clone();
    lcm.subscribe(&channels.sensors)?;
    lcm.subscribe(&channels.range)?;
    if opts.announce {
        eprintln!(
            "listening: AUV {} on {} ({}, {}) publishing {}",
            nav.auv(),
            opts.url,
            channels.sensors,
            channels.range,
            channels.estimate
        );
    }
    let mut log = open_log(&opts.log)?;
    let publish = |lcm: &mut Udpm, log: &mut Option<Log>, out: Vec<Published>| -> Result<(), LiveError> {
        for p in out {
            lcm.publish(&channels.estimate, &p.payload)?;
            if let Some(log) = log.as_mut() {
                log.write(now_utime(), &channels.estimate, &p.payload)?;
            }
        }
        Ok(())
    };
    let mut last_input = Instant::now();
    let stopped_by = loop {
        if let Some(reason) = stop_reason(opts, start, last_input) {
            break reason;
        }
        let wait = wait_budget(opts, start, last_input);
        let Some(msg) = lcm.recv_timeout(wait)? else { continue };
        last_input = Instant::now();
        if let Some(log) = log.as_mut() {
            log.write(msg.recv_utime, &msg.channel, &msg.data)?;
        }
        let out = nav.handle(&msg.channel, &msg.data)?;
        publish(&mut lcm, &mut log, out)?;
    };
    let out = nav.flush()?;
    publish(&mut lcm, &mut log, out)?;
    let log_events = close_log(log)?;
    Ok(RunSummary {
        auv: nav.auv(),
        stopped_by,
        counts: nav.counts().clone(),
        bad_datagrams: lcm.bad_datagrams(),
        dropped_fragments: lcm.dropped_messages(),
        log_events,
        wall_s: start.elapsed().as_secs_f64(),
        cpu_s: cpu_time_s(),
    })
}
