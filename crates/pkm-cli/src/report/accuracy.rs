//! Report section for serial machines with tolerances (seed 003): the error budget at
//! mid travel, a Monte Carlo of the tolerances, and the largest sensitivities.

use anyhow::Result;
use pkm::serial::tolerance::{budget, monte_carlo};
use pkm::serial::SerialModel;

use super::html::{esc, Html};
use crate::report::plot::{bars_svg, histogram_svg};

/// Monte Carlo size in the report (a fraction of a second on two cores).
const SAMPLES: usize = 200_000;

pub fn section(h: &mut Html, s: &SerialModel, mech: &dyn pkm::DynMechanism) -> Result<()> {
    let m = s.mechanism.machine();
    h.h2_id("accuracy", "Accuracy: primary deviations (seed 003)");
    if s.tolerances.is_empty() {
        h.p("The machine file gives no <code>[[tolerance]]</code> entries: no budget.");
        return Ok(());
    }
    // Mid travel of every axis.
    let x: Vec<f64> = mech
        .actuators()
        .iter()
        .map(|a| 0.5 * (a.range.min + a.range.max))
        .collect();
    let (qt, qw) = s.mechanism.split_joints(&x);
    let at: Vec<String> = mech
        .actuators()
        .iter()
        .zip(&x)
        .map(|(a, v)| {
            format!(
                "{} = {:.3} {}",
                esc(&a.name),
                a.quantity.to_user(*v),
                a.quantity.unit()
            )
        })
        .collect();
    let b = budget(m, qt, qw, &s.tolerances)?;
    let mc = monte_carlo(m, qt, qw, &s.tolerances, SAMPLES, 1)?;
    h.p(&format!(
        "At mid travel ({}): the tool-point error each of the {} toleranced deviations causes at \
         its tolerance (first order, in the workpiece frame), their worst-case sum and root sum \
         of squares, and a Monte Carlo of {} machines with every deviation drawn from its \
         distribution (uniform in ±t, or normal with t = 3σ; exact poses). docs/serial.md \
         explains the model and its limits (an angle between aligned axes has no first-order \
         effect when perturbed alone).",
        at.join(", "),
        s.tolerances.len(),
        SAMPLES
    ));
    budget_and_monte_carlo(h, &b, &mc)?;
    let rows: Vec<Vec<String>> = b
        .items
        .iter()
        .map(|i| {
            vec![
                esc(&i.name),
                format!("{:.4}", i.tolerance),
                format!("{:.3}", 1e3 * i.position),
                format!("{:.2e}", i.orientation),
            ]
        })
        .collect();
    h.details(
        "Every toleranced deviation (tolerance in mm or rad)",
        &Html::table_string(
            &[
                "deviation",
                "tolerance",
                "tool-point error [µm]",
                "tool rotation [rad]",
            ],
            &rows,
        ),
    );
    Ok(())
}

/// The budget and Monte Carlo figures of a tolerance study: the summary table, the
/// largest 20 budget lines as bars and the histogram of the tool-point error.
pub fn budget_and_monte_carlo(
    h: &mut Html,
    b: &pkm::serial::tolerance::Budget,
    mc: &pkm::serial::tolerance::MonteCarlo,
) -> Result<()> {
    h.table(
        &[
            "worst case [µm]",
            "RSS [µm]",
            "MC mean [µm]",
            "MC std [µm]",
            "MC p95 [µm]",
            "MC p99 [µm]",
            "MC max [µm]",
        ],
        &[vec![
            format!("{:.2}", 1e3 * b.worst_case),
            format!("{:.2}", 1e3 * b.rss),
            format!("{:.2}", 1e3 * mc.mean),
            format!("{:.2}", 1e3 * mc.std),
            format!("{:.2}", 1e3 * mc.p95),
            format!("{:.2}", 1e3 * mc.p99),
            format!("{:.2}", 1e3 * mc.max),
        ]],
    );
    let top: Vec<(String, f64)> = b
        .items
        .iter()
        .take(20)
        .map(|i| (i.name.clone(), 1e3 * i.position))
        .collect();
    let bars = bars_svg("error budget (largest 20)", "contribution [µm]", &top, 640)?;
    let bins: Vec<(f64, usize)> = mc.histogram.iter().map(|(x, c)| (1e3 * x, *c)).collect();
    let hist = histogram_svg(
        "Monte Carlo: tool-point error",
        "|error| [µm]",
        &bins,
        (560, 400),
    )?;
    h.raw(&format!("<div class=\"views\">{bars}{hist}</div>"));
    Ok(())
}
