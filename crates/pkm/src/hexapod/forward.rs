//! Hexapod forward kinematics: Newton on SE(3).
//!
//! Unknowns: the tool tip `p` and the rotation `R`. Residual `r = L(p, R) - q`. Each step
//! solves `J_twist d = r` with the analytic twist Jacobian and updates
//! `p <- p - t d_v`, `R <- exp(-t [d_w]x) R` — a proper rotation update, unlike an
//! update of roll/pitch/yaw by an angular-velocity step (genhexkins). The step `t` is
//! halved until the residual decreases. A (nearly) singular Jacobian is reported as
//! [`Error::Singular`], never returned as a pose.
//!
//! Once a full step is small (below [`FkOptions::chord_step`]) the factorised Jacobian
//! is kept for the following steps (simplified Newton): near the solution it changes by
//! about the step over the strut length, so each kept step still gains three to four
//! digits, and it saves the factorisation that dominates a step's cost. A kept step
//! that does not reduce the residual tenfold triggers a fresh Jacobian.

use nalgebra::{Matrix3, SMatrix, Vector3, Vector6};

use super::Hexapod;
use crate::error::{Error, Result};
use crate::linalg::{max_abs, norm1, rcond1, SmallLu};

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
    /// A full Newton step shorter than this (mm, rotation scaled by the characteristic
    /// length) keeps the factorised Jacobian for the next steps; 0 = always Newton.
    pub chord_step: f64,
}

impl Default for FkOptions {
    fn default() -> Self {
        FkOptions {
            max_iterations: 40,
            tolerance: 1e-11,
            min_rcond: 1e-9,
            max_pose_uncertainty: 1e-8,
            chord_step: 0.5,
        }
    }
}

impl FkOptions {
    /// These options for strut lengths `q`: the residual tolerance no finer than
    /// rounding allows (8 ulp of the longest length: 1.8e-12 mm on a 1 m strut, below
    /// the default 1e-11; 1.8e-10 mm on a 100 m one, where 1e-11 is 1e-16 relative and
    /// rounding alone exceeds it), and the pose uncertainty accepted at convergence
    /// scaled alike (1e-8 mm per metre of strut beyond the first).
    fn for_lengths(&self, q: &Vector6<f64>) -> FkOptions {
        let size = max_abs(q);
        FkOptions {
            tolerance: self.tolerance.max(8.0 * f64::EPSILON * size),
            max_pose_uncertainty: self.max_pose_uncertainty.max(1e-11 * size),
            ..*self
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

/// The nearest proper rotation to an almost-orthonormal `m` (Gram-Schmidt on the
/// first two columns, the third their cross product).
fn orthonormalize(m: &Matrix3<f64>) -> Matrix3<f64> {
    let c0 = m.column(0).normalize();
    let c1 = m.column(1) - c0 * c0.dot(&m.column(1));
    let c1 = c1.normalize();
    Matrix3::from_columns(&[c0, c1, c0.cross(&c1)])
}

/// `exp([w]x)` by Rodrigues' formula (a proper rotation for any `w`).
#[inline]
fn exp_so3(w: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = w.norm_squared();
    let k = Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0);
    let (a, b) = if t2 < 1e-6 {
        // sin t / t and (1 - cos t) / t^2 by their series, to rounding for |t| < 1e-3
        // (the next terms are below t^6 / 5040): the small steps near convergence
        // skip the sine and cosine.
        (
            1.0 - t2 * (1.0 / 6.0) * (1.0 - t2 * (1.0 / 20.0)),
            0.5 - t2 * (1.0 / 24.0) * (1.0 - t2 * (1.0 / 30.0)),
        )
    } else {
        let t = t2.sqrt();
        let (s, c) = t.sin_cos();
        (s / t, (1.0 - c) / t2)
    };
    Matrix3::identity() + k * a + k * k * b
}

/// Newton on SE(3) from `(p0, r0)` to strut lengths `q`.
pub fn solve(
    h: &Hexapod,
    q: &Vector6<f64>,
    p0: &Vector3<f64>,
    r0: &Matrix3<f64>,
    o: &FkOptions,
) -> Result<FkReport> {
    solve_from(h, q, p0, r0, &mut None, o)
}

/// Forward kinematics along a stream of strut lengths (a trajectory sampled at a
/// controller's rate, encoder readings): the per-stream scratch state of
/// [`FkTracker::track`], kept by the caller while the model stays shared.
///
/// Each solve starts from the previous pose with the previous solve's factorised
/// Jacobian (the Jacobian changes by about the pose step over the strut length, so
/// kept-Jacobian steps converge at once); a step that does not cut the residual
/// tenfold refactorises, so a jump in the stream costs a full Newton solve, never a
/// wrong pose.
#[derive(Debug, Clone)]
pub struct FkTracker {
    p: Vector3<f64>,
    r: Matrix3<f64>,
    /// The pose before, for a linear prediction of the next one.
    prev: Option<(Vector3<f64>, Matrix3<f64>)>,
    lu: Option<(SmallLu<6>, f64)>,
    options: FkOptions,
}

impl FkTracker {
    /// A tracker starting at pose coordinates `start` (X..C).
    pub fn new(start: &Vector6<f64>, options: FkOptions) -> Self {
        let (p, r) = crate::legs::split_pose(start);
        FkTracker {
            p,
            r,
            prev: None,
            lu: None,
            options,
        }
    }

    /// The pose for strut lengths `q`, started from the last pose found moved on by
    /// the last step (a linear prediction: at a controller's rate the next pose is
    /// closer to it than to the last one), or from the last pose after a large step.
    pub fn track(&mut self, h: &Hexapod, q: &Vector6<f64>) -> Result<FkReport> {
        let (p0, r0) = match self.prev {
            Some((pp, rp)) if (self.p - pp).norm() < 5.0 => {
                let dr = self.r * rp.transpose();
                // Products of rotations drift from orthonormality, and the solver keeps
                // whatever drift its start has: re-orthonormalise the prediction.
                (2.0 * self.p - pp, orthonormalize(&(dr * self.r)))
            }
            _ => (self.p, self.r),
        };
        let mut lu = self.lu;
        let rep = match solve_from(h, q, &p0, &r0, &mut lu, &self.options) {
            Ok(x) => x,
            // A prediction can overshoot at a sharp turn: retry from the last pose.
            Err(_) => {
                lu = None;
                solve_from(h, q, &self.p, &self.r, &mut lu, &self.options)?
            }
        };
        self.prev = Some((self.p, self.r));
        self.p = rep.position;
        self.r = rep.rotation;
        self.lu = lu;
        Ok(rep)
    }
}

/// The factorisation `lu` kept for the next solve with its smallest pivot, or dropped.
#[inline(always)]
fn keep(lu: &mut Option<(SmallLu<6>, f64)>, worth_it: bool, min_pivot: f64) {
    match lu {
        Some(l) if worth_it => l.1 = min_pivot,
        _ => *lu = None,
    }
}

/// [`solve`] with an optional factorisation (and its smallest pivot) to start with,
/// replaced in place by the factorisation in use at the end (`None`: not worth
/// keeping). In place, not passed and returned: the hexapod's Monte Carlo solves
/// once per machine, and moving the 400-byte factorisation in and out was 4 % of it.
fn solve_from(
    h: &Hexapod,
    q: &Vector6<f64>,
    p0: &Vector3<f64>,
    r0: &Matrix3<f64>,
    lu: &mut Option<(SmallLu<6>, f64)>,
    o: &FkOptions,
) -> Result<FkReport> {
    let o = &o.for_lengths(q);
    let lc = h.info.characteristic_length();
    let inv_lc = 1.0 / lc;
    let soa = h.soa();
    let (l0, mut j) = soa.lengths_and_jacobian(p0, r0, lc);
    let res_v = l0 - q;
    let mut x = Iterate {
        p: *p0,
        r: *r0,
        res: max_abs(&res_v),
        res_v,
    };
    // j is the Jacobian at the current pose.
    let mut fresh = true;
    // Smallest LU pivot of the factorisation in use: the pose uncertainty is about
    // 6 * residual / pivot (cheap); the exact |J^-1| is computed only when that is large.
    let mut min_pivot = lu.as_ref().map(|l| l.1).unwrap_or(0.0);
    // A kept factorisation that converged slowly: not worth keeping for the next solve.
    let mut stale = false;
    for it in 0..o.max_iterations {
        if x.res <= o.tolerance {
            check_determined(h, &x, it, min_pivot, o)?;
            keep(lu, !stale, min_pivot);
            return Ok(x.report(it));
        }
        let chord = lu.is_some(); // the factorisation is kept from an earlier pose
        if lu.is_none() {
            if !fresh {
                j = soa.lengths_and_jacobian(&x.p, &x.r, lc).1;
            }
            let f = factorise(&j, &x.p, o)?;
            min_pivot = f.1;
            *lu = Some(f);
        }
        let d = lu.as_ref().map(|f| f.0.solve(&x.res_v)).unwrap_or_default();
        let res_before = x.res;
        let step = line_search(h, q, &mut x, &d, inv_lc, chord, o);
        fresh = false;
        let Some((t, aged)) = step else {
            if chord {
                // Retry this iteration with a fresh Jacobian.
                *lu = None;
                continue;
            }
            return Err(Error::NotConverged {
                solver: "hexapod forward kinematics",
                iterations: it + 1,
                residual: x.res,
            });
        };
        stale |= aged;
        // Keep the factorisation only after a small full step that cut the residual
        // tenfold (Newton's quadratic regime), or after a chord step that did.
        if !(t == 1.0 && d.norm() <= o.chord_step && x.res <= 0.1 * res_before) {
            *lu = None;
        }
    }
    if x.res <= o.tolerance {
        keep(lu, true, min_pivot);
        Ok(x.report(o.max_iterations))
    } else {
        Err(Error::NotConverged {
            solver: "hexapod forward kinematics",
            iterations: o.max_iterations,
            residual: x.res,
        })
    }
}

/// The Newton iterate: the pose and its strut length residual.
struct Iterate {
    p: Vector3<f64>,
    r: Matrix3<f64>,
    res_v: Vector6<f64>,
    /// Largest entry of `res_v`.
    res: f64,
}

impl Iterate {
    /// The solution this iterate is, after `iterations` linear solves.
    #[inline(always)]
    fn report(&self, iterations: usize) -> FkReport {
        FkReport {
            position: self.p,
            rotation: self.r,
            iterations,
            residual: self.res,
        }
    }
}

/// Refuses a converged pose that the strut lengths do not determine (a (near-)singular
/// configuration): its uncertainty, residual times `|J^-1|`, must be small.
#[inline]
fn check_determined(
    h: &Hexapod,
    x: &Iterate,
    it: usize,
    min_pivot: f64,
    o: &FkOptions,
) -> Result<()> {
    let (p, r) = (&x.p, &x.r);
    let tol = o.tolerance.max(x.res);
    let cheap_ok = it > 0 && 6.0 * tol / min_pivot <= o.max_pose_uncertainty;
    let inv_norm = if cheap_ok {
        0.0
    } else {
        let j = h.scaled_twist_jacobian(p, r);
        SmallLu::new(&j)
            .map(|lu| norm1(&lu.inverse()))
            .unwrap_or(f64::INFINITY)
    };
    // Refuse a (near-)singular solution: the lengths do not determine it.
    if !(inv_norm * tol <= o.max_pose_uncertainty) {
        let j = h.scaled_twist_jacobian(p, r);
        return Err(Error::Singular {
            what: format!(
                "hexapod forward kinematics: the strut lengths do not determine the pose near \
                 X={:.3} Y={:.3} Z={:.3} mm (singular configuration)",
                p.x, p.y, p.z
            ),
            rcond: rcond1(&j),
        });
    }
    Ok(())
}

/// Factorises the Jacobian `j` at `p`, with its smallest pivot, refusing a singular one.
#[inline(always)]
fn factorise(j: &SMatrix<f64, 6, 6>, p: &Vector3<f64>, o: &FkOptions) -> Result<(SmallLu<6>, f64)> {
    let f = SmallLu::new(j);
    let (lo, hi) = f.map(|l| l.pivot_range()).unwrap_or((0.0, 1.0));
    let rc = if hi > 0.0 { lo / hi } else { 0.0 };
    match f {
        Some(f) if rc >= o.min_rcond => Ok((f, lo)),
        _ => Err(Error::Singular {
            what: format!(
                "hexapod forward kinematics: the Jacobian is singular near X={:.3} Y={:.3} Z={:.3} mm",
                p.x, p.y, p.z
            ),
            rcond: rc,
        }),
    }
}

/// Moves `x` along the Newton step `d` (rotation part scaled by `inv_lc`), halving
/// the step until the residual decreases (a kept Jacobian, `chord`, gets the full
/// step only). Returns the step length taken and whether a kept Jacobian is getting
/// old, or `None` when no step was accepted.
#[inline(always)]
fn line_search(
    h: &Hexapod,
    q: &Vector6<f64>,
    x: &mut Iterate,
    d: &Vector6<f64>,
    inv_lc: f64,
    chord: bool,
    o: &FkOptions,
) -> Option<(f64, bool)> {
    let dv = Vector3::new(d[0], d[1], d[2]);
    let dw = Vector3::new(d[3], d[4], d[5]) * inv_lc;
    let mut t = 1.0;
    for _ in 0..30 {
        let pn = x.p - dv * t;
        let rn = exp_so3(&(-dw * t)) * x.r;
        let vn = h.lengths(&pn, &rn) - q;
        let resn = max_abs(&vn);
        if resn < x.res || resn <= o.tolerance {
            // A kept Jacobian must still pay: otherwise refresh it and retry.
            if chord && t == 1.0 && resn > 0.1 * x.res && resn > o.tolerance {
                return None;
            }
            // Still converging, but the kept Jacobian is getting old.
            let aged = chord && resn > 1e-3 * x.res && resn > o.tolerance;
            *x = Iterate {
                p: pn,
                r: rn,
                res_v: vn,
                res: resn,
            };
            return Some((t, aged));
        }
        if chord {
            return None;
        }
        t *= 0.5;
    }
    None
}
