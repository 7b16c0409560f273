//! Kinematics of many poses or actuator sets at once (a design sweep's, a notebook's
//! arrays): columns in, columns out, on all cores (rayon, chunks of
//! [`BATCH_CHUNK`] rows), fixed-size types per row, and why a row failed kept as a
//! code into a table of distinct causes (violated limits by name, solver failures by
//! [`crate::Error::category`]) rather than a message per row.

use serde::Serialize;

use crate::error::Result;
use crate::limits::FirstLimit;
use crate::machine::{Analysable, Machine, Visitor};
use crate::mechanism::{abilities, inverse_continuing};

mod causes;
mod chunks;
pub use causes::{BatchReason, Causes};
use chunks::{chunked, filled, per_chunk, rows, Outputs};

/// Rows per rayon task (per-task overhead small against the work: a hexapod solves
/// 4 096 poses in about 20 us). A batch of at most one chunk runs on the calling
/// thread.
pub const BATCH_CHUNK: usize = 4096;

/// The most rows one batch call takes (1e8: 4.8 GB of input at six coordinates).
pub const MAX_BATCH: usize = 100_000_000;

/// Inverse kinematics of many poses: [`inverse_batch`].
///
/// # Examples
///
/// ```
/// use pkm::analysis::batch::inverse_batch;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// // Two poses, row-major: home, and 400 mm above it (beyond the 1000 mm strokes).
/// let poses = [0.0, 0.0, 508.0, 0.0, 0.0, 0.0, 0.0, 0.0, 908.0, 0.0, 0.0, 0.0];
/// let b = inverse_batch(&machine, &poses).unwrap();
/// assert_eq!((b.len(), b.actuators.len()), (2, 12));
/// assert_eq!(b.reachable, [true, false]);
/// // The second row has a solution, beyond a limit: its causes say which.
/// assert!(b.actuators[6..].iter().all(|l| *l > 1000.0));
/// assert_eq!(b.causes.reason[0], -1);
/// assert!(b.causes.message(1).unwrap().contains("length"));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchInverse {
    /// Actuators per pose, row-major (`poses x actuators`, internal units); NaN where
    /// the pose has no geometric solution.
    pub actuators: Vec<f64>,
    /// Per pose: a solution within every limit.
    pub reachable: Vec<bool>,
    /// Why the others are not reachable.
    pub causes: Causes,
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
}

/// Forward kinematics of many actuator sets: [`forward_batch`].
///
/// # Examples
///
/// See [`forward_batch`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchForward {
    /// Pose coordinates per set, row-major (`sets x coordinates`, internal units); NaN
    /// where the solver failed.
    pub poses: Vec<f64>,
    /// Per set: the solver found a pose.
    pub solved: Vec<bool>,
    /// Per set: a pose found within every limit.
    pub reachable: Vec<bool>,
    /// Per set: solver iterations (0 for a closed form or a failure).
    pub iterations: Vec<u32>,
    /// Per set: largest actuator residual `|IK(pose) - q|` (mm or rad; NaN on failure).
    pub residual: Vec<f64>,
    /// Why the others failed or are not reachable.
    pub causes: Causes,
}

/// Inverse kinematics with the limit check of every pose in `poses` (row-major,
/// `n x P` pose coordinates in internal units, `P` the machine's coordinate count),
/// on all cores. The first violated limit of a pose is kept as a code into a table of
/// distinct causes with its value and bound ([`Causes`]), so a row's message is only
/// formatted when asked for ([`Causes::message`]).
///
/// # Examples
///
/// Row by row the batch equals the single call ([`crate::analysis::kinematics::inverse`]).
///
/// ```
/// use pkm::analysis::batch::inverse_batch;
/// use pkm::analysis::kinematics::inverse;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let poses: Vec<f64> = (0..5)
///     .flat_map(|k| [10.0 * k as f64, 0.0, 508.0 + 100.0 * k as f64, 0.0, 0.0, 0.0])
///     .collect();
/// let b = inverse_batch(&machine, &poses).unwrap();
/// for (i, x) in poses.chunks(6).enumerate() {
///     let one = inverse(&machine, x).unwrap();
///     assert_eq!(&b.actuators[6 * i..6 * i + 6], &one.actuators[..]);
///     assert_eq!(b.reachable[i], one.violations.is_empty());
/// }
/// assert!(b.reachable[0] && !b.reachable[4]);
/// // Not whole rows of six: refused.
/// assert!(inverse_batch(&machine, &poses[..7]).is_err());
/// ```
pub fn inverse_batch(machine: &Machine, poses: &[f64]) -> Result<BatchInverse> {
    inverse_batch_with(machine, poses, true)
}

/// [`inverse_batch`], with the limit check only when `check` is set: without it a
/// pose counts as reachable when it has a geometric solution (the inverse kinematics
/// alone, for callers that check limits of their own).
///
/// # Examples
///
/// ```
/// use pkm::analysis::batch::inverse_batch_with;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// // Two poses, row-major: home, and 400 mm above it (beyond the 1000 mm strokes).
/// let poses = [0.0, 0.0, 508.0, 0.0, 0.0, 0.0, 0.0, 0.0, 908.0, 0.0, 0.0, 0.0];
/// let checked = inverse_batch_with(&machine, &poses, true).unwrap();
/// let unchecked = inverse_batch_with(&machine, &poses, false).unwrap();
/// // The same struts; without the check both poses have a solution.
/// assert_eq!(checked.actuators, unchecked.actuators);
/// assert_eq!(checked.reachable, [true, false]);
/// assert_eq!(unchecked.reachable, [true, true]);
/// ```
pub fn inverse_batch_with(machine: &Machine, poses: &[f64], check: bool) -> Result<BatchInverse> {
    machine.visit(InverseJob {
        poses,
        check,
        continuous: false,
    })
}

/// [`inverse_batch_with`] for the rows of a path: each pose solved from the previous
/// row's solution ([`crate::mechanism::inverse_continuing`]; the first from home), so
/// a robot keeps its posture and the whole turns of its joints, as a controller moving
/// it does, where [`inverse_batch`] takes each row's solution nearest home. Rows
/// depend on each other: solved in order on the calling thread. A row without a
/// solution leaves the next to continue the last row solved. A type whose inverse has
/// one solution ([`crate::Mechanism::follower`] `None`) gives [`inverse_batch_with`]'s
/// rows, solved as those are, on all cores.
///
/// # Examples
///
/// A six-axis robot along a short path keeps its posture: each row equals the solve
/// from the previous row's joints.
///
/// ```
/// use pkm::analysis::batch::inverse_path;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/kr30-dh.toml"
/// ))
/// .unwrap();
/// let m = machine.mechanism();
/// let home = m.home();
/// let poses: Vec<f64> = (0..4)
///     .flat_map(|k| {
///         let mut x = home.clone();
///         x[1] += 20.0 * k as f64; // 20 mm steps along Y
///         x
///     })
///     .collect();
/// let b = inverse_path(&machine, &poses, true).unwrap();
/// assert!(b.reachable.iter().all(|r| *r));
/// let mut last: Option<Vec<f64>> = None;
/// for (i, x) in poses.chunks(6).enumerate() {
///     let q = m.inverse_continuing(x, last.as_deref()).unwrap();
///     assert!(b.actuators[6 * i..6 * i + 6].iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-9));
///     last = Some(q);
/// }
/// ```
pub fn inverse_path(machine: &Machine, poses: &[f64], check: bool) -> Result<BatchInverse> {
    machine.visit(InverseJob {
        poses,
        check,
        continuous: true,
    })
}

/// [`inverse_batch_with`] and [`inverse_path`] on the machine's own type.
struct InverseJob<'a> {
    poses: &'a [f64],
    check: bool,
    continuous: bool,
}

impl Visitor for InverseJob<'_> {
    type Output = Result<BatchInverse>;
    fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
        let n = rows(self.poses, P, "poses")?;
        // Only a type with several solutions per pose has a path to continue.
        let continuous = self.continuous && m.follower().is_some();
        let mut actuators = filled(n * A, f64::NAN);
        let mut reachable = filled(n, false);
        let mut causes = Causes::new(n);
        // The last row solved, along a path (chunks run in order then: no contention).
        let last = std::sync::Mutex::new(None::<nalgebra::SVector<f64, A>>);
        chunked(
            self.poses,
            P,
            Outputs {
                values: &mut actuators,
                width: A,
                flags: &mut reachable,
                records: &mut vec![(); n],
            },
            &mut causes,
            continuous,
            |xs, qs, ok, _, why| {
                let mut buf = Vec::new();
                // Locked along a path only: independent rows run in parallel.
                let mut last = continuous.then(|| last.lock().unwrap_or_else(|e| e.into_inner()));
                // The mechanism's block kernel, where it has one, settles the rows it
                // clears; the rest go through the per-pose path.
                let screened =
                    !continuous && abilities::inverse_screened(m, xs, qs, ok, self.check);
                for (i, x) in xs.chunks_exact(P).enumerate() {
                    if screened && ok[i] {
                        continue;
                    }
                    let x = nalgebra::SVector::<f64, P>::from_column_slice(x);
                    let solved = match last.as_deref_mut() {
                        Some(last) => inverse_continuing(m, &x, last.as_ref()).map(|q| {
                            *last = Some(q);
                            buf.clear();
                            if self.check {
                                m.check_limits(&x, &q, &mut buf);
                            }
                            (q, buf.drain(..).next().map(FirstLimit::Violation))
                        }),
                        None if self.check => abilities::inverse_first_limit(m, &x, &mut buf),
                        None => m.inverse(&x).map(|q| (q, None)),
                    };
                    match solved {
                        Ok((q, v)) => {
                            qs[i * A..(i + 1) * A].copy_from_slice(q.as_slice());
                            match v {
                                None => ok[i] = true,
                                Some(FirstLimit::Violation(v)) => why.violation(i, v),
                                Some(FirstLimit::Code(c)) => {
                                    why.coded(i, &c, || abilities::limit_violation(m, &c))
                                }
                            }
                        }
                        Err(e) => {
                            qs[i * A..(i + 1) * A].fill(f64::NAN);
                            why.error(i, &e)
                        }
                    }
                }
            },
        );
        Ok(BatchInverse {
            actuators,
            reachable,
            causes,
        })
    }
}

/// Forward kinematics with the limit check of every actuator set in `actuators`
/// (row-major, `n x A`, internal units), each solved from `start` (pose coordinates;
/// `None`: home) on all cores: rows are independent (a trajectory whose rows follow
/// each other is better served by [`super::kinematics::ForwardStream`]). Per row the
/// pose, whether the solver found one, its iterations and residual, and the first
/// violated limit or the solver's failure ([`Causes`]).
///
/// # Examples
///
/// ```
/// use pkm::analysis::batch::forward_batch;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// // Every strut 755.6 mm, then every strut 1100 mm (beyond the 1000 mm stroke).
/// let mut q = vec![755.6; 6];
/// q.extend([1100.0; 6]);
/// let f = forward_batch(&machine, &q, None).unwrap();
/// assert_eq!(f.solved, [true, true]);
/// assert_eq!(f.reachable, [true, false]);
/// assert!((f.poses[2] - 508.0).abs() < 0.1); // the platform near home height
/// assert!(f.poses[8] > 908.0); // and much higher
/// assert!(f.residual.iter().all(|r| *r < 1e-9));
/// assert!(f.causes.violation(1).is_some_and(|v| v.bound == 1000.0));
/// ```
pub fn forward_batch(
    machine: &Machine,
    actuators: &[f64],
    start: Option<&[f64]>,
) -> Result<BatchForward> {
    struct Job<'a>(&'a [f64], Option<&'a [f64]>);
    impl Visitor for Job<'_> {
        type Output = Result<BatchForward>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let n = rows(self.0, A, "actuators")?;
            let start = match self.1 {
                Some(x) => crate::dynamic::fixed::<P>("start pose", x)?,
                None => m.info().home(),
            };
            let mut poses = filled(n * P, f64::NAN);
            let mut reachable = vec![false; n];
            // Per row: solved, iterations, residual.
            let mut solver = filled(n, (false, 0u32, f64::NAN));
            let mut causes = Causes::new(n);
            chunked(
                self.0,
                A,
                Outputs {
                    values: &mut poses,
                    width: P,
                    flags: &mut reachable,
                    records: &mut solver,
                },
                &mut causes,
                false,
                |qs, xs, ok, rec, why| {
                    let mut buf = Vec::new();
                    for (i, q) in qs.chunks_exact(A).enumerate() {
                        let q = nalgebra::SVector::<f64, A>::from_column_slice(q);
                        match m.forward(&q, &start) {
                            Ok(f) => {
                                xs[i * P..(i + 1) * P].copy_from_slice(f.pose.as_slice());
                                rec[i] = (true, f.iterations as u32, f.residual);
                                buf.clear();
                                m.check_limits(&f.pose, &q, &mut buf);
                                match buf.drain(..).next() {
                                    None => ok[i] = true,
                                    Some(v) => why.violation(i, v),
                                }
                            }
                            Err(e) => why.error(i, &e),
                        }
                    }
                },
            );
            let solved = solver.iter().map(|r| r.0).collect();
            let iterations = solver.iter().map(|r| r.1).collect();
            let residual = solver.iter().map(|r| r.2).collect();
            Ok(BatchForward {
                poses,
                solved,
                reachable,
                iterations,
                residual,
                causes,
            })
        }
    }
    machine.visit(Job(actuators, start))
}

/// The condition number ([`crate::Mechanism::condition`]: 2-norm of the driven
/// Jacobian, dimensionally consistent) of every pose in `poses` (row-major, `n x P`,
/// internal units) on all cores; NaN where the pose has no inverse solution or the
/// Jacobian cannot be formed, infinity at a singular pose.
///
/// # Examples
///
/// ```
/// use pkm::analysis::batch::condition_batch;
/// use pkm::analysis::kinematics::transmission;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let mut poses = home.clone();
/// poses.extend([0.0, 0.0, 5000.0, 0.0, 0.0, 0.0]); // far out of reach
/// let c = condition_batch(&machine, &poses).unwrap();
/// assert_eq!(c.len(), 2);
/// let at_home = transmission(&machine, &home).unwrap().condition;
/// assert!((c[0] - at_home).abs() < 1e-6 * at_home);
/// assert!(c[1].is_nan() || c[1] > c[0]);
/// ```
pub fn condition_batch(machine: &Machine, poses: &[f64]) -> Result<Vec<f64>> {
    struct Job<'a>(&'a [f64]);
    impl Visitor for Job<'_> {
        type Output = Result<Vec<f64>>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let n = rows(self.0, P, "poses")?;
            let mut out = filled(n, f64::NAN);
            // A chunk's poses in one call (the hexapod's eigenvalues run eight poses
            // across SIMD lanes); a failure is NaN.
            let work = |(xs, c): (&[f64], &mut [f64])| {
                let xs: Vec<nalgebra::SVector<f64, P>> = xs
                    .chunks_exact(P)
                    .map(nalgebra::SVector::<f64, P>::from_column_slice)
                    .collect();
                abilities::conditions(m, &xs, &[], c);
            };
            per_chunk(self.0, P, &mut out, 1, work);
            Ok(out)
        }
    }
    machine.visit(Job(poses))
}

/// The tool pose ([`crate::Mechanism::tool_pose`]: the tool relative to the part, mm)
/// of every pose in `poses` (row-major, `n x P`, internal units) on all cores, as 4 x 4
/// homogeneous matrices, each row-major: `n x 16` values; NaN where the single call
/// fails for the row. For a machine
/// in its own coordinates (a serial machine in joint coordinates) this is its forward
/// kinematics, from its prepared chains.
///
/// # Examples
///
/// ```
/// use pkm::analysis::batch::tool_pose_batch;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let x = [10.0, 20.0, 500.0, 0.0, 0.0, 0.5];
/// let t = tool_pose_batch(&machine, &x).unwrap();
/// assert_eq!(t.len(), 16);
/// // Row-major 4 x 4: the translation in the last column, the bottom row 0 0 0 1.
/// assert_eq!([t[3], t[7], t[11]], [10.0, 20.0, 500.0]);
/// assert_eq!(&t[12..], [0.0, 0.0, 0.0, 1.0]);
/// // A rotation of 0.5 rad about Z.
/// assert!((t[0] - 0.5f64.cos()).abs() < 1e-12 && (t[4] - 0.5f64.sin()).abs() < 1e-12);
/// ```
pub fn tool_pose_batch(machine: &Machine, poses: &[f64]) -> Result<Vec<f64>> {
    struct Job<'a>(&'a [f64]);
    impl Visitor for Job<'_> {
        type Output = Result<Vec<f64>>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let n = rows(self.0, P, "poses")?;
            let mut out = filled(16 * n, f64::NAN);
            let work = |(xs, t): (&[f64], &mut [f64])| {
                for (x, t) in xs.chunks_exact(P).zip(t.chunks_exact_mut(16)) {
                    if let Ok(pose) =
                        m.tool_pose(&nalgebra::SVector::<f64, P>::from_column_slice(x))
                    {
                        let h = pose.to_homogeneous();
                        for (k, v) in t.iter_mut().enumerate() {
                            *v = h[(k / 4, k % 4)];
                        }
                    }
                }
            };
            per_chunk(self.0, P, &mut out, 16, work);
            Ok(out)
        }
    }
    machine.visit(Job(poses))
}
