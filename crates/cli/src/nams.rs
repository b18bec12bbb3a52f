//! `coopnav nams [exp.toml]`: runs a Nams adaptive-rate experiment described in a TOML file
//! (tables `[experiment]` — any field of `ExperimentConfig`, defaults = the thesis set-up — and
//! `[tl]`; no file: the thesis set-up itself), prints the per-cell table and writes a run
//! directory (manifest.json, summary.json, cells.csv). The file is validated before anything runs.

use crate::input;
use anyhow::{Context, Result};
use coopnav_acomms::tl::analytic::Thorp;
use coopnav_acomms::tl::bellhop::{AcousticEnv, Bellhop};
use coopnav_acomms::tl::cached::{CachedGrid, GridSpec};
use coopnav_acomms::TransmissionLoss;
use coopnav_core::limits;
use coopnav_core::{Bathymetry, Vec3};
use coopnav_sim::batch::nams::{run_experiment, ExperimentTl};
use coopnav_sim::batch::work;
use coopnav_sim::output::Manifest;
use coopnav_sim::scenario::nams::ExperimentConfig;
use indicatif::ProgressBar;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[derive(clap::Args)]
pub struct Args {
    /// Experiment file (TOML); `--example` prints one. Omit it to run the thesis set-up.
    file: Option<PathBuf>,
    /// Output directory (default: a fresh runs/nams-N).
    #[arg(short, long = "output", alias = "out")]
    out: Option<PathBuf>,
    /// Replace the output directory if it exists.
    #[arg(long)]
    force: bool,
    /// Read an experiment file above coopnav's input size limit (coopnav_core::limits).
    #[arg(long)]
    allow_large: bool,
    /// Print the thesis experiment (every field at its default) as TOML and exit.
    #[arg(long)]
    example: bool,
}

/// Transmission-loss model of the experiment.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
enum TlChoice {
    /// Spreading + Thorp absorption with factor k.
    Analytic { k: f64 },
    /// A cached grid of real BELLHOP runs from one anchor (x, y, depth).
    BellhopGrid { anchor: [f64; 3], bearings: usize, range_step: f64, depth_step: f64 },
}

impl Default for TlChoice {
    fn default() -> Self {
        TlChoice::Analytic { k: 2.0 }
    }
}

#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub(crate) struct File {
    experiment: ExperimentConfig,
    tl: TlChoice,
}

fn provider(tl: &TlChoice, cfg: &ExperimentConfig) -> Result<Arc<dyn TransmissionLoss>> {
    Ok(match *tl {
        TlChoice::Analytic { k } => {
            anyhow::ensure!(k > 0.0 && k <= 4.0, "tl.k = {k} must be in (0, 4]");
            Arc::new(Thorp { k, ..Thorp::default() })
        }
        TlChoice::BellhopGrid { anchor, bearings, range_step, depth_step } => {
            let bathy = Arc::new(Bathymetry::shelf(&cfg.shelf)?);
            let max_depth = bathy.max_depth();
            let bh = Bellhop::new(AcousticEnv::nams(bathy))?;
            let spec = GridSpec {
                bearings,
                range_step,
                max_range: 1.5 * cfg.scenarios.iter().map(|s| s.square).fold(0.0, f64::max),
                depth_step,
                max_depth,
            };
            let pb = ProgressBar::new(bearings as u64).with_message("bellhop grid");
            let grid = CachedGrid::build(&bh, Vec3::new(anchor[0], anchor[1], anchor[2]), spec, &|k| pb.inc(k))?;
            pb.finish_and_clear();
            Arc::new(grid)
        }
    })
}

/// The thesis experiment as a commented TOML file.
pub(crate) fn example() -> Result<String> {
    Ok(format!(
        "# coopnav Nams rate-selection experiment for `coopnav nams FILE` (the thesis set-up).\n\
         # Every field is at its default and optional: keep only what you change (a scenario's\n\
         # missing fields are scenario 1's). The four scenarios are Table 6's\n\
         # (scenarios/experiments/nams-table-6.toml). Units and sources: the rustdoc of\n\
         # coopnav_sim::scenario::nams::ExperimentConfig (`cargo doc --open`).\n{}",
        toml::to_string_pretty(&File::default())?
    ))
}

/// Keys of an experiment file that have a new name (one name for a count of runs across coopnav).
const RENAMED: &[(&str, &str)] = &[("experiment.repetitions", "experiment.runs")];

/// Parses and validates an experiment file (`path` names it in errors).
pub(crate) fn parse_file(text: &str, path: &Path) -> Result<File> {
    let renamed = coopnav_sim::scenario::moved::moved_keys(text, RENAMED);
    if !renamed.is_empty() {
        let list: String = renamed.iter().map(|(old, new)| format!("\n  {old} -> {new}")).collect();
        anyhow::bail!("{}: renamed key(s), each with its new name:{list}", path.display());
    }
    let file: File = toml::from_str(text)
        .map_err(|e| anyhow::anyhow!(coopnav_core::validation::shortened(&e.to_string())))
        .with_context(|| format!("{}: invalid experiment file", path.display()))?;
    file.experiment.validate_file(path, "experiment")?;
    Ok(file)
}

pub fn run(args: Args) -> Result<()> {
    if args.example {
        print!("{}", example()?);
        return Ok(());
    }
    let file = match &args.file {
        Some(path) => {
            let text = input::read(path, args.allow_large)?;
            input::parsed_as(parse_file(&text, path), &text, path, input::Format::Nams)?
        }
        None => File::default(),
    };
    limits::check(work::nams(&file.experiment), args.allow_large)?;
    let tl = provider(&file.tl, &file.experiment)?;
    let inputs: Vec<&Path> = args.file.as_deref().into_iter().collect();
    let run = crate::run_dir::given_or_fresh(args.out.as_deref(), args.force, &inputs, "nams")?;
    let cfg = &file.experiment;
    let pb = ProgressBar::new((cfg.scenarios.len() * cfg.behaviours.len() * cfg.runs) as u64);
    let result = run_experiment(cfg, &ExperimentTl::Shared(tl), &|k| pb.inc(k))?;
    pb.finish_and_clear();
    println!("{:<14} {:<16} {:>9} {:>9} {:>6} {:>6}", "scenario", "behaviour", "BW B/s", "period s", "duty", "score");
    for c in &result.cells {
        println!(
            "{:<14} {:<16} {:>9.2} {:>9.1} {:>6.2} {:>6.3}",
            c.scenario, c.behaviour, c.mean.bandwidth, c.mean.status_period, c.mean.duty_cycle, c.mean.score
        );
    }
    #[derive(Serialize)]
    struct Row<'a> {
        scenario: &'a str,
        behaviour: &'a str,
        bandwidth: f64,
        bandwidth_net: f64,
        status_period: f64,
        duty_cycle: f64,
        score: f64,
        header_bytes: f64,
    }
    run.write_csv(
        "cells.csv",
        result.cells.iter().map(|c| Row {
            scenario: &c.scenario,
            behaviour: &c.behaviour,
            bandwidth: c.mean.bandwidth,
            bandwidth_net: c.mean.bandwidth_net,
            status_period: c.mean.status_period,
            duty_cycle: c.mean.duty_cycle,
            score: c.mean.score,
            header_bytes: c.mean.header_bytes_mean,
        }),
    )?;
    run.write_json("summary.json", &result)?;
    run.write_json("manifest.json", &Manifest::new("nams", Some(cfg.seed), serde_json::to_value(&file)?))?;
    eprintln!("wrote {}", run.finish()?.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use coopnav_acomms::selector::RatePolicySpec;

    #[test]
    fn the_example_loads_back_with_the_thesis_behaviours() {
        let file = parse_file(&example().unwrap(), Path::new("example.toml")).unwrap();
        assert_eq!(file.experiment.behaviours, RatePolicySpec::thesis());
        let old = "[experiment]\nbehaviours = [\"fixed_rate1\"]\n";
        let e = format!("{:#}", parse_file(old, Path::new("old.toml")).err().unwrap());
        assert!(e.contains("old.toml") && e.contains("behaviours"), "{e}");
    }
}
