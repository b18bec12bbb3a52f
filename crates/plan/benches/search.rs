//! Criterion benches of one planner decision on the standard workloads (`Workload::standard`, the
//! list `coopnav bench planner` runs too): branch-and-bound on one thread, in parallel (L ≥ 7), and
//! brute force (up to 10⁶ leaves). Run with short times on the shared machine:
//! `cargo bench -p coopnav-plan -- --warm-up-time 1 --measurement-time 3`.

use coopnav_plan::workload::Workload;
use coopnav_plan::Algorithm;
use criterion::{criterion_group, criterion_main, Criterion};

fn search(c: &mut Criterion) {
    let mut g = c.benchmark_group("decision");
    g.sample_size(10);
    for w in Workload::standard() {
        let name = w.name();
        g.bench_function(format!("bnb_1thread/{name}"), |b| {
            b.iter(|| w.decide(Workload::search(Algorithm::BranchAndBound, false)).unwrap())
        });
        if w.l >= 7 {
            g.bench_function(format!("bnb_parallel/{name}"), |b| {
                b.iter(|| w.decide(Workload::search(Algorithm::BranchAndBound, true)).unwrap())
            });
        }
        if w.leaves() <= 1_000_000 {
            let brute = Workload::search(Algorithm::BruteForce, false);
            g.bench_function(format!("brute/{name}"), |b| b.iter(|| w.decide(brute).unwrap()));
        }
    }
    g.finish();
}

criterion_group!(benches, search);
criterion_main!(benches);
