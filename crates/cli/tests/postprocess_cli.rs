//! `coopnav hbl postprocess` never drops rows in silence: rows it does not use are warnings on
//! stderr, and under `--strict` an error that writes nothing.

mod common;

use common::coopnav;

#[test]
fn unused_rows_warn_and_strict_refuses_them() {
    let tmp = tempfile::tempdir().unwrap();
    let log = tmp.path().join("log.csv");
    // A speed row before init, a second init, and a buoy range with no buoy fix at all.
    std::fs::write(
        &log,
        "t,kind,src,v1,v2,v3,v4\n-1,speed,,1,,,\n0,init,,0,0,1,90\n1,init,,5,5,1,90\n2,range,13,0.1,,,\n",
    )
    .unwrap();
    let post = tmp.path().join("post");
    let args = |dir: &std::path::Path, strict: bool| {
        let mut a = vec!["hbl", "postprocess", log.to_str().unwrap(), "--out"];
        a.push(dir.to_str().unwrap());
        if strict {
            a.push("--strict");
        }
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |a: Vec<String>| coopnav(tmp.path(), &a.iter().map(String::as_str).collect::<Vec<_>>());
    let out = run(args(&post, false));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let err = String::from_utf8_lossy(&out.stderr);
    for said in ["1 row(s) timed before the first 'init'", "1 'init' row(s) after the first", "1 range(s) had no"] {
        assert!(err.contains(said), "missing {said:?} in {err}");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(post.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["ranges_without_fix"], 1);
    let strict = tmp.path().join("strict");
    let out = run(args(&strict, true));
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--strict") && err.contains("log.csv") && err.contains("1 range(s) had no"), "{err}");
    assert!(!strict.exists());
}

#[test]
fn run_directory_holds_residuals_and_the_latlon_track() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join("sim");
    let out = coopnav(tmp.path(), &["hbl", "simulate", "--out", sim.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let cfg = tmp.path().join("post.toml");
    std::fs::write(&cfg, "origin = { lat_deg = 47.97, lon_deg = -116.5 }\n").unwrap();
    let post = tmp.path().join("post");
    let log = sim.join("log.csv");
    let (log, cfg, dir) = (log.to_str().unwrap(), cfg.to_str().unwrap(), post.to_str().unwrap());
    let out = coopnav(tmp.path(), &["hbl", "postprocess", log, "--config", cfg, "--out", dir]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(post.join("summary.json")).unwrap()).unwrap();
    let (before, after) =
        (summary["residual_rms_filter_m"].as_f64().unwrap(), summary["residual_rms_smoothed_m"].as_f64().unwrap());
    assert!(after < before, "residual RMS {before} m before smoothing, {after} m after");
    let residuals = std::fs::read_to_string(post.join("residuals.csv")).unwrap();
    let used = summary["ranges_applied"].as_u64().unwrap() + summary["ranges_gated"].as_u64().unwrap();
    assert_eq!(residuals.lines().count() as u64, used + 1, "{residuals}");
    let html = std::fs::read_to_string(post.join("report.html")).unwrap();
    let ids = ["id=\"track\"", "id=\"residuals\"", "id=\"nis\"", "id=\"sigma\"", "id=\"north-error\""];
    for id in ids.into_iter().chain(["id=\"beacon-residuals\"", "residual RMS before", "mean NIS of"]) {
        assert!(html.contains(id), "report.html lacks {id}");
    }
    assert!(!html.contains("<script") && !html.contains("src=\"http"), "report.html must be self-contained");
    let track = std::fs::read_to_string(post.join("estimates.csv")).unwrap();
    let ll = std::fs::read_to_string(post.join("smoothed_ll.csv")).unwrap();
    assert_eq!(ll.lines().count(), track.lines().count());
    for row in ll.lines().skip(1) {
        let f: Vec<f64> = row.split(',').map(|v| v.parse().unwrap()).collect();
        assert!((f[1] - 47.97).abs() < 0.05 && (f[2] + 116.5).abs() < 0.05, "{row}");
    }
}

/// A post-processing CSV log rewritten as a MOOS alog with the default variable names, times at
/// the millisecond as MOOS loggers write them.
fn as_alog(csv: &str) -> String {
    let mut out = String::from("%%%%%%%%\n%% LOG FILE:       sim.alog\n%% LOGSTART        1700000000.000\n%%%%%%%%\n");
    for row in csv.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        let t = format!("{:.3}", f[0].parse::<f64>().unwrap());
        let mut post = |var: &str, value: String| out.push_str(&format!("{t} {var} uSim {value}\n"));
        match f[1] {
            "init" => {
                post("NAV_X", f[3].into());
                post("NAV_Y", f[4].into());
                post("NAV_SPEED", f[5].into());
                post("NAV_HEADING", f[6].into());
            }
            "speed" => post("NAV_SPEED", f[3].into()),
            "heading" => post("NAV_HEADING", f[3].into()),
            "yaw_rate" => post("NAV_YAW_RATE", f[3].into()),
            "depth" => post("NAV_DEPTH", f[3].into()),
            "range" => post("OWTT_RANGE", format!("id={},travel_time={}", f[2], f[3])),
            "buoy_fix" => post("BUOY_FIX", format!("x={},y={}", f[3], f[4])),
            "ship_fix" => post("SHIP_FIX", format!("x={},y={},heading={}", f[3], f[4], f[5])),
            "truth" => {
                post("TRUTH_X", f[3].into());
                post("TRUTH_Y", f[4].into());
            }
            other => panic!("kind {other}"),
        }
    }
    out
}

#[test]
fn an_alog_postprocesses_like_the_csv_log() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join("sim");
    assert!(coopnav(tmp.path(), &["hbl", "simulate", "--out", sim.to_str().unwrap()]).status.success());
    let csv = sim.join("log.csv");
    let alog = tmp.path().join("sim.alog");
    std::fs::write(&alog, as_alog(&std::fs::read_to_string(&csv).unwrap())).unwrap();
    let map = tmp.path().join("map.toml");
    let out = coopnav(tmp.path(), &["hbl", "example", "alog-map"]);
    std::fs::write(&map, &out.stdout).unwrap();
    let summary = |log: &std::path::Path, name: &str| {
        let dir = tmp.path().join(name);
        let mut args = vec!["hbl", "postprocess", log.to_str().unwrap(), "--out", dir.to_str().unwrap()];
        if name == "alog" {
            args.extend(["--alog-map", map.to_str().unwrap()]);
        }
        let out = coopnav(tmp.path(), &args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };
    let (a, c) = (summary(&alog, "alog"), summary(&csv, "csv"));
    for key in ["ranges", "ranges_applied", "ranges_without_fix", "truth_points"] {
        assert_eq!(a[key], c[key], "{key}: alog {a} vs csv {c}");
    }
    // Millisecond times move each row by ≤ 0.5 ms: millimetres of motion (see nav's post_field).
    let (ea, ec) = (a["mean_smoothed_error"].as_f64().unwrap(), c["mean_smoothed_error"].as_f64().unwrap());
    assert!((ea - ec).abs() < 0.01, "mean smoothed error: alog {ea} m vs csv {ec} m");
}

#[test]
fn bad_alog_entries_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let head = "%% LOGSTART 0\n0.000 NAV_X a 1\n0.000 NAV_Y a 2\n0.000 NAV_SPEED a 1\n0.000 NAV_HEADING a 90\n";
    for (bad, said) in [
        ("1.000 NAV_SPEED a fast\n", "NAV_SPEED at t = 1 s: value \"fast\" is not a finite number"),
        // Any beacon id is allowed since the general log format; not 2.5.
        ("1.000 OWTT_RANGE a id=2.5,travel_time=0.2\n", "id 2.5 is not a beacon id"),
        ("1.000 OWTT_RANGE a id=99,travel_time=75\n", "travel_time 75 s must be in (0, 60]"),
        ("1.000 BEACON_FIX a id=4,x=1,y=2,depth=deep\n", "field 'depth' = \"deep\""),
        ("1.000 OWTT_RANGE a id=13\n", "has no field 'travel_time'"),
        ("1.000 SHIP_FIX a x=1,y=2,heading=north\n", "field 'heading' = \"north\""),
        ("1.000\n", "line 6"),
    ] {
        let log = tmp.path().join("bad.alog");
        std::fs::write(&log, format!("{head}{bad}")).unwrap();
        let dir = tmp.path().join("out");
        let out = coopnav(tmp.path(), &["hbl", "postprocess", log.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
        assert!(!out.status.success());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(said) && err.contains("bad.alog"), "{bad:?}: {err}");
        assert!(!dir.exists());
    }
    let log = tmp.path().join("none.alog");
    std::fs::write(&log, "0.000 NAV_X a 1\n1.000 NAV_Y a 2\n").unwrap();
    let dir = tmp.path().join("out");
    let out = coopnav(tmp.path(), &["hbl", "postprocess", log.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("both NAV_X and NAV_Y"));
}

/// An acoustic outlier the gate rejects is the filter working: `--strict` warns about it and still
/// writes the run; the log's own faults stay refused (above).
#[test]
fn strict_accepts_a_log_whose_only_unused_range_is_a_gated_outlier() {
    let tmp = tempfile::tempdir().unwrap();
    let log = tmp.path().join("log.csv");
    // The AUV sits at the origin heading north; the buoy 100 m east is fixed before each range.
    // Ranges of 100 m, then one 40 m long (a multipath arrival), then 100 m again.
    let mut text = String::from("t,kind,src,v1,v2,v3,v4\n0,init,,0,0,0,0\n");
    for (k, range) in [100.0, 100.0, 140.0, 100.0].iter().enumerate() {
        let t = 10.0 * (k + 1) as f64;
        text += &format!("{},buoy_fix,,100,0,,\n{t},speed,,0,,,\n{t},heading,,0,,,\n", t - 1.0);
        text += &format!("{t},range,13,{},,,\n", range / 1500.0);
    }
    std::fs::write(&log, text).unwrap();
    let post = tmp.path().join("post");
    let args = ["hbl", "postprocess", log.to_str().unwrap(), "--out", post.to_str().unwrap(), "--strict"];
    let out = coopnav(tmp.path(), &args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("1 range(s) were rejected by the innovation gate (range_gate)"), "{err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(post.join("summary.json")).unwrap()).unwrap();
    assert_eq!((summary["ranges_gated"].as_u64(), summary["ranges_applied"].as_u64()), (Some(1), Some(3)));
}
