//! `coopnav plan [scenario.toml] [-o dir] [--force] [--example] [--moos [--moos-origin LAT,LON]]`:
//! pre-deployment planning of a whole mission. Without a scenario it plans the embedded example;
//! without -o it writes a fresh directory under runs/ (`runs/plan-<name>`, `runs/plan-<name>-2`, ...).
//! `--moos` adds MOOS-IvP mission files for the CNA (cna.moos, cna.bhv) to the run directory.

use crate::scenario_args::{Loaded, ScenarioArgs, ScenarioCommand};
use anyhow::{anyhow, Context, Result};
use coopnav_core::limits::{self, Estimate};
use coopnav_core::LatLon;
use coopnav_moos::mission::EXAMPLE_ORIGIN_DEG;
use coopnav_plan::predeploy;
use coopnav_plan::LookAheadPlanner;
use coopnav_sim::batch::work;
use coopnav_sim::output::moos_export;
use coopnav_sim::output::plan::write_run;
use coopnav_sim::scenario::file::Validate;
use coopnav_sim::scenario::plan::{Scenario, EXAMPLE};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    /// Also write MOOS-IvP mission files that fly the planned CNA path (cna.moos, cna.bhv).
    #[arg(long)]
    moos: bool,
    /// LatOrigin,LongOrigin of the mission files, degrees (default: MOOS-IvP's example origin,
    /// 42.358456,-71.087589).
    #[arg(long, value_name = "LAT,LON", requires = "moos")]
    moos_origin: Option<String>,
    /// Scenario file, -o, --force, --example.
    #[command(flatten)]
    scenario: ScenarioArgs<Plan>,
}

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
    const FORMAT: crate::input::Format = crate::input::Format::Plan;
    const READ: fn(&str, &Path) -> Result<Scenario, coopnav_sim::scenario::file::ScenarioError> = Scenario::read;
    const VALIDATE: Validate<Scenario> = Scenario::validate;
    const WORK: fn(&Scenario) -> Vec<Estimate> = work::predeploy;
}

/// The `--moos-origin` value, or MOOS-IvP's example origin.
fn moos_origin(text: Option<&str>) -> Result<LatLon> {
    let Some(text) = text else {
        return Ok(LatLon::new(EXAMPLE_ORIGIN_DEG.0, EXAMPLE_ORIGIN_DEG.1)?);
    };
    let bad = || anyhow!("--moos-origin {text:?}: expected LAT,LON in degrees, e.g. 42.358456,-71.087589");
    let (lat, lon) = text.split_once(',').ok_or_else(bad)?;
    let (lat, lon) = (lat.trim().parse().map_err(|_| bad())?, lon.trim().parse().map_err(|_| bad())?);
    LatLon::new(lat, lon).with_context(|| format!("--moos-origin {text:?}"))
}

pub fn run(args: Args) -> Result<()> {
    if args.scenario.print_example() {
        return Ok(());
    }
    let Loaded { scenario, file, base, stem } = args.scenario.load()?;
    // Everything is validated before any output is created.
    let mission = scenario.build(&file, &base)?;
    limits::check(work::predeploy_mission(&mission), args.scenario.allow_large())?;
    // The MOOS files' LatOrigin/LongOrigin: the scenario's site origin, where its metres start.
    let origin = match (scenario.site.origin, args.moos_origin.as_deref()) {
        (Some(_), Some(_)) => {
            anyhow::bail!("--moos-origin: the scenario's site.origin already places its metres; leave the option out")
        }
        (Some(site), None) => args.moos.then_some(site.latlon()),
        (None, text) => args.moos.then(|| moos_origin(text)).transpose()?,
    };
    let tracks: Vec<PathBuf> = scenario.auv.iter().filter_map(|a| a.track_csv.as_ref().map(|t| base.join(t))).collect();
    let inputs: Vec<&Path> = std::iter::once(file.as_path()).chain(tracks.iter().map(PathBuf::as_path)).collect();
    let dir = args.scenario.run_dir(&stem, &inputs)?;
    let mut planner = LookAheadPlanner::new(mission.planner)?;
    let bar = if std::io::stderr().is_terminal() {
        ProgressBar::new(predeploy::step_count(&mission))
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(ProgressStyle::with_template("{bar:40} {pos}/{len} decisions [{elapsed_precise} < {eta_precise}]")?);
    let result = predeploy::run(&mission, &mut planner, &|s| bar.set_position(s))?;
    bar.finish_and_clear();
    if let Some(origin) = origin {
        let files = moos_export::plan_mission(&mission, &result, origin);
        dir.write_text(&files.moos_name, &files.moos)?;
        dir.write_text(&files.bhv_name, &files.bhv)?;
    }
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
