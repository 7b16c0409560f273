//! Kinematics on numpy arrays: `Machine.ik`, `fk`, `jacobian`, `condition`,
//! `tool_pose`, `check_limits`. Batches release the GIL and run on all cores
//! (`pkm::analysis::batch`); one row is solved on the calling thread.

use numpy::{PyArray2, PyArrayMethods};
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
/// `actuators, reachable, limit = m.ik(poses)`. The arrays are made once (the
/// library's vectors handed to numpy, no copy) and shared by every access.
#[pyclass(module = "pkm", frozen)]
pub struct IkBatch {
    actuators: Py<PyAny>,
    reachable: Py<PyAny>,
    limit: Py<PyAny>,
    /// Made on first access (most callers unpack the three arrays only).
    excess: std::sync::OnceLock<Py<PyAny>>,
    causes: pkm::analysis::batch::Causes,
}

impl IkBatch {
    fn new(py: Python<'_>, b: pkm::analysis::batch::BatchInverse, width: usize) -> PyResult<Self> {
        let reason = b.causes.reason.clone();
        Ok(IkBatch {
            actuators: vec2(py, b.actuators, width)?.unbind(),
            reachable: vec1(py, b.reachable).into_any().unbind(),
            limit: vec1(py, reason).into_any().unbind(),
            excess: std::sync::OnceLock::new(),
            causes: b.causes,
        })
    }
}

#[pymethods]
impl IkBatch {
    /// Actuator values, shape (N, A), mm or rad; NaN where the pose has no solution.
    #[getter]
    fn actuators(&self, py: Python<'_>) -> Py<PyAny> {
        self.actuators.clone_ref(py)
    }
    /// Per pose: a solution within every limit, shape (N,), bool.
    #[getter]
    fn reachable(&self, py: Python<'_>) -> Py<PyAny> {
        self.reachable.clone_ref(py)
    }
    /// Per pose: index into `limit_names` of the first violated limit (or of why the
    /// pose has no solution); -1 where reachable. Shape (N,), int32.
    #[getter]
    fn limit(&self, py: Python<'_>) -> Py<PyAny> {
        self.limit.clone_ref(py)
    }
    /// The distinct violated limits (`strut 3 length`) and solver messages the rows
    /// point to.
    #[getter]
    fn limit_names(&self) -> Vec<String> {
        self.causes.reasons.iter().map(|r| r.text.clone()).collect()
    }
    /// Per pose: by how much the first violated limit is crossed, in that limit's
    /// unit (`limit_units`: mm, deg); NaN where reachable or without solution.
    #[getter]
    fn excess(&self, py: Python<'_>) -> Py<PyAny> {
        self.excess
            .get_or_init(|| {
                let c = &self.causes;
                let excess: Vec<f64> = (0..c.reason.len()).map(|i| c.excess(i)).collect();
                vec1(py, excess).into_any().unbind()
            })
            .clone_ref(py)
    }
    /// Unit of each entry of `limit_names` ("" for a solver message).
    #[getter]
    fn limit_units(&self) -> Vec<&'static str> {
        self.causes.reasons.iter().map(|r| r.unit).collect()
    }
    /// Per pose: pkm's message (as `pkm ik` prints it), None where reachable.
    fn messages(&self) -> Vec<Option<String>> {
        messages(&self.causes)
    }
    fn __len__(&self) -> usize {
        self.causes.reason.len()
    }
    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let t = PyTuple::new(
            py,
            [
                self.actuators.clone_ref(py),
                self.reachable.clone_ref(py),
                self.limit.clone_ref(py),
            ],
        )?;
        t.try_iter().map(|i| i.into_any())
    }
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let n = self.causes.reason.len();
        let ok: usize = self.reachable.bind(py).call_method0("sum")?.extract()?;
        Ok(format!("<pkm.IkBatch: {n} poses, {ok} reachable>"))
    }
}

/// Forward kinematics of many actuator sets (`Machine.fk` on an (N, A) array).
/// Unpacks as `poses, solved, reachable = m.fk(q)`.
#[pyclass(module = "pkm", frozen)]
pub struct FkBatch {
    poses: Py<PyAny>,
    solved: Py<PyAny>,
    reachable: Py<PyAny>,
    iterations: Py<PyAny>,
    residual: Py<PyAny>,
    limit: Py<PyAny>,
    causes: pkm::analysis::batch::Causes,
}

impl FkBatch {
    fn new(py: Python<'_>, b: pkm::analysis::batch::BatchForward, width: usize) -> PyResult<Self> {
        let reason = b.causes.reason.clone();
        Ok(FkBatch {
            poses: vec2(py, b.poses, width)?.unbind(),
            solved: vec1(py, b.solved).into_any().unbind(),
            reachable: vec1(py, b.reachable).into_any().unbind(),
            iterations: vec1(py, b.iterations).into_any().unbind(),
            residual: vec1(py, b.residual).into_any().unbind(),
            limit: vec1(py, reason).into_any().unbind(),
            causes: b.causes,
        })
    }
}

#[pymethods]
impl FkBatch {
    /// Poses, shape (N, P), mm or rad; NaN where the solver failed.
    #[getter]
    fn poses(&self, py: Python<'_>) -> Py<PyAny> {
        self.poses.clone_ref(py)
    }
    /// Per set: the solver found a pose.
    #[getter]
    fn solved(&self, py: Python<'_>) -> Py<PyAny> {
        self.solved.clone_ref(py)
    }
    /// Per set: a pose found within every limit.
    #[getter]
    fn reachable(&self, py: Python<'_>) -> Py<PyAny> {
        self.reachable.clone_ref(py)
    }
    /// Per set: solver iterations (0: closed form or failure).
    #[getter]
    fn iterations(&self, py: Python<'_>) -> Py<PyAny> {
        self.iterations.clone_ref(py)
    }
    /// Per set: largest actuator residual |IK(pose) - q| (mm or rad).
    #[getter]
    fn residual(&self, py: Python<'_>) -> Py<PyAny> {
        self.residual.clone_ref(py)
    }
    /// Per set: index into `limit_names` of the first violated limit or the solver's
    /// failure; -1 where reachable.
    #[getter]
    fn limit(&self, py: Python<'_>) -> Py<PyAny> {
        self.limit.clone_ref(py)
    }
    /// The distinct violated limits and solver messages the rows point to.
    #[getter]
    fn limit_names(&self) -> Vec<String> {
        self.causes.reasons.iter().map(|r| r.text.clone()).collect()
    }
    /// Per set: pkm's message, None where reachable.
    fn messages(&self) -> Vec<Option<String>> {
        messages(&self.causes)
    }
    fn __len__(&self) -> usize {
        self.causes.reason.len()
    }
    fn __iter__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let t = PyTuple::new(
            py,
            [
                self.poses.clone_ref(py),
                self.solved.clone_ref(py),
                self.reachable.clone_ref(py),
            ],
        )?;
        t.try_iter().map(|i| i.into_any())
    }
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let n = self.causes.reason.len();
        let ok: usize = self.reachable.bind(py).call_method0("sum")?.extract()?;
        Ok(format!("<pkm.FkBatch: {n} actuator sets, {ok} reachable>"))
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
    /// geometric solution (the inverse kinematics alone, fastest). With
    /// `continuous=True` the rows are a path: each solved from the previous row's
    /// solution (a robot keeps its posture and the whole turns of its joints, as a
    /// controller moving it does; without it each row takes the solution nearest
    /// home), in order on one thread.
    #[pyo3(signature = (poses, check = true, continuous = false))]
    fn ik<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
        check: bool,
        continuous: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let p = self.m().coordinates().len();
        let r = convert::rows_ref(poses, p, "poses")?;
        let (x, single) = (r.values(), r.single);
        if single && !check {
            let q = self.m().inverse(x).map_err(to_py)?;
            return Ok((vec1(py, q), true, None::<String>)
                .into_pyobject(py)?
                .into_any());
        }
        if single {
            let s = pkm::analysis::kinematics::inverse(&self.inner, x).map_err(to_py)?;
            let msg = s.violations.first().map(|v| v.to_string());
            return Ok((vec1(py, s.actuators), s.violations.is_empty(), msg)
                .into_pyobject(py)?
                .into_any());
        }
        let inner = &self.inner;
        let b = py
            .detach(|| {
                if continuous {
                    pkm::analysis::batch::inverse_path(inner, x, check)
                } else {
                    pkm::analysis::batch::inverse_batch_with(inner, x, check)
                }
            })
            .map_err(to_py)?;
        let width = self.m().actuators().len();
        Ok(Bound::new(py, IkBatch::new(py, b, width)?)?.into_any())
    }

    /// Forward kinematics with every limit checked, each actuator set solved from
    /// `start` (a pose, default home).
    ///
    /// `q`: one set, shape (A,), or many, shape (N, A) (mm, rad). One set gives
    /// `(pose, info)` with `info` a dict (`iterations`, `residual`, `closed_form`,
    /// `reachable`, `violations`; the conditioning is `condition(pose)`), and raises
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
        let start = convert::one_pose(start, p, "start")?;
        if single {
            // The solve and the limit check (the condition number is `condition`'s:
            // a robot's takes an inverse kinematics solve, 30 times the forward one).
            let m = self.m();
            let st = start.unwrap_or_else(|| m.home());
            let f = m.forward(&q, &st).map_err(to_py)?;
            let violations = m.check_limits(&f.pose, &q).map_err(to_py)?;
            let info = pyo3::types::PyDict::new(py);
            info.set_item("iterations", f.iterations)?;
            info.set_item("residual", f.residual)?;
            info.set_item("closed_form", m.forward_closed_form())?;
            info.set_item("reachable", violations.is_empty())?;
            info.set_item("violations", convert::to_py(py, &violations)?)?;
            return Ok((vec1(py, f.pose), info).into_pyobject(py)?.into_any());
        }
        let inner = self.inner.clone();
        let b = py
            .detach(move || pkm::analysis::batch::forward_batch(&inner, &q, start.as_deref()))
            .map_err(to_py)?;
        Ok(Bound::new(py, FkBatch::new(py, b, p)?)?.into_any())
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

    /// The tool pose (the tool relative to the part) at pose coordinates `pose`, as a
    /// 4 x 4 homogeneous matrix (mm): one pose, shape (P,), gives shape (4, 4); many,
    /// shape (N, P), give shape (N, 4, 4) (on all cores; NaN where the single call
    /// would raise for the row). For a machine in joint coordinates this is its
    /// forward kinematics.
    fn tool_pose<'py>(
        &self,
        py: Python<'py>,
        pose: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let p = self.m().coordinates().len();
        let (x, single) = rows(pose, p, "pose")?;
        if single {
            let t = self.m().tool_pose(&x).map_err(to_py)?.to_homogeneous();
            let rows: Vec<Vec<f64>> = (0..4)
                .map(|r| (0..4).map(|c| t[(r, c)]).collect())
                .collect();
            return Ok(PyArray2::from_vec2(py, &rows)?.into_any());
        }
        let inner = self.inner.clone();
        let t = py
            .detach(move || pkm::analysis::batch::tool_pose_batch(&inner, &x))
            .map_err(to_py)?;
        let n = t.len() / 16;
        Ok(vec1(py, t).reshape([n, 4, 4])?.into_any())
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
