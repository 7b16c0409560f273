//! The pentapod of LinuxCNC's `pentakins`: five struts from base joints to joints that
//! run on rings around the spindle.
//!
//! Strut `i` joins base joint `b_i` (base frame) to a joint on a ring of radius `r_i`
//! whose centre lies on the tool axis `k = R e_z`, at height `z_i` above the effector
//! origin `O`. The ring joint turns about the axis, so it lies in the plane through the
//! axis and `b_i`, on the side of `b_i`; the strut length is the distance from `b_i` to
//! that nearest point of the ring. With `w = b_i - O`, `h = w . k` and
//! `rho = |w - h k|` (pentakins.c `InvKins`, written in the base frame):
//!
//! `L_i = sqrt((h - z_i)^2 + (rho - r_i)^2)`.
//!
//! Pose coordinates are X, Y, Z of the tool tip (on the axis, `t` above `O`:
//! `p = O + t k`) and A, B, C of the default convention (`R = Rz(C) Ry(B) Rx(A)`). The
//! struts drive X, Y, Z, A, B; the spin about the tool axis is free (the rings turn),
//! so C is held: at `C = 0`, which is where a pentapod's home keeps it, `R = Ry(B)
//! Rx(A)` is pentakins' `pmRpyMatConvert(a, b, 0)` and the coordinates are LinuxCNC's
//! X, Y, Z, A, B.

// Struts and vector components are indexed together.
#![allow(clippy::needless_range_loop)]

mod accuracy;
pub(crate) use accuracy::TOOL;

use nalgebra::{Matrix3, SMatrix, SVector, Vector3, Vector6};

use crate::error::{Error, Result};
use crate::hexapod::{strut_interference, JointCone};
use crate::legs::split_pose;
use crate::limits::{AxisLimits, PositionLimits, Violation};
use crate::mechanism::{
    spatial_coordinates, Actuator, ActuatorMotion, LinkKind, Mechanism, MechanismInfo, PointRole,
    PoseSpace, Skeleton,
};
use crate::pose::Pose;

/// One strut of a pentapod.
#[derive(Debug, Clone, PartialEq)]
pub struct PentaStrut {
    /// Actuator (name, stroke, rate limits).
    pub actuator: Actuator,
    /// Base joint name.
    pub base_name: String,
    /// Base joint centre (base frame, mm).
    pub base: Vector3<f64>,
    /// Radius `r_i` of the ring its effector joint runs on (mm).
    pub ring_radius: f64,
    /// Height `z_i` of the ring's centre along the tool axis above the effector origin
    /// (mm; pentakins' `effector.N.z`).
    pub ring_height: f64,
    /// Cone of the base joint.
    pub base_cone: Option<JointCone>,
}

/// A pentapod machine (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct Pentapod {
    /// The five struts.
    struts: [PentaStrut; 5],
    /// Tool tip height `t` along the tool axis above the effector origin (mm).
    tool: f64,
    /// Strut diameter for strut-strut interference (mm), if checked.
    strut_diameter: Option<f64>,
    /// Soft limits of the pose coordinates (LinuxCNC's `[AXIS_n]`).
    axes: AxisLimits,
    /// Strut lengths at the control's zero readings (`[calibration] zero_lengths`,
    /// written by `pkm calibrate`); `None`: the lengths at home.
    zero_lengths: Option<SVector<f64, 5>>,
    /// Name, coordinates, actuators, home pose, characteristic length (the mean
    /// distance of the ring joints from the tool tip), the free spin.
    info: MechanismInfo<6, 5>,
    /// The struts' length limits, named once (`strut 1 length`).
    position_limits: PositionLimits,
}

/// One strut's geometry at a pose: what the length, the Jacobian and the motion share.
struct StrutAt {
    /// `b_i - O` in the effector frame: `s = R^T (b_i - O)`.
    s: Vector3<f64>,
    /// `rho = |s_xy|`.
    rho: f64,
    /// `A = s_z - z_i`.
    a: f64,
    /// `B = rho - r_i`.
    b: f64,
    /// The strut length `sqrt(A^2 + B^2)`.
    l: f64,
}

impl StrutAt {
    /// `grad_s L = (B/L s_xy/rho, A/L)` (effector frame), or `None` when the base joint
    /// is on the tool axis (the ring joint's azimuth is undetermined) or the strut has
    /// no length.
    #[inline]
    fn gradient(&self) -> Option<Vector3<f64>> {
        let scale = self.s.norm().max(1.0);
        if !(self.rho > 1e-12 * scale) || !(self.l > 1e-12 * scale) {
            return None;
        }
        let c = self.b / (self.l * self.rho);
        Some(Vector3::new(c * self.s.x, c * self.s.y, self.a / self.l))
    }
}

impl Pentapod {
    /// Assembles a pentapod.
    pub fn new(
        name: String,
        struts: [PentaStrut; 5],
        tool: f64,
        strut_diameter: Option<f64>,
        axes: AxisLimits,
        home: Vector6<f64>,
    ) -> Self {
        let actuators = std::array::from_fn(|i| struts[i].actuator.clone());
        let characteristic_length = characteristic_length(&struts, tool);
        Pentapod {
            position_limits: PositionLimits::strut_lengths(&actuators),
            info: MechanismInfo::new(
                name,
                "pentapod",
                spatial_coordinates(),
                actuators,
                PoseSpace::Spatial,
                home,
            )
            .with_characteristic_length(characteristic_length)
            .with_free_spin(),
            struts,
            tool,
            strut_diameter,
            axes,
            zero_lengths: None,
        }
    }

    /// The five struts (names, actuators, base joints, rings, cones).
    pub fn penta_struts(&self) -> &[PentaStrut; 5] {
        &self.struts
    }

    /// Tool tip height `t` along the tool axis above the effector origin (mm).
    pub fn tool_height(&self) -> f64 {
        self.tool
    }

    /// Strut diameter for strut-strut interference (mm), if checked.
    pub fn strut_diameter(&self) -> Option<f64> {
        self.strut_diameter
    }

    /// Soft limits of the pose coordinates (LinuxCNC's `[AXIS_n]`).
    pub fn axes(&self) -> &AxisLimits {
        &self.axes
    }

    /// Strut lengths at the control's zero readings; `None`: the lengths at home.
    pub fn zero_lengths(&self) -> Option<SVector<f64, 5>> {
        self.zero_lengths
    }

    /// Replaces the struts and the tool height; what derives from them (actuators,
    /// their limits, the characteristic length) is built again, the name, home, soft
    /// limits, strut diameter and zero lengths kept.
    pub fn set_geometry(&mut self, struts: [PentaStrut; 5], tool: f64) {
        let mut p = Pentapod::new(
            self.info.name().to_string(),
            struts,
            tool,
            self.strut_diameter,
            std::mem::take(&mut self.axes),
            self.info.home(),
        );
        p.zero_lengths = self.zero_lengths;
        *self = p;
    }

    /// Sets the strut diameter for strut-strut interference (mm; `None`: unchecked).
    pub fn set_strut_diameter(&mut self, d: Option<f64>) {
        self.strut_diameter = d;
    }

    /// Sets the strut lengths at the control's zero readings (`None`: those at home).
    pub fn set_zero_lengths(&mut self, z: Option<SVector<f64, 5>>) {
        self.zero_lengths = z;
    }

    /// Pose coordinates of the tool tip `p` on the unit tool axis `k`, with the held C
    /// of home: `Rz(C) Ry(B) Rx(A) e_z = k` gives, with `k' = Rz(-C) k`,
    /// `A = atan2(-k'_y, sqrt(k'_x^2 + k'_z^2))`, `B = atan2(k'_x, k'_z)`.
    pub fn coords_from_axis(&self, p: &Vector3<f64>, k: &Vector3<f64>) -> Vector6<f64> {
        let c = self.info.home()[5];
        let kk = crate::rotation::rz(-c) * k;
        let (a, b) = ((-kk.y).atan2(kk.x.hypot(kk.z)), kk.x.atan2(kk.z));
        Vector6::new(p.x, p.y, p.z, a, b, c)
    }

    /// Effector origin `O = p - t k` and rotation of pose coordinates.
    #[inline]
    fn frame(&self, x: &Vector6<f64>) -> (Vector3<f64>, Matrix3<f64>) {
        let (p, r) = split_pose(x);
        (p - r.column(2) * self.tool, r)
    }

    #[inline]
    fn strut_at(&self, i: usize, o: &Vector3<f64>, r: &Matrix3<f64>) -> StrutAt {
        let st = &self.struts[i];
        let s = r.tr_mul(&(st.base - o));
        let rho = s.x.hypot(s.y);
        let a = s.z - st.ring_height;
        let b = rho - st.ring_radius;
        StrutAt {
            s,
            rho,
            a,
            b,
            l: a.hypot(b),
        }
    }

    /// The ring joint's centre of strut `i` (base frame) at an effector frame: the
    /// point of the ring nearest the base joint (on the axis' side of it when the base
    /// joint lies on the axis, where the ring turns freely).
    fn ring_joint(&self, i: usize, o: &Vector3<f64>, r: &Matrix3<f64>) -> Vector3<f64> {
        let st = &self.struts[i];
        let g = self.strut_at(i, o, r);
        let radial = if g.rho > 0.0 {
            Vector3::new(g.s.x / g.rho, g.s.y / g.rho, 0.0)
        } else {
            Vector3::x()
        };
        o + r * (radial * st.ring_radius + Vector3::z() * st.ring_height)
    }

    /// The effector joints (base frame) at pose `x`.
    pub fn ring_joints(&self, x: &Vector6<f64>) -> [Vector3<f64>; 5] {
        let (o, r) = self.frame(x);
        std::array::from_fn(|i| self.ring_joint(i, &o, &r))
    }

    /// `grad_s L` of strut `i` (see [`StrutAt`]), or [`Error::Singular`] naming the
    /// strut whose base joint is on the tool axis.
    fn gradient(&self, i: usize, g: &StrutAt) -> Result<Vector3<f64>> {
        g.gradient().ok_or_else(|| Error::Singular {
            what: format!(
                "pentapod strut {}: its base joint {} lies on the tool axis (the ring \
                 joint's position around the axis is undetermined) or the strut has no \
                 length",
                self.struts[i].actuator.name, self.struts[i].base_name
            ),
            rcond: 0.0,
        })
    }

    /// Jacobian of the strut lengths with respect to the tool twist `(v, w)` (base
    /// frame). The ring joint is where the distance to the ring is least, so moving it
    /// along the ring changes the length to first order not at all (envelope theorem):
    /// row i is the hexapod's `[n_i^T, ((b_i - p) x n_i)^T]` with the ring joint as the
    /// platform joint (`(b_i - p) x n_i = (E_i - p) x n_i`, since `b_i - E_i` is
    /// parallel to `n_i`).
    pub fn twist_jacobian(&self, x: &Vector6<f64>) -> Result<SMatrix<f64, 5, 6>> {
        let (o, r) = self.frame(x);
        let p = Vector3::new(x[0], x[1], x[2]);
        let mut j = SMatrix::<f64, 5, 6>::zeros();
        for i in 0..5 {
            // The unit strut vector (base joint to ring joint): n = -R grad_s L.
            let n = -(r * self.gradient(i, &self.strut_at(i, &o, &r))?);
            let m = (self.struts[i].base - p).cross(&n);
            for k in 0..3 {
                j[(i, k)] = n[k];
                j[(i, 3 + k)] = m[k];
            }
        }
        Ok(j)
    }
}

fn characteristic_length(struts: &[PentaStrut; 5], tool: f64) -> f64 {
    (struts
        .iter()
        .map(|s| s.ring_radius.hypot(s.ring_height - tool))
        .sum::<f64>()
        / 5.0)
        .max(1e-9)
}

impl Mechanism<6, 5> for Pentapod {
    fn info(&self) -> &MechanismInfo<6, 5> {
        &self.info
    }

    /// `L_i = sqrt((s_z - z_i)^2 + (|s_xy| - r_i)^2)`, `s = R^T (b_i - O)` (pentakins.c
    /// `InvKins`).
    #[inline]
    fn inverse(&self, x: &Vector6<f64>) -> Result<SVector<f64, 5>> {
        let (o, r) = self.frame(x);
        Ok(SVector::<f64, 5>::from_fn(|i, _| {
            self.strut_at(i, &o, &r).l
        }))
    }

    /// Newton on the driven coordinates X, Y, Z, A, B (C held), continued along the
    /// actuators from `IK(start)` in steps of at most a tenth of the characteristic
    /// length (19 mm on LinuxCNC's sim) when they are farther (see
    /// [`crate::mechanism::continued_forward`]): the solution on the branch through
    /// `start`.
    fn forward(
        &self,
        q: &SVector<f64, 5>,
        start: &Vector6<f64>,
    ) -> Result<crate::mechanism::Forward<6>> {
        crate::mechanism::continued_forward(
            self,
            q,
            start,
            &crate::mechanism::NewtonOptions::default(),
            0.1 * self.info.characteristic_length(),
        )
    }

    /// The twist Jacobian (see [`Pentapod::twist_jacobian`]) times `diag(I, E(A, B, C))`.
    fn jacobian(&self, x: &Vector6<f64>) -> Result<SMatrix<f64, 5, 6>> {
        let mut j = self.twist_jacobian(x)?;
        crate::legs::twist_to_coords(&mut j, x);
        Ok(j)
    }

    /// The tip is `p = E_i + (t - z_i) k - r_i u` with `|E_i - b_i| <= L_max` and `u` a
    /// unit vector normal to `k`: within `L_max + r_i` of `b_i + (t - z_i) k` per axis.
    fn position_bound(&self, x: &Vector6<f64>) -> Option<[[f64; 2]; 3]> {
        let (_, r) = split_pose(x);
        let k = r.column(2).into_owned();
        crate::legs::box_intersection(self.struts.iter().map(|s| {
            (
                s.base + k * (self.tool - s.ring_height),
                s.actuator.range.max + s.ring_radius,
            )
        }))
    }

    fn tool_pose(&self, x: &Vector6<f64>) -> Result<Pose> {
        Ok(crate::legs::spatial_tool_pose(x))
    }

    /// The tool tip, and the tool axis of a given orientation with the held C of home
    /// ([`Pentapod::coords_from_axis`]). The spin of the given frame about its axis is
    /// not the machine's to set and is dropped.
    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<Vector6<f64>> {
        let p = pose.translation.vector;
        if orientation_given {
            let k = crate::pose::rotation_matrix(pose).column(2).into_owned();
            return Ok(self.coords_from_axis(&p, &k));
        }
        Ok(Vector6::new(
            p.x,
            p.y,
            p.z,
            self.info.home()[3],
            self.info.home()[4],
            self.info.home()[5],
        ))
    }

    fn check_limits(&self, x: &Vector6<f64>, q: &SVector<f64, 5>, out: &mut Vec<Violation>) {
        self.axes.check(self.info.coordinates(), x, out);
        let joints = self.ring_joints(x);
        for i in 0..5 {
            let s = &self.struts[i];
            self.position_limits
                .check_one(i, &self.info.actuators()[i], q[i], out);
            if let Some(c) = &s.base_cone {
                let d = joints[i] - s.base;
                let cos = if d.norm() > 0.0 {
                    d.normalize().dot(&c.axis)
                } else {
                    1.0
                };
                c.check(
                    cos,
                    || {
                        format!(
                            "base joint {} angle (strut {})",
                            s.base_name, s.actuator.name
                        )
                    },
                    out,
                );
            }
        }
        if let Some(dia) = self.strut_diameter {
            let base: [Vector3<f64>; 5] = std::array::from_fn(|i| self.struts[i].base);
            let names: [&str; 5] = std::array::from_fn(|i| self.struts[i].actuator.name.as_str());
            let same = |i: usize, k: usize| self.struts[i].base_name == self.struts[k].base_name;
            strut_interference(&names, &base, &joints, same, dia, out);
        }
    }

    /// Base joints, the effector (ring) joints `effector <strut>`, the rings' centres on
    /// the tool axis `ring <strut>`, the spindle between the lowest and the highest ring
    /// and the tool from the ring nearer the tip.
    fn skeleton(&self, x: &Vector6<f64>) -> Result<Skeleton> {
        let (o, r) = self.frame(x);
        let k = r.column(2).into_owned();
        let p = Vector3::new(x[0], x[1], x[2]);
        let mut s = Skeleton::default();
        let mut bases: Vec<(String, usize)> = Vec::new();
        let mut top = (f64::NEG_INFINITY, 0usize);
        let mut low = (f64::INFINITY, 0usize);
        for (i, st) in self.struts.iter().enumerate() {
            let b = match bases.iter().find(|(n, _)| *n == st.base_name) {
                Some((_, b)) => *b,
                None => {
                    let b = s.point(&st.base_name, PointRole::BaseJoint, &st.base);
                    bases.push((st.base_name.clone(), b));
                    b
                }
            };
            let e = s.point(
                &format!("effector {}", st.actuator.name),
                PointRole::PlatformJoint,
                &self.ring_joint(i, &o, &r),
            );
            let c = s.point(
                &format!("ring {}", st.actuator.name),
                PointRole::Other,
                &(o + k * st.ring_height),
            );
            s.link(&st.actuator.name, LinkKind::Strut, b, e);
            s.link("", LinkKind::Platform, e, c);
            if st.ring_height > top.0 {
                top = (st.ring_height, c);
            }
            if st.ring_height < low.0 {
                low = (st.ring_height, c);
            }
        }
        if top.1 != low.1 {
            s.link("spindle", LinkKind::Platform, low.1, top.1);
        }
        let t = s.point("tool", PointRole::Tool, &p);
        let from = if (self.tool - top.0).abs() < (self.tool - low.0).abs() {
            top.1
        } else {
            low.1
        };
        s.link("tool", LinkKind::Tool, from, t);
        Ok(s)
    }

    /// `s' = -R^T (O' + w x (b - O))`,
    /// `s'' = R^T (2 w x O' + w x (w x (b - O)) - O'' - al x (b - O))`, with
    /// `O' = v - t w x k`, `O'' = a - t (al x k + w x (w x k))`; then `L' = g . s'` and
    /// `L'' = s'^T H s' + g . s''`, `g` and `H` the gradient and Hessian of `L(s)`:
    /// `s'^T H s' = (A (n . s'_xy) - B s'_z)^2 / L^3 + B / (L rho) (|s'_xy|^2 - (n . s'_xy)^2)`,
    /// `n = s_xy / rho` (exact, no finite differences).
    fn actuator_motion(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
    ) -> Result<ActuatorMotion<5>> {
        let (o, r) = self.frame(x);
        let k = r.column(2).into_owned();
        let v = xd.fixed_rows::<3>(0).into_owned();
        let acc = xdd.fixed_rows::<3>(0).into_owned();
        let (w, al) = crate::rotation::rpy_angular_motion(
            [x[3], x[4], x[5]],
            &xd.fixed_rows::<3>(3).into_owned(),
            &xdd.fixed_rows::<3>(3).into_owned(),
        );
        let od = v - w.cross(&k) * self.tool;
        let odd = acc - (al.cross(&k) + w.cross(&w.cross(&k))) * self.tool;
        let mut out = ActuatorMotion {
            q: SVector::zeros(),
            qd: SVector::zeros(),
            qdd: SVector::zeros(),
        };
        for i in 0..5 {
            let g = self.strut_at(i, &o, &r);
            let grad = self.gradient(i, &g)?;
            let wb = self.struts[i].base - o;
            let sd = -r.tr_mul(&(od + w.cross(&wb)));
            let sdd =
                r.tr_mul(&(w.cross(&od) * 2.0 + w.cross(&w.cross(&wb)) - odd - al.cross(&wb)));
            let (nx, ny) = (g.s.x / g.rho, g.s.y / g.rho);
            let ns = nx * sd.x + ny * sd.y;
            let sxy2 = sd.x * sd.x + sd.y * sd.y;
            let t = g.a * ns - g.b * sd.z;
            let hess = t * t / (g.l * g.l * g.l) + g.b / (g.l * g.rho) * (sxy2 - ns * ns);
            out.q[i] = g.l;
            out.qd[i] = grad.dot(&sd);
            out.qdd[i] = hess + grad.dot(&sdd);
        }
        Ok(out)
    }
}
