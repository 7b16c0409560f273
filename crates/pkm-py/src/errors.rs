//! pkm's errors as Python exceptions: `pkm.Error` and one subclass per
//! [`pkm::Error`] variant, with the library's message and its structured fields as
//! attributes.

use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;

pyo3::create_exception!(
    pkm,
    Error,
    PyException,
    "Base of every pkm error; the message is pkm's, `details` its structured fields."
);
pyo3::create_exception!(
    pkm,
    MachineFileError,
    Error,
    "A machine file (or dict) that cannot be read or describes no valid machine: \
     `file`, `line`, `column`, `field` say where."
);
pyo3::create_exception!(
    pkm,
    InvalidInputError,
    Error,
    "A value that is not acceptable (wrong shape, not finite, out of range): `what` names it."
);
pyo3::create_exception!(
    pkm,
    UnreachableError,
    Error,
    "A pose or actuator set beyond the machine's limits: `violations` lists them."
);
pyo3::create_exception!(
    pkm,
    NotAttainableError,
    Error,
    "A pose the mechanism cannot produce at all: `reason` says why."
);
pyo3::create_exception!(
    pkm,
    NotConvergedError,
    Error,
    "An iterative solver that did not converge: `solver`, `iterations`, `residual`."
);
pyo3::create_exception!(
    pkm,
    NotIdentifiableError,
    Error,
    "Measurements that cannot determine a combination of parameters: `combination`."
);
pyo3::create_exception!(
    pkm,
    SingularError,
    Error,
    "A singular configuration for the requested operation: `what`, `rcond`."
);
pyo3::create_exception!(
    pkm,
    UnsupportedError,
    Error,
    "An analysis this machine type cannot run: `analysis`, `kind`, `reason`."
);

/// The exception of `e`, its fields set as attributes (and together as `details`).
pub fn to_py(e: pkm::Error) -> PyErr {
    Python::attach(|py| {
        let msg = e.to_string();
        let details = serde_details(py, &e);
        let err = match &e {
            pkm::Error::MachineFile { .. } => MachineFileError::new_err(msg),
            pkm::Error::InvalidInput { .. } => InvalidInputError::new_err(msg),
            pkm::Error::Unreachable { .. } => UnreachableError::new_err(msg),
            pkm::Error::NotAttainable { .. } => NotAttainableError::new_err(msg),
            pkm::Error::NotConverged { .. } => NotConvergedError::new_err(msg),
            pkm::Error::NotIdentifiable { .. } => NotIdentifiableError::new_err(msg),
            pkm::Error::Singular { .. } => SingularError::new_err(msg),
            pkm::Error::Unsupported { .. } => UnsupportedError::new_err(msg),
            _ => Error::new_err(msg),
        };
        if let Ok(d) = details {
            let value = err.value(py);
            for (k, v) in d.iter() {
                if let Ok(k) = k.extract::<String>() {
                    let _ = value.setattr(k.as_str(), v);
                }
            }
            let _ = value.setattr("details", d);
        }
        err
    })
}

/// The error's fields as a dict.
fn serde_details<'py>(py: Python<'py>, e: &pkm::Error) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    match e {
        pkm::Error::MachineFile {
            file,
            line,
            column,
            field,
            message,
        } => {
            d.set_item("file", file)?;
            d.set_item("line", line)?;
            d.set_item("column", column)?;
            d.set_item("field", field)?;
            d.set_item("reason", message)?;
        }
        pkm::Error::InvalidInput { what, message } => {
            d.set_item("what", what)?;
            d.set_item("reason", message)?;
        }
        pkm::Error::Unreachable { violations } => {
            let v = serde_json::to_value(violations).unwrap_or_default();
            d.set_item("violations", crate::convert::json_to_py(py, &v)?)?;
        }
        pkm::Error::NotAttainable { reason } => d.set_item("reason", reason.to_string())?,
        pkm::Error::NotConverged {
            solver,
            iterations,
            residual,
        } => {
            d.set_item("solver", solver)?;
            d.set_item("iterations", iterations)?;
            d.set_item("residual", residual)?;
        }
        pkm::Error::NotIdentifiable {
            combination,
            relative_singular_value,
        } => {
            d.set_item("combination", combination)?;
            d.set_item("relative_singular_value", relative_singular_value)?;
        }
        pkm::Error::Singular { what, rcond } => {
            d.set_item("what", what)?;
            d.set_item("rcond", rcond)?;
        }
        pkm::Error::Unsupported {
            machine,
            kind,
            analysis,
            reason,
        } => {
            d.set_item("machine", machine)?;
            d.set_item("kind", kind)?;
            d.set_item("analysis", analysis)?;
            d.set_item("reason", reason)?;
        }
        _ => {}
    }
    Ok(d)
}

/// A Python-side input error as pkm's `InvalidInputError`.
pub fn invalid(what: &str, message: impl Into<String>) -> PyErr {
    to_py(pkm::Error::InvalidInput {
        what: what.into(),
        message: message.into(),
    })
}

/// Adds the exception classes to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("MachineFileError", py.get_type::<MachineFileError>())?;
    m.add("InvalidInputError", py.get_type::<InvalidInputError>())?;
    m.add("UnreachableError", py.get_type::<UnreachableError>())?;
    m.add("NotAttainableError", py.get_type::<NotAttainableError>())?;
    m.add("NotConvergedError", py.get_type::<NotConvergedError>())?;
    m.add(
        "NotIdentifiableError",
        py.get_type::<NotIdentifiableError>(),
    )?;
    m.add("SingularError", py.get_type::<SingularError>())?;
    m.add("UnsupportedError", py.get_type::<UnsupportedError>())?;
    Ok(())
}
