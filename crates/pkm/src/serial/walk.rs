//! The walk along a chain: seed 003's product `A_(0,0*) prod_i A_((i-1)*,i)(q_i)
//! A_(i,i*)` (eqs. 1, 4) taken factor by factor, the running transform held as its
//! four columns.
//!
//! Each column is four lanes (the three rows and the homogeneous row), so every step
//! is a few whole-column operations: a turn about Z mixes columns 0 and 1, a slide
//! along Z adds a multiple of column 2 to column 3, and a link's 3 x 4 block `L`
//! makes column `c` the sum `col_0 L_0c + col_1 L_1c + col_2 L_2c` (plus `col_3` for
//! the translation). The link's entries are scalars, broadcast as they are needed;
//! the running columns stay in registers. This is the same arithmetic, entry by entry
//! and in the same order, as the row-wise product `n_rc = a_r0 b_0c + a_r1 b_1c +
//! a_r2 b_2c (+ a_r3)`, so it gives the same bits (tested against it).
//!
//! A walk is written once over a [`Column`] and [`fast`] runs it with one 256-bit AVX2
//! register per column where the CPU has it, else with four plain lanes. Each lane
//! takes the same IEEE operations in either (no fused multiply-adds: Rust never
//! contracts `a * b + c`), so both give the same bits.

use nalgebra::{Matrix4, Vector3};

use super::{Affine, JointKind};

/// The arithmetic of a column of the running transform (rows 0, 1, 2 and the
/// homogeneous row), lane by lane.
pub(super) trait Column: Copy {
    /// The column of four values.
    fn new(v: [f64; 4]) -> Self;
    /// Its four values.
    fn lanes(self) -> [f64; 4];
    /// `self * s`.
    fn scale(self, s: f64) -> Self;
    /// `self + o`.
    fn add(self, o: Self) -> Self;
    /// `self - o`.
    fn sub(self, o: Self) -> Self;
}

/// A column as four plain lanes (any CPU).
#[derive(Clone, Copy)]
pub(super) struct Lanes([f64; 4]);

impl Column for Lanes {
    #[inline(always)]
    fn new(v: [f64; 4]) -> Lanes {
        Lanes(v)
    }
    #[inline(always)]
    fn lanes(self) -> [f64; 4] {
        self.0
    }
    #[inline(always)]
    fn scale(self, s: f64) -> Lanes {
        Lanes(self.0.map(|x| x * s))
    }
    #[inline(always)]
    fn add(self, o: Lanes) -> Lanes {
        Lanes(std::array::from_fn(|k| self.0[k] + o.0[k]))
    }
    #[inline(always)]
    fn sub(self, o: Lanes) -> Lanes {
        Lanes(std::array::from_fn(|k| self.0[k] - o.0[k]))
    }
}

/// A column in one AVX register. Its operations are the intrinsics themselves (plain
/// lane loops would be split into scalars by the compiler), so it is only used inside
/// [`fast`]'s AVX2 function, into which they inline. Private to this file: no other
/// code can name it, so no `Ymm` runs outside `avx2`, on a CPU without AVX.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Ymm(std::arch::x86_64::__m256d);

#[cfg(target_arch = "x86_64")]
impl Column for Ymm {
    #[inline(always)]
    fn new(v: [f64; 4]) -> Ymm {
        // SAFETY: both are four f64, any bits valid.
        Ymm(unsafe { std::mem::transmute::<[f64; 4], std::arch::x86_64::__m256d>(v) })
    }
    #[inline(always)]
    fn lanes(self) -> [f64; 4] {
        // SAFETY: as in `new`.
        unsafe { std::mem::transmute::<std::arch::x86_64::__m256d, [f64; 4]>(self.0) }
    }
    #[inline(always)]
    fn scale(self, s: f64) -> Ymm {
        use std::arch::x86_64::{_mm256_mul_pd, _mm256_set1_pd};
        // SAFETY: a `Ymm` exists only inside `avx2` (`fast`), on a CPU with AVX2.
        Ymm(unsafe { _mm256_mul_pd(self.0, _mm256_set1_pd(s)) })
    }
    #[inline(always)]
    fn add(self, o: Ymm) -> Ymm {
        // SAFETY: as in `scale`.
        Ymm(unsafe { std::arch::x86_64::_mm256_add_pd(self.0, o.0) })
    }
    #[inline(always)]
    fn sub(self, o: Ymm) -> Ymm {
        // SAFETY: as in `scale`.
        Ymm(unsafe { std::arch::x86_64::_mm256_sub_pd(self.0, o.0) })
    }
}

/// The running transform of a walk, column by column (nalgebra's layout of a
/// [`Matrix4`]).
#[derive(Clone, Copy)]
pub(super) struct Frame<C: Column>([C; 4]);

impl<C: Column> Frame<C> {
    /// The frame of a 3 x 4 block (its bottom row `0 0 0 1`).
    #[inline(always)]
    pub(super) fn of(a: &Affine) -> Self {
        Frame(std::array::from_fn(|c| {
            C::new([a[0][c], a[1][c], a[2][c], if c == 3 { 1.0 } else { 0.0 }])
        }))
    }

    /// `T A_((i-1)*,i)(v)` (eq. 4): a turn about Z (`(s, c)` the sine and cosine of
    /// `v`) mixes columns 0 and 1, `(c col_0 + s col_1, c col_1 - s col_0)`; a slide
    /// along Z adds `v col_2` to the translation.
    #[inline(always)]
    pub(super) fn joint(&mut self, kind: JointKind, v: f64, (s, c): (f64, f64)) {
        let t = &mut self.0;
        match kind {
            JointKind::Revolute => {
                let (a, b) = (t[0], t[1]);
                t[0] = a.scale(c).add(b.scale(s));
                t[1] = b.scale(c).sub(a.scale(s));
            }
            JointKind::Prismatic => t[3] = t[3].add(t[2].scale(v)),
        }
    }

    /// `T L` for a link's block `L`: column `c` becomes `col_0 L_0c + col_1 L_1c +
    /// col_2 L_2c`, and the translation adds `col_3`.
    #[inline(always)]
    pub(super) fn times(&mut self, l: &Affine) {
        let t = self.0;
        let column = |c: usize| {
            t[0].scale(l[0][c])
                .add(t[1].scale(l[1][c]))
                .add(t[2].scale(l[2][c]))
        };
        self.0 = [column(0), column(1), column(2), column(3).add(t[3])];
    }

    /// The frame's Z axis (column 2): a joint's axis before its motion.
    #[inline(always)]
    pub(super) fn axis(&self) -> Vector3<f64> {
        let l = self.0[2].lanes();
        Vector3::new(l[0], l[1], l[2])
    }

    /// The frame's origin (column 3): a point of that axis.
    #[inline(always)]
    pub(super) fn origin(&self) -> Vector3<f64> {
        let l = self.0[3].lanes();
        Vector3::new(l[0], l[1], l[2])
    }

    /// The homogeneous matrix, its bottom row exactly `0 0 0 1` (the lanes carried
    /// along would hold NaN after a NaN joint value).
    #[inline(always)]
    pub(super) fn matrix(&self) -> Matrix4<f64> {
        let t = self.0.map(C::lanes);
        Matrix4::from_column_slice(&[
            t[0][0], t[0][1], t[0][2], 0.0, //
            t[1][0], t[1][1], t[1][2], 0.0, //
            t[2][0], t[2][1], t[2][2], 0.0, //
            t[3][0], t[3][1], t[3][2], 1.0,
        ])
    }
}

/// Joints whose sines and cosines [`joint_sines`] computes in one vectorised pass (a
/// later joint's come from `f64::sin_cos` as it is reached).
pub(super) const VECTOR_JOINTS: usize = 8;

/// `(sin v_k, cos v_k)` of the first `n` joint values `v_k = value(k)` (at most
/// [`VECTOR_JOINTS`]; the other lanes `(0, 1)`), in one branch-free pass over eight
/// lanes ([`crate::trig::sin_cos_array_inline`]): independent of each other and of the
/// products, they overlap instead of waiting on the walk's chain. The values are made
/// in registers, lane by lane, and the pass fills whole registers: a vector load of
/// values stored one by one, or of a part-filled register's masked store, would wait
/// for those stores to retire.
#[inline(always)]
pub(super) fn joint_sines(
    n: usize,
    value: impl Fn(usize) -> f64,
) -> ([f64; VECTOR_JOINTS], [f64; VECTOR_JOINTS]) {
    // Written out: `array::from_fn` is not inlined and fills the array in memory.
    let at = |k: usize| if k < n { value(k) } else { 0.0 };
    let v = [at(0), at(1), at(2), at(3), at(4), at(5), at(6), at(7)];
    crate::trig::sin_cos_array_inline(&v)
}

/// A walk written once over its column arithmetic.
pub(super) trait Walk {
    /// What the walk returns.
    type Out;
    /// Runs the walk with columns `C`.
    fn run<C: Column>(self) -> Self::Out;
}

/// Runs `walk` with one AVX2 register per column where the CPU has it (compiled for
/// AVX2), else with plain lanes: the same bits either way.
#[inline(always)]
pub(super) fn fast<W: Walk>(walk: W) -> W::Out {
    #[cfg(target_arch = "x86_64")]
    if crate::simd::level() >= crate::simd::Level::Avx2 {
        // SAFETY: the CPU has AVX2 (checked on the line above).
        return unsafe { avx2(walk) };
    }
    walk.run::<Lanes>()
}

/// `walk` with AVX registers, in a function compiled for AVX2 (the walk inlined).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn avx2<W: Walk>(walk: W) -> W::Out {
    walk.run::<Ymm>()
}

#[cfg(test)]
mod tests {
    use super::super::{affine_mul, apply_joint, matrix_of, AFFINE_IDENTITY};
    use super::*;
    use rand::{Rng, SeedableRng};

    /// A walk through `links` from `head`, with each joint's axis and origin.
    #[derive(Clone, Copy)]
    struct TestWalk<'a> {
        head: &'a Affine,
        links: &'a [(JointKind, f64, Affine)],
    }

    impl Walk for TestWalk<'_> {
        type Out = (Matrix4<f64>, Vec<[f64; 6]>);

        fn run<C: Column>(self) -> Self::Out {
            let mut t = Frame::<C>::of(self.head);
            let mut axes = Vec::new();
            for (kind, v, l) in self.links {
                let (z, o) = (t.axis(), t.origin());
                axes.push([z.x, z.y, z.z, o.x, o.y, o.z]);
                t.joint(*kind, *v, v.sin_cos());
                t.times(l);
            }
            (t.matrix(), axes)
        }
    }

    /// The column walk equals the row-wise product (`affine_mul`, `apply_joint`) bit
    /// for bit, built for AVX2 and as built: random chains of turns and slides and
    /// random blocks (general entries, exact zeros and ones, signed zeros), joint
    /// values from 1e-9 to 1e3, infinities and NaN (the bottom row stays `0 0 0 1`).
    #[test]
    fn columns_give_the_rows_bits() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let entry = |rng: &mut rand::rngs::StdRng| match rng.random_range(0..10) {
            0 => 0.0,
            1 => -0.0,
            2 => 1.0,
            3 => -1.0,
            _ => rng.random_range(-2.0..2.0) * 10f64.powi(rng.random_range(-3..3)),
        };
        for case in 0..5_000 {
            let links: Vec<(JointKind, f64, Affine)> = (0..rng.random_range(1..9))
                .map(|_| {
                    let kind = if rng.random_bool(0.7) {
                        JointKind::Revolute
                    } else {
                        JointKind::Prismatic
                    };
                    let mut v = rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-9..4));
                    if case % 499 == 7 {
                        v = [f64::NAN, f64::INFINITY, -0.0][case % 3];
                    }
                    let l: Affine =
                        std::array::from_fn(|_| std::array::from_fn(|_| entry(&mut rng)));
                    (kind, v, l)
                })
                .collect();
            let head: Affine = std::array::from_fn(|_| std::array::from_fn(|_| entry(&mut rng)));
            let mut rows = head;
            let mut row_axes = Vec::new();
            for (kind, v, l) in &links {
                row_axes.push([
                    rows[0][2], rows[1][2], rows[2][2], rows[0][3], rows[1][3], rows[2][3],
                ]);
                apply_joint(&mut rows, *kind, *v, v.sin_cos());
                rows = affine_mul(&rows, l);
            }
            let expected = matrix_of(&rows);
            let walk = TestWalk {
                head: &head,
                links: &links,
            };
            let bits = |m: &Matrix4<f64>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let axis_bits =
                |a: &Vec<[f64; 6]>| a.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            for (m, axes) in [walk.run::<Lanes>(), fast(walk)] {
                assert_eq!(bits(&m), bits(&expected), "case {case}");
                assert_eq!(axis_bits(&axes), axis_bits(&row_axes), "case {case}");
            }
        }
        // The identity walks to the identity.
        assert_eq!(
            Frame::<Lanes>::of(&AFFINE_IDENTITY).matrix(),
            Matrix4::identity()
        );
    }
}
