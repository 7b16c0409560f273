//! Report section for strut machines: the tool-point error that tolerances on the
//! joint centres and zero lengths cause at home (`pkm::accuracy`).

use anyhow::Result;
use nalgebra::SVector;
use pkm::accuracy::{budget, monte_carlo, GeometricTolerances};
use pkm::identify::Identifiable;
use pkm::serial::tolerance::Distribution;

use super::html::Html;
use crate::report::plot::{bars_svg, histogram_svg};

/// Tolerance of every joint coordinate and zero length in the report (mm).
const TOLERANCE: f64 = 0.01;
/// Monte Carlo size.
const SAMPLES: usize = 20_000;
/// Its size as printed.
const SAMPLES_TEXT: &str = "20 000";

pub fn section<M: Identifiable<6, A>, const A: usize>(
    h: &mut Html,
    m: &M,
    zero: &SVector<f64, A>,
) -> Result<()> {
    h.h2_id("geometric", "Accuracy from geometric tolerances");
    let x = m.home();
    let tol = GeometricTolerances {
        joint: TOLERANCE,
        zero: TOLERANCE,
        distribution: Distribution::Uniform,
    };
    let b = budget(m, &x, &tol)?;
    let mc = monte_carlo(m, &x, zero, &tol, SAMPLES, 1)?;
    h.p(&format!(
        "At home, every joint-centre coordinate and every strut's zero length within \
         ±{} µm (uniform, illustrative: <code>pkm errors MACHINE --joint-tolerance MM \
         --length-tolerance MM</code> takes yours): the tool-point error each causes with the \
         control's nominal readings (first order), their worst-case sum and RSS, and a \
         Monte Carlo of {SAMPLES_TEXT} machines solved exactly. docs/identification.md explains \
         the model; the same parameters are what calibration identifies.",
        1000.0 * TOLERANCE
    ));
    h.table(
        &[
            "worst case [µm]",
            "RSS [µm]",
            "MC mean [µm]",
            "MC p95 [µm]",
            "MC p99 [µm]",
            "MC max [µm]",
        ],
        &[vec![
            format!("{:.2}", 1e3 * b.worst_case),
            format!("{:.2}", 1e3 * b.rss),
            format!("{:.2}", 1e3 * mc.mean),
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
