//! AUV EKF cost per step: predict + speed + compass updates (5 states, and 7 with the current),
//! and a range update.

use coopnav_core::Vec3;
use coopnav_nav::{AuvEkf, AuvParams, CurrentParams, RangeMeasurement};
use criterion::{black_box, criterion_group, criterion_main, Bencher, Criterion};

/// One filter step of `f` per iteration: prediction, speed and compass updates.
fn filter_steps<const M: usize>(b: &mut Bencher, mut f: AuvEkf<M>) {
    let mut t = 0.0;
    b.iter(|| {
        t += 0.1;
        f.predict_to(t, black_box(0.001));
        f.update_speed(black_box(0.85));
        f.update_heading(black_box(0.0))
    })
}

fn bench(c: &mut Criterion) {
    c.bench_function("auv_ekf_step_predict_speed_heading", |b| {
        filter_steps(b, AuvEkf::new(0.0, 0.0, 0.0, 0.85, 0.0, AuvParams::default()))
    });
    c.bench_function("auv_ekf_current_step_predict_speed_heading", |b| {
        let current = CurrentParams::default();
        filter_steps(b, AuvEkf::with_current(0.0, 0.0, 0.0, 0.85, 0.0, AuvParams::default(), current))
    });
    c.bench_function("auv_ekf_range_update", |b| {
        let f0 = AuvEkf::new(0.0, 0.0, 0.0, 0.85, 0.0, AuvParams::default());
        let m =
            RangeMeasurement { range: 101.0, travel_time: 101.0 / 1500.0, transponder: Vec3::new(100.0, 10.0, 1.5) };
        b.iter(|| {
            let mut f = f0.clone();
            f.update_range(black_box(&m), None)
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
