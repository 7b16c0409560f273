//! The analyses on a machine: `Machine.workspace`, `errors` (`motion` in `motion.rs`). Options are
//! keyword arguments (mm, rad, s); results are numpy arrays and plain dicts. Each
//! calls one entry point of `pkm::analysis` with the GIL released.

use std::collections::BTreeMap;

use numpy::PyArrayMethods;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{self, vec1, vec2};
use crate::errors::{invalid, to_py};
use crate::machine::{internal_unit, Machine};

/// A workspace map's points in columns: the grid axes' values (mm, rad), the
/// reachability, the condition number (NaN where unreachable), and the status and
/// binding limit as codes into their names.
struct MapColumns {
    points: Vec<f64>,
    reachable: Vec<bool>,
    condition: Vec<f64>,
    status: Vec<i32>,
    status_names: Vec<String>,
    binding: Vec<i32>,
    binding_names: Vec<String>,
}

impl MapColumns {
    fn of(wm: &pkm::workspace::WorkspaceMap) -> Self {
        let n = wm.points.len();
        let mut c = MapColumns {
            points: Vec::with_capacity(n * wm.axes.len()),
            reachable: Vec::with_capacity(n),
            condition: Vec::with_capacity(n),
            status: Vec::with_capacity(n),
            status_names: Vec::new(),
            binding: Vec::with_capacity(n),
            binding_names: Vec::new(),
        };
        let mut statuses: Vec<pkm::workspace::PointStatus> = Vec::new();
        let mut bindings: std::collections::HashMap<&str, i32> = Default::default();
        for (k, p) in wm.points.iter().enumerate() {
            let x = wm.coords(k);
            c.points.extend(wm.axes.iter().map(|a| x[a.coordinate]));
            c.reachable.push(p.reachable);
            c.condition
                .push(if p.reachable { p.condition } else { f64::NAN });
            let s = match statuses.iter().position(|s| *s == p.status) {
                Some(i) => i,
                None => {
                    statuses.push(p.status);
                    c.status_names.push(
                        serde_json::to_value(p.status)
                            .ok()
                            .and_then(|v| v.as_str().map(str::to_string))
                            .unwrap_or_default(),
                    );
                    statuses.len() - 1
                }
            };
            c.status.push(s as i32);
            c.binding.push(match &p.binding {
                Some(b) => *bindings.entry(b.as_str()).or_insert_with(|| {
                    c.binding_names.push(b.to_string());
                    c.binding_names.len() as i32 - 1
                }),
                None => -1,
            });
        }
        c
    }
}

/// A positive, finite option value.
pub(crate) fn positive(what: &str, v: Option<f64>) -> PyResult<Option<f64>> {
    match v {
        Some(x) if !(x > 0.0 && x.is_finite()) => Err(invalid(
            what,
            format!("expected a positive number, got {x}"),
        )),
        v => Ok(v),
    }
}

#[pymethods]
impl Machine {
    /// The reachable workspace on a grid: every point checked against every limit,
    /// with its condition number (pkm workspace).
    ///
    /// `bounds`: `[[min, max], ...]` per grid axis (mm, rad; the axes are X, Y, Z for
    /// spatial machines, else up to three of the machine's own coordinates); None:
    /// the machine's whole reach, found by search. `step`: grid step (mm, or rad when
    /// every axis is an angle); None: 1/40 of each range. `orientation`: the pose
    /// whose orientation the grid holds (default home). `tilt`: a point counts only
    /// when reachable at this tilt (rad) in eight directions too.
    ///
    /// Returns a dict: `axes` (name, unit, min, max, step, count), `points` (N, axes)
    /// array, `reachable` (N,) bool, `condition` (N,) (NaN where unreachable),
    /// `status` (N,) codes into `status_names`, `binding` (N,) codes into
    /// `binding_names` (-1 where reachable), `summary` (as `pkm workspace` writes
    /// it: mm, deg) and `grid` (how its bounds were found).
    #[pyo3(signature = (bounds = None, step = None, orientation = None, tilt = None))]
    fn workspace<'py>(
        &self,
        py: Python<'py>,
        bounds: Option<&Bound<'py, PyAny>>,
        step: Option<f64>,
        orientation: Option<&Bound<'py, PyAny>>,
        tilt: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let m = self.m();
        let base = match convert::one_pose(orientation, m.coordinates().len(), "orientation")? {
            Some(x) => x,
            None => m.home(),
        };
        // The grid's axes, to convert bounds and step to the library's user units.
        let axes = pkm::workspace::default_grid(m, &base, None, None).map_err(to_py)?;
        let bounds = grid_bounds(m, &axes, bounds)?;
        let step = grid_step(m, &axes, step)?;
        let orientations = match positive("tilt", tilt)? {
            Some(t) => pkm::workspace::tilt_orientations(t),
            None => Vec::new(),
        };
        let inner = self.inner.clone();
        let (wm, how, cols) = py
            .detach(|| {
                let (wm, how) = pkm::analysis::workspace::map(
                    &inner,
                    &base,
                    bounds.as_deref(),
                    step,
                    &orientations,
                    &|_| {},
                )?;
                let cols = MapColumns::of(&wm);
                Ok((wm, how, cols))
            })
            .map_err(to_py)?;
        let summary = wm.summary_of(m.coordinates());
        let d = PyDict::new(py);
        d.set_item("axes", grid_axes(py, m, &wm)?)?;
        d.set_item("points", vec2(py, cols.points, wm.axes.len())?)?;
        d.set_item("reachable", vec1(py, cols.reachable))?;
        d.set_item("condition", vec1(py, cols.condition))?;
        d.set_item("status", vec1(py, cols.status))?;
        d.set_item("status_names", cols.status_names)?;
        d.set_item("binding", vec1(py, cols.binding))?;
        d.set_item("binding_names", cols.binding_names)?;
        d.set_item("summary", convert::to_py(py, &summary)?)?;
        d.set_item("grid", how)?;
        Ok(d)
    }

    /// The accuracy at a pose (pkm errors): the tool-pose error of given parameter
    /// deviations, the sensitivity to every parameter, the error budget of the
    /// tolerances and optionally a Monte Carlo.
    ///
    /// `pose`: pose coordinates (mm, rad; default home). `tolerances`: None (the
    /// machine file's, else one per kind), a dict of one tolerance per kind
    /// (`joint`, `length`, `zero` in mm, `angle` in rad, `distribution`: `uniform` or
    /// `normal`), or the text of a tolerances file (`[[tolerance]]` entries, mm and
    /// deg, as `pkm errors --tolerances` reads). `deviations`: `{parameter name:
    /// value}` (mm, rad) whose exact pose error is wanted. `monte_carlo`: machines
    /// drawn from the tolerances (`seed`).
    ///
    /// Returns a dict (mm, rad): `parameters`, `sensitivities`, `budget`,
    /// `pose_error`, `tolerances`, `monte_carlo`, and the `violations` of the pose
    /// (each in its own unit, as pkm prints them).
    #[pyo3(signature = (pose = None, *, tolerances = None, deviations = None,
        monte_carlo = None, seed = 1))]
    fn errors<'py>(
        &self,
        py: Python<'py>,
        pose: Option<&Bound<'py, PyAny>>,
        tolerances: Option<&Bound<'py, PyAny>>,
        deviations: Option<BTreeMap<String, f64>>,
        monte_carlo: Option<usize>,
        seed: u64,
    ) -> PyResult<Bound<'py, PyAny>> {
        use pkm::analysis::accuracy::{AccuracyOptions, Tolerances};
        let m = self.m();
        let pose = convert::one_pose(pose, m.coordinates().len(), "pose")?;
        let params = self.inner.parameters();
        let tolerances = match tolerances {
            None => Tolerances::Default,
            Some(t) if t.extract::<String>().is_ok() => {
                let text: String = t.extract()?;
                Tolerances::Given(
                    pkm::machine::read_tolerances(&params, &text, "<tolerances>").map_err(to_py)?,
                )
            }
            Some(t) => Tolerances::ByKind(kind_tolerances(t)?),
        };
        let deviations = deviations_of(&params, m.name(), deviations)?;
        let opt = AccuracyOptions {
            pose,
            deviations,
            tolerances,
            monte_carlo,
            seed,
            ..Default::default()
        };
        let inner = self.inner.clone();
        let r = py
            .detach(|| pkm::analysis::accuracy::accuracy(&inner, &opt))
            .map_err(to_py)?;
        convert::to_py(py, &r)
    }

    /// Statics at one pose (pkm statics): the actuator forces that hold `wrench` on
    /// the tool, the tool's stiffness and deflection.
    ///
    /// `pose`: the pose coordinates (mm, rad; default home). `wrench`: the load on the
    /// tool, base frame: `[fx, fy, fz]` (N, at the tool tip) or `[fx, fy, fz, mx, my,
    /// mz]` (N, N mm); default none. Returns a dict (N, mm, rad): `actuator_forces`
    /// (array, N or N mm; positive where the drive pushes its coordinate to grow),
    /// `stiffness` (a dict: `matrix` 6 x 6 in N/mm, N/rad, N, N mm/rad or None where
    /// the machine holds coordinates rigidly, `geometric`, `compliance`, `deflection`,
    /// `deflection_exact`, `smallest_translational_n_per_um`, `weakest_direction`), or
    /// None with `stiffness_error` saying why (drives without `stiffness`).
    #[pyo3(signature = (pose = None, wrench = None))]
    fn statics<'py>(
        &self,
        py: Python<'py>,
        pose: Option<&Bound<'py, PyAny>>,
        wrench: Option<Vec<f64>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let m = self.m();
        let pose =
            convert::one_pose(pose, m.coordinates().len(), "pose")?.unwrap_or_else(|| m.home());
        let mut w = [0.0; 6];
        match wrench.as_deref() {
            None => {}
            Some(v) if (v.len() == 3 || v.len() == 6) && v.iter().all(|x| x.is_finite()) => {
                w[..v.len()].copy_from_slice(v)
            }
            Some(v) => {
                return Err(invalid(
                    "wrench",
                    format!("expected 3 or 6 finite values (N, N mm), found {v:?}"),
                ))
            }
        }
        let o = pkm::analysis::statics::StaticsOptions { pose, wrench: w };
        let inner = self.inner.clone();
        let r = py
            .detach(|| pkm::analysis::statics::statics(&inner, &o))
            .map_err(to_py)?;
        let d = convert::to_py(py, &r)?;
        d.set_item("actuator_forces", vec1(py, r.actuator_forces.clone()))?;
        Ok(d)
    }

    /// The unloaded stiffness at many poses, on every core: a stiffness map.
    ///
    /// `poses`: `(N, P)` array (mm, rad). Returns a dict: `smallest_n_per_um` (N,)
    /// the smallest stiffness of the tool tip against a force, `direction` (N, 3) its
    /// direction, `weakest` the index of the weakest pose (None if no pose has a
    /// value), `failed` the count of poses without a value (NaN: no inverse solution,
    /// singular), and with `matrices=True` `matrices` (N, 6, 6) in N/mm, N/rad, N,
    /// N mm/rad.
    #[pyo3(signature = (poses, matrices = false))]
    fn stiffness<'py>(
        &self,
        py: Python<'py>,
        poses: &Bound<'py, PyAny>,
        matrices: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let m = self.m();
        let (x, _) = convert::rows(poses, m.coordinates().len(), "poses")?;
        let inner = self.inner.clone();
        let map = py
            .detach(|| pkm::analysis::statics::stiffness_map(&inner, &x, matrices))
            .map_err(to_py)?;
        let d = PyDict::new(py);
        let n = map.smallest_n_per_um.len();
        d.set_item("smallest_n_per_um", vec1(py, map.smallest_n_per_um))?;
        d.set_item("direction", vec2(py, map.direction.concat(), 3)?)?;
        d.set_item("weakest", map.weakest)?;
        d.set_item("failed", map.failed)?;
        if matrices {
            d.set_item("matrices", vec1(py, map.matrices).reshape([n, 6, 6])?)?;
        }
        Ok(d.into_any())
    }

    /// Inverse dynamics of a serial machine or robot (recursive Newton-Euler, the
    /// links' URDF `<inertial>`): the joint forces (N) and torques (N mm) for joint
    /// positions `q`, rates `qd` and accelerations `qdd` (mm or rad, per s, per s^2),
    /// each `(n,)` or `(N, n)`, on every core. `gravity`: mm/s^2 in the base frame
    /// (default 9806.65 along -Z); `wrench`: the load on the tool `[fx, fy, fz, mx, my,
    /// mz]` (N, N mm, base frame). Returns an array shaped like `q`.
    #[pyo3(signature = (q, qd, qdd, gravity = None, wrench = None))]
    fn inverse_dynamics<'py>(
        &self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
        qd: &Bound<'py, PyAny>,
        qdd: &Bound<'py, PyAny>,
        gravity: Option<[f64; 3]>,
        wrench: Option<[f64; 6]>,
    ) -> PyResult<Bound<'py, PyAny>> {
        use pkm::analysis::dynamics::{inverse_dynamics_batch, DynamicsOptions};
        let n = self.m().actuators().len();
        let (q, single) = convert::rows(q, n, "q")?;
        let (qd, _) = convert::rows(qd, n, "qd")?;
        let (qdd, _) = convert::rows(qdd, n, "qdd")?;
        let mut o = DynamicsOptions::default();
        if let Some(g) = gravity {
            o.gravity = g.into();
        }
        if let Some(w) = wrench {
            o.wrench = w;
        }
        if !(o.gravity.iter().all(|v| v.is_finite()) && o.wrench.iter().all(|v| v.is_finite())) {
            return Err(invalid("gravity, wrench", "expected finite values"));
        }
        let inner = self.inner.clone();
        let t = py
            .detach(|| inverse_dynamics_batch(&inner, &q, &qd, &qdd, &o))
            .map_err(to_py)?;
        if single {
            return Ok(vec1(py, t).into_any());
        }
        vec2(py, t, n)
    }

    /// The geometric parameters (name, quantity, kind) whose deviations the accuracy
    /// analyses take (`errors(deviations=...)`, tolerances).
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        convert::to_py(py, &self.inner.parameters())
    }
}

/// The grid bounds given (`[[min, max], ...]` per grid axis, internal units) in the
/// library's user units.
fn grid_bounds(
    m: &dyn pkm::DynMechanism,
    axes: &[pkm::workspace::GridAxis],
    bounds: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<Vec<f64>>> {
    let Some(b) = bounds else {
        return Ok(None);
    };
    let (v, _) = convert::array(b, "bounds")?;
    let max = pkm::machine::MAX_MAGNITUDE;
    if v.len() != 2 * axes.len() || v.iter().any(|x| !(x.abs() <= max)) {
        return Err(invalid(
            "bounds",
            format!(
                "expected {} [min, max] pairs of finite numbers up to {max:.0e} \
                 (axes {}), got {} values",
                axes.len(),
                axes.iter()
                    .map(|a| m.coordinates()[a.coordinate].name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                v.len()
            ),
        ));
    }
    Ok(Some(
        v.iter()
            .enumerate()
            .map(|(k, x)| axis_quantity(m, axes, k / 2).to_user(*x))
            .collect::<Vec<_>>(),
    ))
}

/// The grid step given (internal units) in the library's user units: one step for
/// axes of one unit only.
fn grid_step(
    m: &dyn pkm::DynMechanism,
    axes: &[pkm::workspace::GridAxis],
    step: Option<f64>,
) -> PyResult<Option<f64>> {
    let Some(s) = positive("step", step)? else {
        return Ok(None);
    };
    let q0 = axis_quantity(m, axes, 0);
    if (1..axes.len()).any(|i| axis_quantity(m, axes, i) != q0) {
        return Err(invalid(
            "step",
            "one step for axes of different units (mm and rad): leave it out \
             (1/40 of each range)",
        ));
    }
    Ok(Some(q0.to_user(s)))
}

/// The quantity of grid axis `i`.
fn axis_quantity(
    m: &dyn pkm::DynMechanism,
    axes: &[pkm::workspace::GridAxis],
    i: usize,
) -> pkm::units::Quantity {
    m.coordinates()[axes[i].coordinate].quantity
}

/// The workspace map's axes as dicts: name, unit, min, max, step, count.
fn grid_axes<'py>(
    py: Python<'py>,
    m: &dyn pkm::DynMechanism,
    wm: &pkm::workspace::WorkspaceMap,
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    wm.axes
        .iter()
        .map(|a| {
            let c = &m.coordinates()[a.coordinate];
            let e = PyDict::new(py);
            e.set_item("name", &c.name)?;
            e.set_item("unit", internal_unit(c.quantity))?;
            e.set_item("min", a.min)?;
            e.set_item("max", a.max)?;
            e.set_item("step", a.step)?;
            e.set_item("count", a.count())?;
            Ok(e)
        })
        .collect()
}

/// The tolerances of `errors(tolerances={kind: value})`.
fn kind_tolerances(t: &Bound<'_, PyAny>) -> PyResult<pkm::analysis::accuracy::KindTolerances> {
    let d: BTreeMap<String, Bound<'_, PyAny>> = t.extract().map_err(|_| {
        invalid(
            "tolerances",
            "expected a dict of kinds or a tolerances file's text",
        )
    })?;
    let mut k = pkm::analysis::accuracy::KindTolerances::default();
    for (key, v) in d {
        let num = || -> PyResult<f64> {
            v.extract::<f64>()
                .map_err(|_| invalid(&format!("tolerances.{key}"), "expected a number"))
        };
        match key.as_str() {
            "joint" => k.joint = num()?,
            "length" => k.length = num()?,
            "zero" => k.zero = num()?,
            "angle" => k.angle = num()?,
            "distribution" => {
                let s: String = v.extract()?;
                k.distribution = s.parse().map_err(to_py)?;
            }
            other => {
                return Err(invalid(
                    "tolerances",
                    format!(
                        "unknown kind `{other}` (expected joint, length, zero, angle, \
                         distribution)"
                    ),
                ))
            }
        }
    }
    Ok(k)
}

/// The deviations of `errors(deviations={name: value})` as (parameter index, value) of
/// machine `machine`'s `params`.
fn deviations_of(
    params: &[pkm::accuracy::Parameter],
    machine: &str,
    deviations: Option<BTreeMap<String, f64>>,
) -> PyResult<Vec<(usize, f64)>> {
    deviations
        .unwrap_or_default()
        .into_iter()
        .map(|(name, v)| {
            let i = params.iter().position(|p| p.name == name).ok_or_else(|| {
                invalid(
                    "deviations",
                    format!("`{name}` is not a parameter of {machine}"),
                )
            })?;
            if !v.is_finite() {
                return Err(invalid(
                    &format!("deviations.{name}"),
                    "not a finite number",
                ));
            }
            Ok((i, v))
        })
        .collect()
}
