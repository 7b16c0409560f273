//! A block of a run: the sample instants the planner laid out, on their moves, and
//! their computation (the compute stage of [`super::plan`]): poses from the time laws
//! and the geometry, then the mechanism's block kernel or its screen, then the exact
//! `q, q', q''` and the mechanism's own limits of every sample, on one thread (a run
//! hands whole blocks to the rayon pool).

use std::sync::Arc;

use super::plan::BLOCK;
use super::run::{Move, Sample};
use crate::error::Error;
use crate::limits::Violation;
use crate::mechanism::{abilities, ActuatorMotion, Mechanism};

/// Planned instants of a stretch of the run, then their computed samples.
pub(crate) struct Block<M, const P: usize, const A: usize> {
    /// The moves the instants lie on, with the time each starts and its serial number.
    pub moves: Vec<(Move<P>, f64, u64)>,
    /// Per instant: index into `moves`, time from the move's start (s).
    pub plan: Vec<(u32, f64)>,
    /// The mechanism with the program's tool, when it differs from the machine file's.
    pub tooled: Option<Arc<M>>,
    /// A tool length set before the block's first sample (the recorder passes it on).
    pub tool: Option<f64>,
    /// The computed samples, one per instant (up to `failed`); slots beyond the plan
    /// are left over from earlier use of the block.
    pub samples: Vec<Sample<P, A>>,
    /// Violations of the mechanism's own limits: (instant, violation), in order.
    pub violations: Vec<(u32, Violation)>,
    /// The first instant whose computation failed, and why.
    pub failed: Option<(usize, Error)>,
    /// An error after the block's samples (the planner stopped there).
    pub tail: Option<Error>,
}

impl<M, const P: usize, const A: usize> Block<M, P, A> {
    pub(crate) fn new() -> Self {
        Block {
            moves: Vec::new(),
            plan: Vec::with_capacity(BLOCK),
            tooled: None,
            tool: None,
            samples: Vec::new(),
            violations: Vec::new(),
            failed: None,
            tail: None,
        }
    }

    /// Empties the block for reuse (its buffers stay allocated).
    pub(crate) fn clear(&mut self) {
        self.moves.clear();
        self.plan.clear();
        self.tooled = None;
        self.tool = None;
        self.violations.clear();
        self.failed = None;
        self.tail = None;
    }

    /// Whether nothing was planned into it.
    pub(crate) fn is_empty(&self) -> bool {
        self.plan.is_empty() && self.tool.is_none() && self.tail.is_none()
    }
}

impl<M: Mechanism<P, A>, const P: usize, const A: usize> Block<M, P, A> {
    /// Computes every planned instant on `base` (or the block's tooled mechanism), on
    /// the calling thread: a run spreads its blocks, not their samples, over the pool
    /// ([`super::plan::drive`]).
    pub(crate) fn compute(&mut self, base: &M) {
        let m = self.tooled.as_deref().unwrap_or(base);
        let n = self.plan.len();
        let zero = Sample {
            t: 0.0,
            line: None,
            x: nalgebra::SVector::zeros(),
            xd: nalgebra::SVector::zeros(),
            xdd: nalgebra::SVector::zeros(),
            act: ActuatorMotion {
                q: nalgebra::SVector::zeros(),
                qd: nalgebra::SVector::zeros(),
                qdd: nalgebra::SVector::zeros(),
            },
        };
        // Every slot up to n is written below: the buffer only grows, never cleared.
        if self.samples.len() < n {
            self.samples.resize(n, zero);
        }
        self.violations.clear();
        self.failed = None;
        let (violations, failed) =
            compute_range(m, &self.moves, &self.plan, &mut self.samples[..n]);
        self.violations = violations;
        self.failed = failed;
    }
}

/// Computes the instants `plan` of a block into `out` (its samples, by index). Stops
/// at the first failure.
///
/// The poses come first, then the mechanism's block kernel where it has one:
/// [`crate::mechanism::BlockKernels::motion_screened`] (the hexapod's: the motion of eight samples per
/// AVX-512 register, with the limit screen) computes the motion of the samples; those
/// it does not clear of every limit have their limits checked by
/// [`Mechanism::check_limits`] (a program beyond a limit costs the check, not a second
/// motion). Else [`crate::mechanism::BlockKernels::inverse_screened`]'s screen clears poses whose motion
/// is then [`Mechanism::actuator_motion`] with no violation to look for. The others,
/// and every sample of a type with neither, go through
/// [`Mechanism::actuator_motion_checked`]. All give the same motion and violations,
/// bit for bit: the screen only decides which code makes them.
#[allow(clippy::type_complexity)]
fn compute_range<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    moves: &[(Move<P>, f64, u64)],
    plan: &[(u32, f64)],
    out: &mut [Sample<P, A>],
) -> (Vec<(u32, Violation)>, Option<(usize, Error)>) {
    let mut violations = Vec::new();
    let n = out.len();
    ROWS.with_borrow_mut(|rows| {
        rows.grow::<P, A>(n);
        let Rows {
            x,
            q,
            clear,
            computed,
        } = rows;
        let [x0, x1, x2] = x;
        let x = [&mut x0[..P * n], &mut x1[..P * n], &mut x2[..P * n]];
        write_poses(moves, plan, out, x);
        let x = [&x0[..P * n], &x1[..P * n], &x2[..P * n]];
        if clear.len() < n {
            clear.resize(n, false);
            computed.resize(n, false);
        }
        let (clear, computed) = (&mut clear[..n], &mut computed[..n]);
        let [q0, q1, q2] = q;
        let mut q = [&mut q0[..A * n], &mut q1[..A * n], &mut q2[..A * n]];
        kernel_or_screen(m, x, &mut q, clear, computed);
        let failed = actuator_motion(m, out, clear, computed, q, &mut violations);
        (violations, failed)
    })
}

/// Each pose of `plan` (on `moves`) written from registers into its sample of `out`
/// and into the kernel's rows `x` (poses, rates, accelerations), whole rows of `P` at
/// once (not stored, then loaded back for a copy).
#[inline]
fn write_poses<const P: usize, const A: usize>(
    moves: &[(Move<P>, f64, u64)],
    plan: &[(u32, f64)],
    out: &mut [Sample<P, A>],
    x: [&mut [f64]; 3],
) {
    let [x0, x1, x2] = x;
    for ((&(mi, tl), out), ((r0, r1), r2)) in plan.iter().zip(out.iter_mut()).zip(
        x0.chunks_exact_mut(P)
            .zip(x1.chunks_exact_mut(P))
            .zip(x2.chunks_exact_mut(P)),
    ) {
        let (mv, t0, _) = &moves[mi as usize];
        let (s, sd, sdd) = mv.profile.eval(tl);
        let (x, xs, xss) = mv.segment.eval(s);
        let (xd, xdd) = (xs * sd, xss * (sd * sd) + xs * sdd);
        out.t = t0 + tl;
        out.line = mv.line;
        (out.x, out.xd, out.xdd) = (x, xd, xdd);
        r0.copy_from_slice(x.as_slice());
        r1.copy_from_slice(xd.as_slice());
        r2.copy_from_slice(xdd.as_slice());
    }
}

/// The motion kernel on rows `x` into rows `q` where the type has one (`computed`
/// marks its samples, `clear` those clear of every limit), else the inverse's screen
/// (`clear`: poses whose motion needs no limit check), else neither.
#[inline]
fn kernel_or_screen<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: [&[f64]; 3],
    q: &mut [&mut [f64]; 3],
    clear: &mut [bool],
    computed: &mut [bool],
) {
    let [q0, q1, q2] = q;
    let kernel =
        abilities::motion_screened(m, x, [&mut **q0, &mut **q1, &mut **q2], clear, computed);
    if !kernel {
        computed.fill(false);
        if !abilities::inverse_screened(m, x[0], q0, clear, true) {
            clear.fill(false);
        }
    }
}

/// The actuator motion of every sample of `out`: copied from the kernel's rows `q`
/// where it `computed` it (its limits checked unless `clear`), else computed (checked
/// unless `clear`); violations into `violations`. The first sample that fails, and
/// why.
#[inline]
fn actuator_motion<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    out: &mut [Sample<P, A>],
    clear: &[bool],
    computed: &[bool],
    q: [&mut [f64]; 3],
    violations: &mut Vec<(u32, Violation)>,
) -> Option<(usize, Error)> {
    let mut buf = Vec::new();
    let [q0, q1, q2] = q;
    let rows = q0
        .chunks_exact(A)
        .zip(q1.chunks_exact(A))
        .zip(q2.chunks_exact(A));
    for (j, ((s, (&clear, &computed)), ((q0, q1), q2))) in out
        .iter_mut()
        .zip(clear.iter().zip(computed.iter()))
        .zip(rows)
        .enumerate()
    {
        if computed {
            // In place, whole rows: a 144-byte `ActuatorMotion` moved through a
            // `Result` is two `memcpy` calls per sample.
            s.act.q.as_mut_slice().copy_from_slice(q0);
            s.act.qd.as_mut_slice().copy_from_slice(q1);
            s.act.qdd.as_mut_slice().copy_from_slice(q2);
            if !clear {
                // Beyond a limit, or near one: its limits checked with the motion
                // the kernel wrote (not computed a second time).
                buf.clear();
                m.check_limits(&s.x, &s.act.q, &mut buf);
                let k = j as u32;
                violations.extend(buf.drain(..).map(|v| (k, v)));
            }
            continue;
        }
        buf.clear();
        let act = if clear {
            m.actuator_motion(&s.x, &s.xd, &s.xdd)
        } else {
            m.actuator_motion_checked(&s.x, &s.xd, &s.xdd, &mut buf)
        };
        match act {
            Ok(act) => {
                s.act = act;
                let k = j as u32;
                violations.extend(buf.drain(..).map(|v| (k, v)));
            }
            Err(e) => return Some((j, at_sample(e, s.line, s.t))),
        }
    }
    None
}

/// Per-thread rows of [`compute_range`]: the samples' poses, rates and accelerations,
/// the kernel's actuator rows and its masks, kept between calls (a run allocates
/// them once per thread, not per chunk). Borrowed for the whole of one call: nothing
/// inside it may run rayon work on the same thread (a stolen `compute_range` would
/// borrow them again and panic); the mechanism calls it makes are plain per-pose code.
#[derive(Default)]
struct Rows {
    /// Poses, rates, accelerations: `P` per sample.
    x: [Vec<f64>; 3],
    /// Actuator positions, rates, accelerations: `A` per sample.
    q: [Vec<f64>; 3],
    /// Per sample, clear of every limit.
    clear: Vec<bool>,
    /// Per sample, computed by the motion kernel.
    computed: Vec<bool>,
}

impl Rows {
    /// Grows the pose and actuator rows to `n` samples, never shrinking or clearing
    /// them: every row up to `n` is written by [`compute_range`] (x) or, where a kernel
    /// clears or computes it, by the kernel (q).
    fn grow<const P: usize, const A: usize>(&mut self, n: usize) {
        for v in self.x.iter_mut() {
            if v.len() < P * n {
                v.resize(P * n, 0.0);
            }
        }
        for v in self.q.iter_mut() {
            if v.len() < A * n {
                v.resize(A * n, 0.0);
            }
        }
    }
}

thread_local! {
    static ROWS: std::cell::RefCell<Rows> = std::cell::RefCell::new(Rows::default());
}

/// Error `e` of the sample at time `t` of G-code line `line`: a pose out of reach says
/// where in the program it is.
fn at_sample(e: Error, line: Option<u64>, t: f64) -> Error {
    match e {
        Error::NotAttainable { reason } => Error::NotAttainable {
            reason: format!(
                "{}t = {t:.4} s: {reason}",
                line.map(|l| format!("line {l}, ")).unwrap_or_default()
            )
            .into(),
        },
        e => e,
    }
}
