//! The residual equations of an identification: the actuator equations with measured
//! poses, or the measured points through forward kinematics, and their analytic
//! Jacobians (see the module documentation of [`super`]).

use levenberg_marquardt::LeastSquaresProblem;
use nalgebra::{DMatrix, DVector, Dyn, Owned, SVector};

use super::*;
use crate::error::{Error, Result};

/// The residuals of a campaign for a parameter vector, and their Jacobian.
pub(super) struct Problem<'a, M, const P: usize, const A: usize> {
    pub(super) nominal: &'a M,
    pub(super) meas: &'a Measurements,
    pub(super) model: MeasurementModel,
    /// Measured poses (pose model).
    pub(super) poses: Vec<SVector<f64, P>>,
    /// Last forward-kinematics poses (point model), warm starts.
    pub(super) fk: Vec<SVector<f64, P>>,
    pub(super) theta: Vec<f64>,
    pub(super) free: Vec<usize>,
    /// Residuals and Jacobian (all parameters) at `theta`; `None` when the candidate
    /// machine cannot reach a state.
    pub(super) eval: Option<(DVector<f64>, DMatrix<f64>)>,
}

impl<M: Identifiable<P, A>, const P: usize, const A: usize> Problem<'_, M, P, A> {
    pub(super) fn n_geometry(&self) -> usize {
        self.theta.len() - A
    }

    pub(super) fn rows_per_state(&self) -> usize {
        match self.model {
            MeasurementModel::Pose => A,
            MeasurementModel::Points => 3 * self.meas.fixture.len(),
        }
    }

    pub(super) fn evaluate(&mut self) {
        self.eval = self.compute().ok();
    }

    pub(super) fn compute(&mut self) -> Result<(DVector<f64>, DMatrix<f64>)> {
        let ng = self.n_geometry();
        let n = self.theta.len();
        let m = self.nominal.with_geometry(&self.theta[..ng])?;
        let zero = &self.theta[ng..];
        let rows = self.rows_per_state();
        let mut r = DVector::zeros(rows * self.meas.states.len());
        let mut jac = DMatrix::zeros(r.len(), n);
        let mut jg = DMatrix::zeros(A, ng);
        for (i, st) in self.meas.states.iter().enumerate() {
            let base = i * rows;
            match self.model {
                MeasurementModel::Pose => {
                    let q = m.inverse_with_geometry_jacobian(&self.poses[i], &mut jg)?;
                    for j in 0..A {
                        r[base + j] = q[j] - zero[j] - st.readings[j];
                        for c in 0..ng {
                            jac[(base + j, c)] = jg[(j, c)];
                        }
                        jac[(base + j, ng + j)] = -1.0;
                    }
                }
                MeasurementModel::Points => {
                    let target = SVector::<f64, A>::from_fn(|j, _| zero[j] + st.readings[j]);
                    let f = m.forward(&target, &self.fk[i])?;
                    self.fk[i] = f.pose;
                    let x = f.pose;
                    m.inverse_with_geometry_jacobian(&x, &mut jg)?;
                    let jx = m.jacobian(&x)?;
                    // The driven coordinates move with the parameters; the held ones (a
                    // pentapod's C) stay.
                    let driven = m.info().driven();
                    let lu = DMatrix::from_fn(A, A, |r, c| jx[(r, driven[c])]).lu();
                    // dx/dtheta = -J_x^-1 [dq/dg, -I] (over the driven coordinates)
                    let mut dq = DMatrix::zeros(A, n);
                    dq.view_mut((0, 0), (A, ng)).copy_from(&jg);
                    for j in 0..A {
                        dq[(j, ng + j)] = -1.0;
                    }
                    let dx = -lu.solve(&dq).ok_or_else(|| Error::Singular {
                        what: "mechanism Jacobian in point identification".into(),
                        rcond: 0.0,
                    })?;
                    for (k, s) in self.meas.fixture.iter().enumerate() {
                        let (p, dp) = m.platform_point(&x, s);
                        let e = st.points[k] - p;
                        for a in 0..3 {
                            r[base + 3 * k + a] = e[a];
                        }
                        // d e / d theta = -dP/dx dx/dtheta
                        for c in 0..n {
                            for a in 0..3 {
                                let mut v = 0.0;
                                for (k2, &d) in driven.iter().enumerate() {
                                    v += dp[(a, d)] * dx[(k2, c)];
                                }
                                jac[(base + 3 * k + a, c)] = -v;
                            }
                        }
                    }
                }
            }
        }
        Ok((r, jac))
    }

    pub(super) fn free_jacobian(&self, jac: &DMatrix<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(jac.nrows(), self.free.len(), |r, c| jac[(r, self.free[c])])
    }
}

impl<M: Identifiable<P, A>, const P: usize, const A: usize> LeastSquaresProblem<f64, Dyn, Dyn>
    for Problem<'_, M, P, A>
{
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        for (k, &i) in self.free.iter().enumerate() {
            self.theta[i] = x[k];
        }
        self.evaluate();
    }

    fn params(&self) -> DVector<f64> {
        DVector::from_iterator(self.free.len(), self.free.iter().map(|&i| self.theta[i]))
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.eval.as_ref().map(|(r, _)| r.clone())
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        self.eval.as_ref().map(|(_, j)| self.free_jacobian(j))
    }
}

/// Poses of every state from the fixture's measured points ([`Identifiable::measured_pose`]).
pub fn measured_poses<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    meas: &Measurements,
) -> Result<Vec<SVector<f64, P>>> {
    meas.states
        .iter()
        .enumerate()
        .map(|(i, st)| {
            m.measured_pose(&meas.fixture, &st.points)
                .map_err(|e| Error::InvalidInput {
                    what: format!("measured state {}", i + 1),
                    message: e.to_string(),
                })
        })
        .collect()
}

/// Residuals and their Jacobian (all parameters, in [`parameter_names`] order) of a
/// campaign for parameters `theta` (geometry, then zero readings) under `model`; the
/// point model's forward kinematics starts from `nominal`'s home.
pub fn residuals<M: Identifiable<P, A>, const P: usize, const A: usize>(
    nominal: &M,
    meas: &Measurements,
    model: MeasurementModel,
    theta: &[f64],
) -> Result<(DVector<f64>, DMatrix<f64>)> {
    let poses = match model {
        MeasurementModel::Pose => measured_poses(nominal, meas)?,
        MeasurementModel::Points => Vec::new(),
    };
    let mut problem = Problem {
        nominal,
        meas,
        model,
        poses,
        fk: vec![nominal.info().home(); meas.states.len()],
        theta: theta.to_vec(),
        free: (0..theta.len()).collect(),
        eval: None,
    };
    problem.compute()
}
