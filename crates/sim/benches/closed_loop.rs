//! Criterion bench: one closed-loop hour (3 survey AUVs, planner A = 5, L = 5, 10 Hz EKFs) and a
//! baseline hour (centroid), so the planner's share of a run shows as the difference.

use coopnav_sim::engine::Faults;
use coopnav_sim::observe::metrics::run;
use coopnav_sim::policy::PolicySpec;
use coopnav_sim::scenario::Scenario;
use criterion::{criterion_group, criterion_main, Criterion};

fn benches(c: &mut Criterion) {
    let sc = Scenario::example();
    let mut g = c.benchmark_group("closed_loop_1h_3auvs");
    g.sample_size(10);
    for name in ["planner", "centroid"] {
        let spec = PolicySpec::new(name, &sc).expect("known policy");
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut p = spec.build(&sc).expect("builds");
                run(&sc, &mut p, 1, &Faults::default(), &mut ())
            })
        });
    }
    g.finish();
}

criterion_group!(closed_loop, benches);
criterion_main!(closed_loop);
