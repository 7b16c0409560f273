//! Forward workspace: over a grid of actuator positions, the pose the mechanism takes
//! (forward kinematics from a start pose) and whether it is within every limit
//! (seed 004 fig. 5: reachable `(z, theta)` over the slider strokes).

use nalgebra::SVector;
use rayon::prelude::*;

use super::{check_axes, grid_point, GridAxis};
use crate::error::{Error, Result};
use crate::limits::LimitName;
use crate::mechanism::Mechanism;

/// One grid node of actuator positions.
#[derive(Debug, Clone, PartialEq)]
pub struct ForwardPoint<const P: usize> {
    /// The pose found, when forward kinematics found one.
    pub pose: Option<SVector<f64, P>>,
    /// The pose is within every limit.
    pub reachable: bool,
    /// Why not: the first violated limit, or the solver's failure (no assembly,
    /// singular, not converged), as shared text ([`LimitName`]).
    pub binding: Option<LimitName>,
}

/// A forward map over actuator axes (`GridAxis::coordinate` is an actuator index).
#[derive(Debug, Clone, PartialEq)]
pub struct ForwardMap<const P: usize> {
    /// The actuator axes (first varies slowest).
    pub axes: Vec<GridAxis>,
    /// Actuator positions of the actuators not on an axis.
    pub base: Vec<f64>,
    /// One point per grid node, row-major.
    pub points: Vec<ForwardPoint<P>>,
}

/// Solves forward kinematics at every node of a grid over actuator positions (`base`
/// with the axis actuators set), each from `start`, and checks the limits.
pub fn forward_map<M, const P: usize, const A: usize>(
    m: &M,
    base: &SVector<f64, A>,
    axes: &[GridAxis],
    start: &SVector<f64, P>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<ForwardMap<P>>
where
    M: Mechanism<P, A>,
{
    check_axes(axes, A)?;
    let counts: Vec<usize> = axes.iter().map(|a| a.count()).collect();
    let total: usize = counts.iter().product();
    let chunk = 1024;
    let points = (0..total)
        .into_par_iter()
        .with_min_len(chunk)
        .map_init(Vec::new, |v, k| {
            let q = grid_point(base, axes, &counts, k);
            if k % chunk == chunk - 1 {
                progress(chunk as u64);
            }
            match m.forward(&q, start) {
                Ok(f) => {
                    v.clear();
                    m.check_limits(&f.pose, &q, v);
                    ForwardPoint {
                        pose: Some(f.pose),
                        reachable: v.is_empty(),
                        binding: v.first().map(|x| x.limit.clone()),
                    }
                }
                Err(e) => ForwardPoint {
                    pose: None,
                    reachable: false,
                    binding: Some(match e {
                        Error::NotAttainable { .. } => "no assembly".into(),
                        Error::Singular { .. } => "singular".into(),
                        Error::NotConverged { .. } => "not converged".into(),
                        other => other.to_string().into(),
                    }),
                },
            }
        })
        .collect();
    Ok(ForwardMap {
        axes: axes.to_vec(),
        base: base.as_slice().to_vec(),
        points,
    })
}
