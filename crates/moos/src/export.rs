//! A [`RunLog`] written as a MOOS `.alog`, so alogview, pMarineViewer-style tools and the alog
//! utilities replay a coopnav run. The mapping (source column `coopnav` throughout):
//!
//! | alog variable | when | value |
//! |---|---|---|
//! | `COOPNAV_SCENARIO`, `COOPNAV_COMMAND`, `COOPNAV_VERSION` | t = 0 | the run's description |
//! | `NODE_REPORT` | every whole second of each vehicle's track | `NAME`, `X`, `Y`, `LAT`/`LON` (only with an origin), `SPD`, `HDG`, `DEP`, `TIME`, `TYPE`, `GROUP`, and for estimates `NAV_SD` (1σ, m) and, where the run has it, `NAV_PEE`/`NAV_PEN`/`NAV_PNN` (horizontal covariance, m²) |
//! | `VIEW_RANGE_PULSE` | each ranging broadcast | ring centred on the sender at `t`, `radius` = distance to the receiver |
//! | `VIEW_COMMS_PULSE` | each data packet | beam from sender (`sx`,`sy`) to receiver (`tx`,`ty`) |
//! | `VIEW_SEGLIST` | each leg the planner chose | `pts={x,y,depth:…}`, label `cna_leg` |
//! | any other | a caller's [`Posting`]s ([`write_run_alog_with`]) | as given |
//!
//! Truth and estimate are separate vehicles (`auv0` and `auv0_est`), `GROUP` says which
//! (`truth`, `estimate`, `cna`, `beacon`). Positions between a track's samples are interpolated
//! linearly; `SPD` and `HDG` (compass degrees, 0 = north, clockwise) are the speed and course over
//! ground from the previous second (from the next one at the first second). `TIME` is the Unix
//! time (LOGSTART + t). Pulses carry `msg=received` or `msg=lost` and are filled green or red;
//! a pulse at a time outside a vehicle's track uses the nearest end of that track.

use std::fmt::Write as _;
use std::io::Write;

use coopnav_core::{CompassDeg, Heading};
use thiserror::Error;

use crate::alog::{AlogError, AlogWriter};
use crate::run::{Pulse, PulseKind, Role, RunLog, Sample, Vehicle};

/// The alog source column of every exported entry.
pub const SOURCE: &str = "coopnav";

/// How long a pulse stays drawn, s.
const PULSE_SECONDS: f64 = 3.0;
/// Beam width of a comms pulse, m.
const BEAM_WIDTH_M: f64 = 20.0;

#[derive(Debug, Error)]
pub enum ExportError {
    #[error(transparent)]
    Alog(#[from] AlogError),
    #[error("pulse at t = {t} s names vehicle {name:?}, which has no track in the run")]
    UnknownVehicle { t: f64, name: String },
}

/// One entry before sorting: (time, variable, value).
type Row<'a> = (f64, &'a str, String);

/// An entry a caller posts beside the run's own, in a variable the mapping above does not write
/// (e.g. the CNA's commands and decisions read from a live run's LCM logs).
#[derive(Debug, Clone, PartialEq)]
pub struct Posting {
    /// Seconds since LOGSTART.
    pub t: f64,
    pub variable: String,
    pub value: String,
}

/// Writes `run` as an alog into `out`, entries in time order, starting at `log_start` (Unix s).
pub fn write_run_alog<W: Write>(run: &RunLog, file_name: &str, log_start: f64, out: W) -> Result<W, ExportError> {
    write_run_alog_with(run, &[], file_name, log_start, out)
}

/// [`write_run_alog`] with `extra` entries merged in time order; at one instant they follow the
/// run's own entries, in the order given.
pub fn write_run_alog_with<W: Write>(
    run: &RunLog,
    extra: &[Posting],
    file_name: &str,
    log_start: f64,
    out: W,
) -> Result<W, ExportError> {
    let mut rows: Vec<Row> = vec![
        (0.0, "COOPNAV_SCENARIO", one_line(&run.scenario)),
        (0.0, "COOPNAV_COMMAND", one_line(&run.command)),
        (0.0, "COOPNAV_VERSION", one_line(&run.version)),
    ];
    for vehicle in &run.vehicles {
        node_reports(run, vehicle, log_start, &mut rows);
    }
    for pulse in &run.pulses {
        rows.push(pulse_row(run, pulse, log_start)?);
    }
    for leg in &run.legs {
        let pts: Vec<String> = leg.points.iter().map(|p| format!("{:.2},{:.2},{:.2}", p[0], p[1], p[2])).collect();
        rows.push((leg.t, "VIEW_SEGLIST", format!("pts={{{}}},label=cna_leg,edge_color=orange", pts.join(":"))));
    }
    for posting in extra {
        rows.push((posting.t, &posting.variable, posting.value.clone()));
    }
    // Stable: entries at one instant keep the order above (description, vehicles, pulses, legs,
    // extra postings).
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut writer = AlogWriter::new(out, file_name, log_start)?;
    for (t, variable, value) in &rows {
        writer.write(*t, variable, SOURCE, value)?;
    }
    Ok(writer.finish()?)
}

/// Free text as one alog value: line breaks become spaces, padding is dropped.
fn one_line(text: &str) -> String {
    text.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn node_reports(run: &RunLog, vehicle: &Vehicle, log_start: f64, rows: &mut Vec<Row<'_>>) {
    let (Some(first), Some(last)) = (vehicle.samples.first(), vehicle.samples.last()) else {
        return;
    };
    let seconds = first.t.ceil() as i64..=last.t.floor() as i64;
    let mut previous: Option<Sample> = None;
    for second in seconds {
        let t = second as f64;
        let Some(here) = vehicle.at(t) else { continue };
        let motion = match previous {
            Some(before) => course(&before, &here),
            None => vehicle.at(t + 1.0).map_or((0.0, 0.0), |next| course(&here, &next)),
        };
        rows.push((t, "NODE_REPORT", node_report(run, vehicle, &here, motion, log_start + t)));
        previous = Some(here);
    }
}

/// (speed m/s, compass heading deg) over ground from `a` to `b`.
fn course(a: &Sample, b: &Sample) -> (f64, f64) {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let dt = b.t - a.t;
    if dt <= 0.0 || (dx == 0.0 && dy == 0.0) {
        return (0.0, 0.0);
    }
    let heading = CompassDeg::from(Heading::from_radians(dy.atan2(dx))).0;
    (dx.hypot(dy) / dt, heading)
}

fn node_report(run: &RunLog, vehicle: &Vehicle, s: &Sample, (speed, heading): (f64, f64), unix: f64) -> String {
    let mut v = format!("NAME={},X={:.3},Y={:.3}", vehicle.name, s.x, s.y);
    if let Some(ll) = run.origin.as_ref().and_then(|frame| frame.from_plane(s.x, s.y).ok()) {
        let _ = write!(v, ",LAT={:.8},LON={:.8}", ll.lat_deg(), ll.lon_deg());
    }
    let _ = write!(
        v,
        ",SPD={speed:.2},HDG={heading:.1},DEP={:.3},TIME={unix:.3},TYPE={},GROUP={}",
        s.depth,
        vehicle.kind,
        vehicle.role.group()
    );
    if let (Role::Estimate, Some(sd)) = (vehicle.role, s.sd) {
        let _ = write!(v, ",NAV_SD={sd:.3}");
    }
    if let (Role::Estimate, Some([ee, en, nn])) = (vehicle.role, s.cov) {
        let _ = write!(v, ",NAV_PEE={ee:.4},NAV_PEN={en:.4},NAV_PNN={nn:.4}");
    }
    v
}

fn pulse_row(run: &RunLog, pulse: &Pulse, log_start: f64) -> Result<Row<'static>, ExportError> {
    let from = position(run, &pulse.from, pulse.t)?;
    let to = position(run, &pulse.to, pulse.t)?;
    let (fate, colour) = if pulse.received { ("received", "green") } else { ("lost", "red") };
    let common = format!(
        "duration={PULSE_SECONDS},fill=0.4,fill_color={colour},edge_color={colour},label={}_{}_{},msg={fate},time={:.3}",
        pulse.from,
        pulse.to,
        kind_word(pulse.kind),
        log_start + pulse.t
    );
    Ok(match pulse.kind {
        PulseKind::Range => {
            let radius = (to.x - from.x).hypot(to.y - from.y);
            (pulse.t, "VIEW_RANGE_PULSE", format!("x={:.2},y={:.2},radius={radius:.2},{common}", from.x, from.y))
        }
        PulseKind::Comms => (
            pulse.t,
            "VIEW_COMMS_PULSE",
            format!(
                "sx={:.2},sy={:.2},tx={:.2},ty={:.2},beam_width={BEAM_WIDTH_M},{common}",
                from.x, from.y, to.x, to.y
            ),
        ),
    })
}

fn kind_word(kind: PulseKind) -> &'static str {
    match kind {
        PulseKind::Range => "range",
        PulseKind::Comms => "comms",
    }
}

/// Where `name` was at `t`, the nearest end of its track outside it.
fn position(run: &RunLog, name: &str, t: f64) -> Result<Sample, ExportError> {
    let unknown = || ExportError::UnknownVehicle { t, name: name.to_string() };
    let vehicle = run.vehicle(name).ok_or_else(unknown)?;
    let (first, last) = (vehicle.samples.first().ok_or_else(unknown)?, vehicle.samples.last().ok_or_else(unknown)?);
    Ok(vehicle.at(t.clamp(first.t, last.t)).unwrap_or(*last))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::alog::read_alog;
    use crate::run::{Leg, SIMULATED_LOG_START};
    use coopnav_core::{Geodetic, LatLon, LocalFrame};

    fn track(name: &str, role: Role, points: &[(f64, f64, f64)]) -> Vehicle {
        let samples =
            points.iter().map(|&(t, x, y)| Sample { t, x, y, depth: 30.0, sd: Some(2.5), cov: None }).collect();
        Vehicle { name: name.into(), role, kind: "auv", samples }
    }

    fn small_run() -> RunLog {
        RunLog {
            scenario: "two vehicles\nheading east".into(),
            command: "simulate".into(),
            version: "0.1.0".into(),
            origin: None,
            vehicles: vec![
                track("auv1", Role::Truth, &[(0.0, 0.0, 0.0), (10.0, 20.0, 0.0)]),
                track("auv1_est", Role::Estimate, &[(0.5, 1.0, 1.0), (2.5, 1.0, 5.0)]),
                track("cna", Role::Cna, &[(0.0, 0.0, 100.0), (10.0, 0.0, 100.0)]),
            ],
            pulses: vec![
                Pulse { t: 5.0, kind: PulseKind::Range, from: "cna".into(), to: "auv1".into(), received: true },
                Pulse { t: 6.0, kind: PulseKind::Comms, from: "auv1".into(), to: "cna".into(), received: false },
            ],
            legs: vec![Leg { t: 2.0, points: vec![[0.0, 100.0, 0.0], [50.0, 100.0, 10.0]] }],
        }
    }

    fn export(run: &RunLog) -> crate::alog::Alog {
        let bytes = write_run_alog(run, "run.alog", SIMULATED_LOG_START, Vec::new()).unwrap();
        read_alog(bytes.as_slice()).unwrap()
    }

    #[test]
    fn node_reports_come_every_whole_second_of_each_track() {
        let log = export(&small_run());
        let names: Vec<&str> = log.postings("NODE_REPORT").filter_map(|e| e.field("NAME")).collect();
        assert_eq!(names.iter().filter(|n| **n == "auv1").count(), 11);
        assert_eq!(names.iter().filter(|n| **n == "auv1_est").count(), 2, "t = 1 and 2 inside 0.5..2.5");
        let at_three = log.postings("NODE_REPORT").find(|e| e.time == 3.0 && e.field("NAME") == Some("auv1")).unwrap();
        assert_eq!(at_three.field("X"), Some("6.000"));
        assert_eq!(at_three.field("SPD"), Some("2.00"));
        assert_eq!(at_three.field("HDG"), Some("90.0"), "due east is compass 90");
        assert_eq!(at_three.field("TIME"), Some("946684803.000"));
        assert_eq!(at_three.field("GROUP"), Some("truth"));
        assert_eq!(at_three.field("NAV_SD"), None, "only estimates carry the filter's sigma");
        assert_eq!(at_three.field("LAT"), None, "no origin, no LAT/LON");
        let est = log.postings("NODE_REPORT").find(|e| e.field("NAME") == Some("auv1_est")).unwrap();
        assert_eq!(
            (est.field("Y"), est.field("HDG"), est.field("NAV_SD")),
            (Some("2.000"), Some("0.0"), Some("2.500"))
        );
    }

    #[test]
    fn entries_are_in_time_order_and_the_description_comes_first() {
        let log = export(&small_run());
        assert!(log.entries.windows(2).all(|w| w[0].time <= w[1].time));
        assert_eq!(log.entries[0].variable, "COOPNAV_SCENARIO");
        assert_eq!(log.entries[0].value, "two vehicles heading east");
        assert_eq!(log.log_start, Some(SIMULATED_LOG_START));
    }

    #[test]
    fn pulses_reach_from_sender_to_receiver_and_say_their_fate() {
        let log = export(&small_run());
        let range = log.postings("VIEW_RANGE_PULSE").next().unwrap();
        assert_eq!(range.time, 5.0);
        assert_eq!((range.field("x"), range.field("y")), (Some("0.00"), Some("100.00")));
        assert_eq!(range.field("radius"), Some(format!("{:.2}", 10f64.hypot(100.0)).as_str()));
        assert_eq!(range.field("msg"), Some("received"));
        let comms = log.postings("VIEW_COMMS_PULSE").next().unwrap();
        assert_eq!(
            (comms.field("sx"), comms.field("tx"), comms.field("ty")),
            (Some("12.00"), Some("0.00"), Some("100.00"))
        );
        assert_eq!((comms.field("msg"), comms.field("fill_color")), (Some("lost"), Some("red")));
    }

    #[test]
    fn legs_become_seglists_with_depths() {
        let log = export(&small_run());
        let leg = log.postings("VIEW_SEGLIST").next().unwrap();
        assert_eq!(
            (leg.time, leg.value.as_str()),
            (2.0, "pts={0.00,100.00,0.00:50.00,100.00,10.00},label=cna_leg,edge_color=orange")
        );
    }

    #[test]
    fn an_origin_adds_lat_lon() {
        let mut run = small_run();
        let origin = Geodetic::new(LatLon::new(42.35, -70.95).unwrap(), 0.0).unwrap();
        run.origin = Some(LocalFrame::new(origin));
        let log = export(&run);
        let first = log.postings("NODE_REPORT").find(|e| e.field("NAME") == Some("cna")).unwrap();
        let lat: f64 = first.field("LAT").unwrap().parse().unwrap();
        let lon: f64 = first.field("LON").unwrap().parse().unwrap();
        // 100 m north of the origin is 100 / 111 100 m per degree ≈ 0.0009 deg further north.
        assert!((lat - 42.3509).abs() < 2e-5 && (lon + 70.95).abs() < 1e-7, "{lat} {lon}");
    }

    #[test]
    fn a_pulse_naming_an_unknown_vehicle_is_refused() {
        let mut run = small_run();
        run.pulses[0].to = "auv9".into();
        let err = write_run_alog(&run, "run.alog", 0.0, Vec::new()).unwrap_err();
        assert_eq!(err.to_string(), "pulse at t = 5 s names vehicle \"auv9\", which has no track in the run");
    }
}
