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
pub mod arm;
pub mod completion;
pub mod deviations;
pub mod dynamics;
pub mod jacobian;
pub mod machine;
pub mod mechanism;
mod parallel_axes;
mod prepared;
pub mod spherical_wrist;
pub mod tcp;
pub mod tcp_axis;
mod walk;

use nalgebra::{Matrix3, Matrix4, Vector3};

/// A serial machine loaded from a file: the mechanism and its tolerances.
#[derive(Debug, Clone, PartialEq)]
pub struct SerialModel {
    /// The machine as a mechanism (joint count fixed at load time).
    pub mechanism: mechanism::SerialAny,
    /// Tolerances of primary deviations from the file (`[[tolerance]]`).
    pub tolerances: Vec<crate::accuracy::Tolerance>,
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
    /// Largest speed (mm/s or rad/s), when the file gives one.
    pub max_velocity: Option<f64>,
    /// Largest acceleration (mm/s^2 or rad/s^2), when the file gives one.
    pub max_acceleration: Option<f64>,
    /// Stiffness of the joint's drive along its coordinate (N/mm, or N mm/rad for a
    /// revolute joint), when the file gives one.
    pub stiffness: Option<f64>,
}

impl Joint {
    /// Angle (revolute) or length (prismatic).
    pub fn quantity(&self) -> crate::units::Quantity {
        match self.kind {
            JointKind::Revolute => crate::units::Quantity::Angle,
            JointKind::Prismatic => crate::units::Quantity::Length,
        }
    }

    /// The joint as a mechanism's actuator (its name, travel and rates).
    pub fn actuator(&self) -> crate::mechanism::Actuator {
        crate::mechanism::Actuator {
            name: self.name.clone(),
            quantity: self.quantity(),
            range: self.range,
            max_velocity: self.max_velocity,
            max_acceleration: self.max_acceleration,
            stiffness: self.stiffness,
        }
    }
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
    /// The link's mass properties in its frame `S_i`, when the file gives them (URDF
    /// `<inertial>`); `None`: massless. Inverse dynamics ([`dynamics`]) needs them.
    pub inertial: Option<Inertial>,
}

/// A rigid body's mass properties in its link frame: mass (kg), centre of mass (mm)
/// and inertia tensor about the centre of mass (kg mm^2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertial {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the link frame (mm).
    pub com: Vector3<f64>,
    /// Inertia about the centre of mass, link-frame axes (kg mm^2).
    pub inertia: Matrix3<f64>,
}

impl Inertial {
    /// The body with `other` (both in the same frame) joined: masses added, the centre
    /// of mass their mean, the inertia moved to it by the parallel-axis theorem
    /// `I = sum (I_k + m_k (|d_k|^2 E - d_k d_k^T))`, `d_k = c_k - c`.
    pub fn joined(&self, other: &Inertial) -> Inertial {
        let mass = self.mass + other.mass;
        if !(mass > 0.0) {
            return Inertial {
                mass: 0.0,
                com: Vector3::zeros(),
                inertia: Matrix3::zeros(),
            };
        }
        let com = (self.com * self.mass + other.com * other.mass) / mass;
        let shift = |b: &Inertial| {
            let d = b.com - com;
            b.inertia + (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * b.mass
        };
        Inertial {
            mass,
            com,
            inertia: shift(self) + shift(other),
        }
    }

    /// The same body seen from a frame in which the link frame has rotation `r` and
    /// origin `p` (mm).
    pub fn transformed(&self, r: &Matrix3<f64>, p: &Vector3<f64>) -> Inertial {
        Inertial {
            mass: self.mass,
            com: r * self.com + p,
            inertia: r * self.inertia * r.transpose(),
        }
    }
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
    /// The deviated block itself, when a completion (eq. 3) has found it: it replaces
    /// `cos(phi + alpha)` (the same block, without the `acos`/`cos` round trip).
    pub block: Option<Matrix3<f64>>,
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
    matrix_of(&link_affine(link, dev))
}

/// The rotation block of a deviated link (eq. 2): the completed block where a
/// completion (eq. 3) found it, else `cos(phi_ab + alpha_ab)` entry by entry, with
/// `c = cos(phi_ab)` the nominal direction cosine, evaluated without the `acos`:
///
/// `cos(phi + alpha) = c cos(alpha) - sqrt(1 - c^2) sin(alpha)`
///
/// (`phi = acos c` lies in `[0, pi]`, so `sin(phi) = sqrt(1 - c^2) >= 0`). The nine
/// sines and cosines come from one vectorised pass ([`crate::trig::sin_cos_small`]:
/// short series for deviations below 7.8 mrad, the usual case). An axis-aligned link
/// whose deviations are all below 0.98 mrad (a machine's, in practice) needs only
/// `c cos(alpha)` or `-sin(alpha)` per entry, by shorter series still
/// ([`crate::trig::cos_sum_aligned_tiny`]; within one unit in the last place of the
/// longer ones, tested).
/// An entry without angular deviation is `c` itself (`c * 1 - s * 0`, exactly). An
/// axis-aligned link (every `c` exactly 0 or +-1) takes `sqrt(1 - c^2) = 1 - |c|`,
/// exact, without the nine square roots. The
/// `acos`/`cos` round trip, 2 x 49 libm calls per pose of a deviated 6R arm, was
/// nine tenths of [`Chain::pose`]; the two agree within 1e-15 per entry (tested).
///
/// On a CPU with AVX2 the same code runs compiled for it (the same operations in the
/// same order, so the same bits: Rust does not contract `a * b + c`; tested); inside
/// [`Chain::pose`] it is inlined into the AVX2 walk (`walk.rs`). Its range tests are
/// folds that vectorise rather than nine compare-and-branch pairs each, and the
/// deviations are read in place (a copy, stored and read back at other offsets,
/// waited for its stores). Each of these cut the time of a deviated 6R [`Chain::pose`]
/// (243 ns before them on one EPYC); `docs/performance.md` has the current figures.
#[inline]
pub fn deviated_block(link: &Link, dev: &LinkDeviation) -> Matrix3<f64> {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::level() >= crate::simd::Level::Avx2 {
        // SAFETY: the CPU has AVX2 (checked on the line above).
        return unsafe { deviated_block_avx2(link, dev) };
    }
    deviated_block_body(link, dev)
}

/// [`deviated_block_body`] compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn deviated_block_avx2(link: &Link, dev: &LinkDeviation) -> Matrix3<f64> {
    deviated_block_body(link, dev)
}

/// [`deviated_block`]'s code, for every build of it.
#[inline(always)]
fn deviated_block_body(link: &Link, dev: &LinkDeviation) -> Matrix3<f64> {
    if let Some(b) = &dev.block {
        return *b;
    }
    let mut b = link.rotation;
    // A fold, not `all`: nine comparisons in a few vector instructions.
    if dev.alpha.iter().fold(true, |none, a| none & (*a == 0.0)) {
        return b;
    }
    // Read in place: a copy (stored as two 32-byte halves, read back at other offsets)
    // would wait for the stores to retire.
    let alpha: &[f64; 9] = dev.alpha.as_slice().try_into().expect("3 x 3");
    // Axis-aligned links (every nominal cosine 0 or +-1, exactly: `c^2 = |c|` holds
    // for nothing else) have `sqrt(1 - c^2) = 1 - |c|` exactly: no square root.
    // A fold, not `all`: nine comparisons in a few vector instructions instead of nine
    // compare-and-branch pairs (the same answer).
    let aligned = b.iter().fold(true, |ok, c| ok & (*c * *c == c.abs()));
    if aligned
        && alpha
            .iter()
            .fold(true, |ok, a| ok & (a.abs() <= crate::trig::TINY))
    {
        // Each entry is `c cos(alpha)` or `-sin(alpha)`: only the one series it needs.
        let c: &[f64; 9] = b.as_slice().try_into().expect("3 x 3");
        return Matrix3::from_column_slice(&crate::trig::cos_sum_aligned_tiny(c, alpha));
    }
    let (sa, ca) = crate::trig::sin_cos_small(alpha);
    let sine: [f64; 9] = if aligned {
        std::array::from_fn(|k| 1.0 - b[k].abs())
    } else {
        std::array::from_fn(|k| (1.0 - b[k] * b[k]).max(0.0).sqrt())
    };
    for (k, c) in b.iter_mut().enumerate() {
        *c = *c * ca[k] - sine[k] * sa[k];
    }
    b
}

/// `A_(i,i*)` with deviations as a 3 x 4 affine block.
#[inline(always)]
fn link_affine(link: &Link, dev: &LinkDeviation) -> Affine {
    affine_of(link, dev, deviated_block(link, dev))
}

/// [`link_affine`] with the deviated block's code inlined (for a caller compiled for
/// AVX2, which then needs no second test of the CPU).
#[inline(always)]
fn link_affine_body(link: &Link, dev: &LinkDeviation) -> Affine {
    affine_of(link, dev, deviated_block_body(link, dev))
}

/// The 3 x 4 block of rotation `r` and the link's deviated translation.
#[inline(always)]
fn affine_of(link: &Link, dev: &LinkDeviation, r: Matrix3<f64>) -> Affine {
    let t = link.translation + dev.delta;
    [
        [r[(0, 0)], r[(0, 1)], r[(0, 2)], t.x],
        [r[(1, 0)], r[(1, 1)], r[(1, 2)], t.y],
        [r[(2, 0)], r[(2, 1)], r[(2, 2)], t.z],
    ]
}

/// `t A_((i-1)*,i)(v)` in place (eq. 4) as the column operation it is: a turn about Z
/// mixes the first two columns (`(s, c)` its sine and cosine), a slide along Z adds `v`
/// times the third column to the translation.
#[inline(always)]
fn apply_joint(t: &mut Affine, kind: JointKind, v: f64, (s, c): (f64, f64)) {
    match kind {
        JointKind::Revolute => {
            for row in t {
                let (a, b) = (row[0], row[1]);
                row[0] = c * a + s * b;
                row[1] = c * b - s * a;
            }
        }
        JointKind::Prismatic => {
            for row in t {
                row[3] += v * row[2];
            }
        }
    }
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
        // The walk in column form (`walk.rs`): joints as column operations, each
        // link's deviated block made as it is reached; AVX2 registers where the CPU
        // has them.
        Ok(walk::fast(DeviatedWalk {
            chain: self,
            q,
            dq,
            dev,
        }))
    }
}

/// [`Chain::pose`] over any column arithmetic (its arguments checked).
struct DeviatedWalk<'a> {
    chain: &'a Chain,
    q: &'a [f64],
    dq: &'a [f64],
    dev: &'a [LinkDeviation],
}

impl walk::Walk for DeviatedWalk<'_> {
    type Out = Matrix4<f64>;

    #[inline(always)]
    fn run<C: walk::Column>(self) -> Matrix4<f64> {
        let DeviatedWalk { chain, q, dq, dev } = self;
        let zero = LinkDeviation::default();
        let value = |k: usize| q[k] + dq.get(k).copied().unwrap_or(0.0);
        let (sn, cs) = walk::joint_sines(q.len(), value);
        let mut t = walk::Frame::<C>::of(&AFFINE_IDENTITY);
        let mut k = 0;
        for (i, link) in chain.links.iter().enumerate() {
            if let Some(j) = &link.joint {
                let v = value(k);
                let sc = match j.kind {
                    JointKind::Revolute if k < walk::VECTOR_JOINTS => (sn[k], cs[k]),
                    JointKind::Revolute => v.sin_cos(),
                    JointKind::Prismatic => (0.0, 1.0),
                };
                t.joint(j.kind, v, sc);
                k += 1;
            }
            t.times(&link_affine_body(link, dev.get(i).unwrap_or(&zero)));
        }
        t.matrix()
    }
}

/// A 3 x 4 affine transform, row-major (the bottom row `0 0 0 1` implied).
type Affine = [[f64; 4]; 3];

const AFFINE_IDENTITY: Affine = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
];

#[inline(always)]
fn affine_mul(a: &Affine, b: &Affine) -> Affine {
    // Row by row: `n_r = a_r0 b_0 + a_r1 b_1 + a_r2 b_2 + (0, 0, 0, a_r3)`, each row of
    // `b` one 4-wide vector.
    let mut n = [[0.0; 4]; 3];
    for r in 0..3 {
        for c in 0..4 {
            n[r][c] = a[r][0] * b[0][c] + a[r][1] * b[1][c] + a[r][2] * b[2][c];
        }
        n[r][3] += a[r][3];
    }
    n
}

fn matrix_of(a: &Affine) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    for r in 0..3 {
        for c in 0..4 {
            m[(r, c)] = a[r][c];
        }
    }
    m
}

pub use accuracy::sensitivity;
pub use jacobian::{jacobian_of_axes, jacobian_rate_times_rates};
pub use machine::{ChainDeviations, Parameter as Deviation, SerialMachine};
pub use prepared::{JointAxis, PreparedChain};

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The AVX2 build of the deviated block equals the plain build bit for bit:
    /// random, identity and axis-permuting rotations; deviations from 1e-9 rad to
    /// 0.3 rad (beyond the small-angle series too), sparse ones, NaN; completed blocks.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn deviated_block_is_the_same_in_every_build() {
        if !std::arch::is_x86_feature_detected!("avx2") {
            return;
        }
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for case in 0..20_000 {
            let rotation = match case % 4 {
                0 => Matrix3::identity(),
                1 => Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0),
                _ => *nalgebra::Rotation3::from_euler_angles(
                    rng.random_range(-3.0..3.0),
                    rng.random_range(-3.0..3.0),
                    rng.random_range(-3.0..3.0),
                )
                .matrix(),
            };
            let scale = 10f64.powf(rng.random_range(-9.0..-0.5));
            let mut alpha = Matrix3::from_fn(|_, _| {
                if rng.random_bool(0.3) {
                    0.0
                } else {
                    scale * rng.random_range(-1.0..1.0)
                }
            });
            if case % 997 == 5 {
                alpha[case % 9] = f64::NAN;
            }
            let link = Link {
                name: "l".into(),
                joint: None,
                translation: Vector3::zeros(),
                rotation,
                inertial: None,
            };
            let dev = LinkDeviation {
                alpha,
                block: (case % 101 == 3).then_some(rotation * 0.5),
                ..Default::default()
            };
            let plain = deviated_block_body(&link, &dev);
            // SAFETY: the CPU has AVX2 (checked above).
            let avx2 = unsafe { deviated_block_avx2(&link, &dev) };
            for k in 0..9 {
                assert_eq!(
                    plain[k].to_bits(),
                    avx2[k].to_bits(),
                    "case {case} entry {k}"
                );
            }
        }
    }

    /// `Chain::pose` and the prepared chain's pose and axes are the same bits with
    /// plain lanes as with the AVX2 registers `walk::fast` picks here: random 6R and
    /// 5-axis chains (turns and slides), deviated links, joint values near zero, far
    /// beyond a turn and beyond the vectorised sines' eight joints.
    #[test]
    fn walks_are_the_same_in_every_build() {
        use walk::{Lanes, Walk};
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        for case in 0..2_000 {
            let n = [5, 6, 9][case % 3];
            let links: Vec<Link> = (0..=n)
                .map(|i| Link {
                    name: format!("{i}"),
                    joint: (i > 0).then(|| Joint {
                        name: format!("j{i}"),
                        kind: if rng.random_bool(0.6) {
                            JointKind::Revolute
                        } else {
                            JointKind::Prismatic
                        },
                        range: Range {
                            min: -1e9,
                            max: 1e9,
                        },
                        max_velocity: None,
                        max_acceleration: None,
                        stiffness: None,
                    }),
                    translation: Vector3::from_fn(|_, _| rng.random_range(-500.0..500.0)),
                    rotation: *nalgebra::Rotation3::from_euler_angles(
                        rng.random_range(-3.0..3.0),
                        rng.random_range(-3.0..3.0),
                        rng.random_range(-3.0..3.0),
                    )
                    .matrix(),
                    inertial: None,
                })
                .collect();
            let chain = Chain {
                name: "c".into(),
                links,
            };
            let dev: Vec<LinkDeviation> = (0..=n)
                .map(|_| LinkDeviation {
                    delta: Vector3::from_fn(|_, _| rng.random_range(-0.1..0.1)),
                    alpha: Matrix3::from_fn(|_, _| rng.random_range(-1e-3..1e-3)),
                    block: None,
                })
                .collect();
            let scale = [1e-9, 1.0, 30.0][case % 3];
            let q: Vec<f64> = (0..n)
                .map(|_| scale * rng.random_range(-3.0..3.0))
                .collect();
            let dq: Vec<f64> = (0..n).map(|_| rng.random_range(-1e-3..1e-3)).collect();
            let bits = |m: &Matrix4<f64>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let lanes = DeviatedWalk {
                chain: &chain,
                q: &q,
                dq: &dq,
                dev: &dev,
            }
            .run::<Lanes>();
            assert_eq!(
                bits(&lanes),
                bits(&chain.pose(&q, &dq, &dev).unwrap()),
                "case {case}"
            );
            let prepared = PreparedChain::new(&chain, &dq, &dev);
            let (mut axes_plain, mut axes_fast) = (Vec::new(), Vec::new());
            let plain = prepared::PreparedWalk {
                chain: &prepared,
                q: &q,
                at_joint: |z: Vector3<f64>, o: Vector3<f64>, _| {
                    axes_plain.extend(z.iter().chain(o.iter()).map(|x| x.to_bits()))
                },
            }
            .run::<Lanes>();
            let fast = prepared.walk(&q, |z, o, _| {
                axes_fast.extend(z.iter().chain(o.iter()).map(|x| x.to_bits()))
            });
            assert_eq!(bits(&plain), bits(&fast), "case {case}");
            assert_eq!(axes_plain, axes_fast, "case {case}");
            assert_eq!(axes_plain.len(), 6 * n);
        }
    }
}
