//! Inverse dynamics of a loaded machine: the joint forces and torques that move it
//! along given positions, rates and accelerations under gravity and a wrench on the
//! tool ([`crate::serial::dynamics`] for serial machines and robots).

use nalgebra::Vector3;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::machine::{Machine, Model};
use crate::serial::dynamics::GRAVITY;
use crate::serial::Chain;

/// What [`inverse_dynamics`] computes (internal units).
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicsOptions {
    /// Gravity in the base frame (mm/s^2); default [`GRAVITY`], 9.80665 m/s^2 along -Z.
    pub gravity: Vector3<f64>,
    /// The load on the tool: force (N, at the tool frame's origin), moment (N mm), base
    /// frame.
    pub wrench: [f64; 6],
}

impl Default for DynamicsOptions {
    fn default() -> Self {
        DynamicsOptions {
            gravity: GRAVITY,
            wrench: [0.0; 6],
        }
    }
}

/// The chain of a machine inverse dynamics runs on, or why there is none.
fn chain(machine: &Machine) -> Result<&Chain> {
    let unsupported = |reason: &str| Error::Unsupported {
        machine: machine.mechanism().name().into(),
        kind: machine.mechanism().kind().into(),
        analysis: "inverse dynamics",
        reason: reason.into(),
    };
    match &machine.model {
        Model::Serial(s) => {
            let m = s.mechanism.machine();
            if m.workpiece.as_ref().is_some_and(|w| w.dof() > 0) {
                return Err(unsupported(
                    "its workpiece chain moves: only tool chains are modelled yet",
                ));
            }
            Ok(&m.tool)
        }
        _ => Err(unsupported(
            "only serial machines and robots have inverse dynamics yet",
        )),
    }
}

/// The joint forces (N) and torques (N mm) of `machine` at joint positions `q`, rates
/// `qd` and accelerations `qdd` (mm or rad, per s, per s^2), one value per joint.
///
/// # Examples
///
/// A UR5-class arm with the masses of its URDF, held still: the shoulder carries the
/// arm's weight, the base joint (vertical) none.
///
/// ```
/// use pkm::analysis::dynamics::{inverse_dynamics, DynamicsOptions};
/// let robot = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/robots/ur5-like.urdf"
/// ))
/// .unwrap();
/// let q = [0.0, -1.0, 0.5, 0.0, 0.0, 0.0];
/// let t = inverse_dynamics(&robot, &q, &[0.0; 6], &[0.0; 6], &DynamicsOptions::default())
///     .unwrap();
/// assert!(t[0].abs() < 1e-6);
/// assert!(t[1].abs() > 10e3); // more than 10 N m, in N mm
/// ```
pub fn inverse_dynamics(
    machine: &Machine,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    o: &DynamicsOptions,
) -> Result<Vec<f64>> {
    let w = &o.wrench;
    crate::serial::dynamics::inverse_dynamics(
        chain(machine)?,
        q,
        qd,
        qdd,
        &o.gravity,
        &Vector3::new(w[0], w[1], w[2]),
        &Vector3::new(w[3], w[4], w[5]),
    )
}

/// [`inverse_dynamics`] of many rows (`q`, `qd`, `qdd`: rows of one value per joint,
/// one after another), on every core: the torques row after row.
pub fn inverse_dynamics_batch(
    machine: &Machine,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    o: &DynamicsOptions,
) -> Result<Vec<f64>> {
    let n = chain(machine)?.dof();
    if n == 0 || !q.len().is_multiple_of(n) || qd.len() != q.len() || qdd.len() != q.len() {
        return Err(Error::InvalidInput {
            what: "inverse dynamics".into(),
            message: format!(
                "expected three arrays of rows of {n} values, found {}, {} and {} values",
                q.len(),
                qd.len(),
                qdd.len()
            ),
        });
    }
    let c = chain(machine)?;
    let w = &o.wrench;
    let (force, moment) = (
        Vector3::new(w[0], w[1], w[2]),
        Vector3::new(w[3], w[4], w[5]),
    );
    let mut out = vec![0.0; q.len()];
    out.par_chunks_mut(n)
        .zip(q.par_chunks(n).zip(qd.par_chunks(n)).zip(qdd.par_chunks(n)))
        .try_for_each(|(tau, ((q, qd), qdd))| {
            crate::serial::dynamics::inverse_dynamics_into(
                c,
                [q, qd, qdd],
                &o.gravity,
                [&force, &moment],
                tau,
            )
        })?;
    Ok(out)
}
