//! Where to map: the grid over a machine's whole reach (the type's bound on the tool
//! position, or a box grown and shrunk by probing), the default grid over given
//! bounds, and the reachable tilt at a point (orientation workspace).

use nalgebra::SVector;
use serde::Serialize;

use super::{check_axes, evaluate, map, GridAxis, WorkspaceMap, MAX_GRID_POINTS};
use crate::dynamic::DynMechanism;
use crate::error::{Error, Result};
use crate::limits::Violation;
use crate::mechanism::{Mechanism, PoseSpace};
use crate::rotation::Convention;
use crate::units::Quantity;

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
    if P != 6 || m.info().pose_space() != crate::mechanism::PoseSpace::Spatial {
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

/// The orientation set of a tilt workspace: the base orientation and a tilt of `tilt`
/// (rad) about eight horizontal axes 45 degrees apart, as A, B, C offsets (rad, RPY)
/// for [`map`](super::map)'s `orientations`: a point is in the workspace when the
/// machine reaches it at all nine (the "tilt capability" of a PKM spindle).
pub fn tilt_orientations(tilt: f64) -> Vec<[f64; 3]> {
    let mut o = vec![[0.0; 3]];
    for k in 0..8 {
        let az = k as f64 * std::f64::consts::FRAC_PI_4;
        let axis = nalgebra::Unit::new_normalize(nalgebra::Vector3::new(-az.sin(), az.cos(), 0.0));
        let r = nalgebra::Rotation3::from_axis_angle(&axis, tilt);
        o.push(crate::Convention::Rpy.from_matrix(r.matrix()));
    }
    o
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
    check_size(&axes)?;
    Ok(axes)
}

/// Refuses a grid of more than [`MAX_GRID_POINTS`] points, naming the options.
fn check_size(axes: &[GridAxis]) -> Result<()> {
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
    Ok(())
}

/// A grid over the machine's whole reach, and how its bounds were found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReachGrid {
    /// The grid's axes (the coordinates of [`default_grid`]).
    pub axes: Vec<GridAxis>,
    /// How the bounds were found, for reports.
    pub method: String,
    /// Per axis, whether its faces are bounds of the reach ([`WorkspaceMap::closed`]).
    pub closed: Vec<[bool; 2]>,
}

/// Points per axis of the probing grids of [`reach_grid`].
const PROBE_POINTS: usize = 16;

/// A bound on the tool position: `[min, max]` per axis X, Y, Z (mm).
type PositionBound = [[f64; 2]; 3];

/// [`reach_grid`]'s start box over the grid axes `idx`: the type's bound on the tool
/// position when it gives one (returned too), else [`default_span`] per axis.
fn start_box<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    base: &SVector<f64, P>,
    idx: &[usize],
) -> (Option<PositionBound>, Vec<(f64, f64)>) {
    let bound = if idx == [0, 1, 2] && m.info().pose_space() != PoseSpace::Own {
        m.position_bound(base)
    } else {
        None
    };
    let ranges = match bound {
        Some(b) => b.iter().map(|r| (r[0], r[1])).collect(),
        None => idx
            .iter()
            .map(|&k| {
                span_of(
                    m.info().coordinates(),
                    m.info().actuators(),
                    m.info().pose_space(),
                    m.info().characteristic_length(),
                    base.as_slice(),
                    k,
                )
            })
            .collect(),
    };
    (bound, ranges)
}

/// A grid over the whole reach of the machine at `base`'s orientation (the held
/// coordinates from `base`), `steps` cells per axis, or `step` (user units) when given.
///
/// The start box is [`Mechanism::position_bound`] when the type gives one (a bound:
/// nothing reachable lies outside), else [`default_span`] per axis. A probing grid of
/// 16 cells per axis then maps the box; without a bound, every face that reachable
/// points lie on is moved out by half the box (angles up to a whole turn), up to eight
/// times, until no reachable point lies on a face. Finally the box is shrunk to the
/// reachable probe points plus one probing cell on every side, so the map's cells are
/// spent where the machine reaches. A region thinner than a probing cell can be
/// missed by the shrink; [`super::WorkspaceSummary::cut`] of the final map says when
/// reachable points lie on its faces.
pub fn reach_grid<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    base: &SVector<f64, P>,
    steps: usize,
    step: Option<f64>,
) -> Result<ReachGrid> {
    if let Some(s) = step.filter(|s| !(*s > 0.0 && s.is_finite())) {
        return Err(Error::InvalidInput {
            what: "grid".into(),
            message: format!("--step: expected a step > 0, found {s}"),
        });
    }
    let idx: Vec<usize> = match m.info().pose_space() {
        PoseSpace::Own => (0..P.min(3)).collect(),
        _ => vec![0, 1, 2],
    };
    let q = |k: usize| m.info().coordinates()[k].quantity;
    let (bound, mut ranges) = start_box(m, base, &idx);
    let mut method = match bound {
        Some(_) => "the type's bound on the tool position".to_string(),
        None => "the default span".to_string(),
    };
    let mut closed = vec![[bound.is_some(); 2]; idx.len()];
    let mut grown = 0;
    for round in 0..9 {
        let probe = grid_over(&idx, &ranges, &|_, lo, hi| (hi - lo) / PROBE_POINTS as f64);
        let map = map(m, base, &probe, &[], &|_| {})?;
        let Some(ext) = map.reachable_extent() else {
            method.push_str(" (no reachable point found by a probing grid: kept whole)");
            break;
        };
        if bound.is_none() && round < 8 && grow_faces(m, base, &probe, &ext, &mut ranges) {
            grown += 1;
            continue;
        }
        shrink_to_reach(m, &probe, &ext, &mut ranges, &mut closed);
        if grown > 0 {
            method.push_str(&format!(", grown {grown} times"));
        }
        method.push_str(", shrunk to the reachable points of a 16-cell probing grid plus one cell");
        break;
    }
    let axes = grid_over(&idx, &ranges, &|k, lo, hi| {
        step.map(|s| q(k).from_user(s))
            .unwrap_or((hi - lo) / steps.max(1) as f64)
    });
    check_size(&axes)?;
    check_axes(&axes, P)?;
    Ok(ReachGrid {
        axes,
        method,
        closed,
    })
}

/// Moves out by half the box every face of `ranges` (one per axis of the grid
/// `probe`) that reachable points lie on (`ext`: their first and last index per axis),
/// angles up to half a turn either side of `base`; whether any moved.
fn grow_faces<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    base: &SVector<f64, P>,
    probe: &[GridAxis],
    ext: &[[usize; 2]],
    ranges: &mut [(f64, f64)],
) -> bool {
    let turn = std::f64::consts::TAU;
    let mut grew = false;
    for (i, a) in probe.iter().enumerate() {
        let k = a.coordinate;
        let quantity = m.info().coordinates()[k].quantity;
        if a.covers_turn(quantity) {
            continue;
        }
        let (lo, hi) = ranges[i];
        let half = 0.5 * (hi - lo);
        // Angles grow up to half a turn either side of the base.
        let cap = |v: f64| match quantity {
            Quantity::Angle => v.clamp(base[k] - 0.5 * turn, base[k] + 0.5 * turn),
            Quantity::Length => v,
        };
        let new_lo = if ext[i][0] == 0 { cap(lo - half) } else { lo };
        let new_hi = if ext[i][1] + 1 == a.count() {
            cap(hi + half)
        } else {
            hi
        };
        ranges[i] = (new_lo, new_hi);
        grew |= ranges[i] != (lo, hi);
    }
    grew
}

/// Shrinks `ranges` to the reachable points of the grid `probe` (`ext`: their first
/// and last index per axis) plus one probing cell, except on axes that go round a
/// turn; a face moved in is no longer `closed` (the type's bound).
fn shrink_to_reach<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    probe: &[GridAxis],
    ext: &[[usize; 2]],
    ranges: &mut [(f64, f64)],
    closed: &mut [[bool; 2]],
) {
    for (i, a) in probe.iter().enumerate() {
        if a.covers_turn(m.info().coordinates()[a.coordinate].quantity) {
            continue;
        }
        // A face moved in is no longer the type's bound.
        closed[i][0] &= ext[i][0] == 0;
        closed[i][1] &= ext[i][1] + 1 == a.count();
        let lo = a.value(ext[i][0].saturating_sub(1));
        let hi = a.value((ext[i][1] + 1).min(a.count() - 1));
        ranges[i] = (lo, hi.max(lo + a.step));
    }
}

/// Grid axes over coordinates `idx` and their `ranges`, the step of each from
/// `step_of(coordinate, min, max)`.
fn grid_over(
    idx: &[usize],
    ranges: &[(f64, f64)],
    step_of: &dyn Fn(usize, f64, f64) -> f64,
) -> Vec<GridAxis> {
    idx.iter()
        .zip(ranges)
        .map(|(&k, &(lo, hi))| GridAxis {
            coordinate: k,
            min: lo,
            max: hi,
            step: step_of(k, lo, hi),
        })
        .collect()
}

/// [`map`] over the machine's whole reach: the grid of [`reach_grid`], then, while
/// reachable points lie on a face that is not a bound of the reach (the probing grid
/// missed part of the region), that face moved out by a quarter of the axis' span and
/// the map made again (at most three times). Returns the map and how its grid was
/// found.
pub fn map_reach<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    base: &SVector<f64, P>,
    steps: usize,
    step: Option<f64>,
    orientations: &[[f64; 3]],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(WorkspaceMap, String)> {
    let g = reach_grid(m, base, steps, step)?;
    let mut axes = g.axes;
    let mut method = g.method;
    let mut round = 0;
    loop {
        let mut wm = map(m, base, &axes, orientations, progress)?;
        wm.closed = g.closed.clone();
        let open = wm.open_faces(m.info().coordinates());
        if round == 3 || open.iter().all(|f| !f[0] && !f[1]) {
            return Ok((wm, method));
        }
        round += 1;
        let mut widened = Vec::new();
        for (a, f) in axes.iter_mut().zip(&open) {
            // A quarter of the span, in whole steps so the grid keeps its points.
            let n = (0.25 * (a.max - a.min) / a.step).ceil().max(1.0) * a.step;
            let name = &m.info().coordinates()[a.coordinate].name;
            if f[0] {
                a.min -= n;
                widened.push(format!("{name} min"));
            }
            if f[1] {
                a.max += n;
                widened.push(format!("{name} max"));
            }
        }
        check_axes(&axes, P)?;
        method.push_str(&format!(
            "; widened at {} where the map reached its edge",
            widened.join(", ")
        ));
    }
}

/// The default span of pose coordinate `k` around `base`: a joint of a machine in
/// joint space, its travel; otherwise `base +- 0.6` reach for lengths (the largest
/// stroke of linear drives; for revolute drives the tool's distance from the base at
/// home / 0.6) and `+-pi` for angles.
pub fn default_span(m: &dyn DynMechanism, base: &[f64], k: usize) -> (f64, f64) {
    span_of(
        m.coordinates(),
        m.actuators(),
        m.pose_space(),
        m.characteristic_length(),
        base,
        k,
    )
}

/// [`default_span`] from the machine's coordinates, actuators, pose space and
/// characteristic length.
fn span_of(
    coordinates: &[crate::mechanism::Coordinate],
    actuators: &[crate::mechanism::Actuator],
    pose_space: PoseSpace,
    characteristic_length: f64,
    base: &[f64],
    k: usize,
) -> (f64, f64) {
    let c = &coordinates[k];
    if pose_space == PoseSpace::Own {
        if let Some(a) = actuators
            .iter()
            .find(|a| a.name == c.name && a.quantity == c.quantity)
        {
            return (a.range.min, a.range.max);
        }
    }
    // Linear drives: their largest stroke sets the scale. A machine with revolute
    // drives (a robot arm): the distance of the tool from the base at home.
    let reach = if actuators
        .iter()
        .any(|a| a.quantity == crate::units::Quantity::Angle)
        && pose_space != PoseSpace::Own
    {
        characteristic_length / 0.6
    } else {
        actuators
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
