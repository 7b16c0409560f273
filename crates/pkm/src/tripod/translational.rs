use nalgebra::{Matrix3, SMatrix, SVector, Vector3, Vector6};

use super::geometry::TripodGeometry;
use crate::error::{Error, Result};
use crate::limits::Violation;
use crate::mechanism::{
    spatial_coordinates, ActuatorMotion, Forward, Mechanism, MechanismInfo, PoseSpace, Skeleton,
};
use crate::pose::Pose;

/// A tripod whose mechanism holds the platform orientation constant (seed 000's arc
/// study). Pose coordinates X, Y, Z, A, B, C of the tool tip (default convention); the
/// struts drive X, Y, Z and A, B, C are held.
#[derive(Debug, Clone, PartialEq)]
pub struct TranslationalTripod {
    /// Geometry and limits.
    geometry: TripodGeometry,
    /// Name, coordinates, actuators (the geometry's) and home pose.
    info: MechanismInfo<6, 3>,
}

impl TranslationalTripod {
    /// New translational tripod with a home pose.
    pub fn new(geometry: TripodGeometry, home: Vector6<f64>) -> Self {
        let info = MechanismInfo::new(
            geometry.name().to_string(),
            "tripod/translational",
            spatial_coordinates(),
            geometry.actuators().clone(),
            PoseSpace::Spatial,
            home,
        )
        .with_forward_closed_form();
        TranslationalTripod { geometry, info }
    }

    /// Geometry and limits.
    pub fn tripod_geometry(&self) -> &TripodGeometry {
        &self.geometry
    }

    /// Sets the travel of the pose coordinates (`[limits] axes`).
    pub fn set_axes(&mut self, axes: crate::limits::AxisLimits) {
        self.geometry.axes = axes;
    }

    /// Tool tip and rotation matrix of pose coordinates.
    #[inline]
    pub fn split(x: &Vector6<f64>) -> (Vector3<f64>, Matrix3<f64>) {
        crate::legs::split_pose(x)
    }

    /// Forward kinematics in closed form for a given platform rotation: the tool tip
    /// lies on three spheres (centre `F_i - R (c_i - t)`, radius `L_i`); of their two
    /// intersections (mirror images in the plane of the centres) the one nearest
    /// `near` is returned.
    pub fn forward_closed_form(
        &self,
        q: &Vector3<f64>,
        r: &Matrix3<f64>,
        near: &Vector3<f64>,
    ) -> Result<Vector3<f64>> {
        let g = &self.geometry;
        let c = [0, 1, 2].map(|i| g.struts()[i].base - r * (g.struts()[i].platform - g.tool()));
        let d21 = c[1] - c[0];
        let d = d21.norm();
        let ex = d21 / d;
        let d31 = c[2] - c[0];
        let i = ex.dot(&d31);
        let ey_raw = d31 - ex * i;
        let jn = ey_raw.norm();
        let scale = d.max(d31.norm());
        if !(d > 1e-9 * scale) || !(jn > 1e-9 * scale) {
            return Err(Error::Singular {
                what: "tripod joints are collinear: the strut lengths do not fix the platform"
                    .into(),
                rcond: 0.0,
            });
        }
        let ey = ey_raw / jn;
        let ez = ex.cross(&ey);
        let (l1, l2, l3) = (q[0] * q[0], q[1] * q[1], q[2] * q[2]);
        let x = (l1 - l2 + d * d) / (2.0 * d);
        let y = (l1 - l3 + i * i + jn * jn) / (2.0 * jn) - i / jn * x;
        let z2 = l1 - x * x - y * y;
        if z2 < 0.0 {
            return Err(Error::NotAttainable {
                reason: format!(
                    "no platform position has strut lengths {:.4}, {:.4}, {:.4} mm at this \
                     orientation: the three spheres miss each other ({:.3e} mm^2 short)",
                    q[0], q[1], q[2], -z2
                )
                .into(),
            });
        }
        let z = z2.sqrt();
        if z < 1e-9 * scale {
            return Err(Error::Singular {
                what: "the struts lie in one plane with the platform joints (the two assembly \
                       modes meet)"
                    .into(),
                rcond: 0.0,
            });
        }
        let base = c[0] + ex * x + ey * y;
        let p1 = base + ez * z;
        let p2 = base - ez * z;
        Ok(if (p1 - near).norm() <= (p2 - near).norm() {
            p1
        } else {
            p2
        })
    }
}

impl Mechanism<6, 3> for TranslationalTripod {
    fn info(&self) -> &MechanismInfo<6, 3> {
        &self.info
    }

    #[inline]
    fn inverse(&self, x: &Vector6<f64>) -> Result<Vector3<f64>> {
        let (p, r) = Self::split(x);
        Ok(self.geometry.strut_lengths(&p, &r))
    }

    /// `dL/dx = J_twist diag(I, E(A, B, C))`, with `E` the angular-velocity map of the
    /// A, B, C rates.
    fn jacobian(&self, x: &Vector6<f64>) -> Result<SMatrix<f64, 3, 6>> {
        Ok(self.geometry.strut_set().coords_jacobian(x))
    }

    /// [`crate::legs::StrutSet::tip_bound`] with the struts' longest strokes.
    fn position_bound(&self, x: &Vector6<f64>) -> Option<[[f64; 2]; 3]> {
        let (_, r) = Self::split(x);
        let max = std::array::from_fn(|i| self.info().actuators()[i].range.max);
        self.geometry.strut_set().tip_bound(&r, &max)
    }

    fn forward(&self, q: &Vector3<f64>, start: &Vector6<f64>) -> Result<Forward<6>> {
        let (p0, r) = Self::split(start);
        let p = self.forward_closed_form(q, &r, &p0)?;
        let mut x = *start;
        x.fixed_rows_mut::<3>(0).copy_from(&p);
        let residual = (self.geometry.strut_lengths(&p, &r) - q).amax();
        Ok(Forward {
            pose: x,
            iterations: 0,
            residual,
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

    fn check_limits(&self, x: &Vector6<f64>, q: &Vector3<f64>, out: &mut Vec<Violation>) {
        let (p, r) = Self::split(x);
        self.geometry.check_limits(&p, &r, q, out);
        self.geometry.axes.check(self.info.coordinates(), x, out);
    }

    fn actuator_motion(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
    ) -> Result<ActuatorMotion<3>> {
        Ok(self.geometry.strut_set().coords_motion(x, xd, xdd))
    }

    fn skeleton(&self, x: &SVector<f64, 6>) -> Result<Skeleton> {
        let (p, r) = Self::split(x);
        Ok(self.geometry.skeleton(&p, &r).0)
    }
}
