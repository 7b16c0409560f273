//! The hexapod (Stewart-Gough platform) of seed 001 and of LinuxCNC's genhexkins.
//!
//! Six struts join base joints `a_j` (universal joints, base frame) to platform joints
//! `b'_j` (spherical joints, platform frame): `L_j = |p + R (b'_j - t) - a_j|` (seed 001
//! eq. 1 with the tool tip `t` as the characteristic point). Pose coordinates X, Y, Z, A,
//! B, C of the tool tip (default convention), all six driven.

// Struts, joints and sample vectors are indexed together.
#![allow(clippy::needless_range_loop)]

mod accuracy;
mod block;
#[cfg(target_arch = "x86_64")]
mod block_lanes;
mod block_motion;
pub mod forward;
mod interference;
mod lengths;
mod limits;
mod simd;
#[cfg(target_arch = "x86_64")]
mod transpose;

use std::sync::Arc;

use nalgebra::{Matrix3, SMatrix, Vector3, Vector6};

use crate::error::Result;
use crate::legs::{split_pose, StrutSet};
use crate::limits::{LimitCode, LimitName, Violation};
use crate::mechanism::{
    spatial_coordinates, Actuator, ActuatorMotion, BlockKernels, ConditionBatch, Forward, LinkKind,
    Mechanism, MechanismInfo, PointRole, PoseSpace, Skeleton,
};
use crate::pose::Pose;
use crate::rotation::Convention;

pub use forward::{FkOptions, FkReport, FkTracker};
pub use interference::segment_distance;
use limits::limit_names;
pub use limits::JointCone;

pub(crate) use interference::strut_interference;

/// One strut of a hexapod.
#[derive(Debug, Clone, PartialEq)]
pub struct HexStrut {
    /// Actuator (name, stroke, rate limits).
    pub actuator: Actuator,
    /// Base joint name.
    pub base_name: String,
    /// Platform joint name.
    pub platform_name: String,
    /// Base joint centre (base frame, mm).
    pub base: Vector3<f64>,
    /// Platform joint centre (platform frame, mm).
    pub platform: Vector3<f64>,
    /// Cone of the base (universal) joint.
    pub base_cone: Option<JointCone>,
    /// Cone of the platform (spherical) joint.
    pub platform_cone: Option<JointCone>,
}

/// A hexapod machine.
#[derive(Debug, Clone, PartialEq)]
pub struct Hexapod {
    /// The six struts.
    struts: [HexStrut; 6],
    /// Tool tip in the platform frame (mm).
    tool: Vector3<f64>,
    /// Strut diameter for strut-strut interference (mm), if checked.
    strut_diameter: Option<f64>,
    /// Soft limits of the pose coordinates (LinuxCNC's `[AXIS_n]`); none by default.
    axes: crate::limits::AxisLimits,
    /// Strut lengths at the control's zero readings (`L_j^(0)` of seed 001), from a
    /// calibration; `None`: the lengths at home.
    zero_lengths: Option<Vector6<f64>>,
    set: StrutSet<6>,
    soa: crate::legs::StrutSoa<6>,
    lanes: simd::Lanes,
    /// Name, coordinates, actuators, home pose and characteristic length (the mean
    /// distance of the platform joints from the tool tip).
    info: MechanismInfo<6, 6>,
    /// Pairs of struts that share a joint (never checked for interference).
    shares: [[bool; 6]; 6],
    /// The name of every limit code of [`Hexapod::scan`], built with the machine.
    limit_names: Arc<[LimitName]>,
}

/// What a hexapod derives from its joint centres and tool: the strut set, the
/// characteristic length (mean distance of the platform joints from the tool tip), the
/// struct-of-arrays and SIMD lanes of its inverse kinematics.
fn derived(
    base: &[Vector3<f64>; 6],
    platform: &[Vector3<f64>; 6],
    tool: Vector3<f64>,
) -> (StrutSet<6>, f64, crate::legs::StrutSoa<6>, simd::Lanes) {
    let set = StrutSet::new(*base, *platform, tool);
    let characteristic_length = characteristic_length(&set);
    let soa = (&set).into();
    let lanes = simd::Lanes::new(&set.arms, &set.base);
    (set, characteristic_length, soa, lanes)
}

/// The mean distance of the platform joints from the tool tip (at least 1e-9 mm).
fn characteristic_length(set: &StrutSet<6>) -> f64 {
    (set.arms.iter().map(|a| a.norm()).sum::<f64>() / 6.0).max(1e-9)
}

impl Hexapod {
    /// Forward kinematics with the default options from the pose coordinates `start`
    /// ([`forward::solve`]): what [`Mechanism::forward`] and
    /// [`Mechanism::forward_tool_pose`] share.
    fn solve_from_pose(&self, q: &Vector6<f64>, start: &Vector6<f64>) -> Result<FkReport> {
        let (p0, r0) = split_pose(start);
        forward::solve(self, q, &p0, &r0, &FkOptions::default())
    }

    /// Assembles a hexapod.
    pub fn new(
        name: String,
        struts: [HexStrut; 6],
        tool: Vector3<f64>,
        strut_diameter: Option<f64>,
        home: Vector6<f64>,
    ) -> Self {
        let (set, characteristic_length, soa, lanes) = derived(
            &std::array::from_fn(|i| struts[i].base),
            &std::array::from_fn(|i| struts[i].platform),
            tool,
        );
        let actuators = std::array::from_fn(|i| struts[i].actuator.clone());
        let shares = std::array::from_fn(|i| {
            std::array::from_fn(|k| {
                i != k
                    && (struts[i].base_name == struts[k].base_name
                        || struts[i].platform_name == struts[k].platform_name)
            })
        });
        let coordinates = spatial_coordinates();
        Hexapod {
            limit_names: limit_names(&struts, &coordinates),
            info: MechanismInfo::new(
                name,
                "hexapod",
                coordinates,
                actuators,
                PoseSpace::Spatial,
                home,
            )
            .with_characteristic_length(characteristic_length),
            struts,
            tool,
            strut_diameter,
            axes: Default::default(),
            zero_lengths: None,
            soa,
            lanes,
            set,
            shares,
        }
    }

    /// Moves the joint centres in place (names, limits, home and calibration kept):
    /// what [`Hexapod::new`] derives from them is derived again, nothing is allocated
    /// (the accuracy engine re-solves a deviated machine per sample this way).
    pub fn set_joint_centres(&mut self, base: &[Vector3<f64>; 6], platform: &[Vector3<f64>; 6]) {
        for (s, (b, p)) in self.struts.iter_mut().zip(base.iter().zip(platform)) {
            s.base = *b;
            s.platform = *p;
        }
        // Field by field, in place: the derived data (about 1.2 kB) is not built
        // elsewhere and copied over (a tenth of a Monte Carlo sample's time). The
        // tool is the one set_tool left.
        self.set = StrutSet::new(*base, *platform, self.tool);
        self.info
            .set_characteristic_length(characteristic_length(&self.set));
        self.soa = (&self.set).into();
        self.lanes.set_geometry(&self.set.arms, &self.set.base);
    }

    /// The six struts (names, actuators, joint centres and cones).
    pub fn hex_struts(&self) -> &[HexStrut; 6] {
        &self.struts
    }

    /// Replaces the six struts; everything derived from them (strut geometry, lanes,
    /// limit names, actuators, characteristic length) is built again, and the name,
    /// tool, home, soft limits, strut diameter and zero lengths are kept.
    pub fn set_struts(&mut self, struts: [HexStrut; 6]) {
        let mut h = Hexapod::new(
            self.info.name().to_string(),
            struts,
            self.tool,
            self.strut_diameter,
            self.info.home(),
        );
        h.axes = std::mem::take(&mut self.axes);
        h.zero_lengths = self.zero_lengths;
        *self = h;
    }

    /// Tool tip in the platform frame (mm).
    pub fn tool(&self) -> Vector3<f64> {
        self.tool
    }

    /// Moves the tool tip in the platform frame (mm); the strut geometry, its lanes and
    /// the characteristic length are derived again.
    pub fn set_tool(&mut self, tool: Vector3<f64>) {
        self.tool = tool;
        let base = std::array::from_fn(|i| self.struts[i].base);
        let platform = std::array::from_fn(|i| self.struts[i].platform);
        self.set_joint_centres(&base, &platform);
    }

    /// Strut diameter for strut-strut interference (mm), if checked.
    pub fn strut_diameter(&self) -> Option<f64> {
        self.strut_diameter
    }

    /// Sets the strut diameter for strut-strut interference (mm; `None`: unchecked).
    pub fn set_strut_diameter(&mut self, d: Option<f64>) {
        self.strut_diameter = d;
    }

    /// Soft limits of the pose coordinates (LinuxCNC's `[AXIS_n]`); none by default.
    pub fn axes(&self) -> &crate::limits::AxisLimits {
        &self.axes
    }

    /// Sets the soft limits of the pose coordinates.
    pub fn set_axes(&mut self, axes: crate::limits::AxisLimits) {
        self.axes = axes;
    }

    /// Strut lengths at the control's zero readings (`L_j^(0)` of seed 001), from a
    /// calibration; `None`: the lengths at home.
    pub fn zero_lengths(&self) -> Option<Vector6<f64>> {
        self.zero_lengths
    }

    /// Sets the strut lengths at the control's zero readings (`None`: those at home).
    pub fn set_zero_lengths(&mut self, z: Option<Vector6<f64>>) {
        self.zero_lengths = z;
    }

    /// The strut geometry.
    pub fn strut_set(&self) -> &StrutSet<6> {
        &self.set
    }

    /// The strut geometry laid out for the hot length computation.
    pub fn soa(&self) -> &crate::legs::StrutSoa<6> {
        &self.soa
    }

    /// Twist Jacobian with the rotation columns scaled by the characteristic length, so
    /// that its singular values are all in mm per mm: `J diag(I, I / l_c)`.
    pub fn scaled_twist_jacobian(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> SMatrix<f64, 6, 6> {
        self.soa
            .lengths_and_jacobian(p, r, self.info.characteristic_length())
            .1
    }

    /// `J^T J` of [`Self::scaled_twist_jacobian`] at pose coordinates `x`.
    fn gram(&self, x: &Vector6<f64>) -> SMatrix<f64, 6, 6> {
        let (p, r) = split_pose(x);
        let j = self.scaled_twist_jacobian(&p, &r);
        j.transpose() * j
    }
}

impl Mechanism<6, 6> for Hexapod {
    fn info(&self) -> &MechanismInfo<6, 6> {
        &self.info
    }

    #[inline]
    fn inverse(&self, x: &Vector6<f64>) -> Result<Vector6<f64>> {
        Ok(self.pose_lengths(x))
    }

    fn jacobian(&self, x: &Vector6<f64>) -> Result<SMatrix<f64, 6, 6>> {
        Ok(self.set.coords_jacobian(x))
    }

    /// [`crate::legs::StrutSet::tip_bound`] with the struts' longest strokes.
    fn position_bound(&self, x: &Vector6<f64>) -> Option<[[f64; 2]; 3]> {
        let (_, r) = split_pose(x);
        let max = std::array::from_fn(|i| self.struts[i].actuator.range.max);
        self.set.tip_bound(&r, &max)
    }

    /// Newton on SE(3) from `start` (see [`forward::solve`]).
    fn forward(&self, q: &Vector6<f64>, start: &Vector6<f64>) -> Result<Forward<6>> {
        let rep = self.solve_from_pose(q, start)?;
        let a = Convention::Rpy.from_matrix(&rep.rotation);
        Ok(Forward {
            pose: Vector6::new(
                rep.position.x,
                rep.position.y,
                rep.position.z,
                a[0],
                a[1],
                a[2],
            ),
            iterations: rep.iterations,
            residual: rep.residual,
        })
    }

    /// The solver's position and rotation as they are (no round trip through A, B, C).
    fn forward_tool_pose(&self, q: &Vector6<f64>, start: &Vector6<f64>) -> Result<Pose> {
        let rep = self.solve_from_pose(q, start)?;
        Ok(crate::pose::pose_from_parts(rep.position, &rep.rotation))
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

    fn check_limits(&self, x: &Vector6<f64>, q: &Vector6<f64>, out: &mut Vec<Violation>) {
        let (p, r) = split_pose(x);
        self.scan(x, q, &p, &r, |c| {
            out.push(self.violation_of(&c));
            false
        });
    }

    fn skeleton(&self, x: &Vector6<f64>) -> Result<Skeleton> {
        let (p, r) = split_pose(x);
        let joints = self.set.platform_joints(&p, &r);
        let mut s = Skeleton::default();
        let mut base_idx: Vec<(String, usize)> = Vec::new();
        let mut plat_idx: Vec<(String, usize)> = Vec::new();
        let idx = |s: &mut Skeleton,
                   list: &mut Vec<(String, usize)>,
                   name: &str,
                   role,
                   v: &Vector3<f64>| {
            if let Some((_, i)) = list.iter().find(|(n, _)| n == name) {
                return *i;
            }
            let i = s.point(name, role, v);
            list.push((name.to_string(), i));
            i
        };
        let mut pairs = Vec::new();
        for i in 0..6 {
            let st = &self.struts[i];
            let b = idx(
                &mut s,
                &mut base_idx,
                &st.base_name,
                PointRole::BaseJoint,
                &st.base,
            );
            let q = idx(
                &mut s,
                &mut plat_idx,
                &st.platform_name,
                PointRole::PlatformJoint,
                &joints[i],
            );
            pairs.push((b, q));
        }
        for (i, (b, q)) in pairs.iter().enumerate() {
            s.link(&self.struts[i].actuator.name, LinkKind::Strut, *b, *q);
        }
        for list in [(&base_idx, LinkKind::Base), (&plat_idx, LinkKind::Platform)] {
            let n = list.0.len();
            for k in 0..n {
                s.link("", list.1, list.0[k].1, list.0[(k + 1) % n].1);
            }
        }
        let c = s.point("P", PointRole::PlatformCentre, &(p - r * self.tool));
        let a = s.point("tool", PointRole::Tool, &p);
        s.link("tool", LinkKind::Tool, c, a);
        Ok(s)
    }

    /// Condition number of the twist Jacobian with rotations scaled by the
    /// characteristic length (mean platform joint distance from the tool tip): the ratio
    /// of the largest to the smallest strut rate per unit tool twist.
    ///
    /// From the eigenvalues of `J^T J` ([`crate::linalg::gram_conditions`]: eight
    /// poses per call of its lane kernel in [`ConditionBatch::conditions`], the same value
    /// for one pose alone).
    fn condition(&self, x: &Vector6<f64>) -> Result<f64> {
        Ok(crate::linalg::gram_condition(&self.gram(x)))
    }

    fn block_kernels(&self) -> Option<&dyn BlockKernels<6, 6>> {
        Some(self)
    }

    fn condition_batch(&self) -> Option<&dyn ConditionBatch<6, 6>> {
        Some(self)
    }

    fn actuator_motion(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
    ) -> Result<ActuatorMotion<6>> {
        let (p, r) = split_pose(x);
        Ok(self.motion_at(x, xd, xdd, &p, &r))
    }

    /// One rotation of the pose for both the motion and the limits.
    fn actuator_motion_checked(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
        out: &mut Vec<Violation>,
    ) -> Result<ActuatorMotion<6>> {
        let (p, r) = split_pose(x);
        let act = self.motion_at(x, xd, xdd, &p, &r);
        self.scan(x, &act.q, &p, &r, |c| {
            out.push(self.violation_of(&c));
            false
        });
        Ok(act)
    }
}

impl BlockKernels<6, 6> for Hexapod {
    /// The first violated limit as a code (the limit scan's numbering: axis travel, strut
    /// lengths, base and platform cones, strut pairs): no name is formatted. One
    /// rotation and one set of joints for both, and the check stops at the first
    /// violation.
    fn inverse_first_limit(&self, x: &Vector6<f64>) -> Result<(Vector6<f64>, Option<LimitCode>)> {
        let (p, r) = split_pose(x);
        let q = self.lengths(&p, &r);
        let mut first = None;
        self.scan(x, &q, &p, &r, |c| {
            first = Some(c);
            true
        });
        Ok((q, first))
    }

    fn limit_violation(&self, code: &LimitCode) -> Violation {
        self.violation_of(code)
    }

    /// Eight poses at a time: the kernel and limit screen of `hexapod/block.rs`.
    fn inverse_screened(
        &self,
        xs: &[f64],
        qs: &mut [f64],
        clear: &mut [bool],
        check: bool,
    ) -> bool {
        let n = clear.len();
        if xs.len() != 6 * n || qs.len() != 6 * n {
            return false;
        }
        block::screen_rows(&block::Screen::new(self), xs, qs, clear, check)
    }

    fn motion_screened(
        &self,
        x: [&[f64]; 3],
        q: [&mut [f64]; 3],
        clear: &mut [bool],
        computed: &mut [bool],
    ) -> bool {
        let n = clear.len();
        if computed.len() != n
            || x.iter().any(|x| x.len() != 6 * n)
            || q.iter().any(|q| q.len() != 6 * n)
        {
            return false;
        }
        block_motion::motion_rows(&block::Screen::new(self), x, q, clear, computed)
    }
}

impl ConditionBatch<6, 6> for Hexapod {
    /// Eight poses per call of the lanes' eigenvalue kernel.
    fn conditions(&self, xs: &[Vector6<f64>], _qs: &[Vector6<f64>], out: &mut [f64]) {
        crate::linalg::gram_conditions_by(|k| self.gram(&xs[k]), out);
    }
}
