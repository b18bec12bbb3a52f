//! Post-processing of a logged run (Gill 2013, §2.4.3 and §3.4): the AUV EKF re-run over a CSV log with
//! transponder positions from the logged ship DGPS and buoy topside fixes (not the onboard
//! ship/buoy filters), a per-run acoustic time offset, then the EKF-RTS backward pass.
//!
//! # Log format
//! One CSV file with the header `t,kind,src,v1,v2,v3,v4` (unused fields empty). Times are
//! seconds on the AUV clock; headings are compass degrees (0 = north, clockwise), rates deg/s
//! clockwise-positive, positions metres in the local east/north frame — or, in the `_ll` kinds,
//! WGS-84 latitude/longitude in degrees, converted on reading to that frame's east/north about the
//! config's geodetic `origin` (the local tangent plane at the origin's height,
//! docs/models.md#gill-geodesy), so the filter only ever sees metres.
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

use crate::auv::{AuvEkf, AuvParams, ParamError, BIAS, CURRENT_E, CURRENT_N};
use crate::cycle::Transmitter;
use crate::ekf::{Ekf, Gate, UpdateOutcome};
use crate::fieldlog::{self, BeaconId, FieldLog, Fields, LogRow, Observation, TimeBase};
use crate::range::RangeMeasurement;
use crate::smoother::{rts_step, urts_step, wrap, SmoothError, Smoothed, SmootherKind};
use crate::surface::Outriggers;
use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::{wrap_pi, CompassDeg, GeodesyError, Geodetic, Heading, LocalFrame, Vec3};
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read};
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
    #[error("log line {line}: field '{field}' = {value:e}: allowed {allowed}")]
    OutOfRange { line: u64, field: &'static str, value: f64, allowed: &'static str },
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
    #[error("log line 1 is {found:?}; a version-2 log starts with `# coopnav-log 2 time=relative` or `# coopnav-log 2 time=unix` (a version-1 log starts with its column header `t,kind,src,v1,v2,v3,v4`)")]
    VersionLine { found: String },
    #[error("log line {line}: {found} fields; every row has the header's {expected} fields (empty ones too)")]
    FieldCount { line: u64, expected: u64, found: u64 },
    #[error("log format version {found} is not supported (this coopnav reads version 2, and version 1 without a version line)")]
    Version { found: u32 },
    #[error("log line {line}: unknown kind {kind:?} (allowed: init, yaw_rate, speed, dvl_body, dvl_earth, heading, depth, gps, range, beacon_fix, beacon_fixed, ship_fix, truth; init, gps, beacon_fix, beacon_fixed, ship_fix and truth also as _ll in latitude/longitude)")]
    KindV2 { line: u64, kind: String },
    #[error("log line {line}: field 'src' = {src:?} of a '{kind}' row is not a beacon id (an integer 0 … 4294967295)")]
    Beacon { line: u64, kind: String, src: String },
    #[error("log line {line}: range travel time {value} s must be in (0, {max}] s")]
    TravelTimeV2 { line: u64, value: f64, max: f64 },
    #[error("log line {line}: a '{kind}' row takes no sigma (only speed, dvl_*, heading, gps, range and beacon_fix* rows do); leave the field empty")]
    SigmaNotUsed { line: u64, kind: String },
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
        let f = Fields { row: &row, line: row.position().map_or(0, |p| p.line()) };
        let (line, num, kind) = (f.line, |i, field| f.num(i, field), f.text(1));
        let t = num(0, "t")?;
        let pos = || f.position(kind, frame);
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

/// Reads a log of either version: version 2 by its first line, else version 1 (its rows mapped
/// onto the general ones, relative time).
pub fn read_any_log<R: Read>(input: R, cfg: &PostConfig) -> Result<FieldLog, PostError> {
    let mut input = BufReader::new(input);
    let frame = cfg.frame();
    if fieldlog::is_field_log(input.fill_buf().map_err(csv::Error::from)?) {
        return fieldlog::read_field_log(input, frame.as_ref());
    }
    let entries = read_log(input, frame.as_ref())?;
    Ok(FieldLog { time: TimeBase::Relative, rows: fieldlog::from_v1(&entries, cfg.buoy_depth) })
}

/// How a transponder's position at a transmit time between two logged fixes is obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FixUse {
    /// Most recent fix (zero-order hold, the thesis's buoy treatment, Gill 2013, §2.4.3).
    Hold,
    /// Linear interpolation between the fixes either side (default: a timestamp rounded to the
    /// millisecond then costs a millisecond of transponder motion, not a whole fix interval).
    #[default]
    Linear,
}

/// How logged fixes are matched to a range's transmit time t_rx − τ. Invented parameters (the
/// thesis does not say how its post-processing matched fixes, Gill 2013, §2.4.3): rounded log times put
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

/// The initial E/N variance the first ranges support (docs/models.md#post-start). Each range
/// received within `window_s` of the start is predicted by the filter dead-reckoning from the
/// `init` row without any range: its innovation y has variance S = R + h P hᵀ, of which h P₀ hᵀ
/// (at most the larger of `auv.p0[0]`, `auv.p0[1]`) is the start's. The mean of y² − (S − h P₀ hᵀ)
/// over those ranges is the start's variance along their lines of sight that the ranges show;
/// when it exceeds the configured p0, both p0[0] and p0[1] are widened to it. It only widens: a
/// start the ranges agree with keeps the configured p0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StartVariance {
    /// The ranges received within this many seconds of the start are used (0: off). Invented
    /// default: 120 s, the first minutes of a log (not tuned on any log).
    pub window_s: f64,
}

impl Default for StartVariance {
    fn default() -> Self {
        StartVariance { window_s: 120.0 }
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
    /// pieces, and counted as a gap. Invented bound: no logged sensor is silent
    /// this long in a working mission.
    pub max_gap_s: f64,
    /// Horizontal SD (m, each axis) of the logged transponder fixes, added to the range noise
    /// along the line of sight. Default 0: the thesis's fixes are DGPS (Gill 2013, §2.4.3).
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
    /// Backward pass: `ekf` (EKF-RTS, default) or `unscented` (URTS, the thesis's reference 25).
    pub smoother: SmootherKind,
    /// SD (m, each axis) of a `gps` row without its own σ. Invented default: a
    /// consumer GPS at the surface.
    pub gps_sd_m: f64,
    /// SD (m/s, each component) of a `dvl_*` row without its own σ. Invented default.
    pub velocity_sd_m_s: f64,
    /// Multiplies every `speed` row (a speed log's scale error; `--tune` estimates it).
    pub speed_scale: f64,
    /// Subtracted from every `heading` row (deg; a compass offset; `--tune` estimates it).
    pub heading_bias_deg: f64,
    /// The filter's initial E/N variance from the log's first ranges: widened from `auv.p0` to
    /// what the ranges of the first `window_s` seconds, dead-reckoned from the `init` row, show
    /// (docs/models.md#post-start). `{ window_s = 0 }` keeps `auv.p0` as configured.
    pub start: StartVariance,
    /// Geodetic origin of the local east/north frame, needed by `_ll` log rows (docs/models.md#gill-geodesy).
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
            gps_sd_m: 3.0,
            velocity_sd_m_s: 0.05,
            speed_scale: 1.0,
            heading_bias_deg: 0.0,
            start: StartVariance::default(),
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
        if self.auv.range_gate_recovery.is_some() {
            // Post-processing applies each range through `update_range_with` and its own gate.
            p.push("auv.range_gate_recovery", "a recovery", "none here: post-processing has no gate recovery");
        }
        if let AuvModel::Current(c) = &self.model {
            c.check_fields("model.", &mut p);
        }
        self.range_gate.check_fields("range_gate.", &mut p);
        p.positive("max_gap_s", self.max_gap_s);
        p.non_negative("transponder_sd_m", self.transponder_sd_m);
        p.positive("gps_sd_m", self.gps_sd_m);
        p.positive("velocity_sd_m_s", self.velocity_sd_m_s);
        p.positive("speed_scale", self.speed_scale);
        p.finite("heading_bias_deg", self.heading_bias_deg);
        p.finite("acoustic_time_offset_s", self.acoustic_time_offset_s);
        self.outriggers.check_fields("outriggers.", &mut p);
        self.fixes.check_fields("fixes.", &mut p);
        p.non_negative("buoy_depth", self.buoy_depth);
        p.non_negative("start.window_s", self.start.window_s);
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
    /// Covariance of the smoothed E and N (m²): with `smoothed_sd`, the position's 2×2 covariance.
    pub smoothed_cov_en: f64,
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
    /// Ranges left out of the filter to be predicted (cross-validation), not in the other counts.
    pub ranges_held_out: usize,
    /// Ranges with no fix of their transponder within `fixes.max_age_s` of the transmit time.
    pub ranges_without_fix: usize,
    /// Ranges rejected by the innovation gate (`range_gate`).
    pub ranges_gated: usize,
    /// Ranges with no usable geometry (transponder overhead, non-finite numbers).
    pub ranges_unusable: usize,
    /// Rows timed before the first `init` row (not processed).
    pub rows_before_init: usize,
    /// `init` rows after the first (ignored: the filter starts once).
    pub extra_inits: usize,
    /// Silences longer than `max_gap_s` between rows, each dead-reckoned in one step.
    pub gaps: usize,
    /// Rows logged earlier than the row before them in the file (a clock that jumped back): the
    /// log is processed in time order, which interleaves the stretches before and after a jump.
    pub time_reversals: usize,
    /// The first such row, counted from 1 among the log's data rows.
    pub first_time_reversal: Option<usize>,
    /// Rows identical to an earlier row of the same time (a row logged twice): applied once.
    pub duplicate_rows: usize,
    /// The first duplicate, counted from 1 among the log's data rows.
    pub first_duplicate: Option<usize>,
    /// RMS range residual of the applied ranges before their update (innovations) and against
    /// the smoothed track (m).
    pub residual_rms_filter_m: Option<f64>,
    pub residual_rms_smoothed_m: Option<f64>,
    /// The same for the held-out ranges, which neither pass used: the prediction error.
    pub held_out_rms_filter_m: Option<f64>,
    pub held_out_rms_smoothed_m: Option<f64>,
    /// Σ −½(ln 2πS + y²/S) over the ranges the filter saw (applied or gated, not held out): the
    /// innovation log-likelihood of the ranges.
    pub range_log_likelihood: f64,
    /// Σ −½(ln 2πS + min(r²/S, g)) over the held-out ranges, r their residual against the
    /// smoothed track, S = R + h Pˢ hᵀ its predicted variance and g the gate's `max_nis`: how well
    /// the track smoothed without a range predicts it (the score `--tune` maximises over folds of
    /// held-out ranges; docs/models.md#post-tuning).
    pub held_out_log_predictive: f64,
    /// The filter's initial E and N variance (m²): `auv.p0`, or wider when the first ranges
    /// showed the start further off (`start`), and how many ranges that used.
    pub initial_en_variance_m2: [f64; 2],
    pub start_ranges: usize,
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
    /// One sentence per kind of row that was not used as logged (empty when every row was): the
    /// log's own faults, then the ranges the filter rejected.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = self.log_faults();
        w.extend(self.rejections());
        w
    }

    /// One sentence per kind of row the log itself left unusable as logged (what
    /// `hbl postprocess --strict` refuses).
    pub fn log_faults(&self) -> Vec<String> {
        let at = |row: Option<usize>| row.map_or(String::new(), |k| format!(", the first at data row {k}"));
        let mut faults = Vec::new();
        if self.time_reversals > 0 {
            faults.push(format!(
                "{} row(s) were timed earlier than the row before them (the clock jumped back{}); the log was processed in time order, interleaving the stretches",
                self.time_reversals,
                at(self.first_time_reversal)
            ));
        }
        if self.duplicate_rows > 0 {
            faults.push(format!(
                "{} row(s) repeated an earlier row of the same time exactly{}; each was applied once",
                self.duplicate_rows,
                at(self.first_duplicate)
            ));
        }
        faults.extend(sentences(&[
            (self.rows_before_init, "row(s) timed before the first 'init' row were not processed"),
            (self.extra_inits, "'init' row(s) after the first were ignored (the filter starts once)"),
            (
                self.ranges_without_fix,
                "range(s) had no transponder fix within fixes.max_age_s of their transmit time and were not applied",
            ),
            (self.gaps, "silence(s) longer than max_gap_s between rows were dead-reckoned in one step (a time typo?)"),
            (self.ranges_unusable, "range(s) had no usable geometry (transponder overhead) and were not applied"),
        ]));
        faults
    }

    /// One sentence per kind of range the filter set aside on the evidence of the data: a gated
    /// range is an acoustic outlier the gate caught (Gill's field ranges hold about 5 % of them,
    /// Gill 2013, §2.4.1), not a fault of the log.
    pub fn rejections(&self) -> Vec<String> {
        sentences(&[(self.ranges_gated, "range(s) were rejected by the innovation gate (range_gate)")])
    }
}

/// "n what" for every count above zero.
fn sentences(counts: &[(usize, &str)]) -> Vec<String> {
    counts.iter().filter(|(n, _)| *n > 0).map(|(n, what)| format!("{n} {what}")).collect()
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
    pub beacon: BeaconId,
    /// False when the gate rejected it or it was held out.
    pub applied: bool,
    /// Left out of the filter on purpose (cross-validation): only predicted.
    pub held_out: bool,
    /// Against the filter's prediction just before the update (the innovation).
    pub innovation: f64,
    /// √S, the innovation's predicted SD (m).
    pub innovation_sd: f64,
    /// Against the smoothed track at the same step.
    pub smoothed: f64,
    /// The smoothed residual's predicted SD √(R + h Pˢ hᵀ) (m): the range noise with the smoothed
    /// track's own uncertainty along the line of sight.
    pub smoothed_sd: f64,
    /// The range noise alone √R (m), with the transponder fix's term along the smoothed line of sight.
    pub noise_sd: f64,
    /// Normalised innovation squared y²/S (χ² with 1 degree of freedom when consistent).
    pub nis: f64,
}

/// Root mean square, None for no values.
fn rms(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v * v, n + 1));
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// One logged fix of a beacon's vehicle: position, depth, (ship) heading in math radians, and the
/// row's horizontal SD if it gave one.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Fix {
    t: f64,
    e: f64,
    n: f64,
    z: f64,
    psi: f64,
    sd: Option<f64>,
}

impl Fix {
    fn lerp(&self, b: &Fix, t: f64) -> Fix {
        let f = (t - self.t) / (b.t - self.t);
        // The less certain of the two fixes bounds the interpolated one.
        let sd = match (self.sd, b.sd) {
            (Some(x), Some(y)) => Some(x.max(y)),
            (x, y) => x.or(y),
        };
        Fix {
            t,
            e: self.e + f * (b.e - self.e),
            n: self.n + f * (b.n - self.n),
            z: self.z + f * (b.z - self.z),
            psi: self.psi + f * wrap_pi(b.psi - self.psi),
            sd,
        }
    }
}

/// A vehicle's fixes in time order, matched to transmit times by [`FixMatching`]; a moored
/// (`fixed`) beacon's nearest fix holds at every time.
#[derive(Debug, Default)]
struct Track {
    fixes: Vec<Fix>,
    fixed: bool,
}

impl Track {
    /// The vehicle at time `t`, or None when no fix is fresh enough.
    fn at(&self, t: f64, m: &FixMatching) -> Option<Fix> {
        let i = self.fixes.partition_point(|f| f.t <= t);
        let (before, after) = (i.checked_sub(1).map(|k| &self.fixes[k]), self.fixes.get(i));
        let age = |f: &Fix| (f.t - t).abs();
        let nearest = [before, after].into_iter().flatten().min_by(|a, b| age(a).total_cmp(&age(b)))?;
        if self.fixed || age(nearest) <= m.match_tolerance_s {
            return Some(*nearest);
        }
        match (m.between, before, after) {
            (FixUse::Linear, Some(a), Some(b)) if age(nearest) <= m.max_age_s => Some(a.lerp(b, t)),
            (_, Some(a), _) if age(a) <= m.max_age_s => Some(*a),
            _ => None,
        }
    }
}

/// Every beacon's track, and the version-1 ship whose outriggers are beacons 14 and 15.
#[derive(Debug, Default)]
struct Beacons {
    tracks: BTreeMap<BeaconId, Track>,
    ship: Track,
}

impl Beacons {
    fn from_rows(rows: &[LogRow], order: &[usize]) -> Beacons {
        let mut b = Beacons::default();
        for row in order.iter().map(|&i| &rows[i]) {
            match row.obs {
                Observation::ShipFix { e, n, compass_deg } => {
                    b.ship.fixes.push(Fix { t: row.t, e, n, z: 0.0, psi: math_heading(compass_deg), sd: None })
                }
                Observation::BeaconFix { beacon, e, n, depth, fixed } => {
                    let track = b.tracks.entry(beacon).or_default();
                    track.fixed |= fixed;
                    track.fixes.push(Fix { t: row.t, e, n, z: depth, psi: 0.0, sd: row.sigma });
                }
                _ => {}
            }
        }
        b
    }

    /// Where `beacon` was at `t` and its horizontal SD if its fix gave one.
    fn at(&self, beacon: BeaconId, t: f64, cfg: &PostConfig) -> Option<(Vec3, Option<f64>)> {
        if let Some(track) = self.tracks.get(&beacon) {
            return track.at(t, &cfg.fixes).map(|f| (Vec3::new(f.e, f.n, f.z), f.sd));
        }
        match u8::try_from(beacon).ok().and_then(Transmitter::from_modem_id) {
            Some(Transmitter::Ship(side)) => {
                self.ship.at(t, &cfg.fixes).map(|x| (cfg.outriggers.position(side, x.e, x.n, x.psi), None))
            }
            _ => None,
        }
    }
}

fn math_heading(compass_deg: f64) -> f64 {
    Heading::from(CompassDeg(compass_deg)).radians()
}

/// Runs the post-processing EKF and the RTS smoother over a version-1 log.
pub fn postprocess(entries: &[Entry], cfg: &PostConfig) -> Result<PostResult, PostError> {
    postprocess_rows(&fieldlog::from_v1(entries, cfg.buoy_depth), cfg)
}

/// Runs the post-processing EKF and the RTS smoother over general log rows.
pub fn postprocess_rows(rows: &[LogRow], cfg: &PostConfig) -> Result<PostResult, PostError> {
    run(rows, cfg, Pass::FULL)
}

/// What one pass over a log computes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Pass {
    /// Record the compact history and run the backward pass (false: forward filter only).
    pub smooth: bool,
    /// Leave every k-th range out of the filter and only predict it (0: use every range): the
    /// ranges numbered (from 1) n with n mod k = `hold_out_phase` mod k.
    pub hold_out_every: usize,
    pub hold_out_phase: usize,
    /// Longest prediction piece (s) instead of `auv.step_s`: the tuning's coarse steps over its
    /// block-averaged dead reckoning. Q stays per `auv.step_s` (a step of h adds Q·h/step_s), so
    /// the process noise means the same at any piece length.
    pub prediction_step_s: Option<f64>,
    /// Predict every range without applying it (the start's pre-pass): `held_out` still marks
    /// the pass's held-out ones.
    pub predict_only: bool,
}

impl Pass {
    /// A full pass: every range used, smoothed, at the log's rate.
    pub(crate) const FULL: Pass =
        Pass { smooth: true, hold_out_every: 0, hold_out_phase: 0, prediction_step_s: None, predict_only: false };
}

/// One pass of the filter (and smoother) over the rows, processed in time order.
pub(crate) fn run(rows: &[LogRow], cfg: &PostConfig, pass: Pass) -> Result<PostResult, PostError> {
    cfg.validate()?;
    let time = |r: &LogRow| match r.obs {
        Observation::Range { .. } => r.t + cfg.acoustic_time_offset_s,
        _ => r.t,
    };
    // Time order as indices: the rows are not copied (a day's log is millions of rows).
    let mut order: Vec<usize> = (0..rows.len()).collect();
    order.sort_by(|&a, &b| time(&rows[a]).total_cmp(&time(&rows[b])));
    let (t0, init) = order
        .iter()
        .find_map(|&i| match rows[i].obs {
            Observation::Init { e, n, speed, compass_deg } => Some((time(&rows[i]), (e, n, speed, compass_deg))),
            _ => None,
        })
        .ok_or(PostError::NoInit)?;
    let beacons = Beacons::from_rows(rows, &order);
    let reversals: Vec<usize> = (1..rows.len()).filter(|&i| rows[i].t < rows[i - 1].t).collect();
    let duplicate = duplicates(rows, &order, &time);
    let first_duplicate = duplicate.iter().position(|&d| d).map(|i| i + 1);
    let summary = PostSummary {
        time_reversals: reversals.len(),
        first_time_reversal: reversals.first().map(|i| i + 1),
        duplicate_rows: duplicate.iter().filter(|&&d| d).count(),
        first_duplicate,
        rows_before_init: order.iter().filter(|&&i| time(&rows[i]) < t0).count(),
        extra_inits: order
            .iter()
            .filter(|&&i| time(&rows[i]) >= t0 && matches!(rows[i].obs, Observation::Init { .. }))
            .count()
            - 1,
        ..PostSummary::default()
    };
    let mut params = AuvParams { range_gate: cfg.range_gate, ..cfg.auv.clone() };
    let mut summary = summary;
    if cfg.start.window_s > 0.0 && !pass.predict_only {
        let pre = Pass { smooth: false, predict_only: true, ..pass };
        let (p0, n) = start_variance(&run(rows, cfg, pre)?.residuals, t0 + cfg.start.window_s, &cfg.auv.p0);
        params.p0[0] = params.p0[0].max(p0);
        params.p0[1] = params.p0[1].max(p0);
        summary.start_ranges = n;
    }
    summary.initial_en_variance_m2 = [params.p0[0], params.p0[1]];
    let (e0, n0, speed0, psi0) = (init.0, init.1, init.2, math_heading(init.3));
    // The start's pre-pass needs only its window.
    let end = if pass.predict_only { t0 + cfg.start.window_s } else { f64::INFINITY };
    let events = order
        .iter()
        .filter(|&&i| !duplicate[i])
        .map(|&i| (time(&rows[i]), &rows[i]))
        .filter(|(t, _)| *t >= t0)
        .take_while(|(t, _)| *t <= end);
    let run = Run { beacons: &beacons, cfg, pass };
    match cfg.model {
        AuvModel::Thesis => run.filter(AuvEkf::new(t0, e0, n0, speed0, psi0, params), events, summary),
        AuvModel::Current(c) => run.filter(AuvEkf::with_current(t0, e0, n0, speed0, psi0, params, c), events, summary),
    }
}

/// The start's E/N variance the pre-pass's ranges received before `until` show (0 when they show
/// none), and how many of them (those the pass does not hold out) it used ([`StartVariance`]).
fn start_variance(residuals: &[RangeResidual], until: f64, p0: &[f64; 5]) -> (f64, usize) {
    let start = p0[0].max(p0[1]);
    let early: Vec<f64> = residuals
        .iter()
        .filter(|r| r.t <= until && !r.held_out && r.innovation_sd.is_finite())
        .map(|r| r.innovation.powi(2) - (r.innovation_sd.powi(2) - start))
        .collect();
    if early.is_empty() {
        return (0.0, 0);
    }
    ((early.iter().sum::<f64>() / early.len() as f64).max(0.0), early.len())
}

/// Which rows repeat an earlier row exactly (same time, observation and σ), by file index. Rows of
/// one time are adjacent in `order`; each is compared with at most the `DUPLICATE_WINDOW` rows of
/// its time before it, so a log of one repeated time stays linear.
fn duplicates(rows: &[LogRow], order: &[usize], time: &dyn Fn(&LogRow) -> f64) -> Vec<bool> {
    const DUPLICATE_WINDOW: usize = 64;
    let mut duplicate = vec![false; rows.len()];
    let mut group_start = 0;
    for (k, &i) in order.iter().enumerate() {
        if time(&rows[order[group_start]]) != time(&rows[i]) {
            group_start = k;
        }
        let from = group_start.max(k.saturating_sub(DUPLICATE_WINDOW));
        duplicate[i] = order[from..k].iter().any(|&j| rows[j] == rows[i]);
    }
    duplicate
}

/// The filtered states of every step, packed: per step t, the heading rate of the prediction
/// into it, x⁺ and the upper triangle of P⁺ (lossless: the filter keeps P exactly symmetric).
/// The priors, F and Q are recomputed in the backward pass by the same code as forward, so the
/// smoother gets bit-identical inputs at 22 numbers (176 B) a step for 5 states instead of 111.
pub struct CompactHistory<const M: usize> {
    data: Vec<f64>,
}

impl<const M: usize> CompactHistory<M> {
    const STRIDE: usize = 2 + M + M * (M + 1) / 2;

    /// Bytes kept per step, with the output sample: what the work limits estimate memory with.
    pub const STEP_BYTES: usize = Self::STRIDE * std::mem::size_of::<f64>() + std::mem::size_of::<PostSample>();

    /// Steps between two hand-backs of the consumed history's memory (about 10 MB of it).
    const RELEASE_EVERY: usize = 1 << 16;

    fn len(&self) -> usize {
        self.data.len() / Self::STRIDE
    }
    /// Drops every step from `steps` on and returns their memory to the allocator (a large
    /// allocation shrinks in place).
    fn keep_first(&mut self, steps: usize) {
        self.data.truncate(steps * Self::STRIDE);
        self.data.shrink_to_fit();
    }
    /// Records the filter's state: a new step when its time moved, else the same step updated.
    fn record(&mut self, ekf: &Ekf<M>, yaw_rate: f64) {
        let same_step = self.len() > 0 && self.data[self.data.len() - Self::STRIDE] == ekf.t();
        if same_step {
            let at = self.data.len() - Self::STRIDE;
            self.data.truncate(at + 2);
        } else {
            self.data.extend([ekf.t(), yaw_rate]);
        }
        self.data.extend(ekf.x().iter());
        let p = ekf.p();
        for j in 0..M {
            self.data.extend((0..=j).map(|i| p[(i, j)]));
        }
    }
    /// Step k: its time, the heading rate into it, and the filtered estimate.
    fn get(&self, k: usize) -> (f64, f64, Smoothed<M>) {
        let d = &self.data[k * Self::STRIDE..(k + 1) * Self::STRIDE];
        let x = SVector::<f64, M>::from_column_slice(&d[2..2 + M]);
        let mut p = SMatrix::<f64, M, M>::zeros();
        let mut it = d[2 + M..].iter();
        for j in 0..M {
            for i in 0..=j {
                let v = it.next().copied().unwrap_or(f64::NAN);
                p[(i, j)] = v;
                p[(j, i)] = v;
            }
        }
        (d[0], d[1], Smoothed { t: d[0], x, p })
    }
}

/// A range that reached the filter, with what the smoothed residual needs.
struct RangeSeen {
    residual: RangeResidual,
    step: usize,
    range: f64,
    at: Vec3,
    auv_depth: Option<f64>,
    /// The range's noise variance and its transponder fix's horizontal SD.
    noise: (f64, f64),
}

/// One post-processing pass over time-sorted events, for either state vector.
struct Run<'a> {
    beacons: &'a Beacons,
    cfg: &'a PostConfig,
    pass: Pass,
}

/// A gate no range passes: a held-out range is predicted (innovation, S, NIS), never applied.
const HOLD_OUT: Gate = Gate { max_abs_residual: Some(-1.0), max_nis: None };

impl Run<'_> {
    fn filter<'r, const M: usize>(
        &self,
        mut f: AuvEkf<M>,
        events: impl Iterator<Item = (f64, &'r LogRow)>,
        mut summary: PostSummary,
    ) -> Result<PostResult, PostError> {
        let cfg = self.cfg;
        let mut history = CompactHistory::<M> { data: Vec::new() };
        let record = |f: &AuvEkf<M>, yaw_rate: f64, history: &mut CompactHistory<M>| {
            if self.pass.smooth {
                history.record(f.ekf(), yaw_rate);
            }
            history.len().saturating_sub(1)
        };
        record(&f, 0.0, &mut history);
        let (mut yaw_rate, mut depth) = (0.0, None);
        let mut ranges = Vec::new();
        let mut truth_at: Vec<(usize, [f64; 2])> = Vec::new();
        let mut log_likelihood = 0.0;
        let piece_s = self.pass.prediction_step_s.unwrap_or(cfg.auv.step_s);
        for (t, row) in events {
            // Across a silence longer than max_gap_s one prediction spans it: the history (and
            // memory) grows with the rows, never with the log's time span.
            if t - f.ekf().t() > cfg.max_gap_s {
                summary.gaps += 1;
                if f.predict_to(t, yaw_rate) {
                    record(&f, yaw_rate, &mut history);
                }
            }
            // Dynamic step: predict to the event in pieces no longer than the nominal step.
            while t - f.ekf().t() > 1e-9 {
                let to = (f.ekf().t() + piece_s).min(t);
                if !f.predict_to(to, yaw_rate) {
                    break;
                }
                record(&f, yaw_rate, &mut history);
            }
            match row.obs {
                Observation::YawRate { compass_deg_s } => yaw_rate = -compass_deg_s.to_radians(),
                Observation::Speed(s) => {
                    f.update_speed_sd(s * cfg.speed_scale, row.sigma.unwrap_or(cfg.auv.sigma_speed));
                }
                Observation::Velocity { frame, v } => {
                    f.update_velocity(frame, v, row.sigma.unwrap_or(cfg.velocity_sd_m_s));
                }
                Observation::Heading { compass_deg } => {
                    let sd = row.sigma.map_or(cfg.auv.sigma_heading, f64::to_radians);
                    f.update_heading_sd(math_heading(compass_deg - cfg.heading_bias_deg), sd);
                }
                Observation::Gps { e, n } => {
                    f.update_position(e, n, row.sigma.unwrap_or(cfg.gps_sd_m));
                }
                Observation::Depth(z) => depth = Some(z),
                Observation::Range { beacon, travel_time } => {
                    summary.ranges += 1;
                    let Some((transponder, fix_sd)) = self.beacons.at(beacon, t - travel_time, cfg) else {
                        summary.ranges_without_fix += 1;
                        continue;
                    };
                    let m = RangeMeasurement {
                        range: cfg.auv.range_noise.sound_speed * travel_time,
                        travel_time,
                        transponder,
                    };
                    let auv_depth = if cfg.slant_range { depth } else { None };
                    let k = self.pass.hold_out_every;
                    let held_out = k > 0 && summary.ranges % k == self.pass.hold_out_phase % k;
                    let variance = row.sigma.map_or_else(|| cfg.auv.range_noise.variance(travel_time), |s| s * s);
                    let gate = if held_out || self.pass.predict_only { HOLD_OUT } else { cfg.range_gate };
                    let sd = fix_sd.unwrap_or(cfg.transponder_sd_m);
                    let up = f.update_range_with(&m, auv_depth, variance, sd, &gate);
                    let step = record(&f, yaw_rate, &mut history);
                    if let (UpdateOutcome::Applied { nis } | UpdateOutcome::Gated { nis }, false) =
                        (up.outcome, held_out)
                    {
                        log_likelihood -= 0.5 * ((2.0 * std::f64::consts::PI * up.variance).ln() + nis);
                    }
                    if let UpdateOutcome::Applied { nis } | UpdateOutcome::Gated { nis } = up.outcome {
                        let residual = RangeResidual {
                            t,
                            beacon,
                            applied: up.outcome.applied(),
                            held_out,
                            innovation: up.innovation,
                            innovation_sd: up.variance.sqrt(),
                            smoothed: f64::NAN,
                            smoothed_sd: f64::NAN,
                            noise_sd: f64::NAN,
                            nis,
                        };
                        let noise = (variance, sd);
                        ranges.push(RangeSeen { residual, step, range: m.range, at: transponder, auv_depth, noise });
                    }
                    match up.outcome {
                        _ if held_out => summary.ranges_held_out += 1,
                        UpdateOutcome::Applied { .. } => summary.ranges_applied += 1,
                        UpdateOutcome::Gated { .. } => summary.ranges_gated += 1,
                        UpdateOutcome::Unusable => summary.ranges_unusable += 1,
                    }
                    continue;
                }
                Observation::Truth { e, n } => {
                    truth_at.push((history.len().saturating_sub(1), [e, n]));
                    continue;
                }
                Observation::Init { .. } | Observation::ShipFix { .. } | Observation::BeaconFix { .. } => continue,
            }
            record(&f, yaw_rate, &mut history);
        }
        summary.range_log_likelihood = log_likelihood;
        let mut samples = Vec::new();
        if self.pass.smooth {
            let mut backward = Backward::new(&ranges, &truth_at);
            samples = self.smooth(&f, history, &mut backward)?;
            score(&mut samples, &mut summary, &truth_at, &backward);
            let smoothed = backward.residual_smoothed;
            for (seen, (smoothed, sd, noise_sd)) in ranges.iter_mut().zip(smoothed) {
                seen.residual.smoothed = smoothed;
                seen.residual.smoothed_sd = sd;
                seen.residual.noise_sd = noise_sd;
                if seen.residual.held_out && sd > 0.0 {
                    // A range the gate would reject scores as one at the gate's bound: an outlier
                    // costs no more than that, so the score does not widen the noise to fit it.
                    let s = sd * sd;
                    let nis = (smoothed * smoothed / s).min(cfg.range_gate.max_nis.unwrap_or(f64::INFINITY));
                    summary.held_out_log_predictive -= 0.5 * ((2.0 * std::f64::consts::PI * s).ln() + nis);
                }
            }
        }
        let residuals: Vec<RangeResidual> = ranges.into_iter().map(|r| r.residual).collect();
        let used = |held_out: bool| residuals.iter().filter(move |r| r.held_out == held_out && (held_out || r.applied));
        summary.residual_rms_filter_m = rms(used(false).map(|r| r.innovation));
        summary.residual_rms_smoothed_m = rms(used(false).map(|r| r.smoothed).filter(|v| !v.is_nan()));
        summary.held_out_rms_filter_m = rms(used(true).map(|r| r.innovation));
        summary.held_out_rms_smoothed_m = rms(used(true).map(|r| r.smoothed).filter(|v| !v.is_nan()));
        Ok(PostResult { samples, summary, residuals })
    }

    /// The backward pass over the compact history (EKF-RTS or unscented RTS), one sample per
    /// step in time order; ranges and truth points are scored as their steps go by. The history
    /// is consumed from its end, and its memory handed back as the samples grow, so the two are
    /// never both whole (a day's log: 150 MB of history and 110 MB of samples).
    fn smooth<const M: usize>(
        &self,
        f: &AuvEkf<M>,
        mut history: CompactHistory<M>,
        backward: &mut Backward,
    ) -> Result<Vec<PostSample>, PostError> {
        let n = history.len();
        let angles = f.ekf().angles();
        let mut samples = Vec::with_capacity(n);
        let (_, _, mut later) = history.get(n - 1);
        backward.visit(n - 1, &later, &later);
        samples.push(sample(&later, &later));
        for k in (0..n - 1).rev() {
            let (_, _, filtered) = history.get(k);
            let (t_next, yaw_next, _) = history.get(k + 1);
            let h = t_next - filtered.t;
            let (x_new, jac, q) = f.prediction(&filtered.x, h, yaw_next);
            let smoothed = match self.cfg.smoother {
                SmootherKind::Ekf => {
                    let p_prior = f.prior_covariance(&filtered.x, &filtered.p, h);
                    rts_step(&filtered, &jac, &wrap(x_new, angles), &p_prior, &later, angles)
                        .ok_or(SmoothError::Singular(k + 1))?
                }
                SmootherKind::Unscented => {
                    urts_step(&filtered, &q, |x| f.mean_step(x, h, yaw_next), &later, angles, k)?
                }
            };
            backward.visit(k, &filtered, &smoothed);
            samples.push(sample(&filtered, &smoothed));
            later = smoothed;
            if k % CompactHistory::<M>::RELEASE_EVERY == 0 {
                history.keep_first(k + 1);
            }
        }
        samples.reverse();
        Ok(samples)
    }
}

fn sample<const M: usize>(filtered: &Smoothed<M>, s: &Smoothed<M>) -> PostSample {
    PostSample {
        t: filtered.t,
        filtered: [filtered.x[0], filtered.x[1]],
        filtered_sd: [filtered.p[(0, 0)].sqrt(), filtered.p[(1, 1)].sqrt()],
        smoothed: [s.x[0], s.x[1]],
        smoothed_sd: [s.p[(0, 0)].sqrt(), s.p[(1, 1)].sqrt()],
        smoothed_cov_en: s.p[(0, 1)],
        smoothed_heading_bias: s.x[BIAS],
        smoothed_current: (M > CURRENT_N).then(|| [s.x[CURRENT_E], s.x[CURRENT_N]]),
        truth: None,
    }
}

/// What the backward pass scores at the steps of ranges and truth points (both lists are in
/// step order, walked from the end).
struct Backward<'a> {
    ranges: &'a [RangeSeen],
    truth_at: &'a [(usize, [f64; 2])],
    /// Per range: its residual against the smoothed track, that residual's predicted SD and the
    /// range noise's SD.
    residual_smoothed: Vec<(f64, f64, f64)>,
    /// Per truth point: (filtered error, smoothed error, filtered NEES, smoothed NEES).
    truth_scores: Vec<(f64, f64, Option<f64>, Option<f64>)>,
}

impl<'a> Backward<'a> {
    fn new(ranges: &'a [RangeSeen], truth_at: &'a [(usize, [f64; 2])]) -> Self {
        Backward {
            ranges,
            truth_at,
            residual_smoothed: vec![(f64::NAN, f64::NAN, f64::NAN); ranges.len()],
            truth_scores: vec![(f64::NAN, f64::NAN, None, None); truth_at.len()],
        }
    }

    fn visit<const M: usize>(&mut self, k: usize, filtered: &Smoothed<M>, smoothed: &Smoothed<M>) {
        let x = &smoothed.x;
        let first = self.ranges.partition_point(|r| r.step < k);
        for (i, r) in self.ranges.iter().enumerate().skip(first).take_while(|(_, r)| r.step == k) {
            let dz = r.auv_depth.map_or(0.0, |z| z - r.at.z);
            let (de, dn) = (x[0] - r.at.x, x[1] - r.at.y);
            let predicted = de.hypot(dn).hypot(dz);
            // Line of sight h = ∂ρ/∂(E, N), as the filter's range Jacobian (zero overhead).
            let h = if predicted > 1e-6 { [de / predicted, dn / predicted] } else { [0.0, 0.0] };
            let p = &smoothed.p;
            let track = h[0] * h[0] * p[(0, 0)] + 2.0 * h[0] * h[1] * p[(0, 1)] + h[1] * h[1] * p[(1, 1)];
            let (variance, fix_sd) = r.noise;
            let noise = variance + fix_sd * fix_sd * (h[0] * h[0] + h[1] * h[1]);
            self.residual_smoothed[i] = (r.range - predicted, (noise + track).sqrt(), noise.sqrt());
        }
        let first = self.truth_at.partition_point(|(s, _)| *s < k);
        for (i, (_, tr)) in self.truth_at.iter().enumerate().skip(first).take_while(|(_, (s, _))| *s == k) {
            let err = |x: &SVector<f64, M>| (x[0] - tr[0]).hypot(x[1] - tr[1]);
            self.truth_scores[i] = (err(&filtered.x), err(x), nees(filtered, *tr), nees(smoothed, *tr));
        }
    }
}

/// 2-D NEES eᵀP⁻¹e of the position against a truth point.
fn nees<const M: usize>(s: &Smoothed<M>, tr: [f64; 2]) -> Option<f64> {
    let e = nalgebra::Vector2::new(s.x[0] - tr[0], s.x[1] - tr[1]);
    let pp = s.p.fixed_view::<2, 2>(0, 0).into_owned();
    pp.cholesky().map(|c| (e.transpose() * c.solve(&e))[(0, 0)])
}

fn score(samples: &mut [PostSample], summary: &mut PostSummary, truth_at: &[(usize, [f64; 2])], b: &Backward) {
    for &(i, tr) in truth_at {
        samples[i].truth = Some(tr);
    }
    let filtered: Vec<f64> = b.truth_scores.iter().map(|s| s.0).collect();
    let smoothed_errors: Vec<f64> = b.truth_scores.iter().map(|s| s.1).collect();
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
    let both: Vec<(f64, f64)> = b.truth_scores.iter().filter_map(|s| Some((s.2?, s.3?))).collect();
    if !both.is_empty() {
        let nn = both.len() as f64;
        summary.mean_filtered_nees = Some(both.iter().map(|s| s.0).sum::<f64>() / nn);
        summary.mean_smoothed_nees = Some(both.iter().map(|s| s.1).sum::<f64>() / nn);
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
    fn the_start_variance_is_the_mean_excess_of_the_early_innovations() {
        let r = |t: f64, innovation: f64, held_out: bool| RangeResidual {
            t,
            beacon: 1,
            applied: false,
            held_out,
            innovation,
            innovation_sd: 5.0,
            smoothed: f64::NAN,
            smoothed_sd: f64::NAN,
            noise_sd: f64::NAN,
            nis: 0.0,
        };
        let p0 = [16.0, 9.0, 0.0, 0.0, 0.0];
        // S = 25 of which 16 is the start's: each range's excess is y² − 9.
        let early = [r(10.0, 20.0, false), r(20.0, 0.0, false), r(30.0, 50.0, true), r(200.0, 50.0, false)];
        assert_eq!(start_variance(&early, 120.0, &p0), ((391.0 - 9.0) / 2.0, 2));
        assert_eq!(start_variance(&early[1..2], 120.0, &p0), (0.0, 1), "never below zero");
        assert_eq!(start_variance(&early[3..], 120.0, &p0), (0.0, 0), "none in the window");
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
        assert_eq!(back.len(), entries.len(), "{text}");
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
