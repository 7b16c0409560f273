//! Rotation conventions users type, and conversions between them.
//!
//! All conventions map three angles (radians here; degrees at the user boundary) to a
//! proper rotation matrix `R` that takes vectors from the moving (platform / tool) frame
//! to the fixed (base) frame: `x_base = R x_moving + p`.
//!
//! | convention | angles typed | matrix |
//! |---|---|---|
//! | [`Convention::Rpy`] (default) | A, B, C | `Rz(C) Ry(B) Rx(A)`: fixed-axis roll-pitch-yaw X-Y-Z, the A/B/C convention of CNC controllers such as LinuxCNC |
//! | [`Convention::Zyx`] | alpha, beta, gamma | `Rz(alpha) Ry(beta) Rx(gamma)`: intrinsic Z-Y'-X'' Euler angles (same matrix as RPY, angles typed in the opposite order) |
//! | [`Convention::Zyz`] | alpha, beta, gamma | `Rz(alpha) Ry(beta) Rz(gamma)`: intrinsic Z-Y'-Z'' Euler angles |
//! | [`Convention::Krylov`] | psi, theta, gamma | seed 001 eq. 2, which equals `Rz(-psi) Rx(-theta) Ry(-gamma)` |
//! | [`Convention::RotationVector`] | rx, ry, rz | axis * angle (axis-angle as one vector) |
//!
//! `Rx`, `Ry`, `Rz` are right-hand rotations about the base axes. Quaternions and
//! axis-angle pairs are converted with [`quaternion_wxyz`], [`from_quaternion_wxyz`],
//! [`axis_angle`] and [`from_axis_angle`].

use std::fmt;
use std::str::FromStr;

use nalgebra::{Matrix3, Rotation3, Unit, UnitQuaternion, Vector3};
use serde::Serialize;

use crate::error::Error;

/// A way of writing an orientation as three angles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Convention {
    /// Fixed-axis X-Y-Z roll/pitch/yaw: `R = Rz(c) Ry(b) Rx(a)` for angles `(a, b, c)`.
    #[default]
    Rpy,
    /// Intrinsic Z-Y'-X'' Euler: `R = Rz(a) Ry(b) Rx(c)` for angles `(a, b, c)`.
    Zyx,
    /// Intrinsic Z-Y'-Z'' Euler: `R = Rz(a) Ry(b) Rz(c)` for angles `(a, b, c)`.
    Zyz,
    /// Krylov angles of seed 001 (Smirnov 2009, eq. 2) for `(psi, theta, gamma)`:
    /// `R = Rz(-psi) Rx(-theta) Ry(-gamma)`.
    Krylov,
    /// Rotation vector: axis times angle.
    RotationVector,
}

impl Convention {
    /// Every convention, for help texts and tests.
    pub const ALL: [Convention; 5] = [
        Convention::Rpy,
        Convention::Zyx,
        Convention::Zyz,
        Convention::Krylov,
        Convention::RotationVector,
    ];

    /// The name users type.
    pub fn name(self) -> &'static str {
        match self {
            Convention::Rpy => "rpy",
            Convention::Zyx => "zyx",
            Convention::Zyz => "zyz",
            Convention::Krylov => "krylov",
            Convention::RotationVector => "rotvec",
        }
    }

    /// Names of the three angles in this convention.
    pub fn angle_names(self) -> [&'static str; 3] {
        match self {
            Convention::Rpy => ["A", "B", "C"],
            Convention::Zyx | Convention::Zyz => ["alpha", "beta", "gamma"],
            Convention::Krylov => ["psi", "theta", "gamma"],
            Convention::RotationVector => ["rx", "ry", "rz"],
        }
    }

    /// Rotation matrix from three angles (radians).
    pub fn to_matrix(self, a: [f64; 3]) -> Matrix3<f64> {
        match self {
            Convention::Rpy => rpy_matrix(a[0], a[1], a[2]),
            Convention::Zyx => rz(a[0]) * ry(a[1]) * rx(a[2]),
            Convention::Zyz => rz(a[0]) * ry(a[1]) * rz(a[2]),
            Convention::Krylov => krylov_matrix(a[0], a[1], a[2]),
            Convention::RotationVector => {
                *Rotation3::from_scaled_axis(Vector3::new(a[0], a[1], a[2])).matrix()
            }
        }
    }

    /// Three angles (radians) of a rotation matrix in this convention.
    ///
    /// At a gimbal lock (the middle angle at +-90 deg for RPY/ZYX/Krylov, 0 or 180 deg
    /// for ZYZ) only a sum or difference of the outer angles is defined; the last one
    /// is then set to zero. The result always reproduces the matrix.
    pub fn from_matrix(self, m: &Matrix3<f64>) -> [f64; 3] {
        match self {
            Convention::Rpy => rpy_from_matrix(m),
            Convention::Zyx => {
                let [a, b, c] = rpy_from_matrix(m);
                [c, b, a]
            }
            Convention::Zyz => zyz_from_matrix(m),
            Convention::Krylov => krylov_from_matrix(m),
            Convention::RotationVector => {
                let v = rotation_vector(m);
                [v.x, v.y, v.z]
            }
        }
    }
}

impl fmt::Display for Convention {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Convention {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        Convention::ALL
            .into_iter()
            .find(|c| c.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| Error::InvalidInput {
                what: "rotation convention".into(),
                message: format!(
                    "unknown convention `{s}`, expected one of {}",
                    Convention::ALL.map(|c| c.name()).join(", ")
                ),
            })
    }
}

/// `Rz(c) Ry(b) Rx(a)` written out (the default A, B, C convention), without matrix
/// products: on the hot path of every spatial pose. The three sines and cosines come
/// from one vectorised pass ([`crate::trig::sin_cos_array`], within 2 units in the
/// last place of libm's): libm's `sin_cos`, three calls per pose, was the largest cost
/// of a hexapod's inverse kinematics on random poses. Compiled with FMA enabled where
/// the CPU has it (the kernel's and the entries' multiply-adds are fused: the same bits
/// as the AVX-512 kernels').
#[inline]
pub fn rpy_matrix(a: f64, b: f64, c: f64) -> Matrix3<f64> {
    if a == 0.0 && b == 0.0 && c == 0.0 {
        return Matrix3::identity();
    }
    crate::trig::with_fma!((a: f64, b: f64, c: f64) -> Matrix3<f64> {
        let (s, c) = crate::trig::sin_cos_array_by::<crate::trig::Fused, 3>(&[a, b, c]);
        rpy_from_sin_cos(s, c)
    })
}

/// [`rpy_matrix`] from the sines `[sa, sb, sc]` and cosines `[ca, cb, cc]` of the
/// angles (the one sequence of operations of every path that builds it).
#[inline(always)]
pub(crate) fn rpy_from_sin_cos(s: [f64; 3], c: [f64; 3]) -> Matrix3<f64> {
    let e = rpy_entries(s, c);
    Matrix3::new(e[0], e[1], e[2], e[3], e[4], e[5], e[6], e[7], e[8])
}

/// The entries of [`rpy_from_sin_cos`], row by row, on any number type (`f64`, or an
/// AVX-512 register of eight poses' values: [`crate::lane`]). The four entries of two
/// terms take a fused multiply-add each (`(c_C s_B) s_A - s_C c_A` with one rounding
/// for the product and the difference), a step less on the rotation's longest path;
/// on `f64` the caller runs it with FMA enabled where the CPU has it
/// ([`crate::trig::with_fma`]).
#[inline(always)]
pub(crate) fn rpy_entries<T: crate::lane::Lane>(s: [T; 3], c: [T; 3]) -> [T; 9] {
    let ([sa, sb, sc], [ca, cb, cc]) = (s, c);
    [
        cc.mul(cb),
        cc.mul(sb).mul_add(sa, sc.mul(ca).neg()),
        cc.mul(sb).mul_add(ca, sc.mul(sa)),
        sc.mul(cb),
        sc.mul(sb).mul_add(sa, cc.mul(ca)),
        sc.mul(sb).mul_add(ca, cc.mul(sa).neg()),
        sb.neg(),
        cb.mul(sa),
        cb.mul(ca),
    ]
}

/// The angle `a` (rad) wrapped into `(-pi, pi]`.
pub fn wrap_angle(a: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let w = (a + pi).rem_euclid(2.0 * pi) - pi;
    if w <= -pi {
        w + 2.0 * pi
    } else {
        w
    }
}

/// The whole turns `(d / 2 pi).round()` in an angle difference `d` (rad), bit for bit,
/// signed zeros and NaN included: within half a turn (nearly every call, a joint
/// compared with its previous value) `d / 2 pi` times zero, which is the rounding's
/// signed zero, without the call to libm's `round` (the baseline x86-64 target has no
/// rounding instruction; 3.6 % of a 6R robot's motion went to it).
#[inline]
pub fn whole_turns(d: f64) -> f64 {
    let r = d / std::f64::consts::TAU;
    if r.abs() < 0.5 {
        r * 0.0
    } else {
        r.round()
    }
}

/// Right-hand rotation about the X axis.
pub fn rx(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
}

/// Right-hand rotation about the Y axis.
pub fn ry(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// Right-hand rotation about the Z axis.
pub fn rz(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// The direction-cosine matrix of seed 001 (Smirnov 2009, eq. 2), written entry by
/// entry as the paper prints it; rows `(l1 l2 l3)`, `(m1 m2 m3)`, `(n1 n2 n3)`.
///
/// It equals `Rz(-psi) Rx(-theta) Ry(-gamma)` (checked in the tests), i.e. the
/// transpose of `Ry(gamma) Rx(theta) Rz(psi)`.
pub fn krylov_matrix(psi: f64, theta: f64, gamma: f64) -> Matrix3<f64> {
    let (sp, cp) = psi.sin_cos();
    let (st, ct) = theta.sin_cos();
    let (sg, cg) = gamma.sin_cos();
    Matrix3::new(
        cp * cg + st * sp * sg,
        sp * ct,
        -cp * sg + sp * st * cg,
        -sp * cg + st * cp * sg,
        cp * ct,
        sp * sg + cp * st * cg,
        ct * sg,
        -st,
        ct * cg,
    )
}

const LOCK: f64 = 1e-12;

fn rpy_from_matrix(m: &Matrix3<f64>) -> [f64; 3] {
    // R = Rz(c) Ry(b) Rx(a): r20 = -sin b, r21 = cos b sin a, r22 = cos b cos a,
    // r10 = sin c cos b, r00 = cos c cos b.
    let cb = m[(0, 0)].hypot(m[(1, 0)]);
    let b = (-m[(2, 0)]).atan2(cb);
    if cb > LOCK {
        [m[(2, 1)].atan2(m[(2, 2)]), b, m[(1, 0)].atan2(m[(0, 0)])]
    } else {
        // Gimbal lock: only c -+ a is defined; take a = 0.
        // b = +90: r01 = -sin c, r11 = cos c (with a = 0); b = -90 likewise.
        [0.0, b, (-m[(0, 1)]).atan2(m[(1, 1)])]
    }
}

fn zyz_from_matrix(m: &Matrix3<f64>) -> [f64; 3] {
    // R = Rz(a) Ry(b) Rz(c): r22 = cos b, r02 = cos a sin b, r12 = sin a sin b,
    // r20 = -sin b cos c, r21 = sin b sin c.
    let sb = m[(0, 2)].hypot(m[(1, 2)]);
    let b = sb.atan2(m[(2, 2)]);
    if sb > LOCK {
        [m[(1, 2)].atan2(m[(0, 2)]), b, m[(2, 1)].atan2(-m[(2, 0)])]
    } else if m[(2, 2)] > 0.0 {
        // b = 0: R = Rz(a + c).
        [m[(1, 0)].atan2(m[(0, 0)]), b, 0.0]
    } else {
        // b = pi: R = Rz(a) diag(-1, 1, -1) Rz(c); with c = 0, r00 = -cos a, r10 = -sin a.
        [(-m[(1, 0)]).atan2(-m[(0, 0)]), b, 0.0]
    }
}

fn krylov_from_matrix(m: &Matrix3<f64>) -> [f64; 3] {
    // n2 = -sin theta, l2 = sin psi cos theta, m2 = cos psi cos theta,
    // n1 = cos theta sin gamma, n3 = cos theta cos gamma.
    let ct = m[(0, 1)].hypot(m[(1, 1)]);
    let theta = (-m[(2, 1)]).atan2(ct);
    if ct > LOCK {
        [
            m[(0, 1)].atan2(m[(1, 1)]),
            theta,
            m[(2, 0)].atan2(m[(2, 2)]),
        ]
    } else {
        // theta = +-90 deg: only psi -+ gamma is defined; take gamma = 0. Then
        // l1 = cos psi, m1 = -sin psi.
        [(-m[(1, 0)]).atan2(m[(0, 0)]), theta, 0.0]
    }
}

/// Unit quaternion `[w, x, y, z]` of a rotation matrix.
pub fn quaternion_wxyz(m: &Matrix3<f64>) -> [f64; 4] {
    let q = UnitQuaternion::from_matrix(m);
    [q.w, q.i, q.j, q.k]
}

/// The unit quaternion of a rotation matrix that is orthonormal to rounding (a nominal
/// chain's frame, a product of exact rotations): Shepperd's method (nalgebra's
/// `UnitQuaternion::from_rotation_matrix`: the largest of `w, x, y, z` from the trace
/// or a diagonal entry, the others from sums and differences of the off-diagonal
/// ones), renormalised. A few dozen operations where `UnitQuaternion::from_matrix`'s
/// iterative extraction of the rotational part (Mueller et al. 2016, for matrices
/// that are not orthonormal, such as deviated blocks) takes about a microsecond; the
/// two agree within 1e-15 on such matrices (tested). A matrix `e` from orthonormal
/// gives a quaternion in error by about `e` (machine files accept link rotations
/// within 1e-9).
pub fn orthonormal_quaternion(m: &Matrix3<f64>) -> UnitQuaternion<f64> {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*m));
    UnitQuaternion::new_normalize(q.into_inner())
}

/// Rotation matrix of a quaternion `[w, x, y, z]` (normalised first).
pub fn from_quaternion_wxyz(q: [f64; 4]) -> Result<Matrix3<f64>, Error> {
    let raw = nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]);
    if !(raw.norm() > 1e-12) || !raw.norm().is_finite() {
        return Err(Error::InvalidInput {
            what: "quaternion".into(),
            message: "must be finite and non-zero".into(),
        });
    }
    Ok(*UnitQuaternion::from_quaternion(raw)
        .to_rotation_matrix()
        .matrix())
}

/// Axis (unit) and angle (radians, in `[0, pi]`) of a rotation matrix; the axis is
/// `+Z` for the identity. Accurate to rounding at every angle (see [`rotation_vector`]).
pub fn axis_angle(m: &Matrix3<f64>) -> (Vector3<f64>, f64) {
    let v = rotation_vector(m);
    let angle = v.norm();
    if angle == 0.0 {
        (Vector3::z(), 0.0)
    } else {
        (v / angle, angle)
    }
}

/// The axial vector of the skew part of `m`, `vee((m - m^T) / 2)`: for `m = dR R^T` the
/// small rotation `dR` applies, exact to first order and defined for blocks that are not
/// exactly orthonormal (seed 003's deviated links).
pub fn skew_vee(m: &Matrix3<f64>) -> Vector3<f64> {
    Vector3::new(
        0.5 * (m[(2, 1)] - m[(1, 2)]),
        0.5 * (m[(0, 2)] - m[(2, 0)]),
        0.5 * (m[(1, 0)] - m[(0, 1)]),
    )
}

/// Rotation vector (axis times angle, angle in `[0, pi]`) of a rotation matrix.
///
/// The angle is `atan2(|w| / 2, (tr R - 1) / 2)` with `w = vee(R - R^T) = 2 sin(angle) n`.
/// Below 120 deg the axis is `w / |w|`; above, where `w` vanishes towards 180 deg, it
/// comes from the symmetric part `(R + R^T)/2 - cos(angle) I = (1 - cos(angle)) n n^T`
/// (its largest column), signed by `w`. The usual `acos`/`w`-only formula loses digits
/// near 180 deg (4e-13 matrix error found by the rotation proptest), this does not.
pub fn rotation_vector(m: &Matrix3<f64>) -> Vector3<f64> {
    let w = 2.0 * skew_vee(m);
    let s = 0.5 * w.norm();
    let c = 0.5 * (m.trace() - 1.0);
    let angle = s.atan2(c);
    if c > -0.5 {
        if s < 1e-8 {
            // angle / (2 sin angle) = (1 + angle^2 / 6) / 2 to rounding.
            return w * (0.5 * (1.0 + angle * angle / 6.0));
        }
        return w * (angle / (2.0 * s));
    }
    let b = 0.5 * (m + m.transpose()) - Matrix3::identity() * c;
    let k = (0..3)
        .max_by(|&i, &j| b[(i, i)].total_cmp(&b[(j, j)]))
        .unwrap_or(0);
    let mut n = b.column(k).into_owned();
    let norm = n.norm();
    if !(norm > 0.0) {
        return Vector3::zeros();
    }
    n /= norm;
    if n.dot(&w) < 0.0 {
        n = -n;
    }
    n * angle
}

/// Rotation matrix of a rotation by `angle` (radians) about `axis` (any length > 0).
pub fn from_axis_angle(axis: &Vector3<f64>, angle: f64) -> Result<Matrix3<f64>, Error> {
    let unit = Unit::try_new(*axis, 1e-12).ok_or_else(|| Error::InvalidInput {
        what: "rotation axis".into(),
        message: "must be a non-zero vector".into(),
    })?;
    Ok(*Rotation3::from_axis_angle(&unit, angle).matrix())
}

/// Angle (radians) between the Z axes of the moving and fixed frames: the tilt of a
/// spindle whose axis is the moving frame's Z.
///
/// Computed as `atan2(|(r02, r12)|, r22)`, accurate for small and large tilts alike.
pub fn tilt(m: &Matrix3<f64>) -> f64 {
    m[(0, 2)].hypot(m[(1, 2)]).atan2(m[(2, 2)])
}

/// Angle (radians) of the relative rotation `a^T b`, in `[0, pi]`.
///
/// Computed as `atan2(|vee(R - R^T)| / 2, (tr R - 1) / 2)` with `R = a^T b`, accurate
/// near 0 (where `acos` of the trace alone loses half the digits) and near pi.
pub fn angle_between(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let r = a.transpose() * b;
    let v = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    );
    (0.5 * v.norm()).atan2(0.5 * (r.trace() - 1.0))
}

/// Angular velocity and acceleration of the A, B, C angles moving with rates `ad` and
/// accelerations `add`: `w = E ad`, `al = E add + E' ad`, with `E` from
/// [`rpy_rate_matrix`] and `E'` its time derivative, written out from one sine and
/// cosine of `B` and of `C` (`c_B`, `s_B`, ...):
///
/// `E = [(c_C c_B, s_C c_B, -s_B), (-s_C, c_C, 0), (0, 0, 1)]` (columns),
/// `E' = [C' (-s_C c_B, c_C c_B, 0) + B' (-c_C s_B, -s_C s_B, -c_B), C' (-c_C, -s_C, 0), 0]`,
///
/// so, component by component (the one sequence of operations of every path that
/// computes it, the hexapod's motion kernel across SIMD lanes included):
///
/// `w = (c_C c_B A' - s_C B', s_C c_B A' + c_C B', C' - s_B A')`,
/// `al = (c_C c_B A'' - s_C B'' - (s_C c_B C' + c_C s_B B') A' - c_C C' B',
///        s_C c_B A'' + c_C B'' + (c_C c_B C' - s_C s_B B') A' - s_C C' B',
///        C'' - s_B A'' - c_B B' A')`.
///
/// The sines and cosines come from [`crate::trig::sin_cos`] (within 2 units in the
/// last place of libm's; the same kernel as [`rpy_matrix`]). No angular motion at all
/// (`ad = add = 0`, held orientations) gives exact zeros.
#[inline]
pub fn rpy_angular_motion(
    a: [f64; 3],
    ad: &Vector3<f64>,
    add: &Vector3<f64>,
) -> (Vector3<f64>, Vector3<f64>) {
    if *ad == Vector3::zeros() && *add == Vector3::zeros() {
        return (Vector3::zeros(), Vector3::zeros());
    }
    let (sb, cb) = crate::trig::sin_cos(a[1]);
    let (sc, cc) = crate::trig::sin_cos(a[2]);
    let [w, al] = rpy_angular_terms([sb, cb, sc, cc], [ad.x, ad.y, ad.z], [add.x, add.y, add.z]);
    (Vector3::from(w), Vector3::from(al))
}

/// [`rpy_angular_motion`]'s arithmetic on any number type (`f64`, or an AVX-512
/// register of eight poses' values: [`crate::lane`]): the same operations in the same
/// order, so every path gives the same bits.
#[inline(always)]
pub(crate) fn rpy_angular_terms<T: crate::lane::Lane>(
    [sb, cb, sc, cc]: [T; 4],
    [a1, b1, c1]: [T; 3],
    [a2, b2, c2]: [T; 3],
) -> [[T; 3]; 2] {
    let ccb = cc.mul(cb);
    let scb = sc.mul(cb);
    let w = [
        ccb.mul(a1).sub(sc.mul(b1)),
        scb.mul(a1).add(cc.mul(b1)),
        c1.sub(sb.mul(a1)),
    ];
    let al = [
        ccb.mul(a2)
            .sub(sc.mul(b2))
            .sub(scb.mul(c1).add(cc.mul(sb).mul(b1)).mul(a1))
            .sub(cc.mul(c1).mul(b1)),
        scb.mul(a2)
            .add(cc.mul(b2))
            .add(ccb.mul(c1).sub(sc.mul(sb).mul(b1)).mul(a1))
            .sub(sc.mul(c1).mul(b1)),
        c2.sub(sb.mul(a2)).sub(cb.mul(b1).mul(a1)),
    ];
    [w, al]
}

/// Angular-velocity map of the A, B, C angles (`R = Rz(C) Ry(B) Rx(A)`):
/// `w = E (A', B', C')` with columns `Rz(C) Ry(B) e_x`, `Rz(C) e_y`, `e_z`.
pub fn rpy_rate_matrix(a: [f64; 3]) -> Matrix3<f64> {
    let rzc = rz(a[2]);
    let c0 = rzc * ry(a[1]) * Vector3::x();
    let c1 = rzc * Vector3::y();
    Matrix3::from_columns(&[c0, c1, Vector3::z()])
}
