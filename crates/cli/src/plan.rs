//! `coopnav plan [scenario.toml] [-o dir] [--force] [--example]`: pre-deployment planning of a
//! whole mission. Without a scenario it plans the embedded example; without -o it writes a fresh
//! directory under runs/ (runs/plan-<name>, runs/plan-<name>-2, ...).

use anyhow::{Context, Result};
use coopnav_plan::LookAheadPlanner;
use coopnav_sim::output::RunDir;
use coopnav_sim::predeploy::{self, output::write_run, Scenario, EXAMPLE};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    /// Scenario file (TOML). Omit it to plan the embedded example scenario.
    scenario: Option<PathBuf>,
    /// Output directory (default: a fresh runs/plan-<name>).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Replace the output directory if it exists.
    #[arg(long)]
    force: bool,
    /// Print the embedded example scenario and exit.
    #[arg(long)]
    example: bool,
}

pub fn run(args: Args) -> Result<()> {
    if args.example {
        print!("{EXAMPLE}");
        return Ok(());
    }
    let (scenario, file, base, stem) = match &args.scenario {
        Some(path) => {
            let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scenario".into());
            let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
            (Scenario::load(path)?, path.clone(), base, stem)
        }
        None => {
            let file = PathBuf::from("<embedded example>");
            (Scenario::parse(EXAMPLE, &file)?, file, PathBuf::from("."), "example".to_string())
        }
    };
    // Everything is validated before any output is created.
    let mission = scenario.build(&file, &base)?;
    let dir = match &args.output {
        Some(o) => RunDir::create(o, args.force)?,
        None => RunDir::create_fresh("runs", &format!("plan-{stem}"))?,
    };
    let mut planner = LookAheadPlanner::new(mission.planner)?;
    let bar = if std::io::stderr().is_terminal() { ProgressBar::new(predeploy::step_count(&mission)) } else { ProgressBar::hidden() };
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
