//! A live navigator's LCM log read back as a post-processing log (docs/log-format.md, version 2,
//! relative time): what `coopnav live auv --auv K --log FILE` received becomes the rows
//! `coopnav hbl postprocess` reads, so a live run is post-processed and viewed unchanged.
//!
//! | logged message (channel of AUV K) | rows |
//! |-----------------------------------|------|
//! | the first `auv_sensors_t`          | `init` at its time: the config's `[start]`, its speed and compass heading |
//! | every `auv_sensors_t`              | `speed`, `heading` (compass deg), `depth` at its time |
//! | `owtt_range_t`                     | `beacon_fix` of beacon `src` at its transmit time (its transponder), `range` at its receive time |
//! | `auv_estimate_t` (published)       | kept apart: the live estimates ([`Imported::estimates`]) |
//!
//! and, when the caller has them, `truth` rows (the world's truth once a second). A range's
//! beacon id is its `src` plus 128 (an id is unsigned; `src` is a signed byte). The navigator
//! starts its filter on the first sensors message and holds the heading rate at zero, as
//! post-processing does on a log without `yaw_rate` rows; so the forward pass over these rows is
//! the live navigator's filter (the reorder buffer, in time order, is the log's own ordering).
//! Payloads that do not decode, sensors of another AUV and repeated payloads (the navigator
//! counted and dropped them) are left out and counted.
//!
//! All the live processes' logs together ([`LiveRecord`], the CNA's and every navigator's) become
//! a run as the MOOS tools see it ([`run_alog`]: `coopnav live import` writes it as `run.alog`).

use crate::auv::{Channels, LiveError, Start};
use crate::cna::CnaChannels;
use coopnav_lcm::messages::{AuvEstimate, AuvSensors, CnaCommand, CnaFix, Decision, Message, OwttRange, StatusFrame};
use coopnav_lcm::{LogReader, Schema};
use coopnav_moos::{Leg, Posting, Pulse, PulseKind, Role, RunLog, Sample, Vehicle, SIMULATED_LOG_START};
use serde::Serialize;
use std::collections::{BTreeMap, HashSet};
use std::fmt::Write as _;
use std::io::Read;

/// A navigator's log as rows, its published estimates and what was left out.
#[derive(Debug, Clone, Default)]
pub struct Imported {
    /// The post-processing log's text.
    pub log: String,
    pub sensors: u64,
    pub ranges: u64,
    pub estimates: Vec<AuvEstimate>,
    /// Payloads that do not decode, of another AUV, or repeated.
    pub left_out: u64,
}

/// The beacon id of a range's `src`.
pub fn beacon_id(src: i8) -> u32 {
    (i32::from(src) + 128) as u32
}

/// Reads the LCM log `input` of AUV `auv`'s navigator, started at `start`; `truth`: (t, e, n)
/// rows to add.
pub fn field_log(input: impl Read, auv: i16, start: Start, truth: &[(f64, f64, f64)]) -> Result<Imported, LiveError> {
    let schema = Schema::coopnav();
    let ch = Channels::for_auv(auv);
    let mut out = Imported::default();
    let mut rows: Vec<(f64, String)> = Vec::new();
    let mut seen = HashSet::new();
    let mut started = false;
    for event in LogReader::new(input) {
        let event = event.map_err(|source| LiveError::Log { path: format!("LCM log of AUV {auv}"), source })?;
        let fresh = seen.insert((event.channel.clone(), event.data.clone()));
        if event.channel == ch.sensors {
            match AuvSensors::decode(&schema, &event.data) {
                Ok(s) if fresh && s.auv == auv => {
                    let t = s.utime as f64 / 1e6;
                    let compass = s.heading.to_degrees();
                    let speed = f64::from(s.speed);
                    if !started {
                        started = true;
                        rows.push((t, format!("{t},init,,{},{},{speed},{compass},", start.e, start.n)));
                    }
                    rows.push((t, format!("{t},speed,,{speed},,,,")));
                    rows.push((t, format!("{t},heading,,{compass},,,,")));
                    rows.push((t, format!("{t},depth,,{},,,,", f64::from(s.depth))));
                    out.sensors += 1;
                }
                _ => out.left_out += 1,
            }
        } else if event.channel == ch.range {
            match OwttRange::decode(&schema, &event.data) {
                Ok(r) if fresh => {
                    let id = beacon_id(r.src);
                    let p = r.transponder;
                    rows.push((
                        r.transmit_time,
                        format!("{},beacon_fix,{id},{},{},{},,", r.transmit_time, p.x, p.y, p.z),
                    ));
                    rows.push((r.receive_time, format!("{},range,{id},{},,,,", r.receive_time, r.travel_time)));
                    out.ranges += 1;
                }
                _ => out.left_out += 1,
            }
        } else if event.channel == ch.estimate {
            if let Ok(e) = AuvEstimate::decode(&schema, &event.data) {
                out.estimates.push(e);
            }
        }
    }
    for &(t, e, n) in truth {
        rows.push((t, format!("{t},truth,,{e},{n},,,")));
    }
    // Time order, stably: rows of one time keep the order they were read in (init first).
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut log = String::from("# coopnav-log 2 time=relative\nt,kind,src,v1,v2,v3,v4,sigma\n");
    for (_, row) in rows {
        let _ = writeln!(log, "{row}");
    }
    out.log = log;
    Ok(out)
}

/// The alog variables of the CNA's messages that the run mapping (`coopnav_moos::export`) has no
/// place for, named as their LCM channels.
pub const COMMAND_VARIABLE: &str = "COOPNAV_CNA_COMMAND";
pub const DECISION_VARIABLE: &str = "COOPNAV_CNA_DECISION";

/// A bus time (s) at or after this is a Unix time (a vehicle's clock), before it a mission time
/// from epoch 0 (the software-in-the-loop world's clock): 2001-09-09T01:46:40Z, a format choice
/// (no mission lasts 31 years, no vehicle's clock reads before 2001).
const UNIX_TIME_FROM_S: f64 = 1e9;

/// The `owtt_range_t` `src` of the CNA's ranging broadcasts, as the software-in-the-loop world
/// sends them (buoy b is 100 + b).
pub const CNA_RANGE_SRC: i8 = -1;

/// Every coopnav message of a live run's LCM logs, decoded once, in log order.
#[derive(Debug, Clone, Default)]
pub struct LiveRecord {
    /// What the CNA's planner received (its fixes, the statuses its modem heard) and published.
    pub fixes: Vec<CnaFix>,
    pub statuses: Vec<StatusFrame>,
    pub commands: Vec<CnaCommand>,
    pub decisions: Vec<Decision>,
    /// Per survey AUV (the channels' K): what its navigator received and published.
    pub auvs: BTreeMap<i16, AuvRecord>,
    pub counts: RecordCounts,
    seen: HashSet<(String, Vec<u8>)>,
}

/// What was read and what was left out: nothing is dropped without being counted.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct RecordCounts {
    /// Events read, over all logs.
    pub events: u64,
    /// Events repeating a (channel, payload) already read (in this log or another), left out.
    pub repeated: u64,
    /// Events on a coopnav channel whose payload does not decode as its type, left out.
    pub undecodable: u64,
    /// Sensors or estimates whose `auv` is not their channel's K, left out.
    pub other_auv: u64,
    /// Events on channels the import does not read (COOPNAV_CLOCK among them).
    pub other_channels: u64,
}

/// One survey AUV's messages.
#[derive(Debug, Clone, Default)]
pub struct AuvRecord {
    pub sensors: Vec<AuvSensors>,
    pub ranges: Vec<OwttRange>,
    pub estimates: Vec<AuvEstimate>,
}

/// The K of a `COOPNAV_AUV{K}_{SUFFIX}` channel.
fn auv_of(channel: &str, suffix: &str) -> Option<i16> {
    channel.strip_prefix("COOPNAV_AUV")?.strip_suffix(suffix)?.parse().ok()
}

impl LiveRecord {
    /// Adds the events of one LCM log; `name` is how errors name it.
    pub fn read(&mut self, input: impl Read, name: &str) -> Result<(), LiveError> {
        let schema = Schema::coopnav();
        let cna = CnaChannels::default();
        for event in LogReader::new(input) {
            let event = event.map_err(|source| LiveError::Log { path: name.to_string(), source })?;
            self.counts.events += 1;
            let (channel, data) = (event.channel, event.data);
            if !self.seen.insert((channel.clone(), data.clone())) {
                self.counts.repeated += 1;
                continue;
            }
            let decoded = if channel == cna.fix {
                CnaFix::decode(&schema, &data).map(|m| self.fixes.push(m))
            } else if channel == cna.status {
                StatusFrame::decode(&schema, &data).map(|m| self.statuses.push(m))
            } else if channel == cna.command {
                CnaCommand::decode(&schema, &data).map(|m| self.commands.push(m))
            } else if channel == cna.decision {
                Decision::decode(&schema, &data).map(|m| self.decisions.push(m))
            } else if let Some(k) = auv_of(&channel, "_SENSORS") {
                AuvSensors::decode(&schema, &data).map(|m| self.auv_message(k, m.auv, |a| a.sensors.push(m)))
            } else if let Some(k) = auv_of(&channel, "_RANGE") {
                OwttRange::decode(&schema, &data).map(|m| self.auvs.entry(k).or_default().ranges.push(m))
            } else if let Some(k) = auv_of(&channel, "_ESTIMATE") {
                AuvEstimate::decode(&schema, &data).map(|m| self.auv_message(k, m.auv, |a| a.estimates.push(m)))
            } else {
                self.counts.other_channels += 1;
                continue;
            };
            self.counts.undecodable += u64::from(decoded.is_err());
        }
        Ok(())
    }

    fn auv_message(&mut self, k: i16, auv: i16, add: impl FnOnce(&mut AuvRecord)) {
        if auv == k {
            add(self.auvs.entry(k).or_default());
        } else {
            self.counts.other_auv += 1;
        }
    }

    /// The earliest bus time of any message, s.
    fn first_time(&self) -> Option<f64> {
        let fixes = self.fixes.iter().map(|m| m.utime);
        let statuses = self.statuses.iter().map(|m| m.utime);
        let commands = self.commands.iter().map(|m| m.utime);
        let decisions = self.decisions.iter().map(|m| m.utime);
        let auvs = self.auvs.values().flat_map(|a| {
            let sensors = a.sensors.iter().map(|m| m.utime);
            sensors.chain(a.ranges.iter().map(|m| utime(m.transmit_time))).chain(a.estimates.iter().map(|m| m.utime))
        });
        fixes.chain(statuses).chain(commands).chain(decisions).chain(auvs).min().map(|u| u as f64 / 1e6)
    }

    /// The Unix time (s) the run's alog counts from: the first message's whole second when the
    /// bus carried Unix times, else the simulated runs' log start (the bus carried mission time).
    pub fn log_start(&self) -> f64 {
        match self.first_time() {
            Some(t) if t >= UNIX_TIME_FROM_S => t.floor(),
            _ => SIMULATED_LOG_START,
        }
    }
}

fn utime(t: f64) -> i64 {
    (t * 1e6).round() as i64
}

/// A survey AUV's true track, (t, x, y, depth) in mission seconds, when a simulated world has one.
pub type TruthTrack = Vec<(f64, f64, f64, f64)>;

/// The truth of every survey AUV in a run directory's `timeseries.csv` (columns `t`, `auv`,
/// `true_x`, `true_y`, `true_z`); `name` is how errors name the file.
pub fn truth_from_timeseries(text: &str, name: &str) -> Result<BTreeMap<i16, TruthTrack>, LiveError> {
    let bad = |line: usize, what: String| LiveError::Truth { path: name.to_string(), line, what };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().ok_or_else(|| bad(1, "the file is empty".into()))?.split(',').collect();
    let column = |c: &str| {
        header
            .iter()
            .position(|h| *h == c)
            .ok_or_else(|| bad(1, format!("no column {c} (a timeseries.csv has t, auv, true_x, true_y, true_z)")))
    };
    let cols = [column("t")?, column("auv")?, column("true_x")?, column("true_y")?, column("true_z")?];
    let mut out: BTreeMap<i16, TruthTrack> = BTreeMap::new();
    for (i, line) in lines.enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        let mut v = [0.0; 5];
        for (slot, &c) in v.iter_mut().zip(&cols) {
            let text = fields.get(c).copied().unwrap_or("");
            *slot = text
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| bad(i + 2, format!("column {} is {text:?}, not a finite number", header[c])))?;
        }
        let auv = i16::try_from(v[1] as i64).map_err(|_| bad(i + 2, format!("auv {} is not an AUV id", v[1])))?;
        out.entry(auv).or_default().push((v[0], v[2], v[3], v[4]));
    }
    Ok(out)
}

/// The name of survey AUV `k`'s vehicles in the alog, as simulate's alog names them.
fn auv_name(k: i16) -> String {
    format!("auv{k}")
}

/// A live run as an alog: the [`RunLog`] (tracks, pulses, legs) and the CNA's commands and
/// decisions as [`Posting`]s.
#[derive(Debug, Clone)]
pub struct ImportedRun {
    pub run: RunLog,
    pub postings: Vec<Posting>,
    pub log_start: f64,
    /// Pulses left out because a vehicle they join has no track in the logs (a status of an AUV
    /// whose navigator's log was not given, a range to an AUV without estimates).
    pub pulses_without_track: u64,
    /// Legs left out because no CNA track was there to start them from.
    pub legs_without_track: u64,
}

/// The run of `record`, mapped as follows.
///
/// | LCM message | alog |
/// |---|---|
/// | `auv_estimate_t` (valid) of AUV K | NODE_REPORT of `auvK_est` (GROUP estimate, NAV_SD, NAV_PEE/PEN/PNN), depth the latest `auv_sensors_t` depth |
/// | truth rows of AUV K (only with `truth`) | NODE_REPORT of `auvK` (GROUP truth) |
/// | `cna_fix_t` | NODE_REPORT of `cna` (a GPS fix is a ship at depth 0, a dead-reckoned fix an AUV at its depth) |
/// | `owtt_range_t` to AUV K | VIEW_RANGE_PULSE at its transmit time from the CNA (`src` −1) or `beaconI` (I = src + 128, its transponder positions as its track), received |
/// | `status_frame_t` from AUV K | VIEW_COMMS_PULSE at its receive time from `auvK` to `cna`, received |
/// | `cna_command_t` with a waypoint | VIEW_SEGLIST from the CNA's position at its time to the waypoint; every command also as COOPNAV_CNA_COMMAND |
/// | `decision_t` | COOPNAV_CNA_DECISION |
///
/// Without truth the AUVs' pulses join their estimates (`auvK_est`), and COOPNAV_SCENARIO says
/// that the run has no truth.
pub fn run_alog(record: &LiveRecord, truth: Option<&BTreeMap<i16, TruthTrack>>, sources: &str) -> ImportedRun {
    let log_start = record.log_start();
    let t_of = |utime: i64| utime as f64 / 1e6 - if log_start == SIMULATED_LOG_START { 0.0 } else { log_start };
    let s_of = |t: f64| t - if log_start == SIMULATED_LOG_START { 0.0 } else { log_start };
    let mut vehicles = Vec::new();
    let sample = |t: f64, x: f64, y: f64, depth: f64| Sample { t, x, y, depth, sd: None, cov: None };
    for (&k, a) in &record.auvs {
        if let Some(track) = truth.and_then(|tr| tr.get(&k)) {
            let samples = track.iter().map(|&(t, x, y, z)| sample(t, x, y, z)).collect();
            vehicles.push(Vehicle { name: auv_name(k), role: Role::Truth, kind: "auv", samples });
        }
        let mut depths: Vec<(i64, f64)> = a.sensors.iter().map(|s| (s.utime, f64::from(s.depth))).collect();
        depths.sort_by_key(|d| d.0);
        let mut samples: Vec<Sample> = a
            .estimates
            .iter()
            .filter(|e| e.valid)
            .map(|e| {
                let depth = depths.partition_point(|d| d.0 <= e.utime).checked_sub(1).map_or(0.0, |i| depths[i].1);
                let [[ee, en], [_, nn]] = e.cov;
                Sample { sd: Some((ee + nn).sqrt()), cov: Some([ee, en, nn]), ..sample(t_of(e.utime), e.x, e.y, depth) }
            })
            .collect();
        samples.sort_by(|p, q| p.t.total_cmp(&q.t));
        samples.dedup_by(|p, q| p.t == q.t);
        if !samples.is_empty() {
            vehicles.push(Vehicle { name: format!("{}_est", auv_name(k)), role: Role::Estimate, kind: "auv", samples });
        }
    }
    let mut fixes: Vec<&CnaFix> = record.fixes.iter().collect();
    fixes.sort_by_key(|f| f.utime);
    let auv_cna = fixes.iter().any(|f| f.source == CnaFix::SOURCE_DEAD_RECKONING);
    let mut cna: Vec<Sample> = fixes
        .iter()
        .map(|f| sample(t_of(f.utime), f.x, f.y, if f.source == CnaFix::SOURCE_DEAD_RECKONING { f.depth } else { 0.0 }))
        .collect();
    cna.dedup_by(|p, q| p.t == q.t);
    // Transmitters other than a CNA with fixes: their track is where the ranges put their
    // transponder.
    let mut transmitters: BTreeMap<String, Vec<Sample>> = BTreeMap::new();
    let sender = |src: i8| if src == CNA_RANGE_SRC { "cna".to_string() } else { format!("beacon{}", beacon_id(src)) };
    for a in record.auvs.values() {
        for r in &a.ranges {
            let name = sender(r.src);
            if name == "cna" && !cna.is_empty() {
                continue;
            }
            let p = r.transponder;
            transmitters.entry(name).or_default().push(sample(s_of(r.transmit_time), p.x, p.y, p.z));
        }
    }
    let has_cna_track = !cna.is_empty() || transmitters.contains_key("cna");
    if !cna.is_empty() {
        vehicles.push(Vehicle {
            name: "cna".into(),
            role: Role::Cna,
            kind: if auv_cna { "auv" } else { "ship" },
            samples: cna,
        });
    }
    for (name, mut samples) in transmitters {
        samples.sort_by(|p, q| p.t.total_cmp(&q.t));
        samples.dedup_by(|p, q| p.t == q.t);
        let role = if name == "cna" { Role::Cna } else { Role::Beacon };
        vehicles.push(Vehicle { name, role, kind: if role == Role::Cna { "ship" } else { "buoy" }, samples });
    }
    let has_track = |name: &str| vehicles.iter().any(|v| v.name == name);
    let auv_track = |k: i16| {
        let truth = auv_name(k);
        if has_track(&truth) {
            Some(truth)
        } else {
            let est = format!("{truth}_est");
            has_track(&est).then_some(est)
        }
    };
    let mut pulses = Vec::new();
    let mut pulses_without_track = 0;
    for (&k, a) in &record.auvs {
        for r in &a.ranges {
            match auv_track(k) {
                Some(to) => pulses.push(Pulse {
                    t: s_of(r.transmit_time),
                    kind: PulseKind::Range,
                    from: sender(r.src),
                    to,
                    received: true,
                }),
                None => pulses_without_track += 1,
            }
        }
    }
    for s in &record.statuses {
        match (auv_track(s.src), has_cna_track) {
            (Some(from), true) => pulses.push(Pulse {
                t: s_of(s.receive_time),
                kind: PulseKind::Comms,
                from,
                to: "cna".into(),
                received: true,
            }),
            _ => pulses_without_track += 1,
        }
    }
    pulses.sort_by(|p, q| p.t.total_cmp(&q.t));
    let cna_track = vehicles.iter().find(|v| v.name == "cna");
    let mut legs = Vec::new();
    let mut legs_without_track = 0;
    let mut postings = Vec::new();
    let mut commands: Vec<&CnaCommand> = record.commands.iter().collect();
    commands.sort_by_key(|c| (c.utime, c.seq));
    for c in commands {
        let t = t_of(c.utime);
        let value = if c.has_waypoint {
            format!(
                "seq={},waypoint_x={:.3},waypoint_y={:.3},waypoint_depth={:.3},speed={}",
                c.seq, c.waypoint_x, c.waypoint_y, c.waypoint_depth, c.speed
            )
        } else {
            format!("seq={},heading={:.6},speed={}", c.seq, c.heading, c.speed)
        };
        postings.push(Posting { t, variable: COMMAND_VARIABLE.into(), value });
        if c.has_waypoint {
            let from = cna_track.and_then(|v| {
                let (first, last) = (v.samples.first()?, v.samples.last()?);
                v.at(t.clamp(first.t, last.t))
            });
            match from {
                Some(p) => legs
                    .push(Leg { t, points: vec![[p.x, p.y, p.depth], [c.waypoint_x, c.waypoint_y, c.waypoint_depth]] }),
                None => legs_without_track += 1,
            }
        }
    }
    let mut decisions: Vec<&Decision> = record.decisions.iter().collect();
    decisions.sort_by_key(|d| (d.utime, d.seq));
    for d in decisions {
        let value = format!(
            "seq={},policy={},outcome={},option={},cost={},levels_searched={},nodes={},n_status={},fix_utime={}",
            d.seq, d.policy, d.outcome, d.option, d.cost, d.levels_searched, d.nodes, d.n_status, d.fix_utime
        );
        postings.push(Posting { t: t_of(d.utime), variable: DECISION_VARIABLE.into(), value });
    }
    let truth_note =
        if truth.is_some() { "truth from the simulated world" } else { "no truth (a real vehicle has none)" };
    let run = RunLog {
        scenario: format!(
            "live run imported from LCM logs ({sources}), {} survey AUVs, {truth_note}",
            record.auvs.len()
        ),
        command: "live import".into(),
        version: env!("CARGO_PKG_VERSION").into(),
        origin: None,
        vehicles,
        pulses,
        legs,
    };
    ImportedRun { run, postings, log_start, pulses_without_track, legs_without_track }
}
