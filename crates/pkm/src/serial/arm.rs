//! A six-joint serial robot as a spatial [`Mechanism`]: its pose coordinates are the
//! tool's X, Y, Z, A, B, C (the frame of link 0 of the tool chain; a workpiece chain
//! without joints is the fixed part the tool pose is taken relative to), its actuators
//! the six joints. Inverse kinematics is in closed form for arms with a spherical wrist
//! and parallel second and third axes (most industrial robots;
//! [`super::spherical_wrist`]) and for arms with parallel second, third and fourth axes
//! and meeting fifth and sixth (the Universal Robots; `serial/parallel_axes.rs`), and
//! numeric otherwise (Newton on SE(3) with the geometric Jacobian, damped near singular
//! configurations), so any geometry works.
//!
//! Which of a robot's inverse solutions (up to 8 in closed form, up to 16 for a general
//! 6R) is returned: in closed form the one nearest the home joint values (or the joint
//! values given to [`SerialArm::inverse_from`]), numerically the one Newton reaches
//! from them. Along a tool path the motion engine asks for poses close to each other,
//! and the solution stays on the branch it started on as long as the path does not pass
//! a singular configuration.

use nalgebra::{Matrix3, Matrix4, Matrix6, SMatrix, Vector3, Vector6};

use super::machine::SerialMachine;
use super::mechanism::chain_skeleton;
use super::PreparedChain;
use crate::error::{Error, Result};
use crate::limits::{PositionLimits, Violation};
use crate::mechanism::{
    ActuatorMotion, ConditionBatch, Follow, Forward, Mechanism, MechanismInfo, Skeleton,
};
use crate::pose::Pose;
use crate::rotation::{rpy_angular_motion, rpy_rate_matrix, Convention};
use crate::units::Quantity;

/// Up to eight postures and how many there are.
pub(super) type Postures = [Vector6<f64>; 8];

/// A six-joint serial robot with tool-pose coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct SerialArm {
    /// The chains and their geometry.
    machine: SerialMachine,
    /// Home joint values (rad, mm).
    home_joints: Vector6<f64>,
    /// Name, tool-pose coordinates, joints as actuators, home pose, characteristic
    /// length (the tool's distance from the first joint at home), the inverse's method.
    info: MechanismInfo<6, 6>,
    tool: PreparedChain,
    /// The fixed workpiece frame's inverse (identity without a workpiece chain).
    part_inverse: Matrix4<f64>,
    /// The joints' position limits by name (`joint A4 position`), named once: a
    /// motion beyond one clones the name per sample.
    position_limits: PositionLimits,
    /// Links whose angular deviations are completed from a triple (accuracy engine).
    pub(crate) completions: Vec<crate::accuracy::LinkCompletion>,
    /// The base origin in the part frame and an upper bound of the tool's distance from
    /// it (sum of the link translations and prismatic travels): a target beyond it is
    /// out of reach without iterating.
    base_origin: Vector3<f64>,
    reach: f64,
    /// The closed form's geometry, when it applies.
    wrist: Option<closed_form::ClosedForm>,
}

impl SerialArm {
    /// The chains and their geometry.
    pub fn machine(&self) -> &SerialMachine {
        &self.machine
    }

    /// Home joint values (rad, mm).
    pub fn home_joints(&self) -> Vector6<f64> {
        self.home_joints
    }

    /// Whether inverse kinematics is in closed form: a spherical wrist and parallel
    /// second and third axes ([`super::spherical_wrist`]), or parallel second, third
    /// and fourth axes with the fifth and sixth meeting (the Universal Robots).
    pub fn closed_form_inverse(&self) -> bool {
        self.wrist.is_some()
    }

    /// Tool pose relative to the part (homogeneous) and geometric Jacobian (tool-point
    /// velocity over angular velocity, part frame) at joint values `q`.
    pub fn pose_and_jacobian(&self, q: &Vector6<f64>) -> (Matrix4<f64>, Matrix6<f64>) {
        let (t, j) = self.tool.jacobian::<6>(&(*q).into());
        (self.part_inverse * t, self.in_part_frame(&j))
    }

    /// Velocity-over-angular-velocity columns (a Jacobian, `J' q'`) turned from the
    /// base frame into the part frame: both halves by the part's fixed rotation.
    fn in_part_frame<const C: usize>(&self, j: &SMatrix<f64, 6, C>) -> SMatrix<f64, 6, C> {
        let r = self.part_inverse.fixed_view::<3, 3>(0, 0).into_owned();
        let mut jp = SMatrix::<f64, 6, C>::zeros();
        jp.fixed_view_mut::<3, C>(0, 0)
            .copy_from(&(r * j.fixed_view::<3, C>(0, 0)));
        jp.fixed_view_mut::<3, C>(3, 0)
            .copy_from(&(r * j.fixed_view::<3, C>(3, 0)));
        jp
    }

    /// Pose coordinates X..C of joint values `q` (forward kinematics, closed form).
    pub fn coords_of_joints(&self, q: &Vector6<f64>) -> Vector6<f64> {
        let (t, _) = self.pose_and_jacobian(q);
        coords_of(&t)
    }

    /// Inverse kinematics from joint values `start`. In closed form
    /// ([`super::spherical_wrist`]) where it applies: the solution nearest `start`,
    /// polished by one Newton step; a pose out of reach fails with
    /// [`Error::NotAttainable`] naming why. Otherwise numeric: Newton on the pose error
    /// `e = [p* - p; log(R* R^T)]` with the geometric Jacobian, `J dq = e` (seed 003's
    /// chain, differentiated), damped least squares `dq = J^T (J J^T + l^2 I)^-1 e`
    /// (angular rows weighted by the characteristic length) when `J` is close to
    /// singular, steps limited to 0.3 rad / mm and halved until the error decreases,
    /// one more step after convergence so the result is exact to rounding. When Newton
    /// stalls from `start` (a far target can trap it), it is restarted from joint values
    /// spread over the joints' ranges (a fixed sequence: the answer is deterministic).
    /// Revolute joints are returned within half a turn of `start`. Fails with
    /// [`Error::NotConverged`] and the smallest residual found (mm, rad times the
    /// characteristic length) when the pose is out of reach.
    pub fn inverse_from(&self, x: &Vector6<f64>, start: &Vector6<f64>) -> Result<Vector6<f64>> {
        self.inverse_with(x, start, true)
    }

    /// [`SerialArm::inverse_from`] by the numeric solver alone, whatever the geometry:
    /// the closed form's independent check.
    pub fn inverse_numeric_from(
        &self,
        x: &Vector6<f64>,
        start: &Vector6<f64>,
    ) -> Result<Vector6<f64>> {
        self.inverse_with(x, start, false)
    }

    /// Revolute joints shifted by whole turns to lie within half a turn of `near`.
    fn wrap(&self, mut q: Vector6<f64>, near: &Vector6<f64>) -> Vector6<f64> {
        use std::f64::consts::TAU;
        for (i, a) in self.info.actuators().iter().enumerate() {
            if a.quantity == Quantity::Angle {
                q[i] -= TAU * crate::rotation::whole_turns(q[i] - near[i]);
            }
        }
        q
    }

    /// `dq/dx` from the geometric Jacobian `J` at joints `q` and the angles of `x`:
    /// `q' = J^-1 [v; E(A, B, C) (A', B', C')]`.
    fn coords_jacobian(&self, x: &Vector6<f64>, j: &Matrix6<f64>) -> Result<Matrix6<f64>> {
        let inv = self.inverse_geometric(j)?;
        let e = rpy_rate_matrix([x[3], x[4], x[5]]);
        let mut m = Matrix6::identity();
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&e);
        Ok(inv * m)
    }

    /// `K^T K` of `K = dq/dx` at joints `q` with its angle columns divided by the
    /// characteristic length ([`crate::mechanism::scale_driven_columns`]): the 2-norm
    /// condition number of `K` is `sqrt(lambda_max / lambda_min)` of it. `None` at a
    /// singular configuration (`dq/dx` does not exist).
    fn condition_gram(&self, x: &Vector6<f64>, q: &Vector6<f64>) -> Result<Option<Matrix6<f64>>> {
        let (_, j) = self.pose_and_jacobian(q);
        match self.coords_jacobian(x, &j) {
            Ok(jx) => {
                let k = crate::mechanism::scale_driven_columns(self, &jx);
                Ok(Some(k.transpose() * k))
            }
            Err(Error::Singular { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    }

    fn inverse_geometric(&self, j: &Matrix6<f64>) -> Result<Matrix6<f64>> {
        let lc = self.info.characteristic_length();
        let mut js = *j;
        for r in 3..6 {
            js.row_mut(r).scale_mut(lc);
        }
        let singular = |rcond| Error::Singular {
            what: "serial robot Jacobian".into(),
            rcond,
        };
        // nalgebra's `js.try_inverse()`, bit for bit (a pivot not finite refused:
        // singular, where nalgebra returned NaN rates).
        let inv = crate::linalg::inverse_lu(&js).ok_or_else(|| singular(0.0))?;
        let rcond = 1.0 / (crate::linalg::norm1(&js) * crate::linalg::norm1(&inv));
        if rcond < 1e-12 {
            return Err(singular(rcond));
        }
        // Undo the row scaling: J^-1 = (S J)^-1 S.
        let mut out = inv;
        for c in 3..6 {
            out.column_mut(c).scale_mut(lc);
        }
        Ok(out)
    }
}

/// X..C of a homogeneous tool pose.
fn coords_of(t: &Matrix4<f64>) -> Vector6<f64> {
    let r: Matrix3<f64> = t.fixed_view::<3, 3>(0, 0).into_owned();
    let a = Convention::Rpy.from_matrix(&r);
    Vector6::new(t[(0, 3)], t[(1, 3)], t[(2, 3)], a[0], a[1], a[2])
}

impl Mechanism<6, 6> for SerialArm {
    fn info(&self) -> &MechanismInfo<6, 6> {
        &self.info
    }

    /// Numeric inverse kinematics from the home joint values
    /// ([`SerialArm::inverse_from`]).
    fn inverse(&self, x: &Vector6<f64>) -> Result<Vector6<f64>> {
        self.inverse_from(x, &self.home_joints)
    }

    /// In closed form, the solution nearest `q_start` ([`SerialArm::inverse_from`]).
    /// Numerically, Newton from `q_start` alone (a neighbour's solution: one descent,
    /// no restarts, so retrying a point from several neighbours stays cheap); fails
    /// with [`Error::NotConverged`] when it stalls.
    fn inverse_near(&self, x: &Vector6<f64>, q_start: &Vector6<f64>) -> Result<Vector6<f64>> {
        let target_p = Vector3::new(x[0], x[1], x[2]);
        let distance = (target_p - self.base_origin).norm();
        if self.wrist.is_some() || distance > self.reach * (1.0 + 1e-12) {
            return self.inverse_from(x, q_start);
        }
        let target_r = crate::rotation::rpy_matrix(x[3], x[4], x[5]);
        match self.newton(&target_p, &target_r, *q_start) {
            Ok(q) => Ok(self.wrap(q, q_start)),
            Err((residual, iterations, _)) => Err(Error::NotConverged {
                solver: "serial robot inverse kinematics (Newton on SE(3) from a neighbour)",
                iterations,
                residual,
            }),
        }
    }

    /// The cube around the base origin whose half side is the links' reach (sum of the
    /// link translations and prismatic travels): the tool point cannot leave that
    /// sphere, whatever the orientation.
    fn position_bound(&self, _x: &Vector6<f64>) -> Option<[[f64; 2]; 3]> {
        let (o, r) = (self.base_origin, self.reach);
        r.is_finite()
            .then(|| std::array::from_fn(|i| [o[i] - r, o[i] + r]))
    }

    fn jacobian(&self, x: &Vector6<f64>) -> Result<SMatrix<f64, 6, 6>> {
        let q = self.inverse(x)?;
        let (_, j) = self.pose_and_jacobian(&q);
        self.coords_jacobian(x, &j)
    }

    /// The scaled condition number from the joints already solved (no second inverse);
    /// infinite at a singular configuration (a robot's stretched zero pose often is).
    /// The eigenvalues of `K^T K` (`K` the scaled `dq/dx`) by the kernel a map uses for
    /// eight poses at once ([`crate::linalg::gram_condition`]), so a pose gets the same
    /// value here as in [`ConditionBatch::conditions`].
    fn condition_at(&self, x: &Vector6<f64>, q: &Vector6<f64>) -> Result<f64> {
        Ok(match self.condition_gram(x, q)? {
            Some(g) => crate::linalg::gram_condition(&g),
            None => f64::INFINITY,
        })
    }

    /// [`Mechanism::condition_at`] at the joints of `x`'s inverse solution.
    fn condition(&self, x: &Vector6<f64>) -> Result<f64> {
        let q = self.inverse(x)?;
        self.condition_at(x, &q)
    }

    /// Closed form: the chain's pose at `q` (`start` is not needed).
    fn forward(&self, q: &Vector6<f64>, _start: &Vector6<f64>) -> Result<Forward<6>> {
        Ok(Forward {
            pose: self.coords_of_joints(q),
            iterations: 0,
            residual: 0.0,
        })
    }

    fn tool_pose(&self, x: &Vector6<f64>) -> Result<Pose> {
        Ok(crate::legs::spatial_tool_pose(x))
    }

    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<Vector6<f64>> {
        Ok(crate::legs::spatial_coords_from_pose(
            pose,
            orientation_given,
            &self.info.home(),
        ))
    }

    fn check_limits(&self, _x: &Vector6<f64>, q: &Vector6<f64>, out: &mut Vec<Violation>) {
        self.position_limits
            .check(self.info.actuators(), q.as_slice(), out);
    }

    fn skeleton(&self, x: &Vector6<f64>) -> Result<Skeleton> {
        let q = self.inverse(x)?;
        chain_skeleton(&self.machine, q.as_slice(), &[])
    }

    /// At the inverse solution nearest the home joints ([`Mechanism::inverse`]):
    /// `q' = J^-1 [v; w]`, `q'' = J^-1 ([a; al] - J' q')` with `J' q'` exact from the
    /// chain's axes (one pass along the chain). A motion carries the posture on from
    /// sample to sample ([`crate::mechanism::Follow::follow`]).
    fn condition_batch(&self) -> Option<&dyn ConditionBatch<6, 6>> {
        Some(self)
    }

    /// A posture is one of up to eight inverse solutions, and each revolute joint's
    /// position is defined up to whole turns: a motion carries both on.
    fn follower(&self) -> Option<&dyn Follow<6, 6>> {
        Some(self)
    }

    fn actuator_motion(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
    ) -> Result<ActuatorMotion<6>> {
        self.motion_at(self.inverse(x)?, x, xd, xdd)
    }
}

impl SerialArm {
    /// [`Mechanism::actuator_motion`] at the joints `q` of `x` (one inverse solution):
    /// `q' = J^-1 [v; w]`, `q'' = J^-1 ([a; al] - J' q')`.
    fn motion_at(
        &self,
        q: Vector6<f64>,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
    ) -> Result<ActuatorMotion<6>> {
        // One pass along the chain: the axes give J and, once q' is known, J' q'.
        let (t, axes) = self.tool.axes::<6>(&q.into());
        let p = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]);
        let j = self.in_part_frame(&super::jacobian_of_axes(&p, &axes));
        let inv = self.inverse_geometric(&j)?;
        let a = [x[3], x[4], x[5]];
        let (w, al) = rpy_angular_motion(
            a,
            &Vector3::new(xd[3], xd[4], xd[5]),
            &Vector3::new(xdd[3], xdd[4], xdd[5]),
        );
        let twist = Vector6::new(xd[0], xd[1], xd[2], w.x, w.y, w.z);
        let qd = inv * twist;
        // J' q' exactly (the part frame is fixed: its rotation commutes with d/dt).
        let jd_qd = self.in_part_frame(&super::jacobian_rate_times_rates(&p, &axes, &qd.into()));
        let acc = Vector6::new(xdd[0], xdd[1], xdd[2], al.x, al.y, al.z);
        Ok(ActuatorMotion {
            q,
            qd,
            qdd: inv * (acc - jd_qd),
        })
    }
}

mod closed_form;
mod follow;
mod numeric;
mod setup;

#[cfg(test)]
mod tests;

impl ConditionBatch<6, 6> for SerialArm {
    /// Eight poses per call of the lanes' eigenvalue kernel, each equal to
    /// [`Mechanism::condition_at`] (or [`Mechanism::condition`] without `qs`).
    fn conditions(&self, xs: &[Vector6<f64>], qs: &[Vector6<f64>], out: &mut [f64]) {
        let grams: Vec<Result<Option<Matrix6<f64>>>> = xs
            .iter()
            .enumerate()
            .map(|(i, x)| match qs.get(i) {
                Some(q) => self.condition_gram(x, q),
                None => self.inverse(x).and_then(|q| self.condition_gram(x, &q)),
            })
            .collect();
        crate::linalg::gram_conditions_by(
            |k| match &grams[k] {
                Ok(Some(g)) => *g,
                // A stand-in (lanes do not interact); its value is replaced below.
                _ => Matrix6::identity(),
            },
            out,
        );
        for (o, g) in out.iter_mut().zip(&grams) {
            match g {
                Ok(Some(_)) => {}
                Ok(None) => *o = f64::INFINITY,
                Err(_) => *o = f64::NAN,
            }
        }
    }
}

impl Follow<6, 6> for SerialArm {
    /// The solution continuing `prev`: each revolute joint shifted by whole turns to
    /// within half a turn of `prev`; then, when a joint still moved more than the two
    /// samples' rates explain (`|q - q_prev| > r = 2 dt max|q'| + dt^2 max|q''| +
    /// 1e-9`: another posture) or the rates cannot tell (`r > 0.25` rad: coarse
    /// samples), the inverse solved again from `prev` (closed form: the posture
    /// nearest `prev`; else Newton from `prev`) and taken when nearer `prev`.
    fn follow(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
        dt: f64,
        prev: &ActuatorMotion<6>,
        act: &mut ActuatorMotion<6>,
    ) -> bool {
        self.continue_motion(x, xd, xdd, dt, prev, act)
    }
}
