//! The hexapod's limits as codes: the six axes' travel, each strut's length and its
//! base and platform joint cones, the 36 ordered strut pairs' interference. One scan
//! ([`Hexapod::scan`]) finds them for the full check, the batch's first violation and
//! the block kernels; each code's name is made once, when the machine is built.

use std::sync::Arc;

use nalgebra::{Matrix3, Vector3, Vector6};

use super::interference::{interference_name, interference_scan};
use super::{HexStrut, Hexapod};
use crate::limits::{LimitCode, LimitKind, LimitName, Side, Violation};
use crate::mechanism::Coordinate;
use crate::units::Quantity;

/// First codes of [`Hexapod::scan`]'s families: axis travel from 0, strut lengths,
/// base cones, platform cones, strut pairs.
const RANGE: usize = 6;
const BASE_CONE: usize = 12;
const PLATFORM_CONE: usize = 18;
const PAIR: usize = 24;

/// A joint's allowed cone: the strut must stay within `max_angle` of `axis`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointCone {
    /// Unit axis (base frame for base joints, platform frame for platform joints).
    pub axis: Vector3<f64>,
    /// Largest angle between the strut and the axis (rad).
    pub max_angle: f64,
    /// `cos(max_angle)`, computed once: the limit checks compare the strut's cosine
    /// with it (per pose, six struts, two cones each).
    cos_max: f64,
}

impl JointCone {
    /// The cone of half-angle `max_angle` (rad) about unit `axis`.
    pub fn new(axis: Vector3<f64>, max_angle: f64) -> Self {
        JointCone {
            axis,
            max_angle,
            cos_max: max_angle.cos(),
        }
    }

    /// `cos(max_angle)`: a strut along unit `n` is within the cone when
    /// `n . axis >= cos_max`.
    #[inline]
    pub fn cos_max(&self) -> f64 {
        self.cos_max
    }

    /// Pushes a joint-angle violation (named by `name`, built only then) when `cos`,
    /// the cosine of the strut's angle from the axis, is below [`JointCone::cos_max`].
    #[inline]
    pub fn check(&self, cos: f64, name: impl FnOnce() -> String, out: &mut Vec<Violation>) {
        if cos < self.cos_max {
            out.push(Violation::new(
                name(),
                LimitKind::JointAngle,
                Side::Max,
                Quantity::Angle,
                cos.clamp(-1.0, 1.0).acos(),
                self.max_angle,
            ));
        }
    }
}

/// Codes of [`Hexapod::scan`]: the six axes' travel, then per strut its length, its
/// base and platform joint cones, then the 36 ordered pairs' interference.
const LIMIT_CODES: usize = PAIR + 36;

/// The name of limit code `id` ([`Hexapod::scan`]'s numbering).
fn limit_name(struts: &[HexStrut; 6], coordinates: &[Coordinate; 6], id: usize) -> LimitName {
    let strut = |i: usize| &struts[i % 6];
    match id {
        0..RANGE => format!("axis {} travel", coordinates[id].name),
        RANGE..BASE_CONE => crate::limits::strut_length_name(&strut(id - RANGE).actuator.name),
        BASE_CONE..PLATFORM_CONE => {
            let s = strut(id - BASE_CONE);
            format!(
                "base joint {} angle (strut {})",
                s.base_name, s.actuator.name
            )
        }
        PLATFORM_CONE..PAIR => {
            let s = strut(id - PLATFORM_CONE);
            format!(
                "platform joint {} angle (strut {})",
                s.platform_name, s.actuator.name
            )
        }
        _ => {
            let (i, k) = ((id - PAIR) / 6 % 6, (id - PAIR) % 6);
            interference_name(&strut(i).actuator.name, &strut(k).actuator.name)
        }
    }
    .into()
}

/// Every limit code's name, in code order.
pub(super) fn limit_names(
    struts: &[HexStrut; 6],
    coordinates: &[Coordinate; 6],
) -> Arc<[LimitName]> {
    (0..LIMIT_CODES)
        .map(|id| limit_name(struts, coordinates, id))
        .collect()
}

impl Hexapod {
    /// The limit check of [`Mechanism::check_limits`] at pose `x` (position `p`,
    /// rotation `r`) with actuators `q`, in its order: `found` is called with every
    /// violated limit as a code ([`Hexapod::violation_of`] names it) and the scan stops
    /// when it returns true. One scan serves the full check and the batch's first
    /// violation. Codes: axis travel `0..6` (by coordinate), strut lengths `6..12`,
    /// base cones `12..18`, platform cones `18..24`, interference `24 + 6 i + k`.
    pub(super) fn scan(
        &self,
        x: &Vector6<f64>,
        q: &Vector6<f64>,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        mut found: impl FnMut(LimitCode) -> bool,
    ) {
        if self.scan_axes(x, &mut found) {
            return;
        }
        let joints = self.set.platform_joints(p, r);
        if self.scan_struts(q, r, &joints, &mut found) {
            return;
        }
        if let Some(dia) = self.strut_diameter {
            let base: [Vector3<f64>; 6] = std::array::from_fn(|i| self.struts[i].base);
            interference_scan(
                &base,
                &joints,
                |i, k| self.shares[i][k],
                dia,
                |i, k, d| {
                    found(LimitCode {
                        id: (PAIR + 6 * i + k) as u32,
                        side: Side::Min,
                        quantity: Quantity::Length,
                        value: d,
                        bound: dia,
                    })
                },
            );
        }
    }

    /// [`Hexapod::scan`]'s axis travel at pose `x`; whether `found` stopped it.
    #[inline(always)]
    fn scan_axes(&self, x: &Vector6<f64>, found: &mut impl FnMut(LimitCode) -> bool) -> bool {
        for (k, range) in &self.axes.ranges {
            if let Some((side, bound)) = range.crossed(x[*k]) {
                let quantity = self.info.coordinates()[*k].quantity;
                let (id, value) = (*k as u32, x[*k]);
                if found(LimitCode {
                    id,
                    side,
                    quantity,
                    value,
                    bound,
                }) {
                    return true;
                }
            }
        }
        false
    }

    /// [`Hexapod::scan`]'s strut lengths `q` and joint cones (rotation `r`, platform
    /// joints `joints`); whether `found` stopped it.
    #[inline(always)]
    fn scan_struts(
        &self,
        q: &Vector6<f64>,
        r: &Matrix3<f64>,
        joints: &[Vector3<f64>; 6],
        found: &mut impl FnMut(LimitCode) -> bool,
    ) -> bool {
        let cone = |id: usize, c: &JointCone, cos: f64| {
            (cos < c.cos_max()).then(|| LimitCode {
                id: id as u32,
                side: Side::Max,
                quantity: Quantity::Angle,
                value: cos.clamp(-1.0, 1.0).acos(),
                bound: c.max_angle,
            })
        };
        for i in 0..6 {
            let s = &self.struts[i];
            if let Some((side, bound)) = s.actuator.range.crossed(q[i]) {
                if found(LimitCode {
                    id: (RANGE + i) as u32,
                    side,
                    quantity: Quantity::Length,
                    value: q[i],
                    bound,
                }) {
                    return true;
                }
            }
            let n = (joints[i] - s.base) / q[i];
            if let Some(c) = &s.base_cone {
                if let Some(code) = cone(BASE_CONE + i, c, n.dot(&c.axis)) {
                    if found(code) {
                        return true;
                    }
                }
            }
            if let Some(c) = &s.platform_cone {
                if let Some(code) = cone(PLATFORM_CONE + i, c, (-n).dot(&(r * c.axis))) {
                    if found(code) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// The violation a code of [`Hexapod::scan`] stands for, named as
    /// [`Mechanism::check_limits`] names it (the name from the table built with the
    /// machine: a motion beyond a limit clones it per sample, formats nothing).
    pub(super) fn violation_of(&self, c: &LimitCode) -> Violation {
        let id = c.id as usize;
        let kind = match id {
            0..RANGE => LimitKind::AxisTravel,
            RANGE..BASE_CONE => LimitKind::ActuatorPosition,
            BASE_CONE..PAIR => LimitKind::JointAngle,
            _ => LimitKind::StrutInterference,
        };
        let name = match self.limit_names.get(id) {
            Some(n) => n.clone(),
            None => limit_name(&self.struts, self.info.coordinates(), id),
        };
        Violation::new(name, kind, c.side, c.quantity, c.value, c.bound)
    }
}
