//! `coopnav reproduce <id>`: runs one thesis reproduction and prints it. Its exit status tells a
//! script the outcome: 0 no check and no thesis table failed (undecided ones do not fail),
//! [`CAUSES_MEASURED`] (3) every failed check or table has its measured cause printed, 1 some
//! check or table failed without one (or the run itself failed).

use anyhow::{bail, Context, Result};
use coopnav_sim::experiments::{self, generalization, Outcome, ReproOptions, ReproReport, Size};
use coopnav_sim::output::{check_replaceable, write_file, Manifest, RunDir};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

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
    /// Print the report as JSON (report.json's content) on stdout in place of the table.
    #[arg(long)]
    json: bool,
    /// Also write the table, the numbers (report.json) and the plots to this directory.
    /// closed-loop-generalization writes each mission's runs there as it goes
    /// (missions/NNN.cbor), and a rerun with the same directory resumes the study.
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
    let size = if args.reduced { Size::Reduced } else { Size::Full };
    if id == generalization::ID {
        if let Some(out) = &args.out {
            return study(&id, size, args.seed, out, args.force, args.json);
        }
    }
    // Refuse a bad output directory before the work, not after it.
    let dir = args.out.as_ref().map(|p| RunDir::create(p, args.force)).transpose()?;
    let bar = spinner(&id)?;
    let finished = AtomicU64::new(0);
    let tell = |_: u64| {
        let n = finished.fetch_add(1, Ordering::Relaxed) + 1;
        bar.set_message(format!("{n} simulation runs finished"));
    };
    let opts = ReproOptions { size, seed: args.seed, progress: &tell };
    let report = experiments::run(&id, &opts);
    bar.finish_and_clear();
    let report = report?;
    let text = printed(&report, args.json)?;
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
    exit(&report)
}

/// Prints the report (with `json`, as JSON in place of the table) and returns the table:
/// what `table.txt` holds.
fn printed(report: &ReproReport, json: bool) -> Result<String> {
    let text = report.printed();
    if json {
        println!("{}", serde_json::to_string_pretty(report)?);
    } else {
        println!("{text}");
    }
    Ok(text)
}

/// The exit status the report's checks and thesis tables call for.
fn exit(report: &ReproReport) -> Result<ExitCode> {
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

/// A study that writes its output directory as it goes ([`generalization::run_in`]): each
/// mission's runs land in `out/missions/` as soon as the mission finishes, a rerun with the same
/// `out` resumes where the last one stopped (`--force` starts over), and the table, report and
/// plots are written beside them at the end. Progress goes to stderr: the spinner on a terminal,
/// otherwise a line at most every [`PROGRESS_EVERY`].
fn study(id: &str, size: Size, seed: u64, out: &Path, force: bool, json: bool) -> Result<ExitCode> {
    if force && out.exists() {
        check_replaceable(out)?;
        std::fs::remove_dir_all(out).with_context(|| format!("cannot remove {}", out.display()))?;
    }
    let bar = spinner(id)?;
    let lines = !std::io::stderr().is_terminal();
    let started = Instant::now();
    let last_line: Mutex<Option<Instant>> = Mutex::new(None);
    let tell = |s: generalization::Status| {
        let text = status_line(&s, started.elapsed());
        if lines {
            let mut last = last_line.lock().unwrap_or_else(|p| p.into_inner());
            let finished = s.missions_done == s.missions_total;
            if finished || last.map_or(true, |t| t.elapsed() >= PROGRESS_EVERY) {
                eprintln!("{id}: {text}");
                *last = Some(Instant::now());
            }
        } else {
            bar.set_message(text);
        }
    };
    let opts = ReproOptions { size, seed, progress: &|_| {} };
    let report = generalization::run_in(&opts, out, &tell);
    bar.finish_and_clear();
    let report = report?;
    let text = printed(&report, json)?;
    let write = |name: &str, bytes: &[u8]| write_file(&out.join(name), bytes, true, |_| true, &[]);
    write("table.txt", text.as_bytes())?;
    write("report.json", (serde_json::to_string_pretty(&report)? + "\n").as_bytes())?;
    for (name, svg) in &report.plots {
        write(name, svg.as_bytes())?;
    }
    eprintln!("wrote {}", out.display());
    exit(&report)
}

/// How often, at most, a study off a terminal prints its progress line.
const PROGRESS_EVERY: Duration = Duration::from_secs(10);

/// `missions 12/200 (3 read back), runs 990/20570, elapsed 0:12:31, ETA 3:50:02`.
fn status_line(s: &generalization::Status, elapsed: Duration) -> String {
    let hms = |d: f64| {
        let t = d.max(0.0).round() as u64;
        format!("{}:{:02}:{:02}", t / 3600, t / 60 % 60, t % 60)
    };
    let eta = if s.runs_done == 0 {
        if s.runs_total == 0 {
            hms(0.0)
        } else {
            "unknown".to_string()
        }
    } else {
        hms(elapsed.as_secs_f64() * (s.runs_total - s.runs_done) as f64 / s.runs_done as f64)
    };
    format!(
        "missions {}/{} ({} read back), runs {}/{}, elapsed {}, ETA {eta}",
        s.missions_done,
        s.missions_total,
        s.missions_resumed,
        s.runs_done,
        s.runs_total,
        hms(elapsed.as_secs_f64())
    )
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
