//! Kinematics on numpy arrays: `Machine.ik`, `fk`, `jacobian`, `condition`,
//! `tool_pose`, `check_limits`. Batches release the GIL and run on all cores
//! (`pkm::analysis::batch`); one row is solved on the calling thread.

use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::convert::{self, rows, vec1, vec2};
use crate::errors::to_py;
use crate::machine::Machine;

/// Why rows failed: shared by [`IkBatch`] and [`FkBatch`].
fn messages(c: &pkm::analysis::batch::Causes) -> Vec<Option<String>> {
    (0..c.reason.len()).map(|i| c.message(i)).collect()
}

/// Inverse kinematics of many poses (`Machine.ik` on an (N, P) array). Unpacks as
/// `actuators, reachable, limit = m.ik(poses)`.
#[pyclass(module = "pkm", frozen)]
pub struct IkBatch {
    width: usize,
    inner: pkm::analysis::batch::BatchInverse,
}

#[pymethods]
impl IkBatch {
    /// Actuator values, shape (N, A), mm or rad; NaN where the pose has no solution.
    #[getter]
    fn actuators<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        vec2(py, self.inner.actuators.clone(), self.width)
    }
    /// Per pose: a solution within every limit, shape (N,), bool.
    #[getter]
    fn reachable<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        vec1(py, self.inner.reachable.clone())
    }
    /// Per pose: index into `limit_names` of the first violated limit (or of why the
    /// pose has no solution); -1 where reachable. Shape (N,), int32.
    #[getter]
    fn limit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i32>> {
        vec1(py, self.inner.causes.reason.clone())
    }
    /// The distinct violated limits (`strut 3 length`) and solver messages the rows
    /// point to.
    #[getter]
    fn limit_names(&self) -> Vec<String> {
        self.inner
            .causes
            .reasons
            .iter()
            .map(|r| r.text.clone())
            .collect()
    }
    /// Per pose: by how much the first violated limit is crossed, in that limit's
    /// unit (`limit_units`: mm, deg); NaN where reachable or without solution.
    #[getter]
    fn excess<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let c = &self.inner.causes;
        vec1(py, (0..c.reason.len()).map(|i| c.excess(i)).collect())
    }
    /// Unit of each entry of `limit_names` ("" for a solver message).
    #[getter]
    fn limit_units(&self) -> Vec<&'static str> {
        self.inner.causes.reasons.iter().map(|r| r.unit).collect()
    }
    /// Per pose: pkm's message (as `pkm ik` prints it), None where reachable.
    fn messages(&self) -> Vec<Option<String>> {
        messages(&self.inner.causes)
    }
    fn __len__(&self) -> usize {
        self.inner.len()
    }
    fn __iter__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let me = slf.get();
        let t = PyTuple::new(
            py,
            [
                me.actuators(py)?,
                me.reachable(py).into_any(),
                me.limit(py).into_any(),
            ],
        )?;
        t.try_iter().map(|i| i.into_any())
    }
    fn __repr__(&self) -> String {
        let n = self.inner.len();
        let ok = self.inner.reachable.iter().filter(|r| **r).count();
        format!("<pkm.IkBatch: {n} poses, {ok} reachable>")
    }
}

/// Forward kinematics of many actuator sets (`Machine.fk` on an (N, A) array).
/// Unpacks as `poses, solved, reachable = m.fk(q)`.
#[pyclass(module = "pkm", frozen)]
pub struct FkBatch {
    width: usize,
    inner: pkm::analysis::batch::BatchForward,
}

#[pymethods]
impl FkBatch {
    /// Poses, shape (N, P), mm or rad; NaN where the solver failed.
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        vec2(py, self.inner.poses.clone(), self.width)
    }
    /// Per set: the solver found a pose.
    #[getter]
    fn solved<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        vec1(py, self.inner.solved.clone())
    }
    /// Per set: a pose found within every limit.
    #[getter]
    fn reachable<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        vec1(py, self.inner.reachable.clone())
    }
    /// Per set: solver iterations (0: closed form or failure).
    #[getter]
    fn iterations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u32>> {
        vec1(py, self.inner.iterations.clone())
    }
    /// Per set: largest actuator residual |IK(pose) - q| (mm or rad).
    #[getter]
    fn residual<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec1(py, self.inner.residual.clone())
    }
    /// Per set: index into `limit_names` of the first violated limit or the solver's
    /// failure; -1 where reachable.
    #[getter]
    fn limit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i32>> {
        vec1(py, self.inner.causes.reason.clone())
    }
    /// The distinct violated limits and solver messages the rows point to.
    #[getter]
    fn limit_names(&self) -> Vec<String> {
        self.inner
            .causes
            .reasons
            .iter()
            .map(|r| r.text.clone())
            .collect()
    }
    /// Per set: pkm's message, None where reachable.
    fn messages(&self) -> Vec<Option<String>> {
        messages(&self.inner.causes)
    }
    fn __len__(&self) -> usize {
        self.inner.solved.len()
    }
    fn __iter__<'py>(slf: &Bound<'py, Self>) -> PyResult<Bound<'py, PyAny>> {
        let py = slf.py();
        let me = slf.get();
        let t = PyTuple::new(
            py,
            [
                me.poses(py)?,
                me.solved(py).into_any(),
                me.reachable(py).into_any(),
            ],
        )?;
        t.try_iter().map(|i| i.into_any())
    }
    fn __repr__(&self) -> String {
        let n = self.inner.solved.len();
        let ok = self.inner.reachable.iter().filter(|r| **r).count();
        format!("<pkm.FkBatch: {n} actuator sets, {ok} reachable>")
    }
}

#[pymethods]
impl Machine {
    /// Inverse kinematics with every limit checked.
    ///
    /// `poses`: one pose, shape (P,), or many, shape (N, P) (mm, rad; P =
    /// len(m.coordinates)). One pose gives `(actuators, reachable, message)`: an
    /// array (A,), a bool and pkm's text of the first violated limit (None when
    /// reachable). Many give an `IkBatch` (`actuators, reachable, limit = ...`),
    /// solved on all cores with the GIL released. Raises `pkm.InvalidInputError` for
    /// a wrong shape or a value that is not finite; a pose without solution is a row
    /// with NaN actuators (batch) or `pkm.NotAttainableError` (one pose). With
    /// `check=False` the limits are not checked: `reachable` then says the pose has a
    /// geometric solution (the inverse kinematics alone, fastest).
    #[pyo3(signature = (poses, check = true))]
    fn ik<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
        check: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let p = self.m().coordinates().len();
        let (x, single) = rows(poses, p, "poses")?;
        if single && !check {
            let q = self.m().inverse(&x).map_err(to_py)?;
            return Ok((vec1(py, q), true, None::<String>)
                .into_pyobject(py)?
                .into_any());
        }
        if single {
            let s = pkm::analysis::kinematics::inverse(&self.inner, &x).map_err(to_py)?;
            let msg = s.violations.first().map(|v| v.to_string());
            return Ok((vec1(py, s.actuators), s.violations.is_empty(), msg)
                .into_pyobject(py)?
                .into_any());
        }
        let inner = self.inner.clone();
        let b = py
            .detach(move || pkm::analysis::batch::inverse_batch_with(&inner, &x, check))
            .map_err(to_py)?;
        let width = self.m().actuators().len();
        Ok(Bound::new(py, IkBatch { width, inner: b })?.into_any())
    }

    /// Forward kinematics with every limit checked, each actuator set solved from
    /// `start` (a pose, default home).
    ///
    /// `q`: one set, shape (A,), or many, shape (N, A) (mm, rad). One set gives
    /// `(pose, info)` with `info` a dict (`iterations`, `residual`, `closed_form`,
    /// `condition`, `near_singular`, `reachable`, `violations`), and raises
    /// `pkm.NotConvergedError` when the solver fails. Many give an `FkBatch` (`poses,
    /// solved, reachable = ...`) with a status per row, on all cores.
    #[pyo3(signature = (q, start = None))]
    fn fk<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        start: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let p = self.m().coordinates().len();
        let a = self.m().actuators().len();
        let (q, single) = rows(q, a, "q")?;
        let start = match start {
            Some(s) => {
                let (s, one) = rows(s, p, "start")?;
                if !one {
                    return Err(crate::errors::invalid("start", "expected one pose"));
                }
                Some(s)
            }
            None => None,
        };
        if single {
            let st = start.unwrap_or_else(|| self.m().home());
            let f = pkm::analysis::kinematics::forward(&self.inner, &q, &st).map_err(to_py)?;
            let info = pyo3::types::PyDict::new(py);
            info.set_item("iterations", f.iterations)?;
            info.set_item("residual", f.residual)?;
            info.set_item("closed_form", f.closed_form)?;
            info.set_item("condition", f.condition)?;
            info.set_item("near_singular", f.near_singular)?;
            info.set_item("reachable", f.violations.is_empty())?;
            info.set_item("violations", convert::to_py(py, &f.violations)?)?;
            return Ok((vec1(py, f.pose), info).into_pyobject(py)?.into_any());
        }
        let inner = self.inner.clone();
        let b = py
            .detach(move || pkm::analysis::batch::forward_batch(&inner, &q, start.as_deref()))
            .map_err(to_py)?;
        Ok(Bound::new(py, FkBatch { width: p, inner: b })?.into_any())
    }

    /// The Jacobian at a pose (shape (A, P)): actuator rates per pose-coordinate rate
    /// (mm or rad per mm or rad), as `pkm ik` uses it.
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let p = self.m().coordinates().len();
        let (x, single) = rows(pose, p, "pose")?;
        if !single {
            return Err(crate::errors::invalid(
                "pose",
                "expected one pose, shape (P,)",
            ));
        }
        let j = self.m().jacobian(&x).map_err(to_py)?;
        let rows: Vec<Vec<f64>> = (0..j.nrows())
            .map(|r| (0..j.ncols()).map(|c| j[(r, c)]).collect())
            .collect();
        Ok(PyArray2::from_vec2(py, &rows)?)
    }

    /// Condition number (2-norm of the driven Jacobian, rotations scaled by the
    /// characteristic length) of one pose (a float) or of each row of an (N, P) array
    /// (on all cores); NaN where the pose has no solution, inf where singular.
    fn condition<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let p = self.m().coordinates().len();
        let (x, single) = rows(poses, p, "poses")?;
        let inner = self.inner.clone();
        let c = py
            .detach(move || pkm::analysis::batch::condition_batch(&inner, &x))
            .map_err(to_py)?;
        if single {
            return Ok(c[0].into_pyobject(py)?.into_any());
        }
        Ok(vec1(py, c).into_any())
    }

    /// The tool pose at pose coordinates `pose`, as a 4 x 4 homogeneous matrix (mm).
    fn tool_pose<'py>(
        &self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let p = self.m().coordinates().len();
        let (x, single) = rows(pose, p, "pose")?;
        if !single {
            return Err(crate::errors::invalid(
                "pose",
                "expected one pose, shape (P,)",
            ));
        }
        let t = self.m().tool_pose(&x).map_err(to_py)?.to_homogeneous();
        let rows: Vec<Vec<f64>> = (0..4)
            .map(|r| (0..4).map(|c| t[(r, c)]).collect())
            .collect();
        Ok(PyArray2::from_vec2(py, &rows)?)
    }

    /// Every limit the pose (and its actuators, default its inverse kinematics)
    /// violates: list of dicts (`limit`, `kind`, `side`, `value`, `bound`, `excess`,
    /// `unit`; values in that unit, mm or deg). Empty: within every limit.
    #[pyo3(signature = (pose, actuators = None))]
    fn check_limits<'py>(
        &self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
        actuators: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let m = self.m();
        let (x, single) = rows(pose, m.coordinates().len(), "pose")?;
        if !single {
            return Err(crate::errors::invalid(
                "pose",
                "expected one pose, shape (P,)",
            ));
        }
        let q = match actuators {
            Some(a) => rows(a, m.actuators().len(), "actuators")?.0,
            None => m.inverse(&x).map_err(to_py)?,
        };
        let v = m.check_limits(&x, &q).map_err(to_py)?;
        convert::to_py(py, &v)
    }
}
