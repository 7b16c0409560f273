//! Sets of primary deviations of a serial machine (seed 003): zero, from named values,
//! and the exact tool-pose error they cause. Budgets and Monte Carlo are the generic
//! accuracy engine's ([`crate::accuracy`]).

use nalgebra::Vector3;

use super::machine::{ChainDeviations, Parameter, SerialMachine};
use super::LinkDeviation;
use crate::error::Result;

/// Zero deviations for every link and joint of a machine's chains.
pub fn zero_deviations(m: &SerialMachine) -> Vec<ChainDeviations> {
    let mut v = vec![ChainDeviations {
        links: vec![LinkDeviation::default(); m.tool.links.len()],
        dq: vec![0.0; m.tool.dof()],
        ..Default::default()
    }];
    if let Some(w) = &m.workpiece {
        v.push(ChainDeviations {
            links: vec![LinkDeviation::default(); w.links.len()],
            dq: vec![0.0; w.dof()],
            ..Default::default()
        });
    }
    v
}

/// Deviations with the given values (internal units) and every other deviation zero.
pub fn deviations_from(m: &SerialMachine, values: &[(Parameter, f64)]) -> Vec<ChainDeviations> {
    let mut d = zero_deviations(m);
    for (p, v) in values {
        apply(&mut d, p, *v);
    }
    d
}

/// Tool-point displacement (mm) and tool-frame rotation (small rotation vector, rad)
/// of the deviated machine against the nominal one, in the workpiece frame, at joints
/// `qt`, `qw`: exact poses, the rotation from the skew part of `R_dev R_nom^T`.
pub fn pose_error(
    m: &SerialMachine,
    qt: &[f64],
    qw: &[f64],
    dev: &[ChainDeviations],
) -> Result<(Vector3<f64>, Vector3<f64>)> {
    Ok(error_between(&m.pose(qt, qw, &[])?, &m.pose(qt, qw, dev)?))
}

/// The error of pose `b` against `a`: `t_b - t_a` and the skew part of `R_b R_a^T`.
/// Seed 003's blocks with angular deviations (`cos(phi + alpha)`) are not exactly
/// orthonormal; the skew part is exact to first order and never undefined.
pub(crate) fn error_between(
    a: &nalgebra::Matrix4<f64>,
    b: &nalgebra::Matrix4<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    let dp = b.fixed_view::<3, 1>(0, 3) - a.fixed_view::<3, 1>(0, 3);
    let dr = b.fixed_view::<3, 3>(0, 0) * a.fixed_view::<3, 3>(0, 0).transpose();
    (dp.into_owned(), crate::rotation::skew_vee(&dr))
}

pub(crate) fn apply(d: &mut [ChainDeviations], p: &Parameter, v: f64) {
    match *p {
        Parameter::Delta { chain, link, axis } => d[chain].links[link].delta[axis] += v,
        Parameter::Alpha {
            chain,
            link,
            row,
            col,
        } => d[chain].links[link].alpha[(row, col)] += v,
        Parameter::Dq { chain, joint } => d[chain].dq[joint] += v,
        Parameter::Installation { axis } => d[0].installation[axis.min(2)] += v,
    }
}

/// Sets the slot of deviation `p` back to zero (and a completed block with it).
pub(crate) fn clear(d: &mut [ChainDeviations], p: &Parameter) {
    match *p {
        Parameter::Delta { chain, link, axis } => d[chain].links[link].delta[axis] = 0.0,
        Parameter::Alpha {
            chain,
            link,
            row,
            col,
        } => {
            let l = &mut d[chain].links[link];
            l.alpha[(row, col)] = 0.0;
            l.block = None;
        }
        Parameter::Dq { chain, joint } => d[chain].dq[joint] = 0.0,
        Parameter::Installation { axis } => d[0].installation[axis.min(2)] = 0.0,
    }
}
