//! Quiet stretches change nothing: a run with them, on one thread or with the fleet split over
//! two, makes the same observer calls with the same numbers, and ends with the same metrics, as
//! the loop that runs every step's phases one by one.

use super::*;
use crate::closed_loop::PolicySpec;
use crate::models::finish::Finish;

/// Every observer call in order, with its numbers to the last bit (`{:?}` prints an f64 so that
/// it parses back to the same bits).
#[derive(Default)]
struct Calls(Vec<String>);

impl Calls {
    fn push(&mut self, call: &str, what: impl std::fmt::Debug) {
        self.0.push(format!("{call} {what:?}"));
    }
}

impl Observer for Calls {
    fn on_decision(&mut self, d: &Decision) {
        self.push("decision", d);
    }
    fn on_sample(&mut self, t: f64, cna: Vec3, rows: &[TraceRow]) {
        self.push("sample", (t, cna, rows));
    }
    fn on_ships(&mut self, t: f64, ships: &[Vec3]) {
        self.push("ships", (t, ships));
    }
    fn on_buoys(&mut self, t: f64, buoys: &[BuoySample]) {
        self.push("buoys", (t, buoys));
    }
    fn on_ship_samples(&mut self, t: f64, ships: &[crate::engine::observe::ShipSample]) {
        self.push("ship samples", (t, ships));
    }
    fn on_filter_start(&mut self, start: &FilterStart) {
        self.push("filter start", start);
    }
    fn on_dead_reckoning(&mut self, dr: &DeadReckoning) {
        self.push("dead reckoning", dr);
    }
    fn on_ship_pose(&mut self, pose: &ShipPose) {
        self.push("ship pose", pose);
    }
    fn on_buoy_fix(&mut self, fix: &BuoyFix) {
        self.push("buoy fix", fix);
    }
    fn on_range(&mut self, range: &RangeHeard) {
        self.push("range", range);
    }
    fn on_status_choice(&mut self, choice: &StatusChoice) {
        self.push("status choice", choice);
    }
    fn on_status_sent(&mut self, sent: &StatusSent) {
        self.push("status sent", sent);
    }
    fn on_status_frames(&mut self, frames: &StatusFrames) {
        self.push("status frames", frames);
    }
    fn on_shadow(&mut self, sample: &ShadowSample) {
        self.push("shadow", sample);
    }
    fn on_packet(&mut self, event: &CommsEvent) {
        self.push("packet", event);
    }
}

/// The run's metrics as JSON and its observer calls.
type Outcome = (String, Vec<String>);

fn with_stretches(sc: &Scenario, policy: &str, seed: u64) -> Outcome {
    let mut p = PolicySpec::new(policy, sc).unwrap().build(sc).unwrap();
    let mut calls = Calls::default();
    let r = run(sc, &mut p, seed, &Faults::default(), &mut calls);
    (serde_json::to_string(&r).unwrap(), calls.0)
}

fn step_by_step(sc: &Scenario, policy: &str, seed: u64) -> Outcome {
    let mut p = PolicySpec::new(policy, sc).unwrap().build(sc).unwrap();
    let mut calls = Calls::default();
    let faults = Faults::default();
    let mut engine = Engine::new(sc, &mut p, seed, &faults, None);
    engine.report_start(&mut calls);
    for step in 0..engine.steps() {
        engine.step(step, &mut calls);
    }
    (serde_json::to_string(&engine.finish(seed, 0.0)).unwrap(), calls.0)
}

fn on_two_threads(sc: &Scenario, policy: &str, seed: u64) -> Outcome {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    pool.install(|| with_stretches(sc, policy, seed))
}

fn assert_same(sc: &Scenario, policy: &str, seed: u64) {
    let reference = step_by_step(sc, policy, seed);
    let (metrics, calls) = &reference;
    let count = |call: &str| calls.iter().filter(|c| c.starts_with(call)).count();
    assert!(count("range") > 10, "the AUVs hear ranges");
    let filter_steps = sc.duration_s / sc.dt / sc.filter.rate.steps(sc.dt) as f64 * sc.fleet.n_auvs as f64;
    assert_eq!(count("dead reckoning") as f64, filter_steps.round(), "every filter step of every AUV");
    for (how, outcome) in [("one thread", with_stretches(sc, policy, seed)), ("two", on_two_threads(sc, policy, seed))]
    {
        assert_eq!(&outcome.0, metrics, "metrics, {how}");
        let first_difference = outcome.1.iter().zip(calls).position(|(a, b)| a != b);
        assert_eq!(first_difference, None, "observer calls, {how}");
        assert_eq!(outcome.1.len(), calls.len(), "observer calls, {how}");
    }
}

/// Three AUVs that surface at the end (GPS fixes once a second), a drifting buoy's broadcasts
/// among the CNA's and the statuses.
#[test]
fn a_fleet_with_a_buoy_runs_the_same_with_quiet_stretches() {
    let mut sc = Scenario::example().with_auvs(3);
    (sc.duration_s, sc.fleet.lanes, sc.fleet.lane_length) = (900.0, 2, 300.0);
    sc.fleet.finish = Finish::Surface { ascent_rate_m_s: 0.5, gps_sd_m: 3.0 };
    sc.buoys = vec![toml::from_str(
        "x = 900.0\ny = 300.0\ndrift = { kind = \"lake\", mean_m_s = 0.056, sd_m_s = 0.039, circular_fraction = 0.5, \
         circular_radius_m = 200.0 }",
    )
    .unwrap()];
    (sc.planner.look_ahead, sc.planner.deadline) = (3, coopnav_plan::Deadline::None);
    sc.validate(std::path::Path::new("t")).unwrap();
    assert_same(&sc, "planner", 4);
}

/// Gill's ship on its track and a buoy sending mini-packets (the ship steps in the stretch's
/// replay; its poses and samples come in order).
#[test]
fn a_ship_and_a_buoys_mini_packets_run_the_same_with_quiet_stretches() {
    let text = include_str!("../../../../scenarios/gill-table5-hbl-two.toml");
    let mut sc = Scenario::parse(text, std::path::Path::new("gill-table5-hbl-two.toml")).unwrap();
    sc.duration_s = 600.0;
    assert_same(&sc, "none", 2);
}
