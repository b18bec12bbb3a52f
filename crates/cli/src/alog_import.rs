//! MOOS `.alog` logs as post-processing input: a TOML mapping from MOOS variable
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
//! | `gps_x/gps_y` | GPS_X, GPS_Y   | local east/north m (same time)          | `gps`            |
//! | `gps_lat/gps_lon` | GPS_LATITUDE, GPS_LONGITUDE | WGS-84 deg (same time; needs `origin`) | `gps_ll` |
//! | `dvl_body_forward/dvl_body_starboard` | DVL_BODY_VEL_Y, DVL_BODY_VEL_X | m/s (same time) | `dvl_body` |
//! | `dvl_earth_east/dvl_earth_north` | DVL_EARTH_VEL_X, DVL_EARTH_VEL_Y | m/s (same time) | `dvl_earth` |
//! | `truth_x/truth_y` | TRUTH_X, TRUTH_Y | local east/north m (same time)      | `truth`          |
//! | `range`       | OWTT_RANGE     | `id=13,travel_time=0.2345[,sigma=…]`    | `range`          |
//! | `beacon_fix`  | BEACON_FIX     | `id=…,x=…,y=…[,depth=…][,sigma=…]`      | `beacon_fix`     |
//! | `buoy_fix`    | BUOY_FIX       | `x=…,y=…` (beacon 13 at 1.5 m)          | `beacon_fix`     |
//! | `ship_fix`    | SHIP_FIX       | `x=…,y=…,heading=…` (compass deg)       | `ship_fix`       |
//!
//! Any beacon id (0 … 2³²−1) and travel time in (0, 60] s are accepted, as in the log format.
//! The GPS names are those of the MOOS iGPS instrument (GPS_X/GPS_Y on the local grid and
//! GPS_LATITUDE/GPS_LONGITUDE); the DVL names those of the MOOS iDVL instrument, whose body frame
//! (RDI's) has X to starboard and Y forward, its earth frame X east and Y north. A two-variable
//! row is made when both halves are posted at the same time. Errors name the alog line.
//!
//! The filter starts at the first time with both NAV_X and NAV_Y; NAV_SPEED and NAV_HEADING
//! posted at that same time give its speed and heading (and are not also measurements). Later
//! NAV_X/NAV_Y are the vehicle's own solution and are not used.

use anyhow::{anyhow, bail, Context, Result};
use coopnav_core::{LatLon, LocalFrame};
use coopnav_moos::{Alog, AlogEntry};
use coopnav_nav::auv::VelocityFrame;
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
    pub gps_lat: String,
    pub gps_lon: String,
    pub dvl_body_forward: String,
    pub dvl_body_starboard: String,
    pub dvl_earth_east: String,
    pub dvl_earth_north: String,
    pub truth_x: String,
    pub truth_y: String,
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
            gps_lat: s("GPS_LATITUDE"),
            gps_lon: s("GPS_LONGITUDE"),
            dvl_body_forward: s("DVL_BODY_VEL_Y"),
            dvl_body_starboard: s("DVL_BODY_VEL_X"),
            dvl_earth_east: s("DVL_EARTH_VEL_X"),
            dvl_earth_north: s("DVL_EARTH_VEL_Y"),
            truth_x: s("TRUTH_X"),
            truth_y: s("TRUTH_Y"),
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
    format!("alog line {}: {} at t = {} s", e.line, e.variable, e.time)
}

/// A row posted as two variables at the same time (a position or a velocity), latest of each kept.
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

/// The rows made of two variables.
#[derive(Clone, Copy)]
enum Paired {
    Gps,
    GpsLatLon,
    DvlBody,
    DvlEarth,
    Truth,
}

impl Paired {
    const ALL: [Paired; 5] = [Paired::Gps, Paired::GpsLatLon, Paired::DvlBody, Paired::DvlEarth, Paired::Truth];

    /// Its (first, second) variable names.
    fn variables(self, map: &AlogMapping) -> (&str, &str) {
        match self {
            Paired::Gps => (&map.gps_x, &map.gps_y),
            Paired::GpsLatLon => (&map.gps_lat, &map.gps_lon),
            Paired::DvlBody => (&map.dvl_body_forward, &map.dvl_body_starboard),
            Paired::DvlEarth => (&map.dvl_earth_east, &map.dvl_earth_north),
            Paired::Truth => (&map.truth_x, &map.truth_y),
        }
    }

    /// The row of both values; `e` is the entry that completed the pair (for errors).
    fn observation(self, (a, b): (f64, f64), frame: Option<&LocalFrame>, e: &AlogEntry) -> Result<Observation> {
        Ok(match self {
            Paired::Gps => Observation::Gps { e: a, n: b },
            Paired::GpsLatLon => {
                let Some(frame) = frame else {
                    bail!("{}: a latitude/longitude GPS fix needs `origin = {{ lat_deg = ..., lon_deg = ... }}` in the post-processing config", at(e));
                };
                let ll = LatLon::new(a, b).with_context(|| at(e))?;
                let (e, n) = frame.to_plane(ll);
                Observation::Gps { e, n }
            }
            Paired::DvlBody | Paired::DvlEarth => {
                let v = [
                    within(e, "a DVL velocity", a, SPEED_RANGE, "m/s")?,
                    within(e, "a DVL velocity", b, SPEED_RANGE, "m/s")?,
                ];
                let frame = if matches!(self, Paired::DvlBody) { VelocityFrame::Body } else { VelocityFrame::Earth };
                Observation::Velocity { frame, v }
            }
            Paired::Truth => Observation::Truth { e: a, n: b },
        })
    }
}

/// A numeric `key=value` field that may be absent.
fn optional_field(e: &AlogEntry, key: &str) -> Result<Option<f64>> {
    e.field(key).map(|_| field(e, key)).transpose()
}

/// The post-processing log rows of an alog, in its order.
/// BUOY_FIX is beacon 13 at `buoy_depth` (the post-processing config's); `frame` (the config's
/// origin) places latitude/longitude GPS fixes.
pub fn rows(alog: &Alog, map: &AlogMapping, buoy_depth: f64, frame: Option<&LocalFrame>) -> Result<Vec<LogRow>> {
    let Some(t0) = first_pair_time(alog, &map.nav_x, &map.nav_y) else {
        bail!("the alog has no time at which both {} and {} are posted (the filter's start)", map.nav_x, map.nav_y);
    };
    let value_at_start = |var: &str, check: Option<(&str, (f64, f64), &str)>| -> Result<f64> {
        let posted = alog.entries.iter().find(|e| e.variable == var && e.time == t0);
        let Some(e) = posted else { bail!("no {var} posted at the start time {t0} s (with {})", map.nav_x) };
        let v = number(e)?;
        check.map_or(Ok(v), |(key, range, unit)| within(e, key, v, range, unit))
    };
    let init = Observation::Init {
        e: value_at_start(&map.nav_x, None)?,
        n: value_at_start(&map.nav_y, None)?,
        speed: value_at_start(&map.speed, Some(("speed", SPEED_RANGE, "m/s")))?,
        compass_deg: value_at_start(&map.heading, Some(("heading", HEADING_RANGE, "deg")))?,
    };
    let mut out = vec![LogRow { t: t0, obs: init, sigma: None }];
    let mut pairs: [Pair; 5] = Default::default();
    for e in &alog.entries {
        let v = e.variable.as_str();
        if e.time == t0 && [&map.nav_x, &map.nav_y, &map.speed, &map.heading].iter().any(|m| *m == v) {
            continue;
        }
        if let Some((i, first)) = paired(map, v) {
            if let Some(values) = pairs[i].post(first, e.time, number(e)?) {
                out.push(LogRow { t: e.time, obs: Paired::ALL[i].observation(values, frame, e)?, sigma: None });
            }
            continue;
        }
        let (obs, sigma) = match v {
            _ if v == map.speed => (Observation::Speed(within(e, "speed", number(e)?, SPEED_RANGE, "m/s")?), None),
            _ if v == map.heading => {
                (Observation::Heading { compass_deg: within(e, "heading", number(e)?, HEADING_RANGE, "deg")? }, None)
            }
            _ if v == map.depth => (Observation::Depth(within(e, "depth", number(e)?, DEPTH_RANGE, "m")?), None),
            _ if v == map.yaw_rate => {
                let rate = within(e, "yaw_rate", number(e)?, YAW_RATE_RANGE, "deg/s")?;
                (Observation::YawRate { compass_deg_s: rate }, None)
            }
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

/// Which pair `variable` is half of (its index in [`Paired::ALL`]) and whether the first half.
fn paired(map: &AlogMapping, variable: &str) -> Option<(usize, bool)> {
    Paired::ALL.iter().enumerate().find_map(|(i, p)| {
        let (a, b) = p.variables(map);
        (variable == a || variable == b).then_some((i, variable == a))
    })
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
    let text = crate::input::read(p, false)?;
    let map: AlogMapping = toml::from_str(&text).with_context(|| format!("in {}", p.display()))?;
    map.check().with_context(|| format!("in {}", p.display()))?;
    Ok(map)
}

impl AlogMapping {
    /// Every key with its variable, in the file's order.
    fn keys(&self) -> [(&'static str, &str); 20] {
        [
            ("nav_x", &self.nav_x),
            ("nav_y", &self.nav_y),
            ("speed", &self.speed),
            ("heading", &self.heading),
            ("depth", &self.depth),
            ("yaw_rate", &self.yaw_rate),
            ("gps_x", &self.gps_x),
            ("gps_y", &self.gps_y),
            ("gps_lat", &self.gps_lat),
            ("gps_lon", &self.gps_lon),
            ("dvl_body_forward", &self.dvl_body_forward),
            ("dvl_body_starboard", &self.dvl_body_starboard),
            ("dvl_earth_east", &self.dvl_earth_east),
            ("dvl_earth_north", &self.dvl_earth_north),
            ("truth_x", &self.truth_x),
            ("truth_y", &self.truth_y),
            ("range", &self.range),
            ("beacon_fix", &self.beacon_fix),
            ("buoy_fix", &self.buoy_fix),
            ("ship_fix", &self.ship_fix),
        ]
    }

    /// Each variable feeds one kind of row: one named under two keys (a speed variable mapped
    /// to a position as well, say) is refused, naming both keys.
    pub fn check(&self) -> Result<()> {
        let keys = self.keys();
        for (i, (key, var)) in keys.iter().enumerate() {
            if var.trim().is_empty() {
                bail!("{key} = \"\": name the alog variable it reads");
            }
            if let Some((other, _)) = keys[..i].iter().find(|(_, v)| v == var) {
                bail!("{other} and {key} both read {var:?}: each alog variable can feed one kind of row");
            }
        }
        Ok(())
    }
}

/// `v`, read from `e` as the mapping's `key`, when inside what that quantity can physically be.
fn within(e: &AlogEntry, key: &str, v: f64, (lo, hi): (f64, f64), unit: &str) -> Result<f64> {
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        bail!("{}: {v} read as {key} is outside [{lo}, {hi}] {unit}: is --alog-map's {key} the right variable?", at(e))
    }
}

// What a mapped quantity can physically be: the bounds a version-2 log's rows are held to.
use coopnav_nav::fieldlog::{
    DEPTH_RANGE_M as DEPTH_RANGE, HEADING_RANGE_DEG as HEADING_RANGE, SPEED_RANGE_M_S as SPEED_RANGE,
    YAW_RATE_RANGE_DEG_S as YAW_RATE_RANGE,
};

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_nav::fieldlog::read_field_log;
    use coopnav_nav::post::PostConfig;

    fn frame() -> LocalFrame {
        let cfg = PostConfig::from_toml("origin = { lat_deg = 47.97, lon_deg = -116.5 }\n").unwrap();
        cfg.frame().unwrap()
    }

    fn alog_rows(text: &str, frame: Option<&LocalFrame>) -> Result<Vec<LogRow>> {
        let alog = coopnav_moos::read_alog(text.as_bytes())?;
        rows(&alog, &AlogMapping::default(), 1.5, frame)
    }

    const START: &str = "%% LOGSTART 1750000000\n0.000 NAV_X pNav 10\n0.000 NAV_Y pNav -5\n0.000 NAV_SPEED pNav 1.5\n0.000 NAV_HEADING pNav 90\n";

    /// GPS on the grid and in latitude/longitude, DVL in both frames and truth, under the default
    /// names, give the rows of the same mission written as a version-2 log.
    #[test]
    fn gps_and_dvl_variables_give_the_rows_of_the_v2_log() {
        let alog = format!(
            "{START}\
             0.500 DVL_BODY_VEL_X iDVL 0.05\n0.500 DVL_BODY_VEL_Y iDVL 1.48\n\
             1.000 DVL_EARTH_VEL_X iDVL 1.47\n1.000 DVL_EARTH_VEL_Y iDVL -0.12\n\
             2.000 GPS_X iGPS 12.5\n2.000 GPS_Y iGPS -4.25\n\
             3.000 GPS_LATITUDE iGPS 47.9701\n3.000 GPS_LONGITUDE iGPS -116.4999\n\
             4.000 TRUTH_X topside 13\n4.000 TRUTH_Y topside -4\n\
             5.000 GPS_X iGPS 99\n5.500 GPS_Y iGPS 98\n"
        );
        let v2 = "# coopnav-log 2 time=relative\nt,kind,src,v1,v2,v3,v4,sigma\n\
                  0,init,,10,-5,1.5,90,\n\
                  0.5,dvl_body,,1.48,0.05,,,\n\
                  1,dvl_earth,,1.47,-0.12,,,\n\
                  2,gps,,12.5,-4.25,,,\n\
                  3,gps_ll,,47.9701,-116.4999,,,\n\
                  4,truth,,13,-4,,,\n";
        let f = frame();
        let expected = read_field_log(v2.as_bytes(), Some(&f)).unwrap().rows;
        // GPS_X and GPS_Y posted at different times (5 s, 5.5 s) make no fix.
        assert_eq!(alog_rows(&alog, Some(&f)).unwrap(), expected);
        assert!(
            matches!(expected[1].obs, Observation::Velocity { frame: VelocityFrame::Body, v } if v == [1.48, 0.05])
        );
    }

    #[test]
    fn malformed_gps_and_dvl_values_name_their_line() {
        let f = frame();
        for (bad, said) in [
            ("1.000 GPS_X iGPS abc\n", "alog line 6: GPS_X at t = 1 s: value \"abc\" is not a finite number"),
            ("1.000 DVL_BODY_VEL_X iDVL nan\n", "alog line 6: DVL_BODY_VEL_X"),
            ("1.000 DVL_EARTH_VEL_Y iDVL inf\n", "alog line 6: DVL_EARTH_VEL_Y"),
            ("1.000 GPS_LATITUDE iGPS 95\n1.000 GPS_LONGITUDE iGPS 3\n", "alog line 7: GPS_LONGITUDE"),
            ("1.000 TRUTH_Y topside north\n", "alog line 6: TRUTH_Y"),
        ] {
            let e = format!("{:#}", alog_rows(&format!("{START}{bad}"), Some(&f)).unwrap_err());
            assert!(e.contains(said), "{bad:?}: {e}");
        }
        let e = format!(
            "{:#}",
            alog_rows(&format!("{START}1.000 GPS_LATITUDE iGPS 95\n1 GPS_LONGITUDE a 3\n"), Some(&f)).unwrap_err()
        );
        assert!(e.contains("latitude 95"), "{e}");
        let latlon = format!("{START}2.000 GPS_LATITUDE iGPS 47.9\n2.000 GPS_LONGITUDE iGPS -116.5\n");
        let e = format!("{:#}", alog_rows(&latlon, None).unwrap_err());
        assert!(e.contains("alog line 7") && e.contains("origin = {"), "{e}");
    }

    /// A variable mapped under two keys is refused naming both; a mapped value outside what its
    /// quantity can be (a position read as a speed or a heading) names the line, key and bounds.
    #[test]
    fn a_variable_of_the_wrong_kind_is_caught() {
        let twice = AlogMapping { nav_x: "NAV_SPEED".into(), ..AlogMapping::default() };
        let e = twice.check().unwrap_err().to_string();
        assert!(e.contains("nav_x and speed both read \"NAV_SPEED\""), "{e}");
        assert!(AlogMapping::default().check().is_ok());

        let alog = coopnav_moos::read_alog(format!("{START}1.000 NAV_X pNav 1543.0\n").as_bytes()).unwrap();
        let as_speed = AlogMapping { speed: "NAV_X".into(), nav_x: "NAV_EAST".into(), ..AlogMapping::default() };
        let start = START.replace("NAV_X", "NAV_EAST");
        let alog2 =
            coopnav_moos::read_alog(format!("{start}0.000 NAV_X pNav 1.4\n1.000 NAV_X pNav 1543.0\n").as_bytes())
                .unwrap();
        let e = rows(&alog2, &as_speed, 1.5, None).unwrap_err().to_string();
        assert!(e.contains("alog line 7") && e.contains("read as speed") && e.contains("[-10, 20] m/s"), "{e}");
        assert!(rows(&alog, &AlogMapping::default(), 1.5, None).is_ok(), "a position read as a position is fine");
        let heading = coopnav_moos::read_alog(format!("{START}2.000 NAV_HEADING pNav 4200\n").as_bytes()).unwrap();
        let e = rows(&heading, &AlogMapping::default(), 1.5, None).unwrap_err().to_string();
        assert!(e.contains("read as heading"), "{e}");
    }
}
