//! Post-processing (EKF + RTS) of synthetic field logs with 5 beacons, a range every 15 s and
//! sensor rows at 10 Hz (target: 24 h ≤ 10 s; `coopnav bench post` runs the full
//! day and prints JSON). Criterion times one simulated hour, which scales linearly.

use coopnav_nav::post::{postprocess_rows, PostConfig};
use coopnav_nav::synthetic::{synthetic_log, SyntheticSpec};
use criterion::{criterion_group, criterion_main, Criterion};

fn bench(c: &mut Criterion) {
    let spec = SyntheticSpec { duration_s: 3600.0, beacons: 5, ..SyntheticSpec::default() };
    let rows = synthetic_log(&spec);
    let cfg = PostConfig::default();
    let mut g = c.benchmark_group("post");
    g.sample_size(10);
    g.bench_function("postprocess_1h_10hz_5_beacons", |b| b.iter(|| postprocess_rows(&rows, &cfg)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
