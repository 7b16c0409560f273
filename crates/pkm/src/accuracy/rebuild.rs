//! Parallel and hybrid machines in the accuracy engine: the machine rebuilt with its
//! deviated geometry, its forward kinematics solved from the nominal pose at the
//! nominal readings plus the drives' offsets. Written once for every such machine
//! through [`Rebuild`]; strut machines add analytic sensitivities.

use nalgebra::{DMatrix, SVector, Vector3};

use super::{Evaluate, Parameter, ParameterKind, PoseError};
use crate::error::{Error, Result};
use crate::identify::Identifiable;
use crate::mechanism::{Mechanism, PoseSpace};
use crate::pose::Pose;
use crate::units::Quantity;

/// A machine that can be rebuilt with other values of its geometric parameters.
/// Its [`super::Parametric::parameters`] are these, then one drive offset per actuator.
pub trait Rebuild<const P: usize, const A: usize>:
    Mechanism<P, A> + Sized + Sync + Send + Clone
{
    /// The geometric parameters (without the drives), in the order of
    /// [`Rebuild::geometry_values`].
    fn geometry_parameters(&self) -> Vec<Parameter>;
    /// Their values (mm, rad).
    fn geometry_values(&self) -> Vec<f64>;
    /// The same machine with other values (names, limits and home kept).
    fn with_geometry_values(&self, v: &[f64]) -> Result<Self>;
    /// Sets `target` (a clone of this machine) to this machine with geometry `v`: by
    /// default a rebuild; a type can do it in place without allocating.
    fn update_geometry(&self, target: &mut Self, v: &[f64]) -> Result<()> {
        *target = self.with_geometry_values(v)?;
        Ok(())
    }
    /// The passive joints whose centres are among the geometric parameters (see
    /// [`super::Parametric::passive_joints`]): none, by default.
    fn passive_joints(&self) -> Vec<super::clearance::PassiveJoint> {
        Vec::new()
    }
    /// Kind and name of the drive offsets: strut machines' zero lengths
    /// (`zero(L1)`), otherwise drive positioning deviations (`dq(U)`).
    fn drive_parameter(&self, actuator: usize) -> Parameter {
        let a = &self.info().actuators()[actuator];
        Parameter::new(
            format!("dq({})", a.name),
            a.quantity,
            ParameterKind::DrivePositioning,
        )
    }
}

/// The exact error of a rebuilt machine (see the module documentation).
#[derive(Clone)]
pub struct RebuildEvaluator<'a, M, const P: usize, const A: usize> {
    m: &'a M,
    x: SVector<f64, P>,
    q: SVector<f64, A>,
    nominal: Pose,
    g0: Vec<f64>,
    g: Vec<f64>,
    /// The deviated machine, updated per evaluation (per-thread scratch).
    scratch: M,
}

impl<M: Rebuild<P, A>, const P: usize, const A: usize> Evaluate for RebuildEvaluator<'_, M, P, A> {
    fn pose_error(&mut self, deviations: &[(usize, f64)]) -> Result<PoseError> {
        let ng = self.g0.len();
        self.g.copy_from_slice(&self.g0);
        let mut dq = SVector::<f64, A>::zeros();
        let mut geometry = false;
        for &(k, v) in deviations {
            if v == 0.0 && k < ng + A {
                // Nothing moves: the nominal machine, solved exactly (below).
                continue;
            }
            if k < ng {
                self.g[k] += v;
                geometry = true;
            } else if k < ng + A {
                dq[k - ng] += v;
            } else {
                return Err(Error::InvalidInput {
                    what: "deviation".into(),
                    message: format!("parameter index {k} beyond the machine's {}", ng + A),
                });
            }
        }
        if !geometry && dq.iter().all(|d| *d == 0.0) {
            return Ok(PoseError {
                position: Vector3::zeros(),
                orientation: Vector3::zeros(),
            });
        }
        let actual = if geometry {
            self.m.update_geometry(&mut self.scratch, &self.g)?;
            self.scratch.forward_tool_pose(&(self.q + dq), &self.x)?
        } else {
            self.m.forward_tool_pose(&(self.q + dq), &self.x)?
        };
        let e = PoseError::between(&self.nominal, &actual);
        Ok(if self.m.info().free_spin() {
            e.without_spin(&(self.nominal.rotation * Vector3::z()))
        } else {
            e
        })
    }
}

/// The parameters of a rebuildable machine: geometry, then the drives.
pub(crate) fn rebuild_parameters<M: Rebuild<P, A>, const P: usize, const A: usize>(
    m: &M,
) -> Vec<Parameter> {
    let mut v = m.geometry_parameters();
    v.extend((0..A).map(|k| m.drive_parameter(k)));
    v
}

/// Prepares the rebuild evaluator at `x`.
pub(crate) fn rebuild_evaluator<'a, M: Rebuild<P, A>, const P: usize, const A: usize>(
    m: &'a M,
    x: &SVector<f64, P>,
) -> Result<RebuildEvaluator<'a, M, P, A>> {
    let g0 = m.geometry_values();
    Ok(RebuildEvaluator {
        m,
        x: *x,
        q: m.inverse(x)?,
        nominal: m.tool_pose(x)?,
        g: g0.clone(),
        g0,
        scratch: m.clone(),
    })
}

/// Implements [`super::Parametric`] for a [`Rebuild`] machine; `analytic` names a function
/// `fn(&M, &SVector<f64, P>) -> Result<Vec<PoseError>>` giving its sensitivities.
macro_rules! parametric_by_rebuild {
    ($t:ty, $p:literal, $a:literal) => {
        $crate::accuracy::rebuild::parametric_by_rebuild!($t, $p, $a, |_m, _x| None);
    };
    ($t:ty, $p:literal, $a:literal, $analytic:expr) => {
        impl $crate::accuracy::Parametric<$p, $a> for $t {
            type Evaluator<'a> = $crate::accuracy::rebuild::RebuildEvaluator<'a, $t, $p, $a>;
            fn parameters(&self) -> Vec<$crate::accuracy::Parameter> {
                $crate::accuracy::rebuild::rebuild_parameters(self)
            }
            fn evaluator(
                &self,
                x: &nalgebra::SVector<f64, $p>,
            ) -> $crate::error::Result<Self::Evaluator<'_>> {
                $crate::accuracy::rebuild::rebuild_evaluator(self, x)
            }
            fn analytic_sensitivities(
                &self,
                x: &nalgebra::SVector<f64, $p>,
            ) -> Option<$crate::error::Result<Vec<$crate::accuracy::PoseError>>> {
                let f: fn(
                    &$t,
                    &nalgebra::SVector<f64, $p>,
                )
                    -> Option<$crate::error::Result<Vec<$crate::accuracy::PoseError>>> = $analytic;
                f(self, x)
            }
            fn passive_joints(&self) -> Vec<$crate::accuracy::clearance::PassiveJoint> {
                $crate::accuracy::Rebuild::passive_joints(self)
            }
        }
    };
}
pub(crate) use parametric_by_rebuild;

/// Implements [`Rebuild`] and [`super::Parametric`] for a strut machine (`$t` with
/// `$a` struts, [`crate::identify::struts::StrutMachine`]): every joint-centre
/// coordinate is a parameter (what identification estimates), the drives are the
/// struts' zero lengths, the sensitivities analytic. Invoked in the type's own folder
/// (`hexapod/accuracy.rs`, `tripod/accuracy.rs`).
macro_rules! strut_rebuild {
    ($t:ty, $a:literal) => {
        impl $crate::accuracy::Rebuild<6, $a> for $t {
            fn geometry_parameters(&self) -> Vec<$crate::accuracy::Parameter> {
                $crate::identify::Identifiable::geometry_names(self)
                    .into_iter()
                    .map(|n| {
                        $crate::accuracy::Parameter::new(
                            n,
                            $crate::units::Quantity::Length,
                            $crate::accuracy::ParameterKind::JointCentre,
                        )
                    })
                    .collect()
            }
            fn geometry_values(&self) -> Vec<f64> {
                $crate::identify::Identifiable::geometry(self)
            }
            fn with_geometry_values(&self, v: &[f64]) -> $crate::error::Result<Self> {
                $crate::identify::Identifiable::with_geometry(self, v)
            }
            fn update_geometry(&self, target: &mut Self, v: &[f64]) -> $crate::error::Result<()> {
                let (base, platform) = $crate::identify::struts::split(v)?;
                $crate::identify::struts::StrutMachine::set_joints(target, &base, &platform);
                Ok(())
            }
            fn drive_parameter(&self, k: usize) -> $crate::accuracy::Parameter {
                $crate::accuracy::rebuild::zero_length_parameter(
                    &$crate::Mechanism::info(self).actuators()[k].name,
                )
            }
            fn passive_joints(&self) -> Vec<$crate::accuracy::clearance::PassiveJoint> {
                let s = $crate::identify::struts::StrutMachine::struts(self);
                let base: Vec<&str> = s.iter().map(|s| s.base_name.as_str()).collect();
                let platform: Vec<&str> = s.iter().map(|s| s.platform_name.as_str()).collect();
                $crate::accuracy::rebuild::strut_joints(&base, &platform)
            }
        }
        $crate::accuracy::rebuild::parametric_by_rebuild!($t, 6, $a, |m, x| Some(
            $crate::accuracy::rebuild::strut_sensitivities(m, x)
        ));
    };
}
pub(crate) use strut_rebuild;

/// The zero length of strut `name` as a parameter (`zero(L1)`): the drive parameter of
/// every strut machine.
pub(crate) fn zero_length_parameter(name: &str) -> Parameter {
    Parameter::new(
        format!("zero({name})"),
        Quantity::Length,
        ParameterKind::ZeroLength,
    )
}

/// The passive joints of struts whose base joints are named `base` and platform joints
/// `platform` (per strut; a name used by several struts is one joint): the base
/// joints' centres are the first `3 n` geometric parameters, the platform joints' the
/// next `3 n` (the order of [`crate::identify::struts::names`]).
pub(crate) fn strut_joints(
    base: &[&str],
    platform: &[&str],
) -> Vec<super::clearance::PassiveJoint> {
    let n = base.len();
    let mut out: Vec<super::clearance::PassiveJoint> = Vec::new();
    for (body, names, offset) in [("base", base, 0), ("platform", platform, 3 * n)] {
        for (i, name) in names.iter().enumerate() {
            let c = [offset + 3 * i, offset + 3 * i + 1, offset + 3 * i + 2];
            match out.iter_mut().find(|j| j.body == body && j.name == *name) {
                Some(j) => j.centres.push(c),
                None => out.push(super::clearance::PassiveJoint {
                    name: name.to_string(),
                    body: body.into(),
                    centres: vec![c],
                }),
            }
        }
    }
    out
}

/// Analytic sensitivities of a strut machine (implicit function theorem, see
/// [`implicit_sensitivities`]).
pub(crate) fn strut_sensitivities<M: Identifiable<6, A>, const A: usize>(
    m: &M,
    x: &SVector<f64, 6>,
) -> Result<Vec<PoseError>> {
    let mut jg = DMatrix::zeros(A, m.geometry().len());
    m.inverse_with_geometry_jacobian(x, &mut jg)?;
    implicit_sensitivities(m, x, &jg)
}

/// Sensitivities of a spatial machine's tool pose to its geometry and drives by the
/// implicit function theorem: the readings held, `q(x'; g) = q + dz`, so
/// `dx/d(g, z) = -J_d^-1 [dq/dg, -I]` with `jg = dq/dg` (`A x ng`, at fixed `x`); the
/// tool point moves by `dx[X, Y, Z]` and turns by `E(A, B, C) dx[A, B, C]` (held
/// coordinates stay).
pub(crate) fn implicit_sensitivities<M: Mechanism<6, A>, const A: usize>(
    m: &M,
    x: &SVector<f64, 6>,
    jg: &DMatrix<f64>,
) -> Result<Vec<PoseError>> {
    if m.info().pose_space() != PoseSpace::Spatial {
        return Err(Error::InvalidInput {
            what: "geometric accuracy".into(),
            message: "needs a spatial machine (pose X, Y, Z, A, B, C)".into(),
        });
    }
    let ng = jg.ncols();
    let n = ng + A;
    let j = m.jacobian(x)?;
    let driven = m.info().driven();
    let jd = DMatrix::from_fn(A, A, |r, c| j[(r, driven[c])]);
    let mut rhs = DMatrix::zeros(A, n);
    rhs.view_mut((0, 0), (A, ng)).copy_from(jg);
    for k in 0..A {
        rhs[(k, ng + k)] = -1.0;
    }
    let dxd = -jd.lu().solve(&rhs).ok_or_else(|| Error::Singular {
        what: "driven Jacobian (geometric accuracy)".into(),
        rcond: 0.0,
    })?;
    let e = crate::rotation::rpy_rate_matrix([x[3], x[4], x[5]]);
    // A tool free to spin: only the tilt of its axis is an error.
    let axis = if m.info().free_spin() {
        Some(m.tool_pose(x)?.rotation * Vector3::z())
    } else {
        None
    };
    Ok((0..n)
        .map(|c| {
            let mut dx = SVector::<f64, 6>::zeros();
            for (k, &d) in driven.iter().enumerate() {
                dx[d] = dxd[(k, c)];
            }
            let err = PoseError {
                position: Vector3::new(dx[0], dx[1], dx[2]),
                orientation: e * Vector3::new(dx[3], dx[4], dx[5]),
            };
            match &axis {
                Some(k) => err.without_spin(k),
                None => err,
            }
        })
        .collect())
}
