//! `coopnav bench <target>`: timing runs that print JSON (wall-clock figures on this machine;
//! compare ratios, not absolutes).

use anyhow::Result;
use clap::Subcommand;

#[derive(Subcommand)]
pub enum Target {
    /// The acoustic link: the full Nams experiment (4 scenarios × 4 behaviours × 40 runs) on the
    /// analytic TL and on a cached TL grid, tracker encode/decode throughput, and one BELLHOP run
    /// against a cached-grid lookup.
    Acomms(crate::bench_acomms::Args),
}

pub fn run(target: Target) -> Result<()> {
    match target {
        Target::Acomms(args) => crate::bench_acomms::run(args),
    }
}
