//! The accuracy engine, written once for every machine type: a machine names its
//! geometric parameters ([`Parameter`]: link dimensions, joint centres, zero lengths,
//! drive positioning, angular deviations, installation angles) and evaluates its tool
//! pose with any of them deviated ([`Parametric`]); sensitivities, the error budget
//! ([`budget()`]), the seeded Monte Carlo ([`monte_carlo()`]) and error maps ([`error_map`]) are
//! generic on top.
//!
//! What is evaluated is seed 003's question for every mechanism: the control commands
//! the actuator readings it computes with the *nominal* model for pose `x`,
//! `q = IK(x; p_0)`; the real machine, whose parameters are `p = p_0 + dp`, then sits at
//! the pose `FK(q; p)`. The error is that pose against the nominal tool pose at `x`:
//! the tool-point displacement `dp` (mm, base or workpiece frame) and the small rotation
//! `w` of the tool frame (rad, rotation vector of `R_real R_nominal^T`).
//!
//! * Serial chains (seed 003, eqs. 1-4): `FK(q; p)` is the product of the deviated link
//!   and joint transforms; sensitivities analytic (`dT/dp = T_before dM/dp T_after`).
//! * Parallel machines (strut machines, P3RP head, hybrid machine): `FK(q; p)` is the
//!   forward kinematics of the machine rebuilt with the deviated geometry, started from
//!   `x`; strut machines give analytic sensitivities by the implicit function theorem,
//!   `dx/dp = -J_d^-1 [dq/dg, -I]`, the others central differences of the exact error.
//!
//! [`sensitivities`] returns the analytic ones where a machine has them;
//! [`finite_difference_sensitivities`] the central differences for any machine (the
//! tests hold one against the other).

pub mod budget;
pub mod clearance;
pub mod map;
pub mod monte_carlo;
pub mod path;
pub(crate) mod rebuild;
pub mod streamed;
pub use budget::tolerances_of_kind;

use nalgebra::{SVector, Vector3};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::mechanism::Mechanism;
use crate::pose::Pose;
use crate::units::Quantity;

pub use budget::{budget, Budget, BudgetItem, Distribution, Tolerance};

/// The largest tolerance or deviation of a length pkm takes (mm). A tolerance is a small
/// departure from the nominal geometry and pkm propagates it to first order: 100 mm is
/// beyond any machine's tolerances, and a value there is a typing error (a tolerance of
/// 1e5 mm printed a budget of 1e5 mm that meant nothing).
pub const MAX_TOLERANCE_LENGTH: f64 = 100.0;

/// The largest tolerance or deviation of an angle pkm takes (rad): 10 deg, where the
/// first-order model is already off by 1.5 % (`sin x / x`).
pub const MAX_TOLERANCE_ANGLE: f64 = 10.0 * std::f64::consts::PI / 180.0;

/// Checks a tolerance or deviation of quantity `q` (internal units: mm, rad) against
/// [`MAX_TOLERANCE_LENGTH`] / [`MAX_TOLERANCE_ANGLE`] by magnitude; the message says the
/// range in the user's unit (mm, deg).
pub fn check_tolerance_magnitude(q: Quantity, v: f64) -> std::result::Result<(), String> {
    let max = match q {
        Quantity::Length => MAX_TOLERANCE_LENGTH,
        Quantity::Angle => MAX_TOLERANCE_ANGLE,
    };
    if v.abs() <= max {
        return Ok(());
    }
    let u = q.to_user(v);
    Err(format!(
        "{} {} is not a tolerance or deviation: pkm takes at most {} {} (first-order error \
         propagation of small departures from the nominal geometry)",
        if u.is_finite() && u.abs() < 1e6 {
            format!("{u}")
        } else {
            format!("{u:e}")
        },
        q.unit(),
        q.to_user(max).round(),
        q.unit()
    ))
}
pub use crate::serial::accuracy::{
    serial_completions, serial_parameters, serial_tolerable, LinkCompletion,
};
pub use map::{error_map, ErrorMap};
pub use monte_carlo::{monte_carlo, monte_carlo_with_progress, statistics, MonteCarlo};
pub use rebuild::Rebuild;

/// What a geometric parameter of a machine is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum ParameterKind {
    /// A length or angle of a link (P3RP crank `l1`, rod `l2`, offset `e`, `delta`,
    /// the tool length).
    LinkDimension,
    /// One coordinate of a joint centre (strut machines' base and platform joints).
    JointCentre,
    /// A strut's length at the control's zero reading.
    ZeroLength,
    /// Positioning deviation `dq` of a driven joint (seed 003).
    DrivePositioning,
    /// Linear deviation `delta` of a link frame (seed 003).
    LinkOffset,
    /// Angular deviation `alpha` of a link frame (seed 003).
    AngularDeviation,
    /// Installation angle of the bed in the world (seed 003's `theta_x0`, ...).
    Installation,
    /// Radial play of a passive joint (reserved for the clearance model).
    Clearance,
}

impl ParameterKind {
    /// The kind's name in files and on the command line (`joint-centre`, ...).
    pub fn as_str(self) -> &'static str {
        match self {
            ParameterKind::LinkDimension => "link-dimension",
            ParameterKind::JointCentre => "joint-centre",
            ParameterKind::ZeroLength => "zero-length",
            ParameterKind::DrivePositioning => "drive-positioning",
            ParameterKind::LinkOffset => "link-offset",
            ParameterKind::AngularDeviation => "angular-deviation",
            ParameterKind::Installation => "installation",
            ParameterKind::Clearance => "clearance",
        }
    }
}

/// One geometric parameter of a machine.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Parameter {
    /// Name (`A1.x`, `zero(L1)`, `l2`, `delta_x(1 slide)`, `dq(X)`).
    pub name: String,
    /// Length (mm) or angle (rad inside, deg at the user boundary).
    pub quantity: Quantity,
    /// What it is.
    pub kind: ParameterKind,
}

impl Parameter {
    /// A parameter.
    pub fn new(name: impl Into<String>, quantity: Quantity, kind: ParameterKind) -> Self {
        Parameter {
            name: name.into(),
            quantity,
            kind,
        }
    }
}

/// Tool-pose error: tool-point displacement (mm) and small rotation of the tool frame
/// (rad, rotation vector), base or workpiece frame.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct PoseError {
    /// Tool-point displacement (mm).
    pub position: Vector3<f64>,
    /// Rotation of the tool frame (rad).
    pub orientation: Vector3<f64>,
}

impl PoseError {
    /// The error of `actual` against `nominal`: `t_a - t_n` and the rotation vector of
    /// `R_a R_n^T`.
    pub fn between(nominal: &Pose, actual: &Pose) -> Self {
        PoseError {
            position: actual.translation.vector - nominal.translation.vector,
            orientation: (actual.rotation * nominal.rotation.inverse()).scaled_axis(),
        }
    }

    /// The error without its rotation about the unit tool axis `k`: `w - (w . k) k`, the
    /// part that tilts the axis (`dk = w x k` is unchanged). For a mechanism that leaves
    /// the tool free to spin ([`crate::mechanism::MechanismInfo::free_spin`]).
    pub fn without_spin(self, k: &Vector3<f64>) -> Self {
        PoseError {
            position: self.position,
            orientation: self.orientation - k * self.orientation.dot(k),
        }
    }
}

/// Exact evaluation of the tool-pose error at one prepared machine state.
pub trait Evaluate {
    /// The error with the parameters `deviations` (`(index into
    /// [`Parametric::parameters`], deviation in internal units)`) deviated and every
    /// other parameter nominal.
    fn pose_error(&mut self, deviations: &[(usize, f64)]) -> Result<PoseError>;
}

/// A machine whose geometric parameters can be deviated: the accuracy engine's view of
/// every machine type.
pub trait Parametric<const P: usize, const A: usize>: Mechanism<P, A> {
    /// The evaluator prepared at one pose (per-thread scratch: the Monte Carlo clones
    /// it once per chunk, not per sample).
    type Evaluator<'a>: Evaluate + Clone + Send + Sync
    where
        Self: 'a;

    /// Every geometric parameter, in a fixed order (the indices of deviations and
    /// tolerances).
    fn parameters(&self) -> Vec<Parameter>;

    /// The evaluator of the tool-pose error at pose `x` (the nominal readings
    /// `q = IK(x)` commanded).
    fn evaluator(&self, x: &SVector<f64, P>) -> Result<Self::Evaluator<'_>>;

    /// Analytic first-order sensitivities of the tool pose to every parameter at `x`
    /// (per unit of the parameter, internal units), where the machine has them.
    fn analytic_sensitivities(&self, _x: &SVector<f64, P>) -> Option<Result<Vec<PoseError>>> {
        None
    }

    /// First-order sensitivities of the tool pose to the parameters `which` (indices
    /// into [`Parametric::parameters`]) at `x`, into `out` (one per entry of `which`),
    /// with scratch `s` kept between calls (a path's samples, one scratch per thread).
    /// `q` are the actuators at `x` as the caller solved them (a run's sample): serial
    /// machines evaluate at those joints (a robot keeps the posture the run chose, no
    /// second inverse per sample) with a plan prepared on the first call, without
    /// allocating ([`crate::serial::sensitivity`]); the default picks the sensitivities
    /// at `x` from [`sensitivities`]. Returns the tool axis (the tool frame's Z, unit,
    /// in the frame of the errors), which a path's surface error is taken along.
    fn sensitivities_into(
        &self,
        x: &SVector<f64, P>,
        q: &SVector<f64, A>,
        which: &[usize],
        s: &mut SensitivityScratch,
        out: &mut [PoseError],
    ) -> Result<Vector3<f64>> {
        let _ = (s, q);
        let all = match self.analytic_sensitivities(x) {
            Some(a) => a?,
            None => finite_difference_sensitivities(self, x)?,
        };
        pick(&all, which, out)?;
        Ok(self.tool_pose(x)?.rotation * Vector3::z())
    }

    /// The machine prepared for deviations of the parameters `given` (the toleranced or
    /// measured ones): `None` when nothing changes, an error saying why when one of them
    /// cannot be given (a serial machine completes a link's angular deviations from the
    /// ones given, eq. 3, and refuses those that mean nothing alone).
    fn with_given(&self, _given: &[usize]) -> Result<Option<Self>>
    where
        Self: Sized,
    {
        Ok(None)
    }

    /// Which parameters can be toleranced one by one (default tolerances skip the
    /// others): all, by default.
    fn tolerable(&self) -> Vec<bool> {
        vec![true; self.parameters().len()]
    }

    /// The passive joints whose centres are parameters of the machine (the joints a
    /// clearance can be given for, [`clearance`]): none, by default.
    fn passive_joints(&self) -> Vec<clearance::PassiveJoint> {
        Vec::new()
    }
}

/// Scratch of [`Parametric::sensitivities_into`]: what a machine prepares on the first
/// call for the parameters asked for (a serial machine's plan), reused by the next.
#[derive(Debug, Clone, Default)]
pub struct SensitivityScratch {
    pub(crate) serial: Option<crate::serial::accuracy::SerialScratch>,
}

/// `out[i] = all[which[i]]`, refusing an index beyond `all`.
pub(crate) fn pick(all: &[PoseError], which: &[usize], out: &mut [PoseError]) -> Result<()> {
    if out.len() != which.len() {
        return Err(Error::InvalidInput {
            what: "sensitivities".into(),
            message: format!("expected {} outputs, got {}", which.len(), out.len()),
        });
    }
    for (o, &k) in out.iter_mut().zip(which) {
        *o = *all.get(k).ok_or_else(|| Error::InvalidInput {
            what: "sensitivities".into(),
            message: format!("parameter index {k} beyond the machine's {}", all.len()),
        })?;
    }
    Ok(())
}

/// First-order sensitivities of the tool pose to every parameter at `x`: the machine's
/// analytic ones, else [`finite_difference_sensitivities`].
pub fn sensitivities<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<Vec<PoseError>>
where
    M: Parametric<P, A>,
{
    match m.analytic_sensitivities(x) {
        Some(s) => s,
        None => finite_difference_sensitivities(m, x),
    }
}

/// Central differences of the exact error, `(e(+h) - e(-h)) / 2h`, with `h = 1e-4` mm
/// for lengths and `1e-6` rad for angles (truncation `O(h^2)`, far below the forward
/// solvers' `1e-11` residual over `h`).
pub fn finite_difference_sensitivities<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<Vec<PoseError>>
where
    M: Parametric<P, A> + ?Sized,
{
    let params = m.parameters();
    let mut ev = m.evaluator(x)?;
    params
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let h = match p.quantity {
                Quantity::Length => 1e-4,
                Quantity::Angle => 1e-6,
            };
            let plus = ev.pose_error(&[(k, h)])?;
            let minus = ev.pose_error(&[(k, -h)])?;
            Ok(PoseError {
                position: (plus.position - minus.position) / (2.0 * h),
                orientation: (plus.orientation - minus.orientation) / (2.0 * h),
            })
        })
        .collect()
}

/// The exact tool-pose error at `x` with the named deviations (`(parameter index,
/// value)`, internal units); an index beyond the machine's parameters is an error.
pub fn pose_error<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    deviations: &[(usize, f64)],
) -> Result<PoseError>
where
    M: Parametric<P, A>,
{
    m.evaluator(x)?.pose_error(deviations)
}

/// Index of the parameter named `name`, or an error listing what names look like.
pub fn parameter_index(params: &[Parameter], name: &str) -> Result<usize> {
    params
        .iter()
        .position(|p| p.name == name)
        .ok_or_else(|| Error::InvalidInput {
            what: "parameter".into(),
            message: format!(
                "unknown parameter `{name}`, expected one of {}{}",
                params
                    .iter()
                    .take(8)
                    .map(|p| p.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                if params.len() > 8 {
                    format!(", ... ({} in all)", params.len())
                } else {
                    String::new()
                }
            ),
        })
}
