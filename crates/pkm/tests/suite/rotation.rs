//! Rotation conventions: round trips, the Krylov matrix of seed 001, gimbal locks.

use nalgebra::{Matrix3, Rotation3, Vector3};
use pkm::rotation::{
    axis_angle, from_axis_angle, from_quaternion_wxyz, krylov_matrix, orthonormal_quaternion,
    quaternion_wxyz, rx, ry, rz, Convention,
};
use proptest::prelude::*;

fn is_rotation(m: &Matrix3<f64>) -> bool {
    (m.transpose() * m - Matrix3::identity()).amax() < 1e-12
        && (m.determinant() - 1.0).abs() < 1e-12
}

#[test]
fn krylov_equals_composed_rotations() {
    // Seed 001 eq. 2, as printed, equals Rz(-psi) Rx(-theta) Ry(-gamma) (spec 02).
    for &(psi, theta, gamma) in &[
        (0.3, -0.2, 0.7),
        (-1.2, 0.9, 2.5),
        (3.0, 1.4, -0.1),
        (0.0, 0.0, 0.0),
    ] {
        let paper = krylov_matrix(psi, theta, gamma);
        let composed = rz(-psi) * rx(-theta) * ry(-gamma);
        assert!((paper - composed).amax() < 1e-15, "{paper} vs {composed}");
        assert!(is_rotation(&paper));
        // ... and is the transpose of Ry(gamma) Rx(theta) Rz(psi).
        let t = (ry(gamma) * rx(theta) * rz(psi)).transpose();
        assert!((paper - t).amax() < 1e-15);
    }
}

#[test]
fn rpy_matches_nalgebra_euler_angles() {
    // Independent implementation: nalgebra's from_euler_angles(roll, pitch, yaw) is
    // Rz(yaw) Ry(pitch) Rx(roll).
    let (a, b, c) = (0.4, -0.3, 1.1);
    let ours = Convention::Rpy.to_matrix([a, b, c]);
    let theirs = *Rotation3::from_euler_angles(a, b, c).matrix();
    assert!((ours - theirs).amax() < 1e-15);
    let back = Convention::Rpy.from_matrix(&theirs);
    assert!(
        (back[0] - a).abs() < 1e-14 && (back[1] - b).abs() < 1e-14 && (back[2] - c).abs() < 1e-14
    );
}

#[test]
fn elementary_rotations_are_right_handed() {
    let v = rz(std::f64::consts::FRAC_PI_2) * Vector3::x();
    assert!((v - Vector3::y()).amax() < 1e-15);
    let v = rx(std::f64::consts::FRAC_PI_2) * Vector3::y();
    assert!((v - Vector3::z()).amax() < 1e-15);
    let v = ry(std::f64::consts::FRAC_PI_2) * Vector3::z();
    assert!((v - Vector3::x()).amax() < 1e-15);
}

#[test]
fn zyx_is_rpy_typed_in_reverse() {
    let m1 = Convention::Zyx.to_matrix([0.1, 0.2, 0.3]);
    let m2 = Convention::Rpy.to_matrix([0.3, 0.2, 0.1]);
    assert!((m1 - m2).amax() < 1e-15);
}

#[test]
fn gimbal_locks_reproduce_the_matrix() {
    let h = std::f64::consts::FRAC_PI_2;
    let cases = [
        (Convention::Rpy, [0.3, h, 0.5]),
        (Convention::Rpy, [0.3, -h, 0.5]),
        (Convention::Zyx, [0.3, h, -0.5]),
        (Convention::Zyz, [0.3, 0.0, 0.5]),
        (Convention::Zyz, [0.3, std::f64::consts::PI, 0.5]),
        (Convention::Krylov, [0.3, h, 0.5]),
        (Convention::Krylov, [0.3, -h, 0.5]),
    ];
    for (c, a) in cases {
        let m = c.to_matrix(a);
        let back = c.from_matrix(&m);
        let m2 = c.to_matrix(back);
        assert!((m - m2).amax() < 1e-12, "{c}: {a:?} -> {back:?}");
    }
}

#[test]
fn conventions_parse_by_name() {
    for c in Convention::ALL {
        assert_eq!(c.name().parse::<Convention>().unwrap(), c);
    }
    assert!("euler".parse::<Convention>().is_err());
}

fn angles() -> impl Strategy<Value = [f64; 3]> {
    [-3.1f64..3.1, -3.1f64..3.1, -3.1f64..3.1]
}

proptest! {
    #[test]
    fn every_convention_round_trips(a in angles()) {
        // Any matrix -> angles -> matrix, in every convention, and conversions between
        // every pair of conventions through the matrix.
        let m = Convention::Rpy.to_matrix(a);
        prop_assert!(is_rotation(&m));
        // Near a convention's gimbal lock its outer angles are determined only to
        // eps / (distance from the lock): the first proptest run found a case 4.6e-5
        // rad from it with a 5e-12 matrix error. The tolerance follows that bound.
        let margin = [
            m[(0, 0)].hypot(m[(1, 0)]),
            m[(0, 2)].hypot(m[(1, 2)]),
            m[(0, 1)].hypot(m[(1, 1)]),
        ]
        .into_iter()
        .fold(f64::INFINITY, f64::min);
        let tol = (1e-15 / margin).max(1e-12);
        for c in Convention::ALL {
            let ang = c.from_matrix(&m);
            let m2 = c.to_matrix(ang);
            prop_assert!((m - m2).amax() < tol, "{} {:?}", c, a);
            for d in Convention::ALL {
                let other = d.from_matrix(&c.to_matrix(ang));
                prop_assert!((d.to_matrix(other) - m).amax() < tol);
            }
        }
    }

    #[test]
    fn angles_inside_principal_ranges_come_back_unchanged(
        a in -3.0f64..3.0, b in -1.5f64..1.5, c in -3.0f64..3.0
    ) {
        for conv in [Convention::Rpy, Convention::Zyx, Convention::Krylov] {
            let back = conv.from_matrix(&conv.to_matrix([a, b, c]));
            prop_assert!((back[0] - a).abs() < 1e-9 && (back[1] - b).abs() < 1e-9 && (back[2] - c).abs() < 1e-9);
        }
        let bz = b.abs() + 0.05; // ZYZ middle angle in (0, pi)
        let back = Convention::Zyz.from_matrix(&Convention::Zyz.to_matrix([a, bz, c]));
        prop_assert!((back[0] - a).abs() < 1e-9 && (back[1] - bz).abs() < 1e-9 && (back[2] - c).abs() < 1e-9);
    }

    #[test]
    fn quaternion_and_axis_angle_round_trip(a in angles()) {
        let m = Convention::Rpy.to_matrix(a);
        let q = quaternion_wxyz(&m);
        prop_assert!((from_quaternion_wxyz(q).unwrap() - m).amax() < 1e-12);
        let (axis, angle) = axis_angle(&m);
        prop_assert!((from_axis_angle(&axis, angle).unwrap() - m).amax() < 1e-12);
    }
}

/// The quaternion by Shepperd's method against nalgebra's iterative extraction (an
/// independent algorithm) and against the matrix it came from; `q` and `-q` are one
/// rotation, so the sign is matched first.
fn check_orthonormal_quaternion(m: &Matrix3<f64>) -> Result<(), TestCaseError> {
    let q = orthonormal_quaternion(m);
    let r = nalgebra::UnitQuaternion::from_matrix(m);
    let d = (q.coords - r.coords)
        .amax()
        .min((q.coords + r.coords).amax());
    // Both round: nalgebra's iteration stops within its own tolerance, the closed form
    // within a few ulp; 16 ulp of 1 (3.6e-15) bounds their difference on any CPU.
    prop_assert!(d < 16.0 * f64::EPSILON, "{d:e} for {m}");
    prop_assert!((q.norm() - 1.0).abs() < 1e-15);
    prop_assert!((q.to_rotation_matrix().matrix() - m).amax() < 2e-15);
    Ok(())
}

proptest! {
    #[test]
    fn orthonormal_quaternion_is_the_iterative_one(a in angles()) {
        check_orthonormal_quaternion(&Convention::Rpy.to_matrix(a))?;
    }

    /// Half turns and their neighbourhood (trace near -1), where the quaternion comes
    /// from a diagonal entry instead of the trace.
    #[test]
    fn orthonormal_quaternion_near_half_turns(
        axis in [-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0],
        off in -1e-6f64..1e-6,
    ) {
        let axis = Vector3::from(axis);
        prop_assume!(axis.norm() > 0.1);
        let angle = std::f64::consts::PI - off.abs();
        check_orthonormal_quaternion(&from_axis_angle(&axis, angle).unwrap())?;
    }
}

#[test]
fn orthonormal_quaternion_of_exact_frames() {
    let half = std::f64::consts::PI;
    for m in [
        Matrix3::identity(),
        rx(half),
        ry(half),
        rz(half),
        rz(half / 2.0) * rx(-half / 2.0),
    ] {
        check_orthonormal_quaternion(&m).unwrap();
    }
}

#[test]
fn bad_quaternion_and_axis_are_errors() {
    assert!(from_quaternion_wxyz([0.0; 4]).is_err());
    assert!(from_quaternion_wxyz([f64::NAN, 0.0, 0.0, 1.0]).is_err());
    assert!(from_axis_angle(&Vector3::zeros(), 1.0).is_err());
}

#[test]
fn rotation_vector_is_accurate_near_half_turn() {
    // Found by the round-trip proptest: the acos / vee formula lost digits here (a
    // 4e-13 matrix error for a rotation of 3.14 rad).
    let m =
        Convention::Rpy.to_matrix([-0.3721998244087995, 1.6940759419981726, 2.7215548861255954]);
    let v = Convention::RotationVector.from_matrix(&m);
    assert!((Convention::RotationVector.to_matrix(v) - m).amax() < 1e-15);
    use std::f64::consts::PI;
    for angle in [
        PI - 1e-9,
        PI - 1e-5,
        PI - 0.3,
        PI,
        2.0 * PI / 3.0,
        1e-9,
        0.0,
    ] {
        let axis = nalgebra::Vector3::new(0.3, -0.5, 0.8).normalize();
        let r = pkm::rotation::from_axis_angle(&axis, angle).unwrap();
        let (n, a) = pkm::rotation::axis_angle(&r);
        assert!((a - angle).abs() < 1e-15, "{angle}: {a}");
        if angle > 0.0 {
            assert!((n - axis).amax() < 1e-12, "{angle}: {n:?}");
        }
    }
}

/// The written-out angular velocity and acceleration of A, B, C (sines from pkm's
/// kernel) equal the products `Rz(C) Ry(B) e_x`, `e_z x c` they come from (the former
/// code, libm's sines) within 1e-15 and 1e-14, and the velocity is `vee(R' R^T)` of the
/// rotation by central differences. Held angles give exact zeros.
#[test]
fn rpy_angular_motion_equals_the_matrix_products_and_differences() {
    use nalgebra::{Matrix3, Vector3};
    use pkm::rotation::{rpy_angular_motion, rpy_matrix, ry, rz};
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(8);
    for _ in 0..10_000 {
        let a = [
            rng.random_range(-3.0..3.0),
            rng.random_range(-1.5..1.5),
            rng.random_range(-3.0..3.0),
        ];
        let ad = Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0));
        let add = Vector3::from_fn(|_, _| rng.random_range(-5.0..5.0));
        let (w, al) = rpy_angular_motion(a, &ad, &add);
        // The products, as the former code formed them.
        let (ex, ey, ez) = (Vector3::x(), Vector3::y(), Vector3::z());
        let c0 = rz(a[2]) * ry(a[1]) * ex;
        let c1 = rz(a[2]) * ey;
        let e = Matrix3::from_columns(&[c0, c1, ez]);
        let dc0 = ez.cross(&c0) * ad[2] + rz(a[2]) * (ey.cross(&(ry(a[1]) * ex)) * ad[1]);
        let dc1 = ez.cross(&c1) * ad[2];
        let edot = Matrix3::from_columns(&[dc0, dc1, Vector3::zeros()]);
        assert!((w - e * ad).amax() <= 1e-15 * (1.0 + ad.amax()), "{a:?}");
        assert!(
            (al - (e * add + edot * ad)).amax() <= 1e-14 * (1.0 + add.amax() + ad.amax().powi(2)),
            "{a:?}"
        );
        // w = vee(R' R^T), R' by central differences along the rates.
        let h = 1e-6;
        let at = |t: f64| rpy_matrix(a[0] + ad[0] * t, a[1] + ad[1] * t, a[2] + ad[2] * t);
        let rd = (at(h) - at(-h)) / (2.0 * h);
        let s = rd * at(0.0).transpose();
        let wn = Vector3::new(s[(2, 1)], s[(0, 2)], s[(1, 0)]);
        assert!(
            (w - wn).amax() <= 1e-7 * (1.0 + ad.amax()),
            "{a:?}: {w} vs {wn}"
        );
        let z = Vector3::zeros();
        let (w0, al0) = rpy_angular_motion(a, &z, &z);
        assert!(
            w0.iter().chain(al0.iter()).all(|v| v.to_bits() == 0),
            "{a:?}"
        );
    }
}

/// `whole_turns` is `(d / 2 pi).round()` bit for bit: over random differences of many
/// sizes, the half-turn boundary and its neighbours, signed zeros, subnormals,
/// infinities and NaN.
#[test]
fn whole_turns_is_the_rounded_turns_bit_for_bit() {
    use pkm::rotation::whole_turns;
    use rand::{Rng, SeedableRng};
    use std::f64::consts::{PI, TAU};
    let plain = |d: f64| (d / TAU).round();
    let mut cases = vec![
        0.0,
        -0.0,
        f64::MIN_POSITIVE / 4.0,
        -f64::MIN_POSITIVE / 4.0,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        f64::MAX,
        -f64::MAX,
    ];
    for b in [PI, 3.0 * PI, 5.0 * PI, 1e6 * PI] {
        for d in [b, -b] {
            let mut x = d;
            let mut y = d;
            for _ in 0..8 {
                cases.extend([x, y]);
                x = f64::from_bits(x.to_bits() + 1);
                y = f64::from_bits(y.to_bits() - 1);
            }
        }
    }
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    for scale in [1e-9, 1.0, PI, 10.0, 1e3, 1e9] {
        cases.extend((0..20_000).map(|_| rng.random_range(-scale..scale)));
    }
    let mut turned = 0;
    for d in cases {
        assert_eq!(whole_turns(d).to_bits(), plain(d).to_bits(), "d = {d:e}");
        turned += usize::from(plain(d).abs() >= 1.0);
    }
    // Not vacuous: both branches taken.
    assert!(turned > 10_000, "{turned}");
}
