//! Reading scenario files (TOML, `deny_unknown_fields` on every table): one error type and one
//! loader — read the file, parse it, validate it — shared by the pre-deployment planner and the
//! closed-loop simulator. Every error names the file, and a bad value names its field, the value
//! found and what is allowed.

use crate::scenario::tracks::TrackLoadError;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The underlying errors are part of each message (fields named `cause`, not `source`), so a
/// printed cause chain shows them once.
#[derive(Debug, Error)]
pub enum ScenarioError {
    #[error("cannot read scenario {file}: {}", read_cause(cause))]
    Read { file: PathBuf, cause: coopnav_core::limits::InputError },
    #[error("scenario {file}: {message}")]
    Parse { file: PathBuf, message: String },
    #[error("scenario {file}: field {field} = {value}: allowed {allowed}")]
    Invalid { file: PathBuf, field: String, value: String, allowed: String },
    #[error("scenario {file}: {} bad fields:{}", problems.len(), problems.iter().map(|p| format!("\n  {p}")).collect::<String>())]
    Several { file: PathBuf, problems: Vec<Problem> },
    #[error("scenario {file}: auv[{index}] track: {cause}")]
    Track { file: PathBuf, index: usize, cause: TrackLoadError },
}

/// Why a scenario could not be read, without the path its message names already.
fn read_cause(cause: &coopnav_core::limits::InputError) -> String {
    match cause {
        coopnav_core::limits::InputError::Io { source, .. } => source.to_string(),
        other => other.to_string(),
    }
}

impl ScenarioError {
    /// The bad fields of `file`: one as [`ScenarioError::Invalid`], more as `Several`.
    pub fn fields(file: &Path, InvalidFields(mut problems): InvalidFields) -> Self {
        match problems.len() {
            1 => {
                let p = problems.remove(0);
                ScenarioError::Invalid { file: file.to_path_buf(), field: p.field, value: p.value, allowed: p.allowed }
            }
            _ => ScenarioError::Several { file: file.to_path_buf(), problems },
        }
    }

    /// A field of `file` holds `value` where only `allowed` is.
    pub fn invalid(
        file: &Path,
        field: impl Into<String>,
        value: impl Into<String>,
        allowed: impl Into<String>,
    ) -> Self {
        ScenarioError::Invalid {
            file: file.to_path_buf(),
            field: field.into(),
            value: value.into(),
            allowed: allowed.into(),
        }
    }
}

pub use coopnav_core::validation::Problem;
use coopnav_core::validation::{self, shortened, InvalidFields};

/// Collects every bad field of a scenario file (the checks are core's [`validation::Problems`]),
/// so one run of the validator reports them all, naming the file.
#[derive(Debug)]
pub struct Problems {
    file: PathBuf,
    found: validation::Problems,
}

impl std::ops::Deref for Problems {
    type Target = validation::Problems;
    fn deref(&self) -> &Self::Target {
        &self.found
    }
}

impl std::ops::DerefMut for Problems {
    fn deref_mut(&mut self) -> &mut Self::Target {
        &mut self.found
    }
}

impl Problems {
    pub fn new(file: &Path) -> Self {
        Problems { file: file.to_path_buf(), found: validation::Problems::new() }
    }

    /// Ok when nothing was found; one problem as [`ScenarioError::Invalid`], more as `Several`.
    pub fn finish(self) -> Result<(), ScenarioError> {
        self.found.finish().map_err(|fields| ScenarioError::fields(&self.file, fields))
    }
}

/// What a scenario type checks before anything runs (`file` names it in messages).
pub type Validate<T> = fn(&T, &Path) -> Result<(), ScenarioError>;

/// Parses TOML `text` as a `T` and validates it; `file` names the text in messages.
pub fn parse<T: DeserializeOwned>(text: &str, file: &Path, validate: Validate<T>) -> Result<T, ScenarioError> {
    let scenario: T = toml::from_str(text)
        .map_err(|e| ScenarioError::Parse { file: file.to_path_buf(), message: shortened(&e.to_string()) })?;
    validate(&scenario, file)?;
    Ok(scenario)
}

/// Builds a `T` from a TOML tree (a file whose site was resolved, `scenario::site`) and validates it.
pub fn parse_tree<T: DeserializeOwned>(
    tree: toml::Value,
    file: &Path,
    validate: Validate<T>,
) -> Result<T, ScenarioError> {
    let scenario = T::deserialize(tree)
        .map_err(|e| ScenarioError::Parse { file: file.to_path_buf(), message: shortened(&e.to_string()) })?;
    validate(&scenario, file)?;
    Ok(scenario)
}

/// The text of scenario `file`, read through the bounded reader (the input-file limit unless
/// `allow_large`), so every front end refuses the same inputs with the same words.
pub fn read_scenario_text(file: &Path, allow_large: bool) -> Result<String, ScenarioError> {
    let limit = coopnav_core::limits::MAX_INPUT_FILE_BYTES;
    coopnav_core::limits::read_text(file, "input file (bytes)", limit, allow_large)
        .map_err(|cause| ScenarioError::Read { file: file.to_path_buf(), cause })
}

/// Reads `file`, then [`parse`]s it.
pub fn load<T: DeserializeOwned>(file: &Path, validate: Validate<T>) -> Result<T, ScenarioError> {
    let text = read_scenario_text(file, false)?;
    parse(&text, file, validate)
}

/// Reads a TOML table over `base`: keys present replace base's, nested tables merge, absent keys
/// keep base's values (unknown keys are still refused by `T`). For a field whose scenario default
/// differs from its type's `Default`, so that a partial table does not fall back to the latter.
pub fn overlay<T: Serialize + DeserializeOwned>(base: &T, patch: toml::Value) -> Result<T, String> {
    let mut merged = toml::Value::try_from(base).map_err(|e| e.to_string())?;
    merge(&mut merged, patch);
    merged.try_into().map_err(|e: toml::de::Error| e.to_string())
}

/// `patch` merged into `into` key by key; a table whose `kind` the patch changes is replaced
/// whole (a model of another kind keeps none of the old kind's fields).
fn merge(into: &mut toml::Value, patch: toml::Value) {
    match (into, patch) {
        (toml::Value::Table(a), toml::Value::Table(b)) if b.get("kind").is_none_or(|k| a.get("kind") == Some(k)) => {
            for (k, v) in b {
                match a.get_mut(&k) {
                    Some(slot) => merge(slot, v),
                    None => {
                        a.insert(k, v);
                    }
                }
            }
        }
        (slot, v) => *slot = v,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Outer {
        a: f64,
        inner: Inner,
    }
    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Inner {
        b: f64,
        c: f64,
    }

    #[test]
    fn overlay_keeps_absent_keys_and_refuses_unknown_ones() {
        let base = Outer { a: 1.0, inner: Inner { b: 2.0, c: 3.0 } };
        let patch: toml::Value = toml::from_str("[inner]\nc = 9.0\n").unwrap();
        assert_eq!(overlay(&base, patch).unwrap(), Outer { a: 1.0, inner: Inner { b: 2.0, c: 9.0 } });
        let bad: toml::Value = toml::from_str("[inner]\nd = 1.0\n").unwrap();
        assert!(overlay(&base, bad).unwrap_err().contains("unknown field"));
    }

    /// A patch that names another kind replaces the model; one of the same kind merges into it.
    #[test]
    fn overlay_replaces_a_model_whose_kind_the_patch_changes() {
        let base: toml::Value = toml::from_str("m = { kind = \"gps\", sd_m = 2.0 }\nn = 1").unwrap();
        let other: toml::Value = toml::from_str("m = { kind = \"walk\", d = 0.1 }").unwrap();
        let replaced: toml::Value = overlay(&base, other).unwrap();
        assert_eq!(replaced, toml::from_str::<toml::Value>("m = { kind = \"walk\", d = 0.1 }\nn = 1").unwrap());
        let same: toml::Value = toml::from_str("m = { kind = \"gps\", extra = 3 }").unwrap();
        let merged: toml::Value = overlay(&base, same).unwrap();
        assert_eq!(merged["m"]["sd_m"].as_float(), Some(2.0));
        assert_eq!(merged["m"]["extra"].as_integer(), Some(3));
    }

    #[derive(Debug, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Tiny {
        n: u32,
    }

    fn at_most_three(t: &Tiny, file: &Path) -> Result<(), ScenarioError> {
        if t.n > 3 {
            return Err(ScenarioError::invalid(file, "n", t.n.to_string(), "0..=3"));
        }
        Ok(())
    }

    #[test]
    fn every_error_names_the_file_and_what_was_wrong() {
        let f = Path::new("tiny.toml");
        assert_eq!(parse("n = 2", f, at_most_three).unwrap().n, 2);
        let e = parse("n = 7", f, at_most_three).unwrap_err().to_string();
        assert_eq!(e, "scenario tiny.toml: field n = 7: allowed 0..=3");
        let e = parse("n = 1\nm = 2", f, at_most_three).unwrap_err().to_string();
        assert!(e.contains("tiny.toml") && e.contains("unknown field") && e.contains('m'), "{e}");
        let e = load(Path::new("/nonexistent/tiny.toml"), at_most_three).unwrap_err().to_string();
        assert!(e.starts_with("cannot read scenario /nonexistent/tiny.toml"), "{e}");
    }
}
