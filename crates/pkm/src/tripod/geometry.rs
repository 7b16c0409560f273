use nalgebra::{Matrix3, SMatrix, Vector3};

use crate::limits::{AxisLimits, LimitKind, PositionLimits, Side, Violation};
use crate::mechanism::{Actuator, LinkKind, PointRole, Skeleton};
use crate::units::Quantity;

/// One strut: its actuator (name, stroke, rate limits) and the joints it joins.
#[derive(Debug, Clone, PartialEq)]
pub struct Strut {
    /// Actuator data; the name is the strut's (`e`, `f`, `g`).
    pub actuator: Actuator,
    /// Name of its base joint (`F`).
    pub base_name: String,
    /// Name of its platform joint (`C`).
    pub platform_name: String,
    /// Base joint centre in the base frame (mm).
    pub base: Vector3<f64>,
    /// Platform joint centre in the platform frame (mm).
    pub platform: Vector3<f64>,
}

/// Geometry and limits shared by both tripod variants.
///
/// Frames: the base frame XYZ of seed 000; the platform frame X1Y1Z1 with its origin
/// at the platform centre B. The tool tip A is at `tool` in the platform frame (seed 000:
/// `(0, 0, -a)`, `a` = 90 mm); the spindle axis is the platform's +Z axis.
#[derive(Debug, Clone, PartialEq)]
pub struct TripodGeometry {
    /// Machine name.
    name: String,
    /// The three struts.
    struts: [Strut; 3],
    /// Tool tip in the platform frame (mm).
    tool: Vector3<f64>,
    /// Largest tilt of the spindle axis from the base Z axis (rad), if limited.
    pub max_tilt: Option<f64>,
    /// Smallest allowed inclination of a strut relative to the spindle axis (rad), the
    /// seed-000 collision condition `phi <= lambda` (see [`TripodGeometry::strut_spindle_angles`]);
    /// `None` disables the check.
    pub min_strut_spindle_angle: Option<f64>,
    /// Strut lengths at the control's zero readings (from a calibration); `None`: the
    /// lengths at home.
    pub zero_lengths: Option<Vector3<f64>>,
    /// Travel of the pose coordinates (`[limits] axes`, LinuxCNC's `[AXIS_L]`), checked
    /// by both tripods against their own coordinates.
    pub axes: AxisLimits,
    /// Cached: the actuators of the three struts.
    actuators: [Actuator; 3],
    /// Cached: their length limits, named once (`strut 1 length`).
    position_limits: PositionLimits,
    /// Cached: base joints and arms (`c_i - t`) for the shared strut computations.
    set: crate::legs::StrutSet<3>,
}

impl TripodGeometry {
    /// Assembles the geometry.
    pub fn new(
        name: String,
        struts: [Strut; 3],
        tool: Vector3<f64>,
        max_tilt: Option<f64>,
        min_strut_spindle_angle: Option<f64>,
    ) -> Self {
        let actuators = [0, 1, 2].map(|i| struts[i].actuator.clone());
        let set = crate::legs::StrutSet::new(
            [0, 1, 2].map(|i| struts[i].base),
            [0, 1, 2].map(|i| struts[i].platform),
            tool,
        );
        TripodGeometry {
            name,
            struts,
            tool,
            max_tilt,
            min_strut_spindle_angle,
            zero_lengths: None,
            axes: AxisLimits::default(),
            position_limits: PositionLimits::strut_lengths(&actuators),
            actuators,
            set,
        }
    }

    /// The same geometry with other struts: name, tool, tilt and collision limits, zero
    /// lengths and travel kept, what derives from the struts built anew.
    pub fn with_struts(&self, struts: [Strut; 3]) -> Self {
        let mut g = TripodGeometry::new(
            self.name.clone(),
            struts,
            self.tool,
            self.max_tilt,
            self.min_strut_spindle_angle,
        );
        g.zero_lengths = self.zero_lengths;
        g.axes = self.axes.clone();
        g
    }

    /// Machine name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The three struts (what the strut geometry, actuators and limits derive from:
    /// a geometry of other struts is built anew with [`TripodGeometry::new`]).
    pub fn struts(&self) -> &[Strut; 3] {
        &self.struts
    }

    /// Tool tip in the platform frame (mm).
    pub fn tool(&self) -> Vector3<f64> {
        self.tool
    }

    /// The shared strut geometry.
    pub fn strut_set(&self) -> &crate::legs::StrutSet<3> {
        &self.set
    }

    /// The three actuators.
    pub fn actuators(&self) -> &[Actuator; 3] {
        &self.actuators
    }

    /// Platform joint centres in the base frame for tool tip `p` and platform rotation
    /// `r` (seed 000 eq. 3-6): `P_i = p + R (c_i - t)`.
    #[inline]
    pub fn platform_joints(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> [Vector3<f64>; 3] {
        self.set.platform_joints(p, r)
    }

    /// Platform centre B in the base frame: `B = p - R t`.
    #[inline]
    pub fn platform_centre(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> Vector3<f64> {
        p - r * self.tool
    }

    /// Strut lengths for any platform pose (seed 000 eq. 7): `L_i = |P_i - F_i|`.
    /// Allocation-free; this is the tripod's inverse kinematics.
    #[inline]
    pub fn strut_lengths(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> Vector3<f64> {
        self.set.lengths(p, r)
    }

    /// Jacobian of the strut lengths with respect to the tool twist `(v, w)`: tool tip
    /// velocity `v` and platform angular velocity `w`, both in the base frame.
    ///
    /// Row i is `[n_i^T, (r_i x n_i)^T]` with `n_i` the unit vector from the base joint
    /// to the platform joint and `r_i = R (c_i - t)`, since
    /// `dL_i/dt = n_i . (v + w x r_i)`.
    pub fn twist_jacobian(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> SMatrix<f64, 3, 6> {
        self.set.twist_jacobian(p, r)
    }

    /// Inclination of each strut relative to the spindle axis (rad), measured in the
    /// plane through the spindle axis and the strut's platform joint, positive when the
    /// strut leans away from the axis.
    ///
    /// Seed 000 requires the spindle tilt `phi` to stay below the strut inclination
    /// `lambda` (`phi <= lambda`), otherwise a strut hits the motor-spindle. For a
    /// spindle tilted by `phi` towards a strut inclined by `lambda` this angle is
    /// `lambda - phi`; the general form holds for any pose and direction of tilt.
    pub fn strut_spindle_angles(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> [f64; 3] {
        let b = self.platform_centre(p, r);
        let u = r.column(2).into_owned();
        let joints = self.platform_joints(p, r);
        [0, 1, 2].map(|i| {
            let rad = joints[i] - b;
            let radial = rad - u * rad.dot(&u);
            let s = (self.struts[i].base - joints[i]).normalize();
            let rn = radial.norm();
            let out = if rn > 1e-12 {
                s.dot(&(radial / rn))
            } else {
                0.0
            };
            out.atan2(s.dot(&u))
        })
    }

    /// Checks strut strokes, tilt and strut/spindle collision; pushes violations.
    pub fn check_limits(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        q: &Vector3<f64>,
        out: &mut Vec<Violation>,
    ) {
        self.position_limits
            .check(&self.actuators, q.as_slice(), out);
        if let Some(max) = self.max_tilt {
            // tilt > max  <=>  R22 < cos(max); the angle itself only when violated.
            if r[(2, 2)] < max.cos() {
                let tilt = crate::rotation::tilt(r);
                if tilt > max {
                    out.push(Violation::new(
                        "spindle tilt",
                        LimitKind::Tilt,
                        Side::Max,
                        Quantity::Angle,
                        tilt,
                        max,
                    ));
                }
            }
        }
        if let Some(min) = self.min_strut_spindle_angle {
            // Fast test: the strut's angle atan2(y, x) is >= min when (x, y) turned by
            // -min lies in the upper half plane; the angle itself only otherwise.
            let (sm, cm) = min.sin_cos();
            let b = self.platform_centre(p, r);
            let u = r.column(2).into_owned();
            let joints = self.platform_joints(p, r);
            let mut exact = None;
            for i in 0..3 {
                let rad = joints[i] - b;
                let radial = rad - u * rad.dot(&u);
                let s = self.struts[i].base - joints[i];
                let (x, y) = (s.dot(&u), s.dot(&radial));
                if y * cm - x * sm >= 0.0 && radial.norm_squared() > 1e-24 {
                    continue;
                }
                let ang = *exact.get_or_insert_with(|| self.strut_spindle_angles(p, r));
                if ang[i] < min {
                    out.push(Violation::new(
                        format!(
                            "strut {}/spindle collision (inclination relative to spindle, phi <= lambda)",
                            self.struts[i].actuator.name
                        ),
                        LimitKind::StrutSpindleCollision,
                        Side::Min,
                        Quantity::Angle,
                        ang[i],
                        min,
                    ));
                }
            }
        }
    }

    /// Base joints, platform joints, platform centre, tool tip, struts and edges.
    /// Returns the skeleton and the index of the platform centre.
    pub fn skeleton(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> (Skeleton, usize) {
        let mut s = Skeleton::default();
        let joints = self.platform_joints(p, r);
        let base: Vec<usize> = self
            .struts
            .iter()
            .map(|st| s.point(&st.base_name, PointRole::BaseJoint, &st.base))
            .collect();
        let plat: Vec<usize> = (0..3)
            .map(|i| {
                s.point(
                    &self.struts[i].platform_name,
                    PointRole::PlatformJoint,
                    &joints[i],
                )
            })
            .collect();
        let b = s.point("B", PointRole::PlatformCentre, &self.platform_centre(p, r));
        let a = s.point("A", PointRole::Tool, p);
        for i in 0..3 {
            s.link(
                &self.struts[i].actuator.name,
                LinkKind::Strut,
                base[i],
                plat[i],
            );
        }
        for i in 0..3 {
            let k = (i + 1) % 3;
            s.link("", LinkKind::Base, base[i], base[k]);
            s.link("", LinkKind::Platform, plat[i], plat[k]);
        }
        s.link("tool", LinkKind::Tool, b, a);
        (s, b)
    }
}
