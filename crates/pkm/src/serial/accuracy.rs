//! The accuracy model of a serial machine: tool pose relative to the workpiece with any
//! set of primary deviations, and the first-order sensitivity of the tool pose to every
//! deviation (analytic, through the product of the chain's transforms).

use nalgebra::{Matrix3, Matrix4, Vector3};
use serde::Serialize;

use super::{joint_transform, link_transform, Chain, JointKind, LinkDeviation};
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
    fn chain(&self, k: usize) -> Result<&Chain> {
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

    /// First-order sensitivity of the tool pose relative to the workpiece to each of
    /// `params` at joints `qt`, `qw` and deviations `dev`: per parameter the tool-point
    /// displacement (mm per unit) and the small rotation of the tool frame (rad per
    /// unit), both in the workpiece frame. Exact derivatives of the product of
    /// transforms: `dT/dp = T_before dM/dp T_after`.
    pub fn sensitivities(
        &self,
        qt: &[f64],
        qw: &[f64],
        dev: &[ChainDeviations],
        params: &[Parameter],
    ) -> Result<Vec<(Vector3<f64>, Vector3<f64>)>> {
        let none = ChainDeviations::default();
        let pt = Products::new(&factors(&self.tool, qt, dev.first().unwrap_or(&none))?);
        let tt = pt.total();
        let (pw, tw_inv) = match &self.workpiece {
            Some(w) => {
                let p = Products::new(&factors(w, qw, dev.get(1).unwrap_or(&none))?);
                let inv = inverse(&p.total())?;
                (Some(p), inv)
            }
            // Without a workpiece chain the part stands in the world.
            None => (
                None,
                installation(&dev.first().unwrap_or(&none).installation),
            ),
        };
        let rel = tw_inv * tt;
        let rot = rel.fixed_view::<3, 3>(0, 0).into_owned();
        params
            .iter()
            .map(|p| {
                if let Parameter::Installation { axis } = *p {
                    return Ok(if self.workpiece.is_some() {
                        (Vector3::zeros(), Vector3::zeros())
                    } else {
                        // d(R T)/d theta = (a x) R T exactly, `a` the world direction
                        // of the axis that angle turns about.
                        let a = installation_axis(
                            &dev.first().unwrap_or(&none).installation,
                            axis.min(2),
                        );
                        (a.cross(&rel.fixed_view::<3, 1>(0, 3).into_owned()), a)
                    });
                }
                let (c, k, dm) = derivative(self, p, qt, qw, dev)?;
                let d_rel = if c == 0 {
                    tw_inv * pt.derivative(k, &dm)
                } else {
                    let pw = pw.as_ref().expect("chain checked");
                    -tw_inv * pw.derivative(k, &dm) * tw_inv * tt
                };
                let dp = d_rel.fixed_view::<3, 1>(0, 3).into_owned();
                let dr = d_rel.fixed_view::<3, 3>(0, 0) * rot.transpose();
                // The skew part of dR R^T is the small rotation.
                let w = Vector3::new(
                    0.5 * (dr[(2, 1)] - dr[(1, 2)]),
                    0.5 * (dr[(0, 2)] - dr[(2, 0)]),
                    0.5 * (dr[(1, 0)] - dr[(0, 1)]),
                );
                Ok((dp, w))
            })
            .collect()
    }
}

/// The bed's installation in the world, `Rz(theta_z0) Ry(theta_y0) Rx(theta_x0)`.
fn installation(theta: &Vector3<f64>) -> Matrix4<f64> {
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
fn installation_axis(theta: &Vector3<f64>, axis: usize) -> Vector3<f64> {
    use crate::rotation::{ry, rz};
    match axis {
        0 => rz(theta.z) * ry(theta.y) * Vector3::x(),
        1 => rz(theta.z) * Vector3::y(),
        _ => Vector3::z(),
    }
}

/// Inverse of a homogeneous transform whose block may be slightly non-orthonormal
/// (deviated blocks): a general 4x4 inverse.
fn inverse(t: &Matrix4<f64>) -> Result<Matrix4<f64>> {
    t.try_inverse().ok_or_else(|| Error::Singular {
        what: "workpiece-chain transform (deviated blocks far from a rotation)".into(),
        rcond: 0.0,
    })
}

/// The chain's factors in order: link 0, then per link its joint and its geometry.
fn factors(ch: &Chain, q: &[f64], d: &ChainDeviations) -> Result<Vec<Matrix4<f64>>> {
    let n = ch.dof();
    if q.len() != n {
        return Err(Error::InvalidInput {
            what: format!("chain `{}`", ch.name),
            message: format!("expected {n} joint values, got {}", q.len()),
        });
    }
    let zero = LinkDeviation::default();
    let mut f = Vec::with_capacity(2 * ch.links.len());
    let mut k = 0;
    for (i, link) in ch.links.iter().enumerate() {
        if let Some(j) = &link.joint {
            let dq = d.dq.get(k).copied().unwrap_or(0.0);
            f.push(joint_transform(j.kind, q[k] + dq));
            k += 1;
        }
        f.push(link_transform(link, d.links.get(i).unwrap_or(&zero)));
    }
    Ok(f)
}

/// Prefix and suffix products of a chain's factors, computed once for all parameters:
/// `prefix[k] = F_0 .. F_(k-1)`, `suffix[k] = F_(k+1) .. F_(n-1)`.
struct Products {
    prefix: Vec<Matrix4<f64>>,
    suffix: Vec<Matrix4<f64>>,
}

impl Products {
    fn new(f: &[Matrix4<f64>]) -> Self {
        let n = f.len();
        let mut prefix = Vec::with_capacity(n + 1);
        prefix.push(Matrix4::identity());
        for m in f {
            let last = *prefix.last().expect("non-empty");
            prefix.push(last * m);
        }
        let mut suffix = vec![Matrix4::identity(); n];
        for k in (0..n.saturating_sub(1)).rev() {
            suffix[k] = f[k + 1] * suffix[k + 1];
        }
        Products { prefix, suffix }
    }

    /// The whole product.
    fn total(&self) -> Matrix4<f64> {
        *self.prefix.last().expect("non-empty")
    }

    /// `prod_(i<k) F_i * dm * prod_(i>k) F_i`.
    fn derivative(&self, k: usize, dm: &Matrix4<f64>) -> Matrix4<f64> {
        self.prefix[k] * dm * self.suffix[k]
    }
}

/// The chain, the index of the factor a parameter enters, and that factor's derivative.
fn derivative(
    m: &SerialMachine,
    p: &Parameter,
    qt: &[f64],
    qw: &[f64],
    dev: &[ChainDeviations],
) -> Result<(usize, usize, Matrix4<f64>)> {
    let none = ChainDeviations::default();
    // Index of link l's geometry factor and of joint j's factor in `factors`.
    let link_factor = |ch: &Chain, l: usize| -> usize {
        ch.links[..=l].iter().filter(|x| x.joint.is_some()).count() + l
    };
    let joint_factor = |ch: &Chain, j: usize| -> Option<usize> {
        let mut seen = 0;
        let mut idx = 0;
        for link in &ch.links {
            if link.joint.is_some() {
                if seen == j {
                    return Some(idx);
                }
                seen += 1;
                idx += 1;
            }
            idx += 1;
        }
        None
    };
    match *p {
        Parameter::Delta { chain, link, axis } => {
            let ch = m.chain(chain)?;
            check_link(ch, link)?;
            let mut d = Matrix4::zeros();
            d[(axis.min(2), 3)] = 1.0;
            Ok((chain, link_factor(ch, link), d))
        }
        Parameter::Alpha {
            chain,
            link,
            row,
            col,
        } => {
            let ch = m.chain(chain)?;
            check_link(ch, link)?;
            let d = dev.get(chain).unwrap_or(&none);
            let a = d
                .links
                .get(link)
                .map(|x| x.alpha)
                .unwrap_or_else(Matrix3::zeros);
            let phi = ch.links[link].angles();
            let mut dm = Matrix4::zeros();
            dm[(row, col)] = -(phi[(row, col)] + a[(row, col)]).sin();
            Ok((chain, link_factor(ch, link), dm))
        }
        Parameter::Dq { chain, joint } => {
            let ch = m.chain(chain)?;
            let idx = joint_factor(ch, joint).ok_or_else(|| Error::InvalidInput {
                what: "deviation".into(),
                message: format!("chain `{}` has no joint {joint}", ch.name),
            })?;
            let j = ch.joints().nth(joint).expect("found above");
            let q = if chain == 0 { qt } else { qw };
            let d = dev.get(chain).unwrap_or(&none);
            let qv = q.get(joint).copied().unwrap_or(0.0) + d.dq.get(joint).copied().unwrap_or(0.0);
            let mut dm = Matrix4::zeros();
            match j.kind {
                JointKind::Revolute => {
                    let (s, c) = qv.sin_cos();
                    dm[(0, 0)] = -s;
                    dm[(0, 1)] = -c;
                    dm[(1, 0)] = c;
                    dm[(1, 1)] = -s;
                }
                JointKind::Prismatic => dm[(2, 3)] = 1.0,
            }
            Ok((chain, idx, dm))
        }
        Parameter::Installation { .. } => Err(Error::InvalidInput {
            what: "deviation".into(),
            message: "an installation angle is not a factor of a chain".into(),
        }),
    }
}

fn check_link(ch: &Chain, l: usize) -> Result<()> {
    if l >= ch.links.len() {
        return Err(Error::InvalidInput {
            what: "deviation".into(),
            message: format!("chain `{}` has no link {l}", ch.name),
        });
    }
    Ok(())
}
