//! Rotary angles from a tool axis vector (`I, J, K` of a 5-axis program): the
//! orientation inverse of a [`TcpMachine`] with two rotary axes.
//!
//! The tool relative to the part turns by the product of exponentials
//! `R(t1, t2) = exp(w1 t1) exp(w2 t2) R(0)` with `w1`, `w2` the rotary axes at zero
//! (part frame, signed as seen from the part, `w1` the one nearer the part). Pointing
//! the tool axis `a0 = R(0) e_z` along `a` is Paden-Kahan subproblem 2: the
//! intermediate direction `z = exp(w2 t2) a0 = exp(-w1 t1) a` lies on the cone of
//! half-angle `f1 = angle(w1, a)` about `w1` and on the cone of half-angle
//! `f2 = angle(w2, a0)` about `w2`. In the spherical triangle `w1, w2, z` (side
//! `psi = angle(w1, w2)`) the angle `A` at `w1` follows from the law of cosines,
//! `cos A = (cos f2 - cos psi cos f1) / (sin psi sin f1)`, and
//! `z = cos f1 w1 + sin f1 (cos A u + sin A (w1 x u))`, `u` the unit part of `w2`
//! normal to `w1`: two branches (`sin A` of either sign; one when it is 0, none when
//! `|cos A| > 1`: the axis is out of the rotary axes' reach). Every angle is taken
//! with `atan2` of a sine and a cosine, so no digits are lost near the singular
//! direction (the textbook form `gamma^2 = 1 - |alpha w1 + beta w2|^2` loses half of
//! them there). Each joint angle then turns one vector into another about one axis
//! (subproblem 1: `t = atan2(w.(u' x v'), u'.v')` of the parts `u'`, `v'` normal to
//! `w`).
//!
//! **The singular direction.** When `a` is along `w1` (a trt table's C axis with the
//! tool axis vertical, B = 0) every `t1` gives the same axis: `t1` is undetermined.
//! It is then held at the previous value (the continuity rule along a path) and the
//! solution says so; nothing is divided by the vanishing projection.
//!
//! **Branches and turns.** Of the branches and of the equivalents `t + 2 pi k` of each
//! angle, the one chosen is within the joints' ranges and nearest the previous angles
//! (`near`; home when there is none).

use nalgebra::{SVector, Vector3};
use serde::Serialize;

use super::tcp::TcpMachine;
use crate::error::{Error, Result};

/// The rotary angles that point the tool along an axis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AxisSolution {
    /// Every branch: the rotary angles (rad) in pose-coordinate order, each angle the
    /// equivalent (mod 2 pi) within its range nearest the previous one.
    pub branches: Vec<Vec<f64>>,
    /// The branch the continuity rule chose.
    pub chosen: usize,
    /// The axis is within [`SINGULAR_ANGLE`] of the rotary axis nearest the part,
    /// whose angle is undetermined there: it was held at its previous value.
    pub singular: bool,
    /// Angle between the tool axis and that rotary axis (rad).
    pub singular_distance: f64,
}

impl AxisSolution {
    /// The chosen branch's angles.
    pub fn chosen(&self) -> &[f64] {
        &self.branches[self.chosen]
    }
}

/// Angle (rad) between the tool axis and the first rotary axis under which the first
/// rotary angle is taken as undetermined and held: the axis pointed is then within
/// twice this angle of the one asked for. Above it the angle is computed (from
/// `atan2` of the axis' small normal part, accurate to rounding).
pub const SINGULAR_ANGLE: f64 = 1e-12;

/// The angle about unit `w` turning `u` into `v` (their parts normal to `w`), or `None`
/// when either lies along `w`.
fn turn_about(w: &Vector3<f64>, u: &Vector3<f64>, v: &Vector3<f64>) -> Option<f64> {
    let up = u - w * w.dot(u);
    let vp = v - w * w.dot(v);
    if up.norm() < SINGULAR_ANGLE || vp.norm() < SINGULAR_ANGLE {
        return None;
    }
    Some(w.dot(&up.cross(&vp)).atan2(up.dot(&vp)))
}

/// The equivalent `t + 2 pi k` nearest `near`, preferring those within `[lo, hi]`.
fn unwrap_near(t: f64, near: f64, lo: f64, hi: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let base = t + crate::rotation::whole_turns(near - t) * tau;
    let mut best = base;
    let mut best_key = (true, f64::INFINITY);
    for k in -2..=2 {
        let c = base + k as f64 * tau;
        let key = (!(lo - 1e-12..=hi + 1e-12).contains(&c), (c - near).abs());
        if key < best_key {
            best_key = key;
            best = c;
        }
    }
    best
}

/// The tool axis `axis` scaled to unit length, refusing a zero or non-finite one.
fn unit_axis(axis: &Vector3<f64>) -> Result<Vector3<f64>> {
    let n = axis.norm();
    if !(n > 1e-12) || !n.is_finite() {
        return Err(Error::InvalidInput {
            what: "tool axis".into(),
            message: format!(
                "expected a finite non-zero vector, got ({}, {}, {})",
                axis.x, axis.y, axis.z
            ),
        });
    }
    Ok(axis / n)
}

/// Subproblem 2 for a tool axis: the rotary axes `w1`, `w2`, the tool axis at zero
/// `a0`, the `target`, and the spherical triangle's angles giving the intermediate
/// direction `z`.
struct Cones {
    w1: Vector3<f64>,
    w2: Vector3<f64>,
    a0: Vector3<f64>,
    target: Vector3<f64>,
    /// Half-angle of the cone of `z` about `w1`.
    f1: f64,
    /// `w2`'s unit part normal to `w1`, and `w1 x u`.
    u: Vector3<f64>,
    v: Vector3<f64>,
    /// The angle `A` at `w1` between `w2` and `z`.
    cos_a: f64,
    sin_a: f64,
}

impl Cones {
    /// The triangle for axes `w1`, `w2` (`c` their cosine), or the angle (rad) by which
    /// `target` is out of their reach.
    fn new(
        w1: Vector3<f64>,
        w2: Vector3<f64>,
        a0: Vector3<f64>,
        target: Vector3<f64>,
        c: f64,
    ) -> std::result::Result<Self, f64> {
        // Angles of the spherical triangle w1, w2, z, each from atan2 (no cosine near
        // 1 to lose digits in): the cone of z about w1 has half-angle f1, about w2 f2.
        let angle = |u: &Vector3<f64>, v: &Vector3<f64>| u.cross(v).norm().atan2(u.dot(v));
        let (f1, f2, psi) = (angle(&w1, &target), angle(&w2, &a0), angle(&w1, &w2));
        let u = (w2 - w1 * c).normalize();
        let v = w1.cross(&u);
        // Spherical law of cosines for the angle A at w1 between w2 and z.
        let num = f2.cos() - psi.cos() * f1.cos();
        let den = psi.sin() * f1.sin();
        if num.abs() > den + 1e-12 {
            return Err((f1 - (psi + f2)).max((psi - f2).abs() - f1).max(0.0));
        }
        let cos_a = if den > 0.0 {
            (num / den).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        let sin_a = (1.0 - cos_a * cos_a).sqrt();
        Ok(Cones {
            w1,
            w2,
            a0,
            target,
            f1,
            u,
            v,
            cos_a,
            sin_a,
        })
    }

    /// The intermediate direction `z` of the branch with `sin A` of sign `sg`.
    fn intermediate(&self, sg: f64) -> Vector3<f64> {
        self.w1 * self.f1.cos() + (self.u * self.cos_a + self.v * (sg * self.sin_a)) * self.f1.sin()
    }
}

impl<const N: usize> TcpMachine<N> {
    /// The rotary angles pointing the tool along `axis` (part frame, from the tip to the
    /// spindle; any length > 0), both branches, the one nearest `near` (rotary angles in
    /// pose-coordinate order, rad; home when `None`) chosen. Machines with two rotary
    /// axes; fails with [`Error::NotAttainable`] (and the angle by which the axis is out
    /// of reach) when no turn of the rotary axes points the tool that way.
    pub fn rotary_for_axis(
        &self,
        axis: &Vector3<f64>,
        near: Option<&[f64]>,
    ) -> Result<AxisSolution> {
        if N != 5 {
            return Err(Error::InvalidInput {
                what: "tool axis".into(),
                message: format!(
                    "a tool axis vector sets two rotary axes; this machine has {}",
                    N - 3
                ),
            });
        }
        let target = unit_axis(axis)?;
        let near = self.previous_rotary(near)?;
        let a0: Vector3<f64> = self.at_zero.frame.column(2).into_owned();
        let (k1, k2, w1, w2) = self.rotary_pair();
        let c = w1.dot(&w2);
        let s2 = 1.0 - c * c;
        if s2 < 1e-12 {
            return Err(Error::InvalidInput {
                what: "tool axis".into(),
                message: "the two rotary axes are parallel: they cannot point the tool".into(),
            });
        }
        let cones = Cones::new(w1, w2, a0, target, c).map_err(|gap| Error::NotAttainable {
            reason: format!(
                "the tool axis ({:.6}, {:.6}, {:.6}) is {:.4} deg beyond what the rotary \
                 axes {} and {} can point",
                target.x,
                target.y,
                target.z,
                gap.to_degrees(),
                self.info.coordinates()[3 + k1].name,
                self.info.coordinates()[3 + k2].name
            )
            .into(),
        })?;
        let singular_distance = cones.f1.min(std::f64::consts::PI - cones.f1);
        let singular = singular_distance < SINGULAR_ANGLE;
        let branches = self.axis_branches(&cones, singular, &near, (k1, k2));
        let chosen = self.nearest_branch(&branches, &near);
        Ok(AxisSolution {
            branches,
            chosen,
            singular,
            singular_distance,
        })
    }

    /// The previous rotary angles `near` checked, or home's when `None`.
    fn previous_rotary(&self, near: Option<&[f64]>) -> Result<[f64; 2]> {
        let home = self.info.home();
        Ok(match near {
            Some(v) if v.len() == 2 && v.iter().all(|x| x.is_finite()) => [v[0], v[1]],
            Some(v) => {
                return Err(Error::InvalidInput {
                    what: "tool axis".into(),
                    message: format!("expected 2 previous rotary angles, got {}", v.len()),
                })
            }
            None => [home[3], home[4]],
        })
    }

    /// The rotary angles of each branch of `cones` (`k1`, `k2` the pose coordinates of
    /// `w1`, `w2`), each the equivalent within its range nearest `near`; the first
    /// angle held at `near` when `singular`.
    fn axis_branches(
        &self,
        cones: &Cones,
        singular: bool,
        near: &[f64; 2],
        (k1, k2): (usize, usize),
    ) -> Vec<Vec<f64>> {
        let rot = self.rotary_joints();
        let range = |k: usize| self.info.actuators()[rot[k]].range;
        let signs: &[f64] = if cones.sin_a > 0.0 {
            &[1.0, -1.0]
        } else {
            &[1.0]
        };
        let mut branches = Vec::new();
        for &sg in signs {
            let z = cones.intermediate(sg);
            let t2 = turn_about(&cones.w2, &cones.a0, &z).unwrap_or(near[k2]);
            let t1 = match turn_about(&cones.w1, &z, &cones.target) {
                Some(t) if !singular => t,
                _ => near[k1],
            };
            let mut v = [0.0; 2];
            v[k1] = t1;
            v[k2] = t2;
            for (k, vk) in v.iter_mut().enumerate() {
                let r = range(k);
                *vk = unwrap_near(*vk, near[k], r.min, r.max);
            }
            if !branches.contains(&v.to_vec()) {
                branches.push(v.to_vec());
            }
        }
        branches
    }

    /// The branch within the ranges nearest `near` (the continuity rule).
    fn nearest_branch(&self, branches: &[Vec<f64>], near: &[f64; 2]) -> usize {
        let rot = self.rotary_joints();
        let range = |k: usize| self.info.actuators()[rot[k]].range;
        let within = |b: &Vec<f64>| {
            (0..2).all(|k| {
                let r = range(k);
                (r.min - 1e-12..=r.max + 1e-12).contains(&b[k])
            })
        };
        let dist = |b: &Vec<f64>| (b[0] - near[0]).powi(2) + (b[1] - near[1]).powi(2);
        (0..branches.len())
            .min_by(|&a, &b| {
                (!within(&branches[a]), dist(&branches[a]))
                    .partial_cmp(&(!within(&branches[b]), dist(&branches[b])))
                    .unwrap_or(std::cmp::Ordering::Equal)
            })
            .unwrap_or(0)
    }

    /// The two rotary axes as pose coordinates `k1` (the one nearer the part) and `k2`
    /// (0 or 1 after X, Y, Z) and their directions at zero, `w1`, `w2` (part frame,
    /// as seen from the part). Machines with two rotary axes.
    fn rotary_pair(&self) -> (usize, usize, Vector3<f64>, Vector3<f64>) {
        let rot = self.rotary_joints();
        let pos = |j: usize| self.order.iter().position(|&o| o == j).unwrap_or(0);
        let (k1, k2) = if pos(rot[0]) < pos(rot[1]) {
            (0, 1)
        } else {
            (1, 0)
        };
        (
            k1,
            k2,
            self.at_zero.axis[rot[k1]],
            self.at_zero.axis[rot[k2]],
        )
    }

    /// Angle (rad, 0 to pi/2) between the tool axis at pose `x` and the rotary axis
    /// nearer the part, whose angle is undetermined when they are aligned: with
    /// `R(t1, t2) = exp(w1 t1) exp(w2 t2) R(0)` the turn about `w1` keeps the angle to
    /// `w1`, so it is the angle between `w1` and `exp(w2 t2) a0` (Rodrigues), folded
    /// onto the line (`min(f, pi - f)`). `None` unless the machine has two rotary axes.
    pub fn singular_angle(&self, x: &SVector<f64, N>) -> Option<f64> {
        if N != 5 {
            return None;
        }
        let (_, k2, w1, w2) = self.rotary_pair();
        let a0: Vector3<f64> = self.at_zero.frame.column(2).into_owned();
        let z = nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_unchecked(w2), x[3 + k2])
            * a0;
        let f = w1.cross(&z).norm().atan2(w1.dot(&z));
        Some(f.min(std::f64::consts::PI - f))
    }

    /// Pose coordinates (tip X, Y, Z and rotary angles) for a tip `tip` and a tool axis
    /// `axis` (part frame), the rotary branch nearest `near` ([`Self::rotary_for_axis`]).
    pub fn pose_for_axis(
        &self,
        tip: &Vector3<f64>,
        axis: &Vector3<f64>,
        near: Option<&[f64]>,
    ) -> Result<(SVector<f64, N>, AxisSolution)> {
        let sol = self.rotary_for_axis(axis, near)?;
        Ok((tcp_coords(tip, sol.chosen()), sol))
    }
}

/// TCP pose coordinates of tip `tip` and rotary angles `angles`.
pub(super) fn tcp_coords<const N: usize>(tip: &Vector3<f64>, angles: &[f64]) -> SVector<f64, N> {
    let mut x = SVector::<f64, N>::zeros();
    x[0] = tip.x;
    x[1] = tip.y;
    x[2] = tip.z;
    for (k, v) in angles.iter().enumerate() {
        x[3 + k] = *v;
    }
    x
}
