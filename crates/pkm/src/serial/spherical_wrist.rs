//! Closed-form inverse kinematics of a six-revolute arm whose last three axes meet in one
//! point (a spherical wrist) and whose second and third axes are parallel: the geometry
//! of most industrial robots (KUKA, ABB, Fanuc, Yaskawa, Staubli, the PUMA 560), with
//! any shoulder offset, elbow offset or tool.
//!
//! Pieper (1968) showed that the wrist centre `c` of such an arm depends on the first
//! three joints only. Written as a product of exponentials (Murray, Li and Sastry, *A
//! Mathematical Introduction to Robotic Manipulation*, 1994, ch. 3), each joint `k`
//! turning about its axis `(w_k, p_k)` at the zero configuration, the tool pose is
//! `T(q) = E_1(q_1) ... E_6(q_6) T_0` and the problem splits into Paden-Kahan
//! subproblems, each `a cos t + b sin t = g` (two solutions, one, or none):
//!
//! 1. **Shoulder** `q_1`. The target wrist centre is `w = p* + R* c_T` (`c_T` the
//!    centre in the tool frame). Turns about axes parallel to `n = w_2` keep the
//!    component along `n`, so `n . E_1(q_1)^-1 w = n . c`.
//! 2. **Elbow** `q_3`. In the plane normal to `n` the arm is planar: the distance of
//!    `V = E_1^-1 w` from axis 2 equals that of `E_3(q_3) c`, a law of cosines in
//!    `q_3`. Then `q_2` is the angle about `n` between the two.
//! 3. **Wrist** `q_4, q_5, q_6`. With `M = R_123^T R* R_0^T = Rot(w_4, q_4) Rot(w_5,
//!    q_5) Rot(w_6, q_6)`: `w_4 . M w_6 = w_4 . Rot(w_5, q_5) w_6` gives `q_5`; `q_4`
//!    turns `Rot(w_5, q_5) w_6` onto `M w_6` about `w_4`; `q_6` is what remains.
//!
//! Up to eight solutions (shoulder, elbow, wrist flip). Where a subproblem has
//! infinitely many (the wrist centre on axis 1, axes 4 and 6 aligned) the joint keeps
//! its start value, as Newton would. Where one has none (beyond a tolerance of 1e-10
//! relative) the pose is out of reach, proven, and the reason names the distances
//! involved. Every solution is then polished by one Newton step of the numeric solver
//! ([`super::arm::SerialArm`]), which also guards against the few ulps the axes of a
//! file may be off parallel or off meeting.

use nalgebra::{Matrix3, Matrix4, Rotation3, Unit, Vector3, Vector6};

mod search;

pub(super) use search::{Nearest, Search};

use super::{JointKind, PreparedChain};
use crate::error::Unattainable;

/// How far (relative) two axes may be off parallel, or three axes off meeting, for the
/// closed form to apply: the rounding of a Denavit-Hartenberg table or a URDF's angles.
pub(super) const GEOMETRY_TOLERANCE: f64 = 1e-10;
/// How far beyond 1 the cosine of a subproblem may be and still count as reached (the
/// boundary of the workspace, computed with rounding).
pub(super) const REACH_TOLERANCE: f64 = 1e-10;

/// The zero-configuration geometry of an arm the closed form applies to (part frame).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct SphericalWrist {
    /// Joint axes: unit directions and a point of each.
    w: [Vector3<f64>; 6],
    p: [Vector3<f64>; 6],
    /// The wrist centre (where axes 4, 5, 6 meet).
    centre: Vector3<f64>,
    /// The wrist centre in the tool frame.
    centre_tool: Vector3<f64>,
    /// The tool orientation at zero.
    r0: Matrix3<f64>,
    /// The planar arm: `(p_3 - p_2)` and `(c - p_3)` normal to `n`.
    elbow: Elbow,
    /// A unit vector normal to `w_6`.
    across6: Vector3<f64>,
    /// Length scale (mm) of the tolerances.
    scale: f64,
}

/// `Rot(w, t)`, `w` unit.
pub(super) fn rot(w: &Vector3<f64>, t: f64) -> Matrix3<f64> {
    Rotation3::from_axis_angle(&Unit::new_unchecked(*w), t).into_inner()
}

/// The component of `v` normal to unit `n`.
pub(super) fn normal(v: &Vector3<f64>, n: &Vector3<f64>) -> Vector3<f64> {
    v - n * n.dot(v)
}

/// The solutions of `a cos t + b sin t = g` (`(a, b)` not zero): `t = atan2(b, a) +-
/// acos(g / hypot(a, b))`, the cosine clamped within [`REACH_TOLERANCE`]; `None`
/// beyond it.
pub(super) fn cos_sin(a: f64, b: f64, g: f64) -> Option<[f64; 2]> {
    let rho = a.hypot(b);
    let ratio = g / rho;
    if !(ratio.abs() <= 1.0 + REACH_TOLERANCE) {
        return None;
    }
    let phi = b.atan2(a);
    let delta = ratio.clamp(-1.0, 1.0).acos();
    Some([phi + delta, phi - delta])
}

/// The angle about unit `n` that turns `a` onto `b` (both normal to `n`).
pub(super) fn angle_about(n: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    n.dot(&a.cross(b)).atan2(a.dot(b))
}

/// An arm's joint axes at the zero configuration, in the part frame, and the tool
/// pose there: what both closed forms are written on.
pub(super) struct ZeroPose {
    /// Unit directions and a point of each axis.
    pub w: [Vector3<f64>; 6],
    pub p: [Vector3<f64>; 6],
    /// The tool's rotation and position.
    pub r0: Matrix3<f64>,
    pub t0: Vector3<f64>,
}

impl ZeroPose {
    /// The zero pose of `chain` seen from the part (`part_inverse`); `None` unless
    /// every joint is revolute.
    pub(super) fn of(chain: &PreparedChain, part_inverse: &Matrix4<f64>) -> Option<ZeroPose> {
        let (t0, axes) = chain.axes::<6>(&[0.0; 6]);
        if axes.iter().any(|a| a.2 != JointKind::Revolute) {
            return None;
        }
        let r = part_inverse.fixed_view::<3, 3>(0, 0).into_owned();
        let o = Vector3::new(
            part_inverse[(0, 3)],
            part_inverse[(1, 3)],
            part_inverse[(2, 3)],
        );
        let tool = part_inverse * t0;
        Some(ZeroPose {
            w: std::array::from_fn(|k| (r * axes[k].0).normalize()),
            p: std::array::from_fn(|k| r * axes[k].1 + o),
            r0: tool.fixed_view::<3, 3>(0, 0).into_owned(),
            t0: Vector3::new(tool[(0, 3)], tool[(1, 3)], tool[(2, 3)]),
        })
    }
}

/// Two axes parallel within [`GEOMETRY_TOLERANCE`].
pub(super) fn parallel(a: &Vector3<f64>, b: &Vector3<f64>) -> bool {
    a.cross(b).norm() <= GEOMETRY_TOLERANCE
}

/// Two axes clearly not parallel (1e-6 rad apart or more).
pub(super) fn apart(a: &Vector3<f64>, b: &Vector3<f64>) -> bool {
    a.cross(b).norm() >= 1e-6
}

/// A unit vector normal to unit `w`.
pub(super) fn across(w: &Vector3<f64>) -> Vector3<f64> {
    let pick = if w.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    w.cross(&pick).normalize()
}

/// The shoulder step of both closed forms: the angles `q_1` that bring the point `zero`
/// (zero configuration) to `target`, given that turns 2 onwards are about axes
/// parallel to `n = w_2` (or fix the point): `n . E_1(q_1)^-1 target = n . zero`.
/// With `target` on axis 1, any `q_1` when the arm's plane passes through it (`start`
/// kept). Else out of reach: `Err` with the target's distance from axis 1 and the
/// plane's offset from it (mm).
pub(super) fn shoulder(
    w: &[Vector3<f64>; 6],
    p: &[Vector3<f64>; 6],
    zero: &Vector3<f64>,
    target: &Vector3<f64>,
    tol: f64,
    start: f64,
) -> Result<[f64; 2], (f64, f64)> {
    let n = w[1];
    let x = target - p[0];
    let x_axial = w[0].dot(&x);
    let x_normal = x - w[0] * x_axial;
    let a = n.dot(&x_normal);
    let b = -n.dot(&w[0].cross(&x));
    let g = n.dot(&(zero - p[0])) - x_axial * n.dot(&w[0]);
    let found = if x_normal.norm() <= tol {
        (g.abs() <= tol).then_some([start, start])
    } else {
        cos_sin(a, b, g)
    };
    found.ok_or_else(|| (x_normal.norm(), g.abs() / normal(&n, &w[0]).norm()))
}

/// The planar two-link elbow of both closed forms, in the plane normal to `n = w_2`:
/// link `e` from axis 2 to axis 3, link `f` from axis 3 to the point the elbow places,
/// `w_3 = sigma n`.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Elbow {
    pub e: Vector3<f64>,
    pub f: Vector3<f64>,
    pub sigma: f64,
}

impl Elbow {
    /// The elbow angles `q_3` that put the point at the distance `|d|` from axis 2
    /// (`d` normal to `n`): the law of cosines `|e + Rot(w_3, q_3) f|^2 = |d|^2`. Else
    /// `Err` with how far `|d|` lies outside the span `[| |e| - |f| |, |e| + |f|]` and
    /// `|d|` (mm).
    pub(super) fn bend(&self, n: &Vector3<f64>, d: &Vector3<f64>) -> Result<[f64; 2], (f64, f64)> {
        let (e2, f2, r2) = (
            self.e.norm_squared(),
            self.f.norm_squared(),
            d.norm_squared(),
        );
        let a3 = 2.0 * self.e.dot(&self.f);
        let b3 = 2.0 * self.sigma * self.e.dot(&n.cross(&self.f));
        cos_sin(a3, b3, r2 - e2 - f2).ok_or_else(|| {
            let (e, f, r) = (e2.sqrt(), f2.sqrt(), r2.sqrt());
            (((e - f).abs() - r).max(r - (e + f)), r)
        })
    }

    /// The shoulder lift `q_2`: the turn about `n` taking the bent elbow `e + r_3 f`
    /// (`r_3 = Rot(w_3, q_3)`) onto `d`; `start` where either is within `tol` of zero.
    pub(super) fn lift(
        &self,
        n: &Vector3<f64>,
        r3: &Matrix3<f64>,
        d: &Vector3<f64>,
        tol: f64,
        start: f64,
    ) -> f64 {
        let u = self.e + r3 * self.f;
        if u.norm() <= tol || d.norm() <= tol {
            start
        } else {
            angle_about(n, &u, d)
        }
    }

    /// Why the elbow cannot place `what` at `r` mm from axis 2.
    pub(super) fn miss(&self, what: &'static str, r: f64) -> Unattainable {
        let (e, f) = (self.e.norm(), self.f.norm());
        Unattainable::ElbowSpan {
            what,
            distance: r,
            min: (e - f).abs(),
            max: e + f,
        }
    }
}

/// The solutions in `slots` (in slot order) into the front of `out`; their number.
pub(super) fn gather(slots: [Option<Vector6<f64>>; 8], out: &mut [Vector6<f64>; 8]) -> usize {
    let mut count = 0;
    for q in slots.into_iter().flatten() {
        out[count] = q;
        count += 1;
    }
    count
}

impl SphericalWrist {
    /// The closed form's geometry of `chain` seen from the part (`part_inverse`), if it
    /// applies: six revolute joints, axes 2 and 3 parallel, axis 1 not parallel to
    /// them, axes 4, 5 and 6 meeting in one point (4 and 5, 5 and 6 not parallel), the
    /// wrist centre off axis 3 and axis 3 apart from axis 2. `scale` is the arm's
    /// length scale (mm).
    pub(super) fn detect(
        chain: &PreparedChain,
        part_inverse: &Matrix4<f64>,
        scale: f64,
    ) -> Option<SphericalWrist> {
        let ZeroPose { w, p, r0, t0: t } = ZeroPose::of(chain, part_inverse)?;
        if !parallel(&w[1], &w[2]) || !apart(&w[0], &w[1]) {
            return None;
        }
        if !apart(&w[3], &w[4]) || !apart(&w[4], &w[5]) {
            return None;
        }
        // The wrist centre: the point of axis 4 closest to axis 5.
        let (d, d5) = (p[4] - p[3], w[3].dot(&w[4]));
        let s = (w[3].dot(&d) - d5 * w[4].dot(&d)) / (1.0 - d5 * d5);
        let centre = p[3] + w[3] * s;
        let tol = GEOMETRY_TOLERANCE * scale;
        let off = |k: usize| normal(&(centre - p[k]), &w[k]).norm();
        if off(4) > tol || off(5) > tol {
            return None;
        }
        let n = w[1];
        let e = normal(&(p[2] - p[1]), &n);
        let f = normal(&(centre - p[2]), &n);
        if e.norm() <= tol || f.norm() <= tol {
            return None;
        }
        Some(SphericalWrist {
            elbow: Elbow {
                e,
                f,
                sigma: w[2].dot(&n).signum(),
            },
            centre_tool: r0.transpose() * (centre - t),
            across6: across(&w[5]),
            w,
            p,
            centre,
            r0,
            scale,
        })
    }

    /// Every solution of the tool pose `(target_p, target_r)` (at most eight; joints
    /// with infinitely many solutions at `start`'s values) into `out`, not polished and
    /// not wrapped, in the order shoulder, elbow, wrist flip; their number, or why the
    /// pose is out of reach.
    ///
    /// With `nearest`, the branches that cannot hold the solution nearest its joint
    /// values are skipped ([`Nearest`]): the solutions returned are a subset, in the
    /// same order, that holds every one as near as the nearest.
    pub(super) fn solve(
        &self,
        target_p: &Vector3<f64>,
        target_r: &Matrix3<f64>,
        start: &Vector6<f64>,
        nearest: Option<&Nearest>,
        out: &mut [Vector6<f64>; 8],
    ) -> Result<usize, Unattainable> {
        let (w, p) = (&self.w, &self.p);
        let tol = GEOMETRY_TOLERANCE * self.scale;
        let centre = target_p + target_r * self.centre_tool;
        // 1. Shoulder: n . E_1(q_1)^-1 centre = n . c.
        let q1s = shoulder(w, p, &self.centre, &centre, tol, start[0]).map_err(|(r, off)| {
            Unattainable::ShoulderOffset {
                what: "the wrist centre would be",
                distance: r,
                offset: off,
            }
        })?;
        let mut s = Solving {
            target_r,
            centre,
            tol,
            start,
            slots: [None; 8],
            search: Search::new(nearest),
            elbow_miss: None,
            wrist_miss: false,
        };
        for i in s.search.order(0, &q1s) {
            let q1 = q1s[i];
            let d1 = s.search.term(0, q1);
            if s.search.beyond(d1) {
                continue;
            }
            self.after_shoulder(&mut s, i, q1, d1);
        }
        let count = gather(s.slots, out);
        if count > 0 {
            return Ok(count);
        }
        Err(match s.elbow_miss {
            Some((_, r, _)) if !s.wrist_miss => self.elbow.miss("the wrist centre", r),
            _ => "the tool orientation needs a wrist bend the wrist's axes cannot make".into(),
        })
    }

    /// Step 2 after shoulder `i` at `q1` (partial distance `d1`): the elbow's
    /// solutions, then the wrist of each.
    fn after_shoulder(&self, s: &mut Solving, i: usize, q1: f64, d1: f64) {
        let (w, p, n) = (&self.w, &self.p, self.w[1]);
        let r1 = rot(&w[0], q1);
        // 2. Elbow: the planar distance from axis 2.
        let v = p[0] + r1.transpose() * (s.centre - p[0]);
        let d = normal(&(v - p[1]), &n);
        let q3s = match self.elbow.bend(&n, &d) {
            Ok(q3s) => q3s,
            Err((miss, r)) => {
                // Of the shoulder's two solutions, report the nearer miss (the first
                // shoulder's on a tie, whatever the order they were tried in).
                if s.elbow_miss
                    .is_none_or(|(m, _, k)| miss < m || (miss == m && i < k))
                {
                    s.elbow_miss = Some((miss, r, i));
                }
                return;
            }
        };
        for j in s.search.order(2, &q3s) {
            let q3 = q3s[j];
            let d13 = d1 + s.search.term(2, q3);
            if s.search.beyond(d13) {
                continue;
            }
            let r3 = rot(&w[2], q3);
            let q2 = self.elbow.lift(&n, &r3, &d, s.tol, s.start[1]);
            let d123 = d13 + s.search.term(1, q2);
            if s.search.beyond(d123) {
                continue;
            }
            let r123 = r1 * rot(&n, q2) * r3;
            self.wrist_branches(s, 4 * i + 2 * j, [q1, q2, q3], &r123, d123);
        }
    }

    /// Step 3, the wrist, of an arm branch at joints `q123` (turn `r123`, partial
    /// distance `d123`), its solutions into slots `slot` and `slot + 1`.
    fn wrist_branches(
        &self,
        s: &mut Solving,
        slot: usize,
        [q1, q2, q3]: [f64; 3],
        r123: &Matrix3<f64>,
        d123: f64,
    ) {
        let w = &self.w;
        let m = r123.transpose() * s.target_r * self.r0.transpose();
        let (w4, w5, w6) = (&w[3], &w[4], &w[5]);
        let (c45, c56) = (w4.dot(w5), w5.dot(w6));
        let a5 = w4.dot(w6) - c56 * c45;
        let b5 = w4.dot(&w5.cross(w6));
        let z = m * w6;
        let Some(q5s) = cos_sin(a5, b5, w4.dot(&z) - c56 * c45) else {
            s.wrist_miss = true;
            return;
        };
        for k in s.search.order(4, &q5s) {
            let q5 = q5s[k];
            let d1235 = d123 + s.search.term(4, q5);
            if s.search.beyond(d1235) {
                continue;
            }
            let r5 = rot(w5, q5);
            let y = r5 * w6;
            let (y_n, z_n) = (normal(&y, w4), normal(&z, w4));
            let q4 = if y_n.norm() <= 1e-9 {
                s.start[3]
            } else {
                angle_about(w4, &y_n, &z_n)
            };
            let d12345 = d1235 + s.search.term(3, q4);
            if s.search.beyond(d12345) {
                continue;
            }
            let k6 = r5.transpose() * rot(w4, q4).transpose() * m;
            let q6 = angle_about(w6, &self.across6, &(k6 * self.across6));
            s.search.found(d12345 + s.search.term(5, q6));
            s.slots[slot + k] = Some(Vector6::new(q1, q2, q3, q4, q5, q6));
        }
    }
}

/// One solve's state: the target, the branch-and-bound, the solutions found by slot
/// and why branches failed.
struct Solving<'a> {
    target_r: &'a Matrix3<f64>,
    /// The wrist centre at the target.
    centre: Vector3<f64>,
    tol: f64,
    start: &'a Vector6<f64>,
    /// Slot `4 i + 2 j + k` holds the solution of shoulder `i`, elbow `j`, wrist `k`.
    slots: [Option<Vector6<f64>>; 8],
    search: Search<'a>,
    /// The nearest elbow miss: how far, the distance it reports, its shoulder.
    elbow_miss: Option<(f64, f64, usize)>,
    wrist_miss: bool,
}
