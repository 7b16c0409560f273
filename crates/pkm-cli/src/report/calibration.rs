//! Report section for hexapods: a simulated identification campaign (seed 001) — the
//! 42 parameters identified from 50 random states, validated on 20 held-out ones, and
//! the conditioning of seed 001's seven-state design beside it.

use anyhow::Result;
use nalgebra::Vector6;
use pkm::hexapod::Hexapod;
use pkm::identify::hexapod::seed_procedure;
use pkm::identify::simulate::{pose_errors, simulate, simulate_on, triangle, Design, Experiment};
use pkm::identify::{identify, Identifiable, Options};

use super::html::Html;
use crate::commands::calibrate::plot_svgs;

pub fn section(h: &mut Html, hex: &Hexapod) -> Result<()> {
    h.h2_id(
        "calibration",
        "Calibration: identification of the 42 parameters (seed 001)",
    );
    let zero = hex.zero_readings()?;
    let e = Experiment {
        deviation: 1.0,
        point_noise: 0.005,
        length_noise: 0.001,
        states: 50,
        design: Design::Random,
        translation: 100.0,
        rotation: 10f64.to_radians(),
        step: 40.0,
        fixture: triangle(200.0, 0.0),
        seed: 1,
    };
    let s = simulate(hex, &zero, &e)?;
    let id = identify(hex, &zero, &s.measurements, &Options::default())?;
    let held = simulate_on(
        s.truth.clone(),
        s.true_zero,
        &Experiment {
            states: 20,
            seed: 2,
            ..e.clone()
        },
    )?;
    let readings = held.measurements.readings();
    let before = pose_errors(hex, &zero, &readings, &held.poses)?;
    let model = hex.with_geometry(&id.values[..36])?;
    let z = Vector6::from_column_slice(&id.values[36..]);
    let after = pose_errors(&model, &z, &readings, &held.poses)?;
    // Seed 001's design: seven states, one strut more changed per state.
    let seven = simulate(
        hex,
        &zero,
        &Experiment {
            states: 7,
            design: Design::OneActuator,
            point_noise: 0.0,
            length_noise: 0.0,
            ..e.clone()
        },
    )?;
    let sp = seed_procedure(hex, &zero, &seven.measurements)?;
    let worst_seven = sp.conditions.iter().copied().fold(0.0, f64::max);
    h.p(
        "A simulated campaign (<code>pkm simulate-measurements</code> + <code>pkm \
         calibrate</code> do the same from files): a true machine whose 36 joint coordinates \
         and 6 zero lengths deviate uniformly by up to ±1 mm, a triangular fixture of \
         circumradius 200 mm measured with 5 µm noise per coordinate, strut readings with \
         1 µm noise, 50 random states (±100 mm, ±10°). Levenberg-Marquardt on the actuator \
         equations with the measured poses; the pose error is the tool tip's, at 20 held-out \
         states, when the control's readings are put through each model's forward \
         kinematics. docs/identification.md explains the method.",
    );
    h.table(
        &["quantity", "nominal model", "identified model"],
        &[
            vec![
                "residual RMS [µm]".into(),
                format!("{:.1}", 1e3 * id.rms_before),
                format!("{:.2}", 1e3 * id.rms_after),
            ],
            vec![
                "held-out position error max / RMS [µm]".into(),
                format!(
                    "{:.0} / {:.0}",
                    1e3 * before.position_max,
                    1e3 * before.position_rms
                ),
                format!(
                    "{:.1} / {:.1}",
                    1e3 * after.position_max,
                    1e3 * after.position_rms
                ),
            ],
            vec![
                "held-out orientation error max [µrad]".into(),
                format!("{:.0}", 1e6 * before.orientation_max),
                format!("{:.1}", 1e6 * after.orientation_max),
            ],
            vec![
                "condition number (scaled Jacobian)".into(),
                "".into(),
                format!(
                    "{:.0} ({} states, {} equations)",
                    id.condition, e.states, id.equations
                ),
            ],
            vec![
                "seed 001's seven-state design: worst per-strut condition".into(),
                "".into(),
                format!("{worst_seven:.2e} (exactly determined)"),
            ],
        ],
    );
    let (residuals, singular) = plot_svgs(&id)?;
    h.raw(&format!("<div class=\"views\">{residuals}{singular}</div>"));
    Ok(())
}
