//! Reading scenario files (TOML, `deny_unknown_fields` on every table): one error type and one
//! loader — read the file, parse it, validate it — shared by the pre-deployment planner and the
//! closed-loop simulator. Every error names the file, and a bad value names its field, the value
//! found and what is allowed.

use crate::predeploy::tracks::TrackLoadError;
use coopnav_plan::PlanError;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// The underlying errors are part of each message (fields named `cause`, not `source`), so a
/// printed cause chain shows them once.
#[derive(Debug, Error)]
pub enum ScenarioError {
    #[error("cannot read scenario {file}: {cause}")]
    Read { file: PathBuf, cause: std::io::Error },
    #[error("scenario {file}: {message}")]
    Parse { file: PathBuf, message: String },
    #[error("scenario {file}: field {field} = {value}: allowed {allowed}")]
    Invalid { file: PathBuf, field: String, value: String, allowed: String },
    #[error("scenario {file}: {} bad fields:{}", problems.len(), problems.iter().map(|p| format!("\n  {p}")).collect::<String>())]
    Several { file: PathBuf, problems: Vec<Problem> },
    #[error("scenario {file}: {cause}")]
    Planner { file: PathBuf, cause: PlanError },
    #[error("scenario {file}: auv[{index}] track: {cause}")]
    Track { file: PathBuf, index: usize, cause: TrackLoadError },
}

impl ScenarioError {
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

/// One bad field: where, what was found, what is allowed.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub field: String,
    pub value: String,
    pub allowed: String,
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "field {} = {}: allowed {}", self.field, self.value, self.allowed)
    }
}

/// Collects every bad field of a file, so one run of the validator reports them all.
#[derive(Debug)]
pub struct Problems {
    file: PathBuf,
    list: Vec<Problem>,
}

impl Problems {
    pub fn new(file: &Path) -> Self {
        Problems { file: file.to_path_buf(), list: Vec::new() }
    }

    pub fn push(&mut self, field: impl Into<String>, value: impl Into<String>, allowed: impl Into<String>) {
        self.list.push(Problem { field: field.into(), value: value.into(), allowed: allowed.into() });
    }

    /// Adds (field, value, allowed) triples, as the models' `problems()` return them.
    pub fn extend(&mut self, found: impl IntoIterator<Item = (String, String, String)>) {
        for (field, value, allowed) in found {
            self.push(field, value, allowed);
        }
    }

    /// `value` must be finite and inside `ok`; `allowed` says so in words.
    pub fn check(&mut self, field: &str, value: f64, ok: impl FnOnce(f64) -> bool, allowed: &str) {
        if !(value.is_finite() && ok(value)) {
            self.push(field, value.to_string(), allowed);
        }
    }

    pub fn positive(&mut self, field: &str, value: f64) {
        self.check(field, value, |v| v > 0.0, "a finite number > 0");
    }

    pub fn non_negative(&mut self, field: &str, value: f64) {
        self.check(field, value, |v| v >= 0.0, "a finite number >= 0");
    }

    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Ok when nothing was found; one problem as [`ScenarioError::Invalid`], more as `Several`.
    pub fn finish(mut self) -> Result<(), ScenarioError> {
        match self.list.len() {
            0 => Ok(()),
            1 => {
                let p = self.list.remove(0);
                Err(ScenarioError::Invalid { file: self.file, field: p.field, value: p.value, allowed: p.allowed })
            }
            _ => Err(ScenarioError::Several { file: self.file, problems: self.list }),
        }
    }
}

/// What a scenario type checks before anything runs (`file` names it in messages).
pub type Validate<T> = fn(&T, &Path) -> Result<(), ScenarioError>;

/// Parses TOML `text` as a `T` and validates it; `file` names the text in messages.
pub fn parse<T: DeserializeOwned>(text: &str, file: &Path, validate: Validate<T>) -> Result<T, ScenarioError> {
    let scenario: T =
        toml::from_str(text).map_err(|e| ScenarioError::Parse { file: file.to_path_buf(), message: e.to_string() })?;
    validate(&scenario, file)?;
    Ok(scenario)
}

/// Reads `file`, then [`parse`]s it.
pub fn load<T: DeserializeOwned>(file: &Path, validate: Validate<T>) -> Result<T, ScenarioError> {
    let text =
        std::fs::read_to_string(file).map_err(|cause| ScenarioError::Read { file: file.to_path_buf(), cause })?;
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

fn merge(into: &mut toml::Value, patch: toml::Value) {
    match (into, patch) {
        (toml::Value::Table(a), toml::Value::Table(b)) => {
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
