//! The accuracy model of a serial machine: the first-order sensitivity of the tool pose
//! to every primary deviation (analytic, through the product of the chain's transforms).

use nalgebra::{Matrix3, Matrix4, Vector3};

use crate::error::{Error, Result};
use crate::serial::machine::{installation, installation_axis, inverse};
use crate::serial::machine::{ChainDeviations, Parameter, SerialMachine};
use crate::serial::{joint_transform, link_transform, Chain, JointKind, LinkDeviation};

mod parametric;
pub mod sensitivity;

pub(crate) use parametric::SerialScratch;
pub use parametric::{serial_completions, serial_parameters, serial_tolerable, LinkCompletion};

impl SerialMachine {
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
                let w = crate::rotation::skew_vee(&dr);
                Ok((dp, w))
            })
            .collect()
    }
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
pub(super) fn derivative(
    m: &SerialMachine,
    p: &Parameter,
    qt: &[f64],
    qw: &[f64],
    dev: &[ChainDeviations],
) -> Result<(usize, usize, Matrix4<f64>)> {
    let none = ChainDeviations::default();
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
            Ok((chain, idx, joint_derivative(j.kind, qv)))
        }
        Parameter::Installation { .. } => Err(Error::InvalidInput {
            what: "deviation".into(),
            message: "an installation angle is not a factor of a chain".into(),
        }),
    }
}

/// Index of link `l`'s geometry factor in [`factors`].
fn link_factor(ch: &Chain, l: usize) -> usize {
    ch.links[..=l].iter().filter(|x| x.joint.is_some()).count() + l
}

/// Index of joint `j`'s factor in [`factors`], if the chain has that joint.
fn joint_factor(ch: &Chain, j: usize) -> Option<usize> {
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
}

/// The derivative of a joint's transform of `kind` at value `q` by its value.
fn joint_derivative(kind: JointKind, q: f64) -> Matrix4<f64> {
    let mut dm = Matrix4::zeros();
    match kind {
        JointKind::Revolute => {
            let (s, c) = q.sin_cos();
            dm[(0, 0)] = -s;
            dm[(0, 1)] = -c;
            dm[(1, 0)] = c;
            dm[(1, 1)] = -s;
        }
        JointKind::Prismatic => dm[(2, 3)] = 1.0,
    }
    dm
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
