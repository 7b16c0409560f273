//! The arm's numeric inverse kinematics, for any geometry and as the closed form's
//! polish and check: Newton on SE(3) with the geometric Jacobian (damped least squares
//! near singular configurations, steps limited and halved until the error decreases),
//! restarts from joint values spread over the ranges when it stalls, and a truncated
//! pseudo-inverse onto singular solutions.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

use super::SerialArm;
use crate::error::{Error, Result, Unattainable};
use crate::rotation::rotation_vector;
use crate::units::Quantity;
use std::f64::consts::PI;

/// Settings of the arm's inverse kinematics.
const MAX_ITERATIONS: usize = 60;
/// Converged when the position error is below this (mm) ...
const POSITION_TOLERANCE: f64 = 1e-10;
/// ... and the orientation error below this (rad).
const ORIENTATION_TOLERANCE: f64 = 1e-13;
/// Largest joint step of one Newton iteration (rad or mm): keeps the iteration on its
/// branch far from the solution.
const MAX_STEP: f64 = 0.3;
/// Restarts from spread joint values when Newton stalls from the given start. Eight
/// left 1 in 450 of a UR5's reachable poses unsolved; with 32, none
/// of 10^5 per example robot (`examples/roundtrip_campaign.rs`). A stalled start gives
/// up within ten iterations, so an unreachable pose costs about 33 x 10 of them.
const RESTARTS: usize = 32;

/// Which iteration [`SerialArm::descend`] runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Descent {
    /// Newton, damped least squares near singular configurations, stall test.
    Damped,
    /// Truncated pseudo-inverse, no stall test (onto singular solutions).
    PseudoInverse,
}

impl SerialArm {
    pub(super) fn inverse_with(
        &self,
        x: &Vector6<f64>,
        start: &Vector6<f64>,
        closed_form: bool,
    ) -> Result<Vector6<f64>> {
        // A NaN target would reach the SVD of the singular descent, which never
        // returns on NaN (nalgebra iterates until convergence).
        if let Some(k) = x.iter().chain(start.iter()).position(|v| !v.is_finite()) {
            let (what, k) = if k < 6 {
                ("pose", k)
            } else {
                ("start joints", k - 6)
            };
            return Err(Error::InvalidInput {
                what: what.into(),
                message: format!("value {k} is not a finite number"),
            });
        }
        let target_p = Vector3::new(x[0], x[1], x[2]);
        let distance = (target_p - self.base_origin).norm();
        if distance > self.reach * (1.0 + 1e-12) {
            return Err(Error::NotAttainable {
                reason: Unattainable::BeyondReach {
                    distance,
                    reach: self.reach,
                },
            });
        }
        let target_r = crate::rotation::rpy_matrix(x[3], x[4], x[5]);
        if closed_form {
            let mut sols = [Vector6::zeros(); 8];
            match self.closed_form(&target_p, &target_r, start, false, &mut sols) {
                Err(reason) => return Err(Error::NotAttainable { reason }),
                Ok(Some(n)) if n > 0 => return Ok(sols[0]),
                // Not in closed form, or Newton could not polish a closed-form
                // solution (a pose at a singular configuration): numerically below.
                Ok(_) => {}
            }
        }
        let mut best = f64::INFINITY;
        let mut best_q = *start;
        let mut iterations = 0;
        for k in 0..=RESTARTS {
            let q0 = if k == 0 { *start } else { self.spread_start(k) };
            match self.newton(&target_p, &target_r, q0) {
                Ok(q) => return Ok(self.wrap(q, start)),
                Err((residual, it, q)) => {
                    if residual < best {
                        (best, best_q) = (residual, q);
                    }
                    iterations += it;
                }
            }
        }
        // Every start stalled: the solution may be a singular configuration (a wrist
        // centre on the first axis), where damped steps cannot remove the error along
        // the lost direction. Gauss-Newton with a truncated pseudo-inverse from the
        // closest point found.
        match self.singular_newton(&target_p, &target_r, best_q) {
            Ok(q) => return Ok(self.wrap(q, start)),
            Err((residual, it, _)) => {
                best = best.min(residual);
                iterations += it;
            }
        }
        Err(Error::NotConverged {
            solver: "serial robot inverse kinematics (Newton on SE(3))",
            iterations,
            residual: best,
        })
    }

    /// Every inverse solution: in closed form where it applies (all of them, up to 8:
    /// shoulder left/right, elbow up/down, wrist flipped or not; `starts` unused), else
    /// those Newton finds from the home joints and `starts - 1` joint values spread over
    /// the ranges (a general 6R has up to 16). Distinct to 1e-6 modulo whole turns,
    /// revolute joints shifted by whole turns into their ranges where they fit, nearest
    /// to home first. Joint limits are not checked here.
    pub fn inverse_solutions(&self, x: &Vector6<f64>, starts: usize) -> Vec<Vector6<f64>> {
        use std::f64::consts::TAU;
        let target_p = Vector3::new(x[0], x[1], x[2]);
        if (target_p - self.base_origin).norm() > self.reach * (1.0 + 1e-12) {
            return Vec::new();
        }
        let target_r = crate::rotation::rpy_matrix(x[3], x[4], x[5]);
        let mut sols = [Vector6::zeros(); 8];
        let found: Vec<Vector6<f64>> =
            match self.closed_form(&target_p, &target_r, &self.home_joints, true, &mut sols) {
                Err(_) => Vec::new(),
                Ok(Some(n)) if n > 0 => sols[..n].to_vec(),
                // Not in closed form, or no closed-form posture Newton could polish (as
                // in `inverse_from`): the spread starts.
                Ok(_) => (0..starts.max(1))
                    .filter_map(|k| {
                        let q0 = if k == 0 {
                            self.home_joints
                        } else {
                            self.spread_start(k)
                        };
                        self.newton(&target_p, &target_r, q0).ok()
                    })
                    .collect(),
            };
        let mut out: Vec<Vector6<f64>> = Vec::new();
        for q in found {
            let mut q = self.wrap(q, &self.home_joints);
            for (i, a) in self.info.actuators().iter().enumerate() {
                if a.quantity == Quantity::Angle {
                    while q[i] < a.range.min && q[i] + TAU <= a.range.max {
                        q[i] += TAU;
                    }
                    while q[i] > a.range.max && q[i] - TAU >= a.range.min {
                        q[i] -= TAU;
                    }
                }
            }
            // The same posture modulo whole turns of revolute joints counts once.
            let same = |o: &Vector6<f64>| {
                (0..6).all(|i| {
                    let d = (o[i] - q[i]).abs();
                    if self.info.actuators()[i].quantity == Quantity::Angle {
                        let d = d.rem_euclid(TAU);
                        d.min(TAU - d) < 1e-6
                    } else {
                        d < 1e-6
                    }
                })
            };
            if !out.iter().any(same) {
                out.push(q);
            }
        }
        out.sort_by(|a, b| {
            (a - self.home_joints)
                .amax()
                .total_cmp(&(b - self.home_joints).amax())
        });
        out
    }

    /// The `k`-th restart: a Halton point of the joints' ranges (clipped to one turn).
    fn spread_start(&self, k: usize) -> Vector6<f64> {
        const PRIMES: [usize; 6] = [2, 3, 5, 7, 11, 13];
        Vector6::from_fn(|i, _| {
            let range = self.info.actuators()[i].range;
            let (lo, hi) = (range.min.max(-PI), range.max.min(PI));
            lo + crate::mechanism::halton(k, PRIMES[i]) * (hi - lo)
        })
    }

    /// Pose error `[dp; dw]` at `q` and its weighted norm.
    fn pose_error(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        q: &Vector6<f64>,
    ) -> (Vector6<f64>, Matrix6<f64>, f64) {
        let (t, j) = self.pose_and_jacobian(q);
        let dp = p - Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]);
        let rt: Matrix3<f64> = t.fixed_view::<3, 3>(0, 0).into_owned();
        let dw = rotation_vector(&(r * rt.transpose()));
        let e = Vector6::new(dp.x, dp.y, dp.z, dw.x, dw.y, dw.z);
        (
            e,
            j,
            dp.norm().max(dw.norm() * self.info.characteristic_length()),
        )
    }

    /// Newton from `q`; on failure the residual, the iterations spent and the joints
    /// reached.
    pub(super) fn newton(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        q: Vector6<f64>,
    ) -> std::result::Result<Vector6<f64>, (f64, usize, Vector6<f64>)> {
        self.descend(p, r, q, Descent::Damped)
    }

    /// Gauss-Newton with the pseudo-inverse of the scaled Jacobian (singular values
    /// below 1e-10 of the largest dropped) and no stall test: converges, linearly at
    /// worst, onto a singular solution, where damped steps cannot remove the error along
    /// the lost direction.
    fn singular_newton(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        q: Vector6<f64>,
    ) -> std::result::Result<Vector6<f64>, (f64, usize, Vector6<f64>)> {
        self.descend(p, r, q, Descent::PseudoInverse)
    }

    /// The iteration of [`SerialArm::newton`] and [`SerialArm::singular_newton`]: steps
    /// limited to [`MAX_STEP`], halved until the error decreases.
    fn descend(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        mut q: Vector6<f64>,
        how: Descent,
    ) -> std::result::Result<Vector6<f64>, (f64, usize, Vector6<f64>)> {
        let damped = how == Descent::Damped;
        let (max_iterations, halvings) = if damped {
            (MAX_ITERATIONS, 12)
        } else {
            (4 * MAX_ITERATIONS, 20)
        };
        let (mut e, mut j, mut norm) = self.pose_error(p, r, &q);
        // Progress check of the damped steps: an iteration that has not cut the error
        // by 0.1 % in ten iterations is stuck (a local minimum of the error, typically
        // an unreachable target); give up and let the caller restart elsewhere.
        let mut norm_before = norm;
        for it in 0..max_iterations {
            if damped && it > 0 && it % 10 == 0 {
                if norm > 0.999 * norm_before {
                    return Err((norm, it, q));
                }
                norm_before = norm;
            }
            let converged = e.fixed_rows::<3>(0).norm() <= POSITION_TOLERANCE
                && e.fixed_rows::<3>(3).norm() <= ORIENTATION_TOLERANCE;
            let step = if damped {
                Some(self.step(&j, &e))
            } else {
                self.pseudo_inverse_step(&j, &e)
            };
            let Some(mut dq) = step else {
                return Err((norm, it, q));
            };
            if converged {
                // Damped: one polishing step, quadratic convergence takes the error to
                // rounding. At a singular solution the pseudo-inverse step is not
                // quadratic: the point reached is returned.
                return Ok(if damped { q + dq } else { q });
            }
            let big = dq.amax();
            if big > MAX_STEP {
                dq *= MAX_STEP / big;
            }
            let mut improved = false;
            for _ in 0..halvings {
                let qn = q + dq;
                let (en, jn, nn) = self.pose_error(p, r, &qn);
                if nn < norm {
                    (q, e, j, norm) = (qn, en, jn, nn);
                    improved = true;
                    break;
                }
                dq *= 0.5;
            }
            if !improved {
                return Err((norm, it + 1, q));
            }
        }
        Err((norm, max_iterations, q))
    }

    /// The truncated pseudo-inverse step `J+ e` in the scaled space (angular rows
    /// times the characteristic length).
    fn pseudo_inverse_step(&self, j: &Matrix6<f64>, e: &Vector6<f64>) -> Option<Vector6<f64>> {
        let lc = self.info.characteristic_length();
        let mut js = *j;
        let mut es = *e;
        for k in 3..6 {
            js.row_mut(k).scale_mut(lc);
            es[k] *= lc;
        }
        if !js.iter().chain(es.iter()).all(|v| v.is_finite()) {
            return None;
        }
        // Bounded iterations: never more than a few dozen on a finite 6x6.
        let svd = js.try_svd(true, true, f64::EPSILON, 10_000)?;
        svd.solve(&es, 1e-10 * svd.singular_values.max()).ok()
    }

    /// The Newton step: `J^-1 e` when `J` is well conditioned, else damped least squares
    /// in the scaled space (angular rows times the characteristic length).
    fn step(&self, j: &Matrix6<f64>, e: &Vector6<f64>) -> Vector6<f64> {
        let lc = self.info.characteristic_length();
        let mut js = *j;
        let mut es = *e;
        for r in 3..6 {
            js.row_mut(r).scale_mut(lc);
            es[r] *= lc;
        }
        // nalgebra's `js.lu().try_inverse()`, bit for bit (refused where a pivot is
        // not finite, where nalgebra returns NaN: the damped step below then).
        if let Some(inv) = crate::linalg::inverse_lu(&js) {
            // Reciprocal condition estimate in the 1-norm.
            let rcond = 1.0 / (crate::linalg::norm1(&js) * crate::linalg::norm1(&inv));
            if rcond > 1e-8 {
                return inv * es;
            }
        }
        let damping = 1e-3 * lc;
        let jjt = js * js.transpose() + Matrix6::identity() * (damping * damping);
        match jjt.try_inverse() {
            Some(inv) => js.transpose() * (inv * es),
            None => Vector6::zeros(),
        }
    }
}
