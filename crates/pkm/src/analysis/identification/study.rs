//! The report's calibration study: identification on a simulated campaign, validated
//! on held-out states, beside the conditioning of seed 001's one-strut design.

use nalgebra::SVector;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::identify::simulate::{simulate, Design, Experiment};
use crate::identify::{self, Calibratable, Identification, Measurements};
use crate::machine::{Analysable, CalibratableVisitor, Machine};

/// A simulated calibration study (the report's): identification on a simulated
/// campaign, validated on held-out states of the same true machine, beside the
/// conditioning of seed 001's one-strut design.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibrationStudy {
    /// The campaign.
    pub experiment_states: usize,
    /// Held-out states.
    pub holdout: usize,
    /// Parameters held (the machine's trading pairs, [`Calibratable::must_hold`]).
    pub held: Vec<String>,
    /// The identification.
    pub identification: Identification,
    /// Tool-pose errors of the nominal model at the held-out states.
    pub nominal: identify::simulate::PoseErrors,
    /// Held-out states whose readings the nominal model cannot reach (left out of
    /// `nominal`).
    pub nominal_failed: usize,
    /// Tool-pose errors of the identified model at the held-out states.
    pub identified: identify::simulate::PoseErrors,
    /// Held-out states whose readings the identified model cannot reach.
    pub identified_failed: usize,
    /// Worst per-actuator condition number of seed 001's one-strut design with
    /// [`identify::hexapod::SEED_PROCEDURE_STATES`] noise-free states (`None` when it
    /// does not apply or does not solve).
    pub one_strut_condition: Option<f64>,
    /// Why the machine has no such design (seed 001's procedure does not apply to it),
    /// `None` where it has one.
    pub one_strut_note: Option<String>,
    /// Why the design, where the machine has one, gives no solution (the procedure's
    /// error: a singular strut system, no convergence, or a state the simulated
    /// machine could not reach); `None` where it solves or does not apply.
    pub one_strut_failure: Option<String>,
}

/// Runs [`CalibrationStudy`] with experiment `e` and `holdout` held-out states (seed
/// `e.seed + 1`).
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::{calibration_study, sized_experiment};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-seed001.toml"
/// ))
/// .unwrap();
/// let mut e = sized_experiment(&machine).unwrap().experiment;
/// e.states = 20;
/// let study = calibration_study(&machine, &e, 5).unwrap();
/// assert_eq!((study.experiment_states, study.holdout), (20, 5));
/// // The identified model predicts the held-out poses better than the nominal one.
/// assert!(study.identified.position_rms < study.nominal.position_rms / 10.0);
/// assert_eq!(study.identified_failed, 0);
/// // A hexapod has seed 001's one-strut design.
/// assert!(study.one_strut_note.is_none());
/// ```
pub fn calibration_study(
    machine: &Machine,
    e: &Experiment,
    holdout: usize,
) -> Result<CalibrationStudy> {
    machine.visit_calibratable(StudyJob(e, holdout))?
}

/// [`calibration_study`] on a concrete machine: experiment and held-out states.
struct StudyJob<'a>(&'a Experiment, usize);

impl CalibratableVisitor for StudyJob<'_> {
    type Output = Result<CalibrationStudy>;
    fn visit<M: Calibratable<A> + Analysable<6, A>, const A: usize>(self, h: &M) -> Self::Output {
        let (e, holdout) = (self.0, self.1);
        let zero = h.zero_readings()?;
        let s = simulate(h, &zero, e)?;
        let names = identify::parameter_names(h);
        let held = h.must_hold();
        let id = identify::identify(
            h,
            &zero,
            &s.measurements,
            &identify::Options {
                fixed: held.clone(),
                ..Default::default()
            },
        )?;
        let test = identify::simulate::simulate_on(
            s.truth,
            s.true_zero,
            &Experiment {
                states: holdout,
                seed: e.seed + 1,
                ..e.clone()
            },
        )?;
        let readings = test.measurements.readings();
        let (nominal, nominal_failed) =
            identify::simulate::pose_errors(h, &zero, &readings, &test.poses)?;
        let ng = id.values.len() - A;
        let model = h.with_geometry(&id.values[..ng])?;
        let z = SVector::<f64, A>::from_column_slice(&id.values[ng..]);
        let (identified, identified_failed) =
            identify::simulate::pose_errors(&model, &z, &readings, &test.poses)?;
        let (one_strut_condition, one_strut_note, one_strut_failure) =
            one_strut_design(h, &zero, e);
        Ok(CalibrationStudy {
            experiment_states: e.states,
            holdout,
            held: held.iter().map(|&k| names[k].clone()).collect(),
            identification: id,
            nominal,
            nominal_failed,
            identified,
            identified_failed,
            one_strut_condition,
            one_strut_note,
            one_strut_failure,
        })
    }
}

/// Whether seed 001's procedure applies at all (a machine without it says why
/// whatever the states), then its design's conditioning: the worst condition number,
/// why it does not apply, or why it gives no solution.
fn one_strut_design<M: Calibratable<A> + Analysable<6, A>, const A: usize>(
    h: &M,
    zero: &SVector<f64, A>,
    e: &Experiment,
) -> (Option<f64>, Option<String>, Option<String>) {
    match h.seed_procedure(zero, &Measurements::default()) {
        Err(Error::Unsupported { reason, .. }) => (None, Some(reason), None),
        _ => {
            let seven = simulate(
                h,
                zero,
                &Experiment {
                    // The procedure's own count: seven parameters per
                    // strut (A + 1 states coincide with it only for six
                    // struts, and a tripod's four cannot determine seven).
                    states: identify::hexapod::SEED_PROCEDURE_STATES,
                    design: Design::OneActuator,
                    point_noise: 0.0,
                    length_noise: 0.0,
                    ..e.clone()
                },
            );
            match seven.and_then(|s| h.seed_procedure(zero, &s.measurements)) {
                Ok(sp) => (
                    Some(sp.conditions.iter().copied().fold(0.0, f64::max)),
                    None,
                    None,
                ),
                Err(err) => (None, None, Some(err.to_string())),
            }
        }
    }
}
