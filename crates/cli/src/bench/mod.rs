//! `coopnav bench <target>`: speed measurements printed as JSON (one target per crate), one file
//! per target.

use anyhow::Result;
use clap::Subcommand;

mod acomms;
mod closed_loop;
mod generated;
mod hbl;
mod planner;
mod post;

#[derive(Subcommand)]
pub enum Target {
    /// One planner decision on the standard workloads: branch-and-bound (1 thread and rayon) vs
    /// brute force, with node counts and AUV-updates per second.
    Planner(planner::Args),
    /// The Table 5 Monte Carlo (Δt = 0.1 s) for MSBL, HBL One and HBL Two.
    Hbl(hbl::Args),
    /// The acoustic link: the full Nams experiment (4 scenarios × 4 behaviours × 40 runs) on the
    /// analytic TL and on a cached TL grid, tracker encode/decode throughput, and one BELLHOP run
    /// against a cached-grid lookup.
    Acomms(acomms::Args),
    /// The closed loop: 3 h mission, 5 survey AUVs, τ = 30 s, planner A = 5, L = 5, 10 Hz EKFs;
    /// wall time against the ≤ 0.22 s target (5×10⁴ × real time), split by engine phase.
    ClosedLoop(closed_loop::Args),
    /// Missions of the generalization study's generator file, one run per CNA policy as the
    /// study flies it: CPU and wall seconds per mission-hour per policy.
    GeneratedMission(generated::Args),
    /// Post-processing (EKF + RTS) of a generated 24 h, 10 Hz, 5-beacon field log (targets:
    /// ≤ 10 s, ≤ 500 MB under `/usr/bin/time -v`); `--tune` times the tuning too (≤ 2 min).
    Post(post::Args),
}

pub fn run(target: Target) -> Result<()> {
    match target {
        Target::Planner(args) => planner::run(args),
        Target::Hbl(args) => hbl::run(args),
        Target::Acomms(args) => acomms::run(args),
        Target::ClosedLoop(args) => closed_loop::run(args),
        Target::GeneratedMission(args) => generated::run(args),
        Target::Post(args) => post::run(args),
    }
}
