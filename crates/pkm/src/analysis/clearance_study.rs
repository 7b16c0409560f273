//! The clearance analysis at one pose, step by step: the largest clearance within a
//! tolerance at the pose, the bounds of a clearance series, the largest clearance per
//! class of joints, and the designer's answer over the surface and the path.

use nalgebra::SVector;

use super::clearance::{fit_scale, scaled, ClearanceRequest, Prepared, SeriesPoint};
use super::clearance_class::{per_class, ClassClearance};
use super::clearance_path::{path_points, path_worst, PathReport};
use super::clearance_surface::{worst_of, SurfaceReport};
use crate::accuracy::clearance::surface::{hemisphere_sweep, Hemisphere};
use crate::accuracy::clearance::{self, ClearanceBounds, Region};
use crate::error::{Error, Result};
use crate::machine::Analysable;

/// The largest clearance within a tolerance: the factor on every clearance, and the
/// same as a uniform diametral clearance (mm) when every joint has one.
#[derive(Debug, Clone, Copy)]
pub(super) struct Largest {
    /// Factor on every clearance.
    pub(super) scale: Option<f64>,
    /// Uniform diametral clearance (mm).
    pub(super) mm: Option<f64>,
}

impl Largest {
    /// No answer (no tolerance).
    pub(super) const NONE: Largest = Largest {
        scale: None,
        mm: None,
    };
}

/// The designer's answer over everything: over the surface and the path when given
/// (the smaller of the two), else `at_pose`.
pub(super) fn overall_largest(
    at_pose: Largest,
    surface: Option<&SurfaceReport>,
    path: Option<&PathReport>,
) -> Largest {
    let wholes: Vec<Largest> = surface
        .iter()
        .map(|s| Largest {
            scale: s.largest_clearance_scale,
            mm: s.largest_clearance_mm,
        })
        .chain(path.iter().map(|p| Largest {
            scale: p.largest_clearance_scale,
            mm: p.largest_clearance_mm,
        }))
        .collect();
    if wholes.is_empty() {
        return at_pose;
    }
    wholes
        .into_iter()
        .min_by(|a, b| {
            a.scale
                .unwrap_or(f64::INFINITY)
                .total_cmp(&b.scale.unwrap_or(f64::INFINITY))
        })
        .unwrap_or(Largest::NONE)
}

/// A clearance analysis at pose `x` of `m`: the request, what was prepared, the
/// joints' clearance regions and their uniform diametral clearance, if any.
pub(super) struct Study<'a, M, const P: usize, const A: usize> {
    /// The machine.
    pub(super) m: &'a M,
    /// The pose.
    pub(super) x: &'a SVector<f64, P>,
    /// The request.
    pub(super) req: &'a ClearanceRequest,
    /// Joints, clearances, path samples.
    pub(super) prepared: &'a Prepared,
    /// The clearance regions of the joints.
    pub(super) regions: Vec<Region>,
    /// The diametral clearance every joint has, when they all have the same.
    pub(super) uniform: Option<f64>,
}

impl<M: Analysable<P, A>, const P: usize, const A: usize> Study<'_, M, P, A> {
    /// The largest clearance within tolerance `t` at the pose alone, from the bounds
    /// with the clearances as given.
    pub(super) fn largest_at_pose(&self, t: f64, bounds: &ClearanceBounds) -> Result<Largest> {
        let w1 = bounds.upper.max(-bounds.lower);
        if !(w1 > 0.0) {
            return Err(Error::InvalidInput {
                what: "clearance tolerance".into(),
                message: "the clearances cause no error along the direction at this pose: \
                          any clearance keeps it within the tolerance"
                    .into(),
            });
        }
        let s = fit_scale(t, w1, |s| {
            let (_, u, l) = clearance::bounds_along(
                self.m,
                self.x,
                &scaled(&self.regions, s)?,
                &self.req.options,
            )?;
            Ok(u.max(-l))
        })?;
        Ok(Largest {
            scale: Some(s),
            mm: self.uniform.map(|c| c * s),
        })
    }

    /// The bounds at the pose for each clearance of the request's series.
    pub(super) fn series(&self) -> Result<Vec<SeriesPoint>> {
        self.req
            .series
            .iter()
            .map(|&c| {
                let r: Vec<Region> = self
                    .regions
                    .iter()
                    .map(|r| Region::new(r.joint.clone(), r.clearance.with_diametral(c)))
                    .collect::<Result<_>>()?;
                let (_, upper, lower) =
                    clearance::bounds_along(self.m, self.x, &r, &self.req.options)?;
                Ok(SeriesPoint {
                    clearance_mm: c,
                    upper,
                    lower,
                })
            })
            .collect()
    }

    /// The largest clearance of each class of joints within tolerance `t`: over the
    /// `surface` and the `path` when given, else at the pose (`bounds`).
    pub(super) fn largest_per_class(
        &self,
        t: f64,
        bounds: &ClearanceBounds,
        surface: Option<&SurfaceReport>,
        path: Option<&PathReport>,
    ) -> Result<Vec<ClassClearance>> {
        // The worst error with the clearances as given is known already: over the
        // surface and the path when given, else at the pose.
        let sweep = surface
            .zip(self.req.surface.as_ref())
            .map(|(s, sr)| (s.hemisphere, sr.heights));
        let along_path =
            path.and_then(|p| p.worst.map(|i| p.points[i].upper.max(-p.points[i].lower)));
        let given = match (&sweep, &self.prepared.path) {
            (None, None) => bounds.upper.max(-bounds.lower),
            _ => surface
                .and_then(|s| s.worst)
                .unwrap_or(0.0)
                .max(along_path.unwrap_or(0.0)),
        };
        per_class(&self.regions, t, given, |r: &[Region]| {
            self.worst_with(r, sweep.as_ref())
        })
    }

    /// The worst error along the direction with regions `r`: over the surface swept
    /// by `sweep` (hemisphere, heights) and the path when given, else at the pose.
    fn worst_with(&self, r: &[Region], sweep: Option<&(Hemisphere, usize)>) -> Result<f64> {
        let (m, options) = (self.m, &self.req.options);
        let mut w = None::<f64>;
        if let Some((h, n)) = sweep {
            let points = hemisphere_sweep(m, h, r, options, *n)?;
            w = Some(worst_of(&points).map_or(0.0, |v| v.1));
        }
        if let Some((samples, _)) = &self.prepared.path {
            let pts = path_points(m, samples, r, options)?;
            let p = path_worst(&pts).map_or(0.0, |v| v.1);
            w = Some(w.map_or(p, |w| w.max(p)));
        }
        match w {
            Some(w) => Ok(w),
            None => {
                let (_, u, l) = clearance::bounds_along(m, self.x, r, options)?;
                Ok(u.max(-l))
            }
        }
    }
}
