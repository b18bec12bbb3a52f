//! Criterion benches of one planner decision: branch-and-bound (one thread) vs brute force on
//! the issue-2 speed targets.

use coopnav_plan::workload::Workload;
use coopnav_plan::{Algorithm, CostSpec};
use criterion::{criterion_group, criterion_main, Criterion};

fn search(c: &mut Criterion) {
    let mut g = c.benchmark_group("decision");
    g.sample_size(10);
    for w in [
        Workload { n: 2, a: 5, b: 1, l: 5, gap: 500.0, cost: CostSpec::Hudson },
        Workload { n: 5, a: 7, b: 1, l: 7, gap: 500.0, cost: CostSpec::Hudson },
        Workload { n: 5, a: 7, b: 1, l: 7, gap: 100.0, cost: CostSpec::Hudson },
        Workload { n: 2, a: 5, b: 3, l: 3, gap: 500.0, cost: CostSpec::Hudson },
    ] {
        let name = format!("N{}_A{}_B{}_L{}_gap{}", w.n, w.a, w.b, w.l, w.gap);
        g.bench_function(format!("bnb_1thread/{name}"), |b| {
            b.iter(|| w.decide(Algorithm::BranchAndBound, false).unwrap())
        });
        if w.leaves() <= 1_000_000 {
            g.bench_function(format!("brute/{name}"), |b| b.iter(|| w.decide(Algorithm::BruteForce, false).unwrap()));
        }
    }
    g.finish();
}

criterion_group!(benches, search);
criterion_main!(benches);
