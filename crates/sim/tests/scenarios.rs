//! Every file of the scenario library (`scenarios/*.toml` at the repository root) loads,
//! validates and runs, reduced to a short mission with a shallow planner.

use coopnav_sim::closed_loop::{run, Faults, PolicySpec, Scenario};
use std::path::PathBuf;

fn library() -> Vec<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    files
}

/// Whether the file's transmission loss runs the real BELLHOP (`[comms] tl.kind = "bellhop…"`).
fn uses_bellhop(file: &PathBuf) -> bool {
    let value: toml::Value = toml::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
    value
        .get("comms")
        .and_then(|c| c.get("tl"))
        .and_then(|t| t.get("kind"))
        .and_then(|k| k.as_str())
        .is_some_and(|k| k.starts_with("bellhop"))
}

/// Runs `file` for 600 s with a shallow planner; checks the run is healthy and every AUV filtered.
fn runs_reduced(file: &PathBuf) -> coopnav_sim::closed_loop::RunResult {
    let mut sc = Scenario::load(file).unwrap_or_else(|e| panic!("{e}"));
    sc.duration_s = sc.duration_s.min(600.0);
    sc.planner.look_ahead = sc.planner.look_ahead.min(3);
    sc.planner.deadline = coopnav_plan::Deadline::None;
    let mut policy = PolicySpec::new("planner", &sc).unwrap().build(&sc).unwrap();
    let r = run(&sc, &mut policy, sc.seed, &Faults::default(), &mut ());
    let name = file.display();
    assert!(r.fleet.healthy && r.fleet.error.mean.is_finite(), "{name}");
    assert_eq!(r.auvs.len(), sc.fleet.n_auvs, "{name}");
    r
}

/// Every AUV applied a range and its status reached the CNA: the example's geometry serves the
/// whole fleet under its own transmission loss.
fn assert_every_auv_served(file: &PathBuf, r: &coopnav_sim::closed_loop::RunResult) {
    assert!(r.auvs.iter().all(|a| a.ranges_applied > 0 && a.uplink.received > 0), "{file:?}: {:?}", r.auvs);
}

#[test]
fn every_scenario_in_the_library_loads_and_runs_reduced() {
    let files = library();
    assert!(files.len() >= 3, "{files:?}");
    let names: Vec<String> = files.iter().map(|f| f.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert!(names.contains(&"default.toml".to_string()) && names.contains(&"full-stack.toml".to_string()));
    for file in files.iter().filter(|f| !uses_bellhop(f)) {
        assert_every_auv_served(file, &runs_reduced(file));
    }
}

#[test]
#[cfg_attr(not(bellhop_installed), ignore = "BELLHOP is not installed: run scripts/install-bellhop.sh")]
fn every_bellhop_scenario_in_the_library_loads_and_runs_reduced() {
    let files: Vec<PathBuf> = library().into_iter().filter(uses_bellhop).collect();
    assert!(!files.is_empty(), "the full-stack example uses the BELLHOP grid");
    for file in &files {
        let r = runs_reduced(file);
        assert_every_auv_served(file, &r);
        assert!(r.auvs.iter().any(|a| a.downlink.received < a.downlink.sent), "{file:?}: BELLHOP loses packets");
    }
}

#[test]
fn the_embedded_default_mission_is_the_library_file() {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/default.toml");
    assert_eq!(std::fs::read_to_string(file).unwrap(), coopnav_sim::closed_loop::EXAMPLE);
}
