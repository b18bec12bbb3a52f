//! The world's physics does not depend on the step the engine takes: the default mission flown at
//! several `dt` gives the same true trajectories (without noise) and the same error statistics
//! (within the Monte Carlo spread).

use coopnav_sim::engine::Faults;
use coopnav_sim::observe::metrics::{run, run_traced};
use coopnav_sim::policy::PolicySpec;
use coopnav_sim::scenario::Scenario;

/// The embedded default mission at step `dt`.
fn at_step(dt: f64) -> Scenario {
    let mut sc = Scenario::example();
    sc.dt = dt;
    sc
}

/// Every survey AUV's true horizontal position at every whole minute of one run.
fn truth_by_minute(sc: &Scenario, policy: &str) -> Vec<(f64, usize, f64, f64)> {
    let mut p = PolicySpec::new(policy, sc).unwrap().build(sc).unwrap();
    let r = run_traced(sc, &mut p, 1, &Faults::default());
    let rows = r.trace.unwrap().rows;
    rows.iter()
        .filter(|row| (row.t / 60.0 - (row.t / 60.0).round()).abs() < 1e-6)
        .map(|row| (row.t.round(), row.auv, row.true_x, row.true_y))
        .collect()
}

/// With perfect sensors and a current, the vehicles fly the same tracks at every step: the truth
/// moves `dt` of the vehicle model and of the current per engine step.
#[test]
fn noise_free_truth_is_the_same_at_every_step() {
    let quiet = |dt: f64| {
        let mut sc = at_step(dt);
        let s = &mut sc.sensors;
        (s.speed_sd, s.compass_bias_step_deg, s.compass_white_deg, s.yaw_rate_white_deg_s) = (0.0, 0.0, 0.0, 0.0);
        sc.fleet.init_position_sd = 0.0;
        sc.fleet.current = (0.05, -0.03);
        sc
    };
    let reference = truth_by_minute(&quiet(0.1), "none");
    assert!(reference.len() > 100, "{} samples", reference.len());
    for dt in [0.05, 0.2, 0.5, 1.0] {
        let other = truth_by_minute(&quiet(dt), "none");
        assert_eq!(other.len(), reference.len(), "dt = {dt}");
        let worst = reference
            .iter()
            .zip(&other)
            .map(|(a, b)| {
                assert_eq!((a.0, a.1), (b.0, b.1), "dt = {dt}");
                (a.2 - b.2).hypot(a.3 - b.3)
            })
            .fold(0.0, f64::max);
        // The IVER2 controller is discrete: at a lane's turn a coarser step captures the waypoint
        // up to one step's travel later and turns one step of yaw later, so the tracks part by
        // an amount that grows with the step (about 13 m per second of step at the lanes' turns),
        // never with the mission's length.
        let bound = 0.5 + 14.0 * dt;
        assert!(worst < bound, "dt = {dt}: the truth departs {worst:.2} m from dt = 0.1 (allowed {bound:.2})");
    }
}

/// Mean and standard error of the fleet's mean true error over `runs` seeds.
fn fleet_error(sc: &Scenario, policy: &str, runs: u64) -> (f64, f64) {
    let means: Vec<f64> = (0..runs)
        .map(|seed| {
            let mut p = PolicySpec::new(policy, sc).unwrap().build(sc).unwrap();
            run(sc, &mut p, 100 + seed, &Faults::default(), &mut ()).fleet.error.mean
        })
        .collect();
    let n = means.len() as f64;
    let mean = means.iter().sum::<f64>() / n;
    let var = means.iter().map(|m| (m - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Dead reckoning and a CNA give the same true error statistics at every step the validator
/// accepts, within the Monte Carlo spread (the runs at different steps draw different noise, so
/// the comparison is unpaired: four standard errors of the difference).
#[test]
fn error_statistics_agree_at_every_step() {
    for policy in ["none", "centroid"] {
        let (m0, se0) = fleet_error(&at_step(0.1), policy, 16);
        for dt in [0.05, 0.2, 0.5] {
            let (m, se) = fleet_error(&at_step(dt), policy, 16);
            let bound = 4.0 * se0.hypot(se);
            assert!(
                (m - m0).abs() <= bound,
                "{policy}, dt = {dt}: mean error {m:.2} m against {m0:.2} m at dt = 0.1 (allowed ± {bound:.2})"
            );
        }
    }
}

/// A file may restate the step in the vehicle's table, never name another one.
#[test]
fn a_vehicle_step_other_than_dt_is_refused() {
    let text = coopnav_sim::scenario::EXAMPLE.replace("\ndt = 0.1", "\ndt = 0.2");
    let path = std::path::Path::new("s.toml");
    assert!(Scenario::parse(&text, path).is_ok());
    let with = |step: &str| format!("{text}\n[fleet.vehicle]\ntimestep = {step}\n");
    // The table goes at the end of the file: it must follow [fleet]'s keys.
    let restated = Scenario::parse(&with("0.2"), path);
    assert!(restated.is_ok(), "{:?}", restated.err());
    let e = Scenario::parse(&with("0.05"), path).unwrap_err().to_string();
    assert!(e.contains("fleet.vehicle.timestep") && e.contains("dt (0.2 s)"), "{e}");
}
