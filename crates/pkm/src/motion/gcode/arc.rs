//! Arcs of the interpreter (G2, G3): the centre from I, J, K or the radius R, full
//! circles and P turns, helical arcs, in the selected plane.

use nalgebra::Vector3;

use super::{err, Interpreter, Motion, Plane, TWO_PI};
use crate::error::Result;

impl Interpreter {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn arc(
        &self,
        ccw: bool,
        start: &[f64; 6],
        end: &[f64; 6],
        ijk: [Option<f64>; 3],
        r: Option<f64>,
        p: Option<f64>,
        line: u64,
    ) -> Result<Motion> {
        let (i1, i2, _) = self.plane.axes();
        let (a0, b0) = (start[i1], start[i2]);
        let (a1, b1) = (end[i1], end[i2]);
        let turns = match p {
            None => 0.0,
            Some(v) if v >= 1.0 && v.fract() == 0.0 => v - 1.0,
            Some(v) => {
                return Err(err(
                    line,
                    format!("P{v}: expected a whole number of turns >= 1"),
                ))
            }
        };
        let (ca, cb) = if let Some(rad) = r {
            if ijk.iter().any(Option::is_some) {
                return Err(err(line, "give either R or I, J, K, not both".into()));
            }
            let (dx, dy) = (a1 - a0, b1 - b0);
            let d = dx.hypot(dy);
            if d < 1e-9 {
                return Err(err(
                    line,
                    "an R arc cannot be a full circle: use I, J, K".into(),
                ));
            }
            let h2 = rad * rad - d * d / 4.0;
            if h2 < -1e-6 * rad * rad {
                return Err(err(
                    line,
                    format!("R{rad}: the end point is {d:.4} mm away, more than the diameter"),
                ));
            }
            let h = h2.max(0.0).sqrt();
            // Left of the chord for G3 with R > 0; the other side for G2 or R < 0.
            let side = if ccw == (rad > 0.0) { 1.0 } else { -1.0 };
            let (mx, my) = ((a0 + a1) / 2.0, (b0 + b1) / 2.0);
            (mx - side * h * dy / d, my + side * h * dx / d)
        } else {
            let idx = |axis: usize| match axis {
                0 => ijk[0],
                1 => ijk[1],
                _ => ijk[2],
            };
            let (oa, ob) = (idx(i1), idx(i2));
            if oa.is_none() && ob.is_none() {
                return Err(err(
                    line,
                    "arc without a centre: give I, J, K (in the active plane) or R".into(),
                ));
            }
            let (oa, ob) = (oa.unwrap_or(0.0), ob.unwrap_or(0.0));
            if self.arc_absolute {
                (oa, ob)
            } else {
                (a0 + oa, b0 + ob)
            }
        };
        let r0 = (a0 - ca).hypot(b0 - cb);
        let r1 = (a1 - ca).hypot(b1 - cb);
        if r0 < 1e-9 {
            return Err(err(line, "the arc centre is the start point".into()));
        }
        if (r0 - r1).abs() > 0.002_f64.max(1e-6 * r0) {
            return Err(err(
                line,
                format!("radius to start {r0:.4} mm differs from radius to end {r1:.4} mm"),
            ));
        }
        let t0 = (b0 - cb).atan2(a0 - ca);
        let t1 = (b1 - cb).atan2(a1 - ca);
        let mut sweep = (t1 - t0).rem_euclid(TWO_PI);
        if ccw {
            if sweep < 1e-12 {
                sweep = TWO_PI;
            }
        } else {
            sweep = -((TWO_PI - sweep) % TWO_PI);
            if sweep > -1e-12 {
                sweep = -TWO_PI;
            }
        }
        sweep += turns * TWO_PI * sweep.signum();
        let mut centre = Vector3::new(start[0], start[1], start[2]);
        centre[i1] = ca;
        centre[i2] = cb;
        Ok(Motion::Arc {
            centre,
            plane: self.plane,
            sweep,
        })
    }
}

/// In-plane unit axes `(e1, e2)` of a plane.
pub fn plane_axes(plane: Plane) -> (Vector3<f64>, Vector3<f64>) {
    let (i1, i2, _) = plane.axes();
    let mut e1 = Vector3::zeros();
    let mut e2 = Vector3::zeros();
    e1[i1] = 1.0;
    e2[i2] = 1.0;
    (e1, e2)
}
