//! `coopnav plan [scenario.toml] [-o dir] [--force] [--example]`: pre-deployment planning of a
//! whole mission. Without a scenario it plans the embedded example; without -o it writes a fresh
//! directory under runs/ (runs/plan-<name>, runs/plan-<name>-2, ...).

use crate::scenario_args::{Loaded, ScenarioArgs, ScenarioCommand};
use anyhow::{Context, Result};
use coopnav_core::limits::Estimate;
use coopnav_plan::LookAheadPlanner;
use coopnav_sim::predeploy::{self, output::write_run, Scenario, EXAMPLE};
use coopnav_sim::scenario_file::Validate;
use coopnav_sim::work;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;

/// `coopnav plan`'s arguments: just the shared scenario arguments.
pub type Args = ScenarioArgs<Plan>;

/// What `coopnav plan` reads: a pre-deployment scenario.
pub enum Plan {}

impl ScenarioCommand for Plan {
    type Scenario = Scenario;
    const SCENARIO_HELP: &'static str = "Scenario file (TOML). Omit it to plan the embedded example scenario";
    const OUTPUT_HELP: &'static str = "Output directory (default: a fresh runs/plan-<name>)";
    const EXAMPLE_HELP: &'static str = "Print the embedded example scenario and exit";
    const EXAMPLE: &'static str = EXAMPLE;
    const EMBEDDED: &'static str = "example";
    const RUN_PREFIX: &'static str = "plan";
    const VALIDATE: Validate<Scenario> = Scenario::validate;
    const WORK: fn(&Scenario) -> Vec<Estimate> = work::predeploy;
}

pub fn run(args: Args) -> Result<()> {
    if args.print_example() {
        return Ok(());
    }
    let Loaded { scenario, file, base, stem } = args.load()?;
    // Everything is validated before any output is created.
    let mission = scenario.build(&file, &base)?;
    let dir = args.run_dir(&stem)?;
    let mut planner = LookAheadPlanner::new(mission.planner)?;
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(predeploy::step_count(&mission))
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} decisions [{elapsed_precise} < {eta_precise}]")?);
    let result = predeploy::run(&mission, &mut planner, &|s| bar.set_position(s))?;
    bar.finish_and_clear();
    let inputs = serde_json::json!({ "scenario_file": file.display().to_string(), "scenario": scenario });
    let out = write_run(dir, &mission, inputs, &result).context("writing the run directory")?;
    let s = &result.summary;
    println!("planned {} decisions for {} survey AUVs -> {}", s.steps, s.n_auvs, out.display());
    println!(
        "average cost {:.2} m^2, max error {:.2} m, RMS error {:.2} m, distance {:.0}..{:.0} m ({} too close, {} too far)",
        s.average_cost, s.max_error, s.rms_error, s.min_distance, s.max_distance, s.too_close_steps, s.too_far_steps
    );
    Ok(())
}
