//! The block kernel of `block.rs` on the portable lanes ([`crate::lane::Lanes`]),
//! compiled with AVX2 and FMA: the same steps and tests, written once over the lane
//! type instead of AVX-512 intrinsics, for CPUs without AVX-512 (each eight-lane
//! operation two 256-bit instructions).
//!
//! Its lengths are [`super::simd`]'s AVX2 single-pose kernel's bit for bit (the same
//! sines, rotation, strut sums and square roots), so whichever path settles a row the
//! lengths agree; its screen makes the AVX-512 screen's comparisons with the same
//! margin, so it clears a pose only when the exact scan finds it within every limit.

// Struts, pairs, coordinates and lanes are indexed together.
#![allow(clippy::needless_range_loop)]

use super::block::{Screen, LANES, MARGIN, PARALLEL};
use crate::lane::{Lane, Lanes};

/// `v` in every lane.
#[inline(always)]
fn c<const N: usize>(v: f64) -> Lanes<N> {
    Lanes::from(v)
}

/// The columns of `N` rows (row-major, six per row): coordinate or strut `k` of the
/// rows in the lanes of column `k`.
#[inline(always)]
fn columns<const N: usize>(xs: &[f64]) -> [Lanes<N>; 6] {
    let mut cols = [Lanes([0.0; N]); 6];
    for l in 0..N {
        for k in 0..6 {
            cols[k].0[l] = xs[6 * l + k];
        }
    }
    cols
}

/// [`columns`] undone.
#[inline(always)]
fn rows<const N: usize>(cols: &[Lanes<N>; 6], out: &mut [f64]) {
    for l in 0..N {
        for k in 0..6 {
            out[6 * l + k] = cols[k].0[l];
        }
    }
}

/// One block with AVX2 and FMA: lengths into `qs`, the mask of cleared lanes returned
/// (with `CHECK`, the lanes within every limit of the screen; else the lanes within the
/// fast sine's range). `PLANAR` as in [`super::simd::strut_component`]. Eight lanes are
/// two AVX2 registers each, and the screen's values do not fit AVX2's sixteen: two
/// halves of four rows measured 9 % faster without the screen and 27 % slower with it
/// (AMD EPYC Zen 3), so the block stays whole.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn block_avx2<const CHECK: bool, const PLANAR: bool>(
    s: &Screen,
    xs: &[f64; 6 * LANES],
    qs: &mut [f64; 6 * LANES],
) -> u8 {
    block::<LANES, CHECK, PLANAR>(s, xs, qs)
}

/// [`block_avx2`]'s body, compiled in its caller.
#[inline(always)]
fn block<const N: usize, const CHECK: bool, const PLANAR: bool>(
    s: &Screen,
    xs: &[f64],
    qs: &mut [f64],
) -> u8 {
    let x = columns::<N>(xs);
    let (sa, ca, ma) = crate::trig::sin_cos_lanes_masked(&x[3].0);
    let (sb, cb, mb) = crate::trig::sin_cos_lanes_masked(&x[4].0);
    let (sc, cc, mc) = crate::trig::sin_cos_lanes_masked(&x[5].0);
    // R = Rz(C) Ry(B) Rx(A), as rotation::rpy_matrix (same operations, same order).
    let r = crate::rotation::rpy_entries(
        [Lanes(sa), Lanes(sb), Lanes(sc)],
        [Lanes(ca), Lanes(cb), Lanes(cc)],
    );
    let mut d = [[c::<N>(0.0); 3]; 6];
    let mut len = [c::<N>(0.0); 6];
    for i in 0..6 {
        let arm = [c(s.arm[0][i]), c(s.arm[1][i]), c(s.arm[2][i])];
        for k in 0..3 {
            let offset = x[k].sub(c(s.base[k][i]));
            let t = if PLANAR {
                offset
            } else {
                r[3 * k + 2].mul_add(arm[2], offset)
            };
            let t = r[3 * k + 1].mul_add(arm[1], t);
            d[i][k] = r[3 * k].mul_add(arm[0], t);
        }
        let [dx, dy, dz] = d[i];
        len[i] = strut_length(dx, dy, dz);
    }
    rows(&len, qs);
    let ok = ma & mb & mc;
    if !CHECK || ok == 0 {
        return ok;
    }
    let ok = strut_limits(s, &x, &r, &d, &len, ok);
    if ok == 0 || s.pairs.is_empty() {
        return ok;
    }
    pair_limits(s, &d, &len, ok)
}

/// `|d|` by lane, the CPU's correctly rounded root of `d . d` (the single pose's AVX2
/// kernel's steps). A refined estimate from the single-precision reciprocal root, as
/// the AVX-512 kernels take, was slower here than `vsqrtpd` (31 against 27 ns a pose,
/// AMD EPYC Zen 3).
#[inline(always)]
pub(super) fn strut_length<const N: usize>(dx: Lanes<N>, dy: Lanes<N>, dz: Lanes<N>) -> Lanes<N> {
    dz.mul_add(dz, dy.mul_add(dy, dx.mul(dx))).sqrt()
}

/// `u . w` by lane.
#[inline(always)]
fn dot<const N: usize>(u: &[Lanes<N>; 3], w: [Lanes<N>; 3]) -> Lanes<N> {
    u[0].mul(w[0]).add(u[1].mul(w[1])).add(u[2].mul(w[2]))
}

/// Narrows `ok` by the limits of each coordinate and strut alone: axis travel, strut
/// length, base and platform cones (`block.rs`'s AVX-512 screen, test for test).
#[inline(always)]
fn strut_limits<const N: usize>(
    s: &Screen,
    x: &[Lanes<N>; 6],
    r: &[Lanes<N>; 9],
    d: &[[Lanes<N>; 3]; 6],
    len: &[Lanes<N>; 6],
    mut ok: u8,
) -> u8 {
    for (k, v) in x.iter().enumerate() {
        let (lo, hi) = s.axis[k];
        if lo.is_finite() || hi.is_finite() {
            ok &= v.ge(c(lo)) & v.le(c(hi));
        }
    }
    for i in 0..6 {
        let q = len[i];
        let m = c(MARGIN).mul(q);
        let (lo, hi) = s.length[i];
        ok &= q.gt(c(0.0)) & q.sub(c(lo)).ge(m) & c(hi).sub(q).ge(m);
        let (w, cos_max) = s.base_cone[i];
        if cos_max > f64::NEG_INFINITY {
            let along = dot(&d[i], [c(w[0]), c(w[1]), c(w[2])]);
            ok &= along.ge(c(cos_max).mul(q).add(m));
        }
        let (w, cos_max) = s.platform_cone[i];
        if cos_max > f64::NEG_INFINITY {
            // R w' in the base frame.
            let mut u = [c::<N>(0.0); 3];
            for k in 0..3 {
                u[k] = r[3 * k]
                    .mul(c(w[0]))
                    .add(r[3 * k + 1].mul(c(w[1])))
                    .add(r[3 * k + 2].mul(c(w[2])));
            }
            let along = c(0.0).sub(dot(&d[i], u));
            ok &= along.ge(c(cos_max).mul(q).add(m));
        }
    }
    ok
}

/// Narrows `ok` by the interference of the screen's strut pairs: bounding boxes apart,
/// else the lines' distance, else the segments' distance (by the clamped parameters of
/// [`super::segment_distance`], with selects instead of branches).
#[inline(always)]
fn pair_limits<const N: usize>(
    s: &Screen,
    d: &[[Lanes<N>; 3]; 6],
    len: &[Lanes<N>; 6],
    mut ok: u8,
) -> u8 {
    let need = s.diameter * (1.0 + MARGIN);
    let (need2, needv, one, zero) = (c::<N>(need * need), c(need), c(1.0), c(0.0));
    let mut sq = [zero; 6];
    let mut boxes = [[(zero, zero); 3]; 6];
    for i in 0..6 {
        sq[i] = len[i].mul(len[i]);
        for j in 0..3 {
            boxes[i][j] = c(s.base[j][i]).min_max(c(s.base[j][i]).add(d[i][j]));
        }
    }
    for &(i, k) in &s.pairs {
        let mut apart = 0u8;
        for j in 0..3 {
            let ((li, hi), (lk, hk)) = (boxes[i][j], boxes[k][j]);
            apart |= lk.sub(hi).ge(needv) | li.sub(hk).ge(needv);
        }
        if apart & ok == ok {
            continue;
        }
        let rv = [
            c(s.base[0][i] - s.base[0][k]),
            c(s.base[1][i] - s.base[1][k]),
            c(s.base[2][i] - s.base[2][k]),
        ];
        let (u, w) = (&d[i], &d[k]);
        let (a2, e2) = (sq[i], sq[k]);
        let n = [
            u[1].mul(w[2]).sub(u[2].mul(w[1])),
            u[2].mul(w[0]).sub(u[0].mul(w[2])),
            u[0].mul(w[1]).sub(u[1].mul(w[0])),
        ];
        let (rn, nn) = (dot(&rv, n), dot(&n, n));
        let parallel = c(PARALLEL).mul(a2.mul(e2));
        let lines = (rn.mul(rn).ge(need2.mul(nn)) & nn.gt(parallel)) | apart;
        if lines & ok == ok {
            continue;
        }
        let (inv_i, inv_k) = (one.div(sq[i]), one.div(sq[k]));
        let f = dot(w, rv);
        let cr = dot(u, rv);
        let bb = dot(u, *w);
        let denom = a2.mul(e2).sub(bb.mul(bb));
        let s0 = bb.mul(f).sub(cr.mul(e2)).div(denom).clamp01();
        let t0 = bb.mul(s0).add(f).mul(inv_k);
        let (below, above) = (t0.lt(zero), t0.gt(one));
        let t = t0.blend(below, zero).blend(above, one);
        let s_below = zero.sub(cr).mul(inv_i).clamp01();
        let s_above = bb.sub(cr).mul(inv_i).clamp01();
        let s1 = s0.blend(below, s_below).blend(above, s_above);
        let mut g = [zero; 3];
        for j in 0..3 {
            g[j] = rv[j].add(u[j].mul(s1)).sub(w[j].mul(t));
        }
        let far = dot(&g, g).ge(need2) & denom.gt(parallel);
        ok &= lines | far;
        if ok == 0 {
            return 0;
        }
    }
    ok
}
