//! Joint clearances of any machine with passive joints (seed 002): bounds of the error
//! along a direction and as a length, the worst joint states, a Monte Carlo of joint
//! states, and the designer's question (the largest clearance that keeps the error
//! within a tolerance), on the engine of [`crate::accuracy::clearance`].

use nalgebra::SVector;
use serde::Serialize;

use super::clearance_class::ClassClearance;
use super::clearance_path::{
    path_points, path_samples, path_worst, PathReport, PathRequest, PathSample,
};
use super::clearance_study::{overall_largest, Largest, Study};
use super::clearance_surface::surface_report;
pub use super::clearance_surface::{SurfaceReport, SurfaceRequest};
use crate::accuracy::clearance::surface::Hemisphere;
use crate::accuracy::clearance::{
    self, ClearanceBounds, ClearanceMonteCarlo, ClearanceOptions, JointClearance, PassiveJoint,
    Region,
};
use crate::error::{Error, Result};
use crate::machine::{Analysable, Analysis, Machine, Visitor};

/// What [`clearance()`] computes.
///
/// # Examples
///
/// ```
/// use pkm::analysis::clearance::ClearanceRequest;
/// // By default: the file's clearances, bounds along the tool axis, nothing more.
/// let r = ClearanceRequest::default();
/// assert!(r.diametral.is_none() && r.options.direction.is_none());
/// assert!(r.monte_carlo.is_none() && r.tolerance.is_none() && r.surface.is_none());
/// // 20 um in every joint, 1000 sampled joint states, the largest clearance for 10 um.
/// let r = ClearanceRequest {
///     diametral: Some(0.02),
///     monte_carlo: Some(1000),
///     tolerance: Some(0.01),
///     ..Default::default()
/// };
/// assert_eq!(r.seed, 1);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ClearanceRequest {
    /// One diametral clearance (mm) for every passive joint: the file's joint types,
    /// bearing lengths and axes kept, joints it does not list spherical. `None`: the
    /// machine file's `[[clearance]]` entries.
    pub diametral: Option<f64>,
    /// Direction and method of the bounds.
    pub options: ClearanceOptions,
    /// Monte Carlo of this many joint states.
    pub monte_carlo: Option<usize>,
    /// Its seed.
    pub seed: u64,
    /// Tolerance on the error along the direction (mm): the largest clearance within it
    /// is wanted (over the surface too, when one is given).
    pub tolerance: Option<f64>,
    /// Bounds over a part surface.
    pub surface: Option<SurfaceRequest>,
    /// Diametral clearances (mm) for every joint at which the bounds at the pose are
    /// wanted (seed 002's Fig. 5: the bounds against the clearance).
    pub series: Vec<f64>,
    /// Bounds along a G-code path.
    pub path: Option<PathRequest>,
}

impl Default for ClearanceRequest {
    fn default() -> Self {
        ClearanceRequest {
            diametral: None,
            options: ClearanceOptions::default(),
            monte_carlo: None,
            seed: 1,
            tolerance: None,
            surface: None,
            series: Vec::new(),
            path: None,
        }
    }
}

/// Everything [`clearance()`] found (mm, rad).
///
/// # Examples
///
/// See [`clearance()`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClearanceReport {
    /// The clearances used, per joint.
    pub clearances: Vec<JointClearance>,
    /// The bounds (direction, upper, lower, method, worst joint states, ...).
    #[serde(flatten)]
    pub bounds: ClearanceBounds,
    /// The Monte Carlo of joint states, when asked for.
    pub monte_carlo: Option<ClearanceMonteCarlo>,
    /// The tolerance asked about.
    pub tolerance: Option<f64>,
    /// The factor on every clearance that keeps the error along the direction within
    /// the tolerance: at the pose, or over the whole surface when one is given.
    pub largest_clearance_scale: Option<f64>,
    /// The same as a uniform diametral clearance (when every joint has the same
    /// clearance).
    pub largest_clearance_mm: Option<f64>,
    /// The largest uniform diametral clearance within the tolerance at the pose alone.
    pub largest_clearance_at_pose_mm: Option<f64>,
    /// With a tolerance, the largest clearance of each class of joints (the bodies that
    /// carry them) that keeps the error within it, the other classes as given: over
    /// the surface and the path when given, else at the pose.
    pub largest_per_class: Vec<ClassClearance>,
    /// The bounds over the surface, when asked for.
    pub surface: Option<SurfaceReport>,
    /// The bounds at the pose for each clearance of the request's series.
    pub series: Vec<SeriesPoint>,
    /// The bounds along the path, when asked for.
    pub path: Option<PathReport>,
}

/// The bounds at one clearance of a series (mm).
///
/// # Examples
///
/// Seed 002's Fig. 5: the bounds grow with the clearance.
///
/// ```
/// use pkm::analysis::clearance::{clearance, ClearanceRequest};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hybrid-am-seed002.toml"
/// ))
/// .unwrap();
/// let req = ClearanceRequest { series: vec![0.05, 0.1, 0.2], ..Default::default() };
/// let r = clearance(&machine, None, &req).unwrap();
/// assert_eq!(r.series.len(), 3);
/// assert_eq!(r.series[1].clearance_mm, 0.1);
/// for w in r.series.windows(2) {
///     assert!(w[1].upper > w[0].upper && w[1].lower < w[0].lower);
/// }
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SeriesPoint {
    /// Diametral clearance of every joint (mm).
    pub clearance_mm: f64,
    /// Largest error along the direction.
    pub upper: f64,
    /// Smallest error along the direction.
    pub lower: f64,
}

/// The clearances of `req` on `machine`: one diametral value for every joint, or the
/// file's.
///
/// # Examples
///
/// ```
/// use pkm::analysis::clearance::{effective_clearances, ClearanceRequest};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hybrid-am-seed002.toml"
/// ))
/// .unwrap();
/// let joints = machine.passive_joints();
/// // The file gives 0.1 mm in every joint.
/// let file = effective_clearances(&machine, &joints, &ClearanceRequest::default()).unwrap();
/// assert_eq!(file.len(), joints.len());
/// assert!(file.iter().all(|c| c.diametral == 0.1));
/// // One value for every joint replaces it.
/// let req = ClearanceRequest { diametral: Some(0.02), ..Default::default() };
/// let given = effective_clearances(&machine, &joints, &req).unwrap();
/// assert!(given.iter().all(|c| c.diametral == 0.02));
/// ```
pub fn effective_clearances(
    machine: &Machine,
    joints: &[PassiveJoint],
    req: &ClearanceRequest,
) -> Result<Vec<JointClearance>> {
    // Without a clearance of its own, a series' first value stands for it.
    let diametral = match req.diametral {
        None if machine.clearances.is_empty() => req.series.first().copied(),
        d => d,
    };
    match diametral {
        Some(c) => Ok(joints
            .iter()
            .map(|j| {
                machine
                    .clearances
                    .iter()
                    .find(|f| f.joint == j.name)
                    .map(|f| f.with_diametral(c))
                    .unwrap_or_else(|| JointClearance::spherical(j.name.clone(), c))
            })
            .collect()),
        None if machine.clearances.is_empty() => Err(Error::InvalidInput {
            what: "clearance".into(),
            message: "the machine file gives no [[clearance]] entries: give one diametral \
                      clearance for every joint (--clearance C, or a --clearance-series)"
                .into(),
        }),
        None => Ok(machine.clearances.clone()),
    }
}

/// What a clearance analysis needs from the loaded machine before it visits the
/// concrete type: its passive joints, the clearances in effect, the path's samples.
///
/// # Examples
///
/// See [`prepare`] and [`clearance_at`].
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// The machine's passive joints.
    pub joints: Vec<PassiveJoint>,
    /// The clearances in effect.
    pub clearances: Vec<JointClearance>,
    /// The path's samples to bound and the run's sample count (the motion run makes
    /// its own visit, so it comes first).
    pub path: Option<(Vec<PathSample>, u64)>,
}

/// Checks that `machine` supports clearances and prepares `req` on it.
///
/// # Examples
///
/// ```
/// use pkm::analysis::clearance::{prepare, ClearanceRequest};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hybrid-am-seed002.toml"
/// ))
/// .unwrap();
/// let p = prepare(&machine, &ClearanceRequest::default()).unwrap();
/// // Seed 002's machine: four carriage joints and four platform joints.
/// assert_eq!(p.joints.len(), 8);
/// assert_eq!(p.clearances.len(), 8);
/// assert!(p.path.is_none());
/// // A machine without passive joints' clearances says so.
/// let robot = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/kr30-dh.toml"
/// ))
/// .unwrap();
/// assert!(prepare(&robot, &ClearanceRequest::default()).is_err());
/// ```
pub fn prepare(machine: &Machine, req: &ClearanceRequest) -> Result<Prepared> {
    machine.supports(Analysis::Clearance)?;
    let joints = machine.passive_joints();
    let clearances = effective_clearances(machine, &joints, req)?;
    let path = req
        .path
        .as_ref()
        .map(|p| path_samples(machine, p))
        .transpose()?;
    Ok(Prepared {
        joints,
        clearances,
        path,
    })
}

/// The clearance analysis of `machine` at `pose` (internal units; `None`: home).
///
/// # Examples
///
/// Seed 002's machine at home with the file's 0.1 mm in every joint: the error along
/// the nozzle axis lies between the bounds, and so do 500 sampled joint states; with a
/// tolerance, the largest uniform clearance that keeps within it at the pose.
///
/// ```
/// use pkm::analysis::clearance::{clearance, ClearanceRequest};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hybrid-am-seed002.toml"
/// ))
/// .unwrap();
/// let req = ClearanceRequest {
///     monte_carlo: Some(500),
///     tolerance: Some(0.01),
///     ..Default::default()
/// };
/// let r = clearance(&machine, None, &req).unwrap();
/// let b = &r.bounds;
/// assert!(b.upper > 0.0 && b.lower < 0.0);
/// let mc = r.monte_carlo.as_ref().unwrap();
/// assert!(mc.max <= b.upper + 1e-12 && mc.min >= b.lower - 1e-12);
/// let c = r.largest_clearance_at_pose_mm.unwrap();
/// assert!(c > 0.0);
/// // The error grows about linearly with the clearance: within 10 um at `c`.
/// let at_c = ClearanceRequest { diametral: Some(c), ..Default::default() };
/// let r = clearance(&machine, None, &at_c).unwrap();
/// assert!(r.bounds.upper.max(-r.bounds.lower) <= 0.01 * (1.0 + 1e-6));
/// ```
pub fn clearance(
    machine: &Machine,
    pose: Option<&[f64]>,
    req: &ClearanceRequest,
) -> Result<ClearanceReport> {
    let prepared = prepare(machine, req)?;
    let home = machine.mechanism().home();
    let pose = pose.unwrap_or(&home);
    machine.visit(ClearanceJob {
        pose,
        req,
        prepared: &prepared,
    })
}

struct ClearanceJob<'a> {
    pose: &'a [f64],
    req: &'a ClearanceRequest,
    prepared: &'a Prepared,
}

impl Visitor for ClearanceJob<'_> {
    type Output = Result<ClearanceReport>;
    fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
        let x = crate::dynamic::fixed::<P>("pose", self.pose)?;
        clearance_at(m, &x, self.req, self.prepared)
    }
}

/// [`clearance()`] on a concrete machine, `prepared` by [`prepare`].
///
/// # Examples
///
/// ```
/// use pkm::analysis::clearance::{clearance, clearance_at, prepare, ClearanceRequest};
/// use pkm::machine::Model;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hybrid-am-seed002.toml"
/// ))
/// .unwrap();
/// let Model::HybridAm(am) = &machine.model else { panic!() };
/// let req = ClearanceRequest::default();
/// let prepared = prepare(&machine, &req).unwrap();
/// let home = nalgebra::SVector::<f64, 6>::from_column_slice(&machine.mechanism().home());
/// let r = clearance_at(am.as_ref(), &home, &req, &prepared).unwrap();
/// assert_eq!(r, clearance(&machine, None, &req).unwrap());
/// ```
pub fn clearance_at<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    req: &ClearanceRequest,
    prepared: &Prepared,
) -> Result<ClearanceReport>
where
    M: Analysable<P, A>,
{
    let (joints, clearances) = (&prepared.joints, &prepared.clearances);
    check_request(req)?;
    let regions = clearance::regions(joints, clearances)?;
    let uniform = clearances
        .first()
        .map(|c| c.diametral)
        .filter(|c| clearances.iter().all(|o| o.diametral == *c));
    let study = Study {
        m,
        x,
        req,
        prepared,
        regions,
        uniform,
    };
    let bounds = clearance::bounds(m, x, &study.regions, &req.options)?;
    let direction = nalgebra::Vector3::from(bounds.direction);
    let monte_carlo = match req.monte_carlo {
        Some(n) => Some(clearance::clearance_monte_carlo(
            m,
            x,
            &study.regions,
            &direction,
            n,
            req.seed,
        )?),
        None => None,
    };
    let at_pose = match req.tolerance {
        None => Largest::NONE,
        Some(t) => study.largest_at_pose(t, &bounds)?,
    };
    let surface = match &req.surface {
        None => None,
        Some(sr) => Some(surface_report(m, &study.regions, req, sr, uniform)?),
    };
    let series = study.series()?;
    let path = match &prepared.path {
        None => None,
        Some((samples, total)) => Some(path_report(
            m,
            &study.regions,
            req,
            samples,
            *total,
            uniform,
        )?),
    };
    let overall = overall_largest(at_pose, surface.as_ref(), path.as_ref());
    // Per class of joints: over the surface and the path when given, else at the pose.
    let largest_per_class = match req.tolerance {
        None => Vec::new(),
        Some(t) => study.largest_per_class(t, &bounds, surface.as_ref(), path.as_ref())?,
    };
    Ok(ClearanceReport {
        largest_per_class,
        clearances: clearances.to_vec(),
        bounds,
        monte_carlo,
        tolerance: req.tolerance,
        largest_clearance_scale: overall.scale,
        largest_clearance_mm: overall.mm,
        largest_clearance_at_pose_mm: at_pose.mm,
        surface,
        series,
        path,
    })
}

/// Refuses sizes and values of `req` before any work.
fn check_request(req: &ClearanceRequest) -> Result<()> {
    if let Some(n) = req.monte_carlo {
        if n > 100_000_000 {
            return Err(Error::InvalidInput {
                what: "clearance Monte Carlo".into(),
                message: format!("expected at most 1e8 samples, got {n}"),
            });
        }
    }
    if req.series.len() > 1000 {
        return Err(Error::InvalidInput {
            what: "clearance series".into(),
            message: format!("expected at most 1000 clearances, got {}", req.series.len()),
        });
    }
    if let Some(sr) = &req.surface {
        Hemisphere {
            radius: sr.radius,
            centre: sr.centre.unwrap_or_default(),
            azimuth: sr.azimuth,
        }
        .validate()?;
        crate::accuracy::clearance::surface::check_heights(sr.heights)?;
    }
    if let Some(t) = req.tolerance.filter(|t| !(*t > 0.0 && t.is_finite())) {
        return Err(Error::InvalidInput {
            what: "clearance tolerance".into(),
            message: format!("expected a tolerance > 0 mm, found {t}"),
        });
    }
    Ok(())
}

/// The bounds at each path sample (rayon), and with a tolerance the factor on the
/// clearances that keeps every sample within it (`s <- s t / worst(s)`, to 1e-9).
fn path_report<M, const P: usize, const A: usize>(
    m: &M,
    regions: &[Region],
    req: &ClearanceRequest,
    samples: &[PathSample],
    total: u64,
    uniform: Option<f64>,
) -> Result<PathReport>
where
    M: Analysable<P, A>,
{
    let at = |regions: &[Region]| path_points(m, samples, regions, &req.options);
    let points = at(regions)?;
    let worst = path_worst(&points);
    let scale = match (req.tolerance, worst) {
        (Some(t), Some((_, w))) if w > 0.0 => Some(fit_scale(t, w, |s| {
            Ok(path_worst(&at(&scaled(regions, s)?)?).map_or(0.0, |v| v.1))
        })?),
        _ => None,
    };
    Ok(PathReport {
        samples: total,
        worst: worst.map(|w| w.0),
        largest_clearance_scale: scale,
        largest_clearance_mm: scale.zip(uniform).map(|(s, c)| s * c),
        points,
    })
}

/// Regions with every clearance times `s`.
pub(crate) fn scaled(regions: &[Region], s: f64) -> Result<Vec<Region>> {
    regions
        .iter()
        .map(|r| {
            Region::new(
                r.joint.clone(),
                r.clearance.with_diametral(r.clearance.diametral * s),
            )
        })
        .collect()
}

/// The factor `s` on every clearance with `worst(s) = t`, from `worst(1) = w1 > 0`: the
/// bounds grow about linearly with the clearance, so `s <- s t / worst(s)` from
/// `s = t / w1`, each step on exact bounds (to `1e-9` relative, at most 8 steps).
pub(crate) fn fit_scale(t: f64, w1: f64, mut worst: impl FnMut(f64) -> Result<f64>) -> Result<f64> {
    let mut s = t / w1;
    for _ in 0..8 {
        let f = worst(s)?;
        if !(f > 0.0) || (f - t).abs() <= 1e-9 * t {
            break;
        }
        s *= t / f;
    }
    Ok(s)
}
