//! The P3RP head and the hybrid machine in the accuracy engine: the head's link
//! dimensions (seed 004), and its three hinges as passive joints for clearances.
//!
//! A hinge's centre moved by `d` in the frame of the body that carries it (hinge A:
//! slider D; hinge B: the platform, frame turned by `theta`, origin A; hinge C: slider
//! E; axes X along the hinge axes, Y horizontal, Z up) changes the planar loop exactly
//! as follows, and the head is rebuilt with it:
//!
//! ```text
//! B:  AB_p = l1 (-sin delta, cos delta) + (d_y, d_z)   ->  l1' = |AB_p|,
//!     delta' = atan2(-AB_p,y, AB_p,z)
//! C:  e' = e + d_y, C's height above slider E: d_z
//! A:  e' = e - d_y (C relative to A), the platform and tool shift by d_y in Y, A's
//!     height above slider D: d_z
//! ```
//!
//! A shift along a hinge's own axis (`d_x`) moves nothing of the planar head. These
//! nine coordinates are parameters of kind [`ParameterKind::Clearance`]: a default
//! tolerance budget leaves them out (the link dimensions already carry the hinges'
//! manufactured places).

use super::{HeadGeometry, HingeOffsets};
use crate::accuracy::clearance::PassiveJoint;
use crate::accuracy::rebuild::parametric_by_rebuild;
use crate::accuracy::{Parameter, ParameterKind, Rebuild};
use crate::error::{Error, Result};
use crate::units::Quantity;

/// The link dimensions, then hinges A, B, C (x, y, z each).
const COUNT: usize = 14;
/// Index of hinge A's x in the parameters.
const HINGES: usize = 5;

fn head_parameters() -> Vec<Parameter> {
    let l = |n: &str| Parameter::new(n, Quantity::Length, ParameterKind::LinkDimension);
    let mut v = vec![
        l("l1"),
        l("l2"),
        l("e"),
        Parameter::new("delta", Quantity::Angle, ParameterKind::LinkDimension),
        l("tool_length"),
    ];
    for h in ["A", "B", "C"] {
        for a in ["x", "y", "z"] {
            v.push(Parameter::new(
                format!("{h}.{a}"),
                Quantity::Length,
                ParameterKind::Clearance,
            ));
        }
    }
    v
}

fn head_values(g: &HeadGeometry) -> Vec<f64> {
    let mut v = vec![g.l1, g.l2, g.e, g.delta, g.tool_length];
    v.resize(COUNT, 0.0);
    v
}

/// `g` with the link dimensions and hinge displacements `v` (the module's formulas);
/// `g` must be the nominal head (no offsets of its own).
fn head_with(g: &HeadGeometry, v: &[f64]) -> Result<HeadGeometry> {
    if v.len() != COUNT {
        return Err(Error::InvalidInput {
            what: "P3RP head geometry".into(),
            message: format!(
                "expected {COUNT} values (l1, l2, e, delta, tool_length, hinges A, B, C), got {}",
                v.len()
            ),
        });
    }
    let mut g = g.clone();
    (g.l1, g.l2, g.e, g.delta, g.tool_length) = (v[0], v[1], v[2], v[3], v[4]);
    let [a, b, c] = [0, 1, 2].map(|k| &v[HINGES + 3 * k..HINGES + 3 * k + 3]);
    if b[1] != 0.0 || b[2] != 0.0 {
        let (s, co) = g.delta.sin_cos();
        let (y, z) = (-g.l1 * s + b[1], g.l1 * co + b[2]);
        g.l1 = y.hypot(z);
        g.delta = (-y).atan2(z);
    }
    g.e += c[1] - a[1];
    g.offsets = HingeOffsets {
        a_y: a[1],
        a_z: a[2],
        c_z: c[2],
    };
    Ok(g)
}

/// Hinges A (on slider D), B (platform), C (on slider E); the sliders' frames have the
/// base frame's axes, so A and C are one class, `slider`.
fn head_joints() -> Vec<PassiveJoint> {
    [("A", "slider"), ("B", "platform"), ("C", "slider")]
        .into_iter()
        .enumerate()
        .map(|(k, (name, body))| {
            let o = HINGES + 3 * k;
            PassiveJoint {
                name: name.into(),
                body: body.into(),
                centres: vec![[o, o + 1, o + 2]],
            }
        })
        .collect()
}

impl Rebuild<2, 2> for super::P3rpHead {
    fn geometry_parameters(&self) -> Vec<Parameter> {
        head_parameters()
    }
    fn geometry_values(&self) -> Vec<f64> {
        head_values(self.geometry())
    }
    fn with_geometry_values(&self, v: &[f64]) -> Result<Self> {
        let mut h = self.clone();
        h.set_geometry(head_with(self.geometry(), v)?);
        Ok(h)
    }
    fn passive_joints(&self) -> Vec<PassiveJoint> {
        head_joints()
    }
}
parametric_by_rebuild!(super::P3rpHead, 2, 2);

impl Rebuild<6, 4> for super::HybridMachine {
    fn geometry_parameters(&self) -> Vec<Parameter> {
        head_parameters()
    }
    fn geometry_values(&self) -> Vec<f64> {
        head_values(self.head())
    }
    fn with_geometry_values(&self, v: &[f64]) -> Result<Self> {
        let mut h = self.clone();
        h.set_head(head_with(self.head(), v)?);
        Ok(h)
    }
    fn passive_joints(&self) -> Vec<PassiveJoint> {
        head_joints()
    }
}
parametric_by_rebuild!(super::HybridMachine, 6, 4);
