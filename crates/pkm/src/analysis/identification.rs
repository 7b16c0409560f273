//! Identification on a loaded machine (seed 001): simulate a measurement campaign,
//! identify the geometric parameters from measurements, validate on held-out states,
//! and the identified machine as a machine file. Machines that cannot be identified
//! answer [`crate::Error::Unsupported`] (see [`crate::machine::Analysis`]).

use nalgebra::SVector;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::identify::hexapod::SeedProcedure;
use crate::identify::simulate::{sized, Design, Experiment, Sizing, DEFAULT_FIXTURE_SIZE};
use crate::identify::{self, Calibratable, Fixture, Identification, Measurements, PointErrors};
use crate::machine::{Analysable, CalibratableVisitor, Machine};

mod simulate;
mod study;

pub use simulate::{simulate_measurements, SimulateOptions, SimulatedCampaign};
pub use study::{calibration_study, CalibrationStudy};

/// The fixture a simulated campaign on `machine` measures, of size `size` (mm):
/// [`Calibratable::fixture`] (a triangle on a strut machine's platform, points on a
/// pentapod's tool axis).
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::fixture;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-seed001.toml"
/// ))
/// .unwrap();
/// // Seed 001's triangle: three points 100 mm from the platform centre.
/// let f = fixture(&machine, 100.0).unwrap();
/// assert_eq!(f.points.len(), 3);
/// assert!(f.points.iter().all(|p| (p.norm() - 100.0).abs() < 1e-9));
/// assert!(fixture(&machine, -1.0).is_err());
/// ```
pub fn fixture(machine: &Machine, size: f64) -> Result<Fixture> {
    if !(size > 0.0 && size <= crate::machine::MAX_MAGNITUDE) {
        return Err(Error::InvalidInput {
            what: "fixture size".into(),
            message: format!("expected a size in (0, 1e6] mm, found {size}"),
        });
    }
    struct Job(f64);
    impl CalibratableVisitor for Job {
        type Output = Fixture;
        fn visit<M: Calibratable<A> + Analysable<6, A>, const A: usize>(self, h: &M) -> Fixture {
            h.fixture(self.0)
        }
    }
    machine.visit_calibratable(Job(size))
}

/// [`Experiment::default`] fitted to `machine` ([`sized_experiment`]), with its fixture.
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::sized_experiment;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-seed001.toml"
/// ))
/// .unwrap();
/// let s = sized_experiment(&machine).unwrap();
/// // The experiment's fixture is the one described, of the size given.
/// assert_eq!(s.experiment.fixture.len(), 3);
/// assert!(s.experiment.fixture.iter().all(|p| (p.norm() - s.fixture_size).abs() < 1e-9));
/// assert!(s.fixture.contains("triangle"));
/// assert!(s.sizing.share > 0.0 && s.sizing.share <= 1.0);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SizedExperiment {
    /// The experiment (fixture points included).
    #[serde(skip)]
    pub experiment: Experiment,
    /// The fixture's size (mm; see [`fixture`]).
    pub fixture_size: f64,
    /// What the fixture is.
    pub fixture: String,
    /// How the default was fitted.
    pub sizing: Sizing,
}

/// The campaign `pkm simulate-measurements` and the report simulate on `machine` by
/// default: [`Experiment::default`] (deviations +-1 mm, +-100 mm and +-10 deg around
/// home, 40 mm steps, a 200 mm fixture) where at least a fifth of its random poses
/// are within the machine's limits and 4 times its home pose's condition number and
/// its struts average at most 1 m at home; on a smaller or tighter machine the spans
/// shrink by halves, on one with struts of metres they grow by doubling
/// ([`crate::identify::simulate::sized`]), the fixture, step and deviations with the
/// translation span, so that a 15 mm micro-hexapod and a 6 m one get campaigns of their
/// own size instead of a failed search or an unidentifiable one.
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::sized_experiment;
/// use pkm::identify::simulate::Experiment;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-seed001.toml"
/// ))
/// .unwrap();
/// let s = sized_experiment(&machine).unwrap();
/// // The spans scale by powers of two; the fixture and the deviations with them.
/// let base = Experiment::default();
/// assert_eq!(s.sizing.scale.log2().fract(), 0.0);
/// assert!((s.experiment.translation - base.translation * s.sizing.scale).abs() < 1e-9);
/// assert!((s.experiment.deviation - base.deviation * s.sizing.scale).abs() < 1e-9);
/// assert!(s.sizing.home_length > 0.0); // mean strut length at home (mm)
/// ```
pub fn sized_experiment(machine: &Machine) -> Result<SizedExperiment> {
    struct Job;
    impl CalibratableVisitor for Job {
        type Output = Result<SizedExperiment>;
        fn visit<M: Calibratable<A> + Analysable<6, A>, const A: usize>(
            self,
            h: &M,
        ) -> Self::Output {
            let base = Experiment::default();
            let sizing = sized(h, &base);
            let s = sizing.scale;
            let size = DEFAULT_FIXTURE_SIZE * s;
            let f = h.fixture(size);
            Ok(SizedExperiment {
                experiment: base.scaled(s, sizing.rotation_scale, f.points),
                fixture_size: size,
                fixture: f.description,
                sizing,
            })
        }
    }
    machine.visit_calibratable(Job)?
}

/// Reads a measurement CSV for `machine` (its actuators name the reading columns).
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::{parse_measurements, write_measurements};
/// use pkm::identify::{Measurements, State};
/// use nalgebra::Vector3;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-seed001.toml"
/// ))
/// .unwrap();
/// let m = Measurements {
///     fixture: vec![Vector3::new(0.0, 200.0, 0.0)],
///     states: vec![State {
///         readings: vec![0.5, -0.25, 0.0, 1.0, 0.0, 2.0],
///         points: vec![Vector3::new(1.0, 2.0, 3.0)],
///     }],
/// };
/// let text = write_measurements(&machine, &m, "one state");
/// assert_eq!(parse_measurements(&machine, &text, "m.csv").unwrap(), m);
/// // Readings for six struts: five are refused with the file and line.
/// let bad = text.replace("0.5,-0.25,0,1,0,2", "0.5,-0.25,0,1,0");
/// assert!(bad != text && parse_measurements(&machine, &bad, "m.csv").is_err());
/// ```
pub fn parse_measurements(machine: &Machine, text: &str, file: &str) -> Result<Measurements> {
    identify::csv::parse(text, file, machine.mechanism().actuators())
}

/// Writes measurements as the CSV [`parse_measurements`] reads.
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::{
///     parse_measurements, simulate_measurements, sized_experiment, write_measurements,
///     SimulateOptions,
/// };
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-seed001.toml"
/// ))
/// .unwrap();
/// let mut experiment = sized_experiment(&machine).unwrap().experiment;
/// experiment.states = 5;
/// let opt = SimulateOptions { experiment, holdout: 0, comment: String::new() };
/// let m = simulate_measurements(&machine, None, &opt).unwrap().measurements;
/// let text = write_measurements(&machine, &m, "five simulated states");
/// assert!(text.starts_with('#')); // the comment heads the file
/// let back = parse_measurements(&machine, &text, "m.csv").unwrap();
/// assert_eq!(back.states.len(), 5);
/// for (a, b) in back.states.iter().zip(&m.states) {
///     assert!(a.readings.iter().zip(&b.readings).all(|(x, y)| (x - y).abs() < 1e-9));
///     assert!(a.points.iter().zip(&b.points).all(|(x, y)| (x - y).norm() < 1e-9));
/// }
/// ```
pub fn write_measurements(machine: &Machine, m: &Measurements, comment: &str) -> String {
    identify::csv::write(m, machine.mechanism().actuators(), comment)
}

/// Settings of [`calibrate`].
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::CalibrateOptions;
/// use pkm::identify::MeasurementModel;
/// // By default: pose equations, nothing held, Levenberg-Marquardt's solution.
/// let opt = CalibrateOptions::default();
/// assert_eq!(opt.model, MeasurementModel::Pose);
/// assert!(opt.fix.is_empty() && !opt.seed_procedure);
/// // Hold every coordinate of base joint A1 and platform joint C's height.
/// let opt = CalibrateOptions { fix: vec!["A1.*".into(), "C.z".into()], ..opt };
/// assert_eq!(opt.fix.len(), 2);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrateOptions {
    /// Measurement equations.
    pub model: identify::MeasurementModel,
    /// Parameters held at their nominal values: names, `*` matching any run of
    /// characters (`A1.z`, `C.*`).
    pub fix: Vec<String>,
    /// Take seed 001's procedure's solution (first seven states) for the identified
    /// machine instead of Levenberg-Marquardt's.
    pub seed_procedure: bool,
}

impl Default for CalibrateOptions {
    fn default() -> Self {
        CalibrateOptions {
            model: identify::MeasurementModel::Pose,
            fix: Vec::new(),
            seed_procedure: false,
        }
    }
}

/// Point errors of the nominal and the identified machine on held-out states.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Validation {
    /// Held-out states.
    pub states: usize,
    /// The nominal machine's errors.
    pub nominal: PointErrors,
    /// The identified machine's errors.
    pub identified: PointErrors,
}

/// What [`calibrate`] found.
///
/// # Examples
///
/// See [`calibrate`]; the parts of the result:
///
/// ```
/// use pkm::analysis::identification::{
///     calibrate, simulate_measurements, sized_experiment, CalibrateOptions, SimulateOptions,
/// };
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
/// let c = calibrate(&machine, &campaign.measurements, None, &CalibrateOptions::default())
///     .unwrap();
/// // One value per parameter (geometry, then zero readings), as the simulation's truth.
/// assert_eq!(c.values.len(), campaign.true_parameters.len());
/// assert_eq!(c.identification.names, campaign.names);
/// assert!(c.seed_procedure.is_none() && c.validation.is_none());
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Calibration {
    /// Levenberg-Marquardt's identification (residuals, standard errors,
    /// identifiability).
    pub identification: Identification,
    /// The parameter values of the identified machine (LM's, or the seed procedure's).
    pub values: Vec<f64>,
    /// Seed 001's procedure, when asked for.
    pub seed_procedure: Option<SeedProcedure>,
    /// Validation on held-out states, when given.
    pub validation: Option<Validation>,
}

/// Whether `name` matches `pattern` (`*` matches any run of characters).
fn glob(pattern: &str, name: &str) -> bool {
    let parts: Vec<&str> = pattern.split('*').collect();
    if parts.len() == 1 {
        return pattern == name;
    }
    let mut rest = name;
    for (i, p) in parts.iter().enumerate() {
        if i == 0 {
            let Some(r) = rest.strip_prefix(p) else {
                return false;
            };
            rest = r;
        } else if i == parts.len() - 1 {
            return rest.ends_with(p);
        } else {
            let Some(k) = rest.find(p) else { return false };
            rest = &rest[k + p.len()..];
        }
    }
    true
}

/// Identifies `machine`'s parameters from `measurements`, validates on `validation`
/// when given.
///
/// # Examples
///
/// A noise-free simulated campaign: the identified machine fits the measurements and
/// predicts the held-out states, which the nominal machine misses by its deviations.
///
/// ```
/// use pkm::analysis::identification::{
///     calibrate, simulate_measurements, sized_experiment, CalibrateOptions, SimulateOptions,
/// };
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
/// let c = calibrate(
///     &machine,
///     &campaign.measurements,
///     Some(&campaign.validation),
///     &CalibrateOptions::default(),
/// )
/// .unwrap();
/// let id = &c.identification;
/// assert!(id.rms_before > 1e-2 && id.rms_after < 1e-6);
/// let v = c.validation.unwrap();
/// assert_eq!(v.states, 5);
/// assert!(v.identified.rms < 1e-5 && v.nominal.rms > 1e-2);
/// ```
pub fn calibrate(
    machine: &Machine,
    measurements: &Measurements,
    validation: Option<&Measurements>,
    opt: &CalibrateOptions,
) -> Result<Calibration> {
    machine.visit_calibratable(CalibrateJob {
        meas: measurements,
        validation,
        opt,
    })?
}

/// The identified machine of `c` as a machine file: `source` (the nominal machine's
/// file text) with the identified joints and zero lengths, headed by `comment`.
///
/// # Examples
///
/// The identified machine, written and read back, fits the measurements it was
/// identified from.
///
/// ```
/// use pkm::analysis::identification::{
///     calibrate, identified_machine_file, simulate_measurements, sized_experiment,
///     CalibrateOptions, SimulateOptions,
/// };
/// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/machines/hexapod-seed001.toml");
/// let text = std::fs::read_to_string(path).unwrap();
/// let machine = pkm::Machine::from_toml_str(&text, path).unwrap();
/// let mut experiment = sized_experiment(&machine).unwrap().experiment;
/// experiment.states = 20;
/// experiment.point_noise = 0.0; // noise-free, so the fit is exact
/// experiment.length_noise = 0.0;
/// let opt = SimulateOptions { experiment, holdout: 5, comment: "example".into() };
/// let campaign = simulate_measurements(&machine, None, &opt).unwrap();
/// let c = calibrate(&machine, &campaign.measurements, None, &CalibrateOptions::default())
///     .unwrap();
/// let file = identified_machine_file(&machine, &text, &c, "identified from 20 states").unwrap();
/// let identified = pkm::Machine::from_toml_str(&file, "identified.toml").unwrap();
/// let again = calibrate(&identified, &campaign.measurements, None, &CalibrateOptions::default())
///     .unwrap();
/// assert!(again.identification.rms_before < 1e-5);
/// ```
pub fn identified_machine_file(
    machine: &Machine,
    source: &str,
    c: &Calibration,
    comment: &str,
) -> Result<String> {
    struct Write<'a> {
        file: &'a str,
        source: &'a str,
        values: &'a [f64],
        comment: &'a str,
    }
    impl CalibratableVisitor for Write<'_> {
        type Output = Result<String>;
        fn visit<M: Calibratable<A> + Analysable<6, A>, const A: usize>(
            self,
            h: &M,
        ) -> Self::Output {
            let ng = h.geometry().len();
            if self.values.len() != ng + A {
                return Err(Error::InvalidInput {
                    what: "identified parameters".into(),
                    message: format!("expected {} values, got {}", ng + A, self.values.len()),
                });
            }
            let identified = h.with_geometry(&self.values[..ng])?;
            identified.rewrite_file(
                self.source,
                self.file,
                Some(&self.values[ng..]),
                self.comment,
            )
        }
    }
    machine.visit_calibratable(Write {
        file: &machine.source,
        source,
        values: &c.values,
        comment,
    })?
}

struct CalibrateJob<'a> {
    meas: &'a Measurements,
    validation: Option<&'a Measurements>,
    opt: &'a CalibrateOptions,
}

impl CalibratableVisitor for CalibrateJob<'_> {
    type Output = Result<Calibration>;
    fn visit<M: Calibratable<A> + Analysable<6, A>, const A: usize>(self, h: &M) -> Self::Output {
        let zero = h.zero_readings()?;
        let names = identify::parameter_names(h);
        let mut fixed = Vec::new();
        for n in self
            .opt
            .fix
            .iter()
            .map(|n| n.trim())
            .filter(|n| !n.is_empty())
        {
            let hits: Vec<usize> = (0..names.len()).filter(|&i| glob(n, &names[i])).collect();
            if hits.is_empty() {
                return Err(Error::InvalidInput {
                    what: "fixed parameters".into(),
                    message: format!(
                        "no parameter matches `{n}`; the parameters are {}",
                        names.join(", ")
                    ),
                });
            }
            fixed.extend(hits);
        }
        fixed.sort_unstable();
        fixed.dedup();
        if fixed.len() == names.len() {
            return Err(Error::InvalidInput {
                what: "fixed parameters".into(),
                message: format!(
                    "nothing to identify: every parameter is fixed by --fix '{}'",
                    self.opt.fix.join(",")
                ),
            });
        }
        let o = identify::Options {
            model: self.opt.model,
            fixed,
            ..Default::default()
        };
        let id = identify::identify(h, &zero, self.meas, &o)?;
        let seed = if self.opt.seed_procedure {
            Some(h.seed_procedure(&zero, self.meas)?)
        } else {
            None
        };
        let values = seed
            .as_ref()
            .map(|s| s.values.clone())
            .unwrap_or(id.values.clone());
        let ng = values.len() - A;
        let identified = h.with_geometry(&values[..ng])?;
        let z = SVector::<f64, A>::from_column_slice(&values[ng..]);
        let validation = self.validation.map(|v| Validation {
            states: v.states.len(),
            nominal: identify::point_errors(h, &zero, v),
            identified: identify::point_errors(&identified, &z, v),
        });
        Ok(Calibration {
            identification: id,
            values,
            seed_procedure: seed,
            validation,
        })
    }
}

/// Parses the design names of [`Design`] (`random`, `one-strut`).
///
/// # Examples
///
/// ```
/// use pkm::analysis::identification::parse_design;
/// use pkm::identify::simulate::Design;
/// assert_eq!(parse_design("random").unwrap(), Design::Random);
/// assert_eq!(parse_design("one-strut").unwrap(), Design::OneActuator);
/// assert!(parse_design("grid").unwrap_err().to_string().contains("one-strut"));
/// ```
pub fn parse_design(s: &str) -> Result<Design> {
    match s {
        "random" => Ok(Design::Random),
        "one-strut" => Ok(Design::OneActuator),
        d => Err(Error::InvalidInput {
            what: "design".into(),
            message: format!("expected `random` or `one-strut`, found `{d}`"),
        }),
    }
}
