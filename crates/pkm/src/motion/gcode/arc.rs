//! Arcs of the interpreter (G2, G3): the centre from I, J, K or the radius R, full
//! circles and P turns, helical arcs, in the selected plane.

use nalgebra::Vector3;

use super::{err, Interpreter, Motion, Plane, TWO_PI};
use crate::error::Result;

impl Interpreter {
    /// The motion of a G2 (`ccw` false) or G3 arc from `start` to `end` with the
    /// line's I, J, K (`ijk`), R (`r`) and P (`p`: turns) in the active plane.
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
        let turns = arc_turns(p, line)?;
        let (ca, cb) = match r {
            Some(rad) => centre_from_radius(rad, ijk, ccw, [a0, b0], [a1, b1], line)?,
            None => self.centre_from_offsets(ijk, [a0, b0], line)?,
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
        let sweep = arc_sweep(ccw, t0, t1, turns);
        let mut centre = Vector3::new(start[0], start[1], start[2]);
        centre[i1] = ca;
        centre[i2] = cb;
        Ok(Motion::Arc {
            centre,
            plane: self.plane,
            sweep,
        })
    }

    /// The centre (in-plane coordinates) of an arc from `start` given by its I, J, K
    /// words `ijk`: offsets from the start (G91.1) or the centre itself (G90.1).
    fn centre_from_offsets(
        &self,
        ijk: [Option<f64>; 3],
        start: [f64; 2],
        line: u64,
    ) -> Result<(f64, f64)> {
        let (i1, i2, _) = self.plane.axes();
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
        Ok(if self.arc_absolute {
            (oa, ob)
        } else {
            (start[0] + oa, start[1] + ob)
        })
    }
}

/// The whole turns an arc makes besides its sweep, from its P word (`None`: none).
fn arc_turns(p: Option<f64>, line: u64) -> Result<f64> {
    match p {
        None => Ok(0.0),
        Some(v) if v >= 1.0 && v.fract() == 0.0 => Ok(v - 1.0),
        Some(v) => Err(err(
            line,
            format!("P{v}: expected a whole number of turns >= 1"),
        )),
    }
}

/// The centre (in-plane coordinates) of an arc of radius `rad` (R word; negative:
/// the longer way) from `start` to `end`, G3 when `ccw`; `ijk` must be empty.
fn centre_from_radius(
    rad: f64,
    ijk: [Option<f64>; 3],
    ccw: bool,
    start: [f64; 2],
    end: [f64; 2],
    line: u64,
) -> Result<(f64, f64)> {
    let ([a0, b0], [a1, b1]) = (start, end);
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
    Ok((mx - side * h * dy / d, my + side * h * dx / d))
}

/// The signed sweep (rad; positive = G3, `ccw`) from angle `t0` to `t1` about the
/// centre, plus `turns` whole turns; a full circle when the two coincide.
fn arc_sweep(ccw: bool, t0: f64, t1: f64, turns: f64) -> f64 {
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
    sweep + turns * TWO_PI * sweep.signum()
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
