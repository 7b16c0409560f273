//! Kinematics on a loaded machine beyond one pose: inverse kinematics with the limit
//! check, every inverse solution of a pose (robots), and forward kinematics along a
//! stream of actuator sets (each solved from the last; hexapods keep a tracking solver).

use serde::Serialize;

use crate::dynamic::DynForward;
use crate::error::{Error, Result};
use crate::limits::{LimitKind, Side, Violation};
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
/// Machines whose pose takes a tool axis ([`crate::Mechanism::poses_for_tool_axis`]);
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
                .poses_for_tool_axis(&tip, &axis, near.as_ref())
                .ok_or_else(|| Error::Unsupported {
                    machine: m.name().into(),
                    kind: m.kind().into(),
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

/// Why poses of a batch are not reachable: one entry per distinct cause, shared by
/// every row with that cause (a million rows need no million strings).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchReason {
    /// The violated limit's name (`strut L2 length`), or the solver's message where
    /// the pose has no solution.
    pub text: String,
    /// Family of the limit; `None` where the pose has no solution.
    pub kind: Option<LimitKind>,
    /// Unit of the rows' values and bounds (empty where the pose has no solution).
    pub unit: &'static str,
}

/// Inverse kinematics of many poses at once (a design sweep's, a notebook's array),
/// in columns: one value per pose, no allocation per pose.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchInverse {
    /// Actuators per pose, row-major (`poses x actuators`, internal units); NaN where
    /// the pose has no geometric solution.
    pub actuators: Vec<f64>,
    /// Per pose: a solution within every limit.
    pub reachable: Vec<bool>,
    /// Per pose: index into [`BatchInverse::reasons`] of its first violated limit or
    /// of why it has no solution; -1 when reachable.
    pub reason: Vec<i32>,
    /// Per pose: the value found for its first violated limit (user units); NaN when
    /// reachable or without solution.
    pub value: Vec<f64>,
    /// Per pose: the bound that value crossed (user units); NaN when reachable or
    /// without solution.
    pub bound: Vec<f64>,
    /// The distinct causes the rows point to.
    pub reasons: Vec<BatchReason>,
}

impl BatchInverse {
    /// Number of poses.
    pub fn len(&self) -> usize {
        self.reachable.len()
    }

    /// Whether the batch has no pose.
    pub fn is_empty(&self) -> bool {
        self.reachable.is_empty()
    }

    /// By how much pose `i`'s first violated limit is crossed (user units, positive);
    /// NaN when it is reachable or has no solution.
    pub fn excess(&self, i: usize) -> f64 {
        (self.value[i] - self.bound[i]).abs()
    }

    /// The first violated limit of pose `i`, as [`crate::Violation`] (`None` when it is
    /// reachable or has no solution).
    pub fn violation(&self, i: usize) -> Option<Violation> {
        let r = &self.reasons[usize::try_from(self.reason[i]).ok()?];
        let kind = r.kind?;
        let (value, bound) = (self.value[i], self.bound[i]);
        Some(Violation {
            limit: r.text.clone(),
            kind,
            side: if value < bound { Side::Min } else { Side::Max },
            value,
            bound,
            excess: (value - bound).abs(),
            unit: r.unit,
        })
    }

    /// Why pose `i` is not reachable, as the single-pose call says it (the violated
    /// limit with its value, bound and excess, or the solver's message); `None` when
    /// reachable.
    pub fn message(&self, i: usize) -> Option<String> {
        let r = &self.reasons[usize::try_from(self.reason[i]).ok()?];
        Some(match self.violation(i) {
            Some(v) => v.to_string(),
            None => r.text.clone(),
        })
    }
}

/// Poses per rayon task of [`inverse_batch`] (per-task overhead small against the
/// work: a hexapod solves 4 096 poses in about 20 us).
const BATCH_CHUNK: usize = 4096;

/// The most poses one [`inverse_batch`] call takes (1e8: 4.8 GB of input at six
/// coordinates).
pub const MAX_BATCH: usize = 100_000_000;

/// One chunk's distinct reasons and the map from them to their indices.
#[derive(Default)]
struct Interner {
    reasons: Vec<BatchReason>,
    index: std::collections::HashMap<(String, Option<LimitKind>), i32>,
}

impl Interner {
    fn code(&mut self, text: String, kind: Option<LimitKind>, unit: &'static str) -> i32 {
        let next = self.reasons.len() as i32;
        *self
            .index
            .entry((text, kind))
            .or_insert_with_key(|(text, kind)| {
                self.reasons.push(BatchReason {
                    text: text.clone(),
                    kind: *kind,
                    unit,
                });
                next
            })
    }
}

/// Inverse kinematics with the limit check of every pose in `poses` (row-major,
/// `n x P` pose coordinates in internal units, `P` the machine's coordinate count),
/// on all cores (rayon, chunks of 4 096 poses, fixed-size types per pose). The
/// violated limits are kept as codes into a table of distinct causes
/// ([`BatchInverse::reasons`]) with their values and bounds, so a row's message is
/// only formatted when asked for ([`BatchInverse::message`]).
pub fn inverse_batch(machine: &Machine, poses: &[f64]) -> Result<BatchInverse> {
    struct Job<'a>(&'a [f64]);
    impl Visitor for Job<'_> {
        type Output = Result<BatchInverse>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            use rayon::prelude::*;
            let poses = self.0;
            if !poses.len().is_multiple_of(P) || poses.len() / P > MAX_BATCH {
                return Err(Error::InvalidInput {
                    what: "poses".into(),
                    message: format!(
                        "expected up to {MAX_BATCH:.0e} rows of {P} pose coordinates, got {} \
                         values",
                        poses.len()
                    ),
                });
            }
            let n = poses.len() / P;
            let mut out = BatchInverse {
                actuators: vec![f64::NAN; n * A],
                reachable: vec![false; n],
                reason: vec![-1; n],
                value: vec![f64::NAN; n],
                bound: vec![f64::NAN; n],
                reasons: Vec::new(),
            };
            let tables: Vec<(usize, Vec<BatchReason>)> = poses
                .par_chunks(P * BATCH_CHUNK)
                .zip(out.actuators.par_chunks_mut(A * BATCH_CHUNK))
                .zip(out.reachable.par_chunks_mut(BATCH_CHUNK))
                .zip(out.reason.par_chunks_mut(BATCH_CHUNK))
                .zip(out.value.par_chunks_mut(BATCH_CHUNK))
                .zip(out.bound.par_chunks_mut(BATCH_CHUNK))
                .enumerate()
                .map(|(c, (((((xs, qs), ok), why), value), bound))| {
                    let mut buf = Vec::new();
                    let mut table = Interner::default();
                    for (i, x) in xs.chunks_exact(P).enumerate() {
                        let x = nalgebra::SVector::<f64, P>::from_column_slice(x);
                        match m.inverse(&x) {
                            Ok(q) => {
                                qs[i * A..(i + 1) * A].copy_from_slice(q.as_slice());
                                buf.clear();
                                m.check_limits(&x, &q, &mut buf);
                                match buf.drain(..).next() {
                                    None => ok[i] = true,
                                    Some(v) => {
                                        why[i] = table.code(v.limit, Some(v.kind), v.unit);
                                        value[i] = v.value;
                                        bound[i] = v.bound;
                                    }
                                }
                            }
                            Err(e) => why[i] = table.code(e.to_string(), None, ""),
                        }
                    }
                    (c, table.reasons)
                })
                .collect();
            // One table for the batch: the chunks' codes renumbered into it.
            let mut all = Interner::default();
            for (c, reasons) in tables {
                if reasons.is_empty() {
                    continue;
                }
                let map: Vec<i32> = reasons
                    .into_iter()
                    .map(|r| all.code(r.text, r.kind, r.unit))
                    .collect();
                let rows = c * BATCH_CHUNK..((c + 1) * BATCH_CHUNK).min(n);
                for code in &mut out.reason[rows] {
                    if *code >= 0 {
                        *code = map[*code as usize];
                    }
                }
            }
            out.reasons = all.reasons;
            Ok(out)
        }
    }
    machine.visit(Job(poses))
}

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
    /// Whether the solver is closed-form ([`crate::Mechanism::forward_closed_form`]).
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
