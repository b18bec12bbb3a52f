//! The CNA path planner from Python: a [`LookAheadPlanner`] built from a planner config (the
//! `coopnav_plan::PlannerConfig` fields as a dict or TOML) or from a scenario, asked for one
//! decision at a time with numpy inputs, and the whole pre-deployment `plan` of `coopnav plan`.
//! Headings here are math radians (0 = east, counter-clockwise), as inside every crate.

use crate::convert::{column, columns, matrix, to_py, toml_text};
use crate::scenario::{Kind, Scenario};
use crate::value_error;
use coopnav_core::{Heading, Vec3};
use coopnav_plan::auto::{CnaFact, MissionFacts};
use coopnav_plan::predeploy;
use coopnav_plan::{AuvError, AuvEstimate, AuvForecast, CnaPose, LookAheadPlanner, PlanInput, Planner as _};
use coopnav_plan::{PlannerConfig, PlannerSpec, Platform};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The AUVs' predicted positions at t + τ, t + 2τ, … (one row per look-ahead level; fewer rows
/// than levels truncate the horizon, as a forecast that ends does).
struct ArrayForecast {
    t: f64,
    tau: f64,
    /// [AUV][level] positions.
    positions: Vec<Vec<Vec3>>,
}

impl AuvForecast for ArrayForecast {
    fn n_auvs(&self) -> usize {
        self.positions.len()
    }
    fn position(&self, k: usize, t: f64) -> Option<Vec3> {
        let level = ((t - self.t) / self.tau).round() as i64 - 1;
        let level = usize::try_from(level).ok()?;
        self.positions.get(k)?.get(level).copied()
    }
}

fn pose(cna_pose: &[f64]) -> PyResult<CnaPose> {
    match *cna_pose {
        [x, y, z, heading] => {
            Ok(CnaPose { pos: Vec3::new(x, y, z), heading: Heading::from_radians(heading), pitch: 0.0 })
        }
        [x, y, z, heading, pitch] => {
            Ok(CnaPose { pos: Vec3::new(x, y, z), heading: Heading::from_radians(heading), pitch })
        }
        _ => Err(PyValueError::new_err(format!(
            "cna_pose: expected [x, y, z, heading_rad] or [x, y, z, heading_rad, pitch_rad], got {} numbers",
            cna_pose.len()
        ))),
    }
}

/// Rows of a 2-D array of width `width`, named `what` in the error.
fn rows(a: &PyReadonlyArray2<'_, f64>, width: usize, what: &str) -> PyResult<Vec<Vec<f64>>> {
    let v = a.as_array();
    if v.ncols() != width {
        return Err(PyValueError::new_err(format!("{what}: expected shape (N, {width}), got {:?}", v.shape())));
    }
    Ok(v.rows().into_iter().map(|r| r.to_vec()).collect())
}

fn errors_of(a: &PyReadonlyArray2<'_, f64>) -> PyResult<Vec<AuvError>> {
    Ok(rows(a, 5, "errors (sigma2, eps2, los_x, los_y, los_z)")?
        .into_iter()
        .map(|r| AuvError { sigma2: r[0], eps2: r[1], los: [r[2], r[3], r[4]] })
        .collect())
}

fn estimates_of(a: Option<&PyReadonlyArray2<'_, f64>>) -> PyResult<Vec<AuvEstimate>> {
    let Some(a) = a else { return Ok(Vec::new()) };
    Ok(rows(a, 4, "estimates (p_ee, p_en, p_nn, process_noise)")?
        .into_iter()
        .map(|r| AuvEstimate { cov: [r[0], r[1], r[2]], process_noise: r[3] })
        .collect())
}

/// The receding-horizon look-ahead planner (Hudson 2012).
#[pyclass(module = "coopnav", name = "Planner")]
pub struct Planner {
    inner: LookAheadPlanner,
}

#[pymethods]
impl Planner {
    /// A planner from its config: a dict or TOML text with `coopnav_plan::PlannerConfig`'s fields
    /// (look_ahead, motion, penalties, and optionally error, cost, limits, search).
    #[new]
    fn new(config: &Bound<'_, PyAny>) -> PyResult<Self> {
        let cfg: PlannerConfig = toml::from_str(&toml_text(config, "planner config")?)
            .map_err(|e| PyValueError::new_err(format!("planner config: {e}")))?;
        Ok(Planner { inner: LookAheadPlanner::new(cfg).map_err(value_error)? })
    }

    /// The planner a scenario's `[policy.NAME]` table configures: the closed loop's `planner` or
    /// `planner-estimator` (with the settings its table and the planner's rule give for the
    /// mission), or the pre-deployment file's `planner`.
    #[staticmethod]
    #[pyo3(signature = (scenario, policy = "planner"))]
    fn from_scenario(scenario: &Scenario, policy: &str) -> PyResult<Self> {
        let cfg = match &scenario.kind {
            Kind::Simulate(sc) => coopnav_sim::policy::registry::planner_config(policy, sc).map_err(value_error)?,
            Kind::Plan(_) if policy != "planner" => {
                return Err(PyValueError::new_err(format!(
                    "policy '{policy}': a \"plan\" scenario has only [policy.planner]"
                )))
            }
            Kind::Plan(sc) => sc.build(&scenario.file, &scenario.base).map_err(value_error)?.planner,
        };
        Ok(Planner { inner: LookAheadPlanner::new(cfg).map_err(value_error)? })
    }

    /// A planner from a `[policy.planner]` table as every scenario file writes it (a dict or TOML
    /// text with `coopnav_plan::PlannerSpec`'s keys: tree, limits, penalty, deadline, search,
    /// cost) on `platform` (`coopnav_plan::Platform`'s keys: speed, tau, max_turn_rate_deg_s,
    /// cna). Hudson's cost only: the estimator cost reads a mission (`from_scenario`).
    #[staticmethod]
    fn from_spec(spec: &Bound<'_, PyAny>, platform: &Bound<'_, PyAny>) -> PyResult<Self> {
        let spec: PlannerSpec = toml::from_str(&toml_text(spec, "planner spec")?)
            .map_err(|e| PyValueError::new_err(format!("planner spec: {e}")))?;
        let platform: Platform = toml::from_str(&toml_text(platform, "platform")?)
            .map_err(|e| PyValueError::new_err(format!("platform: {e}")))?;
        if spec.estimator_cost().is_some() {
            return Err(PyValueError::new_err(
                "planner spec: cost.kind = \"estimator\" reads a mission: use Planner.from_scenario(scenario, \"planner-estimator\")",
            ));
        }
        let facts =
            MissionFacts { n_auvs: 1, cna: CnaFact::Asc, adcp_current: [0.0, 0.0], filters_estimate_current: false };
        spec.validate(&platform, &facts, 0.0).map_err(value_error)?;
        Ok(Planner { inner: LookAheadPlanner::new(spec.config(&platform, &facts, 0.0)).map_err(value_error)? })
    }

    /// The config as a dict (edit it and build a new `Planner`).
    #[getter]
    fn config<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, self.inner.config())
    }

    /// The error state at planning start of AUVs at `auv_positions` (N, 3) seen from the CNA at
    /// `cna_position` (3,): rows (sigma2, eps2, los_x, los_y, los_z), the input `decide` takes.
    fn initial_errors<'py>(
        &self,
        py: Python<'py>,
        sigma0: f64,
        eps0: f64,
        cna_position: PyReadonlyArray1<'_, f64>,
        auv_positions: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let c = cna_position.as_slice()?;
        let [cx, cy, cz] = c else { return Err(PyValueError::new_err("cna_position: expected 3 numbers")) };
        let cna = Vec3::new(*cx, *cy, *cz);
        let model = self.inner.config().error;
        let out: Vec<[f64; 5]> = rows(&auv_positions, 3, "auv_positions")?
            .iter()
            .map(|p| {
                let e = model.initial(sigma0, eps0, &cna, &Vec3::new(p[0], p[1], p[2]));
                [e.sigma2, e.eps2, e.los[0], e.los[1], e.los[2]]
            })
            .collect();
        Ok(matrix(py, &out)?.into_any())
    }

    /// One decision at time `t` from `cna_pose` [x, y, z, heading_rad(, pitch_rad)], the AUVs'
    /// modelled `errors` (N, 5) and `forecast` (N, levels, 3): their positions at t + τ, t + 2τ, ….
    /// `estimates` (N, 4: p_ee, p_en, p_nn, process_noise) feed the estimator-aware cost, and
    /// `cna_variance` (m² per horizontal axis, ≥ 0) is the CNA's own position variance it adds to
    /// every ping's range variance; 0, the default, is the cost as before that term existed.
    /// Returns heading and pitch of the next waypoint, the cost, the levels searched, ….
    #[pyo3(signature = (t, cna_pose, errors, forecast, estimates = None, cna_variance = 0.0))]
    fn decide<'py>(
        &mut self,
        py: Python<'py>,
        t: f64,
        cna_pose: PyReadonlyArray1<'_, f64>,
        errors: PyReadonlyArray2<'_, f64>,
        forecast: PyReadonlyArray3<'_, f64>,
        estimates: Option<PyReadonlyArray2<'_, f64>>,
        cna_variance: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        if !(cna_variance.is_finite() && cna_variance >= 0.0) {
            return Err(PyValueError::new_err(format!(
                "cna_variance: expected a finite variance >= 0 m², got {cna_variance}"
            )));
        }
        let cna = pose(cna_pose.as_slice()?)?;
        let errors = errors_of(&errors)?;
        let estimates = estimates_of(estimates.as_ref())?;
        let f = forecast.as_array();
        if f.shape()[2] != 3 {
            return Err(PyValueError::new_err(format!("forecast: expected shape (N, levels, 3), got {:?}", f.shape())));
        }
        let positions =
            f.outer_iter().map(|auv| auv.outer_iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect()).collect();
        let forecast = ArrayForecast { t, tau: self.inner.config().motion.tau, positions };
        let inner = &mut self.inner;
        let d = py
            .detach(|| {
                let input = PlanInput {
                    t,
                    cna,
                    errors: &errors,
                    estimates: &estimates,
                    cna_variance,
                    forecast: &forecast,
                    slot_reach_m: &[],
                };
                inner.decide(&input)
            })
            .map_err(value_error)?;
        let out = PyDict::new(py);
        out.set_item("option", d.option)?;
        out.set_item("heading", d.next.heading.radians())?;
        out.set_item("pitch", d.next.pitch)?;
        out.set_item("cost", d.value)?;
        out.set_item("levels_searched", d.levels_searched)?;
        out.set_item("levels_requested", d.levels_requested)?;
        out.set_item("nodes", d.nodes)?;
        out.set_item("next", PyArray1::from_vec(py, vec![d.next.pos.x, d.next.pos.y, d.next.pos.z]))?;
        out.set_item("turn", d.motion.dpsi)?;
        out.set_item("pitch_change", d.motion.dphi)?;
        Ok(out)
    }

    fn __repr__(&self) -> String {
        let c = self.inner.config();
        format!(
            "Planner(look_ahead={}, heading_options={}, tau={})",
            c.look_ahead, c.motion.heading_options, c.motion.tau
        )
    }
}

/// The whole pre-deployment plan of a "plan" scenario, as `coopnav plan` computes it. Returns a
/// dict: `steps` (per τ: time, CNA pose, cost; per AUV: position, error variances, distance),
/// `decisions` and `summary` (summary.json's content).
#[pyfunction]
fn plan<'py>(py: Python<'py>, scenario: &Scenario) -> PyResult<Bound<'py, PyDict>> {
    let Kind::Plan(sc) = &scenario.kind else {
        return Err(PyValueError::new_err("plan needs a \"plan\" scenario, not \"simulate\""));
    };
    let mission = sc.build(&scenario.file, &scenario.base).map_err(value_error)?;
    let mut planner = LookAheadPlanner::new(mission.planner).map_err(value_error)?;
    let result = py.detach(|| predeploy::run(&mission, &mut planner, &|_| {})).map_err(value_error)?;
    let s = &result.steps;
    let per_auv = |f: &dyn Fn(&predeploy::StepRecord, usize) -> f64| -> PyResult<Bound<'py, PyAny>> {
        let n = mission.tracks.len();
        let flat: Vec<f64> = s.iter().flat_map(|r| (0..n).map(move |k| f(r, k))).collect();
        Ok(PyArray1::from_vec(py, flat).reshape([s.len(), n])?.into_any())
    };
    let steps = columns(
        py,
        [
            ("t", column(py, s.iter().map(|r| r.t)).into_any()),
            ("cna_x", column(py, s.iter().map(|r| r.cna.pos.x)).into_any()),
            ("cna_y", column(py, s.iter().map(|r| r.cna.pos.y)).into_any()),
            ("cna_z", column(py, s.iter().map(|r| r.cna.pos.z)).into_any()),
            ("cna_heading", column(py, s.iter().map(|r| r.cna.heading.radians())).into_any()),
            ("cna_pitch", column(py, s.iter().map(|r| r.cna.pitch)).into_any()),
            ("cost", column(py, s.iter().map(|r| r.cost)).into_any()),
            ("penalised_cost", column(py, s.iter().map(|r| r.penalised_cost)).into_any()),
            ("auv_x", per_auv(&|r, k| r.auv[k].x)?),
            ("auv_y", per_auv(&|r, k| r.auv[k].y)?),
            ("auv_z", per_auv(&|r, k| r.auv[k].z)?),
            ("sigma2", per_auv(&|r, k| r.errors[k].sigma2)?),
            ("eps2", per_auv(&|r, k| r.errors[k].eps2)?),
            ("distance", per_auv(&|r, k| r.distance[k])?),
        ],
    )?;
    let d = &result.decisions;
    let decisions = columns(
        py,
        [
            ("option", PyArray1::from_vec(py, d.iter().map(|x| x.option as i64).collect()).into_any()),
            ("cost", column(py, d.iter().map(|x| x.value)).into_any()),
            (
                "levels_searched",
                PyArray1::from_vec(py, d.iter().map(|x| x.levels_searched as i64).collect()).into_any(),
            ),
        ],
    )?;
    let out = PyDict::new(py);
    out.set_item("names", mission.names.clone())?;
    out.set_item("steps", steps)?;
    out.set_item("decisions", decisions)?;
    out.set_item("summary", to_py(py, &result.summary)?)?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Planner>()?;
    m.add_function(wrap_pyfunction!(plan, m)?)
}
