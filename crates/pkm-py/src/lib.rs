//! Python bindings of pkm (`import pkm`): machines from files, TOML text or dicts;
//! kinematics on numpy arrays with the GIL released and rayon inside; the analyses of
//! `pkm::analysis` with numpy arrays and plain dicts out; pkm's errors as a
//! `pkm.Error` hierarchy. A thin front end: every computation is the library's.
//!
//! Units: millimetres and radians in and out of arrays (numpy's convention, as in
//! Pinocchio and the Robotics Toolbox); limit violations and summaries carry their
//! unit (deg for angles, as pkm prints them).

// PyO3's generated code for `PyResult` functions trips this lint.
#![allow(clippy::useless_conversion)]
// `!(x <= max)` is used on purpose: it is also true for NaN, which must be refused.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use pyo3::prelude::*;

mod analyses;
mod convert;
mod errors;
mod identification;
mod kinematics;
mod machine;
mod motion;

pub use machine::Machine;

/// pkm's extension module (`pkm._pkm`); the Python package `pkm` re-exports it.
#[pymodule]
fn _pkm(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<machine::Machine>()?;
    m.add_class::<kinematics::IkBatch>()?;
    m.add_class::<kinematics::FkBatch>()?;
    m.add_function(wrap_pyfunction!(machine::load, m)?)?;
    m.add_function(wrap_pyfunction!(machine::machine_types, m)?)?;
    m.add_function(wrap_pyfunction!(identification::simulate_measurements, m)?)?;
    m.add_function(wrap_pyfunction!(identification::calibrate, m)?)?;
    errors::register(m)?;
    Ok(())
}
