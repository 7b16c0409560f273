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

/// Links a chain may have beyond its base (pkm loads at most 8 joints; fixed links
/// between them count too): the walk keeps them on the stack.
pub const MAX_LINKS: usize = 24;

/// The base-frame state of one moving link of the walk (SI units).
#[derive(Clone, Copy)]
struct Body {
    /// Origin of `S_i` (m).
    p: Vector3<f64>,
    /// Joint kind and axis (unit); `None` for a link without joint.
    axis: Option<(JointKind, Vector3<f64>)>,
    /// Mass (kg), centre of mass from `p` (m), inertia in base axes (kg m^2).
    mass: f64,
    r: Vector3<f64>,
    inertia: Matrix3<f64>,
    /// Angular velocity, angular acceleration, acceleration of `p`.
    w: Vector3<f64>,
    dw: Vector3<f64>,
    a: Vector3<f64>,
}

const REST: Body = Body {
    p: Vector3::new(0.0, 0.0, 0.0),
    axis: None,
    mass: 0.0,
    r: Vector3::new(0.0, 0.0, 0.0),
    inertia: Matrix3::new(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
    w: Vector3::new(0.0, 0.0, 0.0),
    dw: Vector3::new(0.0, 0.0, 0.0),
    a: Vector3::new(0.0, 0.0, 0.0),
};

/// The joint forces and torques (N, N mm) that move `chain` with joint positions `q`,
/// rates `qd` and accelerations `qdd` (mm or rad, per s, per s^2) under gravity
/// `gravity` (mm/s^2, base frame), the tool pushed by `force` (N, at the tool frame's
/// origin) and `moment` (N mm), both in the base frame. Nothing is allocated but the
/// result.
///
/// Fails when the counts differ from the chain's joints, when the chain has more than
/// [`MAX_LINKS`] links, or when no link has mass properties.
pub fn inverse_dynamics(
    chain: &Chain,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    gravity: &Vector3<f64>,
    force: &Vector3<f64>,
    moment: &Vector3<f64>,
) -> Result<Vec<f64>> {
    let mut tau = vec![0.0; q.len()];
    inverse_dynamics_into(chain, [q, qd, qdd], gravity, [force, moment], &mut tau)?;
    Ok(tau)
}

/// [`inverse_dynamics`] into `tau` (one value per joint): no allocation at all, for
/// sweeps. `state` is `[q, qd, qdd]`, `load` `[force, moment]`.
pub fn inverse_dynamics_into(
    chain: &Chain,
    [q, qd, qdd]: [&[f64]; 3],
    gravity: &Vector3<f64>,
    [force, moment]: [&Vector3<f64>; 2],
    tau: &mut [f64],
) -> Result<()> {
    check(chain, q, qd, qdd)?;
    if tau.len() != q.len() {
        return Err(Error::InvalidInput {
            what: format!("chain `{}`: inverse dynamics", chain.name),
            message: format!("expected room for {} values, found {}", q.len(), tau.len()),
        });
    }
    let mut bodies = [REST; MAX_LINKS];
    let n = chain.links.len() - 1;
    let tool = walk(chain, q, &mut bodies[..n]);
    forward(&mut bodies[..n], qd, qdd, &(gravity * 1e-3));
    backward(&bodies[..n], tool, force, &(moment * 1e-3), tau);
    Ok(())
}

fn check(chain: &Chain, q: &[f64], qd: &[f64], qdd: &[f64]) -> Result<()> {
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
    if chain.links.is_empty() || chain.links.len() > MAX_LINKS + 1 {
        return Err(Error::InvalidInput {
            what: format!("chain `{}`: inverse dynamics", chain.name),
            message: format!(
                "expected 1 to {} links, found {}",
                MAX_LINKS + 1,
                chain.links.len()
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
    Ok(())
}

/// The moving links in the base frame at `q` into `bodies`; the tool frame's origin (m).
fn walk(chain: &Chain, q: &[f64], bodies: &mut [Body]) -> Vector3<f64> {
    let none = LinkDeviation::default();
    let mut t = link_transform(&chain.links[0], &none);
    let mut k = 0;
    for (link, b) in chain.links[1..].iter().zip(bodies.iter_mut()) {
        b.axis = link.joint.as_ref().map(|j| {
            let z = Vector3::new(t[(0, 2)], t[(1, 2)], t[(2, 2)]);
            t *= joint_transform(j.kind, q[k]);
            k += 1;
            (j.kind, z)
        });
        let r = t.fixed_view::<3, 3>(0, 0).into_owned();
        b.p = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]) * 1e-3;
        if let Some(m) = &link.inertial {
            b.mass = m.mass;
            b.r = r * m.com * 1e-3;
            b.inertia = r * m.inertia * r.transpose() * 1e-6;
        }
        t *= link_transform(link, &none);
    }
    Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]) * 1e-3
}

/// Angular velocity, angular acceleration and the acceleration of each origin (SI),
/// from the base out.
fn forward(bodies: &mut [Body], qd: &[f64], qdd: &[f64], g: &Vector3<f64>) {
    let (mut w, mut dw, mut a) = (Vector3::zeros(), Vector3::zeros(), -g);
    let mut p = Vector3::zeros();
    let si = |kind: JointKind, v: f64| match kind {
        JointKind::Prismatic => v * 1e-3,
        JointKind::Revolute => v,
    };
    let mut k = 0;
    for b in bodies.iter_mut() {
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
        (b.w, b.dw, b.a) = (w, dw, a);
    }
}

/// The joints' forces (N) and torques (N mm) into `tau`, from the tool back to the
/// base.
fn backward(
    bodies: &[Body],
    tool: Vector3<f64>,
    force: &Vector3<f64>,
    moment: &Vector3<f64>,
    tau: &mut [f64],
) {
    let (mut f, mut n, mut p_next) = (-force, -moment, tool);
    let mut k = tau.len();
    for b in bodies.iter().rev() {
        let (w, dw) = (&b.w, &b.dw);
        let a_c = b.a + dw.cross(&b.r) + w.cross(&w.cross(&b.r));
        let big_f = a_c * b.mass;
        let big_n = b.inertia * dw + w.cross(&(b.inertia * w));
        n = big_n + b.r.cross(&big_f) + n + (p_next - b.p).cross(&f);
        f += big_f;
        p_next = b.p;
        if let Some((kind, z)) = b.axis {
            k -= 1;
            tau[k] = match kind {
                JointKind::Revolute => z.dot(&n) * 1e3,
                JointKind::Prismatic => z.dot(&f),
            };
        }
    }
}
