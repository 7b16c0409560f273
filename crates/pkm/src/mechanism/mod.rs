//! The mechanism abstraction every analysis is written against.
//!
//! A mechanism maps its *pose coordinates* `x` (what the machine controls: X, Y, Z, A,
//! B, C of the tool for a spatial machine; `z, theta` for a planar head; ...) to its
//! *actuator coordinates* `q` (strut lengths, slider positions, joint angles) and back.
//!
//! * `P` is the number of pose coordinates, `A` the number of actuators. A mechanism
//!   with fewer actuators than pose coordinates *holds* the others: the translational
//!   tripod, for instance, takes X, Y, Z, A, B, C but its three struts only move X, Y, Z;
//!   A, B, C stay where the mechanism holds them. [`Mechanism::driven`] says which
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

mod skeleton;
mod solve;

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
/// ([`Mechanism::poses_for_tool_axis`]).
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

/// A mechanism with `P` pose coordinates and `A` actuators.
pub trait Mechanism<const P: usize, const A: usize>: Send + Sync {
    /// Machine name from its file.
    fn name(&self) -> &str;

    /// Machine type (`tripod/translational`, ...).
    fn kind(&self) -> &'static str;

    /// The pose coordinates, in order.
    fn coordinates(&self) -> &[Coordinate; P];

    /// The actuators, in order.
    fn actuators(&self) -> &[Actuator; A];

    /// Indices of the pose coordinates driven by the actuators. The others are held by
    /// the mechanism: forward kinematics takes them from its starting pose.
    fn driven(&self) -> [usize; A];

    /// How the pose coordinates relate to a full tool pose.
    fn pose_space(&self) -> PoseSpace;

    /// The home pose from the machine file.
    fn home(&self) -> SVector<f64, P>;

    /// Inverse kinematics: actuator coordinates for pose `x`. Fails only when no
    /// geometric solution exists; stroke and other limits are checked separately by
    /// [`Mechanism::check_limits`].
    fn inverse(&self, x: &SVector<f64, P>) -> Result<SVector<f64, A>>;

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

    /// A box of tool positions X, Y, Z (mm, base frame; `[min, max]` per axis) that
    /// holds every tool position the machine reaches with the orientation of `x`, when
    /// the type bounds it without searching (a serial arm: the sphere of its links'
    /// reach; struts: the intersection of the spheres their longest strokes allow);
    /// `None` otherwise (then a workspace search grows its box until the reachable
    /// region is inside).
    fn position_bound(&self, _x: &SVector<f64, P>) -> Option<[[f64; 2]; 3]> {
        None
    }

    /// Inverse Jacobian `dq/dx` at `x` (`A x P`).
    fn jacobian(&self, x: &SVector<f64, P>) -> Result<SMatrix<f64, A, P>>;

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

    /// Whether the mechanism leaves the tool free to spin about its own axis (a
    /// pentapod's ring joints turn): a rotation about the tool axis is then no error of
    /// the machine, and the accuracy engine keeps only the tilt of the tool axis
    /// ([`crate::accuracy::PoseError::without_spin`]). Default: no.
    fn free_spin(&self) -> bool {
        false
    }

    /// How [`Mechanism::inverse`] solves, in words (`pkm check` prints it): `closed
    /// form`, the default (every type's inverse but a robot's of general geometry), or
    /// the robot's method.
    fn inverse_method(&self) -> &'static str {
        "closed form"
    }

    /// Whether [`Mechanism::forward`] is a closed-form solution: then its
    /// [`Forward::iterations`] is 0 by construction, not a count of iterations.
    fn forward_closed_form(&self) -> bool {
        false
    }

    /// The full tool pose (tool tip position and tool frame) at `x`.
    fn tool_pose(&self, x: &SVector<f64, P>) -> Result<Pose>;

    /// Pose coordinates of a full tool pose. `orientation_given` says whether the
    /// orientation part was given by the user (and must then be consistent with what
    /// the mechanism can produce) or may be chosen by the mechanism.
    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<SVector<f64, P>>;

    /// Pushes every violated limit at pose `x` with actuators `q` onto `out`.
    fn check_limits(&self, x: &SVector<f64, P>, q: &SVector<f64, A>, out: &mut Vec<Violation>);

    /// Inverse kinematics of `x` and the first limit it violates in the order of
    /// [`Mechanism::check_limits`] (`None`: within every limit): what a batch of poses
    /// needs. Equal to [`Mechanism::inverse`] then the first of
    /// [`Mechanism::check_limits`]; a type may share work between the two and stop at
    /// the first violation.
    fn inverse_first_violation(
        &self,
        x: &SVector<f64, P>,
        buf: &mut Vec<Violation>,
    ) -> Result<(SVector<f64, A>, Option<Violation>)> {
        let q = self.inverse(x)?;
        buf.clear();
        self.check_limits(x, &q, buf);
        Ok((q, buf.drain(..).next()))
    }

    /// [`Mechanism::inverse_first_violation`] for batches: a type that numbers its
    /// limits returns the first violated one as a [`crate::limits::LimitCode`] (no name
    /// formatted per row), turned into the violation by [`Mechanism::limit_violation`]
    /// once per distinct limit; the default returns the violation itself.
    fn inverse_first_limit(
        &self,
        x: &SVector<f64, P>,
        buf: &mut Vec<Violation>,
    ) -> Result<(SVector<f64, A>, Option<crate::limits::FirstLimit>)> {
        let (q, v) = self.inverse_first_violation(x, buf)?;
        Ok((q, v.map(crate::limits::FirstLimit::Violation)))
    }

    /// Inverse kinematics of many poses with a conservative limit screen, for batches:
    /// `xs` holds whole rows of `P` pose coordinates, `qs` receives `A` actuators per
    /// row (equal to [`Mechanism::inverse`]'s to rounding), and `clear[i]` is set where
    /// row `i` is certainly within every limit (with `check`; without it, where the
    /// row certainly has a solution). A row left uncleared is solved again by
    /// [`Mechanism::inverse_first_limit`], which decides it. A row cleared with
    /// `check` is one where [`Mechanism::actuator_motion_checked`] finds no violation
    /// either: the motion engine then calls [`Mechanism::actuator_motion`] alone.
    /// Returns `false` (nothing written) for a type without such a kernel, the
    /// default; the hexapod's runs eight poses at a time across SIMD lanes.
    fn inverse_screened(
        &self,
        xs: &[f64],
        qs: &mut [f64],
        clear: &mut [bool],
        check: bool,
    ) -> bool {
        let _ = (xs, qs, clear, check);
        false
    }

    /// [`Mechanism::actuator_motion`] of many samples with the limit screen of
    /// [`Mechanism::inverse_screened`], for the motion engine: `x` holds the samples'
    /// poses, rates and accelerations (each whole rows of `P`, row-major), `q` receives
    /// the actuators' positions, rates and accelerations (`A` per row) of the rows it
    /// computes (other rows may be overwritten and are not to be read):
    /// `computed[i]` is set where row `i`'s motion is written, equal bit for bit to
    /// [`Mechanism::actuator_motion`]'s, and `clear[i]` where it is moreover certainly
    /// within every limit ([`Mechanism::actuator_motion_checked`] finds no
    /// violation). A row computed but not cleared has its limits checked by
    /// [`Mechanism::check_limits`] with the written positions (what
    /// `actuator_motion_checked` finds: a type with this kernel must keep the two
    /// equal); a row not computed is computed again by `actuator_motion_checked`.
    /// Returns `false` (nothing written) for a type without such a kernel, the
    /// default; the hexapod's runs eight samples at a time across SIMD lanes.
    fn motion_screened(
        &self,
        x: [&[f64]; 3],
        q: [&mut [f64]; 3],
        clear: &mut [bool],
        computed: &mut [bool],
    ) -> bool {
        let _ = (x, q, clear, computed);
        false
    }

    /// The violation a code of [`Mechanism::inverse_first_limit`] stands for (equal to
    /// the one [`Mechanism::check_limits`] reports). The default, for types that never
    /// return codes, names the limit by its number.
    fn limit_violation(&self, code: &crate::limits::LimitCode) -> Violation {
        Violation::new(
            format!("limit {}", code.id),
            crate::limits::LimitKind::ActuatorPosition,
            code.side,
            code.quantity,
            code.value,
            code.bound,
        )
    }

    /// Points and links of the mechanism at `x`, for drawings and joint reports.
    fn skeleton(&self, x: &SVector<f64, P>) -> Result<Skeleton>;

    /// 2-norm condition number of the Jacobian's driven columns at `x`, dimensionally
    /// consistent: the default divides angle columns (mm/rad) by
    /// [`Mechanism::characteristic_length`] so every column is in actuator units per mm.
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

    /// [`Mechanism::condition_at`] of many poses: `out[i]` at `xs[i]` with actuator
    /// positions `qs[i]` (or [`Mechanism::condition`] when `qs` is empty), NaN where it
    /// fails. Types with a kernel for several poses at once (the hexapod's eigenvalues
    /// across SIMD lanes) override it with the same values as one pose at a time.
    ///
    /// # Panics
    /// When `out` differs from `xs` in length, or `qs` is neither empty nor as long.
    fn conditions(&self, xs: &[SVector<f64, P>], qs: &[SVector<f64, A>], out: &mut [f64]) {
        assert!(
            out.len() == xs.len() && (qs.is_empty() || qs.len() == xs.len()),
            "one condition number per pose"
        );
        for (i, (x, o)) in xs.iter().zip(out.iter_mut()).enumerate() {
            let c = match qs.get(i) {
                Some(q) => self.condition_at(x, q),
                None => self.condition(x),
            };
            *o = c.unwrap_or(f64::NAN);
        }
    }

    /// Pose coordinates putting the tool tip at `tip` with the tool axis along `axis`
    /// (the frame of the pose coordinates; from the tip towards the spindle, any length):
    /// every branch of the rotary axes, the continuity rule's choice (the branch within
    /// the ranges nearest `near`, pose coordinates; home when `None`) and the angle to
    /// the singular direction. `None` for mechanisms that take no tool axis vector
    /// (the default; a 5-axis TCP machine takes one, [`crate::serial::tcp_axis`]).
    fn poses_for_tool_axis(
        &self,
        _tip: &nalgebra::Vector3<f64>,
        _axis: &nalgebra::Vector3<f64>,
        _near: Option<&SVector<f64, P>>,
    ) -> Option<Result<ToolAxisPoses<P>>> {
        None
    }

    /// Angle (rad, 0 to pi/2) between the tool axis at `x` and the nearest direction in
    /// which one of the mechanism's rotary axes has an undetermined angle: a 5-axis
    /// machine's tool axis along its rotary axis nearest the part (a trt table's C axis
    /// at B = 0), where a path passing close by makes that axis turn fast. `None` for
    /// mechanisms without such a direction (the default).
    fn singular_distance(&self, _x: &SVector<f64, P>) -> Option<f64> {
        None
    }

    /// Length (mm) that scales rotations against translations in conditioning: a
    /// rotation of 1 rad counts as a displacement of this many mm. Default 1 mm.
    fn characteristic_length(&self) -> f64 {
        1.0
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

    /// Whether a motion carries the actuator positions on from sample to sample with
    /// [`Mechanism::follow`]: a type whose inverse picks one of several solutions (a
    /// 6R robot's posture, a revolute joint's whole turns) says `true`. Default `false`:
    /// the inverse has one solution.
    fn follows(&self) -> bool {
        false
    }

    /// Carries the motion on from the previous sample: `act` is
    /// [`Mechanism::actuator_motion`] at `x` (rates `xd`, `xdd`), `prev` the previous
    /// sample's motion, `dt` seconds before. A type with several inverse solutions
    /// returns in `act` the one that continues `prev`, as a controller moving the
    /// machine does, where `actuator_motion` alone picks one by a fixed rule (nearest
    /// the home joints). Returns whether `act.q` changed (the motion engine then checks
    /// its limits again). Called in sample order, on one thread. Default: unchanged.
    fn follow(
        &self,
        _x: &SVector<f64, P>,
        _xd: &SVector<f64, P>,
        _xdd: &SVector<f64, P>,
        _dt: f64,
        _prev: &ActuatorMotion<A>,
        _act: &mut ActuatorMotion<A>,
    ) -> bool {
        false
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
