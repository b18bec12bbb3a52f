//! A survey AUV's OWTT navigator on LCM messages: decodes what one AUV's backseat receives, runs
//! coopnav-nav's [`AuvEkf`] on it exactly as post-processing does (`coopnav_nav::post`'s forward
//! pass), and encodes an estimate after every update. No socket here: [`AuvNavigator::handle`]
//! takes a channel and payload, and returns the payloads to publish; [`crate::run`] does the I/O.
//!
//! # Channels (AUV K)
//! | channel                  | type                    | direction |
//! |--------------------------|-------------------------|-----------|
//! | `COOPNAV_AUV{K}_SENSORS` | `coopnav.auv_sensors_t` | in: dead-reckoning sensors of one step |
//! | `COOPNAV_AUV{K}_RANGE`   | `coopnav.owtt_range_t`  | in: an OWTT broadcast this AUV received |
//! | `COOPNAV_AUV{K}_ESTIMATE`| `coopnav.auv_estimate_t`| out: position and its covariance after each update |
//!
//! # Time
//! The filter's clock is seconds: a sensors message at `utime as f64 / 1e6` (`utime` in
//! microseconds, on the synchronous clock the OWTT ranges use), a range at its `receive_time`
//! (seconds on that clock) plus the config's `acoustic_time_offset_s`. An estimate's `utime` is
//! its filter time in microseconds, rounded.
//!
//! # What each message does (the same calls, in the same order, as post-processing's rows)
//! - `auv_sensors_t`: predict to its time (in pieces of `auv.step_s`; a silence longer than
//!   `max_gap_s` in one step, counted), then the speed update (`speed × speed_scale`, σ
//!   `auv.sigma_speed`) and the compass update (`heading` is radians clockwise from north;
//!   `heading_bias_deg` subtracted). Its depth is kept for the slant range (`slant_range`). The
//!   first one starts the filter at its time, at the config's `[start]` position, with its speed
//!   and heading. The type has no yaw rate: the prediction holds the heading rate at zero, as
//!   post-processing does over a log without `yaw_rate` rows, and the compass updates carry the
//!   turns (the heading's process noise covers a turn's change over one step). Its DVL fields are
//!   not used.
//! - `owtt_range_t`: the range update at the receive time with range = sound speed × travel time,
//!   the transponder where the message says it was at launch (σ `transponder_sd_m`), variance
//!   from `auv.range_noise`, and the config's `range_gate` (a gated range is counted, not applied).
//! - No GPS: coopnav's `.lcm` types have no AUV GPS fix (`cna_fix_t` is the CNA's own), so a
//!   surfaced AUV's fixes are not used.
//!
//! # Out of order, duplicated, malformed, stale
//! [`AuvEkf`] has no out-of-order update, so messages wait in a **reorder buffer** of
//! `reorder_window_s` (default 2 s) of message time: a message is applied once a message at least
//! that much later has arrived (or at [`AuvNavigator::flush`]), in time order; messages of equal
//! time in arrival order. A message late by less than the window is applied where it belongs and
//! changes nothing; one whose time is before the last applied one is **stale**: counted and
//! dropped. The estimates therefore lag the newest message by the window. A message with the same
//! channel and bytes as one seen in the last two windows is a **duplicate**: counted, dropped. A
//! payload that does not decode as its channel's type, or whose values cannot be a measurement
//! (not finite, a negative speed, a travel time outside (0, 60] s, a transmit time inconsistent
//! with the receive and travel times by more than 1 ms) is **malformed**: counted, dropped. A
//! sensors message of another AUV id is counted as `wrong_auv` and dropped. A message timed more
//! than `max_gap_s` after the newest one is counted as `implausible_time` and dropped (one corrupt
//! time would otherwise make every later message stale), unless several come in a row: then the
//! clock jumped, and the jump is taken (counted in `clock_jumps`). Every one is logged
//! with `tracing` (a warning for the first ten of a kind, then at debug level); none stops the
//! navigator. The buffer holds at most [`MAX_BUFFERED`] messages (a flood shortens the window,
//! counted in `released_early`), and the duplicate memory at most twice that.

use coopnav_core::{CompassDeg, Heading, Vec3};
use coopnav_lcm::messages::{AuvEstimate, AuvSensors, Message, OwttRange};
use coopnav_lcm::Schema;
use coopnav_nav::ekf::UpdateOutcome;
use coopnav_nav::fieldlog::MAX_TRAVEL_TIME_S;
use coopnav_nav::post::{AuvModel, PostConfig, PostError, StartVariance};
use coopnav_nav::{AuvEkf, AuvParams, RangeMeasurement};
use serde::{Deserialize, Serialize};
use std::cmp::Ordering;
use std::collections::{BTreeMap, HashSet, VecDeque};
use thiserror::Error;

#[derive(Debug, Error)]
pub enum LiveError {
    #[error("live config: {0}")]
    Toml(#[from] toml::de::Error),
    #[error("live config [filter]: {0}")]
    Filter(#[from] PostError),
    #[error("live config: {field} = {value}: {allowed}")]
    Field { field: &'static str, value: f64, allowed: &'static str },
    #[error("encoding the estimate: {0}")]
    Encode(#[from] coopnav_lcm::CodecError),
    #[error("LCM transport: {0}")]
    Transport(#[from] coopnav_lcm::TransportError),
    #[error("LCM log {path}: {source}")]
    Log { path: String, source: coopnav_lcm::LogError },
    #[error("live cna: {0}")]
    Policy(#[from] coopnav_sim::policy::PolicyError),
    #[error("live cna: {what}: not supported")]
    Unsupported { what: String },
    #[error("sitl: {0}")]
    Child(String),
    #[error("truth {path}, line {line}: {what}")]
    Truth { path: String, line: usize, what: String },
}

/// Where the filter starts (local east/north, metres).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Start {
    pub e: f64,
    pub n: f64,
}

/// The navigator's settings (`--config FILE.toml`): `[filter]` is post-processing's config
/// (`coopnav_nav::post::PostConfig`, the same keys as `hbl postprocess --config`; its `start`
/// variance, a pre-pass over the first minutes' ranges, is post-processing's only: a live filter
/// cannot read ranges it has not received), `[start]` the starting position, and
/// `reorder_window_s` the reorder buffer's length.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LiveConfig {
    pub filter: PostConfig,
    pub start: Start,
    /// Message time (s) a message waits for later ones before it is applied. Invented default.
    pub reorder_window_s: f64,
}

impl LiveConfig {
    /// The post-processing config whose forward filter is this navigator's filter: `filter` with
    /// the start variance off, since the live filter starts from the configured p0.
    pub fn post_equivalent(&self) -> PostConfig {
        PostConfig { start: StartVariance { window_s: 0.0 }, ..self.filter.clone() }
    }
}

impl Default for LiveConfig {
    fn default() -> Self {
        LiveConfig { filter: PostConfig::default(), start: Start::default(), reorder_window_s: 2.0 }
    }
}

impl LiveConfig {
    pub fn from_toml(text: &str) -> Result<Self, LiveError> {
        let c: LiveConfig = toml::from_str(text)?;
        c.validate()?;
        Ok(c)
    }
    pub fn validate(&self) -> Result<(), LiveError> {
        self.filter.validate()?;
        if !(self.reorder_window_s >= 0.0 && self.reorder_window_s <= 600.0) {
            return Err(LiveError::Field {
                field: "reorder_window_s",
                value: self.reorder_window_s,
                allowed: "0 ... 600 s",
            });
        }
        for (field, value) in [("start.e", self.start.e), ("start.n", self.start.n)] {
            if !value.is_finite() {
                return Err(LiveError::Field { field, value, allowed: "a finite number of metres" });
            }
        }
        Ok(())
    }
}

/// The channel names of AUV K.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Channels {
    pub sensors: String,
    pub range: String,
    pub estimate: String,
}

impl Channels {
    pub fn for_auv(k: i16) -> Self {
        Channels {
            sensors: format!("COOPNAV_AUV{k}_SENSORS"),
            range: format!("COOPNAV_AUV{k}_RANGE"),
            estimate: format!("COOPNAV_AUV{k}_ESTIMATE"),
        }
    }
}

/// What happened to every message: nothing is dropped without being counted.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Counts {
    /// Messages received per channel (every one, before any check).
    pub messages: BTreeMap<String, u64>,
    pub sensors_applied: u64,
    pub ranges_applied: u64,
    pub ranges_gated: u64,
    /// Ranges with no line of sight (transponder overhead in 2-D).
    pub ranges_unusable: u64,
    /// Ranges applied before the first sensors message started the filter: dropped.
    pub ranges_before_start: u64,
    pub malformed: u64,
    pub duplicates: u64,
    /// Messages timed before the last one applied (later than the reorder window allows).
    pub stale: u64,
    pub wrong_auv: u64,
    /// Messages timed more than `filter.max_gap_s` after the newest one (a corrupt or jumped
    /// clock): dropped, unless [`CLOCK_JUMP_CONFIRMATIONS`] such messages come in a row, when the
    /// jump is taken as real (and counted in `clock_jumps`).
    pub implausible_time: u64,
    pub clock_jumps: u64,
    /// Messages on channels the navigator does not read.
    pub other_channel: u64,
    /// Messages applied before their reorder window had passed because the buffer was full
    /// ([`MAX_BUFFERED`]).
    pub released_early: u64,
    /// Silences longer than `max_gap_s`, each predicted in one step.
    pub gaps: u64,
    /// Times the filter's own range check (`filter.auv.range_health`) found it out of its NIS
    /// bounds and recovered it (each also logged as a warning).
    pub recoveries: u64,
    pub estimates_published: u64,
}

/// Most messages the reorder buffer holds: past it the oldest is applied at once (a flood of
/// messages shortens the window instead of growing the memory). 20 s of a 100 Hz sensor stream.
pub const MAX_BUFFERED: usize = 2000;

/// Messages in a row timed far ahead of the newest that make the navigator accept the jump.
pub const CLOCK_JUMP_CONFIRMATIONS: u32 = 4;

/// One estimate to publish: the filter's time (s; within 1 ns of the message's), the message
/// and its payload.
#[derive(Debug, Clone, PartialEq)]
pub struct Published {
    pub t: f64,
    pub estimate: AuvEstimate,
    pub payload: Vec<u8>,
}

/// A decoded input at its filter time.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Input {
    Sensors { speed: f64, compass_deg: f64, depth: f64 },
    Range { travel_time: f64, transponder: Vec3 },
}

/// A buffered input's place: filter time, then arrival order.
#[derive(Debug, Clone, Copy)]
struct Key(f64, u64);

impl PartialEq for Key {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Key {
    fn cmp(&self, o: &Self) -> Ordering {
        self.0.total_cmp(&o.0).then(self.1.cmp(&o.1))
    }
}

/// Either state vector of the filter.
#[derive(Debug, Clone)]
enum Filter {
    Thesis(AuvEkf<5>),
    Current(AuvEkf<7>),
}

macro_rules! each {
    ($self:expr, $f:ident => $body:expr) => {
        match $self {
            Filter::Thesis($f) => $body,
            Filter::Current($f) => $body,
        }
    };
}

fn math_heading(compass_deg: f64) -> f64 {
    Heading::from(CompassDeg(compass_deg)).radians()
}

/// What one input did to the filter.
enum Applied {
    Sensors,
    Range(UpdateOutcome),
}

/// Predicts to `t` as post-processing does (a silence longer than `max_gap_s` in one step, then
/// pieces of `auv.step_s`), then applies the input. The heading rate is zero (module doc).
fn apply<const M: usize>(
    f: &mut AuvEkf<M>,
    cfg: &PostConfig,
    t: f64,
    input: &Input,
    depth: &mut Option<f64>,
    gaps: &mut u64,
) -> Applied {
    let yaw_rate = 0.0;
    if t - f.ekf().t() > cfg.max_gap_s {
        *gaps += 1;
        f.predict_to(t, yaw_rate);
    }
    while t - f.ekf().t() > 1e-9 {
        let to = (f.ekf().t() + cfg.auv.step_s).min(t);
        if !f.predict_to(to, yaw_rate) {
            break;
        }
    }
    match *input {
        Input::Sensors { speed, compass_deg, depth: z } => {
            f.update_speed_sd(speed * cfg.speed_scale, cfg.auv.sigma_speed);
            f.update_heading_sd(math_heading(compass_deg - cfg.heading_bias_deg), cfg.auv.sigma_heading);
            *depth = Some(z);
            Applied::Sensors
        }
        Input::Range { travel_time, transponder } => {
            let m = RangeMeasurement { range: cfg.auv.range_noise.sound_speed * travel_time, travel_time, transponder };
            let auv_depth = if cfg.slant_range { *depth } else { None };
            let variance = cfg.auv.range_noise.variance(travel_time);
            let up = f.update_range_with(&m, auv_depth, variance, cfg.transponder_sd_m, &cfg.range_gate);
            Applied::Range(up.outcome)
        }
    }
}

/// The navigator of one AUV: reorder buffer, filter, counts.
#[derive(Debug)]
pub struct AuvNavigator {
    auv: i16,
    cfg: LiveConfig,
    channels: Channels,
    schema: Schema,
    filter: Option<Filter>,
    depth: Option<f64>,
    buffer: BTreeMap<Key, Input>,
    arrivals: u64,
    /// The newest message time seen.
    newest: f64,
    /// The time of the last input applied.
    applied_to: f64,
    /// (time, channel kind byte + payload) of the messages of the last two windows.
    recent: VecDeque<(f64, Vec<u8>)>,
    recent_set: HashSet<Vec<u8>>,
    /// Messages in a row timed far ahead of the newest.
    ahead_in_row: u32,
    counts: Counts,
}

fn warn_counted(kind: &str, count: u64, what: &str) {
    if count <= 10 {
        tracing::warn!("{kind} message #{count}: {what}");
    } else {
        tracing::debug!("{kind} message #{count}: {what}");
    }
}

impl AuvNavigator {
    pub fn new(auv: i16, cfg: LiveConfig) -> Result<Self, LiveError> {
        cfg.validate()?;
        Ok(AuvNavigator {
            auv,
            cfg,
            channels: Channels::for_auv(auv),
            schema: Schema::coopnav(),
            filter: None,
            depth: None,
            buffer: BTreeMap::new(),
            arrivals: 0,
            newest: f64::NEG_INFINITY,
            applied_to: f64::NEG_INFINITY,
            recent: VecDeque::new(),
            recent_set: HashSet::new(),
            ahead_in_row: 0,
            counts: Counts::default(),
        })
    }

    pub fn auv(&self) -> i16 {
        self.auv
    }
    pub fn channels(&self) -> &Channels {
        &self.channels
    }
    pub fn counts(&self) -> &Counts {
        &self.counts
    }
    pub fn schema(&self) -> &Schema {
        &self.schema
    }
    /// Inputs waiting in the reorder buffer.
    pub fn buffered(&self) -> usize {
        self.buffer.len()
    }

    /// Decodes and checks one message, buffers it, and applies what the reorder window releases;
    /// returns the estimates to publish (in time order).
    pub fn handle(&mut self, channel: &str, payload: &[u8]) -> Result<Vec<Published>, LiveError> {
        *self.counts.messages.entry(channel.to_string()).or_default() += 1;
        let decoded = if channel == self.channels.sensors {
            self.decode_sensors(payload).map(|i| (0u8, i))
        } else if channel == self.channels.range {
            self.decode_range(payload).map(|i| (1u8, i))
        } else {
            self.counts.other_channel += 1;
            return Ok(Vec::new());
        };
        let Some((kind, (t, input))) = decoded else { return Ok(Vec::new()) };
        if t < self.applied_to {
            self.counts.stale += 1;
            warn_counted(
                "stale",
                self.counts.stale,
                &format!("on {channel} at t = {t} s, before the last applied {} s", self.applied_to),
            );
            return Ok(Vec::new());
        }
        if self.newest.is_finite() && t > self.newest + self.cfg.filter.max_gap_s {
            self.ahead_in_row += 1;
            if self.ahead_in_row < CLOCK_JUMP_CONFIRMATIONS {
                self.counts.implausible_time += 1;
                let what = format!("on {channel} at t = {t} s, over max_gap_s after the newest {} s", self.newest);
                warn_counted("implausibly timed", self.counts.implausible_time, &what);
                return Ok(Vec::new());
            }
            self.counts.clock_jumps += 1;
            tracing::warn!("the clock jumped to t = {t} s from {} s: taken as real", self.newest);
        }
        self.ahead_in_row = 0;
        let mut id = Vec::with_capacity(payload.len() + 1);
        id.push(kind);
        id.extend_from_slice(payload);
        if self.recent_set.contains(&id) {
            self.counts.duplicates += 1;
            warn_counted("duplicate", self.counts.duplicates, &format!("on {channel} at t = {t} s"));
            return Ok(Vec::new());
        }
        self.recent_set.insert(id.clone());
        self.recent.push_back((t, id));
        self.buffer.insert(Key(t, self.arrivals), input);
        self.arrivals += 1;
        self.newest = self.newest.max(t);
        let until = self.newest - self.cfg.reorder_window_s;
        let mut out = self.release(|k| k.0 <= until)?;
        while self.buffer.len() > MAX_BUFFERED {
            self.counts.released_early += 1;
            out.extend(self.release_first()?);
        }
        // Forget duplicates older than two windows behind the newest message.
        let forget = self.newest - 2.0 * self.cfg.reorder_window_s;
        while self.recent.front().is_some_and(|(t, _)| *t < forget) || self.recent.len() > 2 * MAX_BUFFERED {
            let (_, id) = self.recent.pop_front().expect("front checked");
            self.recent_set.remove(&id);
        }
        Ok(out)
    }

    /// Applies everything still buffered (at shutdown, or at the end of a test's stream).
    pub fn flush(&mut self) -> Result<Vec<Published>, LiveError> {
        self.release(|_| true)
    }

    fn release_first(&mut self) -> Result<Option<Published>, LiveError> {
        match self.buffer.pop_first() {
            Some((key, input)) => self.apply(key.0, input),
            None => Ok(None),
        }
    }

    fn release(&mut self, ready: impl Fn(&Key) -> bool) -> Result<Vec<Published>, LiveError> {
        let mut out = Vec::new();
        while let Some(entry) = self.buffer.first_entry() {
            if !ready(entry.key()) {
                break;
            }
            let (key, input) = entry.remove_entry();
            if let Some(p) = self.apply(key.0, input)? {
                out.push(p);
            }
        }
        Ok(out)
    }

    fn apply(&mut self, t: f64, input: Input) -> Result<Option<Published>, LiveError> {
        self.applied_to = t;
        let cfg = &self.cfg.filter;
        if self.filter.is_none() {
            let Input::Sensors { speed, compass_deg, .. } = input else {
                self.counts.ranges_before_start += 1;
                return Ok(None);
            };
            let params = AuvParams { range_gate: cfg.range_gate, ..cfg.auv.clone() };
            let (e, n, psi) = (self.cfg.start.e, self.cfg.start.n, math_heading(compass_deg));
            self.filter = Some(match cfg.model {
                AuvModel::Thesis => Filter::Thesis(AuvEkf::new(t, e, n, speed, psi, params)),
                AuvModel::Current(c) => Filter::Current(AuvEkf::with_current(t, e, n, speed, psi, params, c)),
            });
        }
        let filter = self.filter.as_mut().expect("started above");
        let recovered = each!(filter, f => f.recoveries().count);
        let applied = each!(filter, f => apply(f, cfg, t, &input, &mut self.depth, &mut self.counts.gaps));
        if each!(filter, f => f.recoveries().count) > recovered {
            self.counts.recoveries += 1;
            tracing::warn!(
                t,
                auv = self.auv,
                "the filter's ranges left their NIS bounds: it recovered (inflated and relinearised)"
            );
        }
        match applied {
            Applied::Sensors => self.counts.sensors_applied += 1,
            Applied::Range(UpdateOutcome::Applied { .. }) => self.counts.ranges_applied += 1,
            Applied::Range(UpdateOutcome::Gated { .. }) => self.counts.ranges_gated += 1,
            Applied::Range(UpdateOutcome::Unusable) => self.counts.ranges_unusable += 1,
        }
        // The filter's own time: within 1 ns of `t` (its prediction stops there).
        let (t, x, [pee, pen, pnn], finite) = each!(filter, f => {
            let p = f.ekf().p();
            (f.ekf().t(), f.position(), [p[(0, 0)], p[(0, 1)], p[(1, 1)]], f.ekf().is_finite())
        });
        let estimate = AuvEstimate {
            utime: (t * 1e6).round() as i64,
            auv: self.auv,
            x: x.0,
            y: x.1,
            cov: [[pee, pen], [pen, pnn]],
            valid: finite,
        };
        let payload = estimate.encode(&self.schema)?;
        self.counts.estimates_published += 1;
        Ok(Some(Published { t, estimate, payload }))
    }

    fn malformed(&mut self, channel: &str, why: &str) -> Option<(f64, Input)> {
        self.counts.malformed += 1;
        warn_counted("malformed", self.counts.malformed, &format!("on {channel}: {why}"));
        None
    }

    fn decode_sensors(&mut self, payload: &[u8]) -> Option<(f64, Input)> {
        let channel = self.channels.sensors.clone();
        let s = match AuvSensors::decode(&self.schema, payload) {
            Ok(s) => s,
            Err(e) => return self.malformed(&channel, &e.to_string()),
        };
        if s.auv != self.auv {
            self.counts.wrong_auv += 1;
            warn_counted(
                "wrong-AUV",
                self.counts.wrong_auv,
                &format!("on {channel}: auv {} is not {}", s.auv, self.auv),
            );
            return None;
        }
        let (speed, heading, depth) = (f64::from(s.speed), s.heading, f64::from(s.depth));
        if !(speed.is_finite() && speed >= 0.0 && heading.is_finite() && depth.is_finite()) {
            return self.malformed(&channel, &format!("speed {speed}, heading {heading}, depth {depth}"));
        }
        let t = s.utime as f64 / 1e6;
        Some((t, Input::Sensors { speed, compass_deg: heading.to_degrees(), depth }))
    }

    fn decode_range(&mut self, payload: &[u8]) -> Option<(f64, Input)> {
        let channel = self.channels.range.clone();
        let r = match OwttRange::decode(&self.schema, payload) {
            Ok(r) => r,
            Err(e) => return self.malformed(&channel, &e.to_string()),
        };
        let p = r.transponder;
        let finite = [r.transmit_time, r.receive_time, r.travel_time, p.x, p.y, p.z].iter().all(|v| v.is_finite());
        if !finite {
            return self.malformed(&channel, "a field is not finite");
        }
        if !(r.travel_time > 0.0 && r.travel_time <= MAX_TRAVEL_TIME_S) {
            return self
                .malformed(&channel, &format!("travel time {} s outside (0, {MAX_TRAVEL_TIME_S}] s", r.travel_time));
        }
        if (r.receive_time - r.transmit_time - r.travel_time).abs() > 1e-3 {
            return self.malformed(
                &channel,
                &format!(
                    "receive time {} − transmit time {} is not the travel time {} s",
                    r.receive_time, r.transmit_time, r.travel_time
                ),
            );
        }
        let t = r.receive_time + self.cfg.filter.acoustic_time_offset_s;
        Some((t, Input::Range { travel_time: r.travel_time, transponder: Vec3::new(p.x, p.y, p.z) }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_config_reads_its_three_parts_and_names_a_bad_field() {
        let c =
            LiveConfig::from_toml("reorder_window_s = 0.5\n[start]\ne = 10.0\nn = -4.0\n[filter]\nmax_gap_s = 30.0\n")
                .unwrap();
        assert_eq!((c.reorder_window_s, c.start, c.filter.max_gap_s), (0.5, Start { e: 10.0, n: -4.0 }, 30.0));
        let e = LiveConfig::from_toml("reorder_window_s = -1.0").unwrap_err().to_string();
        assert!(e.contains("reorder_window_s = -1"), "{e}");
        let e = LiveConfig::from_toml("[filter]\nmax_gap_s = -5.0").unwrap_err().to_string();
        assert!(e.contains("max_gap_s"), "{e}");
        let e = LiveConfig::from_toml("window = 2.0").unwrap_err().to_string();
        assert!(e.contains("unknown field `window`"), "{e}");
    }

    #[test]
    fn channels_are_named_per_auv() {
        let c = Channels::for_auv(12);
        assert_eq!(
            [c.sensors.as_str(), c.range.as_str(), c.estimate.as_str()],
            ["COOPNAV_AUV12_SENSORS", "COOPNAV_AUV12_RANGE", "COOPNAV_AUV12_ESTIMATE"]
        );
    }
}
