//! Tool-space Jacobian and numeric inverse kinematics of a serial machine's tool chain
//! (damped least squares with joint limits).

use nalgebra::{DMatrix, DVector, Matrix4};

use super::accuracy::{Parameter, SerialMachine};
use crate::error::{Error, Result};

impl SerialMachine {
    /// Geometric Jacobian of the tool pose relative to the workpiece with respect to
    /// every joint (tool joints, then workpiece joints): `6 x n`, rows the tool-point
    /// velocity (mm per unit) and the angular velocity (rad per unit), workpiece frame.
    /// These are the sensitivities to the positioning deviations `dq`.
    pub fn tool_jacobian(&self, qt: &[f64], qw: &[f64]) -> Result<DMatrix<f64>> {
        let nw = self.workpiece.as_ref().map(|w| w.dof()).unwrap_or(0);
        self.dq_jacobian(qt, qw, nw)
    }

    /// The columns of [`SerialMachine::tool_jacobian`] for the tool joints and the
    /// first `nw` workpiece joints.
    fn dq_jacobian(&self, qt: &[f64], qw: &[f64], nw: usize) -> Result<DMatrix<f64>> {
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

/// Settings of [`inverse`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkOptions {
    /// Largest number of iterations.
    pub max_iterations: usize,
    /// Converged when the position error is below this (mm)...
    pub position_tolerance: f64,
    /// ... and the orientation error below this (rad).
    pub orientation_tolerance: f64,
    /// Length (mm) that weighs a radian of orientation error against a millimetre.
    pub characteristic_length: f64,
    /// Damping of the least-squares step (mm).
    pub damping: f64,
}

impl Default for IkOptions {
    fn default() -> Self {
        IkOptions {
            max_iterations: 200,
            position_tolerance: 1e-9,
            orientation_tolerance: 1e-11,
            characteristic_length: 500.0,
            damping: 1e-3,
        }
    }
}

/// Tool-chain joint values that bring the tool pose (relative to the workpiece, with
/// the workpiece joints `qw` fixed) to `target`, from `start`: damped least squares
/// `dq = J^T (J J^T + l^2 I)^-1 e` on the weighted 6D error, joint values kept inside
/// their ranges. Fails with [`Error::NotConverged`] (with the residual) when the target
/// is out of reach or a limit blocks it.
pub fn inverse(
    m: &SerialMachine,
    target: &Matrix4<f64>,
    start: &[f64],
    qw: &[f64],
    o: &IkOptions,
) -> Result<(Vec<f64>, usize)> {
    let nt = m.tool.dof();
    if start.len() != nt {
        return Err(Error::InvalidInput {
            what: "inverse kinematics start".into(),
            message: format!("expected {nt} tool-chain joint values, got {}", start.len()),
        });
    }
    let ranges: Vec<_> = m.tool.joints().map(|j| j.range).collect();
    let mut q: Vec<f64> = start
        .iter()
        .zip(&ranges)
        .map(|(v, r)| v.clamp(r.min, r.max))
        .collect();
    let lc = o.characteristic_length;
    let error = |q: &[f64]| -> Result<(DVector<f64>, f64, f64)> {
        let t = m.pose(q, qw, &[])?;
        let dp = target.fixed_view::<3, 1>(0, 3) - t.fixed_view::<3, 1>(0, 3);
        let dr = target.fixed_view::<3, 3>(0, 0) * t.fixed_view::<3, 3>(0, 0).transpose();
        let w = crate::rotation::rotation_vector(&dr.into_owned());
        let e = DVector::from_vec(vec![dp.x, dp.y, dp.z, w.x * lc, w.y * lc, w.z * lc]);
        Ok((e, dp.norm(), w.norm()))
    };
    let (mut e, mut ep, mut ew) = error(&q)?;
    for it in 0..o.max_iterations {
        if ep <= o.position_tolerance && ew <= o.orientation_tolerance {
            return Ok((q, it));
        }
        // Tool joints only: the workpiece joints are fixed here.
        let mut j = m.dq_jacobian(&q, qw, 0)?;
        for r in 3..6 {
            for c in 0..nt {
                j[(r, c)] *= lc;
            }
        }
        let jjt = &j * j.transpose() + DMatrix::identity(6, 6) * (o.damping * o.damping);
        let Some(inv) = jjt.try_inverse() else {
            break;
        };
        let dq = j.transpose() * (inv * &e);
        // Step, halved until the error decreases.
        let mut t = 1.0;
        let mut improved = false;
        let norm = e.norm();
        for _ in 0..30 {
            let qn: Vec<f64> = q
                .iter()
                .zip(dq.iter())
                .zip(&ranges)
                .map(|((v, d), r)| (v + t * d).clamp(r.min, r.max))
                .collect();
            let (en, epn, ewn) = error(&qn)?;
            if en.norm() < norm {
                q = qn;
                e = en;
                ep = epn;
                ew = ewn;
                improved = true;
                break;
            }
            t *= 0.5;
        }
        if !improved {
            break;
        }
    }
    if ep <= o.position_tolerance && ew <= o.orientation_tolerance {
        return Ok((q, o.max_iterations));
    }
    Err(Error::NotConverged {
        solver: "serial inverse kinematics (damped least squares)",
        iterations: o.max_iterations,
        residual: ep.max(ew * lc),
    })
}
