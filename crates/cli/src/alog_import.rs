//! MOOS `.alog` logs as post-processing input (issue 12 item 2): a TOML mapping from MOOS variable
//! names to rows of the general log (`coopnav_nav::fieldlog`, docs/log-format.md), read on top of `coopnav_moos::alog` (which owns the text format and reports
//! malformed lines by number). Times are seconds since the alog's LOGSTART.
//!
//! | mapping field | default        | value                                   | row              |
//! |---------------|----------------|-----------------------------------------|------------------|
//! | `nav_x/nav_y` | NAV_X, NAV_Y   | local east/north m                      | `init` (first)   |
//! | `speed`       | NAV_SPEED      | m/s                                     | `speed`          |
//! | `heading`     | NAV_HEADING    | compass deg                             | `heading`        |
//! | `depth`       | NAV_DEPTH      | m                                       | `depth`          |
//! | `yaw_rate`    | NAV_YAW_RATE   | compass deg/s                           | `yaw_rate`       |
//! | `gps_x/gps_y` | GPS_X, GPS_Y   | local east/north m (same time)          | `truth`          |
//! | `range`       | OWTT_RANGE     | `id=13,travel_time=0.2345[,sigma=…]`    | `range`          |
//! | `beacon_fix`  | BEACON_FIX     | `id=…,x=…,y=…[,depth=…][,sigma=…]`      | `beacon_fix`     |
//! | `buoy_fix`    | BUOY_FIX       | `x=…,y=…` (beacon 13 at 1.5 m)          | `beacon_fix`     |
//! | `ship_fix`    | SHIP_FIX       | `x=…,y=…,heading=…` (compass deg)       | `ship_fix`       |
//!
//! Any beacon id (0 … 2³²−1) and travel time in (0, 60] s are accepted, as in the log format.
//!
//! The filter starts at the first time with both NAV_X and NAV_Y; NAV_SPEED and NAV_HEADING
//! posted at that same time give its speed and heading (and are not also measurements). Later
//! NAV_X/NAV_Y are the vehicle's own solution and are not used.

use anyhow::{anyhow, bail, Context, Result};
use coopnav_moos::{Alog, AlogEntry};
use coopnav_nav::fieldlog::{BeaconId, LogRow, Observation, MAX_TRAVEL_TIME_S};
use serde::{Deserialize, Serialize};

/// Which MOOS variable feeds which log row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AlogMapping {
    pub nav_x: String,
    pub nav_y: String,
    pub speed: String,
    pub heading: String,
    pub depth: String,
    pub yaw_rate: String,
    pub gps_x: String,
    pub gps_y: String,
    pub range: String,
    pub beacon_fix: String,
    pub buoy_fix: String,
    pub ship_fix: String,
}

impl Default for AlogMapping {
    fn default() -> Self {
        let s = String::from;
        AlogMapping {
            nav_x: s("NAV_X"),
            nav_y: s("NAV_Y"),
            speed: s("NAV_SPEED"),
            heading: s("NAV_HEADING"),
            depth: s("NAV_DEPTH"),
            yaw_rate: s("NAV_YAW_RATE"),
            gps_x: s("GPS_X"),
            gps_y: s("GPS_Y"),
            range: s("OWTT_RANGE"),
            beacon_fix: s("BEACON_FIX"),
            buoy_fix: s("BUOY_FIX"),
            ship_fix: s("SHIP_FIX"),
        }
    }
}

/// A number posted as an entry's whole value.
fn number(e: &AlogEntry) -> Result<f64> {
    e.number().filter(|v| v.is_finite()).ok_or_else(|| anyhow!("{}: value {:?} is not a finite number", at(e), e.value))
}

/// A numeric `key=value` field of an entry's value.
fn field(e: &AlogEntry, key: &str) -> Result<f64> {
    let text = e.field(key).ok_or_else(|| anyhow!("{}: value {:?} has no field '{key}'", at(e), e.value))?;
    text.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| anyhow!("{}: field '{key}' = {text:?} is not a finite number", at(e)))
}

fn at(e: &AlogEntry) -> String {
    format!("alog entry {} at t = {} s", e.variable, e.time)
}

/// An `(east, north)` pair posted as two variables at the same time, latest of each kept.
#[derive(Default)]
struct Pair {
    x: Option<(f64, f64)>,
    y: Option<(f64, f64)>,
}

impl Pair {
    /// Records one half; returns the pair once both halves carry the same time.
    fn post(&mut self, is_x: bool, t: f64, v: f64) -> Option<(f64, f64)> {
        *(if is_x { &mut self.x } else { &mut self.y }) = Some((t, v));
        match (self.x, self.y) {
            (Some((tx, x)), Some((ty, y))) if tx == ty => {
                *self = Pair::default();
                Some((x, y))
            }
            _ => None,
        }
    }
}

/// A numeric `key=value` field that may be absent.
fn optional_field(e: &AlogEntry, key: &str) -> Result<Option<f64>> {
    e.field(key).map(|_| field(e, key)).transpose()
}

/// The post-processing log rows of an alog, in its order.
/// BUOY_FIX is beacon 13 at `buoy_depth` (the post-processing config's).
pub fn rows(alog: &Alog, map: &AlogMapping, buoy_depth: f64) -> Result<Vec<LogRow>> {
    let Some(t0) = first_pair_time(alog, &map.nav_x, &map.nav_y) else {
        bail!("the alog has no time at which both {} and {} are posted (the filter's start)", map.nav_x, map.nav_y);
    };
    let value_at_start = |var: &str| -> Result<f64> {
        let posted = alog.entries.iter().find(|e| e.variable == var && e.time == t0);
        posted.map(number).unwrap_or_else(|| bail!("no {var} posted at the start time {t0} s (with {})", map.nav_x))
    };
    let init = Observation::Init {
        e: value_at_start(&map.nav_x)?,
        n: value_at_start(&map.nav_y)?,
        speed: value_at_start(&map.speed)?,
        compass_deg: value_at_start(&map.heading)?,
    };
    let mut out = vec![LogRow { t: t0, obs: init, sigma: None }];
    let mut gps = Pair::default();
    for e in &alog.entries {
        let v = e.variable.as_str();
        if e.time == t0 && [&map.nav_x, &map.nav_y, &map.speed, &map.heading].iter().any(|m| *m == v) {
            continue;
        }
        let (obs, sigma) = match v {
            _ if v == map.speed => (Observation::Speed(number(e)?), None),
            _ if v == map.heading => (Observation::Heading { compass_deg: number(e)? }, None),
            _ if v == map.depth => (Observation::Depth(number(e)?), None),
            _ if v == map.yaw_rate => (Observation::YawRate { compass_deg_s: number(e)? }, None),
            _ if v == map.gps_x || v == map.gps_y => match gps.post(v == map.gps_x, e.time, number(e)?) {
                Some((x, y)) => (Observation::Truth { e: x, n: y }, None),
                None => continue,
            },
            _ if v == map.range => {
                let travel_time = field(e, "travel_time")?;
                if !(travel_time > 0.0 && travel_time <= MAX_TRAVEL_TIME_S) {
                    bail!("{}: travel_time {travel_time} s must be in (0, {MAX_TRAVEL_TIME_S}]", at(e));
                }
                (Observation::Range { beacon: beacon(e)?, travel_time }, optional_field(e, "sigma")?)
            }
            _ if v == map.beacon_fix => {
                let depth = optional_field(e, "depth")?.unwrap_or(0.0);
                let (x, y) = (field(e, "x")?, field(e, "y")?);
                let fix = Observation::BeaconFix { beacon: beacon(e)?, e: x, n: y, depth, fixed: false };
                (fix, optional_field(e, "sigma")?)
            }
            _ if v == map.buoy_fix => {
                let (x, y) = (field(e, "x")?, field(e, "y")?);
                (Observation::BeaconFix { beacon: 13, e: x, n: y, depth: buoy_depth, fixed: false }, None)
            }
            _ if v == map.ship_fix => {
                let fix =
                    Observation::ShipFix { e: field(e, "x")?, n: field(e, "y")?, compass_deg: field(e, "heading")? };
                (fix, None)
            }
            _ => continue,
        };
        if sigma.is_some_and(|s| !(s > 0.0)) {
            bail!("{}: sigma must be > 0", at(e));
        }
        out.push(LogRow { t: e.time, obs, sigma });
    }
    Ok(out)
}

fn beacon(e: &AlogEntry) -> Result<BeaconId> {
    let id = field(e, "id")?;
    (id.fract() == 0.0 && (0.0..=f64::from(BeaconId::MAX)).contains(&id))
        .then_some(id as BeaconId)
        .ok_or_else(|| anyhow!("{}: id {id} is not a beacon id (an integer 0 … {})", at(e), BeaconId::MAX))
}

fn first_pair_time(alog: &Alog, x: &str, y: &str) -> Option<f64> {
    let mut pair = Pair::default();
    alog.entries
        .iter()
        .filter(|e| e.variable == x || e.variable == y)
        .find_map(|e| pair.post(e.variable == x, e.time, 0.0).map(|_| e.time))
}

/// Reads the mapping file, or the defaults.
pub fn mapping(path: Option<&std::path::Path>) -> Result<AlogMapping> {
    let Some(p) = path else { return Ok(AlogMapping::default()) };
    let text = std::fs::read_to_string(p).with_context(|| format!("reading {}", p.display()))?;
    toml::from_str(&text).with_context(|| format!("in {}", p.display()))
}
