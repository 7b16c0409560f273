//! The workspace engine, generic over mechanisms: grids of poses, which limit binds
//! where, and the conditioning inside the reachable region (rayon, flat per point);
//! performance atlases (actuator positions, and the actuator rates a given pose
//! rate/acceleration capacity needs, [`atlas`]); forward workspaces over the actuator
//! strokes ([`forward`]).

pub mod atlas;
mod connected;
pub mod forward;
mod mapping;
mod reach;
mod summary;
mod verdict;

pub use mapping::map;
pub use reach::{
    default_grid, default_span, map_reach, reach_grid, reachable_tilt, tilt_orientations, ReachGrid,
};
pub use summary::WorkspaceSummary;

pub(crate) use verdict::{evaluate, reach};

use nalgebra::SVector;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::limits::LimitName;

/// One axis of a grid: a pose coordinate swept from `min` to `max` by `step`
/// (internal units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GridAxis {
    /// Index of the pose coordinate.
    pub coordinate: usize,
    /// First value.
    pub min: f64,
    /// Last value (included when on the step).
    pub max: f64,
    /// Step.
    pub step: f64,
}

impl GridAxis {
    /// Number of grid values.
    /// Saturates at `usize::MAX` for a step that is not positive or too fine, so a size
    /// check refuses it instead of arithmetic overflowing.
    pub fn count(&self) -> usize {
        let n = ((self.max - self.min) / self.step + 1e-9).floor();
        if (0.0..1e15).contains(&n) {
            n as usize + 1
        } else {
            usize::MAX
        }
    }

    /// The `i`-th value.
    pub fn value(&self, i: usize) -> f64 {
        self.min + self.step * i as f64
    }

    /// Whether the axis, over a coordinate of quantity `q`, is an angle whose values
    /// go round a whole turn (it has no faces a region could continue beyond).
    pub fn covers_turn(&self, q: crate::units::Quantity) -> bool {
        q == crate::units::Quantity::Angle
            && self.max - self.min + self.step >= std::f64::consts::TAU - 1e-9
    }
}

/// The per-axis indices of the grid point with flat index `k` (row-major over axes of
/// `counts` values), into `idx`.
pub(crate) fn unflatten(counts: &[usize], mut k: usize, idx: &mut [usize]) {
    for (i, n) in counts.iter().enumerate().rev() {
        idx[i] = k % n;
        k /= n;
    }
}

/// What a grid point's inverse kinematics and limits found: the categories a map
/// counts separately, so a solver failure is never reported as a limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PointStatus {
    /// A solution within every limit, not singular.
    Reachable,
    /// A solution exists; at least one limit is violated.
    Limits,
    /// No geometric solution exists (a strut shorter than its joints' distance, a
    /// target beyond the links' reach): proven, not searched.
    NoSolution,
    /// The numeric inverse kinematics did not converge from any start (robots), nor
    /// from the solutions of the reachable neighbours: unknown, not proven unreachable.
    SolverFailed,
    /// A solution at a singular configuration (the Jacobian has no inverse).
    Singular,
    /// A solution within every limit, but cut off from the base pose's region by
    /// points that are not: another assembly mode (a platform on the far side of its
    /// base, which it cannot reach without crossing a singular configuration), or a
    /// region the tool reaches only by changing its orientation on the way.
    Separate,
}

impl PointStatus {
    /// Every status, in the order above.
    pub const ALL: [PointStatus; 6] = [
        PointStatus::Reachable,
        PointStatus::Limits,
        PointStatus::NoSolution,
        PointStatus::SolverFailed,
        PointStatus::Singular,
        PointStatus::Separate,
    ];

    /// Its name in outputs (`no_solution`), as serialised.
    pub fn name(self) -> &'static str {
        match self {
            PointStatus::Reachable => "reachable",
            PointStatus::Limits => "limits",
            PointStatus::NoSolution => "no_solution",
            PointStatus::SolverFailed => "solver_failed",
            PointStatus::Singular => "singular",
            PointStatus::Separate => "separate",
        }
    }
}

/// What one grid point found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointResult {
    /// Within every limit (for every orientation of the set).
    pub reachable: bool,
    /// The category of the result.
    pub status: PointStatus,
    /// Condition number (worst over the orientation set), when reachable.
    pub condition: f64,
    /// The first violated limit in the machine's check order, or why there is no
    /// solution, when not reachable (shared text: a map of millions of points beyond
    /// a limit clones a pointer per point, not a string).
    pub binding: Option<LimitName>,
}

impl PointResult {
    fn unreachable(status: PointStatus, binding: LimitName) -> Self {
        PointResult {
            reachable: false,
            status,
            condition: f64::NAN,
            binding: Some(binding),
        }
    }
}

/// Statistics of the condition number over the reachable points.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct ConditionStats {
    /// Smallest.
    pub min: f64,
    /// Median.
    pub median: f64,
    /// Mean.
    pub mean: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Largest.
    pub max: f64,
}

/// A map of a grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WorkspaceMap {
    /// The grid axes (first varies slowest).
    pub axes: Vec<GridAxis>,
    /// The pose all points start from (coordinates not on an axis keep its values).
    pub base: Vec<f64>,
    /// Orientation offsets tested at every point (total orientation workspace), as
    /// A, B, C (rad) added through rotation composition; empty = base orientation only.
    pub orientations: usize,
    /// One result per grid point, in row-major order of `axes`.
    pub points: Vec<PointResult>,
    /// Points per violated limit, every violated limit of a point counted (not only
    /// the first), most frequent first.
    pub violated: Vec<(String, usize)>,
    /// Per axis, whether its `[min, max]` faces are bounds of the machine's reach (the
    /// type's [`Mechanism::position_bound`]): reachable points on them do not mean the
    /// region goes on beyond the grid.
    ///
    /// [`Mechanism::position_bound`]: crate::mechanism::Mechanism::position_bound
    pub closed: Vec<[bool; 2]>,
}

/// Index of a grid point from its per-axis indices.
pub fn flat_index(axes: &[GridAxis], idx: &[usize]) -> usize {
    let mut k = 0;
    for (a, i) in axes.iter().zip(idx) {
        k = k * a.count() + i;
    }
    k
}

/// The grid point with flat index `k` (row-major over `axes`, `counts` their sizes):
/// `base` with the axis coordinates set.
#[inline]
pub(crate) fn grid_point<const N: usize>(
    base: &SVector<f64, N>,
    axes: &[GridAxis],
    counts: &[usize],
    k: usize,
) -> SVector<f64, N> {
    let mut x = *base;
    let mut rem = k;
    for (a, n) in axes.iter().zip(counts).rev() {
        x[a.coordinate] = a.value(rem % n);
        rem /= n;
    }
    x
}

/// Checks grid axes against `n` coordinates.
pub(crate) fn check_axes(axes: &[GridAxis], n: usize) -> Result<()> {
    for (i, a) in axes.iter().enumerate() {
        if a.coordinate >= n || !(a.step > 0.0) || !(a.max >= a.min) || !a.min.is_finite() {
            return Err(Error::InvalidInput {
                what: "workspace grid".into(),
                message: format!(
                    "axis {} (coordinate {}): expected a step > 0 and finite bounds with max >= \
                     min, found step {}, bounds [{}, {}]",
                    i + 1,
                    a.coordinate,
                    a.step,
                    a.min,
                    a.max
                ),
            });
        }
    }
    let total = axes.iter().map(|a| a.count() as f64).product::<f64>();
    if total > MAX_GRID_POINTS as f64 {
        return Err(Error::InvalidInput {
            what: "workspace grid".into(),
            message: format!(
                "the grid has {total:.3e} points, more than {MAX_GRID_POINTS:.0e}: give a \
                 larger step or smaller bounds"
            ),
        });
    }
    Ok(())
}

/// The largest number of points a grid may have (5e7: seconds to a minute of work).
pub const MAX_GRID_POINTS: usize = 50_000_000;
