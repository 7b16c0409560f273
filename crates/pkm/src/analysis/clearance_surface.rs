//! Clearance bounds over a part surface in the analysis layer (seed 002's Fig. 4): the
//! sweep of a hemisphere and the largest clearance that keeps the whole surface within
//! a tolerance.

use serde::Serialize;

use super::clearance::{fit_scale, scaled, ClearanceRequest};
use crate::accuracy::clearance::surface::{hemisphere_sweep, Hemisphere, SurfacePoint};
use crate::accuracy::clearance::Region;
use crate::error::Result;
use crate::machine::Analysable;

/// A hemisphere to sweep (seed 002's Figs. 4 and 5).
///
/// # Examples
///
/// Seed 002's part: a hemisphere of radius 75 mm whose pole is at the home tool point,
/// five heights along one meridian, the nozzle normal to it.
///
/// ```
/// use pkm::analysis::clearance::{clearance, ClearanceRequest, SurfaceRequest};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hybrid-am-seed002.toml"
/// ))
/// .unwrap();
/// let surface = SurfaceRequest { radius: 75.0, centre: None, azimuth: 0.0, heights: 5 };
/// let req = ClearanceRequest {
///     surface: Some(surface),
///     tolerance: Some(0.05),
///     ..Default::default()
/// };
/// let r = clearance(&machine, None, &req).unwrap();
/// let s = r.surface.unwrap();
/// assert_eq!(s.points.len(), 5);
/// assert_eq!(s.unreachable, 0);
/// assert!(s.worst.unwrap() > 0.0 && s.largest_clearance_scale.unwrap() > 0.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceRequest {
    /// Radius (mm).
    pub radius: f64,
    /// Centre (mm); `None`: `R` below the home tool point (the pole there).
    pub centre: Option<[f64; 3]>,
    /// Azimuth of the meridian (rad).
    pub azimuth: f64,
    /// Heights from the equator to the pole (2 to 100000).
    pub heights: usize,
}

/// The bounds over a surface.
///
/// # Examples
///
/// See [`SurfaceRequest`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SurfaceReport {
    /// The surface.
    pub hemisphere: Hemisphere,
    /// Every height.
    pub points: Vec<SurfacePoint>,
    /// Heights the tool cannot reach along the normal.
    pub unreachable: usize,
    /// Height of the largest `max(upper, -lower)`.
    pub worst_z: Option<f64>,
    /// That largest value (mm).
    pub worst: Option<f64>,
    /// The factor on every clearance that keeps every reachable height within the
    /// tolerance.
    pub largest_clearance_scale: Option<f64>,
    /// The same as a uniform diametral clearance (mm).
    pub largest_clearance_mm: Option<f64>,
}

/// The largest `max(upper, -lower)` over the reachable points and its height.
pub(crate) fn worst_of(points: &[SurfacePoint]) -> Option<(f64, f64)> {
    points
        .iter()
        .filter_map(|p| Some((p.z, p.upper?.max(-p.lower?))))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// The sweep of `sr`, and with a tolerance the factor on the clearances that keeps the
/// whole surface within it (`s <- s t / worst(s)` on exact sweeps, to 1e-9).
pub(crate) fn surface_report<M, const P: usize, const A: usize>(
    m: &M,
    regions: &[Region],
    req: &ClearanceRequest,
    sr: &SurfaceRequest,
    uniform: Option<f64>,
) -> Result<SurfaceReport>
where
    M: Analysable<P, A>,
{
    let hemisphere = hemisphere_of(m, sr)?;
    let points = hemisphere_sweep(m, &hemisphere, regions, &req.options, sr.heights)?;
    let worst = worst_of(&points);
    let scale = match (req.tolerance, worst) {
        (Some(t), Some((_, w))) if w > 0.0 => Some(fit_scale(t, w, |s| {
            let sweep = hemisphere_sweep(
                m,
                &hemisphere,
                &scaled(regions, s)?,
                &req.options,
                sr.heights,
            )?;
            Ok(worst_of(&sweep).map_or(0.0, |v| v.1))
        })?),
        _ => None,
    };
    Ok(SurfaceReport {
        hemisphere,
        unreachable: points.iter().filter(|p| p.unreachable.is_some()).count(),
        worst_z: worst.map(|w| w.0),
        worst: worst.map(|w| w.1),
        largest_clearance_scale: scale,
        largest_clearance_mm: scale.zip(uniform).map(|(s, c)| s * c),
        points,
    })
}

/// The hemisphere of `sr` on `m`: its centre `R` below the home tool point unless given.
fn hemisphere_of<M, const P: usize, const A: usize>(
    m: &M,
    sr: &SurfaceRequest,
) -> Result<Hemisphere>
where
    M: Analysable<P, A>,
{
    let centre = match sr.centre {
        Some(c) => c,
        None => {
            let p = m.tool_pose(&m.info().home())?.translation.vector;
            [p.x, p.y, p.z - sr.radius]
        }
    };
    Ok(Hemisphere {
        radius: sr.radius,
        centre,
        azimuth: sr.azimuth,
    })
}
