//! Post-processing of a logged run (digest §3.6): the AUV EKF re-run over a CSV log with
//! transponder positions from the logged ship DGPS and buoy topside fixes (not the onboard
//! ship/buoy filters), a per-run acoustic time offset, then the EKF-RTS backward pass.
//!
//! # Log format
//! One CSV file with the header `t,kind,src,v1,v2,v3,v4` (unused fields empty). Times are
//! seconds on the AUV clock; headings are compass degrees (0 = north, clockwise), rates deg/s
//! clockwise-positive, positions metres in the local east/north frame — or, in the `_ll` kinds,
//! WGS-84 latitude/longitude in degrees, converted on reading to that frame's east/north about the
//! config's geodetic `origin` (the local tangent plane at the origin's height, gill digest §10
//! A28), so the filter only ever sees metres.
//!
//! | kind       | src      | v1                 | v2     | v3          | v4              |
//! |------------|----------|--------------------|--------|-------------|-----------------|
//! | `init`     |          | E                  | N      | speed (m/s) | heading (deg)   |
//! | `yaw_rate` |          | heading rate deg/s |        |             |                 |
//! | `speed`    |          | speed m/s          |        |             |                 |
//! | `heading`  |          | compass deg        |        |             |                 |
//! | `depth`    |          | AUV depth m        |        |             |                 |
//! | `range`    | modem id | travel time s      |        |             |                 |
//! | `ship_fix` |          | E                  | N      | heading deg |                 |
//! | `buoy_fix` |          | E                  | N      |             |                 |
//! | `truth`    |          | E                  | N      |             |                 |
//! | `init_ll`     |       | latitude deg       | longitude deg | speed (m/s) | heading (deg) |
//! | `ship_fix_ll` |       | latitude deg       | longitude deg | heading deg |               |
//! | `buoy_fix_ll` |       | latitude deg       | longitude deg |             |               |
//! | `truth_ll`    |       | latitude deg       | longitude deg |             |               |
//!
//! A `range` row's `t` is the **modem receive time**; the transmit time is t − travel time
//! (top of a second). `init` is the filter's starting estimate (the first one is used);
//! `truth` rows (topside AUV fixes) are only used to score the result.

use crate::auv::{transition, AuvEkf, AuvParams, ParamError, BIAS, CURRENT_E, CURRENT_N, PSI};
use crate::cycle::Transmitter;
use crate::ekf::{Gate, Step, UpdateOutcome};
use crate::range::RangeMeasurement;
use crate::smoother::{rts, urts, SmoothError, Smoothed, SmootherKind};
use crate::surface::Outriggers;
use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::{wrap_pi, CompassDeg, GeodesyError, Geodetic, Heading, LatLon, LocalFrame, Vec3};
use serde::{Deserialize, Serialize};
use std::io::Read;
use thiserror::Error;

pub const LOG_HEADER: [&str; 7] = ["t", "kind", "src", "v1", "v2", "v3", "v4"];

#[derive(Debug, Error)]
pub enum PostError {
    #[error("log: {0}")]
    Csv(#[from] csv::Error),
    #[error("log header is {found:?}; expected exactly {expected:?}")]
    Header { found: Vec<String>, expected: Vec<String> },
    #[error("log line {line}: field '{field}' = {value:?} is not a finite number")]
    Number { line: u64, field: &'static str, value: String },
    #[error("log line {line}: unknown kind {kind:?} (allowed: init, yaw_rate, speed, heading, depth, range, ship_fix, buoy_fix, truth, init_ll, ship_fix_ll, buoy_fix_ll, truth_ll)")]
    Kind { line: u64, kind: String },
    #[error("log line {line}: a '{kind}' row is in latitude/longitude but the post-processing config has no geodetic origin; add `origin = {{ lat_deg = ..., lon_deg = ..., height_m = ... }}` (height optional)")]
    NoOrigin { line: u64, kind: String },
    #[error("log line {line}: fields v1/v2 (latitude, longitude): {source}")]
    LatLon { line: u64, source: GeodesyError },
    #[error("writing the log in latitude/longitude: row at t = {t} s: {source}")]
    Unplaceable { t: f64, source: GeodesyError },
    #[error("log line {line}: range src {src:?} is not a transponder modem id (allowed 13 buoy, 14 ship port, 15 ship starboard)")]
    Source { line: u64, src: String },
    #[error("log line {line}: range travel time {value} s must be in [0, 1) (OWTT from the top of the second)")]
    TravelTime { line: u64, value: f64 },
    #[error("log has no 'init' row: the filter needs a starting estimate")]
    NoInit,
    #[error("post-processing config: {0}")]
    Param(#[from] ParamError),
    #[error("post-processing config: {0}")]
    Toml(#[from] toml::de::Error),
    #[error("smoother: {0}")]
    Smooth(#[from] SmoothError),
}

/// One log row, parsed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Record {
    Init { e: f64, n: f64, speed: f64, compass_deg: f64 },
    YawRate { compass_deg_s: f64 },
    Speed(f64),
    Heading { compass_deg: f64 },
    Depth(f64),
    Range { src: Transmitter, travel_time: f64 },
    ShipFix { e: f64, n: f64, compass_deg: f64 },
    BuoyFix { e: f64, n: f64 },
    Truth { e: f64, n: f64 },
}

impl Record {
    fn kind(&self) -> &'static str {
        match self {
            Record::Init { .. } => "init",
            Record::YawRate { .. } => "yaw_rate",
            Record::Speed(_) => "speed",
            Record::Heading { .. } => "heading",
            Record::Depth(_) => "depth",
            Record::Range { .. } => "range",
            Record::ShipFix { .. } => "ship_fix",
            Record::BuoyFix { .. } => "buoy_fix",
            Record::Truth { .. } => "truth",
        }
    }
    /// The local (east, north) of the position rows.
    fn position(&self) -> Option<(f64, f64)> {
        match *self {
            Record::Init { e, n, .. }
            | Record::ShipFix { e, n, .. }
            | Record::BuoyFix { e, n }
            | Record::Truth { e, n } => Some((e, n)),
            _ => None,
        }
    }
    /// The row's fields (src, v1..v4) as written to the log.
    fn fields(&self) -> [String; 5] {
        let f = |v: f64| format!("{v}");
        let e = String::new;
        match *self {
            Record::Init { e: x, n, speed, compass_deg } => [e(), f(x), f(n), f(speed), f(compass_deg)],
            Record::YawRate { compass_deg_s } => [e(), f(compass_deg_s), e(), e(), e()],
            Record::Speed(s) => [e(), f(s), e(), e(), e()],
            Record::Heading { compass_deg } => [e(), f(compass_deg), e(), e(), e()],
            Record::Depth(z) => [e(), f(z), e(), e(), e()],
            Record::Range { src, travel_time } => [src.modem_id().to_string(), f(travel_time), e(), e(), e()],
            Record::ShipFix { e: x, n, compass_deg } => [e(), f(x), f(n), f(compass_deg), e()],
            Record::BuoyFix { e: x, n } | Record::Truth { e: x, n } => [e(), f(x), f(n), e(), e()],
        }
    }
}

/// A time-stamped log row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Entry {
    pub t: f64,
    pub record: Record,
}

/// Writes entries in the log format: positions in metres, or with a `frame` as `_ll` rows in
/// latitude/longitude (the exact inverse of reading them with the same frame).
pub fn write_log<W: std::io::Write>(out: W, entries: &[Entry], frame: Option<&LocalFrame>) -> Result<(), PostError> {
    let mut w = csv::Writer::from_writer(out);
    w.write_record(LOG_HEADER)?;
    for en in entries {
        let [src, mut v1, mut v2, v3, v4] = en.record.fields();
        let mut kind = en.record.kind().to_string();
        if let (Some(f), Some((e, n))) = (frame, en.record.position()) {
            let ll = f.from_plane(e, n).map_err(|source| PostError::Unplaceable { t: en.t, source })?;
            kind.push_str("_ll");
            (v1, v2) = (format!("{}", ll.lat_deg()), format!("{}", ll.lon_deg()));
        }
        w.write_record([format!("{}", en.t), kind, src, v1, v2, v3, v4])?;
    }
    w.flush().map_err(csv::Error::from)?;
    Ok(())
}

/// Reads and checks a log; errors name the line and field. `frame` (from
/// [`PostConfig::frame`]) places the `_ll` rows; without it they are an error.
pub fn read_log<R: Read>(input: R, frame: Option<&LocalFrame>) -> Result<Vec<Entry>, PostError> {
    let mut r = csv::ReaderBuilder::new().has_headers(true).flexible(false).from_reader(input);
    let header: Vec<String> = r.headers()?.iter().map(|s| s.trim().to_string()).collect();
    if header != LOG_HEADER {
        return Err(PostError::Header { found: header, expected: LOG_HEADER.iter().map(|s| s.to_string()).collect() });
    }
    let mut entries = Vec::new();
    for row in r.records() {
        let row = row?;
        let line = row.position().map_or(0, |p| p.line());
        let num = |i: usize, field: &'static str| -> Result<f64, PostError> {
            let v = row.get(i).unwrap_or("").trim();
            match v.parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                _ => Err(PostError::Number { line, field, value: v.to_string() }),
            }
        };
        let t = num(0, "t")?;
        let kind = row.get(1).unwrap_or("").trim();
        // v1, v2 of a position row as local (east, north).
        let pos = || -> Result<(f64, f64), PostError> {
            let (a, b) = (num(3, "v1")?, num(4, "v2")?);
            if !kind.ends_with("_ll") {
                return Ok((a, b));
            }
            let f = frame.ok_or_else(|| PostError::NoOrigin { line, kind: kind.to_string() })?;
            let ll = LatLon::new(a, b).map_err(|source| PostError::LatLon { line, source })?;
            Ok(f.to_plane(ll))
        };
        let record = match kind {
            "init" | "init_ll" => {
                let (e, n) = pos()?;
                Record::Init { e, n, speed: num(5, "v3")?, compass_deg: num(6, "v4")? }
            }
            "yaw_rate" => Record::YawRate { compass_deg_s: num(3, "v1")? },
            "speed" => Record::Speed(num(3, "v1")?),
            "heading" => Record::Heading { compass_deg: num(3, "v1")? },
            "depth" => Record::Depth(num(3, "v1")?),
            "range" => {
                let src_text = row.get(2).unwrap_or("").trim();
                let src = src_text
                    .parse::<u8>()
                    .ok()
                    .and_then(Transmitter::from_modem_id)
                    .ok_or_else(|| PostError::Source { line, src: src_text.to_string() })?;
                let travel_time = num(3, "v1")?;
                if !(0.0..1.0).contains(&travel_time) {
                    return Err(PostError::TravelTime { line, value: travel_time });
                }
                Record::Range { src, travel_time }
            }
            "ship_fix" | "ship_fix_ll" => {
                let (e, n) = pos()?;
                Record::ShipFix { e, n, compass_deg: num(5, "v3")? }
            }
            "buoy_fix" | "buoy_fix_ll" => {
                let (e, n) = pos()?;
                Record::BuoyFix { e, n }
            }
            "truth" | "truth_ll" => {
                let (e, n) = pos()?;
                Record::Truth { e, n }
            }
            other => return Err(PostError::Kind { line, kind: other.to_string() }),
        };
        entries.push(Entry { t, record });
    }
    Ok(entries)
}

/// How a transponder's position at a transmit time between two logged fixes is obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FixUse {
    /// Most recent fix (zero-order hold, the thesis's buoy treatment, digest §3.6).
    Hold,
    /// Linear interpolation between the fixes either side (default: a timestamp rounded to the
    /// millisecond then costs a millisecond of transponder motion, not a whole fix interval).
    #[default]
    Linear,
}

/// How logged fixes are matched to a range's transmit time t_rx − τ. Invented parameters (the
/// thesis does not say how its post-processing matched fixes, digest §3.6): rounded log times put
/// a transmission's own fix a little after the recovered transmit time, so a fix this close counts
/// as that transmission's fix; a fix older (or newer) than `max_age_s` is stale, and a range with
/// no fresh fix is counted as without a fix, never applied with a stale position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FixMatching {
    pub between: FixUse,
    /// A fix within this many seconds of the transmit time is used as is (s).
    pub match_tolerance_s: f64,
    /// The fix used (the nearer one when interpolating) must be within this many seconds (s).
    pub max_age_s: f64,
}

impl Default for FixMatching {
    fn default() -> Self {
        FixMatching { between: FixUse::Linear, match_tolerance_s: 0.01, max_age_s: 120.0 }
    }
}

impl CheckFields for FixMatching {
    fn check_fields(&self, prefix: &str, p: &mut Problems) {
        p.non_negative(&format!("{prefix}match_tolerance_s"), self.match_tolerance_s);
        p.positive(&format!("{prefix}max_age_s"), self.max_age_s);
    }
}

/// The post-processing filter's state vector (the model lives beside the filter, in `auv`).
pub use crate::auv::AuvModel;

/// Post-processing settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PostConfig {
    /// The thesis's coefficients. Its `range_gate` must stay off: post-processing gates with the
    /// top-level `range_gate`.
    pub auv: AuvParams,
    /// The filter's states: `{ kind = "thesis" }` (5, default) or `{ kind = "current", p0, q }` (7).
    pub model: AuvModel,
    /// Innovation gate on ranges; default NIS ≤ 10.83 (χ² with 1 degree of freedom at 99.9 %),
    /// so an acoustic outlier is counted in `ranges_gated` instead of pulling the track.
    pub range_gate: Gate,
    /// A silence between rows longer than this (s) is predicted in one step, not in `auv.step_s`
    /// pieces, and counted as a gap. Invented bound (issue 11 item 2): no logged sensor is silent
    /// this long in a working mission.
    pub max_gap_s: f64,
    /// Horizontal SD (m, each axis) of the logged transponder fixes, added to the range noise
    /// along the line of sight. Default 0: the thesis's fixes are DGPS (digest §3.6).
    pub transponder_sd_m: f64,
    /// Added to every range row's time before processing (e.g. −2 removes a 2 s modem delay).
    pub acoustic_time_offset_s: f64,
    /// Use the 3-D slant range with logged depth (field mode) instead of the horizontal range.
    pub slant_range: bool,
    pub outriggers: Outriggers,
    /// Matching logged transponder fixes to transmit times.
    pub fixes: FixMatching,
    /// Depth of the buoy transponder (m).
    pub buoy_depth: f64,
    /// Backward pass: `ekf` (EKF-RTS, default) or `unscented` (URTS, the thesis's [25]).
    pub smoother: SmootherKind,
    /// Geodetic origin of the local east/north frame, needed by `_ll` log rows (digest §10 A28).
    /// `_ll` positions are taken at its height above the ellipsoid (the site's water surface).
    pub origin: Option<Geodetic>,
}

impl Default for PostConfig {
    fn default() -> Self {
        PostConfig {
            auv: AuvParams::default(),
            model: AuvModel::Thesis,
            range_gate: Gate { max_abs_residual: None, max_nis: Some(10.83) },
            transponder_sd_m: 0.0,
            max_gap_s: 600.0,
            acoustic_time_offset_s: 0.0,
            slant_range: false,
            outriggers: Outriggers::default(),
            fixes: FixMatching::default(),
            buoy_depth: 1.5,
            smoother: SmootherKind::Ekf,
            origin: None,
        }
    }
}

impl PostConfig {
    pub fn from_toml(text: &str) -> Result<Self, PostError> {
        let c: PostConfig = toml::from_str(text)?;
        c.validate()?;
        Ok(c)
    }
    /// Checks every field and reports every bad one at once.
    pub fn validate(&self) -> Result<(), PostError> {
        let mut p = Problems::new();
        self.auv.check_fields("auv.", &mut p);
        if self.auv.range_gate != Gate::OFF {
            p.push("auv.range_gate", "a gate", "none here: set the top-level range_gate instead");
        }
        if let AuvModel::Current(c) = &self.model {
            c.check_fields("model.", &mut p);
        }
        self.range_gate.check_fields("range_gate.", &mut p);
        p.positive("max_gap_s", self.max_gap_s);
        p.non_negative("transponder_sd_m", self.transponder_sd_m);
        p.finite("acoustic_time_offset_s", self.acoustic_time_offset_s);
        self.outriggers.check_fields("outriggers.", &mut p);
        self.fixes.check_fields("fixes.", &mut p);
        p.non_negative("buoy_depth", self.buoy_depth);
        Ok(p.finish()?)
    }
    /// The local frame of `_ll` log rows, if an origin is configured.
    pub fn frame(&self) -> Option<LocalFrame> {
        self.origin.map(LocalFrame::new)
    }
}

/// Filtered and smoothed estimates at one filter step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PostSample {
    pub t: f64,
    pub filtered: [f64; 2],
    pub filtered_sd: [f64; 2],
    pub smoothed: [f64; 2],
    pub smoothed_sd: [f64; 2],
    /// Smoothed heading bias b (rad): the compass's offset from the direction of motion.
    pub smoothed_heading_bias: f64,
    /// Smoothed water current (east, north, m/s), with the `current` model.
    pub smoothed_current: Option<[f64; 2]>,
    /// Topside truth at this time, if the log had a fix here.
    pub truth: Option<[f64; 2]>,
}

/// What happened to every row: nothing is dropped without being counted here.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct PostSummary {
    pub ranges: usize,
    pub ranges_applied: usize,
    /// Ranges with no fix of their transponder within `fixes.max_age_s` of the transmit time.
    pub ranges_without_fix: usize,
    /// Ranges rejected by the innovation gate (`auv.range_gate`).
    pub ranges_gated: usize,
    /// Ranges with no usable geometry (transponder overhead, non-finite numbers).
    pub ranges_unusable: usize,
    /// Rows timed before the first `init` row (not processed).
    pub rows_before_init: usize,
    /// `init` rows after the first (ignored: the filter starts once).
    pub extra_inits: usize,
    /// Silences longer than `max_gap_s` between rows, each dead-reckoned in one step.
    pub gaps: usize,
    /// RMS range residual of the applied ranges before their update (innovations) and against
    /// the smoothed track (m).
    pub residual_rms_filter_m: Option<f64>,
    pub residual_rms_smoothed_m: Option<f64>,
    pub truth_points: usize,
    pub mean_filtered_error: Option<f64>,
    pub mean_smoothed_error: Option<f64>,
    /// RMS, largest and last horizontal error against the truth rows (m).
    pub rms_filtered_error: Option<f64>,
    pub rms_smoothed_error: Option<f64>,
    pub max_smoothed_error: Option<f64>,
    pub final_smoothed_error: Option<f64>,
    /// Mean 2-D NEES eᵀP⁻¹e of position at truth points (≈ 2 when the covariance is consistent).
    pub mean_filtered_nees: Option<f64>,
    pub mean_smoothed_nees: Option<f64>,
}

impl PostSummary {
    /// One sentence per kind of row that was not used as logged (empty when every row was).
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        let mut say = |n: usize, what: &str| {
            if n > 0 {
                w.push(format!("{n} {what}"));
            }
        };
        say(self.rows_before_init, "row(s) timed before the first 'init' row were not processed");
        say(self.extra_inits, "'init' row(s) after the first were ignored (the filter starts once)");
        say(
            self.ranges_without_fix,
            "range(s) had no transponder fix within fixes.max_age_s of their transmit time and were not applied",
        );
        say(self.gaps, "silence(s) longer than max_gap_s between rows were dead-reckoned in one step (a time typo?)");
        say(self.ranges_gated, "range(s) were rejected by the innovation gate (auv.range_gate)");
        say(self.ranges_unusable, "range(s) had no usable geometry (transponder overhead) and were not applied");
        w
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PostResult {
    pub samples: Vec<PostSample>,
    pub summary: PostSummary,
    /// Every range that reached the filter (applied or gated), in log order.
    pub residuals: Vec<RangeResidual>,
}

/// One range's residual (measured − predicted, m) before its update and after smoothing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RangeResidual {
    /// Receive time (s, after `acoustic_time_offset_s`).
    pub t: f64,
    pub modem_id: u8,
    /// False when the gate rejected it.
    pub applied: bool,
    /// Against the filter's prediction just before the update (the innovation).
    pub innovation: f64,
    /// Against the smoothed track at the same step.
    pub smoothed: f64,
    /// Normalised innovation squared y²/S (χ² with 1 degree of freedom when consistent).
    pub nis: f64,
}

/// Root mean square, None for no values.
fn rms(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// One logged fix of a transponder's vehicle: position and (ship) heading, math radians.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Fix {
    t: f64,
    e: f64,
    n: f64,
    psi: f64,
}

impl Fix {
    fn lerp(&self, b: &Fix, t: f64) -> Fix {
        let f = (t - self.t) / (b.t - self.t);
        Fix {
            t,
            e: self.e + f * (b.e - self.e),
            n: self.n + f * (b.n - self.n),
            psi: self.psi + f * wrap_pi(b.psi - self.psi),
        }
    }
}

/// A vehicle's fixes in time order, matched to transmit times by [`FixMatching`].
#[derive(Debug, Default)]
struct Track(Vec<Fix>);

impl Track {
    /// The vehicle at time `t`, or None when no fix is fresh enough.
    fn at(&self, t: f64, m: &FixMatching) -> Option<Fix> {
        let i = self.0.partition_point(|f| f.t <= t);
        let (before, after) = (i.checked_sub(1).map(|k| &self.0[k]), self.0.get(i));
        let age = |f: &Fix| (f.t - t).abs();
        let nearest = [before, after].into_iter().flatten().min_by(|a, b| age(a).total_cmp(&age(b)))?;
        if age(nearest) <= m.match_tolerance_s {
            return Some(*nearest);
        }
        match (m.between, before, after) {
            (FixUse::Linear, Some(a), Some(b)) if age(nearest) <= m.max_age_s => Some(a.lerp(b, t)),
            (_, Some(a), _) if age(a) <= m.max_age_s => Some(*a),
            _ => None,
        }
    }
}

/// Positions of the surface transponders over time, from logged fixes.
#[derive(Debug, Default)]
struct Fixes {
    ship: Track,
    buoy: Track,
}

fn math_heading(compass_deg: f64) -> f64 {
    Heading::from(CompassDeg(compass_deg)).radians()
}

/// Runs the post-processing EKF and the RTS smoother over a log.
pub fn postprocess(entries: &[Entry], cfg: &PostConfig) -> Result<PostResult, PostError> {
    cfg.validate()?;
    let mut events: Vec<Entry> = entries
        .iter()
        .map(|e| match e.record {
            Record::Range { .. } => Entry { t: e.t + cfg.acoustic_time_offset_s, record: e.record },
            _ => *e,
        })
        .collect();
    events.sort_by(|a, b| a.t.total_cmp(&b.t));
    let (t0, init) = events
        .iter()
        .find_map(|e| match e.record {
            Record::Init { e: x, n, speed, compass_deg } => Some((e.t, (x, n, speed, compass_deg))),
            _ => None,
        })
        .ok_or(PostError::NoInit)?;
    let mut fixes = Fixes::default();
    for e in &events {
        match e.record {
            Record::ShipFix { e: x, n, compass_deg } => {
                fixes.ship.0.push(Fix { t: e.t, e: x, n, psi: math_heading(compass_deg) })
            }
            Record::BuoyFix { e: x, n } => fixes.buoy.0.push(Fix { t: e.t, e: x, n, psi: 0.0 }),
            _ => {}
        }
    }
    let summary = PostSummary {
        rows_before_init: events.iter().filter(|e| e.t < t0).count(),
        extra_inits: events.iter().filter(|e| e.t >= t0 && matches!(e.record, Record::Init { .. })).count() - 1,
        ..PostSummary::default()
    };
    let params = AuvParams { range_gate: cfg.range_gate, ..cfg.auv.clone() };
    let (e0, n0, speed0, psi0) = (init.0, init.1, init.2, math_heading(init.3));
    let run = Run { events: &events, fixes: &fixes, cfg, t0 };
    match cfg.model {
        AuvModel::Thesis => run.filter(AuvEkf::new(t0, e0, n0, speed0, psi0, params), summary),
        AuvModel::Current(c) => run.filter(AuvEkf::with_current(t0, e0, n0, speed0, psi0, params, c), summary),
    }
}

/// One post-processing pass over time-sorted events, for either state vector.
struct Run<'a> {
    events: &'a [Entry],
    fixes: &'a Fixes,
    cfg: &'a PostConfig,
    t0: f64,
}

impl Run<'_> {
    fn filter<const M: usize>(&self, mut f: AuvEkf<M>, mut summary: PostSummary) -> Result<PostResult, PostError> {
        let (cfg, fixes) = (self.cfg, self.fixes);
        f.ekf_mut().record_history();
        let (mut yaw_rate, mut depth) = (0.0, None);
        let mut residuals = Vec::new();
        let mut truth_at: Vec<(usize, [f64; 2])> = Vec::new();
        for ev in self.events.iter().filter(|e| e.t >= self.t0) {
            // Across a silence longer than max_gap_s one prediction spans it: the history (and
            // memory) grows with the rows, never with the log's time span (issue 11 item 2).
            if ev.t - f.ekf().t() > cfg.max_gap_s {
                summary.gaps += 1;
                f.predict_to(ev.t, yaw_rate);
            }
            // Dynamic step: predict to the event in pieces no longer than the nominal step.
            while ev.t - f.ekf().t() > 1e-9 {
                let to = (f.ekf().t() + cfg.auv.step_s).min(ev.t);
                if !f.predict_to(to, yaw_rate) {
                    break;
                }
            }
            match ev.record {
                Record::YawRate { compass_deg_s } => yaw_rate = -compass_deg_s.to_radians(),
                Record::Speed(s) => {
                    f.update_speed(s);
                }
                Record::Heading { compass_deg } => {
                    f.update_heading(math_heading(compass_deg));
                }
                Record::Depth(z) => depth = Some(z),
                Record::Range { src, travel_time } => {
                    summary.ranges += 1;
                    let t_tx = ev.t - travel_time;
                    let pos = match src {
                        Transmitter::Ship(side) => {
                            fixes.ship.at(t_tx, &cfg.fixes).map(|x| cfg.outriggers.position(side, x.e, x.n, x.psi))
                        }
                        Transmitter::Buoy => {
                            fixes.buoy.at(t_tx, &cfg.fixes).map(|x| Vec3::new(x.e, x.n, cfg.buoy_depth))
                        }
                    };
                    let Some(transponder) = pos else {
                        summary.ranges_without_fix += 1;
                        continue;
                    };
                    let m = RangeMeasurement {
                        range: cfg.auv.range_noise.sound_speed * travel_time,
                        travel_time,
                        transponder,
                    };
                    let auv_depth = if cfg.slant_range { depth } else { None };
                    let innovation = m.range - f.predicted_range(&transponder, auv_depth);
                    let outcome = f.update_range_from_uncertain(&m, auv_depth, cfg.transponder_sd_m);
                    let step = f.ekf().history().map_or(0, |h| h.len().saturating_sub(1));
                    if let UpdateOutcome::Applied { nis } | UpdateOutcome::Gated { nis } = outcome {
                        let residual = RangeResidual {
                            t: ev.t,
                            modem_id: src.modem_id(),
                            applied: outcome.applied(),
                            innovation,
                            smoothed: f64::NAN,
                            nis,
                        };
                        residuals.push((residual, step, m.range, transponder, auv_depth));
                    }
                    match outcome {
                        UpdateOutcome::Applied { .. } => summary.ranges_applied += 1,
                        UpdateOutcome::Gated { .. } => summary.ranges_gated += 1,
                        UpdateOutcome::Unusable => summary.ranges_unusable += 1,
                    }
                }
                Record::Truth { e, n } => {
                    let len = f.ekf().history().map_or(0, |h| h.len());
                    truth_at.push((len.saturating_sub(1), [e, n]));
                }
                Record::Init { .. } | Record::ShipFix { .. } | Record::BuoyFix { .. } => {}
            }
        }
        let history = f.ekf().history().ok_or(SmoothError::NoHistory)?;
        let smoothed = smooth(history, f.ekf().angles(), cfg.smoother)?;
        let mut samples: Vec<PostSample> = history
            .iter()
            .zip(&smoothed)
            .map(|(h, s)| PostSample {
                t: h.t,
                filtered: [h.x_post[0], h.x_post[1]],
                filtered_sd: [h.p_post[(0, 0)].sqrt(), h.p_post[(1, 1)].sqrt()],
                smoothed: [s.x[0], s.x[1]],
                smoothed_sd: [s.p[(0, 0)].sqrt(), s.p[(1, 1)].sqrt()],
                smoothed_heading_bias: s.x[BIAS],
                smoothed_current: (M > CURRENT_N).then(|| [s.x[CURRENT_E], s.x[CURRENT_N]]),
                truth: None,
            })
            .collect();
        score(&mut samples, &mut summary, &truth_at, history, &smoothed);
        let residuals = residuals
            .into_iter()
            .map(|(r, step, range, at, auv_depth)| {
                let x = &smoothed[step].x;
                let dz = auv_depth.map_or(0.0, |z| z - at.z);
                RangeResidual { smoothed: range - (x[0] - at.x).hypot(x[1] - at.y).hypot(dz), ..r }
            })
            .collect::<Vec<_>>();
        let applied = || residuals.iter().filter(|r| r.applied);
        summary.residual_rms_filter_m = rms(applied().map(|r| r.innovation));
        summary.residual_rms_smoothed_m = rms(applied().map(|r| r.smoothed));
        Ok(PostResult { samples, summary, residuals })
    }
}

/// The chosen backward pass. The unscented one replays the forward filter's dead reckoning:
/// each step's interval and heading change are read back from the recorded means.
fn smooth<const M: usize>(
    history: &[Step<M>],
    angles: &[bool; M],
    kind: SmootherKind,
) -> Result<Vec<Smoothed<M>>, SmoothError> {
    match kind {
        SmootherKind::Ekf => rts(history, angles),
        SmootherKind::Unscented => urts(history, angles, |k, x| {
            let (cur, next) = (&history[k], &history[k + 1]);
            transition(x, next.t - cur.t, wrap_pi(next.x_prior[PSI] - cur.x_post[PSI]))
        }),
    }
}

fn score<const M: usize>(
    samples: &mut [PostSample],
    summary: &mut PostSummary,
    truth_at: &[(usize, [f64; 2])],
    history: &[Step<M>],
    smoothed: &[Smoothed<M>],
) {
    let nees = |x: &nalgebra::SVector<f64, M>, p: &nalgebra::SMatrix<f64, M, M>, tr: [f64; 2]| {
        let e = nalgebra::Vector2::new(x[0] - tr[0], x[1] - tr[1]);
        let pp = p.fixed_view::<2, 2>(0, 0).into_owned();
        pp.cholesky().map(|c| (e.transpose() * c.solve(&e))[(0, 0)])
    };
    let (mut nf, mut ns, mut nn) = (0.0, 0.0, 0usize);
    let (mut filtered, mut smoothed_errors) = (Vec::new(), Vec::new());
    for &(i, tr) in truth_at {
        samples[i].truth = Some(tr);
        filtered.push((history[i].x_post[0] - tr[0]).hypot(history[i].x_post[1] - tr[1]));
        smoothed_errors.push((smoothed[i].x[0] - tr[0]).hypot(smoothed[i].x[1] - tr[1]));
        if let (Some(a), Some(b)) =
            (nees(&history[i].x_post, &history[i].p_post, tr), nees(&smoothed[i].x, &smoothed[i].p, tr))
        {
            nf += a;
            ns += b;
            nn += 1;
        }
    }
    summary.truth_points = truth_at.len();
    if !truth_at.is_empty() {
        let k = truth_at.len() as f64;
        summary.mean_filtered_error = Some(filtered.iter().sum::<f64>() / k);
        summary.mean_smoothed_error = Some(smoothed_errors.iter().sum::<f64>() / k);
    }
    summary.rms_filtered_error = rms(filtered.iter().copied());
    summary.rms_smoothed_error = rms(smoothed_errors.iter().copied());
    summary.max_smoothed_error = smoothed_errors.iter().copied().reduce(f64::max);
    summary.final_smoothed_error = smoothed_errors.last().copied();
    if nn > 0 {
        summary.mean_filtered_nees = Some(nf / nn as f64);
        summary.mean_smoothed_nees = Some(ns / nn as f64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn log(text: &str) -> Result<Vec<Entry>, PostError> {
        read_log(text.as_bytes(), None)
    }

    fn pend_oreille() -> LocalFrame {
        PostConfig::from_toml("origin = { lat_deg = 47.97, lon_deg = -116.5, height_m = 630.0 }\n")
            .unwrap()
            .frame()
            .unwrap()
    }

    #[test]
    fn round_trip_through_csv() {
        let entries = vec![
            Entry { t: 0.0, record: Record::Init { e: 1.0, n: 2.0, speed: 0.85, compass_deg: 90.0 } },
            Entry { t: 0.1, record: Record::Range { src: Transmitter::Buoy, travel_time: 0.05 } },
            Entry { t: 0.2, record: Record::ShipFix { e: 3.0, n: 4.0, compass_deg: 270.0 } },
        ];
        let mut buf = Vec::new();
        write_log(&mut buf, &entries, None).unwrap();
        assert_eq!(log(std::str::from_utf8(&buf).unwrap()).unwrap(), entries);
    }

    #[test]
    fn latlon_rows_round_trip_to_the_same_metres() {
        let entries = vec![
            Entry { t: 0.0, record: Record::Init { e: -79.0, n: 2.0, speed: 0.85, compass_deg: 90.0 } },
            Entry { t: 0.1, record: Record::Range { src: Transmitter::Buoy, travel_time: 0.05 } },
            Entry { t: 0.2, record: Record::ShipFix { e: 121.0, n: -4.0, compass_deg: 270.0 } },
            Entry { t: 0.3, record: Record::BuoyFix { e: 20.0, n: 80.0 } },
            Entry { t: 0.4, record: Record::Truth { e: -300.0, n: 150.0 } },
        ];
        let f = pend_oreille();
        let mut buf = Vec::new();
        write_log(&mut buf, &entries, Some(&f)).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert!(text.contains(",buoy_fix_ll,,47.97") && text.contains(",range,13,0.05,"), "{text}");
        let back = read_log(text.as_bytes(), Some(&f)).unwrap();
        for (a, b) in entries.iter().zip(&back) {
            assert_eq!((a.t, a.record.kind()), (b.t, b.record.kind()));
            match (a.record.position(), b.record.position()) {
                (Some(p), Some(q)) => assert!((p.0 - q.0).abs() < 1e-6 && (p.1 - q.1).abs() < 1e-6, "{p:?} {q:?}"),
                _ => assert_eq!(a.record, b.record),
            }
        }
        // Metric rows read the same with or without an origin.
        assert_eq!(
            read_log("t,kind,src,v1,v2,v3,v4\n0,truth,,1,2,,\n".as_bytes(), Some(&f)).unwrap()[0].record,
            Record::Truth { e: 1.0, n: 2.0 }
        );
    }

    #[test]
    fn bad_latlon_rows_name_the_line() {
        let h = "t,kind,src,v1,v2,v3,v4\n0,speed,,1,,,\n";
        let f = pend_oreille();
        let e = read_log(format!("{h}1,buoy_fix_ll,,95,-116.5,,\n").as_bytes(), Some(&f)).unwrap_err();
        assert!(matches!(e, PostError::LatLon { line: 3, source: GeodesyError::Latitude(_) }), "{e:?}");
        assert!(e.to_string().contains("line 3") && e.to_string().contains("latitude 95"), "{e}");
        let e = read_log(format!("{h}1,ship_fix_ll,,47.9,-190,0,\n").as_bytes(), Some(&f)).unwrap_err();
        assert!(matches!(e, PostError::LatLon { line: 3, source: GeodesyError::Longitude(_) }), "{e:?}");
        let e = read_log(format!("{h}1,truth_ll,,47.97,-116.5,,\n").as_bytes(), None).unwrap_err();
        assert!(matches!(e, PostError::NoOrigin { line: 3, .. }), "{e:?}");
        assert!(e.to_string().contains("truth_ll") && e.to_string().contains("origin = {"), "{e}");
        let e = read_log(format!("{h}1,init_ll,,north,-116.5,0.8,90\n").as_bytes(), Some(&f)).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("v1") && e.contains("north"), "{e}");
        let e = read_log(format!("{h}1,yaw_rate_ll,,1,,,\n").as_bytes(), Some(&f)).unwrap_err();
        assert!(matches!(e, PostError::Kind { line: 3, .. }), "{e:?}");
        let e = PostConfig::from_toml("origin = { lat_deg = 95.0, lon_deg = 0.0 }\n").unwrap_err().to_string();
        assert!(e.contains("origin") && e.contains("latitude 95"), "{e}");
        let e = PostConfig::from_toml("origin = { lat_deg = 45.0, lon_deg = 0.0, height_m = nan }\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("origin") && e.contains("height NaN"), "{e}");
        let far = [Entry { t: 7.0, record: Record::Truth { e: 5e6, n: 0.0 } }];
        let e = write_log(Vec::new(), &far, Some(&f)).unwrap_err().to_string();
        assert!(e.contains("t = 7"), "{e}");
    }

    #[test]
    fn bad_logs_name_line_and_field() {
        let h = "t,kind,src,v1,v2,v3,v4\n";
        let e = log("t,kind,v1\n0,speed,1\n").unwrap_err().to_string();
        assert!(e.contains("header"), "{e}");
        let e = log(&format!("{h}0,speed,,abc,,,\n")).unwrap_err().to_string();
        assert!(e.contains("line 2") && e.contains("v1") && e.contains("abc"), "{e}");
        let e = log(&format!("{h}0,speed,,1,,,\n1,warp,,1,,,\n")).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("warp"), "{e}");
        let e = log(&format!("{h}0,range,7,0.1,,,\n")).unwrap_err().to_string();
        assert!(e.contains("src") && e.contains("13"), "{e}");
        let e = log(&format!("{h}0,range,13,1.5,,,\n")).unwrap_err().to_string();
        assert!(e.contains("travel time"), "{e}");
        let e = log(&format!("{h}0,speed,,1,,\n")).unwrap_err().to_string();
        assert!(e.contains("line 2") || e.contains("fields"), "{e}");
        let e = postprocess(&log(&format!("{h}0,speed,,1,,,\n")).unwrap(), &PostConfig::default()).unwrap_err();
        assert!(matches!(e, PostError::NoInit));
        let e = PostConfig::from_toml("acoustic_time_offset = 2\n").unwrap_err().to_string();
        assert!(e.contains("acoustic_time_offset"), "{e}");
        let e = PostConfig::from_toml("buoy_depth = -3.0\n").unwrap_err().to_string();
        assert!(e.contains("buoy_depth"), "{e}");
        let e = PostConfig::from_toml("[auv]\nsigma_speed = -1\n").unwrap_err().to_string();
        assert!(e.contains("auv.sigma_speed"), "{e}");
        let e = PostConfig::from_toml("smoother = 'particle'\n").unwrap_err().to_string();
        assert!(e.contains("particle") && e.contains("unscented"), "{e}");
        assert_eq!(PostConfig::from_toml("smoother = 'unscented'\n").unwrap().smoother, SmootherKind::Unscented);
    }
}
