//! The 4-axis hybrid machine of seed 004: a serial XY cross table under the P3RP head.

use nalgebra::{SMatrix, Vector2, Vector3, Vector4, Vector6};

use super::head::{head_motion, head_skeleton, HeadGeometry};
use crate::error::{Error, Result};
use crate::limits::{LimitKind, PositionLimits, Range, Violation};
use crate::mechanism::{
    spatial_coordinates, Actuator, ActuatorMotion, Forward, LinkKind, Mechanism, MechanismInfo,
    PointRole, PoseSpace, Skeleton,
};
use crate::pose::{rotation_matrix, Pose};
use crate::rotation::{angle_between, rx};
use crate::units::Quantity;

/// The hybrid machine: tool tip X, Y, Z relative to the part (table frame, origin on
/// the table surface under the spindle at X = Y = 0) and the spindle deflection A
/// (rotation about X, the head's theta). B and C are held coordinates the machine keeps
/// at 0: kinematics ignores them and [`Mechanism::check_limits`] reports any other value
/// as a violated limit with its excess.
///
/// Actuators `X`, `Y` (table axes, valued as the tool's position relative to the part,
/// as CNC axes are) and the head's sliders `U`, `V`:
///
/// ```text
/// X_t = X,  Y_t = Y - L sin A,  z = Z + L cos A,  (U, V) = head IK(z, A)
/// ```
///
/// (less hinge A's horizontal offset from the guide line in `Y_t`, zero as built:
/// [`super::HingeOffsets`]).
///
/// with `L` the head's tool length: the head tilts the tool tip sideways by
/// `L sin A` and lifts it by `L (1 - cos A)`, which the table and the U slider
/// compensate.
#[derive(Debug, Clone, PartialEq)]
pub struct HybridMachine {
    /// The head's geometry and limits.
    head: HeadGeometry,
    /// Name, coordinates, the table axes and sliders, home pose X, Y, Z, A, B, C
    /// (B = C = 0), characteristic length (the head's `l1`).
    info: MechanismInfo<6, 4>,
    /// The table axes' and sliders' position limits, named once.
    position_limits: PositionLimits,
}

impl HybridMachine {
    /// New hybrid machine; `actuators` are `X`, `Y` (table) and `U`, `V` (head).
    pub fn new(
        name: String,
        head: HeadGeometry,
        actuators: [Actuator; 4],
        home: Vector6<f64>,
    ) -> Self {
        let l1 = head.l1;
        HybridMachine {
            head,
            position_limits: PositionLimits::from_fn(&actuators, |i, a| {
                let what = if i < 2 { "table axis" } else { "slider" };
                format!("{what} {} position", a.name)
            }),
            info: MechanismInfo::new(
                name,
                "p3rp/hybrid",
                spatial_coordinates(),
                actuators,
                PoseSpace::Spatial,
                home,
            )
            .with_characteristic_length(l1)
            .with_forward_closed_form(),
        }
    }

    /// The head's geometry and limits.
    pub fn head(&self) -> &HeadGeometry {
        &self.head
    }

    /// Replaces the head's geometry (names, actuators and home kept); the
    /// characteristic length follows it.
    pub fn set_head(&mut self, head: HeadGeometry) {
        self.info.set_characteristic_length(head.l1);
        self.head = head;
    }

    /// The head alone (pose `(z, theta)` of its output point, sliders U and V), at the
    /// home pose's head configuration: for the head's own analyses (seed 004's maps).
    pub fn head_mechanism(&self) -> super::P3rpHead {
        super::P3rpHead::new(
            format!("{} (head)", self.info.name()),
            self.head.clone(),
            [
                self.info.actuators()[2].clone(),
                self.info.actuators()[3].clone(),
            ],
            self.head_pose(&self.info.home()),
        )
    }

    /// Head pose `(z, theta)` of a machine pose.
    fn head_pose(&self, x: &Vector6<f64>) -> Vector2<f64> {
        Vector2::new(x[2] + self.head.tool_length * x[3].cos(), x[3])
    }
}

impl Mechanism<6, 4> for HybridMachine {
    fn info(&self) -> &MechanismInfo<6, 4> {
        &self.info
    }

    fn inverse(&self, x: &Vector6<f64>) -> Result<Vector4<f64>> {
        let h = self.head_pose(x);
        let q = self.head.inverse(h[0], h[1])?;
        Ok(Vector4::new(
            x[0],
            x[1] - self.head.tool_length * x[3].sin() - self.head.offsets.a_y,
            q[0],
            q[1],
        ))
    }

    /// `d(X_t, Y_t, U, V)/d(X, Y, Z, A, B, C)`: rows `[1 0 0 0 0 0]`,
    /// `[0 1 0 -L cos A 0 0]`, `[0 0 1 -L sin A 0 0]`, `[0 0 1 g' - L sin A 0 0]`.
    fn jacobian(&self, x: &Vector6<f64>) -> Result<SMatrix<f64, 4, 6>> {
        let l = self.head.tool_length;
        let (s, c) = x[3].sin_cos();
        let dg = self.head.separation(x[3])?.dg;
        let mut j = SMatrix::<f64, 4, 6>::zeros();
        j[(0, 0)] = 1.0;
        j[(1, 1)] = 1.0;
        j[(1, 3)] = -l * c;
        j[(2, 2)] = 1.0;
        j[(2, 3)] = -l * s;
        j[(3, 2)] = 1.0;
        j[(3, 3)] = dg - l * s;
        Ok(j)
    }

    /// Closed form: the head's forward solution on the branch of `start`, then the
    /// table; B and C are taken from `start` (held).
    fn forward(&self, q: &Vector4<f64>, start: &Vector6<f64>) -> Result<Forward<6>> {
        let branch = self.head.branch_of(start[3]).unwrap_or(self.head.branch);
        let h = self.head.forward(q[2], q[3], branch)?;
        let l = self.head.tool_length;
        let (s, c) = h[1].sin_cos();
        let y = q[1] + l * s + self.head.offsets.a_y;
        let pose = Vector6::new(q[0], y, h[0] - l * c, h[1], start[4], start[5]);
        let residual = (self.inverse(&pose)? - q).amax();
        Ok(Forward {
            pose,
            iterations: 0,
            residual,
        })
    }

    fn tool_pose(&self, x: &Vector6<f64>) -> Result<Pose> {
        Ok(crate::legs::spatial_tool_pose(x))
    }

    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<Vector6<f64>> {
        let p = pose.translation.vector;
        let a = if orientation_given {
            let r = rotation_matrix(pose);
            let a = r[(2, 1)].atan2(r[(1, 1)]);
            let off = angle_between(&rx(a), &r);
            if off > 1e-6 {
                return Err(Error::NotAttainable {
                    reason: format!(
                        "the machine turns the spindle about X only: the orientation is \
                         {:.4} deg from any rotation about X",
                        off.to_degrees()
                    )
                    .into(),
                });
            }
            a
        } else {
            self.info.home()[3]
        };
        Ok(Vector6::new(p.x, p.y, p.z, a, 0.0, 0.0))
    }

    fn check_limits(&self, x: &Vector6<f64>, q: &Vector4<f64>, out: &mut Vec<Violation>) {
        // The table axes and the sliders, then the head's joints (the order of
        // `HeadGeometry::check_limits` after the table's).
        self.position_limits
            .check(self.info.actuators(), q.as_slice(), out);
        self.head.check_joint_limits(x[3], out);
        for (k, n) in [(4, "B"), (5, "C")] {
            Range { min: 0.0, max: 0.0 }.check(
                || format!("spindle angle {n} (the head turns about X only)"),
                LimitKind::Tilt,
                Quantity::Angle,
                x[k],
                out,
            );
        }
    }

    fn skeleton(&self, x: &Vector6<f64>) -> Result<Skeleton> {
        let q = self.inverse(x)?;
        let h = self.head_pose(x);
        let mut s = head_skeleton(&self.head, &self.info.actuators()[2..], h[0], h[1])?;
        let o = s.point(
            "O (spindle axis on the table)",
            PointRole::Other,
            &Vector3::zeros(),
        );
        let part = s.point(
            "part origin",
            PointRole::Other,
            &Vector3::new(-q[0], -q[1], 0.0),
        );
        s.link("table", LinkKind::Base, o, part);
        Ok(s)
    }

    fn actuator_motion(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
    ) -> Result<ActuatorMotion<4>> {
        let l = self.head.tool_length;
        let (s, c) = x[3].sin_cos();
        let (a1, a2) = (xd[3], xdd[3]);
        // z = Z + L cos A and Y_t = Y - L sin A, differentiated twice.
        let h = Vector2::new(x[2] + l * c, x[3]);
        let hd = Vector2::new(xd[2] - l * s * a1, a1);
        let hdd = Vector2::new(xdd[2] - l * c * a1 * a1 - l * s * a2, a2);
        let m = head_motion(&self.head, &h, &hd, &hdd)?;
        Ok(ActuatorMotion {
            q: Vector4::new(x[0], x[1] - l * s - self.head.offsets.a_y, m.q[0], m.q[1]),
            qd: Vector4::new(xd[0], xd[1] - l * c * a1, m.qd[0], m.qd[1]),
            qdd: Vector4::new(
                xdd[0],
                xdd[1] + l * s * a1 * a1 - l * c * a2,
                m.qdd[0],
                m.qdd[1],
            ),
        })
    }
}
