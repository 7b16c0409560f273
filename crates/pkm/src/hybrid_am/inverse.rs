//! The hybrid machine's inverse kinematics (module documentation of
//! [`super::HybridAm`]): the platform placed from the pose, each carriage above its
//! platform joint, the strut vectors and the rate vectors the derivatives take.

use nalgebra::{SMatrix, SVector, Vector3, Vector6};

use super::{HybridAm, Placement};
use crate::error::{Error, Result};
use crate::rotation::{ry, rz};

impl HybridAm {
    /// The platform and its joints at pose `x` (module documentation).
    #[inline]
    pub fn placement(&self, x: &SVector<f64, 6>) -> Placement {
        let beta = x[4] - self.tool_tilt;
        let rotation = ry(beta);
        let table = rz(-x[5]);
        let tip = self.table + table * Vector3::new(x[0], x[1], x[2]);
        let joints = std::array::from_fn(|i| tip + rotation * (self.legs[i].platform - self.tool));
        Placement {
            beta,
            rotation,
            table,
            tip,
            joints,
        }
    }

    /// Carriage reading of leg `i` with its platform joint at `p` (base frame): the
    /// carriage above the joint, `q = d_z + sqrt(L^2 - d_x^2 - d_y^2)`, `d = p - g_i`.
    #[inline]
    pub fn carriage(&self, i: usize, p: &Vector3<f64>) -> Result<f64> {
        let leg = &self.legs[i];
        let d = p - leg.guide;
        let h2 = leg.length * leg.length - d.x * d.x - d.y * d.y;
        if !(h2 >= 0.0) {
            return Err(Error::NotAttainable {
                reason: crate::error::Unattainable::StrutReach {
                    strut: leg.actuator.name.clone(),
                    joint: leg.platform_name.clone(),
                    length: leg.length,
                    distance: d.x.hypot(d.y),
                },
            });
        }
        Ok(d.z + h2.sqrt())
    }

    /// Carriage joint centre of leg `i` at reading `q` (base frame).
    #[inline]
    pub fn carriage_joint(&self, i: usize, q: f64) -> Vector3<f64> {
        self.legs[i].guide + Vector3::new(0.0, 0.0, q)
    }

    /// Strut vectors `s_i = P_i - c_i` (carriage joint to platform joint) at a
    /// placement with readings `q`.
    #[inline]
    pub(super) fn struts(&self, pl: &Placement, q: &SVector<f64, 5>) -> [Vector3<f64>; 4] {
        std::array::from_fn(|i| pl.joints[i] - self.carriage_joint(i, q[i]))
    }

    /// The placement at `x`, its readings and strut vectors: the inverse solution with
    /// what the derivatives need, the placement computed once.
    #[inline]
    pub(super) fn solve(
        &self,
        x: &Vector6<f64>,
    ) -> Result<(Placement, SVector<f64, 5>, [Vector3<f64>; 4])> {
        let pl = self.placement(x);
        let mut q = SVector::<f64, 5>::zeros();
        for i in 0..4 {
            q[i] = self.carriage(i, &pl.joints[i])?;
        }
        q[4] = x[5];
        let s = self.struts(&pl, &q);
        Ok((pl, q, s))
    }

    /// `d(q1..q4) / d(p_b, beta)` at a placement with rate vectors `k`: rows
    /// `[k_i^T, k_i . (e_y x (P_i - p_b))]`, the tip `p_b` in the base frame. The
    /// platform's part of the Jacobian; [`Mechanism::jacobian`] turns it to the part
    /// frame and [`Mechanism::condition`] measures it.
    #[inline]
    pub(super) fn platform_jacobian(pl: &Placement, k: &[Vector3<f64>; 4]) -> SMatrix<f64, 4, 4> {
        SMatrix::<f64, 4, 4>::from_fn(|i, c| match c {
            3 => k[i].dot(&Vector3::y().cross(&(pl.joints[i] - pl.tip))),
            _ => k[i][c],
        })
    }

    /// `s_i / s_iz`, or the inverse singularity (a horizontal strut).
    #[inline]
    pub(super) fn rate_vectors(&self, s: &[Vector3<f64>; 4]) -> Result<[Vector3<f64>; 4]> {
        let mut k = [Vector3::zeros(); 4];
        for i in 0..4 {
            if s[i].z.abs() <= 1e-9 * self.legs[i].length {
                return Err(Error::Singular {
                    what: format!(
                        "strut {} is horizontal (inverse singularity)",
                        self.legs[i].actuator.name
                    ),
                    rcond: 0.0,
                });
            }
            k[i] = s[i] / s[i].z;
        }
        Ok(k)
    }
}
