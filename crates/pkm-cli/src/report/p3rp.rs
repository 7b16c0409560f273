//! Report section for P3RP heads and the hybrid machine built on one: seed 004's
//! numbers reproduced, its figs. 4-7 redrawn from the model.

use anyhow::Result;
use pkm::analysis::seed004::reproduction;
use pkm::workspace::GridAxis;
use pkm::Machine;

use super::html::{esc, Html};
use crate::commands::atlas::{
    atlas_outputs, forward_axes, forward_outputs, run_atlas, run_forward,
};

fn num(v: &[f64]) -> String {
    match v {
        [] => "-".into(),
        [x] => format!("{x:.2}"),
        [a, b] => format!("[{a:.2}, {b:.2}]"),
        _ => format!("{v:?}"),
    }
}

/// Capacities of seed 004's fig. 6 (internal units): z' = 150 mm/s and theta' = 1
/// rad/s (the cruise of its fig. 7 move), z'' = 1 g, theta'' = 30 rad/s^2.
const FIG6_VELOCITY: [f64; 2] = [150.0, 1.0];
const FIG6_ACCELERATION: [f64; 2] = [9806.65, 30.0];

pub fn section(h: &mut Html, machine: &Machine, _ctx: &super::Context) -> Result<()> {
    let geometry = machine.p3rp_head()?;
    let g = &geometry.geometry();
    // The head as a machine of its own (for the hybrid machine, its head at home).
    let hm = machine.p3rp_head_machine()?;
    h.h2_id("seed004", "P3RP head: seed 004 reproduced");
    h.p(&format!(
        "The head's structural parameters: l1 = |AB| = {:.2} mm, l2 = |BC| = {:.2} mm, \
         e = {:.2} mm, delta = {:.3}° (psi = theta + delta), tool length {:.1} mm, \
         assembly branch {:?}. Seed 004 lost its parameter tables; the example file's \
         values were fitted to the numbers it reports (see docs/seed-004.md).",
        g.l1,
        g.l2,
        g.e,
        g.delta.to_degrees(),
        g.tool_length,
        g.branch
    ));
    reproduction_table(h, machine)?;
    atlas_figures(h, &hm)?;
    forward_figure(h, &hm)?;
    move_figure(h, &hm)
}

/// Seed 004's numbers beside pkm's.
fn reproduction_table(h: &mut Html, machine: &Machine) -> Result<()> {
    let rows: Vec<Vec<String>> = reproduction(machine)?
        .iter()
        .map(|r| {
            vec![
                esc(&r.quantity),
                num(&r.paper),
                num(&r.pkm),
                r.unit.into(),
                if r.paper.is_empty() {
                    "-".into()
                } else {
                    format!("{:.2} %", 100.0 * r.deviation)
                },
                esc(r.note.as_deref().unwrap_or("")),
            ]
        })
        .collect();
    h.table(
        &["quantity", "paper", "pkm", "unit", "deviation", "note"],
        &rows,
    );
    Ok(())
}

/// Fig. 4 and 6: the atlas of the head `hm` over (z, theta).
fn atlas_figures(h: &mut Html, hm: &Machine) -> Result<()> {
    let head = hm.mechanism();
    let axes = vec![
        GridAxis {
            coordinate: 0,
            min: 180.0,
            max: 540.0,
            step: 6.0,
        },
        GridAxis {
            coordinate: 1,
            min: (-5f64).to_radians(),
            max: 95f64.to_radians(),
            step: 2f64.to_radians(),
        },
    ];
    let base = head.home();
    let at = run_atlas(hm, &base, &axes, &FIG6_VELOCITY, &FIG6_ACCELERATION)?;
    let coords_user = |k: usize| {
        let n1 = axes[1].count();
        vec![axes[0].value(k / n1), axes[1].value(k % n1).to_degrees()]
    };
    let out = atlas_outputs(head, &axes, &base, &at, &coords_user)?;
    let pick = |key: &str| -> String {
        out.plots
            .iter()
            .filter(|(n, _)| n.contains(key))
            .map(|(_, s)| s.as_str())
            .collect()
    };
    h.p(
        "<b>Inverse workspace (fig. 4)</b>: slider positions over the platform pose \
         (z, theta); grey where a limit binds (slider strokes, hinge A deflection \
         0-90°, rod angle, transmission angle).",
    );
    h.raw(&format!(
        "<div class=\"views\">{}{}</div>",
        pick("u-position"),
        pick("v-position")
    ));
    h.p(&format!(
        "<b>Performance atlas (fig. 6)</b>: the slider velocity and acceleration needed, per \
         slider in its worst direction, for |z'| ≤ {} mm/s, |theta'| ≤ {} rad/s, |z''| ≤ 1 g and \
         |theta''| ≤ {} rad/s² (the velocities are the cruise of the fig. 7 move; the paper's \
         velocity figures are lost). Slider D needs exactly the z capacity everywhere.",
        FIG6_VELOCITY[0], FIG6_VELOCITY[1], FIG6_ACCELERATION[1]
    ));
    h.raw(&format!(
        "<div class=\"views\">{}{}</div>",
        pick("v-velocity"),
        pick("v-acceleration")
    ));
    Ok(())
}

/// Fig. 5: the forward workspace of the head `hm` over the slider strokes.
fn forward_figure(h: &mut Html, hm: &Machine) -> Result<()> {
    let head = hm.mechanism();
    let base = head.home();
    let faxes = forward_axes(head, Some(8.0))?;
    let fm = run_forward(hm, &faxes, &base)?;
    let q0 = head.inverse(&head.home())?;
    let fo = forward_outputs(head, &faxes, &q0, &fm)?;
    let svgs: String = fo.plots.iter().map(|(_, s)| s.as_str()).collect();
    h.p(&format!(
        "<b>Forward workspace (fig. 5)</b>: the pose the head takes over the slider strokes \
         (closed-form forward solution on the machine's branch), {} of {} slider pairs within \
         every limit; grey: no assembly or a limit binds.",
        fo.summary["reachable"], fo.summary["points"]
    ));
    h.raw(&format!("<div class=\"views\">{svgs}</div>"));
    Ok(())
}

/// Fig. 7: the paper's move of the head `hm`.
fn move_figure(h: &mut Html, hm: &Machine) -> Result<()> {
    use crate::commands::motion::plots;
    use pkm::analysis::motion::{run_motion, MotionSource, NoSink};
    use pkm::motion::program::{FeedOptions, ProfileKind};
    let sim = run_motion(
        hm,
        MotionSource::PointToPoint {
            from: vec![200.0, 0.0],
            to: vec![335.0, 0.9],
            duration: Some(1.0),
            accel_time: Some(0.1),
        },
        &FeedOptions {
            profile: ProfileKind::Trapezoid,
            ..Default::default()
        },
        pkm::motion::Sampling::Rate(1000.0),
        &mut NoSink,
    )?;
    let (a, b) = plots(hm.mechanism(), &sim, "fig. 7 move")?;
    h.p(
        "<b>The fig. 7 move</b>: (z, theta) from (200 mm, 0) to (335 mm, 0.9 rad) in 1 s, \
         trapezoidal velocity with 0.1 s ramps, 1 kHz; the same as \
         <code>pkm motion MACHINE --from 200,0 --to 335,51.566 --duration 1 --profile \
         trapezoid --accel-time 0.1 --out DIR</code> on the head's file. Slider D follows \
         z; slider V carries the nonlinear part.",
    );
    h.raw(&format!("<div class=\"views\">{a}{b}</div>"));
    Ok(())
}
