//! Kinematics on a loaded machine beyond one pose: inverse kinematics with the limit
//! check, every inverse solution of a pose (robots), and forward kinematics along a
//! stream of actuator sets (each solved from the last; hexapods keep a tracking solver).

use serde::Serialize;

use crate::dynamic::DynForward;
use crate::error::{Error, Result};
use crate::limits::Violation;
use crate::machine::{Analysable, Machine, Visitor};

/// An inverse solution with its limit check.
///
/// # Examples
///
/// ```
/// use pkm::analysis::kinematics::inverse;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let s = inverse(&machine, &machine.mechanism().home()).unwrap();
/// // The pose asked for, one value per actuator, and no violated limit at home.
/// assert_eq!(s.pose, machine.mechanism().home());
/// assert_eq!(s.actuators.len(), 6);
/// assert!(s.violations.is_empty());
/// ```
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
///
/// # Examples
///
/// The LinuxCNC hexapod at home (platform 508 mm above the base, level): every strut
/// 755.56 mm long, as genhexkins says; 400 mm higher the struts leave their stroke.
///
/// ```
/// use pkm::analysis::kinematics::inverse;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let s = inverse(&machine, &[0.0, 0.0, 508.0, 0.0, 0.0, 0.0]).unwrap();
/// assert!(s.actuators.iter().all(|l| (l - 755.56).abs() < 0.01));
/// assert!(s.violations.is_empty());
///
/// let high = inverse(&machine, &[0.0, 0.0, 908.0, 0.0, 0.0, 0.0]).unwrap();
/// assert!(high.actuators.iter().all(|l| *l > 1000.0));
/// assert!(high.violations.iter().any(|v| v.bound == 1000.0 && v.unit == "mm"));
/// ```
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
///
/// # Examples
///
/// ```
/// use pkm::analysis::kinematics::{inverse, InverseStream};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let mut stream = InverseStream::new(&machine);
/// for k in 0..5 {
///     let mut x = home.clone();
///     x[0] += 10.0 * k as f64; // 10 mm steps along X
///     let s = stream.next(&x).unwrap();
///     // A hexapod has one inverse solution: the stream gives `inverse`'s.
///     assert_eq!(s.actuators, inverse(&machine, &x).unwrap().actuators);
/// }
/// ```
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
///
/// # Examples
///
/// ```
/// use pkm::analysis::kinematics::inverse_for_tool_axis;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/mc300.toml"
/// ))
/// .unwrap();
/// let s = inverse_for_tool_axis(&machine, [0.0; 3], [0.0, 0.0, 1.0], None).unwrap();
/// // Along the C axis: B = 0, C is free and held, the axis is singular.
/// assert!(s.singular && s.singular_distance < 1e-12);
/// assert!(s.branches[s.chosen].pose[3].abs() < 1e-12);
/// ```
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
///
/// # Examples
///
/// The MC-300-like machining centre (tool tip X, Y, Z in the part frame, then B, C):
/// a tool tilted 30 degrees from the part's Z axis has two branches, B = +-30 degrees;
/// the one chosen is within the ranges and nearest home.
///
/// ```
/// use pkm::analysis::kinematics::inverse_for_tool_axis;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/mc300.toml"
/// ))
/// .unwrap();
/// let t = 30f64.to_radians();
/// let s = inverse_for_tool_axis(&machine, [10.0, 0.0, 5.0], [t.sin(), 0.0, t.cos()], None)
///     .unwrap();
/// assert_eq!(s.branches.len(), 2);
/// for b in &s.branches {
///     assert!((b.pose[3].abs() - t).abs() < 1e-9); // |B| = 30 deg
///     assert_eq!(&b.pose[..3], &[10.0, 0.0, 5.0]); // the tip asked for
/// }
/// assert!(!s.singular && (s.singular_distance - t).abs() < 1e-9);
/// assert!(s.branches[s.chosen].violations.is_empty());
/// ```
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
///
/// # Examples
///
/// ```
/// use pkm::analysis::kinematics::forward;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// // Every strut 755.6 mm (genhexkins' home is 755.56): the platform near Z = 508 mm.
/// let f = forward(&machine, &[755.6; 6], &home).unwrap();
/// // An iterative solver for a hexapod, converged, well conditioned there.
/// assert!(!f.closed_form && f.residual < 1e-9);
/// assert!(!f.near_singular && f.condition.is_some_and(|c| c < 1e3));
/// assert!((f.pose[2] - 508.0).abs() < 0.1 && f.pose[2] > 508.0);
/// ```
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
///
/// # Examples
///
/// A round trip: the struts of a pose moved off home give that pose back.
///
/// ```
/// use pkm::analysis::kinematics::{forward, inverse};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let x = [20.0, -10.0, 540.0, 0.02, -0.01, 0.03];
/// let q = inverse(&machine, &x).unwrap().actuators;
/// let f = forward(&machine, &q, &home).unwrap();
/// assert!(f.pose.iter().zip(&x).all(|(a, b)| (a - b).abs() < 1e-9));
/// assert!(f.violations.is_empty() && !f.near_singular);
/// ```
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
///
/// # Examples
///
/// A six-axis robot has several postures (shoulder, elbow, wrist) for one tool pose:
/// each gives the same tool pose; the first is the one nearest home.
///
/// ```
/// use pkm::analysis::kinematics::{inverse, inverse_solutions};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/kr30-dh.toml"
/// ))
/// .unwrap();
/// let m = machine.mechanism();
/// let x = m.home();
/// let sols = inverse_solutions(&machine, &x, 16).unwrap();
/// assert!(sols.len() >= 2);
/// let p = m.tool_pose(&x).unwrap();
/// for s in &sols {
///     let f = m.forward(&s.actuators, &x).unwrap();
///     let d = m.tool_pose(&f.pose).unwrap().translation.vector - p.translation.vector;
///     assert!(d.norm() < 1e-6);
/// }
/// let nearest = inverse(&machine, &x).unwrap().actuators;
/// assert!(sols[0].actuators.iter().zip(&nearest).all(|(a, b)| (a - b).abs() < 1e-6));
/// ```
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
///
/// # Examples
///
/// ```
/// use pkm::analysis::kinematics::ForwardStream;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let m = machine.mechanism();
/// let home = m.home();
/// let mut stream = ForwardStream::new(&machine, &home).unwrap();
/// for k in 1..=4 {
///     let mut x = home.clone();
///     x[2] += 5.0 * k as f64; // the platform rising in 5 mm steps
///     let (f, violations) = stream.next(&m.inverse(&x).unwrap()).unwrap();
///     assert!((f.pose[2] - x[2]).abs() < 1e-8 && violations.is_empty());
/// }
/// ```
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
///
/// # Examples
///
/// ```
/// use pkm::analysis::kinematics::transmission;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let t = transmission(&machine, &machine.mechanism().home()).unwrap();
/// // Regular at home: a condition number of at least one, away from singularity.
/// assert!(t.condition >= 1.0 && t.condition < 1e3);
/// assert!(t.distance_to_singularity > 0.0);
/// assert!(t.velocity.is_some_and(|v| v > 0.0));
/// ```
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
