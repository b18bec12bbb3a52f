//! The live process around an [`AuvNavigator`]: subscribes on LCM UDP multicast to AUV K's
//! sensors and range channels, hands every message to the navigator, publishes its estimates,
//! and, with a log path, writes everything received and published to an LCM log (lcm-logger's
//! format, coopnav-lcm's [`LogWriter`]; received events stamped with their arrival time,
//! published ones with their send time, both microseconds since the epoch).
//!
//! It stops when the stop flag is set (the CLI sets it on SIGINT/SIGTERM), after `duration`, or
//! after `until_idle` without a message on its channels; then it applies what the reorder buffer
//! still holds, publishes those estimates, flushes the log, and returns a [`RunSummary`] with the
//! navigator's counts and the process's CPU time (getrusage, user + system).

use crate::auv::{AuvNavigator, Counts, LiveError, Published};
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
    let mut log = match &opts.log {
        Some(path) => {
            let path_text = path.display().to_string();
            let file = File::create(path).map_err(|e| LiveError::Log { path: path_text.clone(), source: e.into() })?;
            Some(Log { path: path_text, writer: LogWriter::new(BufWriter::new(file)), events: 0 })
        }
        None => None,
    };
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
        if opts.stop.load(Ordering::SeqCst) {
            break StopReason::Signal;
        }
        let now = Instant::now();
        if opts.duration.is_some_and(|d| now.duration_since(start) >= d) {
            break StopReason::Duration;
        }
        if opts.until_idle.is_some_and(|d| now.duration_since(last_input) >= d) {
            break StopReason::Idle;
        }
        // Wake at least every 100 ms to see the stop flag and the deadlines.
        let mut wait = Duration::from_millis(100);
        if let Some(d) = opts.duration {
            wait = wait.min(d.saturating_sub(now.duration_since(start)));
        }
        if let Some(d) = opts.until_idle {
            wait = wait.min(d.saturating_sub(now.duration_since(last_input)));
        }
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
    let log_events = match log {
        Some(log) => {
            let Log { path, writer, events } = log;
            writer.into_inner().map_err(|source| LiveError::Log { path, source })?;
            events
        }
        None => 0,
    };
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
