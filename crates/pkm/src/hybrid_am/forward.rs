//! Forward kinematics of the seed-002 machine: the platform's four freedoms from the
//! four carriage readings by Newton's method, followed from the start's readings so the
//! platform stays on the start's assembly, then the tool relative to the part.

use nalgebra::{SMatrix, SVector, Vector3, Vector4, Vector6};

use super::HybridAm;
use crate::error::{Error, Result};
use crate::linalg::{rcond1, SmallLu};
use crate::mechanism::{Forward, Mechanism};
use crate::rotation::{ry, rz};

/// Largest Newton iterations per continuation step.
const MAX_ITERATIONS: usize = 50;
/// Strut-length residual at which the last step stops (mm).
const TOLERANCE: f64 = 1e-12;
/// Strut-length residual at which an intermediate step stops (mm).
const STEP_TOLERANCE: f64 = 1e-6;
/// Largest actuator residual of a returned solution (mm).
const ACCEPT: f64 = 1e-9;
/// Largest change of a carriage reading per continuation step, in strut lengths.
const STEP: f64 = 0.1;
/// Largest number of continuation steps.
const MAX_STEPS: usize = 200;

/// The platform: origin `O` (base frame) and tilt `beta`.
#[derive(Clone, Copy)]
struct Platform {
    origin: Vector3<f64>,
    beta: f64,
}

/// The pose with readings `q`, from the platform of `start` (A held from `start`).
///
/// Unknowns: the platform origin `O` (base frame) and its tilt `beta`. Equations
/// `f_i = |O + Ry(beta) rho_i - c_i| - L_i = 0` with `c_i = g_i + q_i e_z`; rows of the
/// Jacobian `[n_i^T, n_i . (e_y x Ry(beta) rho_i)]`, `n_i` the unit strut vector; each
/// step halved until the residual decreases. The readings move from the start's to `q`
/// in steps of at most a tenth of a strut, each solved from the last, as the machine
/// itself moves: a distant start cannot jump to another assembly of the platform. Then
/// the tip `p_b = O + Ry(beta) t`, `p = Rz(C) (p_b - c_t)`, `B = beta + gamma` (the turn
/// nearest the start's), `C = q5`. Should the path of readings leave the machine's
/// reach, Newton's method from the start alone is tried before failing.
pub(super) fn forward(
    m: &HybridAm,
    q: &SVector<f64, 5>,
    start: &Vector6<f64>,
) -> Result<Forward<6>> {
    let shortest = m
        .legs
        .iter()
        .map(|l| l.length)
        .fold(f64::INFINITY, f64::min);
    let from = m.inverse(start).ok();
    if let Some(q0) = &from {
        // The start is the solution already (a re-solve with nothing moved).
        let residual = (q0 - q).amax();
        if residual <= TOLERANCE {
            return Ok(Forward {
                pose: *start,
                iterations: 0,
                residual,
            });
        }
    }
    let steps = match &from {
        Some(q0) => {
            let dq = (0..4).map(|i| (q[i] - q0[i]).abs()).fold(0.0, f64::max);
            ((dq / (STEP * shortest)).ceil() as usize).clamp(1, MAX_STEPS)
        }
        None => 1,
    };
    match solve(m, q, start, from.as_ref(), steps) {
        Err(_) if steps > 1 => solve(m, q, start, None, 1),
        r => r,
    }
}

/// [`forward`] in `steps` steps of the readings from `from` (the start's).
fn solve(
    m: &HybridAm,
    q: &SVector<f64, 5>,
    start: &Vector6<f64>,
    from: Option<&SVector<f64, 5>>,
    steps: usize,
) -> Result<Forward<6>> {
    let pl = m.placement(start);
    let mut platform = Platform {
        origin: pl.tip - pl.rotation * m.tool,
        beta: pl.beta,
    };
    let mut iterations = 0;
    let mut res = f64::INFINITY;
    for k in 1..=steps {
        let qk: Vector4<f64> = match from {
            Some(q0) if k < steps => {
                Vector4::from_fn(|i, _| q0[i] + (q[i] - q0[i]) * k as f64 / steps as f64)
            }
            _ => Vector4::from_fn(|i, _| q[i]),
        };
        let tolerance = if k < steps { STEP_TOLERANCE } else { TOLERANCE };
        let (p, it, r) = newton(m, &qk, platform, tolerance)?;
        (platform, res) = (p, r);
        iterations += it;
    }
    let tip = platform.origin + ry(platform.beta) * m.tool;
    let p = rz(q[4]) * (tip - m.table);
    // The tilt is periodic: B is taken nearest to the start's.
    let b = platform.beta + m.tool_tilt;
    let b = start[4] + crate::rotation::wrap_angle(b - start[4]);
    let pose = Vector6::new(p.x, p.y, p.z, start[3], b, q[4]);
    let residual = match m.inverse(&pose) {
        Ok(qi) => (qi - q).amax(),
        Err(_) => f64::INFINITY,
    };
    if !(residual <= ACCEPT) {
        return Err(Error::NotConverged {
            solver: "forward kinematics of the seed-002 machine (Newton)",
            iterations,
            residual: if residual.is_finite() { residual } else { res },
        });
    }
    Ok(Forward {
        pose,
        iterations,
        residual,
    })
}

/// Newton's method on the strut equations with readings `q` from `p`: the platform,
/// the iterations used and the final largest strut-length residual (mm). Stops at
/// `tolerance` or when no step decreases the residual.
fn newton(
    m: &HybridAm,
    q: &Vector4<f64>,
    mut p: Platform,
    tolerance: f64,
) -> Result<(Platform, usize, f64)> {
    let c: [Vector3<f64>; 4] = std::array::from_fn(|i| m.carriage_joint(i, q[i]));
    let residual = |p: &Platform| -> Vector4<f64> {
        let r = ry(p.beta);
        Vector4::from_fn(|i, _| {
            (p.origin + r * m.legs[i].platform - c[i]).norm() - m.legs[i].length
        })
    };
    let mut f = residual(&p);
    let mut res = f.amax();
    let mut iterations = 0;
    // At the final tolerance, one more full step once it is met: quadratic convergence
    // takes the residual to rounding, which near a forward singularity (condition in
    // the thousands) is what keeps the pose itself within 1e-9 mm.
    let mut polish = tolerance <= TOLERANCE;
    while (res > tolerance || polish) && iterations < MAX_ITERATIONS {
        if res <= tolerance {
            polish = false;
        }
        iterations += 1;
        let r = ry(p.beta);
        let mut j = SMatrix::<f64, 4, 4>::zeros();
        for i in 0..4 {
            let arm = r * m.legs[i].platform;
            let s = p.origin + arm - c[i];
            let n = s / s.norm().max(1e-300);
            j[(i, 0)] = n.x;
            j[(i, 1)] = n.y;
            j[(i, 2)] = n.z;
            j[(i, 3)] = n.dot(&Vector3::y().cross(&arm));
        }
        let rc = rcond1(&j);
        let step = match SmallLu::new(&j) {
            Some(lu) if rc >= 1e-12 => lu.solve(&f),
            _ => {
                return Err(Error::Singular {
                    what: "platform of the seed-002 machine (forward singularity)".into(),
                    rcond: rc,
                })
            }
        };
        let mut t = 1.0;
        let mut accepted = false;
        let polishing = res <= tolerance;
        for _ in 0..if polishing { 1 } else { 30 } {
            let next = Platform {
                origin: p.origin - t * Vector3::new(step[0], step[1], step[2]),
                beta: p.beta - t * step[3],
            };
            let fnew = residual(&next);
            if fnew.amax() < res || (polishing && fnew.amax() <= res) {
                (p, f, res) = (next, fnew, fnew.amax());
                accepted = true;
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    Ok((p, iterations, res))
}
