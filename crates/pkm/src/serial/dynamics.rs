//! Inverse dynamics of a serial chain by the recursive Newton-Euler algorithm.
//!
//! Links carry their mass properties ([`super::Inertial`], link frame `S_i`); the base
//! (link 0) is fixed. In the base frame, with `z_i` the axis of joint `i`, `p_i` the
//! origin of `S_i` and gravity `g` (Luh, Walker and Paul, 1980; Craig, "Introduction to
//! Robotics", ch. 6, here in base-frame vectors):
//!
//! forward, from the base (`w_0 = dw_0 = 0`, `a_0 = -g`):
//!
//! * `a_i = a_(i-1) + dw_(i-1) x d_i + w_(i-1) x (w_(i-1) x d_i)`, `d_i = p_i - p_(i-1)`;
//! * revolute: `w_i = w_(i-1) + q'_i z_i`, `dw_i = dw_(i-1) + q''_i z_i + w_(i-1) x q'_i z_i`;
//! * prismatic: `w_i = w_(i-1)`, and `a_i += q''_i z_i + 2 w_(i-1) x q'_i z_i`;
//! * `F_i = m_i (a_i + dw_i x r_i + w_i x (w_i x r_i))`, `N_i = I_i dw_i + w_i x I_i w_i`
//!   (`r_i` the centre of mass from `p_i`, `I_i` the inertia in base axes);
//!
//! backward, from the tool (`f = -F_ext`, `n = -M_ext` at the tool tip):
//!
//! * `f_i = F_i + f_(i+1)`, `n_i = N_i + r_i x F_i + n_(i+1) + (p_(i+1) - p_i) x f_(i+1)`;
//! * the joint's force or torque: `z_i . n_i` (revolute), `z_i . f_i` (prismatic).
//!
//! Computed in SI units (m, kg, s) and returned in pkm's: N for a slide, N mm for a
//! turn. A link without mass properties is massless, as in URDF.

use nalgebra::{Matrix3, Vector3};

use super::{joint_transform, link_transform, Chain, JointKind, LinkDeviation};
use crate::error::{Error, Result};

/// Standard gravity along -Z of the base frame (mm/s^2).
pub const GRAVITY: Vector3<f64> = Vector3::new(0.0, 0.0, -9806.65);

/// The base-frame state of one moving link of the walk.
struct Body {
    /// Origin of `S_i` (m).
    p: Vector3<f64>,
    /// Joint axis (unit), `None` for a link without joint.
    axis: Option<(JointKind, Vector3<f64>)>,
    /// Mass (kg), centre of mass from `p` (m), inertia in base axes (kg m^2).
    mass: f64,
    r: Vector3<f64>,
    inertia: Matrix3<f64>,
}

/// The joint forces and torques (N, N mm) that move `chain` with joint positions `q`,
/// rates `qd` and accelerations `qdd` (mm or rad, per s, per s^2) under gravity
/// `gravity` (mm/s^2, base frame), the tool pushed by `force` (N, at the tool frame's
/// origin) and `moment` (N mm), both in the base frame.
///
/// Fails when the counts differ from the chain's joints or when no link has mass
/// properties (a chain that would need none: then every torque is the wrench's).
pub fn inverse_dynamics(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    gravity: &Vector3<f64>,
    force: &Vector3<f64>,
    moment: &Vector3<f64>,
) -> Result<Vec<f64>> {
    let n = chain.dof();
    if q.len() != n || qd.len() != n || qdd.len() != n {
        return Err(Error::InvalidInput {
            what: format!("chain `{}`", chain.name),
            message: format!(
                "expected {n} joint positions, rates and accelerations, got {}, {} and {}",
                q.len(),
                qd.len(),
                qdd.len()
            ),
        });
    }
    if chain.links.iter().skip(1).all(|l| l.inertial.is_none()) {
        return Err(Error::InvalidInput {
            what: format!("chain `{}`: inverse dynamics", chain.name),
            message: "no link has mass properties (URDF `<inertial>`): a model without \
                      masses has no dynamics"
                .into(),
        });
    }
    let (bodies, tool) = walk(chain, q);
    let (w, dw, acc) = forward(&bodies, qd, qdd, &(gravity * 1e-3));
    Ok(backward(
        &bodies,
        &w,
        &dw,
        &acc,
        tool,
        force,
        &(moment * 1e-3),
    ))
}

/// The moving links in the base frame at `q`, and the tool frame's origin (m).
fn walk(chain: &Chain, q: &[f64]) -> (Vec<Body>, Vector3<f64>) {
    let none = LinkDeviation::default();
    let mut t = link_transform(&chain.links[0], &none);
    let mut bodies = Vec::with_capacity(chain.links.len());
    let mut k = 0;
    for link in &chain.links[1..] {
        let axis = link.joint.as_ref().map(|j| {
            let z = Vector3::new(t[(0, 2)], t[(1, 2)], t[(2, 2)]);
            t *= joint_transform(j.kind, q[k]);
            k += 1;
            (j.kind, z)
        });
        let r = t.fixed_view::<3, 3>(0, 0).into_owned();
        let p = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]);
        let (mass, r_c, inertia) = match &link.inertial {
            Some(b) => (
                b.mass,
                r * b.com * 1e-3,
                r * b.inertia * r.transpose() * 1e-6,
            ),
            None => (0.0, Vector3::zeros(), Matrix3::zeros()),
        };
        bodies.push(Body {
            p: p * 1e-3,
            axis,
            mass,
            r: r_c,
            inertia,
        });
        t *= link_transform(link, &none);
    }
    (bodies, Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]) * 1e-3)
}

type Motion = (Vec<Vector3<f64>>, Vec<Vector3<f64>>, Vec<Vector3<f64>>);

/// Angular velocity, angular acceleration and the acceleration of each origin (SI).
fn forward(bodies: &[Body], qd: &[f64], qdd: &[f64], g: &Vector3<f64>) -> Motion {
    let (mut w, mut dw, mut a) = (Vector3::zeros(), Vector3::zeros(), -g);
    let mut p = Vector3::zeros();
    let mut out = (Vec::new(), Vec::new(), Vec::new());
    let si = |kind: JointKind, v: f64| match kind {
        JointKind::Prismatic => v * 1e-3,
        JointKind::Revolute => v,
    };
    let mut k = 0;
    for b in bodies {
        let d = b.p - p;
        a += dw.cross(&d) + w.cross(&w.cross(&d));
        if let Some((kind, z)) = b.axis {
            let (v, acc) = (si(kind, qd[k]), si(kind, qdd[k]));
            k += 1;
            match kind {
                JointKind::Revolute => {
                    dw += z * acc + w.cross(&(z * v));
                    w += z * v;
                }
                JointKind::Prismatic => a += z * acc + w.cross(&(z * v)) * 2.0,
            }
        }
        p = b.p;
        out.0.push(w);
        out.1.push(dw);
        out.2.push(a);
    }
    out
}

/// The joints' forces (N) and torques (N mm), from the tool back to the base.
fn backward(
    bodies: &[Body],
    w: &[Vector3<f64>],
    dw: &[Vector3<f64>],
    acc: &[Vector3<f64>],
    tool: Vector3<f64>,
    force: &Vector3<f64>,
    moment: &Vector3<f64>,
) -> Vec<f64> {
    let (mut f, mut n, mut p_next) = (-force, -moment, tool);
    let mut tau = Vec::new();
    for (i, b) in bodies.iter().enumerate().rev() {
        let a_c = acc[i] + dw[i].cross(&b.r) + w[i].cross(&w[i].cross(&b.r));
        let big_f = a_c * b.mass;
        let big_n = b.inertia * dw[i] + w[i].cross(&(b.inertia * w[i]));
        n = big_n + b.r.cross(&big_f) + n + (p_next - b.p).cross(&f);
        f += big_f;
        p_next = b.p;
        if let Some((kind, z)) = b.axis {
            tau.push(match kind {
                JointKind::Revolute => z.dot(&n) * 1e3,
                JointKind::Prismatic => z.dot(&f),
            });
        }
    }
    tau.reverse();
    tau
}
