//! Clearance bounds over a part surface (seed 002's Figs. 4 and 5): at each point of
//! the surface the tool is placed on it with its axis along the surface normal, and the
//! error is bounded along that normal (the shaping error).

use nalgebra::{SVector, UnitQuaternion, Vector3};
use rayon::prelude::*;
use serde::Serialize;

use super::{bounds_along, ClearanceOptions, Region};
use crate::accuracy::Parametric;
use crate::error::{Error, Result};
use crate::pose::Pose;

/// A hemisphere of radius `radius` (mm) whose centre is `centre` (base or workpiece
/// frame, mm), parametrised by the height `z` of its point above the equator (seed 002's
/// example part, `r(z) = c + (sqrt(R^2 - z^2) cos(phi), sqrt(R^2 - z^2) sin(phi), z)` at
/// azimuth `phi`), outward normal `(r - c) / R`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Hemisphere {
    /// Radius `R` (mm).
    pub radius: f64,
    /// Centre (mm).
    pub centre: [f64; 3],
    /// Azimuth `phi` of the meridian swept (rad).
    pub azimuth: f64,
}

impl Hemisphere {
    /// Checks the values.
    pub fn validate(&self) -> Result<()> {
        let finite = self
            .centre
            .iter()
            .chain([&self.azimuth])
            .all(|v| v.is_finite());
        if !(self.radius > 0.0 && self.radius.is_finite() && finite) {
            return Err(Error::InvalidInput {
                what: "hemisphere".into(),
                message: format!(
                    "expected a radius > 0 mm and a finite centre and azimuth, found R = {}, \
                     centre {:?}, azimuth {}",
                    self.radius, self.centre, self.azimuth
                ),
            });
        }
        Ok(())
    }

    /// The point and outward unit normal at height `z` (`0 <= z <= R`).
    pub fn at(&self, z: f64) -> (Vector3<f64>, Vector3<f64>) {
        let rho = (self.radius * self.radius - z * z).max(0.0).sqrt();
        let (s, c) = self.azimuth.sin_cos();
        let n = Vector3::new(rho * c, rho * s, z) / self.radius;
        (Vector3::from(self.centre) + n * self.radius, n)
    }
}

/// The bounds at one point of the surface (mm); `None` where the machine cannot place
/// its tool there (`unreachable` says why).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SurfacePoint {
    /// Height above the equator (mm).
    pub z: f64,
    /// The point (mm).
    pub point: [f64; 3],
    /// The outward normal: the direction of the bounds.
    pub normal: [f64; 3],
    /// Largest error along the normal.
    pub upper: Option<f64>,
    /// Smallest error along the normal.
    pub lower: Option<f64>,
    /// Why the tool cannot be placed there (a pose the machine cannot take, a violated
    /// limit).
    pub unreachable: Option<String>,
}

/// The tool pose on the surface at `point` with normal `n`: the machine's `home` tool
/// orientation turned by the rotation that takes the pole's normal (+Z) to `n`, so a
/// tool normal to the surface at the pole stays normal to it everywhere.
pub fn pose_on_surface(home: &Pose, point: &Vector3<f64>, n: &Vector3<f64>) -> Pose {
    let turn = UnitQuaternion::rotation_between(&Vector3::z(), n).unwrap_or_else(|| {
        // n = -Z: half a turn about X.
        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI)
    });
    Pose::from_parts((*point).into(), turn * home.rotation)
}

/// Checks a number of heights of a sweep: 2 to 100000.
pub fn check_heights(heights: usize) -> Result<()> {
    if !(2..=100_000).contains(&heights) {
        return Err(Error::InvalidInput {
            what: "surface heights".into(),
            message: format!("expected 2 to 100000 heights, got {heights}"),
        });
    }
    Ok(())
}

/// Bounds along the normal at `heights` heights from `z = 0` (the equator) to `z = R`,
/// each point solved independently (rayon).
pub fn hemisphere_sweep<M, const P: usize, const A: usize>(
    m: &M,
    surface: &Hemisphere,
    regions: &[Region],
    options: &ClearanceOptions,
    heights: usize,
) -> Result<Vec<SurfacePoint>>
where
    M: Parametric<P, A>,
{
    surface.validate()?;
    check_heights(heights)?;
    let home = m.tool_pose(&m.info().home())?;
    (0..heights)
        .into_par_iter()
        .map(|i| {
            let z = surface.radius * i as f64 / (heights - 1) as f64;
            let (p, n) = surface.at(z);
            let mut row = SurfacePoint {
                z,
                point: p.into(),
                normal: n.into(),
                upper: None,
                lower: None,
                unreachable: None,
            };
            match place(m, &home, &p, &n) {
                Err(e) => row.unreachable = Some(e.to_string()),
                Ok(x) => {
                    let (_, upper, lower) = bounds_along(
                        m,
                        &x,
                        regions,
                        &ClearanceOptions {
                            direction: Some(n),
                            ..*options
                        },
                    )?;
                    (row.upper, row.lower) = (Some(upper), Some(lower));
                }
            }
            Ok(row)
        })
        .collect()
}

/// The pose coordinates with the tool at `p` along `n`, or why the machine cannot take
/// that pose (no such coordinates, or a violated limit).
fn place<M, const P: usize, const A: usize>(
    m: &M,
    home: &Pose,
    p: &Vector3<f64>,
    n: &Vector3<f64>,
) -> Result<SVector<f64, P>>
where
    M: Parametric<P, A>,
{
    let want = pose_on_surface(home, p, n);
    let x = m.coords_from_pose(&want, true)?;
    // A machine with fewer freedoms takes the nearest pose it has: it must be this one.
    let got = m.tool_pose(&x)?;
    let (dp, dr) = (
        (got.translation.vector - want.translation.vector).norm(),
        got.rotation.angle_to(&want.rotation),
    );
    if dp > 1e-6 || dr > 1e-9 {
        return Err(Error::InvalidInput {
            what: "surface point".into(),
            message: format!(
                "the machine cannot put its tool there along the normal (off by {dp:.3e} mm, \
                 {:.3e} deg)",
                dr.to_degrees()
            ),
        });
    }
    let q = m.inverse(&x)?;
    let mut v = Vec::new();
    m.check_limits(&x, &q, &mut v);
    match v.first() {
        Some(first) => Err(Error::InvalidInput {
            what: "surface point".into(),
            message: format!("limit violated: {first}"),
        }),
        None => Ok(x),
    }
}
