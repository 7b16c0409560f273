//! Interference of struts: the distance between their axes (segments from base joint
//! to moving joint) against the strut diameter, for every pair that does not share a
//! joint. Pairs whose bounding boxes are more than a diameter apart are settled
//! without the distance (exactly: the result is the check of every pair's).

use nalgebra::Vector3;

use crate::limits::{LimitKind, Side, Violation};
use crate::units::Quantity;

/// Distance between segments `p0-p1` and `q0-q1`.
pub fn segment_distance(
    p0: &Vector3<f64>,
    p1: &Vector3<f64>,
    q0: &Vector3<f64>,
    q1: &Vector3<f64>,
) -> f64 {
    let d1 = p1 - p0;
    let d2 = q1 - q0;
    let r = p0 - q0;
    let a = d1.dot(&d1);
    let e = d2.dot(&d2);
    let f = d2.dot(&r);
    let (s, t);
    if a <= 1e-300 && e <= 1e-300 {
        return r.norm();
    }
    if a <= 1e-300 {
        s = 0.0;
        t = (f / e).clamp(0.0, 1.0);
    } else {
        let c = d1.dot(&r);
        if e <= 1e-300 {
            t = 0.0;
            s = (-c / a).clamp(0.0, 1.0);
        } else {
            let b = d1.dot(&d2);
            let denom = a * e - b * b;
            let mut s0 = if denom > 1e-300 {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t0 = (b * s0 + f) / e;
            if t0 < 0.0 {
                t0 = 0.0;
                s0 = (-c / a).clamp(0.0, 1.0);
            } else if t0 > 1.0 {
                t0 = 1.0;
                s0 = ((b - c) / a).clamp(0.0, 1.0);
            }
            s = s0;
            t = t0;
        }
    }
    ((p0 + d1 * s) - (q0 + d2 * t)).norm()
}

/// Pushes a violation for every pair of struts (base joint `base[i]` to moving joint
/// `joints[i]`) whose axes come closer than `dia`, except pairs `skip(i, k)` (struts
/// that share a joint touch there by construction).
pub(crate) fn strut_interference<const N: usize>(
    names: &[&str; N],
    base: &[Vector3<f64>; N],
    joints: &[Vector3<f64>; N],
    skip: impl Fn(usize, usize) -> bool,
    dia: f64,
    out: &mut Vec<Violation>,
) {
    interference_scan(base, joints, skip, dia, |i, k, d| {
        out.push(interference_violation(names[i], names[k], d, dia));
        false
    });
}

/// The violation of struts `a` and `b` whose axes are `d` apart, closer than `dia`.
pub(crate) fn interference_violation(a: &str, b: &str, d: f64, dia: f64) -> Violation {
    Violation::new(
        interference_name(a, b),
        LimitKind::StrutInterference,
        Side::Min,
        Quantity::Length,
        d,
        dia,
    )
}

/// The name of the interference limit of struts `a` and `b`.
pub(crate) fn interference_name(a: &str, b: &str) -> String {
    format!("struts {a}/{b} interference (axis distance)")
}

/// Calls `found(i, k, distance)` for every pair of struts (base joint `base[i]` to
/// `joints[i]`) whose axes come closer than `dia`, in the order of
/// [`strut_interference`], except pairs `skip(i, k)`; stops when `found` returns true.
/// An exact bounding-box test skips the pairs whose boxes are more than `dia` apart.
pub(crate) fn interference_scan<const N: usize>(
    base: &[Vector3<f64>; N],
    joints: &[Vector3<f64>; N],
    skip: impl Fn(usize, usize) -> bool,
    dia: f64,
    mut found: impl FnMut(usize, usize, f64) -> bool,
) {
    let lo: [Vector3<f64>; N] = std::array::from_fn(|i| base[i].inf(&joints[i]));
    let hi: [Vector3<f64>; N] = std::array::from_fn(|i| base[i].sup(&joints[i]));
    for i in 0..N {
        for k in i + 1..N {
            if skip(i, k) {
                continue;
            }
            let apart = (0..3).any(|c| lo[i][c] - hi[k][c] > dia || lo[k][c] - hi[i][c] > dia);
            if apart {
                continue;
            }
            let d = segment_distance(&base[i], &joints[i], &base[k], &joints[k]);
            if d < dia && found(i, k, d) {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The boxes skip no interfering pair: the check equals the plain one (every pair
    /// by [`segment_distance`]) over random struts of every size and orientation,
    /// crossing, touching and nearly parallel ones included.
    #[test]
    fn equals_the_check_of_every_pair() {
        let mut state = 0x9e3779b97f4a7c15u64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let names = ["1", "2", "3", "4", "5", "6"];
        let mut found = 0;
        for round in 0..20_000 {
            let mut v = |s: f64| Vector3::new(rnd() * s, rnd() * s, rnd() * s);
            let base: [Vector3<f64>; 6] = std::array::from_fn(|_| v(300.0));
            let mut joints: [Vector3<f64>; 6] = std::array::from_fn(|i| base[i] + v(500.0));
            if round % 5 == 0 {
                joints[1] = base[1] + (joints[0] - base[0]) * 1.000001;
            }
            let dia = 10.0 + 100.0 * rnd().abs();
            let skip = |i: usize, k: usize| (i + k).is_multiple_of(7);
            let mut fast = Vec::new();
            strut_interference(&names, &base, &joints, skip, dia, &mut fast);
            let mut plain = Vec::new();
            for i in 0..6 {
                for k in i + 1..6 {
                    let d = segment_distance(&base[i], &joints[i], &base[k], &joints[k]);
                    if !skip(i, k) && d < dia {
                        plain.push((
                            format!(
                                "struts {}/{} interference (axis distance)",
                                names[i], names[k]
                            ),
                            d,
                        ));
                    }
                }
            }
            assert_eq!(fast.len(), plain.len(), "round {round}");
            for (f, (name, d)) in fast.iter().zip(&plain) {
                assert_eq!(&f.limit, name);
                assert_eq!(f.value, *d);
            }
            found += plain.len();
        }
        assert!(found > 1000, "{found}");
    }
}
