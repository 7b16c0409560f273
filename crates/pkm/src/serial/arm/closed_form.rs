//! The arm's closed-form inverse kinematics ([`crate::serial::spherical_wrist`]): every
//! solution of a pose, or only the nearest branch, each polished by one Newton step and
//! wrapped to within half a turn of the joint values asked for.

use nalgebra::{Matrix3, Vector3, Vector6};

use super::{Postures, SerialArm};
use crate::serial::spherical_wrist::Nearest;
use crate::units::Quantity;

impl SerialArm {
    /// The closed form's solutions of the pose `(p, r)`, each polished by Newton and
    /// wrapped to within half a turn of `near`, nearest `near` first (sum of squared
    /// joint differences); with `all` false only the nearest one Newton can polish
    /// (one Newton step instead of eight). `Ok(None)` when the closed form does not
    /// apply, `Err` with the reason when the pose is out of reach.
    ///
    /// With `all` false the closed form skips the branches that cannot hold the
    /// nearest solution ([`Nearest`]); should Newton fail to
    /// polish the nearest (a singular pose), every branch is solved and the next
    /// nearest tried, as with `all`. The answer is the same either way.
    ///
    /// The solutions are written into `sols`, the first `n` of the returned
    /// `Some(n)` (eight 48-byte vectors: written in place, not moved through the
    /// results).
    pub(super) fn closed_form(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        near: &Vector6<f64>,
        all: bool,
        sols: &mut Postures,
    ) -> std::result::Result<Option<usize>, String> {
        if self.wrist.is_none() {
            return Ok(None);
        }
        if !all {
            let nearest = Nearest {
                near,
                wrapped: std::array::from_fn(|i| self.actuators[i].quantity == Quantity::Angle),
            };
            let n = self.polished(p, r, near, false, Some(&nearest), sols)?;
            if n > 0 {
                return Ok(Some(n));
            }
        }
        self.polished(p, r, near, all, None, sols).map(Some)
    }

    /// [`SerialArm::closed_form`] with the arm's wrist, over the branches `nearest`
    /// leaves; with `nearest`, only the first (the nearest) may be polished.
    pub(super) fn polished(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        near: &Vector6<f64>,
        all: bool,
        nearest: Option<&Nearest>,
        sols: &mut Postures,
    ) -> std::result::Result<usize, String> {
        let Some(wrist) = &self.wrist else {
            return Ok(0);
        };
        let mut raw = [Vector6::zeros(); 8];
        let n = wrist.solve(p, r, near, nearest, &mut raw)?;
        for q in &mut raw[..n] {
            *q = self.wrap(*q, near);
        }
        raw[..n].sort_by(|a, b| {
            (a - near)
                .norm_squared()
                .total_cmp(&(b - near).norm_squared())
        });
        let mut count = 0;
        // Of a partial set, only the first is sure to be where it is in the whole.
        let tries = if nearest.is_some() { n.min(1) } else { n };
        for q in &raw[..tries] {
            if let Ok(q) = self.newton(p, r, *q) {
                sols[count] = self.wrap(q, near);
                count += 1;
                if !all {
                    break;
                }
            }
        }
        Ok(count)
    }
}
