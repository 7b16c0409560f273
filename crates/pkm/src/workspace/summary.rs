//! What a map says in user units: reachable measure, bounding box, conditioning,
//! outcomes, the limits that bind, and the faces where the reachable region meets the
//! grid's edge.

use serde::Serialize;

use super::{ConditionStats, PointStatus, WorkspaceMap};
use crate::units::Quantity;

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
    /// Points per binding limit (the first violated one in the machine's check order),
    /// sorted by count; points without a solution under their reason.
    pub binding: Vec<(String, usize)>,
    /// Points per violated limit, every limit a point violates counted (a point beyond
    /// two limits counts for both), sorted by count.
    pub violated: Vec<(String, usize)>,
    /// Points per outcome: reachable, limits violated, no solution, solver failed,
    /// singular, separate.
    pub outcomes: Vec<(PointStatus, usize)>,
    /// Faces of the grid that reachable points lie on (`"Z min"`), where the reachable
    /// region may go on beyond the grid; empty when the grid holds all of it. An angle
    /// axis spanning a whole turn has no faces.
    pub cut: Vec<String>,
}

impl WorkspaceSummary {
    /// The number of points with outcome `status`.
    pub fn outcome(&self, status: PointStatus) -> usize {
        self.outcomes
            .iter()
            .find(|(k, _)| *k == status)
            .map_or(0, |x| x.1)
    }
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

    /// Per axis, the smallest and largest grid index of the reachable points (`None`
    /// when none is reachable).
    pub fn reachable_extent(&self) -> Option<Vec<[usize; 2]>> {
        let counts: Vec<usize> = self.axes.iter().map(|a| a.count()).collect();
        let mut ext: Option<Vec<[usize; 2]>> = None;
        let mut idx = vec![0; counts.len()];
        for (k, p) in self.points.iter().enumerate() {
            if !p.reachable {
                continue;
            }
            super::unflatten(&counts, k, &mut idx);
            let e = ext.get_or_insert_with(|| idx.iter().map(|&i| [i, i]).collect());
            for (e, &i) in e.iter_mut().zip(&idx) {
                e[0] = e[0].min(i);
                e[1] = e[1].max(i);
            }
        }
        ext
    }

    /// Per axis, whether reachable points lie on its `[min, max]` faces where the
    /// region may go on beyond the grid: faces that are no bound of the reach
    /// ([`WorkspaceMap::closed`]), of axes that do not go round a whole turn
    /// (`coordinates`: the machine's pose coordinates, which the axes index).
    pub fn open_faces(&self, coordinates: &[crate::mechanism::Coordinate]) -> Vec<[bool; 2]> {
        let Some(ext) = self.reachable_extent() else {
            return vec![[false; 2]; self.axes.len()];
        };
        self.axes
            .iter()
            .zip(ext)
            .enumerate()
            .map(|(i, (a, e))| {
                let q = coordinates
                    .get(a.coordinate)
                    .map(|c| c.quantity)
                    .unwrap_or(Quantity::Length);
                let n = a.count();
                if a.covers_turn(q) || n < 2 {
                    return [false; 2];
                }
                let closed = self.closed.get(i).copied().unwrap_or([false; 2]);
                [e[0] == 0 && !closed[0], e[1] + 1 == n && !closed[1]]
            })
            .collect()
    }

    /// Summary statistics in user units (mm, deg); `coordinates` are the machine's
    /// pose coordinates (the axes name them by index).
    pub fn summary_of(&self, coordinates: &[crate::mechanism::Coordinate]) -> WorkspaceSummary {
        let coord = |i: usize| coordinates.get(self.axes[i].coordinate);
        let q = |i: usize| coord(i).map(|c| c.quantity).unwrap_or(Quantity::Length);
        let mut cut = Vec::new();
        for (i, f) in self.open_faces(coordinates).iter().enumerate() {
            let name = coord(i)
                .map(|c| c.name.clone())
                .unwrap_or_else(|| format!("axis {}", i + 1));
            for (side, open) in ["min", "max"].iter().zip(f) {
                if *open {
                    cut.push(format!("{name} {side}"));
                }
            }
        }
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
        let mut s = self.summary(&|i, v| q(i).to_user(v), cell, &unit, name);
        s.cut = cut;
        s
    }

    /// Summary statistics; `to_user` converts a coordinate value of axis `i` to user
    /// units; `cell` is the measure of one cell in user units, `unit` its unit and
    /// `name` what it is (see [`WorkspaceSummary`]). [`WorkspaceSummary::cut`] is left
    /// empty ([`WorkspaceMap::summary_of`] names the open faces).
    pub fn summary(
        &self,
        to_user: &dyn Fn(usize, f64) -> f64,
        cell: f64,
        unit: &str,
        name: &str,
    ) -> WorkspaceSummary {
        let mut conds: Vec<f64> = Vec::new();
        let mut bbox = vec![[f64::INFINITY, f64::NEG_INFINITY]; self.axes.len()];
        // Counted by the names as they are (no string per point).
        let mut binding: std::collections::HashMap<&str, usize> = Default::default();
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
                *binding.entry(b.as_str()).or_default() += 1;
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
        let mut binding: Vec<(String, usize)> = binding
            .into_iter()
            .map(|(b, n)| (b.to_string(), n))
            .collect();
        binding.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        let outcomes = PointStatus::ALL
            .map(|st| (st, self.points.iter().filter(|p| p.status == st).count()))
            .to_vec();
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
            violated: self.violated.clone(),
            outcomes,
            cut: Vec::new(),
        }
    }
}
