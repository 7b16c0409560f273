//! What is written once over [`Mechanism`] for every machine type: Newton's forward
//! kinematics and its continuation along a path, the inverse with every limit
//! checked, the driven Jacobian and its scaling by the characteristic length, and the
//! spread starting poses that find a machine's assembly modes.

use nalgebra::{SMatrix, SVector};

use super::{Forward, Mechanism, PoseSpace};
use crate::error::{Error, Result};
use crate::linalg::{max_abs, rcond1, SmallLu};
use crate::pose::Pose;

/// Settings of [`newton_forward`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonOptions {
    /// Largest number of iterations.
    pub max_iterations: usize,
    /// Convergence tolerance on the largest actuator residual (mm or rad).
    pub tolerance: f64,
    /// Reciprocal condition number of the driven Jacobian below which the pose is
    /// reported as singular.
    pub min_rcond: f64,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            max_iterations: 50,
            tolerance: 1e-11,
            min_rcond: 1e-10,
        }
    }
}

/// The driven columns of the Jacobian at `x` with angle columns divided by the
/// characteristic length: every column in actuator units per mm (the matrix whose
/// conditioning [`Mechanism::condition`] reports by default).
pub fn scaled_driven_jacobian<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<SMatrix<f64, A, A>>
where
    M: Mechanism<P, A> + ?Sized,
{
    Ok(scale_driven_columns(m, &m.jacobian(x)?))
}

/// The driven columns of a Jacobian `j` of `m`, angle columns divided by the
/// characteristic length (see [`scaled_driven_jacobian`]).
pub fn scale_driven_columns<M, const P: usize, const A: usize>(
    m: &M,
    j: &SMatrix<f64, A, P>,
) -> SMatrix<f64, A, A>
where
    M: Mechanism<P, A> + ?Sized,
{
    let d = m.info().driven();
    let lc = m.info().characteristic_length();
    SMatrix::<f64, A, A>::from_fn(|r, c| {
        let k = d[c];
        match m.info().coordinates()[k].quantity {
            crate::units::Quantity::Angle => j[(r, k)] / lc,
            crate::units::Quantity::Length => j[(r, k)],
        }
    })
}

/// The columns of `J` belonging to the driven coordinates (`A x A`).
pub fn driven_jacobian<const P: usize, const A: usize>(
    j: &SMatrix<f64, A, P>,
    driven: &[usize; A],
) -> SMatrix<f64, A, A> {
    SMatrix::<f64, A, A>::from_fn(|r, c| j[(r, driven[c])])
}

/// Inverse kinematics of `x` continuing `last`, the previous pose's actuators along a
/// path: [`Mechanism::inverse_near`] from them (a robot keeps its posture and the whole
/// turns of its joints, as a controller moving it does); [`Mechanism::inverse`] for the
/// first pose (`None`) and where Newton from `last` stalls ([`Error::NotConverged`]:
/// robots without a closed form). Mechanisms with one solution per pose give
/// [`Mechanism::inverse`]'s.
pub fn inverse_continuing<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    last: Option<&SVector<f64, A>>,
) -> Result<SVector<f64, A>>
where
    M: Mechanism<P, A> + ?Sized,
{
    match last {
        Some(q0) => match m.inverse_near(x, q0) {
            Err(Error::NotConverged { .. }) => m.inverse(x),
            solved => solved,
        },
        None => m.inverse(x),
    }
}

/// Forward kinematics by damped Newton iteration on the driven coordinates:
/// `x <- x - t Jd^-1 (IK(x) - q)`, with `Jd` the driven columns of the analytic
/// inverse Jacobian and the step `t` halved until the residual decreases.
///
/// Converges quadratically near the solution; reports [`Error::Singular`] when `Jd`
/// is (nearly) singular and [`Error::NotConverged`] with its residual otherwise.
pub fn newton_forward<M, const P: usize, const A: usize>(
    m: &M,
    q: &SVector<f64, A>,
    start: &SVector<f64, P>,
    opt: &NewtonOptions,
) -> Result<Forward<P>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let driven = m.info().driven();
    let mut x = *start;
    let mut r = m.inverse(&x)? - q;
    let mut res = max_abs(&r);
    for it in 0..opt.max_iterations {
        if res <= opt.tolerance {
            return Ok(Forward {
                pose: x,
                iterations: it,
                residual: res,
            });
        }
        let jd = driven_jacobian(&m.jacobian(&x)?, &driven);
        let rc = rcond1(&jd);
        let step = match SmallLu::new(&jd) {
            Some(lu) if rc >= opt.min_rcond => lu.solve(&r),
            _ => {
                return Err(Error::Singular {
                    what: "forward kinematics Jacobian".into(),
                    rcond: rc,
                })
            }
        };
        let mut t = 1.0;
        let mut accepted = false;
        for _ in 0..30 {
            let mut xn = x;
            for (k, &d) in driven.iter().enumerate() {
                xn[d] -= t * step[k];
            }
            if let Ok(qn) = m.inverse(&xn) {
                let rn = qn - q;
                let resn = max_abs(&rn);
                if resn < res || resn <= opt.tolerance {
                    x = xn;
                    r = rn;
                    res = resn;
                    accepted = true;
                    break;
                }
            }
            t *= 0.5;
        }
        if !accepted {
            return Err(Error::NotConverged {
                solver: "forward kinematics (Newton)",
                iterations: it + 1,
                residual: res,
            });
        }
    }
    if res <= opt.tolerance {
        Ok(Forward {
            pose: x,
            iterations: opt.max_iterations,
            residual: res,
        })
    } else {
        Err(Error::NotConverged {
            solver: "forward kinematics (Newton)",
            iterations: opt.max_iterations,
            residual: res,
        })
    }
}

/// Forward kinematics on the branch of solutions through `start`: when the actuators
/// `q` are within `max_step` (mm or rad) of `IK(start)`, [`newton_forward`]; otherwise
/// continuation, the actuators moved from `IK(start)` to `q` in steps of at most
/// `max_step`, each solved by Newton from the last. Newton alone from a far start may
/// stall in a local minimum of the residual or land on another assembly mode; the
/// continuation returns the solution a machine moving from `start` reaches. When the
/// continuation fails (a singularity on the way), Newton from `start` is tried; when
/// that fails too, its error (with its residual) is returned.
pub fn continued_forward<M, const P: usize, const A: usize>(
    m: &M,
    q: &SVector<f64, A>,
    start: &SVector<f64, P>,
    opt: &NewtonOptions,
    max_step: f64,
) -> Result<Forward<P>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let span = match m.inverse(start) {
        Ok(q0) => Some((q0, (q - q0).amax())),
        Err(_) => None,
    };
    let Some((q0, span)) = span.filter(|(_, s)| s.is_finite() && *s > max_step) else {
        return newton_forward(m, q, start, opt);
    };
    let steps = ((span / max_step).ceil() as usize).clamp(2, 1000);
    let loose = NewtonOptions {
        tolerance: opt.tolerance.max(1e-9 * span),
        ..*opt
    };
    let mut x = *start;
    let mut iterations = 0;
    for k in 1..=steps {
        let qk = q0 + (q - q0) * (k as f64 / steps as f64);
        let o = if k == steps { opt } else { &loose };
        match newton_forward(m, &qk, &x, o) {
            Ok(f) => {
                x = f.pose;
                iterations += f.iterations;
                if k == steps {
                    return Ok(Forward {
                        pose: x,
                        iterations,
                        residual: f.residual,
                    });
                }
            }
            Err(_) => break,
        }
    }
    newton_forward(m, q, start, opt)
}

/// Inverse kinematics with every limit checked: the actuator coordinates, or
/// [`Error::Unreachable`] listing every violated limit.
pub fn inverse_checked<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<SVector<f64, A>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let q = m.inverse(x)?;
    let mut v = Vec::new();
    m.check_limits(x, &q, &mut v);
    if v.is_empty() {
        Ok(q)
    } else {
        Err(Error::Unreachable { violations: v })
    }
}

/// The `i`-th point of the Halton sequence in base `b` (in `[0, 1)`).
pub(crate) fn halton(mut i: usize, b: usize) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= b as f64;
        r += f * (i % b) as f64;
        i /= b;
    }
    r
}

/// `n` deterministic starting poses spread around the home pose for
/// [`assembly_modes`]: the home pose first, then Halton points with lengths within
/// `+-2` characteristic lengths (at least 100 mm) of home and angles anywhere; for
/// spatial machines the orientation is a rotation vector of any direction up to 180 deg
/// and every other start is mirrored through the base plane (Z -> -Z), where the
/// mirror-image assembly modes of parallel machines lie. Held coordinates keep their
/// home values (forward kinematics takes them from the start).
pub fn spread_starts<M, const P: usize, const A: usize>(m: &M, n: usize) -> Vec<SVector<f64, P>>
where
    M: Mechanism<P, A> + ?Sized,
{
    const PRIMES: [usize; 8] = [2, 3, 5, 7, 11, 13, 17, 19];
    let home = m.info().home();
    let span = (2.0 * m.info().characteristic_length()).max(100.0);
    let spatial = m.info().pose_space() == PoseSpace::Spatial && P == 6;
    let mut out = vec![home];
    for i in 1..n {
        let u = |k: usize| halton(i, PRIMES[k % PRIMES.len()]) - 0.5;
        let mut x = home;
        if spatial {
            for k in 0..3 {
                x[k] = home[k] + 2.0 * span * u(k);
            }
            if i % 2 == 1 {
                x[2] = -x[2];
            }
            let w = nalgebra::Vector3::new(u(3), u(4), u(5));
            let w = if w.norm() > 1e-12 {
                w.normalize() * (2.0 * std::f64::consts::PI * u(6).abs())
            } else {
                w
            };
            let r = nalgebra::Rotation3::new(w).matrix()
                * crate::rotation::rpy_matrix(home[3], home[4], home[5]);
            let a = crate::rotation::Convention::Rpy.from_matrix(&r);
            x[3] = a[0];
            x[4] = a[1];
            x[5] = a[2];
        } else {
            for k in 0..P {
                x[k] = match m.info().coordinates()[k].quantity {
                    crate::units::Quantity::Length => home[k] + 2.0 * span * u(k),
                    crate::units::Quantity::Angle => 2.0 * std::f64::consts::PI * u(k),
                };
            }
        }
        // Held coordinates are the machine's, not the solver's: they stay at home.
        let driven = m.info().driven();
        for k in (0..P).filter(|k| !driven.contains(k)) {
            x[k] = home[k];
        }
        out.push(x);
    }
    out
}

/// Distinct forward solutions (assembly modes) for actuators `q`, found by solving
/// from every pose of `starts` (e.g. [`spread_starts`]); two solutions are the same
/// when their tool poses are within `tol` (mm and rad). Sorted by distance of the tool
/// tip from the first start's. Starts that fail (no convergence, singular) are skipped.
pub fn assembly_modes<M, const P: usize, const A: usize>(
    m: &M,
    q: &SVector<f64, A>,
    starts: &[SVector<f64, P>],
    tol: f64,
) -> Vec<Forward<P>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let mut found: Vec<(Forward<P>, Pose)> = Vec::new();
    for s in starts {
        let Ok(f) = m.forward(q, s) else { continue };
        let Ok(pose) = m.tool_pose(&f.pose) else {
            continue;
        };
        let same = found.iter().any(|(_, p)| {
            (p.translation.vector - pose.translation.vector).norm() <= tol
                && p.rotation.angle_to(&pose.rotation) <= tol
        });
        if !same {
            found.push((f, pose));
        }
    }
    let origin = starts
        .first()
        .and_then(|s| m.tool_pose(s).ok())
        .map(|p| p.translation.vector)
        .unwrap_or_default();
    found.sort_by(|a, b| {
        let da = (a.1.translation.vector - origin).norm();
        let db = (b.1.translation.vector - origin).norm();
        da.total_cmp(&db)
    });
    found.into_iter().map(|(f, _)| f).collect()
}
