//! `coopnav sweep`: a study of many missions from one sweep file, run in shards anywhere.
//! `--example` prints a sweep file; `plan FILE --shards N -o DIR` checks it and writes the plan;
//! `run DIR --shard I` (or `--all`) runs shards; `merge DIR` writes the comparison and the tables;
//! `status DIR` says where each shard stands; `slurm DIR` writes the batch scripts for a cluster. The work is in the `coopnav-sweep` crate.

use crate::input;
use anyhow::{bail, Context, Result};
use coopnav_sweep::expand::Form;
use coopnav_sweep::plan::{plan_form, Plan};
use coopnav_sweep::slurm::{write_scripts, SlurmSpec};
use coopnav_sweep::{merge, shard, status};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Args {
    /// Print an example sweep file (scenarios/sweeps/fleet-size.toml) and exit.
    #[arg(long)]
    example: bool,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(clap::Subcommand)]
pub enum Command {
    /// Check a sweep file whole and write its plan: manifest, one scenario per cell, N shard files.
    Plan {
        /// The sweep file (TOML; `coopnav sweep --example` prints one).
        file: PathBuf,
        /// Shards to split the runs into (one per process or Slurm task).
        #[arg(long, default_value_t = 1)]
        shards: usize,
        /// The plan directory.
        #[arg(short, long)]
        output: PathBuf,
        /// Replace the output directory if it exists.
        #[arg(long)]
        force: bool,
        /// Plan even when the estimated work is above coopnav's limits (coopnav_core::limits).
        #[arg(long)]
        allow_large: bool,
        /// Plan the sweep file's reduced form (its [reduced] table: fewer runs and cells).
        #[arg(long)]
        reduced: bool,
    },
    /// Run shards of a plan (restartable: finished runs are skipped, an interrupted shard resumes).
    Run {
        dir: PathBuf,
        /// The shards to run, comma-separated.
        #[arg(long, value_delimiter = ',', required_unless_present = "all", conflicts_with = "all")]
        shard: Vec<usize>,
        /// Every shard, in this one process.
        #[arg(long)]
        all: bool,
    },
    /// Join the finished shards: comparison table, JSON, plots, Parquet and CSV tables.
    Merge {
        dir: PathBuf,
        /// Output directory (default: DIR/merged).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Replace the output directory if it exists.
        #[arg(long)]
        force: bool,
    },
    /// Which shards are done, failed, running, interrupted or missing.
    Status { dir: PathBuf },
    /// Write DIR/slurm/: an `sbatch --array` script (one task per shard), the merge's script and
    /// submit.sh, which submits both (the merge once every shard has succeeded).
    Slurm {
        dir: PathBuf,
        /// The coopnav binary the tasks run (default: this one).
        #[arg(long)]
        coopnav: Option<PathBuf>,
        /// CPUs per shard task.
        #[arg(long, default_value_t = 1)]
        cpus_per_task: usize,
        /// Slurm partition.
        #[arg(long)]
        partition: Option<String>,
        /// Wall-time limit per task (Slurm's notation, e.g. 2:00:00).
        #[arg(long)]
        time: Option<String>,
        /// A further #SBATCH option for both scripts (repeatable), e.g. --sbatch=--account=lab.
        #[arg(long = "sbatch", allow_hyphen_values = true)]
        extra: Vec<String>,
        /// Replace scripts coopnav wrote before.
        #[arg(long)]
        force: bool,
    },
}

fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

pub fn run(args: Args) -> Result<()> {
    let Some(command) = args.command else {
        if args.example {
            print!("{}", coopnav_sweep::file::EXAMPLE);
            return Ok(());
        }
        bail!("give a sweep command (plan, run, merge, status, slurm) or --example; see `coopnav sweep --help`");
    };
    match command {
        Command::Plan { file, shards, output, force, allow_large, reduced } => {
            let text = input::read(&file, allow_large)?;
            let form = if reduced { Form::Reduced } else { Form::Full };
            let planned = plan_form(&file, &text, form, shards, &output, force, allow_large, &command_line());
            let (dir, e) = input::parsed_as(planned, &text, &file, input::Format::Sweep)?;
            let runs = e.cells.len() * e.policies.len() * e.runs;
            println!(
                "{} cells x {} policies x {} runs = {runs} runs in {shards} shards -> {}",
                e.cells.len(),
                e.policies.len(),
                e.runs,
                dir.display()
            );
        }
        Command::Run { dir, shard, all } => {
            let plan = Plan::open(&dir)?;
            let shards: Vec<usize> = if all { (0..plan.inputs.shards).collect() } else { shard };
            let total = shard::pending_runs(&plan, &shards)?;
            let bar = if std::io::stderr().is_terminal() { ProgressBar::new(total) } else { ProgressBar::hidden() };
            bar.set_style(ProgressStyle::with_template(
                "{bar:40} {pos}/{len} runs [{elapsed_precise} < {eta_precise}]",
            )?);
            let reports = shard::run_shards(&plan, &shards, &|done| bar.set_position(done))?;
            bar.finish_and_clear();
            for r in reports {
                println!(
                    "shard {}: {} runs now, {} finished before, {} failed -> {}",
                    r.shard,
                    r.ran,
                    r.skipped,
                    r.failed,
                    shard::finished_path(&plan, r.shard).display()
                );
            }
        }
        Command::Merge { dir, output, force } => {
            let plan = Plan::open(&dir)?;
            let m = merge::merge(&plan, output.as_deref(), force, &command_line())?;
            match &m.report {
                // The table `coopnav reproduce` prints for the reproduction the sweep file holds.
                Some(report) => println!("{}", report.printed()),
                None => print!("{}", m.table),
            }
            println!("wrote {}", m.dir.display());
            if !m.failures.is_empty() {
                for f in &m.failures {
                    eprintln!("failed: run {} (cell {}, {} run {}): {}", f.run_id, f.cell, f.policy, f.run, f.error);
                }
                bail!(
                    "{} runs failed; their cells have no comparison (listed in {})",
                    m.failures.len(),
                    m.dir.join("failures.csv").display()
                );
            }
        }
        Command::Status { dir } => {
            let plan = Plan::open(&dir)?;
            print!("{}", status::status_table(&status::status(&plan)?));
        }
        Command::Slurm { dir, coopnav, cpus_per_task, partition, time, extra, force } => {
            let plan = Plan::open(&dir)?;
            let coopnav = match coopnav {
                Some(p) => std::fs::canonicalize(&p).with_context(|| format!("--coopnav {}", p.display()))?,
                None => std::env::current_exe()?,
            };
            let spec = SlurmSpec { coopnav, cpus_per_task, partition, time, extra };
            let submit = write_scripts(&plan, &spec, force)?;
            println!("wrote {}; submit with: bash {}", submit.parent().unwrap_or(&dir).display(), submit.display());
        }
    }
    Ok(())
}
