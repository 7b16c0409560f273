//! Carrying a robot's joints on along a motion: the posture and the whole turns of the
//! previous sample, where [`Mechanism::actuator_motion`] alone takes the solution
//! nearest the home joints. A path that turns a wrist joint past half a turn from home,
//! or along which another posture comes nearer home, would otherwise jump by a turn or
//! flip posture between two samples; a controller moving the robot does neither.

use nalgebra::Vector6;

use super::SerialArm;
use crate::mechanism::ActuatorMotion;
#[cfg(doc)]
use crate::mechanism::Mechanism;
use crate::units::Quantity;

/// Absolute slack (rad or mm) of the jump test: the rounding of two solutions of
/// neighbouring poses, far below any joint step a rate could explain.
const SLACK: f64 = 1e-9;

/// A revolute joint's step (rad) the rates allow beyond which they cannot tell a
/// posture from another (coarse samples: a few points per move, or a singular
/// passage): the posture nearest the previous sample's is then solved for.
const COARSE: f64 = 0.25;

impl SerialArm {
    /// The motion at `x` (rates `xd`, `xdd`) continuing `prev`, the previous sample's,
    /// `dt` seconds before; `act` holds [`Mechanism::actuator_motion`]'s on entry:
    ///
    /// 1. Each revolute joint is shifted by whole turns to within half a turn of
    ///    `prev` (its rates do not change).
    /// 2. When a joint then still moved more than the two samples' rates explain,
    ///    `|q - q_prev| > r = 2 dt max(|q'|, |q'_prev|) + dt^2 max(|q''|, |q''_prev|)`
    ///    (plus 1e-9), the solution is another posture; so it may be when the rates
    ///    allow a revolute joint more than 0.25 rad (`r > 0.25`: coarse samples). The
    ///    inverse is then solved again from `prev` ([`SerialArm::inverse_from`]: in
    ///    closed form the posture nearest `prev`, else Newton from `prev`) and its
    ///    motion taken when it lies nearer `prev` (sum of squared joint differences).
    ///
    /// Returns whether `act.q` changed. Two postures within the rates' reach of each
    /// other (near a singular configuration, where branches meet) are not told apart.
    pub(super) fn continue_motion(
        &self,
        x: &Vector6<f64>,
        xd: &Vector6<f64>,
        xdd: &Vector6<f64>,
        dt: f64,
        prev: &ActuatorMotion<6>,
        act: &mut ActuatorMotion<6>,
    ) -> bool {
        // Within half a turn already (nearly always): no shift to compute.
        let shifted = if (act.q - prev.q).amax() < std::f64::consts::PI {
            act.q
        } else {
            self.wrap(act.q, &prev.q)
        };
        let reach = |i: usize, m: &ActuatorMotion<6>| {
            2.0 * dt * m.qd[i].abs().max(prev.qd[i].abs())
                + dt * dt * m.qdd[i].abs().max(prev.qdd[i].abs())
                + SLACK
        };
        let unsure = (0..6).any(|i| {
            let r = reach(i, act);
            (shifted[i] - prev.q[i]).abs() > r
                || (self.info.actuators()[i].quantity == Quantity::Angle && r > COARSE)
        });
        if unsure {
            let other = self
                .inverse_from(x, &prev.q)
                .and_then(|q| self.motion_at(q, x, xd, xdd));
            if let Ok(other) = other {
                let far = |q: &Vector6<f64>| (q - prev.q).norm_squared();
                if far(&other.q) < far(&shifted) {
                    *act = other;
                    return true;
                }
            }
        }
        let changed = shifted != act.q;
        act.q = shifted;
        changed
    }
}
