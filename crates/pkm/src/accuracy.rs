//! Accuracy of parameterised mechanisms (hexapods, tripods) from tolerances on their
//! geometric parameters: the joint centres and the actuators' zero readings of
//! [`Identifiable`], the same parameter vector identification estimates.
//!
//! The control commands readings `dL = q(x; theta_0) - L^(0)` computed with the nominal
//! model; the real machine (parameters `theta`) then sits at the pose `x'` solving
//! `q(x'; g) = L^(0)' + dL`. To first order (implicit function theorem, as in
//! identification's point model) `dx/dtheta = -J_d^-1 [dq/dg, -I]`, `J_d` the Jacobian's
//! driven columns; the tool point moves by `dx[X, Y, Z]` and turns by
//! `E(A, B, C) dx[A, B, C]`. The budget multiplies these by the tolerances; the Monte
//! Carlo draws whole machines and solves their forward kinematics exactly.

use nalgebra::{DMatrix, SVector, Vector3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution as _, Normal};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::identify::{parameter_names, Identifiable};
use crate::mechanism::PoseSpace;
use crate::rotation::rpy_rate_matrix;
use crate::serial::tolerance::{statistics, Budget, BudgetItem, Distribution, MonteCarlo};

/// Tolerances of a strut machine's geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeometricTolerances {
    /// Every joint-centre coordinate (mm): bound of a uniform distribution or three
    /// standard deviations of a normal one.
    pub joint: f64,
    /// Every actuator's zero reading (strut length at zero, mm or rad).
    pub zero: f64,
    /// Distribution in Monte Carlo.
    pub distribution: Distribution,
}

impl GeometricTolerances {
    fn of(&self, k: usize, n_geometry: usize) -> f64 {
        if k < n_geometry {
            self.joint
        } else {
            self.zero
        }
    }
}

/// First-order tool-point displacement (mm per unit) and tool rotation (rad per unit)
/// for each parameter ([`parameter_names`] order) at pose `x`, the readings held.
pub fn sensitivities<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<Vec<(Vector3<f64>, Vector3<f64>)>> {
    if m.pose_space() != PoseSpace::Spatial {
        return Err(Error::InvalidInput {
            what: "geometric accuracy".into(),
            message: "needs a spatial machine (pose X, Y, Z, A, B, C)".into(),
        });
    }
    let ng = m.geometry().len();
    let n = ng + A;
    let mut jg = DMatrix::zeros(A, ng);
    m.inverse_with_geometry_jacobian(x, &mut jg)?;
    let j = m.jacobian(x)?;
    let driven = m.driven();
    let jd = DMatrix::from_fn(A, A, |r, c| j[(r, driven[c])]);
    let mut rhs = DMatrix::zeros(A, n);
    rhs.view_mut((0, 0), (A, ng)).copy_from(&jg);
    for k in 0..A {
        rhs[(k, ng + k)] = -1.0;
    }
    let dxd = -jd.lu().solve(&rhs).ok_or_else(|| Error::Singular {
        what: "driven Jacobian (geometric accuracy)".into(),
        rcond: 0.0,
    })?;
    let e = rpy_rate_matrix([x[3], x[4], x[5]]);
    Ok((0..n)
        .map(|c| {
            let mut dx = SVector::<f64, P>::zeros();
            for (k, &d) in driven.iter().enumerate() {
                dx[d] = dxd[(k, c)];
            }
            let dp = Vector3::new(dx[0], dx[1], dx[2]);
            let w = e * Vector3::new(dx[3], dx[4], dx[5]);
            (dp, w)
        })
        .collect())
}

/// The error budget of the tolerances at pose `x`: each parameter's tool-point error at
/// its tolerance, their sum and root sum of squares.
pub fn budget<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    tol: &GeometricTolerances,
) -> Result<Budget> {
    let s = sensitivities(m, x)?;
    let names = parameter_names(m);
    let ng = names.len() - A;
    let items: Vec<BudgetItem> = s
        .iter()
        .enumerate()
        .map(|(k, (dp, w))| {
            let t = tol.of(k, ng);
            BudgetItem {
                name: names[k].clone(),
                tolerance: t,
                position: dp.norm() * t,
                orientation: w.norm() * t,
            }
        })
        .collect();
    Ok(Budget::from_items(items))
}

/// Monte Carlo of `n` machines with every parameter drawn within its tolerance (seeded
/// per chunk: the same result on any number of threads): the tool-point error of each
/// (exact forward kinematics at the nominal readings of `x`) against `x`.
pub fn monte_carlo<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    zero: &SVector<f64, A>,
    tol: &GeometricTolerances,
    n: usize,
    seed: u64,
) -> Result<MonteCarlo> {
    let q = m.inverse(x)?;
    let readings = q - zero;
    let g0 = m.geometry();
    let p0 = m.tool_pose(x)?.translation.vector;
    const CHUNK: usize = 1024;
    let errors: Vec<Vector3<f64>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .flat_map_iter(|c| {
            let mut rng = rand::rngs::StdRng::seed_from_u64(
                seed ^ (c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
            );
            let normal = Normal::new(0.0, 1.0).expect("unit normal");
            let count = CHUNK.min(n - c * CHUNK);
            let mut out = Vec::with_capacity(count);
            let mut g = g0.clone();
            for _ in 0..count {
                let mut draw = |t: f64| match tol.distribution {
                    Distribution::Uniform => rng.random_range(-1.0..=1.0) * t,
                    Distribution::Normal => normal.sample(&mut rng) * t / 3.0,
                };
                for (gi, g0i) in g.iter_mut().zip(&g0) {
                    *gi = g0i + draw(tol.joint);
                }
                let z = SVector::<f64, A>::from_fn(|k, _| zero[k] + draw(tol.zero));
                let e = m
                    .with_geometry(&g)
                    .and_then(|mm| {
                        let f = mm.forward(&(z + readings), x)?;
                        Ok(mm.tool_pose(&f.pose)?.translation.vector - p0)
                    })
                    .unwrap_or_else(|_| Vector3::repeat(f64::NAN));
                out.push(e);
            }
            out
        })
        .collect();
    Ok(statistics(&errors))
}
