//! The [`Mechanism`] of a serial machine tool in tool-centre-point coordinates: the
//! trait's answers from [`TcpMachine`]'s solver (module docs of [`super`]).

use nalgebra::{Isometry3, SMatrix, SVector, Translation3, Vector3};

use super::TcpMachine;
use crate::error::{Error, Result};
use crate::limits::Violation;
use crate::mechanism::{ActuatorMotion, Forward, Mechanism, MechanismInfo, Skeleton, ToolAxis};
use crate::pose::Pose;
use crate::serial::mechanism::chain_skeleton;
use crate::serial::JointKind;

impl<const N: usize> Mechanism<N, N> for TcpMachine<N> {
    fn info(&self) -> &MechanismInfo<N, N> {
        &self.info
    }

    /// Closed form: the rotary joints at the pose's angles, the linear ones from
    /// `M q_lin = x_p - p_0` (module docs).
    fn inverse(&self, x: &SVector<f64, N>) -> Result<SVector<f64, N>> {
        Ok(self.solve(x)?.0)
    }

    fn jacobian(&self, x: &SVector<f64, N>) -> Result<SMatrix<f64, N, N>> {
        let (q, rel0, minv) = self.solve(x)?;
        let rel = self.at_solution(&rel0, &q);
        let mut j = SMatrix::<f64, N, N>::zeros();
        for (r, &lj) in self.linear.iter().enumerate() {
            for c in 0..3 {
                j[(lj, c)] = minv[(r, c)];
            }
        }
        for k in 3..N {
            let rj = self.rotary[k - 3];
            j[(rj, k)] = 1.0;
            let g = minv * rel.column(rj, JointKind::Revolute);
            for (r, &lj) in self.linear.iter().enumerate() {
                j[(lj, k)] = -g[r];
            }
        }
        Ok(j)
    }

    fn forward(&self, q: &SVector<f64, N>, _start: &SVector<f64, N>) -> Result<Forward<N>> {
        if q.iter().any(|v| !v.is_finite()) {
            return Err(Error::InvalidInput {
                what: "actuators".into(),
                message: "not a finite number".into(),
            });
        }
        Ok(Forward {
            pose: self.coords_of_joints(q),
            iterations: 0,
            residual: 0.0,
        })
    }

    /// The nominal tool pose relative to the part (the orientation by
    /// [`crate::rotation::orthonormal_quaternion`]: the frame is a product of the
    /// nominal chains' rotations).
    fn tool_pose(&self, x: &SVector<f64, N>) -> Result<Pose> {
        let (q, rel0, _) = self.solve(x)?;
        let rel = self.at_solution(&rel0, &q);
        Ok(Isometry3::from_parts(
            Translation3::from(rel.tip),
            crate::rotation::orthonormal_quaternion(&rel.frame),
        ))
    }

    /// The tip of `pose` and the rotary angles that point the tool along its Z axis
    /// (the branch nearest home when the orientation is given; home's angles otherwise).
    fn coords_from_pose(&self, pose: &Pose, orientation_given: bool) -> Result<SVector<f64, N>> {
        let p = pose.translation.vector;
        let mut x = self.info.home();
        x[0] = p.x;
        x[1] = p.y;
        x[2] = p.z;
        if orientation_given {
            let axis = pose.rotation * Vector3::z();
            let near: Vec<f64> = (3..N).map(|k| self.info.home()[k]).collect();
            let sol = self.rotary_for_axis(&axis, Some(&near))?;
            for k in 3..N {
                x[k] = sol.chosen()[k - 3];
            }
        }
        Ok(x)
    }

    fn check_limits(&self, _x: &SVector<f64, N>, q: &SVector<f64, N>, out: &mut Vec<Violation>) {
        self.position_limits
            .check(self.info.actuators(), q.as_slice(), out);
    }

    fn skeleton(&self, x: &SVector<f64, N>) -> Result<Skeleton> {
        let q = self.inverse(x)?;
        let (qt, qw) = q.as_slice().split_at(self.tool_joints);
        chain_skeleton(&self.machine, qt, qw)
    }

    fn tool_axis(&self) -> Option<&dyn ToolAxis<N>> {
        Some(self)
    }

    /// The 2-norm condition number of `dq/dx` with every angle, of a coordinate (column)
    /// or of a rotary axis (row), counted as [`MechanismInfo::characteristic_length`] mm per
    /// radian: the default scales only the columns, and a rotary axis' own row (1 rad
    /// per rad) would then weigh a 150th of a slide's.
    fn condition(&self, x: &SVector<f64, N>) -> Result<f64> {
        let mut j = crate::mechanism::scaled_driven_jacobian(self, x)?;
        for (r, a) in self.info.actuators().iter().enumerate() {
            if a.quantity == crate::units::Quantity::Angle {
                j.row_mut(r).scale_mut(self.info.characteristic_length());
            }
        }
        Ok(crate::linalg::condition_number(&j))
    }

    fn with_tool_length(&self, length: f64) -> Option<Result<Self>> {
        Some(TcpMachine::with_tool_length(self, length))
    }

    /// Exact: `q' = J x'`, `M q_lin'' = x_p'' - G x_r'' - J' q'` (module docs).
    fn actuator_motion(
        &self,
        x: &SVector<f64, N>,
        xd: &SVector<f64, N>,
        xdd: &SVector<f64, N>,
    ) -> Result<ActuatorMotion<N>> {
        let (q, rel0, minv) = self.solve(x)?;
        let rel = self.at_solution(&rel0, &q);
        let qd = self.rates(&rel, &minv, xd, Vector3::zeros());
        let h = self.velocity_product(&rel, &qd);
        let qdd = self.rates(&rel, &minv, xdd, h);
        Ok(ActuatorMotion { q, qd, qdd })
    }
}

impl<const N: usize> ToolAxis<N> for TcpMachine<N> {
    fn poses_for_tool_axis(
        &self,
        tip: &Vector3<f64>,
        axis: &Vector3<f64>,
        near: Option<&SVector<f64, N>>,
    ) -> Result<crate::mechanism::ToolAxisPoses<N>> {
        let near: Option<Vec<f64>> = near.map(|x| x.as_slice()[3..].to_vec());
        self.rotary_for_axis(axis, near.as_deref())
            .map(|sol| crate::mechanism::ToolAxisPoses {
                branches: sol
                    .branches
                    .iter()
                    .map(|b| crate::serial::tcp_axis::tcp_coords(tip, b))
                    .collect(),
                chosen: sol.chosen,
                singular: sol.singular,
                singular_distance: sol.singular_distance,
            })
    }

    fn singular_distance(&self, x: &SVector<f64, N>) -> Option<f64> {
        self.singular_angle(x)
    }
}
