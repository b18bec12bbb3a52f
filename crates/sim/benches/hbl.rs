//! One HBL Two run of the Table 5 scenario (Δt = 0.1 s) and a 250-run Monte Carlo.

use coopnav_nav::cycle::Configuration;
use coopnav_sim::hbl::{monte_carlo, run, Scenario};
use criterion::{criterion_group, criterion_main, Criterion};

fn bench(c: &mut Criterion) {
    let sc = Scenario::table5(Configuration::HblTwo);
    let cycle = sc.resolved_cycle().expect("preset cycle");
    c.bench_function("hbl_one_run_table5", |b| b.iter(|| run(&sc, &cycle, 42, false)));
    let mut g = c.benchmark_group("hbl_mc");
    g.sample_size(10);
    g.bench_function("hbl_250_runs_table5", |b| b.iter(|| monte_carlo(&sc, 250, 1, &|_| {})));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
