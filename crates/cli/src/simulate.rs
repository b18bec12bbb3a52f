//! `coopnav simulate [scenario.toml] [--policy p] [-o dir] [--force] [--example]`: one closed-loop
//! mission (no scenario: the embedded default, 3 survey AUVs, ASC CNA, 1 h, seed 1) written to a
//! run directory with plots and report.html; `--runs N --policy a,b,c` instead runs a seeded
//! Monte Carlo comparison and prints a table with 95 % confidence intervals.

use anyhow::{bail, Context, Result};
use coopnav_sim::closed_loop::{self, comparison_table, output::write_run, Faults, PolicySpec, Scenario, EXAMPLE};
use coopnav_sim::output::RunDir;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Scenario file (TOML). Omit it to run the embedded default mission.
    scenario: Option<PathBuf>,
    /// CNA policies, comma-separated: planner, none, racetrack, zigzag, centroid, trail, relay,
    /// open-loop. One run writes a run directory for the first; --runs compares them all.
    #[arg(long, value_delimiter = ',', default_value = "planner")]
    policy: Vec<String>,
    /// Monte Carlo runs per policy (comparison table instead of a run directory).
    #[arg(long)]
    runs: Option<usize>,
    /// Base seed (default: the scenario's).
    #[arg(long)]
    seed: Option<u64>,
    /// Output directory (default: a fresh runs/sim-<name>).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Replace the output directory if it exists.
    #[arg(long)]
    force: bool,
    /// Print the embedded default scenario as TOML and exit.
    #[arg(long)]
    example: bool,
    /// Also write the comparison as JSON here (with --runs).
    #[arg(long)]
    json: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    if args.example {
        print!("{EXAMPLE}");
        return Ok(());
    }
    let (mut scenario, stem) = match &args.scenario {
        Some(path) => (Scenario::load(path)?, path.file_stem().map_or("scenario".into(), |s| s.to_string_lossy().into_owned())),
        None => (Scenario::parse(EXAMPLE, &PathBuf::from("<embedded default>"))?, "default".to_string()),
    };
    if let Some(seed) = args.seed {
        scenario.seed = seed;
    }
    // Every policy name is checked before any work starts.
    let specs = args.policy.iter().map(|p| PolicySpec::new(p, &scenario)).collect::<Result<Vec<_>, _>>()?;
    match args.runs {
        Some(0) => bail!("--runs must be at least 1"),
        Some(runs) => compare(&scenario, &args.policy, runs, args.json.as_ref()),
        None => single(&scenario, &specs[0], &stem, &args),
    }
}

fn single(sc: &Scenario, spec: &PolicySpec, stem: &str, args: &Args) -> Result<()> {
    let dir = match &args.output {
        Some(o) => RunDir::create(o, args.force)?,
        None => RunDir::create_fresh("runs", &format!("sim-{stem}"))?,
    };
    let mut policy = spec.build(sc)?;
    let result = closed_loop::run(sc, &mut policy, sc.seed, true, &Faults::default());
    let out = write_run(dir, sc, &result, &std::env::args().collect::<Vec<_>>().join(" ")).context("writing the run directory")?;
    println!("policy {} · {} survey AUVs · {} s · seed {} -> {}", result.policy, sc.fleet.n_auvs, sc.duration_s, sc.seed, out.display());
    println!("{:<6} {:>9} {:>8} {:>8} {:>8} {:>8} {:>9} {:>12} {:>12}", "AUV", "mean [m]", "RMS", "p95", "max", "CEP50", "modelled", "ranges rx/tx", "status rx/tx");
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
        println!("planner: {} decisions, {} deadline misses, mean levels {:.2} of {}", p.decisions, p.deadline_misses, p.mean_levels_searched, p.levels_requested);
    }
    println!("open {}", out.join("report.html").display());
    Ok(())
}

fn compare(sc: &Scenario, policies: &[String], runs: usize, json: Option<&PathBuf>) -> Result<()> {
    let total = (runs * policies.len()) as u64;
    let bar = if std::io::stderr().is_terminal() { ProgressBar::new(total) } else { ProgressBar::hidden() };
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} runs [{elapsed_precise} < {eta_precise}]")?);
    let c = closed_loop::monte_carlo(sc, policies, runs, &|done| bar.set_position(done))?;
    bar.finish_and_clear();
    print!("{}", comparison_table(&c));
    if let Some(path) = json {
        std::fs::write(path, serde_json::to_string_pretty(&c)?).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
