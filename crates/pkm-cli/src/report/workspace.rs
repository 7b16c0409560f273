//! The report's workspace section.

use anyhow::Result;
use pkm::workspace::{PointStatus as St, WorkspaceMap, WorkspaceSummary};
use pkm::{DynMechanism, Machine};

use super::html::{esc, Html};
use super::Context;
use crate::commands::workspace::{run_map, slices, summarise};

/// Workspace at the report pose's orientation, over the machine's whole reach or the
/// given bounds: summary, slices with the condition number, the outcomes and the
/// limits that bind.
pub fn section(h: &mut Html, machine: &Machine, ctx: &Context) -> Result<()> {
    let m = machine.mechanism();
    let (wm, grid_bounds) = run_map(
        machine,
        &ctx.pose,
        ctx.bounds.as_deref(),
        ctx.step,
        &[],
        false,
    )?;
    let s = summarise(m, &wm);
    // The 3D view's cloud: reachable tool positions of a map over X, Y, Z.
    if m.pose_space() != pkm::PoseSpace::Own && wm.axes.iter().map(|a| a.coordinate).eq(0..3) {
        ctx.scene.borrow_mut().cloud = wm
            .points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.reachable)
            .map(|(k, p)| {
                let x = wm.coords(k);
                ([x[0], x[1], x[2]], p.condition)
            })
            .collect();
    }
    h.h2_id("workspace", "Workspace and conditioning");
    let names: Vec<String> = wm
        .axes
        .iter()
        .map(|a| m.coordinates()[a.coordinate].name.clone())
        .collect();
    h.p(&grid_text(m, &wm, &s, &names, &grid_bounds, ctx));
    if !s.cut.is_empty() {
        h.p(&format!(
            "<span class=\"bad\">Reachable points lie on the grid's faces ({}): the region \
             may go on beyond the map (pkm workspace MACHINE --bounds ... maps it).</span>",
            esc(&s.cut.join(", "))
        ));
    }
    summary_table(h, &s, &names);
    let svgs: String = slices(m, &wm)?.into_iter().map(|(_, s)| s).collect();
    h.raw(&format!("<div class=\"views\">{svgs}</div>"));
    h.p("Grey cells: not reachable. Every point falls in one category:");
    outcome_table(h, &s);
    limit_table(h, &s);
    Ok(())
}

/// The paragraph saying what the grid is and what reachable means.
fn grid_text(
    m: &dyn DynMechanism,
    wm: &WorkspaceMap,
    s: &WorkspaceSummary,
    names: &[String],
    grid_bounds: &str,
    ctx: &Context,
) -> String {
    let span: Vec<String> = wm
        .axes
        .iter()
        .zip(names)
        .map(|(a, n)| {
            let q = m.coordinates()[a.coordinate].quantity;
            format!(
                "{n} [{:.1}, {:.1}] {}",
                q.to_user(a.min),
                q.to_user(a.max),
                q.unit()
            )
        })
        .collect();
    format!(
        "A grid of {} points over {} ({}), bounds from {}; the other coordinates at {}. \
         A point is reachable when inverse kinematics has a solution within every limit, \
         the Jacobian is regular, and the region of the pose reaches it through such \
         points. The condition number is that of the Jacobian's driven \
         columns, rotations scaled by a characteristic length of {:.1} mm (1 = isotropic).",
        s.points,
        names.join(", "),
        span.join(", "),
        esc(grid_bounds),
        ctx.pose_label,
        m.characteristic_length()
    )
}

/// Reachable points, measure, reachable range and conditioning.
fn summary_table(h: &mut Html, s: &WorkspaceSummary, names: &[String]) {
    let bbox: Vec<String> = s
        .bounding_box
        .iter()
        .zip(names)
        .map(|(b, n)| format!("{n} [{:.1}, {:.1}]", b[0], b[1]))
        .collect();
    let c = &s.condition;
    h.table(
        &[
            "reachable",
            "measure",
            "reachable range",
            "condition min / median / p95 / max",
        ],
        &[vec![
            format!("{} ({:.1} %)", s.reachable, 100.0 * s.reachable_fraction),
            format!("{} {:.4e} {}", s.measure_name, s.measure, s.measure_unit),
            bbox.join("<br>"),
            format!(
                "{:.3} / {:.3} / {:.3} / {:.3}",
                c.min, c.median, c.p95, c.max
            ),
        ]],
    );
}

/// The points of each outcome.
fn outcome_table(h: &mut Html, s: &WorkspaceSummary) {
    h.table(
        &["outcome", "points"],
        &[
            ("reachable", St::Reachable),
            ("a solution beyond at least one limit", St::Limits),
            ("no solution (proven: out of the mechanism's reach)", St::NoSolution),
            (
                "solver failed from every start and from the reachable neighbours' solutions (not proven unreachable)",
                St::SolverFailed,
            ),
            ("singular", St::Singular),
            (
                "within every limit but cut off from the region of the pose by points that are not (another assembly mode, or reached only by turning the tool on the way)",
                St::Separate,
            ),
        ]
        .map(|(k, st)| vec![k.to_string(), s.outcome(st).to_string()]),
    );
}

/// The points violating each limit, and where it is the first violated.
fn limit_table(h: &mut Html, s: &WorkspaceSummary) {
    let first: std::collections::HashMap<&str, usize> =
        s.binding.iter().map(|(k, n)| (k.as_str(), *n)).collect();
    let rows: Vec<Vec<String>> = s
        .violated
        .iter()
        .map(|(k, n)| {
            vec![
                esc(k),
                n.to_string(),
                first.get(k.as_str()).copied().unwrap_or(0).to_string(),
            ]
        })
        .collect();
    h.p(
        "Points per limit: every limit a point violates is counted (a point beyond two \
         limits counts for both); the last column counts the points where it is \
         the first violated limit in the machine's check order.",
    );
    h.table(&["limit", "points violating it", "first violated"], &rows);
}
