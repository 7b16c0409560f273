//! A serial machine as a [`Mechanism`]: its pose coordinates are the joint values (the
//! axes a CNC program or a robot controller commands), its actuators the same joints,
//! and its tool pose the tool relative to the workpiece.
//!
//! The joint count is a const parameter (`N` = tool joints + workpiece joints), so the
//! hot paths stay fixed-size; [`SerialAny`] holds the sizes pkm loads from files.

use nalgebra::{Isometry3, Matrix3, SMatrix, SVector, Translation3, Vector3};

use super::machine::SerialMachine;
use super::PreparedChain;
use crate::error::{Error, Result};
use crate::limits::{PositionLimits, Violation};
use crate::mechanism::{
    Actuator, ActuatorMotion, Coordinate, LinkKind, Mechanism, MechanismInfo, PointRole, PoseSpace,
    Skeleton,
};
use crate::pose::Pose;

/// A serial machine with `N` joints in all.
#[derive(Debug, Clone, PartialEq)]
pub struct SerialMechanism<const N: usize> {
    /// The chains and their geometry ([`SerialMechanism::machine`]); a machine of other
    /// chains is built anew with [`SerialMechanism::new`] (it prepares its chains from
    /// this one).
    machine: SerialMachine,
    /// Name, joints as coordinates and actuators, home joint values.
    info: MechanismInfo<N, N>,
    /// The axes' position limits by name, named once.
    position_limits: PositionLimits,
    /// Joints of the tool chain (the first ones).
    tool_joints: usize,
    /// Links whose angular deviations are completed from a triple (accuracy engine).
    pub(crate) completions: Vec<crate::accuracy::LinkCompletion>,
    /// The nominal chains prepared for repeated evaluation (the tool poses).
    tool: PreparedChain,
    work: Option<PreparedChain>,
}

impl<const N: usize> SerialMechanism<N> {
    /// Wraps a machine with `N` joints; `home` in internal units.
    pub fn new(machine: SerialMachine, home: SVector<f64, N>) -> Result<Self> {
        let joints = machine.all_joints();
        if joints.len() != N {
            return Err(Error::InvalidInput {
                what: "serial machine".into(),
                message: format!("{} joints, expected {N}", joints.len()),
            });
        }
        let coordinates = std::array::from_fn(|i| Coordinate {
            name: joints[i].name.clone(),
            quantity: joints[i].quantity(),
        });
        let actuators: [Actuator; N] = std::array::from_fn(|i| joints[i].actuator());
        Ok(SerialMechanism {
            position_limits: PositionLimits::new("axis", &actuators),
            tool_joints: machine.tool.dof(),
            tool: PreparedChain::new(&machine.tool, &[], &[]),
            work: machine
                .workpiece
                .as_ref()
                .map(|w| PreparedChain::new(w, &[], &[])),
            info: MechanismInfo::new(
                machine.name.clone(),
                "serial",
                coordinates,
                actuators,
                PoseSpace::Own,
                home,
            )
            .with_forward_closed_form(),
            machine,
            completions: Vec::new(),
        })
    }

    /// The chains and their geometry.
    pub fn machine(&self) -> &SerialMachine {
        &self.machine
    }

    fn split(&self, x: &SVector<f64, N>) -> (Vec<f64>, Vec<f64>) {
        let s = x.as_slice();
        (
            s[..self.tool_joints].to_vec(),
            s[self.tool_joints..].to_vec(),
        )
    }

    /// Joint values of tool and workpiece chains for pose coordinates `x`.
    pub fn joint_split(&self, x: &SVector<f64, N>) -> (Vec<f64>, Vec<f64>) {
        self.split(x)
    }
}

impl<const N: usize> Mechanism<N, N> for SerialMechanism<N> {
    fn info(&self) -> &MechanismInfo<N, N> {
        &self.info
    }

    /// The joints are the pose coordinates: identity.
    fn inverse(&self, x: &SVector<f64, N>) -> Result<SVector<f64, N>> {
        Ok(*x)
    }

    fn jacobian(&self, _x: &SVector<f64, N>) -> Result<SMatrix<f64, N, N>> {
        Ok(SMatrix::<f64, N, N>::identity())
    }

    fn forward(
        &self,
        q: &SVector<f64, N>,
        _start: &SVector<f64, N>,
    ) -> Result<crate::mechanism::Forward<N>> {
        Ok(crate::mechanism::Forward {
            pose: *q,
            iterations: 0,
            residual: 0.0,
        })
    }

    /// The nominal tool pose relative to the workpiece, `T_w^-1 T_t` (the forward
    /// kinematics of both chains), from the chains prepared once
    /// ([`PreparedChain::pose`]: within rounding of [`SerialMachine::pose`], tested to
    /// 1e-12 relative) and the workpiece frame inverted as the rigid transform it is
    /// (`R_w^T`, `-R_w^T o_w`); the orientation by
    /// [`crate::rotation::orthonormal_quaternion`]. Allocation-free.
    fn tool_pose(&self, x: &SVector<f64, N>) -> Result<Pose> {
        let (qt, qw) = x.as_slice().split_at(self.tool_joints);
        let t = self.tool.pose(qt);
        let mut r: Matrix3<f64> = t.fixed_view::<3, 3>(0, 0).into_owned();
        let mut p = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]);
        if let Some(work) = &self.work {
            let w = work.pose(qw);
            let rwt = w.fixed_view::<3, 3>(0, 0).transpose();
            r = rwt * r;
            p = rwt * (p - Vector3::new(w[(0, 3)], w[(1, 3)], w[(2, 3)]));
        }
        Ok(Isometry3::from_parts(
            Translation3::from(p),
            crate::rotation::orthonormal_quaternion(&r),
        ))
    }

    fn coords_from_pose(&self, _pose: &Pose, _orientation_given: bool) -> Result<SVector<f64, N>> {
        Err(Error::InvalidInput {
            what: "pose".into(),
            message: "a serial machine's pose is its joint values".into(),
        })
    }

    fn check_limits(&self, x: &SVector<f64, N>, _q: &SVector<f64, N>, out: &mut Vec<Violation>) {
        self.position_limits
            .check(self.info.actuators(), x.as_slice(), out);
    }

    /// Frame origins of both chains (bed frame), consecutive ones linked.
    fn skeleton(&self, x: &SVector<f64, N>) -> Result<Skeleton> {
        let (qt, qw) = self.split(x);
        chain_skeleton(&self.machine, &qt, &qw)
    }

    fn condition(&self, _x: &SVector<f64, N>) -> Result<f64> {
        Ok(1.0)
    }

    fn actuator_motion(
        &self,
        x: &SVector<f64, N>,
        xd: &SVector<f64, N>,
        xdd: &SVector<f64, N>,
    ) -> Result<ActuatorMotion<N>> {
        Ok(ActuatorMotion {
            q: *x,
            qd: *xd,
            qdd: *xdd,
        })
    }
}

/// A serial machine of any joint count pkm loads (1 to 8).
#[derive(Debug, Clone, PartialEq)]
#[allow(missing_docs)]
// One per loaded machine, never in a collection: the arm's inline size costs nothing,
// and a box would hide its type from the generic dispatch (`with_serial!`).
#[allow(clippy::large_enum_variant)]
pub enum SerialAny {
    J1(SerialMechanism<1>),
    J2(SerialMechanism<2>),
    J3(SerialMechanism<3>),
    J4(SerialMechanism<4>),
    J5(SerialMechanism<5>),
    J6(SerialMechanism<6>),
    J7(SerialMechanism<7>),
    J8(SerialMechanism<8>),
    /// A six-joint robot with tool-pose coordinates X..C.
    Arm(super::arm::SerialArm),
    /// A 4-axis machine tool with tool-centre-point coordinates (X, Y, Z, one rotary).
    Tcp4(super::tcp::TcpMachine<4>),
    /// A 5-axis machine tool with tool-centre-point coordinates (X, Y, Z, two rotary).
    Tcp5(super::tcp::TcpMachine<5>),
}

/// Applies `$body` to the `SerialMechanism<N>` inside a [`SerialAny`].
#[macro_export]
macro_rules! with_serial {
    ($any:expr, $m:ident => $body:expr) => {
        match $any {
            $crate::serial::mechanism::SerialAny::J1($m) => $body,
            $crate::serial::mechanism::SerialAny::J2($m) => $body,
            $crate::serial::mechanism::SerialAny::J3($m) => $body,
            $crate::serial::mechanism::SerialAny::J4($m) => $body,
            $crate::serial::mechanism::SerialAny::J5($m) => $body,
            $crate::serial::mechanism::SerialAny::J6($m) => $body,
            $crate::serial::mechanism::SerialAny::J7($m) => $body,
            $crate::serial::mechanism::SerialAny::J8($m) => $body,
            $crate::serial::mechanism::SerialAny::Arm($m) => $body,
            $crate::serial::mechanism::SerialAny::Tcp4($m) => $body,
            $crate::serial::mechanism::SerialAny::Tcp5($m) => $body,
        }
    };
}

impl SerialAny {
    /// Wraps a machine with its home joint values (internal units).
    pub fn new(machine: SerialMachine, home: &[f64]) -> Result<Self> {
        macro_rules! mk {
            ($n:literal, $v:ident) => {
                SerialAny::$v(SerialMechanism::<$n>::new(
                    machine,
                    crate::dynamic::fixed::<$n>("home", home)?,
                )?)
            };
        }
        Ok(match home.len() {
            1 => mk!(1, J1),
            2 => mk!(2, J2),
            3 => mk!(3, J3),
            4 => mk!(4, J4),
            5 => mk!(5, J5),
            6 => mk!(6, J6),
            7 => mk!(7, J7),
            8 => mk!(8, J8),
            n => {
                return Err(Error::InvalidInput {
                    what: "serial machine".into(),
                    message: format!("{n} joints: pkm handles 1 to 8"),
                })
            }
        })
    }

    /// Wraps a six-joint robot with tool-pose coordinates X..C
    /// ([`super::arm::SerialArm`]); `home` are its home joint values.
    pub fn spatial(machine: SerialMachine, home: &[f64]) -> Result<Self> {
        let home = crate::dynamic::fixed::<6>("home", home)?;
        Ok(SerialAny::Arm(super::arm::SerialArm::new(machine, home)?))
    }

    /// Wraps a machine tool with three linear and one or two rotary axes with
    /// tool-centre-point coordinates ([`super::tcp::TcpMachine`]).
    pub fn tcp(machine: SerialMachine, home: &[f64]) -> Result<Self> {
        Ok(match home.len() {
            4 => SerialAny::Tcp4(super::tcp::TcpMachine::new(
                machine,
                crate::dynamic::fixed::<4>("home", home)?,
            )?),
            5 => SerialAny::Tcp5(super::tcp::TcpMachine::new(
                machine,
                crate::dynamic::fixed::<5>("home", home)?,
            )?),
            n => {
                return Err(Error::InvalidInput {
                    what: "TCP coordinates".into(),
                    message: format!(
                        "tool-centre-point coordinates are for 4- and 5-axis machine tools \
                         (three linear axes, one or two rotary); this machine has {n} axes"
                    ),
                })
            }
        })
    }

    /// Whether a machine can take tool-pose coordinates: six tool-chain joints and
    /// no workpiece joints.
    pub fn can_be_spatial(machine: &SerialMachine) -> bool {
        machine.tool.dof() == 6 && machine.workpiece.as_ref().is_none_or(|w| w.dof() == 0)
    }

    /// The machine's chains.
    pub fn machine(&self) -> &SerialMachine {
        with_serial!(self, m => &m.machine())
    }

    /// The home joint values (tool chain, then workpiece chain; internal units).
    pub fn home_joints(&self) -> Vec<f64> {
        match self {
            SerialAny::Arm(a) => a.home_joints().as_slice().to_vec(),
            SerialAny::Tcp4(a) => a.home_joints().as_slice().to_vec(),
            SerialAny::Tcp5(a) => a.home_joints().as_slice().to_vec(),
            other => with_serial!(other, m => m.info().home().as_slice().to_vec()),
        }
    }

    /// Tool-chain and workpiece-chain joint values of actuator values `q` (the
    /// actuators of every serial mechanism are its joints, tool chain first).
    pub fn split_joints<'a>(&self, q: &'a [f64]) -> (&'a [f64], &'a [f64]) {
        q.split_at(self.machine().tool.dof().min(q.len()))
    }
}

/// Frame origins of both chains of `machine` at joint values `qt`, `qw` (bed frame),
/// consecutive ones linked; the tool chain's last point is the tool.
pub(crate) fn chain_skeleton(machine: &SerialMachine, qt: &[f64], qw: &[f64]) -> Result<Skeleton> {
    let mut s = Skeleton::default();
    let chains = std::iter::once((&machine.tool, qt.to_vec()))
        .chain(machine.workpiece.iter().map(|w| (w, qw.to_vec())));
    for (ci, (ch, q)) in chains.enumerate() {
        let mut prev = s.point(
            &format!("{} base", ch.name),
            PointRole::BaseJoint,
            &Vector3::zeros(),
        );
        let mut t = nalgebra::Matrix4::identity();
        let mut k = 0;
        for link in &ch.links {
            if let Some(j) = &link.joint {
                t *= super::joint_transform(j.kind, q[k]);
                k += 1;
            }
            t *= super::link_transform(link, &Default::default());
            let p = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]);
            let last = std::ptr::eq(link, ch.links.last().expect("links"));
            let role = if last && ci == 0 {
                PointRole::Tool
            } else {
                PointRole::Other
            };
            let i = s.point(&link.name, role, &p);
            s.link(&link.name, LinkKind::Passive, prev, i);
            prev = i;
        }
    }
    Ok(s)
}
