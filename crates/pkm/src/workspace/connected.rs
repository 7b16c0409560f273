//! The grid's neighbours and the connected region of a workspace map: the points a
//! machine can move through from its base pose at one orientation, not a mirror
//! assembly mode beyond a singular configuration.

use nalgebra::SVector;

use super::{unflatten, GridAxis, PointResult, PointStatus};

/// The per-axis grid indices nearest the pose `base`.
pub(super) fn nearest_index<const N: usize>(
    base: &SVector<f64, N>,
    axes: &[GridAxis],
    counts: &[usize],
) -> Vec<usize> {
    axes.iter()
        .zip(counts)
        .map(|(a, &n)| {
            let i = ((base[a.coordinate] - a.min) / a.step).round();
            (i.max(0.0) as usize).min(n - 1)
        })
        .collect()
}

/// Marks [`PointStatus::Separate`] every reachable point not connected (through
/// reachable grid neighbours, one step along one axis) to the region of the grid point
/// `start`, or, when that point is not reachable, of the reachable point nearest it
/// (fewest steps; none reachable: nothing to do). The map then measures the region the
/// machine can move through at this orientation, not a mirror assembly mode beyond a
/// singular configuration.
pub(super) fn keep_connected(points: &mut [PointResult], counts: &[usize], start: &[usize]) {
    let mut idx = vec![0; counts.len()];
    let flat = |i: &[usize]| i.iter().zip(counts).fold(0, |k, (i, n)| k * n + i);
    let seed = if points[flat(start)].reachable {
        flat(start)
    } else {
        let steps = |k: usize, idx: &mut Vec<usize>| {
            unflatten(counts, k, idx);
            idx.iter()
                .zip(start)
                .map(|(a, b)| a.abs_diff(*b))
                .sum::<usize>()
        };
        match (0..points.len())
            .filter(|&k| points[k].reachable)
            .min_by_key(|&k| steps(k, &mut idx))
        {
            Some(k) => k,
            None => return,
        }
    };
    let mut seen = vec![false; points.len()];
    let mut stack = vec![seed];
    seen[seed] = true;
    while let Some(k) = stack.pop() {
        for nb in neighbours(counts, k) {
            if !seen[nb] && points[nb].reachable {
                seen[nb] = true;
                stack.push(nb);
            }
        }
    }
    for (p, s) in points.iter_mut().zip(seen) {
        if p.reachable && !s {
            p.reachable = false;
            p.status = PointStatus::Separate;
            p.binding = Some("separate region (not connected to the base pose)".into());
        }
    }
}

/// Flat indices of the grid neighbours (one step along one axis) of point `k`.
pub(super) fn neighbours(counts: &[usize], k: usize) -> Vec<usize> {
    let mut idx = vec![0; counts.len()];
    unflatten(counts, k, &mut idx);
    let mut out = Vec::new();
    let mut stride = 1;
    for (&n, &i) in counts.iter().zip(&idx).rev() {
        if i > 0 {
            out.push(k - stride);
        }
        if i + 1 < n {
            out.push(k + stride);
        }
        stride *= n;
    }
    out
}
