//! The limits of the seed-002 machine: carriage strokes, the table's range, the held
//! angle A, the platform tilt, the joints' cones and strut interference.

use nalgebra::{SVector, Vector3, Vector6};

use super::{HybridAm, Placement};
use crate::hexapod::segment_distance;
use crate::limits::{LimitKind, Range, Side, Violation};
use crate::units::Quantity;

/// Pushes every violated limit at pose `x` with readings `q` onto `out`; allocates only
/// for a violation.
pub(super) fn check(m: &HybridAm, x: &Vector6<f64>, q: &SVector<f64, 5>, out: &mut Vec<Violation>) {
    m.position_limits
        .check(m.info.actuators(), q.as_slice(), out);
    Range { min: 0.0, max: 0.0 }.check(
        || "nozzle angle A (the platform tilts about Y only)",
        LimitKind::Tilt,
        Quantity::Angle,
        x[3],
        out,
    );
    let pl = m.placement(x);
    if let Some(r) = &m.tilt {
        r.check(
            || "platform tilt (B minus the nozzle's tilt on the platform)",
            LimitKind::Tilt,
            Quantity::Angle,
            pl.beta,
            out,
        );
    }
    let s = m.struts(&pl, q);
    let c: [Vector3<f64>; 4] = std::array::from_fn(|i| m.carriage_joint(i, q[i]));
    check_cones(m, &pl, &s, out);
    if let Some(dia) = m.strut_diameter {
        check_interference(m, &pl, &c, dia, out);
    }
}

/// Pushes the violated joint cones of the struts `s` (platform placed at `pl`).
fn check_cones(m: &HybridAm, pl: &Placement, s: &[Vector3<f64>; 4], out: &mut Vec<Violation>) {
    for (leg, si) in m.legs.iter().zip(s) {
        let n = si / si.norm().max(1e-300);
        if let Some(cn) = &m.carriage_cone {
            cn.check(
                n.dot(&cn.axis),
                || {
                    format!(
                        "carriage joint {} angle (strut {})",
                        leg.carriage_name, leg.actuator.name
                    )
                },
                out,
            );
        }
        if let Some(cn) = &m.platform_cone {
            cn.check(
                -n.dot(&(pl.rotation * cn.axis)),
                || {
                    format!(
                        "platform joint {} angle (strut {})",
                        leg.platform_name, leg.actuator.name
                    )
                },
                out,
            );
        }
    }
}

/// Pushes every pair of struts (carriage joints `c` to the platform joints of `pl`)
/// closer than the strut diameter `dia`.
fn check_interference(
    m: &HybridAm,
    pl: &Placement,
    c: &[Vector3<f64>; 4],
    dia: f64,
    out: &mut Vec<Violation>,
) {
    for i in 0..4 {
        for k in i + 1..4 {
            let d = segment_distance(&c[i], &pl.joints[i], &c[k], &pl.joints[k]);
            if d < dia {
                out.push(Violation::new(
                    format!(
                        "struts {} and {} distance",
                        m.legs[i].actuator.name, m.legs[k].actuator.name
                    ),
                    LimitKind::StrutInterference,
                    Side::Min,
                    Quantity::Length,
                    d,
                    dia,
                ));
            }
        }
    }
}
