//! The workspace engine, generic over mechanisms: grids of poses, which limit binds
//! where, and the conditioning inside the reachable region (rayon, flat per point);
//! performance atlases (actuator positions, and the actuator rates a given pose
//! rate/acceleration capacity needs, [`atlas`]); forward workspaces over the actuator
//! strokes ([`forward`]).

pub mod atlas;
mod connected;
pub mod forward;
mod reach;
mod summary;
mod verdict;

pub use reach::{
    default_grid, default_span, map_reach, reach_grid, reachable_tilt, tilt_orientations, ReachGrid,
};
pub use summary::WorkspaceSummary;

use connected::{keep_connected, nearest_index, neighbours};
use verdict::{admit, conditioned, fold_conditions, Tally};
pub(crate) use verdict::{evaluate, reach};

use nalgebra::SVector;
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::limits::{LimitName, Violation};
use crate::mechanism::Mechanism;
use crate::rotation::Convention;

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

/// Maps a grid of poses: for each point the base pose with the axis coordinates set,
/// then, for spatial machines, each orientation of `orientations` (A, B, C in rad,
/// composed with the base orientation) — a point is reachable when every one is.
/// `progress` is called with the number of points done (from several threads).
pub fn map<M, const P: usize, const A: usize>(
    m: &M,
    base: &SVector<f64, P>,
    axes: &[GridAxis],
    orientations: &[[f64; 3]],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<WorkspaceMap>
where
    M: Mechanism<P, A>,
{
    check_axes(axes, P)?;
    if !orientations.is_empty() && P != 6 {
        return Err(Error::InvalidInput {
            what: "orientation set".into(),
            message: "orientation sets need a machine with X, Y, Z, A, B, C".into(),
        });
    }
    let counts: Vec<usize> = axes.iter().map(|a| a.count()).collect();
    let total: usize = counts.iter().product();
    let base_r = if P == 6 {
        Convention::Rpy.to_matrix([base[3], base[4], base[5]])
    } else {
        nalgebra::Matrix3::identity()
    };
    let rots: Vec<[f64; 3]> = orientations
        .iter()
        .map(|o| Convention::Rpy.from_matrix(&(Convention::Rpy.to_matrix(*o) * base_r)))
        .collect();
    let chunk = 4096;
    // Inverse kinematics (from `seed`, else home) and limits at `x` in each orientation
    // of the set: the poses within every limit, in orientation order, go to `pend`; the
    // result of the first one that is not, if any.
    let admit_all = |x: &SVector<f64, P>,
                     v: &mut Vec<Violation>,
                     seed: Option<&SVector<f64, A>>,
                     pend: &mut dyn FnMut(SVector<f64, P>, SVector<f64, A>)|
     -> Option<PointResult> {
        let solve = |x: &SVector<f64, P>| match seed {
            Some(q) => m.inverse_near(x, q),
            None => m.inverse(x),
        };
        if rots.is_empty() {
            return match admit(m, x, solve(x), v) {
                Ok(q) => {
                    pend(*x, q);
                    None
                }
                Err(r) => Some(r),
            };
        }
        let mut x = *x;
        for o in &rots {
            for (i, val) in o.iter().enumerate() {
                x[3 + i] = *val;
            }
            match admit(m, &x, solve(&x), v) {
                Ok(q) => pend(x, q),
                Err(r) => return Some(r),
            }
        }
        None
    };
    // One point alone (the retries from a neighbour's solution): `v` is left with the
    // violations of a point beyond a limit.
    let evaluate_all =
        |x: &SVector<f64, P>, v: &mut Vec<Violation>, seed: Option<&SVector<f64, A>>| {
            let (mut xs, mut qs) = (Vec::new(), Vec::new());
            let r = admit_all(x, v, seed, &mut |x, q| {
                xs.push(x);
                qs.push(q);
            });
            let mut cs = vec![0.0; xs.len()];
            crate::mechanism::abilities::conditions(m, &xs, &qs, &mut cs);
            let mut point = [r.unwrap_or_else(|| conditioned(0.0))];
            fold_conditions(
                &mut point,
                &vec![0; cs.len()],
                &cs,
                Vec::new(),
                &mut Tally::default(),
            );
            let [point] = point;
            point
        };
    // Chunks in parallel, each with its own tally of every violated limit (merged in
    // order afterwards: no locks, and the points keep their grid order). In a chunk,
    // inverse kinematics and limits point by point, then the condition numbers of
    // every pose within the limits in one call (`abilities::conditions`: the
    // hexapod's runs eight poses across SIMD lanes), folded as `evaluate_all` does:
    // the worst over the orientations; singular at the first that is not finite, also
    // before an orientation beyond a limit.
    let chunks: Vec<(Vec<PointResult>, Tally)> = (0..total.div_ceil(chunk))
        .into_par_iter()
        .map_init(Vec::new, |v, c| {
            let range = c * chunk..((c + 1) * chunk).min(total);
            let mut tally = Tally::default();
            let mut points: Vec<PointResult> = Vec::with_capacity(range.len());
            let (mut xs, mut qs, mut owner) = (Vec::new(), Vec::new(), Vec::new());
            // Points beyond a limit after orientations whose conditions are pending:
            // their violations, tallied unless one of those is singular.
            let mut deferred: Vec<(usize, Vec<Violation>)> = Vec::new();
            for k in range.clone() {
                let i = points.len();
                let before = xs.len();
                let mut pend = |x, q| {
                    xs.push(x);
                    qs.push(q);
                    owner.push(i);
                };
                match admit_all(&grid_point(base, axes, &counts, k), v, None, &mut pend) {
                    Some(r) => {
                        if r.status == PointStatus::Limits {
                            if xs.len() > before {
                                deferred.push((i, v.clone()));
                            } else {
                                tally.add(v);
                            }
                        }
                        points.push(r);
                    }
                    None => points.push(conditioned(0.0)),
                }
            }
            let mut cs = vec![0.0; xs.len()];
            crate::mechanism::abilities::conditions(m, &xs, &qs, &mut cs);
            fold_conditions(&mut points, &owner, &cs, deferred, &mut tally);
            progress(range.len() as u64);
            (points, tally)
        })
        .collect();
    let mut tally = Tally::default();
    let mut points = Vec::with_capacity(total);
    for (p, t) in chunks {
        points.extend(p);
        tally.merge(t);
    }
    // A point the solver failed on is tried again from the solutions of its reachable
    // neighbours (continuation), a few sweeps so that solved points seed the next.
    for _ in 0..3 {
        let failed: Vec<usize> = (0..total)
            .filter(|&k| points[k].status == PointStatus::SolverFailed)
            .collect();
        if failed.is_empty() {
            break;
        }
        let retried: Vec<(usize, PointResult, Tally)> = failed
            .par_iter()
            .filter_map(|&k| {
                let mut v = Vec::new();
                let x = grid_point(base, axes, &counts, k);
                for nb in neighbours(&counts, k) {
                    if !matches!(
                        points[nb].status,
                        PointStatus::Reachable | PointStatus::Limits
                    ) {
                        continue;
                    }
                    let Ok(seed) = m.inverse(&grid_point(base, axes, &counts, nb)) else {
                        continue;
                    };
                    let r = evaluate_all(&x, &mut v, Some(&seed));
                    if r.status != PointStatus::SolverFailed {
                        let mut t = Tally::default();
                        if r.status == PointStatus::Limits {
                            t.add(&v);
                        }
                        return Some((k, r, t));
                    }
                }
                None
            })
            .collect();
        if retried.is_empty() {
            break;
        }
        for (k, r, t) in retried {
            points[k] = r;
            tally.merge(t);
        }
    }
    keep_connected(&mut points, &counts, &nearest_index(base, axes, &counts));
    Ok(WorkspaceMap {
        axes: axes.to_vec(),
        base: base.as_slice().to_vec(),
        orientations: orientations.len(),
        points,
        violated: tally.sorted(),
        closed: vec![[false; 2]; axes.len()],
    })
}
