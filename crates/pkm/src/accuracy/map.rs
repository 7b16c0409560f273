//! Error maps: the first-order budget of a set of tolerances over a grid of two pose
//! coordinates (the others held at a base pose), poses beyond a limit left blank.

use nalgebra::SVector;
use rayon::prelude::*;
use serde::Serialize;

use super::{sensitivities, Budget, Parametric, Tolerance};
use crate::error::{Error, Result};
use crate::mechanism::inverse_checked;
use crate::workspace::GridAxis;

/// One cell of an error map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MapCell {
    /// Values of the two mapped coordinates (internal units).
    pub at: [f64; 2],
    /// RSS and worst case of the budget (mm); `None` where the pose is beyond a limit
    /// or has no solution.
    pub budget: Option<[f64; 2]>,
}

/// An error map over two pose coordinates.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ErrorMap {
    /// The two grid axes.
    pub axes: [GridAxis; 2],
    /// Cells, the second axis varying fastest.
    pub cells: Vec<MapCell>,
    /// Cells left blank (unreachable).
    pub unreachable: usize,
    /// Largest RSS over the map (mm).
    pub max_rss: f64,
}

/// The budget of `tol` over the grid `axes` around pose `base` (rayon).
pub fn error_map<M, const P: usize, const A: usize>(
    m: &M,
    base: &SVector<f64, P>,
    axes: [GridAxis; 2],
    tol: &[Tolerance],
) -> Result<ErrorMap>
where
    M: Parametric<P, A>,
{
    for a in &axes {
        if a.coordinate >= P || !(a.step > 0.0) || !(a.max >= a.min) {
            return Err(Error::InvalidInput {
                what: "error map".into(),
                message: format!(
                    "axis {} with range [{}, {}] and step {} is not a grid of this machine's {P} coordinates",
                    a.coordinate, a.min, a.max, a.step
                ),
            });
        }
    }
    if axes[0].coordinate == axes[1].coordinate {
        return Err(Error::InvalidInput {
            what: "error map".into(),
            message: "expected two different coordinates".into(),
        });
    }
    let (n0, n1) = (axes[0].count(), axes[1].count());
    let params = m.parameters();
    let cells: Vec<MapCell> = (0..n0 * n1)
        .into_par_iter()
        .map(|flat| {
            let (i, k) = (flat / n1, flat % n1);
            let mut y = *base;
            y[axes[0].coordinate] = axes[0].value(i);
            y[axes[1].coordinate] = axes[1].value(k);
            let b = inverse_checked(m, &y)
                .ok()
                .and_then(|_| sensitivities(m, &y).ok())
                .and_then(|s| Budget::from_sensitivities(&params, &s, tol).ok())
                .map(|b| [b.rss, b.worst_case]);
            MapCell {
                at: [axes[0].value(i), axes[1].value(k)],
                budget: b,
            }
        })
        .collect();
    let unreachable = cells.iter().filter(|c| c.budget.is_none()).count();
    let max_rss = cells
        .iter()
        .filter_map(|c| c.budget.map(|b| b[0]))
        .fold(0.0, f64::max);
    Ok(ErrorMap {
        axes,
        cells,
        unreachable,
        max_rss,
    })
}
