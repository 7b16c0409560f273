//! A serial machine of seed 003: a tool chain and optionally a workpiece chain, its
//! primary deviations by name, and its tool pose with any of them applied (eqs. 1-4).

use nalgebra::{Matrix4, Vector3};
use serde::Serialize;

use super::{Chain, JointKind, LinkDeviation};
use crate::error::{Error, Result};

/// A machine of one tool chain and, optionally, a workpiece chain, both starting at the
/// bed frame; the tool pose is taken relative to the workpiece chain's end.
#[derive(Debug, Clone, PartialEq)]
pub struct SerialMachine {
    /// Name.
    pub name: String,
    /// The chain carrying the tool (its last `S*` is the tool frame).
    pub tool: Chain,
    /// The chain carrying the workpiece, if any (its last `S*` is the part frame).
    pub workpiece: Option<Chain>,
}

/// Deviations of one chain: one per link, one positioning deviation per joint.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ChainDeviations {
    /// Per link (empty: none).
    pub links: Vec<LinkDeviation>,
    /// Per joint (empty: none).
    pub dq: Vec<f64>,
    /// Installation angles of the bed in the world (rad, about x, y, z: the world is
    /// `R = Rz(theta_z0) Ry(theta_y0) Rx(theta_x0)` from the bed; seed 003's theta_x0,
    /// theta_z0). Read from the tool chain's entry only.
    pub installation: Vector3<f64>,
}

/// One primary deviation of a machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Parameter {
    /// `delta_(axis)` of a link (mm); axis 0, 1, 2 = x, y, z.
    Delta {
        /// 0 = tool chain, 1 = workpiece chain.
        chain: usize,
        /// Link index in the chain.
        link: usize,
        /// Axis.
        axis: usize,
    },
    /// `alpha_(row, col)` of a link (rad).
    Alpha {
        /// 0 = tool chain, 1 = workpiece chain.
        chain: usize,
        /// Link index.
        link: usize,
        /// Axis of `S_i`.
        row: usize,
        /// Axis of `S_i*`.
        col: usize,
    },
    /// Positioning deviation `dq` of a joint (mm or rad).
    Dq {
        /// 0 = tool chain, 1 = workpiece chain.
        chain: usize,
        /// Joint index in the chain.
        joint: usize,
    },
    /// Installation angle `theta_(axis)0` of the bed in the world (rad). It turns both
    /// chains alike, so it moves the tool relative to a part on the workpiece chain not
    /// at all; without a workpiece chain (a robot; the part stands in the world) it
    /// turns the tool about the world origin.
    Installation {
        /// Axis 0, 1, 2 = x, y, z.
        axis: usize,
    },
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl SerialMachine {
    /// Every joint, tool chain first, then workpiece chain: the order of a serial
    /// mechanism's actuators.
    pub fn all_joints(&self) -> Vec<super::Joint> {
        self.tool
            .joints()
            .chain(self.workpiece.iter().flat_map(|w| w.joints()))
            .cloned()
            .collect()
    }

    pub(super) fn chain(&self, k: usize) -> Result<&Chain> {
        match k {
            0 => Ok(&self.tool),
            1 => self.workpiece.as_ref().ok_or_else(|| Error::InvalidInput {
                what: "deviation".into(),
                message: "the machine has no workpiece chain".into(),
            }),
            _ => Err(Error::InvalidInput {
                what: "deviation".into(),
                message: format!("chain {k} does not exist"),
            }),
        }
    }

    /// Name of a parameter in seed 003's notation with the link's name:
    /// `delta_x(1 slide)`, `alpha_xz(4 table)`, `dq(X)`.
    pub fn parameter_name(&self, p: &Parameter) -> String {
        let link_name = |c: usize, l: usize| {
            self.chain(c)
                .ok()
                .and_then(|ch| ch.links.get(l))
                .map(|x| x.name.clone())
                .unwrap_or_else(|| format!("{c}.{l}"))
        };
        match *p {
            Parameter::Delta { chain, link, axis } => {
                format!("delta_{}({})", AXES[axis], link_name(chain, link))
            }
            Parameter::Alpha {
                chain,
                link,
                row,
                col,
            } => format!(
                "alpha_{}{}({})",
                AXES[row],
                AXES[col],
                link_name(chain, link)
            ),
            Parameter::Installation { axis } => format!("theta_{}0", AXES[axis.min(2)]),
            Parameter::Dq { chain, joint } => {
                let j = self
                    .chain(chain)
                    .ok()
                    .and_then(|c| c.joints().nth(joint))
                    .map(|j| j.name.clone())
                    .unwrap_or_else(|| format!("{chain}.{joint}"));
                format!("dq({j})")
            }
        }
    }

    /// The deviation with this name ([`SerialMachine::parameter_name`]), or a message
    /// saying what names look like (for file and command-line errors).
    pub fn parameter_by_name(&self, name: &str) -> std::result::Result<Parameter, String> {
        let all = self.all_parameters();
        all.iter()
            .copied()
            .find(|p| self.parameter_name(p) == name)
            .ok_or_else(|| {
                let examples: Vec<String> =
                    all.iter().take(4).map(|p| self.parameter_name(p)).collect();
                format!(
                    "unknown deviation `{name}`: expected delta_x|y|z(LINK), alpha_ab(LINK) \
                     with a, b in x, y, z, dq(JOINT) or theta_x0|y0|z0, e.g. {}",
                    examples.join(", ")
                )
            })
    }

    /// Whether a deviation is an angle (rad inside, deg at the boundary): the angular
    /// deviations, and the positioning deviation of a revolute joint.
    pub fn is_angular(&self, p: &Parameter) -> bool {
        match *p {
            Parameter::Alpha { .. } | Parameter::Installation { .. } => true,
            Parameter::Delta { .. } => false,
            Parameter::Dq { chain, joint } => self
                .chain(chain)
                .ok()
                .and_then(|c| c.joints().nth(joint))
                .is_some_and(|j| j.kind == JointKind::Revolute),
        }
    }

    /// Every primary deviation of the machine: per link 3 linear and 9 angular, per
    /// joint 1 positioning, and the bed's three installation angles.
    pub fn all_parameters(&self) -> Vec<Parameter> {
        let mut v = Vec::new();
        let chains: Vec<&Chain> = std::iter::once(&self.tool)
            .chain(self.workpiece.iter())
            .collect();
        for (c, ch) in chains.iter().enumerate() {
            for l in 0..ch.links.len() {
                for axis in 0..3 {
                    v.push(Parameter::Delta {
                        chain: c,
                        link: l,
                        axis,
                    });
                }
                for row in 0..3 {
                    for col in 0..3 {
                        v.push(Parameter::Alpha {
                            chain: c,
                            link: l,
                            row,
                            col,
                        });
                    }
                }
            }
            for joint in 0..ch.dof() {
                v.push(Parameter::Dq { chain: c, joint });
            }
        }
        v.extend((0..3).map(|axis| Parameter::Installation { axis }));
        v
    }

    /// The tool pose relative to the workpiece (or the bed) for tool-chain joints `qt`,
    /// workpiece-chain joints `qw` and deviations `dev` (`[tool, workpiece]`, missing =
    /// none).
    pub fn pose(&self, qt: &[f64], qw: &[f64], dev: &[ChainDeviations]) -> Result<Matrix4<f64>> {
        let none = ChainDeviations::default();
        let dt = dev.first().unwrap_or(&none);
        let t = self.tool.pose(qt, &dt.dq, &dt.links)?;
        match &self.workpiece {
            // The installation turns both chains alike: it cancels relative to the part.
            None => Ok(installation(&dt.installation) * t),
            Some(w) => {
                let dw = dev.get(1).unwrap_or(&none);
                let tw = w.pose(qw, &dw.dq, &dw.links)?;
                Ok(inverse(&tw)? * t)
            }
        }
    }
}

/// The bed's installation in the world, `Rz(theta_z0) Ry(theta_y0) Rx(theta_x0)`.
pub(super) fn installation(theta: &Vector3<f64>) -> Matrix4<f64> {
    if *theta == Vector3::zeros() {
        return Matrix4::identity();
    }
    let r =
        crate::rotation::rz(theta.z) * crate::rotation::ry(theta.y) * crate::rotation::rx(theta.x);
    r.to_homogeneous()
}

/// World direction of installation axis `axis` at installation `theta`: turning
/// `theta_axis` turns the bed about this axis (`Rz Ry Rx`: z about the world z, y about
/// `Rz e_y`, x about `Rz Ry e_x`).
pub(super) fn installation_axis(theta: &Vector3<f64>, axis: usize) -> Vector3<f64> {
    use crate::rotation::{ry, rz};
    match axis {
        0 => rz(theta.z) * ry(theta.y) * Vector3::x(),
        1 => rz(theta.z) * Vector3::y(),
        _ => Vector3::z(),
    }
}

/// Inverse of a homogeneous transform whose block may be slightly non-orthonormal
/// (deviated blocks): a general 4x4 inverse.
pub(super) fn inverse(t: &Matrix4<f64>) -> Result<Matrix4<f64>> {
    t.try_inverse().ok_or_else(|| Error::Singular {
        what: "workpiece-chain transform (deviated blocks far from a rotation)".into(),
        rcond: 0.0,
    })
}
