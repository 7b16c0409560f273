//! Mapping a grid of poses: inverse kinematics and limits point by point in parallel
//! chunks, the condition numbers of each chunk in one batch, retries from the
//! neighbours' solutions where the solver failed, then the region connected to the
//! base pose.

use nalgebra::SVector;
use rayon::prelude::*;

use super::connected::{keep_connected, nearest_index, neighbours};
use super::verdict::{admit, conditioned, fold_conditions, Tally};
use super::{check_axes, grid_point, GridAxis, PointResult, PointStatus, WorkspaceMap};
use crate::error::{Error, Result};
use crate::limits::Violation;
use crate::mechanism::Mechanism;
use crate::rotation::Convention;

/// Grid points per parallel chunk.
const CHUNK: usize = 4096;

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
    let grid = Grid::<M, P, A>::new(m, base, axes, orientations);
    let (mut points, mut tally) = grid.map_chunks(progress);
    // A point the solver failed on is tried again from the solutions of its reachable
    // neighbours (continuation), a few sweeps so that solved points seed the next.
    for _ in 0..3 {
        if !grid.retry_failed(&mut points, &mut tally) {
            break;
        }
    }
    keep_connected(
        &mut points,
        &grid.counts,
        &nearest_index(base, axes, &grid.counts),
    );
    Ok(WorkspaceMap {
        axes: axes.to_vec(),
        base: base.as_slice().to_vec(),
        orientations: orientations.len(),
        points,
        violated: tally.sorted(),
        closed: vec![[false; 2]; axes.len()],
    })
}

/// A grid to map on one mechanism: the base pose, the axes and their sizes, and the
/// orientation set composed with the base orientation.
struct Grid<'a, M, const P: usize, const A: usize> {
    /// The mechanism.
    m: &'a M,
    /// The pose every point starts from.
    base: &'a SVector<f64, P>,
    /// The grid axes (first varies slowest).
    axes: &'a [GridAxis],
    /// Values per axis.
    counts: Vec<usize>,
    /// Points of the grid.
    total: usize,
    /// The orientations (A, B, C) tested at every point; empty: the base one only.
    rots: Vec<[f64; 3]>,
}

/// What one chunk of the grid found: its points in grid order, and every violated
/// limit counted.
struct Chunk {
    /// The points.
    points: Vec<PointResult>,
    /// Points per violated limit.
    tally: Tally,
}

/// A point the solver failed on, solved again from a neighbour's solution.
struct Retried {
    /// Its flat index.
    k: usize,
    /// Its new result.
    result: PointResult,
    /// Its violated limits.
    tally: Tally,
}

impl<'a, M: Mechanism<P, A>, const P: usize, const A: usize> Grid<'a, M, P, A> {
    /// The grid over `axes` on `m` from `base`, each point in each of `orientations`
    /// (A, B, C in rad, composed with the base orientation).
    fn new(
        m: &'a M,
        base: &'a SVector<f64, P>,
        axes: &'a [GridAxis],
        orientations: &[[f64; 3]],
    ) -> Self {
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
        Grid {
            m,
            base,
            axes,
            counts,
            total,
            rots,
        }
    }

    /// Chunks in parallel, each with its own tally of every violated limit (merged in
    /// order afterwards: no locks, and the points keep their grid order); `progress`
    /// is called with the points of each chunk done.
    fn map_chunks(&self, progress: &(dyn Fn(u64) + Sync)) -> (Vec<PointResult>, Tally) {
        let chunks: Vec<Chunk> = (0..self.total.div_ceil(CHUNK))
            .into_par_iter()
            .map_init(Vec::new, |v, c| {
                let range = c * CHUNK..((c + 1) * CHUNK).min(self.total);
                let done = range.len() as u64;
                let chunk = self.map_chunk(range, v);
                progress(done);
                chunk
            })
            .collect();
        let mut tally = Tally::default();
        let mut points = Vec::with_capacity(self.total);
        for c in chunks {
            points.extend(c.points);
            tally.merge(c.tally);
        }
        (points, tally)
    }

    /// The points of flat indices `range` (`v`: storage for violations): inverse
    /// kinematics and limits point by point, then the condition numbers of every pose
    /// within the limits in one call (`abilities::conditions`: the hexapod's runs
    /// eight poses across SIMD lanes), folded as [`Grid::evaluate_alone`] does: the
    /// worst over the orientations; singular at the first that is not finite, also
    /// before an orientation beyond a limit.
    fn map_chunk(&self, range: std::ops::Range<usize>, v: &mut Vec<Violation>) -> Chunk {
        let mut tally = Tally::default();
        let mut points: Vec<PointResult> = Vec::with_capacity(range.len());
        let (mut xs, mut qs, mut owner) = (Vec::new(), Vec::new(), Vec::new());
        // Points beyond a limit after orientations whose conditions are pending:
        // their violations, tallied unless one of those is singular.
        let mut deferred: Vec<(usize, Vec<Violation>)> = Vec::new();
        for k in range {
            let i = points.len();
            let before = xs.len();
            let mut pend = |x, q| {
                xs.push(x);
                qs.push(q);
                owner.push(i);
            };
            let x = grid_point(self.base, self.axes, &self.counts, k);
            match self.admit_all(&x, v, None, &mut pend) {
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
        crate::mechanism::abilities::conditions(self.m, &xs, &qs, &mut cs);
        fold_conditions(&mut points, &owner, &cs, deferred, &mut tally);
        Chunk { points, tally }
    }

    /// Inverse kinematics (from `seed`, else home) and limits at `x` in each
    /// orientation of the set: the poses within every limit, in orientation order, go
    /// to `pend`; the result of the first one that is not, if any.
    fn admit_all<F>(
        &self,
        x: &SVector<f64, P>,
        v: &mut Vec<Violation>,
        seed: Option<&SVector<f64, A>>,
        pend: &mut F,
    ) -> Option<PointResult>
    where
        F: FnMut(SVector<f64, P>, SVector<f64, A>),
    {
        let m = self.m;
        let solve = |x: &SVector<f64, P>| match seed {
            Some(q) => m.inverse_near(x, q),
            None => m.inverse(x),
        };
        if self.rots.is_empty() {
            return match admit(m, x, solve(x), v) {
                Ok(q) => {
                    pend(*x, q);
                    None
                }
                Err(r) => Some(r),
            };
        }
        let mut x = *x;
        for o in &self.rots {
            for (i, val) in o.iter().enumerate() {
                x[3 + i] = *val;
            }
            match admit(m, &x, solve(&x), v) {
                Ok(q) => pend(x, q),
                Err(r) => return Some(r),
            }
        }
        None
    }

    /// One point alone (the retries from a neighbour's solution): `v` is left with
    /// the violations of a point beyond a limit.
    fn evaluate_alone(
        &self,
        x: &SVector<f64, P>,
        v: &mut Vec<Violation>,
        seed: Option<&SVector<f64, A>>,
    ) -> PointResult {
        let (mut xs, mut qs) = (Vec::new(), Vec::new());
        let r = self.admit_all(x, v, seed, &mut |x, q| {
            xs.push(x);
            qs.push(q);
        });
        let mut cs = vec![0.0; xs.len()];
        crate::mechanism::abilities::conditions(self.m, &xs, &qs, &mut cs);
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
    }

    /// One sweep of retries over the points the solver failed on, in parallel;
    /// `false` when none was left or none could be solved.
    fn retry_failed(&self, points: &mut [PointResult], tally: &mut Tally) -> bool {
        let failed: Vec<usize> = (0..self.total)
            .filter(|&k| points[k].status == PointStatus::SolverFailed)
            .collect();
        if failed.is_empty() {
            return false;
        }
        let found: &[PointResult] = points;
        let retried: Vec<Retried> = failed
            .par_iter()
            .filter_map(|&k| self.retry(found, k))
            .collect();
        if retried.is_empty() {
            return false;
        }
        for r in retried {
            points[r.k] = r.result;
            tally.merge(r.tally);
        }
        true
    }

    /// Point `k` solved from the solution of its first reachable neighbour (or one
    /// beyond a limit) from which the solver converges, if any.
    fn retry(&self, points: &[PointResult], k: usize) -> Option<Retried> {
        let mut v = Vec::new();
        let x = grid_point(self.base, self.axes, &self.counts, k);
        for nb in neighbours(&self.counts, k) {
            if !matches!(
                points[nb].status,
                PointStatus::Reachable | PointStatus::Limits
            ) {
                continue;
            }
            let Ok(seed) = self
                .m
                .inverse(&grid_point(self.base, self.axes, &self.counts, nb))
            else {
                continue;
            };
            let r = self.evaluate_alone(&x, &mut v, Some(&seed));
            if r.status != PointStatus::SolverFailed {
                let mut tally = Tally::default();
                if r.status == PointStatus::Limits {
                    tally.add(&v);
                }
                return Some(Retried {
                    k,
                    result: r,
                    tally,
                });
            }
        }
        None
    }
}
