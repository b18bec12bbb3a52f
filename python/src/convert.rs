//! Conversions between Python objects and the libraries' types: serde values go through JSON
//! (Python's own `json` module), so a dict in is exactly what a TOML file would hold and a dict
//! out is exactly what the CLI writes to its JSON files.

use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::de::DeserializeOwned;
use serde::Serialize;

/// Any serialisable value as the Python object `json.loads` makes of it.
pub fn to_py<'py>(py: Python<'py>, value: &impl Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| PyValueError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A Python container (dict, list, numbers, strings) as a JSON value. Keys holding `None` are
/// dropped: an absent key is how TOML says "none", and `to_dict()` writes absent options as `None`.
pub fn to_json(obj: &Bound<'_, PyAny>) -> PyResult<serde_json::Value> {
    if let Some((field, value)) = non_finite(obj, "")? {
        return Err(PyValueError::new_err(format!("field {field} = {value}: allowed a finite number")));
    }
    let text: String = obj.py().import("json")?.call_method1("dumps", (obj,))?.extract()?;
    let mut value = serde_json::from_str(&text).map_err(|e| PyValueError::new_err(e.to_string()))?;
    drop_nulls(&mut value);
    Ok(value)
}

/// The first NaN or infinite float inside `obj`, with its field path (`fleet.current[0]`): JSON
/// cannot carry it, and a message must name where it is.
fn non_finite(obj: &Bound<'_, PyAny>, at: &str) -> PyResult<Option<(String, f64)>> {
    if let Ok(dict) = obj.cast::<PyDict>() {
        for (key, value) in dict.iter() {
            let key: String = key.str()?.extract()?;
            let path = if at.is_empty() { key } else { format!("{at}.{key}") };
            if let Some(found) = non_finite(&value, &path)? {
                return Ok(Some(found));
            }
        }
    } else if let Ok(list) = obj.cast::<pyo3::types::PyList>() {
        for (i, value) in list.iter().enumerate() {
            if let Some(found) = non_finite(&value, &format!("{at}[{i}]"))? {
                return Ok(Some(found));
            }
        }
    } else if let Ok(tuple) = obj.cast::<pyo3::types::PyTuple>() {
        for (i, value) in tuple.iter().enumerate() {
            if let Some(found) = non_finite(&value, &format!("{at}[{i}]"))? {
                return Ok(Some(found));
            }
        }
    } else if let Ok(float) = obj.cast::<pyo3::types::PyFloat>() {
        let v = float.value();
        if !v.is_finite() {
            return Ok(Some((at.to_string(), v)));
        }
    }
    Ok(None)
}

fn drop_nulls(value: &mut serde_json::Value) {
    match value {
        serde_json::Value::Object(map) => {
            map.retain(|_, v| !v.is_null());
            map.values_mut().for_each(drop_nulls);
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(drop_nulls),
        _ => {}
    }
}

/// A TOML text, or a dict turned into one (so both go through the same parser and messages).
pub fn toml_text(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<String> {
    if let Ok(text) = obj.extract::<String>() {
        return Ok(text);
    }
    if obj.is_instance_of::<PyDict>() {
        return toml::to_string(&to_json(obj)?).map_err(|e| PyValueError::new_err(format!("{what}: {e}")));
    }
    Err(PyValueError::new_err(format!("{what}: expected a dict or a TOML string")))
}

/// A settings struct from a dict or TOML string, or its default for `None`.
pub fn settings<T: DeserializeOwned + Default>(obj: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<T> {
    match obj {
        None => Ok(T::default()),
        Some(o) => toml::from_str(&toml_text(o, what)?).map_err(|e| PyValueError::new_err(format!("{what}: {e}"))),
    }
}

/// A column of numbers as a 1-D array.
pub fn column<'py>(py: Python<'py>, values: impl IntoIterator<Item = f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, values.into_iter().collect())
}

/// Rows of equal length as a 2-D array.
pub fn matrix<'py, const W: usize>(py: Python<'py>, rows: &[[f64; W]]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    Ok(PyArray1::from_vec(py, flat).reshape([rows.len(), W])?)
}

/// A dict of named columns (a `pandas.DataFrame` takes it directly).
pub fn columns<'py>(
    py: Python<'py>,
    named: impl IntoIterator<Item = (&'static str, Bound<'py, PyAny>)>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, col) in named {
        d.set_item(name, col)?;
    }
    Ok(d)
}

/// An optional number as a float, NaN for none (so a column stays numeric).
pub fn or_nan(v: Option<f64>) -> f64 {
    v.unwrap_or(f64::NAN)
}
