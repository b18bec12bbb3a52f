//! The `coopnav hbl` subcommands end to end: a run directory is written whole, bad input exits
//! non-zero and writes nothing, and a simulated log post-processes.

mod common;

use common::coopnav;

#[test]
fn simulate_then_postprocess() {
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join("sim");
    let out = coopnav(tmp.path(), &["hbl", "simulate", "--seed", "4", "--out", sim.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for f in ["manifest.json", "summary.json", "trace.csv", "log.csv", "tracks.svg", "error_vs_xrel.svg"] {
        assert!(sim.join(f).exists(), "missing {f}");
    }
    let again = coopnav(tmp.path(), &["hbl", "simulate", "--out", sim.to_str().unwrap()]);
    assert!(!again.status.success(), "must refuse to overwrite without --force");
    let post = tmp.path().join("post");
    let out = coopnav(
        tmp.path(),
        &["hbl", "postprocess", sim.join("log.csv").to_str().unwrap(), "--out", post.to_str().unwrap()],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary = std::fs::read_to_string(post.join("summary.json")).unwrap();
    assert!(summary.contains("mean_smoothed_error"));
}

/// `hbl simulate --run I` replays exactly run I of `hbl montecarlo` with the same seed, and the
/// Monte Carlo directory carries its error profile.
#[test]
fn simulate_run_replays_a_monte_carlo_run() {
    let tmp = tempfile::tempdir().unwrap();
    let mc = tmp.path().join("mc");
    let out = coopnav(tmp.path(), &["hbl", "montecarlo", "--runs", "4", "--seed", "9", "--out", mc.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for f in ["runs.csv", "profile.csv", "profile.svg", "summary.json"] {
        assert!(mc.join(f).exists(), "missing {f}");
    }
    let runs = std::fs::read_to_string(mc.join("runs.csv")).unwrap();
    let zone_of_run_2: f64 = runs.lines().nth(3).unwrap().split(',').nth(1).unwrap().parse().unwrap();
    let sim = tmp.path().join("sim");
    let out = coopnav(tmp.path(), &["hbl", "simulate", "--seed", "9", "--run", "2", "--out", sim.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sim.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["zone_error"].as_f64().unwrap(), zone_of_run_2);
}

/// The printed examples are valid inputs of the commands they are for.
#[test]
fn examples_load_back() {
    let tmp = tempfile::tempdir().unwrap();
    let write = |kind: &str| {
        let out = coopnav(tmp.path(), &["hbl", "example", kind]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let path = tmp.path().join(format!("{kind}.toml"));
        std::fs::write(&path, &out.stdout).unwrap();
        path
    };
    let (scenario, post, format) = (write("scenario"), write("post"), write("log-format"));
    let mc = tmp.path().join("mc");
    let out = coopnav(
        tmp.path(),
        &["hbl", "montecarlo", "--runs", "3", scenario.to_str().unwrap(), "--out", mc.to_str().unwrap()],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let sim = tmp.path().join("sim");
    let out = coopnav(
        tmp.path(),
        &["hbl", "simulate", "--log-format", format.to_str().unwrap(), "--out", sim.to_str().unwrap()],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let pp = tmp.path().join("pp");
    let out = coopnav(
        tmp.path(),
        &[
            "hbl",
            "postprocess",
            sim.join("log.csv").to_str().unwrap(),
            "--config",
            post.to_str().unwrap(),
            "--out",
            pp.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn bad_config_exits_nonzero_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let cfg = tmp.path().join("bad.toml");
    // A file of the former `hbl` scenario format.
    std::fs::write(&cfg, "[acoustic]\np_drop = 0.7\n").unwrap();
    let out_dir = tmp.path().join("mc");
    let out = coopnav(
        tmp.path(),
        &["hbl", "montecarlo", "--runs", "4", cfg.to_str().unwrap(), "--out", out_dir.to_str().unwrap()],
    );
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.toml") && err.contains("former") && err.contains("hbl example scenario"), "{err}");
    assert!(!out_dir.exists());
    let log = tmp.path().join("log.csv");
    std::fs::write(&log, "t,kind,src,v1,v2,v3,v4\n0,init,,0,0,0.85,90\n1,range,99,0.1,,,\n").unwrap();
    let post = tmp.path().join("post");
    let out = coopnav(tmp.path(), &["hbl", "postprocess", log.to_str().unwrap(), "--out", post.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("line 3") && err.contains("99"), "{err}");
    assert!(!post.exists());
}

#[test]
fn geodetic_log_needs_the_origin_to_postprocess() {
    let tmp = tempfile::tempdir().unwrap();
    let origin = "{ lat_deg = 47.97, lon_deg = -116.5, height_m = 630.0 }";
    let format = tmp.path().join("log.toml");
    std::fs::write(&format, format!("geodetic_origin = {origin}\nbuoy_fix_storage = \"f32_lost_bit\"\n")).unwrap();
    let sim = tmp.path().join("sim");
    let out = coopnav(
        tmp.path(),
        &["hbl", "simulate", "--log-format", format.to_str().unwrap(), "--out", sim.to_str().unwrap()],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let log = sim.join("log.csv");
    assert!(std::fs::read_to_string(&log).unwrap().contains(",buoy_fix_ll,"));
    let post = tmp.path().join("post");
    let out = coopnav(tmp.path(), &["hbl", "postprocess", log.to_str().unwrap(), "--out", post.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("log.csv") && err.contains("line 2") && err.contains("origin = {"), "{err}");
    assert!(!post.exists());
    let cfg = tmp.path().join("post.toml");
    std::fs::write(&cfg, format!("origin = {origin}\n")).unwrap();
    let out = coopnav(
        tmp.path(),
        &[
            "hbl",
            "postprocess",
            log.to_str().unwrap(),
            "--config",
            cfg.to_str().unwrap(),
            "--out",
            post.to_str().unwrap(),
        ],
    );
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::read_to_string(post.join("summary.json")).unwrap().contains("mean_smoothed_error"));
}

/// The measurement zone's edges are options: by default Table 5's (the same bytes as giving them),
/// a narrower zone scores fewer samples and is recorded in the manifest, and a zone whose edges
/// are crossed is refused naming both options, writing nothing.
#[test]
fn the_zone_is_configurable_and_defaults_to_table_5() {
    let tmp = tempfile::tempdir().unwrap();
    let simulate = |name: &str, zone: &[&str]| {
        let dir = tmp.path().join(name);
        let mut args = vec!["hbl", "simulate", "--seed", "3", "--out", dir.to_str().unwrap()];
        args.extend_from_slice(zone);
        (coopnav(tmp.path(), &args), dir)
    };
    let read = |dir: &std::path::Path, f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    let (out, default) = simulate("default", &[]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (out, table5) = simulate("table5", &["--zone-min-m", "-30", "--zone-max-m", "75"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for f in ["summary.json", "trace.csv", "log.csv"] {
        assert_eq!(read(&default, f), read(&table5, f), "{f}");
    }
    let (out, narrow) = simulate("narrow", &["--zone-min-m", "0", "--zone-max-m", "10"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let samples = |dir: &std::path::Path| {
        let v: serde_json::Value = serde_json::from_str(&read(dir, "summary.json")).unwrap();
        v["zone_samples"].as_u64().unwrap()
    };
    // 105 m of zone against 10 m, passed at about 2.15 m/s of closing speed, 10 samples a second.
    assert!(
        samples(&narrow) > 0 && samples(&narrow) * 5 < samples(&default),
        "{} vs {}",
        samples(&narrow),
        samples(&default)
    );
    let manifest: serde_json::Value = serde_json::from_str(&read(&narrow, "manifest.json")).unwrap();
    assert_eq!(manifest["inputs"]["zone"]["zone_max_m"], 10.0);
    let (out, crossed) = simulate("crossed", &["--zone-min-m", "20", "--zone-max-m", "10"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("--zone-min-m 20") && err.contains("--zone-max-m 10"), "{err}");
    assert!(!crossed.exists());
}
