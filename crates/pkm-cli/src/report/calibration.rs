//! Report section for machines that can be identified (strut machines): a simulated
//! identification campaign (seed 001) — the parameters identified from 50 random
//! states, validated on 20 held-out ones, and the conditioning of seed 001's one-strut
//! design beside it (`pkm::analysis::identification::calibration_study`).

use anyhow::Result;
use pkm::analysis::identification::{
    calibration_study, sized_experiment, CalibrationStudy, SizedExperiment,
};
use pkm::Machine;

use super::html::{esc, Html};
use super::ticks::tick;
use crate::commands::calibrate::plot_svgs;

pub fn section(h: &mut Html, machine: &Machine, _ctx: &super::Context) -> Result<()> {
    // The campaign `pkm simulate-measurements` simulates by default, fitted to the
    // machine.
    let sized = sized_experiment(machine)?;
    let st = calibration_study(machine, &sized.experiment, 20)?;
    let n = st.identification.names.len();
    h.h2_id(
        "calibration",
        &format!(
            "Calibration: identification of the {n} parameters{}",
            // Seed 001's name where its method (and one-strut design) applies.
            if st.one_strut_note.is_none() {
                " (seed 001)"
            } else {
                ""
            }
        ),
    );
    h.p(&campaign_text(machine, &sized, &st));
    h.table(
        &["quantity", "nominal model", "identified model"],
        &result_rows(&st),
    );
    let (residuals, singular) = plot_svgs(&st.identification)?;
    h.raw(&format!("<div class=\"views\">{residuals}{singular}</div>"));
    Ok(())
}

/// A number as short as it reads.
fn num(v: f64) -> String {
    tick(v, v)
}

/// The paragraph describing the simulated campaign and how it was fitted to the
/// machine.
fn campaign_text(machine: &Machine, sized: &SizedExperiment, st: &CalibrationStudy) -> String {
    let e = &sized.experiment;
    let n = st.identification.names.len();
    let held = if st.held.is_empty() {
        String::new()
    } else {
        format!(
            " Held at nominal (they trade exactly against others for this machine): {}.",
            esc(&st.held.join(", "))
        )
    };
    let fitted = fitted_text(sized);
    let unreached = unreached(st.holdout, st.nominal_failed, "nominal")
        + &unreached(st.holdout, st.identified_failed, "identified");
    // The rotation span where the machine turns its platform (not a translational
    // tripod's).
    let m = machine.mechanism();
    let turns = if m
        .driven()
        .iter()
        .any(|&k| m.coordinates()[k].quantity == pkm::Quantity::Angle)
    {
        format!(", ±{}°", num(e.rotation.to_degrees()))
    } else {
        String::new()
    };
    format!(
        "A simulated campaign (<code>pkm simulate-measurements</code> + <code>pkm \
             calibrate</code> do the same from files): a true machine whose joint coordinates \
             and zero lengths ({n} parameters) deviate uniformly by up to ±{} mm, {} \
             measured with {} µm noise per coordinate, strut readings with {} µm noise, {} \
             random states (±{} mm{turns}).{fitted} Levenberg-Marquardt on the actuator \
             equations with the measured poses; the pose error is the tool tip's, at {} \
             held-out states, when the control's readings are put through each model's \
             forward kinematics.{unreached}{held} docs/identification.md explains the method.",
        num(e.deviation),
        esc(&sized.fixture),
        num(1e3 * e.point_noise),
        num(1e3 * e.length_noise),
        st.experiment_states,
        num(e.translation),
        st.holdout
    )
}

/// How the default campaign was shrunk or scaled to the machine (empty when neither).
fn fitted_text(sized: &SizedExperiment) -> String {
    let e = &sized.experiment;
    let default = pkm::identify::simulate::Experiment::default();
    let z = &sized.sizing;
    let base = format!(
        "The default campaign (±{} mm deviations, ±{} mm, ±{}°, a {} mm fixture)",
        num(default.deviation),
        num(default.translation),
        num(default.rotation.to_degrees()),
        num(pkm::identify::simulate::DEFAULT_FIXTURE_SIZE),
    );
    if z.scale < 1.0 || z.rotation_scale < 1.0 {
        format!(
            " {base} is shrunk to fit this machine: fewer than a fifth of its random \
             poses are within the limits and within {} times the home pose's condition \
             number, against {:.0}% of these.",
            num(e.condition_ratio),
            100.0 * z.share
        )
    } else if z.scale > 1.0 {
        format!(
            " {base} is scaled ×{} to this machine's size: its struts average {:.0} mm at \
             home, over which ±{} mm would hardly turn them ({:.0}% of these random poses \
             are within the limits).",
            num(z.scale),
            z.home_length,
            num(default.translation),
            100.0 * z.share
        )
    } else {
        String::new()
    }
}

/// The table of the nominal and identified models: residuals, held-out errors,
/// conditioning.
fn result_rows(st: &CalibrationStudy) -> Vec<Vec<String>> {
    let id = &st.identification;
    let before = st.nominal;
    let after = st.identified;
    let worst_seven = match (
        &st.one_strut_condition,
        &st.one_strut_note,
        &st.one_strut_failure,
    ) {
        (Some(c), _, _) => format!("{c:.2e} (exactly determined)"),
        (None, Some(why), _) => format!("not applicable: {why}"),
        (None, None, why) => format!(
            "no solution: {}",
            why.as_deref().unwrap_or("the procedure gave none")
        ),
    };
    vec![
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
                id.condition, st.experiment_states, id.equations
            ),
        ],
        vec![
            "seed 001's one-strut design: worst per-strut condition".into(),
            "".into(),
            worst_seven,
        ],
    ]
}

/// Held-out states beyond a model's reach (`k` of `holdout`; none since the random
/// states keep within 4 times the home pose's condition number, but a machine homed
/// near a singularity can still give some): the sentence saying they were left out.
fn unreached(holdout: usize, k: usize, model: &str) -> String {
    if k == 0 {
        String::new()
    } else {
        format!(
            " {k} of the {holdout} held-out states' readings are beyond the {model} \
             model's reach (its forward kinematics finds no pose) and are left out of its \
             errors."
        )
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn unreached_states_are_counted_per_model() {
        assert_eq!(super::unreached(20, 0, "nominal"), "");
        assert_eq!(
            super::unreached(20, 2, "nominal"),
            " 2 of the 20 held-out states' readings are beyond the nominal model's reach \
             (its forward kinematics finds no pose) and are left out of its errors."
        );
    }
}
