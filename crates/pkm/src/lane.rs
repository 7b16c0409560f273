//! One formula for scalar and SIMD paths: the arithmetic a shared formula needs, on
//! `f64` and (on x86-64) on an AVX-512 register of eight values, so a kernel that runs
//! eight poses per register computes, lane by lane, exactly what the scalar code does.
//!
//! Every operation is one IEEE operation with one rounding (Rust never contracts
//! `a * b + c`; a fused multiply-add is asked for by name, [`Lane::mul_add`], and is
//! one rounding on either type), so a formula written once over [`Lane`] gives the
//! same bits on either type; the tests of the kernels that use it check that.

// Lanes are indexed together.
#![allow(clippy::needless_range_loop)]

/// The arithmetic of a formula shared by scalar and SIMD code.
pub(crate) trait Lane: Copy {
    fn add(self, o: Self) -> Self;
    fn sub(self, o: Self) -> Self;
    fn mul(self, o: Self) -> Self;
    fn div(self, o: Self) -> Self;
    fn sqrt(self) -> Self;
    /// `-self` (the sign bit flipped, as `-x` on `f64`: `-0.0` from `0.0`).
    fn neg(self) -> Self;
    /// `self * a + b` with one rounding.
    fn mul_add(self, a: Self, b: Self) -> Self;
}

impl Lane for f64 {
    #[inline(always)]
    fn add(self, o: f64) -> f64 {
        self + o
    }
    #[inline(always)]
    fn sub(self, o: f64) -> f64 {
        self - o
    }
    #[inline(always)]
    fn mul(self, o: f64) -> f64 {
        self * o
    }
    #[inline(always)]
    fn div(self, o: f64) -> f64 {
        self / o
    }
    #[inline(always)]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn neg(self) -> f64 {
        -self
    }
    #[inline(always)]
    fn mul_add(self, a: f64, b: f64) -> f64 {
        f64::mul_add(self, a, b)
    }
}

/// Eight doubles, the lanes of an AVX-512 register. The operations are plain loops
/// over the lanes: inlined into a function compiled with AVX-512F enabled, each becomes
/// one 512-bit instruction (the intrinsics themselves cannot be called from a trait
/// method, which cannot enable the feature, without a function call per operation).
///
/// The type is [`Lanes`] of any width: four lanes are one AVX2 register, so a kernel
/// on them keeps twice as many values in AVX2's sixteen registers.
#[cfg(target_arch = "x86_64")]
pub(crate) type Zmm = Lanes<8>;

/// `N` doubles operated on lane by lane ([`Zmm`]: eight).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
#[repr(C, align(32))]
pub(crate) struct Lanes<const N: usize>(pub [f64; N]);

#[cfg(target_arch = "x86_64")]
impl Zmm {
    /// The lanes of a register.
    #[inline(always)]
    pub(crate) fn of(v: std::arch::x86_64::__m512d) -> Zmm {
        // SAFETY: both are eight f64 (64 bytes), any bits valid.
        Lanes(unsafe { std::mem::transmute::<std::arch::x86_64::__m512d, [f64; 8]>(v) })
    }

    /// The register of the lanes.
    #[inline(always)]
    pub(crate) fn reg(self) -> std::arch::x86_64::__m512d {
        // SAFETY: as in `of`.
        unsafe { std::mem::transmute::<[f64; 8], std::arch::x86_64::__m512d>(self.0) }
    }
}

#[cfg(target_arch = "x86_64")]
impl<const N: usize> Lanes<N> {
    /// `f` lane by lane (a plain loop: `std::array::from_fn` and `map`, generic
    /// functions compiled without the caller's instructions, are not always inlined into
    /// a large kernel, whose lanes then leave the registers).
    #[inline(always)]
    fn zip(self, o: Self, f: impl Fn(f64, f64) -> f64) -> Self {
        let mut r = [0.0; N];
        for k in 0..N {
            r[k] = f(self.0[k], o.0[k]);
        }
        Lanes(r)
    }

    /// `f` lane by lane, one operand.
    #[inline(always)]
    fn each(self, f: impl Fn(f64) -> f64) -> Self {
        let mut r = [0.0; N];
        for k in 0..N {
            r[k] = f(self.0[k]);
        }
        Lanes(r)
    }
}

/// Comparisons, selections and bounds by lane, for the screens of the lane kernels:
/// plain loops that the instructions of the caller's function make one or two vector
/// operations of (a mask is bit `k` for lane `k`).
#[cfg(target_arch = "x86_64")]
impl<const N: usize> Lanes<N> {
    /// The mask of lanes where `f(self, o)` (`N <= 8`).
    #[inline(always)]
    fn mask(self, o: Self, f: impl Fn(f64, f64) -> bool) -> u8 {
        let mut m = 0u8;
        for k in 0..N {
            m |= u8::from(f(self.0[k], o.0[k])) << k;
        }
        m
    }
    /// The lanes where `self >= o` (false where either is NaN).
    #[inline(always)]
    pub(crate) fn ge(self, o: Self) -> u8 {
        self.mask(o, |a, b| a >= b)
    }
    /// The lanes where `self <= o` (false where either is NaN).
    #[inline(always)]
    pub(crate) fn le(self, o: Self) -> u8 {
        self.mask(o, |a, b| a <= b)
    }
    /// The lanes where `self > o` (false where either is NaN).
    #[inline(always)]
    pub(crate) fn gt(self, o: Self) -> u8 {
        self.mask(o, |a, b| a > b)
    }
    /// The lanes where `self < o` (false where either is NaN).
    #[inline(always)]
    pub(crate) fn lt(self, o: Self) -> u8 {
        self.mask(o, |a, b| a < b)
    }
    /// `o` where `m` has the lane, else `self` (as `_mm512_mask_blend_pd(m, self, o)`).
    #[inline(always)]
    pub(crate) fn blend(self, m: u8, o: Self) -> Self {
        let mut r = self.0;
        for k in 0..N {
            if m >> k & 1 == 1 {
                r[k] = o.0[k];
            }
        }
        Lanes(r)
    }
    /// `self` clamped to `[0, 1]` as `min(max(self, 0), 1)` of the SSE instructions
    /// (`max(NaN, 0)` is 0).
    #[inline(always)]
    pub(crate) fn clamp01(self) -> Self {
        let max = |a: f64, b: f64| if a > b { a } else { b };
        let min = |a: f64, b: f64| if a < b { a } else { b };
        self.each(|a| min(max(a, 0.0), 1.0))
    }
    /// The lanewise minimum and maximum of two lanes, as `_mm512_min_pd`/`max_pd`
    /// (the second operand where either is NaN).
    #[inline(always)]
    pub(crate) fn min_max(self, o: Self) -> (Self, Self) {
        (
            self.zip(o, |a, b| if a < b { a } else { b }),
            self.zip(o, |a, b| if a > b { a } else { b }),
        )
    }
}

#[cfg(target_arch = "x86_64")]
impl<const N: usize> From<f64> for Lanes<N> {
    #[inline(always)]
    fn from(v: f64) -> Self {
        Lanes([v; N])
    }
}

#[cfg(target_arch = "x86_64")]
impl<const N: usize> Lane for Lanes<N> {
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self.zip(o, |a, b| a + b)
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self.zip(o, |a, b| a - b)
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self.zip(o, |a, b| a * b)
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self.zip(o, |a, b| a / b)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        self.each(f64::sqrt)
    }
    #[inline(always)]
    fn neg(self) -> Self {
        self.each(|a| -a)
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        let mut r = [0.0; N];
        for k in 0..N {
            r[k] = f64::mul_add(self.0[k], a.0[k], b.0[k]);
        }
        Lanes(r)
    }
}

/// `sqrt(x)` by lane (`x > 0`) without the square-root unit: `y ~ 1/sqrt(x)` by the
/// 14-bit estimate and one Newton step `y (1.5 - 0.5 x y^2)` (28 bits), then
/// `l = x y` and one Heron step `l + (x - l^2) y / 2` (56 bits). The hexapod's strut
/// lengths and the lanes' Jacobi rotations take their square roots from it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
#[inline]
pub(crate) fn sqrt_refined(x: std::arch::x86_64::__m512d) -> std::arch::x86_64::__m512d {
    use std::arch::x86_64::*;
    let b = |v: f64| _mm512_set1_pd(v);
    let half = _mm512_mul_pd(x, b(0.5));
    let y0 = _mm512_rsqrt14_pd(x);
    let yy = _mm512_mul_pd(y0, y0);
    let y = _mm512_mul_pd(y0, _mm512_fnmadd_pd(half, yy, b(1.5)));
    let l = _mm512_mul_pd(x, y);
    let e = _mm512_fnmadd_pd(l, l, x);
    _mm512_fmadd_pd(e, _mm512_mul_pd(y, b(0.5)), l)
}
