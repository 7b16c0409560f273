//! Inverse kinematics of many poses eight at a time, with a conservative limit screen
//! (what [`crate::mechanism::BlockKernels::inverse_screened`] asks of a hexapod).
//!
//! The poses of a block are transposed into lanes, so everything vectorises over
//! poses: the sines and cosines of A, B, C ([`crate::trig::sin_cos_array`], the same
//! kernel as [`crate::rotation::rpy_matrix`]), the rotation, the six strut vectors
//! `d_i = p + R arm_i - a_i` and lengths `L_i = |d_i|` (seed 001 eq. 1, the operations
//! of the single pose's AVX-512 kernel, so equal to [`super::Hexapod::lengths`] bit for
//! bit), and every limit of [`super::Hexapod::scan`] as a comparison without division:
//!
//! - axis travel `lo_k <= x_k <= hi_k`;
//! - strut length `lo_i <= L_i <= hi_i`;
//! - base cone `d_i . w_i >= cos(max) L_i` (`w_i` the cone's axis);
//! - platform cone `-d_i . (R w'_i) >= cos(max) L_i`;
//! - strut pairs: bounding boxes apart by the strut diameter along X, Y or Z, else the
//!   lines' distance, else the distance of the segments `a_i -> a_i + d_i` (the closest points
//!   by the clamped parameters of [`super::segment_distance`], with selects instead of
//!   branches) at least the strut diameter.
//!
//! A pose is *cleared* only when every test holds with a relative margin of
//! [`MARGIN`], so a pose the screen clears is within every limit by the exact scan as
//! well; the others (outside, at a boundary, nearly parallel struts, angles beyond the
//! fast sine's range, NaN) are left to the exact per-pose path, which names the first
//! violated limit. The screen changes no result, only which code computes it (tested
//! row by row against the per-pose path).

// Struts, pairs and lanes are indexed together.
#![allow(clippy::needless_range_loop)]

use super::Hexapod;

/// Poses per block (one AVX-512 register of doubles, two AVX2 ones).
pub(crate) const LANES: usize = 8;

/// Relative margin of every screened test: far above the rounding differences between
/// the screen's arithmetic and the exact scan's (a few units in the last place), far
/// below any tolerance a user states.
pub(crate) const MARGIN: f64 = 1e-9;

/// Segments closer to parallel than this (`1 - cos^2` of their angle) are left to the
/// exact path: the closest points of nearly parallel segments are ill-conditioned.
pub(super) const PARALLEL: f64 = 1e-6;

/// The limits of one hexapod laid out for the screen (built per call from the
/// machine's public fields, so it cannot go stale when a caller edits them).
pub(crate) struct Screen {
    /// Arms `R`-free: `b'_i - t` (platform frame) and base joints `a_i`, by component.
    pub(super) arm: [[f64; 6]; 3],
    pub(super) base: [[f64; 6]; 3],
    /// Axis travel by pose coordinate (infinite where unlimited).
    pub(super) axis: [(f64, f64); 6],
    /// Strut length range by strut.
    pub(super) length: [(f64, f64); 6],
    /// Base cone axis and `cos(max)` by strut (`cos = -inf`: no cone).
    pub(super) base_cone: [([f64; 3], f64); 6],
    /// Platform cone axis (platform frame) and `cos(max)` by strut.
    pub(super) platform_cone: [([f64; 3], f64); 6],
    /// Strut pairs checked for interference, and the strut diameter.
    pub(super) pairs: Vec<(usize, usize)>,
    pub(super) diameter: f64,
    /// Every arm's z is exactly 0: the strut vectors need no `R_k2 a_z` term
    /// ([`super::simd::strut_component`]'s `PLANAR`).
    planar: bool,
    /// The CPU has AVX-512F (the hexapod's one detection, `simd.rs`).
    avx512: bool,
    /// The level is AVX2 with FMA: the portable lanes' kernel (`block_lanes.rs`).
    avx2: bool,
}

impl Screen {
    pub(crate) fn new(h: &Hexapod) -> Self {
        let set = &h.set;
        let avx512 = h.simd_lengths();
        let mut axis = [(f64::NEG_INFINITY, f64::INFINITY); 6];
        for (k, r) in &h.axes.ranges {
            if let Some(a) = axis.get_mut(*k) {
                // Two ranges on one coordinate: both apply.
                *a = (a.0.max(r.min), a.1.min(r.max));
            }
        }
        let cone = |c: &Option<super::JointCone>| match c {
            Some(c) => ([c.axis.x, c.axis.y, c.axis.z], c.cos_max()),
            None => ([0.0; 3], f64::NEG_INFINITY),
        };
        let pairs = match h.strut_diameter {
            Some(_) => (0..6)
                .flat_map(|i| (i + 1..6).map(move |k| (i, k)))
                .filter(|&(i, k)| !h.shares[i][k])
                .collect(),
            None => Vec::new(),
        };
        Screen {
            planar: set.arms.iter().all(|a| a.z == 0.0),
            arm: std::array::from_fn(|c| std::array::from_fn(|i| set.arms[i][c])),
            base: std::array::from_fn(|c| std::array::from_fn(|i| set.base[i][c])),
            axis,
            length: std::array::from_fn(|i| {
                let r = &h.struts[i].actuator.range;
                (r.min, r.max)
            }),
            base_cone: std::array::from_fn(|i| cone(&h.struts[i].base_cone)),
            platform_cone: std::array::from_fn(|i| cone(&h.struts[i].platform_cone)),
            pairs,
            diameter: h.strut_diameter.unwrap_or(0.0),
            avx512,
            avx2: h.lanes.avx2,
        }
    }

    /// Whether the CPU has AVX-512F (the kernels run).
    pub(super) fn avx512(&self) -> bool {
        self.avx512
    }
}

/// Lengths of the rows of `xs` (row-major X, Y, Z, A, B, C) into `qs` (row-major, six
/// per row), and `clear[i]` set where row `i` is certainly within every limit (with
/// `check`; without it, where its angles are within the fast sine's range, so its
/// lengths are the single call's). Rows past the last whole block are not cleared.
/// Returns `false` (nothing written) below the AVX2 level ([`crate::simd::level`]),
/// whose callers take the per-pose path.
pub(crate) fn screen_rows(
    s: &Screen,
    xs: &[f64],
    qs: &mut [f64],
    clear: &mut [bool],
    check: bool,
) -> bool {
    if s.planar {
        screen_rows_with::<true>(s, xs, qs, clear, check)
    } else {
        screen_rows_with::<false>(s, xs, qs, clear, check)
    }
}

/// [`screen_rows`] with the kernel for planar arms or not (`PLANAR`, as in
/// [`super::simd::strut_component`]).
fn screen_rows_with<const PLANAR: bool>(
    s: &Screen,
    xs: &[f64],
    qs: &mut [f64],
    clear: &mut [bool],
    check: bool,
) -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        if s.avx512 {
            let n = clear.len();
            let blocks = n / LANES;
            let whole = "whole blocks";
            if check {
                // One block per call: the limit screen's registers leave no room for a
                // second block's.
                let rows = xs
                    .chunks_exact(6 * LANES)
                    .zip(qs.chunks_exact_mut(6 * LANES));
                for ((x, q), c) in rows.zip(clear.chunks_exact_mut(LANES)) {
                    let (x, q) = (x.try_into().expect(whole), q.try_into().expect(whole));
                    // SAFETY: `avx512` is the hexapod's detection of AVX-512F, the one
                    // feature the kernel enables.
                    set_clear(c, &unsafe {
                        avx512::blocks::<1, true, PLANAR>(s, [x], [q])
                    });
                }
            } else {
                // Two blocks per call, interleaved step by step (`avx512::blocks`), then
                // the odd one.
                let pairs = xs[..6 * LANES * (blocks - blocks % 2)]
                    .chunks_exact(12 * LANES)
                    .zip(qs.chunks_exact_mut(12 * LANES))
                    .zip(clear.chunks_exact_mut(2 * LANES));
                for ((x, q), c) in pairs {
                    let (x0, x1) = x.split_at(6 * LANES);
                    let (q0, q1) = q.split_at_mut(6 * LANES);
                    let xs = [x0.try_into().expect(whole), x1.try_into().expect(whole)];
                    let qs = [q0.try_into().expect(whole), q1.try_into().expect(whole)];
                    // SAFETY: as above.
                    set_clear(c, &unsafe { avx512::blocks::<2, false, PLANAR>(s, xs, qs) });
                }
                if blocks % 2 == 1 {
                    let r0 = (blocks - 1) * LANES;
                    let x = xs[6 * r0..6 * (r0 + LANES)].try_into().expect(whole);
                    let q = (&mut qs[6 * r0..6 * (r0 + LANES)]).try_into().expect(whole);
                    // SAFETY: as above.
                    let masks = unsafe { avx512::blocks::<1, false, PLANAR>(s, [x], [q]) };
                    set_clear(&mut clear[r0..r0 + LANES], &masks);
                }
            }
            clear[blocks * LANES..].fill(false);
            return true;
        }
    }
    #[cfg(target_arch = "x86_64")]
    {
        if s.avx2 {
            let rows = xs
                .chunks_exact(6 * LANES)
                .zip(qs.chunks_exact_mut(6 * LANES));
            for ((x, q), c) in rows.zip(clear.chunks_exact_mut(LANES)) {
                let whole = "whole blocks";
                let (x, q) = (x.try_into().expect(whole), q.try_into().expect(whole));
                // SAFETY: `avx2` is set only at the AVX2 level, which a CPU with AVX2
                // and FMA alone reaches (`crate::simd::level`).
                let mask = unsafe {
                    if check {
                        super::block_lanes::block_avx2::<true, PLANAR>(s, x, q)
                    } else {
                        super::block_lanes::block_avx2::<false, PLANAR>(s, x, q)
                    }
                };
                set_clear(c, &[mask]);
            }
            let n = clear.len();
            clear[n / LANES * LANES..].fill(false);
            return true;
        }
    }
    let _ = (s, xs, qs, clear, check);
    false
}

/// `clear` (the rows of consecutive blocks) from the blocks' lane masks: row `r` is
/// lane `r % LANES` of block `r / LANES`.
fn set_clear(clear: &mut [bool], masks: &[u8]) {
    for (r, c) in clear.iter_mut().enumerate() {
        *c = masks[r / LANES] & (1 << (r % LANES)) != 0;
    }
}

#[cfg(target_arch = "x86_64")]
pub(super) mod avx512 {
    use std::arch::x86_64::*;

    use super::super::simd::{strut_component, strut_length};
    use super::super::transpose::{columns, rows};
    use super::{Screen, LANES, MARGIN, PARALLEL};

    /// `K` blocks: lengths into `qs`, the masks of cleared lanes returned (with
    /// `CHECK`, the lanes within every limit of the screen; else the lanes within the
    /// fast sine's range). Each step (transposes, sines and cosines, rotation, each
    /// strut) is made for every block before the next: one block's steps are a chain
    /// of dependent operations too long for the processor to overlap with the next
    /// block's on its own (its scheduler fills with one block's waiting operations),
    /// so two blocks interleaved in program order keep both chains going (5-6 % less
    /// time than one block per call without the screen, measured in
    /// `docs/performance.md`; none with it, whose registers then spill). `PLANAR`: the
    /// arms' z all 0, the strut vectors without that term (the same bits,
    /// [`strut_component`]).
    #[target_feature(enable = "avx512f")]
    pub(super) unsafe fn blocks<const K: usize, const CHECK: bool, const PLANAR: bool>(
        s: &Screen,
        xs: [&[f64; 6 * LANES]; K],
        qs: [&mut [f64; 6 * LANES]; K],
    ) -> [u8; K] {
        let c = |v: f64| _mm512_set1_pd(v);
        let sub = |a: __m512d, b: __m512d| _mm512_sub_pd(a, b);
        let x: [[__m512d; 6]; K] = std::array::from_fn(|j| columns(xs[j]));
        use crate::trig::avx512::sin_cos;
        let angle = |k: usize| -> [((__m512d, __m512d), u8); K] {
            std::array::from_fn(|j| sin_cos(x[j][k]))
        };
        let (ta, tb, tc) = (angle(3), angle(4), angle(5));
        // R = Rz(C) Ry(B) Rx(A), as rotation::rpy_matrix (same operations, same order).
        use crate::lane::Zmm;
        let r: [[__m512d; 9]; K] = std::array::from_fn(|j| {
            let (((sa, ca), _), ((sb, cb), _), ((sc, cc), _)) = (ta[j], tb[j], tc[j]);
            crate::rotation::rpy_entries([sa, sb, sc].map(Zmm::of), [ca, cb, cc].map(Zmm::of))
                .map(Zmm::reg)
        });
        // Strut vectors and lengths by the single pose's AVX-512 steps (`simd.rs`), so
        // a batch's lengths equal `Hexapod::lengths` bit for bit, whichever path
        // settles a row.
        let mut d = [[[c(0.0); 3]; 6]; K];
        let mut len = [[c(0.0); 6]; K];
        for i in 0..6 {
            let arm = [c(s.arm[0][i]), c(s.arm[1][i]), c(s.arm[2][i])];
            for j in 0..K {
                let row = |k: usize| {
                    strut_component::<PLANAR>(
                        [r[j][3 * k], r[j][3 * k + 1], r[j][3 * k + 2]],
                        arm,
                        sub(x[j][k], c(s.base[k][i])),
                    )
                };
                let v = [row(0), row(1), row(2)];
                len[j][i] = strut_length(v);
                d[j][i] = v;
            }
        }
        let mut masks = [0; K];
        for (j, q) in qs.into_iter().enumerate() {
            rows(&len[j], q);
            let ok: u8 = ta[j].1 & tb[j].1 & tc[j].1;
            masks[j] = if !CHECK || ok == 0 {
                ok
            } else {
                limits(s, &x[j], &r[j], &d[j], &len[j], ok)
            };
        }
        masks
    }

    /// Narrows `ok` to the lanes whose pose (coordinates `x` by column, rotation `r`
    /// row by row, strut vectors `d` and lengths `len`) is within every limit of the
    /// screen with its margin.
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub(in crate::hexapod) fn limits(
        s: &Screen,
        x: &[__m512d; 6],
        r: &[__m512d; 9],
        d: &[[__m512d; 3]; 6],
        len: &[__m512d; 6],
        ok: u8,
    ) -> u8 {
        let ok = strut_limits(s, x, r, d, len, ok);
        if ok == 0 || s.pairs.is_empty() {
            return ok;
        }
        pair_limits(s, d, len, ok)
    }

    /// `v` in every lane.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn c(v: f64) -> __m512d {
        _mm512_set1_pd(v)
    }

    /// Lane-wise operations of two registers, each one AVX-512 instruction.
    macro_rules! lane_ops {
        ($($(#[doc = $doc:literal])* fn $name:ident -> $out:ty = $op:expr;)*) => {
            $(
                $(#[doc = $doc])*
                #[target_feature(enable = "avx512f")]
                #[inline]
                fn $name(a: __m512d, b: __m512d) -> $out {
                    $op(a, b)
                }
            )*
        };
    }

    lane_ops! {
        /// `a + b` by lane.
        fn add -> __m512d = _mm512_add_pd;
        /// `a - b` by lane.
        fn sub -> __m512d = _mm512_sub_pd;
        /// `a * b` by lane.
        fn mul -> __m512d = _mm512_mul_pd;
        /// The lanes where `a >= b` (false where either is NaN).
        fn ge -> u8 = _mm512_cmp_pd_mask::<_CMP_GE_OQ>;
        /// The lanes where `a <= b` (false where either is NaN).
        fn le -> u8 = _mm512_cmp_pd_mask::<_CMP_LE_OQ>;
    }

    /// `u . w` by lane.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn dot(u: &[__m512d; 3], w: [__m512d; 3]) -> __m512d {
        add(add(mul(u[0], w[0]), mul(u[1], w[1])), mul(u[2], w[2]))
    }

    /// Narrows `ok` by the limits of each coordinate and strut alone: axis travel,
    /// strut length, base and platform cones.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn strut_limits(
        s: &Screen,
        x: &[__m512d; 6],
        r: &[__m512d; 9],
        d: &[[__m512d; 3]; 6],
        len: &[__m512d; 6],
        mut ok: u8,
    ) -> u8 {
        for (k, v) in x.iter().enumerate() {
            let (lo, hi) = s.axis[k];
            if lo.is_finite() || hi.is_finite() {
                ok &= ge(*v, c(lo)) & le(*v, c(hi));
            }
        }
        for i in 0..6 {
            let q = len[i];
            let m = mul(c(MARGIN), q);
            let (lo, hi) = s.length[i];
            ok &= _mm512_cmp_pd_mask::<_CMP_GT_OQ>(q, c(0.0))
                & ge(sub(q, c(lo)), m)
                & ge(sub(c(hi), q), m);
            let (w, cos_max) = s.base_cone[i];
            if cos_max > f64::NEG_INFINITY {
                let along = dot(&d[i], [c(w[0]), c(w[1]), c(w[2])]);
                ok &= ge(along, add(mul(c(cos_max), q), m));
            }
            let (w, cos_max) = s.platform_cone[i];
            if cos_max > f64::NEG_INFINITY {
                // R w' in the base frame.
                let u = [0, 1, 2].map(|k| {
                    add(
                        add(mul(r[3 * k], c(w[0])), mul(r[3 * k + 1], c(w[1]))),
                        mul(r[3 * k + 2], c(w[2])),
                    )
                });
                let along = sub(c(0.0), dot(&d[i], u));
                ok &= ge(along, add(mul(c(cos_max), q), m));
            }
        }
        ok
    }

    /// Narrows `ok` by the interference of the screen's strut pairs: bounding boxes
    /// apart, else the lines' distance, else the segments' distance.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn pair_limits(s: &Screen, d: &[[__m512d; 3]; 6], len: &[__m512d; 6], mut ok: u8) -> u8 {
        let need = s.diameter * (1.0 + MARGIN);
        let need2 = c(need * need);
        let one = c(1.0);
        let zero = c(0.0);
        let clamp01 = |v: __m512d| _mm512_min_pd(_mm512_max_pd(v, zero), one);
        // 1 / L_i^2, once per strut, when a pair first needs it.
        let mut inv_a: [Option<__m512d>; 6] = [None; 6];
        // |d_i|^2 from the lengths (within a few units in the last place of the dot
        // products, far inside the margin), once per strut instead of twice per pair.
        let sq: [__m512d; 6] = std::array::from_fn(|i| mul(len[i], len[i]));
        // Each strut's bounding box, `a_i` to `a_i + d_i` along X, Y, Z: boxes apart by
        // the diameter along one axis settle a pair in a few operations.
        let needv = c(need);
        let boxes: [[(__m512d, __m512d); 3]; 6] = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let (a, e) = (c(s.base[j][i]), add(c(s.base[j][i]), d[i][j]));
                (_mm512_min_pd(a, e), _mm512_max_pd(a, e))
            })
        });
        for &(i, k) in &s.pairs {
            let apart = (0..3).fold(0u8, |m, j| {
                let ((li, hi), (lk, hk)) = (boxes[i][j], boxes[k][j]);
                m | ge(sub(lk, hi), needv) | ge(sub(li, hk), needv)
            });
            if apart & ok == ok {
                continue;
            }
            // r = a_i - a_k is the same in every lane.
            let rv = [0, 1, 2].map(|j| c(s.base[j][i] - s.base[j][k]));
            let (u, w) = (&d[i], &d[k]);
            let (a2, e2) = (sq[i], sq[k]);
            // The lines' distance, a lower bound of the segments': (r . n)^2 >= need^2
            // |n|^2, n = d_i x d_k, |n|^2 = |d_i|^2 |d_k|^2 sin^2 (nearly parallel
            // lines are not judged).
            let n = [
                sub(mul(u[1], w[2]), mul(u[2], w[1])),
                sub(mul(u[2], w[0]), mul(u[0], w[2])),
                sub(mul(u[0], w[1]), mul(u[1], w[0])),
            ];
            let rn = dot(&rv, n);
            let nn = dot(&n, n);
            let not_parallel = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(nn, mul(c(PARALLEL), mul(a2, e2)));
            let lines = (ge(mul(rn, rn), mul(need2, nn)) & not_parallel) | apart;
            if lines & ok == ok {
                continue;
            }
            // The segments' distance, by the clamped parameters of segment_distance.
            let inv = |j: usize, cache: &mut [Option<__m512d>; 6]| {
                *cache[j].get_or_insert_with(|| _mm512_div_pd(one, mul(len[j], len[j])))
            };
            let (inv_i, inv_k) = (inv(i, &mut inv_a), inv(k, &mut inv_a));
            let f = dot(w, rv);
            let cr = dot(u, rv);
            let bb = dot(u, *w);
            let denom = sub(mul(a2, e2), mul(bb, bb));
            let s0 = clamp01(_mm512_div_pd(sub(mul(bb, f), mul(cr, e2)), denom));
            let t0 = mul(add(mul(bb, s0), f), inv_k);
            let below = _mm512_cmp_pd_mask::<_CMP_LT_OQ>(t0, zero);
            let above = _mm512_cmp_pd_mask::<_CMP_GT_OQ>(t0, one);
            let t = _mm512_mask_blend_pd(above, _mm512_mask_blend_pd(below, t0, zero), one);
            let s_below = clamp01(mul(sub(zero, cr), inv_i));
            let s_above = clamp01(mul(sub(bb, cr), inv_i));
            let s1 = _mm512_mask_blend_pd(above, _mm512_mask_blend_pd(below, s0, s_below), s_above);
            let g = [0, 1, 2].map(|j| sub(add(rv[j], mul(u[j], s1)), mul(w[j], t)));
            let far = ge(dot(&g, g), need2)
                & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(denom, mul(c(PARALLEL), mul(a2, e2)));
            ok &= lines | far;
            if ok == 0 {
                return 0;
            }
        }
        ok
    }
}
