//! Second derivatives of the actuator coordinates in the pose coordinates, from the
//! mechanism's own analytic accelerations.
//!
//! [`Mechanism::actuator_motion`] gives `q'' = J x'' + x'^T H x'` (per actuator) without
//! finite differences, so with `x'' = 0` it gives the quadratic form `Q(v) = v^T H v`,
//! and by polarisation `H_jk = (Q(e_j + e_k) - Q(e_j) - Q(e_k)) / 2`: `A (A + 1) / 2`
//! motion evaluations over the driven coordinates, exact to rounding.

use nalgebra::{SMatrix, SVector};

use crate::error::Result;
use crate::mechanism::Mechanism;

/// The Hessian `H_i = d^2 q_i / dx^2` of every actuator over the driven coordinates
/// (`A x A` each, in the order of [`crate::mechanism::MechanismInfo::driven`]) at `x`.
pub fn actuator_hessians<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<[SMatrix<f64, A, A>; A]>
where
    M: Mechanism<P, A> + ?Sized,
{
    let d = m.info().driven();
    let zero = SVector::<f64, P>::zeros();
    let quadratic = |a: usize, b: Option<usize>| -> Result<SVector<f64, A>> {
        let mut v = SVector::<f64, P>::zeros();
        v[d[a]] = 1.0;
        if let Some(b) = b {
            v[d[b]] = 1.0;
        }
        Ok(m.actuator_motion(x, &v, &zero)?.qdd)
    };
    let mut diag = [SVector::<f64, A>::zeros(); A];
    for (a, q) in diag.iter_mut().enumerate() {
        *q = quadratic(a, None)?;
    }
    let mut h = [SMatrix::<f64, A, A>::zeros(); A];
    for a in 0..A {
        for (i, hi) in h.iter_mut().enumerate() {
            hi[(a, a)] = diag[a][i];
        }
        for b in a + 1..A {
            let both = quadratic(a, Some(b))?;
            for (i, hi) in h.iter_mut().enumerate() {
                let v = 0.5 * (both[i] - diag[a][i] - diag[b][i]);
                hi[(a, b)] = v;
                hi[(b, a)] = v;
            }
        }
    }
    Ok(h)
}
