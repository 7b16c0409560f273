//! Eigenvalues of eight symmetric matrices at once, one matrix per AVX-512 lane: the
//! cyclic Jacobi method (Jacobi 1846; Golub & Van Loan, *Matrix Computations*, 4th ed.,
//! section 8.5.2, algorithm 8.5.3), for conditioning maps over many poses.
//!
//! The root-free QL of [`super::symmetric_eigenvalues_rational`] is a chain of
//! dependent divisions whose length depends on the matrix (deflation, iterations): it
//! cannot share vector lanes between matrices, and a 6 x 6 takes about a microsecond.
//! Jacobi's sweeps make the same operations for every matrix, so eight run side by
//! side. A sweep takes the pairs in round-robin order (Brent & Luk 1985, "The solution
//! of singular-value and symmetric eigenvalue problems on multiprocessor arrays", SIAM
//! J. Sci. Stat. Comput. 6): rounds of disjoint pairs, whose angles depend only on
//! their own 2 x 2 blocks, so a round's angles are computed side by side (row by row,
//! a sweep is one chain of dependent angles). Rotation `(p, q)` (`p < q`) zeroes
//! `a_pq` (Golub & Van Loan, algorithm 8.5.1, written without `tau`'s division by
//! `a_pq`):
//!
//! `d = a_qq - a_pp`, `h = sqrt(d^2 + (2 a_pq)^2)`, `t = sign(d) 2 a_pq / (|d| + h)`
//! (the smaller root of `t^2 + 2 tau t - 1 = 0`, `tau = d / (2 a_pq)`: a rotation of
//! at most 45 degrees), `c = 1 / sqrt(1 + t^2)`, `s = t c`; then `a_pp -= t a_pq`,
//! `a_qq += t a_pq`, `a_pq = 0` and, for every other row `r`,
//! `a_rp = c a_rp - s a_rq`, `a_rq = s a_rp + c a_rq`. The square roots and the
//! quotient come from the 14-bit hardware estimates refined by Newton steps (within
//! an ulp or two, as a rounded division and square root chained are), on the
//! multiply-add units rather than the divider (16-20 cycles per 512-bit operation).
//!
//! Each lane is scaled first by a power of two (exact) to a largest entry in [1, 2),
//! so the squares neither overflow nor underflow, and stops on its own: before each
//! sweep, a lane whose off-diagonal squares sum to at most `TOL^2` times its diagonal
//! squares is converged, and its rotations from then on are the identity (`t = 0`:
//! `c = 1`, `s = 0`, every entry kept bit for bit). A lane's values therefore do not
//! depend on the other lanes: one matrix gives the same bits alone as in a batch.
//! Converged, an off-diagonal below `TOL = 1e-17` of the diagonal moves no
//! eigenvalue by more than that much of the largest (Weyl's inequality), within the
//! rounding of any backward-stable method.

use nalgebra::SMatrix;

/// The condition numbers `sqrt(lambda_max / lambda_min)` of the symmetric positive
/// semi-definite Gram matrices `g` (`J^T J` of a Jacobian `J`: the 2-norm condition
/// number of `J`) into `out` (one per matrix; infinity where `lambda_min <= 0` or is
/// NaN, as for a matrix with an entry that is not finite). Eight at a time by the
/// lanes' Jacobi method where the CPU has AVX-512F; otherwise, and for a matrix the
/// lanes give up on, by the root-free QL ([`super::symmetric_eigenvalues_rational`],
/// the Jacobi method of [`super::symmetric_eigenvalues`] if that fails). A matrix gets
/// the same value whichever matrices share its call.
///
/// # Panics
/// When `out` and `g` differ in length.
pub fn gram_conditions<const N: usize>(g: &[SMatrix<f64, N, N>], out: &mut [f64]) {
    assert_eq!(g.len(), out.len(), "one condition number per matrix");
    gram_conditions_by(|k| g[k], out);
}

/// [`gram_conditions`] of one matrix: what a single pose gets, equal to its value in
/// any batch.
pub fn gram_condition<const N: usize>(g: &SMatrix<f64, N, N>) -> f64 {
    let mut c = [0.0];
    gram_conditions_by(|_| *g, &mut c);
    c[0]
}

/// [`gram_conditions`] of the matrices `gram(0)`, ..., `gram(out.len() - 1)`, each
/// built where the lanes take it (no array of them is copied).
pub fn gram_conditions_by<const N: usize>(
    gram: impl Fn(usize) -> SMatrix<f64, N, N>,
    out: &mut [f64],
) {
    let ratio = |lo: f64, hi: f64| {
        if lo > 0.0 {
            (hi / lo).sqrt()
        } else {
            f64::INFINITY
        }
    };
    let serial = |g: &SMatrix<f64, N, N>| {
        let ev = super::symmetric_eigenvalues_rational(g)
            .unwrap_or_else(|| super::symmetric_eigenvalues(g));
        ratio(ev.min(), ev.max())
    };
    for (c, out) in out.chunks_mut(8).enumerate() {
        // The chunk's matrices, the last copied into the spare lanes (lanes do not
        // interact).
        let n = out.len();
        let mut g = [SMatrix::<f64, N, N>::zeros(); 8];
        for k in 0..8 {
            g[k] = if k < n { gram(8 * c + k) } else { g[n - 1] };
        }
        #[cfg(target_arch = "x86_64")]
        {
            let lanes = &g;
            if let Some((ev, converged)) = symmetric_eigenvalues_x8(lanes) {
                for (k, o) in out.iter_mut().enumerate() {
                    *o = if converged & (1 << k) != 0 {
                        let (lo, hi) = ev
                            .iter()
                            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), e| {
                                (lo.min(e[k]), hi.max(e[k]))
                            });
                        ratio(lo, hi)
                    } else {
                        serial(&g[k])
                    };
                }
                continue;
            }
        }
        for (g, o) in g.iter().zip(out.iter_mut()) {
            *o = serial(g);
        }
    }
}

/// Relative size of the off-diagonal at which a lane stops (see the module docs).
#[cfg(target_arch = "x86_64")]
const TOL: f64 = 1e-17;

/// Sweeps before a lane is given up (quadratic convergence takes 5-7 for a 6 x 6).
#[cfg(target_arch = "x86_64")]
const MAX_SWEEPS: usize = 30;

/// Eigenvalues of the symmetric matrices `m` (only their upper triangles are read),
/// lane `k` the matrix `m[k]`: `(values, converged)`, `values[i][k]` the `i`-th
/// eigenvalue of matrix `k` (in no particular order) and bit `k` of `converged` set
/// when it converged (unset for a matrix with an entry that is not finite, or, in
/// principle, one that did not converge in 30 sweeps; an all-zero matrix too: the
/// caller uses another method). `None` when the CPU lacks AVX-512F, or for `N > 16`.
#[cfg(target_arch = "x86_64")]
pub(crate) fn symmetric_eigenvalues_x8<const N: usize>(
    m: &[SMatrix<f64, N, N>; 8],
) -> Option<([[f64; 8]; N], u8)> {
    // The round-robin order is laid out for at most 16 rows.
    if N > 16 || crate::simd::level() < crate::simd::Level::Avx512 {
        return None;
    }
    // SAFETY: the CPU reported AVX-512F, the one feature the kernel is compiled with.
    Some(unsafe { avx512::eigenvalues(m) })
}

#[cfg(target_arch = "x86_64")]
mod avx512 {
    use std::arch::x86_64::*;

    use nalgebra::SMatrix;

    use super::{MAX_SWEEPS, TOL};

    /// See [`super::symmetric_eigenvalues_x8`].
    #[target_feature(enable = "avx512f")]
    pub(super) fn eigenvalues<const N: usize>(m: &[SMatrix<f64, N, N>; 8]) -> ([[f64; 8]; N], u8) {
        let zero = _mm512_setzero_pd();
        let one = _mm512_set1_pd(1.0);
        // The upper triangle, lane k from m[k] (the lower one mirrors it).
        let mut a = [[zero; N]; N];
        for i in 0..N {
            for j in i..N {
                let v: [f64; 8] = std::array::from_fn(|k| m[k][(i, j)]);
                // SAFETY: an unaligned load of the 8 f64 of `v`.
                a[i][j] = unsafe { _mm512_loadu_pd(v.as_ptr()) };
            }
        }
        // Per lane the largest |entry|; lanes with one that is not finite (or all
        // zero: nothing to rotate) are left out.
        let mut big = zero;
        let mut finite: u8 = 0xff;
        for i in 0..N {
            for j in i..N {
                let v = _mm512_abs_pd(a[i][j]);
                finite &= _mm512_cmp_pd_mask::<_CMP_LT_OQ>(v, _mm512_set1_pd(f64::INFINITY));
                big = _mm512_max_pd(big, v);
            }
        }
        // 2^-e with e the exponent of the largest entry (exact scaling); lanes left
        // out compute on the identity instead (finite, converged at once).
        let live = finite & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(big, zero);
        let neg_exp = _mm512_sub_pd(zero, _mm512_getexp_pd(_mm512_mask_blend_pd(live, one, big)));
        for i in 0..N {
            for j in i..N {
                let ident = if i == j { one } else { zero };
                a[i][j] = _mm512_mask_blend_pd(live, ident, _mm512_scalef_pd(a[i][j], neg_exp));
            }
        }
        let tol2 = _mm512_set1_pd(TOL * TOL);
        let mut done: u8 = 0;
        for _ in 0..MAX_SWEEPS {
            let (mut off, mut diag) = (zero, zero);
            for i in 0..N {
                diag = _mm512_fmadd_pd(a[i][i], a[i][i], diag);
                for j in i + 1..N {
                    off = _mm512_fmadd_pd(a[i][j], a[i][j], off);
                }
            }
            done |= _mm512_cmp_pd_mask::<_CMP_LE_OQ>(off, _mm512_mul_pd(tol2, diag));
            if done == 0xff {
                break;
            }
            // The round-robin order (Brent & Luk 1985): N - 1 rounds (N even) of
            // disjoint pairs, whose rotation angles depend only on their own 2 x 2
            // blocks: a round's angles are computed side by side, then applied (a
            // sweep row by row is one chain of dependent angles).
            let players = N + N % 2;
            let mut order: [usize; 16] = std::array::from_fn(|k| k);
            for _ in 0..players.saturating_sub(1) {
                let mut angles = [(zero, zero, zero, 0u8); 8];
                let mut pairs = [(0usize, 0usize); 8];
                let mut count = 0;
                for i in 0..players / 2 {
                    let (u, v) = (order[i], order[players - 1 - i]);
                    if u < N && v < N {
                        pairs[count] = (u.min(v), u.max(v));
                        angles[count] = angle(&a, pairs[count].0, pairs[count].1, done);
                        count += 1;
                    }
                }
                for k in 0..count {
                    apply(&mut a, pairs[k], angles[k]);
                }
                // Every player but the first moves one place round.
                order[1..players].rotate_right(1);
            }
        }
        let mut out = [[0.0; 8]; N];
        for (i, o) in out.iter_mut().enumerate() {
            // Scaled back (exact); the lanes left out are not read.
            let v = _mm512_scalef_pd(a[i][i], _mm512_sub_pd(zero, neg_exp));
            // SAFETY: an unaligned store of 8 f64 into `o`.
            unsafe { _mm512_storeu_pd(o.as_mut_ptr(), v) };
        }
        (out, done & live)
    }

    /// Entry `(i, j)` of the symmetric matrix stored by its upper triangle.
    #[inline(always)]
    fn at<const N: usize>(a: &[[__m512d; N]; N], i: usize, j: usize) -> __m512d {
        if i <= j {
            a[i][j]
        } else {
            a[j][i]
        }
    }

    /// Sets entry `(i, j)` (and so `(j, i)`).
    #[inline(always)]
    fn set<const N: usize>(a: &mut [[__m512d; N]; N], i: usize, j: usize, v: __m512d) {
        if i <= j {
            a[i][j] = v;
        } else {
            a[j][i] = v;
        }
    }

    /// The rotation `(p, q)` (`p < q`) in every lane not in `frozen`: `(t, c, s,
    /// clear)`, `clear` the lanes whose `a_pq` it zeroes (all but `frozen`; where
    /// `a_pq` is negligible, without rotating: `t = 0, c = 1, s = 0`). The
    /// square roots and the quotient come from the 14-bit estimates refined by Newton
    /// steps (two each: within an ulp or two, as a rounded division and square root
    /// chained are) on the multiply-add units, not the divider.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn angle<const N: usize>(
        a: &[[__m512d; N]; N],
        p: usize,
        q: usize,
        frozen: u8,
    ) -> (__m512d, __m512d, __m512d, u8) {
        let b = |v: f64| _mm512_set1_pd(v);
        let (app, aqq, apq) = (a[p][p], a[q][q], a[p][q]);
        // Rotated: not converged, and a_pq above 2^-500 (the lane is scaled to a largest
        // entry of 1 or more: a smaller one is negligible, set to zero; d^2 + 4 a_pq^2
        // cannot underflow).
        let tiny = b(f64::from_bits((1023 - 500) << 52));
        let still = !frozen & _mm512_cmp_pd_mask::<_CMP_GT_OQ>(_mm512_abs_pd(apq), tiny);
        let d = _mm512_sub_pd(aqq, app);
        let two = _mm512_add_pd(apq, apq);
        let x = _mm512_fmadd_pd(d, d, _mm512_mul_pd(two, two));
        let h = crate::lane::sqrt_refined(x);
        // sign(d) 2 a_pq: the sign bit of d applied to 2 a_pq.
        let sign = _mm512_and_si512(_mm512_castpd_si512(d), _mm512_set1_epi64(i64::MIN));
        let num = _mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(two), sign));
        // t = num / den: r ~ 1/den by two Newton steps, then one correction of t.
        let den = _mm512_add_pd(_mm512_abs_pd(d), h);
        let mut r = _mm512_rcp14_pd(den);
        for _ in 0..2 {
            r = _mm512_mul_pd(r, _mm512_fnmadd_pd(den, r, b(2.0)));
        }
        let t0 = _mm512_mul_pd(num, r);
        let t = _mm512_fmadd_pd(_mm512_fnmadd_pd(den, t0, num), r, t0);
        let t = _mm512_maskz_mov_pd(still, t);
        let c = _mm512_mask_blend_pd(still, b(1.0), rsqrt(_mm512_fmadd_pd(t, t, b(1.0))));
        (t, c, _mm512_mul_pd(t, c), !frozen)
    }

    /// Applies the rotation `(t, c, s, clear)` of pair `(p, q)` ([`angle`]): in the
    /// lanes it does not rotate every entry is kept (`c = 1`, `s = 0`, `t = 0`) but
    /// `a_pq` in the `clear` ones.
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn apply<const N: usize>(
        a: &mut [[__m512d; N]; N],
        (p, q): (usize, usize),
        (t, c, s, clear): (__m512d, __m512d, __m512d, u8),
    ) {
        let (app, aqq, apq) = (a[p][p], a[q][q], a[p][q]);
        for r in 0..N {
            if r == p || r == q {
                continue;
            }
            let (arp, arq) = (at(a, r, p), at(a, r, q));
            set(a, r, p, _mm512_fnmadd_pd(s, arq, _mm512_mul_pd(c, arp)));
            set(a, r, q, _mm512_fmadd_pd(s, arp, _mm512_mul_pd(c, arq)));
        }
        a[p][p] = _mm512_fnmadd_pd(t, apq, app);
        a[q][q] = _mm512_fmadd_pd(t, apq, aqq);
        a[p][q] = _mm512_mask_mov_pd(apq, clear, _mm512_setzero_pd());
    }

    /// `1 / sqrt(x)` for `x > 0`: the 14-bit estimate and two Newton steps
    /// `y (1.5 - 0.5 x y^2)` (56 bits).
    #[target_feature(enable = "avx512f")]
    #[inline]
    fn rsqrt(x: __m512d) -> __m512d {
        let half = _mm512_mul_pd(x, _mm512_set1_pd(0.5));
        let mut y = _mm512_rsqrt14_pd(x);
        for _ in 0..2 {
            y = _mm512_mul_pd(
                y,
                _mm512_fnmadd_pd(half, _mm512_mul_pd(y, y), _mm512_set1_pd(1.5)),
            );
        }
        y
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Matrix3, Matrix6, RowVector6, SMatrix, Vector6};
    use rand::{Rng, SeedableRng};

    use super::gram_conditions;

    /// Symmetric test matrices: random Gram matrices, some with columns graded over
    /// decades (eigenvalues over many orders), and special ones (a multiple of the
    /// identity, a zero row and column, a diagonal with negative, zero, repeated and
    /// tiny entries, all zeros, near underflow and near overflow).
    fn cases(n: usize) -> Vec<Matrix6<f64>> {
        let mut rng = rand::rngs::StdRng::seed_from_u64(32);
        (0..n)
            .map(|case| {
                let mut j = Matrix6::<f64>::from_fn(|_, _| rng.random_range(-1.0..1.0));
                if case % 3 == 1 {
                    for k in 0..6 {
                        let g = 10f64.powi(-(k as i32) * (case % 4) as i32);
                        j.set_column(k, &(j.column(k) * g));
                    }
                }
                let mut m = j.transpose() * j;
                match case % 13 {
                    0 => m = Matrix6::identity() * 2.0,
                    1 => {
                        m.set_column(5, &Vector6::zeros());
                        m.set_row(5, &RowVector6::zeros());
                    }
                    2 => m = Matrix6::from_diagonal(&Vector6::new(3.0, -1.0, 0.0, 7.0, 7.0, 1e-9)),
                    3 => m = Matrix6::zeros(),
                    4 => m *= 1e-150,
                    5 => m *= 1e150,
                    6 => m -= Matrix6::identity() * 0.5 * m.trace() / 6.0,
                    _ => {}
                }
                m
            })
            .collect()
    }

    /// Sorted eigenvalues by the QL with square roots on the matrix scaled to a
    /// largest entry near 1 (exactly, by a power of two).
    fn reference(m: &Matrix6<f64>) -> Vec<f64> {
        let big = m.amax();
        let s = if big > 0.0 {
            2f64.powi(-(big.log2().floor() as i32))
        } else {
            1.0
        };
        let mut b: Vec<f64> = super::super::symmetric_eigenvalues_ql(&(m * s))
            .unwrap()
            .iter()
            .map(|v| v / s)
            .collect();
        b.sort_by(|x, y| x.total_cmp(y));
        b
    }

    /// Eight at a time, every eigenvalue within `1e-13 |M|` of the QL's; every lane
    /// converges except the all-zero matrix's (left to the caller).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn lanes_agree_with_the_ql() {
        let all = cases(8 * 2500);
        for batch in all.chunks_exact(8) {
            let lanes: [Matrix6<f64>; 8] = std::array::from_fn(|k| batch[k]);
            let Some((ev, converged)) = super::symmetric_eigenvalues_x8(&lanes) else {
                eprintln!("no AVX-512F: the lanes are not used on this CPU");
                return;
            };
            for (k, m) in batch.iter().enumerate() {
                if *m == Matrix6::zeros() {
                    assert_eq!(converged & (1 << k), 0);
                    continue;
                }
                assert_ne!(converged & (1 << k), 0, "{m}");
                let mut a: Vec<f64> = ev.iter().map(|e| e[k]).collect();
                a.sort_by(|x, y| x.total_cmp(y));
                let b = reference(m);
                let scale = b.iter().fold(0.0f64, |s, v| s.max(v.abs()));
                for i in 0..6 {
                    assert!((a[i] - b[i]).abs() <= 1e-13 * scale, "{m}: {a:?} vs {b:?}");
                }
            }
        }
    }

    /// A matrix's eigenvalues are the same bits alone (in all eight lanes) as beside
    /// any others: slow ones, zeros, NaN.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn a_lane_does_not_depend_on_the_others() {
        let all = cases(400);
        let mut odd = cases(8);
        odd[1] = Matrix6::from_element(f64::NAN);
        odd[2] = Matrix6::zeros();
        odd[3][(0, 5)] = f64::INFINITY;
        for (i, m) in all.iter().enumerate() {
            let Some(alone) = super::symmetric_eigenvalues_x8(&[*m; 8]) else {
                return;
            };
            let k = i % 8;
            let mut lanes: [Matrix6<f64>; 8] = std::array::from_fn(|j| odd[j]);
            lanes[k] = *m;
            let (ev, converged) = super::symmetric_eigenvalues_x8(&lanes).unwrap();
            for r in 0..6 {
                assert_eq!(ev[r][k].to_bits(), alone.0[r][0].to_bits(), "{m}");
            }
            assert_eq!(converged >> k & 1, alone.1 & 1);
            // The NaN and infinite lanes are given up.
            if k != 1 && k != 3 {
                assert_eq!(converged & 0b1010, 0);
            }
        }
    }

    /// Condition numbers of Gram matrices against nalgebra's SVD of the Jacobian
    /// (within 1e-12 relative where `J^T J` is conditioned below 1e4, the eigen
    /// solvers' `1e-14 kappa^2` beyond), any count (not a multiple of eight) and
    /// size; one matrix alone gives the batch's bits; singular and NaN are infinite.
    #[test]
    fn gram_conditions_agree_with_an_svd() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(33);
        let js: Vec<Matrix6<f64>> = (0..3003)
            .map(|case| {
                let mut j = Matrix6::<f64>::from_fn(|_, _| rng.random_range(-1.0..1.0));
                for k in 0..6 {
                    let g = 10f64.powi(-(k as i32) * (case % 3));
                    j.set_column(k, &(j.column(k) * g));
                }
                j
            })
            .collect();
        let grams: Vec<Matrix6<f64>> = js.iter().map(|j| j.transpose() * j).collect();
        let mut out = vec![0.0; grams.len()];
        gram_conditions(&grams, &mut out);
        let mut seen = 0;
        for ((j, g), c) in js.iter().zip(&grams).zip(&out) {
            let mut one = [0.0];
            gram_conditions(std::slice::from_ref(g), &mut one);
            assert_eq!(one[0].to_bits(), c.to_bits());
            let sv = j.singular_values();
            let svd = sv.max() / sv.min();
            if svd > 1e6 {
                continue;
            }
            seen += 1;
            let tol = 1e-12f64.max(1e-14 * svd * svd);
            assert!((c - svd).abs() <= tol * svd, "{j}: {c} vs {svd}");
        }
        assert!(seen > 1500, "{seen}");
        let mut singular = Matrix6::<f64>::identity();
        singular[(4, 4)] = 0.0;
        let nan = Matrix6::from_element(f64::NAN);
        let mut out = [0.0; 3];
        gram_conditions(&[singular, nan, Matrix6::zeros()], &mut out);
        assert_eq!(out, [f64::INFINITY; 3]);
        // Another size: a 3 x 3 Gram matrix of known condition (diagonal 1, 4, 16: 4).
        let d = Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 4.0, 16.0));
        let r = nalgebra::Rotation3::from_euler_angles(0.3, -0.5, 1.1).into_inner();
        let g: SMatrix<f64, 3, 3> = r.transpose() * d * r;
        let mut out = [0.0];
        gram_conditions(&[g], &mut out);
        assert!((out[0] - 4.0).abs() < 1e-14, "{}", out[0]);
    }
}
