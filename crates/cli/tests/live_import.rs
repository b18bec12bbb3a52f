//! `coopnav live import LOG... -o DIR`: the live processes' LCM logs as a run directory that
//! `view` and `hbl postprocess` read. Logs written here with coopnav-lcm's own log writer, of
//! messages whose values the test chose, are read back and every alog variable is counted and
//! compared with those values; the same logs on a vehicle's Unix clock give the same entries
//! from a Unix LOGSTART. (The import of a software-in-the-loop run's logs, with the world's
//! truth, is in `sitl_live.rs`.)

mod common;

use common::coopnav;
use coopnav_lcm::messages::{
    AuvEstimate, AuvSensors, CnaCommand, CnaFix, Decision, Message, OwttRange, Position, StatusFrame,
};
use coopnav_lcm::{LogWriter, Schema};
use coopnav_moos::{read_alog_file, Alog, AlogEntry};
use std::path::Path;

/// Seconds of the synthetic mission.
const END_S: i64 = 100;
/// The CNA decides every this many seconds.
const TAU_S: i64 = 10;

fn us(t: f64) -> i64 {
    (t * 1e6).round() as i64
}

fn estimate_at(t: f64) -> (f64, f64, [[f64; 2]; 2]) {
    (1.5 * t, -t, [[4.0 + 0.01 * t, 0.5], [0.5, 9.0]])
}

fn cna_at(t: f64) -> (f64, f64) {
    (200.0 + 2.0 * t, 50.0)
}

/// Writes cna.lcm and auv0.lcm in `dir`, every time shifted by `t0` s; returns the number of
/// waypoint commands.
fn write_logs(dir: &Path, t0: f64) -> usize {
    let schema = Schema::coopnav();
    let mut cna = LogWriter::new(std::fs::File::create(dir.join("cna.lcm")).unwrap());
    let mut waypoints = 0;
    for m in 0..=END_S / TAU_S {
        let t = (m * TAU_S) as f64;
        let (x, y) = cna_at(t);
        let fix = CnaFix { utime: us(t0 + t), x, y, depth: 1.5, source: CnaFix::SOURCE_GPS, ..CnaFix::default() };
        let fix = fix.encode(&schema).unwrap();
        cna.write(us(t0 + t), "COOPNAV_CNA_FIX", &fix).unwrap();
        if m == 3 {
            // A repeated payload is read once.
            cna.write(us(t0 + t), "COOPNAV_CNA_FIX", &fix).unwrap();
        }
        let has_waypoint = m % 2 == 0;
        waypoints += usize::from(has_waypoint);
        let command = CnaCommand {
            utime: us(t0 + t),
            seq: m,
            has_waypoint,
            heading: 0.25,
            waypoint_x: x + 100.0,
            waypoint_y: y - 20.0 * m as f64,
            waypoint_depth: 0.0,
            speed: 1.5,
        };
        cna.write(us(t0 + t), "COOPNAV_CNA_COMMAND", &command.encode(&schema).unwrap()).unwrap();
        let decision = Decision {
            utime: us(t0 + t),
            seq: m,
            policy: "planner".into(),
            option: m as i32 % 3,
            cost: 0.5 * m as f64,
            ..Decision::default()
        };
        cna.write(us(t0 + t), "COOPNAV_CNA_DECISION", &decision.encode(&schema).unwrap()).unwrap();
        if m < END_S / TAU_S {
            let status =
                StatusFrame { utime: us(t0 + t + 5.0), src: 0, receive_time: t0 + t + 5.0, data: vec![1, 2, 3] };
            cna.write(us(t0 + t + 5.0), "COOPNAV_CNA_STATUS", &status.encode(&schema).unwrap()).unwrap();
        }
    }
    // A payload that is no decision_t, and the world's clock: both left out, counted.
    cna.write(us(t0 + 50.0), "COOPNAV_CNA_DECISION", &[0xde, 0xad, 0xbe, 0xef]).unwrap();
    cna.write(us(t0 + 50.0), "COOPNAV_CLOCK", &[0; 8]).unwrap();
    cna.into_inner().unwrap();
    let mut auv = LogWriter::new(std::fs::File::create(dir.join("auv0.lcm")).unwrap());
    for s in 0..=END_S {
        let t = s as f64;
        let sensors =
            AuvSensors { utime: us(t0 + t), auv: 0, heading: 0.5, speed: 1.25, depth: 30.0, ..AuvSensors::default() };
        auv.write(us(t0 + t), "COOPNAV_AUV0_SENSORS", &sensors.encode(&schema).unwrap()).unwrap();
        if s > 0 && s % TAU_S == 0 {
            let (x, y) = cna_at(t);
            let range = OwttRange {
                utime: us(t0 + t + 0.5),
                src: -1,
                transmit_time: t0 + t,
                receive_time: t0 + t + 0.5,
                transponder: Position { x, y, z: 1.5 },
                travel_time: 0.5,
            };
            auv.write(us(t0 + t + 0.5), "COOPNAV_AUV0_RANGE", &range.encode(&schema).unwrap()).unwrap();
        }
        if s > 0 {
            let (x, y, cov) = estimate_at(t);
            let estimate = AuvEstimate { utime: us(t0 + t), auv: 0, x, y, cov, valid: true };
            auv.write(us(t0 + t), "COOPNAV_AUV0_ESTIMATE", &estimate.encode(&schema).unwrap()).unwrap();
        }
    }
    auv.into_inner().unwrap();
    waypoints
}

fn reports<'a>(alog: &'a Alog, name: &'a str) -> Vec<&'a AlogEntry> {
    alog.postings("NODE_REPORT").filter(|e| e.field("NAME") == Some(name)).collect()
}

fn import(dir: &Path, out: &str) -> Alog {
    let run = coopnav(dir, &["live", "import", "cna.lcm", "auv0.lcm", "-o", out]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    read_alog_file(&dir.join(out).join("run.alog")).unwrap()
}

#[test]
fn a_vehicles_logs_become_a_run_alog_of_their_messages_and_post_processing_inputs() {
    let tmp = tempfile::tempdir().unwrap();
    let waypoints = write_logs(tmp.path(), 0.0);
    let alog = import(tmp.path(), "run");
    let out = tmp.path().join("run");

    // The estimates, one NODE_REPORT a second at the estimates' own values.
    let est = reports(&alog, "auv0_est");
    assert_eq!(est.len(), END_S as usize, "one report a second from t = 1 to {END_S} s");
    for e in &est {
        let (x, y, cov) = estimate_at(e.time);
        assert_eq!(e.field("X"), Some(format!("{x:.3}").as_str()), "{e:?}");
        assert_eq!(e.field("Y"), Some(format!("{y:.3}").as_str()), "{e:?}");
        assert_eq!(e.field("NAV_SD"), Some(format!("{:.3}", (cov[0][0] + cov[1][1]).sqrt()).as_str()), "{e:?}");
        assert_eq!(e.field("NAV_PEN"), Some("0.5000"), "{e:?}");
        assert_eq!(e.field("DEP"), Some("30.000"), "{e:?}");
        assert_eq!(e.field("GROUP"), Some("estimate"));
    }
    // The CNA's fixes: a ship (GPS) at depth 0, every second between its first and last fix.
    let cna = reports(&alog, "cna");
    assert_eq!(cna.len(), END_S as usize + 1);
    for e in cna.iter().filter(|e| e.time as i64 % TAU_S == 0) {
        let (x, y) = cna_at(e.time);
        assert_eq!((e.field("X"), e.field("Y")), (Some(format!("{x:.3}").as_str()), Some(format!("{y:.3}").as_str())));
        assert_eq!((e.field("TYPE"), e.field("DEP")), (Some("ship"), Some("0.000")));
    }
    // No truth: no truth track, and the run says so.
    assert!(reports(&alog, "auv0").is_empty());
    assert!(alog.postings("NODE_REPORT").all(|e| e.field("GROUP") != Some("truth")));
    let scenario = alog.postings("COOPNAV_SCENARIO").next().unwrap();
    assert!(scenario.value.contains("no truth (a real vehicle has none)"), "{}", scenario.value);

    // Each range a ring from the CNA at its transmit time, each status a beam at its receive time.
    let rings: Vec<_> = alog.postings("VIEW_RANGE_PULSE").collect();
    assert_eq!(rings.len(), (END_S / TAU_S) as usize);
    for r in &rings {
        let (x, _) = cna_at(r.time);
        assert_eq!(r.field("x"), Some(format!("{x:.2}").as_str()), "{r:?}");
        assert_eq!(r.field("label"), Some("cna_auv0_est_range"), "without truth a ring reaches the estimate");
    }
    let beams: Vec<f64> = alog.postings("VIEW_COMMS_PULSE").map(|e| e.time).collect();
    let sent: Vec<f64> = (0..END_S / TAU_S).map(|m| (m * TAU_S) as f64 + 5.0).collect();
    assert_eq!(beams, sent);

    // Every command and decision, in order; a leg for each waypoint.
    let seqs = |v: &str| alog.postings(v).map(|e| e.field("seq").unwrap().to_string()).collect::<Vec<_>>();
    let all: Vec<String> = (0..=END_S / TAU_S).map(|m| m.to_string()).collect();
    assert_eq!(seqs("COOPNAV_CNA_COMMAND"), all);
    assert_eq!(seqs("COOPNAV_CNA_DECISION"), all);
    let costs: Vec<String> =
        alog.postings("COOPNAV_CNA_DECISION").map(|e| e.field("cost").unwrap().to_string()).collect();
    assert_eq!(costs, (0..=END_S / TAU_S).map(|m| (0.5 * m as f64).to_string()).collect::<Vec<_>>());
    assert_eq!(alog.postings("VIEW_SEGLIST").count(), waypoints);

    // What was left out is counted.
    let summary: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("import.json")).unwrap()).unwrap();
    let counts = &summary["counts"];
    assert_eq!(
        (counts["repeated"].as_u64(), counts["undecodable"].as_u64(), counts["other_channels"].as_u64()),
        (Some(1), Some(1), Some(1))
    );
    assert_eq!(summary["cna"]["decisions"], 11);
    assert!(summary["truth"].as_str().unwrap().starts_with("none"));

    // The post-processing log: each sensors message's rows, each range's two.
    let log = std::fs::read_to_string(out.join("auv0.log")).unwrap();
    let kind = |k: &str| log.lines().filter(|l| l.split(',').nth(1) == Some(k)).count();
    assert_eq!((kind("init"), kind("speed"), kind("heading"), kind("depth")), (1, 101, 101, 101));
    assert_eq!((kind("range"), kind("beacon_fix"), kind("truth")), (10, 10, 0));

    // The tools read the run unchanged.
    let post = coopnav(&out, &["hbl", "postprocess", "auv0.log", "--config", "auv0.post.toml", "-o", "post"]);
    assert!(post.status.success(), "{}", String::from_utf8_lossy(&post.stderr));
    assert!(out.join("post").join("estimates.csv").is_file());
    let view = coopnav(tmp.path(), &["view", "run"]);
    assert!(view.status.success(), "{}", String::from_utf8_lossy(&view.stderr));
}

#[test]
fn logs_on_a_vehicles_unix_clock_give_the_same_entries_from_a_unix_log_start() {
    let tmp = tempfile::tempdir().unwrap();
    let (mission, unix) = (tmp.path().join("mission"), tmp.path().join("unix"));
    std::fs::create_dir_all(&mission).unwrap();
    std::fs::create_dir_all(&unix).unwrap();
    // A whole second, so the entries' times are the mission's.
    let t0 = 1_795_622_400.0;
    write_logs(&mission, 0.0);
    write_logs(&unix, t0);
    let (a, b) = (import(&mission, "run"), import(&unix, "run"));
    assert_eq!(a.log_start, Some(946_684_800.0));
    assert_eq!(b.log_start, Some(t0));
    assert_eq!(a.entries.len(), b.entries.len());
    for (p, q) in a.entries.iter().zip(&b.entries) {
        assert_eq!((p.time, &p.variable), (q.time, &q.variable));
        if p.variable != "NODE_REPORT" && !p.variable.starts_with("VIEW_") {
            continue;
        }
        // Only the Unix times differ (TIME, and the pulses' time).
        let strip = |v: &str| {
            v.split(',').filter(|f| !f.starts_with("TIME=") && !f.starts_with("time=")).collect::<Vec<_>>().join(",")
        };
        assert_eq!(strip(&p.value), strip(&q.value));
    }
}
