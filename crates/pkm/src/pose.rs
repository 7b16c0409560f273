//! Poses (position + rotation), homogeneous transforms and small-deviation
//! ("variation") transforms.
//!
//! A [`Pose`] is a rigid transform from a moving frame (platform, tool) to the fixed
//! (base) frame, with the position in millimetres. Homogeneous 4x4 matrices follow the
//! usual layout `[R p; 0 0 0 1]` (seed 003 eq. 1).

use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::error::Error;
use crate::rotation::Convention;

/// Rigid pose: rotation then translation, `x_base = R x_moving + p` (mm).
pub type Pose = Isometry3<f64>;

/// Builds a pose from a position (mm) and a rotation matrix (assumed proper).
pub fn pose_from_parts(p: Vector3<f64>, r: &Matrix3<f64>) -> Pose {
    Isometry3::from_parts(
        Translation3::from(p),
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*r)),
    )
}

/// Builds a pose from a position (mm) and three angles (radians) in `convention`.
pub fn pose_from_angles(p: Vector3<f64>, angles: [f64; 3], convention: Convention) -> Pose {
    pose_from_parts(p, &convention.to_matrix(angles))
}

/// Rotation matrix of a pose.
pub fn rotation_matrix(pose: &Pose) -> Matrix3<f64> {
    *pose.rotation.to_rotation_matrix().matrix()
}

/// Builds a pose from a 4x4 homogeneous matrix, checking that its rotation block is
/// orthonormal with determinant +1 (within `1e-9`) and its last row is `0 0 0 1`.
pub fn pose_from_homogeneous(m: &Matrix4<f64>) -> Result<Pose, Error> {
    let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
    let ortho = (r.transpose() * r - Matrix3::identity()).abs().max();
    let last = (m.fixed_view::<1, 4>(3, 0) - nalgebra::RowVector4::new(0.0, 0.0, 0.0, 1.0))
        .abs()
        .max();
    if !(ortho < 1e-9 && (r.determinant() - 1.0).abs() < 1e-9 && last < 1e-12) {
        return Err(Error::InvalidInput {
            what: "homogeneous transform".into(),
            message: format!(
                "rotation block must be orthonormal with determinant +1 and last row 0 0 0 1 \
                 (orthonormality error {ortho:.2e}, determinant {:.9})",
                r.determinant()
            ),
        });
    }
    Ok(pose_from_parts(m.fixed_view::<3, 1>(0, 3).into_owned(), &r))
}

/// A small rigid displacement: translation `d` (mm) and small rotation `r` (rad)
/// about the axes of the frame it is expressed in.
///
/// Its variation matrix (seed 002 eq. 1, seed 003) is
///
/// ```text
///        [  0   -rz   ry  dx ]
/// dA =   [  rz   0   -rx  dy ]
///        [ -ry   rx   0   dz ]
///        [  0    0    0   0  ]
/// ```
///
/// so that to first order a transform `A` deviates to `A (I + dA)`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SmallDisplacement {
    /// Small translation (mm).
    pub translation: Vector3<f64>,
    /// Small rotation vector (rad).
    pub rotation: Vector3<f64>,
}

impl SmallDisplacement {
    /// New displacement from translation (mm) and rotation vector (rad).
    pub fn new(translation: Vector3<f64>, rotation: Vector3<f64>) -> Self {
        SmallDisplacement {
            translation,
            rotation,
        }
    }

    /// The 4x4 variation matrix `dA` (first-order; see the type documentation).
    pub fn variation_matrix(&self) -> Matrix4<f64> {
        let mut m = Matrix4::zeros();
        m.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&self.rotation.cross_matrix());
        m.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.translation);
        m
    }

    /// First-order deviated transform `I + dA` as a homogeneous matrix.
    pub fn first_order(&self) -> Matrix4<f64> {
        Matrix4::identity() + self.variation_matrix()
    }

    /// The exact rigid transform with this translation and rotation vector (the
    /// rotation is `exp([r]x)`, so the result stays a proper rigid motion however large
    /// the deviation).
    pub fn to_pose(&self) -> Pose {
        Isometry3::from_parts(
            Translation3::from(self.translation),
            UnitQuaternion::from_scaled_axis(self.rotation),
        )
    }

    /// The displacement that takes `from` to `to`, expressed in the frame of `from`:
    /// `to = from * delta.to_pose()` exactly.
    pub fn between(from: &Pose, to: &Pose) -> Self {
        let d = from.inverse() * to;
        SmallDisplacement {
            translation: d.translation.vector,
            rotation: d.rotation.scaled_axis(),
        }
    }
}
