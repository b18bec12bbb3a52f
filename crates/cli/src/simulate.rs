//! `coopnav simulate [scenario.toml] [--policy p] [-o dir] [--force] [--example]`: one closed-loop
//! mission (no scenario: the embedded default, 3 survey AUVs, ASC CNA, 1 h, seed 1) written to a
//! run directory with plots and report.html; `--runs N --policy a,b,c` instead runs a seeded
//! Monte Carlo comparison and prints a table with 95 % confidence intervals.

use crate::scenario_args::{Loaded, ScenarioArgs, ScenarioCommand};
use anyhow::{bail, Context, Result};
use coopnav_core::limits::{self, Estimate};
use coopnav_sim::batch::mc;
use coopnav_sim::batch::mc::comparison_table;
use coopnav_sim::batch::work;
use coopnav_sim::engine::Faults;
use coopnav_sim::observe::metrics;
use coopnav_sim::output::run::{write_comparison, write_run};
use coopnav_sim::policy::PolicySpec;
use coopnav_sim::scenario::file::Validate;
use coopnav_sim::scenario::{Scenario, EXAMPLE};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::Path;

#[derive(clap::Args)]
pub struct Args {
    /// CNA policies, comma-separated: planner, planner-estimator, none, racetrack, zigzag,
    /// centroid, centroid-standoff, trail, relay, open-loop, greedy-fisher. One run writes a run directory for the
    /// first; --runs compares them all, each paired with the first.
    #[arg(long, value_delimiter = ',', default_value = "planner-estimator")]
    policy: Vec<String>,
    /// Monte Carlo runs per policy (comparison table instead of a run directory).
    #[arg(long)]
    runs: Option<usize>,
    /// Base seed (default: the scenario's).
    #[arg(long)]
    seed: Option<u64>,
    /// Scenario file, -o, --force, --example (here, so `--help` lists them after --seed).
    #[command(flatten)]
    scenario: ScenarioArgs<Simulate>,
    /// Print the result as JSON on stdout in place of the table: one run's summary.json, or with
    /// --runs the comparison (comparison.json).
    #[arg(long)]
    json: bool,
}

/// What `coopnav simulate` reads: a closed-loop scenario.
pub enum Simulate {}

impl ScenarioCommand for Simulate {
    type Scenario = Scenario;
    const SCENARIO_HELP: &'static str = "Scenario file (TOML). Omit it to run the embedded default mission";
    const OUTPUT_HELP: &'static str = "Output directory (default: a fresh runs/sim-<name>)";
    const EXAMPLE_HELP: &'static str = "Print the embedded default scenario as TOML and exit";
    const EXAMPLE: &'static str = EXAMPLE;
    const EMBEDDED: &'static str = "default";
    const RUN_PREFIX: &'static str = "sim";
    const FORMAT: crate::input::Format = crate::input::Format::Mission;
    const READ: fn(&str, &Path) -> Result<Scenario, coopnav_sim::scenario::file::ScenarioError> = Scenario::read;
    const VALIDATE: Validate<Scenario> = Scenario::validate;
    /// One run; `--runs` is checked once the policies are known.
    const WORK: fn(&Scenario) -> Vec<Estimate> = |scenario| work::closed_loop(scenario, 1, 1);
}

pub fn run(args: Args) -> Result<()> {
    if args.scenario.print_example() {
        return Ok(());
    }
    let Loaded { mut scenario, stem, file, .. } = args.scenario.load()?;
    if let Some(seed) = args.seed {
        scenario.seed = seed;
    }
    // Every policy name is checked before any work starts.
    let specs = args.policy.iter().map(|p| PolicySpec::new(p, &scenario)).collect::<Result<Vec<_>, _>>()?;
    if let Some(runs) = args.runs {
        limits::check(work::closed_loop(&scenario, runs, specs.len()), args.scenario.allow_large())?;
    }
    match args.runs {
        Some(0) => bail!("--runs must be at least 1"),
        Some(runs) => compare(&scenario, runs, &stem, &file, &args),
        None => single(&scenario, &specs[0], &stem, &file, &args),
    }
}

fn single(sc: &Scenario, spec: &PolicySpec, stem: &str, file: &Path, args: &Args) -> Result<()> {
    let dir = args.scenario.run_dir(stem, &[file])?;
    let mut policy = spec.build(sc)?;
    let result = metrics::run_traced(sc, &mut policy, sc.seed, &Faults::default());
    let out = write_run(dir, sc, &result, &std::env::args().collect::<Vec<_>>().join(" "))
        .context("writing the run directory")?;
    if args.json {
        let summary = out.join("summary.json");
        let text = std::fs::read_to_string(&summary).with_context(|| format!("reading {}", summary.display()))?;
        print!("{text}");
        eprintln!("wrote {}", out.display());
        return Ok(());
    }
    println!(
        "policy {} · {} survey AUVs · {} s · seed {} -> {}",
        result.policy,
        sc.fleet.n_auvs,
        sc.duration_s,
        sc.seed,
        out.display()
    );
    println!(
        "{:<6} {:>9} {:>8} {:>8} {:>8} {:>8} {:>9} {:>12} {:>12}",
        "AUV", "mean [m]", "RMS", "p95", "max", "CEP50", "modelled", "ranges rx/tx", "status rx/tx"
    );
    for a in &result.auvs {
        println!(
            "{:<6} {:>9.2} {:>8.2} {:>8.2} {:>8.2} {:>8.2} {:>9} {:>12} {:>12}",
            a.name,
            a.error.mean,
            a.error.rms,
            a.error.p95,
            a.error.max,
            a.error.cep50,
            a.modelled_mean.map_or("-".into(), |m| format!("{m:.2}")),
            format!("{}/{}", a.downlink.received, a.downlink.sent),
            format!("{}/{}", a.uplink.received, a.uplink.sent),
        );
    }
    if let Some(p) = &result.planner {
        println!(
            "planner: {} decisions, {} deadline misses, mean levels {:.2} of {}",
            p.decisions, p.deadline_misses, p.mean_levels_searched, p.levels_requested
        );
    }
    println!("open {}", out.join("report.html").display());
    Ok(())
}

fn compare(sc: &Scenario, runs: usize, stem: &str, file: &Path, args: &Args) -> Result<()> {
    let policies = &args.policy;
    // The output is opened (and refused) before any work.
    let dir = args.scenario.output().map(|_| args.scenario.run_dir(stem, &[file])).transpose()?;
    let total = (runs * policies.len()) as u64;
    let bar = if std::io::stderr().is_terminal() { ProgressBar::new(total) } else { ProgressBar::hidden() };
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} runs [{elapsed_precise} < {eta_precise}]")?);
    let c = mc::monte_carlo(sc, policies, runs, &|done| bar.set_position(done))?;
    bar.finish_and_clear();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&c)?);
    } else {
        print!("{}", comparison_table(&c));
    }
    if let Some(dir) = dir {
        let out = write_comparison(dir, sc, &c, stem, &std::env::args().collect::<Vec<_>>().join(" "))
            .context("writing the comparison's run directory")?;
        // With --json, stdout holds the JSON alone.
        if args.json {
            eprintln!("wrote {}", out.display());
        } else {
            println!("wrote {}", out.display());
        }
    }
    Ok(())
}
