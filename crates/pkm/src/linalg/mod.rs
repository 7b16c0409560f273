//! Small dense linear algebra for any fixed size `N`, allocation-free.
//!
//! nalgebra's decompositions need type-level dimension bounds that do not hold for a
//! generic `const N: usize`; these routines serve code generic over the mechanism's
//! size (Newton steps, conditioning) without those bounds.

// Parallel fixed-size arrays (struts, rows, columns) are indexed together.
#![allow(clippy::needless_range_loop)]

mod eigen;
mod inverse;
mod jacobi_lanes;
pub use eigen::{
    condition_number, singular_values, symmetric_eigenvalues, symmetric_eigenvalues_ql,
    symmetric_eigenvalues_rational,
};
pub use inverse::inverse_lu;
pub use jacobi_lanes::{gram_condition, gram_conditions, gram_conditions_by};

use nalgebra::{SMatrix, SVector};

/// LU factorisation with partial pivoting, `P M = L U`, stored in place (row-major
/// arrays: row operations are contiguous and vectorise).
#[derive(Debug, Clone, Copy)]
pub struct SmallLu<const N: usize> {
    lu: [[f64; N]; N],
    perm: [usize; N],
    /// `1 / U(k, k)`: solves multiply instead of divide (division latency dominates
    /// the substitution chains of a small system).
    inv_diag: [f64; N],
}

impl<const N: usize> SmallLu<N> {
    /// Factorises `m`; `None` when a pivot is exactly zero or not finite.
    ///
    /// Gaussian elimination with partial pivoting (the largest |entry| of the column,
    /// the first one of equal ones). Up to 8 x 8 the steps are written out, so each
    /// step's loop bounds and row indices are constants: its loops unroll, the rows
    /// stay in registers, and a 6 x 6 factorisation takes 50 ns instead of 140-170 ns
    /// (EPYC, random matrices and matrices near one another), with the same operations
    /// in the same order (the same bits; tested).
    #[inline]
    pub fn new(m: &SMatrix<f64, N, N>) -> Option<Self> {
        let mut f = SmallLu {
            lu: std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)])),
            perm: std::array::from_fn(|i| i),
            inv_diag: [0.0; N],
        };
        let ok = if N <= 8 {
            let mut step = |k: usize| k >= N || f.eliminate(k);
            step(0) && step(1) && step(2) && step(3) && step(4) && step(5) && step(6) && step(7)
        } else {
            (0..N).all(|k| f.eliminate(k))
        };
        ok.then_some(f)
    }

    /// Step `k` of the elimination: picks the pivot of column `k`, swaps it into row
    /// `k`, stores the multipliers below it and updates the rows below; `false` when
    /// the pivot is zero or not finite.
    #[inline(always)]
    fn eliminate(&mut self, k: usize) -> bool {
        let lu = &mut self.lu;
        let mut piv = k;
        let mut best = lu[k][k].abs();
        for (r, row) in lu.iter().enumerate().skip(k + 1) {
            let v = row[k].abs();
            if v > best {
                best = v;
                piv = r;
            }
        }
        if !(best > 0.0) || !best.is_finite() {
            return false;
        }
        // Rows `k` and `piv` swapped by selects over the rows below `k` (constant
        // indices once the steps are written out, so the rows stay in registers; a
        // swap at the index `piv` went through memory and was most of the time).
        let (old_row, old_perm) = (lu[k], self.perm[k]);
        for r in k + 1..N {
            let here = r == piv;
            let row = lu[r];
            for c in 0..N {
                lu[k][c] = if here { row[c] } else { lu[k][c] };
                lu[r][c] = if here { old_row[c] } else { row[c] };
            }
            let p = self.perm[r];
            self.perm[k] = if here { p } else { self.perm[k] };
            self.perm[r] = if here { old_perm } else { p };
        }
        let pivot_row = lu[k];
        let inv = 1.0 / pivot_row[k];
        self.inv_diag[k] = inv;
        for row in lu.iter_mut().skip(k + 1) {
            let f = row[k] * inv;
            row[k] = f;
            for c in k + 1..N {
                row[c] -= f * pivot_row[c];
            }
        }
        true
    }

    /// Smallest and largest |pivot| of the factorisation: a cheap conditioning estimate
    /// (their ratio bounds the reciprocal condition from above).
    pub fn pivot_range(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi: f64 = 0.0;
        for k in 0..N {
            let v = self.lu[k][k].abs();
            lo = lo.min(v);
            hi = hi.max(v);
        }
        (lo, hi)
    }

    /// Solves `M x = b`. Column-oriented substitutions: once `x[c]` is known, every
    /// later row is updated independently, so the dependency chain is one update per
    /// unknown instead of one per matrix entry.
    #[inline]
    pub fn solve(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut x: [f64; N] = std::array::from_fn(|i| b[self.perm[i]]);
        for c in 0..N {
            let xc = x[c];
            for r in c + 1..N {
                x[r] -= self.lu[r][c] * xc;
            }
        }
        for c in (0..N).rev() {
            let xc = x[c] * self.inv_diag[c];
            x[c] = xc;
            for r in 0..c {
                x[r] -= self.lu[r][c] * xc;
            }
        }
        SVector::<f64, N>::from(x)
    }

    /// The inverse `M^-1`.
    pub fn inverse(&self) -> SMatrix<f64, N, N> {
        let mut inv = SMatrix::<f64, N, N>::zeros();
        for c in 0..N {
            let mut e = SVector::<f64, N>::zeros();
            e[c] = 1.0;
            inv.set_column(c, &self.solve(&e));
        }
        inv
    }
}

/// The largest absolute entry, `max_i |v_i|`, or NaN when any entry is NaN: a
/// residual's size for a solver's convergence test. Branch-free (nalgebra's `amax`
/// compares with a branch per entry, mispredicted on a residual's random order, and
/// keeps a NaN only when it is the last entry); equal to `amax` otherwise.
#[inline]
pub fn max_abs<const N: usize>(v: &SVector<f64, N>) -> f64 {
    let mut m = 0.0f64;
    let mut nan = false;
    for x in v.iter() {
        m = m.max(x.abs());
        nan |= x.is_nan();
    }
    if nan {
        f64::NAN
    } else {
        m
    }
}

/// The 1-norm (largest column sum of absolute values).
pub fn norm1<const R: usize, const C: usize>(a: &SMatrix<f64, R, C>) -> f64 {
    (0..C)
        .map(|c| a.column(c).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// Reciprocal condition number of a square matrix in the 1-norm,
/// `1 / (|M|_1 |M^-1|_1)`: 1 for a multiple of an orthogonal permutation-like matrix,
/// 0 for a singular one.
pub fn rcond1<const N: usize>(m: &SMatrix<f64, N, N>) -> f64 {
    let norm1 = |a: &SMatrix<f64, N, N>| {
        (0..N)
            .map(|c| a.column(c).iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    match SmallLu::new(m) {
        Some(lu) => {
            let d = norm1(m) * norm1(&lu.inverse());
            if d.is_finite() && d > 0.0 {
                1.0 / d
            } else {
                0.0
            }
        }
        None => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    #[test]
    fn max_abs_is_amax_and_keeps_every_nan() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for _ in 0..10_000 {
            let scale = 10f64.powi(rng.random_range(-300..300));
            let v = SVector::<f64, 6>::from_fn(|_, _| rng.random_range(-1.0..1.0) * scale);
            assert_eq!(max_abs(&v).to_bits(), v.amax().to_bits(), "{v:?}");
        }
        let v = SVector::<f64, 6>::new(-3.0, 0.0, -0.0, 2.5, f64::INFINITY, -7.0);
        assert_eq!(max_abs(&v), f64::INFINITY);
        assert_eq!(max_abs(&SVector::<f64, 6>::zeros()), 0.0);
        for k in 0..6 {
            let mut v = SVector::<f64, 6>::from_element(1e-3);
            v[k] = f64::NAN;
            assert!(max_abs(&v).is_nan(), "NaN at {k} lost");
        }
        // nalgebra's amax keeps a NaN only as the last entry: why the solvers use max_abs.
        let mut v = SVector::<f64, 6>::from_element(1e-3);
        v[2] = f64::NAN;
        assert_eq!(v.amax(), 1e-3);
    }

    #[test]
    fn solves_and_inverts_like_nalgebra() {
        let m = Matrix3::new(0.0, 2.0, 1.0, 1.0, -1.0, 3.0, 4.0, 0.5, -2.0);
        let b = Vector3::new(1.0, -2.0, 0.5);
        let lu = SmallLu::new(&m).unwrap();
        let x = lu.solve(&b);
        assert!((m * x - b).amax() < 1e-14);
        let inv = m.try_inverse().unwrap();
        assert!((lu.inverse() - inv).amax() < 1e-14);
    }

    /// The loop over elimination steps, as `SmallLu::new` was before its steps were
    /// written out: the reference the written-out steps must equal bit for bit.
    fn factor_by_loop<const N: usize>(m: &SMatrix<f64, N, N>) -> Option<SmallLu<N>> {
        let mut f = SmallLu {
            lu: std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)])),
            perm: std::array::from_fn(|i| i),
            inv_diag: [0.0; N],
        };
        for k in 0..N {
            let mut piv = k;
            let mut best = f.lu[k][k].abs();
            for r in k + 1..N {
                if f.lu[r][k].abs() > best {
                    best = f.lu[r][k].abs();
                    piv = r;
                }
            }
            if !(best > 0.0) || !best.is_finite() {
                return None;
            }
            f.lu.swap(k, piv);
            f.perm.swap(k, piv);
            let p = f.lu[k];
            let inv = 1.0 / p[k];
            f.inv_diag[k] = inv;
            for r in k + 1..N {
                let g = f.lu[r][k] * inv;
                f.lu[r][k] = g;
                for c in k + 1..N {
                    f.lu[r][c] -= g * p[c];
                }
            }
        }
        Some(f)
    }

    /// Bit patterns of a factorisation (NaN compares equal to itself).
    fn bits<const N: usize>(f: &Option<SmallLu<N>>) -> Option<(Vec<u64>, [usize; N])> {
        f.as_ref().map(|f| {
            let v = f.lu.iter().flatten().chain(&f.inv_diag);
            (v.map(|x| x.to_bits()).collect(), f.perm)
        })
    }

    fn written_out_equals_loop<const N: usize>(seed: u64) -> usize {
        let mut s = seed;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let base = SMatrix::<f64, N, N>::from_fn(|_, _| rnd());
        let mut some = 0;
        for case in 0..3000 {
            let mut m = match case % 4 {
                // Random, then near one matrix (the FK's case: the same pivots).
                0 => SMatrix::<f64, N, N>::from_fn(|_, _| rnd()),
                1 => base.map(|v| v + 1e-4 * rnd()),
                // Small integers: exact ties between pivot candidates, exact zeros.
                2 => SMatrix::<f64, N, N>::from_fn(|_, _| (3.0 * rnd()).round()),
                _ => SMatrix::<f64, N, N>::from_fn(|_, _| (1.5 * rnd()).round()),
            };
            if case % 50 == 7 {
                m[(case % N, (case / 3) % N)] = [f64::NAN, f64::INFINITY, -0.0][case % 3];
            }
            let f = SmallLu::new(&m);
            assert_eq!(bits(&f), bits(&factor_by_loop(&m)), "{m}");
            some += f.is_some() as usize;
        }
        some
    }

    /// The written-out elimination steps give the loop's factorisation bit for bit
    /// (and the same refusals): random matrices, matrices near one another, small
    /// integers (ties between pivots, zero pivots, singular matrices), NaN, infinity
    /// and negative zero; at the sizes written out (1, 3, 6, 8) and beyond (9).
    /// Mutations tried: a step skipped, the strict pivot comparison made `>=` (the
    /// last of equal pivots), or the swap's second half dropped, fail it.
    #[test]
    fn written_out_elimination_equals_the_loop() {
        for (some, total) in [
            (written_out_equals_loop::<1>(11), 3000),
            (written_out_equals_loop::<3>(12), 3000),
            (written_out_equals_loop::<6>(13), 3000),
            (written_out_equals_loop::<8>(14), 3000),
            (written_out_equals_loop::<9>(15), 3000),
        ] {
            // Both outcomes are exercised.
            assert!(some > 1000 && some < total, "{some} of {total} factorised");
        }
    }

    #[test]
    fn singular_values_match_nalgebra() {
        let m = nalgebra::Matrix3x2::new(1.0, 2.0, -0.5, 3.0, 4.0, 0.25);
        let ours = singular_values(&m);
        let mut theirs: Vec<f64> = m.singular_values().iter().copied().collect();
        theirs.sort_by(|a, b| b.total_cmp(a));
        assert!((ours[0] - theirs[0]).abs() < 1e-12 && (ours[1] - theirs[1]).abs() < 1e-12);
        let j = nalgebra::Matrix6::<f64>::from_fn(|r, c| {
            ((r * 7 + c * 3) % 5) as f64 - 1.7 + (r == c) as u8 as f64
        });
        let ours = singular_values(&j);
        let mut theirs: Vec<f64> = j.singular_values().iter().copied().collect();
        theirs.sort_by(|a, b| b.total_cmp(a));
        for k in 0..6 {
            assert!(
                (ours[k] - theirs[k]).abs() < 1e-9 * theirs[0],
                "{k}: {} vs {}",
                ours[k],
                theirs[k]
            );
        }
    }

    /// Uniform numbers in [-0.5, 0.5) from a linear congruential generator.
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        }
    }

    #[test]
    fn ql_eigenvalues_match_jacobi() {
        // Random symmetric matrices, including repeated and zero eigenvalues.
        let mut rnd = uniform(12345);
        for case in 0..500 {
            let j = nalgebra::Matrix6::<f64>::from_fn(|_, _| rnd());
            let mut m = j.transpose() * j;
            if case % 5 == 0 {
                m = nalgebra::Matrix6::identity() * 2.0; // repeated eigenvalues
            }
            if case % 7 == 0 {
                m.set_column(5, &nalgebra::Vector6::zeros());
                m.set_row(5, &nalgebra::RowVector6::zeros()); // a zero eigenvalue
            }
            let mut a: Vec<f64> = symmetric_eigenvalues_ql(&m)
                .unwrap()
                .iter()
                .copied()
                .collect();
            let mut b: Vec<f64> = symmetric_eigenvalues(&m).iter().copied().collect();
            a.sort_by(|x, y| x.total_cmp(y));
            b.sort_by(|x, y| x.total_cmp(y));
            let scale = b.iter().fold(0.0f64, |s, v| s.max(v.abs())).max(1e-300);
            for k in 0..6 {
                assert!(
                    (a[k] - b[k]).abs() < 1e-13 * scale,
                    "{case} {k}: {a:?} vs {b:?}"
                );
            }
        }
    }

    /// The rational QL gives the QL's eigenvalues within 1e-13 of the largest: random
    /// Gram matrices, repeated and zero eigenvalues, a diagonal, a zero matrix, graded
    /// and near-singular ones (condition up to 1e12).
    #[test]
    fn rational_ql_eigenvalues_match_ql() {
        let mut rnd = uniform(987);
        for case in 0..20_000 {
            let mut j = nalgebra::Matrix6::<f64>::from_fn(|_, _| rnd());
            if case % 3 == 1 {
                // Graded columns: eigenvalues over many decades.
                for k in 0..6 {
                    let g = 10f64.powi(-(k as i32) * (case % 4));
                    j.set_column(k, &(j.column(k) * g));
                }
            }
            let mut m = j.transpose() * j;
            match case % 11 {
                0 => m = nalgebra::Matrix6::identity() * 2.0,
                1 => {
                    m.set_column(5, &nalgebra::Vector6::zeros());
                    m.set_row(5, &nalgebra::RowVector6::zeros());
                }
                2 => {
                    m = nalgebra::Matrix6::from_diagonal(&nalgebra::Vector6::new(
                        3.0, -1.0, 0.0, 7.0, 7.0, 1e-9,
                    ))
                }
                3 => m = nalgebra::Matrix6::zeros(),
                4 => m *= 1e-150,
                _ => {}
            }
            let mut a: Vec<f64> = symmetric_eigenvalues_rational(&m)
                .unwrap_or_else(|| panic!("{case}: no convergence"))
                .iter()
                .copied()
                .collect();
            // The reference on the matrix scaled (by a power of two, exactly) to a largest
            // entry near 1: the QL squares entries, which lose digits near underflow.
            let big = m.amax();
            let s = if big > 0.0 {
                2f64.powi(-(big.log2().floor() as i32))
            } else {
                1.0
            };
            let mut b: Vec<f64> = symmetric_eigenvalues_ql(&(m * s))
                .unwrap()
                .iter()
                .map(|v| v / s)
                .collect();
            a.sort_by(|x, y| x.total_cmp(y));
            b.sort_by(|x, y| x.total_cmp(y));
            let scale = b.iter().fold(0.0f64, |s, v| s.max(v.abs()));
            for k in 0..6 {
                assert!(
                    (a[k] - b[k]).abs() <= 1e-13 * scale,
                    "{case} {k}: {a:?} vs {b:?}"
                );
            }
        }
    }

    #[test]
    fn singular_is_detected() {
        let m = Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 1.0, 1.0);
        assert!(SmallLu::new(&m).is_none() || rcond1(&m) < 1e-15);
        assert_eq!(rcond1(&Matrix3::<f64>::zeros()), 0.0);
        assert!((rcond1(&Matrix3::<f64>::identity()) - 1.0).abs() < 1e-15);
    }
}
