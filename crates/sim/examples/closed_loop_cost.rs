//! Where the CPU of the full `closed-loop-vs-baselines` evaluation goes: every cell and policy of
//! it, RUNS runs each (run indices 0..RUNS of the evaluation's seeds), one after another on this
//! thread, with the thread's own CPU time per run (Linux `/proc/thread-self/schedstat`, so other
//! processes on a loaded machine count less than in wall time), and the projection to the
//! evaluation's 100 runs per cell. With `--phases`, each policy's split over the engine's phases
//! too (its clock reads cost about as much as a phase, so those runs are slower):
//! `cargo run --release -p coopnav-sim --example closed_loop_cost -- RUNS [--phases] [SCENARIO N POLICY]`

use coopnav_core::run_seed;
use coopnav_sim::engine::Observer;
use coopnav_sim::engine::{Faults, PhaseClock, Timing};
use coopnav_sim::experiments::closed_loop::{policies, setup};
use coopnav_sim::experiments::{ReproOptions, Size};
use coopnav_sim::observe::metrics::run;
use coopnav_sim::policy::PolicySpec;
use std::error::Error;

/// Nanoseconds this thread has run on a CPU.
fn thread_cpu_ns() -> Result<u64, Box<dyn Error>> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat")
        .map_err(|e| format!("/proc/thread-self/schedstat (Linux only): {e}"))?;
    Ok(stat.split_whitespace().next().ok_or("/proc/thread-self/schedstat is empty")?.parse()?)
}

/// Observes nothing (the evaluation's own runs observe nothing either).
struct Quiet;
impl Observer for Quiet {}

fn phases(t: &Timing) -> [f64; 7] {
    [t.setup_s, t.decide_s, t.advance_s, t.transmit_s, t.deliver_s, t.sense_s, t.observe_s]
}

fn main() -> Result<(), Box<dyn Error>> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let timed = args.iter().any(|a| a == "--phases");
    args.retain(|a| a != "--phases");
    let usage = "usage: closed_loop_cost RUNS [--phases] [SCENARIO N POLICY]";
    let runs: usize = args.first().ok_or(usage)?.parse()?;
    let only = &args[1..];
    if !(only.is_empty() || only.len() == 3) {
        return Err(usage.into());
    }
    let chosen = |name: &str, n: usize, policy: &str| {
        only.is_empty() || (only[0] == name && only[1] == n.to_string() && only[2] == policy)
    };
    let (settings, full_runs) = setup(&ReproOptions::new(Size::Full, 1))?;
    println!("scenario n policy cpu_ms_per_run projected_s setup decide advance transmit deliver sense observe");
    let mut total = 0.0;
    for s in &settings {
        for &n in &s.n {
            let sc = s.scenario(n, 1, None)?;
            for p in policies().iter().filter(|p| chosen(&s.name, n, p)) {
                let spec = PolicySpec::new(p, &sc)?;
                let (mut cpu_ns, mut split) = (0u64, [0.0f64; 7]);
                for r in 0..runs {
                    let start = thread_cpu_ns()?;
                    let mut policy = spec.build(&sc)?;
                    let seed = run_seed(sc.seed, r as u64);
                    if timed {
                        let mut clock = PhaseClock::start();
                        run(&sc, &mut policy, seed, &Faults::default(), &mut clock);
                        split.iter_mut().zip(phases(&clock.timing)).for_each(|(a, b)| *a += b);
                    } else {
                        run(&sc, &mut policy, seed, &Faults::default(), &mut Quiet);
                    }
                    cpu_ns += thread_cpu_ns()? - start;
                }
                let per_run_ms = cpu_ns as f64 / 1e6 / runs as f64;
                total += per_run_ms * full_runs as f64 / 1e3;
                let sum: f64 = split.iter().sum();
                let shares: Vec<String> = split.iter().map(|v| format!("{:.2}", v / sum)).collect();
                let shares = if timed { shares.join(" ") } else { "-".into() };
                let projected = per_run_ms * full_runs as f64 / 1e3;
                println!("{} {n} {p} {per_run_ms:.1} {projected:.1} {shares}", s.name);
            }
        }
    }
    println!("projected CPU at {full_runs} runs per cell: {total:.0} s");
    Ok(())
}
