//! What `pkm errors` prints: the report as JSON (`--json`, and `errors.json` in
//! `--out`) and as text for the terminal.

use pkm::analysis::clearance::ClearanceReport;
use pkm::analysis::AccuracyReport;
use serde_json::json;

use crate::out::{outln, Printed};
use crate::poses::{coords_json, coords_text};

/// The `errors.json` contract (user units: mm, deg for angular parameters).
pub(super) fn report_json(m: &dyn pkm::DynMechanism, r: &AccuracyReport) -> serde_json::Value {
    let unit = |p: &pkm::accuracy::Parameter| p.quantity.unit();
    let per_user = |p: &pkm::accuracy::Parameter| p.quantity.from_user(1.0);
    let sens: Vec<_> = r
        .parameters
        .iter()
        .zip(&r.sensitivities)
        .map(|(p, s)| {
            let k = per_user(p);
            let (d, w) = (s.position * k, (s.orientation * k).map(f64::to_degrees));
            json!({
                "parameter": p.name, "deviation": p.name, "kind": p.kind, "unit": unit(p),
                "position_mm_per_unit": [d.x, d.y, d.z],
                "orientation_deg_per_unit": [w.x, w.y, w.z],
            })
        })
        .collect();
    let tol: Vec<_> = r
        .tolerances
        .iter()
        .map(|t| {
            let p = &r.parameters[t.parameter];
            json!({"parameter": p.name, "kind": p.kind, "value": p.quantity.to_user(t.value), "unit": unit(p), "distribution": t.distribution})
        })
        .collect();
    let mut budget = serde_json::Map::new();
    for i in &r.budget.items {
        budget.insert(i.name.clone(), json!(i.position));
    }
    let (dp, dw) = (
        r.pose_error.position,
        r.pose_error.orientation.map(f64::to_degrees),
    );
    json!({
        "machine": r.machine,
        "type": r.kind,
        "pose": coords_json(m, &r.pose),
        "axes": m.coordinates().iter().zip(&r.pose).map(|(c, v)| json!({"name": c.name, "value": c.quantity.to_user(*v), "unit": c.quantity.unit()})).collect::<Vec<_>>(),
        "violations": r.violations,
        "deviations_given": r.deviations.len(),
        "position_error": [dp.x, dp.y, dp.z],
        "position_error_norm": dp.norm(),
        "orientation_error_deg": [dw.x, dw.y, dw.z],
        "sensitivities": sens,
        "analytic_sensitivities": r.analytic,
        "tolerance_source": r.tolerance_source,
        "tolerances": tol,
        "budget": budget,
        "budget_items": r.budget.items.iter().map(|i| json!({"parameter": i.name, "kind": i.kind, "position_mm": i.position, "orientation_deg": i.orientation.to_degrees()})).collect::<Vec<_>>(),
        "budget_worst_case": r.budget.worst_case,
        "budget_rss": r.budget.rss,
    })
}

pub(super) fn print_text(m: &dyn pkm::DynMechanism, r: &AccuracyReport) -> Printed {
    outln!("{} ({})", r.machine, r.kind)?;
    outln!("pose             {}", coords_text(m, &r.pose))?;
    for v in &r.violations {
        outln!("limit            VIOLATED at this pose: {v}")?;
    }
    if !r.deviations.is_empty() {
        print_pose_error(r)?;
    }
    print_budget(r)?;
    if let Some(mc) = &r.monte_carlo {
        outln!(
            "monte carlo      {} samples: mean {:.4}, std {:.4}, p95 {:.4}, p99 {:.4}, max {:.4} mm{}",
            mc.samples, mc.mean, mc.std, mc.p95, mc.p99, mc.max,
            if mc.failed > 0 { format!(" ({} machines without a forward solution left out)", mc.failed) } else { String::new() }
        )?;
    }
    if let Some(c) = &r.clearance {
        print_clearance(c)?;
    }
    if let Some(em) = &r.map {
        outln!(
            "error map        {} points, {} unreachable, largest RSS {:.4} mm",
            em.cells.len(),
            em.unreachable,
            em.max_rss
        )?;
    }
    Ok(())
}

/// The exact tool-pose error of the given deviations.
fn print_pose_error(r: &AccuracyReport) -> Printed {
    let (dp, dw) = (
        r.pose_error.position,
        r.pose_error.orientation.map(f64::to_degrees),
    );
    outln!(
        "position error   dx={:+.6} dy={:+.6} dz={:+.6} mm (|e| = {:.6} mm, {} deviations given)",
        dp.x,
        dp.y,
        dp.z,
        dp.norm(),
        r.deviations.len()
    )?;
    outln!(
        "orientation      rx={:+.3e} ry={:+.3e} rz={:+.3e} deg",
        dw.x,
        dw.y,
        dw.z
    )?;
    Ok(())
}

/// The parameters, the tolerances' source and the error budget with its largest items.
fn print_budget(r: &AccuracyReport) -> Printed {
    let source = r.tolerance_source.describe();
    outln!(
        "parameters       {} ({} sensitivities), {} toleranced, {source}",
        r.parameters.len(),
        if r.analytic {
            "analytic"
        } else {
            "central-difference"
        },
        r.tolerances.len()
    )?;
    outln!(
        "budget           worst case {:.4} mm, RSS {:.4} mm ({} toleranced deviations)",
        r.budget.worst_case,
        r.budget.rss,
        r.tolerances.len()
    )?;
    for i in r.budget.items.iter().take(5) {
        outln!("  largest        {:<28} {:.4} mm", i.name, i.position)?;
    }
    Ok(())
}

/// The clearance bounds at the pose, their Monte Carlo, over the surface and the path,
/// and the largest clearances within the tolerance.
fn print_clearance(c: &ClearanceReport) -> Printed {
    let b = &c.bounds;
    let d = b.direction;
    outln!(
        "clearance        {} joints, along ({:.4}, {:.4}, {:.4}): upper {:+.5} mm, lower {:+.5} mm ({}, {} solves{})",
        c.clearances.len(), d[0], d[1], d[2], b.upper, b.lower,
        match b.method { pkm::accuracy::clearance::ClearanceMethod::FirstOrder => "first-order states re-solved", _ => "enumeration" },
        b.solves,
        if b.refined { ", refined" } else { "" }
    )?;
    outln!(
        "  largest |e|    {:.5} mm (first order {:.5} mm)",
        b.deviation_3d.norm,
        b.deviation_3d.first_order
    )?;
    for j in b.contributions.iter().take(5) {
        outln!(
            "  largest        {:<28} {:.5} mm ({:.0} %)",
            j.joint,
            j.first_order,
            100.0 * j.share
        )?;
    }
    if let Some(mc) = &c.monte_carlo {
        outln!(
            "  monte carlo    {} states: along the direction {:+.5} .. {:+.5} mm (std {:.5}), largest |e| {:.5} mm",
            mc.samples, mc.min, mc.max, mc.std, mc.max_norm
        )?;
    }
    print_clearance_sweeps(c)?;
    if let (Some(t), Some(s)) = (c.tolerance, c.largest_clearance_scale) {
        print_clearance_tolerance(c, t, s)?;
    }
    Ok(())
}

/// The clearance bounds over the part surface and along the path.
fn print_clearance_sweeps(c: &ClearanceReport) -> Printed {
    if let Some(sf) = &c.surface {
        outln!(
            "  surface        hemisphere R = {} mm, {} heights ({} unreachable): largest {}",
            sf.hemisphere.radius,
            sf.points.len(),
            sf.unreachable,
            match (sf.worst, sf.worst_z) {
                (Some(w), Some(z)) => format!("{w:.5} mm at z = {z:.3} mm"),
                _ => "- (no reachable height)".into(),
            }
        )?;
    }
    if let Some(p) = &c.path {
        if let Some(w) = p.worst.and_then(|i| p.points.get(i)) {
            outln!(
                "  path           {} of {} samples bounded: largest {:.5} mm at t = {:.3} s{}",
                p.points.len(),
                p.samples,
                w.upper.max(-w.lower),
                w.sample.t,
                w.sample
                    .line
                    .map(|l| format!(" (line {l})"))
                    .unwrap_or_default()
            )?;
        }
    }
    Ok(())
}

/// The largest clearance within tolerance `t` (mm; `s` the scale of every clearance),
/// and per joint class with the others as given.
fn print_clearance_tolerance(c: &ClearanceReport, t: f64, s: f64) -> Printed {
    let over = match (&c.surface, &c.path) {
        (None, None) => " at the pose",
        (Some(_), None) => " over the surface",
        (None, Some(_)) => " along the path",
        (Some(_), Some(_)) => " over the surface and the path",
    };
    match c.largest_clearance_mm {
        Some(mm) => outln!("  tolerance      {t} mm: largest clearance{over} {mm:.5} mm")?,
        None => outln!("  tolerance      {t} mm: every clearance times {s:.4}{over}")?,
    }
    for k in &c.largest_per_class {
        let what = match (k.largest_mm, k.largest_scale) {
            (Some(mm), _) => format!("largest {mm:.5} mm"),
            (None, Some(s)) => format!("clearances times {s:.4}"),
            (None, None) if k.others_alone_mm >= t => format!(
                "none: the other joints alone give {:.5} mm",
                k.others_alone_mm
            ),
            (None, None) => "any: these joints move nothing along it".to_string(),
        };
        outln!(
            "  class {:<9}{} joints, the others as given: {what}",
            k.class,
            k.joints.len()
        )?;
    }
    Ok(())
}
