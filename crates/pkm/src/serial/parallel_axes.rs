//! Closed-form inverse kinematics of a six-revolute arm whose second, third and fourth
//! axes are parallel and whose fifth and sixth axes meet: the geometry of the Universal
//! Robots arms (UR3, UR5, UR10, UR16, UR20, UR30 and their e-Series), of Kinova's Gen3
//! lite-class and Techman arms, and of other collaborative robots, whose wrist is not
//! spherical (axes 4, 5 and 6 do not meet), so [`super::spherical_wrist`] does not
//! apply.
//!
//! The arm is written as a product of exponentials, `T(q) = E_1(q_1) ... E_6(q_6) T_0`
//! (Murray, Li and Sastry, 1994, ch. 3), with joint `k` turning about its axis
//! `(w_k, p_k)` at the zero configuration, `n = w_2`, `w_3 = sigma_3 n`,
//! `w_4 = sigma_4 n`. The product `E_2 E_3 E_4` turns about `n` by
//! `theta = q_2 + sigma_3 q_3 + sigma_4 q_4` (Hawkins, *Analytic inverse kinematics for
//! the Universal Robots UR-5/UR-10 arms*, 2013, solves the same structure from its
//! Denavit-Hartenberg table; this is that solution for any zero pose, tool and base):
//!
//! 1. **Shoulder** `q_1`. The point `c` where axes 5 and 6 meet is fixed by `E_5` and
//!    `E_6`, so at the target it is `c* = T* T_0^-1 c`, and `E_1^-1 c* = E_2 E_3 E_4 c`.
//!    Turns about axes parallel to `n` keep the component along `n`:
//!    `n . E_1(q_1)^-1 c* = n . c`, a subproblem `a cos q_1 + b sin q_1 = g`.
//! 2. **Wrist** `q_5`. Axis 6 at the target has the direction `w_6* = R* R_0^T w_6`
//!    (`E_6` fixes it), and `R_1^T w_6* = Rot(n, theta) Rot(w_5, q_5) w_6`; the
//!    component along `n` gives `n . Rot(w_5, q_5) w_6 = n . R_1^T w_6*`.
//! 3. **The parallel axes' turn** `theta`: the angle about `n` from
//!    `Rot(w_5, q_5) w_6` to `R_1^T w_6*`.
//! 4. **Elbow** `q_3`, `q_2`. Axis 4's point `p_4` is then at
//!    `p_4* = c* - R_1 Rot(n, theta) (c - p_4)`, and `E_1^-1 p_4* = E_2 E_3 p_4` is the
//!    planar two-link arm of the spherical wrist's elbow (a law of cosines in `q_3`,
//!    then `q_2` the angle about `n`); `q_4 = sigma_4 (theta - q_2 - sigma_3 q_3)`.
//! 5. **Flange** `q_6`: what `Rot(w_6, q_6) = (R_1 Rot(n, theta) Rot(w_5, q_5))^T R*
//!    R_0^T` turns about `w_6`.
//!
//! Up to eight solutions (shoulder, elbow, wrist flip). Where a step has infinitely
//! many (the point `c` on axis 1) the joint keeps its start value, as Newton would;
//! with axis 6 parallel to axes 2 to 4 (`q_5 = 0` on a UR) the orientation leaves the
//! parallel axes' turn free and the position fixes it within a band, the start's turn
//! kept when it lies in it ([`ParallelAxes::singular_turn`]). Where one has none (beyond a
//! tolerance of 1e-10 relative) the pose is out of reach, proven, and the reason names
//! the distances involved. The solutions are polished by one Newton step, as the
//! spherical wrist's are ([`super::arm::SerialArm`]).

use nalgebra::{Matrix3, Matrix4, Vector3, Vector6};

use super::spherical_wrist::{
    across, angle_about, apart, cos_sin, gather, normal, parallel, rot, shoulder, Elbow, Nearest,
    Search, ZeroPose, GEOMETRY_TOLERANCE,
};
use super::PreparedChain;
use crate::error::Unattainable;

/// The zero-configuration geometry of an arm the closed form applies to (part frame).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ParallelAxes {
    /// Joint axes: unit directions and a point of each.
    w: [Vector3<f64>; 6],
    p: [Vector3<f64>; 6],
    /// `w_4 = sigma_4 w_2` (`w_3 = sigma_3 w_2` is the elbow's).
    sigma4: f64,
    /// The point where axes 5 and 6 meet.
    c: Vector3<f64>,
    /// The tool pose at zero: rotation and position.
    r0: Matrix3<f64>,
    t0: Vector3<f64>,
    /// The planar arm: `(p_3 - p_2)` and `(p_4 - p_3)` normal to `n`.
    elbow: Elbow,
    /// A unit vector normal to `w_6`.
    across6: Vector3<f64>,
    /// Length scale (mm) of the tolerances.
    scale: f64,
}

impl ParallelAxes {
    /// The closed form's geometry of `chain` seen from the part (`part_inverse`), if it
    /// applies: six revolute joints, axes 2, 3 and 4 parallel, axis 1 and axis 5 not
    /// parallel to them, axes 5 and 6 meeting in one point and not parallel, axis 3
    /// apart from axis 2 and axis 4 apart from axis 3. `scale` is the arm's length
    /// scale (mm).
    pub(super) fn detect(
        chain: &PreparedChain,
        part_inverse: &Matrix4<f64>,
        scale: f64,
    ) -> Option<ParallelAxes> {
        let ZeroPose { w, p, r0, t0 } = ZeroPose::of(chain, part_inverse)?;
        let n = w[1];
        if !parallel(&n, &w[2]) || !parallel(&n, &w[3]) {
            return None;
        }
        if !apart(&w[0], &n) || !apart(&w[4], &n) || !apart(&w[4], &w[5]) {
            return None;
        }
        // The point of axis 5 closest to axis 6, on axis 6 within the tolerance.
        let (d, d56) = (p[5] - p[4], w[4].dot(&w[5]));
        let s = (w[4].dot(&d) - d56 * w[5].dot(&d)) / (1.0 - d56 * d56);
        let c = p[4] + w[4] * s;
        let tol = GEOMETRY_TOLERANCE * scale;
        if normal(&(c - p[5]), &w[5]).norm() > tol {
            return None;
        }
        let e = normal(&(p[2] - p[1]), &n);
        let f = normal(&(p[3] - p[2]), &n);
        if e.norm() <= tol || f.norm() <= tol {
            return None;
        }
        Some(ParallelAxes {
            sigma4: w[3].dot(&n).signum(),
            elbow: Elbow {
                e,
                f,
                sigma: w[2].dot(&n).signum(),
            },
            c,
            r0,
            t0,
            across6: across(&w[5]),
            w,
            p,
            scale,
        })
    }

    /// Every solution of the tool pose `(target_p, target_r)` (at most eight; joints
    /// with infinitely many solutions at `start`'s values) into `out`, not polished and
    /// not wrapped, in the order shoulder, elbow, wrist flip; their number, or why the
    /// pose is out of reach. With `nearest`, the branches that cannot hold the solution
    /// nearest its joint values are skipped, as in [`super::spherical_wrist`].
    pub(super) fn solve(
        &self,
        target_p: &Vector3<f64>,
        target_r: &Matrix3<f64>,
        start: &Vector6<f64>,
        nearest: Option<&Nearest>,
        out: &mut [Vector6<f64>; 8],
    ) -> Result<usize, Unattainable> {
        let (w, p, n) = (&self.w, &self.p, self.w[1]);
        let tol = GEOMETRY_TOLERANCE * self.scale;
        // T* T_0^-1: the turn and the point c where it takes axes 5 and 6.
        let turn = target_r * self.r0.transpose();
        let c_star = target_p + turn * (self.c - self.t0);
        // 1. Shoulder: n . E_1(q_1)^-1 c* = n . c.
        let q1s = shoulder(w, p, &self.c, &c_star, tol, start[0]).map_err(|(r, off)| {
            Unattainable::ShoulderOffset {
                what: "axes 5 and 6 would meet",
                distance: r,
                offset: off,
            }
        })?;
        let (w5, w6) = (&w[4], &w[5]);
        let c56 = w5.dot(w6);
        let mut s = Solving {
            turn,
            c_star,
            w6_star: turn * w[5],
            tol,
            start,
            wrist: (n.dot(&(w6 - w5 * c56)), n.dot(&w5.cross(w6)), c56),
            theta_start: start[1] + self.elbow.sigma * start[2] + self.sigma4 * start[3],
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
            Some((_, r)) => self.elbow.miss("axis 4", r),
            None if s.wrist_miss => {
                "the tool axis would need a tilt to axes 2 to 4 that axes 5 and 6 cannot \
                 make"
                    .into()
            }
            None => "no solution".into(),
        })
    }

    /// Steps 2 to 4 after shoulder `i` at `q1` (partial distance `d1`): the wrist's
    /// solutions, the parallel axes' turn and the elbow of each.
    fn after_shoulder(&self, s: &mut Solving, i: usize, q1: f64, d1: f64) {
        let (w, n) = (&self.w, self.w[1]);
        let (w5, w6) = (&w[4], &w[5]);
        let (a5, b5, c56) = s.wrist;
        let r1 = rot(&w[0], q1);
        // 2. Wrist: n . Rot(w_5, q_5) w_6 = n . R_1^T w_6*.
        let v = r1.transpose() * s.w6_star;
        let Some(q5s) = cos_sin(a5, b5, n.dot(&v) - n.dot(w5) * c56) else {
            s.wrist_miss = true;
            return;
        };
        let v_n = normal(&v, &n);
        let (q5s, singular) = self.near_tangent(q5s, &v_n);
        for k in s.search.order(4, &q5s) {
            let q5 = q5s[k];
            let d15 = d1 + s.search.term(4, q5);
            if s.search.beyond(d15) {
                continue;
            }
            let r5 = rot(w5, q5);
            // 3. The parallel axes' turn: from the tool axis, unless axis 6 is (nearly)
            // along them, where the orientation fixes only theta + q_6 and the position
            // fixes theta.
            let mut theta = if singular {
                self.singular_turn(s, &r1)
            } else {
                angle_about(&n, &normal(&(r5 * w6), &n), &v_n)
            };
            let mut reached = self.reach(s, &r1, theta);
            if reached.is_err() && !singular && v_n.norm() <= NEAR_TANGENT {
                // So near the singularity the tool axis' turn may be rounding's (a
                // DH chain's sines of 90 deg): the position's.
                theta = self.singular_turn(s, &r1);
                reached = self.reach(s, &r1, theta);
            }
            let (d, q3s) = match reached {
                Ok(found) => found,
                Err((miss, r)) => {
                    if s.elbow_miss.is_none_or(|(m, _)| miss < m) {
                        s.elbow_miss = Some((miss, r));
                    }
                    continue;
                }
            };
            let r_theta = rot(&n, theta);
            let branch = WristBranch {
                slot: 4 * i + k,
                q1,
                q5,
                theta,
                d15,
                r15: r1 * r_theta * r5,
            };
            self.elbow_branches(s, &branch, &d, &q3s);
        }
    }

    /// Step 4 for the parallel axes' turn `theta` after shoulder turn `r1`: axis 4's
    /// point seen from axis 2 before the shoulder's turn (`d`, normal to `n`) and the
    /// elbow's two angles, or the elbow's miss ([`Elbow::bend`]).
    fn reach(
        &self,
        s: &Solving,
        r1: &Matrix3<f64>,
        theta: f64,
    ) -> Result<(Vector3<f64>, [f64; 2]), (f64, f64)> {
        let (p, n) = (&self.p, self.w[1]);
        let p4 = s.c_star - r1 * rot(&n, theta) * (self.c - p[3]);
        let d = normal(&(p[0] + r1.transpose() * (p4 - p[0]) - p[1]), &n);
        self.elbow.bend(&n, &d).map(|q3s| (d, q3s))
    }

    /// The wrist's two solutions `q5s` (`phi +- delta` of the subproblem `n .
    /// Rot(w_5, q_5) w_6 = n . v`) where axis 6 is within [`NEAR_TANGENT`] of the
    /// parallel axes (`delta` near 0 or pi), and whether the wrist is singular there.
    /// Near that tangent the subproblem's `delta = acos(ratio)` is rounding (a ratio within 1e-16 of 1 gives
    /// 1.5e-8 rad), while `v_n`, axis 6's component normal to `n` at the target, still
    /// holds it: `|normal(Rot(w_5, phi +- delta) w_6, n)| = sin(delta) |t|` with
    /// `t = normal(w_5 x Rot(w_5, phi) w_6, n)` (exactly where `w_5` is normal to `n`,
    /// as on a UR; to first order otherwise, which the polishing Newton step takes
    /// up). So `delta = asin(|v_n| / |t|)`; below [`WRIST_NOISE`] the target is on the
    /// singularity itself and the turn comes from the position.
    fn near_tangent(&self, q5s: [f64; 2], v_n: &Vector3<f64>) -> ([f64; 2], bool) {
        let (n, w5, w6) = (self.w[1], &self.w[4], &self.w[5]);
        if normal(&(rot(w5, q5s[0]) * w6), &n).norm() > NEAR_TANGENT {
            return (q5s, false);
        }
        // The tangent: `phi` (axis 6 along n) or `phi + pi` (against it), where the
        // two solutions `phi +- delta` meet at `delta` near 0 or near pi.
        let (phi, delta) = (0.5 * (q5s[0] + q5s[1]), 0.5 * (q5s[0] - q5s[1]));
        let phi = if delta > std::f64::consts::FRAC_PI_2 {
            phi + std::f64::consts::PI
        } else {
            phi
        };
        let along = rot(w5, phi) * w6;
        let t = normal(&w5.cross(&along), &n).norm();
        if v_n.norm() <= WRIST_NOISE || t <= 0.5 {
            return ([phi, phi], true);
        }
        let delta = (v_n.norm() / t).min(1.0).asin();
        ([phi + delta, phi - delta], false)
    }

    /// The parallel axes' turn `theta` at the wrist singularity (axis 6 along axes 2
    /// to 4: `q_5 = 0` or `pi` on a UR), after shoulder turn `r1`. There the tool's
    /// orientation fixes only `theta` and `q_6` together, and the solutions form a
    /// family: axis 4's point `p_4*` seen from axis 2 is `d(theta) = g - Rot(n,
    /// theta) h` (normal to `n`; `g` the wrist centre `c*`, `h = c - p_4`), with
    /// `|d|^2 = |g|^2 + |h|^2 - 2 |g| |h| cos(theta - phi)`, `phi` the angle about `n`
    /// from `h` to `g`. The elbow reaches `|d|` within `[| |e| - |f| |, |e| + |f|]`: a
    /// band of `theta`. The turn is the start's when it lies in the band, else the
    /// band's nearest point a millionth of its width inside (the elbow not at its
    /// stretched or folded edge); the start's when no `theta` reaches (the elbow then
    /// reports the miss).
    fn singular_turn(&self, s: &Solving, r1: &Matrix3<f64>) -> f64 {
        let (p, n) = (&self.p, self.w[1]);
        let g = normal(&(p[0] + r1.transpose() * (s.c_star - p[0]) - p[1]), &n);
        let h = normal(&(self.c - p[3]), &n);
        let (gn, hn) = (g.norm(), h.norm());
        if gn * hn <= s.tol * s.tol {
            // |d| does not depend on theta.
            return s.theta_start;
        }
        let phi = angle_about(&n, &h, &g);
        let (e, f) = (self.elbow.e.norm(), self.elbow.f.norm());
        let (r_min, r_max) = ((e - f).abs(), e + f);
        let cos_at = |r: f64| (gn * gn + hn * hn - r * r) / (2.0 * gn * hn);
        // |d| <= r_max where cos(theta - phi) >= cos_at(r_max); |d| >= r_min where
        // cos(theta - phi) <= cos_at(r_min).
        let (lo, hi) = (cos_at(r_max).max(-1.0), cos_at(r_min).min(1.0));
        // A band of one point (the arm stretched out to the target) may come out a
        // rounding's width empty.
        if lo > hi + 1e-12 {
            return s.theta_start;
        }
        let lo = lo.min(hi);
        // |theta - phi| within [acos(hi), acos(lo)].
        let (a, b) = (hi.acos(), lo.acos());
        let margin = 1e-6 * (b - a);
        let delta = (s.theta_start - phi + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        let inside = delta.abs().clamp(a + margin, b - margin);
        s.theta_start + (inside * if delta < 0.0 { -1.0 } else { 1.0 } - delta)
    }

    /// The elbow's solutions `q3s` (planar distance `d`) of a wrist branch, then `q_2`,
    /// `q_4` and step 5, the flange, into their slots.
    fn elbow_branches(&self, s: &mut Solving, b: &WristBranch, d: &Vector3<f64>, q3s: &[f64; 2]) {
        let n = self.w[1];
        for j in s.search.order(2, q3s) {
            let q3 = q3s[j];
            let d135 = b.d15 + s.search.term(2, q3);
            if s.search.beyond(d135) {
                continue;
            }
            let q2 = self
                .elbow
                .lift(&n, &rot(&self.w[2], q3), d, s.tol, s.start[1]);
            let q4 = self.sigma4 * (b.theta - q2 - self.elbow.sigma * q3);
            let d12345 = d135 + s.search.term(1, q2) + s.search.term(3, q4);
            if s.search.beyond(d12345) {
                continue;
            }
            // 5. Flange.
            let k6 = b.r15.transpose() * s.turn;
            let q6 = angle_about(&self.w[5], &self.across6, &(k6 * self.across6));
            s.search.found(d12345 + s.search.term(5, q6));
            s.slots[b.slot + 2 * j] = Some(Vector6::new(b.q1, q2, q3, q4, b.q5, q6));
        }
    }
}

/// The sine of the angle between axis 6 and the parallel axes below which the wrist
/// subproblem is near its tangent and its solutions are taken from axis 6's normal
/// component instead ([`ParallelAxes::near_tangent`]): there `acos` near 1 loses
/// half the digits (1e-8 rad from rounding), the normal component none.
const NEAR_TANGENT: f64 = 1e-6;

/// Axis 6's component normal to the parallel axes at the target below which the
/// target is on the wrist singularity itself (rounding of a unit vector: a few
/// 1e-16): the turn then comes from the position ([`ParallelAxes::singular_turn`]).
const WRIST_NOISE: f64 = 1e-14;

/// One solve's state: the target seen by the closed form, the branch-and-bound, the
/// solutions found by slot and why branches failed.
struct Solving<'a> {
    /// `T* T_0^-1`'s turn, and where it takes `c` and `w_6`.
    turn: Matrix3<f64>,
    c_star: Vector3<f64>,
    w6_star: Vector3<f64>,
    tol: f64,
    start: &'a Vector6<f64>,
    /// The wrist subproblem's coefficients `a_5`, `b_5` and `w_5 . w_6`.
    wrist: (f64, f64, f64),
    /// The parallel axes' turn at `start`.
    theta_start: f64,
    /// Slot `4 i + 2 j + k` holds the solution of shoulder `i`, elbow `j`, wrist `k`.
    slots: [Option<Vector6<f64>>; 8],
    search: Search<'a>,
    /// The nearest elbow miss (how far, and the distance it reports).
    elbow_miss: Option<(f64, f64)>,
    wrist_miss: bool,
}

/// A branch through the shoulder and the wrist: its slot without the elbow's part,
/// its joints, partial distance, and the turn `R_1 Rot(n, theta) R_5`.
struct WristBranch {
    slot: usize,
    q1: f64,
    q5: f64,
    theta: f64,
    d15: f64,
    r15: Matrix3<f64>,
}
