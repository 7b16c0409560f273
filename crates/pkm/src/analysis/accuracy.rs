//! Accuracy of any loaded machine: the exact error of given deviations, the
//! sensitivities to every parameter, the budget and Monte Carlo of tolerances and an
//! error map, in one call ([`accuracy()`]) on the generic engine of [`crate::accuracy`].

use nalgebra::SVector;
use serde::Serialize;

use crate::accuracy::{
    self, Budget, Distribution, ErrorMap, MonteCarlo, Parameter, ParameterKind, PoseError,
    Tolerance,
};
use crate::error::{Error, Result};
use crate::limits::Violation;
use crate::machine::{Analysable, Machine, Visitor};
use crate::units::Quantity;
use crate::workspace::GridAxis;

/// One tolerance per kind of parameter, for machines whose file gives none (internal
/// units; a value of 0 leaves that kind out).
///
/// # Examples
///
/// ```
/// use pkm::accuracy::Distribution;
/// use pkm::analysis::KindTolerances;
/// // +-10 um on lengths and 10 urad on angles, uniform, unless changed.
/// let k = KindTolerances { joint: 0.02, ..Default::default() };
/// assert_eq!((k.joint, k.length, k.zero, k.angle), (0.02, 0.01, 0.01, 1e-5));
/// assert_eq!(k.distribution, Distribution::Uniform);
/// assert!(k.validate().is_ok());
/// assert!(KindTolerances { length: -1.0, ..k }.validate().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct KindTolerances {
    /// Joint-centre coordinates (mm).
    pub joint: f64,
    /// Link dimensions and linear link deviations (mm).
    pub length: f64,
    /// Zero lengths and positioning of linear drives (mm).
    pub zero: f64,
    /// Every angular parameter, revolute drives' positioning included (rad).
    pub angle: f64,
    /// Distribution in Monte Carlo.
    pub distribution: Distribution,
}

impl Default for KindTolerances {
    /// +-10 um on lengths, +-10 urad (2 arc seconds) on angles, uniform.
    fn default() -> Self {
        KindTolerances {
            joint: 0.01,
            length: 0.01,
            zero: 0.01,
            angle: 1e-5,
            distribution: Distribution::Uniform,
        }
    }
}

impl KindTolerances {
    /// Checks the values: `>= 0` and at most [`crate::accuracy::MAX_TOLERANCE_LENGTH`]
    /// (100 mm) for lengths, [`crate::accuracy::MAX_TOLERANCE_ANGLE`] (10 deg) for
    /// angles: a tolerance of 1e300 printed a 300-digit budget, one of 1e5 mm a budget
    /// that meant nothing.
    pub fn validate(&self) -> Result<()> {
        use crate::accuracy::{MAX_TOLERANCE_ANGLE, MAX_TOLERANCE_LENGTH};
        for (v, what, max, unit) in [
            (
                self.joint,
                "joint-centre tolerance",
                MAX_TOLERANCE_LENGTH,
                "mm",
            ),
            (self.length, "link tolerance", MAX_TOLERANCE_LENGTH, "mm"),
            (
                self.zero,
                "zero-length / drive tolerance",
                MAX_TOLERANCE_LENGTH,
                "mm",
            ),
            (self.angle, "angle tolerance", MAX_TOLERANCE_ANGLE, "rad"),
        ] {
            if !(v >= 0.0 && v <= max) {
                return Err(Error::InvalidInput {
                    what: what.into(),
                    message: format!(
                        "expected a value from 0 to {} {unit}{}, found {}",
                        if unit == "rad" {
                            format!("{max:.4}")
                        } else {
                            format!("{max}")
                        },
                        if unit == "rad" { " (10 deg)" } else { "" },
                        if v.abs() > 1e6 {
                            format!("{v:e}")
                        } else {
                            format!("{v}")
                        }
                    ),
                });
            }
        }
        Ok(())
    }

    /// The tolerance of parameter `p`, `None` when its kind is left out.
    ///
    /// # Examples
    ///
    /// ```
    /// use pkm::accuracy::{Parameter, ParameterKind};
    /// use pkm::analysis::KindTolerances;
    /// use pkm::Quantity;
    /// let k = KindTolerances { zero: 0.0, ..Default::default() };
    /// let joint = Parameter::new("A1.x", Quantity::Length, ParameterKind::JointCentre);
    /// let zero = Parameter::new("zero(L1)", Quantity::Length, ParameterKind::ZeroLength);
    /// assert_eq!(k.of(&joint), Some(0.01));
    /// assert_eq!(k.of(&zero), None); // a tolerance of 0 leaves the kind out
    /// ```
    pub fn of(&self, p: &Parameter) -> Option<f64> {
        let t = match (p.kind, p.quantity) {
            (ParameterKind::Clearance, _) => return None,
            (_, Quantity::Angle) => self.angle,
            (ParameterKind::ZeroLength | ParameterKind::DrivePositioning, _) => self.zero,
            (ParameterKind::JointCentre, _) => self.joint,
            _ => self.length,
        };
        (t > 0.0).then_some(t)
    }

    /// The tolerances of every parameter of `params` whose kind has one and that can
    /// be toleranced alone (`tolerable`, [`crate::accuracy::Parametric::tolerable`]).
    ///
    /// # Examples
    ///
    /// ```
    /// use pkm::analysis::KindTolerances;
    /// let machine = pkm::Machine::from_path(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/machines/hexapod-linuxcnc.toml"
    /// ))
    /// .unwrap();
    /// let params = machine.parameters();
    /// let t = KindTolerances::default().tolerances(&params, &[]);
    /// // Every parameter of the hexapod has a kind with a tolerance.
    /// assert_eq!(t.len(), params.len());
    /// assert!(t.iter().all(|t| t.value > 0.0));
    /// ```
    pub fn tolerances(&self, params: &[Parameter], tolerable: &[bool]) -> Vec<Tolerance> {
        params
            .iter()
            .enumerate()
            .filter(|(k, _)| tolerable.get(*k).copied().unwrap_or(true))
            .filter_map(|(k, p)| {
                self.of(p).map(|value| Tolerance {
                    parameter: k,
                    value,
                    distribution: self.distribution,
                })
            })
            .collect()
    }
}

/// Where the tolerances of an accuracy analysis came from.
///
/// # Examples
///
/// ```
/// use pkm::analysis::ToleranceSource;
/// assert_eq!(ToleranceSource::MachineFile.describe(), "from the machine file");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ToleranceSource {
    /// Given with the options (a tolerances file).
    Given,
    /// The machine file's `[[tolerance]]` entries.
    MachineFile,
    /// One per kind of parameter ([`KindTolerances`]).
    ByKind,
}

/// The tolerances an accuracy analysis uses.
///
/// # Examples
///
/// ```
/// use pkm::analysis::{KindTolerances, ToleranceSource, Tolerances};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/mc300.toml"
/// ))
/// .unwrap();
/// // The MC-300 file gives tolerances: the default takes them.
/// let (params, file) = (machine.parameters(), machine.tolerances());
/// let (source, t) = Tolerances::Default.resolve(&params, &[], file).unwrap();
/// assert_eq!(source, ToleranceSource::MachineFile);
/// assert_eq!(t, file);
/// // One per kind instead.
/// let by_kind = Tolerances::ByKind(KindTolerances::default());
/// let (source, t) = by_kind.resolve(&params, &[], file).unwrap();
/// assert_eq!(source, ToleranceSource::ByKind);
/// assert!(!t.is_empty());
/// ```
#[derive(Debug, Clone, PartialEq)]
pub enum Tolerances {
    /// These (from a tolerances file).
    Given(Vec<Tolerance>),
    /// One per kind of parameter.
    ByKind(KindTolerances),
    /// The machine file's `[[tolerance]]` entries, else [`KindTolerances::default`].
    Default,
}

impl ToleranceSource {
    /// Where the tolerances came from, for a sentence (`from the machine file`).
    pub fn describe(self) -> &'static str {
        match self {
            ToleranceSource::Given => "from the tolerances file",
            ToleranceSource::MachineFile => "from the machine file",
            ToleranceSource::ByKind => "one per kind of parameter",
        }
    }
}

impl Tolerances {
    /// The tolerances on a machine with parameters `params` (those `tolerable` alone)
    /// whose file gives `file`, and where they came from.
    pub fn resolve(
        &self,
        params: &[Parameter],
        tolerable: &[bool],
        file: &[Tolerance],
    ) -> Result<(ToleranceSource, Vec<Tolerance>)> {
        Ok(match self {
            Tolerances::Given(t) => (ToleranceSource::Given, t.clone()),
            Tolerances::ByKind(k) => {
                k.validate()?;
                (ToleranceSource::ByKind, k.tolerances(params, tolerable))
            }
            Tolerances::Default if !file.is_empty() => {
                (ToleranceSource::MachineFile, file.to_vec())
            }
            Tolerances::Default => (
                ToleranceSource::ByKind,
                KindTolerances::default().tolerances(params, tolerable),
            ),
        })
    }
}

/// An error map request: two pose coordinates over their default span
/// ([`crate::workspace::default_span`]), `points` per axis.
///
/// # Examples
///
/// ```
/// use pkm::analysis::{accuracy, AccuracyOptions, MapRequest};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// // The error over X and Y at home height, 3 x 3 points.
/// let opt = AccuracyOptions {
///     map: Some(MapRequest { coordinates: [0, 1], points: 3 }),
///     ..Default::default()
/// };
/// let r = accuracy(&machine, &opt).unwrap();
/// assert!(r.map.is_some());
/// let bad = AccuracyOptions { map: Some(MapRequest { coordinates: [0, 0], points: 3 }), ..opt };
/// assert!(accuracy(&machine, &bad).is_err()); // two different coordinates
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapRequest {
    /// Indices of the two pose coordinates.
    pub coordinates: [usize; 2],
    /// Grid points per axis (2 to 401).
    pub points: usize,
}

/// What [`accuracy()`] computes.
///
/// # Examples
///
/// ```
/// use pkm::analysis::{AccuracyOptions, Tolerances};
/// // By default: at home, no deviations, the file's tolerances, budget only.
/// let o = AccuracyOptions::default();
/// assert!(o.pose.is_none() && o.deviations.is_empty());
/// assert_eq!(o.tolerances, Tolerances::Default);
/// assert!(o.monte_carlo.is_none() && o.map.is_none() && o.clearance.is_none());
/// // Parameter 0 off by 0.05 mm, and a Monte Carlo of 1000 machines.
/// let o = AccuracyOptions { deviations: vec![(0, 0.05)], monte_carlo: Some(1000), ..o };
/// assert_eq!(o.seed, 1);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct AccuracyOptions {
    /// Pose coordinates (internal units); `None`: the home pose.
    pub pose: Option<Vec<f64>>,
    /// Deviations whose exact pose error is wanted (`(parameter index, value)`,
    /// internal units).
    pub deviations: Vec<(usize, f64)>,
    /// Which tolerances.
    pub tolerances: Tolerances,
    /// Monte Carlo with this many machines.
    pub monte_carlo: Option<usize>,
    /// Seed of the Monte Carlo.
    pub seed: u64,
    /// Error map.
    pub map: Option<MapRequest>,
    /// Bounds of the error from joint clearances (machines with passive joints).
    pub clearance: Option<super::clearance::ClearanceRequest>,
}

impl Default for AccuracyOptions {
    fn default() -> Self {
        AccuracyOptions {
            pose: None,
            deviations: Vec::new(),
            tolerances: Tolerances::Default,
            monte_carlo: None,
            seed: 1,
            map: None,
            clearance: None,
        }
    }
}

/// Everything [`accuracy()`] found (internal units: mm, rad).
///
/// # Examples
///
/// ```
/// use pkm::analysis::{accuracy, AccuracyOptions, ToleranceSource};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let r = accuracy(&machine, &AccuracyOptions::default()).unwrap();
/// assert_eq!(r.pose, machine.mechanism().home());
/// assert!(r.violations.is_empty());
/// // One sensitivity per parameter; the file gives no tolerances: one per kind.
/// assert_eq!(r.sensitivities.len(), r.parameters.len());
/// assert_eq!(r.tolerance_source, ToleranceSource::ByKind);
/// // The worst case bounds the root sum of squares.
/// assert!(r.budget.worst_case >= r.budget.rss && r.budget.rss > 0.0);
/// assert_eq!(r.pose_error.position.norm(), 0.0); // no deviations given
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AccuracyReport {
    /// Machine name.
    pub machine: String,
    /// Machine type.
    pub kind: String,
    /// The pose analysed.
    pub pose: Vec<f64>,
    /// Limits the pose violates (the analysis still runs: it is the nominal machine's
    /// error model, but such a pose is not one the machine goes to).
    pub violations: Vec<Violation>,
    /// Every parameter of the machine.
    pub parameters: Vec<Parameter>,
    /// The deviations given.
    pub deviations: Vec<(usize, f64)>,
    /// Their exact tool-pose error (zero without deviations).
    pub pose_error: PoseError,
    /// First-order sensitivity of the tool pose to each parameter (per unit).
    pub sensitivities: Vec<PoseError>,
    /// Whether the sensitivities are analytic or central differences.
    pub analytic: bool,
    /// Where the tolerances came from.
    pub tolerance_source: ToleranceSource,
    /// The tolerances.
    pub tolerances: Vec<Tolerance>,
    /// The error budget of the tolerances.
    pub budget: Budget,
    /// The Monte Carlo, when asked for.
    pub monte_carlo: Option<MonteCarlo>,
    /// The error map, when asked for.
    pub map: Option<ErrorMap>,
    /// The clearance analysis, when asked for.
    pub clearance: Option<super::clearance::ClearanceReport>,
}

/// The accuracy of `machine` at one pose: exact error of the given deviations,
/// sensitivities, budget, and optionally Monte Carlo and an error map. Every machine
/// type supports it.
///
/// # Examples
///
/// A deviation's exact error against its first-order sensitivity, and a Monte Carlo
/// of the tolerances within the budget's worst case.
///
/// ```
/// use pkm::analysis::{accuracy, AccuracyOptions};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let d = 0.01; // mm on parameter 0
/// let opt = AccuracyOptions {
///     deviations: vec![(0, d)],
///     monte_carlo: Some(2000),
///     ..Default::default()
/// };
/// let r = accuracy(&machine, &opt).unwrap();
/// let first_order = r.sensitivities[0].position * d;
/// assert!((r.pose_error.position - first_order).norm() < 1e-3 * first_order.norm());
/// let mc = r.monte_carlo.unwrap();
/// assert_eq!(mc.samples, 2000);
/// assert!(mc.max <= r.budget.worst_case * 1.001);
/// ```
pub fn accuracy(machine: &Machine, opt: &AccuracyOptions) -> Result<AccuracyReport> {
    accuracy_with_progress(machine, opt, &|_| {})
}

/// [`accuracy()`], telling `progress` of the Monte Carlo machines done (from one
/// thread, every 262 144 machines).
///
/// # Examples
///
/// ```
/// use std::sync::atomic::{AtomicU64, Ordering};
/// use pkm::analysis::{accuracy_with_progress, AccuracyOptions};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let done = AtomicU64::new(0);
/// let opt = AccuracyOptions { monte_carlo: Some(1000), ..Default::default() };
/// let r = accuracy_with_progress(&machine, &opt, &|n| {
///     done.fetch_add(n, Ordering::Relaxed);
/// })
/// .unwrap();
/// assert_eq!(r.monte_carlo.unwrap().samples, 1000);
/// assert!(done.load(Ordering::Relaxed) <= 1000);
/// ```
pub fn accuracy_with_progress(
    machine: &Machine,
    opt: &AccuracyOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<AccuracyReport> {
    let dm = machine.mechanism();
    let pose = match &opt.pose {
        Some(p) => p.clone(),
        None => dm.home(),
    };
    let map_axes = match opt.map {
        None => None,
        Some(r) => {
            let n = dm.coordinates().len();
            if r.coordinates.iter().any(|&c| c >= n) || r.coordinates[0] == r.coordinates[1] {
                return Err(Error::InvalidInput {
                    what: "error map".into(),
                    message: format!("expected two different coordinates of the machine's {n}"),
                });
            }
            if !(2..=401).contains(&r.points) {
                return Err(Error::InvalidInput {
                    what: "error map".into(),
                    message: format!("expected 2 to 401 points per axis, got {}", r.points),
                });
            }
            if pose.len() != n {
                return Err(Error::InvalidInput {
                    what: "pose".into(),
                    message: format!("expected {n} values, got {}", pose.len()),
                });
            }
            Some(r.coordinates.map(|c| {
                let (lo, hi) = crate::workspace::default_span(dm, &pose, c);
                GridAxis {
                    coordinate: c,
                    min: lo,
                    max: hi,
                    step: (hi - lo) / (r.points - 1) as f64,
                }
            }))
        }
    };
    let clearance = match &opt.clearance {
        Some(req) => Some((req, super::clearance::prepare(machine, req)?)),
        None => None,
    };
    machine.visit(AccuracyJob {
        pose: &pose,
        opt,
        file: machine.tolerances(),
        map_axes,
        clearance: clearance.as_ref().map(|(r, p)| (*r, p)),
        progress,
    })
}

struct AccuracyJob<'a> {
    pose: &'a [f64],
    opt: &'a AccuracyOptions,
    file: &'a [Tolerance],
    map_axes: Option<[GridAxis; 2]>,
    clearance: Option<(
        &'a super::clearance::ClearanceRequest,
        &'a super::clearance::Prepared,
    )>,
    progress: &'a (dyn Fn(u64) + Sync),
}

impl Visitor for AccuracyJob<'_> {
    type Output = Result<AccuracyReport>;
    fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
        let x = crate::dynamic::fixed::<P>("pose", self.pose)?;
        let params = m.parameters();
        let (tolerance_source, tolerances) =
            self.opt
                .tolerances
                .resolve(&params, &m.tolerable(), self.file)?;
        check_deviations(&params, &self.opt.deviations)?;
        // The machine prepared for what is given (a serial machine completes the
        // angular deviations of a link from the ones given, and refuses what means
        // nothing alone).
        let given = given_parameters(&tolerances, &self.opt.deviations);
        let prepared = m.with_given(&given)?;
        let m = prepared.as_ref().unwrap_or(m);
        let q = m.inverse(&x)?;
        let mut violations = Vec::new();
        m.check_limits(&x, &q, &mut violations);
        let pose_error = accuracy::pose_error(m, &x, &self.opt.deviations)?;
        let analytic = m.analytic_sensitivities(&x);
        let is_analytic = analytic.is_some();
        let sensitivities = match analytic {
            Some(s) => s?,
            None => accuracy::finite_difference_sensitivities(m, &x)?,
        };
        let budget = Budget::from_sensitivities(&params, &sensitivities, &tolerances)?;
        let monte_carlo = match self.opt.monte_carlo {
            Some(n) => Some(accuracy::monte_carlo_with_progress(
                m,
                &x,
                &tolerances,
                n,
                self.opt.seed,
                self.progress,
            )?),
            None => None,
        };
        let map = match self.map_axes {
            Some(axes) => Some(accuracy::error_map(
                m,
                &SVector::<f64, P>::from_column_slice(self.pose),
                axes,
                &tolerances,
            )?),
            None => None,
        };
        let clearance = match self.clearance {
            Some((req, prepared)) => Some(super::clearance::clearance_at(m, &x, req, prepared)?),
            None => None,
        };
        Ok(AccuracyReport {
            machine: m.info().name().to_string(),
            kind: m.info().kind().to_string(),
            pose: self.pose.to_vec(),
            violations,
            parameters: params,
            deviations: self.opt.deviations.clone(),
            pose_error,
            sensitivities,
            analytic: is_analytic,
            tolerance_source,
            tolerances,
            budget,
            monte_carlo,
            map,
            clearance,
        })
    }
}

/// Checks the `deviations` (parameter index, value) name parameters of `params` and
/// are in range of their kind, whichever front end gave them (the file reader checks
/// its own with file and line).
fn check_deviations(params: &[Parameter], deviations: &[(usize, f64)]) -> Result<()> {
    for (k, v) in deviations {
        let p = params.get(*k).ok_or_else(|| Error::InvalidInput {
            what: "deviations".into(),
            message: format!("no parameter {k}: the machine has {}", params.len()),
        })?;
        accuracy::check_tolerance_magnitude(p.quantity, *v).map_err(|message| {
            Error::InvalidInput {
                what: format!("deviation of {}", p.name),
                message,
            }
        })?;
    }
    Ok(())
}

/// The parameters given a tolerance or a deviation, sorted, each once.
fn given_parameters(tolerances: &[Tolerance], deviations: &[(usize, f64)]) -> Vec<usize> {
    let mut given: Vec<usize> = tolerances
        .iter()
        .map(|t| t.parameter)
        .chain(deviations.iter().map(|d| d.0))
        .collect();
    given.sort_unstable();
    given.dedup();
    given
}
