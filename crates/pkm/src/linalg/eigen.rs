//! Eigenvalues of symmetric matrices (cyclic Jacobi; Householder tridiagonalisation
//! then implicit or rational QL) and the singular values and condition number of any
//! fixed-size matrix from them: the conditioning maps' and the identifiability
//! analysis' small dense eigenproblems, allocation-free.

use nalgebra::{SMatrix, SVector};

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

/// Eigenvalues of a symmetric matrix by Householder reduction to tridiagonal form and
/// the implicit QL algorithm with Wilkinson-type shifts (eigenvalues only; the
/// classic `tred2`/`tqli` pair), in no particular order. About ten times faster than
/// [`symmetric_eigenvalues`] for `N = 6`; `None` if QL does not converge in 60
/// iterations per eigenvalue (then use the Jacobi method).
pub fn symmetric_eigenvalues_ql<const N: usize>(m: &SMatrix<f64, N, N>) -> Option<SVector<f64, N>> {
    let (mut d, mut e) = tridiagonal(m);
    tridiagonal_ql(&mut d, &mut e)?;
    Some(SVector::<f64, N>::from(d))
}

/// Eigenvalues of a symmetric matrix by the Householder reduction of
/// [`symmetric_eigenvalues_ql`] and the root-free (rational) QL algorithm on the
/// squared off-diagonal (Reinsch 1973, "A stable, rational QR algorithm for the
/// computation of the eigenvalues of an Hermitian, tridiagonal matrix", Math. Comp.
/// 25; the algorithm of EISPACK's `tqlrat` and, in its Pal-Walker-Kahan form, of
/// LAPACK's `dsterf`). Its inner step has one dependent division and no square root,
/// where the QL step has a square root and a division in a chain: about twice as
/// fast for `N = 6` (the hexapod's conditioning maps). The same backward error
/// (a few `eps * |M|`): agrees with [`symmetric_eigenvalues_ql`] within `1e-13 |M|`
/// (tested). `None` if it does not converge in 60 iterations per eigenvalue.
pub fn symmetric_eigenvalues_rational<const N: usize>(
    m: &SMatrix<f64, N, N>,
) -> Option<SVector<f64, N>> {
    let (mut d, e) = tridiagonal(m);
    // Scaled by a power of two (exact) to a largest entry in [1, 4): the squares and
    // the negligibility bound (eps t)^2 then neither underflow nor overflow.
    let norm = d.iter().chain(&e).fold(0.0f64, |a, v| a.max(v.abs()));
    if !norm.is_finite() {
        return None;
    }
    if norm == 0.0 {
        return Some(SVector::<f64, N>::zeros());
    }
    let biased = ((norm.to_bits() >> 52) & 0x7ff).clamp(1, 2045);
    let scale = f64::from_bits((2046 - biased) << 52);
    for v in d.iter_mut() {
        *v *= scale;
    }
    let mut e2: [f64; N] = std::array::from_fn(|i| (e[i] * scale) * (e[i] * scale));
    tridiagonal_rational_ql(&mut d, &mut e2)?;
    Some(SVector::<f64, N>::from_fn(|k, _| d[k] / scale))
}

/// The Householder reduction of a symmetric matrix to tridiagonal form (`tred2`
/// without the transformation): the diagonal `d` and the off-diagonal `e`, `e[i]`
/// coupling `i` and `i + 1` (`e[N - 1] = 0`).
fn tridiagonal<const N: usize>(m: &SMatrix<f64, N, N>) -> ([f64; N], [f64; N]) {
    let mut a: [[f64; N]; N] = std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]));
    let mut d = [0.0; N];
    let mut e = [0.0; N];
    for i in (1..N).rev() {
        let l = i - 1;
        let mut h = 0.0;
        if l > 0 {
            let scale: f64 = a[i][..=l].iter().map(|v| v.abs()).sum();
            if scale == 0.0 {
                e[i] = a[i][l];
            } else {
                for k in 0..=l {
                    a[i][k] /= scale;
                    h += a[i][k] * a[i][k];
                }
                let f = a[i][l];
                let g = if f >= 0.0 { -h.sqrt() } else { h.sqrt() };
                e[i] = scale * g;
                h -= f * g;
                a[i][l] = f - g;
                let mut f = 0.0;
                for j in 0..=l {
                    let mut g = 0.0;
                    for k in 0..=j {
                        g += a[j][k] * a[i][k];
                    }
                    for k in j + 1..=l {
                        g += a[k][j] * a[i][k];
                    }
                    e[j] = g / h;
                    f += e[j] * a[i][j];
                }
                let hh = f / (h + h);
                for j in 0..=l {
                    let f = a[i][j];
                    let g = e[j] - hh * f;
                    e[j] = g;
                    for k in 0..=j {
                        a[j][k] -= f * e[k] + g * a[i][k];
                    }
                }
            }
        } else {
            e[i] = a[i][l];
        }
        let _ = h;
    }
    for i in 0..N {
        d[i] = a[i][i];
    }
    for i in 1..N {
        e[i - 1] = e[i];
    }
    if N > 0 {
        e[N - 1] = 0.0;
    }
    (d, e)
}

/// Implicit QL with Wilkinson-type shifts on the tridiagonal `(d, e)` (`tqli` without
/// eigenvectors): the eigenvalues in `d`; `None` without convergence.
fn tridiagonal_ql<const N: usize>(d: &mut [f64; N], e: &mut [f64; N]) -> Option<()> {
    for l in 0..N {
        let mut iter = 0;
        loop {
            let mut m = l;
            while m + 1 < N {
                let dd = d[m].abs() + d[m + 1].abs();
                if e[m].abs() <= f64::EPSILON * dd {
                    break;
                }
                m += 1;
            }
            if m == l {
                break;
            }
            iter += 1;
            if iter > 60 {
                return None;
            }
            // sqrt(a^2 + b^2) rather than hypot: libm's hypot costs tens of ns, and the
            // values here (entries of J^T J) are far from overflow.
            let mut g = (d[l + 1] - d[l]) / (2.0 * e[l]);
            let mut r = (g * g + 1.0).sqrt();
            g = d[m] - d[l] + e[l] / (g + if g >= 0.0 { r.abs() } else { -r.abs() });
            let (mut s, mut c, mut p) = (1.0, 1.0, 0.0);
            let mut early = false;
            let mut i = m;
            while i > l {
                i -= 1;
                let f = s * e[i];
                let b = c * e[i];
                r = (f * f + g * g).sqrt();
                e[i + 1] = r;
                if r == 0.0 {
                    d[i + 1] -= p;
                    e[m] = 0.0;
                    early = true;
                    break;
                }
                let inv = 1.0 / r;
                s = f * inv;
                c = g * inv;
                g = d[i + 1] - p;
                r = (d[i] - g) * s + 2.0 * c * b;
                p = s * r;
                d[i + 1] = g + p;
                g = c * r - b;
            }
            if early {
                continue;
            }
            d[l] -= p;
            e[l] = g;
            e[m] = 0.0;
        }
    }
    d.iter().all(|v| v.is_finite()).then_some(())
}

/// Rational QL on the tridiagonal with diagonal `d` and squared off-diagonal `e2`
/// (`e2[i] = e[i]^2`, `e2[N - 1] = 0`): the eigenvalues in `d`, in no particular
/// order; `None` without convergence.
///
/// Per eigenvalue `l`: an off-diagonal is negligible when `e2[m] <= (eps t)^2`, `t`
/// the largest `|d[l]| + |e[l]|` met so far; while `e2[l]` is not, the block `l..=m`
/// is shifted by the eigenvalue of its leading 2x2 nearer `d[l]` (accumulated in
/// `f`), then swept from `m` up to `l` by the root-free rotation recurrences on
/// `g = c^2 (d_i - shift)`-type quantities (Reinsch 1973).
fn tridiagonal_rational_ql<const N: usize>(d: &mut [f64; N], e2: &mut [f64; N]) -> Option<()> {
    if N == 0 {
        return Some(());
    }
    e2[N - 1] = 0.0;
    let (mut f, mut t) = (0.0f64, 0.0f64);
    let (mut b, mut c) = (0.0f64, 0.0f64);
    for l in 0..N {
        let h = d[l].abs() + e2[l].sqrt();
        if h > t {
            t = h;
            b = f64::EPSILON * t;
            c = b * b;
        }
        let mut iter = 0;
        loop {
            let mut m = l;
            while m + 1 < N && e2[m] > c {
                m += 1;
            }
            if m == l {
                break;
            }
            iter += 1;
            if iter > 60 {
                return None;
            }
            // The shift: the eigenvalue of the leading 2x2 nearer d[l].
            let s = e2[l].sqrt();
            let g = d[l];
            let p = (d[l + 1] - g) / (2.0 * s);
            let r = (p * p + 1.0).sqrt();
            d[l] = s / (p + r.copysign(p));
            let h = g - d[l];
            for v in d[l + 1..].iter_mut() {
                *v -= h;
            }
            f += h;
            // The rational sweep from m up to l.
            let mut g = d[m];
            if g == 0.0 {
                g = b;
            }
            let mut h = g;
            let mut s = 0.0;
            for i in (l..m).rev() {
                let p = g * h;
                let r = p + e2[i];
                e2[i + 1] = s * r;
                s = e2[i] / r;
                d[i + 1] = h + s * (h + d[i]);
                g = d[i] - e2[i] / g;
                if g == 0.0 {
                    g = b;
                }
                h = g * p / r;
            }
            e2[l] = s * g;
            d[l] = h;
            // Converged when the new e2[l] = s g h is negligible (tested without
            // forming it, against underflow).
            if h == 0.0 || (s * g).abs() <= (c / h).abs() {
                e2[l] = 0.0;
                break;
            }
            e2[l] *= h;
            if e2[l] == 0.0 {
                break;
            }
        }
        d[l] += f;
    }
    d.iter().all(|v| v.is_finite()).then_some(())
}

/// Singular values of any `R x C` matrix, from the eigenvalues of `M^T M` (sorted
/// descending). Adequate for conditioning maps; loses accuracy below about 1e-8 of
/// the largest singular value.
pub fn singular_values<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> SVector<f64, C> {
    let mtm = m.transpose() * m;
    let ev = symmetric_eigenvalues_rational(&mtm).unwrap_or_else(|| symmetric_eigenvalues(&mtm));
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
