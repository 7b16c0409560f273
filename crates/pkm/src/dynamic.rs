//! A dynamically sized view of any [`crate::Mechanism`], for command lines, reports and
//! bindings that handle machines whose type is known only at run time.
//!
//! Hot loops (sweeps, paths) should use the generic [`crate::Mechanism`] through
//! [`crate::Machine::visit`]; this view allocates small vectors per call.

use nalgebra::{DMatrix, SVector, Vector3};

use crate::error::{Error, Result};
use crate::limits::Violation;
use crate::mechanism::{Actuator, Coordinate, PoseSpace, Skeleton};
use crate::pose::{pose_from_angles, Pose};
use crate::rotation::Convention;

/// Forward-kinematics result with a dynamic pose vector.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct DynForward {
    /// Pose coordinates (mm, rad).
    pub pose: Vec<f64>,
    /// Iterations used (0 for closed form).
    pub iterations: usize,
    /// Largest actuator residual.
    pub residual: f64,
}

/// Object-safe mirror of [`crate::Mechanism`] with slices and vectors (internal units).
pub trait DynMechanism: Send + Sync {
    /// See [`crate::mechanism::MechanismInfo::name`].
    fn name(&self) -> &str;
    /// See [`crate::mechanism::MechanismInfo::kind`].
    fn kind(&self) -> &'static str;
    /// See [`crate::mechanism::MechanismInfo::coordinates`].
    fn coordinates(&self) -> &[Coordinate];
    /// See [`crate::mechanism::MechanismInfo::actuators`].
    fn actuators(&self) -> &[Actuator];
    /// See [`crate::mechanism::MechanismInfo::driven`].
    fn driven(&self) -> Vec<usize>;
    /// See [`crate::mechanism::MechanismInfo::pose_space`].
    fn pose_space(&self) -> PoseSpace;
    /// See [`crate::mechanism::MechanismInfo::home`].
    fn home(&self) -> Vec<f64>;
    /// See [`crate::Mechanism::inverse`].
    fn inverse(&self, x: &[f64]) -> Result<Vec<f64>>;
    /// See [`crate::mechanism::inverse_continuing`].
    fn inverse_continuing(&self, x: &[f64], last: Option<&[f64]>) -> Result<Vec<f64>>;
    /// See [`crate::Mechanism::jacobian`].
    fn jacobian(&self, x: &[f64]) -> Result<DMatrix<f64>>;
    /// See [`crate::Mechanism::forward`].
    fn forward(&self, q: &[f64], start: &[f64]) -> Result<DynForward>;
    /// See [`crate::mechanism::MechanismInfo::inverse_method`].
    fn inverse_method(&self) -> &'static str;
    /// See [`crate::mechanism::MechanismInfo::forward_closed_form`].
    fn forward_closed_form(&self) -> bool;
    /// See [`crate::Mechanism::tool_pose`].
    fn tool_pose(&self, x: &[f64]) -> Result<Pose>;
    /// See [`crate::Mechanism::coords_from_pose`].
    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<Vec<f64>>;
    /// See [`crate::Mechanism::check_limits`]; returns the violations.
    fn check_limits(&self, x: &[f64], q: &[f64]) -> Result<Vec<Violation>>;
    /// See [`crate::Mechanism::skeleton`].
    fn skeleton(&self, x: &[f64]) -> Result<Skeleton>;
    /// See [`crate::Mechanism::condition`] (dimensionally consistent).
    fn condition(&self, x: &[f64]) -> Result<f64>;
    /// See [`crate::mechanism::MechanismInfo::characteristic_length`].
    fn characteristic_length(&self) -> f64;
}

/// Copies a slice into a fixed vector, checking its length and finiteness.
pub fn fixed<const N: usize>(what: &str, v: &[f64]) -> Result<SVector<f64, N>> {
    if v.len() != N {
        return Err(Error::InvalidInput {
            what: what.into(),
            message: format!("expected {N} values, got {}", v.len()),
        });
    }
    if let Some(i) = v.iter().position(|x| !x.is_finite()) {
        return Err(Error::InvalidInput {
            what: what.into(),
            message: format!("value {} is not a finite number ({})", i + 1, v[i]),
        });
    }
    Ok(SVector::<f64, N>::from_column_slice(v))
}

/// Implements [`DynMechanism`] for a type implementing [`crate::Mechanism`]`<P, A>`.
#[macro_export]
macro_rules! impl_dyn_mechanism {
    ($t:ty, $p:literal, $a:literal) => {
        impl $crate::dynamic::DynMechanism for $t {
            fn name(&self) -> &str {
                $crate::Mechanism::<$p, $a>::info(self).name()
            }
            fn kind(&self) -> &'static str {
                $crate::Mechanism::<$p, $a>::info(self).kind()
            }
            fn coordinates(&self) -> &[$crate::Coordinate] {
                $crate::Mechanism::<$p, $a>::info(self).coordinates()
            }
            fn actuators(&self) -> &[$crate::Actuator] {
                $crate::Mechanism::<$p, $a>::info(self).actuators()
            }
            fn driven(&self) -> Vec<usize> {
                $crate::Mechanism::<$p, $a>::info(self).driven().to_vec()
            }
            fn pose_space(&self) -> $crate::PoseSpace {
                $crate::Mechanism::<$p, $a>::info(self).pose_space()
            }
            fn home(&self) -> Vec<f64> {
                $crate::Mechanism::<$p, $a>::info(self)
                    .home()
                    .as_slice()
                    .to_vec()
            }
            fn inverse(&self, x: &[f64]) -> $crate::Result<Vec<f64>> {
                let x = $crate::dynamic::fixed::<$p>("pose", x)?;
                Ok($crate::Mechanism::<$p, $a>::inverse(self, &x)?
                    .as_slice()
                    .to_vec())
            }
            fn inverse_continuing(
                &self,
                x: &[f64],
                last: Option<&[f64]>,
            ) -> $crate::Result<Vec<f64>> {
                let x = $crate::dynamic::fixed::<$p>("pose", x)?;
                let last = match last {
                    Some(q) => Some($crate::dynamic::fixed::<$a>("previous actuators", q)?),
                    None => None,
                };
                Ok(
                    $crate::mechanism::inverse_continuing(self, &x, last.as_ref())?
                        .as_slice()
                        .to_vec(),
                )
            }
            fn jacobian(&self, x: &[f64]) -> $crate::Result<nalgebra::DMatrix<f64>> {
                let x = $crate::dynamic::fixed::<$p>("pose", x)?;
                let j = $crate::Mechanism::<$p, $a>::jacobian(self, &x)?;
                Ok(nalgebra::DMatrix::from_fn($a, $p, |r, c| j[(r, c)]))
            }
            fn forward(
                &self,
                q: &[f64],
                start: &[f64],
            ) -> $crate::Result<$crate::dynamic::DynForward> {
                let q = $crate::dynamic::fixed::<$a>("actuators", q)?;
                let s = $crate::dynamic::fixed::<$p>("start pose", start)?;
                let f = $crate::Mechanism::<$p, $a>::forward(self, &q, &s)?;
                Ok($crate::dynamic::DynForward {
                    pose: f.pose.as_slice().to_vec(),
                    iterations: f.iterations,
                    residual: f.residual,
                })
            }
            fn inverse_method(&self) -> &'static str {
                $crate::Mechanism::<$p, $a>::info(self).inverse_method()
            }
            fn forward_closed_form(&self) -> bool {
                $crate::Mechanism::<$p, $a>::info(self).forward_closed_form()
            }
            fn tool_pose(&self, x: &[f64]) -> $crate::Result<$crate::Pose> {
                let x = $crate::dynamic::fixed::<$p>("pose", x)?;
                $crate::Mechanism::<$p, $a>::tool_pose(self, &x)
            }
            fn coords_from_pose(
                &self,
                pose: &$crate::Pose,
                orientation_given: bool,
            ) -> $crate::Result<Vec<f64>> {
                Ok(
                    $crate::Mechanism::<$p, $a>::coords_from_pose(self, pose, orientation_given)?
                        .as_slice()
                        .to_vec(),
                )
            }
            fn check_limits(&self, x: &[f64], q: &[f64]) -> $crate::Result<Vec<$crate::Violation>> {
                let x = $crate::dynamic::fixed::<$p>("pose", x)?;
                let q = $crate::dynamic::fixed::<$a>("actuators", q)?;
                let mut v = Vec::new();
                $crate::Mechanism::<$p, $a>::check_limits(self, &x, &q, &mut v);
                Ok(v)
            }
            fn skeleton(&self, x: &[f64]) -> $crate::Result<$crate::Skeleton> {
                let x = $crate::dynamic::fixed::<$p>("pose", x)?;
                $crate::Mechanism::<$p, $a>::skeleton(self, &x)
            }
            fn condition(&self, x: &[f64]) -> $crate::Result<f64> {
                let x = $crate::dynamic::fixed::<$p>("pose", x)?;
                $crate::Mechanism::<$p, $a>::condition(self, &x)
            }
            fn characteristic_length(&self) -> f64 {
                $crate::Mechanism::<$p, $a>::info(self).characteristic_length()
            }
        }
    };
}

/// Names of the values `--pose` expects for this machine and convention.
pub fn pose_names(m: &dyn DynMechanism, conv: Convention) -> Vec<String> {
    match m.pose_space() {
        PoseSpace::Spatial | PoseSpace::Position => {
            let mut v: Vec<String> = ["X", "Y", "Z"].iter().map(|s| s.to_string()).collect();
            v.extend(conv.angle_names().iter().map(|s| s.to_string()));
            v
        }
        PoseSpace::Tcp | PoseSpace::Own => m.coordinates().iter().map(|c| c.name.clone()).collect(),
    }
}

/// Converts user values (mm, deg) of a pose into the mechanism's coordinates
/// (mm, rad). Spatial machines take X, Y, Z and optionally three angles in `conv`.
pub fn pose_from_user(m: &dyn DynMechanism, vals: &[f64], conv: Convention) -> Result<Vec<f64>> {
    match m.pose_space() {
        PoseSpace::Spatial | PoseSpace::Position => spatial_pose_from_user(m, vals, conv),
        PoseSpace::Tcp | PoseSpace::Own => {
            let c = m.coordinates();
            if vals.len() != c.len() {
                return Err(Error::InvalidInput {
                    what: "pose".into(),
                    message: format!(
                        "expected {} values ({}), got {}",
                        c.len(),
                        c.iter()
                            .map(|c| c.name.as_str())
                            .collect::<Vec<_>>()
                            .join(","),
                        vals.len()
                    ),
                });
            }
            Ok(vals
                .iter()
                .zip(c)
                .map(|(v, c)| c.quantity.from_user(*v))
                .collect())
        }
    }
}

/// [`pose_from_user`] for a spatial machine: X, Y, Z and optionally three angles in
/// `conv` (five with RPY angles for a machine that holds C).
fn spatial_pose_from_user(
    m: &dyn DynMechanism,
    vals: &[f64],
    conv: Convention,
) -> Result<Vec<f64>> {
    let names = pose_names(m, conv);
    // A machine that drives X, Y, Z, A, B and holds C (a pentapod: LinuxCNC's
    // X, Y, Z, A, B) takes five values in its own RPY angles, C its held value.
    let holds_c = m.pose_space() == PoseSpace::Spatial && m.driven() == [0, 1, 2, 3, 4];
    if holds_c && vals.len() == 5 && conv == Convention::Rpy {
        let h = m.home();
        return Ok(vec![
            vals[0],
            vals[1],
            vals[2],
            vals[3].to_radians(),
            vals[4].to_radians(),
            h[5],
        ]);
    }
    if holds_c && vals.len() != 3 && vals.len() != 6 {
        return Err(Error::InvalidInput {
            what: "pose".into(),
            message: format!(
                "expected 3, 5 (X,Y,Z,A,B; rpy angles, C held) or 6 values ({}), got {}",
                names.join(","),
                vals.len()
            ),
        });
    }
    if vals.len() != 3 && vals.len() != 6 {
        return Err(Error::InvalidInput {
            what: "pose".into(),
            message: format!(
                "expected 3 or 6 values ({}), got {}",
                names.join(","),
                vals.len()
            ),
        });
    }
    let given = vals.len() == 6;
    let angles = if given {
        [vals[3], vals[4], vals[5]].map(f64::to_radians)
    } else {
        [0.0; 3]
    };
    let pose = pose_from_angles(Vector3::new(vals[0], vals[1], vals[2]), angles, conv);
    m.coords_from_pose(&pose, given)
}
