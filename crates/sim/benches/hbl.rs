//! One HBL Two run of Gill's Table 5 scenario on the engine (Δt = 0.1 s, 130 s) and a 250-run
//! zone Monte Carlo.

use coopnav_nav::cycle::Configuration;
use coopnav_sim::observe::zone::{zone_monte_carlo, zone_run, GillZone, ZoneSpec};
use coopnav_sim::policy::PolicySpec;
use coopnav_sim::scenario::hbl::table5_scenario;
use criterion::{criterion_group, criterion_main, Criterion};

fn bench(c: &mut Criterion) {
    let sc = table5_scenario(Configuration::HblTwo).expect("the Table 5 file parses");
    let silent = PolicySpec::new("none", &sc).expect("the silent policy");
    let zone = ZoneSpec::table5();
    c.bench_function("hbl_one_run_table5", |b| {
        b.iter(|| zone_run(&sc, &silent, 42, GillZone::of_scenario(zone, &sc)).expect("silent policy builds"))
    });
    let mut g = c.benchmark_group("hbl_mc");
    g.sample_size(10);
    g.bench_function("hbl_250_runs_table5", |b| b.iter(|| zone_monte_carlo(&sc, zone, 250, 1)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
