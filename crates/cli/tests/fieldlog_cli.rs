//! The general log format through `coopnav hbl postprocess`: a three-beacon mission
//! with a current written as a version-2 log and as a MOOS .alog post-processes to the same
//! estimates both ways, better than the forward filter; `--tune` reports before/after with the
//! held-out residuals.

use coopnav_moos::alog::AlogWriter;
use coopnav_nav::fieldlog::{write_field_log, FieldLog, LogRow, Observation, TimeBase};
use coopnav_nav::synthetic::{synthetic_log, SyntheticSpec};
use std::path::Path;
use std::process::Command;

fn coopnav(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_coopnav")).args(args).output().expect("run coopnav")
}

fn mission() -> Vec<LogRow> {
    synthetic_log(&SyntheticSpec { duration_s: 1800.0, current: [0.15, -0.1], seed: 4, ..SyntheticSpec::default() })
}

/// The rows as alog postings under the default mapping (`hbl example alog-map`).
fn write_alog(path: &Path, rows: &[LogRow]) {
    let mut w = AlogWriter::new(std::fs::File::create(path).unwrap(), "mission.alog", 1.75e9).unwrap();
    for r in rows {
        let posts: Vec<(&str, String)> = match r.obs {
            Observation::Init { e, n, speed, compass_deg } => vec![
                ("NAV_X", e.to_string()),
                ("NAV_Y", n.to_string()),
                ("NAV_SPEED", speed.to_string()),
                ("NAV_HEADING", compass_deg.to_string()),
            ],
            Observation::Speed(s) => vec![("NAV_SPEED", s.to_string())],
            Observation::Heading { compass_deg } => vec![("NAV_HEADING", compass_deg.to_string())],
            Observation::YawRate { compass_deg_s } => vec![("NAV_YAW_RATE", compass_deg_s.to_string())],
            Observation::Truth { e, n } => vec![("TRUTH_X", e.to_string()), ("TRUTH_Y", n.to_string())],
            Observation::Range { beacon, travel_time } => {
                vec![("OWTT_RANGE", format!("id={beacon},travel_time={travel_time}"))]
            }
            Observation::BeaconFix { beacon, e, n, depth, .. } => {
                vec![("BEACON_FIX", format!("id={beacon},x={e},y={n},depth={depth}"))]
            }
            other => panic!("not in the mission: {other:?}"),
        };
        for (var, value) in posts {
            w.write(r.t, var, "pNav", &value).unwrap();
        }
    }
    w.finish().unwrap();
}

fn postprocess(log: &Path, config: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["hbl", "postprocess", log.to_str().unwrap(), "--config", config.to_str().unwrap()];
    args.extend(["-o", out.to_str().unwrap()]);
    args.extend(extra);
    let o = coopnav(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// Smoothed (east, north) at the truth rows of a run's estimates.csv.
fn smoothed_at_truth(out: &Path) -> Vec<[f64; 2]> {
    let text = std::fs::read_to_string(out.join("estimates.csv")).unwrap();
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (!f[9].is_empty()).then(|| [f[5].parse().unwrap(), f[6].parse().unwrap()])
        })
        .collect()
}

#[test]
fn three_beacons_with_a_current_as_v2_and_as_alog_give_the_same_estimates() {
    let tmp = tempfile::tempdir().unwrap();
    let rows = mission();
    let (csv, alog, config) = (tmp.path().join("m.csv"), tmp.path().join("m.alog"), tmp.path().join("post.toml"));
    let log = FieldLog { time: TimeBase::Relative, rows: rows.clone() };
    write_field_log(std::fs::File::create(&csv).unwrap(), &log, None).unwrap();
    write_alog(&alog, &rows);
    std::fs::write(&config, "model = { kind = \"current\" }\n").unwrap();
    let (a, c) = (tmp.path().join("a"), tmp.path().join("c"));
    let (sa, sc) = (postprocess(&alog, &config, &a, &[]), postprocess(&csv, &config, &c, &[]));
    for key in ["ranges", "ranges_applied", "ranges_without_fix", "ranges_gated", "truth_points"] {
        assert_eq!(sa[key], sc[key], "{key}: alog {sa} vs csv {sc}");
    }
    assert_eq!(sc["ranges"], 119);
    assert_eq!(sc["ranges_without_fix"], 0);
    // The alog keeps milliseconds: each row moves ≤ 0.5 ms, millimetres of motion.
    let (pa, pc) = (smoothed_at_truth(&a), smoothed_at_truth(&c));
    assert_eq!(pa.len(), 180);
    assert_eq!(pa.len(), pc.len());
    let worst = pa.iter().zip(&pc).map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1])).fold(0.0, f64::max);
    assert!(worst < 0.05, "smoothed positions differ by up to {worst} m");
    for s in [&sa, &sc] {
        let (f, sm) = (s["rms_filtered_error"].as_f64().unwrap(), s["rms_smoothed_error"].as_f64().unwrap());
        assert!(sm < 0.9 * f, "RMS error smoothed {sm} m vs filtered {f} m");
    }
}

#[test]
fn tune_reports_before_and_after_with_held_out_ranges() {
    let tmp = tempfile::tempdir().unwrap();
    let rows = synthetic_log(&SyntheticSpec { duration_s: 1800.0, range_sd_m: 4.0, seed: 2, ..Default::default() });
    let (csv, config, out) = (tmp.path().join("m.csv"), tmp.path().join("post.toml"), tmp.path().join("o"));
    write_field_log(std::fs::File::create(&csv).unwrap(), &FieldLog { time: TimeBase::Relative, rows }, None).unwrap();
    std::fs::write(&config, "").unwrap();
    let o = coopnav(&[
        "hbl",
        "postprocess",
        csv.to_str().unwrap(),
        "--config",
        config.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--tune",
        "--tune-iters",
        "25",
        "--hold-out-every",
        "4",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("before") && stdout.contains("after") && stdout.contains("out_smth_m"), "{stdout}");
    let t: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("tune.json")).unwrap()).unwrap();
    assert_eq!(t["hold_out_every"], 4);
    let (b, a) = (&t["before"], &t["after"]);
    assert!(a["held_out_log_predictive"].as_f64().unwrap() > b["held_out_log_predictive"].as_f64().unwrap(), "{t}");
    // summary.json records the guard's choice and what the run says without truth.
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s["tuning"]["guard"]["kept"].is_string(), "{s}");
    let q = &s["quality"];
    assert!(q["nis"]["verdict"].is_string() && q["claimed_accuracy"]["p95_sd_m"].is_number(), "{q}");
    assert!(q["held_out"]["rms_smoothed_m"].is_number() && q["beacons"].as_array().unwrap().len() == 3, "{q}");
    assert!(a["held_out_rms_filter_m"].is_number() && b["held_out_rms_smoothed_m"].is_number(), "{t}");
    // The run's outputs use the tuned values.
    let tuned: toml::Value = toml::from_str(&std::fs::read_to_string(out.join("tuned_config.toml")).unwrap()).unwrap();
    let values = &a["values"];
    let noise = &tuned["auv"]["range_noise"];
    let num = |v: &toml::Value| v.as_float().unwrap_or_else(|| panic!("{v} is not a number"));
    let sd = values["range_sd_m"].as_f64().unwrap();
    // The config holds σ_τ = sd / c: equal to sd up to the rounding of a division and a product.
    let sd_in_config = num(&noise["sound_speed"]) * num(&noise["sigma_time"]);
    assert!((sd_in_config - sd).abs() <= 1e-12 * sd, "range SD {sd} m tuned, {sd_in_config} m in the config");
    // The other values are copied; the two files print them each their own way, equal to within
    // the last digit.
    let q = tuned["auv"]["q"].as_array().unwrap();
    let copied = [
        (&q[0], "q_en"),
        (&q[1], "q_en"),
        (&tuned["speed_scale"], "speed_scale"),
        (&tuned["heading_bias_deg"], "heading_bias_deg"),
    ];
    for (in_config, key) in copied {
        let (c, v) = (num(in_config), values[key].as_f64().unwrap());
        assert!((c - v).abs() <= 1e-15 * v.abs().max(1e-300), "{key}: {v} tuned, {c} in the config");
    }
    // The log's ranges have an SD of 4 m and the empty config starts at c·σ_τ = 1.8 m: the tuned
    // value is nearer the truth than the start.
    let start = b["values"]["range_sd_m"].as_f64().unwrap();
    assert!((start - 1.8).abs() < 1e-9, "{t}");
    assert!((sd - 4.0).abs() < (start - 4.0).abs() / 2.0, "range SD tuned from {start} m to {sd} m; the log's is 4 m");
}
