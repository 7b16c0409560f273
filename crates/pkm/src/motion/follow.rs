//! Carrying the actuator positions on from sample to sample: for a mechanism whose
//! inverse picks one of several solutions ([`Mechanism::follower`]: a 6R robot's
//! posture and the whole turns of its joints), each computed sample is continued from
//! the one before it ([`crate::mechanism::Follow::follow`]), in order, on the recorder's thread,
//! before the sample is recorded.
//!
//! The blocks are computed independently across the pool, each sample by the type's
//! fixed rule (nearest the home joints), and this pass then walks the samples in
//! order. The result depends only on the samples, never on how the run was split
//! across threads. Limits are checked again where the positions changed.

use super::block::Block;
use crate::limits::Violation;
use crate::mechanism::{ActuatorMotion, Mechanism};

/// The last sample carried on: its time and motion.
pub(crate) type Last<const A: usize> = Option<(f64, ActuatorMotion<A>)>;

/// Continues the computed samples of `b` (those before a failure) from `last`, the
/// sample before them (`None` at the run's start: the first keeps the fixed rule's
/// solution), on the block's mechanism (`m`, or the block's tooled one), and leaves
/// `last` at the block's final sample. The violations of the mechanism's own limits
/// of every sample whose positions changed are replaced by those at its new
/// positions, in sample order.
pub(crate) fn follow_block<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    b: &mut Block<M, P, A>,
    last: &mut Last<A>,
) {
    let m = b.tooled.as_deref().unwrap_or(m);
    let Some(f) = m.follower() else {
        return;
    };
    let n = b.failed.as_ref().map_or(b.plan.len(), |f| f.0);
    let mut changed: Vec<u32> = Vec::new();
    for k in 0..n {
        // The sample before: the block's previous one, or the last of the block before.
        let (done, rest) = b.samples.split_at_mut(k);
        let s = &mut rest[0];
        let prev = match done.last() {
            Some(p) => Some((p.t, &p.act)),
            None => last.as_ref().map(|(t, a)| (*t, a)),
        };
        if let Some((t, prev)) = prev {
            if f.follow(&s.x, &s.xd, &s.xdd, s.t - t, prev, &mut s.act) {
                changed.push(k as u32);
            }
        }
    }
    if let Some(s) = b.samples[..n].last() {
        *last = Some((s.t, s.act));
    }
    if changed.is_empty() {
        return;
    }
    // The changed samples' violations again; the others' kept. A stable sort by
    // sample keeps each sample's violations in the order its check found them.
    let mut violations: Vec<(u32, Violation)> = std::mem::take(&mut b.violations)
        .into_iter()
        .filter(|(k, _)| changed.binary_search(k).is_err())
        .collect();
    let mut buf = Vec::new();
    for &k in &changed {
        let s = &b.samples[k as usize];
        buf.clear();
        m.check_limits(&s.x, &s.act.q, &mut buf);
        violations.extend(buf.drain(..).map(|v| (k, v)));
    }
    violations.sort_by_key(|v| v.0);
    b.violations = violations;
}
