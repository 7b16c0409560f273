//! Tool-centre-point (TCP) kinematics of a serial machine tool: three linear axes and
//! one to three rotary axes, in the table (workpiece chain) and/or the head (tool
//! chain). Its pose coordinates are what a 5-axis controller in TCP mode takes (LinuxCNC's
//! `xyzbc-trt-kins`, `xyzac-trt-kins`, Siemens' TRAORI, Heidenhain's M128): the tool tip
//! X, Y, Z in the part frame (the workpiece chain's last frame; mm) and the rotary axes'
//! own angles, named as the file names the joints (`B`, `C`).
//!
//! **Inverse, closed form.** With the rotary angles fixed, every prismatic joint moves
//! the tip along an axis that does not depend on the linear joints, so the tip in the
//! part frame is affine in them: `p(q_lin) = p_0 + M q_lin`, `M` the three prismatic
//! axes (part frame, signed: a joint of the workpiece chain moves the part, so the tip
//! relative to it the other way). One evaluation of the chains at `q_lin = 0` gives
//! `p_0` and `M`; `q_lin = M^-1 (x_p - p_0)` is exact (no iteration).
//!
//! **Forward** is the chains' product (seed 003 eqs. 1-4): the tip relative to the
//! part and the rotary angles.
//!
//! **Jacobian** `dq/dx`: `[M^-1, -M^-1 G; 0, I]` with `G` the tip velocity per unit
//! rotary rate (`z_k x (p - o_k)`, part frame). The rates and accelerations along a
//! path are exact: `M q_lin'' = x_p'' - G x_r'' - h` with `h = J' q'` the tip's
//! velocity-product acceleration, from the spatial velocity of each link of the chain
//! read from the part to the tool (no finite differences).
//!
//! **Directions.** A joint value `q` turns its link about the joint frame's +Z by `q`
//! (right-hand rule); for a rotary table that is the table's own turn, and the tool
//! relative to the part turns the other way. LinuxCNC's trt modules with
//! `conventional-directions = 0` (their default) are this with the table axes along
//! +Y (B) or +X (A) and +Z (C); with `conventional-directions = 1` the table axes point
//! along -Y / -X and -Z (ISO 841: a positive table command turns the tool relative to
//! the part positively). `pkm import linuxcnc` writes the chains accordingly.
//!
//! The tool axis (`I, J, K` of a 5-axis program) is the tool frame's +Z (from the tip
//! towards the spindle), in the part frame; [`TcpMachine::rotary_for_axis`] gives the
//! rotary angles for one (both branches; [`super::tcp_axis`]).

use nalgebra::{Matrix3, Matrix4, SVector, Vector3};

use super::machine::SerialMachine;
use super::{JointKind, PreparedChain};
use crate::error::{Error, Result};
use crate::limits::PositionLimits;
use crate::mechanism::{Actuator, Coordinate, MechanismInfo, PoseSpace};

mod mechanism;

/// The relative kinematics at one joint configuration (part frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Relative<const N: usize> {
    /// Tool tip.
    pub tip: Vector3<f64>,
    /// Tool frame (columns: its axes; the third is the tool axis).
    pub frame: Matrix3<f64>,
    /// Per joint (actuator order): its axis as seen from the part (a workpiece
    /// joint's reversed), unit.
    pub axis: [Vector3<f64>; N],
    /// Per joint: a point of its axis.
    pub point: [Vector3<f64>; N],
}

impl<const N: usize> Relative<N> {
    /// Tip velocity per unit rate of joint `j`.
    #[inline]
    fn column(&self, j: usize, kind: JointKind) -> Vector3<f64> {
        match kind {
            JointKind::Revolute => self.axis[j].cross(&(self.tip - self.point[j])),
            JointKind::Prismatic => self.axis[j],
        }
    }
}

/// An invalid machine for TCP coordinates.
fn invalid(message: String) -> Error {
    Error::InvalidInput {
        what: "TCP coordinates".into(),
        message,
    }
}

/// The indices of the prismatic and of the revolute joints among `joints`: three
/// linear axes and one or two rotary ones, each rotary one with a name of its own.
fn linear_and_rotary<const N: usize>(joints: &[super::Joint]) -> Result<(Vec<usize>, Vec<usize>)> {
    let prismatic: Vec<usize> = (0..joints.len())
        .filter(|&i| joints[i].kind == JointKind::Prismatic)
        .collect();
    let revolute: Vec<usize> = (0..joints.len())
        .filter(|&i| joints[i].kind == JointKind::Revolute)
        .collect();
    if joints.len() != N || prismatic.len() != 3 || !(1..=2).contains(&revolute.len()) {
        return Err(invalid(format!(
            "tool-centre-point coordinates need three linear axes and one or two \
             rotary axes; this machine has {} linear and {} rotary",
            prismatic.len(),
            revolute.len()
        )));
    }
    for (k, &j) in revolute.iter().enumerate() {
        if ["X", "Y", "Z"].contains(&joints[j].name.as_str())
            || revolute[..k]
                .iter()
                .any(|&i| joints[i].name == joints[j].name)
        {
            return Err(invalid(format!(
                "the rotary axis `{}` needs a name of its own (X, Y, Z are the tool tip)",
                joints[j].name
            )));
        }
    }
    Ok((prismatic, revolute))
}

/// The joints in the order of the chain read from the part to the tool (the
/// workpiece joints last to first, then the `tool_joints` tool joints).
fn part_to_tool_order<const N: usize>(tool_joints: usize) -> [usize; N] {
    let mut order = [0; N];
    let nw = N - tool_joints;
    for (k, o) in order.iter_mut().enumerate() {
        *o = if k < nw { N - 1 - k } else { k - nw };
    }
    order
}

/// A serial machine tool with TCP pose coordinates (`N` = 3 linear + rotary joints).
#[derive(Debug, Clone, PartialEq)]
pub struct TcpMachine<const N: usize> {
    /// The chains (the tool chain's last link lengthened by [`TcpMachine::tool_length`]).
    machine: SerialMachine,
    /// Home joint values.
    home_joints: SVector<f64, N>,
    /// Tool length added beyond the file's tool point along the tool axis (mm; a
    /// program's `G43 H`).
    tool_length: f64,
    /// The file's last tool link translation (before the tool length).
    tool_origin: Vector3<f64>,
    /// Name, TCP coordinates, joints as actuators, home pose, characteristic length (the
    /// lever of the rotary axes at home).
    pub(super) info: MechanismInfo<N, N>,
    kinds: [JointKind; N],
    tool_joints: usize,
    /// Actuator indices of the three prismatic joints.
    linear: [usize; 3],
    /// Actuator index of pose coordinate `3 + k` (rotary `k`); entries from `N - 3` on
    /// unused.
    rotary: [usize; N],
    /// Joints in the order of the chain read from the part to the tool: workpiece
    /// joints last to first, then tool joints.
    pub(super) order: [usize; N],
    tool: PreparedChain,
    work: Option<PreparedChain>,
    /// The axes' position limits by name, named once.
    position_limits: PositionLimits,
    /// The relative kinematics at zero joint values: the rotary axes and the tool axis
    /// the tool-axis inverse turns ([`super::tcp_axis`]).
    pub(super) at_zero: Relative<N>,
    /// Links whose angular deviations are completed from a triple (accuracy engine).
    pub(crate) completions: Vec<crate::accuracy::LinkCompletion>,
}

impl<const N: usize> TcpMachine<N> {
    /// Wraps a machine with three prismatic and `N - 3` revolute joints; `home` are the
    /// home joint values (internal units).
    pub fn new(machine: SerialMachine, home: SVector<f64, N>) -> Result<Self> {
        let joints = machine.all_joints();
        let (prismatic, revolute) = linear_and_rotary::<N>(&joints)?;
        let actuators: [Actuator; N] = std::array::from_fn(|i| joints[i].actuator());
        let position_limits = PositionLimits::new("axis", &actuators);
        let coordinates = std::array::from_fn(|i| match i {
            0 => Coordinate::length("X"),
            1 => Coordinate::length("Y"),
            2 => Coordinate::length("Z"),
            _ => Coordinate::angle(&joints[revolute[i - 3]].name),
        });
        let tool_joints = machine.tool.dof();
        let tool_origin = machine
            .tool
            .links
            .last()
            .map(|l| l.translation)
            .unwrap_or_default();
        let mut m = TcpMachine {
            tool: PreparedChain::new(&machine.tool, &[], &[]),
            work: machine
                .workpiece
                .as_ref()
                .map(|w| PreparedChain::new(w, &[], &[])),
            info: MechanismInfo::new(
                machine.name.clone(),
                "serial/tcp",
                coordinates,
                actuators,
                PoseSpace::Tcp,
                SVector::zeros(),
            )
            .with_forward_closed_form(),
            machine,
            home_joints: home,
            tool_length: 0.0,
            tool_origin,
            position_limits,
            kinds: std::array::from_fn(|i| joints[i].kind),
            tool_joints,
            linear: [prismatic[0], prismatic[1], prismatic[2]],
            rotary: std::array::from_fn(|k| revolute.get(k).copied().unwrap_or(0)),
            order: part_to_tool_order(tool_joints),
            at_zero: Relative {
                tip: Vector3::zeros(),
                frame: Matrix3::identity(),
                axis: [Vector3::zeros(); N],
                point: [Vector3::zeros(); N],
            },
            completions: Vec::new(),
        };
        m.set_home_kinematics(&home)?;
        Ok(m)
    }

    /// The relative kinematics at zero, and the home pose and characteristic length
    /// from the kinematics at `home`, whose linear axes must be independent.
    fn set_home_kinematics(&mut self, home: &SVector<f64, N>) -> Result<()> {
        self.at_zero = self.relative(&SVector::zeros());
        let rel = self.relative(home);
        let mcols = self.linear_matrix(&rel);
        let rc = crate::linalg::rcond1(&mcols);
        if !(rc > 1e-9) {
            return Err(invalid(format!(
                "the three linear axes are not independent at home (reciprocal condition {rc:.1e})"
            )));
        }
        let home_pose = self.coords_of_joints(home);
        self.info.set_home(home_pose);
        // A radian of a rotary axis counts as the tip's largest displacement per radian
        // at home: the lever of the rotary axes (at least 1 mm).
        let lever = (3..N)
            .map(|k| rel.column(self.rotary[k - 3], JointKind::Revolute).norm())
            .fold(1.0, f64::max);
        self.info.set_characteristic_length(lever);
        Ok(())
    }

    /// The chains (the tool chain's last link lengthened by the tool length).
    pub fn machine(&self) -> &SerialMachine {
        &self.machine
    }

    /// Home joint values.
    pub fn home_joints(&self) -> SVector<f64, N> {
        self.home_joints
    }

    /// Tool length added beyond the file's tool point along the tool axis (mm; a
    /// program's `G43 H`).
    pub fn tool_length(&self) -> f64 {
        self.tool_length
    }

    /// The same machine with tool length `length` (mm) beyond the file's tool point,
    /// along the tool axis away from the spindle (a program's `G43 H`).
    pub fn with_tool_length(&self, length: f64) -> Result<Self> {
        if !length.is_finite() || length.abs() > crate::machine::MAX_MAGNITUDE {
            return Err(Error::InvalidInput {
                what: "tool length".into(),
                message: format!("expected a finite length in mm, got {length}"),
            });
        }
        let mut machine = self.machine.clone();
        let last = machine
            .tool
            .links
            .last_mut()
            .ok_or_else(|| Error::InvalidInput {
                what: "tool length".into(),
                message: "the tool chain has no links".into(),
            })?;
        last.translation = self.tool_origin - last.rotation.column(2) * length;
        let mut m = TcpMachine::new(machine, self.home_joints)?;
        m.tool_origin = self.tool_origin;
        m.tool_length = length;
        m.completions = self.completions.clone();
        Ok(m)
    }

    /// Pose coordinates (tip in the part frame, rotary angles) of joint values `q`.
    pub fn coords_of_joints(&self, q: &SVector<f64, N>) -> SVector<f64, N> {
        let rel = self.relative(q);
        SVector::<f64, N>::from_fn(|i, _| match i {
            0..=2 => rel.tip[i],
            _ => q[self.rotary[i - 3]],
        })
    }

    /// The tool axis (unit, part frame, from the tip towards the spindle) at joints `q`.
    pub fn tool_axis(&self, q: &SVector<f64, N>) -> Vector3<f64> {
        self.relative(q).frame.column(2).into_owned()
    }

    /// Actuator indices of the rotary joints, in pose-coordinate order.
    pub fn rotary_joints(&self) -> &[usize] {
        &self.rotary[..N - 3]
    }

    /// The tool relative to the part at joints `q`: tip, tool frame and each joint's
    /// axis and a point of it, part frame.
    pub(crate) fn relative(&self, q: &SVector<f64, N>) -> Relative<N> {
        let mut axis = [Vector3::zeros(); N];
        let mut point = [Vector3::zeros(); N];
        let nt = self.tool_joints;
        let s = q.as_slice();
        let mut k = 0;
        let t = self.tool.walk(&s[..nt], |z, o, _| {
            axis[k] = z;
            point[k] = o;
            k += 1;
        });
        let w = match &self.work {
            Some(wc) => wc.walk(&s[nt..], |z, o, _| {
                axis[k] = -z;
                point[k] = o;
                k += 1;
            }),
            None => Matrix4::identity(),
        };
        let rw = w.fixed_view::<3, 3>(0, 0).into_owned();
        let ow = Vector3::new(w[(0, 3)], w[(1, 3)], w[(2, 3)]);
        let rwt = rw.transpose();
        for j in 0..N {
            axis[j] = rwt * axis[j];
            point[j] = rwt * (point[j] - ow);
        }
        Relative {
            tip: rwt * (Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]) - ow),
            frame: rwt * t.fixed_view::<3, 3>(0, 0).into_owned(),
            axis,
            point,
        }
    }

    /// The prismatic axes as the columns of `M`.
    fn linear_matrix(&self, rel: &Relative<N>) -> Matrix3<f64> {
        Matrix3::from_columns(&self.linear.map(|j| rel.axis[j]))
    }

    fn solve_linear(&self, m: &Matrix3<f64>) -> Result<Matrix3<f64>> {
        m.try_inverse()
            .filter(|i| i.iter().all(|v| v.is_finite()))
            .ok_or_else(|| Error::Singular {
                what: "linear axes of the TCP machine".into(),
                rcond: crate::linalg::rcond1(m),
            })
    }

    /// Joint values with the rotary joints at the pose's angles and the linear ones at
    /// zero.
    fn rotary_only(&self, x: &SVector<f64, N>) -> SVector<f64, N> {
        let mut q = SVector::<f64, N>::zeros();
        for k in 3..N {
            q[self.rotary[k - 3]] = x[k];
        }
        q
    }

    /// Inverse kinematics: `q` with the relative kinematics at the rotary angles and the
    /// linear joints at zero, and `M^-1`.
    fn solve(&self, x: &SVector<f64, N>) -> Result<(SVector<f64, N>, Relative<N>, Matrix3<f64>)> {
        if x.iter().any(|v| !v.is_finite()) {
            return Err(Error::InvalidInput {
                what: "pose".into(),
                message: "not a finite number".into(),
            });
        }
        let mut q = self.rotary_only(x);
        let rel0 = self.relative(&q);
        let minv = self.solve_linear(&self.linear_matrix(&rel0))?;
        let target = Vector3::new(x[0], x[1], x[2]);
        let ql = minv * (target - rel0.tip);
        for (k, &j) in self.linear.iter().enumerate() {
            q[j] = ql[k];
        }
        Ok((q, rel0, minv))
    }

    /// The relative kinematics at the solution `q` from those with the linear joints at
    /// zero (`rel0`), without walking the chains again: the slides change no axis, they
    /// move every joint after them (from the part) and the tip along their axes.
    fn at_solution(&self, rel0: &Relative<N>, q: &SVector<f64, N>) -> Relative<N> {
        let mut rel = *rel0;
        let mut shift = Vector3::zeros();
        for &j in &self.order {
            rel.point[j] += shift;
            if self.kinds[j] == JointKind::Prismatic {
                shift += rel.axis[j] * q[j];
            }
        }
        rel.tip += shift;
        rel
    }

    /// `h = J' q'`: the tip's acceleration (part frame) for joint rates `qd` and no
    /// joint accelerations, from the spatial velocity `(w, v)` of each link of the
    /// chain read from the part: a point `y` of a link moves at `v + w x y`; joint `k`'s
    /// axis turns at `w_k x z_k` (`w_k` the link carrying it).
    pub(crate) fn velocity_product(&self, rel: &Relative<N>, qd: &SVector<f64, N>) -> Vector3<f64> {
        let mut w = Vector3::zeros();
        let mut v = Vector3::zeros();
        for &j in &self.order {
            let (z, o) = (rel.axis[j], rel.point[j]);
            match self.kinds[j] {
                JointKind::Revolute => {
                    w += z * qd[j];
                    v += o.cross(&z) * qd[j];
                }
                JointKind::Prismatic => v += z * qd[j],
            }
        }
        let tip_v = v + w.cross(&rel.tip);
        let mut h = Vector3::zeros();
        let mut wb = Vector3::zeros();
        let mut vb = Vector3::zeros();
        for &j in &self.order {
            let (z, o) = (rel.axis[j], rel.point[j]);
            let zd = wb.cross(&z);
            match self.kinds[j] {
                JointKind::Revolute => {
                    let od = vb + wb.cross(&o);
                    h += (zd.cross(&(rel.tip - o)) + z.cross(&(tip_v - od))) * qd[j];
                    wb += z * qd[j];
                    vb += o.cross(&z) * qd[j];
                }
                JointKind::Prismatic => {
                    h += zd * qd[j];
                    vb += z * qd[j];
                }
            }
        }
        h
    }

    /// Joint rates for pose rates `xd` at a solution: `q_r' = x_r'`,
    /// `q_lin' = M^-1 (x_p' - G x_r')`.
    fn rates(
        &self,
        rel: &Relative<N>,
        minv: &Matrix3<f64>,
        xd: &SVector<f64, N>,
        h: Vector3<f64>,
    ) -> SVector<f64, N> {
        let mut qd = SVector::<f64, N>::zeros();
        let mut rhs = Vector3::new(xd[0], xd[1], xd[2]) - h;
        for k in 3..N {
            let j = self.rotary[k - 3];
            qd[j] = xd[k];
            rhs -= rel.column(j, JointKind::Revolute) * xd[k];
        }
        let ql = minv * rhs;
        for (k, &j) in self.linear.iter().enumerate() {
            qd[j] = ql[k];
        }
        qd
    }
}
