//! The workspace engine, generic over mechanisms: grids of poses, which limit binds
//! where, and the conditioning inside the reachable region (rayon, flat per point);
//! performance atlases (actuator positions, and the actuator rates a given pose
//! rate/acceleration capacity needs, [`atlas`]); forward workspaces over the actuator
//! strokes ([`forward`]).

pub mod atlas;
pub mod forward;

use nalgebra::SVector;
use rayon::prelude::*;
use serde::Serialize;

use crate::dynamic::DynMechanism;
use crate::error::{Error, Result};
use crate::limits::Violation;
use crate::mechanism::{Mechanism, PoseSpace};
use crate::rotation::Convention;
use crate::units::Quantity;

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
}

/// What one grid point found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointResult {
    /// Within every limit (for every orientation of the set).
    pub reachable: bool,
    /// Condition number (worst over the orientation set), when reachable.
    pub condition: f64,
    /// The first violated limit, when not reachable.
    pub binding: Option<String>,
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
}

/// Summary of a map.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WorkspaceSummary {
    /// Points in the grid.
    pub points: usize,
    /// Reachable points.
    pub reachable: usize,
    /// Reachable fraction.
    pub reachable_fraction: f64,
    /// Reachable measure of the grid's space: cell count times cell size, in
    /// [`WorkspaceSummary::measure_unit`] (mm^3 over X, Y, Z; mm·deg over a planar
    /// head's z, theta; mm^3·deg^3 over six axes).
    pub measure: f64,
    /// The unit of [`WorkspaceSummary::measure`]: `mm^k·deg^j` for k length and j
    /// angle axes (`mm^3`, `mm^2`, `mm·deg`, `deg^2`).
    pub measure_unit: String,
    /// What the measure is: `volume` (three length axes), `area` (two), `length`
    /// (one), else `measure` (a product with angles, not a volume).
    pub measure_name: String,
    /// The reachable volume (mm^3) when the grid is over three length axes, else
    /// `None` (an area in mm·deg is not a volume).
    pub volume_mm3: Option<f64>,
    /// Bounding box of the reachable points per axis: `[min, max]` in user units.
    pub bounding_box: Vec<[f64; 2]>,
    /// Condition number statistics.
    pub condition: ConditionStats,
    /// Points per binding limit (the first violated one), sorted by count.
    pub binding: Vec<(String, usize)>,
}

/// Index of a grid point from its per-axis indices.
pub fn flat_index(axes: &[GridAxis], idx: &[usize]) -> usize {
    let mut k = 0;
    for (a, i) in axes.iter().zip(idx) {
        k = k * a.count() + i;
    }
    k
}

/// Inverse kinematics and every limit at `x`: the actuator values when the pose is
/// within every limit, else the name of what binds (`no solution`, the first violated
/// limit) beside the actuator values when they exist.
pub(crate) fn reach<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    v: &mut Vec<Violation>,
) -> (Option<SVector<f64, A>>, Option<String>) {
    let q = match m.inverse(x) {
        Ok(q) => q,
        Err(e) => {
            let why = match e {
                Error::NotAttainable { .. } => "no solution".into(),
                // Numeric inverse kinematics (serial robots): one key, not one per residual.
                Error::NotConverged { .. } => {
                    "no solution (inverse kinematics did not converge)".into()
                }
                Error::Singular { .. } => "singular".into(),
                other => other.to_string(),
            };
            return (None, Some(why));
        }
    };
    v.clear();
    m.check_limits(x, &q, v);
    (Some(q), v.first().map(|f| f.limit.clone()))
}

pub(crate) fn evaluate<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    v: &mut Vec<Violation>,
) -> PointResult {
    let q = match reach(m, x, v) {
        (Some(q), None) => q,
        (_, binding) => {
            return PointResult {
                reachable: false,
                condition: f64::NAN,
                binding,
            }
        }
    };
    let c = m.condition_at(x, &q).unwrap_or(f64::INFINITY);
    PointResult {
        reachable: c.is_finite(),
        condition: c,
        binding: if c.is_finite() {
            None
        } else {
            Some("singular".into())
        },
    }
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
    let points: Vec<PointResult> = (0..total)
        .into_par_iter()
        .with_min_len(chunk)
        .map_init(Vec::new, |v, k| {
            let x = grid_point(base, axes, &counts, k);
            let r = if rots.is_empty() {
                evaluate(m, &x, v)
            } else {
                let mut worst = PointResult {
                    reachable: true,
                    condition: 0.0,
                    binding: None,
                };
                let mut x = x;
                for o in &rots {
                    for (i, val) in o.iter().enumerate() {
                        x[3 + i] = *val;
                    }
                    let r = evaluate(m, &x, v);
                    if !r.reachable {
                        worst = r;
                        break;
                    }
                    worst.condition = worst.condition.max(r.condition);
                }
                worst
            };
            if k % chunk == chunk - 1 {
                progress(chunk as u64);
            }
            r
        })
        .collect();
    Ok(WorkspaceMap {
        axes: axes.to_vec(),
        base: base.as_slice().to_vec(),
        orientations: orientations.len(),
        points,
    })
}

impl WorkspaceMap {
    /// Coordinates (internal units) of the point with flat index `k`.
    pub fn coords(&self, k: usize) -> Vec<f64> {
        let mut x = self.base.clone();
        let mut rem = k;
        for a in self.axes.iter().rev() {
            let n = a.count();
            x[a.coordinate] = a.value(rem % n);
            rem /= n;
        }
        x
    }

    /// Summary statistics in user units (mm, deg) for the grid's axes of quantities
    /// `quantities` (one per axis).
    pub fn summary_of(&self, quantities: &[Quantity]) -> WorkspaceSummary {
        let q = |i: usize| quantities.get(i).copied().unwrap_or(Quantity::Length);
        let cell: f64 = (0..self.axes.len())
            .map(|i| q(i).to_user(self.axes[i].step))
            .product();
        let lengths = (0..self.axes.len())
            .filter(|&i| q(i) == Quantity::Length)
            .count();
        let angles = self.axes.len() - lengths;
        let power = |u: &str, k: usize| match k {
            0 => None,
            1 => Some(u.to_string()),
            k => Some(format!("{u}^{k}")),
        };
        let unit = [power("mm", lengths), power("deg", angles)]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join("·");
        let name = match (lengths, angles) {
            (3, 0) => "volume",
            (2, 0) => "area",
            (1, 0) => "length",
            _ => "measure",
        };
        self.summary(&|i, v| q(i).to_user(v), cell, &unit, name)
    }

    /// Summary statistics; `to_user` converts a coordinate value of axis `i` to user
    /// units; `cell` is the measure of one cell in user units, `unit` its unit and
    /// `name` what it is (see [`WorkspaceSummary`]).
    pub fn summary(
        &self,
        to_user: &dyn Fn(usize, f64) -> f64,
        cell: f64,
        unit: &str,
        name: &str,
    ) -> WorkspaceSummary {
        let mut conds: Vec<f64> = Vec::new();
        let mut bbox = vec![[f64::INFINITY, f64::NEG_INFINITY]; self.axes.len()];
        let mut binding: std::collections::HashMap<String, usize> = Default::default();
        for (k, p) in self.points.iter().enumerate() {
            if p.reachable {
                conds.push(p.condition);
                let x = self.coords(k);
                for (i, a) in self.axes.iter().enumerate() {
                    let v = to_user(i, x[a.coordinate]);
                    bbox[i][0] = bbox[i][0].min(v);
                    bbox[i][1] = bbox[i][1].max(v);
                }
            } else if let Some(b) = &p.binding {
                *binding.entry(b.clone()).or_default() += 1;
            }
        }
        conds.sort_by(|a, b| a.total_cmp(b));
        let pick = |f: f64| conds[((conds.len() - 1) as f64 * f).round() as usize];
        let condition = if conds.is_empty() {
            ConditionStats::default()
        } else {
            ConditionStats {
                min: conds[0],
                median: pick(0.5),
                mean: conds.iter().sum::<f64>() / conds.len() as f64,
                p95: pick(0.95),
                max: conds[conds.len() - 1],
            }
        };
        let mut binding: Vec<(String, usize)> = binding.into_iter().collect();
        binding.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        WorkspaceSummary {
            points: self.points.len(),
            reachable: conds.len(),
            reachable_fraction: conds.len() as f64 / self.points.len().max(1) as f64,
            measure: conds.len() as f64 * cell,
            measure_unit: unit.to_string(),
            measure_name: name.to_string(),
            volume_mm3: (unit == "mm^3").then_some(conds.len() as f64 * cell),
            bounding_box: bbox,
            condition,
            binding,
        }
    }
}

/// The largest tilt (rad) reachable at tool position `x` (spatial machines) towards
/// each of `azimuths` directions, by bisection to `tol` rad up to `max_tilt`: the
/// orientation workspace at a point. The tilt is a rotation about a horizontal axis
/// at the azimuth, composed with the base orientation of `x`.
pub fn reachable_tilt<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    azimuths: &[f64],
    max_tilt: f64,
    tol: f64,
) -> Result<Vec<f64>> {
    if P != 6 || m.pose_space() != crate::mechanism::PoseSpace::Spatial {
        return Err(Error::InvalidInput {
            what: "orientation workspace".into(),
            message: "needs a machine with X, Y, Z, A, B, C".into(),
        });
    }
    let base_r = Convention::Rpy.to_matrix([x[3], x[4], x[5]]);
    let mut v = Vec::new();
    let ok = |az: f64, t: f64, v: &mut Vec<Violation>| {
        let axis = nalgebra::Unit::new_normalize(nalgebra::Vector3::new(-az.sin(), az.cos(), 0.0));
        let r = nalgebra::Rotation3::from_axis_angle(&axis, t).matrix() * base_r;
        let a = Convention::Rpy.from_matrix(&r);
        let mut y = *x;
        y[3] = a[0];
        y[4] = a[1];
        y[5] = a[2];
        evaluate(m, &y, v).reachable
    };
    Ok(azimuths
        .iter()
        .map(|&az| {
            if !ok(az, 0.0, &mut v) {
                return f64::NAN;
            }
            if ok(az, max_tilt, &mut v) {
                return max_tilt;
            }
            let (mut lo, mut hi) = (0.0, max_tilt);
            while hi - lo > tol {
                let mid = 0.5 * (lo + hi);
                if ok(az, mid, &mut v) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        })
        .collect())
}

/// The default grid of a machine around pose `base`: X, Y, Z for spatial machines
/// (the other coordinates from `base`), else up to three of its own coordinates, over
/// `bounds` (user units, min,max per axis) or [`default_span`], with `step` (user
/// units) or 1/40 of each range. Grids beyond 5e7 points are refused.
pub fn default_grid(
    m: &dyn DynMechanism,
    base: &[f64],
    bounds: Option<&[f64]>,
    step: Option<f64>,
) -> crate::Result<Vec<GridAxis>> {
    let idx: Vec<usize> = match m.pose_space() {
        PoseSpace::Own => (0..m.coordinates().len().min(3)).collect(),
        _ => vec![0, 1, 2],
    };
    let q = |k: usize| m.coordinates()[k].quantity;
    let mut ranges = Vec::new();
    match bounds {
        Some(b) => {
            if b.len() != 2 * idx.len() {
                return Err(crate::Error::InvalidInput {
                    what: "grid".into(),
                    message: format!(
                        "--bounds: expected {} values (min,max per axis), got {}",
                        2 * idx.len(),
                        b.len()
                    ),
                });
            }
            for (i, &k) in idx.iter().enumerate() {
                let (lo, hi) = (q(k).from_user(b[2 * i]), q(k).from_user(b[2 * i + 1]));
                if hi <= lo {
                    return Err(crate::Error::InvalidInput {
                        what: "grid".into(),
                        message: format!(
                            "--bounds: axis {} has max <= min",
                            m.coordinates()[k].name
                        ),
                    });
                }
                ranges.push((lo, hi));
            }
        }
        None => {
            for &k in &idx {
                ranges.push(default_span(m, base, k));
            }
        }
    }
    let axes = idx
        .iter()
        .zip(&ranges)
        .map(|(&k, &(lo, hi))| GridAxis {
            coordinate: k,
            min: lo,
            max: hi,
            step: step.map(|s| q(k).from_user(s)).unwrap_or((hi - lo) / 40.0),
        })
        .collect::<Vec<_>>();
    if let Some(s) = step.filter(|s| !(*s > 0.0 && s.is_finite())) {
        return Err(crate::Error::InvalidInput {
            what: "grid".into(),
            message: format!("--step: expected a step > 0, found {s}"),
        });
    }
    let total: f64 = axes.iter().map(|a| a.count() as f64).product();
    if total > MAX_GRID_POINTS as f64 {
        return Err(crate::Error::InvalidInput {
            what: "grid".into(),
            message: format!(
                "the grid has {total:.3e} points; give a larger --step or smaller --bounds \
                 (at most 5e7)"
            ),
        });
    }
    Ok(axes)
}

/// The default span of pose coordinate `k` around `base`: a joint of a machine in
/// joint space, its travel; otherwise `base +- 0.6` reach for lengths (the largest
/// stroke of linear drives; for revolute drives the tool's distance from the base at
/// home / 0.6) and `+-pi` for angles.
pub fn default_span(m: &dyn DynMechanism, base: &[f64], k: usize) -> (f64, f64) {
    let c = &m.coordinates()[k];
    if m.pose_space() == PoseSpace::Own {
        if let Some(a) = m
            .actuators()
            .iter()
            .find(|a| a.name == c.name && a.quantity == c.quantity)
        {
            return (a.range.min, a.range.max);
        }
    }
    // Linear drives: their largest stroke sets the scale. A machine with revolute
    // drives (a robot arm): the distance of the tool from the base at home.
    let reach = if m
        .actuators()
        .iter()
        .any(|a| a.quantity == crate::units::Quantity::Angle)
        && m.pose_space() != PoseSpace::Own
    {
        m.characteristic_length() / 0.6
    } else {
        m.actuators()
            .iter()
            .map(|a| a.range.max.abs())
            .fold(0.0, f64::max)
    };
    let half = match c.quantity {
        crate::units::Quantity::Length => 0.6 * reach,
        crate::units::Quantity::Angle => std::f64::consts::PI,
    };
    (base[k] - half, base[k] + half)
}
