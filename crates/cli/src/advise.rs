//! `coopnav advise [MISSION.toml] [--runs N] [--policy a,b] [--tau s,s] [--status-rate r,r]
//! [--duration S] [-o DIR]`: the Monte Carlo a team needs before going to sea, over the candidate
//! CNA policies, cycles and status rates, written as one page (`advice.html`) with the
//! recommendation, a map of where the error peaks and the MOOS files to fly
//! (`coopnav_sim::batch::advise`, `coopnav_sim::output::advise`).

use crate::scenario_args::{Loaded, ScenarioArgs, ScenarioCommand};
use anyhow::{Context, Result};
use coopnav_acomms::Rate;
use coopnav_core::limits::{self, Estimate};
use coopnav_sim::batch::advise::{self, AdviseSpec};
use coopnav_sim::batch::work;
use coopnav_sim::output::advise::{write_advice, PAGE};
use coopnav_sim::scenario::file::Validate;
use coopnav_sim::scenario::{Scenario, EXAMPLE};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

#[derive(clap::Args)]
pub struct Args {
    /// Monte Carlo runs per candidate (and again for the two best, on the next seed).
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Candidate CNA policies, comma-separated (default: planner-estimator, centroid, zigzag, none).
    #[arg(long, value_delimiter = ',')]
    policy: Vec<String>,
    /// Candidate ranging cycles τ, s, comma-separated (default: the scenario's).
    #[arg(long, value_delimiter = ',')]
    tau: Vec<f64>,
    /// Candidate fixed status rates (0, 1, 4, 5), comma-separated (default: the scenario's).
    #[arg(long, value_delimiter = ',')]
    status_rate: Vec<u8>,
    /// Mission length instead of the scenario's, s (a shorter, cheaper look).
    #[arg(long)]
    duration: Option<f64>,
    /// Scenario file, -o, --force, --allow-large, --example.
    #[command(flatten)]
    scenario: ScenarioArgs<Advise>,
}

/// What `coopnav advise` reads: a closed-loop scenario.
pub enum Advise {}

impl ScenarioCommand for Advise {
    type Scenario = Scenario;
    const SCENARIO_HELP: &'static str = "Mission file (TOML). Omit it to advise on the embedded default mission";
    const OUTPUT_HELP: &'static str = "Output directory (default: a fresh runs/advise-<name>)";
    const EXAMPLE_HELP: &'static str = "Print the embedded default scenario as TOML and exit";
    const EXAMPLE: &'static str = EXAMPLE;
    const EMBEDDED: &'static str = "default";
    const RUN_PREFIX: &'static str = "advise";
    const FORMAT: crate::input::Format = crate::input::Format::Mission;
    const READ: fn(&str, &std::path::Path) -> Result<Scenario, coopnav_sim::scenario::file::ScenarioError> =
        Scenario::read;
    const VALIDATE: Validate<Scenario> = Scenario::validate;
    /// One run; the candidates' runs are checked once they are known.
    const WORK: fn(&Scenario) -> Vec<Estimate> = |scenario| work::closed_loop(scenario, 1, 1);
}

pub fn run(args: Args) -> Result<()> {
    if args.scenario.print_example() {
        return Ok(());
    }
    let Loaded { scenario, stem, file, .. } = args.scenario.load()?;
    let mut spec =
        AdviseSpec { runs: args.runs, duration_s: args.duration, taus: args.tau.clone(), ..AdviseSpec::default() };
    if !args.policy.is_empty() {
        spec.policies = args.policy.clone();
    }
    spec.status_rates = args
        .status_rate
        .iter()
        .map(|&r| Rate::try_from(r).map_err(|e| anyhow::anyhow!("--status-rate {r}: {e}")))
        .collect::<Result<_>>()?;
    // Every candidate is checked, and its work estimated, before any run starts.
    let (cands, _) = advise::candidates(&scenario, &spec)?;
    let per_setting = spec.policies.len();
    for c in cands.iter().step_by(per_setting) {
        limits::check(work::closed_loop(&c.scenario, 2 * spec.runs, per_setting), args.scenario.allow_large())?;
    }
    let dir = args.scenario.run_dir(&stem, &[file.as_path()])?;
    let total = advise::total_runs(cands.len(), spec.runs);
    let bar = if std::io::stderr().is_terminal() { ProgressBar::new(total) } else { ProgressBar::hidden() };
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} runs [{elapsed_precise} < {eta_precise}]")?);
    let advice = advise::advise(&scenario, &spec, &|done| bar.set_position(done))?;
    bar.finish_and_clear();
    let command = std::env::args().collect::<Vec<_>>().join(" ");
    let base = cands[0].scenario.clone();
    let out = write_advice(dir, &base, &advice, &command).context("writing the advice")?;
    let best = &advice.candidates[advice.recommended];
    println!("recommended: {}", best.label);
    let c = &advice.confirmed.mean_error;
    println!(
        "expected fleet mean true error {:.2} m (95 % CI {:.2} to {:.2}) on seed {}",
        c.mean,
        c.low,
        c.high,
        advice.seed.wrapping_add(1)
    );
    if let Some(m) = &advice.margin {
        let word = if m.decided { "better than" } else { "undecided against" };
        println!(
            "{word} {}: paired difference {:.2} m (95 % CI {:.2} to {:.2})",
            m.runner_up, m.difference.mean, m.difference.low, m.difference.high
        );
    }
    println!("open {}", out.join(PAGE).display());
    Ok(())
}
