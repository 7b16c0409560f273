//! A chain with one deviation set applied, prepared once for fast repeated evaluation
//! (the robot's and the joint-space machines' poses and Jacobians, the sensitivities
//! along a path).

use nalgebra::{Matrix4, Vector3};

use super::walk::{fast, joint_sines, Column, Frame, Walk, VECTOR_JOINTS};
use super::{
    affine_mul, jacobian_of_axes, link_affine, Affine, Chain, JointKind, LinkDeviation,
    AFFINE_IDENTITY,
};

/// A chain with one deviation set applied, prepared for fast repeated evaluation: the
/// deviated link transforms are computed once (consecutive fixed links multiplied
/// together), stored as 3 x 4 affine blocks, and each joint is applied as the column
/// operation it is (a turn mixes two columns, a slide adds to the translation).
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedChain {
    /// The fixed links before the first joint.
    head: Affine,
    /// Each joint with its positioning deviation and the fixed links after it.
    steps: Vec<(JointKind, f64, Affine)>,
}

/// A joint's axis: unit direction, a point of it, the joint's kind.
pub type JointAxis = (Vector3<f64>, Vector3<f64>, JointKind);

impl PreparedChain {
    /// Prepares `chain` with positioning deviations `dq` and link deviations `dev`
    /// (empty slices: none).
    pub fn new(chain: &Chain, dq: &[f64], dev: &[LinkDeviation]) -> Self {
        let zero = LinkDeviation::default();
        let mut head = AFFINE_IDENTITY;
        let mut steps: Vec<(JointKind, f64, Affine)> = Vec::with_capacity(chain.links.len());
        let mut k = 0;
        for (i, link) in chain.links.iter().enumerate() {
            if let Some(j) = &link.joint {
                steps.push((j.kind, dq.get(k).copied().unwrap_or(0.0), AFFINE_IDENTITY));
                k += 1;
            }
            let l = link_affine(link, dev.get(i).unwrap_or(&zero));
            match steps.last_mut() {
                Some(s) => s.2 = affine_mul(&s.2, &l),
                None => head = affine_mul(&head, &l),
            }
        }
        PreparedChain { head, steps }
    }

    /// The pose and each joint's axis at joint values `q`: its unit direction `z_i`
    /// (the frame's Z before the joint's motion), a point `o_i` of it (that frame's
    /// origin), both in the base frame, and its kind (`N` must be the joint count).
    #[inline]
    pub fn axes<const N: usize>(&self, q: &[f64; N]) -> (Matrix4<f64>, [JointAxis; N]) {
        let mut axes = [(Vector3::zeros(), Vector3::zeros(), JointKind::Prismatic); N];
        let mut k = 0;
        let t = self.walk(q, |z, o, kind| {
            if k < N {
                axes[k] = (z, o, kind);
            }
            k += 1;
        });
        (t, axes)
    }

    /// The pose and the geometric Jacobian (`6 x N`: tool-point velocity over angular
    /// velocity, base frame) at joint values `q`, in one pass: a revolute joint with
    /// axis `z_i` through `o_i` contributes `[z_i x (p - o_i); z_i]`, a prismatic one
    /// `[z_i; 0]` (allocation-free; `N` must be the joint count).
    #[inline]
    pub fn jacobian<const N: usize>(
        &self,
        q: &[f64; N],
    ) -> (Matrix4<f64>, nalgebra::SMatrix<f64, 6, N>) {
        let (t, axes) = self.axes(q);
        let p = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]);
        (t, jacobian_of_axes(&p, &axes))
    }

    /// The chain's pose at joint values `q` (exactly [`Chain::pose`] with the prepared
    /// deviations, up to rounding). `q` must hold one value per joint.
    #[inline]
    pub fn pose(&self, q: &[f64]) -> Matrix4<f64> {
        self.walk(q, |_, _, _| {})
    }

    /// Runs through the chain, calling `at_joint` with the axis and origin of each
    /// joint's frame (before its motion) and its kind; returns the pose. With AVX2
    /// registers where the CPU has them (`walk.rs`: the same bits).
    #[inline(always)]
    pub(super) fn walk<F: FnMut(Vector3<f64>, Vector3<f64>, JointKind)>(
        &self,
        q: &[f64],
        at_joint: F,
    ) -> Matrix4<f64> {
        fast(PreparedWalk {
            chain: self,
            q,
            at_joint,
        })
    }
}

/// [`PreparedChain::walk`] over any column arithmetic.
pub(super) struct PreparedWalk<'a, F> {
    pub(super) chain: &'a PreparedChain,
    pub(super) q: &'a [f64],
    pub(super) at_joint: F,
}

impl<F: FnMut(Vector3<f64>, Vector3<f64>, JointKind)> Walk for PreparedWalk<'_, F> {
    type Out = Matrix4<f64>;

    #[inline(always)]
    fn run<C: Column>(mut self) -> Matrix4<f64> {
        let (steps, q) = (&self.chain.steps, self.q);
        let n = steps.len().min(q.len());
        let (sn, cs) = joint_sines(n, |k| q[k] + steps[k].1);
        let mut t = Frame::<C>::of(&self.chain.head);
        for (k, ((kind, dq, link), qk)) in steps.iter().zip(q).enumerate() {
            (self.at_joint)(t.axis(), t.origin(), *kind);
            let v = qk + dq;
            let sc = match kind {
                JointKind::Revolute if k < VECTOR_JOINTS => (sn[k], cs[k]),
                JointKind::Revolute => v.sin_cos(),
                JointKind::Prismatic => (0.0, 1.0),
            };
            t.joint(*kind, v, sc);
            t.times(link);
        }
        t.matrix()
    }
}
