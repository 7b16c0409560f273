//! Between Python values and pkm's: a `Serialize` result as plain Python objects, a
//! dict as the TOML text of a machine file, numpy arrays as row-major slices.

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use rayon::prelude::*;

use crate::errors::invalid;

/// A JSON value as Python objects (dicts, lists, floats, ints, str, None).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => PyBool::new(py, *b).to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_f64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(f)) => PyFloat::new(py, f).into_any(),
            _ => py.None().into_bound(py),
        },
        Value::String(s) => PyString::new(py, s).into_any(),
        Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// A `Serialize` value as Python objects. serde_json writes non-finite floats as
/// null: they come back as None.
pub fn to_py<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let j = serde_json::to_value(v).map_err(|e| invalid("result", e.to_string()))?;
    json_to_py(py, &j)
}

/// A Python value (dict, list, str, number, bool) as a TOML value; `path` names it
/// in errors (`struts[2].length`).
pub fn py_to_toml(v: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
    if v.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(v.extract()?));
    }
    if v.is_instance_of::<PyInt>() {
        return match v.extract::<i64>() {
            Ok(i) => Ok(toml::Value::Integer(i)),
            Err(_) => Err(invalid(path, "integer beyond 64 bits")),
        };
    }
    if v.is_instance_of::<PyString>() {
        return Ok(toml::Value::String(v.extract()?));
    }
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::map::Map::new();
        for (k, x) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| invalid(path, "dict keys must be strings"))?;
            let p = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            t.insert(k, py_to_toml(&x, &p)?);
        }
        return Ok(toml::Value::Table(t));
    }
    if v.is_instance_of::<PyList>() || v.is_instance_of::<PyTuple>() {
        let mut a = Vec::new();
        for (i, x) in v.try_iter()?.enumerate() {
            a.push(py_to_toml(&x?, &format!("{path}[{i}]"))?);
        }
        return Ok(toml::Value::Array(a));
    }
    // numpy arrays and scalars, anything with a float value.
    if let Ok(l) = v.call_method0("tolist") {
        if !l.is(v) && (l.is_instance_of::<PyList>() || !l.hasattr("tolist")?) {
            return py_to_toml(&l, path);
        }
    }
    match v.extract::<f64>() {
        Ok(f) => Ok(toml::Value::Float(f)),
        Err(_) => Err(invalid(
            path,
            format!(
                "expected a dict, list, string, number or bool, got {}",
                v.get_type().name()?
            ),
        )),
    }
}

/// A float64 array (any shape, any strides) as a row-major vector with its shape;
/// other dtypes are converted by numpy first (`numpy.asarray(x, dtype=float)`).
pub fn array(v: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let py = v.py();
    let arr: PyReadonlyArrayDyn<f64> = match v.extract() {
        Ok(a) => a,
        Err(_) => {
            let np = py.import("numpy")?;
            let c = np
                .call_method1("asarray", (v, np.getattr("float64")?))
                .map_err(|e| invalid(what, format!("expected an array of numbers: {e}")))?;
            c.extract()
                .map_err(|e| invalid(what, format!("expected an array of numbers: {e}")))?
        }
    };
    let shape = arr.shape().to_vec();
    // `as_slice` also accepts a Fortran-ordered array, whose memory is column-major:
    // only a C-contiguous one is copied as it lies (reading a Fortran array's memory
    // as rows gave wrong poses).
    let data = match arr.as_slice() {
        Ok(s) if arr.is_c_contiguous() => s.to_vec(),
        _ => arr.as_array().iter().copied().collect(),
    };
    Ok((data, shape))
}

/// Rows of `width` read from a numpy array: borrowed where the array is C-contiguous
/// float64 (a million poses are 48 MB: copying them, page faults included, took a
/// third of a batch), copied otherwise.
pub struct RowsRef<'py> {
    borrowed: Option<numpy::PyReadonlyArrayDyn<'py, f64>>,
    owned: Vec<f64>,
    /// The array was one row, shape `(width,)`.
    pub single: bool,
}

impl RowsRef<'_> {
    /// The values, row-major.
    pub fn values(&self) -> &[f64] {
        match &self.borrowed {
            Some(a) => a.as_slice().unwrap_or(&[]),
            None => &self.owned,
        }
    }
}

/// [`rows`] without copying a C-contiguous float64 array; the values are checked on
/// all cores.
pub fn rows_ref<'py>(v: &Bound<'py, PyAny>, width: usize, what: &str) -> PyResult<RowsRef<'py>> {
    let borrowed = v
        .extract::<numpy::PyReadonlyArrayDyn<'py, f64>>()
        .ok()
        .filter(|a| a.is_c_contiguous() && a.as_slice().is_ok());
    let Some(arr) = borrowed else {
        let (owned, single) = rows(v, width, what)?;
        return Ok(RowsRef {
            borrowed: None,
            owned,
            single,
        });
    };
    let single = shape_is_rows(arr.shape(), width, what)?;
    let r = RowsRef {
        borrowed: Some(arr),
        owned: Vec::new(),
        single,
    };
    let data = r.values();
    let max = pkm::machine::MAX_MAGNITUDE;
    // By blocks of 64 Ki values: rayon's per-element `position_first` polls a shared
    // flag per value, and took a third of a million-pose batch.
    const BLOCK: usize = 1 << 16;
    let bad = v.py().detach(|| {
        let block = data
            .par_chunks(BLOCK)
            .position_first(|c| c.iter().any(|x| !(x.abs() <= max)))?;
        let start = block * BLOCK;
        data[start..]
            .iter()
            .position(|x| !(x.abs() <= max))
            .map(|i| start + i)
    });
    if let Some(i) = bad {
        return Err(out_of_range(data, i, width, what));
    }
    Ok(r)
}

/// Whether `shape` is one row of `width` (else rows of it); an error naming `what`
/// for any other shape.
fn shape_is_rows(shape: &[usize], width: usize, what: &str) -> PyResult<bool> {
    match shape {
        [w] if *w == width => Ok(true),
        [_, w] if *w == width => Ok(false),
        _ => Err(invalid(
            what,
            format!("expected shape (N, {width}) or ({width},), got {shape:?}"),
        )),
    }
}

/// The error of value `i` of `data`, not finite or beyond [`pkm::machine::MAX_MAGNITUDE`].
fn out_of_range(data: &[f64], i: usize, width: usize, what: &str) -> PyErr {
    let max = pkm::machine::MAX_MAGNITUDE;
    let what_is = if data[i].is_finite() {
        format!("beyond the largest magnitude pkm takes ({max:.0e} mm or rad)")
    } else {
        "not a finite number".into()
    };
    invalid(
        what,
        format!(
            "row {}, column {}: {:e} is {what_is}",
            i / width,
            i % width,
            data[i]
        ),
    )
}

/// Rows of `width` from an array of shape `(n, width)` or `(width,)`; whether it was
/// one row. Every value must be finite and at most
/// [`pkm::machine::MAX_MAGNITUDE`] (1e6 mm or rad) in size, as the `pkm` command
/// takes its values: beyond, the kinematics compute with numbers that mean nothing.
pub fn rows(v: &Bound<'_, PyAny>, width: usize, what: &str) -> PyResult<(Vec<f64>, bool)> {
    let (data, shape) = array(v, what)?;
    let single = shape_is_rows(&shape, width, what)?;
    let max = pkm::machine::MAX_MAGNITUDE;
    if let Some(i) = data.iter().position(|x| !(x.abs() <= max)) {
        return Err(out_of_range(&data, i, width, what));
    }
    Ok((data, single))
}

/// The one pose of `width` coordinates `v` holds, if given: a single row of [`rows`].
pub fn one_pose(
    v: Option<&Bound<'_, PyAny>>,
    width: usize,
    what: &str,
) -> PyResult<Option<Vec<f64>>> {
    v.map(|v| {
        let (x, one) = rows(v, width, what)?;
        if !one {
            return Err(invalid(what, "expected one pose"));
        }
        Ok(x)
    })
    .transpose()
}

/// A vector as a 1-D numpy array (no copy).
pub fn vec1<'py, T: numpy::Element>(py: Python<'py>, v: Vec<T>) -> Bound<'py, PyArray1<T>> {
    PyArray1::from_vec(py, v)
}

/// A row-major vector as an `(n, width)` numpy array (no copy).
pub fn vec2<'py>(py: Python<'py>, v: Vec<f64>, width: usize) -> PyResult<Bound<'py, PyAny>> {
    let n = v.len().checked_div(width).unwrap_or(0);
    Ok(PyArray1::from_vec(py, v).reshape([n, width])?.into_any())
}
