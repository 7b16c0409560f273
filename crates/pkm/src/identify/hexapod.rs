//! The hexapod's 42 parameters (seed 001): base joint centres `A_j` (18), platform joint
//! centres `B'_j` in the platform frame (18), and the strut lengths of the zero state
//! `L_j^(0)` (6, the actuators' zero readings), with seed 001's procedure.

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3, Vector6};

use super::{measured_poses, Identifiable, Measurements};
use crate::error::{Error, Result};
use crate::hexapod::Hexapod;
use crate::legs::split_pose;
use crate::mechanism::Mechanism;
use crate::rotation::{rpy_rate_matrix, Convention};

/// Joint names per strut: the file's names, or `name[strut]` when struts share a joint
/// (each strut then has its own parameters).
fn joint_names(h: &Hexapod) -> ([String; 6], [String; 6]) {
    fn unique(names: [&str; 6], h: &Hexapod) -> [String; 6] {
        std::array::from_fn(|i| {
            let shared = (0..6).any(|k| k != i && names[k] == names[i]);
            if shared {
                format!("{}[{}]", names[i], h.struts[i].actuator.name)
            } else {
                names[i].to_string()
            }
        })
    }
    (
        unique(std::array::from_fn(|i| h.struts[i].base_name.as_str()), h),
        unique(
            std::array::from_fn(|i| h.struts[i].platform_name.as_str()),
            h,
        ),
    )
}

impl Identifiable<6, 6> for Hexapod {
    /// `A.x, A.y, A.z` of strut 1..6's base joint, then `B.x, ...` of its platform joint
    /// (named as in the file).
    fn geometry_names(&self) -> Vec<String> {
        let (a, b) = joint_names(self);
        let axes = ["x", "y", "z"];
        a.iter()
            .chain(b.iter())
            .flat_map(|n| axes.iter().map(move |ax| format!("{n}.{ax}")))
            .collect()
    }

    fn geometry(&self) -> Vec<f64> {
        let a = self.struts.iter().flat_map(|s| s.base.iter().copied());
        let b = self.struts.iter().flat_map(|s| s.platform.iter().copied());
        a.chain(b).collect()
    }

    fn with_geometry(&self, g: &[f64]) -> Result<Self> {
        if g.len() != 36 {
            return Err(Error::InvalidInput {
                what: "hexapod geometry".into(),
                message: format!("expected 36 joint coordinates, got {}", g.len()),
            });
        }
        let mut struts = self.struts.clone();
        for (j, s) in struts.iter_mut().enumerate() {
            s.base = Vector3::new(g[3 * j], g[3 * j + 1], g[3 * j + 2]);
            s.platform = Vector3::new(g[18 + 3 * j], g[19 + 3 * j], g[20 + 3 * j]);
        }
        let mut h = Hexapod::new(
            self.name.clone(),
            struts,
            self.tool,
            self.strut_diameter,
            self.home,
        );
        h.zero_lengths = self.zero_lengths;
        Ok(h)
    }

    /// `L_j = |p + R (B'_j - t) - A_j|` (seed 001 eq. 1 with the tool offset `t`):
    /// `dL_j/dA_j = -n_j^T`, `dL_j/dB'_j = n_j^T R`, `n_j` the unit strut vector.
    fn inverse_with_geometry_jacobian(
        &self,
        x: &Vector6<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<Vector6<f64>> {
        let (p, r) = split_pose(x);
        jac.fill(0.0);
        let mut q = Vector6::zeros();
        for (j, s) in self.struts.iter().enumerate() {
            let v = p + r * (s.platform - self.tool) - s.base;
            let l = v.norm();
            if l <= 0.0 {
                return Err(Error::Singular {
                    what: format!("strut {} of zero length", s.actuator.name),
                    rcond: 0.0,
                });
            }
            let n = v / l;
            let nb = r.transpose() * n;
            q[j] = l;
            for k in 0..3 {
                jac[(j, 3 * j + k)] = -n[k];
                jac[(j, 18 + 3 * j + k)] = nb[k];
            }
        }
        Ok(q)
    }

    /// `P = p + R (s - t)`; `dP/dx = [I, -[R (s - t)]x E(A, B, C)]`.
    fn platform_point(
        &self,
        x: &Vector6<f64>,
        s: &Vector3<f64>,
    ) -> (Vector3<f64>, SMatrix<f64, 3, 6>) {
        let (p, r) = split_pose(x);
        let v = r * (s - self.tool);
        let mut d = SMatrix::<f64, 3, 6>::zeros();
        d.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&Matrix3::identity());
        let e = rpy_rate_matrix([x[3], x[4], x[5]]);
        d.fixed_view_mut::<3, 3>(0, 3)
            .copy_from(&(-v.cross_matrix() * e));
        (p + v, d)
    }

    fn coords_from_platform_frame(&self, c: &Vector3<f64>, r: &Matrix3<f64>) -> Vector6<f64> {
        let p = c + r * self.tool;
        let a = Convention::Rpy.from_matrix(r);
        Vector6::new(p.x, p.y, p.z, a[0], a[1], a[2])
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
