//! `pkm workspace`'s optional outputs over the map's grid: the performance atlas
//! (`--atlas-velocity`, `--atlas-acceleration`) and the forward workspace (`--forward`).

use anyhow::Result;
use pkm::workspace::WorkspaceMap;
use pkm::{DynMechanism, Machine};
use serde_json::json;
use std::path::Path;

use super::super::atlas;
use super::{Mapped, WorkspaceArgs};
use crate::io::write_atomic;
use crate::poses::parse_list;

/// Writes the atlas and forward files asked for; their entries of `summary.json`.
pub(super) fn write_extras(
    a: &WorkspaceArgs,
    machine: &Machine,
    mapped: &Mapped,
    inputs: &[&Path],
) -> Result<serde_json::Map<String, serde_json::Value>> {
    let mut extra = serde_json::Map::new();
    if a.atlas_velocity.is_some() || a.atlas_acceleration.is_some() {
        extra.insert("atlas".into(), write_atlas(a, machine, mapped, inputs)?);
    }
    if a.stiffness {
        extra.insert(
            "stiffness".into(),
            super::stiffness::write_stiffness(a, machine, mapped, inputs)?,
        );
    }
    if a.forward {
        extra.insert(
            "forward".into(),
            write_forward(a, machine, mapped.base, inputs)?,
        );
    }
    Ok(extra)
}

/// The performance atlas: `atlas.csv` and its maps; its summary entry.
fn write_atlas(
    a: &WorkspaceArgs,
    machine: &Machine,
    mapped: &Mapped,
    inputs: &[&Path],
) -> Result<serde_json::Value> {
    let m = machine.mechanism();
    let (wm, base) = (mapped.wm, mapped.base);
    let list = |o: &Option<String>, flag: &str| -> Result<Option<Vec<f64>>> {
        o.as_ref().map(|s| parse_list(s, flag)).transpose()
    };
    let v = list(&a.atlas_velocity, "--atlas-velocity")?;
    let acc = list(&a.atlas_acceleration, "--atlas-acceleration")?;
    let at = atlas::run_atlas(
        machine,
        base,
        &wm.axes,
        &atlas::capacity(m, v.as_deref(), "--atlas-velocity")?,
        &atlas::capacity(m, acc.as_deref(), "--atlas-acceleration")?,
    )?;
    let coords_user = |k: usize| user_coords(m, wm, k);
    let o = atlas::atlas_outputs(m, &wm.axes, base, &at, &coords_user)?;
    write_all(&a.out, &o, "atlas.csv", inputs)?;
    Ok(json!({"velocity": v, "acceleration": acc, "actuators": o.summary}))
}

/// The forward workspace: `forward.csv` and its maps; its summary entry.
fn write_forward(
    a: &WorkspaceArgs,
    machine: &Machine,
    base: &[f64],
    inputs: &[&Path],
) -> Result<serde_json::Value> {
    let m = machine.mechanism();
    let faxes = atlas::forward_axes(m, a.forward_step)?;
    let fm = atlas::run_forward(machine, &faxes, base)?;
    let base_q = m.inverse(base)?;
    let o = atlas::forward_outputs(m, &faxes, &base_q, &fm)?;
    write_all(&a.out, &o, "forward.csv", inputs)?;
    Ok(o.summary)
}

/// Writes the table of `o` to `out/csv` and its plots beside it.
fn write_all(out: &Path, o: &atlas::Outputs, csv: &str, inputs: &[&Path]) -> Result<()> {
    write_atomic(&out.join(csv), o.csv.as_bytes(), inputs)?;
    for (name, svg) in &o.plots {
        write_atomic(&out.join(name), svg.as_bytes(), inputs)?;
    }
    Ok(())
}

/// The map's axis coordinates of point `k`, user units.
pub(super) fn user_coords(m: &dyn DynMechanism, wm: &WorkspaceMap, k: usize) -> Vec<f64> {
    let x = wm.coords(k);
    wm.axes
        .iter()
        .map(|ax| {
            m.coordinates()[ax.coordinate]
                .quantity
                .to_user(x[ax.coordinate])
        })
        .collect()
}
