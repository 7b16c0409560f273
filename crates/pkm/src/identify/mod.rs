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

mod calibratable;
pub mod csv;
pub mod fit;
pub mod hexapod;
mod identifiability;
mod pentapod;
mod problem;
pub mod simulate;
mod solve;
pub mod struts;
pub mod tripod;
mod validation;

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3};
use serde::Serialize;

use crate::error::Result;
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

    /// Fixture points per state the pose model needs: 3 for a rigid platform (the
    /// best-fit transform), fewer for a machine whose platform has a free spin (a
    /// pentapod's tool axis: 2 points on it).
    fn pose_points(&self) -> usize {
        3
    }

    /// Refuses a fixture this machine cannot be measured with (default: any will do;
    /// a pentapod's points must lie on its tool axis, since the spin about it is free).
    fn check_fixture(&self, _fixture: &[Vector3<f64>]) -> Result<()> {
        Ok(())
    }

    /// The pose of a state from its measured fixture points (default: the best-fit
    /// rigid transform, [`fit::rigid_transform`], then
    /// [`Identifiable::coords_from_platform_frame`]).
    fn measured_pose(
        &self,
        fixture: &[Vector3<f64>],
        points: &[Vector3<f64>],
    ) -> Result<SVector<f64, P>> {
        let (c, r, _) = fit::rigid_transform(fixture, points)?;
        Ok(self.coords_from_platform_frame(&c, &r))
    }

    /// The actuators' zero readings of the machine as described (a calibrated value
    /// from its file where it has one); default: the actuator positions at home, the
    /// zero state of the campaigns pkm simulates.
    fn zero_readings(&self) -> Result<SVector<f64, A>> {
        self.inverse(&self.info().home())
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
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
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

impl std::str::FromStr for MeasurementModel {
    type Err = crate::error::Error;
    /// `pose` or `points`.
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "pose" => Ok(MeasurementModel::Pose),
            "points" => Ok(MeasurementModel::Points),
            m => Err(crate::error::Error::InvalidInput {
                what: "measurement model".into(),
                message: format!("expected `pose` or `points`, found `{m}`"),
            }),
        }
    }
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
    /// When parameters are held: what the standard errors assume (that the held values
    /// are exact; an error in one moves the identified parameters without showing in
    /// their standard errors).
    pub standard_errors_note: Option<String>,
}

/// Names of all parameters of `m`: its geometry, then `zero(<actuator>)`.
pub fn parameter_names<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
) -> Vec<String> {
    let mut names = m.geometry_names();
    names.extend(
        m.info()
            .actuators()
            .iter()
            .map(|a| format!("zero({})", a.name)),
    );
    names
}

pub use calibratable::{Calibratable, Fixture};
pub use problem::{measured_poses, residuals};
pub use solve::identify;
pub use validation::{point_errors, PointErrors};
