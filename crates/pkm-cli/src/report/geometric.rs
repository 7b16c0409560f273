//! Report section for strut machines: the tool-point error that tolerances on the
//! joint centres and zero lengths cause at home (`pkm::accuracy`).

use anyhow::Result;
use nalgebra::SVector;
use pkm::accuracy::{budget, monte_carlo, GeometricTolerances};
use pkm::identify::Identifiable;
use pkm::serial::tolerance::Distribution;

use super::html::Html;

/// Tolerance of every joint coordinate and zero length in the report (mm).
const TOLERANCE: f64 = 0.01;
/// Monte Carlo size.
const SAMPLES: usize = 20_000;

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
         Monte Carlo of {SAMPLES} machines solved exactly. docs/identification.md explains \
         the model; the same parameters are what calibration identifies.",
        1000.0 * TOLERANCE
    ));
    super::accuracy::budget_and_monte_carlo(h, &b, &mc)?;
    Ok(())
}
