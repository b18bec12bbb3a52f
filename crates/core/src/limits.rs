//! Bounded work: sizes derived from input (simulated steps, planner leaves, grid cells, table
//! points, bytes) are estimated before anything is allocated or run, and checked against the
//! documented limits below. A run above a limit is refused with one message naming, for each
//! size, the input fields it comes from, the estimate and the limit, and the flag that lifts
//! them (`--allow-large`): a typo such as `dt = 1e-9` fails in milliseconds instead of aborting
//! on a failed allocation of many gigabytes after minutes.
//!
//! The limits are about ten times the largest set-ups the theses and benchmarks use, so every
//! documented run passes; they are work budgets, not physical bounds.

use thiserror::Error;

/// Vehicle-steps simulated by one command (steps × vehicles × runs): ≈ 10 min of CPU.
pub const MAX_VEHICLE_STEPS: f64 = 2e9;
/// Leaves of one planner decision's search tree (options^look-ahead).
pub const MAX_PLANNER_LEAVES: f64 = 1e7;
/// Planner work of one command: decisions × leaves × survey AUVs.
pub const MAX_PLANNER_UPDATES: f64 = 1e13;
/// Points of one computed table or grid (ranges, grid cells, track samples).
pub const MAX_POINTS: f64 = 1e7;
/// Memory held at once by one command, bytes (1 GB).
pub const MAX_BYTES: f64 = 1e9;
/// An input file (scenario, config), bytes (1 MB): larger files are read only on request.
pub const MAX_INPUT_FILE_BYTES: f64 = 1e6;

/// The flag that lifts every limit.
pub const ALLOW_LARGE_FLAG: &str = "--allow-large";

/// One size estimated from input: what it counts, the fields it comes from, its value and limit.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    pub what: &'static str,
    pub fields: String,
    pub value: f64,
    pub limit: f64,
}

impl Estimate {
    pub fn new(what: &'static str, fields: impl Into<String>, value: f64, limit: f64) -> Self {
        Estimate { what, fields: fields.into(), value, limit }
    }

    /// Above its limit; an infinite estimate (an overflowing product) is too. A NaN comes from
    /// an invalid field, which validation names better: it is not refused here.
    pub fn exceeded(&self) -> bool {
        self.value > self.limit
    }
}

impl std::fmt::Display for Estimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} ≈ {:.3e} from {} (limit {:.0e})", self.what, self.value, self.fields, self.limit)
    }
}

/// Every size above its limit, reported at once.
#[derive(Debug, Error)]
#[error("too large to run: {}; pass {ALLOW_LARGE_FLAG} to run it anyway", list(.0))]
pub struct TooLarge(pub Vec<Estimate>);

fn list(estimates: &[Estimate]) -> String {
    estimates.iter().map(Estimate::to_string).collect::<Vec<_>>().join("; ")
}

/// Refuses the estimates above their limits, unless `allow_large`.
pub fn check(estimates: impl IntoIterator<Item = Estimate>, allow_large: bool) -> Result<(), TooLarge> {
    let over: Vec<Estimate> = estimates.into_iter().filter(Estimate::exceeded).collect();
    if over.is_empty() || allow_large {
        Ok(())
    } else {
        Err(TooLarge(over))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_sizes_above_their_limit_are_refused_and_all_are_named() {
        let ok = Estimate::new("steps", "dt", 10.0, 100.0);
        let big = Estimate::new("steps", "duration_s, dt", 1e12, 100.0);
        let overflow = Estimate::new("leaves", "heading_options, look_ahead", f64::INFINITY, 1e7);
        let nan = Estimate::new("points", "spacing", f64::NAN, 1e7);
        assert!(check([ok.clone(), nan.clone()], false).is_ok());
        let e = check([ok, big, overflow, nan], false).unwrap_err();
        assert_eq!(e.0.len(), 2);
        let text = e.to_string();
        assert!(
            text.contains("duration_s, dt") && text.contains("1.000e12") && text.contains("--allow-large"),
            "{text}"
        );
        assert!(text.contains("heading_options, look_ahead") && !text.contains("spacing"), "{text}");
    }

    #[test]
    fn allow_large_lifts_every_limit() {
        assert!(check([Estimate::new("steps", "dt", 1e30, 1.0)], true).is_ok());
    }
}
