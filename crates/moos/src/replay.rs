//! The interactive mission replay: one self-contained `replay.html` (no network, no CDN) built
//! from a run's alog. It shows every vehicle's true and estimated track with the filter's 1σ and
//! 2σ ellipses (circles when the run gives only σ), the CNA and the leg it is flying, pings and packets as pulses (received solid
//! green, lost dashed red), each survey AUV's error against time linked to a time slider with
//! play / pause / speed, and the scenario and coopnav version.
//!
//! Any alog with NODE_REPORTs replays; coopnav's own carry `GROUP` (truth / estimate / cna) and
//! `NAV_SD` or the covariance `NAV_PEE`/`NAV_PEN`/`NAV_PNN` (see [`crate::export`]). The page honours `#t=SECONDS` in its URL and keeps a table of
//! the positions it draws (`id="pos-NAME"`), so a headless browser can check what it shows.
//!
//! Size: tracks are decimated to at most [`MAX_SAMPLES`] points in all and quantised to
//! [`QUANTUM_M`], so a 3-hour, 5-AUV run stays near 1 MB.

use crate::palette;
use std::collections::BTreeMap;
use std::fmt::Write as _;

use thiserror::Error;

use crate::alog::{read_alog, Alog, AlogEntry, AlogError};
use crate::run::{sample_at, Role, Sample};

/// The file name `coopnav view` and the run writers use.
pub const FILE: &str = "replay.html";

/// Track points kept in all vehicles together; longer runs keep every n-th report.
pub const MAX_SAMPLES: usize = 60_000;

/// Resolution of positions, radii and σ in the page, m; of times, s.
pub const QUANTUM_M: f64 = 0.1;
const QUANTUM_S: f64 = 0.1;
/// Quantum of the covariance entries, m² (a 0.1 m σ is 1 quantum).
const QUANTUM_VAR: f64 = 0.01;

#[derive(Debug, Error)]
pub enum ReplayError {
    #[error(transparent)]
    Alog(#[from] AlogError),
    #[error("the alog has no NODE_REPORT entries: there is no vehicle to replay")]
    NoVehicles,
    #[error("NODE_REPORT at t = {t} s: field {field} is missing or not a number (a report needs NAME, X and Y)")]
    BadReport { t: f64, field: &'static str },
    #[error("{variable} at t = {t} s: field {field} is missing or not a number")]
    BadView { t: f64, variable: &'static str, field: &'static str },
}

/// One vehicle's reports.
struct Track {
    group: String,
    kind: String,
    samples: Vec<Sample>,
}

/// A pulse as drawn: time, geometry (`x, y, radius` for a ring, `sx, sy, tx, ty` for a beam),
/// whether it was received.
struct Drawn {
    t: f64,
    geometry: Vec<f64>,
    received: bool,
}

/// Builds the page from alog text.
pub fn from_alog_bytes(alog: &[u8]) -> Result<String, ReplayError> {
    from_alog(&read_alog(alog)?)
}

/// Builds the page from a read alog.
pub fn from_alog(log: &Alog) -> Result<String, ReplayError> {
    let tracks = tracks(log)?;
    if tracks.is_empty() {
        return Err(ReplayError::NoVehicles);
    }
    let ranges = drawn(log, "VIEW_RANGE_PULSE", &["x", "y", "radius"])?;
    let comms = drawn(log, "VIEW_COMMS_PULSE", &["sx", "sy", "tx", "ty"])?;
    let mut data = String::from("{");
    let meta = |variable: &'static str| log.postings(variable).next().map_or("unknown", |e| e.value.as_str());
    let _ = write!(
        data,
        "\"scenario\":{},\"command\":{},\"version\":{},\"q\":{QUANTUM_M},\"qt\":{QUANTUM_S},\"qv\":{QUANTUM_VAR},",
        json_string(meta("COOPNAV_SCENARIO")),
        json_string(meta("COOPNAV_COMMAND")),
        json_string(meta("COOPNAV_VERSION"))
    );
    data.push_str("\"vehicles\":[");
    let stride = tracks.values().map(|t| t.samples.len()).sum::<usize>().div_ceil(MAX_SAMPLES).max(1);
    for (i, (name, track)) in tracks.iter().enumerate() {
        if i > 0 {
            data.push(',');
        }
        write_track(&mut data, name, track, stride);
    }
    data.push_str("],\"errors\":[");
    write_errors(&mut data, &tracks, stride);
    data.push_str("],\"ranges\":");
    write_drawn(&mut data, &ranges);
    data.push_str(",\"comms\":");
    write_drawn(&mut data, &comms);
    data.push_str(",\"legs\":");
    write_legs(&mut data, log);
    data.push('}');
    let colours: Vec<String> = palette::VEHICLES.iter().map(|c| format!("\"{}\"", palette::hex(*c))).collect();
    Ok(PAGE
        .replace("__TITLE__", &html_escape(meta("COOPNAV_SCENARIO")))
        .replace("__PALETTE__", &format!("[{}]", colours.join(", ")))
        .replace("__CNA_COLOUR__", &palette::hex(palette::CNA))
        .replace("__DATA__", &data))
}

/// Every NODE_REPORT, grouped by NAME, in time order.
fn tracks(log: &Alog) -> Result<BTreeMap<String, Track>, ReplayError> {
    let mut tracks: BTreeMap<String, Track> = BTreeMap::new();
    for e in log.postings("NODE_REPORT") {
        let name =
            e.field("NAME").filter(|n| !n.is_empty()).ok_or(ReplayError::BadReport { t: e.time, field: "NAME" })?;
        let number = |field: &'static str| -> Result<f64, ReplayError> {
            e.field(field).and_then(|v| v.parse().ok()).ok_or(ReplayError::BadReport { t: e.time, field })
        };
        let optional = |field| e.field(field).and_then(|v| v.parse::<f64>().ok());
        let sample = Sample {
            t: e.time,
            x: number("X")?,
            y: number("Y")?,
            depth: optional("DEP").unwrap_or(0.0),
            sd: optional("NAV_SD"),
            cov: match (optional("NAV_PEE"), optional("NAV_PEN"), optional("NAV_PNN")) {
                (Some(ee), Some(en), Some(nn)) => Some([ee, en, nn]),
                _ => None,
            },
        };
        let track = tracks.entry(name.to_string()).or_insert_with(|| Track {
            group: e.field("GROUP").map_or_else(|| guess_group(name).to_string(), str::to_lowercase),
            kind: e.field("TYPE").unwrap_or("auv").to_lowercase(),
            samples: Vec::new(),
        });
        track.samples.push(sample);
    }
    for track in tracks.values_mut() {
        track.samples.sort_by(|a, b| a.t.total_cmp(&b.t));
    }
    Ok(tracks)
}

/// The role of a report without a GROUP (logs from other tools): coopnav's naming, else truth.
fn guess_group(name: &str) -> &'static str {
    if name.ends_with("_est") {
        Role::Estimate.group()
    } else if name == "cna" {
        Role::Cna.group()
    } else {
        Role::Truth.group()
    }
}

fn drawn(log: &Alog, variable: &'static str, fields: &[&'static str]) -> Result<Vec<Drawn>, ReplayError> {
    log.postings(variable)
        .map(|e: &AlogEntry| {
            let geometry = fields
                .iter()
                .map(|&field| {
                    e.field(field).and_then(|v| v.parse().ok()).ok_or(ReplayError::BadView {
                        t: e.time,
                        variable,
                        field,
                    })
                })
                .collect::<Result<Vec<f64>, _>>()?;
            Ok(Drawn { t: e.time, geometry, received: e.field("msg") != Some("lost") })
        })
        .collect()
}

fn quantised(v: f64, quantum: f64) -> i64 {
    (v / quantum).round() as i64
}

fn write_list(out: &mut String, values: impl Iterator<Item = i64>) {
    out.push('[');
    for (i, v) in values.enumerate() {
        if i > 0 {
            out.push(',');
        }
        let _ = write!(out, "{v}");
    }
    out.push(']');
}

fn write_track(out: &mut String, name: &str, track: &Track, stride: usize) {
    let kept: Vec<&Sample> = decimated(&track.samples, stride);
    let _ = write!(
        out,
        "{{\"name\":{},\"group\":{},\"type\":{},",
        json_string(name),
        json_string(&track.group),
        json_string(&track.kind)
    );
    out.push_str("\"t\":");
    write_list(out, kept.iter().map(|s| quantised(s.t, QUANTUM_S)));
    out.push_str(",\"x\":");
    write_list(out, kept.iter().map(|s| quantised(s.x, QUANTUM_M)));
    out.push_str(",\"y\":");
    write_list(out, kept.iter().map(|s| quantised(s.y, QUANTUM_M)));
    if kept.iter().all(|s| s.sd.is_some()) && !kept.is_empty() {
        out.push_str(",\"sd\":");
        write_list(out, kept.iter().map(|s| quantised(s.sd.unwrap_or(0.0), QUANTUM_M)));
    }
    if kept.iter().all(|s| s.cov.is_some()) && !kept.is_empty() {
        for (i, key) in ["pee", "pen", "pnn"].into_iter().enumerate() {
            let _ = write!(out, ",\"{key}\":");
            write_list(out, kept.iter().map(|s| quantised(s.cov.map_or(0.0, |c| c[i]), QUANTUM_VAR)));
        }
    }
    out.push('}');
}

/// Every `stride`-th sample, and always the last, so the replay ends where the run ended.
fn decimated(samples: &[Sample], stride: usize) -> Vec<&Sample> {
    let mut kept: Vec<&Sample> = samples.iter().step_by(stride).collect();
    if let (Some(last), Some(kept_last)) = (samples.last(), kept.last()) {
        if kept_last.t != last.t {
            kept.push(last);
        }
    }
    kept
}

/// For each estimate `NAME_est` with a truth `NAME`: |estimate − truth| at the estimate's times.
fn write_errors(out: &mut String, tracks: &BTreeMap<String, Track>, stride: usize) {
    let mut first = true;
    for (name, estimate) in tracks.iter().filter(|(_, t)| t.group == Role::Estimate.group()) {
        let Some(truth) = name.strip_suffix("_est").and_then(|base| tracks.get(base)) else { continue };
        let pairs: Vec<(f64, f64)> = decimated(&estimate.samples, stride)
            .into_iter()
            .filter_map(|s| sample_at(&truth.samples, s.t).map(|p| (s.t, (s.x - p.x).hypot(s.y - p.y))))
            .collect();
        if !first {
            out.push(',');
        }
        first = false;
        let _ = write!(out, "{{\"name\":{},\"t\":", json_string(name.trim_end_matches("_est")));
        write_list(out, pairs.iter().map(|p| quantised(p.0, QUANTUM_S)));
        out.push_str(",\"e\":");
        write_list(out, pairs.iter().map(|p| quantised(p.1, QUANTUM_M)));
        out.push('}');
    }
}

fn write_drawn(out: &mut String, pulses: &[Drawn]) {
    out.push('[');
    for (i, p) in pulses.iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        let values = std::iter::once(quantised(p.t, QUANTUM_S))
            .chain(p.geometry.iter().map(|&g| quantised(g, QUANTUM_M)))
            .chain(std::iter::once(i64::from(p.received)));
        write_list(out, values);
    }
    out.push(']');
}

/// VIEW_SEGLIST legs as `[t, [x, y, x, y, …]]`; depths are not drawn.
fn write_legs(out: &mut String, log: &Alog) {
    out.push('[');
    let mut first = true;
    for e in log.postings("VIEW_SEGLIST") {
        let Some(pts) = e.value.split_once("pts={").and_then(|(_, rest)| rest.split_once('}')).map(|(p, _)| p) else {
            continue;
        };
        let coords: Option<Vec<i64>> = pts
            .split(':')
            .flat_map(|vertex| vertex.split(',').take(2))
            .map(|v| v.trim().parse::<f64>().ok().map(|v| quantised(v, QUANTUM_M)))
            .collect();
        let Some(coords) = coords else { continue };
        if !first {
            out.push(',');
        }
        first = false;
        let _ = write!(out, "[{},", quantised(e.time, QUANTUM_S));
        write_list(out, coords.into_iter());
        out.push(']');
    }
    out.push(']');
}

/// A JSON string literal that is also safe inside a `<script>` element.
fn json_string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn html_escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// The page: styles, markup and the script that draws it, with `__TITLE__` and `__DATA__` to fill.
const PAGE: &str = include_str!("replay.html");

#[cfg(test)]
mod tests {
    use super::*;
    use crate::export::write_run_alog;
    use crate::run::{Pulse, PulseKind, RunLog, Vehicle};

    /// A track along x; estimates carry a covariance (σ_E 1.1 m, σ_N 1.5 m, correlated).
    fn track(name: &str, role: Role, seconds: usize, dx: f64) -> Vehicle {
        let cov = (role == Role::Estimate).then_some([1.21, 0.4, 2.25]);
        let samples = (0..=seconds)
            .map(|s| Sample { t: s as f64, x: dx * s as f64, y: 0.0, depth: 0.0, sd: Some(1.5), cov })
            .collect();
        Vehicle { name: name.into(), role, kind: "auv", samples }
    }

    fn run(seconds: usize, n_auvs: usize) -> RunLog {
        let mut vehicles = Vec::new();
        for k in 1..=n_auvs {
            vehicles.push(track(&format!("auv{k}"), Role::Truth, seconds, 1.5));
            vehicles.push(track(&format!("auv{k}_est"), Role::Estimate, seconds, 1.6));
        }
        vehicles.push(track("cna", Role::Cna, seconds, 1.0));
        let pulses = (0..seconds / 10)
            .map(|i| Pulse {
                t: 10.0 * i as f64,
                kind: PulseKind::Range,
                from: "cna".into(),
                to: "auv1".into(),
                received: i % 3 != 0,
            })
            .collect();
        RunLog {
            scenario: "test <run> & co".into(),
            command: "simulate".into(),
            version: "9.9.9".into(),
            origin: None,
            vehicles,
            pulses,
            legs: Vec::new(),
        }
    }

    fn page(run: &RunLog) -> String {
        let alog = write_run_alog(run, "run.alog", 0.0, Vec::new()).unwrap();
        from_alog_bytes(&alog).unwrap()
    }

    #[test]
    fn the_page_is_self_contained_and_names_the_run() {
        let html = page(&run(60, 2));
        assert!(html.contains("<title>coopnav replay: test &lt;run&gt; &amp; co</title>"), "title escaped");
        assert!(html.contains("\"version\":\"9.9.9\""));
        for fetch in ["http://", "https://", "src=", "@import", "url("] {
            assert!(!html.contains(fetch), "the page must fetch nothing, found {fetch}");
        }
        assert!(!html.contains("__DATA__") && !html.contains("__TITLE__"));
    }

    #[test]
    fn errors_are_the_distance_between_estimate_and_truth() {
        let html = page(&run(10, 1));
        // The estimate runs 0.1 m/s ahead: error 0.1 m per second, in 0.1 m units 0..10.
        assert!(html.contains("\"errors\":[{\"name\":\"auv1\",\"t\":[0,10,20,30,40,50,60,70,80,90,100],\"e\":[0,1,2,3,4,5,6,7,8,9,10]}]"), "{}", &html[html.find("\"errors\"").unwrap()..][..200]);
    }

    #[test]
    fn estimates_carry_their_covariance_for_the_ellipses() {
        let html = page(&run(2, 1));
        assert!(html.contains("\"pee\":[121,121,121],\"pen\":[40,40,40],\"pnn\":[225,225,225]"), "{html}");
        assert_eq!(html.matches("\"pee\"").count(), 1, "only the estimate has a covariance");
    }

    #[test]
    fn a_three_hour_five_auv_run_stays_under_five_megabytes() {
        let html = page(&run(3 * 3600, 5));
        assert!(html.len() < 5_000_000, "{} bytes", html.len());
    }

    #[test]
    fn an_alog_without_vehicles_or_with_a_broken_report_is_refused() {
        let none = from_alog_bytes(b"%% LOGSTART 0\n0.0 NAV_X src 1\n").unwrap_err();
        assert!(matches!(none, ReplayError::NoVehicles), "{none}");
        let broken = from_alog_bytes(b"1.0 NODE_REPORT src NAME=a,X=1\n").unwrap_err();
        assert_eq!(
            broken.to_string(),
            "NODE_REPORT at t = 1 s: field Y is missing or not a number (a report needs NAME, X and Y)"
        );
    }

    #[test]
    fn a_foreign_alog_replays_with_guessed_roles() {
        let html = from_alog_bytes(b"0.0 NODE_REPORT pNodeReporter NAME=alpha,X=1,Y=2,TYPE=KAYAK\n").unwrap();
        assert!(html
            .contains("{\"name\":\"alpha\",\"group\":\"truth\",\"type\":\"kayak\",\"t\":[0],\"x\":[10],\"y\":[20]}"));
        assert!(html.contains("\"scenario\":\"unknown\""));
    }
}
