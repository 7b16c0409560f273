//! The mechanism abstraction every analysis is written against.
//!
//! A mechanism maps its *pose coordinates* `x` (what the machine controls: X, Y, Z, A,
//! B, C of the tool for a spatial machine; `z, theta` for a planar head; ...) to its
//! *actuator coordinates* `q` (strut lengths, slider positions, joint angles) and back.
//!
//! * `P` is the number of pose coordinates, `A` the number of actuators. A mechanism
//!   with fewer actuators than pose coordinates *holds* the others: the translational
//!   tripod, for instance, takes X, Y, Z, A, B, C but its three struts only move X, Y, Z;
//!   A, B, C stay where the mechanism holds them. [`MechanismInfo::driven`] says which
//!   coordinates the actuators drive.
//! * Internal units are millimetres and radians; [`Coordinate::quantity`] and
//!   [`Actuator::quantity`] say how to convert at the user boundary.
//! * Fixed-size nalgebra types keep the hot paths free of allocation: an inverse
//!   solution, a Jacobian and a limit check with no violation allocate nothing.
//! * The model is immutable and `Sync`, so sweeps share one model across threads.
//!
//! The inverse Jacobian `J = dq/dx` (`A x P`) relates the rates:
//! `q_dot = J x_dot`; orientation columns are with respect to the coordinates as the
//! mechanism defines them (radians of the RPY angles for spatial machines).

use nalgebra::{SMatrix, SVector};
use serde::Serialize;

use crate::error::Result;
use crate::limits::{Range, Violation};
use crate::pose::Pose;
use crate::units::Quantity;

pub mod abilities;
mod info;
mod skeleton;
mod solve;

pub use abilities::{BlockKernels, ConditionBatch, Follow, ToolAxis};
pub use info::MechanismInfo;

pub use skeleton::{LinkKind, PointRole, Skeleton, SkeletonLink, SkeletonPoint};
pub(crate) use solve::halton;
pub use solve::{
    assembly_modes, continued_forward, driven_jacobian, inverse_checked, inverse_continuing,
    newton_forward, scale_driven_columns, scaled_driven_jacobian, spread_starts, NewtonOptions,
};

/// One pose coordinate of a mechanism.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Coordinate {
    /// Name users type (`X`, `A`, `z`, `theta`).
    pub name: String,
    /// Length or angle.
    pub quantity: Quantity,
}

impl Coordinate {
    /// A length coordinate.
    pub fn length(name: &str) -> Self {
        Coordinate {
            name: name.into(),
            quantity: Quantity::Length,
        }
    }

    /// An angle coordinate.
    pub fn angle(name: &str) -> Self {
        Coordinate {
            name: name.into(),
            quantity: Quantity::Angle,
        }
    }
}

/// The six coordinates of a spatial pose: tool tip X, Y, Z (mm) and the A, B, C angles
/// of the default convention (`R = Rz(C) Ry(B) Rx(A)`).
pub fn spatial_coordinates() -> [Coordinate; 6] {
    [
        Coordinate::length("X"),
        Coordinate::length("Y"),
        Coordinate::length("Z"),
        Coordinate::angle("A"),
        Coordinate::angle("B"),
        Coordinate::angle("C"),
    ]
}

/// One actuated joint (drive).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Actuator {
    /// Name (`e`, `U`, `A1`).
    pub name: String,
    /// Linear (mm) or revolute (rad) drive.
    pub quantity: Quantity,
    /// Position range.
    pub range: Range,
    /// Largest speed (mm/s or rad/s), when the file gives one.
    pub max_velocity: Option<f64>,
    /// Largest acceleration (mm/s^2 or rad/s^2), when the file gives one.
    pub max_acceleration: Option<f64>,
    /// Stiffness of the drive along its own coordinate, when the file gives one: axial
    /// (N/mm) for a linear drive, torsional (N mm/rad) for a revolute one. The
    /// statics and stiffness analyses ([`crate::statics`]) need it.
    pub stiffness: Option<f64>,
}

/// How a mechanism's pose coordinates relate to a full tool pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PoseSpace {
    /// Coordinates are X, Y, Z, A, B, C of the tool (mm, default convention).
    Spatial,
    /// Coordinates are X, Y, Z of the tool tip; the mechanism determines the orientation.
    Position,
    /// Tool-centre-point coordinates of a machine tool with rotary axes: X, Y, Z of the
    /// tool tip in the part frame, then the rotary axes' own angles, named by their
    /// letters (`B`, `C`), as a 5-axis controller in TCP mode takes them.
    Tcp,
    /// The mechanism's own coordinates (a planar head's `z, theta`, joint space, ...).
    Own,
}

/// Result of a forward-kinematics solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forward<const P: usize> {
    /// The pose coordinates found.
    pub pose: SVector<f64, P>,
    /// Iterations used (0 for closed-form solutions).
    pub iterations: usize,
    /// Largest actuator residual `|IK(pose) - q|` (mm or rad).
    pub residual: f64,
}

/// The pose coordinates for a tool tip and tool axis
/// ([`ToolAxis::poses_for_tool_axis`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ToolAxisPoses<const P: usize> {
    /// Every branch (pose coordinates, internal units).
    pub branches: Vec<SVector<f64, P>>,
    /// The branch the continuity rule chose.
    pub chosen: usize,
    /// The axis is (within rounding) along the singular direction: the rotary angle
    /// it leaves undetermined was held at its previous value.
    pub singular: bool,
    /// Angle between the axis and the singular direction (rad).
    pub singular_distance: f64,
}

/// A mechanism with `P` pose coordinates and `A` actuators: the core every machine type
/// implements and every analysis is written against.
///
/// Eight methods are required: what the mechanism is ([`Mechanism::info`]), its
/// inverse kinematics, Jacobian, tool pose both ways, limits, skeleton and actuator
/// motion. The others have defaults a type overrides where it knows better (a numeric
/// inverse started nearby, a closed-form forward, a conditioning of its own). Optional
/// abilities are capability queries returning `None` by default
/// ([`Mechanism::block_kernels`], [`Mechanism::condition_batch`],
/// [`Mechanism::follower`], [`Mechanism::tool_axis`]); the generic engines reach them
/// through the functions of [`abilities`] (`inverse_screened`,
/// `conditions`, ...), which fall back to the core.
///
/// ```
/// use pkm::{Machine, Mechanism};
/// let machine = Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let pkm::machine::Model::Hexapod(h) = &machine.model else { panic!() };
/// let home = h.info().home();
/// let lengths = h.inverse(&home).unwrap();
/// let back = h.forward(&lengths, &home).unwrap();
/// assert!((back.pose - home).norm() < 1e-9);
/// assert_eq!(h.info().actuators().len(), 6);
/// ```
pub trait Mechanism<const P: usize, const A: usize>: Send + Sync {
    /// What the mechanism is: name, type, coordinates, actuators, driven coordinates,
    /// pose space, home pose, characteristic length, methods in words.
    fn info(&self) -> &MechanismInfo<P, A>;

    /// Inverse kinematics: actuator coordinates for pose `x`. Fails only when no
    /// geometric solution exists; stroke and other limits are checked separately by
    /// [`Mechanism::check_limits`].
    fn inverse(&self, x: &SVector<f64, P>) -> Result<SVector<f64, A>>;

    /// Inverse Jacobian `dq/dx` at `x` (`A x P`).
    fn jacobian(&self, x: &SVector<f64, P>) -> Result<SMatrix<f64, A, P>>;

    /// The full tool pose (tool tip position and tool frame) at `x`.
    fn tool_pose(&self, x: &SVector<f64, P>) -> Result<Pose>;

    /// Pose coordinates of a full tool pose. `orientation_given` says whether the
    /// orientation part was given by the user (and must then be consistent with what
    /// the mechanism can produce) or may be chosen by the mechanism.
    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<SVector<f64, P>>;

    /// Pushes every violated limit at pose `x` with actuators `q` onto `out`.
    fn check_limits(&self, x: &SVector<f64, P>, q: &SVector<f64, A>, out: &mut Vec<Violation>);

    /// Points and links of the mechanism at `x`, for drawings and joint reports.
    fn skeleton(&self, x: &SVector<f64, P>) -> Result<Skeleton>;

    /// Exact actuator position, velocity and acceleration for a pose moving with
    /// coordinate rates `xd` and accelerations `xdd`: `q = IK(x)`, `q' = J x'`,
    /// `q'' = J x'' + J' x'`, computed from the mechanism's analytic derivatives (no
    /// finite differences).
    fn actuator_motion(
        &self,
        x: &SVector<f64, P>,
        xd: &SVector<f64, P>,
        xdd: &SVector<f64, P>,
    ) -> Result<ActuatorMotion<A>>;

    /// [`Mechanism::inverse`] started from actuator values `q_start` (a neighbouring
    /// point's solution): numeric solvers (a serial robot's) try it first and return
    /// the solution nearest it; closed-form solvers ignore it (the default).
    fn inverse_near(
        &self,
        x: &SVector<f64, P>,
        _q_start: &SVector<f64, A>,
    ) -> Result<SVector<f64, A>> {
        self.inverse(x)
    }

    /// Forward kinematics: the pose with actuator coordinates `q`, found from the
    /// starting pose `start` (the machine's last known state); held coordinates are
    /// taken from `start`. The default is [`newton_forward`].
    fn forward(&self, q: &SVector<f64, A>, start: &SVector<f64, P>) -> Result<Forward<P>> {
        newton_forward(self, q, start, &NewtonOptions::default())
    }

    /// The tool pose of forward kinematics ([`Mechanism::forward`], then
    /// [`Mechanism::tool_pose`]): the accuracy engine's call per deviated machine. A
    /// type whose solver finds the pose as a rotation may return it without the round
    /// trip through the pose coordinates' angles (the hexapod does).
    fn forward_tool_pose(&self, q: &SVector<f64, A>, start: &SVector<f64, P>) -> Result<Pose> {
        let f = self.forward(q, start)?;
        self.tool_pose(&f.pose)
    }

    /// A box of tool positions X, Y, Z (mm, base frame; `[min, max]` per axis) that
    /// holds every tool position the machine reaches with the orientation of `x`, when
    /// the type bounds it without searching (a serial arm: the sphere of its links'
    /// reach; struts: the intersection of the spheres their longest strokes allow);
    /// `None` otherwise (then a workspace search grows its box until the reachable
    /// region is inside).
    fn position_bound(&self, _x: &SVector<f64, P>) -> Option<[[f64; 2]; 3]> {
        None
    }

    /// 2-norm condition number of the Jacobian's driven columns at `x`, dimensionally
    /// consistent: the default divides angle columns (mm/rad) by
    /// [`MechanismInfo::characteristic_length`] so every column is in actuator units
    /// per mm.
    fn condition(&self, x: &SVector<f64, P>) -> Result<f64> {
        Ok(crate::linalg::condition_number(&scaled_driven_jacobian(
            self, x,
        )?))
    }

    /// [`Mechanism::condition`] when the actuator positions `q = inverse(x)` are already
    /// known (a workspace sweep has just solved them): mechanisms whose inverse is
    /// iterative (a serial robot's) override it so the sweep does not solve twice.
    fn condition_at(&self, x: &SVector<f64, P>, _q: &SVector<f64, A>) -> Result<f64> {
        self.condition(x)
    }

    /// [`Mechanism::actuator_motion`], then [`Mechanism::check_limits`] with its
    /// positions pushed onto `out`: the motion engine's call per sample. A type may
    /// share work between the two (the hexapod computes the pose's rotation once); the
    /// result must be the same.
    fn actuator_motion_checked(
        &self,
        x: &SVector<f64, P>,
        xd: &SVector<f64, P>,
        xdd: &SVector<f64, P>,
        out: &mut Vec<Violation>,
    ) -> Result<ActuatorMotion<A>> {
        let act = self.actuator_motion(x, xd, xdd)?;
        self.check_limits(x, &act.q, out);
        Ok(act)
    }

    /// The same mechanism with a tool `length` mm longer along its tool axis than its
    /// file's (a program's `G43 H`); `None` when the type does not take its tool from a
    /// program (its tool is set in the machine file).
    fn with_tool_length(&self, _length: f64) -> Option<Result<Self>>
    where
        Self: Sized,
    {
        None
    }

    /// Kernels over many poses with a limit screen ([`BlockKernels`]); `None` (the
    /// default): the engines solve one pose at a time.
    fn block_kernels(&self) -> Option<&dyn BlockKernels<P, A>> {
        None
    }

    /// Condition numbers of many poses at once ([`ConditionBatch`]); `None` (the
    /// default): one [`Mechanism::condition_at`] per pose.
    fn condition_batch(&self) -> Option<&dyn ConditionBatch<P, A>> {
        None
    }

    /// The continuation of a motion across several inverse solutions ([`Follow`]);
    /// `None` (the default): the inverse has one solution.
    fn follower(&self) -> Option<&dyn Follow<P, A>> {
        None
    }

    /// Tool-axis coordinates of a 5-axis machine ([`ToolAxis`]); `None` (the default):
    /// the mechanism takes no tool axis vector and has no rotary-axis singularity.
    fn tool_axis(&self) -> Option<&dyn ToolAxis<P>> {
        None
    }
}

/// Actuator position, velocity and acceleration at one instant (mm or rad, per s, per s^2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActuatorMotion<const A: usize> {
    /// Positions.
    pub q: SVector<f64, A>,
    /// Velocities.
    pub qd: SVector<f64, A>,
    /// Accelerations.
    pub qdd: SVector<f64, A>,
}
