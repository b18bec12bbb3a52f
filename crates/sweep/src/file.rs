//! The sweep file (TOML, `deny_unknown_fields`): base closed-loop scenario files, the policies
//! every cell compares, the runs per policy, the axes and the named overlays. Read here; checked
//! and expanded by [`crate::expand`]. `scenarios/sweeps/fleet-size.toml` is the documented
//! example (`coopnav sweep --example`).

use crate::error::SweepError;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The example sweep file `coopnav sweep --example` prints.
pub const EXAMPLE: &str = include_str!("../../../scenarios/sweeps/fleet-size.toml");

/// The name a sweep file uses for the embedded default mission instead of a scenario file.
pub const EMBEDDED: &str = "default";

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Closed-loop scenario files, relative to the sweep file (or [`EMBEDDED`]).
    pub scenarios: Vec<String>,
    /// CNA policies compared in every cell; the first is the paired reference.
    pub policies: Vec<String>,
    /// Runs per policy and cell.
    pub runs: usize,
    /// The axes (`[[axis]]`), expanded in file order, the last changing fastest.
    #[serde(default, rename = "axis")]
    pub axes: Vec<Axis>,
    /// Named overlays (`[overlay.NAME]`): tables merged over the scenario.
    #[serde(default, rename = "overlay")]
    pub overlays: BTreeMap<String, toml::Table>,
}

/// One axis: a scenario field and its values, or a choice among overlays.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Axis {
    /// A scenario field by its path of tables and keys (`comms.tau`, `fleet.n_auvs`, `seed`).
    pub path: Option<String>,
    pub values: Option<Vec<toml::Value>>,
    /// Names of `[overlay.NAME]` tables, one per value of the axis.
    pub overlays: Option<Vec<String>>,
}

impl SweepFile {
    /// Parses the text of sweep `file`.
    pub fn parse(text: &str, file: &Path) -> Result<Self, SweepError> {
        toml::from_str(text).map_err(|e| SweepError::Invalid {
            file: file.to_path_buf(),
            problems: vec![e.message().to_string() + &location(text, &e)],
        })
    }
}

/// Where in `text` a TOML error is, as " (line L)".
fn location(text: &str, e: &toml::de::Error) -> String {
    e.span().map_or(String::new(), |span| format!(" (line {})", text[..span.start].matches('\n').count() + 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_example_parses_and_an_unknown_key_is_named_with_its_line() {
        let f = SweepFile::parse(EXAMPLE, Path::new("example.toml")).unwrap();
        assert_eq!(f.policies[0], "planner-estimator");
        assert_eq!(f.axes.len(), 2);
        let e = SweepFile::parse("scenarios = []\npolicies = []\nruns = 1\nrunz = 2\n", Path::new("s.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("sweep file s.toml: unknown field `runz`") && e.ends_with("(line 4)"), "{e}");
    }
}
