//! `coopnav hbl postprocess` never drops rows in silence: rows it does not use are warnings on
//! stderr, and under `--strict` an error that writes nothing.

use std::process::Command;

fn coopnav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_coopnav")).args(args).output().expect("run coopnav")
}

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
        let mut a = vec!["hbl", "postprocess", "--log", log.to_str().unwrap(), "--out"];
        a.push(dir.to_str().unwrap());
        if strict {
            a.push("--strict");
        }
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |a: Vec<String>| coopnav(&a.iter().map(String::as_str).collect::<Vec<_>>());
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
    let out = coopnav(&["hbl", "simulate", "--out", sim.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let cfg = tmp.path().join("post.toml");
    std::fs::write(&cfg, "origin = { lat_deg = 47.97, lon_deg = -116.5 }\n").unwrap();
    let post = tmp.path().join("post");
    let log = sim.join("log.csv");
    let (log, cfg, dir) = (log.to_str().unwrap(), cfg.to_str().unwrap(), post.to_str().unwrap());
    let out = coopnav(&["hbl", "postprocess", "--log", log, "--config", cfg, "--out", dir]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(post.join("summary.json")).unwrap()).unwrap();
    let (before, after) =
        (summary["residual_rms_filter_m"].as_f64().unwrap(), summary["residual_rms_smoothed_m"].as_f64().unwrap());
    assert!(after < before, "residual RMS {before} m before smoothing, {after} m after");
    let residuals = std::fs::read_to_string(post.join("residuals.csv")).unwrap();
    let used = summary["ranges_applied"].as_u64().unwrap() + summary["ranges_gated"].as_u64().unwrap();
    assert_eq!(residuals.lines().count() as u64, used + 1, "{residuals}");
    let track = std::fs::read_to_string(post.join("estimates.csv")).unwrap();
    let ll = std::fs::read_to_string(post.join("smoothed_ll.csv")).unwrap();
    assert_eq!(ll.lines().count(), track.lines().count());
    for row in ll.lines().skip(1) {
        let f: Vec<f64> = row.split(',').map(|v| v.parse().unwrap()).collect();
        assert!((f[1] - 47.97).abs() < 0.05 && (f[2] + 116.5).abs() < 0.05, "{row}");
    }
}
