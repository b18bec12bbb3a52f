//! The AUV filter under hostile measurement streams: dropped messages, 5–10 m outliers,
//! minute-long gaps, a transponder passing directly overhead, and receiver clock drift.
//! The state must stay finite and the covariance positive definite at every step.

use coopnav_core::{SeedStream, Vec3};
use coopnav_nav::ekf::is_positive_definite;
use coopnav_nav::{AuvEkf, AuvParams, Gate, RangeMeasurement, UpdateOutcome};
use rand::Rng;

#[derive(Clone, Copy)]
struct Hostility {
    p_drop: f64,
    p_outlier: f64,
    /// Silence between these times (s).
    gap: Option<(f64, f64)>,
    /// Receiver clock drift (s of travel-time error per s of mission).
    drift: f64,
    slant: bool,
}

const CALM: Hostility = Hostility { p_drop: 0.0, p_outlier: 0.0, gap: None, drift: 0.0, slant: false };

/// The AUV drives east along y = 0 from x = −80 at 0.85 m/s; a transponder drives west along
/// y = 0 from x = +120 at 1.3 m/s, so it passes exactly overhead; it pings every 2 s.
fn fly(seed: u64, h: Hostility, params: AuvParams) -> AuvEkf {
    fly_recording(seed, h, params).0
}

/// One range update of a flight: its time, whether an outlier was added, and what the filter did.
struct Ping {
    t: f64,
    outlier: bool,
    outcome: UpdateOutcome,
}

/// [`fly`], also returning every range update.
fn fly_recording(seed: u64, h: Hostility, params: AuvParams) -> (AuvEkf, Vec<Ping>) {
    let mut pings = Vec::new();
    let mut rng = SeedStream::new(seed).rng(1);
    let mut f = AuvEkf::new(0.0, -78.0, 3.0, 0.85, 0.0, params);
    let dt = 0.1;
    for k in 1..=2000 {
        let t = k as f64 * dt;
        f.predict_to(t, 0.0);
        f.update_speed(0.85 + 0.05 * (rng.gen::<f64>() - 0.5));
        f.update_heading(0.002 * (rng.gen::<f64>() - 0.5));
        let in_gap = h.gap.is_some_and(|(a, b)| (a..b).contains(&t));
        if k % 20 == 0 && !in_gap && rng.gen::<f64>() >= h.p_drop {
            let auv = Vec3::new(-80.0 + 0.85 * t, 0.0, 10.0);
            let tr = Vec3::new(120.0 - 1.3 * t, 0.0, 1.5);
            let true_range = if h.slant { (auv - tr).norm() } else { (auv.xy() - tr.xy()).norm() };
            let mut range = true_range + 0.2 * (rng.gen::<f64>() - 0.5);
            let outlier = rng.gen::<f64>() < h.p_outlier;
            if outlier {
                range += 5.0 + 5.0 * rng.gen::<f64>();
            }
            let travel_time = range / 1500.0 + h.drift * t;
            let m = RangeMeasurement { range: 1500.0 * travel_time, travel_time, transponder: tr };
            let outcome = f.update_range(&m, h.slant.then_some(10.0));
            pings.push(Ping { t, outlier, outcome });
        }
        assert!(f.state().iter().all(|v| v.is_finite()), "non-finite state at t = {t}: {:?}", f.state());
        assert!(is_positive_definite(f.ekf().p()), "covariance not positive definite at t = {t}");
    }
    (f, pings)
}

#[test]
fn calm_run_tracks_the_truth() {
    let f = fly(1, CALM, AuvParams::default());
    let err = (f.position().0 - (-80.0 + 0.85 * 200.0)).hypot(f.position().1);
    assert!(err < 5.0, "final error {err}");
}

#[test]
fn dropped_messages() {
    for seed in 0..8 {
        fly(seed, Hostility { p_drop: 0.7, ..CALM }, AuvParams::default());
    }
}

#[test]
fn outliers_of_five_to_ten_metres() {
    for seed in 0..8 {
        fly(seed, Hostility { p_outlier: 0.3, ..CALM }, AuvParams::default());
    }
}

#[test]
fn outliers_are_gated_when_asked() {
    let mut gated = AuvParams::default();
    gated.range_gate = Gate { max_abs_residual: Some(4.0), max_nis: Some(10.83) };
    for seed in 0..8 {
        let (_, pings) = fly_recording(seed, Hostility { p_outlier: 0.3, ..CALM }, gated.clone());
        // Outliers add 5 to 10 m and clean ranges are within 0.1 m of the truth, while the filter
        // starts 2 m off: the 4 m gate separates them from the first ping on. Every outlier is
        // gated and every clean range applied.
        assert!(pings.iter().any(|p| p.outlier) && pings.iter().any(|p| !p.outlier), "seed {seed}: both kinds drawn");
        for p in &pings {
            let gated = matches!(p.outcome, UpdateOutcome::Gated { .. });
            assert_eq!(gated, p.outlier, "seed {seed}, t = {} s: outlier {}, {:?}", p.t, p.outlier, p.outcome);
        }
    }
}

#[test]
fn two_minute_gap() {
    for seed in 0..4 {
        fly(seed, Hostility { gap: Some((20.0, 140.0)), ..CALM }, AuvParams::default());
    }
}

#[test]
fn transponder_directly_overhead_in_2d_and_3d() {
    for seed in 0..4 {
        fly(seed, CALM, AuvParams::default());
        fly(seed, Hostility { slant: true, ..CALM }, AuvParams::default());
    }
}

#[test]
fn clock_drift() {
    // 1 ms of travel time per minute: ~1.5 m of range bias per minute.
    for seed in 0..4 {
        fly(seed, Hostility { drift: 1e-3 / 60.0, ..CALM }, AuvParams::default());
    }
}
