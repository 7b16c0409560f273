//! Homogeneous transforms and small-deviation transforms.

use nalgebra::{Matrix4, Vector3};
use pkm::pose::{pose_from_angles, pose_from_homogeneous, SmallDisplacement};
use pkm::Convention;

#[test]
fn homogeneous_round_trip_and_validation() {
    let p = pose_from_angles(
        Vector3::new(1.0, -2.0, 3.0),
        [0.1, 0.2, -0.3],
        Convention::Rpy,
    );
    let h = p.to_homogeneous();
    let back = pose_from_homogeneous(&h).unwrap();
    assert!((back.to_homogeneous() - h).amax() < 1e-14);
    let mut bad = h;
    bad[(0, 0)] += 0.01;
    assert!(pose_from_homogeneous(&bad).is_err());
    let mut bad = Matrix4::identity();
    bad[(3, 0)] = 1.0;
    assert!(pose_from_homogeneous(&bad).is_err());
    let mut mirror = Matrix4::identity();
    mirror[(2, 2)] = -1.0;
    assert!(pose_from_homogeneous(&mirror).is_err());
}

#[test]
fn variation_matrix_is_the_first_order_of_the_exact_transform() {
    // A (I + dA) agrees with A * exact(delta) to second order in the deviation.
    let a = pose_from_angles(
        Vector3::new(10.0, 20.0, 30.0),
        [0.3, -0.2, 0.9],
        Convention::Rpy,
    );
    for k in [1e-2, 1e-3, 1e-4] {
        let d = SmallDisplacement::new(
            Vector3::new(0.5, -0.2, 0.1) * k,
            Vector3::new(1.0, 2.0, -0.5) * k,
        );
        let exact = (a * d.to_pose()).to_homogeneous();
        let first = a.to_homogeneous() * d.first_order();
        let err = (exact - first).amax();
        assert!(err < 5.0 * k * k, "k={k}: {err}");
    }
    let d = SmallDisplacement::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.1, 0.2, 0.3));
    let v = d.variation_matrix();
    assert_eq!(v[(0, 1)], -0.3);
    assert_eq!(v[(1, 0)], 0.3);
    assert_eq!(v[(0, 2)], 0.2);
    assert_eq!(v[(2, 1)], 0.1);
    assert_eq!(v[(2, 3)], 3.0);
    assert_eq!(v[(3, 3)], 0.0);
}

#[test]
fn between_is_exact() {
    let a = pose_from_angles(
        Vector3::new(1.0, 2.0, 3.0),
        [0.3, 0.1, -0.2],
        Convention::Rpy,
    );
    let b = pose_from_angles(
        Vector3::new(1.5, 1.0, 3.2),
        [0.25, 0.2, -0.1],
        Convention::Zyz,
    );
    let d = SmallDisplacement::between(&a, &b);
    let b2 = a * d.to_pose();
    assert!((b2.to_homogeneous() - b.to_homogeneous()).amax() < 1e-12);
}
