//! Joint clearances of any machine with passive joints (seed 002): bounds of the error
//! along a direction and as a length, the worst joint states, a Monte Carlo of joint
//! states, and the designer's question (the largest clearance that keeps the error
//! within a tolerance), on the engine of [`crate::accuracy::clearance`].

use nalgebra::SVector;
use serde::Serialize;

use crate::accuracy::clearance::{
    self, ClearanceBounds, ClearanceMonteCarlo, ClearanceOptions, JointClearance, PassiveJoint,
    Region,
};
use crate::error::{Error, Result};
use crate::machine::{Analysable, Analysis, Machine, Visitor};

/// What [`clearance()`] computes.
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
    /// is wanted.
    pub tolerance: Option<f64>,
}

impl Default for ClearanceRequest {
    fn default() -> Self {
        ClearanceRequest {
            diametral: None,
            options: ClearanceOptions::default(),
            monte_carlo: None,
            seed: 1,
            tolerance: None,
        }
    }
}

/// Everything [`clearance()`] found (mm, rad).
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
    /// The factor on every clearance that brings the larger of `upper` and `-lower` to
    /// the tolerance.
    pub largest_clearance_scale: Option<f64>,
    /// The largest uniform diametral clearance within the tolerance (when every joint
    /// has the same clearance).
    pub largest_clearance_mm: Option<f64>,
}

/// The clearances of `req` on `machine`: one diametral value for every joint, or the
/// file's.
pub fn effective_clearances(
    machine: &Machine,
    joints: &[PassiveJoint],
    req: &ClearanceRequest,
) -> Result<Vec<JointClearance>> {
    match req.diametral {
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
                      clearance for every joint (--clearance C)"
                .into(),
        }),
        None => Ok(machine.clearances.clone()),
    }
}

/// The clearance analysis of `machine` at `pose` (internal units; `None`: home).
pub fn clearance(
    machine: &Machine,
    pose: Option<&[f64]>,
    req: &ClearanceRequest,
) -> Result<ClearanceReport> {
    machine.supports(Analysis::Clearance)?;
    let joints = machine.passive_joints();
    let clearances = effective_clearances(machine, &joints, req)?;
    let home = machine.mechanism().home();
    let pose = pose.unwrap_or(&home);
    machine.visit(ClearanceJob {
        pose,
        joints: &joints,
        clearances: &clearances,
        req,
    })
}

struct ClearanceJob<'a> {
    pose: &'a [f64],
    joints: &'a [PassiveJoint],
    clearances: &'a [JointClearance],
    req: &'a ClearanceRequest,
}

impl Visitor for ClearanceJob<'_> {
    type Output = Result<ClearanceReport>;
    fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
        let x = crate::dynamic::fixed::<P>("pose", self.pose)?;
        clearance_at(m, &x, self.joints, self.clearances, self.req)
    }
}

/// [`clearance()`] on a concrete machine.
pub fn clearance_at<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    joints: &[PassiveJoint],
    clearances: &[JointClearance],
    req: &ClearanceRequest,
) -> Result<ClearanceReport>
where
    M: Analysable<P, A>,
{
    if let Some(n) = req.monte_carlo {
        if n > 100_000_000 {
            return Err(Error::InvalidInput {
                what: "clearance Monte Carlo".into(),
                message: format!("expected at most 1e8 samples, got {n}"),
            });
        }
    }
    let regions = clearance::regions(joints, clearances)?;
    let bounds = clearance::bounds(m, x, &regions, &req.options)?;
    let direction = nalgebra::Vector3::from(bounds.direction);
    let monte_carlo = match req.monte_carlo {
        Some(n) => Some(clearance::clearance_monte_carlo(
            m, x, &regions, &direction, n, req.seed,
        )?),
        None => None,
    };
    let (scale, mm) = match req.tolerance {
        None => (None, None),
        Some(t) if !(t > 0.0 && t.is_finite()) => {
            return Err(Error::InvalidInput {
                what: "clearance tolerance".into(),
                message: format!("expected a tolerance > 0 mm, found {t}"),
            })
        }
        Some(t) => {
            let s = largest_scale(m, x, &regions, &req.options, &bounds, t)?;
            let first = clearances.first().map(|c| c.diametral);
            let uniform = first.filter(|c| clearances.iter().all(|o| o.diametral == *c));
            (Some(s), uniform.map(|c| c * s))
        }
    };
    Ok(ClearanceReport {
        clearances: clearances.to_vec(),
        bounds,
        monte_carlo,
        tolerance: req.tolerance,
        largest_clearance_scale: scale,
        largest_clearance_mm: mm,
    })
}

/// The factor `s` on every clearance with `max(upper, -lower)(s) = t`: the bounds grow
/// about linearly with the clearance, so `s <- s t / f(s)` from `s = t / f(1)`, with
/// exact bounds at each step (to `1e-9` relative, at most 8 steps).
fn largest_scale<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    regions: &[Region],
    opt: &ClearanceOptions,
    at_one: &ClearanceBounds,
    t: f64,
) -> Result<f64>
where
    M: Analysable<P, A>,
{
    let worst = |b: &ClearanceBounds| b.upper.max(-b.lower);
    let f1 = worst(at_one);
    if !(f1 > 0.0) {
        return Err(Error::InvalidInput {
            what: "clearance tolerance".into(),
            message: "the clearances cause no error along the direction at this pose: any \
                      clearance keeps it within the tolerance"
                .into(),
        });
    }
    let mut s = t / f1;
    for _ in 0..8 {
        let scaled: Vec<Region> = regions
            .iter()
            .map(|r| {
                Region::new(
                    r.joint.clone(),
                    r.clearance.with_diametral(r.clearance.diametral * s),
                )
            })
            .collect::<Result<_>>()?;
        let f = worst(&clearance::bounds(m, x, &scaled, opt)?);
        if (f - t).abs() <= 1e-9 * t {
            break;
        }
        s *= t / f;
    }
    Ok(s)
}
