//! Pre-deployment runs: the embedded example, scenario validation (each bad input names its
//! field or line), determinism across thread counts, and the run directory.

use coopnav_plan::predeploy;
use coopnav_plan::LookAheadPlanner;
use coopnav_sim::output::plan::write_run;
use coopnav_sim::output::RunDir;
use coopnav_sim::scenario::plan::{Scenario, ScenarioError, EXAMPLE};
use std::path::Path;

fn example() -> Scenario {
    Scenario::parse(EXAMPLE, Path::new("example.toml")).unwrap()
}

fn err_of(text: &str) -> String {
    let file = Path::new("bad.toml");
    match Scenario::parse(text, file).and_then(|s| s.build(file, Path::new("."))) {
        Ok(_) => panic!("accepted a bad scenario"),
        Err(e) => e.to_string(),
    }
}

fn short_example() -> String {
    EXAMPLE.replace("[cna]", "[mission]\nend_time = 600.0\n\n[cna]")
}

#[test]
fn example_runs_and_respects_limits() {
    let s = Scenario::parse(&short_example(), Path::new("e")).unwrap();
    let m = s.build(Path::new("e"), Path::new(".")).unwrap();
    let mut p = LookAheadPlanner::new(m.planner).unwrap();
    let r = predeploy::run(&m, &mut p, &|_| {}).unwrap();
    assert_eq!(r.summary.steps, 60);
    assert_eq!(r.steps.len(), 61);
    // The CNA moves s·τ each step.
    for w in r.steps.windows(2) {
        assert!(((w[1].cna.pos - w[0].cna.pos).norm() - 30.0).abs() < 1e-9);
    }
    assert!(r.summary.max_error >= r.summary.rms_error && r.summary.rms_error > 1.0);
    assert!(r.summary.min_distance <= r.summary.mean_distance && r.summary.mean_distance <= r.summary.max_distance);
    assert!(example().build(Path::new("e"), Path::new(".")).is_ok());
}

#[test]
fn same_run_on_one_and_two_threads() {
    let s = Scenario::parse(&short_example(), Path::new("e")).unwrap();
    let m = s.build(Path::new("e"), Path::new(".")).unwrap();
    assert!(m.planner.search.parallel);
    let run = |threads| {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
            let mut p = LookAheadPlanner::new(m.planner).unwrap();
            predeploy::run(&m, &mut p, &|_| {}).unwrap()
        })
    };
    let (a, b) = (run(1), run(2));
    assert_eq!(a.summary, b.summary);
    let poses = |r: &predeploy::RunResult| r.steps.iter().map(|s| s.cna.pos).collect::<Vec<_>>();
    assert_eq!(poses(&a), poses(&b));
}

#[test]
fn bad_scenarios_name_the_field() {
    let e = err_of(&EXAMPLE.replace("look_ahead = 4 }", "look_ahead = 4, lookahead = 3 }"));
    assert!(e.contains("unknown field") && e.contains("lookahead"), "{e}");
    let e = err_of(&EXAMPLE.replace("heading_options = 5", "heading_options = 1"));
    assert!(e.contains("policy.planner.tree.heading_options") && e.contains(">= 2"), "{e}");
    let e = err_of(&EXAMPLE.replace("speed = 3.0 ", "speed = -2.0 "));
    assert!(e.contains("platform.speed") && e.contains("> 0"), "{e}");
    let e = err_of(&EXAMPLE.replace("max_turn_rate_deg_s = 4.0", "max_turn_rate_deg_s = 18.0"));
    assert!(e.contains("platform.max_turn_rate_deg_s") && e.contains("180"), "{e}");
    let e = err_of(&EXAMPLE.replace("case = \"8\"", "case = \"14\""));
    assert!(e.contains("policy.planner.penalty.case") && e.contains("12a"), "{e}");
    let e = err_of(&EXAMPLE.replace(
        "cost = { kind = \"hudson\", alpha = 0.1, bearing = \"horizontal\" }",
        "cost = { kind = \"estimator\" }",
    ));
    assert!(e.contains("policy.planner.cost.kind = estimator") && e.contains("hudson"), "{e}");
    let e = err_of(
        &EXAMPLE.replace("speed = 1.5\ndepth = { kind = \"constant\"", "speed = 0.0\ndepth = { kind = \"constant\""),
    );
    assert!(e.contains("auv[0].lawnmower.speed"), "{e}");
}

#[test]
fn bad_track_files_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let with_csv = |csv: &str| {
        std::fs::write(dir.path().join("t.csv"), csv).unwrap();
        let text = "[cna]\nx = 0.0\ny = 0.0\nheading_compass_deg = 90.0\n[platform]\nspeed = 2.0\ntau = 10.0\ncna = { kind = \"asc\" }\n[policy.planner]\ntree = { heading_options = 3, look_ahead = 1 }\npenalty = { case = \"1\" }\ndeadline = { kind = \"none\" }\ncost = { kind = \"hudson\" }\n[[auv]]\nname = \"a\"\ntrack_csv = \"t.csv\"\n";
        Scenario::parse(text, Path::new("s.toml")).unwrap().build(Path::new("s.toml"), dir.path())
    };
    assert!(with_csv("t,x,y,z\n0,0,0,90\n100,150,0,90\n").is_ok());
    let e = with_csv("").unwrap_err().to_string();
    assert!(e.contains("auv[0]") && e.contains("empty"), "{e}");
    let e = with_csv("t,x,y,z\n0,0,0,90\n50,1,0,90\n40,2,0,90\n").unwrap_err().to_string();
    assert!(e.contains("line 4") && e.contains("increase"), "{e}");
}

#[test]
fn missing_track_file_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let text = "[cna]\nx = 0.0\ny = 0.0\nheading_compass_deg = 90.0\n[platform]\nspeed = 2.0\ntau = 10.0\ncna = { kind = \"asc\" }\n[policy.planner]\ntree = { heading_options = 3, look_ahead = 1 }\npenalty = { case = \"1\" }\ndeadline = { kind = \"none\" }\ncost = { kind = \"hudson\" }\n[[auv]]\nname = \"a\"\ntrack_csv = \"missing.csv\"\n";
    let s = Scenario::parse(text, Path::new("s.toml")).unwrap();
    match s.build(Path::new("s.toml"), dir.path()) {
        Err(e @ ScenarioError::Track { .. }) => assert!(e.to_string().contains("missing.csv"), "{e}"),
        other => panic!("expected a track error, got {other:?}"),
    }
}

#[test]
fn missing_scenario_file_is_reported() {
    let e = Scenario::load(Path::new("/nonexistent/s.toml")).unwrap_err().to_string();
    assert!(e.contains("/nonexistent/s.toml"), "{e}");
}

#[test]
fn run_directory_holds_every_output() {
    let dir = tempfile::tempdir().unwrap();
    let s = Scenario::parse(&short_example(), Path::new("e")).unwrap();
    let m = s.build(Path::new("e"), Path::new(".")).unwrap();
    let mut p = LookAheadPlanner::new(m.planner).unwrap();
    let r = predeploy::run(&m, &mut p, &|_| {}).unwrap();
    let out = write_run(RunDir::create(dir.path().join("run"), false).unwrap(), &m, serde_json::json!({}), &r).unwrap();
    for f in [
        "cna_waypoints.csv",
        "cna_waypoints.moos",
        "timeseries.csv",
        "auv_timeseries.csv",
        "summary.json",
        "manifest.json",
        "tracks.svg",
        "error.svg",
        "distance.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let moos = std::fs::read_to_string(out.join("cna_waypoints.moos")).unwrap();
    let points = moos.lines().find_map(|l| l.strip_prefix("points = ")).unwrap();
    assert_eq!(points.split(':').count(), 60);
    let first: Vec<f64> = points.split(':').next().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    assert!((first[0] - r.steps[1].cna.pos.x).abs() < 0.06 && (first[1] - r.steps[1].cna.pos.y).abs() < 0.06);
    let wp = std::fs::read_to_string(out.join("cna_waypoints.csv")).unwrap();
    assert!(wp.starts_with("step,t,x,y,depth,heading_compass_deg"));
    assert!(RunDir::create(&out, false).is_err(), "an existing run is not overwritten without force");
}

#[test]
fn stray_keys_in_tagged_tables_are_rejected() {
    let e = err_of(&EXAMPLE.replace("cna = { kind = \"asc\" }", "cna = { kind = \"asc\", pitch_options = 3 }"));
    assert!(e.contains("unknown field") && e.contains("pitch_options"), "{e}");
    let e = err_of(&EXAMPLE.replace(
        "penalty = { case = \"8\" }",
        "penalty = { primary = { kind = \"none\" }, look_ahead = { kind = \"doubling\", factor = 3 } }",
    ));
    assert!(e.contains("unknown field") && e.contains("factor"), "{e}");
}

/// A file in the old form (`[planner]` with `[planner.motion]`) is refused with every moved key
/// and its new place in one message.
#[test]
fn an_old_form_file_is_refused_listing_every_moved_key() {
    let old =
        "[cna]\nx = 0.0\ny = 0.0\nheading_compass_deg = 90.0\n[planner]\nlook_ahead = 1\npenalty = { case = \"1\" }\n\
               [planner.motion]\nspeed = 2.0\ntau = 10.0\nheading_options = 3\ncna = { kind = \"asc\" }\n\
               [[auv]]\nname = \"a\"\ntrack_csv = \"t.csv\"\n";
    let e = err_of(old);
    for line in [
        "planner.look_ahead -> policy.planner.tree.look_ahead",
        "planner.penalty -> policy.planner.penalty",
        "planner.motion.speed -> platform.speed",
        "planner.motion.tau -> platform.tau",
        "planner.motion.heading_options -> policy.planner.tree.heading_options",
        "planner.motion.cna -> platform.cna",
    ] {
        assert!(e.contains(line), "{line}: {e}");
    }
    assert!(e.contains("6 moved key(s)"), "{e}");
}
