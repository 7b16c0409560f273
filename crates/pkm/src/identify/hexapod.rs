//! The hexapod's 42 parameters (seed 001): base joint centres `A_j` (18), platform joint
//! centres `B'_j` in the platform frame (18), and the strut lengths of the zero state
//! `L_j^(0)` (6, the actuators' zero readings), with seed 001's procedure.

use nalgebra::{SMatrix, SVector, Vector3, Vector6};

use super::struts::{self, StrutMachine};
use super::{measured_poses, Identifiable, Measurements};
use crate::error::{Error, Result};
use crate::hexapod::Hexapod;
use crate::legs::split_pose;
use crate::machine::StrutGeometry;
use crate::mechanism::Mechanism;

impl StrutMachine<6> for Hexapod {
    fn struts(&self) -> [StrutGeometry; 6] {
        std::array::from_fn(|j| {
            let s = &self.hex_struts()[j];
            StrutGeometry {
                name: s.actuator.name.clone(),
                base_name: s.base_name.clone(),
                platform_name: s.platform_name.clone(),
                base: s.base,
                platform: s.platform,
            }
        })
    }

    fn tool(&self) -> Vector3<f64> {
        Hexapod::tool(self)
    }

    fn with_struts(&self, struts: &[StrutGeometry; 6]) -> Self {
        let mut s = self.hex_struts().clone();
        for (st, g) in s.iter_mut().zip(struts) {
            st.base = g.base;
            st.platform = g.platform;
        }
        let mut h = Hexapod::new(
            self.info().name().to_string(),
            s,
            self.tool(),
            self.strut_diameter(),
            self.info().home(),
        );
        h.set_zero_lengths(self.zero_lengths());
        h.set_axes(self.axes().clone());
        h
    }

    fn calibrated_zero(&self) -> Option<Vector6<f64>> {
        self.zero_lengths()
    }

    fn set_joints(&mut self, base: &[Vector3<f64>; 6], platform: &[Vector3<f64>; 6]) {
        self.set_joint_centres(base, platform);
    }
}

/// Result of seed 001's procedure.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SeedProcedure {
    /// The parameters in [`super::parameter_names`] order (42 for a hexapod).
    pub values: Vec<f64>,
    /// Condition number of each strut's 7 x 7 system at its solution (columns scaled
    /// to unit norm).
    pub conditions: Vec<f64>,
    /// Newton iterations per strut.
    pub iterations: Vec<usize>,
}

/// The measured states seed 001's procedure uses: as many as each strut has
/// parameters (its base joint, its platform joint, its zero length), whatever the
/// number of struts.
pub const SEED_PROCEDURE_STATES: usize = 7;

/// Seed 001's procedure: seven measured states (full poses from the fixture) give
/// `7 x 6 = 42` equations that split into six independent systems of seven: strut
/// `j`'s parameters `A_j`, `B'_j`, `L_j^(0)` appear only in its own seven equations
/// `|p_i + R_i (B'_j - t) - A_j| = L_j^(0) + dL_ij`. Each is solved by Newton from the
/// nominal values. Uses the first seven states; fails with [`Error::NotConverged`]
/// when a system does not converge and [`Error::Singular`] when one is singular (the
/// states do not separate that strut's parameters).
/// Written for any strut machine (the systems decouple for every one).
pub fn seed_procedure<M: StrutMachine<A>, const A: usize>(
    nominal: &M,
    zero: &SVector<f64, A>,
    meas: &Measurements,
) -> Result<SeedProcedure> {
    if meas.states.len() < SEED_PROCEDURE_STATES {
        return Err(Error::InvalidInput {
            what: "seed 001 procedure".into(),
            message: format!(
                "needs seven states, the measurements have {}",
                meas.states.len()
            ),
        });
    }
    let seven = Measurements {
        fixture: meas.fixture.clone(),
        states: meas.states[..SEED_PROCEDURE_STATES].to_vec(),
    };
    let poses = measured_poses(nominal, &seven)?;
    let g = nominal.geometry();
    let mut values = g.clone();
    values.extend(zero.iter());
    let mut conditions = vec![0.0; A];
    let mut iterations = vec![0; A];
    let names = nominal.struts();
    let t = nominal.tool();
    for j in 0..A {
        let u = SVector::<f64, 7>::from_fn(|k, _| match k {
            0..=2 => g[3 * j + k],
            3..=5 => g[3 * A + 3 * j + k - 3],
            _ => zero[j],
        });
        let readings = std::array::from_fn(|i| seven.states[i].readings[j]);
        let (u, it, condition) = solve_strut(&poses, &readings, &t, u, &names[j].name)?;
        conditions[j] = condition;
        iterations[j] = it;
        for k in 0..3 {
            values[3 * j + k] = u[k];
            values[3 * A + 3 * j + k] = u[3 + k];
        }
        values[6 * A + j] = u[6];
    }
    Ok(SeedProcedure {
        values,
        conditions,
        iterations,
    })
}

/// One strut's system of seed 001 at its parameters `u` (`A_j`, `B'_j`, `L_j^(0)`): the
/// lengths at the seven `poses` less the strut's `readings`, and their Jacobian.
fn strut_system(
    poses: &[Vector6<f64>],
    readings: &[f64; 7],
    t: &Vector3<f64>,
    u: &SVector<f64, 7>,
) -> (SVector<f64, 7>, SMatrix<f64, 7, 7>) {
    let a = Vector3::new(u[0], u[1], u[2]);
    let b = Vector3::new(u[3], u[4], u[5]);
    let mut f = SVector::<f64, 7>::zeros();
    let mut jac = SMatrix::<f64, 7, 7>::zeros();
    for (i, x) in poses.iter().enumerate() {
        let (p, r) = split_pose(x);
        let (l, da, db) = struts::strut_length(&p, &r, &a, &b, t);
        f[i] = l - u[6] - readings[i];
        for k in 0..3 {
            jac[(i, k)] = da[k];
            jac[(i, 3 + k)] = db[k];
        }
        jac[(i, 6)] = -1.0;
    }
    (f, jac)
}

/// Newton on strut `name`'s system from `u`: its parameters, the iterations taken and
/// the condition number of its column-scaled Jacobian.
fn solve_strut(
    poses: &[Vector6<f64>],
    readings: &[f64; 7],
    t: &Vector3<f64>,
    mut u: SVector<f64, 7>,
    name: &str,
) -> Result<(SVector<f64, 7>, usize, f64)> {
    let mut converged = false;
    let mut it = 0;
    while it < 50 {
        let (f, jac) = strut_system(poses, readings, t, &u);
        let scale = f.amax();
        let lu = jac.lu();
        let Some(step) = lu.solve(&f) else {
            return Err(Error::Singular {
                what: format!(
                    "seed 001 system of strut {name} (the states do not separate its parameters)"
                ),
                rcond: 0.0,
            });
        };
        u -= step;
        it += 1;
        // Converged when the step is at rounding level, or the residual is: on a
        // large, ill-conditioned system (condition ~1e5) rounding keeps the steps
        // above 1e-12 of the parameters while the residual sits at 1e-13 mm.
        let rounding = 1e-12 * (1.0 + u.amax());
        if step.amax() < rounding || scale < rounding {
            converged = true;
            break;
        }
    }
    let (f, jac) = strut_system(poses, readings, t, &u);
    if !converged || f.amax() > 1e-8 {
        return Err(Error::NotConverged {
            solver: "seed 001 procedure (Newton, one strut)",
            iterations: it,
            residual: f.amax(),
        });
    }
    let mut js = jac;
    for c in 0..7 {
        let nrm = js.column(c).norm();
        js.column_mut(c).scale_mut(1.0 / nrm);
    }
    let sv = js.singular_values();
    Ok((u, it, sv.max() / sv.min()))
}
