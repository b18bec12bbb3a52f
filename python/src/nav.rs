//! OWTT navigation from Python: the survey-AUV EKF (Gill's 5 states E, N, speed, heading, compass
//! bias) and the surface-vehicle EKF (E, N, speed, heading) stepped call by call, and the
//! post-processing of a logged mission (EKF + RTS smoother) from a log file or numpy columns.
//! Headings are math radians (0 = east, counter-clockwise) in the filters; the log keeps its own
//! units (compass degrees, see `coopnav_nav::post`).

use crate::convert::{column, columns, or_nan, settings, to_py, toml_text};
use crate::value_error;
use coopnav_core::validation::CheckFields;
use coopnav_core::Vec3;
use coopnav_nav::post::{self, PostConfig, PostResult, LOG_HEADER};
use coopnav_nav::{AuvParams, RangeMeasurement, StateKind, SurfaceParams, UpdateOutcome};
use nalgebra::SMatrix;
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// What happened to a measurement: "applied", "gated" or "unusable".
fn outcome(o: UpdateOutcome) -> &'static str {
    match o {
        UpdateOutcome::Applied { .. } => "applied",
        UpdateOutcome::Gated { .. } => "gated",
        UpdateOutcome::Unusable => "unusable",
    }
}

/// A filter class's Python methods: its own (`$own`), plus the getters every filter shares —
/// `t` (its time, s), `state` (the state vector) and `covariance` (its matrix).
macro_rules! filter_methods {
    ($class:ident { $($own:tt)* }) => {
        #[pymethods]
        impl $class {
            $($own)*

            #[getter]
            fn t(&self) -> f64 {
                self.inner.ekf().t()
            }

            #[getter]
            fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
                PyArray1::from_vec(py, self.inner.ekf().x().iter().copied().collect())
            }

            #[getter]
            fn covariance<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
                covariance_array(py, self.inner.ekf().p())
            }
        }
    };
}

fn covariance_array<'py, const N: usize>(
    py: Python<'py>,
    p: &SMatrix<f64, N, N>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    // nalgebra stores column-major; the matrix is symmetric but we keep rows as rows anyway.
    let rows: Vec<f64> = (0..N).flat_map(|i| (0..N).map(move |j| p[(i, j)])).collect();
    Ok(PyArray1::from_vec(py, rows).reshape([N, N])?)
}

/// The survey AUV's navigation filter; state [E, N, speed, heading, compass bias], covariance 5 × 5.
#[pyclass(module = "coopnav", name = "AuvEkf")]
pub struct AuvEkf {
    inner: coopnav_nav::AuvEkf<5>,
}

filter_methods!(AuvEkf {
    /// Starts at time `t0` from position (e, n), `speed` and math `heading` (rad), zero compass
    /// bias; `params` overrides `coopnav_nav::AuvParams` fields (dict or TOML).
    #[new]
    #[pyo3(signature = (t0, e, n, speed, heading, params = None))]
    fn new(t0: f64, e: f64, n: f64, speed: f64, heading: f64, params: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        let params: AuvParams = settings(params, "AuvEkf params")?;
        params.validate("").map_err(value_error)?;
        Ok(AuvEkf { inner: coopnav_nav::AuvEkf::new(t0, e, n, speed, heading, params) })
    }

    /// Dead-reckons to time `t` with the measured heading rate `yaw_rate` (rad/s, math sense);
    /// False when `t` is not after the filter's time (nothing done).
    #[pyo3(signature = (t, yaw_rate = 0.0))]
    fn predict(&mut self, t: f64, yaw_rate: f64) -> bool {
        self.inner.predict_to(t, yaw_rate)
    }

    /// Speed-sensor update (m/s).
    fn update_speed(&mut self, speed: f64) -> &'static str {
        outcome(self.inner.update_speed(speed))
    }

    /// Compass update (math radians; the compass reads heading + bias).
    fn update_heading(&mut self, heading: f64) -> &'static str {
        outcome(self.inner.update_heading(heading))
    }

    /// OWTT range update: `range` (m) measured over `travel_time` (s) from a transponder at
    /// `transponder` (x, y, depth) at transmit time. `auv_depth` selects the 3-D slant range;
    /// `transponder_sd` (m) adds the transponder's own position uncertainty.
    #[pyo3(signature = (range, travel_time, transponder, auv_depth = None, transponder_sd = 0.0))]
    fn update_range(
        &mut self,
        range: f64,
        travel_time: f64,
        transponder: [f64; 3],
        auv_depth: Option<f64>,
        transponder_sd: f64,
    ) -> &'static str {
        let [x, y, z] = transponder;
        let m = RangeMeasurement { range, travel_time, transponder: Vec3::new(x, y, z) };
        outcome(self.inner.update_range_from_uncertain(&m, auv_depth, transponder_sd))
    }
});

fn surface_params(params: Option<&Bound<'_, PyAny>>) -> PyResult<SurfaceParams> {
    let Some(p) = params else { return Ok(SurfaceParams::ship()) };
    if let Ok(name) = p.extract::<String>() {
        match name.as_str() {
            "ship" => return Ok(SurfaceParams::ship()),
            "buoy" => return Ok(SurfaceParams::buoy()),
            _ => {}
        }
    }
    let params: SurfaceParams = toml::from_str(&toml_text(p, "SurfaceEkf params")?)
        .map_err(|e| PyValueError::new_err(format!("SurfaceEkf params: {e}")))?;
    params.validate("").map_err(value_error)?;
    Ok(params)
}

/// A surface vehicle's filter, as the AUV runs it on the ship's or buoy's broadcast states;
/// state [E, N, speed, heading], covariance 4 × 4.
#[pyclass(module = "coopnav", name = "SurfaceEkf")]
pub struct SurfaceEkf {
    inner: coopnav_nav::SurfaceEkf,
}

filter_methods!(SurfaceEkf {
    /// `params`: "ship" (default), "buoy", or every `coopnav_nav::SurfaceParams` field (dict or TOML).
    #[new]
    #[pyo3(signature = (t0, e, n, speed, heading, params = None))]
    fn new(t0: f64, e: f64, n: f64, speed: f64, heading: f64, params: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        Ok(SurfaceEkf { inner: coopnav_nav::SurfaceEkf::new(t0, e, n, speed, heading, surface_params(params)?) })
    }

    /// Predicts to time `t` (in nominal steps).
    fn predict(&mut self, t: f64) {
        self.inner.predict_to(t);
    }

    /// Scalar update of one state: `kind` "east", "north", "speed" or "heading" (math rad).
    fn update(&mut self, kind: &str, value: f64) -> PyResult<&'static str> {
        let kind = match kind {
            "east" => StateKind::East,
            "north" => StateKind::North,
            "speed" => StateKind::Speed,
            "heading" => StateKind::Heading,
            other => return Err(PyValueError::new_err(format!("kind '{other}': allowed east, north, speed, heading"))),
        };
        Ok(outcome(self.inner.update(kind, value)))
    }
});

/// The log as CSV text: a path's content, or numpy/list columns `t, kind, src, v1..v4` written
/// in the log format (NaN and None become empty fields), so both are read by the same reader.
fn log_text(log: &Bound<'_, PyAny>) -> PyResult<(String, String)> {
    if let Ok(path) = log.extract::<PathBuf>() {
        let text = coopnav_core::limits::read_text(
            &path,
            "post-processing log (bytes)",
            coopnav_sim::batch::work::max_postprocess_log_bytes(),
            false,
        )
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
        return Ok((text, path.display().to_string()));
    }
    let cols: Vec<Vec<Option<String>>> = LOG_HEADER
        .iter()
        .map(|name| {
            let col = log.get_item(name).map_err(|_| PyValueError::new_err(format!("log: no column '{name}'")))?;
            col.try_iter()?.map(|v| field(&v?)).collect::<PyResult<Vec<_>>>()
        })
        .collect::<PyResult<_>>()?;
    let rows = cols[0].len();
    if let Some((i, _)) = cols.iter().enumerate().find(|(_, c)| c.len() != rows) {
        return Err(PyValueError::new_err(format!(
            "log: column '{}' has {} rows, 't' has {rows}",
            LOG_HEADER[i],
            cols[i].len()
        )));
    }
    let mut text = LOG_HEADER.join(",") + "\n";
    for r in 0..rows {
        let row: Vec<&str> = cols.iter().map(|c| c[r].as_deref().unwrap_or("")).collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    Ok((text, "<arrays>".into()))
}

/// One log field as text: a number in Rust's round-trip form, a string as is, NaN/None empty.
fn field(v: &Bound<'_, PyAny>) -> PyResult<Option<String>> {
    if v.is_none() {
        return Ok(None);
    }
    if let Ok(s) = v.extract::<String>() {
        return Ok(Some(s));
    }
    let x: f64 = v.extract()?;
    Ok((!x.is_nan()).then(|| x.to_string()))
}

fn samples<'py>(py: Python<'py>, r: &PostResult) -> PyResult<Bound<'py, PyDict>> {
    let s = &r.samples;
    let col = |f: &dyn Fn(&post::PostSample) -> f64| column(py, s.iter().map(f)).into_any();
    columns(
        py,
        [
            ("t", col(&|x| x.t)),
            ("filt_e", col(&|x| x.filtered[0])),
            ("filt_n", col(&|x| x.filtered[1])),
            ("filt_sd_e", col(&|x| x.filtered_sd[0])),
            ("filt_sd_n", col(&|x| x.filtered_sd[1])),
            ("smooth_e", col(&|x| x.smoothed[0])),
            ("smooth_n", col(&|x| x.smoothed[1])),
            ("smooth_sd_e", col(&|x| x.smoothed_sd[0])),
            ("smooth_sd_n", col(&|x| x.smoothed_sd[1])),
            ("true_e", col(&|x| or_nan(x.truth.map(|p| p[0])))),
            ("true_n", col(&|x| or_nan(x.truth.map(|p| p[1])))),
            ("smooth_heading_bias", col(&|x| x.smoothed_heading_bias)),
            ("smooth_current_e", col(&|x| or_nan(x.smoothed_current.map(|c| c[0])))),
            ("smooth_current_n", col(&|x| or_nan(x.smoothed_current.map(|c| c[1])))),
        ],
    )
}

/// Post-processes a logged mission (EKF forward, RTS smoother backward) as `coopnav hbl
/// postprocess` does. `log`: a CSV log path, or a dict of columns t, kind, src, v1..v4; `config`:
/// the post-processing config (dict or TOML, `coopnav hbl example post`). Returns `samples`
/// (numpy columns as estimates.csv), `residuals` and `summary`.
#[pyfunction]
#[pyo3(signature = (log, config = None))]
fn postprocess<'py>(
    py: Python<'py>,
    log: &Bound<'py, PyAny>,
    config: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let cfg = match config {
        None => PostConfig::default(),
        Some(c) => PostConfig::from_toml(&toml_text(c, "post-processing config")?).map_err(value_error)?,
    };
    let (text, name) = log_text(log)?;
    let too_large = |e: coopnav_core::limits::TooLarge| PyValueError::new_err(e.to_string());
    coopnav_core::limits::check([coopnav_sim::batch::work::postprocess_log(&name, text.len() as u64)], false)
        .map_err(too_large)?;
    let log = post::read_any_log(text.as_bytes(), &cfg)
        .map_err(|e| PyValueError::new_err(format!("in {name}: {}", crate::cause_chain(&e))))?;
    // The same work limits as `coopnav hbl postprocess`, before the filter allocates its history.
    coopnav_core::limits::check(coopnav_sim::batch::work::postprocess(&log.rows, &cfg), false).map_err(too_large)?;
    let result = py.detach(|| post::postprocess_rows(&log.rows, &cfg)).map_err(value_error)?;
    let out = PyDict::new(py);
    out.set_item("samples", samples(py, &result)?)?;
    out.set_item("residuals", to_py(py, &result.residuals)?)?;
    out.set_item("summary", to_py(py, &result.summary)?)?;
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<AuvEkf>()?;
    m.add_class::<SurfaceEkf>()?;
    m.add_function(wrap_pyfunction!(postprocess, m)?)
}
