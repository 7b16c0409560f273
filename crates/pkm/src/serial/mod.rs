//! Serial chains with primary deviations (seed 003, Krakhmalev): the accuracy model of
//! machine tools and robots built from open chains of one-DOF joints.
//!
//! Each link `i` carries two frames, `S_i` at its input joint and `S_i*` at its output.
//! The link's geometry is the homogeneous transform `A_(i,i*)` from `S_i*` to `S_i`
//! (seed 003 eq. 1): a block of direction cosines `cos(a_i, b_i*)` and the origin of
//! `S_i*` in `S_i`. With primary deviations (eq. 2) the block becomes
//! `cos(phi_ab + alpha_ab)` and the translation `l + delta`. The joint between
//! `S_(i-1)*` and `S_i` turns about or slides along their common Z axis by `q_i + dq_i`
//! (eq. 4). A chain's pose is `A_(0,0*) prod_i A_((i-1)*,i)(q_i + dq_i) A_(i,i*)`,
//! its fixed link 0 (the bed or the chain's mount) first; a machine with a tool chain
//! and a workpiece chain is judged by the tool pose relative to the workpiece.
//!
//! Deviations are evaluated exactly, as the paper's matrices: a set of angular
//! deviations that does not keep the block orthonormal gives a block that is not a
//! rotation. [`completion::complete`] derives the six dependent angular deviations
//! from three measured ones (eq. 3) so that it does.

pub mod accuracy;
pub mod completion;
pub mod ik;
pub mod mechanism;
pub mod tolerance;

use nalgebra::{Matrix3, Matrix4, Vector3};

/// A serial machine loaded from a file: the mechanism and its tolerances.
#[derive(Debug, Clone, PartialEq)]
pub struct SerialModel {
    /// The machine as a mechanism (joint count fixed at load time).
    pub mechanism: mechanism::SerialAny,
    /// Tolerances of primary deviations from the file (`[[tolerance]]`).
    pub tolerances: Vec<tolerance::Tolerance>,
}
use serde::Serialize;

use crate::error::{Error, Result};
use crate::limits::Range;

/// Kind of a one-DOF joint; its axis is the Z axis of the frames it joins.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum JointKind {
    /// Turns about Z by `q` (rad); `b_i = 1` in eq. 4.
    Revolute,
    /// Slides along Z by `q` (mm); `b_i = 0`.
    Prismatic,
}

/// The joint at a link's input.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Joint {
    /// Axis name (`X`, `B`, `A1`).
    pub name: String,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Travel (mm or rad).
    pub range: Range,
}

/// One link: its input joint (none for a fixed link) and its nominal geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Name (`1 slide`, `bed`).
    pub name: String,
    /// The joint between the previous link's `S*` and this link's `S`.
    pub joint: Option<Joint>,
    /// Origin of `S_i*` in `S_i` (mm): `(l_x, l_y, l_z)`.
    pub translation: Vector3<f64>,
    /// Nominal direction cosines `cos(a_i, b_i*)` (row: axis of `S_i`, column: axis of
    /// `S_i*`); a rotation matrix.
    pub rotation: Matrix3<f64>,
}

impl Link {
    /// Nominal angles `phi_ab = acos(cos(a_i, b_i*))` (rad).
    pub fn angles(&self) -> Matrix3<f64> {
        self.rotation.map(|c| c.clamp(-1.0, 1.0).acos())
    }
}

/// Primary deviations of one link (eq. 2): linear `delta` (mm) added to the
/// translation, angular `alpha` (rad) added to the nine angles between the axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LinkDeviation {
    /// `(delta_x, delta_y, delta_z)`.
    pub delta: Vector3<f64>,
    /// `alpha_ab` (row: axis of `S_i`, column: axis of `S_i*`).
    pub alpha: Matrix3<f64>,
}

/// An open chain of links.
#[derive(Debug, Clone, PartialEq)]
pub struct Chain {
    /// Name (`tool`, `workpiece`).
    pub name: String,
    /// Links in order from the fixed one (index 0, no joint).
    pub links: Vec<Link>,
}

/// `A_(i,i*)` with deviations (eq. 2).
#[inline]
pub fn link_transform(link: &Link, dev: &LinkDeviation) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    if dev.alpha == Matrix3::zeros() {
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&link.rotation);
    } else {
        let phi = link.angles();
        for r in 0..3 {
            for c in 0..3 {
                m[(r, c)] = (phi[(r, c)] + dev.alpha[(r, c)]).cos();
            }
        }
    }
    let t = link.translation + dev.delta;
    m[(0, 3)] = t.x;
    m[(1, 3)] = t.y;
    m[(2, 3)] = t.z;
    m
}

/// `A_((i-1)*,i)(q)` (eq. 4): a turn about Z by `q` (revolute) or a slide along Z.
#[inline]
pub fn joint_transform(kind: JointKind, q: f64) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    match kind {
        JointKind::Revolute => {
            let (s, c) = q.sin_cos();
            m[(0, 0)] = c;
            m[(0, 1)] = -s;
            m[(1, 0)] = s;
            m[(1, 1)] = c;
        }
        JointKind::Prismatic => m[(2, 3)] = q,
    }
    m
}

impl Chain {
    /// The chain's joints in order.
    pub fn joints(&self) -> impl Iterator<Item = &Joint> {
        self.links.iter().filter_map(|l| l.joint.as_ref())
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.joints().count()
    }

    /// The pose of the last link's `S*` in the frame of link 0's `S` for joint values
    /// `q` (one per joint), positioning deviations `dq` (one per joint) and link
    /// deviations `dev` (one per link); empty slices mean none.
    pub fn pose(&self, q: &[f64], dq: &[f64], dev: &[LinkDeviation]) -> Result<Matrix4<f64>> {
        let n = self.dof();
        if q.len() != n || !(dq.is_empty() || dq.len() == n) {
            return Err(Error::InvalidInput {
                what: format!("chain `{}`", self.name),
                message: format!(
                    "expected {n} joint values (and as many positioning deviations), got {} and {}",
                    q.len(),
                    dq.len()
                ),
            });
        }
        if !(dev.is_empty() || dev.len() == self.links.len()) {
            return Err(Error::InvalidInput {
                what: format!("chain `{}`", self.name),
                message: format!(
                    "expected {} link deviations, got {}",
                    self.links.len(),
                    dev.len()
                ),
            });
        }
        let zero = LinkDeviation::default();
        let mut t = Matrix4::identity();
        let mut k = 0;
        for (i, link) in self.links.iter().enumerate() {
            if let Some(j) = &link.joint {
                let d = dq.get(k).copied().unwrap_or(0.0);
                t *= joint_transform(j.kind, q[k] + d);
                k += 1;
            }
            t *= link_transform(link, dev.get(i).unwrap_or(&zero));
        }
        Ok(t)
    }
}

/// A chain with one deviation set applied, prepared for fast repeated evaluation: the
/// deviated link transforms are computed once, and each joint is applied as the
/// column operation it is (a turn mixes two columns, a slide adds to the translation).
#[derive(Debug, Clone, PartialEq)]
pub struct PreparedChain {
    steps: Vec<Step>,
}

#[derive(Debug, Clone, PartialEq)]
enum Step {
    Joint(JointKind, f64),
    Link(Matrix4<f64>),
}

impl PreparedChain {
    /// Prepares `chain` with positioning deviations `dq` and link deviations `dev`
    /// (empty slices: none).
    pub fn new(chain: &Chain, dq: &[f64], dev: &[LinkDeviation]) -> Self {
        let zero = LinkDeviation::default();
        let mut steps = Vec::with_capacity(2 * chain.links.len());
        let mut k = 0;
        for (i, link) in chain.links.iter().enumerate() {
            if let Some(j) = &link.joint {
                steps.push(Step::Joint(j.kind, dq.get(k).copied().unwrap_or(0.0)));
                k += 1;
            }
            steps.push(Step::Link(link_transform(
                link,
                dev.get(i).unwrap_or(&zero),
            )));
        }
        PreparedChain { steps }
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
        let mut axes = [(Vector3::zeros(), Vector3::zeros(), JointKind::Prismatic); N];
        let mut k = 0;
        let t = self.walk(q, |t: &Matrix4<f64>, kind| {
            if k < N {
                axes[k] = (
                    Vector3::new(t[(0, 2)], t[(1, 2)], t[(2, 2)]),
                    Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]),
                    kind,
                );
            }
            k += 1;
        });
        let p = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]);
        let mut j = nalgebra::SMatrix::<f64, 6, N>::zeros();
        for (c, (z, o, kind)) in axes.iter().enumerate() {
            let (v, w) = match kind {
                JointKind::Revolute => (z.cross(&(p - o)), *z),
                JointKind::Prismatic => (*z, Vector3::zeros()),
            };
            for r in 0..3 {
                j[(r, c)] = v[r];
                j[(r + 3, c)] = w[r];
            }
        }
        (t, j)
    }

    /// The chain's pose at joint values `q` (exactly [`Chain::pose`] with the prepared
    /// deviations). `q` must hold one value per joint.
    #[inline]
    pub fn pose(&self, q: &[f64]) -> Matrix4<f64> {
        self.walk(q, |_, _| {})
    }

    /// Runs through the chain, calling `at_joint` with the frame of each joint (before
    /// its motion) and its kind.
    #[inline]
    fn walk<F: FnMut(&Matrix4<f64>, JointKind)>(&self, q: &[f64], mut at_joint: F) -> Matrix4<f64> {
        // The joints' sines and cosines first: independent of each other and of the
        // matrix products, they overlap instead of sitting on the products' chain.
        const TRIG: [(f64, f64); 12] = [(0.0, 1.0); 12];
        let mut trig = TRIG;
        let mut j = 0;
        for s in &self.steps {
            if let Step::Joint(kind, dq) = s {
                if j < TRIG.len() && *kind == JointKind::Revolute {
                    trig[j] = crate::trig::sin_cos(q[j] + dq);
                }
                j += 1;
            }
        }
        let mut t = Matrix4::identity();
        let mut k = 0;
        for s in &self.steps {
            match s {
                Step::Joint(kind, dq) => {
                    at_joint(&t, *kind);
                    let v = q[k] + dq;
                    k += 1;
                    match kind {
                        JointKind::Revolute => {
                            let (sn, cs) = if k <= TRIG.len() {
                                trig[k - 1]
                            } else {
                                v.sin_cos()
                            };
                            for r in 0..3 {
                                let (a, b) = (t[(r, 0)], t[(r, 1)]);
                                t[(r, 0)] = cs * a + sn * b;
                                t[(r, 1)] = cs * b - sn * a;
                            }
                        }
                        JointKind::Prismatic => {
                            for r in 0..3 {
                                t[(r, 3)] += v * t[(r, 2)];
                            }
                        }
                    }
                }
                Step::Link(m) => {
                    // Affine product: the bottom rows are (0, 0, 0, 1).
                    let mut n = Matrix4::identity();
                    for r in 0..3 {
                        for c in 0..4 {
                            let mut acc = if c == 3 { t[(r, 3)] } else { 0.0 };
                            for j in 0..3 {
                                acc += t[(r, j)] * m[(j, c)];
                            }
                            n[(r, c)] = acc;
                        }
                    }
                    t = n;
                }
            }
        }
        t
    }
}
