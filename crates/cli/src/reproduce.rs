//! `coopnav reproduce <id>`: runs one thesis reproduction and prints it. Its exit status tells a
//! script the outcome: 0 every check passed, [`KNOWN_DEVIATIONS_ONLY`] (3) every failed check is
//! a documented known deviation, 1 some check failed without one (or the run itself failed).

use anyhow::{bail, Result};
use coopnav_sim::experiments::{self, Check, ReproOptions, Size};
use std::process::ExitCode;

/// Exit status when the only failed checks are documented known deviations.
pub const KNOWN_DEVIATIONS_ONLY: u8 = 3;

/// How a reproduction's checks came out.
#[derive(Debug, PartialEq)]
enum Outcome {
    AllPassed,
    KnownDeviationsOnly(usize),
    Unexplained(usize),
}

fn outcome(checks: &[Check]) -> Outcome {
    let failed = checks.iter().filter(|c| !c.passed).count();
    let unexplained = checks.iter().filter(|c| !c.acceptable()).count();
    match (failed, unexplained) {
        (0, _) => Outcome::AllPassed,
        (n, 0) => Outcome::KnownDeviationsOnly(n),
        (_, n) => Outcome::Unexplained(n),
    }
}

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
}

pub fn run(args: Args) -> Result<ExitCode> {
    if args.list {
        for e in experiments::registry() {
            println!("{:<32} {}", e.id, e.about);
        }
        return Ok(ExitCode::SUCCESS);
    }
    let id = args.id.unwrap_or_default();
    let opts = ReproOptions { size: if args.reduced { Size::Reduced } else { Size::Full }, seed: args.seed };
    let report = experiments::run(&id, &opts)?;
    println!("{}", report.table);
    for c in &report.checks {
        println!("{}", c.line());
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    }
    match outcome(&report.checks) {
        Outcome::AllPassed => Ok(ExitCode::SUCCESS),
        Outcome::KnownDeviationsOnly(n) => {
            eprintln!(
                "{}: {n} check(s) failed, each a documented known deviation (exit {KNOWN_DEVIATIONS_ONLY})",
                report.id
            );
            Ok(ExitCode::from(KNOWN_DEVIATIONS_ONLY))
        }
        Outcome::Unexplained(n) => {
            bail!("{}: {n} property check(s) failed without a documented reason; see above", report.id)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exit_outcome_separates_known_deviations_from_unexplained_failures() {
        let pass = Check::new("a", true, "");
        let known = Check::new("b", false, "").known_deviation("measured reason");
        let bad = Check::new("c", false, "");
        assert_eq!(outcome(&[pass.clone()]), Outcome::AllPassed);
        assert_eq!(outcome(&[pass.clone(), pass.clone().known_deviation("unused")]), Outcome::AllPassed);
        assert_eq!(outcome(&[pass.clone(), known.clone()]), Outcome::KnownDeviationsOnly(1));
        assert_eq!(outcome(&[pass, known, bad]), Outcome::Unexplained(1));
    }
}
