//! Report section for a machine whose file gives joint clearances (seed 002): the
//! bounds of the tool-point error at home along the tool axis, the joint states that
//! give them, each joint's share, and a Monte Carlo of joint states
//! (`pkm::analysis::clearance`).

use anyhow::Result;
use pkm::analysis::clearance::{clearance, ClearanceReport, ClearanceRequest};
use pkm::Machine;

use super::html::{esc, Html};
use crate::report::plot::{bars_svg, histogram_svg};

/// Monte Carlo size in the report.
const SAMPLES: usize = 10_000;

pub fn section(h: &mut Html, machine: &Machine, _ctx: &super::Context) -> Result<()> {
    h.h2_id("clearance", "Joint clearances");
    let r = clearance(
        machine,
        None,
        &ClearanceRequest {
            monte_carlo: Some(SAMPLES),
            ..Default::default()
        },
    )?;
    let b = &r.bounds;
    let d = b.direction;
    h.p(&format!(
        "At home, every passive joint given a clearance in the machine file moved inside it \
         (a ball of radius c/2; a disc normal to its axis plus the tilt atan(c/b) through its \
         lever), the mechanism solved again at the same actuator values. Bounds of the \
         tool-point error along the tool axis ({:.4}, {:.4}, {:.4}): the first-order \
         maximising joint states solved exactly{}. docs/seed-002.md explains the model; \
         <code>pkm errors MACHINE --clearance C --surface hemisphere:R --tolerance T</code> \
         sweeps a part surface and answers the largest clearance.",
        d[0],
        d[1],
        d[2],
        if b.refined {
            ", refined where first order was not enough"
        } else {
            ""
        }
    ));
    bounds_table(h, &r);
    let views = plots(&r)?;
    h.raw(&format!("<div class=\"views\">{views}</div>"));
    worst_states(h, &r);
    Ok(())
}

/// The bounds, first order and exact, and the Monte Carlo's range (µm).
fn bounds_table(h: &mut Html, r: &ClearanceReport) {
    let b = &r.bounds;
    let mc = r.monte_carlo.as_ref();
    h.table(
        &[
            "upper [µm]",
            "lower [µm]",
            "first order [µm]",
            "largest |e| [µm]",
            "MC min [µm]",
            "MC max [µm]",
            "MC std [µm]",
        ],
        &[vec![
            format!("{:+.3}", 1e3 * b.upper),
            format!("{:+.3}", 1e3 * b.lower),
            format!("±{:.3}", 1e3 * b.first_order_upper),
            format!("{:.3}", 1e3 * b.deviation_3d.norm),
            mc.map_or("-".into(), |m| format!("{:+.3}", 1e3 * m.min)),
            mc.map_or("-".into(), |m| format!("{:+.3}", 1e3 * m.max)),
            mc.map_or("-".into(), |m| format!("{:.3}", 1e3 * m.std)),
        ]],
    );
}

/// Each joint's share of the bound, and the Monte Carlo's histogram: SVG.
fn plots(r: &ClearanceReport) -> Result<String> {
    let top: Vec<(String, f64)> = r
        .bounds
        .contributions
        .iter()
        .take(20)
        .map(|c| (c.joint.clone(), 1e3 * c.first_order))
        .collect();
    let bars = bars_svg(
        "each joint's share of the bound (first order)",
        "contribution [µm]",
        &top,
        640,
    )?;
    let hist = match &r.monte_carlo {
        Some(m) => {
            let bins: Vec<(f64, usize)> = m.histogram.iter().map(|(x, c)| (1e3 * x, *c)).collect();
            histogram_svg(
                &format!(
                    "Monte Carlo, {} joint states: error along the axis",
                    m.samples
                ),
                "error [µm]",
                &bins,
                (560, 400),
            )?
        }
        None => String::new(),
    };
    Ok(format!("{bars}{hist}"))
}

/// The joint states that give the upper bound, folded.
fn worst_states(h: &mut Html, r: &ClearanceReport) {
    let rows: Vec<Vec<String>> = r
        .clearances
        .iter()
        .zip(&r.bounds.worst_joint_states.upper)
        .map(|(c, s)| {
            vec![
                esc(&c.joint),
                esc(&s.body),
                format!("{:?}", c.kind).to_lowercase(),
                format!("{:.4}", c.diametral),
                format!(
                    "{:+.5}, {:+.5}, {:+.5}",
                    s.displacement[0], s.displacement[1], s.displacement[2]
                ),
            ]
        })
        .collect();
    h.details(
        "The joint states that give the upper bound",
        &Html::table_string(
            &[
                "joint",
                "body",
                "type",
                "clearance [mm]",
                "displacement of the centre [mm]",
            ],
            &rows,
        ),
    );
}
