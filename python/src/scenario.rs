//! Scenarios from Python: the closed-loop mission of `coopnav simulate` ("simulate") and the
//! pre-deployment mission of `coopnav plan` ("plan"), read from a TOML file or string or built
//! from a dict, each checked exactly as the CLI checks it (parse, work limits, validation).

use crate::convert::{to_py, toml_text};
use crate::value_error;
use coopnav_core::limits::{self, Estimate};
use coopnav_sim::scenario;
use coopnav_sim::{batch::work, scenario::file as scenario_file};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// The scenario kinds, as Python names them.
pub const KINDS: [&str; 2] = ["simulate", "plan"];

/// One scenario of either kind.
#[derive(Clone)]
pub enum Kind {
    Simulate(scenario::Scenario),
    Plan(scenario::plan::Scenario),
}

#[pyclass(module = "coopnav", frozen, name = "Scenario")]
#[derive(Clone)]
pub struct Scenario {
    pub kind: Kind,
    /// The file it came from, or `<embedded NAME>` / `<string>` / `<dict>`: messages name it.
    pub file: PathBuf,
    /// The directory relative paths inside it (track CSVs) start from.
    pub base: PathBuf,
}

/// Parses `text`, checks the work it asks for, validates it — the CLI's order, so the same
/// input fails with the same message.
fn checked<T: DeserializeOwned>(
    text: &str,
    file: &Path,
    read: fn(&str, &Path) -> Result<T, scenario_file::ScenarioError>,
    work: fn(&T) -> Vec<Estimate>,
    validate: scenario_file::Validate<T>,
    allow_large: bool,
) -> PyResult<T> {
    let scenario = read(text, file).map_err(value_error)?;
    limits::check(work(&scenario), allow_large).map_err(value_error)?;
    validate(&scenario, file).map_err(value_error)?;
    Ok(scenario)
}

fn one_run(sc: &scenario::Scenario) -> Vec<Estimate> {
    work::closed_loop(sc, 1, 1)
}

impl Scenario {
    fn parse(text: &str, kind: &str, file: PathBuf, base: PathBuf, allow_large: bool) -> PyResult<Self> {
        let kind = match kind {
            "simulate" => Kind::Simulate(checked(
                text,
                &file,
                scenario::Scenario::read,
                one_run,
                scenario::Scenario::validate,
                allow_large,
            )?),
            "plan" => Kind::Plan(checked(
                text,
                &file,
                scenario::plan::Scenario::read,
                work::predeploy,
                scenario::plan::Scenario::validate,
                allow_large,
            )?),
            other => return Err(unknown_kind(other)),
        };
        Ok(Scenario { kind, file, base })
    }

    /// The closed-loop scenario, or a `ValueError` naming what `what` needs.
    pub fn closed_loop(&self, what: &str) -> PyResult<&scenario::Scenario> {
        match &self.kind {
            Kind::Simulate(sc) => Ok(sc),
            Kind::Plan(_) => Err(PyValueError::new_err(format!("{what} needs a \"simulate\" scenario, not \"plan\""))),
        }
    }
}

fn unknown_kind(kind: &str) -> PyErr {
    PyValueError::new_err(format!("unknown scenario kind '{kind}' (allowed: {})", KINDS.join(", ")))
}

#[pymethods]
impl Scenario {
    /// The embedded example of `kind` ("simulate": the default closed-loop mission; "plan": the
    /// pre-deployment example), as `coopnav simulate --example` / `coopnav plan --example` print it.
    #[staticmethod]
    #[pyo3(signature = (kind = "simulate"))]
    fn example(kind: &str) -> PyResult<Self> {
        let (text, name) = match kind {
            "simulate" => (scenario::EXAMPLE, "default"),
            "plan" => (scenario::plan::EXAMPLE, "example"),
            other => return Err(unknown_kind(other)),
        };
        Scenario::parse(text, kind, PathBuf::from(format!("<embedded {name}>")), PathBuf::from("."), false)
    }

    /// The example's TOML text (to edit and load back).
    #[staticmethod]
    #[pyo3(signature = (kind = "simulate"))]
    fn example_toml(kind: &str) -> PyResult<&'static str> {
        match kind {
            "simulate" => Ok(scenario::EXAMPLE),
            "plan" => Ok(scenario::plan::EXAMPLE),
            other => Err(unknown_kind(other)),
        }
    }

    /// Reads a TOML scenario file.
    #[staticmethod]
    #[pyo3(signature = (path, kind = "simulate", allow_large = false))]
    fn load(path: PathBuf, kind: &str, allow_large: bool) -> PyResult<Self> {
        let text = coopnav_sim::scenario::file::read_scenario_text(&path, allow_large).map_err(value_error)?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scenario::parse(&text, kind, path, base, allow_large)
    }

    /// Parses a TOML string.
    #[staticmethod]
    #[pyo3(signature = (text, kind = "simulate", allow_large = false))]
    fn from_toml(text: &str, kind: &str, allow_large: bool) -> PyResult<Self> {
        Scenario::parse(text, kind, PathBuf::from("<string>"), PathBuf::from("."), allow_large)
    }

    /// Builds a scenario from a dict holding what the TOML file would (e.g. an edited `to_dict()`).
    #[staticmethod]
    #[pyo3(signature = (data, kind = "simulate", allow_large = false))]
    fn from_dict(data: &Bound<'_, PyAny>, kind: &str, allow_large: bool) -> PyResult<Self> {
        let text = toml_text(data, "scenario")?;
        Scenario::parse(&text, kind, PathBuf::from("<dict>"), PathBuf::from("."), allow_large)
    }

    /// "simulate" or "plan".
    #[getter]
    fn kind(&self) -> &'static str {
        match self.kind {
            Kind::Simulate(_) => "simulate",
            Kind::Plan(_) => "plan",
        }
    }

    /// Where it came from (a path, or `<embedded ...>`, `<string>`, `<dict>`).
    #[getter]
    fn source(&self) -> String {
        self.file.display().to_string()
    }

    /// Every field as a dict (the TOML file's tables and keys).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        match &self.kind {
            Kind::Simulate(sc) => to_py(py, sc),
            Kind::Plan(sc) => to_py(py, sc),
        }
    }

    /// Every field as TOML text.
    fn to_toml(&self) -> PyResult<String> {
        let text = match &self.kind {
            Kind::Simulate(sc) => toml::to_string(sc),
            Kind::Plan(sc) => toml::to_string(sc),
        };
        text.map_err(|e| PyValueError::new_err(e.to_string()))
    }

    fn __repr__(&self) -> String {
        format!("Scenario(kind={:?}, source={:?})", self.kind(), self.source())
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scenario>()
}
