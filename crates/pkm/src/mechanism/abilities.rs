//! Optional abilities of a mechanism: kernels over many poses at once, the continuation
//! of a motion across several inverse solutions, tool-axis coordinates. A type that
//! has one returns it from its capability query on [`Mechanism`]
//! ([`Mechanism::block_kernels`], [`Mechanism::condition_batch`],
//! [`Mechanism::follower`], [`Mechanism::tool_axis`]); the generic engines ask once
//! and fall back to the core methods where the answer is `None`. The free functions
//! here are those engines' calls: each asks the query and takes the fallback itself.

use nalgebra::{SVector, Vector3};

use super::{ActuatorMotion, Mechanism, ToolAxisPoses};
use crate::error::Result;
use crate::limits::{FirstLimit, LimitCode, LimitKind, Violation};

/// Kernels over many poses with a limit screen, and limits as numbers: what a batch of
/// a million poses or the motion engine's blocks need of a type that has them (the
/// hexapod's run eight poses at a time across SIMD lanes, `hexapod/block.rs`).
pub trait BlockKernels<const P: usize, const A: usize>: Send + Sync {
    /// Inverse kinematics of `x` and the first limit it violates, in the order of
    /// [`Mechanism::check_limits`], as a code of the type's own numbering (no name
    /// formatted); `None`: within every limit.
    fn inverse_first_limit(
        &self,
        x: &SVector<f64, P>,
    ) -> Result<(SVector<f64, A>, Option<LimitCode>)>;

    /// The violation a code of [`BlockKernels::inverse_first_limit`] stands for, equal
    /// to the one [`Mechanism::check_limits`] reports.
    fn limit_violation(&self, code: &LimitCode) -> Violation;

    /// Inverse kinematics of many poses with a conservative limit screen: `xs` holds
    /// whole rows of `P` pose coordinates, `qs` receives `A` actuators per row (equal to
    /// [`Mechanism::inverse`]'s to rounding), and `clear[i]` is set where row `i` is
    /// certainly within every limit (with `check`; without it, where the row certainly
    /// has a solution). A row left uncleared is solved again by
    /// [`inverse_first_limit`], which decides it. A row cleared with `check` is one
    /// where [`Mechanism::actuator_motion_checked`] finds no violation either: the
    /// motion engine then calls [`Mechanism::actuator_motion`] alone. Returns `false`
    /// (nothing written) when the slices' lengths disagree.
    fn inverse_screened(&self, xs: &[f64], qs: &mut [f64], clear: &mut [bool], check: bool)
        -> bool;

    /// [`Mechanism::actuator_motion`] of many samples with the limit screen of
    /// [`BlockKernels::inverse_screened`]: `x` holds the samples' poses, rates and
    /// accelerations (each whole rows of `P`, row-major), `q` receives the actuators'
    /// positions, rates and accelerations (`A` per row) of the rows it computes (other
    /// rows may be overwritten and are not to be read): `computed[i]` is set where row
    /// `i`'s motion is written, equal bit for bit to [`Mechanism::actuator_motion`]'s,
    /// and `clear[i]` where it is moreover certainly within every limit. A row computed
    /// but not cleared has its limits checked by [`Mechanism::check_limits`] with the
    /// written positions (what `actuator_motion_checked` finds: a type with this kernel
    /// keeps the two equal); a row not computed is computed again by
    /// `actuator_motion_checked`. Returns `false` (nothing written) when the slices'
    /// lengths disagree.
    fn motion_screened(
        &self,
        x: [&[f64]; 3],
        q: [&mut [f64]; 3],
        clear: &mut [bool],
        computed: &mut [bool],
    ) -> bool;
}

/// Condition numbers of many poses at once (the hexapod's and the 6R arm's eigenvalues
/// across SIMD lanes), the same values as [`Mechanism::condition_at`] one pose at a
/// time.
pub trait ConditionBatch<const P: usize, const A: usize>: Send + Sync {
    /// `out[i]`: the condition number at `xs[i]` with actuator positions `qs[i]` (or
    /// [`Mechanism::condition`] when `qs` is empty), NaN where it fails. Called with
    /// `out` as long as `xs` and `qs` empty or as long.
    fn conditions(&self, xs: &[SVector<f64, P>], qs: &[SVector<f64, A>], out: &mut [f64]);
}

/// The continuation of a motion for a type whose inverse picks one of several
/// solutions (a 6R robot's posture, a revolute joint's whole turns): the motion engine
/// carries the actuator positions on from sample to sample, as a controller moving the
/// machine does, where [`Mechanism::actuator_motion`] alone picks one by a fixed rule.
pub trait Follow<const P: usize, const A: usize>: Send + Sync {
    /// Carries the motion on from the previous sample: `act` is
    /// [`Mechanism::actuator_motion`] at `x` (rates `xd`, `xdd`), `prev` the previous
    /// sample's motion, `dt` seconds before; `act` becomes the solution that continues
    /// `prev`. Returns whether `act.q` changed (the engine then checks its limits
    /// again). Called in sample order, on one thread.
    fn follow(
        &self,
        x: &SVector<f64, P>,
        xd: &SVector<f64, P>,
        xdd: &SVector<f64, P>,
        dt: f64,
        prev: &ActuatorMotion<A>,
        act: &mut ActuatorMotion<A>,
    ) -> bool;
}

/// Tool-axis coordinates: a 5-axis machine's rotary axes for a tool axis vector, and
/// the distance to the direction where one of them is undetermined
/// ([`crate::serial::tcp_axis`]).
pub trait ToolAxis<const P: usize>: Send + Sync {
    /// Pose coordinates putting the tool tip at `tip` with the tool axis along `axis`
    /// (the frame of the pose coordinates; from the tip towards the spindle, any
    /// length): every branch of the rotary axes, the continuity rule's choice (the
    /// branch within the ranges nearest `near`, pose coordinates; home when `None`) and
    /// the angle to the singular direction.
    fn poses_for_tool_axis(
        &self,
        tip: &Vector3<f64>,
        axis: &Vector3<f64>,
        near: Option<&SVector<f64, P>>,
    ) -> Result<ToolAxisPoses<P>>;

    /// Angle (rad, 0 to pi/2) between the tool axis at `x` and the nearest direction in
    /// which one of the rotary axes has an undetermined angle (a trt table's C axis at
    /// B = 0), where a path passing close by makes that axis turn fast; `None` where
    /// the tool axis at `x` cannot be found.
    fn singular_distance(&self, x: &SVector<f64, P>) -> Option<f64>;
}

/// Inverse kinematics of `x` and the first limit it violates in the order of
/// [`Mechanism::check_limits`] (`None`: within every limit): what a batch of poses
/// needs. A type with [`BlockKernels`] answers with a code (turned into the violation
/// by [`limit_violation`] once per distinct limit); any other with the violation
/// itself, from [`Mechanism::inverse`] then [`Mechanism::check_limits`] into `buf`.
pub fn inverse_first_limit<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    buf: &mut Vec<Violation>,
) -> Result<(SVector<f64, A>, Option<FirstLimit>)>
where
    M: Mechanism<P, A> + ?Sized,
{
    if let Some(k) = m.block_kernels() {
        let (q, c) = k.inverse_first_limit(x)?;
        return Ok((q, c.map(FirstLimit::Code)));
    }
    let q = m.inverse(x)?;
    buf.clear();
    m.check_limits(x, &q, buf);
    Ok((q, buf.drain(..).next().map(FirstLimit::Violation)))
}

/// [`inverse_first_limit`] with the first limit as a [`Violation`].
pub fn inverse_first_violation<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    buf: &mut Vec<Violation>,
) -> Result<(SVector<f64, A>, Option<Violation>)>
where
    M: Mechanism<P, A> + ?Sized,
{
    let (q, first) = inverse_first_limit(m, x, buf)?;
    Ok((q, first.map(|f| first_violation(m, f))))
}

/// The violation a [`FirstLimit`] stands for.
pub fn first_violation<M, const P: usize, const A: usize>(m: &M, first: FirstLimit) -> Violation
where
    M: Mechanism<P, A> + ?Sized,
{
    match first {
        FirstLimit::Code(c) => limit_violation(m, &c),
        FirstLimit::Violation(v) => v,
    }
}

/// The violation a code of [`inverse_first_limit`] stands for: the type's own
/// ([`BlockKernels::limit_violation`]), or the limit named by its number for a type
/// without kernels (which never returns codes).
pub fn limit_violation<M, const P: usize, const A: usize>(m: &M, code: &LimitCode) -> Violation
where
    M: Mechanism<P, A> + ?Sized,
{
    match m.block_kernels() {
        Some(k) => k.limit_violation(code),
        None => Violation::new(
            format!("limit {}", code.id),
            LimitKind::ActuatorPosition,
            code.side,
            code.quantity,
            code.value,
            code.bound,
        ),
    }
}

/// [`BlockKernels::inverse_screened`] where the type has it; `false` (nothing written)
/// otherwise.
pub fn inverse_screened<M, const P: usize, const A: usize>(
    m: &M,
    xs: &[f64],
    qs: &mut [f64],
    clear: &mut [bool],
    check: bool,
) -> bool
where
    M: Mechanism<P, A> + ?Sized,
{
    m.block_kernels()
        .is_some_and(|k| k.inverse_screened(xs, qs, clear, check))
}

/// [`BlockKernels::motion_screened`] where the type has it; `false` (nothing written)
/// otherwise.
pub fn motion_screened<M, const P: usize, const A: usize>(
    m: &M,
    x: [&[f64]; 3],
    q: [&mut [f64]; 3],
    clear: &mut [bool],
    computed: &mut [bool],
) -> bool
where
    M: Mechanism<P, A> + ?Sized,
{
    m.block_kernels()
        .is_some_and(|k| k.motion_screened(x, q, clear, computed))
}

/// [`Mechanism::condition_at`] of many poses: `out[i]` at `xs[i]` with actuator
/// positions `qs[i]` (or [`Mechanism::condition`] when `qs` is empty), NaN where it
/// fails; through the type's [`ConditionBatch`] where it has one (the same values).
///
/// # Panics
/// When `out` differs from `xs` in length, or `qs` is neither empty nor as long.
pub fn conditions<M, const P: usize, const A: usize>(
    m: &M,
    xs: &[SVector<f64, P>],
    qs: &[SVector<f64, A>],
    out: &mut [f64],
) where
    M: Mechanism<P, A> + ?Sized,
{
    assert!(
        out.len() == xs.len() && (qs.is_empty() || qs.len() == xs.len()),
        "one condition number per pose"
    );
    if let Some(b) = m.condition_batch() {
        return b.conditions(xs, qs, out);
    }
    for (i, (x, o)) in xs.iter().zip(out.iter_mut()).enumerate() {
        let c = match qs.get(i) {
            Some(q) => m.condition_at(x, q),
            None => m.condition(x),
        };
        *o = c.unwrap_or(f64::NAN);
    }
}
