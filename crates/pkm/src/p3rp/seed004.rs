//! What seed 004 reports about its head, reproduced from a head's model: the slider
//! ranges of fig. 4, the slider separations they imply, the singular configuration Q
//! outside the working range, and the slider V peaks of the fig. 7 move.

use nalgebra::Vector2;
use serde::Serialize;

use super::P3rpHead;
use crate::error::Result;
use crate::mechanism::Mechanism;
use crate::motion::{Move, Profile, Runner, Sampling, Segment};
use crate::units::Quantity;

/// One reported number (or range) beside pkm's value.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Reproduced {
    /// What it is.
    pub quantity: String,
    /// The paper's value(s).
    pub paper: Vec<f64>,
    /// pkm's value(s).
    pub pkm: Vec<f64>,
    /// Unit of both.
    pub unit: &'static str,
    /// Largest relative deviation pkm / paper - 1 (absolute value).
    pub deviation: f64,
    /// Remarks.
    pub note: Option<String>,
}

fn row(
    quantity: &str,
    paper: Vec<f64>,
    pkm: Vec<f64>,
    unit: &'static str,
    note: Option<&str>,
) -> Reproduced {
    let deviation = paper
        .iter()
        .zip(&pkm)
        .map(|(a, b)| (b / a - 1.0).abs())
        .fold(0.0, f64::max);
    Reproduced {
        quantity: quantity.into(),
        paper,
        pkm,
        unit,
        deviation,
        note: note.map(str::to_string),
    }
}

/// The range of z over which pose `(z, theta)` is within every limit, scanning `z`
/// across the U stroke (widened by 50 mm) in steps of `step` mm; `None` when empty.
pub fn z_range(h: &P3rpHead, theta: f64, step: f64) -> Option<[f64; 2]> {
    let r = h.info().actuators()[0].range;
    let n = ((r.max - r.min + 100.0) / step).ceil() as usize;
    let mut v = Vec::new();
    let (mut lo, mut hi) = (f64::NAN, f64::NAN);
    for k in 0..=n {
        let z = r.min - 50.0 + k as f64 * step;
        let x = Vector2::new(z, theta);
        let Ok(q) = h.inverse(&x) else { continue };
        v.clear();
        h.check_limits(&x, &q, &mut v);
        if v.is_empty() {
            if lo.is_nan() {
                lo = z;
            }
            hi = z;
        }
    }
    (!lo.is_nan()).then_some([lo, hi])
}

/// The deflection of the singular configuration Q (rod stretched along the crank)
/// beyond `from` rad, by bisection on the transmission angle; `None` if none up to pi.
pub fn singular_theta(h: &P3rpHead, from: f64) -> Option<f64> {
    let g = &h.geometry();
    let f = |t: f64| g.transmission_angle(t).ok();
    let (mut a, mut b) = (from, std::f64::consts::PI);
    let fa = f(a)?;
    let fb = f(b)?;
    if fa * fb > 0.0 {
        return None;
    }
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        let fm = f(m)?;
        if fm * fa > 0.0 {
            a = m;
        } else {
            b = m;
        }
    }
    Some(0.5 * (a + b))
}

/// Slider peaks of the paper's move: `(z, theta)` from (200 mm, 0) to (335 mm,
/// 0.9 rad) in 1 s with 0.1 s ramps, sampled at 1 kHz: `[U, V]` as
/// (peak velocity, peak acceleration).
pub fn fig7_peaks(h: &P3rpHead) -> Result<[(f64, f64); 2]> {
    let seg = Segment::line(
        Vector2::new(200.0, 0.0),
        Vector2::new(335.0, 0.9),
        &[Quantity::Length, Quantity::Angle],
        false,
    );
    let mv = Move {
        profile: Profile::trapezoid_timed(seg.length, 1.0, 0.1)?,
        segment: seg,
        line: None,
        rapid: false,
    };
    let mut r = Runner::new(h, Sampling::Rate(1000.0))?;
    r.run_move(&mv, true, &mut |_| Ok(()))?;
    let s = r.finish();
    let p = |i: usize| {
        (
            s.actuators[i].1.peak_velocity,
            s.actuators[i].1.peak_acceleration,
        )
    };
    Ok([p(0), p(1)])
}

/// Every number seed 004 reports, beside the model's.
pub fn reproduction(h: &P3rpHead) -> Result<Vec<Reproduced>> {
    let mut out = Vec::new();
    slider_ranges(h, &mut out)?;
    fig7_rows(h, &mut out)?;
    if let Some(q) = singular_theta(h, T157) {
        out.push(Reproduced {
            quantity: "singular configuration Q (A, B, C collinear) \"outside the working range\""
                .into(),
            paper: Vec::new(),
            pkm: vec![q.to_degrees()],
            unit: "deg",
            deviation: 0.0,
            note: Some(format!(
                "theta_Q = {:.4} rad, beyond the design range [0, 1.57] rad",
                q
            )),
        });
    }
    Ok(out)
}

/// The end of seed 004's design range of theta (rad).
const T157: f64 = 1.57;

/// The slider ranges of fig. 4 and the slider separations they give.
fn slider_ranges(h: &P3rpHead, out: &mut Vec<Reproduced>) -> Result<()> {
    for (theta, label, d_paper, e_paper, note) in [
        (0.0, "theta = 0", [200.0, 518.5], [506.5, 825.0], None),
        (
            T157,
            "theta = 1.57 rad",
            [200.0, 365.0],
            [600.0, 825.0],
            Some(
                "The paper prints E over [600, 825] at 1.57 rad; with D at 200 mm and \
                 g(1.57) = 825 - 365 = 460 mm, E starts at 660 mm: 600 is a plot reading \
                 that does not fit the D range.",
            ),
        ),
    ] {
        let Some(d) = z_range(h, theta, 0.01) else {
            continue;
        };
        let g = h.geometry().separation(theta)?.g;
        out.push(row(
            &format!("slider D range at {label} (fig. 4)"),
            d_paper.to_vec(),
            d.to_vec(),
            "mm",
            None,
        ));
        out.push(row(
            &format!("slider E range at {label} (fig. 4)"),
            e_paper.to_vec(),
            vec![d[0] + g, d[1] + g],
            "mm",
            note,
        ));
    }
    for (theta, paper, label) in [(0.0, 306.5, "0"), (T157, 460.0, "1.57 rad")] {
        out.push(row(
            &format!("slider separation g({label}) = z2 - z1"),
            vec![paper],
            vec![h.geometry().separation(theta)?.g],
            "mm",
            Some("From the fig. 4 ranges (E - D at either end)."),
        ));
    }
    Ok(())
}

/// The slider peaks of the fig. 7 move.
fn fig7_rows(h: &P3rpHead, out: &mut Vec<Reproduced>) -> Result<()> {
    let [u, v] = fig7_peaks(h)?;
    out.push(row(
        "slider V peak velocity in the fig. 7 move",
        vec![260.0],
        vec![v.0],
        "mm/s",
        Some("0.26 m/s: (200 mm, 0) to (335 mm, 0.9 rad) in 1 s, 0.1 s ramps, 1 kHz."),
    ));
    out.push(row(
        "slider V peak acceleration in the fig. 7 move",
        vec![2600.0],
        vec![v.1],
        "mm/s^2",
        Some("2.6 m/s^2, same move."),
    ));
    out.push(Reproduced {
        quantity: "slider D in the fig. 7 move (\"moves smoothly\"): peak velocity, acceleration"
            .into(),
        paper: Vec::new(),
        pkm: vec![u.0, u.1],
        unit: "mm/s, mm/s^2",
        deviation: 0.0,
        note: Some("Not printed. D follows z: 135 mm over 0.9 s of cruise-equivalent time is 150 mm/s, reached in 0.1 s: 1 500 mm/s^2.".into()),
    });
    Ok(())
}
