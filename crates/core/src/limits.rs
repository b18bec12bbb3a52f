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
        write!(f, "{} ≈ {:.3e} from {} (limit {:e})", self.what, self.value, self.fields, self.limit)
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

/// An input file (bytes) that holds a table: a track, a bathymetry grid, a field log (100 MB).
pub const MAX_TABLE_FILE_BYTES: f64 = 1e8;

/// Why an input could not be read.
#[derive(Debug, Error)]
pub enum InputError {
    #[error("cannot read {path}: {source}")]
    Io { path: std::path::PathBuf, source: std::io::Error },
    #[error("{path} is not UTF-8 text: {source}")]
    NotText { path: std::path::PathBuf, source: std::string::FromUtf8Error },
    #[error(transparent)]
    TooLarge(#[from] TooLarge),
}

/// The bytes of `path`, read through one bounded reader: at most `limit` bytes (one more tells a
/// larger input), so a pipe, a device or a file that grows is bounded as a regular file is, and
/// nothing is sized from metadata. A larger input is refused as [`TooLarge`] naming `what` and
/// the path, unless `allow_large` (then it is read whole).
pub fn read_bounded(
    path: &std::path::Path,
    what: &'static str,
    limit: f64,
    allow_large: bool,
) -> Result<Vec<u8>, InputError> {
    use std::io::Read;
    let io = |source| InputError::Io { path: path.to_path_buf(), source };
    let mut file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    if allow_large {
        file.read_to_end(&mut bytes).map_err(io)?;
        return Ok(bytes);
    }
    let cap = limit.max(0.0).min(u64::MAX as f64 / 2.0) as u64;
    file.by_ref().take(cap + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > cap {
        let over =
            Estimate::new(what, format!("{} (more than the limit read)", path.display()), bytes.len() as f64, limit);
        return Err(TooLarge(vec![over]).into());
    }
    Ok(bytes)
}

/// [`read_bounded`] as UTF-8 text.
pub fn read_text(
    path: &std::path::Path,
    what: &'static str,
    limit: f64,
    allow_large: bool,
) -> Result<String, InputError> {
    let bytes = read_bounded(path, what, limit, allow_large)?;
    String::from_utf8(bytes).map_err(|source| InputError::NotText { path: path.to_path_buf(), source })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A regular file, a pipe-like endless device and a file at the limit: only what fits is read.
    #[test]
    fn inputs_are_read_through_one_bounded_reader() {
        let tmp = std::env::temp_dir().join(format!("coopnav-limits-{}", std::process::id()));
        std::fs::write(&tmp, b"0123456789").unwrap();
        assert_eq!(read_bounded(&tmp, "input file (bytes)", 10.0, false).unwrap(), b"0123456789");
        let e = read_bounded(&tmp, "input file (bytes)", 9.0, false).unwrap_err().to_string();
        assert!(e.contains("input file (bytes)") && e.contains("--allow-large"), "{e}");
        assert_eq!(read_bounded(&tmp, "input file (bytes)", 9.0, true).unwrap().len(), 10);
        std::fs::write(&tmp, [0xff, 0xfe]).unwrap();
        assert!(matches!(read_text(&tmp, "input", 10.0, false), Err(InputError::NotText { .. })));
        std::fs::remove_file(&tmp).unwrap();
        // An endless input stops at the limit instead of filling memory.
        let e = read_bounded(std::path::Path::new("/dev/zero"), "input file (bytes)", 1e6, false).unwrap_err();
        assert!(matches!(e, InputError::TooLarge(_)), "{e}");
    }

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
