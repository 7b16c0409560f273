//! A `sin_cos` for the hot loops of serial chains (joint angles of a few turns at
//! most), written so that a loop over several angles vectorises: reduction by
//! multiples of `pi/2` (two-part `pi/2`, rounding by the `1.5 * 2^52` trick, no libm
//! call), then the Taylor series of sine (to `x^15`) and cosine (to `x^16`) on
//! `[-pi/4, pi/4]`, whose first omitted terms are below `5e-17`, evaluated by Estrin's
//! scheme (a shorter chain of dependent operations than Horner's rule: a single pose's
//! latency), and a branch-free quadrant fix-up. Within 2 units in the last place of
//! `f64::sin_cos` for `|x| <= 1e4` (tested over 10^6 points); beyond that it defers to
//! `f64::sin_cos`.
//!
//! Every multiply-add of the kernel is fused (`f64::mul_add`, one rounding): half the
//! dependent steps of a separate product and sum, and the AVX-512 lanes
//! (`avx512`) make the same fused operations, so both give the same bits. The
//! library is built for the baseline x86-64 target, which has no FMA instruction: the
//! scalar kernel runs compiled with FMA enabled where the CPU has it ([`fused`],
//! checked at run time), else with libm's `fma` (correctly rounded too, so the same
//! bits, but a call per operation: only CPUs from before 2013 take it).

/// `pi/2` split so that `k * PIO2_HI` is exact for `|k| < 2^20`: its first 33 bits
/// (1.5707963267341256) and the rest (6.077100506506192e-11).
const PIO2_HI: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
const PIO2_LO: f64 = f64::from_bits(0x3DD0_B461_1A62_6331);
const TWO_OVER_PI: f64 = std::f64::consts::FRAC_2_PI;
const MAGIC: f64 = 6_755_399_441_055_744.0;

/// Taylor coefficients `(-1)^k / (2k+1)!` and `(-1)^k / (2k)!`.
const S: [f64; 7] = [
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5_040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
];
const C: [f64; 8] = [
    -0.5,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
];

/// Whether this CPU has fused multiply-adds (x86-64: FMA3, detected once and cached
/// by the standard library; other targets: whether the build enables them). The
/// kernel's multiply-adds are fused on every CPU, so its bits do not depend on this:
/// where it is `false` each one is libm's `fma`, correctly rounded too but a call.
#[inline(always)]
pub fn fused() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        cfg!(target_feature = "fma") || std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        cfg!(target_feature = "fma") || cfg!(target_arch = "aarch64")
    }
}

/// Runs `$body` (a block over the named arguments) compiled with FMA enabled when
/// [`fused`] (so each `mul_add` in it is one instruction), else as it is (each
/// `mul_add` a libm call): the same bits either way.
macro_rules! with_fma {
    ($(<$(const $g:ident: usize),*>)? ($($arg:ident: $ty:ty),*) -> $ret:ty $body:block) => {{
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = "fma")]
            fn fast$(<$(const $g: usize),*>)?($($arg: $ty),*) -> $ret $body
            if $crate::trig::fused() {
                // SAFETY: the CPU has FMA (and so AVX, which FMA implies), the features
                // the function enables.
                return unsafe { fast$(::<$($g),*>)?($($arg),*) };
            }
        }
        #[inline(always)]
        fn plain$(<$(const $g: usize),*>)?($($arg: $ty),*) -> $ret $body
        plain$(::<$($g),*>)?($($arg),*)
    }};
}
pub(crate) use with_fma;

/// How the kernel evaluates its multiply-adds `a b + c`.
pub(crate) trait MulAdd {
    /// `a b + c`.
    fn mul_add(a: f64, b: f64, c: f64) -> f64;
    /// `c - a b`.
    fn sub_mul(a: f64, b: f64, c: f64) -> f64;
}

/// Fused, one rounding ([`f64::mul_add`]): the AVX-512 lanes' operations.
pub(crate) enum Fused {}

/// A product, then a sum (two roundings): inlined into its caller and vectorised with
/// its loop on any target, no dispatch.
pub(crate) enum Separate {}

impl MulAdd for Fused {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        a.mul_add(b, c)
    }
    #[inline(always)]
    fn sub_mul(a: f64, b: f64, c: f64) -> f64 {
        (-a).mul_add(b, c)
    }
}

impl MulAdd for Separate {
    #[inline(always)]
    fn mul_add(a: f64, b: f64, c: f64) -> f64 {
        c + a * b
    }
    #[inline(always)]
    fn sub_mul(a: f64, b: f64, c: f64) -> f64 {
        c - a * b
    }
}

/// `(sin x, cos x)`, by the fused kernel: the same bits as the AVX-512 lanes.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if !(x.abs() <= 1e4) {
        return x.sin_cos();
    }
    with_fma!((x: f64) -> (f64, f64) { kernel::<Fused>(x) })
}

/// `(sin x, cos x)` of every element of `x`, in one vectorised pass when all of them
/// are within `|x| <= 1e4` (else element by element), by the fused kernel: the same
/// bits as [`sin_cos`] and the AVX-512 lanes.
#[inline(always)]
pub fn sin_cos_array<const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N]) {
    with_fma!(<const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N]) {
        sin_cos_array_by::<Fused, N>(x)
    })
}

/// `(sin x, cos x)` of every lane of `x` by the fused kernel, for a lane kernel compiled
/// with FMA (inlined into it, the loop is its vector instructions): the bits of
/// [`sin_cos`] and of the AVX-512 lanes; `None` when a lane is beyond the kernel's range
/// `|x| <= 1e4` or NaN (the caller takes its scalar path, which defers those to libm).
#[inline(always)]
pub(crate) fn sin_cos_lanes<const N: usize>(x: &[f64; N]) -> Option<([f64; N], [f64; N])> {
    let mut in_range = true;
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    for k in 0..N {
        in_range &= x[k].abs() <= 1e4;
        (s[k], c[k]) = kernel::<Fused>(x[k]);
    }
    in_range.then_some((s, c))
}

/// [`sin_cos_lanes`] on up to eight lanes whatever their range, with the mask of the lanes
/// within it (`|x| <= 1e4`, not NaN): the others hold whatever the kernel gives and
/// are not to be used, as the AVX-512 lanes' (`avx512::sin_cos`).
#[inline(always)]
pub(crate) fn sin_cos_lanes_masked<const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N], u8) {
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    let mut in_range = 0u8;
    for k in 0..N {
        (s[k], c[k]) = kernel::<Fused>(x[k]);
        in_range |= u8::from(x[k].abs() <= 1e4) << k;
    }
    (s, c, in_range)
}

/// [`sin_cos_array`] with separate products and sums, inlined into the caller (whose
/// loop over the angles it vectorises with, on any target, with no call): for a
/// serial chain's joints, which no AVX-512 kernel has to agree with. Within the same
/// 2 units in the last place of libm's (tested).
#[inline(always)]
pub fn sin_cos_array_inline<const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N]) {
    sin_cos_array_by::<Separate, N>(x)
}

/// [`sin_cos_array`]'s pass with the multiply-adds `M`, compiled in its caller.
#[inline(always)]
pub(crate) fn sin_cos_array_by<M: MulAdd, const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N]) {
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    if x.iter().fold(true, |ok, v| ok & (v.abs() <= 1e4)) {
        for k in 0..N {
            (s[k], c[k]) = kernel::<M>(x[k]);
        }
    } else {
        for k in 0..N {
            (s[k], c[k]) = x[k].sin_cos();
        }
    }
    (s, c)
}

/// `(sin x, cos x)` of every element of `x`, for small angles in one short pass: when
/// every `|x| <= 2^-7` (7.8 mrad: the angular deviations of links and joints), the
/// Taylor series to `x^7` and `x^8`, whose first omitted terms are below `4e-23`
/// relative (within one unit in the last place of `f64::sin_cos`, tested); else
/// [`sin_cos_array_inline`].
#[inline(always)]
pub fn sin_cos_small<const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N]) {
    // A fold, not `all`: the comparisons vectorise instead of branching one by one.
    if !x.iter().fold(true, |ok, v| ok & (v.abs() <= SMALL)) {
        return sin_cos_array_inline(x);
    }
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    for k in 0..N {
        let (a, z) = (x[k], x[k] * x[k]);
        s[k] = a + a * z * (S[0] + z * (S[1] + z * S[2]));
        c[k] = 1.0 + z * (C[0] + z * (C[1] + z * (C[2] + z * C[3])));
    }
    (s, c)
}

/// The bound of [`sin_cos_small`]'s series, `2^-7`.
const SMALL: f64 = 0.0078125;

/// The bound of [`cos_sum_aligned_tiny`]'s series, `2^-10` (0.98 mrad): a link's
/// angular deviations in practice.
pub const TINY: f64 = 0.0009765625;

/// `cos(phi_k + x_k)` for nominal cosines `c_k = cos(phi_k)` that are exactly 0 or
/// +-1 and every `|x_k| <= TINY` (the caller checks both): `c cos x` where `|c| = 1`,
/// `-sin x` where `c = 0`, each from its Taylor series to `x^4` and `x^5`, whose
/// first omitted terms are below `2^-60 / 720` and `2^-60 / 5040` relative, far below
/// rounding. Both are one expression, `w = u + u z (k_0 + z k_1)` with `z = x^2` and
/// `u = c`, `k = (-1/2, 1/24)` or `u = x`, `k = (-1/6, 1/120)`, then `c - w` where
/// `c = 0`: a dozen operations an entry where the sine and the cosine both would take
/// twice that. `c + c w` is `c (1 + w)` exactly for `c = +-1`, and `c - sin x` keeps
/// the general path's `c cos x - sin x` signed zeros.
#[inline(always)]
pub fn cos_sum_aligned_tiny<const N: usize>(c: &[f64; N], x: &[f64; N]) -> [f64; N] {
    let mut out = [0.0; N];
    // Selections by bit masks: `if`s here became a branch per entry.
    let pick = |m: u64, a: f64, b: f64| f64::from_bits((a.to_bits() & m) | (b.to_bits() & !m));
    for k in 0..N {
        let zero = ((c[k] == 0.0) as u64).wrapping_neg();
        let u = pick(zero, x[k], c[k]);
        let (k0, k1) = (pick(zero, S[0], C[0]), pick(zero, S[1], C[1]));
        let z = x[k] * x[k];
        let w = u + u * z * (k0 + z * k1);
        out[k] = pick(zero, c[k] - w, w);
    }
    out
}

/// Angles with `|x| <= 0.78` (just inside `pi/4`) reduce to themselves: `x (2/pi)` is
/// at most 0.4966 after rounding, so `k = 0`, `r = (x - 0) - 0 = x` (signed zeros
/// kept) and the quadrant is 0. The AVX-512 lanes skip the reduction when every lane
/// is within it (a hexapod's A, B, C), with the same bits.
#[cfg(target_arch = "x86_64")]
const FIRST_OCTANT: f64 = 0.78;

/// `c_0 + c_1 z + ... + c_6 z^6` by Estrin's scheme (`z2 = z^2`, `z4 = z^4`): pairs,
/// then pairs of pairs, three multiply-add levels deep where Horner's rule is six; the
/// AVX-512 kernel makes the same (fused) operations in the same order.
#[inline(always)]
fn estrin7<M: MulAdd>(z: f64, z2: f64, z4: f64, c: &[f64; 7]) -> f64 {
    let (p0, p1, p2) = (
        M::mul_add(z, c[1], c[0]),
        M::mul_add(z, c[3], c[2]),
        M::mul_add(z, c[5], c[4]),
    );
    M::mul_add(z4, M::mul_add(z2, c[6], p2), M::mul_add(z2, p1, p0))
}

/// The branch-free kernel for `|x| <= 1e4`, its multiply-adds by `M`: `y = x 2/pi +
/// 1.5 2^52`, `r = x - k pio2_hi - k pio2_lo`, `s = r + (r z) P_s(z)`, `c = 1 + z (C_0 +
/// z P_c(z))`.
#[inline(always)]
fn kernel<M: MulAdd>(x: f64) -> (f64, f64) {
    let y = M::mul_add(x, TWO_OVER_PI, MAGIC);
    let q = y.to_bits();
    let k = y - MAGIC;
    let r = M::sub_mul(k, PIO2_LO, M::sub_mul(k, PIO2_HI, x));
    let z = r * r;
    let z2 = z * z;
    let z4 = z2 * z2;
    let ps = estrin7::<M>(z, z2, z4, &S);
    let s = M::mul_add(r * z, ps, r);
    let pc = estrin7::<M>(z, z2, z4, &[C[1], C[2], C[3], C[4], C[5], C[6], C[7]]);
    let c = M::mul_add(z, M::mul_add(z, pc, C[0]), 1.0);
    // Quadrant q mod 4: (s, c), (c, -s), (-s, -c), (-c, s), without branches: swap by
    // a select, signs by flipping the sign bit.
    let swap = q & 1 == 1;
    let (a, b) = (if swap { c } else { s }, if swap { s } else { c });
    let sa = (q & 2) << 62;
    let sb = ((q + 1) & 2) << 62;
    (
        f64::from_bits(a.to_bits() ^ sa),
        f64::from_bits(b.to_bits() ^ sb),
    )
}

/// The fused kernel on eight lanes of AVX-512 (the hexapod's block kernel calls it from
/// its own AVX-512 code).
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx512 {
    use std::arch::x86_64::*;

    use super::{C, MAGIC, PIO2_HI, PIO2_LO, S, TWO_OVER_PI};

    /// `((sin x, cos x), in range)` by lane: [`super::sin_cos`]'s kernel, the same
    /// operations in the same order (so equal to it bit for bit), and the mask of lanes
    /// within its range `|x| <= 1e4` (the others, NaN included, are not cleared). When
    /// every lane is within [`super::FIRST_OCTANT`] the reduction, the identity there,
    /// is skipped: a shorter chain for a hexapod's angles, the same bits.
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub(crate) fn sin_cos(x: __m512d) -> ((__m512d, __m512d), u8) {
        let c = |v: f64| _mm512_set1_pd(v);
        let ax = _mm512_abs_pd(x);
        if _mm512_cmp_pd_mask::<_CMP_LE_OQ>(ax, c(super::FIRST_OCTANT)) == 0xff {
            // Every lane in the first octant: the reduction is the identity (k = 0,
            // r = x, quadrant 0), so skipping it changes no bit.
            return (series(x), 0xff);
        }
        let in_range = _mm512_cmp_pd_mask::<_CMP_LE_OQ>(ax, c(1e4));
        let y = _mm512_fmadd_pd(x, c(TWO_OVER_PI), c(MAGIC));
        let q = _mm512_castpd_si512(y);
        let k = _mm512_sub_pd(y, c(MAGIC));
        let r = _mm512_fnmadd_pd(k, c(PIO2_LO), _mm512_fnmadd_pd(k, c(PIO2_HI), x));
        let (sn, cs) = series(r);
        let swap = _mm512_test_epi64_mask(q, _mm512_set1_epi64(1));
        let (a, b) = (
            _mm512_mask_blend_pd(swap, sn, cs),
            _mm512_mask_blend_pd(swap, cs, sn),
        );
        let two = _mm512_set1_epi64(2);
        let sa = _mm512_slli_epi64::<62>(_mm512_and_si512(q, two));
        let sb = _mm512_slli_epi64::<62>(_mm512_and_si512(
            _mm512_add_epi64(q, _mm512_set1_epi64(1)),
            two,
        ));
        let flip = |v: __m512d, sign: __m512i| {
            _mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(v), sign))
        };
        ((flip(a, sa), flip(b, sb)), in_range)
    }

    /// The series of sine and cosine on the reduced argument `r` (`|r| <= pi/4`), as
    /// the scalar kernel evaluates them.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn series(r: __m512d) -> (__m512d, __m512d) {
        let c = |v: f64| _mm512_set1_pd(v);
        let mul = |a: __m512d, b: __m512d| _mm512_mul_pd(a, b);
        let z = mul(r, r);
        let z2 = mul(z, z);
        let z4 = mul(z2, z2);
        // `super::estrin7`, the same operations in the same order.
        let fma = |a: __m512d, b: __m512d, d: __m512d| _mm512_fmadd_pd(a, b, d);
        let estrin = |k: &[f64]| {
            let pair = |j: usize| fma(z, c(k[j + 1]), c(k[j]));
            let (p0, p1, p2) = (pair(0), pair(2), pair(4));
            fma(z4, fma(z2, c(k[6]), p2), fma(z2, p1, p0))
        };
        let ps = estrin(&S);
        let sn = fma(mul(r, z), ps, r);
        let pc = estrin(&C[1..]);
        let cs = fma(z, fma(z, pc, c(C[0])), c(1.0));
        (sn, cs)
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn array_matches_scalar_and_falls_back_beyond_range() {
        let x = [0.3, -2.0, 7.5, 1e3, -1e4, 0.0, 3.0, -0.7];
        let (s, c) = super::sin_cos_array(&x);
        for k in 0..x.len() {
            assert_eq!((s[k], c[k]), super::sin_cos(x[k]));
        }
        let y = [0.3, 1e6];
        let (s, c) = super::sin_cos_array(&y);
        assert_eq!((s[1], c[1]), 1e6f64.sin_cos());
        assert_eq!((s[0], c[0]), 0.3f64.sin_cos());
    }

    #[test]
    fn matches_std_within_two_ulp() {
        let (mut worst, mut worst_inline): (f64, f64) = (0.0, 0.0);
        let n = 1_000_000;
        for i in 0..=n {
            let x = -20.0 + 40.0 * i as f64 / n as f64;
            let (s, c) = super::sin_cos(x);
            let (si, ci) = super::sin_cos_array_inline(&[x]);
            let (s0, c0) = x.sin_cos();
            // Relative to the value, or absolute near zero crossings.
            let ulp = |v: f64| (v.abs().max(1e-3)) * f64::EPSILON;
            worst = worst
                .max((s - s0).abs() / ulp(s0))
                .max((c - c0).abs() / ulp(c0));
            worst_inline = worst_inline
                .max((si[0] - s0).abs() / ulp(s0))
                .max((ci[0] - c0).abs() / ulp(c0));
        }
        assert!(worst <= 2.0, "fused: {worst} ulp");
        assert!(worst_inline <= 2.0, "separate: {worst_inline} ulp");
        for x in [3e4, -1e5, 1e300] {
            assert_eq!(super::sin_cos(x), x.sin_cos());
        }
        let (s, c) = super::sin_cos(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
    }

    /// The fused kernel gives the same bits whichever way its multiply-adds are made:
    /// compiled with FMA enabled (what [`super::sin_cos_array`] runs on a CPU with it)
    /// and through libm's `fma` (this test function is compiled for the baseline
    /// target, so `f64::mul_add` here is the call a CPU without FMA makes); and the
    /// separate kernel stays within an ulp or two of it.
    #[test]
    fn fused_kernel_has_the_same_bits_with_and_without_the_instruction() {
        let xs: Vec<f64> = angles_up_to(40.0).collect();
        let mut differ = 0;
        for x in xs.chunks_exact(4) {
            let x: &[f64; 4] = x.try_into().unwrap();
            let (s, c) = super::sin_cos_array(x);
            let (sl, cl) = super::sin_cos_array_by::<super::Fused, 4>(x);
            let (si, ci) = super::sin_cos_array_inline(x);
            for k in 0..4 {
                assert_eq!(
                    (s[k].to_bits(), c[k].to_bits()),
                    (sl[k].to_bits(), cl[k].to_bits()),
                    "{:e}",
                    x[k]
                );
                assert_eq!(super::sin_cos(x[k]), (s[k], c[k]));
                let ulp = |v: f64| v.abs().max(1e-3) * f64::EPSILON;
                assert!((si[k] - s[k]).abs() <= 2.0 * ulp(s[k]), "{:e}", x[k]);
                assert!((ci[k] - c[k]).abs() <= 2.0 * ulp(c[k]), "{:e}", x[k]);
                differ += usize::from(si[k] != s[k] || ci[k] != c[k]);
            }
        }
        // The two really are different evaluations (else this test proves nothing).
        assert!(differ > 1000, "{differ}");
    }

    /// The short series of small angles: within one unit in the last place of libm's
    /// (relative, or absolute near zero), both signs, up to the bound; beyond it, the
    /// kernel's values exactly.
    #[test]
    fn small_angles_match_std_within_one_ulp() {
        let mut worst: f64 = 0.0;
        for x in angles_up_to(super::SMALL) {
            let (s, c) = super::sin_cos_small(&[x, -x, 0.0]);
            let (s0, c0) = x.sin_cos();
            let ulp = |v: f64| v.abs().max(f64::MIN_POSITIVE) * f64::EPSILON;
            worst = worst
                .max((s[0] - s0).abs() / ulp(s0))
                .max((s[1] + s0).abs() / ulp(s0))
                .max((c[0] - c0).abs() / ulp(c0));
            assert_eq!((s[2], c[2]), (0.0, 1.0));
        }
        assert!(worst <= 1.0, "{worst} ulp");
        let big = [0.1, 1e-3];
        assert_eq!(
            super::sin_cos_small(&big),
            super::sin_cos_array_inline(&big)
        );
    }

    /// Aligned links' tiny deviations: `c cos x` and `-sin x` within one unit in the
    /// last place of libm's, both signs of `c` and `x`, zero exactly kept; and equal
    /// to the longer series' `c cos x - (1 - |c|) sin x` (the general path) to one
    /// unit in the last place.
    #[test]
    fn aligned_tiny_deviations_match_std_within_one_ulp() {
        let mut worst: f64 = 0.0;
        let mut worst_series: f64 = 0.0;
        let ulp = |v: f64| v.abs().max(f64::MIN_POSITIVE) * f64::EPSILON;
        for x in angles_up_to(super::TINY) {
            let c = [1.0, -1.0, 0.0, -0.0, 1.0, 0.0, -0.0, 0.0];
            let a = [x, x, x, x, 0.0, 0.0, 0.0, -0.0];
            let got = super::cos_sum_aligned_tiny(&c, &a);
            let (s0, c0) = x.sin_cos();
            let want = [c0, -c0, -s0, -s0];
            for k in 0..4 {
                worst = worst.max((got[k] - want[k]).abs() / ulp(want[k]));
            }
            let (ss, cs) = super::sin_cos_small(&a);
            for k in 0..8 {
                let general = c[k] * cs[k] - (1.0 - c[k].abs()) * ss[k];
                worst_series = worst_series.max((got[k] - general).abs() / ulp(general));
                if general == 0.0 {
                    // Zeros with the general path's sign.
                    assert_eq!(got[k].to_bits(), general.to_bits(), "{k} at {x}");
                }
            }
            assert_eq!(got[4], 1.0);
        }
        assert!(worst <= 1.0, "{worst} ulp from libm");
        assert!(
            worst_series <= 1.0,
            "{worst_series} ulp from the longer series"
        );
    }

    /// Angles within `bound`: evenly over it, near zero, and denser near zero.
    fn angles_up_to(bound: f64) -> impl Iterator<Item = f64> {
        let n = 200_000;
        (0..=n).flat_map(move |i| {
            let t = i as f64 / n as f64;
            [
                bound * (2.0 * t - 1.0),
                1e-12 * (2.0 * t - 1.0),
                bound * t * t,
            ]
        })
    }

    /// The AVX-512 kernel on eight lanes, stored: `(sin, cos, in range)`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn lanes(x: &[f64; 8]) -> ([f64; 8], [f64; 8], u8) {
        use std::arch::x86_64::*;
        // SAFETY: 8 f64 loaded from and stored to arrays of 8.
        unsafe {
            let ((s, c), m) = super::avx512::sin_cos(_mm512_loadu_pd(x.as_ptr()));
            let (mut so, mut co) = ([0.0; 8], [0.0; 8]);
            _mm512_storeu_pd(so.as_mut_ptr(), s);
            _mm512_storeu_pd(co.as_mut_ptr(), c);
            (so, co, m)
        }
    }

    /// Every block of eight of `xs` in range, and equal to the scalar kernel lane by
    /// lane, bit for bit.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    fn assert_lanes_equal_the_kernel(xs: &[f64]) {
        for x in xs.chunks_exact(8) {
            let (s, c, m) = lanes(x.try_into().unwrap());
            assert_eq!(m, 0xff);
            for l in 0..8 {
                let (s0, c0) = super::kernel::<super::Fused>(x[l]);
                assert_eq!(
                    (s[l].to_bits(), c[l].to_bits()),
                    (s0.to_bits(), c0.to_bits()),
                    "{:e}",
                    x[l]
                );
            }
        }
    }

    /// Blocks of eight angles all within the first octant (where the lanes skip the
    /// reduction), to its bound and just past it, signed zeros and subnormals
    /// included: equal to the scalar kernel, which reduces, bit for bit. A block with
    /// one lane past the bound takes the reducing path, equal as well.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx512_first_octant_equals_the_reducing_kernel() {
        if !std::arch::is_x86_feature_detected!("avx512f") {
            return;
        }
        let b = super::FIRST_OCTANT;
        let mut xs: Vec<f64> = (0..80_000)
            .map(|i| -b + 2.0 * b * i as f64 / 79_999.0)
            .collect();
        xs.extend([
            0.0,
            -0.0,
            5e-324,
            -5e-324,
            1e-300,
            b,
            -b,
            f64::from_bits(b.to_bits() - 1),
            1e-8,
            -0.5,
            0.3,
            0.78,
            -0.77,
            0.1,
            0.2,
            0.4,
        ]);
        while !xs.len().is_multiple_of(8) {
            xs.push(0.25);
        }
        // The last block has a lane past the bound (pi/4 + 1e-3), the others not.
        xs.extend([
            0.1,
            0.2,
            0.3,
            std::f64::consts::FRAC_PI_4 + 1e-3,
            -0.1,
            0.0,
            b,
            -b,
        ]);
        // SAFETY: the CPU has AVX-512F (checked above).
        unsafe { assert_lanes_equal_the_kernel(&xs) };
    }

    /// The AVX-512 lanes equal the scalar kernel bit for bit over 2e4 rad (both signs,
    /// the quadrant boundaries, zero), and flag what is out of its range (NaN, beyond
    /// 1e4 rad, infinities).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx512_lanes_equal_the_scalar_kernel() {
        if !std::arch::is_x86_feature_detected!("avx512f") {
            return;
        }
        let pio2 = std::f64::consts::FRAC_PI_2;
        let mut xs: Vec<f64> = (0..200_000).map(|i| -1e4 + 0.1 * i as f64 + 1e-3).collect();
        xs.extend((-40..40).flat_map(|k| {
            [
                k as f64 * pio2,
                f64::from_bits((k as f64 * pio2).to_bits() + 1),
            ]
        }));
        xs.extend([0.0, -0.0, 1e4, -1e4]);
        while !xs.len().is_multiple_of(8) {
            xs.push(0.5);
        }
        // SAFETY: as above.
        unsafe { assert_lanes_equal_the_kernel(&xs) };
        let odd = [f64::NAN, 1.0001e4, -2e4, f64::INFINITY, 0.3, 1.0, 2.0, 3.0];
        // SAFETY: as above.
        let (_, _, m) = unsafe { lanes(&odd) };
        assert_eq!(m, 0b1111_0000);
    }
}
