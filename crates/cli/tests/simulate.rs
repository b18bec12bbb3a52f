//! `coopnav simulate` end to end: the default mission writes a run directory with the report,
//! its error plot marks and explains the error's one-second jump, `--example` prints a scenario
//! that runs, and a bad scenario fails naming the field and writes nothing.

mod common;

use common::coopnav;

#[test]
fn default_mission_writes_a_fresh_run_directory() {
    let tmp = tempfile::tempdir().unwrap();
    for expected in ["sim-default", "sim-default-2"] {
        let out = coopnav(tmp.path(), &["simulate"]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let run = tmp.path().join("runs").join(expected);
        for f in [
            "report.html",
            "summary.json",
            "manifest.json",
            "timeseries.csv",
            "comms.csv",
            "tracks.svg",
            "error.svg",
            "comms.svg",
        ] {
            assert!(run.join(f).is_file(), "{expected}/{f}");
        }
    }
}

/// The numbers in `text` (after `after`), as written.
fn number_after(text: &str, after: &str) -> f64 {
    let rest = &text[text.find(after).unwrap_or_else(|| panic!("no {after:?} in {text:?}")) + after.len()..];
    rest.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-')).next().unwrap().parse().unwrap()
}

#[test]
fn the_default_error_plot_explains_its_jump() {
    // The default mission's timeseries.csv (before the plot marked anything): auv2's true error
    // rises from 8.32 m at 1144 s to 23.06 m at 1145 s, the largest one-second rise of the run,
    // at the range of the CNA's 1140 s broadcast.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("run");
    let out = coopnav(tmp.path(), &["simulate", "-o", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let svg = std::fs::read_to_string(dir.join("error.svg")).unwrap();
    let marker = svg
        .split("<text")
        .filter_map(|t| t.split_once('>').map(|(_, x)| x.split("</text>").next().unwrap().trim()))
        .find(|t| t.starts_with("auv2 1145 s, +14.7 m: range "))
        .unwrap_or_else(|| panic!("no marker of auv2's jump at 1145 s"));
    // The scenario's channel: 5.55 % of ranges are outliers 5 to 10 m long.
    let long = number_after(marker, "range ");
    assert!((5.0..=10.0).contains(&long) && marker.contains(" m long applied, NIS "), "{marker}");
    // Applied, so under the 10.83 gate.
    assert!(number_after(marker, "NIS ") < 10.83, "{marker}");
    // The filter's σ before it, from timeseries.csv at 1144 s: 20.6 m.
    assert!(marker.contains("σ 20.6 m before"), "{marker}");
    // A triangle in auv2's colour (Okabe-Ito bluish green), numbered, and the note saying what
    // triangles mark: rises of a quarter of the run's largest error, 26.83 m in timeseries.csv.
    assert!(svg.contains("<polygon") && svg.contains("#009E73"), "the triangle");
    assert!(svg.contains("Triangles: rises of 6.7 m or more in one second"), "the note");
    let report = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(report.contains("Error jumps marked on the error plot: auv2 1145 s, +14.7 m"), "the report");
}

#[test]
fn example_round_trips_and_bad_files_fail_cleanly() {
    let tmp = tempfile::tempdir().unwrap();
    let example = coopnav(tmp.path(), &["simulate", "--example"]);
    assert!(example.status.success());
    let text = String::from_utf8(example.stdout).unwrap();
    let short = text.replace("duration_s = 3600.0", "duration_s = 120.0");
    std::fs::write(tmp.path().join("s.toml"), &short).unwrap();
    let ok = coopnav(tmp.path(), &["simulate", "s.toml", "--runs", "2", "--policy", "planner,centroid"]);
    assert!(ok.status.success(), "{}", String::from_utf8_lossy(&ok.stderr));
    let table = String::from_utf8(ok.stdout).unwrap();
    assert!(table.contains("centroid") && table.contains("95% CI"), "{table}");

    std::fs::write(tmp.path().join("bad.toml"), short.replace("tau = 30.0", "tau = 0.5")).unwrap();
    let bad = coopnav(tmp.path(), &["simulate", "bad.toml"]);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("comms.tau") && err.contains("bad.toml"), "{err}");
    assert!(!tmp.path().join("runs").exists(), "nothing written for a bad scenario");
}

/// `bench closed-loop` lists each AUV's part of its fleet mean (equal samples per AUV, so the
/// fleet mean is the mean of theirs); on the analytic TL the CNA hears and serves every AUV.
#[test]
fn the_closed_loop_bench_splits_its_fleet_error_by_auv() {
    let tmp = tempfile::tempdir().unwrap();
    let out = coopnav(tmp.path(), &["bench", "closed-loop", "--tl", "analytic", "--runs", "1"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let object = json.as_object().unwrap();
    let per_auv = object.iter().find(|(k, _)| k.starts_with("per_auv")).unwrap().1.as_array().unwrap();
    assert_eq!(per_auv.len() as u64, json["n_auvs"].as_u64().unwrap());
    let mean = per_auv.iter().map(|a| a["mean_true_error_m"].as_f64().unwrap()).sum::<f64>() / per_auv.len() as f64;
    let fleet = json["fleet_mean_true_error_m"].as_f64().unwrap();
    assert!((mean - fleet).abs() < 1e-9 * fleet, "per-AUV mean {mean} vs fleet {fleet}");
    for a in per_auv {
        assert!(
            a["ranges_applied"].as_u64().unwrap() > 0 && a["statuses_received_by_cna"].as_u64().unwrap() > 0,
            "{a}"
        );
    }
}

#[test]
fn generated_missions_run_as_they_are_written() {
    let tmp = tempfile::tempdir().unwrap();
    let ranges =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/generators/generalization.toml");
    let ranges = ranges.to_str().unwrap();
    let out = coopnav(tmp.path(), &["generate", ranges, "--missions", "3", "--seed", "500", "-o", "g"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let index = std::fs::read_to_string(tmp.path().join("g/missions.csv")).unwrap();
    assert_eq!(index.lines().count(), 4, "{index}");
    assert!(index.lines().nth(1).unwrap().starts_with("mission-000.toml,500,"), "{index}");
    let text = std::fs::read_to_string(tmp.path().join("g/mission-002.toml")).unwrap();
    assert!(text.contains("seed = 502") && !text.contains("\n[policy"), "{text}");
    // A shorter copy of the mission runs (the full one is the same file with its own duration).
    let duration = text.lines().find(|l| l.starts_with("duration_s = ")).unwrap();
    std::fs::write(tmp.path().join("m.toml"), text.replace(duration, "duration_s = 300.0")).unwrap();
    let run = coopnav(tmp.path(), &["simulate", "m.toml", "--runs", "2", "--policy", "planner-estimator,zigzag"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(String::from_utf8(run.stdout).unwrap().contains("base seed 502"));
    // The same file and seed give the same missions, byte for byte.
    let again = coopnav(tmp.path(), &["generate", ranges, "--missions", "3", "--seed", "500", "-o", "h"]);
    assert!(again.status.success());
    let other = std::fs::read_to_string(tmp.path().join("h/mission-002.toml")).unwrap();
    assert_eq!(text, other);
}
