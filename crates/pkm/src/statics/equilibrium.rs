//! The exact (large-deflection) equilibrium of a mechanism whose drives are springs.
//!
//! The drives hold their positions `q0 = IK(x0)`; under wrench `w` the tool moves to the
//! pose `x` where the springs' forces `tau(x) = -k (q(x) - q0)` balance the wrench:
//! `f(x) = J(x)^T tau(x) + T(x)^T w = 0` (driven coordinates). Newton's method on `f`,
//! whose derivative is minus the tangent stiffness `K_x` ([`super::stiffness`]), so the
//! iteration converges quadratically when the load-dependent term is right.

use nalgebra::{SVector, Vector3, Vector6};

use super::{lu_of, pose_stiffness, wrench, Wrench};
use crate::error::{Error, Result};
use crate::mechanism::{driven_jacobian, Mechanism};

/// Newton stops when every unbalanced generalised force is below this fraction of the
/// size of its terms (the drives' and the wrench's; at least the wrench's largest
/// component, or 1e-9 N without a wrench).
pub const EQUILIBRIUM_TOLERANCE: f64 = 1e-10;

const MAX_ITERATIONS: usize = 50;

/// The tool's deflection (mm, rad: the tip's displacement, then the rotation vector of
/// the tool frame's turn, base frame; for a freely spinning tool the turn that tilts
/// its axis) when wrench `w` loads the machine standing at
/// `x0` with its drives, springs of stiffness `k`, locked. Fails with
/// [`Error::NotConverged`] and the residual when no equilibrium is found (a load that
/// buckles the machine or drives it through a singularity).
pub fn deflection_exact<M, const P: usize, const A: usize>(
    m: &M,
    x0: &SVector<f64, P>,
    w: &Wrench,
    k: &SVector<f64, A>,
) -> Result<Vector6<f64>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let x = equilibrium(m, x0, w, k)?;
    let p0 = m.tool_pose(x0)?;
    let p1 = m.tool_pose(&x)?;
    let dr = p1.translation.vector - p0.translation.vector;
    let dtheta = if m.info().free_spin() {
        // The spindle's own spin is no deflection: the turn that tilts the axis.
        let (a0, a1) = (p0.rotation * Vector3::z(), p1.rotation * Vector3::z());
        let n = a0.cross(&a1);
        let s = n.norm();
        if s > 0.0 {
            n * (s.atan2(a0.dot(&a1)) / s)
        } else {
            Vector3::zeros()
        }
    } else {
        (p1.rotation * p0.rotation.inverse()).scaled_axis()
    };
    Ok(Vector6::new(dr.x, dr.y, dr.z, dtheta.x, dtheta.y, dtheta.z))
}

/// The equilibrium pose coordinates of [`deflection_exact`].
pub fn equilibrium<M, const P: usize, const A: usize>(
    m: &M,
    x0: &SVector<f64, P>,
    w: &Wrench,
    k: &SVector<f64, A>,
) -> Result<SVector<f64, P>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let d = m.info().driven();
    let q0 = m.inverse(x0)?;
    let scale = w.vector().amax().max(1e-9);
    let mut x = *x0;
    let mut residual = f64::INFINITY;
    for _ in 0..MAX_ITERATIONS {
        let q = m.inverse(&x)?;
        let tau = -k.component_mul(&(q - q0));
        let j = m.jacobian(&x)?;
        let jd = driven_jacobian(&j, &d);
        let qf = wrench::generalised_force(m, &x, w)?;
        let qd = SVector::<f64, A>::from_fn(|i, _| qf[d[i]]);
        let f = jd.transpose() * tau + qd;
        // Each equation against the size of its own terms: the moments' rows sum
        // forces times lever arms, whose rounding a force's scale would not allow.
        let terms = jd.abs().transpose() * tau.abs() + qd.abs();
        residual = (0..A)
            .map(|i| f[i].abs() / terms[i].max(scale))
            .fold(0.0, f64::max);
        if residual <= EQUILIBRIUM_TOLERANCE {
            return Ok(x);
        }
        let (kx, _) = pose_stiffness(m, &x, &j, &tau, w, k)?;
        let step = lu_of(&kx, "stiffness in pose coordinates (equilibrium)")?.solve(&f);
        for (i, s) in step.iter().enumerate() {
            x[d[i]] += s;
        }
        if !x.iter().all(|v| v.is_finite()) {
            break;
        }
    }
    Err(Error::NotConverged {
        solver: "static equilibrium under the wrench",
        iterations: MAX_ITERATIONS,
        residual,
    })
}
