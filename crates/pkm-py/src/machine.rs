//! `pkm.Machine`: a loaded machine (immutable, shared by reference between threads)
//! with its metadata; `pkm.load`.

use std::sync::Arc;

use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::{self, vec1};
use crate::errors::{invalid, to_py};

/// A machine: its mechanism, limits, parameters and tolerances, read from a pkm
/// machine file (TOML), a URDF robot, TOML text or a dict. Immutable; arrays in and
/// out are in mm and rad.
#[pyclass(module = "pkm", frozen)]
pub struct Machine {
    pub(crate) inner: Arc<pkm::Machine>,
    /// The TOML text it was read from (a simulated campaign writes the true machine
    /// from it); `None` for URDF files.
    pub(crate) text: Option<String>,
}

impl Machine {
    pub(crate) fn new(inner: pkm::Machine, text: Option<String>) -> Self {
        Machine {
            inner: Arc::new(inner),
            text,
        }
    }

    pub(crate) fn m(&self) -> &dyn pkm::DynMechanism {
        self.inner.mechanism()
    }
}

/// Loads a machine file: a pkm machine file (`.toml`) or a URDF robot (`.urdf`).
/// Raises `pkm.MachineFileError` naming the file, line and field of what is wrong.
#[pyfunction]
pub fn load(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Machine> {
    let text = match path.extension().and_then(|e| e.to_str()) {
        Some("urdf") => None,
        _ => std::fs::read_to_string(&path).ok(),
    };
    let m = py
        .detach(|| pkm::Machine::from_path(&path))
        .map_err(to_py)?;
    Ok(Machine::new(m, text))
}

/// The machine types pkm reads (`type = ...` in a machine file), with what each is.
#[pyfunction]
pub fn machine_types() -> Vec<(&'static str, &'static str)> {
    pkm::machine::FILE_TYPES
        .iter()
        .map(|t| (t.name, t.summary))
        .collect()
}

#[pymethods]
impl Machine {
    /// A machine from the text of a machine file; `name` stands for the file in errors.
    #[staticmethod]
    #[pyo3(signature = (text, name = "<string>"))]
    fn from_toml(text: &str, name: &str) -> PyResult<Machine> {
        let m = pkm::Machine::from_toml_str(text, name).map_err(to_py)?;
        Ok(Machine::new(m, Some(text.to_string())))
    }

    /// A machine from a dict shaped like a machine file (what `tomllib.load` returns
    /// for one): a sweep builds its candidates this way. Values may be numpy scalars
    /// or arrays.
    #[staticmethod]
    #[pyo3(signature = (d, name = "<dict>"))]
    fn from_dict(d: &Bound<'_, PyDict>, name: &str) -> PyResult<Machine> {
        let v = convert::py_to_toml(d.as_any(), "")?;
        let text = toml::to_string(&v).map_err(|e| invalid(name, e.to_string()))?;
        Self::from_toml(&text, name)
    }

    /// The machine file's text (TOML) when it was read from one, a dict or text.
    #[getter]
    fn toml(&self) -> Option<String> {
        self.text.clone()
    }

    /// Machine name.
    #[getter]
    fn name(&self) -> String {
        self.m().name().to_string()
    }

    /// Machine type (`hexapod`, `tripod/translational`, `serial/tcp5`, ...).
    #[getter]
    fn kind(&self) -> &'static str {
        self.m().kind()
    }

    /// What the pose coordinates are: `spatial` (X, Y, Z, A, B, C), `position`
    /// (X, Y, Z), `tcp` (X, Y, Z and rotary axes), `own`.
    #[getter]
    fn pose_space(&self) -> PyResult<String> {
        Ok(serde_json::to_value(self.m().pose_space())
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default())
    }

    /// The pose coordinates: list of `{"name", "unit"}` (unit of arrays: mm or rad).
    #[getter]
    fn coordinates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let items = self
            .m()
            .coordinates()
            .iter()
            .map(|c| {
                let d = PyDict::new(py);
                d.set_item("name", &c.name)?;
                d.set_item("unit", internal_unit(c.quantity))?;
                Ok(d)
            })
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }

    /// The actuators: list of `{"name", "unit", "min", "max", "max_velocity",
    /// "max_acceleration", "stiffness"}` (mm or rad, per s, per s^2; N/mm or N mm/rad;
    /// None where not given).
    #[getter]
    fn actuators<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let items = self
            .m()
            .actuators()
            .iter()
            .map(|a| {
                let d = PyDict::new(py);
                d.set_item("name", &a.name)?;
                d.set_item("unit", internal_unit(a.quantity))?;
                d.set_item("min", a.range.min)?;
                d.set_item("max", a.range.max)?;
                d.set_item("max_velocity", a.max_velocity)?;
                d.set_item("max_acceleration", a.max_acceleration)?;
                d.set_item("stiffness", a.stiffness)?;
                Ok(d)
            })
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, items)
    }

    /// Indices of the coordinates the actuators drive (the others are held).
    #[getter]
    fn driven(&self) -> Vec<usize> {
        self.m().driven()
    }

    /// The home pose (mm, rad).
    #[getter]
    fn home<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.m().home())
    }

    /// The length (mm) that makes rotations and translations comparable in the
    /// condition number.
    #[getter]
    fn characteristic_length(&self) -> f64 {
        self.m().characteristic_length()
    }

    /// The analyses only some machine types run, and whether this one does:
    /// `{"identification": True, ...}`.
    #[getter]
    fn capabilities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for a in pkm::machine::Analysis::ALL {
            let key = serde_json::to_value(a)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default();
            d.set_item(key, self.inner.supports(a).is_ok())?;
        }
        Ok(d)
    }

    /// Pickling (Dask ships machines to workers this way): rebuilt from its TOML text.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, String))> {
        let text = self.text.clone().ok_or_else(|| {
            pyo3::exceptions::PyTypeError::new_err(
                "a machine loaded from a URDF file cannot be pickled: load it from its path \
                 where it is needed",
            )
        })?;
        let from_toml = py.get_type::<Machine>().getattr("from_toml")?;
        Ok((from_toml, (text, self.inner.source.clone())))
    }

    fn __repr__(&self) -> String {
        let m = self.m();
        format!(
            "<pkm.Machine {:?}: {}, {} coordinates ({}), {} actuators>",
            m.name(),
            m.kind(),
            m.coordinates().len(),
            m.coordinates()
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            m.actuators().len()
        )
    }
}

/// The unit of a quantity in arrays (internal units).
pub(crate) fn internal_unit(q: pkm::Quantity) -> &'static str {
    match q {
        pkm::Quantity::Length => "mm",
        pkm::Quantity::Angle => "rad",
    }
}
