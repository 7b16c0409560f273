//! The hybrid additive-manufacturing machine of seed 002 (Kursk group, "parametric
//! synthesis of additive shaping equipment with a hybrid layout"; restated in
//! `../shared/spec/03-hybrid-am-clearance.md`, pkm's choices in `docs/seed-002.md`).
//!
//! Four carriages move along vertical guides (readings `q1..q4`); each carries a joint
//! `c_i = g_i + q_i e_z` (`g_i`: the joint centre at reading 0, base frame). A strut of
//! fixed length `L_i` joins it to a joint `rho_i` of the moving platform (platform
//! frame), which carries the extruder: nozzle tip `t` and nozzle axis `Ry(gamma) e_z`
//! (platform frame). The part sits on a rotary table (reading `C`).
//!
//! **The "vector of zero length".** The paper's constraint system is the four strut
//! equations `|c_i(q_i) - T_p rho_i| = L_i` plus one equation with "a vector of zero
//! length" that it does not print. pkm takes it as `R_p e_y - e_y = 0`: the platform
//! keeps its Y axis parallel to the base's, as a delta robot's parallelogram legs keep
//! their rungs parallel (one strut built as a parallelogram with its rungs along Y does
//! it). That leaves the platform four freedoms, `X, Y, Z` and the tilt `beta` about Y,
//! `R_p = Ry(beta)`, which the four readings determine, and the tilt is what lets the
//! nozzle follow the surface normal while the table turns the part so that the normal
//! lies in the base XZ plane.
//!
//! **Pose coordinates** are those of the nozzle relative to the part (the part frame
//! turns with the table; its origin is the table centre `c_t`, its Z axis the table
//! axis): tool tip `X, Y, Z`, and `A, B, C` with the tool frame `Rz(C) Ry(B) Rx(A)`.
//! The machine reaches `A = 0` only (a held coordinate, checked as a limit); `B` is the
//! nozzle's tilt from the table axis, `C` the table reading (valued as the tool's turn
//! relative to the part, as CNC axes are: the table itself turns by `-C`). Then
//!
//! ```text
//! beta = B - gamma,   p_b = c_t + Rz(-C) p,   P_i = p_b + Ry(beta) (rho_i - t),
//! q_i = d_z + sqrt(L_i^2 - d_x^2 - d_y^2)  with d = P_i - g_i,   q5 = C
//! ```
//!
//! (the carriage above its platform joint: struts hang from the carriages).
//!
//! **Singularities.** `dq_i = s_i . dP_i / s_iz` with `s_i = P_i - c_i`: the inverse is
//! singular where a strut is horizontal (`s_iz = 0`). The forward problem (four
//! unknowns `O, beta` from four readings) has the Jacobian with rows
//! `[s_i^T, e_y . (r_i x s_i)]`, `r_i = Ry(beta) rho_i`; it is singular where those
//! rows are dependent. A layout symmetric in X and Y (a rectangle of guides, the
//! platform joints at the same `|x|`) is singular at `beta = 0`: the X column and the
//! tilt column are then proportional. The example's platform joints form a trapezoid
//! (see `docs/seed-002.md`). Both singularities make the Jacobian `dq/dx` singular,
//! so [`Mechanism::condition`] reports them.

mod accuracy;
mod forward;
mod inverse;
mod limits;

use nalgebra::{Matrix3, SMatrix, SVector, Vector3, Vector6};

use crate::error::{Error, Result};
use crate::hexapod::JointCone;
use crate::limits::{PositionLimits, Range, Violation};
use crate::mechanism::{
    spatial_coordinates, Actuator, ActuatorMotion, LinkKind, Mechanism, MechanismInfo, PointRole,
    PoseSpace, Skeleton,
};
use crate::pose::{rotation_matrix, Pose};
use crate::rotation::{angle_between, ry, rz};

/// One leg: a carriage on its vertical guide, its joint, the strut, the platform joint.
#[derive(Debug, Clone, PartialEq)]
pub struct Leg {
    /// The carriage's drive (name, stroke, rate limits); its reading `q_i` (mm).
    pub actuator: Actuator,
    /// Name of the carriage joint (`C1`).
    pub carriage_name: String,
    /// Name of the platform joint (`P1`).
    pub platform_name: String,
    /// Carriage joint centre at reading 0 (base frame, mm); the guide is vertical.
    pub guide: Vector3<f64>,
    /// Platform joint centre (platform frame, mm).
    pub platform: Vector3<f64>,
    /// Strut length `L_i` (mm).
    pub length: f64,
}

/// The platform and legs at one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Platform tilt `beta` about Y (rad).
    pub beta: f64,
    /// Platform rotation `Ry(beta)`.
    pub rotation: Matrix3<f64>,
    /// The table's turn `Rz(-C)` (part frame to base frame).
    pub table: Matrix3<f64>,
    /// Tool tip in the base frame (mm).
    pub tip: Vector3<f64>,
    /// Platform joint centres in the base frame (mm).
    pub joints: [Vector3<f64>; 4],
}

/// The machine of seed 002: four carriages on vertical guides, fixed struts, a platform
/// that keeps its Y axis, and a rotary table (see the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct HybridAm {
    /// The four legs.
    legs: [Leg; 4],
    /// Nozzle tip in the platform frame (mm).
    tool: Vector3<f64>,
    /// Tilt `gamma` of the nozzle axis about the platform's Y axis (rad): the nozzle
    /// axis is `Ry(gamma) e_z` in the platform frame.
    tool_tilt: f64,
    /// Table centre `c_t`: the part frame's origin (base frame, mm); the table axis is
    /// vertical.
    table: Vector3<f64>,
    /// Range of the platform tilt `beta` (rad), if limited.
    tilt: Option<Range>,
    /// Cone of the carriage joints (base frame axis), if limited.
    carriage_cone: Option<JointCone>,
    /// Cone of the platform joints (platform frame axis), if limited.
    platform_cone: Option<JointCone>,
    /// Strut diameter for strut-strut interference (mm), if checked.
    strut_diameter: Option<f64>,
    /// Name, coordinates, actuators, home pose, characteristic length (the mean
    /// distance of the platform joints from the nozzle tip).
    info: MechanismInfo<6, 5>,
    /// The carriages' and the table's position limits, named once.
    position_limits: PositionLimits,
}

/// The four driven coordinates and the table: `X, Y, Z, B, C`.
const DRIVEN: [usize; 5] = [0, 1, 2, 4, 5];

impl HybridAm {
    /// Assembles the machine; `table` is the table's drive (`C`, rad).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: String,
        legs: [Leg; 4],
        tool: Vector3<f64>,
        tool_tilt: f64,
        table_centre: Vector3<f64>,
        table: Actuator,
        home: Vector6<f64>,
    ) -> Self {
        let actuators = [
            legs[0].actuator.clone(),
            legs[1].actuator.clone(),
            legs[2].actuator.clone(),
            legs[3].actuator.clone(),
            table,
        ];
        let mut m = HybridAm {
            legs,
            tool,
            tool_tilt,
            table: table_centre,
            tilt: None,
            carriage_cone: None,
            platform_cone: None,
            strut_diameter: None,
            position_limits: PositionLimits::from_fn(&actuators, |i, a| {
                let what = if i < 4 { "carriage" } else { "table" };
                format!("{what} {} position", a.name)
            }),
            info: MechanismInfo::new(
                name,
                "hybrid-am",
                spatial_coordinates(),
                actuators,
                PoseSpace::Spatial,
                home,
            )
            .with_driven(DRIVEN),
        };
        m.derive();
        m
    }

    /// The four legs.
    pub fn legs(&self) -> &[Leg; 4] {
        &self.legs
    }

    /// Nozzle tip in the platform frame (mm).
    pub fn tool(&self) -> Vector3<f64> {
        self.tool
    }

    /// Tilt `gamma` of the nozzle axis about the platform's Y axis (rad).
    pub fn tool_tilt(&self) -> f64 {
        self.tool_tilt
    }

    /// Table centre `c_t`: the part frame's origin (base frame, mm).
    pub fn table(&self) -> Vector3<f64> {
        self.table
    }

    /// Range of the platform tilt `beta` (rad), if limited.
    pub fn tilt(&self) -> Option<Range> {
        self.tilt
    }

    /// Cone of the carriage joints (base frame axis), if limited.
    pub fn carriage_cone(&self) -> Option<&JointCone> {
        self.carriage_cone.as_ref()
    }

    /// Cone of the platform joints (platform frame axis), if limited.
    pub fn platform_cone(&self) -> Option<&JointCone> {
        self.platform_cone.as_ref()
    }

    /// Strut diameter for strut-strut interference (mm), if checked.
    pub fn strut_diameter(&self) -> Option<f64> {
        self.strut_diameter
    }

    /// Sets the limits that derive nothing: the platform tilt's range, the joint cones
    /// and the strut diameter.
    pub fn set_limits(
        &mut self,
        tilt: Option<Range>,
        carriage_cone: Option<JointCone>,
        platform_cone: Option<JointCone>,
        strut_diameter: Option<f64>,
    ) {
        self.tilt = tilt;
        self.carriage_cone = carriage_cone;
        self.platform_cone = platform_cone;
        self.strut_diameter = strut_diameter;
    }

    /// What the machine derives from its geometry: the characteristic length (mean
    /// distance of the platform joints from the nozzle tip).
    fn derive(&mut self) {
        let l = (self
            .legs
            .iter()
            .map(|l| (l.platform - self.tool).norm())
            .sum::<f64>()
            / 4.0)
            .max(1e-9);
        self.info.set_characteristic_length(l);
    }

    /// Pose coordinates `(B, C)` whose tool frame `Rz(C) Ry(B)` is `r`, preferring the
    /// platform tilt nearest zero; `None` when `r` is no such rotation.
    fn tilt_and_turn(&self, r: &Matrix3<f64>) -> Option<(f64, f64)> {
        let s = r[(0, 2)].hypot(r[(1, 2)]);
        let cands: [(f64, f64); 2] = if s > 1e-12 {
            let b = s.atan2(r[(2, 2)]);
            let c = r[(1, 2)].atan2(r[(0, 2)]);
            [(b, c), (-b, wrap(c + std::f64::consts::PI))]
        } else if r[(2, 2)] > 0.0 {
            let c = r[(1, 0)].atan2(r[(0, 0)]);
            [(0.0, c), (0.0, c)]
        } else {
            let c = (-r[(1, 0)]).atan2(-r[(0, 0)]);
            [(std::f64::consts::PI, c), (-std::f64::consts::PI, c)]
        };
        cands
            .into_iter()
            .filter(|(b, c)| angle_between(&(rz(*c) * ry(*b)), r) <= 1e-6)
            .min_by(|a, b| {
                (a.0 - self.tool_tilt)
                    .abs()
                    .total_cmp(&(b.0 - self.tool_tilt).abs())
            })
    }
}

use crate::rotation::wrap_angle as wrap;

impl Mechanism<6, 5> for HybridAm {
    fn info(&self) -> &MechanismInfo<6, 5> {
        &self.info
    }

    fn inverse(&self, x: &Vector6<f64>) -> Result<SVector<f64, 5>> {
        Ok(self.solve(x)?.1)
    }

    /// Row `i < 4`: `k_i^T [Rz(-C), 0, e_y x Ry(beta) (rho_i - t), -e_z x Rz(-C) p]`
    /// with `k_i = s_i / s_iz` (from `|s_i|^2 = L_i^2` with the carriage moving along
    /// `e_z`): the platform Jacobian with its tip columns turned by the table; row 5:
    /// `dC`. `A` moves nothing (held at 0).
    fn jacobian(&self, x: &Vector6<f64>) -> Result<SMatrix<f64, 5, 6>> {
        let (pl, _, s) = self.solve(x)?;
        let jp = Self::platform_jacobian(&pl, &self.rate_vectors(&s)?);
        let tip = jp.fixed_view::<4, 3>(0, 0);
        let xyz = tip * pl.table;
        let dc = tip * (-Vector3::z().cross(&(pl.table * Vector3::new(x[0], x[1], x[2]))));
        let mut j = SMatrix::<f64, 5, 6>::zeros();
        j.fixed_view_mut::<4, 3>(0, 0).copy_from(&xyz);
        j.fixed_view_mut::<4, 1>(0, 4).copy_from(&jp.column(3));
        j.fixed_view_mut::<4, 1>(0, 5).copy_from(&dc);
        j[(4, 5)] = 1.0;
        Ok(j)
    }

    fn forward(
        &self,
        q: &SVector<f64, 5>,
        start: &Vector6<f64>,
    ) -> Result<crate::mechanism::Forward<6>> {
        forward::forward(self, q, start)
    }

    fn tool_pose(&self, x: &Vector6<f64>) -> Result<Pose> {
        Ok(crate::legs::spatial_tool_pose(x))
    }

    /// `B, C` from the nozzle axis (`Rz(C) Ry(B) e_z`), the pair whose platform tilt is
    /// nearest zero; a given orientation must be one the machine has (`A = 0`: no turn
    /// of the nozzle about its axis other than the table's).
    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<Vector6<f64>> {
        let p = pose.translation.vector;
        let (b, c) = if orientation_given {
            let r = rotation_matrix(pose);
            self.tilt_and_turn(&r).ok_or_else(|| {
                let n = r.column(2);
                let b = n.z.clamp(-1.0, 1.0).acos();
                let c = n.y.atan2(n.x);
                Error::NotAttainable {
                    reason: format!(
                        "the machine orients the nozzle by the platform's tilt B and the \
                         table's turn C (A = 0): this orientation is {:.4} deg from the \
                         nearest such one (B = {:.4}, C = {:.4} deg); it turns the nozzle \
                         about an axis the machine does not have",
                        angle_between(&(rz(c) * ry(b)), &r).to_degrees(),
                        b.to_degrees(),
                        c.to_degrees()
                    )
                    .into(),
                }
            })?
        } else {
            (self.info.home()[4], self.info.home()[5])
        };
        Ok(Vector6::new(p.x, p.y, p.z, 0.0, b, c))
    }

    fn check_limits(&self, x: &Vector6<f64>, q: &SVector<f64, 5>, out: &mut Vec<Violation>) {
        limits::check(self, x, q, out)
    }

    /// In the base frame: the guides over their strokes, carriage and platform joints,
    /// struts, the platform, the nozzle, the table centre and the part's X axis.
    fn skeleton(&self, x: &Vector6<f64>) -> Result<Skeleton> {
        let (pl, q, _) = self.solve(x)?;
        let mut s = Skeleton::default();
        let mut plat = [0usize; 4];
        for i in 0..4 {
            let leg = &self.legs[i];
            let r = &leg.actuator.range;
            let g0 = s.point(
                &format!("guide {} bottom", leg.actuator.name),
                PointRole::Other,
                &self.carriage_joint(i, r.min),
            );
            let g1 = s.point(
                &format!("guide {} top", leg.actuator.name),
                PointRole::Other,
                &self.carriage_joint(i, r.max),
            );
            s.link(
                &format!("guide {}", leg.actuator.name),
                LinkKind::Base,
                g0,
                g1,
            );
            let c = s.point(
                &leg.carriage_name,
                PointRole::BaseJoint,
                &self.carriage_joint(i, q[i]),
            );
            plat[i] = s.point(&leg.platform_name, PointRole::PlatformJoint, &pl.joints[i]);
            s.link(&leg.actuator.name, LinkKind::Strut, c, plat[i]);
        }
        for i in 0..4 {
            s.link("", LinkKind::Platform, plat[i], plat[(i + 1) % 4]);
        }
        let o = pl.tip - pl.rotation * self.tool;
        let oi = s.point("platform centre", PointRole::PlatformCentre, &o);
        let tip = s.point("nozzle tip", PointRole::Tool, &pl.tip);
        s.link("extruder", LinkKind::Tool, oi, tip);
        let t = s.point("table centre", PointRole::Other, &self.table);
        let reach = self.info.characteristic_length().max(50.0);
        let px = s.point(
            "part X axis",
            PointRole::Other,
            &(self.table + pl.table * Vector3::new(reach, 0.0, 0.0)),
        );
        s.link("table", LinkKind::Base, t, px);
        Ok(s)
    }

    /// Condition number of the platform's part: `dq_1..4 / d(p_b, beta)` with the tip
    /// in the base frame and the tilt column divided by the characteristic length. The
    /// table is a serial axis with a unit ratio (`dq5 = dC`); mixing its radians with
    /// the carriages' millimetres would only measure the units. Infinite at either
    /// singularity (module documentation).
    fn condition(&self, x: &Vector6<f64>) -> Result<f64> {
        let (pl, _, s) = self.solve(x)?;
        let Ok(k) = self.rate_vectors(&s) else {
            return Ok(f64::INFINITY);
        };
        let mut j = Self::platform_jacobian(&pl, &k);
        j.column_mut(3)
            .scale_mut(1.0 / self.info.characteristic_length());
        Ok(crate::linalg::condition_number(&j))
    }

    /// `q' = k . P'`, `q'' = (s . P'' + |s'|^2) / s_z` (from `s . s = L^2` twice, with
    /// `s' = P' - e_z q'`), where `P = c_t + Rz(-C) p + Ry(beta) a` moves with the
    /// table's angular velocity `w = -C' e_z` and the platform's `W = B' e_y`:
    /// `P' = Rz(-C) p' + w x u + W x v`,
    /// `P'' = Rz(-C) p'' + 2 w x Rz(-C) p' + w' x u + w x (w x u) + W' x v + W x (W x v)`
    /// with `u = Rz(-C) p` and `v = Ry(beta) a`.
    fn actuator_motion(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
    ) -> Result<ActuatorMotion<5>> {
        let (pl, q, s) = self.solve(x)?;
        self.rate_vectors(&s)?;
        let u = pl.table * Vector3::new(x[0], x[1], x[2]);
        let pd = pl.table * Vector3::new(xd[0], xd[1], xd[2]);
        let pdd = pl.table * Vector3::new(xdd[0], xdd[1], xdd[2]);
        let w = Vector3::new(0.0, 0.0, -xd[5]);
        let wd = Vector3::new(0.0, 0.0, -xdd[5]);
        let ww = Vector3::new(0.0, xd[4], 0.0);
        let wwd = Vector3::new(0.0, xdd[4], 0.0);
        let ud = pd + w.cross(&u);
        let udd = pdd + 2.0 * w.cross(&pd) + wd.cross(&u) + w.cross(&w.cross(&u));
        let mut qd = SVector::<f64, 5>::zeros();
        let mut qdd = SVector::<f64, 5>::zeros();
        for i in 0..4 {
            let v = pl.joints[i] - pl.tip;
            let vd = ww.cross(&v);
            let vdd = wwd.cross(&v) + ww.cross(&vd);
            let (p1, p2) = (ud + vd, udd + vdd);
            qd[i] = s[i].dot(&p1) / s[i].z;
            let sd = p1 - Vector3::new(0.0, 0.0, qd[i]);
            qdd[i] = (s[i].dot(&p2) + sd.norm_squared()) / s[i].z;
        }
        (qd[4], qdd[4]) = (xd[5], xdd[5]);
        Ok(ActuatorMotion { q, qd, qdd })
    }
}
