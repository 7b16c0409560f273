//! Best-fit rigid transform from `N >= 3` point pairs (seed 001 eqs. 4-5 generalised):
//! the least-squares `R`, `c` minimising `sum |R s_k + c - m_k|^2` (Kabsch / Horn),
//! from the SVD of the cross-covariance `H = sum (s_k - s0)(m_k - m0)^T`:
//! `R = V diag(1, 1, det(V U^T)) U^T`, `c = m0 - R s0`. With three points of an
//! equilateral triangle and exact measurements this is the paper's construction
//! (centroid = intersection of the heights, eq. 4; the frame from the vertices, eq. 5).

use nalgebra::{Matrix3, Vector3};

use crate::error::{Error, Result};

/// `(c, R, rms)`: the transform taking platform-frame points `s` to the measured `m`
/// and the RMS distance left. Fails for fewer than three points, mismatched counts,
/// or points on a line.
pub fn rigid_transform(
    s: &[Vector3<f64>],
    m: &[Vector3<f64>],
) -> Result<(Vector3<f64>, Matrix3<f64>, f64)> {
    let bad = |message: String| Error::InvalidInput {
        what: "fixture points".into(),
        message,
    };
    if s.len() != m.len() || s.len() < 3 {
        return Err(bad(format!(
            "a pose needs at least three fixture points and one measurement of each ({} and {})",
            s.len(),
            m.len()
        )));
    }
    let k = s.len() as f64;
    let s0 = s.iter().sum::<Vector3<f64>>() / k;
    let m0 = m.iter().sum::<Vector3<f64>>() / k;
    let mut h = Matrix3::zeros();
    for (a, b) in s.iter().zip(m) {
        h += (a - s0) * (b - m0).transpose();
    }
    // Collinear fixture points leave the rotation about their line open.
    let spread: Matrix3<f64> = s.iter().map(|a| (a - s0) * (a - s0).transpose()).sum();
    let ev = spread.symmetric_eigenvalues();
    let (lo, hi) = (ev.min(), ev.max());
    if hi <= 0.0 || ev.iter().filter(|&&e| e > 1e-12 * hi).count() < 2 || lo < -1e-9 * hi {
        return Err(bad("the fixture points lie on a line".into()));
    }
    let svd = h.svd(true, true);
    let (u, vt) = (svd.u.expect("u"), svd.v_t.expect("v_t"));
    let v = vt.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    let c = m0 - r * s0;
    let rms = (s
        .iter()
        .zip(m)
        .map(|(a, b)| (r * a + c - b).norm_squared())
        .sum::<f64>()
        / k)
        .sqrt();
    Ok((c, r, rms))
}
