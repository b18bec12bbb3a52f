//! Every field validated: for each input kind, one file (or argument list) with
//! NaN, negative and out-of-range values. coopnav refuses it, writes nothing, and its one message
//! names the file and every bad field. (The closed-loop scenario and the Nams experiment have
//! theirs in crates/sim.)

mod common;

use common::{coopnav, edited_example};
use std::path::Path;

/// Runs `coopnav ARGS` in `dir` and checks it fails, writes no `out` directory, names `file`
/// (when given) and every field of `fields` as `field NAME = ...`.
fn refused_naming_every_field(dir: &Path, args: &[&str], file: Option<&str>, fields: &[&str]) {
    let o = coopnav(dir, args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "`coopnav {args:?}` accepted bad input:\n{err}");
    assert!(!dir.join("out").exists(), "`coopnav {args:?}` wrote an output directory");
    if let Some(file) = file {
        assert!(err.contains(file), "the message does not name {file}:\n{err}");
    }
    let missing: Vec<&&str> = fields.iter().filter(|f| !err.contains(&format!("field {f} = "))).collect();
    assert!(missing.is_empty(), "fields not named: {missing:?}\nin:\n{err}");
}

#[test]
fn plan_scenario_names_every_bad_field() {
    let tmp = tempfile::tempdir().unwrap();
    edited_example(
        tmp.path(),
        &["plan", "--example"],
        "bad.toml",
        &[
            ("x = 140.0", "x = nan"),
            ("alpha = 0.1", "alpha = -0.1"),
            ("speed = 3.0", "speed = -3.0"),
            ("heading_options = 5", "heading_options = 1"),
            ("min = 100.0", "min = 2000.0"),
            ("name = \"auv1\"", "name = \"auv1\"\nsigma0 = -1.0"),
            ("lane_length = 600.0", "lane_length = -600.0"),
            ("period = 600.0", "period = 0.0"),
        ],
    );
    refused_naming_every_field(
        tmp.path(),
        &["plan", "bad.toml", "-o", "out"],
        Some("bad.toml"),
        &[
            "cna.x",
            "policy.planner.cost.alpha",
            "platform.speed",
            "policy.planner.tree.heading_options",
            "policy.planner.limits",
            "auv[0].sigma0",
            "auv[0].lawnmower.lane_length",
            "auv[1].lawnmower.depth.period",
        ],
    );
}

#[test]
fn hbl_scenario_names_every_bad_field() {
    let tmp = tempfile::tempdir().unwrap();
    let out = coopnav(tmp.path(), &["hbl", "example", "scenario"]);
    let text = String::from_utf8(out.stdout).unwrap();
    let mut bad = text.clone();
    for (good, wrong) in [
        ("speed = 0.85", "speed = -1.0"),
        ("speed_sd = 0.05\n", "speed_sd = -0.1\n"),
        ("circular_fraction = 0.5", "circular_fraction = 1.5"),
        ("separation = 9.3", "separation = -1.0"),
        ("gps_sd_m = 0.1\n", "gps_sd_m = nan\n"),
    ] {
        assert!(bad.contains(good), "{good} not in the example");
        bad = bad.replacen(good, wrong, 1);
    }
    std::fs::write(tmp.path().join("bad.toml"), bad).unwrap();
    refused_naming_every_field(
        tmp.path(),
        &["hbl", "simulate", "bad.toml", "-o", "out"],
        Some("bad.toml"),
        &["fleet.speed", "sensors.speed_sd", "buoys[0].drift.circular_fraction", "ships[0].outriggers.separation"],
    );
}

#[test]
fn hbl_grid_spec_names_every_bad_field() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("grid.toml"),
        "x = [nan, 10.0]\ny = [10.0, -5.0]\nspacing = -1.0\nruns_per_cell = 1\n",
    )
    .unwrap();
    refused_naming_every_field(
        tmp.path(),
        &["hbl", "grid", "--grid", "grid.toml", "-o", "out"],
        Some("grid.toml"),
        &["x[0]", "y[1]", "spacing", "runs_per_cell"],
    );
}

#[test]
fn hbl_tune_spec_names_every_bad_field() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(
        tmp.path().join("tune.toml"),
        "coefficients = []\nobjective = 'auv_zone'\nruns = 0\nmax_iters = 0\n",
    )
    .unwrap();
    refused_naming_every_field(
        tmp.path(),
        &["hbl", "tune", "--spec", "tune.toml", "-o", "out"],
        Some("tune.toml"),
        &["coefficients", "runs", "max_iters"],
    );
}

#[test]
fn postprocessing_config_names_every_bad_field() {
    let tmp = tempfile::tempdir().unwrap();
    std::fs::write(tmp.path().join("log.csv"), "t,kind,src,v1,v2,v3,v4\n0,init,,0,0,1,90\n1,speed,,1,,,\n").unwrap();
    let config = "max_gap_s = nan\ntransponder_sd_m = -1.0\nbuoy_depth = -3.0\nacoustic_time_offset_s = inf\n\
                  [auv]\nstep_s = 0.0\n[fixes]\nmax_age_s = -1.0\n[range_gate]\nmax_nis = -2.0\n";
    std::fs::write(tmp.path().join("pp.toml"), config).unwrap();
    refused_naming_every_field(
        tmp.path(),
        &["hbl", "postprocess", "log.csv", "--config", "pp.toml", "-o", "out"],
        Some("pp.toml"),
        &[
            "max_gap_s",
            "transponder_sd_m",
            "buoy_depth",
            "acoustic_time_offset_s",
            "auv.step_s",
            "fixes.max_age_s",
            "range_gate.max_nis",
        ],
    );
}

#[test]
fn channel_arguments_name_every_bad_value() {
    let tmp = tempfile::tempdir().unwrap();
    refused_naming_every_field(
        tmp.path(),
        &["channel", "--k", "nan", "--noise-db=-1", "--source-depth=-5", "--x", "inf", "--step", "0", "-o", "out"],
        None,
        &["--k", "--noise-db", "--source-depth", "--x", "--step"],
    );
}

/// A pre-deployment mission of track files alone is sized from the tracks once they are read,
/// not refused as infinitely long.
#[test]
fn plan_with_only_track_files_is_sized_from_the_tracks() {
    let tmp = tempfile::tempdir().unwrap();
    let example = String::from_utf8(coopnav(tmp.path(), &["plan", "--example"]).stdout).unwrap();
    let head = &example[..example.find("[[auv]]").expect("the example lists its AUVs")];
    let mut text = head.to_string();
    for (k, x) in [(1, 0.0), (2, 150.0)] {
        let rows: String = (0..=1200).map(|i| format!("{i},{x},{},90\n", 1.5 * f64::from(i))).collect();
        std::fs::write(tmp.path().join(format!("auv{k}.csv")), format!("t,x,y,z\n{rows}")).unwrap();
        text.push_str(&format!("[[auv]]\nname = \"auv{k}\"\ntrack_csv = \"auv{k}.csv\"\n\n"));
    }
    std::fs::write(tmp.path().join("tracks.toml"), text).unwrap();
    let out = coopnav(tmp.path(), &["plan", "tracks.toml", "-o", "out"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(tmp.path().join("out/summary.json").is_file());
}

/// Messages a user can act on: a log's absurd time or speed names its line and field, a mission
/// too short to sample is refused before it runs, and a huge offending value is quoted short.
#[test]
fn weak_inputs_get_messages_that_name_the_line_and_field() {
    let tmp = tempfile::tempdir().unwrap();
    let log = "# coopnav-log 2 time=relative\nt,kind,src,v1,v2,v3,v4,sigma\n0,init,,0,0,1.5,90,\n";
    for (row, field) in [("1e300,speed,,1.5,,,,", "'t'"), ("1,speed,,1e300,,,,", "'v1'")] {
        std::fs::write(tmp.path().join("log.csv"), format!("{log}{row}\n")).unwrap();
        let out = coopnav(tmp.path(), &["hbl", "postprocess", "log.csv", "-o", "out"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains("line 4") && err.contains(field), "{row}: {err}");
        assert!(!tmp.path().join("out").exists());
    }
    edited_example(
        tmp.path(),
        &["simulate", "--example"],
        "short.toml",
        &[("duration_s = 3600.0", "duration_s = 1e-9")],
    );
    let out = coopnav(tmp.path(), &["simulate", "short.toml", "-o", "out"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("field duration_s = 0.000000001"), "{err}");
    assert!(!tmp.path().join("out").exists(), "refused before the run");
    // An unknown key a megabyte long: the parser's message quotes the line, shortened.
    let example = String::from_utf8(coopnav(tmp.path(), &["simulate", "--example"]).stdout).unwrap();
    let long = example.replacen("seed = 1", &format!("seed = 1\nzzz = \"{}\"", "a".repeat(300_000)), 1);
    std::fs::write(tmp.path().join("long.toml"), long).unwrap();
    let out = coopnav(tmp.path(), &["simulate", "long.toml", "-o", "out"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("zzz") && err.contains("more characters"),
        "{}",
        &err[..err.len().min(600)]
    );
    assert!(err.len() < 2_000, "the message quotes {} bytes", err.len());
}
