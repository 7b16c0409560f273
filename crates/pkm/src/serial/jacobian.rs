//! Tool-space Jacobian of a serial machine (the sensitivities to the joints). Numeric
//! inverse kinematics is the robot's ([`super::arm::SerialArm::inverse_from`]).

use nalgebra::DMatrix;

use super::machine::{Parameter, SerialMachine};
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
