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
            "planner.error.alpha",
            "planner.motion.speed",
            "planner.motion.heading_options",
            "planner.limits",
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
        &["hbl", "simulate", "--config", "bad.toml", "-o", "out"],
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
        &["hbl", "postprocess", "--log", "log.csv", "--config", "pp.toml", "-o", "out"],
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
