//! The closed-loop simulator from Python: one mission (`simulate`) with its time series as numpy
//! columns and its summary as the CLI's summary.json holds it, and the seeded Monte Carlo
//! comparison of policies (`monte_carlo`) with the CLI's table. Both release the GIL and stop on
//! Ctrl-C (the engine asks its observer before every step).

use crate::convert::{column, columns, or_nan, to_py};
use crate::scenario::Scenario;
use crate::{interruptible, value_error};
use coopnav_core::limits;
use coopnav_core::Vec3;
use coopnav_sim::batch::mc;
use coopnav_sim::batch::mc::comparison_table;
use coopnav_sim::batch::work;
use coopnav_sim::engine::Faults;
use coopnav_sim::engine::{CommsEvent, Decision, Observer, Trace, TraceRow};
use coopnav_sim::observe::metrics;
use coopnav_sim::policy::PolicySpec;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::sync::atomic::{AtomicBool, Ordering};

/// Records the whole trace, and ends the run when the caller is interrupted.
struct Recorder<'a> {
    trace: Trace,
    stop: &'a AtomicBool,
}

impl Observer for Recorder<'_> {
    fn on_decision(&mut self, decision: &Decision) {
        self.trace.on_decision(decision);
    }
    fn on_sample(&mut self, t: f64, cna: Vec3, rows: &[TraceRow]) {
        self.trace.on_sample(t, cna, rows);
    }
    fn on_packet(&mut self, event: &CommsEvent) {
        self.trace.on_packet(event);
    }
    fn stop(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// The trace rows as columns (one row per AUV per second).
fn timeseries<'py>(py: Python<'py>, rows: &[TraceRow]) -> PyResult<Bound<'py, PyDict>> {
    let col = |f: fn(&TraceRow) -> f64| column(py, rows.iter().map(f)).into_any();
    let auv: Vec<i64> = rows.iter().map(|r| r.auv as i64).collect();
    columns(
        py,
        [
            ("t", col(|r| r.t)),
            ("auv", numpy::PyArray1::from_vec(py, auv).into_any()),
            ("true_x", col(|r| r.true_x)),
            ("true_y", col(|r| r.true_y)),
            ("true_z", col(|r| r.true_z)),
            ("est_x", col(|r| r.est_x)),
            ("est_y", col(|r| r.est_y)),
            ("error", col(|r| r.error)),
            ("est_sd", col(|r| r.est_sd)),
            ("p_ee", col(|r| r.p_ee)),
            ("p_en", col(|r| r.p_en)),
            ("p_nn", col(|r| r.p_nn)),
            ("nees", col(|r| r.nees)),
            ("modelled", col(|r| or_nan(r.modelled))),
            ("cna_x", col(|r| r.cna_x)),
            ("cna_y", col(|r| r.cna_y)),
            ("cna_z", col(|r| r.cna_z)),
            ("distance", col(|r| r.distance)),
        ],
    )
}

/// The comms timeline as columns (one row per packet whose fate is known).
fn comms<'py>(py: Python<'py>, events: &[CommsEvent]) -> PyResult<Bound<'py, PyDict>> {
    let strings = |f: fn(&CommsEvent) -> &'static str| PyList::new(py, events.iter().map(f)).map(Bound::into_any);
    columns(
        py,
        [
            ("t", column(py, events.iter().map(|e| e.t)).into_any()),
            ("direction", strings(|e| e.direction)?),
            ("auv", numpy::PyArray1::from_vec(py, events.iter().map(|e| e.auv as i64).collect()).into_any()),
            ("received", numpy::PyArray1::from_vec(py, events.iter().map(|e| e.received).collect()).into_any()),
            ("lost_to", strings(|e| e.lost_to)?),
        ],
    )
}

/// One closed-loop mission of `scenario` under `policy` (default seed: the scenario's), as
/// `coopnav simulate` runs it. Returns a dict: `timeseries`, `comms`, `cna` (dicts of numpy
/// columns) and `summary` (summary.json's content).
#[pyfunction]
#[pyo3(signature = (scenario, policy = "planner-estimator", seed = None))]
fn simulate<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    policy: &str,
    seed: Option<u64>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut sc = scenario.closed_loop("simulate")?.clone();
    if let Some(seed) = seed {
        sc.seed = seed;
    }
    let mut built = PolicySpec::new(policy, &sc).and_then(|spec| spec.build(&sc)).map_err(value_error)?;
    let result = interruptible(py, |stop| {
        let mut recorder = Recorder { trace: Trace::default(), stop };
        let mut r = metrics::run(&sc, &mut built, sc.seed, &Faults::default(), &mut recorder);
        r.trace = Some(recorder.trace);
        r
    })?;
    let trace = result.trace.as_ref().ok_or_else(|| PyValueError::new_err("the run kept no trace"))?;
    let cna = columns(
        py,
        [
            ("t", column(py, trace.cna.iter().map(|c| c.0)).into_any()),
            ("x", column(py, trace.cna.iter().map(|c| c.1.x)).into_any()),
            ("y", column(py, trace.cna.iter().map(|c| c.1.y)).into_any()),
            ("z", column(py, trace.cna.iter().map(|c| c.1.z)).into_any()),
        ],
    )?;
    let out = PyDict::new(py);
    out.set_item("timeseries", timeseries(py, &trace.rows)?)?;
    out.set_item("comms", comms(py, &trace.comms)?)?;
    out.set_item("cna", cna)?;
    out.set_item("summary", to_py(py, &result)?)?;
    Ok(out)
}

/// Seeded Monte Carlo comparison of `policies` over `runs` runs each (run i of every policy
/// shares its seed), as `coopnav simulate --runs N --policy a,b`. Returns the comparison as the
/// CLI's `--json` prints it, plus `table`: the text table the CLI prints.
#[pyfunction]
#[pyo3(signature = (scenario, policies, runs, seed = None, allow_large = false))]
fn monte_carlo<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    policies: Vec<String>,
    runs: usize,
    seed: Option<u64>,
    allow_large: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let mut sc = scenario.closed_loop("monte_carlo")?.clone();
    if let Some(seed) = seed {
        sc.seed = seed;
    }
    if runs == 0 {
        return Err(PyValueError::new_err("runs must be at least 1"));
    }
    for p in &policies {
        PolicySpec::new(p, &sc).map_err(value_error)?;
    }
    limits::check(work::closed_loop(&sc, runs, policies.len()), allow_large).map_err(value_error)?;
    let comparison = interruptible(py, |stop| {
        mc::monte_carlo_until(&sc, &policies, runs, &|_| {}, &|| stop.load(Ordering::Relaxed))
    })?
    .map_err(value_error)?;
    let out = to_py(py, &comparison)?;
    out.set_item("table", comparison_table(&comparison))?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(monte_carlo, m)?)
}
