//! Finds structural parameters of the seed-004 P3RP head that reproduce what the paper
//! reports (its parameter tables are lost; spec 05):
//!
//! * slider separation `g(0) = 306.5 mm` and `g(1.57 rad) = 460 mm` (fig. 4 ranges),
//! * slider V peaks of 0.26 m/s and 2.6 m/s^2 in the trapezoidal move from
//!   `(z, theta) = (200 mm, 0)` to `(335 mm, 0.9 rad)` in 1 s (0.1 s ramps; fig. 7).
//!
//! Four equations in the four unknowns `l1, l2, e, delta`, solved by
//! Levenberg-Marquardt (relative residuals, forward-difference Jacobian) from the
//! spec's rough values. The peaks are taken from the exact slider motion sampled at
//! 10 kHz. Run with `cargo run --release -p pkm --example fit_p3rp_seed004`; it prints
//! the fitted values and the `[head]` table of `examples/machines/p3rp-seed004.toml`.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{storage::Owned, Matrix4, Vector2, Vector4, U4};
use pkm::limits::Range;
use pkm::mechanism::{Actuator, Mechanism};
use pkm::p3rp::{Branch, HeadGeometry, P3rpHead};
use pkm::Quantity;

const TARGETS: [f64; 4] = [306.5, 460.0, 260.0, 2600.0];

fn head(p: &Vector4<f64>) -> P3rpHead {
    let g = HeadGeometry {
        l1: p[0],
        l2: p[1],
        e: p[2],
        delta: p[3],
        tool_length: 0.0,
        theta_range: None,
        rod_angle_range: None,
        min_transmission_angle: None,
        branch: Branch::Positive,
        offsets: Default::default(),
    };
    let slider = |n: &str| Actuator {
        name: n.into(),
        quantity: Quantity::Length,
        range: Range {
            min: -1e9,
            max: 1e9,
        },
        max_velocity: None,
        max_acceleration: None,
        stiffness: None,
    };
    P3rpHead::new(
        "fit".into(),
        g,
        [slider("U"), slider("V")],
        Vector2::new(200.0, 0.0),
    )
}

/// Largest |V'| and |V''| over the seed's trapezoidal move, sampled every `dt`.
fn peaks(h: &P3rpHead, dt: f64) -> Option<(f64, f64)> {
    let (ta, tt) = (0.1, 1.0);
    let vmax = 1.0 / (tt - ta);
    let amax = vmax / ta;
    let (mut pv, mut pa) = (0.0_f64, 0.0_f64);
    let n = (tt / dt).round() as usize;
    for i in 0..=n {
        let t = i as f64 * dt;
        // Normalised path s(t) in [0, 1]: ramp, cruise, ramp.
        let (s, sd, sdd) = if t < ta {
            (0.5 * amax * t * t, amax * t, amax)
        } else if t <= tt - ta {
            (0.5 * amax * ta * ta + vmax * (t - ta), vmax, 0.0)
        } else {
            let r = tt - t;
            (1.0 - 0.5 * amax * r * r, amax * r, -amax)
        };
        let span = Vector2::new(135.0, 0.9);
        let x = Vector2::new(200.0, 0.0) + span * s;
        let m = h.actuator_motion(&x, &(span * sd), &(span * sdd)).ok()?;
        pv = pv.max(m.qd[1].abs());
        pa = pa.max(m.qdd[1].abs());
    }
    Some((pv, pa))
}

fn values(p: &Vector4<f64>) -> Option<Vector4<f64>> {
    let h = head(p);
    let g0 = h.geometry().separation(0.0).ok()?.g;
    let g1 = h.geometry().separation(1.57).ok()?.g;
    let (v, a) = peaks(&h, 1e-4)?;
    Some(Vector4::new(g0, g1, v, a))
}

struct Fit {
    p: Vector4<f64>,
}

impl LeastSquaresProblem<f64, U4, U4> for Fit {
    type ResidualStorage = Owned<f64, U4>;
    type JacobianStorage = Owned<f64, U4, U4>;
    type ParameterStorage = Owned<f64, U4>;

    fn set_params(&mut self, p: &Vector4<f64>) {
        self.p = *p;
    }

    fn params(&self) -> Vector4<f64> {
        self.p
    }

    fn residuals(&self) -> Option<Vector4<f64>> {
        let v = values(&self.p)?;
        Some(Vector4::from_fn(|i, _| v[i] / TARGETS[i] - 1.0))
    }

    fn jacobian(&self) -> Option<Matrix4<f64>> {
        let r0 = self.residuals()?;
        let mut j = Matrix4::zeros();
        for k in 0..4 {
            let h = 1e-6 * self.p[k].abs().max(1.0);
            let mut p = self.p;
            p[k] += h;
            let r = Fit { p }.residuals()?;
            j.set_column(k, &((r - r0) / h));
        }
        Some(j)
    }
}

fn main() {
    let start = Vector4::new(108.0, 377.0, 27.0, -2.24);
    let (fit, report) = LevenbergMarquardt::new().minimize(Fit { p: start });
    let p = fit.p;
    println!(
        "termination: {:?}, evaluations {}",
        report.termination, report.number_of_evaluations
    );
    println!(
        "l1 = {:.4} mm, l2 = {:.4} mm, e = {:.4} mm, delta = {:.6} rad = {:.4} deg",
        p[0],
        p[1],
        p[2],
        p[3],
        p[3].to_degrees()
    );
    // Round to what a drawing would carry and check the rounded set.
    let rounded = Vector4::new(
        (p[0] * 10.0).round() / 10.0,
        (p[1] * 10.0).round() / 10.0,
        (p[2] * 10.0).round() / 10.0,
        (p[3].to_degrees() * 100.0).round().to_radians() / 100.0,
    );
    for (what, q) in [("fitted", p), ("rounded", rounded)] {
        let v = values(&q).expect("the fitted head moves");
        println!(
            "{what:8} g(0) = {:.3} mm, g(1.57) = {:.3} mm, peak V' = {:.2} mm/s, peak V'' = {:.1} mm/s^2",
            v[0], v[1], v[2], v[3]
        );
    }
    println!(
        "\n[head]\nl1 = {:.1}\nl2 = {:.1}\ne = {:.1}\ndelta = {:.2}",
        rounded[0],
        rounded[1],
        rounded[2],
        rounded[3].to_degrees()
    );
}
