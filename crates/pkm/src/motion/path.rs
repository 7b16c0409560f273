//! Path segments in a mechanism's pose coordinates: lines, circular arcs and helices.
//!
//! A segment is parametrised by its path parameter `s` in `[0, length]`: the tool-tip
//! distance (mm) for spatial machines; for a pure reorientation, or a machine with its
//! own coordinates, the Euclidean change of the coordinates in user units (mm, deg), as
//! CNC controllers feed rotary-only moves in deg/min. [`Segment::eval`] gives the pose
//! coordinates and their first and second derivatives with respect to `s`, exactly.

use nalgebra::{SVector, Vector3};

use crate::error::{Error, Result};
use crate::units::Quantity;

/// Geometry of a segment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Straight line (in every coordinate).
    Line,
    /// Circular arc or helix of the tool tip: centre, in-plane unit axes `e1`, `e2`
    /// (normal `e1 x e2`), radius, signed sweep (rad, positive counter-clockwise about
    /// the normal) and start angle; the normal coordinate changes linearly (helix).
    Arc {
        /// Centre in the start plane (mm).
        centre: Vector3<f64>,
        /// First in-plane axis.
        e1: Vector3<f64>,
        /// Second in-plane axis.
        e2: Vector3<f64>,
        /// Radius (mm).
        radius: f64,
        /// Start angle from `e1` towards `e2` (rad).
        start_angle: f64,
        /// Signed sweep (rad).
        sweep: f64,
        /// Travel along the normal over the whole arc (mm): a helix when non-zero.
        lead: f64,
    },
}

/// One segment from `start` to `end` in pose coordinates (internal units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment<const P: usize> {
    /// Start pose coordinates.
    pub start: SVector<f64, P>,
    /// End pose coordinates.
    pub end: SVector<f64, P>,
    /// Geometry.
    pub shape: Shape,
    /// Path length (mm, or deg for a reorientation).
    pub length: f64,
}

/// Shortest straight move (mm, or deg for a reorientation): below it a change is
/// rounding, not motion. A pose computed by forward kinematics (a robot's home pose)
/// carries errors of about 1e-14 mm and 1e-27 rad; a program's first line moving "to"
/// it would otherwise be a move of that length at the programmed feed, and the tiny
/// tip or angle change scaled by the feed over a near-zero length gave rates of
/// 1e12 mm/s. 1e-6 mm (a nanometre) and 1e-6 deg are far below what a controller
/// resolves (1e-4 mm and 1e-4 deg in a metric program).
pub const MIN_MOVE: f64 = 1e-6;

/// Length of a straight move: tool-tip distance for spatial coordinates (the first
/// three are X, Y, Z) when the tip moves at least [`MIN_MOVE`], else the largest
/// rotary change in deg when that is at least [`MIN_MOVE`]; for a machine's own
/// coordinates their Euclidean change in user units. Zero (no motion) below.
fn line_length<const P: usize>(
    start: &SVector<f64, P>,
    end: &SVector<f64, P>,
    quantities: &[Quantity; P],
    spatial: bool,
) -> f64 {
    let d = end - start;
    let l = if spatial {
        let l = d.fixed_rows::<3>(0).norm();
        if l >= MIN_MOVE {
            return l;
        }
        (3..P)
            .map(|k| quantities[k].to_user(d[k]).abs())
            .fold(0.0, f64::max)
    } else {
        (0..P)
            .map(|k| quantities[k].to_user(d[k]).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    if l >= MIN_MOVE {
        l
    } else {
        0.0
    }
}

impl<const P: usize> Segment<P> {
    /// A straight segment.
    pub fn line(
        start: SVector<f64, P>,
        end: SVector<f64, P>,
        quantities: &[Quantity; P],
        spatial: bool,
    ) -> Self {
        let length = line_length(&start, &end, quantities, spatial);
        Segment {
            start,
            end,
            shape: Shape::Line,
            length,
        }
    }

    /// An arc (or helix) of the tool tip around `centre` in the plane spanned by the
    /// unit vectors `e1`, `e2` (orthogonal), from `start` to `end` with the signed
    /// `sweep` (rad). The start and end must lie at the same radius within 1e-3 mm
    /// (after removing the helix travel); the other coordinates change linearly.
    pub fn arc(
        start: SVector<f64, P>,
        end: SVector<f64, P>,
        centre: Vector3<f64>,
        e1: Vector3<f64>,
        e2: Vector3<f64>,
        sweep: f64,
    ) -> Result<Self> {
        if P < 3 {
            return Err(Error::InvalidInput {
                what: "arc".into(),
                message: "arcs need X, Y, Z coordinates".into(),
            });
        }
        let n = e1.cross(&e2);
        let p0: Vector3<f64> = start.fixed_rows::<3>(0).into_owned();
        let p1: Vector3<f64> = end.fixed_rows::<3>(0).into_owned();
        let r0 = p0 - centre;
        let r1 = p1 - centre;
        let lead = (p1 - p0).dot(&n);
        let (u0, u1) = (r0 - n * r0.dot(&n), r1 - n * r1.dot(&n));
        let radius = u0.norm();
        if !(radius > 1e-9) || (u1.norm() - radius).abs() > 1e-3 * radius.max(1.0) {
            return Err(Error::InvalidInput {
                what: "arc".into(),
                message: format!(
                    "start and end are not on one circle about the centre (radii {:.4} and {:.4} mm)",
                    radius,
                    u1.norm()
                ),
            });
        }
        let start_angle = u0.dot(&e2).atan2(u0.dot(&e1));
        let length = (radius * sweep).hypot(lead);
        // Re-centre so that the start plane passes through the start point.
        let centre = centre + n * r0.dot(&n);
        Ok(Segment {
            start,
            end,
            shape: Shape::Arc {
                centre,
                e1,
                e2,
                radius,
                start_angle,
                sweep,
                lead,
            },
            length,
        })
    }

    /// Pose coordinates and their first and second derivatives with respect to the path
    /// parameter `s` (exact).
    #[inline(always)]
    pub fn eval(&self, s: f64) -> (SVector<f64, P>, SVector<f64, P>, SVector<f64, P>) {
        if !(self.length > 0.0) {
            return (self.start, SVector::zeros(), SVector::zeros());
        }
        let u = s / self.length;
        let d1 = (self.end - self.start) / self.length;
        let mut x = self.start + (self.end - self.start) * u;
        let mut xd = d1;
        let mut xdd = SVector::<f64, P>::zeros();
        if let Shape::Arc {
            centre,
            e1,
            e2,
            radius,
            start_angle,
            sweep,
            lead,
        } = self.shape
        {
            let n = e1.cross(&e2);
            let w = sweep / self.length; // dphi/ds
            let phi = start_angle + w * s;
            let (sp, cp) = phi.sin_cos();
            let radial = e1 * cp + e2 * sp;
            let tangent = e2 * cp - e1 * sp;
            let p = centre + radial * radius + n * (lead * u);
            let pd = tangent * (radius * w) + n * (lead / self.length);
            let pdd = -radial * (radius * w * w);
            for k in 0..3 {
                x[k] = p[k];
                xd[k] = pd[k];
                xdd[k] = pdd[k];
            }
        }
        (x, xd, xdd)
    }
}
