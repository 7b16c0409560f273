//! The arm's closed-form inverse kinematics: a spherical wrist
//! ([`crate::serial::spherical_wrist`]) or three parallel axes with axes 5 and 6
//! meeting (`serial/parallel_axes.rs`, the Universal Robots' geometry). Every solution
//! of a pose, or only the nearest branch, each polished by one Newton step and wrapped
//! to within half a turn of the joint values asked for.

use nalgebra::{Matrix3, Matrix4, Vector3, Vector6};

use super::{Postures, SerialArm};
use crate::error::Unattainable;
use crate::serial::parallel_axes::ParallelAxes;
use crate::serial::spherical_wrist::{Nearest, SphericalWrist};
use crate::serial::PreparedChain;
use crate::units::Quantity;

/// The geometry an arm's closed form solves.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum ClosedForm {
    /// Axes 4, 5 and 6 meet; axes 2 and 3 are parallel (most industrial robots).
    Spherical(SphericalWrist),
    /// Axes 2, 3 and 4 are parallel; axes 5 and 6 meet (the Universal Robots).
    ParallelAxes(ParallelAxes),
}

impl ClosedForm {
    /// The closed form of `chain` seen from the part, if one applies (the spherical
    /// wrist's first).
    pub(super) fn detect(
        chain: &PreparedChain,
        part_inverse: &Matrix4<f64>,
        scale: f64,
    ) -> Option<ClosedForm> {
        SphericalWrist::detect(chain, part_inverse, scale)
            .map(ClosedForm::Spherical)
            .or_else(|| {
                ParallelAxes::detect(chain, part_inverse, scale).map(ClosedForm::ParallelAxes)
            })
    }

    /// Every solution of the pose, unpolished ([`SphericalWrist::solve`]).
    pub(super) fn solve(
        &self,
        target_p: &Vector3<f64>,
        target_r: &Matrix3<f64>,
        start: &Vector6<f64>,
        nearest: Option<&Nearest>,
        out: &mut [Vector6<f64>; 8],
    ) -> Result<usize, Unattainable> {
        match self {
            ClosedForm::Spherical(w) => w.solve(target_p, target_r, start, nearest, out),
            ClosedForm::ParallelAxes(w) => w.solve(target_p, target_r, start, nearest, out),
        }
    }
}

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
    ) -> std::result::Result<Option<usize>, Unattainable> {
        if self.wrist.is_none() {
            return Ok(None);
        }
        if !all {
            let nearest = Nearest {
                near,
                wrapped: std::array::from_fn(|i| {
                    self.info.actuators()[i].quantity == Quantity::Angle
                }),
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
    ) -> std::result::Result<usize, Unattainable> {
        let Some(wrist) = &self.wrist else {
            return Ok(0);
        };
        let mut raw = [Vector6::zeros(); 8];
        let n = wrist.solve(p, r, near, nearest, &mut raw)?;
        for q in &mut raw[..n] {
            *q = self.wrap(*q, near);
        }
        // Nearest first; near-ties (mirror-image postures equally near `near` up to
        // rounding: the elbow up and down of a UR stretched at its zero home) in the
        // closed form's order of branches, not as rounding falls, so that neighbouring
        // poses take the same posture.
        // Only the `n` solutions found (usually one or two on the nearest branch).
        let mut dist = [f64::INFINITY; 8];
        for (d, q) in dist.iter_mut().zip(&raw[..n]) {
            *d = (q - near).norm_squared();
        }
        let mut order: [usize; 8] = std::array::from_fn(|i| i);
        order[..n].sort_by(|&a, &b| dist[a].total_cmp(&dist[b]));
        if let Some(&first) = order[..n].first() {
            let band = dist[first] * (1.0 + 1e-9);
            let ties = order[..n].iter().take_while(|&&i| dist[i] <= band).count();
            order[..ties].sort_unstable();
        }
        let mut count = 0;
        // Of a partial set, only the first is sure to be where it is in the whole.
        let tries = if nearest.is_some() { n.min(1) } else { n };
        for q in order[..tries].iter().map(|&i| &raw[i]) {
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
