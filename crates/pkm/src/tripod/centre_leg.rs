use nalgebra::{Matrix3, SMatrix, Vector3};

use super::geometry::TripodGeometry;
use crate::error::{Error, Result};
use crate::limits::{LimitKind, Range, Violation};
use crate::mechanism::{
    ActuatorMotion, Coordinate, LinkKind, Mechanism, MechanismInfo, PointRole, PoseSpace, Skeleton,
};
use crate::pose::{pose_from_parts, rotation_matrix, Pose};
use crate::rotation::{angle_between, rx, ry, Convention};
use crate::units::Quantity;

/// The passive telescopic centre leg of a Tricept-like tripod.
///
/// It is hinged to the base at `base` by a universal joint whose first axis is the base
/// X axis and whose second axis is the (rotated) Y axis, so the platform rotation is
/// `R = Rx(alpha) Ry(beta)` and never spins about the leg. The platform centre B sits at
/// the leg's end: `B = O + R (0, 0, -s)` with `s` the leg length.
#[derive(Debug, Clone, PartialEq)]
pub struct CentreLeg {
    /// Universal-joint centre O in the base frame (mm).
    pub base: Vector3<f64>,
    /// Stroke of the leg length `s` (mm), if limited.
    pub length: Option<Range>,
}

/// The configuration of the centre leg for a tool position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegState {
    /// First universal-joint angle (about base X), rad.
    pub alpha: f64,
    /// Second universal-joint angle (about the rotated Y), rad.
    pub beta: f64,
    /// Leg length O-B (mm).
    pub length: f64,
    /// Platform rotation `Rx(alpha) Ry(beta)`.
    pub rotation: Matrix3<f64>,
}

/// A tripod with a passive centre leg (Tricept-like): pose coordinates X, Y, Z of the
/// tool tip; the leg determines the platform orientation from the position.
#[derive(Debug, Clone, PartialEq)]
pub struct CentreLegTripod {
    /// Geometry and limits of the struts.
    geometry: TripodGeometry,
    /// The passive centre leg.
    leg: CentreLeg,
    /// Name, coordinates, actuators (the geometry's) and home tool position.
    info: MechanismInfo<3, 3>,
}

use crate::rotation::wrap_angle as wrap;

impl CentreLegTripod {
    /// New centre-leg tripod.
    pub fn new(geometry: TripodGeometry, leg: CentreLeg, home: Vector3<f64>) -> Self {
        let info = MechanismInfo::new(
            geometry.name().to_string(),
            "tripod/centre-leg",
            [
                Coordinate::length("X"),
                Coordinate::length("Y"),
                Coordinate::length("Z"),
            ],
            geometry.actuators().clone(),
            PoseSpace::Position,
            home,
        );
        CentreLegTripod {
            geometry,
            leg,
            info,
        }
    }

    /// Geometry and limits of the struts.
    pub fn tripod_geometry(&self) -> &TripodGeometry {
        &self.geometry
    }

    /// The passive centre leg.
    pub fn leg(&self) -> &CentreLeg {
        &self.leg
    }

    /// Sets the travel of the pose coordinates (`[limits] axes`).
    pub fn set_axes(&mut self, axes: crate::limits::AxisLimits) {
        self.geometry.axes = axes;
    }

    /// Closed-form leg configuration for tool tip `p`.
    ///
    /// With `d = p - O` and tool `t` (platform frame), `d = R v` with
    /// `v = (t_x, t_y, t_z - s)`, so `|v| = |d|` gives `s = t_z + sqrt(|d|^2 - t_x^2 - t_y^2)`;
    /// then `beta` solves `v_x cos(beta) + v_z sin(beta) = d_x` (the root nearest 0) and
    /// `alpha` turns `Ry(beta) v` onto `d` about X.
    pub fn leg_state(&self, p: &Vector3<f64>) -> Result<LegState> {
        let t = self.geometry.tool();
        let d = p - self.leg.base;
        let h2 = d.norm_squared() - t.x * t.x - t.y * t.y;
        if !(h2 > 0.0) {
            return Err(Error::NotAttainable {
                reason: format!(
                    "the tool tip is {:.3} mm from the centre-leg joint, closer than the \
                     tool's lateral offset allows",
                    d.norm()
                )
                .into(),
            });
        }
        let h = h2.sqrt();
        let s = t.z + h;
        let v = Vector3::new(t.x, t.y, -h);
        let rho = v.x.hypot(v.z);
        if d.x.abs() > rho {
            return Err(Error::NotAttainable {
                reason: format!(
                    "the universal joint of the centre leg cannot reach X offset {:.3} mm \
                     (largest {:.3} mm)",
                    d.x, rho
                )
                .into(),
            });
        }
        let phi0 = v.z.atan2(v.x);
        let dphi = (d.x / rho).clamp(-1.0, 1.0).acos();
        let (b1, b2) = (wrap(phi0 + dphi), wrap(phi0 - dphi));
        let beta = if b1.abs() <= b2.abs() { b1 } else { b2 };
        let u = ry(beta) * v;
        let alpha = wrap(d.z.atan2(d.y) - u.z.atan2(u.y));
        let rotation = rx(alpha) * ry(beta);
        Ok(LegState {
            alpha,
            beta,
            length: s,
            rotation,
        })
    }
}

impl CentreLegTripod {
    /// Platform angular velocity and acceleration for a tool tip moving with velocity
    /// `v` and acceleration `a`, from the leg's tangent map: with
    /// `u = (alpha', beta', s')`, `p' = M u` and `w = W u`, so `u = M^-1 p'`,
    /// `u' = M^-1 (p'' - M' u)` and `al = W u' + W' u`.
    pub fn angular_motion(
        &self,
        p: &Vector3<f64>,
        v: &Vector3<f64>,
        a: &Vector3<f64>,
    ) -> Result<(LegState, Vector3<f64>, Vector3<f64>)> {
        let st = self.leg_state(p)?;
        let d = p - self.leg.base;
        let ex = Vector3::x();
        let wb = rx(st.alpha) * Vector3::y();
        let ez_r = st.rotation.column(2).into_owned();
        let m = Matrix3::from_columns(&[ex.cross(&d), wb.cross(&d), -ez_r]);
        let minv = m.try_inverse().ok_or_else(|| Error::Singular {
            what: "centre-leg universal joint".into(),
            rcond: 0.0,
        })?;
        let u = minv * v;
        let w = ex * u[0] + wb * u[1];
        let wb_dot = ex.cross(&wb) * u[0];
        let m_dot =
            Matrix3::from_columns(&[ex.cross(v), wb_dot.cross(&d) + wb.cross(v), -w.cross(&ez_r)]);
        let ud = minv * (a - m_dot * u);
        let al = ex * ud[0] + wb * ud[1] + wb_dot * u[1];
        Ok((st, w, al))
    }
}

impl Mechanism<3, 3> for CentreLegTripod {
    fn info(&self) -> &MechanismInfo<3, 3> {
        &self.info
    }

    fn inverse(&self, x: &Vector3<f64>) -> Result<Vector3<f64>> {
        let st = self.leg_state(x)?;
        Ok(self.geometry.strut_lengths(x, &st.rotation))
    }

    /// `dL/dp = N + K W M^-1`: `N` rows are the strut unit vectors `n_i`, `K` rows
    /// `r_i x n_i`; the leg maps `(dalpha, dbeta, ds)` to `dp = M (...)` with
    /// `M = [e_x x d, w_beta x d, -R e_z]` and to the angular velocity
    /// `w = W (...) = e_x dalpha + w_beta dbeta`, `w_beta = Rx(alpha) e_y`.
    fn jacobian(&self, x: &Vector3<f64>) -> Result<SMatrix<f64, 3, 3>> {
        let st = self.leg_state(x)?;
        let jt = self.geometry.twist_jacobian(x, &st.rotation);
        let d = x - self.leg.base;
        let wa = Vector3::x();
        let wb = rx(st.alpha) * Vector3::y();
        let m = Matrix3::from_columns(&[wa.cross(&d), wb.cross(&d), -st.rotation.column(2)]);
        let minv = m.try_inverse().ok_or_else(|| Error::Singular {
            what: "centre-leg universal joint".into(),
            rcond: 0.0,
        })?;
        let w = Matrix3::from_columns(&[wa, wb, Vector3::zeros()]);
        let n = jt.fixed_view::<3, 3>(0, 0).into_owned();
        let k = jt.fixed_view::<3, 3>(0, 3).into_owned();
        Ok(n + k * w * minv)
    }

    fn tool_pose(&self, x: &Vector3<f64>) -> Result<Pose> {
        let st = self.leg_state(x)?;
        Ok(pose_from_parts(*x, &st.rotation))
    }

    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<Vector3<f64>> {
        let p = pose.translation.vector;
        if orientation_given {
            let st = self.leg_state(&p)?;
            let want = rotation_matrix(pose);
            let diff = angle_between(&st.rotation, &want);
            if diff > 1e-6 {
                let a = Convention::Rpy
                    .from_matrix(&st.rotation)
                    .map(f64::to_degrees);
                let g = Convention::Rpy.from_matrix(&want).map(f64::to_degrees);
                return Err(Error::NotAttainable {
                    reason: format!(
                        "the centre leg sets the orientation from the position: at this \
                         position A, B, C = {:.4}, {:.4}, {:.4} deg, requested {:.4}, {:.4}, \
                         {:.4} deg ({:.4} deg apart); give X, Y, Z only",
                        a[0],
                        a[1],
                        a[2],
                        g[0],
                        g[1],
                        g[2],
                        diff.to_degrees()
                    )
                    .into(),
                });
            }
        }
        Ok(p)
    }

    fn check_limits(&self, x: &Vector3<f64>, q: &Vector3<f64>, out: &mut Vec<Violation>) {
        self.geometry.axes.check(self.info.coordinates(), x, out);
        let Ok(st) = self.leg_state(x) else {
            return;
        };
        self.geometry.check_limits(x, &st.rotation, q, out);
        if let Some(r) = &self.leg.length {
            r.check(
                || "centre leg length",
                LimitKind::PassiveJoint,
                Quantity::Length,
                st.length,
                out,
            );
        }
    }

    fn actuator_motion(
        &self,
        x: &Vector3<f64>,
        xd: &Vector3<f64>,
        xdd: &Vector3<f64>,
    ) -> Result<ActuatorMotion<3>> {
        let (st, w, al) = self.angular_motion(x, xd, xdd)?;
        Ok(self
            .geometry
            .strut_set()
            .motion(x, &st.rotation, xd, &w, xdd, &al))
    }

    fn skeleton(&self, x: &Vector3<f64>) -> Result<Skeleton> {
        let st = self.leg_state(x)?;
        let (mut s, b) = self.geometry.skeleton(x, &st.rotation);
        let o = s.point("O", PointRole::Other, &self.leg.base);
        s.link("centre leg", LinkKind::Passive, o, b);
        Ok(s)
    }
}
