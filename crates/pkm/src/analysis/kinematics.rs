//! Kinematics on a loaded machine beyond one pose: inverse kinematics with the limit
//! check, every inverse solution of a pose (robots), and forward kinematics along a
//! stream of actuator sets (each solved from the last; hexapods keep a tracking solver).

use serde::Serialize;

use crate::dynamic::DynForward;
use crate::error::{Error, Result};
use crate::limits::Violation;
use crate::machine::{Analysable, Machine, Visitor};

/// An inverse solution with its limit check.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InverseSolution {
    /// Pose coordinates (internal units).
    pub pose: Vec<f64>,
    /// Actuator values (internal units).
    pub actuators: Vec<f64>,
    /// Violated limits (empty: reachable).
    pub violations: Vec<Violation>,
}

/// Inverse kinematics of pose `x` (internal units) with every limit checked.
pub fn inverse(machine: &Machine, x: &[f64]) -> Result<InverseSolution> {
    let m = machine.mechanism();
    let q = m.inverse(x)?;
    let violations = m.check_limits(x, &q)?;
    Ok(InverseSolution {
        pose: x.to_vec(),
        actuators: q,
        violations,
    })
}

/// Inverse kinematics along a stream of poses, each solved from the previous pose's
/// actuators ([`crate::mechanism::inverse_continuing`]): rows of a path, where a robot
/// keeps its posture and the whole turns of its joints as a controller moving it does,
/// where [`inverse`] takes each pose's solution nearest home. Mechanisms with one
/// solution per pose give [`inverse`]'s. [`crate::analysis::batch::inverse_path`] does
/// the same for a whole array of poses.
pub struct InverseStream<'a> {
    machine: &'a Machine,
    last: Option<Vec<f64>>,
}

impl<'a> InverseStream<'a> {
    /// A stream whose first pose is solved from home.
    pub fn new(machine: &'a Machine) -> Self {
        InverseStream {
            machine,
            last: None,
        }
    }

    /// Pose `x` (internal units) solved from the previous solution, its limits
    /// checked; the next pose starts from it. A pose without a solution leaves the
    /// stream where it was.
    pub fn next(&mut self, x: &[f64]) -> Result<InverseSolution> {
        let m = self.machine.mechanism();
        let q = m.inverse_continuing(x, self.last.as_deref())?;
        let violations = m.check_limits(x, &q)?;
        self.last = Some(q.clone());
        Ok(InverseSolution {
            pose: x.to_vec(),
            actuators: q,
            violations,
        })
    }
}

/// The inverse kinematics for a tool tip and a tool axis vector: every branch of the
/// rotary axes with its limit check.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ToolAxisSolution {
    /// Every branch (pose coordinates with the rotary angles, actuators, violations).
    pub branches: Vec<InverseSolution>,
    /// The branch chosen: within the rotary axes' ranges and nearest the previous
    /// angles (home's when none are given).
    pub chosen: usize,
    /// The axis is along the singular direction: the first rotary angle is held.
    pub singular: bool,
    /// Angle between the axis and the singular direction (rad).
    pub singular_distance: f64,
}

/// Inverse kinematics of a tool tip `tip` (mm) and tool axis `axis` (`I, J, K`, any
/// length; from the tip towards the spindle), both in the frame of the pose
/// coordinates (a TCP machine's part frame), with every limit checked per branch;
/// `near`: the previous pose coordinates (internal units) for the continuity rule.
/// Machines whose pose takes a tool axis ([`crate::mechanism::ToolAxis::poses_for_tool_axis`]);
/// the others answer [`Error::Unsupported`].
pub fn inverse_for_tool_axis(
    machine: &Machine,
    tip: [f64; 3],
    axis: [f64; 3],
    near: Option<&[f64]>,
) -> Result<ToolAxisSolution> {
    struct Job<'a>([f64; 3], [f64; 3], Option<&'a [f64]>);
    type Branches = (Vec<Vec<f64>>, usize, bool, f64);
    impl Visitor for Job<'_> {
        type Output = Result<Branches>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let near = match self.2 {
                Some(x) => Some(crate::dynamic::fixed::<P>("previous pose", x)?),
                None => None,
            };
            let tip = nalgebra::Vector3::from(self.0);
            let axis = nalgebra::Vector3::from(self.1);
            let sol = m
                .tool_axis()
                .map(|t| t.poses_for_tool_axis(&tip, &axis, near.as_ref()))
                .ok_or_else(|| Error::Unsupported {
                    machine: m.info().name().into(),
                    kind: m.info().kind().into(),
                    analysis: "a tool axis vector (I, J, K)",
                    reason: "its tool orientation is not set by two rotary axes in \
                             tool-centre-point coordinates"
                        .into(),
                })??;
            Ok((
                sol.branches.iter().map(|x| x.as_slice().to_vec()).collect(),
                sol.chosen,
                sol.singular,
                sol.singular_distance,
            ))
        }
    }
    let (poses, chosen, singular, singular_distance) = machine.visit(Job(tip, axis, near))?;
    Ok(ToolAxisSolution {
        branches: poses
            .iter()
            .map(|x| inverse(machine, x))
            .collect::<Result<Vec<_>>>()?,
        chosen,
        singular,
        singular_distance,
    })
}

pub use super::batch::{inverse_batch, BatchInverse, BatchReason, Causes, MAX_BATCH};

/// Condition number above which a pose is reported as near a singular configuration:
/// the actuators' errors are magnified more than a thousandfold in the pose, and
/// another assembly mode or posture may lie close by.
pub const NEAR_SINGULAR_CONDITION: f64 = 1e3;

/// A forward solution with its limit check and how well the actuators determine it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ForwardSolution {
    /// Pose coordinates (internal units).
    pub pose: Vec<f64>,
    /// Actuator values solved for (internal units).
    pub actuators: Vec<f64>,
    /// Whether the solver is closed-form ([`crate::mechanism::MechanismInfo::forward_closed_form`]).
    pub closed_form: bool,
    /// Iterations of an iterative solver (0 for a closed form).
    pub iterations: usize,
    /// Largest actuator residual `|IK(pose) - q|` (mm or rad).
    pub residual: f64,
    /// Condition number at the pose ([`crate::Mechanism::condition`]); `None` where it
    /// is infinite or cannot be computed (a singular pose).
    pub condition: Option<f64>,
    /// The condition is above [`NEAR_SINGULAR_CONDITION`], or there is none.
    pub near_singular: bool,
    /// Violated limits (empty: reachable).
    pub violations: Vec<Violation>,
}

/// Forward kinematics of actuators `q` from pose `start` (internal units), with every
/// limit checked and the conditioning of the solution: near a forward singularity (the
/// P3RP head near its configuration Q) a pose is found but small actuator errors move
/// it a lot, which [`ForwardSolution::near_singular`] says.
pub fn forward(machine: &Machine, q: &[f64], start: &[f64]) -> Result<ForwardSolution> {
    let m = machine.mechanism();
    let f = m.forward(q, start)?;
    let violations = m.check_limits(&f.pose, q)?;
    let condition = m.condition(&f.pose).ok().filter(|c| c.is_finite());
    Ok(ForwardSolution {
        closed_form: m.forward_closed_form(),
        iterations: f.iterations,
        residual: f.residual,
        near_singular: condition.is_none_or(|c| c > NEAR_SINGULAR_CONDITION),
        condition,
        violations,
        actuators: q.to_vec(),
        pose: f.pose,
    })
}

/// Every inverse solution found for pose `x` ([`crate::machine::Analysis::InverseSolutions`]: six-axis
/// robots, Newton from home and `starts - 1` spread starts, deduplicated, nearest home
/// first), each with its limit status.
pub fn inverse_solutions(
    machine: &Machine,
    x: &[f64],
    starts: usize,
) -> Result<Vec<InverseSolution>> {
    let arm = machine.robot_arm()?;
    let xv = crate::dynamic::fixed::<6>("pose", x)?;
    let m = machine.mechanism();
    arm.inverse_solutions(&xv, starts)
        .into_iter()
        .map(|q| {
            let violations = m.check_limits(x, q.as_slice())?;
            Ok(InverseSolution {
                pose: x.to_vec(),
                actuators: q.as_slice().to_vec(),
                violations,
            })
        })
        .collect()
}

/// Forward kinematics along a stream of actuator sets, each solved from the previous
/// solution (a machine moving through its states). Hexapods use the tracking solver
/// ([`crate::hexapod::FkTracker`]: predicted start, kept factorisation).
pub struct ForwardStream<'a> {
    machine: &'a Machine,
    last: Vec<f64>,
    tracker: Option<(&'a crate::hexapod::Hexapod, crate::hexapod::FkTracker)>,
}

impl<'a> ForwardStream<'a> {
    /// A stream starting at pose `start` (internal units).
    pub fn new(machine: &'a Machine, start: &[f64]) -> Result<Self> {
        let tracker = match machine.tracked_hexapod() {
            Some(h) => Some((
                h,
                crate::hexapod::FkTracker::new(
                    &crate::dynamic::fixed::<6>("start pose", start)?,
                    Default::default(),
                ),
            )),
            None => None,
        };
        Ok(ForwardStream {
            machine,
            last: start.to_vec(),
            tracker,
        })
    }

    /// The pose of actuator set `q` (internal units) and the limits it violates; the
    /// next set starts from it. A failed solve leaves the stream where it was.
    pub fn next(&mut self, q: &[f64]) -> Result<(DynForward, Vec<Violation>)> {
        let m = self.machine.mechanism();
        let f = match self.tracker.as_mut() {
            Some((h, tr)) => {
                let qv = crate::dynamic::fixed::<6>("actuators", q)?;
                let rep = tr.track(h, &qv)?;
                let a = crate::Convention::Rpy.from_matrix(&rep.rotation);
                let p = rep.position;
                DynForward {
                    pose: vec![p.x, p.y, p.z, a[0], a[1], a[2]],
                    iterations: rep.iterations,
                    residual: rep.residual,
                }
            }
            None => m.forward(q, &self.last)?,
        };
        let v = m.check_limits(&f.pose, q)?;
        self.last.clone_from(&f.pose);
        Ok((f, v))
    }
}

/// Velocity and force transmission and the distance to singularity at pose `x`
/// ([`crate::transmission::transmission`]).
pub fn transmission(machine: &Machine, x: &[f64]) -> Result<crate::transmission::Transmission> {
    struct Job<'a>(&'a [f64]);
    impl crate::machine::Visitor for Job<'_> {
        type Output = Result<crate::transmission::Transmission>;
        fn visit<M: crate::machine::Analysable<P, A>, const P: usize, const A: usize>(
            self,
            m: &M,
        ) -> Self::Output {
            let x = crate::dynamic::fixed::<P>("pose", self.0)?;
            crate::transmission::transmission(m, &x)
        }
    }
    machine.visit(Job(x))
}
