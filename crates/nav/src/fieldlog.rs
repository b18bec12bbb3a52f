//! The general field-log format, version 2 (documented for users in
//! `docs/log-format.md`): any number of beacons with their own tracks, GPS, DVL velocity,
//! per-row σ, and absolute (Unix) or relative time declared in the header line. This module owns
//! the row types the post-processor runs on, reading and writing version 2, and the mapping of
//! the version-1 rows (`post::Record`, still read by `post::read_log`) onto them.
//!
//! A version-2 file starts with the line `# coopnav-log 2 time=relative` (or `time=unix`), then
//! the column header `t,kind,src,v1,v2,v3,v4,sigma`, then one row per line (no comment lines,
//! so that every error's line number is the file's).

use crate::auv::VelocityFrame;
use crate::cycle::Transmitter;
use crate::post::{Entry, PostError, Record};
use coopnav_core::{LatLon, LocalFrame};
use std::io::{BufRead, BufReader, Read};

/// The version this module reads and writes.
pub const LOG_VERSION: u32 = 2;
pub const LOG_COLUMNS: [&str; 8] = ["t", "kind", "src", "v1", "v2", "v3", "v4", "sigma"];
const MAGIC: &str = "# coopnav-log";
/// Longest accepted travel time (s): 60 s is 90 km of water, beyond any acoustic modem's reach.
pub const MAX_TRAVEL_TIME_S: f64 = 60.0;

/// A beacon's id: the `src` of its ranges and fixes (any ship, buoy, CNA or moored transponder).
pub type BeaconId = u32;

/// One observation of a log row. Positions are local east/north metres (the `_ll` kinds are
/// converted on reading), headings compass degrees, rates clockwise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Observation {
    /// The filter's starting estimate (the first one is used).
    Init {
        e: f64,
        n: f64,
        speed: f64,
        compass_deg: f64,
    },
    YawRate {
        compass_deg_s: f64,
    },
    /// Speed through the water (m/s).
    Speed(f64),
    /// Velocity over ground (DVL bottom lock), m/s.
    Velocity {
        frame: VelocityFrame,
        v: [f64; 2],
    },
    Heading {
        compass_deg: f64,
    },
    Depth(f64),
    /// A GPS fix of the vehicle itself.
    Gps {
        e: f64,
        n: f64,
    },
    /// An OWTT range: received at the row's time from `beacon`, travel time in s.
    Range {
        beacon: BeaconId,
        travel_time: f64,
    },
    /// Where `beacon` was at the row's time; `fixed` = a moored transponder, valid at all times.
    BeaconFix {
        beacon: BeaconId,
        e: f64,
        n: f64,
        depth: f64,
        fixed: bool,
    },
    /// The version-1 ship: its outrigger transponders are beacons 14 (port) and 15 (starboard).
    ShipFix {
        e: f64,
        n: f64,
        compass_deg: f64,
    },
    /// A topside fix of the vehicle, only used to score the result.
    Truth {
        e: f64,
        n: f64,
    },
}

impl Observation {
    fn kind(&self) -> &'static str {
        match self {
            Observation::Init { .. } => "init",
            Observation::YawRate { .. } => "yaw_rate",
            Observation::Speed(_) => "speed",
            Observation::Velocity { frame: VelocityFrame::Body, .. } => "dvl_body",
            Observation::Velocity { frame: VelocityFrame::Earth, .. } => "dvl_earth",
            Observation::Heading { .. } => "heading",
            Observation::Depth(_) => "depth",
            Observation::Gps { .. } => "gps",
            Observation::Range { .. } => "range",
            Observation::BeaconFix { fixed: false, .. } => "beacon_fix",
            Observation::BeaconFix { fixed: true, .. } => "beacon_fixed",
            Observation::ShipFix { .. } => "ship_fix",
            Observation::Truth { .. } => "truth",
        }
    }

    /// The row's (src, v1..v4) as written, positions as given.
    fn fields(&self) -> [String; 5] {
        let f = |v: f64| format!("{v}");
        let e = String::new;
        match *self {
            Observation::Init { e: x, n, speed, compass_deg } => [e(), f(x), f(n), f(speed), f(compass_deg)],
            Observation::YawRate { compass_deg_s: v } | Observation::Speed(v) | Observation::Depth(v) => {
                [e(), f(v), e(), e(), e()]
            }
            Observation::Heading { compass_deg } => [e(), f(compass_deg), e(), e(), e()],
            Observation::Velocity { v, .. } => [e(), f(v[0]), f(v[1]), e(), e()],
            Observation::Gps { e: x, n } | Observation::Truth { e: x, n } => [e(), f(x), f(n), e(), e()],
            Observation::Range { beacon, travel_time } => [beacon.to_string(), f(travel_time), e(), e(), e()],
            Observation::BeaconFix { beacon, e: x, n, depth, .. } => [beacon.to_string(), f(x), f(n), f(depth), e()],
            Observation::ShipFix { e: x, n, compass_deg } => [e(), f(x), f(n), f(compass_deg), e()],
        }
    }

    /// The local (east, north) of the position rows (those with an `_ll` form).
    fn position(&self) -> Option<(f64, f64)> {
        match *self {
            Observation::Init { e, n, .. }
            | Observation::Gps { e, n }
            | Observation::BeaconFix { e, n, .. }
            | Observation::ShipFix { e, n, .. }
            | Observation::Truth { e, n } => Some((e, n)),
            _ => None,
        }
    }

    /// What a row's σ means for this kind, None when the kind takes no σ.
    fn sigma_unit(&self) -> Option<&'static str> {
        match self {
            Observation::Speed(_) | Observation::Velocity { .. } => Some("m/s"),
            Observation::Heading { .. } => Some("deg"),
            Observation::Gps { .. } | Observation::Range { .. } | Observation::BeaconFix { .. } => Some("m"),
            _ => None,
        }
    }
}

/// One time-stamped row with its optional σ (the kind's noise SD; absent = the config's).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogRow {
    /// Seconds since the log's time origin.
    pub t: f64,
    pub obs: Observation,
    pub sigma: Option<f64>,
}

/// How the header declares the `t` column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeBase {
    /// Seconds from any origin (e.g. the mission start).
    Relative,
    /// Unix seconds. On reading, rows keep seconds since `origin` (the first row's whole second),
    /// so the filter's times stay small; f64 keeps a Unix time to about 0.2 µs.
    Unix { origin: f64 },
}

/// A whole log: its time base and rows in file order.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldLog {
    pub time: TimeBase,
    pub rows: Vec<LogRow>,
}

/// The version-1 rows on the general ones: the buoy is beacon 13 at `buoy_depth`, ranges keep
/// their modem ids, every row has no σ.
pub fn from_v1(entries: &[Entry], buoy_depth: f64) -> Vec<LogRow> {
    entries
        .iter()
        .map(|en| {
            let obs = match en.record {
                Record::Init { e, n, speed, compass_deg } => Observation::Init { e, n, speed, compass_deg },
                Record::YawRate { compass_deg_s } => Observation::YawRate { compass_deg_s },
                Record::Speed(s) => Observation::Speed(s),
                Record::Heading { compass_deg } => Observation::Heading { compass_deg },
                Record::Depth(z) => Observation::Depth(z),
                Record::Range { src, travel_time } => {
                    Observation::Range { beacon: BeaconId::from(src.modem_id()), travel_time }
                }
                Record::ShipFix { e, n, compass_deg } => Observation::ShipFix { e, n, compass_deg },
                Record::BuoyFix { e, n } => Observation::BeaconFix {
                    beacon: BeaconId::from(Transmitter::Buoy.modem_id()),
                    e,
                    n,
                    depth: buoy_depth,
                    fixed: false,
                },
                Record::Truth { e, n } => Observation::Truth { e, n },
            };
            LogRow { t: en.t, obs, sigma: None }
        })
        .collect()
}

/// One CSV row being parsed: its fields and line number, for errors that name both.
pub(crate) struct Fields<'a> {
    pub row: &'a csv::StringRecord,
    pub line: u64,
}

impl Fields<'_> {
    pub fn text(&self, i: usize) -> &str {
        self.row.get(i).unwrap_or("").trim()
    }
    /// Column `i` (named `field` in errors) as a finite number.
    pub fn num(&self, i: usize, field: &'static str) -> Result<f64, PostError> {
        let v = self.text(i);
        match v.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(PostError::Number {
                line: self.line,
                field,
                value: coopnav_core::validation::quoted(v.to_string()),
            }),
        }
    }
    /// v1, v2 of a position row as local (east, north): metres, or latitude/longitude placed by
    /// `frame` when the kind ends in `_ll`.
    pub fn position(&self, kind: &str, frame: Option<&LocalFrame>) -> Result<(f64, f64), PostError> {
        let (a, b) = (self.num(3, "v1")?, self.num(4, "v2")?);
        if !kind.ends_with("_ll") {
            return Ok((a, b));
        }
        let f = frame.ok_or_else(|| PostError::NoOrigin { line: self.line, kind: kind.to_string() })?;
        let ll = LatLon::new(a, b).map_err(|source| PostError::LatLon { line: self.line, source })?;
        Ok(f.to_plane(ll))
    }
}

/// Reads a version-2 log (errors name the line and field); `frame` places the `_ll` rows.
pub fn read_field_log<R: Read>(input: R, frame: Option<&LocalFrame>) -> Result<FieldLog, PostError> {
    let mut input = BufReader::new(input);
    let mut first = String::new();
    input.read_line(&mut first).map_err(csv::Error::from)?;
    let declared = parse_version_line(&first)?;
    let mut r = csv::ReaderBuilder::new().has_headers(true).flexible(false).from_reader(input);
    let header: Vec<String> = r.headers()?.iter().map(|s| s.trim().to_string()).collect();
    if header != LOG_COLUMNS {
        return Err(PostError::Header { found: header, expected: LOG_COLUMNS.iter().map(|s| s.to_string()).collect() });
    }
    let mut rows = Vec::new();
    let mut record = csv::StringRecord::new();
    while r.read_record(&mut record).map_err(line_counted)? {
        // The version line was read before the CSV reader started counting.
        let line = record.position().map_or(0, |p| p.line()) + 1;
        let row = parse_row(&Fields { row: &record, line }, frame)?;
        check_ranges(&row, line)?;
        rows.push(row);
    }
    let time = match declared {
        DeclaredTime::Relative => TimeBase::Relative,
        DeclaredTime::Unix => {
            let origin = rows.first().map_or(0.0, |r| r.t.floor());
            rows.iter_mut().for_each(|r| r.t -= origin);
            TimeBase::Unix { origin }
        }
    };
    Ok(FieldLog { time, rows })
}

/// True when the text starts like a version-2 (or later) log.
pub fn is_field_log(first_bytes: &[u8]) -> bool {
    first_bytes.starts_with(MAGIC.as_bytes())
}

enum DeclaredTime {
    Relative,
    Unix,
}

/// A CSV error with the file's line number (the CSV reader starts counting after the version line).
fn line_counted(e: csv::Error) -> PostError {
    match e.kind() {
        csv::ErrorKind::UnequalLengths { pos: Some(pos), expected_len, len } => {
            PostError::FieldCount { line: pos.line() + 1, expected: *expected_len, found: *len }
        }
        _ => PostError::Csv(e),
    }
}

fn parse_version_line(line: &str) -> Result<DeclaredTime, PostError> {
    let bad = || PostError::VersionLine { found: line.trim_end().to_string() };
    let rest = line.trim_end().strip_prefix(MAGIC).ok_or_else(bad)?;
    let mut words = rest.split_whitespace();
    let version: u32 = words.next().and_then(|v| v.parse().ok()).ok_or_else(bad)?;
    if version != LOG_VERSION {
        return Err(PostError::Version { found: version });
    }
    match words.next() {
        Some("time=relative") => Ok(DeclaredTime::Relative),
        Some("time=unix") => Ok(DeclaredTime::Unix),
        _ => Err(bad()),
    }
}

/// What a logged quantity can physically be: generous bounds that catch a corrupt or
/// mis-scaled field (1e300 s, a position in a speed column), not a noisy reading. Invented.
pub const TIME_RANGE_S: (f64, f64) = (-1e10, 1e10);
pub const POSITION_RANGE_M: (f64, f64) = (-1e8, 1e8);
pub const SPEED_RANGE_M_S: (f64, f64) = (-10.0, 20.0);
pub const HEADING_RANGE_DEG: (f64, f64) = (-360.0, 720.0);
pub const YAW_RATE_RANGE_DEG_S: (f64, f64) = (-360.0, 360.0);
pub const DEPTH_RANGE_M: (f64, f64) = (-20.0, 11_000.0);

/// Refuses a row whose time or values lie outside what they can physically be, naming the line
/// and the field (a value that large would reach the filter as a covariance it cannot invert).
fn check_ranges(row: &LogRow, line: u64) -> Result<(), PostError> {
    let within = |field: &'static str, value: f64, (lo, hi): (f64, f64), allowed: &'static str| {
        if (lo..=hi).contains(&value) {
            Ok(())
        } else {
            Err(PostError::OutOfRange { line, field, value, allowed })
        }
    };
    within("t", row.t, TIME_RANGE_S, "a time within ±1e10 s")?;
    if let Some((e, n)) = row.obs.position() {
        within("v1", e, POSITION_RANGE_M, "a position within ±1e8 m")?;
        within("v2", n, POSITION_RANGE_M, "a position within ±1e8 m")?;
    }
    let speed = "a speed in [-10, 20] m/s";
    match row.obs {
        Observation::Init { speed: s, compass_deg, .. } => {
            within("v3", s, SPEED_RANGE_M_S, speed)?;
            within("v4", compass_deg, HEADING_RANGE_DEG, "a compass heading in [-360, 720] deg")
        }
        Observation::Speed(s) => within("v1", s, SPEED_RANGE_M_S, speed),
        Observation::Velocity { v, .. } => {
            within("v1", v[0], SPEED_RANGE_M_S, speed)?;
            within("v2", v[1], SPEED_RANGE_M_S, speed)
        }
        Observation::Heading { compass_deg } => {
            within("v1", compass_deg, HEADING_RANGE_DEG, "a compass heading in [-360, 720] deg")
        }
        Observation::YawRate { compass_deg_s } => {
            within("v1", compass_deg_s, YAW_RATE_RANGE_DEG_S, "a yaw rate in [-360, 360] deg/s")
        }
        Observation::Depth(d) => within("v1", d, DEPTH_RANGE_M, "a depth in [-20, 11000] m"),
        _ => Ok(()),
    }
}

fn parse_row(f: &Fields, frame: Option<&LocalFrame>) -> Result<LogRow, PostError> {
    let line = f.line;
    let t = f.num(0, "t")?;
    let kind = f.text(1);
    let beacon = || -> Result<BeaconId, PostError> {
        f.text(2).parse::<BeaconId>().map_err(|_| PostError::Beacon {
            line,
            kind: kind.to_string(),
            src: f.text(2).into(),
        })
    };
    let obs = match kind {
        "init" | "init_ll" => {
            let (e, n) = f.position(kind, frame)?;
            Observation::Init { e, n, speed: f.num(5, "v3")?, compass_deg: f.num(6, "v4")? }
        }
        "yaw_rate" => Observation::YawRate { compass_deg_s: f.num(3, "v1")? },
        "speed" => Observation::Speed(f.num(3, "v1")?),
        "dvl_body" | "dvl_earth" => {
            let frame = if kind == "dvl_body" { VelocityFrame::Body } else { VelocityFrame::Earth };
            Observation::Velocity { frame, v: [f.num(3, "v1")?, f.num(4, "v2")?] }
        }
        "heading" => Observation::Heading { compass_deg: f.num(3, "v1")? },
        "depth" => Observation::Depth(f.num(3, "v1")?),
        "gps" | "gps_ll" => {
            let (e, n) = f.position(kind, frame)?;
            Observation::Gps { e, n }
        }
        "range" => {
            let travel_time = f.num(3, "v1")?;
            if !(travel_time > 0.0 && travel_time <= MAX_TRAVEL_TIME_S) {
                return Err(PostError::TravelTimeV2 { line, value: travel_time, max: MAX_TRAVEL_TIME_S });
            }
            Observation::Range { beacon: beacon()?, travel_time }
        }
        "beacon_fix" | "beacon_fix_ll" | "beacon_fixed" | "beacon_fixed_ll" => {
            let (e, n) = f.position(kind, frame)?;
            let depth = if f.text(5).is_empty() { 0.0 } else { f.num(5, "v3")? };
            Observation::BeaconFix { beacon: beacon()?, e, n, depth, fixed: kind.starts_with("beacon_fixed") }
        }
        "ship_fix" | "ship_fix_ll" => {
            let (e, n) = f.position(kind, frame)?;
            Observation::ShipFix { e, n, compass_deg: f.num(5, "v3")? }
        }
        "truth" | "truth_ll" => {
            let (e, n) = f.position(kind, frame)?;
            Observation::Truth { e, n }
        }
        other => return Err(PostError::KindV2 { line, kind: other.to_string() }),
    };
    let sigma = match (f.text(7), obs.sigma_unit()) {
        ("", _) => None,
        (_, None) => return Err(PostError::SigmaNotUsed { line, kind: kind.to_string() }),
        (_, Some(_)) => {
            let s = f.num(7, "sigma")?;
            if !(s > 0.0) {
                return Err(PostError::Number { line, field: "sigma", value: f.text(7).to_string() });
            }
            Some(s)
        }
    };
    Ok(LogRow { t, obs, sigma })
}

/// Writes a version-2 log: positions in metres, or with a `frame` as `_ll` rows.
pub fn write_field_log<W: std::io::Write>(
    mut out: W,
    log: &FieldLog,
    frame: Option<&LocalFrame>,
) -> Result<(), PostError> {
    let (time, origin) = match log.time {
        TimeBase::Relative => ("relative", 0.0),
        TimeBase::Unix { origin } => ("unix", origin),
    };
    writeln!(out, "{MAGIC} {LOG_VERSION} time={time}").map_err(csv::Error::from)?;
    let mut w = csv::Writer::from_writer(out);
    w.write_record(LOG_COLUMNS)?;
    for row in &log.rows {
        let [src, mut v1, mut v2, v3, v4] = row.obs.fields();
        let mut kind = row.obs.kind().to_string();
        if let (Some(f), Some((e, n))) = (frame, row.obs.position()) {
            let ll = f.from_plane(e, n).map_err(|source| PostError::Unplaceable { t: row.t, source })?;
            kind.push_str("_ll");
            (v1, v2) = (format!("{}", ll.lat_deg()), format!("{}", ll.lon_deg()));
        }
        let sigma = row.sigma.map_or(String::new(), |s| format!("{s}"));
        w.write_record([format!("{}", row.t + origin), kind, src, v1, v2, v3, v4, sigma])?;
    }
    w.flush().map_err(csv::Error::from)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "# coopnav-log 2 time=relative\nt,kind,src,v1,v2,v3,v4,sigma\n";

    fn read(text: &str) -> Result<FieldLog, PostError> {
        read_field_log(text.as_bytes(), None)
    }

    fn every_kind() -> Vec<LogRow> {
        let row = |t: f64, obs: Observation, sigma: Option<f64>| LogRow { t, obs, sigma };
        vec![
            row(0.0, Observation::Init { e: 1.0, n: 2.0, speed: 1.5, compass_deg: 45.0 }, None),
            row(0.1, Observation::YawRate { compass_deg_s: -0.5 }, None),
            row(0.1, Observation::Speed(1.5), Some(0.04)),
            row(0.1, Observation::Velocity { frame: VelocityFrame::Body, v: [1.5, -0.1] }, Some(0.02)),
            row(0.1, Observation::Velocity { frame: VelocityFrame::Earth, v: [1.0, 1.1] }, None),
            row(0.1, Observation::Heading { compass_deg: 44.0 }, Some(1.0)),
            row(0.1, Observation::Depth(20.0), None),
            row(0.2, Observation::Gps { e: 3.0, n: 4.0 }, Some(2.5)),
            row(0.3, Observation::Range { beacon: 2_000_000, travel_time: 3.25 }, Some(4.0)),
            row(0.3, Observation::BeaconFix { beacon: 7, e: -50.0, n: 60.0, depth: 2.0, fixed: false }, Some(1.0)),
            row(0.3, Observation::BeaconFix { beacon: 8, e: 500.0, n: 0.0, depth: 95.0, fixed: true }, None),
            row(0.4, Observation::ShipFix { e: 10.0, n: 11.0, compass_deg: 270.0 }, None),
            row(0.5, Observation::Truth { e: 1.5, n: 2.5 }, None),
        ]
    }

    #[test]
    fn every_kind_round_trips_with_relative_and_unix_time() {
        for time in [TimeBase::Relative, TimeBase::Unix { origin: 1_700_000_000.0 }] {
            let log = FieldLog { time, rows: every_kind() };
            let mut buf = Vec::new();
            write_field_log(&mut buf, &log, None).unwrap();
            let text = String::from_utf8(buf).unwrap();
            assert!(is_field_log(text.as_bytes()), "{text}");
            let back = read(&text).unwrap();
            assert_eq!(back.time, log.time);
            // Unix times keep their fraction to f64 resolution near 1.7e9 s (2.4e-7 s).
            for (a, b) in log.rows.iter().zip(&back.rows) {
                assert!((a.t - b.t).abs() < 5e-7, "{a:?} {b:?}");
                assert_eq!((a.obs, a.sigma), (b.obs, b.sigma));
            }
            assert_eq!(back.rows.len(), log.rows.len());
        }
    }

    fn pend_oreille() -> LocalFrame {
        LocalFrame::new(coopnav_core::Geodetic::new(LatLon::new(47.97, -116.5).unwrap(), 630.0).unwrap())
    }

    #[test]
    fn latlon_rows_round_trip() {
        let frame = pend_oreille();
        let log = FieldLog { time: TimeBase::Relative, rows: every_kind() };
        let mut buf = Vec::new();
        write_field_log(&mut buf, &log, Some(&frame)).unwrap();
        let text = String::from_utf8(buf).unwrap();
        assert!(text.contains(",gps_ll,") && text.contains(",beacon_fixed_ll,8,"), "{text}");
        let back = read_field_log(text.as_bytes(), Some(&frame)).unwrap();
        assert_eq!(back.rows.len(), log.rows.len(), "{text}");
        for (a, b) in log.rows.iter().zip(&back.rows) {
            match (a.obs.position(), b.obs.position()) {
                (Some(p), Some(q)) => assert!((p.0 - q.0).abs() < 1e-6 && (p.1 - q.1).abs() < 1e-6),
                _ => assert_eq!(a, b),
            }
        }
    }

    #[test]
    fn unix_time_is_kept_relative_to_the_first_whole_second() {
        let log = read("# coopnav-log 2 time=unix\nt,kind,src,v1,v2,v3,v4,sigma\n1700000123.75,speed,,1,,,,\n1700000124.25,depth,,3,,,,\n").unwrap();
        assert_eq!(log.time, TimeBase::Unix { origin: 1_700_000_123.0 });
        assert_eq!((log.rows[0].t, log.rows[1].t), (0.75, 1.25));
    }

    #[test]
    fn the_header_declares_version_and_time() {
        let e = read("t,kind,src,v1,v2,v3,v4,sigma\n").unwrap_err().to_string();
        assert!(e.contains("# coopnav-log 2 time=relative"), "{e}");
        let e = read("# coopnav-log 3 time=unix\n").unwrap_err().to_string();
        assert!(e.contains("version 3") && e.contains("2"), "{e}");
        let e = read("# coopnav-log 2\nt,kind,src,v1,v2,v3,v4,sigma\n").unwrap_err().to_string();
        assert!(e.contains("time=unix"), "{e}");
        let e = read("# coopnav-log 2 time=relative\nt,kind,src,v1,v2,v3,v4\n").unwrap_err().to_string();
        assert!(e.contains("header") && e.contains("sigma"), "{e}");
    }

    /// Every row kind, malformed, is refused with its line number and what was wrong.
    #[test]
    fn malformed_rows_of_every_kind_name_their_line() {
        let cases: [(&str, &[&str]); 21] = [
            ("0,init,,1,2,x,90,", &["v3", "\"x\""]),
            ("0,init_ll,,95,2,1,90,", &["latitude 95"]),
            ("0,yaw_rate,,,,,,", &["v1"]),
            ("0,speed,,fast,,,,", &["v1", "fast"]),
            ("0,speed,,1,,,,-2", &["sigma", "-2"]),
            ("0,dvl_body,,1,,,,", &["v2"]),
            ("0,dvl_earth,,1,inf,,,", &["v2", "inf"]),
            ("0,heading,,NaN,,,,", &["v1", "NaN"]),
            ("0,depth,,1,,,,0.5", &["sigma", "depth"]),
            ("0,gps,,1,,,,", &["v2"]),
            ("0,gps_ll,,1,200,,,", &["longitude 200"]),
            ("0,range,,0.5,,,,", &["src", "beacon id"]),
            ("0,range,3,0,,,,", &["travel time", "60"]),
            ("0,range,3,75,,,,", &["travel time"]),
            ("0,range,-1,0.5,,,,", &["src", "-1"]),
            ("0,beacon_fix,buoy,1,2,,,", &["src", "buoy"]),
            ("0,beacon_fixed,4,1,2,deep,,", &["v3", "deep"]),
            ("0,ship_fix,,1,2,,,", &["v3"]),
            ("0,truth,,1,,,,", &["v2"]),
            ("x,speed,,1,,,,", &["field 't'"]),
            ("0,warp,,1,,,,", &["warp", "dvl_body"]),
        ];
        for (row, needles) in cases {
            let text = format!("{HEAD}0,depth,,1,,,,\n0,depth,,2,,,,\n{row}\n");
            let e = read_field_log(text.as_bytes(), Some(&pend_oreille())).unwrap_err().to_string();
            assert!(e.contains("line 5"), "{row}: {e}");
            for n in needles {
                assert!(e.contains(n), "{row}: '{n}' not in: {e}");
            }
        }
        let e = read(&format!("{HEAD}0,speed,,1,,\n")).unwrap_err().to_string();
        assert!(e.contains("line 3") && e.contains("fields"), "{e}");
    }

    #[test]
    fn v1_rows_map_onto_beacons() {
        let entries = [
            Entry { t: 1.0, record: Record::BuoyFix { e: 1.0, n: 2.0 } },
            Entry { t: 2.0, record: Record::Range { src: Transmitter::Buoy, travel_time: 0.5 } },
        ];
        let rows = from_v1(&entries, 1.5);
        assert_eq!(rows[0].obs, Observation::BeaconFix { beacon: 13, e: 1.0, n: 2.0, depth: 1.5, fixed: false });
        assert_eq!(rows[1].obs, Observation::Range { beacon: 13, travel_time: 0.5 });
    }
}
