//! Seed 000, Table 1: the tripod's platform joints for a tilted tool pose.

use nalgebra::{Vector3, Vector6};
use pkm::machine::Model;
use pkm::{Machine, Mechanism};

fn seed000() -> Machine {
    Machine::from_path(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/machines/tripod-seed000.toml"
    ))
    .unwrap()
}

/// Table 1: A = (-20, 45.54, -286.25), a right-hand rotation of +15 deg about X (the paper
/// labels it "about Y"; its numbers rotate about X). The paper prints C_x = 70.00; the
/// right value is -70.00 (C lies on the side of F, x < 0): a sign typo. Its eq. 2 prints
/// sin(phi) with the same sign in both off-diagonal places, which is no rotation; a proper
/// rotation reproduces every other printed number.
#[test]
fn table1_platform_joints() {
    let m = seed000();
    let x = [-20.0, 45.54, -286.25, 15f64.to_radians(), 0.0, 0.0];
    let sk = m.mechanism().skeleton(&x).unwrap();
    let get = |n: &str| {
        let p = sk.points.iter().find(|p| p.name == n).unwrap();
        Vector3::from(p.position)
    };
    let expect = [
        ("C", Vector3::new(-70.00, -5.64, -206.79)),
        ("E", Vector3::new(-20.00, 78.02, -184.38)),
        ("D", Vector3::new(30.00, -5.64, -206.79)),
    ];
    for (n, e) in expect {
        let d = (get(n) - e).amax();
        assert!(d <= 0.02, "{n}: {:?} vs {:?} ({d} mm)", get(n), e);
    }
    // The paper's sign typo: +70.00 is far from the computed C.
    assert!((get("C").x - 70.0).abs() > 100.0);
    // The pose is within every limit (the paper validates it against CAD).
    let q = m.mechanism().inverse(&x).unwrap();
    assert!(m.mechanism().check_limits(&x, &q).unwrap().is_empty());
}

/// The paper's one-signed matrix of eq. 2 is not a rotation: it is not orthogonal and
/// does not reproduce Table 1, while the proper rotation does.
#[test]
fn table1_paper_matrix_is_not_a_rotation() {
    let phi = 15f64.to_radians();
    let (s, c) = phi.sin_cos();
    let paper = nalgebra::Matrix3::new(1.0, 0.0, 0.0, 0.0, c, s, 0.0, s, c);
    assert!((paper.transpose() * paper - nalgebra::Matrix3::identity()).amax() > 0.4);
    let r = 57.7350;
    let e1 = Vector3::new(0.0, r, 0.0);
    let b = Vector3::new(-20.0, 45.54 - 90.0 * s, -286.25 + 90.0 * c);
    // With the paper's matrix E would be at z = B_z + r sin(phi) as well, but the A1
    // offset (0, 0, -a) maps to (0, -a sin, -a cos) instead of (0, +a sin, -a cos), so B
    // computed by eq. 1 is inconsistent with it; the proper rotation is consistent:
    let rot = pkm::rotation::rx(phi);
    let a1 = Vector3::new(0.0, 0.0, -90.0);
    let a_from_b = b + rot * a1;
    assert!((a_from_b - Vector3::new(-20.0, 45.54, -286.25)).amax() < 1e-9);
    let a_paper = b + paper * a1;
    assert!((a_paper - Vector3::new(-20.0, 45.54, -286.25)).amax() > 40.0);
    assert!(((b + rot * e1) - Vector3::new(-20.0, 78.02, -184.38)).amax() < 0.02);
}

#[test]
fn strut_lengths_are_joint_distances() {
    let m = seed000();
    let Model::TranslationalTripod(t) = &m.model else {
        panic!()
    };
    let x = Vector6::new(-20.0, 45.54, -286.25, 15f64.to_radians(), 0.0, 0.0);
    let q: Vector3<f64> = t.inverse(&x).unwrap();
    // Hand construction from the printed joint coordinates (eq. 7).
    let f = Vector3::<f64>::new(-100.0, -57.74, 0.0);
    let c = Vector3::new(-70.0, -5.64, -206.79);
    assert!((q[0] - (c - f).norm()).abs() < 0.02);
}
