//! Decision latency of the live CNA at N = 8 survey AUVs on one core: the default mission with
//! eight AUVs (τ = 43 s so that nine slots fit), its CNA inputs recorded from the engine (`world::record`), replayed into a fresh
//! `CnaPlanner`; each decision timed from its clock message to its encoded command and record
//! (the policy's whole `decide`, its covariance model and the search included), inside a
//! one-thread rayon pool. Prints p50, p99 and the maximum over the mission's decisions, then
//! criterion's statistics of one decision.

use coopnav_live::world::{record, WorldMessage};
use coopnav_live::{CnaChannels, CnaPlanner};
use coopnav_sim::scenario::file::load;
use coopnav_sim::scenario::Scenario;
use criterion::{criterion_group, criterion_main, Criterion};
use std::path::Path;
use std::time::{Duration, Instant};

const N: usize = 8;
const POLICY: &str = "planner-estimator";

fn scenario() -> Scenario {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/default.toml");
    let mut sc: Scenario = load(&path, Scenario::validate).unwrap();
    sc.fleet.n_auvs = N;
    // Nine slots (the CNA's and eight statuses) of 4.78 s each: each holds a rate-0 packet.
    sc.comms.tau = 43.0;
    sc.validate(&path).unwrap();
    sc
}

/// One replay: the wall time of each decision.
fn replay(sc: &Scenario, messages: &[WorldMessage]) -> Vec<Duration> {
    let clock = CnaChannels::default().clock;
    let mut cna = CnaPlanner::new(sc, POLICY, 0).unwrap();
    let mut times = Vec::new();
    for m in messages {
        let start = Instant::now();
        let out = cna.handle(&m.channel, &m.payload).unwrap();
        if m.channel == clock {
            times.push(start.elapsed());
            assert_eq!(out.len(), 2, "a command and a record per decision");
        }
    }
    times
}

fn bench(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let sc = scenario();
    let messages = record(&sc, POLICY).unwrap().messages;
    let replay = |sc: &Scenario, messages: &[WorldMessage]| pool.install(|| replay(sc, messages));
    {
        let mut times = replay(&sc, &messages);
        times.sort();
        let at = |q: f64| times[((times.len() - 1) as f64 * q).round() as usize].as_secs_f64() * 1e3;
        eprintln!(
            "live cna decision latency, N = {N}, one core, {} decisions: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms",
            times.len(),
            at(0.5),
            at(0.99),
            at(1.0)
        );
        let mut group = c.benchmark_group("live_cna");
        group.sample_size(10).measurement_time(Duration::from_secs(20));
        group.bench_function("decision_n8_one_core", |b| {
            b.iter_custom(|iters| {
                let mut spent = Duration::ZERO;
                let mut left = iters;
                while left > 0 {
                    let times = replay(&sc, &messages);
                    let n = (left as usize).min(times.len());
                    spent += times[..n].iter().sum::<Duration>();
                    left -= n as u64;
                }
                spent
            })
        });
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
