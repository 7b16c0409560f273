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
    fn singular_is_detected() {
        let m = Matrix3::new(1.0, 2.0, 3.0, 2.0, 4.0, 6.0, 0.0, 1.0, 1.0);
        assert!(SmallLu::new(&m).is_none() || rcond1(&m) < 1e-15);
        assert_eq!(rcond1(&Matrix3::<f64>::zeros()), 0.0);
        assert!((rcond1(&Matrix3::<f64>::identity()) - 1.0).abs() < 1e-15);
    }
}
