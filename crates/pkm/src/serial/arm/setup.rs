//! Building a [`SerialArm`]: the checks of its chains, its reach, and the inverse it
//! takes.

use nalgebra::{Matrix4, Vector3, Vector6};

use super::{closed_form, SerialArm};
use crate::error::{Error, Result};
use crate::limits::PositionLimits;
use crate::mechanism::{spatial_coordinates, Actuator, MechanismInfo, PoseSpace};
use crate::serial::machine::SerialMachine;
use crate::serial::{Chain, JointKind, PreparedChain};

impl SerialArm {
    /// Wraps a machine whose tool chain has six joints and whose workpiece chain (if
    /// any) has none; `home` are the home joint values in internal units.
    pub fn new(machine: SerialMachine, home: Vector6<f64>) -> Result<Self> {
        if machine.tool.dof() != 6 {
            return Err(invalid(format!(
                "tool-pose coordinates need six tool-chain joints, found {}",
                machine.tool.dof()
            )));
        }
        let part_inverse = part_inverse(&machine)?;
        let joints: Vec<_> = machine.tool.joints().cloned().collect();
        let actuators: [Actuator; 6] = std::array::from_fn(|i| joints[i].actuator());
        let position_limits = PositionLimits::new("joint", &actuators);
        let tool = PreparedChain::new(&machine.tool, &[], &[]);
        let mut arm = SerialArm {
            info: MechanismInfo::new(
                machine.name.clone(),
                "serial",
                spatial_coordinates(),
                actuators,
                PoseSpace::Spatial,
                Vector6::zeros(),
            )
            .with_forward_closed_form(),
            machine,
            home_joints: home,
            tool,
            part_inverse,
            position_limits,
            completions: Vec::new(),
            base_origin: Vector3::zeros(),
            reach: f64::INFINITY,
            wrist: None,
        };
        arm.base_origin = Vector3::new(
            part_inverse[(0, 3)],
            part_inverse[(1, 3)],
            part_inverse[(2, 3)],
        );
        arm.reach = reach(&arm.machine.tool);
        let home_pose = arm.coords_of_joints(&home);
        arm.info.set_home(home_pose);
        Ok(arm.with_inverse(&home))
    }

    /// The characteristic length from the reach at `home` (distance of the tool from
    /// the first joint's axis origin), and the closed form if one applies.
    fn with_inverse(mut self, home: &Vector6<f64>) -> Self {
        // The reach at home weighs a radian against millimetres.
        let (t, _) = self.pose_and_jacobian(home);
        // Relative to the arm, not clamped to a millimetre (a 0.2 mm arm's radian
        // weighs 0.2 mm); 1 mm only for a tool on the first axis' origin.
        let reach = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]).norm();
        let lc = if reach > 0.0 && reach.is_finite() {
            reach
        } else {
            1.0
        };
        self.wrist = closed_form::ClosedForm::detect(&self.tool, &self.part_inverse, lc);
        self.info = self
            .info
            .with_characteristic_length(lc)
            .with_inverse_method(match &self.wrist {
                Some(closed_form::ClosedForm::Spherical(_)) => {
                    "closed form (spherical wrist, axes 2 and 3 parallel)"
                }
                Some(closed_form::ClosedForm::ParallelAxes(_)) => {
                    "closed form (axes 2, 3, 4 parallel, axes 5 and 6 meeting)"
                }
                None => "numeric (Newton on SE(3) from the start, 32 spread restarts)",
            });
        self
    }
}

/// An invalid machine for a serial robot.
fn invalid(message: String) -> Error {
    Error::InvalidInput {
        what: "serial robot".into(),
        message,
    }
}

/// The inverse of the fixed workpiece frame (identity without a workpiece chain),
/// refusing a workpiece chain with joints.
fn part_inverse(machine: &SerialMachine) -> Result<Matrix4<f64>> {
    let part = match &machine.workpiece {
        Some(w) if w.dof() > 0 => {
            return Err(invalid(format!(
                "tool-pose coordinates need a fixed workpiece; its chain has {} joints",
                w.dof()
            )))
        }
        Some(w) => w.pose(&[], &[], &[])?,
        None => Matrix4::identity(),
    };
    part.try_inverse()
        .ok_or_else(|| invalid("the workpiece frame is not invertible".into()))
}

/// An upper bound of the tool's distance from the base origin: the sum of the link
/// translations and prismatic travels.
fn reach(tool: &Chain) -> f64 {
    tool.links
        .iter()
        .map(|l| {
            let travel = match &l.joint {
                Some(j) if j.kind == JointKind::Prismatic => {
                    j.range.min.abs().max(j.range.max.abs())
                }
                _ => 0.0,
            };
            l.translation.norm() + travel
        })
        .sum::<f64>()
}
