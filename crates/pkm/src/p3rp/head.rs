//! The P3RP head alone: pose `(z, theta)`, actuators `U` (slider D) and `V` (slider E).

use std::f64::consts::PI;

use nalgebra::{Matrix2, Vector2, Vector3};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::limits::{LimitKind, Range, Side, Violation};
use crate::mechanism::Actuator;
use crate::units::Quantity;

mod mechanism;
pub use mechanism::P3rpHead;
pub(crate) use mechanism::{head_motion, head_skeleton};

/// Assembly branch of the head: the side of the line A-C on which B lies, i.e. the
/// sign of the planar cross product `AB x AC` (Y, Z components).
///
/// Both branches meet where A, B and C are collinear (the singular configuration Q of
/// seed 004, the rod stretched along the crank, or folded back over it). The paper keeps
/// one branch with the rule "if theta <= -pi/2 correct it to pi + theta; if
/// -pi/2 < theta < 0 discard it"; that rule only makes sense for a formula that
/// determines theta modulo pi (its formula (11) is lost). pkm's closed form gives both
/// branches as exact angles and keeps the one the machine is assembled in;
/// `docs/seed-004.md` shows that over the design workspace this is the paper's branch
/// (theta in `[0, 1.57]` rad) and that the other branch lies at theta in
/// `[-pi, -1.98]` or `[2.80, pi]` rad, where the literal "pi + theta" correction would
/// return a pose that does not close the loop (tested).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Branch {
    /// `AB x AC > 0`: the paper's working branch for its parameters.
    Positive,
    /// `AB x AC < 0`.
    Negative,
}

impl Branch {
    fn sign(self) -> f64 {
        match self {
            Branch::Positive => 1.0,
            Branch::Negative => -1.0,
        }
    }
}

/// `g(theta) = z2 - z1` and its first two derivatives with respect to theta.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Separation {
    /// `g` (mm).
    pub g: f64,
    /// `g' = dg/dtheta` (mm/rad): the V-slider travel per radian of deflection.
    pub dg: f64,
    /// `g'' = d2g/dtheta2` (mm/rad^2).
    pub ddg: f64,
}

/// Where hinges A and C sit off their nominal places (mm, in their sliders' frames,
/// whose axes are the base frame's): what a joint's clearance moves that `l1`, `delta`
/// and `e` cannot express (hinge B's offset on the platform and hinge C's horizontal
/// one fold into those exactly). Zero on a head as its file builds it.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct HingeOffsets {
    /// Hinge A's horizontal offset from the guide line: the platform and tool move
    /// with it.
    pub a_y: f64,
    /// Hinge A's height above slider D's reading.
    pub a_z: f64,
    /// Hinge C's height above slider E's reading.
    pub c_z: f64,
}

/// Geometry and limits of a P3RP head (internal units: mm, rad).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeadGeometry {
    /// `l1 = |AB|`, crank of the swing platform (mm).
    pub l1: f64,
    /// `l2 = |BC|`, the rod (mm).
    pub l2: f64,
    /// Horizontal offset of hinge C from the guide line through A (mm).
    pub e: f64,
    /// `delta`: fixed angle from the platform axis t-A to AB; `psi = theta + delta` (rad).
    pub delta: f64,
    /// Distance from t (= A) along the spindle axis to the tool tip (mm).
    pub tool_length: f64,
    /// Range of the deflection theta allowed by hinge A (rad), if limited.
    pub theta_range: Option<Range>,
    /// Range of the rod angle phi (from the vertical through C to BC,
    /// counter-clockwise; rad), if limited. The paper states `0 <= phi < pi/2`.
    pub rod_angle_range: Option<Range>,
    /// Smallest transmission angle (rad) between crank AB and rod BC, if limited.
    pub min_transmission_angle: Option<f64>,
    /// The assembly branch of the machine.
    pub branch: Branch,
    /// Offsets of hinges A and C from their nominal places (joint clearances).
    pub offsets: HingeOffsets,
}

use crate::rotation::wrap_angle as wrap;

impl HeadGeometry {
    /// `s = e + l1 sin psi` (horizontal reach of the rod) and `h = sqrt(l2^2 - s^2)`
    /// (vertical rise from B to C); fails where the rod cannot reach the guide.
    #[inline]
    fn rod(&self, theta: f64) -> Result<(f64, f64, f64, f64)> {
        let (sp, cp) = (theta + self.delta).sin_cos();
        let s = self.e + self.l1 * sp;
        let h2 = self.l2 * self.l2 - s * s;
        if !(h2 > 0.0) {
            return Err(Error::NotAttainable {
                reason: format!(
                    "at theta = {:.4} deg the rod (l2 = {} mm) cannot reach hinge C: its \
                     horizontal span would be {:.4} mm",
                    theta.to_degrees(),
                    self.l2,
                    s.abs()
                )
                .into(),
            });
        }
        Ok((sp, cp, s, h2.sqrt()))
    }

    /// Slider separation `g(theta) = z2 - z1 = l1 cos psi + sqrt(l2^2 - (e + l1 sin psi)^2)`
    /// and its derivatives (seed 004 eqs. 7-10 reconstructed; spec 05):
    ///
    /// ```text
    /// g'  = -l1 sin psi - l1 s cos psi / h
    /// g'' = -l1 cos psi - l1 (l1 cos^2 psi - s sin psi) / h - l1^2 s^2 cos^2 psi / h^3
    /// ```
    ///
    /// with `s = e + l1 sin psi`, `h = sqrt(l2^2 - s^2)`.
    pub fn separation(&self, theta: f64) -> Result<Separation> {
        let (sp, cp, s, h) = self.rod(theta)?;
        let l1 = self.l1;
        Ok(Separation {
            g: l1 * cp + h,
            dg: -l1 * sp - l1 * s * cp / h,
            ddg: -l1 * cp
                - l1 * (l1 * cp * cp - s * sp) / h
                - l1 * l1 * s * s * cp * cp / h.powi(3),
        })
    }

    /// Inverse position solution: `(z1, z2) = (z, z + g(theta))` (less the hinges'
    /// heights above their sliders, [`HingeOffsets`]).
    pub fn inverse(&self, z: f64, theta: f64) -> Result<Vector2<f64>> {
        let sep = self.separation(theta)?;
        let o = &self.offsets;
        Ok(Vector2::new(z - o.a_z, z + sep.g - o.c_z))
    }

    /// Inverse Jacobian `J_t = d(z1, z2)/d(z, theta) = [[1, 0], [1, g'(theta)]]`
    /// (seed 004 eq. 13, by differentiating the constraint (7)).
    pub fn jacobian(&self, theta: f64) -> Result<Matrix2<f64>> {
        let sep = self.separation(theta)?;
        Ok(Matrix2::new(1.0, 0.0, 1.0, sep.dg))
    }

    /// Time derivative of [`HeadGeometry::jacobian`] for a deflection rate `theta_dot`:
    /// `J_t' = [[0, 0], [0, g''(theta) theta']]`, so that
    /// `(z1'', z2'') = J_t (z'', theta'') + J_t' (z', theta')`.
    pub fn jacobian_derivative(&self, theta: f64, theta_dot: f64) -> Result<Matrix2<f64>> {
        let sep = self.separation(theta)?;
        Ok(Matrix2::new(0.0, 0.0, 0.0, sep.ddg * theta_dot))
    }

    /// Rod angle phi: from the vertical through C counter-clockwise to BC (rad).
    pub fn rod_angle(&self, theta: f64) -> Result<f64> {
        let (_, _, s, h) = self.rod(theta)?;
        // BC = (s, h) in (Y, Z); Z turned counter-clockwise by phi is (-sin phi, cos phi).
        Ok((-s).atan2(h))
    }

    /// Signed transmission angle between the crank AB and the rod BC (rad): `asin` of
    /// `(AB x BC) / (l1 l2)`, positive on the [`Branch::Positive`] side. It is zero at
    /// the singular configuration Q (A, B, C collinear), where the V slider no longer
    /// moves the platform; its magnitude is the sine-measure of how far the head is
    /// from Q.
    pub fn transmission_angle(&self, theta: f64) -> Result<f64> {
        let (sp, cp, s, h) = self.rod(theta)?;
        // AB = l1 (-sin psi, cos psi), BC = (s, h).
        let cross = self.l1 * (-sp * h - cp * s);
        Ok((cross / (self.l1 * self.l2)).clamp(-1.0, 1.0).asin())
    }

    /// The branch a pose lies on.
    pub fn branch_of(&self, theta: f64) -> Result<Branch> {
        Ok(if self.transmission_angle(theta)? >= 0.0 {
            Branch::Positive
        } else {
            Branch::Negative
        })
    }

    /// Forward position solution on one branch: `z = z1` and theta from
    /// `e sin psi - d cos psi = (l2^2 - l1^2 - e^2 - d^2) / (2 l1)`, `d = z2 - z1`:
    /// with `R = |(e, d)|`, `beta = atan2(d, e)`, `sigma = (l2^2 - l1^2 - R^2)/(2 l1 R)`,
    /// `psi = beta + atan2(sigma, -+sqrt(1 - sigma^2))` (minus sign for
    /// [`Branch::Positive`]), `theta = psi - delta` wrapped to `(-pi, pi]`.
    ///
    /// Fails with [`Error::NotAttainable`] when the sliders are too close or too far
    /// apart for the crank and rod, or when the solution would put C below B (not an
    /// assembly of this head), and with [`Error::Singular`] at (and within a sine of
    /// 1e-6 of) Q.
    pub fn forward(&self, z1: f64, z2: f64, branch: Branch) -> Result<Vector2<f64>> {
        let (z1, z2) = (z1 + self.offsets.a_z, z2 + self.offsets.c_z);
        let d = z2 - z1;
        let r = self.e.hypot(d);
        let sigma = (self.l2 * self.l2 - self.l1 * self.l1 - r * r) / (2.0 * self.l1 * r);
        if !(sigma.abs() <= 1.0) {
            return Err(Error::NotAttainable {
                reason: format!(
                    "the sliders are {d:.4} mm apart: hinge C is {r:.4} mm from hinge A, \
                     outside [{:.4}, {:.4}] mm that crank l1 and rod l2 can span",
                    (self.l2 - self.l1).abs(),
                    self.l1 + self.l2
                )
                .into(),
            });
        }
        // c is the sine of the transmission angle; theta's sensitivity to the slider
        // positions grows like 1/c, so below 1e-6 rounding alone moves theta by more
        // than 1e-9 rad: reported as singular rather than returned.
        let c = ((1.0 - sigma) * (1.0 + sigma)).sqrt();
        if c < 1e-6 {
            return Err(Error::Singular {
                what: "P3RP head at Q: hinges A, B, C collinear, the V slider does not \
                       determine theta"
                    .into(),
                rcond: c,
            });
        }
        let psi = d.atan2(self.e) + sigma.atan2(-branch.sign() * c);
        if d - self.l1 * psi.cos() <= 0.0 {
            return Err(Error::NotAttainable {
                reason: format!(
                    "on the {branch:?} branch the rod would hang below hinge B (C below B \
                     is not an assembly of this head)"
                )
                .into(),
            });
        }
        Ok(Vector2::new(z1, wrap(psi - self.delta)))
    }

    /// Both forward solutions, `[Positive, Negative]`, each `None` where that branch
    /// has no assembly.
    pub fn forward_branches(&self, z1: f64, z2: f64) -> [Option<Vector2<f64>>; 2] {
        [Branch::Positive, Branch::Negative].map(|b| self.forward(z1, z2, b).ok())
    }

    /// The paper's branch rule applied literally to an angle: `theta <= -pi/2` becomes
    /// `pi + theta`, `-pi/2 < theta < 0` is discarded, others are kept. Kept for the
    /// record (docs/seed-004.md): applied to pkm's exact angles it maps the other branch
    /// onto a pose that does not close the loop.
    pub fn paper_branch_rule(theta: f64) -> Option<f64> {
        if theta <= -PI / 2.0 {
            Some(PI + theta)
        } else if theta < 0.0 {
            None
        } else {
            Some(theta)
        }
    }

    /// Slider separation at the singular configuration Q with the rod stretched along
    /// the crank: `d_Q = sqrt((l1 + l2)^2 - e^2)`, the largest `z2 - z1` the head
    /// can take.
    pub fn singular_separation(&self) -> f64 {
        ((self.l1 + self.l2).powi(2) - self.e * self.e).sqrt()
    }

    /// Hinge B and C positions and the tool tip in the base frame (X = 0 plane).
    pub fn points(&self, z: f64, theta: f64) -> Result<[Vector3<f64>; 4]> {
        let g = self.separation(theta)?.g;
        let psi = theta + self.delta;
        let a = Vector3::new(0.0, self.offsets.a_y, z);
        let b = a + self.l1 * Vector3::new(0.0, -psi.sin(), psi.cos());
        let c = Vector3::new(0.0, self.offsets.a_y + self.e, z + g);
        let tool = a + self.tool_length * Vector3::new(0.0, theta.sin(), -theta.cos());
        Ok([a, b, c, tool])
    }

    /// Pushes the violated limits of pose `(z, theta)` with sliders `q` (strokes from
    /// `actuators`): the sliders' strokes, then [`HeadGeometry::check_joint_limits`].
    pub fn check_limits(
        &self,
        actuators: &[Actuator],
        theta: f64,
        q: &[f64],
        out: &mut Vec<Violation>,
    ) {
        for (a, v) in actuators.iter().zip(q) {
            a.range.check(
                || format!("slider {} position", a.name),
                LimitKind::ActuatorPosition,
                Quantity::Length,
                *v,
                out,
            );
        }
        self.check_joint_limits(theta, out);
    }

    /// Pushes the violated limits of the head's joints at deflection `theta`: the
    /// deflection's range, the rod angle's, the transmission angle's least value.
    pub fn check_joint_limits(&self, theta: f64, out: &mut Vec<Violation>) {
        if let Some(r) = &self.theta_range {
            r.check(
                || "hinge A deflection theta",
                LimitKind::JointAngle,
                Quantity::Angle,
                theta,
                out,
            );
        }
        if let (Some(r), Ok(phi)) = (&self.rod_angle_range, self.rod_angle(theta)) {
            r.check(
                || "rod angle phi (hinge C)",
                LimitKind::JointAngle,
                Quantity::Angle,
                phi,
                out,
            );
        }
        if let Ok(mu) = self.transmission_angle(theta) {
            let mu = self.branch.sign() * mu;
            let min = self.min_transmission_angle.unwrap_or(0.0);
            if mu < min {
                out.push(Violation::new(
                    format!(
                        "transmission angle AB-BC ({:?} branch; 0 at the singular \
                         configuration Q)",
                        self.branch
                    ),
                    LimitKind::PassiveJoint,
                    Side::Min,
                    Quantity::Angle,
                    mu,
                    min,
                ));
            }
        }
    }
}
