//! Serial chains (seed 003) in the accuracy engine: the primary deviations of every
//! link and joint and the installation angles, the deviated pose from the product of
//! the deviated transforms (eqs. 1-4), analytic sensitivities.

use nalgebra::{Matrix4, SVector, Vector3};

use super::{Evaluate, Parameter, ParameterKind, Parametric, PoseError};
use crate::error::{Error, Result};
use crate::mechanism::Mechanism;
use crate::serial::deviations::{apply, zero_deviations};
use crate::serial::machine::{ChainDeviations, Parameter as Deviation, SerialMachine};
use crate::units::Quantity;

/// The engine's parameter list of a serial machine, in the order of
/// [`SerialMachine::all_parameters`].
pub fn serial_parameters(m: &SerialMachine) -> Vec<Parameter> {
    m.all_parameters()
        .iter()
        .map(|p| {
            let kind = match p {
                Deviation::Delta { .. } => ParameterKind::LinkOffset,
                Deviation::Alpha { .. } => ParameterKind::AngularDeviation,
                Deviation::Dq { .. } => ParameterKind::DrivePositioning,
                Deviation::Installation { .. } => ParameterKind::Installation,
            };
            let quantity = if m.is_angular(p) {
                Quantity::Angle
            } else {
                Quantity::Length
            };
            Parameter::new(m.parameter_name(p), quantity, kind)
        })
        .collect()
}

/// The exact tool pose of the deviated chains against the nominal one at fixed joints.
#[derive(Clone)]
pub struct SerialEvaluator<'a> {
    m: &'a SerialMachine,
    params: Vec<Deviation>,
    qt: Vec<f64>,
    qw: Vec<f64>,
    dev: Vec<ChainDeviations>,
    nominal: Matrix4<f64>,
}

impl<'a> SerialEvaluator<'a> {
    fn new(m: &'a SerialMachine, q: &[f64]) -> Result<Self> {
        let (qt, qw) = q.split_at(m.tool.dof().min(q.len()));
        Ok(SerialEvaluator {
            m,
            params: m.all_parameters(),
            qt: qt.to_vec(),
            qw: qw.to_vec(),
            dev: zero_deviations(m),
            nominal: m.pose(qt, qw, &[])?,
        })
    }

    fn analytic(&self) -> Result<Vec<PoseError>> {
        Ok(self
            .m
            .sensitivities(&self.qt, &self.qw, &[], &self.params)?
            .into_iter()
            .map(|(position, orientation)| PoseError {
                position,
                orientation,
            })
            .collect())
    }
}

impl Evaluate for SerialEvaluator<'_> {
    fn pose_error(&mut self, deviations: &[(usize, f64)]) -> Result<PoseError> {
        for cd in self.dev.iter_mut() {
            cd.links.iter_mut().for_each(|l| *l = Default::default());
            cd.dq.iter_mut().for_each(|x| *x = 0.0);
            cd.installation = Vector3::zeros();
        }
        for &(k, v) in deviations {
            let p = self.params.get(k).ok_or_else(|| Error::InvalidInput {
                what: "deviation".into(),
                message: format!(
                    "parameter index {k} beyond the machine's {}",
                    self.params.len()
                ),
            })?;
            apply(&mut self.dev, p, v);
        }
        let b = self.m.pose(&self.qt, &self.qw, &self.dev)?;
        let a = &self.nominal;
        let dp = b.fixed_view::<3, 1>(0, 3) - a.fixed_view::<3, 1>(0, 3);
        // Seed 003's rotation block with angular deviations (cos(phi + alpha)) is not
        // exactly orthonormal: the rotation is read from the skew part of
        // R_dev R_nom^T, which is exact to first order and never undefined.
        let dr = b.fixed_view::<3, 3>(0, 0) * a.fixed_view::<3, 3>(0, 0).transpose();
        Ok(PoseError {
            position: dp.into_owned(),
            orientation: Vector3::new(
                0.5 * (dr[(2, 1)] - dr[(1, 2)]),
                0.5 * (dr[(0, 2)] - dr[(2, 0)]),
                0.5 * (dr[(1, 0)] - dr[(0, 1)]),
            ),
        })
    }
}

impl<const N: usize> Parametric<N, N> for crate::serial::mechanism::SerialMechanism<N> {
    type Evaluator<'a> = SerialEvaluator<'a>;
    fn parameters(&self) -> Vec<Parameter> {
        serial_parameters(&self.machine)
    }
    fn evaluator(&self, x: &SVector<f64, N>) -> Result<SerialEvaluator<'_>> {
        SerialEvaluator::new(&self.machine, x.as_slice())
    }
    fn analytic_sensitivities(&self, x: &SVector<f64, N>) -> Option<Result<Vec<PoseError>>> {
        Some(SerialEvaluator::new(&self.machine, x.as_slice()).and_then(|e| e.analytic()))
    }
}

impl Parametric<6, 6> for crate::serial::arm::SerialArm {
    type Evaluator<'a> = SerialEvaluator<'a>;
    fn parameters(&self) -> Vec<Parameter> {
        serial_parameters(&self.machine)
    }
    /// The joints commanded for tool pose `x` are the nominal inverse solution.
    fn evaluator(&self, x: &SVector<f64, 6>) -> Result<SerialEvaluator<'_>> {
        let q = self.inverse(x)?;
        SerialEvaluator::new(&self.machine, q.as_slice())
    }
    fn analytic_sensitivities(&self, x: &SVector<f64, 6>) -> Option<Result<Vec<PoseError>>> {
        Some(self.evaluator(x).and_then(|e| e.analytic()))
    }
}
