//! `coopnav reproduce <id>`: runs one thesis reproduction and prints it. Its exit status tells a
//! script the outcome: 0 no check and no thesis table failed (undecided ones do not fail),
//! [`CAUSES_MEASURED`] (3) every failed check or table has its measured cause printed, 1 some
//! check or table failed without one (or the run itself failed).

use anyhow::{bail, Result};
use coopnav_sim::experiments::{self, Outcome, ReproOptions, Size};
use coopnav_sim::output::{Manifest, RunDir};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// Exit status when every failed check or table has its measured cause printed.
pub const CAUSES_MEASURED: u8 = 3;

#[derive(clap::Args)]
pub struct Args {
    /// Experiment id (see --list).
    #[arg(required_unless_present = "list")]
    id: Option<String>,
    /// List the available experiments.
    #[arg(long)]
    list: bool,
    /// Run the reduced (CI) form instead of the thesis's full set-up.
    #[arg(long)]
    reduced: bool,
    /// Base seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also print the numbers as JSON.
    #[arg(long)]
    json: bool,
    /// Also write the table, the numbers (report.json) and the plots to this directory.
    #[arg(short, long = "output", alias = "out")]
    out: Option<PathBuf>,
    /// Replace an existing output directory.
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    if args.list {
        for e in experiments::registry() {
            println!("{:<32} {}", e.id, e.about);
        }
        return Ok(ExitCode::SUCCESS);
    }
    let id = args.id.unwrap_or_default();
    // Refuse a bad output directory before the work, not after it.
    let dir = args.out.as_ref().map(|p| RunDir::create(p, args.force)).transpose()?;
    let bar = spinner(&id)?;
    let finished = AtomicU64::new(0);
    let tell = |_: u64| {
        let n = finished.fetch_add(1, Ordering::Relaxed) + 1;
        bar.set_message(format!("{n} simulation runs finished"));
    };
    let size = if args.reduced { Size::Reduced } else { Size::Full };
    let opts = ReproOptions { size, seed: args.seed, progress: &tell };
    let report = experiments::run(&id, &opts);
    bar.finish_and_clear();
    let report = report?;
    let text = report.printed();
    println!("{text}");
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    }
    if let Some(dir) = dir {
        dir.write_text("table.txt", &text)?;
        dir.write_json("report.json", &report)?;
        for (name, svg) in &report.plots {
            dir.write_text(name, svg)?;
        }
        let inputs = serde_json::json!({ "id": id, "reduced": args.reduced, "seed": args.seed });
        dir.write_json("manifest.json", &Manifest::new("reproduce", Some(args.seed), inputs))?;
        eprintln!("wrote {}", dir.finish()?.display());
    }
    match report.outcome() {
        Outcome::NoFailure => Ok(ExitCode::SUCCESS),
        Outcome::CausesMeasured(n) => {
            eprintln!(
                "{}: {n} check(s) or table(s) failed, each with its measured cause printed (exit {CAUSES_MEASURED})",
                report.id
            );
            Ok(ExitCode::from(CAUSES_MEASURED))
        }
        Outcome::Unexplained(n) => {
            bail!("{}: {n} check(s) or thesis table(s) failed without a measured cause; see above", report.id)
        }
    }
}

/// On a terminal, a line on stderr that shows the reproduction running: its id, the time it has
/// taken and the simulation runs it has finished (nothing where stderr is not a terminal).
fn spinner(id: &str) -> Result<ProgressBar> {
    if !std::io::stderr().is_terminal() {
        return Ok(ProgressBar::hidden());
    }
    let bar = ProgressBar::new_spinner().with_message("starting");
    bar.set_style(ProgressStyle::with_template(&format!("{{spinner}} {id} [{{elapsed_precise}}] {{msg}}"))?);
    bar.enable_steady_tick(Duration::from_millis(200));
    Ok(bar)
}
