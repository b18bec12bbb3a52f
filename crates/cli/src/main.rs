//! The `coopnav` binary: parses arguments and calls the library crates. Nothing here computes.

use anyhow::Result;
use clap::{Parser, Subcommand};

mod bench;
mod bench_acomms;
mod channel;
mod reproduce;

#[derive(Parser)]
#[command(name = "coopnav", version, about = "Cooperative navigation of AUV teams: CNA path planning, OWTT navigation, adaptive acoustic links")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Reproduce a thesis table: prints our numbers beside the thesis's, with property checks.
    Reproduce(reproduce::Args),
    /// Transmission loss and packet-success likelihood per WHOI rate against range (table + SVG).
    Channel(channel::Args),
    /// Timing runs that print JSON.
    Bench {
        #[command(subcommand)]
        target: bench::Target,
    },
}

fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
        .with_writer(std::io::stderr)
        .init();
    match Cli::parse().command {
        Command::Reproduce(args) => reproduce::run(args),
        Command::Channel(args) => channel::run(args),
        Command::Bench { target } => bench::run(target),
    }
}
