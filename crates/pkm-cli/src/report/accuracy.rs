//! Report section for every machine: the error budget of its tolerances at home (the
//! machine file's, else +-10 um on lengths and +-10 urad on angles), a Monte Carlo of
//! them, and every toleranced parameter (`pkm::analysis::accuracy`).

use anyhow::Result;
use pkm::analysis::{accuracy, AccuracyOptions, AccuracyReport, ToleranceSource};
use pkm::Machine;

use super::html::{esc, Html};
use crate::report::plot::{bars_svg, histogram_svg};

/// Monte Carlo size in the report (a fraction of a second on two cores).
const SAMPLES: usize = 20_000;

pub fn section(h: &mut Html, machine: &Machine, ctx: &super::Context) -> Result<()> {
    h.h2_id("accuracy", "Accuracy from geometric tolerances");
    let r = accuracy(
        machine,
        &AccuracyOptions {
            pose: Some(ctx.pose.clone()),
            monte_carlo: Some(SAMPLES),
            ..Default::default()
        },
    )?;
    let source = match r.tolerance_source {
        ToleranceSource::MachineFile => {
            "the machine file's <code>[[tolerance]]</code> entries".to_string()
        }
        _ => "±10 µm on every length and ±10 µrad on every angle (uniform, illustrative: \
              <code>pkm errors MACHINE --joint-tolerance MM --length-tolerance MM \
              --link-tolerance MM --angle-tolerance DEG</code> or <code>--tolerances FILE</code> \
              takes yours)"
            .to_string(),
    };
    h.p(&format!(
        "At {}, {} of the machine's {} geometric parameters toleranced ({source}): the tool-point \
         error each causes with the control's nominal readings (first order, {} sensitivities), \
         their worst-case sum and root sum of squares, and a Monte Carlo of {SAMPLES} machines \
         with every parameter drawn from its distribution and the tool pose solved exactly. \
         docs/serial.md and docs/identification.md explain the model.",
        ctx.pose_label,
        r.tolerances.len(),
        r.parameters.len(),
        if r.analytic {
            "analytic"
        } else {
            "central-difference"
        },
    ));
    if let Some(mc) = &r.monte_carlo {
        budget_and_monte_carlo(h, &r.budget, mc)?;
    }
    parameter_table(h, &r);
    Ok(())
}

/// Every toleranced parameter with its tolerance and the error it causes, folded.
fn parameter_table(h: &mut Html, r: &AccuracyReport) {
    let rows: Vec<Vec<String>> = r
        .budget
        .items
        .iter()
        .map(|i| {
            let p = r.parameters.iter().find(|p| p.name == i.name);
            let unit = p.map(|p| p.quantity.unit()).unwrap_or("");
            let t = p
                .map(|p| p.quantity.to_user(i.tolerance))
                .unwrap_or(i.tolerance);
            vec![
                esc(&i.name),
                i.kind.as_str().into(),
                format!("{t:.4} {unit}"),
                format!("{:.3}", 1e3 * i.position),
                format!("{:.2e}", i.orientation.to_degrees()),
            ]
        })
        .collect();
    h.details(
        "Every toleranced parameter",
        &Html::table_string(
            &[
                "parameter",
                "kind",
                "tolerance",
                "tool-point error [µm]",
                "tool rotation [deg]",
            ],
            &rows,
        ),
    );
}

/// The budget and Monte Carlo figures of a tolerance study: the summary table, the
/// largest 20 budget lines as bars and the histogram of the tool-point error.
pub fn budget_and_monte_carlo(
    h: &mut Html,
    b: &pkm::accuracy::Budget,
    mc: &pkm::accuracy::MonteCarlo,
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
