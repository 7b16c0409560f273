//! Velocity and force transmission of a mechanism at a pose, and its distance to a
//! singularity, from the driven columns of the inverse Jacobian `J = dq/dx`.
//!
//! With `q' = J x'` (driven coordinates) and, by virtual work, actuator forces
//! `tau = J^-T w` for a generalised tool load `w` (N on length coordinates, N mm on
//! angle coordinates):
//!
//! * velocity transmission: the largest actuator rate per unit tool speed,
//!   `s_max(J_L)` over the length columns `J_L` ((mm/s) per (mm/s)); per unit angular
//!   rate, `s_max(J_R)` over the angle columns ((mm/s) per (rad/s));
//! * force transmission: the largest actuator force per unit tool force,
//!   `s_max((J^-T)_L)` (N per N), and per unit tool moment (N per N mm);
//! * conditioning: the condition number `kappa = s_max / s_min` of the driven Jacobian
//!   with angle columns divided by the characteristic length (1 isotropic, infinite at
//!   a singularity of a parallel or a serial machine) and its inverse `1 / kappa` (0 at
//!   a singularity); beside them the smallest singular value `s_min` (actuator units
//!   per tool mm), 0 at a parallel machine's singularity only.
//!
//! Coordinates the mechanism holds are not in these figures. Not a hot path: dynamic
//! matrices (the split into length and angle columns varies by machine).

use nalgebra::{DMatrix, SVector};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::mechanism::Mechanism;
use crate::units::Quantity;

/// Transmission figures at one pose (`None` where the machine has no driven
/// coordinate of that kind).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Transmission {
    /// Largest actuator rate per unit tool speed (mm/s per mm/s).
    pub velocity: Option<f64>,
    /// Largest actuator rate per unit angular rate (mm/s per rad/s).
    pub angular_velocity: Option<f64>,
    /// Largest actuator force per unit tool force (N per N).
    pub force: Option<f64>,
    /// Largest actuator force per unit tool moment (N per N mm).
    pub moment: Option<f64>,
    /// Smallest singular value of the scaled driven Jacobian `dq/dx` (actuator units
    /// per tool mm). 0 at a parallel machine's singularity, where `dq/dx` loses rank;
    /// a serial chain's singularity makes `dq/dx` unbounded instead and leaves this
    /// figure small but not 0 (a robot's joints turn rad per tool mm: 0.0003 on a
    /// KR 30 far from any singularity). [`Transmission::condition`] reads the same on
    /// both kinds.
    pub distance_to_singularity: f64,
    /// Condition number of the mechanism ([`Mechanism::condition`]: the scaled driven
    /// Jacobian's, unless the machine defines its own): 1 isotropic, infinite at a
    /// singularity of either kind.
    pub condition: f64,
    /// `1 / condition`: 1 isotropic, 0 at a singularity (Gosselin and Angeles'
    /// local conditioning index).
    pub inverse_condition: f64,
    /// The characteristic length the angle columns are scaled by (mm).
    pub characteristic_length: f64,
}

fn smax(m: &DMatrix<f64>) -> Option<f64> {
    if m.ncols() == 0 {
        return None;
    }
    m.singular_values().iter().copied().reduce(f64::max)
}

/// Transmission figures at pose `x`.
pub fn transmission<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<Transmission>
where
    M: Mechanism<P, A> + ?Sized,
{
    let j = m.jacobian(x)?;
    let d = m.info().driven();
    let jd = DMatrix::from_fn(A, A, |r, c| j[(r, d[c])]);
    let lc = m.info().characteristic_length();
    let is_angle = |c: usize| m.info().coordinates()[d[c]].quantity == Quantity::Angle;
    let cols = |mat: &DMatrix<f64>, angle: bool| -> DMatrix<f64> {
        let idx: Vec<usize> = (0..A).filter(|&c| is_angle(c) == angle).collect();
        DMatrix::from_fn(mat.nrows(), idx.len(), |r, k| mat[(r, idx[k])])
    };
    let scaled = crate::mechanism::scaled_driven_jacobian(m, x)?;
    let sv = DMatrix::from_fn(A, A, |r, c| scaled[(r, c)]).singular_values();
    let smin = sv.iter().copied().fold(f64::INFINITY, f64::min);
    let smax_all = sv.iter().copied().fold(0.0, f64::max);
    let inv_t = jd.clone().try_inverse().map(|i| i.transpose());
    let (force, moment) = match &inv_t {
        Some(it) => (smax(&cols(it, false)), smax(&cols(it, true))),
        None if smin <= 0.0 => (Some(f64::INFINITY), Some(f64::INFINITY)),
        None => {
            return Err(Error::Singular {
                what: "inverse Jacobian (force transmission)".into(),
                rcond: smin / smax_all,
            })
        }
    };
    // The mechanism's own measure (a machine with a serial table axis leaves it out).
    let condition = m.condition(x).unwrap_or(f64::INFINITY);
    Ok(Transmission {
        velocity: smax(&cols(&jd, false)),
        angular_velocity: smax(&cols(&jd, true)),
        force,
        moment,
        distance_to_singularity: smin,
        condition,
        inverse_condition: 1.0 / condition,
        characteristic_length: lc,
    })
}
