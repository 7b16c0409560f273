//! Small dense linear algebra for any fixed size `N`, allocation-free.
//!
//! nalgebra's decompositions need type-level dimension bounds that do not hold for a
//! generic `const N: usize`; these routines serve code generic over the mechanism's
//! size (Newton steps, conditioning) without those bounds.

use nalgebra::{SMatrix, SVector};

/// LU factorisation with partial pivoting, `P M = L U`, stored in place.
#[derive(Debug, Clone, Copy)]
pub struct SmallLu<const N: usize> {
    lu: SMatrix<f64, N, N>,
    perm: [usize; N],
}

impl<const N: usize> SmallLu<N> {
    /// Factorises `m`; `None` when a pivot is exactly zero or not finite.
    pub fn new(m: &SMatrix<f64, N, N>) -> Option<Self> {
        let mut lu = *m;
        let mut perm = [0usize; N];
        for (i, p) in perm.iter_mut().enumerate() {
            *p = i;
        }
        for k in 0..N {
            let mut piv = k;
            let mut best = lu[(k, k)].abs();
            for r in k + 1..N {
                let v = lu[(r, k)].abs();
                if v > best {
                    best = v;
                    piv = r;
                }
            }
            if !(best > 0.0) || !best.is_finite() {
                return None;
            }
            if piv != k {
                lu.swap_rows(k, piv);
                perm.swap(k, piv);
            }
            let d = lu[(k, k)];
            for r in k + 1..N {
                let f = lu[(r, k)] / d;
                lu[(r, k)] = f;
                for c in k + 1..N {
                    lu[(r, c)] -= f * lu[(k, c)];
                }
            }
        }
        Some(SmallLu { lu, perm })
    }

    /// Smallest and largest |pivot| of the factorisation: a cheap conditioning estimate
    /// (their ratio bounds the reciprocal condition from above).
    pub fn pivot_range(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi: f64 = 0.0;
        for k in 0..N {
            let v = self.lu[(k, k)].abs();
            lo = lo.min(v);
            hi = hi.max(v);
        }
        (lo, hi)
    }

    /// Solves `M x = b`.
    pub fn solve(&self, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut x = SVector::<f64, N>::from_fn(|i, _| b[self.perm[i]]);
        for r in 0..N {
            for c in 0..r {
                x[r] -= self.lu[(r, c)] * x[c];
            }
        }
        for r in (0..N).rev() {
            for c in r + 1..N {
                x[r] -= self.lu[(r, c)] * x[c];
            }
            x[r] /= self.lu[(r, r)];
        }
        x
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

/// Eigenvalues of a symmetric matrix by cyclic Jacobi rotations (allocation-free,
/// any fixed size), in no particular order.
pub fn symmetric_eigenvalues<const N: usize>(m: &SMatrix<f64, N, N>) -> SVector<f64, N> {
    let mut a = *m;
    for _sweep in 0..50 {
        let mut off = 0.0;
        for p in 0..N {
            for q in p + 1..N {
                off += a[(p, q)] * a[(p, q)];
            }
        }
        let scale: f64 = (0..N)
            .map(|k| a[(k, k)] * a[(k, k)])
            .sum::<f64>()
            .max(1e-300);
        if off <= 1e-30 * scale {
            break;
        }
        for p in 0..N {
            for q in p + 1..N {
                let apq = a[(p, q)];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..N {
                    let akp = a[(k, p)];
                    let akq = a[(k, q)];
                    a[(k, p)] = c * akp - s * akq;
                    a[(k, q)] = s * akp + c * akq;
                }
                for k in 0..N {
                    let apk = a[(p, k)];
                    let aqk = a[(q, k)];
                    a[(p, k)] = c * apk - s * aqk;
                    a[(q, k)] = s * apk + c * aqk;
                }
            }
        }
    }
    SVector::<f64, N>::from_fn(|k, _| a[(k, k)])
}

/// Singular values of any `R x C` matrix, from the eigenvalues of `M^T M` (sorted
/// descending). Adequate for conditioning maps; loses accuracy below about 1e-8 of
/// the largest singular value.
pub fn singular_values<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> SVector<f64, C> {
    let ev = symmetric_eigenvalues(&(m.transpose() * m));
    let mut v: [f64; C] = std::array::from_fn(|k| ev[k].max(0.0).sqrt());
    v.sort_by(|a, b| b.total_cmp(a));
    SVector::<f64, C>::from_fn(|k, _| v[k])
}

/// 2-norm condition number `s_max / s_min` (infinite when singular).
pub fn condition_number<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> f64 {
    let sv = singular_values(m);
    if C == 0 {
        return 1.0;
    }
    let (max, min) = (sv[0], sv[C - 1]);
    if min > 0.0 {
        max / min
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

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

    #[test]
    fn singular_is_detected() {
        let m = Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 1.0, 1.0);
        assert!(SmallLu::new(&m).is_none() || rcond1(&m) < 1e-15);
        assert_eq!(rcond1(&Matrix3::<f64>::zeros()), 0.0);
        assert!((rcond1(&Matrix3::<f64>::identity()) - 1.0).abs() < 1e-15);
    }
}
