//! Joint clearances (seed 002): the play of a machine's passive joints, carried up to
//! the tool point by re-solving the mechanism with the same actuator values.
//!
//! A clearance is one more kind of geometric deviation: a passive joint's centre is a
//! triple of the machine's joint-centre parameters ([`PassiveJoint`]), and a joint
//! state moves that centre inside the region its clearance allows ([`Region`]):
//!
//! * a spherical joint with diametral clearance `c`: anywhere in the ball of radius
//!   `c / 2` (seed 002: "the joint centre can shift within the clearance");
//! * a revolute or universal joint: within the disc of radius `c / 2` normal to its
//!   axis `a`, and the axis may tilt by up to `theta = atan(c / b)` over the bearing
//!   length `b` (seed 002's "perekos"). The tilt turns the joint about the bearing's
//!   middle, which sits `h` (the `lever`) before the joint centre along the axis, so the
//!   centre moves by `(R(t) - I) h a` as well; with `h = 0` (the centre in the bearing's
//!   middle) the tilt does not move it.
//!
//! The moved centres go into the machine's constraint equations and the mechanism is
//! solved again (the accuracy engine's exact evaluator): the change of the tool point
//! relative to the part is the error. [`bounds()`] bounds its component along a
//! direction (seed 002's shaping error along the surface normal) and its length.

mod bounds;
mod sample;
pub mod surface;

use nalgebra::{Rotation3, Vector3};
use rand::Rng;
use serde::Serialize;

use crate::error::{Error, Result};

pub use bounds::{
    bounds, bounds_along, enumeration_size, ClearanceBounds, ClearanceMethod, ClearanceOptions,
    Deviation3d, JointContribution, WorstStates, MAX_ENUMERATION,
};
pub use sample::{clearance_monte_carlo, ClearanceMonteCarlo};

/// Why a machine type cannot take clearances (the registry's `Unsupported` reason and
/// the machine-file reader's message).
pub(crate) const NO_PASSIVE_JOINTS: &str = "this machine type has no passive joints whose \
     centres pkm models: clearances move the centres of passive joints (the joints of strut \
     machines, tripods and hexapods, of the seed-002 machine and of the P3RP head); a serial \
     chain's joints are all driven";

/// Kind of a passive joint, for its clearance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum JointType {
    /// Ball joint: the centre moves in a ball.
    Spherical,
    /// Pin joint: the centre moves in a disc normal to the axis, the axis tilts.
    Revolute,
    /// Cardan joint: as a revolute joint about the axis fixed in its body.
    Universal,
}

impl std::str::FromStr for JointType {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "spherical" => Ok(JointType::Spherical),
            "revolute" => Ok(JointType::Revolute),
            "universal" => Ok(JointType::Universal),
            _ => Err(format!(
                "unknown joint type `{s}`, expected spherical, revolute or universal"
            )),
        }
    }
}

/// A passive joint of a machine whose centre is a triple of its joint-centre
/// parameters (several triples when struts share the joint: they move together).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassiveJoint {
    /// Name as in the machine file (`A1`, `B3`, `leg`).
    pub name: String,
    /// The body that carries the centre, whose frame the parameters are in (`base`,
    /// `platform`).
    pub body: String,
    /// Indices into [`super::Parametric::parameters`]: x, y, z of the centre, per strut
    /// using the joint.
    pub centres: Vec<[usize; 3]>,
}

/// The clearance of one passive joint (mm, internal units).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointClearance {
    /// Joint name (one of the machine's [`PassiveJoint`]s).
    pub joint: String,
    /// Kind of joint.
    pub kind: JointType,
    /// Diametral clearance `c` (mm).
    pub diametral: f64,
    /// Bearing length `b` (mm) of a revolute or universal joint: its axis tilts by up to
    /// `atan(c / b)`. `None`: no tilt.
    pub bearing_length: Option<f64>,
    /// Axis of a revolute or universal joint in its body's frame (unit).
    pub axis: Option<Vector3<f64>>,
    /// Distance `h` (mm) from the bearing's middle to the joint centre along the axis:
    /// the lever through which the tilt moves the centre.
    pub lever: f64,
}

impl JointClearance {
    /// A spherical joint's clearance.
    pub fn spherical(joint: impl Into<String>, diametral: f64) -> Self {
        JointClearance {
            joint: joint.into(),
            kind: JointType::Spherical,
            diametral,
            bearing_length: None,
            axis: None,
            lever: 0.0,
        }
    }

    /// Checks the values: `c >= 0`, `b > 0`, a unit-normalisable axis for revolute and
    /// universal joints, finite lever.
    pub fn validate(&self) -> Result<()> {
        self.check().map_err(|(_, message)| Error::InvalidInput {
            what: format!("clearance of joint `{}`", self.joint),
            message,
        })
    }

    /// [`JointClearance::validate`] naming the field at fault (`diametral`,
    /// `bearing_length`, `lever`, `axis`) with the message, for file readers.
    pub fn check(&self) -> std::result::Result<(), (&'static str, String)> {
        if !(self.diametral >= 0.0 && self.diametral <= crate::accuracy::MAX_TOLERANCE_LENGTH) {
            return Err((
                "diametral",
                format!(
                    "expected a diametral clearance from 0 to {} mm (a gap in a joint, \
                     propagated to first order), found {}",
                    crate::accuracy::MAX_TOLERANCE_LENGTH,
                    self.diametral
                ),
            ));
        }
        if let Some(b) = self.bearing_length {
            if !(b > 0.0 && b.is_finite()) {
                return Err((
                    "bearing_length",
                    format!("expected a bearing length > 0 mm, found {b}"),
                ));
            }
        }
        if !self.lever.is_finite() {
            return Err((
                "lever",
                format!("expected a finite lever, found {}", self.lever),
            ));
        }
        if self.kind != JointType::Spherical {
            match self.axis {
                Some(a) if a.norm() > 1e-9 && a.iter().all(|v| v.is_finite()) => {}
                Some(a) => {
                    return Err((
                        "axis",
                        format!("expected a non-zero axis, found {:?}", a.as_slice()),
                    ))
                }
                None => {
                    return Err((
                        "axis",
                        "a revolute or universal joint needs its `axis` (in its body's frame)"
                            .into(),
                    ))
                }
            }
        }
        Ok(())
    }

    /// Largest tilt of the axis (rad): `atan(c / b)`, 0 for a spherical joint or
    /// without a bearing length.
    pub fn max_tilt(&self) -> f64 {
        match (self.kind, self.bearing_length) {
            (JointType::Spherical, _) | (_, None) => 0.0,
            (_, Some(b)) => (self.diametral / b).atan(),
        }
    }

    /// This clearance with another diametral value (everything else kept).
    pub fn with_diametral(&self, c: f64) -> Self {
        JointClearance {
            diametral: c,
            ..self.clone()
        }
    }
}

/// The state of one joint inside its clearance: the shift of its centre and the tilt
/// of its axis, and the centre's resulting displacement (mm, rad; body frame).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct JointState {
    /// Shift of the centre (mm).
    pub shift: [f64; 3],
    /// Tilt of the axis (rotation vector normal to the axis, rad).
    pub tilt: [f64; 3],
    /// Displacement of the centre: shift plus what the tilt moves through the lever.
    pub displacement: [f64; 3],
}

/// A joint's clearance resolved against its machine: the region its centre moves in.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// The joint.
    pub joint: PassiveJoint,
    /// Its clearance.
    pub clearance: JointClearance,
    radius: f64,
    axis: Option<Vector3<f64>>,
    tilt: f64,
}

impl Region {
    /// The region of `joint` with `clearance` (validated).
    pub fn new(joint: PassiveJoint, clearance: JointClearance) -> Result<Self> {
        clearance.validate()?;
        let axis = match clearance.kind {
            JointType::Spherical => None,
            _ => clearance.axis.map(|a| a.normalize()),
        };
        Ok(Region {
            radius: clearance.diametral / 2.0,
            tilt: clearance.max_tilt(),
            axis,
            joint,
            clearance,
        })
    }

    /// `v` without its component along the axis (a disc's plane), or `v` (a ball).
    fn in_plane(&self, v: &Vector3<f64>) -> Vector3<f64> {
        match &self.axis {
            Some(a) => v - a * a.dot(v),
            None => *v,
        }
    }

    /// The state with shift `s` and tilt `t` (`t` normal to the axis).
    pub fn state(&self, s: Vector3<f64>, t: Vector3<f64>) -> JointState {
        let d = match &self.axis {
            Some(a) if self.clearance.lever != 0.0 && t != Vector3::zeros() => {
                s + (Rotation3::new(t) * a - a) * self.clearance.lever
            }
            _ => s,
        };
        JointState {
            shift: s.into(),
            tilt: t.into(),
            displacement: d.into(),
        }
    }

    /// Largest in-plane displacement to first order: `c / 2 + |h| sin(theta)`.
    pub fn reach(&self) -> f64 {
        self.radius + self.clearance.lever.abs() * self.tilt.sin()
    }

    /// First-order support function: the largest `g . d` over the region,
    /// `(c / 2 + |h| sin theta) |P g|` (`P` the projection on the disc's plane; the
    /// identity for a ball).
    pub fn support(&self, g: &Vector3<f64>) -> f64 {
        self.reach() * self.in_plane(g).norm()
    }

    /// The state that maximises `g . d` to first order: shift `c / 2` along `P g`, the
    /// axis tilted by `theta` towards it (the lever's end moves the same way).
    pub fn argmax(&self, g: &Vector3<f64>) -> JointState {
        let p = self.in_plane(g);
        let n = p.norm();
        if n == 0.0 || self.reach() == 0.0 {
            return self.state(Vector3::zeros(), Vector3::zeros());
        }
        self.toward(&(p / n))
    }

    /// The extreme state in the in-plane unit direction `u`.
    fn toward(&self, u: &Vector3<f64>) -> JointState {
        let t = match &self.axis {
            // Turning a by theta about a x u moves the lever's end (h a) along
            // sign(h) u.
            Some(a) if self.tilt > 0.0 && self.clearance.lever != 0.0 => {
                a.cross(u) * self.tilt * self.clearance.lever.signum()
            }
            _ => Vector3::zeros(),
        };
        self.state(u * self.radius, t)
    }

    /// The extreme states the paper's enumeration visits: `+-` the limit along each
    /// axis of the body frame (a ball: 6) or of the disc's plane (4), the tilt with it.
    pub fn extremes(&self) -> Vec<JointState> {
        let dirs: Vec<Vector3<f64>> = match &self.axis {
            None => vec![Vector3::x(), Vector3::y(), Vector3::z()],
            Some(a) => plane_basis(a).to_vec(),
        };
        dirs.iter()
            .flat_map(|u| [self.toward(u), self.toward(&-u)])
            .collect()
    }

    /// A state drawn uniformly: the shift uniform in the ball or disc, the tilt uniform
    /// in the disc of angles `|t| <= theta` normal to the axis.
    pub fn sample<R: Rng>(&self, rng: &mut R) -> JointState {
        let in_ball = |rng: &mut R, planar: bool| loop {
            let v = Vector3::new(
                rng.random_range(-1.0..=1.0),
                rng.random_range(-1.0..=1.0),
                if planar {
                    0.0
                } else {
                    rng.random_range(-1.0..=1.0)
                },
            );
            if v.norm_squared() <= 1.0 {
                return v;
            }
        };
        match &self.axis {
            None => self.state(in_ball(rng, false) * self.radius, Vector3::zeros()),
            Some(a) => {
                let [e1, e2] = plane_basis(a);
                let s = in_ball(rng, true);
                let t = in_ball(rng, true);
                self.state(
                    (e1 * s.x + e2 * s.y) * self.radius,
                    (e1 * t.x + e2 * t.y) * self.tilt,
                )
            }
        }
    }
}

/// An orthonormal basis of the plane normal to unit `a`.
fn plane_basis(a: &Vector3<f64>) -> [Vector3<f64>; 2] {
    let c = a.cross(&Vector3::x());
    let e1 = if c.norm() < 0.5 {
        a.cross(&Vector3::y()).normalize()
    } else {
        c.normalize()
    };
    [e1, a.cross(&e1)]
}

/// The machine's regions for `clearances`: each names one of `joints`; a joint named
/// twice is an error.
pub fn regions(joints: &[PassiveJoint], clearances: &[JointClearance]) -> Result<Vec<Region>> {
    let mut out: Vec<Region> = Vec::with_capacity(clearances.len());
    for c in clearances {
        let j = joints
            .iter()
            .find(|j| j.name == c.joint)
            .ok_or_else(|| Error::InvalidInput {
                what: "clearance".into(),
                message: format!(
                    "unknown joint `{}`, expected one of {}",
                    c.joint,
                    joints
                        .iter()
                        .map(|j| j.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            })?;
        if out.iter().any(|r| r.joint.name == c.joint) {
            return Err(Error::InvalidInput {
                what: "clearance".into(),
                message: format!("joint `{}` has a clearance already", c.joint),
            });
        }
        out.push(Region::new(j.clone(), c.clone())?);
    }
    Ok(out)
}

/// The deviations (`(parameter, value)`) that put every region in its state.
pub(crate) fn deviations_of(
    regions: &[Region],
    states: &[JointState],
    out: &mut Vec<(usize, f64)>,
) {
    out.clear();
    for (r, s) in regions.iter().zip(states) {
        for c in &r.joint.centres {
            for (&p, &d) in c.iter().zip(&s.displacement) {
                if d != 0.0 {
                    out.push((p, d));
                }
            }
        }
    }
}
