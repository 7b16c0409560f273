//! `pkm workspace --stiffness`: the stiffness map over the reachable points of the grid
//! (`pkm::analysis::statics::stiffness_map`): `stiffness.csv`, slice maps and the
//! summary's weakest point.

use anyhow::Result;
use pkm::workspace::WorkspaceMap;
use pkm::Machine;
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::path::Path;

use super::{slice_pairs, slice_plot, Mapped, WorkspaceArgs};
use crate::io::write_atomic;
use crate::report::heatmap::Scale;

/// A stiffness map's outputs: the table, the slice maps (file name, SVG), the summary.
pub struct StiffnessOutputs {
    /// `stiffness.csv`: grid coordinates (user units), smallest stiffness of the tool
    /// tip against a force (N/um), its direction.
    pub csv: String,
    /// `stiffness-<axes>.svg` slices through the map's pose.
    pub slices: Vec<(String, String)>,
    /// The summary entry: the weakest point, the strongest, the median.
    pub summary: Value,
}

/// The stiffness map over the reachable points of `wm` and its outputs.
pub fn stiffness_outputs(machine: &Machine, wm: &WorkspaceMap) -> Result<StiffnessOutputs> {
    let m = machine.mechanism();
    let reach: Vec<usize> = (0..wm.points.len())
        .filter(|&k| wm.points[k].reachable)
        .collect();
    let poses: Vec<f64> = reach.iter().flat_map(|&k| wm.coords(k)).collect();
    let map = pkm::analysis::statics::stiffness_map(machine, &poses, false)?;
    let mut by_point: Vec<Option<f64>> = vec![None; wm.points.len()];
    for (i, &k) in reach.iter().enumerate() {
        by_point[k] = Some(map.smallest_n_per_um[i]).filter(|v| v.is_finite());
    }
    let coord = |i: usize| {
        let c = &m.coordinates()[wm.axes[i].coordinate];
        (c.name.clone(), c.quantity)
    };
    let user = |k: usize| super::extra::user_coords(m, wm, k);
    let mut csv = String::new();
    let names: Vec<String> = (0..wm.axes.len()).map(|i| coord(i).0).collect();
    writeln!(
        csv,
        "{},stiffness_n_per_um,direction_x,direction_y,direction_z",
        names.join(",")
    )?;
    for (i, &k) in reach.iter().enumerate() {
        let cells: Vec<String> = user(k).iter().map(|v| format!("{v:.6}")).collect();
        let d = map.direction[i];
        writeln!(
            csv,
            "{},{:.6},{:.6},{:.6},{:.6}",
            cells.join(","),
            map.smallest_n_per_um[i],
            d[0],
            d[1],
            d[2]
        )?;
    }
    let mut slices = Vec::new();
    for (ha, va) in slice_pairs(wm.axes.len()) {
        let what = format!("smallest stiffness, {}{} slice", coord(ha).0, coord(va).0);
        let svg = slice_plot(
            &wm.axes,
            &wm.base,
            &coord,
            (ha, va),
            &what,
            Scale::Linear("N/um"),
            &|k| by_point[k],
        )?;
        let name = format!("stiffness-{}{}.svg", coord(ha).0, coord(va).0).to_lowercase();
        slices.push((name, svg));
    }
    Ok(StiffnessOutputs {
        csv,
        slices,
        summary: summary(&map, &reach, &user, &names),
    })
}

/// Writes [`stiffness_outputs`] to `--out`; the summary entry.
pub(super) fn write_stiffness(
    a: &WorkspaceArgs,
    machine: &Machine,
    mapped: &Mapped,
    inputs: &[&Path],
) -> Result<Value> {
    let o = stiffness_outputs(machine, mapped.wm)?;
    write_atomic(&a.out.join("stiffness.csv"), o.csv.as_bytes(), inputs)?;
    for (name, svg) in &o.slices {
        write_atomic(&a.out.join(name), svg.as_bytes(), inputs)?;
    }
    Ok(o.summary)
}

fn summary(
    map: &pkm::analysis::statics::StiffnessMap,
    reach: &[usize],
    user: &dyn Fn(usize) -> Vec<f64>,
    names: &[String],
) -> Value {
    let mut finite: Vec<f64> = map
        .smallest_n_per_um
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    finite.sort_by(f64::total_cmp);
    let at = |i: usize| -> Value {
        names
            .iter()
            .zip(user(reach[i]))
            .map(|(n, v)| (n.clone(), json!(v)))
            .collect::<serde_json::Map<_, _>>()
            .into()
    };
    let weakest = map.weakest.map(|i| {
        json!({
            "stiffness_n_per_um": map.smallest_n_per_um[i],
            "direction": map.direction[i],
            "at": at(i),
        })
    });
    json!({
        "points": reach.len(),
        "failed": map.failed,
        "weakest": weakest,
        "median_n_per_um": finite.get(finite.len() / 2),
        "largest_n_per_um": finite.last(),
        "measure": "smallest stiffness of the tool tip against a force (N/um), unloaded, the tool free to turn as the machine lets it, from the drives' `stiffness`",
    })
}
