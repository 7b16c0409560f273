//! Tool-space Jacobian of a serial machine (the sensitivities to the joints), and the
//! geometric Jacobian of a chain's joint axes with its rate `J'(q) q'`. Numeric
//! inverse kinematics is the robot's ([`super::arm::SerialArm::inverse_from`]).

use nalgebra::{DMatrix, Vector3};

use super::machine::{Parameter, SerialMachine};
use super::{JointAxis, JointKind};
use crate::error::Result;

impl SerialMachine {
    /// Geometric Jacobian of the tool pose relative to the workpiece with respect to
    /// every joint (tool joints, then workpiece joints): `6 x n`, rows the tool-point
    /// velocity (mm per unit) and the angular velocity (rad per unit), workpiece frame.
    /// These are the sensitivities to the positioning deviations `dq`.
    pub fn tool_jacobian(&self, qt: &[f64], qw: &[f64]) -> Result<DMatrix<f64>> {
        let nw = self.workpiece.as_ref().map(|w| w.dof()).unwrap_or(0);
        let nt = self.tool.dof();
        let params: Vec<Parameter> = (0..nt)
            .map(|joint| Parameter::Dq { chain: 0, joint })
            .chain((0..nw).map(|joint| Parameter::Dq { chain: 1, joint }))
            .collect();
        let s = self.sensitivities(qt, qw, &[], &params)?;
        Ok(DMatrix::from_fn(6, params.len(), |r, c| {
            if r < 3 {
                s[c].0[r]
            } else {
                s[c].1[r - 3]
            }
        }))
    }
}

/// The geometric Jacobian (`6 x N`: velocity of the point `p` over angular velocity)
/// of joints with `axes` (from [`super::PreparedChain::axes`]): a revolute joint with axis
/// `z_i` through `o_i` contributes `[z_i x (p - o_i); z_i]`, a prismatic one `[z_i; 0]`.
pub fn jacobian_of_axes<const N: usize>(
    p: &Vector3<f64>,
    axes: &[JointAxis; N],
) -> nalgebra::SMatrix<f64, 6, N> {
    let mut j = nalgebra::SMatrix::<f64, 6, N>::zeros();
    for (c, (z, o, kind)) in axes.iter().enumerate() {
        let (v, w) = match kind {
            JointKind::Revolute => (z.cross(&(p - o)), *z),
            JointKind::Prismatic => (*z, Vector3::zeros()),
        };
        for r in 0..3 {
            j[(r, c)] = v[r];
            j[(r + 3, c)] = w[r];
        }
    }
    j
}

/// `J'(q) q'` of [`jacobian_of_axes`], exactly: the point `p`'s acceleration and the
/// angular acceleration the joint rates `qd` give with the joints at rest
/// (`[p''; w'] = J q'' + J' q'`), from the axes at `q` alone (no finite differences).
///
/// Axis `i` turns with the links before it: `z_i' = w_i x z_i`, with
/// `w_i = sum_(k<i, revolute) z_k q_k'` the angular velocity of the link carrying it,
/// and its point moves at `o_i' = o_(i-1)' + [z_(i-1) q_(i-1)' if joint i-1 slides] +
/// w_i x (o_i - o_(i-1))` (the forward velocity recursion). Differentiating the
/// columns:
///
/// `J_i' = [z_i' x (p - o_i) + z_i x (p' - o_i'); z_i']` (revolute), `[z_i'; 0]`
/// (prismatic), with `p' = J_v q'`,
///
/// the time derivative of [`jacobian_of_axes`]'s columns (derived here; tested against
/// central differences of the Jacobian along `q'`).
pub fn jacobian_rate_times_rates<const N: usize>(
    p: &Vector3<f64>,
    axes: &[JointAxis; N],
    qd: &[f64; N],
) -> nalgebra::Vector6<f64> {
    // p' = J_v q'.
    let mut pd = Vector3::zeros();
    for ((z, o, kind), v) in axes.iter().zip(qd) {
        pd += match kind {
            JointKind::Revolute => z.cross(&(p - o)) * *v,
            JointKind::Prismatic => z * *v,
        };
    }
    let mut acc = Vector3::zeros();
    let mut alpha = Vector3::zeros();
    // Forward recursion: the angular velocity `w` of the link carrying the next axis
    // and the velocity `od` of that axis' point, from the previous axis' point.
    let mut w = Vector3::zeros();
    let mut od = Vector3::zeros();
    let mut prev: Option<(&Vector3<f64>, &Vector3<f64>, JointKind, f64)> = None;
    for ((z, o, kind), v) in axes.iter().zip(qd) {
        if let Some((zp, op, kp, vp)) = prev {
            match kp {
                JointKind::Revolute => w += zp * vp,
                JointKind::Prismatic => od += zp * vp,
            }
            od += w.cross(&(o - op));
        }
        let zd = w.cross(z);
        match kind {
            JointKind::Revolute => {
                acc += (zd.cross(&(p - o)) + z.cross(&(pd - od))) * *v;
                alpha += zd * *v;
            }
            JointKind::Prismatic => acc += zd * *v,
        }
        prev = Some((z, o, *kind, *v));
    }
    nalgebra::Vector6::new(acc.x, acc.y, acc.z, alpha.x, alpha.y, alpha.z)
}
