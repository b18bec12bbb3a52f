//! The sweep file (TOML, `deny_unknown_fields`): base closed-loop scenario files, the policies
//! every cell compares, the runs per policy, the axes, the named overlays, the overlays applied
//! where a cell's axis values meet a condition, and the reduced form. Read here; checked and
//! expanded by [`super::expand`]. `scenarios/sweeps/fleet-size.toml` is the documented example
//! (`coopnav sweep --example`); `scenarios/experiments/closed-loop-vs-baselines.toml` uses the
//! per-scenario values, a conditional overlay and the reduced form.

use super::SweepFileError;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The example sweep file `coopnav sweep --example` prints.
pub const EXAMPLE: &str = include_str!("../../../../../scenarios/sweeps/fleet-size.toml");

/// The name a sweep file uses for the embedded default mission instead of a scenario file.
pub const EMBEDDED: &str = "default";

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    /// Closed-loop scenario files, relative to the sweep file (or [`EMBEDDED`]), each named by
    /// its file; `[[scenario]]` ([`SweepFile::bases`]) is the long form. Give one of the two.
    #[serde(default)]
    pub scenarios: Vec<String>,
    /// Base scenarios with a name and their own values of some axes (`[[scenario]]`).
    #[serde(default, rename = "scenario", skip_serializing_if = "Vec::is_empty")]
    pub bases: Vec<Base>,
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
    /// Overlays merged over the cells whose axis values meet a condition (`[[conditional]]`),
    /// after the axes, in file order.
    #[serde(default, rename = "conditional", skip_serializing_if = "Vec::is_empty")]
    pub conditionals: Vec<Conditional>,
    /// A reproduction (`coopnav reproduce --list`) whose cells this file holds: `coopnav sweep
    /// merge` also writes its report from the merged runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub report: Option<String>,
    /// The reduced form (`coopnav sweep plan --reduced`, a reproduction's `--reduced`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reduced: Option<Reduced>,
}

/// One axis: a scenario field and its values, or a choice among overlays.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Axis {
    /// The axis's name in labels, tables, `values.NAME` and `when` (default: its path, or
    /// `overlay`, `overlay2`, ... for overlay axes).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A scenario field by its path of tables and keys (`comms.tau`, `fleet.n_auvs`, `seed`).
    pub path: Option<String>,
    /// Its values; may be left out when every `[[scenario]]` gives its own (`values.NAME`).
    pub values: Option<Vec<toml::Value>>,
    /// Names of `[overlay.NAME]` tables, one per value of the axis.
    pub overlays: Option<Vec<String>>,
}

/// One base scenario of the long form (`[[scenario]]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Base {
    /// How cells, tables and `[reduced]` name it (default: its file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A closed-loop scenario file relative to the sweep file, or [`EMBEDDED`].
    pub file: String,
    /// Its own values of axes, by axis name, in place of the axis's `values` (for an overlay
    /// axis: overlay names). Its cells are the combinations of these and the other axes' values.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub values: BTreeMap<String, Vec<toml::Value>>,
}

impl Base {
    /// Its name: the one given, or its file.
    pub fn name(&self) -> &str {
        self.name.as_deref().unwrap_or(&self.file)
    }
}

/// An overlay merged over every cell whose axis values meet every condition of `when`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Conditional {
    /// The `[overlay.NAME]` it merges.
    pub overlay: String,
    /// Axis name → [`Condition`] (a table); every one must hold. Empty: every cell.
    #[serde(default)]
    pub when: BTreeMap<String, toml::Value>,
}

/// What an axis value must satisfy: at least `min`, at most `max` (both inclusive, numbers
/// only), equal to one of `in`. The keys given must all hold; give at least one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Condition {
    pub min: Option<f64>,
    pub max: Option<f64>,
    #[serde(rename = "in")]
    pub one_of: Option<Vec<toml::Value>>,
}

/// The reduced form: fewer runs, an overlay over every cell (shorter missions, say) and fewer
/// cells.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reduced {
    /// Runs per policy and cell (default: the file's `runs`).
    pub runs: Option<usize>,
    /// An `[overlay.NAME]` merged over every cell, after the axes and the conditional overlays.
    pub overlay: Option<String>,
    /// The base scenarios it keeps, in this order, each with its own axis values (`values`:
    /// default, the full form's). Empty: every base scenario, as in the full form.
    #[serde(default, rename = "scenario")]
    pub bases: Vec<ReducedBase>,
}

/// One base scenario of the reduced form.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReducedBase {
    /// The base scenario's name (`[[scenario]] name`, or its file).
    pub name: String,
    #[serde(default)]
    pub values: BTreeMap<String, Vec<toml::Value>>,
}

impl SweepFile {
    /// Parses the text of sweep `file`.
    pub fn parse(text: &str, file: &Path) -> Result<Self, SweepFileError> {
        toml::from_str(text).map_err(|e| SweepFileError::Invalid {
            file: file.to_path_buf(),
            problems: vec![e.message().to_string() + &location(text, &e)],
        })
    }

    /// The base scenarios' files as written, in file order (`scenarios`, then `[[scenario]]`).
    pub fn scenario_files(&self) -> Vec<&str> {
        self.scenarios.iter().map(String::as_str).chain(self.bases.iter().map(|b| b.file.as_str())).collect()
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
        let e = SweepFile::parse(
            "policies = []\nruns = 1\n[[scenario]]\nfile = \"default\"\nvalue = { n = [1] }\n",
            Path::new("s.toml"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("sweep file s.toml: unknown field `value`") && e.ends_with("(line 5)"), "{e}");
    }
}
