//! Criterion benches of one planner decision: branch-and-bound on one thread, in parallel, and
//! brute force, under Hudson's cost (the issue-2 speed targets) and the estimator-aware cost (the
//! issue-10 targets: N = 5, A = 7, L = 5 and L = 7). Run with short times on the shared machine:
//! `cargo bench -p coopnav-plan -- --warm-up-time 1 --measurement-time 3`.

use coopnav_plan::workload::Workload;
use coopnav_plan::{Algorithm, CostSpec, EstimatorSpec};
use criterion::{criterion_group, criterion_main, Criterion};

fn search(c: &mut Criterion) {
    let mut g = c.benchmark_group("decision");
    g.sample_size(10);
    let estimator = CostSpec::Estimator(EstimatorSpec::default());
    for w in [
        Workload { n: 2, a: 5, b: 1, l: 5, gap: 500.0, cost: CostSpec::Hudson },
        Workload { n: 5, a: 7, b: 1, l: 7, gap: 500.0, cost: CostSpec::Hudson },
        Workload { n: 5, a: 7, b: 1, l: 7, gap: 100.0, cost: CostSpec::Hudson },
        Workload { n: 2, a: 5, b: 3, l: 3, gap: 500.0, cost: CostSpec::Hudson },
        Workload { n: 5, a: 7, b: 1, l: 5, gap: 500.0, cost: estimator },
        Workload { n: 5, a: 7, b: 1, l: 7, gap: 500.0, cost: estimator },
    ] {
        let kind = if w.cost == CostSpec::Hudson { "hudson" } else { "estimator" };
        let name = format!("{kind}_N{}_A{}_B{}_L{}_gap{}", w.n, w.a, w.b, w.l, w.gap);
        g.bench_function(format!("bnb_1thread/{name}"), |b| {
            b.iter(|| w.decide(Algorithm::BranchAndBound, false).unwrap())
        });
        if w.l >= 7 {
            g.bench_function(format!("bnb_parallel/{name}"), |b| {
                b.iter(|| w.decide(Algorithm::BranchAndBound, true).unwrap())
            });
        }
        if w.leaves() <= 1_000_000 {
            g.bench_function(format!("brute/{name}"), |b| b.iter(|| w.decide(Algorithm::BruteForce, false).unwrap()));
        }
    }
    g.finish();
}

criterion_group!(benches, search);
criterion_main!(benches);
