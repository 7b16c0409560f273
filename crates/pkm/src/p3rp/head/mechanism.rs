//! The P3RP head as a [`Mechanism`] ([`P3rpHead`]) over its [`HeadGeometry`], and the
//! head's motion and drawing, which the hybrid machine shares.

use nalgebra::{Matrix2, Vector2, Vector3};

use super::{Branch, HeadGeometry};
use crate::error::{Error, Result};
use crate::limits::{PositionLimits, Violation};
use crate::mechanism::{
    Actuator, ActuatorMotion, Coordinate, LinkKind, Mechanism, MechanismInfo, PointRole, PoseSpace,
    Skeleton,
};
use crate::pose::{pose_from_parts, rotation_matrix, Pose};
use crate::rotation::{angle_between, rx};

/// The P3RP head as a [`Mechanism`]: pose `(z, theta)` of the output point t, sliders
/// `U` (D) and `V` (E).
#[derive(Debug, Clone, PartialEq)]
pub struct P3rpHead {
    /// Geometry and limits.
    geometry: HeadGeometry,
    /// Name, coordinates `(z, theta)`, sliders, home pose, characteristic length
    /// (the geometry's `l1`).
    info: MechanismInfo<2, 2>,
    /// The sliders' position limits, named once (`slider U position`).
    position_limits: PositionLimits,
}

impl P3rpHead {
    /// New head; `actuators` are the U and V sliders (strokes, rate limits).
    pub fn new(
        name: String,
        geometry: HeadGeometry,
        actuators: [Actuator; 2],
        home: Vector2<f64>,
    ) -> Self {
        let l1 = geometry.l1;
        P3rpHead {
            geometry,
            position_limits: PositionLimits::new("slider", &actuators),
            info: MechanismInfo::new(
                name,
                "p3rp/head",
                [Coordinate::length("z"), Coordinate::angle("theta")],
                actuators,
                PoseSpace::Own,
                home,
            )
            .with_characteristic_length(l1)
            .with_forward_closed_form(),
        }
    }

    /// Geometry and limits.
    pub fn geometry(&self) -> &HeadGeometry {
        &self.geometry
    }

    /// Replaces the geometry (names, sliders and home kept); the characteristic length
    /// follows it.
    pub fn set_geometry(&mut self, geometry: HeadGeometry) {
        self.info.set_characteristic_length(geometry.l1);
        self.geometry = geometry;
    }

    /// Forward solution on the branch of `start` (the machine's last known state), or
    /// on the machine's branch when `start` is not a pose of the head.
    fn start_branch(&self, start: &Vector2<f64>) -> Branch {
        self.geometry
            .branch_of(start[1])
            .unwrap_or(self.geometry.branch)
    }
}

/// Slider motion of the head: `z1 = z`, `z2 = z + g`, `z2' = z' + g' theta'`,
/// `z2'' = z'' + g' theta'' + g'' theta'^2`.
pub(crate) fn head_motion(
    g: &HeadGeometry,
    x: &Vector2<f64>,
    xd: &Vector2<f64>,
    xdd: &Vector2<f64>,
) -> Result<ActuatorMotion<2>> {
    let s = g.separation(x[1])?;
    let o = &g.offsets;
    Ok(ActuatorMotion {
        q: Vector2::new(x[0] - o.a_z, x[0] + s.g - o.c_z),
        qd: Vector2::new(xd[0], xd[0] + s.dg * xd[1]),
        qdd: Vector2::new(xdd[0], xdd[0] + s.dg * xdd[1] + s.ddg * xd[1] * xd[1]),
    })
}

/// Skeleton of the head at `(z, theta)`, guide drawn over the actuators' strokes.
pub(crate) fn head_skeleton(
    g: &HeadGeometry,
    actuators: &[Actuator],
    z: f64,
    theta: f64,
) -> Result<Skeleton> {
    let [a, b, c, tool] = g.points(z, theta)?;
    let mut s = Skeleton::default();
    let lo = actuators[0].range.min.min(z);
    let hi = actuators[1].range.max.max(c.z);
    let g0 = s.point(
        "guide bottom",
        PointRole::BaseJoint,
        &Vector3::new(0.0, 0.0, lo),
    );
    let g1 = s.point(
        "guide top",
        PointRole::BaseJoint,
        &Vector3::new(0.0, 0.0, hi),
    );
    s.link("guide", LinkKind::Base, g0, g1);
    let ia = s.point("A (slider D)", PointRole::PlatformCentre, &a);
    let ib = s.point("B", PointRole::PlatformJoint, &b);
    let ic = s.point("C (slider E)", PointRole::Other, &c);
    let it = s.point("tool", PointRole::Tool, &tool);
    s.link("AB", LinkKind::Platform, ia, ib);
    s.link("rod BC", LinkKind::Passive, ib, ic);
    s.link("spindle", LinkKind::Tool, ia, it);
    Ok(s)
}

impl Mechanism<2, 2> for P3rpHead {
    fn info(&self) -> &MechanismInfo<2, 2> {
        &self.info
    }

    fn inverse(&self, x: &Vector2<f64>) -> Result<Vector2<f64>> {
        self.geometry.inverse(x[0], x[1])
    }

    fn jacobian(&self, x: &Vector2<f64>) -> Result<Matrix2<f64>> {
        self.geometry.jacobian(x[1])
    }

    /// Closed form ([`HeadGeometry::forward`]) on the branch of `start`.
    fn forward(
        &self,
        q: &Vector2<f64>,
        start: &Vector2<f64>,
    ) -> Result<crate::mechanism::Forward<2>> {
        let pose = self
            .geometry
            .forward(q[0], q[1], self.start_branch(start))?;
        let residual = (self.inverse(&pose)? - q).amax();
        Ok(crate::mechanism::Forward {
            pose,
            iterations: 0,
            residual,
        })
    }

    /// Tool tip `A + Rx(theta) (0, 0, -L)`, tool frame `Rx(theta)` (spindle axis = the
    /// tool frame's z, vertical at `theta = 0`).
    fn tool_pose(&self, x: &Vector2<f64>) -> Result<Pose> {
        let [.., tool] = self.geometry.points(x[0], x[1])?;
        Ok(pose_from_parts(tool, &rx(x[1])))
    }

    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<Vector2<f64>> {
        if !orientation_given {
            return Err(Error::InvalidInput {
                what: "pose".into(),
                message: "the P3RP head's pose is z, theta".into(),
            });
        }
        let r = rotation_matrix(pose);
        let theta = r[(2, 1)].atan2(r[(1, 1)]);
        let off = angle_between(&rx(theta), &r);
        let l = self.geometry.tool_length;
        let p = pose.translation.vector;
        let dy = p.y - self.geometry.offsets.a_y - l * theta.sin();
        if off > 1e-6 || p.x.abs() > 1e-6 || dy.abs() > 1e-6 {
            return Err(Error::NotAttainable {
                reason: format!(
                    "the head only turns about X and moves along Z: the pose is {:.4} deg \
                     from a rotation about X and {:.4} mm off the head's plane",
                    off.to_degrees(),
                    p.x.hypot(dy)
                )
                .into(),
            });
        }
        Ok(Vector2::new(p.z + l * theta.cos(), theta))
    }

    /// [`HeadGeometry::check_limits`], the sliders' names made once.
    fn check_limits(&self, x: &Vector2<f64>, q: &Vector2<f64>, out: &mut Vec<Violation>) {
        self.position_limits
            .check(self.info.actuators(), q.as_slice(), out);
        self.geometry.check_joint_limits(x[1], out);
    }

    fn skeleton(&self, x: &Vector2<f64>) -> Result<Skeleton> {
        head_skeleton(&self.geometry, self.info.actuators(), x[0], x[1])
    }

    fn actuator_motion(
        &self,
        x: &Vector2<f64>,
        xd: &Vector2<f64>,
        xdd: &Vector2<f64>,
    ) -> Result<ActuatorMotion<2>> {
        head_motion(&self.geometry, x, xd, xdd)
    }
}
