//! Hexapod forward kinematics: Newton on SE(3).
//!
//! Unknowns: the tool tip `p` and the rotation `R`. Residual `r = L(p, R) - q`. Each step
//! solves `J_twist d = r` with the analytic twist Jacobian and updates
//! `p <- p - t d_v`, `R <- exp(-t [d_w]x) R` — a proper rotation update, unlike an
//! update of roll/pitch/yaw by an angular-velocity step (genhexkins). The step `t` is
//! halved until the residual decreases. A (nearly) singular Jacobian is reported as
//! [`Error::Singular`], never returned as a pose.

use nalgebra::{Matrix3, Rotation3, Vector3, Vector6};

use super::Hexapod;
use crate::error::{Error, Result};
use crate::linalg::{norm1, rcond1, SmallLu};

/// Settings of the hexapod FK solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FkOptions {
    /// Largest number of Newton iterations.
    pub max_iterations: usize,
    /// Converged when every strut length is within this (mm).
    pub tolerance: f64,
    /// Ratio of the smallest to the largest LU pivot of the scaled Jacobian below which
    /// the pose is reported as singular.
    pub min_rcond: f64,
    /// Largest pose uncertainty (mm, from the residual times `|J^-1|`) accepted at
    /// convergence; beyond it the configuration is reported as singular.
    pub max_pose_uncertainty: f64,
}

impl Default for FkOptions {
    fn default() -> Self {
        FkOptions {
            max_iterations: 40,
            tolerance: 1e-11,
            min_rcond: 1e-9,
            max_pose_uncertainty: 1e-8,
        }
    }
}

/// A forward solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FkReport {
    /// Tool tip (mm).
    pub position: Vector3<f64>,
    /// Platform rotation.
    pub rotation: Matrix3<f64>,
    /// Linear solves used.
    pub iterations: usize,
    /// Largest strut length residual (mm).
    pub residual: f64,
}

/// Newton on SE(3) from `(p0, r0)` to strut lengths `q`.
pub fn solve(
    h: &Hexapod,
    q: &Vector6<f64>,
    p0: &Vector3<f64>,
    r0: &Matrix3<f64>,
    o: &FkOptions,
) -> Result<FkReport> {
    let mut p = *p0;
    let mut r = *r0;
    let mut res_v = h.lengths(&p, &r) - q;
    let mut res = res_v.amax();
    let lc = h.characteristic_length;
    // Smallest LU pivot of the last step: the pose uncertainty is about
    // 6 * residual / pivot (cheap); the exact |J^-1| is computed only when that is large.
    let mut min_pivot = 0.0;
    for it in 0..o.max_iterations {
        if res <= o.tolerance {
            let tol = o.tolerance.max(res);
            let cheap_ok = it > 0 && 6.0 * tol / min_pivot <= o.max_pose_uncertainty;
            let inv_norm = if cheap_ok {
                0.0
            } else {
                let j = h.scaled_twist_jacobian(&p, &r);
                SmallLu::new(&j)
                    .map(|lu| norm1(&lu.inverse()))
                    .unwrap_or(f64::INFINITY)
            };
            // Refuse a (near-)singular solution: the lengths do not determine it.
            if !(inv_norm * tol <= o.max_pose_uncertainty) {
                let j = h.scaled_twist_jacobian(&p, &r);
                return Err(Error::Singular {
                    what: format!(
                        "hexapod forward kinematics: the strut lengths do not determine the pose near \
                         X={:.3} Y={:.3} Z={:.3} mm (singular configuration)",
                        p.x, p.y, p.z
                    ),
                    rcond: rcond1(&j),
                });
            }
            return Ok(FkReport {
                position: p,
                rotation: r,
                iterations: it,
                residual: res,
            });
        }
        let j = h.scaled_twist_jacobian(&p, &r);
        let lu = SmallLu::new(&j);
        let (lo, hi) = lu.map(|l| l.pivot_range()).unwrap_or((0.0, 1.0));
        min_pivot = lo;
        let rc = if hi > 0.0 { lo / hi } else { 0.0 };
        let lu = match lu {
            Some(lu) if rc >= o.min_rcond => lu,
            _ => {
                return Err(Error::Singular {
                    what: format!(
                        "hexapod forward kinematics: the Jacobian is singular near X={:.3} Y={:.3} Z={:.3} mm",
                        p.x, p.y, p.z
                    ),
                    rcond: rc,
                })
            }
        };
        let d = lu.solve(&res_v);
        let dv = Vector3::new(d[0], d[1], d[2]);
        let dw = Vector3::new(d[3], d[4], d[5]) / lc;
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let pn = p - dv * t;
            let rn = Rotation3::new(-dw * t).matrix() * r;
            let vn = h.lengths(&pn, &rn) - q;
            let resn = vn.amax();
            if resn < res || resn <= o.tolerance {
                p = pn;
                r = rn;
                res_v = vn;
                res = resn;
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            return Err(Error::NotConverged {
                solver: "hexapod forward kinematics",
                iterations: it + 1,
                residual: res,
            });
        }
    }
    if res <= o.tolerance {
        Ok(FkReport {
            position: p,
            rotation: r,
            iterations: o.max_iterations,
            residual: res,
        })
    } else {
        Err(Error::NotConverged {
            solver: "hexapod forward kinematics",
            iterations: o.max_iterations,
            residual: res,
        })
    }
}
