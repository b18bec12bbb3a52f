//! The acoustic channel from Python: transmission loss (analytic spreading + Thorp absorption,
//! the real BELLHOP when installed, or a cached grid of either) and the WHOI packet-success
//! likelihood per rate, both vectorised over numpy arrays — the models `coopnav channel` tabulates.

use crate::convert::settings;
use crate::value_error;
use coopnav_acomms::tl::analytic::Thorp;
use coopnav_acomms::tl::bellhop::{AcousticEnv, Bellhop};
use coopnav_acomms::tl::cached::{CachedGrid, GridSpec};
use coopnav_acomms::{Rate, SuccessModel, TransmissionLoss as Tl};
use coopnav_core::validation::{CheckFields, Problems};
use coopnav_core::{Bathymetry, Shelf, Vec3};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

/// A transmission-loss model (dB re 1 m).
#[pyclass(module = "coopnav", name = "TransmissionLoss", frozen)]
pub struct TransmissionLoss {
    model: Arc<dyn Tl>,
    name: String,
}

fn vec3(p: [f64; 3]) -> Vec3 {
    Vec3::new(p[0], p[1], p[2])
}

#[pymethods]
impl TransmissionLoss {
    /// Spreading k·10·log10(d) plus Thorp absorption at `freq_hz` (`coopnav channel --k`).
    #[staticmethod]
    #[pyo3(signature = (k = 1.5, freq_hz = 25000.0))]
    fn analytic(k: f64, freq_hz: f64) -> PyResult<Self> {
        if !(k > 0.0 && k <= 4.0 && freq_hz > 0.0 && freq_hz.is_finite()) {
            return Err(PyValueError::new_err(format!("k {k} must be in (0, 4] and freq_hz {freq_hz} > 0")));
        }
        Ok(TransmissionLoss { model: Arc::new(Thorp { k, freq_hz }), name: format!("analytic(k={k})") })
    }

    /// The real BELLHOP program in the thesis's environment over `bathymetry` (an ESRI ASCII grid
    /// or x,y,depth CSV; default the synthetic shelf). Raises `ValueError` when BELLHOP is not
    /// installed ($COOPNAV_BELLHOP or tools/bellhop/bellhop.exe; scripts/install-bellhop.sh).
    #[staticmethod]
    #[pyo3(signature = (bathymetry = None))]
    fn bellhop(bathymetry: Option<PathBuf>) -> PyResult<Self> {
        let bathy = match bathymetry {
            Some(p) => Bathymetry::load(&p),
            None => Bathymetry::shelf(&Shelf::default()),
        }
        .map_err(value_error)?;
        let model = Bellhop::new(AcousticEnv::nams(Arc::new(bathy))).map_err(value_error)?;
        Ok(TransmissionLoss { model: Arc::new(model), name: "bellhop".into() })
    }

    /// This model run once per bearing from `anchor` (x, y, depth) over a range × depth grid
    /// (`grid`: bearings, range_step, max_range, depth_step, max_depth) and interpolated after.
    fn cached(&self, py: Python<'_>, anchor: [f64; 3], grid: &Bound<'_, PyAny>) -> PyResult<Self> {
        let spec: GridSpec = toml::from_str(&crate::convert::toml_text(grid, "grid")?)
            .map_err(|e| PyValueError::new_err(format!("grid: {e}")))?;
        let model = &*self.model;
        let cached = py.detach(|| CachedGrid::build(model, vec3(anchor), spec, &|_| {})).map_err(value_error)?;
        Ok(TransmissionLoss { model: Arc::new(cached), name: format!("cached({})", self.name) })
    }

    /// TL from `source` (x, y, depth) to each receiver row of `receivers` (M, 3).
    fn between<'py>(
        &self,
        py: Python<'py>,
        source: [f64; 3],
        receivers: PyReadonlyArray2<'_, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let rx = receivers.as_array();
        if rx.ncols() != 3 {
            return Err(PyValueError::new_err(format!("receivers: expected shape (M, 3), got {:?}", rx.shape())));
        }
        let points: Vec<Vec3> = rx.rows().into_iter().map(|r| Vec3::new(r[0], r[1], r[2])).collect();
        let src = vec3(source);
        let model = &*self.model;
        let tl = py.detach(|| points.iter().map(|p| model.tl(&src, p)).collect::<Result<Vec<f64>, _>>());
        Ok(PyArray1::from_vec(py, tl.map_err(value_error)?))
    }

    /// TL over `ranges` (m) × receiver `depths` (m) along the radial from `source` (x, y, depth)
    /// at `bearing_deg` (math: 0 = east, counter-clockwise): shape (len(depths), len(ranges)).
    #[pyo3(signature = (source, bearing_deg, ranges, depths))]
    fn field<'py>(
        &self,
        py: Python<'py>,
        source: [f64; 3],
        bearing_deg: f64,
        ranges: PyReadonlyArray1<'_, f64>,
        depths: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let (r, z) = (ranges.as_slice()?.to_vec(), depths.as_slice()?.to_vec());
        let model = &*self.model;
        let f = py.detach(|| model.field(&vec3(source), bearing_deg.to_radians(), &r, &z)).map_err(value_error)?;
        Ok(PyArray1::from_vec(py, f).reshape([z.len(), r.len()])?)
    }

    fn __repr__(&self) -> String {
        format!("TransmissionLoss({})", self.name)
    }
}

/// Likelihood that a packet at WHOI `rate` (0..=5) gets through `tl_db` (array or number) of
/// transmission loss, with `noise_db` extra ambient noise; `model` overrides
/// `coopnav_acomms::SuccessModel` fields (curves, partial) as a dict or TOML.
#[pyfunction]
#[pyo3(signature = (rate, tl_db, noise_db = 0.0, model = None))]
fn p_success<'py>(
    py: Python<'py>,
    rate: u8,
    tl_db: PyReadonlyArray1<'_, f64>,
    noise_db: f64,
    model: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let rate = Rate::new(rate).map_err(value_error)?;
    let mut m: SuccessModel = settings(model, "success model")?;
    m.noise_db = noise_db;
    let mut problems = Problems::new();
    m.check_fields("", &mut problems);
    problems.finish().map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(PyArray1::from_vec(py, tl_db.as_array().iter().map(|&tl| m.p_success(rate, tl)).collect()))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<TransmissionLoss>()?;
    m.add_function(wrap_pyfunction!(p_success, m)?)
}
