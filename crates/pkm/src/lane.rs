//! One formula for scalar and SIMD paths: the arithmetic a shared formula needs, on
//! `f64` and (on x86-64) on an AVX-512 register of eight values, so a kernel that runs
//! eight poses per register computes, lane by lane, exactly what the scalar code does.
//!
//! Every operation is one IEEE operation with one rounding (Rust never contracts
//! `a * b + c`; a fused multiply-add is asked for by name, [`Lane::mul_add`], and is
//! one rounding on either type), so a formula written once over [`Lane`] gives the
//! same bits on either type; the tests of the kernels that use it check that.

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
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
#[repr(C, align(64))]
pub(crate) struct Zmm(pub [f64; 8]);

#[cfg(target_arch = "x86_64")]
impl Zmm {
    /// The lanes of a register.
    #[inline(always)]
    pub(crate) fn of(v: std::arch::x86_64::__m512d) -> Zmm {
        // SAFETY: both are eight f64 (64 bytes), any bits valid.
        Zmm(unsafe { std::mem::transmute::<std::arch::x86_64::__m512d, [f64; 8]>(v) })
    }

    /// The register of the lanes.
    #[inline(always)]
    pub(crate) fn reg(self) -> std::arch::x86_64::__m512d {
        // SAFETY: as in `of`.
        unsafe { std::mem::transmute::<[f64; 8], std::arch::x86_64::__m512d>(self.0) }
    }

    /// `f` lane by lane.
    #[inline(always)]
    fn zip(self, o: Zmm, f: impl Fn(f64, f64) -> f64) -> Zmm {
        Zmm(std::array::from_fn(|k| f(self.0[k], o.0[k])))
    }
}

#[cfg(target_arch = "x86_64")]
impl From<f64> for Zmm {
    #[inline(always)]
    fn from(v: f64) -> Zmm {
        Zmm([v; 8])
    }
}

#[cfg(target_arch = "x86_64")]
impl Lane for Zmm {
    #[inline(always)]
    fn add(self, o: Zmm) -> Zmm {
        self.zip(o, |a, b| a + b)
    }
    #[inline(always)]
    fn sub(self, o: Zmm) -> Zmm {
        self.zip(o, |a, b| a - b)
    }
    #[inline(always)]
    fn mul(self, o: Zmm) -> Zmm {
        self.zip(o, |a, b| a * b)
    }
    #[inline(always)]
    fn div(self, o: Zmm) -> Zmm {
        self.zip(o, |a, b| a / b)
    }
    #[inline(always)]
    fn sqrt(self) -> Zmm {
        Zmm(self.0.map(f64::sqrt))
    }
    #[inline(always)]
    fn neg(self) -> Zmm {
        Zmm(self.0.map(|a| -a))
    }
    #[inline(always)]
    fn mul_add(self, a: Zmm, b: Zmm) -> Zmm {
        Zmm(std::array::from_fn(|k| {
            f64::mul_add(self.0[k], a.0[k], b.0[k])
        }))
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
