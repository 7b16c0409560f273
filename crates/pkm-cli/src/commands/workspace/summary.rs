//! `pkm workspace`'s summary: `summary.json` and the text printed.

use anyhow::Result;
use pkm::DynMechanism;
use serde_json::json;

use super::Mapped;
use crate::out::{outln, Printed};

/// `summary.json` of a map (without the atlas and forward entries).
pub(super) fn summary_json(
    m: &dyn DynMechanism,
    mapped: &Mapped,
    tilt: Option<f64>,
) -> Result<serde_json::Value> {
    let s = mapped.summary;
    let counts = |v: &[(String, usize)]| {
        let mut o = serde_json::Map::new();
        for (k, n) in v {
            o.insert(k.clone(), json!(n));
        }
        o
    };
    let (binding, violated) = (counts(&s.binding), counts(&s.violated));
    let mut outcomes = serde_json::Map::new();
    for (k, n) in &s.outcomes {
        outcomes.insert(
            serde_json::to_value(k)?.as_str().unwrap_or("").into(),
            json!(n),
        );
    }
    let axes_json: Vec<_> = mapped
        .wm
        .axes
        .iter()
        .map(|x| {
            let c = &m.coordinates()[x.coordinate];
            json!({"name": c.name, "unit": c.quantity.unit(), "min": c.quantity.to_user(x.min), "max": c.quantity.to_user(x.max), "step": c.quantity.to_user(x.step), "count": x.count()})
        })
        .collect();
    Ok(json!({
        "machine": m.name(),
        "type": m.kind(),
        "axes": axes_json,
        "base_pose": crate::poses::coords_json(m, mapped.base),
        "tilt_set_deg": tilt,
        "points": s.points,
        "reachable": s.reachable,
        "reachable_fraction": s.reachable_fraction,
        "volume_mm3": s.volume_mm3,
        "measure": s.measure,
        "measure_unit": s.measure_unit,
        "measure_name": s.measure_name,
        "bounding_box": s.bounding_box,
        "condition": s.condition,
        "grid_bounds": mapped.grid_bounds,
        "outcomes": outcomes,
        "binding": binding,
        "violated": violated,
        "cut": s.cut,
        "seconds": mapped.seconds,
    }))
}

/// The map as text (without the closing `wrote DIR`).
pub(super) fn print_text(m: &dyn DynMechanism, mapped: &Mapped) -> Printed {
    let s = mapped.summary;
    outln!(
        "{} ({}): {} points in {:.3} s",
        m.name(),
        m.kind(),
        s.points,
        mapped.seconds
    )?;
    outln!(
        "reachable  {} ({:.1} %), {} {:.4e} {}",
        s.reachable,
        100.0 * s.reachable_fraction,
        s.measure_name,
        s.measure,
        s.measure_unit
    )?;
    for (i, b) in s.bounding_box.iter().enumerate() {
        let c = &m.coordinates()[mapped.wm.axes[i].coordinate];
        outln!(
            "range      {} [{:.3}, {:.3}] {}",
            c.name,
            b[0],
            b[1],
            c.quantity.unit()
        )?;
    }
    outln!(
        "condition  min {:.3}, median {:.3}, p95 {:.3}, max {:.3}",
        s.condition.min,
        s.condition.median,
        s.condition.p95,
        s.condition.max
    )?;
    outln!("grid       over {}", mapped.grid_bounds)?;
    print_outcomes(s)?;
    Ok(())
}

/// The outcome of every point, the limits that bind, and whether the region is cut.
fn print_outcomes(s: &pkm::workspace::WorkspaceSummary) -> Printed {
    use pkm::workspace::PointStatus as St;
    outln!(
        "outcomes   {} reachable, {} beyond a limit, {} without solution, {} solver failures, {} singular, {} in separate regions",
        s.outcome(St::Reachable),
        s.outcome(St::Limits),
        s.outcome(St::NoSolution),
        s.outcome(St::SolverFailed),
        s.outcome(St::Singular),
        s.outcome(St::Separate)
    )?;
    for (k, n) in s.binding.iter().take(8) {
        outln!("first      {n:>8} x {k}")?;
    }
    for (k, n) in s.violated.iter().take(8) {
        outln!("violated   {n:>8} x {k}")?;
    }
    if !s.cut.is_empty() {
        outln!(
            "warning    reachable points lie on the grid's faces ({}): the reachable region may go on beyond the grid; widen --bounds",
            s.cut.join(", ")
        )?;
    }
    Ok(())
}
