//! The `coopnav` binary: parses arguments and calls the library crates. Nothing here computes.

use anyhow::Result;
use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod advise;
mod alog_import;
mod bench;
mod channel;
#[cfg(test)]
mod fuzz;
mod generate;
mod hbl;
mod input;
mod live;
mod nams;
mod plan;
mod post_report;
mod reproduce;
mod run_dir;
mod scenario_args;
mod simulate;
mod sitl;
mod sweep;
mod view;

#[derive(Parser)]
#[command(
    name = "coopnav",
    version,
    about = "Cooperative navigation of AUV teams: CNA path planning, OWTT navigation, adaptive acoustic links"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Reproduce a thesis table: prints our numbers beside the thesis's, with property checks.
    Reproduce(reproduce::Args),
    /// Pre-deployment CNA path planning of a whole mission (no scenario: the embedded example).
    Plan(plan::Args),
    /// Hybrid-baseline (Gill) navigation: simulate, Monte Carlo, buoy grid, tuning, post-processing.
    #[command(subcommand)]
    Hbl(hbl::Command),
    /// Transmission loss and packet-success likelihood per WHOI rate against range (table + SVG).
    Channel(channel::Args),
    /// Run a Nams adaptive-rate experiment from a TOML file (scenarios × behaviours × runs).
    Nams(nams::Args),
    /// Write the missions a generator file draws, one scenario file each (for `simulate`).
    Generate(generate::Args),
    /// Closed-loop mission: CNA policy, survey-AUV OWTT filters and the acoustic link together
    /// (no scenario: the embedded default mission; --runs: Monte Carlo comparison of policies).
    Simulate(simulate::Args),
    /// Before going to sea: the Monte Carlo over candidate CNA policies, cycles and status rates,
    /// written as one page with the recommendation, an error map and the MOOS files to fly.
    Advise(advise::Args),
    /// Software in the loop: the closed-loop mission with the CNA's planner as a `live cna` child
    /// process on LCM (--lockstep: the same results as `simulate` with the same seed).
    Sitl(sitl::Args),
    /// Sweeps of many missions from one file, in shards (one process, many, or a Slurm array).
    Sweep(sweep::Args),
    /// Write a run directory's interactive replay.html (time slider, tracks, pulses, errors).
    View(view::Args),
    /// Benchmarks, printed as JSON.
    #[command(subcommand)]
    Bench(bench::Target),
    /// Live processes on LCM for a vehicle's backseat (`live auv`: a survey AUV's navigator;
    /// `live cna`: the CNA's planner).
    #[command(subcommand)]
    Live(live::Command),
}

/// Errors print as one chain of causes ("what: why: detail"), never a backtrace: a failed
/// check or a bad file is the user's business, not a crash.
fn main() -> ExitCode {
    match run() {
        Ok(code) => code,
        Err(e) => {
            eprintln!("Error: {}", cause_chain(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by ": ", each text once: a library error whose message
/// already ends with its source's text (thiserror's `"...: {0}"` beside `#[from]`) would
/// otherwise print that text twice.
fn cause_chain(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if line.ends_with(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

/// Exit status of a run stopped by Ctrl-C or SIGTERM (128 + SIGINT, as shells report it).
const INTERRUPTED: i32 = 130;

/// Runs the command; `reproduce` chooses its own exit status (see its module).
fn run() -> Result<ExitCode> {
    let command = Cli::parse().command;
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .init();
    // A live process stops cleanly on SIGINT/SIGTERM (it installs its own handler).
    if let Command::Live(cmd) = command {
        return live::run(cmd).map(|()| ExitCode::SUCCESS);
    }
    // An interrupted run must not leave its half-written staging directory behind.
    ctrlc::set_handler(|| {
        coopnav_sim::output::remove_unfinished_runs();
        eprintln!("Interrupted: the unfinished run directory was removed");
        std::process::exit(INTERRUPTED);
    })?;
    let done = match command {
        Command::Reproduce(args) => return reproduce::run(args),
        Command::Plan(args) => plan::run(args),
        Command::Hbl(cmd) => hbl::run_command(cmd),
        Command::Channel(args) => channel::run(args),
        Command::Nams(args) => nams::run(args),
        Command::Generate(args) => generate::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::Advise(args) => advise::run(args),
        Command::Sitl(args) => sitl::run(args),
        Command::Sweep(args) => sweep::run(args),
        Command::View(args) => view::run(args),
        Command::Bench(target) => bench::run(target),
        Command::Live(_) => unreachable!("handled above"),
    };
    done.map(|()| ExitCode::SUCCESS)
}
