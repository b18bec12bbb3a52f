//! Behaviour of the HBL world: determinism across thread counts, common random numbers across
//! configurations, robustness of the filters under hostile conditions, and the simulator →
//! log → post-processing → RTS pipeline end to end.

use coopnav_core::run_seed;
use coopnav_nav::cycle::{Configuration, Cycle, SlotContent};
use coopnav_nav::post::{postprocess, read_log, write_log, PostConfig};
use coopnav_nav::smoother::SmootherKind;
use coopnav_sim::hbl::{monte_carlo, run, Scenario};

#[test]
fn monte_carlo_is_identical_on_one_and_two_threads() {
    let sc = Scenario::table5(Configuration::HblOne);
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let one = pool(1).install(|| monte_carlo(&sc, 12, 7, &|_| {}).unwrap());
    let two = pool(2).install(|| monte_carlo(&sc, 12, 7, &|_| {}).unwrap());
    assert_eq!(one.runs, two.runs);
    assert_eq!(one.summary, two.summary);
}

#[test]
fn configurations_share_their_noise() {
    let seed = run_seed(3, 0);
    let start = |c| {
        let sc = Scenario::table5(c);
        let (_, tr) = run(&sc, &sc.resolved_cycle().unwrap(), seed, true);
        let r = tr.unwrap().rows[0];
        (r.auv_true, r.ship_true)
    };
    assert_eq!(start(Configuration::Msbl), start(Configuration::HblTwo));
    assert_eq!(start(Configuration::HblOne), start(Configuration::HblTwo));
}

fn assert_healthy(sc: &Scenario, what: &str) {
    sc.validate().unwrap();
    let cycle = sc.resolved_cycle().unwrap();
    for i in 0..6 {
        let (m, tr) = run(sc, &cycle, run_seed(11, i), true);
        assert!(m.healthy, "{what}: run {i} lost positive definiteness or went non-finite");
        for r in tr.unwrap().rows {
            assert!(r.auv_est.iter().chain(&r.auv_sd).all(|v| v.is_finite()), "{what}: run {i} at t = {}", r.t);
        }
    }
}

#[test]
fn robust_to_dropped_messages() {
    let mut sc = Scenario::default();
    sc.acoustic.p_drop = 0.8;
    sc.acoustic.p_slightly_long = 0.1;
    sc.acoustic.p_slightly_short = 0.05;
    sc.acoustic.p_outlier = 0.05;
    assert_healthy(&sc, "80% drops");
}

#[test]
fn robust_to_outliers() {
    let mut sc = Scenario::default();
    sc.acoustic.p_outlier = 0.5;
    sc.acoustic.p_slightly_long = 0.2;
    sc.acoustic.p_slightly_short = 0.2;
    sc.acoustic.p_drop = 0.1;
    assert_healthy(&sc, "50% 5-10 m outliers");
}

#[test]
fn robust_to_minute_long_gaps() {
    let mut sc = Scenario::default();
    let mut slots = vec![SlotContent::ShipEast, SlotContent::BuoyNorth, SlotContent::ShipNorth];
    slots.extend(std::iter::repeat(SlotContent::Silent).take(45)); // 90 s of silence per cycle
    sc.custom_cycle = Some(Cycle { name: "gappy".into(), slot_seconds: 2.0, slots });
    assert_healthy(&sc, "90 s gaps");
}

#[test]
fn robust_to_clock_drift_and_sound_speed_bias() {
    let mut sc = Scenario::default();
    sc.acoustic.clock_drift = true;
    // Exaggerated: ~0.1 s/h, i.e. metres of range error within the run.
    sc.acoustic.clock_drift_mean_us_h = 1e5;
    sc.acoustic.filter_sound_speed_bias = 20.0;
    assert_healthy(&sc, "clock drift");
}

#[test]
fn robust_with_the_buoy_on_the_path_and_the_ship_overhead() {
    // The AUV passes directly under the buoy (and, at the crossing, within metres of the ship).
    let mut sc = Scenario::default();
    sc.buoy.fixed = Some([20.0, 0.0]);
    sc.buoy.drift = coopnav_sim::hbl::config::Drift::None;
    sc.init.position_sd = 0.0;
    assert_healthy(&sc, "buoy overhead");
}

#[test]
fn simulated_logs_postprocess_end_to_end() {
    let sc = Scenario::table5(Configuration::HblTwo);
    let cycle = sc.resolved_cycle().unwrap();
    let (mut filt, mut smooth, mut nees, mut n) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..8 {
        let (_, tr) = run(&sc, &cycle, run_seed(21, i), true);
        let mut csv = Vec::new();
        write_log(&mut csv, &tr.unwrap().log, None).unwrap();
        let entries = read_log(csv.as_slice(), None).unwrap();
        let r = postprocess(&entries, &PostConfig::default()).unwrap();
        let s = r.summary;
        // The unscented backward pass over the same forward run: with 0.1 s steps the dead
        // reckoning is nearly linear, so it must land on the EKF-RTS answer (thesis: "similar").
        let u = postprocess(&entries, &PostConfig { smoother: SmootherKind::Unscented, ..PostConfig::default() })
            .unwrap()
            .summary;
        let (se, su) = (s.mean_smoothed_error.unwrap(), u.mean_smoothed_error.unwrap());
        assert!((se - su).abs() <= 0.01 * se, "run {i}: EKF-RTS {se} vs URTS {su}");
        assert_eq!(u.mean_filtered_error, s.mean_filtered_error);
        assert!(s.ranges_applied > 20, "{s:?}");
        assert!(r.samples.iter().all(|p| p.smoothed.iter().chain(&p.smoothed_sd).all(|v| v.is_finite())));
        filt += s.mean_filtered_error.unwrap();
        smooth += s.mean_smoothed_error.unwrap();
        nees += s.mean_smoothed_nees.unwrap();
        n += 1.0;
    }
    let (filt, smooth, nees) = (filt / n, smooth / n, nees / n);
    assert!(smooth <= filt, "smoothed {smooth} vs filtered {filt}");
    // Consistency: a 2-D NEES averages 2 for a consistent filter; allow a wide band since the
    // transponder positions carry unmodelled DGPS error.
    assert!((0.3..8.0).contains(&nees), "mean smoothed NEES {nees} (filtered error {filt}, smoothed {smooth})");
}
