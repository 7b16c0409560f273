//! The hexapod's 42 parameters (seed 001): base joint centres `A_j` (18), platform joint
//! centres `B'_j` in the platform frame (18), and the strut lengths of the zero state
//! `L_j^(0)` (6, the actuators' zero readings), with seed 001's procedure.

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3, Vector6};

use super::{measured_poses, struts, Identifiable, Measurements};
use crate::error::{Error, Result};
use crate::hexapod::Hexapod;
use crate::legs::split_pose;
use crate::mechanism::Mechanism;

impl Identifiable<6, 6> for Hexapod {
    /// `A.x, A.y, A.z` of strut 1..6's base joint, then `B.x, ...` of its platform joint
    /// (named as in the file).
    fn geometry_names(&self) -> Vec<String> {
        let b: Vec<&str> = self.struts.iter().map(|s| s.base_name.as_str()).collect();
        let p: Vec<&str> = self
            .struts
            .iter()
            .map(|s| s.platform_name.as_str())
            .collect();
        let n: Vec<&str> = self
            .struts
            .iter()
            .map(|s| s.actuator.name.as_str())
            .collect();
        struts::names(&b, &p, &n)
    }

    fn geometry(&self) -> Vec<f64> {
        let a = self.struts.iter().flat_map(|s| s.base.iter().copied());
        let b = self.struts.iter().flat_map(|s| s.platform.iter().copied());
        a.chain(b).collect()
    }

    fn with_geometry(&self, g: &[f64]) -> Result<Self> {
        let (base, platform) = struts::split::<6>(g)?;
        let mut s = self.struts.clone();
        for (j, st) in s.iter_mut().enumerate() {
            st.base = base[j];
            st.platform = platform[j];
        }
        let mut h = Hexapod::new(
            self.name.clone(),
            s,
            self.tool,
            self.strut_diameter,
            self.home,
        );
        h.zero_lengths = self.zero_lengths;
        Ok(h)
    }

    /// `L_j = |p + R (B'_j - t) - A_j|` (seed 001 eq. 1 with the tool offset `t`).
    fn inverse_with_geometry_jacobian(
        &self,
        x: &Vector6<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<Vector6<f64>> {
        struts::lengths_with_jacobian(
            &std::array::from_fn(|j| self.struts[j].base),
            &std::array::from_fn(|j| self.struts[j].platform),
            &self.tool,
            x,
            jac,
        )
    }

    fn platform_point(
        &self,
        x: &Vector6<f64>,
        s: &Vector3<f64>,
    ) -> (Vector3<f64>, SMatrix<f64, 3, 6>) {
        struts::platform_point(&self.tool, x, s)
    }

    fn coords_from_platform_frame(&self, c: &Vector3<f64>, r: &Matrix3<f64>) -> Vector6<f64> {
        struts::coords_from_platform_frame(&self.tool, c, r)
    }

    fn explain(&self, terms: &[(usize, f64)]) -> Option<String> {
        let (p, r) = crate::legs::split_pose(&self.home());
        let s = &self.struts;
        let dirs: [Vector3<f64>; 6] =
            std::array::from_fn(|j| (p + r * (s[j].platform - self.tool) - s[j].base).normalize());
        struts::explain(terms, &super::parameter_names(self), &dirs, &r)
    }
}

/// Result of seed 001's procedure.
#[derive(Debug, Clone, PartialEq)]
pub struct SeedProcedure {
    /// The 42 parameters in [`super::parameter_names`] order.
    pub values: Vec<f64>,
    /// Condition number of each strut's 7 x 7 system at its solution (columns scaled
    /// to unit norm).
    pub conditions: [f64; 6],
    /// Newton iterations per strut.
    pub iterations: [usize; 6],
}

/// Seed 001's procedure: seven measured states (full poses from the fixture) give
/// `7 x 6 = 42` equations that split into six independent systems of seven: strut
/// `j`'s parameters `A_j`, `B'_j`, `L_j^(0)` appear only in its own seven equations
/// `|p_i + R_i (B'_j - t) - A_j| = L_j^(0) + dL_ij`. Each is solved by Newton from the
/// nominal values. Uses the first seven states; fails with [`Error::NotConverged`]
/// when a system does not converge and [`Error::Singular`] when one is singular (the
/// states do not separate that strut's parameters).
pub fn seed_procedure(
    nominal: &Hexapod,
    zero: &Vector6<f64>,
    meas: &Measurements,
) -> Result<SeedProcedure> {
    if meas.states.len() < 7 {
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
        states: meas.states[..7].to_vec(),
    };
    let poses = measured_poses(nominal, &seven)?;
    let g = nominal.geometry();
    let mut values = g.clone();
    values.extend(zero.iter());
    let mut conditions = [0.0; 6];
    let mut iterations = [0; 6];
    for j in 0..6 {
        let mut u = SVector::<f64, 7>::from_fn(|k, _| match k {
            0..=2 => g[3 * j + k],
            3..=5 => g[18 + 3 * j + k - 3],
            _ => zero[j],
        });
        let t = nominal.tool;
        let eval = |u: &SVector<f64, 7>| {
            let a = Vector3::new(u[0], u[1], u[2]);
            let b = Vector3::new(u[3], u[4], u[5]);
            let mut f = SVector::<f64, 7>::zeros();
            let mut jac = SMatrix::<f64, 7, 7>::zeros();
            for (i, x) in poses.iter().enumerate() {
                let (p, r) = split_pose(x);
                let v = p + r * (b - t) - a;
                let l = v.norm();
                let n = v / l;
                let nb = r.transpose() * n;
                f[i] = l - u[6] - seven.states[i].readings[j];
                for k in 0..3 {
                    jac[(i, k)] = -n[k];
                    jac[(i, 3 + k)] = nb[k];
                }
                jac[(i, 6)] = -1.0;
            }
            (f, jac)
        };
        let mut converged = false;
        let mut it = 0;
        while it < 50 {
            let (f, jac) = eval(&u);
            let scale = f.amax();
            let lu = jac.lu();
            let Some(step) = lu.solve(&f) else {
                return Err(Error::Singular {
                    what: format!(
                        "seed 001 system of strut {} (the states do not separate its parameters)",
                        nominal.struts[j].actuator.name
                    ),
                    rcond: 0.0,
                });
            };
            u -= step;
            it += 1;
            if step.amax() < 1e-12 * (1.0 + u.amax()) || scale < 1e-13 {
                converged = true;
                break;
            }
        }
        let (f, jac) = eval(&u);
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
        conditions[j] = sv.max() / sv.min();
        iterations[j] = it;
        for k in 0..3 {
            values[3 * j + k] = u[k];
            values[18 + 3 * j + k] = u[3 + k];
        }
        values[36 + j] = u[6];
    }
    Ok(SeedProcedure {
        values,
        conditions,
        iterations,
    })
}

/// A hexapod's zero readings `L^(0)`: the calibrated ones from its file
/// (`[calibration] zero_lengths`), else its strut lengths at home (the zero state of
/// the measurements pkm simulates).
pub fn zero_lengths(h: &Hexapod) -> Result<Vector6<f64>> {
    match h.zero_lengths {
        Some(z) => Ok(z),
        None => h.inverse(&h.home()),
    }
}
