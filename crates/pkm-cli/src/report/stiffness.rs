//! The report's stiffness section: the smallest stiffness of the tool tip over the
//! workspace map's reachable points (slices through the report's pose), and the
//! drives' forces per kilonewton on the tool at that pose.

use anyhow::Result;
use pkm::analysis::statics::{statics, StaticsOptions};
use pkm::{Machine, PoseSpace, Quantity};

use super::html::{esc, Html};
use super::Context;
use crate::commands::workspace::run_map;
use crate::commands::workspace::stiffness::stiffness_outputs;

/// Whether the machine has the data: X, Y, Z, A, B, C and a stiffness on every drive.
pub fn shown(machine: &Machine) -> bool {
    let m = machine.mechanism();
    m.pose_space() == PoseSpace::Spatial && m.actuators().iter().all(|a| a.stiffness.is_some())
}

pub fn section(h: &mut Html, machine: &Machine, ctx: &Context) -> Result<()> {
    let (wm, _) = run_map(
        machine,
        &ctx.pose,
        ctx.bounds.as_deref(),
        ctx.step,
        &[],
        false,
    )?;
    let o = stiffness_outputs(machine, &wm)?;
    h.h2_id("stiffness", "Stiffness");
    let s = &o.summary;
    let num = |p: &str| s.pointer(p).and_then(|v| v.as_f64()).unwrap_or(f64::NAN);
    let at: Vec<String> = s
        .pointer("/weakest/at")
        .and_then(|v| v.as_object())
        .into_iter()
        .flatten()
        .map(|(k, v)| format!("{k} = {:.1}", v.as_f64().unwrap_or(f64::NAN)))
        .collect();
    h.p(&format!(
        "The smallest stiffness of the tool tip against a force, over the workspace map's \
         {} reachable points (the drives' axial stiffness from the machine file; joints and \
         links rigid; the tool free to turn as the machine lets it): weakest {:.1} N/um at {}, \
         median {:.1} N/um, largest {:.1} N/um (pkm workspace MACHINE --stiffness).",
        s["points"],
        num("/weakest/stiffness_n_per_um"),
        esc(&at.join(", ")),
        num("/median_n_per_um"),
        num("/largest_n_per_um"),
    ));
    let svgs: String = o.slices.into_iter().map(|(_, s)| s).collect();
    h.raw(&format!("<div class=\"views\">{svgs}</div>"));
    drive_table(h, machine, ctx)
}

/// Each drive's force holding 1 kN on the tool along X, Y and Z at the report's pose.
fn drive_table(h: &mut Html, machine: &Machine, ctx: &Context) -> Result<()> {
    let m = machine.mechanism();
    let mut columns = Vec::new();
    for k in 0..3 {
        let mut wrench = [0.0; 6];
        wrench[k] = 1000.0;
        let pose = ctx.pose.clone();
        columns.push(statics(machine, &StaticsOptions { pose, wrench })?.actuator_forces);
    }
    let rows: Vec<Vec<String>> = m
        .actuators()
        .iter()
        .enumerate()
        .map(|(i, a)| {
            let unit = match a.quantity {
                Quantity::Angle => ("N m", 1e-3),
                Quantity::Length => ("N", 1.0),
            };
            let mut row = vec![esc(&a.name)];
            row.extend(
                columns
                    .iter()
                    .map(|c| format!("{:.1} {}", c[i] * unit.1, unit.0)),
            );
            row
        })
        .collect();
    h.p(&format!(
        "Drive forces holding 1 kN on the tool at {} (positive: the drive pushes its \
         coordinate to grow; pkm statics MACHINE --wrench ...):",
        esc(&ctx.pose_label)
    ));
    h.table(&["drive", "Fx = 1 kN", "Fy = 1 kN", "Fz = 1 kN"], &rows);
    Ok(())
}
