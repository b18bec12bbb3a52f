//! Behaviour of the closed loop: determinism over thread counts, dead reckoning against a CNA,
//! graceful degradation when packets are lost, and the run directory.

use crate::batch::mc::{monte_carlo, monte_carlo_grid, Comparison};
use crate::engine::Faults;
use crate::observe::metrics::{run, run_traced, RunResult};
use crate::output::run::{write_run, PLOTS};
use crate::output::RunDir;
use crate::policy::{PolicySpec, POLICY_NAMES};
use crate::scenario::world as scenario;
use crate::scenario::Scenario;

/// A short mission for tests.
fn short(n: usize, duration: f64) -> Scenario {
    let mut sc = Scenario::example().with_auvs(n);
    sc.duration_s = duration;
    sc.policy.planner.tree.look_ahead = Some(3);
    sc.policy.planner.deadline = coopnav_plan::Deadline::None;
    sc
}

fn one_run(sc: &Scenario, policy: &str, seed: u64, record: bool, faults: &Faults) -> RunResult {
    let mut p = PolicySpec::new(policy, sc).unwrap().build(sc).unwrap();
    if record {
        run_traced(sc, &mut p, seed, faults)
    } else {
        run(sc, &mut p, seed, faults, &mut ())
    }
}

#[test]
fn monte_carlo_is_identical_on_one_and_two_threads() {
    let sc = short(2, 600.0);
    let policies = vec!["planner".to_string(), "centroid".to_string()];
    let go = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| serde_json::to_string(&monte_carlo(&sc, &policies, 3, &|_| {}).unwrap()).unwrap())
    };
    let (a, b) = (go(1), go(2));
    assert_eq!(a, b);
    assert!(a.contains("\"paired\""));
}

/// The cells of a grid share one pool of runs, the larger fleet's first: each comparison is
/// still the one its cell gives alone, on any thread count.
#[test]
fn a_grid_gives_each_cell_its_own_comparison() {
    let cells = [short(1, 300.0), short(3, 300.0)];
    let policies = vec!["planner".to_string(), "centroid".to_string()];
    let json = |c: &Comparison| serde_json::to_string(c).unwrap();
    let alone: Vec<String> = cells.iter().map(|sc| json(&monte_carlo(sc, &policies, 3, &|_| {}).unwrap())).collect();
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let grid = pool.install(|| monte_carlo_grid(&cells, &policies, 3, &|_| {}).unwrap());
        assert_eq!(grid.iter().map(json).collect::<Vec<_>>(), alone, "{threads} thread(s)");
    }
    assert!(monte_carlo_grid(&cells, &policies, 0, &|_| {}).unwrap().iter().all(|c| c.policies.is_empty()));
}

/// Mean of the errors of AUV 0 over [from, to).
fn window(r: &RunResult, from: f64, to: f64) -> f64 {
    let rows: Vec<f64> = r
        .trace
        .as_ref()
        .unwrap()
        .rows
        .iter()
        .filter(|x| x.auv == 0 && x.t >= from && x.t < to)
        .map(|x| x.error)
        .collect();
    rows.iter().sum::<f64>() / rows.len() as f64
}

#[test]
fn dead_reckoning_drifts_and_a_cna_bounds_the_error() {
    let sc = short(1, 2400.0);
    let dr = one_run(&sc, "none", 7, true, &Faults::default());
    let aided = one_run(&sc, "planner", 7, true, &Faults::default());
    assert_eq!(dr.auvs[0].downlink.sent, 0, "no CNA, no ranges");
    // Dead reckoning: the error keeps growing.
    let (early, late) = (window(&dr, 300.0, 900.0), window(&dr, 1800.0, 2400.0));
    assert!(late > 2.0 * early, "DR error should grow: {early:.1} → {late:.1}");
    // With the CNA: bounded, and far below dead reckoning at the end.
    let (mid, end) = (window(&aided, 900.0, 1500.0), window(&aided, 1800.0, 2400.0));
    assert!(end < 2.0 * mid + 5.0, "aided error should not keep growing: {mid:.1} → {end:.1}");
    assert!(end < late / 3.0, "aided {end:.1} vs DR {late:.1}");
    assert!(aided.auvs[0].ranges_applied > 0);
}

#[test]
fn lost_packets_degrade_gracefully() {
    let sc = short(2, 900.0);
    // AUV 1 goes silent after 5 minutes: its filter dead-reckons, the planner keeps predicting it.
    let faults = Faults { silent_auvs: vec![1], silent_from_s: 300.0 };
    let r = one_run(&sc, "planner", 3, true, &faults);
    assert!(r.fleet.healthy);
    let trace = r.trace.as_ref().unwrap();
    assert!(trace
        .rows
        .iter()
        .all(|x| x.error.is_finite() && x.est_x.is_finite() && x.modelled.is_none_or(f64::is_finite)));
    let p = r.planner.as_ref().unwrap();
    assert_eq!(p.failures, 0);
    assert_eq!(p.decisions, 30);
    assert!(p.min_levels_searched >= 1);
    let late_received = trace.comms.iter().filter(|e| e.auv == 1 && e.t >= 300.0 && e.received).count();
    assert_eq!(late_received, 0);
    // Every packet of every AUV lost from the start: nothing known, the CNA holds, no panic.
    let all = Faults { silent_auvs: vec![0, 1], silent_from_s: 0.0 };
    let r = one_run(&sc, "planner", 3, false, &all);
    assert!(r.fleet.healthy && r.fleet.error.mean.is_finite());
    let p = r.planner.unwrap();
    assert_eq!(p.waiting, p.decisions);
    assert!(r.auvs.iter().all(|a| a.downlink.received == 0 && a.uplink.received == 0));
}

#[test]
fn run_directory_holds_data_plots_and_a_report_referencing_every_plot() {
    let sc = short(2, 300.0);
    let r = one_run(&sc, "planner", 1, true, &Faults::default());
    let tmp = tempfile::tempdir().unwrap();
    let dir = RunDir::create_fresh(tmp.path(), "sim").unwrap();
    let out = write_run(dir, &sc, &r, "test").unwrap();
    for f in ["timeseries.csv", "comms.csv", "summary.json", "manifest.json", "report.html"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    for (file, _) in PLOTS {
        let svg = std::fs::read_to_string(out.join(file)).unwrap();
        assert!(svg.contains("<svg"), "{file}");
        assert!(html.contains(&format!("id=\"{file}\"")), "report lacks {file}");
    }
    assert!(
        !html.contains("<script") && !html.contains("src=\"http"),
        "self-contained: no scripts, no fetched resources"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["auvs"].as_array().unwrap().len(), 2);
    // Recording changes nothing in the results.
    let plain = one_run(&sc, "planner", 1, false, &Faults::default());
    assert_eq!(serde_json::to_string(&plain).unwrap(), serde_json::to_string(&r).unwrap());
}

#[test]
fn unknown_policy_names_the_allowed_ones() {
    let e = PolicySpec::new("circle", &Scenario::example()).unwrap_err().to_string();
    assert!(e.contains("circle") && e.contains("centroid") && e.contains("planner"), "{e}");
}

#[test]
fn every_policy_runs() {
    let sc = short(2, 240.0);
    for name in POLICY_NAMES {
        let r = one_run(&sc, name, 2, false, &Faults::default());
        assert!(r.fleet.healthy, "{name}");
        assert_eq!(r.policy, name);
    }
}

#[test]
fn altitude_keeping_follows_the_shelf() {
    let mut sc = short(1, 900.0);
    // Lanes run north; the shelf deepens eastwards, so turn the lanes east to cross it.
    sc.fleet.lane_heading_compass_deg = 90.0;
    sc.fleet.shelf =
        Some(coopnav_core::Shelf { shallow: 30.0, deep: 90.0, x_shallow: 0.0, x_deep: 800.0, ..Default::default() });
    sc.fleet.depth = coopnav_core::DepthTarget::Altitude { altitude: 15.0 };
    sc.validate(std::path::Path::new("t")).unwrap();
    let r = one_run(&sc, "planner", 4, true, &Faults::default());
    let z: Vec<f64> = r.trace.unwrap().rows.iter().map(|x| x.true_z).collect();
    let (lo, hi) = z.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, &v| (a.0.min(v), a.1.max(v)));
    assert!(lo > 10.0 && hi - lo > 30.0, "depth should follow the sloping bottom: {lo:.1}..{hi:.1}");
    assert!(r.fleet.healthy);
}

#[test]
fn status_rates_follow_the_fixed_rate_or_the_adaptive_selector() {
    let mut sc = short(2, 900.0);
    let fixed = one_run(&sc, "planner", 5, false, &Faults::default());
    for a in &fixed.auvs {
        assert_eq!(a.uplink.sent_by_rate[0], a.uplink.sent, "fixed rate 0 only");
        assert_eq!(a.downlink.sent_by_rate[0], a.downlink.sent);
    }
    sc.comms.status_adaptive = Some(coopnav_acomms::selector::AdaptiveConfig::default());
    sc.validate(std::path::Path::new("t")).unwrap();
    let adaptive = one_run(&sc, "planner", 5, false, &Faults::default());
    for a in &adaptive.auvs {
        let up = &a.uplink;
        // Thesis Table 8 targets enable rates 1 and 4 only (status bins: rate 1).
        assert_eq!(up.sent_by_rate[0] + up.sent_by_rate[5], 0, "{up:?}");
        assert!(up.sent_by_rate[1] + up.sent_by_rate[4] == up.sent && up.sent > 0, "{up:?}");
        assert!(up.received > 0 && up.received <= up.sent);
    }
    assert_eq!(adaptive.planner.unwrap().failures, 0);
}

#[test]
fn an_auv_cna_plans_with_pitch_and_broadcasts_its_own_estimate() {
    let mut sc = short(2, 1200.0);
    sc.policy.planner.tree.look_ahead = Some(2);
    sc.cna.auv =
        Some(scenario::AuvCna { pitch_options: 3, depth: scenario::CruiseDepth::Metres(10.0), min_depth_m: 0.0 });
    sc.cna.navigation =
        crate::models::cna_navigation::CnaNavigation::DeadReckoning(crate::models::cna_navigation::DeadReckoning {
            diffusion_m2_s: 0.01,
            surfacing: None,
        });
    sc.validate(std::path::Path::new("t")).unwrap();
    let r = one_run(&sc, "planner", 6, true, &Faults::default());
    let dr = one_run(&sc, "none", 6, false, &Faults::default());
    assert!(r.fleet.healthy);
    let p = r.planner.as_ref().unwrap();
    assert_eq!((p.failures, p.min_levels_searched), (0, 3));
    assert!(r.auvs.iter().all(|a| a.ranges_applied > 0));
    assert!(r.fleet.error.mean < dr.fleet.error.mean / 2.0, "{} vs DR {}", r.fleet.error.mean, dr.fleet.error.mean);
}

/// Filters that expect the channel's outliers (`filter.range_outliers`, on in the sloping file):
/// over the same runs (same draws), ranges weighted by their inlier probability leave a smaller
/// error than ranges all taken as Gaussian, and so do the PDA update's.
#[test]
fn filters_expecting_the_channels_outliers_navigate_better_on_the_same_draws() {
    let file = include_str!("../../../../scenarios/sloping-auv-cna.toml");
    let expecting = toml::from_str::<Scenario>(file).unwrap().with_auvs(1);
    assert_eq!(expecting.filter.params.range_outliers, Some(coopnav_nav::RangeOutliers::GILL));
    let mut gaussian = expecting.clone();
    gaussian.filter.params.range_outliers = None;
    let mut pda = expecting.clone();
    pda.filter.params.range_outliers = Some(coopnav_nav::RangeOutliers {
        update: coopnav_nav::OutlierUpdate::Pda,
        ..coopnav_nav::RangeOutliers::GILL
    });
    let mean_error = |sc: &Scenario| {
        let runs: Vec<f64> = (0..12)
            .map(|k| one_run(sc, "centroid-standoff", 70 + k, false, &Faults::default()).fleet.error.mean)
            .collect();
        runs.iter().sum::<f64>() / runs.len() as f64
    };
    let (weighted, with_spread, without) = (mean_error(&expecting), mean_error(&pda), mean_error(&gaussian));
    assert!(weighted < without - 0.1, "weighted {weighted:.2} m, all Gaussian {without:.2} m");
    assert!(with_spread < without - 0.1, "PDA {with_spread:.2} m, all Gaussian {without:.2} m");
}

#[test]
fn a_cast_cruise_depth_follows_the_fleets_depths_and_reads_back() {
    let file = include_str!("../../../../scenarios/sloping-auv-cna.toml");
    let sc: Scenario = toml::from_str(file).unwrap();
    assert_eq!(sc.cna.auv.as_ref().map(|a| a.depth), Some(scenario::CruiseDepth::Cast));
    // One AUV over the shelf's shallow end (20–38 m) wants the CNA below the warm surface layer;
    // eight, most of them at 80 m in the slow deep water, want it in the fastest water on top.
    let (one, eight) = (sc.with_auvs(1).cna_cruise_depth(), sc.with_auvs(8).cna_cruise_depth());
    assert!((5.0..=25.0).contains(&one) && eight < one, "1 AUV: {one} m, 8 AUVs: {eight} m");
    assert_eq!(crate::scenario::start::cna_start(&sc.with_auvs(1)).pos.z, one);
    let again: Scenario = toml::from_str(&toml::to_string(&sc).unwrap()).unwrap();
    assert_eq!(again, sc);
    let mut fixed = sc.clone();
    fixed.cna.auv.as_mut().unwrap().depth = scenario::CruiseDepth::Metres(12.5);
    assert!(toml::to_string(&fixed).unwrap().contains("depth = 12.5"));
    assert_eq!(fixed.cna_cruise_depth(), 12.5);
    let bad = file.replace("depth = \"cast\"", "depth = \"deep\"");
    let err = toml::from_str::<Scenario>(&bad).unwrap_err().to_string();
    assert!(err.contains("`deep`: expected a depth in metres or \"cast\""), "{err}");
}

/// A drifting buoy draws its drift from its own stream: a Monte Carlo batch is bit-identical on
/// one and two threads, and differs from the batch without the buoy (its ranges are in it).
#[test]
fn a_drifting_buoys_batch_is_identical_on_one_and_two_threads() {
    let mut alone = Scenario::example().with_auvs(2);
    (alone.duration_s, alone.policy.planner.tree.look_ahead, alone.policy.planner.deadline) =
        (600.0, Some(3), coopnav_plan::Deadline::None);
    let mut sc = alone.clone();
    sc.buoys = vec![toml::from_str(
        "x = 900.0\ny = 300.0\ndrift = { kind = \"lake\", mean_m_s = 0.056, sd_m_s = 0.039, circular_fraction = 0.5, \
         circular_radius_m = 200.0 }",
    )
    .unwrap()];
    sc.validate(std::path::Path::new("t")).unwrap();
    let policies = vec!["planner".to_string()];
    let go = |sc: &Scenario, threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            serde_json::to_string(&crate::batch::mc::monte_carlo(sc, &policies, 3, &|_| {}).unwrap()).unwrap()
        })
    };
    let (a, b) = (go(&sc, 1), go(&sc, 2));
    assert_eq!(a, b);
    assert_ne!(a, go(&alone, 2));
}
