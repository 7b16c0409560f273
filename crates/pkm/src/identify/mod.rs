//! Identification (calibration) of a machine's geometric parameters from measurements
//! (seed 001, Smirnov 2009; spec 02).
//!
//! The parameter vector is the mechanism's geometry ([`Identifiable::geometry`]: for
//! the hexapod the 36 joint coordinates `A_j`, `B'_j`) followed by one *zero reading*
//! per actuator, `L_j^(0)`: the control knows only the increments `dL_j` it commands, so
//! the actuator position is `q_j = L_j^(0) + dL_j` (seed 001: 36 + 6 = 42). Any subset
//! can be held at its nominal value ([`Options::fixed`]).
//!
//! Two measurement models, per state `i` (the readings `dL_i` and the measured points):
//! * [`MeasurementModel::Pose`]: the fixture's points (`N >= 3` known points of the moving
//!   platform, e.g. the vertices of seed 001's triangle, eqs. 4-5) give the platform's
//!   full pose by a best-fit rigid transform ([`fit::rigid_transform`]); residuals are
//!   the actuator equations `q_j(x_i; g) - L_j^(0) - dL_ij` (seed 001 eq. 1), `A` per
//!   state. Their Jacobian is analytic and decoupled per actuator.
//! * [`MeasurementModel::Points`]: the points alone (a laser tracker on the tool: 3 equations per
//!   point per state). The pose is not measured: `x_i` solves `q(x_i; g) = L^(0) +
//!   dL_i` (forward kinematics of the candidate machine) and the residual is measured
//!   minus predicted point. By the implicit function theorem
//!   `dx_i/dtheta = -J_x^-1 [dq/dg, -I]` with `J_x = dq/dx`, so the residual Jacobian is
//!   `dP/dx dx/dtheta`, analytic too.
//!
//! Solvers: Levenberg-Marquardt ([`identify`], the `levenberg-marquardt` crate; its
//! column scaling puts mm and rad on one footing) over any number of states, and the
//! seed's procedure for the hexapod ([`hexapod::seed_procedure`]). Identifiability:
//! singular values of the residual Jacobian with its columns scaled to unit norm,
//! condition number, the combinations of parameters in near-null directions named, and
//! standard errors `s sqrt(diag (J^T J)^-1)` with `s` the residual RMS.

pub mod csv;
pub mod fit;
pub mod hexapod;
pub mod simulate;
pub mod struts;
pub mod tripod;

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Matrix3, Owned, SMatrix, SVector, Vector3};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::mechanism::Mechanism;

/// A mechanism whose geometry can be identified.
pub trait Identifiable<const P: usize, const A: usize>: Mechanism<P, A> + Sized + Sync {
    /// Names of the geometric parameters (`A1.x`, ...), in the order of
    /// [`Identifiable::geometry`].
    fn geometry_names(&self) -> Vec<String>;

    /// The geometric parameters (mm or rad).
    fn geometry(&self) -> Vec<f64>;

    /// The same machine with other geometric parameters.
    fn with_geometry(&self, g: &[f64]) -> Result<Self>;

    /// Actuator positions at pose `x` and their derivatives with respect to the
    /// geometric parameters, written into `jac` (`A x n`, already sized).
    fn inverse_with_geometry_jacobian(
        &self,
        x: &SVector<f64, P>,
        jac: &mut DMatrix<f64>,
    ) -> Result<SVector<f64, A>>;

    /// Base-frame position of a point `s` fixed to the moving platform (platform
    /// frame, mm) at pose `x`, and its derivative with respect to `x` (`3 x P`).
    fn platform_point(
        &self,
        x: &SVector<f64, P>,
        s: &Vector3<f64>,
    ) -> (Vector3<f64>, SMatrix<f64, 3, P>);

    /// Pose coordinates of a platform frame measured with origin `c` and rotation `r`
    /// (platform frame to base frame).
    fn coords_from_platform_frame(&self, c: &Vector3<f64>, r: &Matrix3<f64>) -> SVector<f64, P>;

    /// The mechanism's reading of a combination the data cannot separate, given as
    /// `(parameter index, coefficient)` (geometry first, then one zero reading per
    /// actuator), e.g. "joint A4 moved along strut L4 trades against zero(L4)"; `None`
    /// when it has none.
    fn explain(&self, _terms: &[(usize, f64)]) -> Option<String> {
        None
    }

    /// The actuators' zero readings of the machine as described (a calibrated value
    /// from its file where it has one); default: the actuator positions at home, the
    /// zero state of the campaigns pkm simulates.
    fn zero_readings(&self) -> Result<SVector<f64, A>> {
        self.inverse(&self.home())
    }
}

/// One measured state: the actuator readings (increments from the zero state, mm or
/// rad) and the measured base-frame positions of the fixture's points.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct State {
    /// Readings `dL_j`, one per actuator.
    pub readings: Vec<f64>,
    /// Measured points, one per fixture point (mm).
    pub points: Vec<Vector3<f64>>,
}

/// A measurement campaign: the fixture's points (platform frame) and the states.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Measurements {
    /// Known fixture points in the platform frame (mm).
    pub fixture: Vec<Vector3<f64>>,
    /// Measured states.
    pub states: Vec<State>,
}

impl Measurements {
    /// The readings of every state.
    pub fn readings(&self) -> Vec<Vec<f64>> {
        self.states.iter().map(|s| s.readings.clone()).collect()
    }
}

/// Which measurement equations to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MeasurementModel {
    /// Full pose per state from the fixture (`>= 3` points), actuator equations.
    Pose,
    /// Measured points only, pose through forward kinematics.
    Points,
}

/// Settings of [`identify`].
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Measurement equations.
    pub model: MeasurementModel,
    /// Indices of parameters held at their starting values.
    pub fixed: Vec<usize>,
    /// Singular values of the scaled Jacobian below this fraction of the largest mark
    /// a combination the data cannot determine.
    pub rank_tolerance: f64,
    /// Largest number of residual evaluations of Levenberg-Marquardt.
    pub max_evaluations: usize,
    /// Largest acceptable standard error of an identified parameter (its unit, mm for
    /// the hexapod): with noisy data a nearly undetermined combination does not show as
    /// a zero singular value but as a huge standard error; beyond this the result is
    /// noise and [`identify`] fails naming the weakest combination.
    pub max_standard_error: f64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            model: MeasurementModel::Pose,
            fixed: Vec::new(),
            rank_tolerance: 1e-9,
            max_evaluations: 400,
            max_standard_error: 1.0,
        }
    }
}

/// A direction in parameter space the data determine poorly or not at all.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Combination {
    /// Singular value of the scaled Jacobian along it (relative to the largest).
    pub relative_singular_value: f64,
    /// Its terms `(parameter, coefficient)` in parameter units (mm, rad), the largest
    /// scaled to 1 and listed first: moving the parameters by these amounts together
    /// changes the measurements not at all (null space) or little.
    pub terms: Vec<(String, f64)>,
    /// The combination in words.
    pub description: String,
}

/// Result of an identification.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Identification {
    /// Parameter names: geometry, then one `zero(<actuator>)` per actuator.
    pub names: Vec<String>,
    /// Whether each parameter was identified (false: held).
    pub free: Vec<bool>,
    /// Starting (nominal) values.
    pub start: Vec<f64>,
    /// Identified values.
    pub values: Vec<f64>,
    /// Standard errors (0 for held parameters).
    pub standard_errors: Vec<f64>,
    /// Residual RMS with the start values (mm).
    pub rms_before: f64,
    /// Residual RMS with the identified values (mm).
    pub rms_after: f64,
    /// Residual RMS per state, start values.
    pub state_rms_before: Vec<f64>,
    /// Residual RMS per state, identified values.
    pub state_rms_after: Vec<f64>,
    /// Singular values of the column-scaled residual Jacobian at the solution,
    /// largest first.
    pub singular_values: Vec<f64>,
    /// Their ratio, largest over smallest.
    pub condition: f64,
    /// Undetermined (relative singular value 0, in reduced row echelon form) and poorly
    /// determined combinations (relative singular value below 1e-3), weakest first.
    pub weak: Vec<Combination>,
    /// Residual evaluations of Levenberg-Marquardt.
    pub evaluations: usize,
    /// Number of equations.
    pub equations: usize,
}

/// The residuals of a campaign for a parameter vector, and their Jacobian.
struct Problem<'a, M, const P: usize, const A: usize> {
    nominal: &'a M,
    meas: &'a Measurements,
    model: MeasurementModel,
    /// Measured poses (pose model).
    poses: Vec<SVector<f64, P>>,
    /// Last forward-kinematics poses (point model), warm starts.
    fk: Vec<SVector<f64, P>>,
    theta: Vec<f64>,
    free: Vec<usize>,
    /// Residuals and Jacobian (all parameters) at `theta`; `None` when the candidate
    /// machine cannot reach a state.
    eval: Option<(DVector<f64>, DMatrix<f64>)>,
}

impl<M: Identifiable<P, A>, const P: usize, const A: usize> Problem<'_, M, P, A> {
    fn n_geometry(&self) -> usize {
        self.theta.len() - A
    }

    fn rows_per_state(&self) -> usize {
        match self.model {
            MeasurementModel::Pose => A,
            MeasurementModel::Points => 3 * self.meas.fixture.len(),
        }
    }

    fn evaluate(&mut self) {
        self.eval = self.compute().ok();
    }

    fn compute(&mut self) -> Result<(DVector<f64>, DMatrix<f64>)> {
        let ng = self.n_geometry();
        let n = self.theta.len();
        let m = self.nominal.with_geometry(&self.theta[..ng])?;
        let zero = &self.theta[ng..];
        let rows = self.rows_per_state();
        let mut r = DVector::zeros(rows * self.meas.states.len());
        let mut jac = DMatrix::zeros(r.len(), n);
        let mut jg = DMatrix::zeros(A, ng);
        for (i, st) in self.meas.states.iter().enumerate() {
            let base = i * rows;
            match self.model {
                MeasurementModel::Pose => {
                    let q = m.inverse_with_geometry_jacobian(&self.poses[i], &mut jg)?;
                    for j in 0..A {
                        r[base + j] = q[j] - zero[j] - st.readings[j];
                        for c in 0..ng {
                            jac[(base + j, c)] = jg[(j, c)];
                        }
                        jac[(base + j, ng + j)] = -1.0;
                    }
                }
                MeasurementModel::Points => {
                    let target = SVector::<f64, A>::from_fn(|j, _| zero[j] + st.readings[j]);
                    let f = m.forward(&target, &self.fk[i])?;
                    self.fk[i] = f.pose;
                    let x = f.pose;
                    m.inverse_with_geometry_jacobian(&x, &mut jg)?;
                    let jx = m.jacobian(&x)?;
                    if P != A {
                        return Err(Error::InvalidInput {
                            what: "point identification".into(),
                            message: "needs as many actuators as pose coordinates".into(),
                        });
                    }
                    let lu = DMatrix::from_fn(A, P, |r, c| jx[(r, c)]).lu();
                    // dx/dtheta = -J_x^-1 [dq/dg, -I]
                    let mut dq = DMatrix::zeros(A, n);
                    dq.view_mut((0, 0), (A, ng)).copy_from(&jg);
                    for j in 0..A {
                        dq[(j, ng + j)] = -1.0;
                    }
                    let dx = -lu.solve(&dq).ok_or_else(|| Error::Singular {
                        what: "mechanism Jacobian in point identification".into(),
                        rcond: 0.0,
                    })?;
                    for (k, s) in self.meas.fixture.iter().enumerate() {
                        let (p, dp) = m.platform_point(&x, s);
                        let e = st.points[k] - p;
                        for a in 0..3 {
                            r[base + 3 * k + a] = e[a];
                        }
                        // d e / d theta = -dP/dx dx/dtheta
                        for c in 0..n {
                            for a in 0..3 {
                                let mut v = 0.0;
                                for k2 in 0..P {
                                    v += dp[(a, k2)] * dx[(k2, c)];
                                }
                                jac[(base + 3 * k + a, c)] = -v;
                            }
                        }
                    }
                }
            }
        }
        Ok((r, jac))
    }

    fn free_jacobian(&self, jac: &DMatrix<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(jac.nrows(), self.free.len(), |r, c| jac[(r, self.free[c])])
    }
}

impl<M: Identifiable<P, A>, const P: usize, const A: usize> LeastSquaresProblem<f64, Dyn, Dyn>
    for Problem<'_, M, P, A>
{
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        for (k, &i) in self.free.iter().enumerate() {
            self.theta[i] = x[k];
        }
        self.evaluate();
    }

    fn params(&self) -> DVector<f64> {
        DVector::from_iterator(self.free.len(), self.free.iter().map(|&i| self.theta[i]))
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.eval.as_ref().map(|(r, _)| r.clone())
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        self.eval.as_ref().map(|(_, j)| self.free_jacobian(j))
    }
}

/// Names of all parameters of `m`: its geometry, then `zero(<actuator>)`.
pub fn parameter_names<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
) -> Vec<String> {
    let mut names = m.geometry_names();
    names.extend(m.actuators().iter().map(|a| format!("zero({})", a.name)));
    names
}

/// Poses of every state from the fixture's measured points (best-fit rigid transform).
pub fn measured_poses<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    meas: &Measurements,
) -> Result<Vec<SVector<f64, P>>> {
    meas.states
        .iter()
        .enumerate()
        .map(|(i, st)| {
            let (c, r, _) = fit::rigid_transform(&meas.fixture, &st.points).map_err(|e| {
                Error::InvalidInput {
                    what: format!("measured state {}", i + 1),
                    message: e.to_string(),
                }
            })?;
            Ok(m.coords_from_platform_frame(&c, &r))
        })
        .collect()
}

/// Residuals and their Jacobian (all parameters, in [`parameter_names`] order) of a
/// campaign for parameters `theta` (geometry, then zero readings) under `model`; the
/// point model's forward kinematics starts from `nominal`'s home.
pub fn residuals<M: Identifiable<P, A>, const P: usize, const A: usize>(
    nominal: &M,
    meas: &Measurements,
    model: MeasurementModel,
    theta: &[f64],
) -> Result<(DVector<f64>, DMatrix<f64>)> {
    let poses = match model {
        MeasurementModel::Pose => measured_poses(nominal, meas)?,
        MeasurementModel::Points => Vec::new(),
    };
    let mut problem = Problem {
        nominal,
        meas,
        model,
        poses,
        fk: vec![nominal.home(); meas.states.len()],
        theta: theta.to_vec(),
        free: (0..theta.len()).collect(),
        eval: None,
    };
    problem.compute()
}

/// Identifies the parameters of `nominal` (geometry, then the actuators' zero readings
/// `zero`) from `meas`: Levenberg-Marquardt from the nominal values, with the
/// identifiability analysis. Fails with [`Error::NotIdentifiable`] naming the
/// combination when the free parameters are not all determined by the data (hold one
/// of its parameters, or measure states that move it), and with
/// [`Error::InvalidInput`] for inconsistent measurements.
pub fn identify<M: Identifiable<P, A>, const P: usize, const A: usize>(
    nominal: &M,
    zero: &SVector<f64, A>,
    meas: &Measurements,
    o: &Options,
) -> Result<Identification> {
    validate(nominal, meas, o)?;
    let names = parameter_names(nominal);
    let mut theta = nominal.geometry();
    theta.extend(zero.iter());
    let n = theta.len();
    let free: Vec<usize> = (0..n).filter(|i| !o.fixed.contains(i)).collect();
    let poses = match o.model {
        MeasurementModel::Pose => measured_poses(nominal, meas)?,
        MeasurementModel::Points => Vec::new(),
    };
    // Warm starts of the point model: the nominal machine's forward kinematics from
    // home.
    let fk = match o.model {
        MeasurementModel::Points => meas
            .states
            .iter()
            .map(|st| {
                let q = SVector::<f64, A>::from_fn(|j, _| zero[j] + st.readings[j]);
                nominal
                    .forward(&q, &nominal.home())
                    .map(|f| f.pose)
                    .unwrap_or_else(|_| nominal.home())
            })
            .collect(),
        MeasurementModel::Pose => Vec::new(),
    };
    let mut problem = Problem {
        nominal,
        meas,
        model: o.model,
        poses,
        fk,
        theta: theta.clone(),
        free: free.clone(),
        eval: None,
    };
    problem.evaluate();
    let Some((r0, j0)) = problem.eval.clone() else {
        return Err(Error::InvalidInput {
            what: "identification".into(),
            message: "the nominal machine cannot reach the measured states".into(),
        });
    };
    let per_state = problem.rows_per_state();
    let state_rms = |r: &DVector<f64>| -> Vec<f64> {
        r.as_slice()
            .chunks(per_state)
            .map(|c| (c.iter().map(|v| v * v).sum::<f64>() / c.len() as f64).sqrt())
            .collect()
    };
    let rms = |r: &DVector<f64>| (r.norm_squared() / r.len().max(1) as f64).sqrt();
    // Identifiability at the start: a rank-deficient problem is reported, not solved.
    let jf0 = problem.free_jacobian(&j0);
    let explain = |t: &[(usize, f64)]| nominal.explain(t);
    let (sv0, weak0) = analyse(&jf0, &free, &names, &explain);
    let null: Vec<&Combination> = weak0
        .iter()
        .filter(|w| w.relative_singular_value < o.rank_tolerance)
        .collect();
    if let Some(w) = null.first() {
        let more = if null.len() > 1 {
            format!(" (and {} more such combinations)", null.len() - 1)
        } else {
            String::new()
        };
        return Err(Error::NotIdentifiable {
            combination: format!("{}{more}", w.description),
            relative_singular_value: w.relative_singular_value,
        });
    }
    let _ = sv0;
    let lm = LevenbergMarquardt::new()
        .with_ftol(1e-15)
        .with_xtol(1e-15)
        .with_gtol(1e-15)
        .with_patience(o.max_evaluations.div_ceil(n.max(1) + 1));
    let (problem, report) = lm.minimize(problem);
    let Some((r1, j1)) = problem.eval.clone() else {
        return Err(Error::NotConverged {
            solver: "identification (Levenberg-Marquardt)",
            iterations: report.number_of_evaluations,
            residual: f64::NAN,
        });
    };
    let jf = problem.free_jacobian(&j1);
    let (sv, weak) = analyse(&jf, &free, &names, &explain);
    // Standard errors: s^2 (J^T J)^-1, s^2 = |r|^2 / (m - n).
    let dof = (r1.len() as f64 - free.len() as f64).max(1.0);
    let s2 = r1.norm_squared() / dof;
    let jtj = jf.transpose() * &jf;
    let cov = jtj
        .clone()
        .try_inverse()
        .or_else(|| jtj.pseudo_inverse(1e-300).ok());
    let mut se = vec![0.0; n];
    if let Some(c) = cov {
        for (k, &i) in free.iter().enumerate() {
            se[i] = (s2 * c[(k, k)].max(0.0)).sqrt();
        }
    }
    let condition = sv.first().copied().unwrap_or(0.0) / sv.last().copied().unwrap_or(0.0);
    let (worst, worst_se) =
        se.iter()
            .enumerate()
            .fold((0, 0.0), |a, (i, v)| if *v > a.1 { (i, *v) } else { a });
    if worst_se > o.max_standard_error {
        let (what, rel) = match weak.first() {
            Some(w) => (w.description.clone(), w.relative_singular_value),
            None => (
                format!("`{}` is poorly determined by these states", names[worst]),
                sv.last().copied().unwrap_or(0.0) / sv.first().copied().unwrap_or(1.0),
            ),
        };
        return Err(Error::NotIdentifiable {
            combination: format!(
                "{what}; with this data the standard error of `{}` is {worst_se:.3} (limit {})",
                names[worst], o.max_standard_error
            ),
            relative_singular_value: rel,
        });
    }
    Ok(Identification {
        free: (0..n).map(|i| free.contains(&i)).collect(),
        names,
        start: theta,
        values: problem.theta.clone(),
        standard_errors: se,
        rms_before: rms(&r0),
        rms_after: rms(&r1),
        state_rms_before: state_rms(&r0),
        state_rms_after: state_rms(&r1),
        singular_values: sv,
        condition,
        weak,
        evaluations: report.number_of_evaluations,
        equations: r1.len(),
    })
}

fn validate<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    meas: &Measurements,
    o: &Options,
) -> Result<()> {
    let bad = |message: String| Error::InvalidInput {
        what: "measurements".into(),
        message,
    };
    let n = m.geometry().len() + A;
    if let Some(i) = o.fixed.iter().find(|&&i| i >= n) {
        return Err(bad(format!(
            "fixed parameter {i} does not exist ({n} parameters)"
        )));
    }
    let need = match o.model {
        MeasurementModel::Pose => 3,
        MeasurementModel::Points => 1,
    };
    if meas.fixture.len() < need {
        return Err(bad(format!(
            "the {:?} model needs at least {need} fixture points, the file gives {}",
            o.model,
            meas.fixture.len()
        )));
    }
    for (i, st) in meas.states.iter().enumerate() {
        if st.readings.len() != A || st.points.len() != meas.fixture.len() {
            return Err(bad(format!(
                "state {}: expected {A} readings and {} points, found {} and {}",
                i + 1,
                meas.fixture.len(),
                st.readings.len(),
                st.points.len()
            )));
        }
    }
    let free = n - o.fixed.len();
    let per_state = match o.model {
        MeasurementModel::Pose => A,
        MeasurementModel::Points => 3 * meas.fixture.len(),
    };
    if meas.states.len() * per_state < free {
        return Err(bad(format!(
            "{} states give {} equations for {free} free parameters",
            meas.states.len(),
            meas.states.len() * per_state
        )));
    }
    Ok(())
}

/// A mechanism's reading of a combination ([`Identifiable::explain`]).
type Explain<'a> = dyn Fn(&[(usize, f64)]) -> Option<String> + 'a;

/// Singular values of the column-scaled Jacobian (largest first) and its weak
/// directions (relative singular value below 1e-3), named. The directions of the
/// numerical null space (relative singular value below 1e-9) are put in reduced row
/// echelon form, so that each names a few parameters (e.g. a base joint coordinate and
/// the platform joint coordinate that trades against it) instead of a mix of all.
fn analyse(
    j: &DMatrix<f64>,
    free: &[usize],
    names: &[String],
    explain: &Explain,
) -> (Vec<f64>, Vec<Combination>) {
    let norms: Vec<f64> = (0..j.ncols())
        .map(|c| j.column(c).norm().max(1e-300))
        .collect();
    let mut js = j.clone();
    for (c, nrm) in norms.iter().enumerate() {
        js.column_mut(c).scale_mut(1.0 / nrm);
    }
    // SVD of the scaled Jacobian itself (not of J^T J, whose eigenvalues square the
    // condition number and lose the small singular values to rounding).
    let svd = js.clone().svd(false, true);
    let vt = svd.v_t.expect("v_t requested");
    let values = svd.singular_values;
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    let mut sv: Vec<f64> = order.iter().map(|&k| values[k]).collect();
    // A Jacobian with fewer rows than columns has that many zero singular values more.
    sv.resize(j.ncols(), 0.0);
    let top = sv.first().copied().unwrap_or(0.0).max(1e-300);
    let rel = |k: usize| values[k] / top;
    let null: Vec<usize> = order
        .iter()
        .rev()
        .copied()
        .filter(|&k| rel(k) < 1e-9)
        .collect();
    let weak: Vec<usize> = order
        .iter()
        .rev()
        .copied()
        .filter(|&k| (1e-9..1e-3).contains(&rel(k)))
        .collect();
    // Directions in physical units (undo the column scaling).
    let physical = |v: DVector<f64>| -> DVector<f64> {
        DVector::from_iterator(v.len(), v.iter().zip(&norms).map(|(x, n)| x / n))
    };
    let mut dirs: Vec<(f64, DVector<f64>)> = Vec::new();
    if !null.is_empty() {
        let rows: Vec<DVector<f64>> = null
            .iter()
            .map(|&k| physical(vt.row(k).transpose()))
            .collect();
        for v in echelon(rows) {
            dirs.push((0.0, v));
        }
    }
    for &k in &weak {
        dirs.push((rel(k), physical(vt.row(k).transpose())));
    }
    let out = dirs
        .into_iter()
        .map(|(r, v)| {
            let big = v.amax().max(1e-300);
            let mut indexed: Vec<(usize, f64)> = v
                .iter()
                .enumerate()
                .filter(|(_, c)| c.abs() >= 0.05 * big)
                .map(|(c, x)| (free[c], x / big))
                .collect();
            indexed.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
            // Sign convention: the largest term positive.
            if indexed.first().is_some_and(|t| t.1 < 0.0) {
                indexed.iter_mut().for_each(|t| t.1 = -t.1);
            }
            let terms: Vec<(String, f64)> = indexed
                .iter()
                .map(|(i, c)| (names[*i].clone(), *c))
                .collect();
            let description = describe(&terms, explain(&indexed), r);
            Combination {
                relative_singular_value: r,
                terms,
                description,
            }
        })
        .collect();
    (sv, out)
}

/// Reduced row echelon form of a set of directions (Gauss-Jordan with partial
/// pivoting): a sparse basis of the space they span.
fn echelon(rows: Vec<DVector<f64>>) -> Vec<DVector<f64>> {
    let k = rows.len();
    let n = rows.first().map(|r| r.len()).unwrap_or(0);
    let mut m = DMatrix::from_fn(k, n, |r, c| rows[r][c]);
    let scale = m.amax().max(1e-300);
    let mut row = 0;
    for col in 0..n {
        if row == k {
            break;
        }
        let (p, best) = (row..k)
            .map(|r| (r, m[(r, col)].abs()))
            .fold((row, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        if best <= 1e-8 * scale {
            continue;
        }
        m.swap_rows(row, p);
        let pivot = m[(row, col)];
        m.row_mut(row).scale_mut(1.0 / pivot);
        for r in 0..k {
            if r != row {
                let f = m[(r, col)];
                if f != 0.0 {
                    for c in 0..n {
                        m[(r, c)] -= f * m[(row, c)];
                    }
                }
            }
        }
        row += 1;
    }
    (0..row)
        .map(|r| {
            DVector::from_iterator(
                n,
                m.row(r)
                    .iter()
                    .map(|v| if v.abs() < 1e-10 { 0.0 } else { *v }),
            )
        })
        .collect()
}

fn describe(terms: &[(String, f64)], reading: Option<String>, relative: f64) -> String {
    let sum: Vec<String> = terms.iter().map(|(n, c)| format!("{c:+.3} {n}")).collect();
    let effect = if relative == 0.0 {
        "does not change any measured quantity".to_string()
    } else {
        format!("changes the measurements little (relative singular value {relative:.1e})")
    };
    let what = if let Some(r) = reading {
        r
    } else if terms.len() == 1 {
        format!("`{}` {effect}", terms[0].0)
    } else {
        format!(
            "these parameters trade against each other: changing them together along this \
             direction {effect}"
        )
    };
    format!(
        "{} ({what}; hold one of them or measure states that separate them)",
        sum.join(" ")
    )
}

/// How well a model predicts measured states.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PointErrors {
    /// Largest distance between a predicted and a measured point (mm).
    pub max: f64,
    /// RMS distance (mm).
    pub rms: f64,
    /// With three or more fixture points: the tool pose predicted against the pose
    /// measured by the best-fit transform (position and orientation, max and RMS).
    pub pose: Option<simulate::PoseErrors>,
    /// States whose readings the model cannot reach (forward kinematics failed).
    pub failed: usize,
}

/// Validation on states not used for identification: forward kinematics of the model
/// `m` at `zero + dL` for each state, the fixture's points predicted and compared with
/// the measured ones, and with three or more points the tool pose against the measured
/// pose (the measurement noise is part of the result).
pub fn point_errors<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    zero: &SVector<f64, A>,
    meas: &Measurements,
) -> PointErrors {
    let mut max: f64 = 0.0;
    let mut sum = 0.0;
    let mut count = 0usize;
    let mut failed = 0;
    let mut start = m.home();
    let measured = if meas.fixture.len() >= 3 {
        measured_poses(m, meas).ok()
    } else {
        None
    };
    let mut stats = simulate::PoseStats::default();
    for (i, st) in meas.states.iter().enumerate() {
        let q =
            SVector::<f64, A>::from_fn(|j, _| zero[j] + st.readings.get(j).copied().unwrap_or(0.0));
        match m.forward(&q, &start) {
            Ok(f) => {
                start = f.pose;
                if let Some(x) = measured.as_ref().map(|v| v[i]) {
                    if let (Ok(a), Ok(b)) = (m.tool_pose(&x), m.tool_pose(&f.pose)) {
                        stats.add(&a, &b);
                    }
                }
                for (s, p) in meas.fixture.iter().zip(&st.points) {
                    let d = (m.platform_point(&f.pose, s).0 - p).norm();
                    max = max.max(d);
                    sum += d * d;
                    count += 1;
                }
            }
            Err(_) => failed += 1,
        }
    }
    PointErrors {
        max,
        rms: (sum / count.max(1) as f64).sqrt(),
        pose: measured.map(|_| stats.finish()),
        failed,
    }
}
