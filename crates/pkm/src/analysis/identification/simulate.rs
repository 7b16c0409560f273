//! Simulated measurement campaigns on a loaded machine: [`simulate_measurements`].

use serde::Serialize;

use crate::error::{Error, Result};
use crate::identify::simulate::{simulate, Experiment};
use crate::identify::{self, Calibratable, Measurements};
use crate::machine::{Analysable, CalibratableVisitor, Machine};
/// Settings of [`simulate_measurements`]: the experiment and how many of its states
/// are held out for validation.
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::SimulateOptions;
/// use pkm::identify::simulate::Experiment;
/// let opt = SimulateOptions {
///     experiment: Experiment { states: 30, seed: 7, ..Default::default() },
///     holdout: 10,
///     comment: "30 random states, 10 held out".into(),
/// };
/// // 30 identification states and 10 more for validation; 5 um point noise by default.
/// assert_eq!(opt.experiment.states + opt.holdout, 40);
/// assert_eq!(opt.experiment.point_noise, 0.005);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SimulateOptions {
    /// The experiment (its `states` are the identification states).
    pub experiment: Experiment,
    /// Further states on the same true machine, for validation.
    pub holdout: usize,
    /// What the campaign was (heads the true machine file).
    pub comment: String,
}

/// A simulated campaign on a true machine drawn around the nominal one.
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::{simulate_measurements, sized_experiment, SimulateOptions};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-seed001.toml"
/// ))
/// .unwrap();
/// let mut experiment = sized_experiment(&machine).unwrap().experiment;
/// experiment.states = 20;
/// experiment.point_noise = 0.0; // noise-free, so the fit is exact
/// experiment.length_noise = 0.0;
/// let opt = SimulateOptions { experiment, holdout: 5, comment: "example".into() };
/// let campaign = simulate_measurements(&machine, None, &opt).unwrap();
/// // A state per reading set, every fixture point measured in each.
/// assert_eq!(campaign.measurements.states.len(), 20);
/// assert_eq!(campaign.validation.states.len(), 5);
/// assert_eq!(campaign.true_poses.len(), 25);
/// let points = campaign.measurements.fixture.len();
/// assert!(campaign.measurements.states.iter().all(|s| s.points.len() == points));
/// // Geometry then one zero reading per strut.
/// assert_eq!(campaign.names.len(), campaign.true_parameters.len());
/// assert_eq!(campaign.names.last().unwrap(), "zero(L6)");
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SimulatedCampaign {
    /// The identification states.
    pub measurements: Measurements,
    /// The held-out states (empty without holdout).
    pub validation: Measurements,
    /// Parameter names (geometry, then zero readings).
    pub names: Vec<String>,
    /// The true parameters.
    pub true_parameters: Vec<f64>,
    /// The true pose of every state (identification states first).
    pub true_poses: Vec<Vec<f64>>,
    /// The true machine as a machine file: the nominal file's text with the true
    /// joints and zero lengths (when the nominal file's text was given).
    pub true_machine_file: Option<String>,
}

/// Simulates a campaign on `machine` (`source`: the text of its machine file, to write
/// the true machine; `None` to skip that).
///
/// # Examples
///
/// The true machine file is the nominal one rewritten: it loads, and it differs from
/// the nominal machine by the simulated deviations (up to 1 mm).
///
/// ```
/// use pkm::analysis::identification::{simulate_measurements, sized_experiment, SimulateOptions};
/// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/machines/hexapod-seed001.toml");
/// let text = std::fs::read_to_string(path).unwrap();
/// let machine = pkm::Machine::from_toml_str(&text, path).unwrap();
/// let mut experiment = sized_experiment(&machine).unwrap().experiment;
/// experiment.states = 10;
/// let opt = SimulateOptions { experiment, holdout: 0, comment: "example".into() };
/// let campaign = simulate_measurements(&machine, Some(&text), &opt).unwrap();
/// assert_eq!(campaign.measurements.states.len(), 10);
/// assert!(campaign.validation.states.is_empty());
/// let true_file = campaign.true_machine_file.unwrap();
/// let truth = pkm::Machine::from_toml_str(&true_file, "true.toml").unwrap();
/// let home = machine.mechanism().home();
/// let (q0, q1) = (machine.mechanism().inverse(&home).unwrap(),
///                 truth.mechanism().inverse(&home).unwrap());
/// assert!(q0.iter().zip(&q1).any(|(a, b)| a != b));
/// assert!(q0.iter().zip(&q1).all(|(a, b)| (a - b).abs() < 10.0));
/// ```
pub fn simulate_measurements(
    machine: &Machine,
    source: Option<&str>,
    opt: &SimulateOptions,
) -> Result<SimulatedCampaign> {
    if opt.experiment.states == 0 {
        return Err(Error::InvalidInput {
            what: "states".into(),
            message: "expected at least one state".into(),
        });
    }
    let r = opt.experiment.condition_ratio;
    // NaN refused too; a bound below home's own would refuse the poses around it.
    if !(r >= 1.0) {
        return Err(Error::InvalidInput {
            what: "condition ratio".into(),
            message: format!("expected a number >= 1 (inf: no bound), found {r}"),
        });
    }
    machine.visit_calibratable(SimulateJob {
        machine,
        source,
        opt,
    })?
}

struct SimulateJob<'a> {
    machine: &'a Machine,
    source: Option<&'a str>,
    opt: &'a SimulateOptions,
}

impl CalibratableVisitor for SimulateJob<'_> {
    type Output = Result<SimulatedCampaign>;
    fn visit<M: Calibratable<A> + Analysable<6, A>, const A: usize>(self, h: &M) -> Self::Output {
        let zero = h.zero_readings()?;
        let mut e = self.opt.experiment.clone();
        e.states += self.opt.holdout;
        let s = simulate(h, &zero, &e)?;
        let (used, held) = s.measurements.states.split_at(self.opt.experiment.states);
        let part = |states: &[identify::State]| Measurements {
            fixture: s.measurements.fixture.clone(),
            states: states.to_vec(),
        };
        let mut theta = s.truth.geometry();
        theta.extend(s.true_zero.iter());
        let true_machine_file = match self.source {
            Some(text) => Some(s.truth.rewrite_file(
                text,
                &self.machine.source,
                Some(s.true_zero.as_slice()),
                &format!(
                    "The TRUE machine of a simulated experiment ({})",
                    self.opt.comment
                ),
            )?),
            None => None,
        };
        Ok(SimulatedCampaign {
            measurements: part(used),
            validation: part(held),
            names: identify::parameter_names(h),
            true_parameters: theta,
            true_poses: s.poses.iter().map(|x| x.as_slice().to_vec()).collect(),
            true_machine_file,
        })
    }
}
