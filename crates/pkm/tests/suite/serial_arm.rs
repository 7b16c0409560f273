//! Six-joint robots as spatial mechanisms: tool-pose coordinates through numeric
//! inverse kinematics.

use nalgebra::{Matrix6, Vector6};
use pkm::machine::Model;
use pkm::mechanism::{Mechanism, PoseSpace};
use pkm::serial::arm::SerialArm;
use pkm::serial::mechanism::SerialAny;
use proptest::prelude::*;

pub(crate) fn arm(file: &str) -> SerialArm {
    let m = pkm::Machine::from_path(format!(
        "{}/../../examples/{file}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let Model::Serial(s) = m.model else { panic!() };
    let SerialAny::Arm(a) = s.mechanism else {
        panic!("{file}: expected tool-pose coordinates")
    };
    a
}

/// Joint values from unit-interval samples, inside a band of each joint's range that
/// keeps the KR 30 away from its wrist singularity (q5 near 0) and on one side of its
/// elbow singularity (arm stretched at q3 = -90 + atan(145 / 820) = -80 deg).
fn kr30_joints(u: &[f64; 6]) -> Vector6<f64> {
    kr30_band(u)
}

/// Whether the robot is clear of singular configurations at `q`: the smallest singular
/// value of the geometric Jacobian (mm or rad per rad) above 0.05. Close to one, two
/// inverse solutions are close together and Newton may return either.
fn regular(a: &SerialArm, q: &Vector6<f64>) -> bool {
    let (_, j) = a.pose_and_jacobian(q);
    j.singular_values().min() > 0.05
}

fn kr30_band(u: &[f64; 6]) -> Vector6<f64> {
    let d = std::f64::consts::PI / 180.0;
    let band = [
        (-150.0, 150.0),
        (-30.0, 90.0),
        (-65.0, 55.0),
        (-150.0, 150.0),
        (20.0, 110.0),
        (-150.0, 150.0),
    ];
    Vector6::from_fn(|i, _| (band[i].0 + u[i] * (band[i].1 - band[i].0)) * d)
}

#[test]
fn six_joint_files_take_tool_poses_and_five_axis_files_their_joints() {
    let a = arm("machines/kr30-dh.toml");
    assert_eq!(a.info().pose_space(), PoseSpace::Spatial);
    assert_eq!(
        a.info()
            .coordinates()
            .iter()
            .map(|c| c.name.as_str())
            .collect::<Vec<_>>(),
        ["X", "Y", "Z", "A", "B", "C"]
    );
    // Home: wrist centre at X = a1 + d4 = 1170, Z = d1 + a2 + a3 = 1810; wrist bent
    // 90 deg, so flange (170) and tool (100) hang straight down from it.
    let h = a.info().home();
    assert!((h[0] - 1170.0).abs() < 1e-9, "{h}");
    assert!(h[1].abs() < 1e-9, "{h}");
    assert!((h[2] - 1540.0).abs() < 1e-9, "{h}");
    let _ = arm("robots/ur5-like.urdf");
    let m = pkm::Machine::from_path(format!(
        "{}/../../examples/machines/mc300.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    // Its file asks for tool-centre-point coordinates (a 5-axis machine tool).
    assert_eq!(m.mechanism().pose_space(), PoseSpace::Tcp);
}

#[test]
fn pose_jacobian_and_forward_agree_with_the_chain() {
    let a = arm("machines/kr30-dh.toml");
    let q = kr30_joints(&[0.3, 0.6, 0.4, 0.7, 0.5, 0.2]);
    let x = a.forward(&q, &a.info().home()).unwrap().pose;
    let t = a.machine().pose(q.as_slice(), &[], &[]).unwrap();
    for r in 0..3 {
        assert!((x[r] - t[(r, 3)]).abs() < 1e-9);
    }
    let rot = pkm::rotation::rpy_matrix(x[3], x[4], x[5]);
    assert!((rot - t.fixed_view::<3, 3>(0, 0)).amax() < 1e-12);
}

#[test]
fn inverse_recovers_the_joints_from_a_nearby_start_and_the_pose_from_home() {
    let a = arm("machines/kr30-dh.toml");
    let mut worst_q: f64 = 0.0;
    let mut worst_p: f64 = 0.0;
    let mut rng = 12345u64;
    let mut next = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..500 {
        let u: [f64; 6] = std::array::from_fn(|_| next());
        let q = kr30_joints(&u);
        if !regular(&a, &q) {
            continue;
        }
        let x = a.coords_of_joints(&q);
        let start = q + Vector6::from_fn(|i, _| 0.05 * (u[(i + 1) % 6] - 0.5));
        let back = a.inverse_from(&x, &start).unwrap();
        worst_q = worst_q.max((back - q).amax());
        // From home Newton may land on another branch: the pose must still match.
        if let Ok(qh) = a.inverse(&x) {
            worst_p = worst_p.max((a.coords_of_joints(&qh) - x).amax());
        }
    }
    assert!(worst_q < 1e-9, "joints {worst_q}");
    assert!(worst_p < 1e-9, "pose {worst_p}");
}

#[test]
fn unreachable_pose_reports_the_residual() {
    let a = arm("machines/kr30-dh.toml");
    // Beyond any reach: refused at once, with the distances.
    let mut x = a.info().home();
    x[0] = 5000.0;
    // The bound: the sum of the tool chain's link translations (all joints revolute).
    let reach: f64 = a
        .machine()
        .tool
        .links
        .iter()
        .map(|l| l.translation.norm())
        .sum();
    match a.inverse(&x) {
        Err(pkm::Error::NotAttainable { reason }) => {
            let reason = reason.to_string();
            assert!(
                reason.contains(&format!("beyond the {reach:.3} mm")),
                "{reason}"
            )
        }
        other => panic!("{other:?}"),
    }
    // Within the bound but out of the arm's reach: the closed form proves it (the
    // elbow cannot span the distance); Newton alone fails, with its residual.
    x[0] = 2500.0;
    match a.inverse(&x) {
        Err(pkm::Error::NotAttainable { reason }) => {
            let reason = reason.to_string();
            assert!(reason.contains("the elbow spans"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
    match a.inverse_numeric_from(&x, &a.home_joints()) {
        Err(pkm::Error::NotConverged { residual, .. }) => assert!(residual > 100.0, "{residual}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn coordinate_jacobian_equals_finite_differences_of_the_inverse() {
    let a = arm("machines/kr30-dh.toml");
    for u in [
        [0.3, 0.6, 0.4, 0.7, 0.5, 0.2],
        [0.8, 0.2, 0.7, 0.1, 0.9, 0.6],
    ] {
        let x = a.coords_of_joints(&kr30_joints(&u));
        // The branch the mechanism's inverse (from home) picks.
        let q = a.inverse(&x).unwrap();
        let j = a.jacobian(&x).unwrap();
        let mut fd = Matrix6::zeros();
        for c in 0..6 {
            let h = if c < 3 { 1e-3 } else { 1e-6 };
            let mut xp = x;
            let mut xm = x;
            xp[c] += h;
            xm[c] -= h;
            let d =
                (a.inverse_from(&xp, &q).unwrap() - a.inverse_from(&xm, &q).unwrap()) / (2.0 * h);
            fd.set_column(c, &d);
        }
        let rel = (j - fd).amax() / j.amax();
        assert!(rel < 1e-6, "relative {rel}\n{j}\n{fd}");
    }
}

#[test]
fn condition_from_known_joints_equals_the_condition_of_the_pose() {
    let a = arm("machines/kr30-dh.toml");
    for u in [
        [0.3, 0.6, 0.4, 0.7, 0.5, 0.2],
        [0.8, 0.2, 0.7, 0.1, 0.9, 0.6],
    ] {
        let x = a.coords_of_joints(&kr30_joints(&u));
        let q = a.inverse(&x).unwrap();
        let (c1, c2) = (a.condition(&x).unwrap(), a.condition_at(&x, &q).unwrap());
        assert!((c1 - c2).abs() < 1e-9 * c1, "{c1} {c2}");
    }
}

#[test]
fn actuator_motion_equals_differences_along_a_path() {
    let a = arm("machines/kr30-dh.toml");
    let x0 = a.coords_of_joints(&kr30_joints(&[0.4, 0.5, 0.5, 0.6, 0.5, 0.4]));
    // A curved path with turning orientation: x(t) = x0 + v t + w t^2.
    let v = Vector6::new(120.0, -80.0, 50.0, 0.2, -0.1, 0.3);
    let w = Vector6::new(-300.0, 100.0, 200.0, 0.5, 0.4, -0.6);
    let path = |t: f64| x0 + v * t + w * (t * t);
    let t = 0.1;
    let m = a
        .actuator_motion(&path(t), &(v + w * (2.0 * t)), &(w * 2.0))
        .unwrap();
    let h = 1e-4;
    let qp = a.inverse_from(&path(t + h), &m.q).unwrap();
    let qm = a.inverse_from(&path(t - h), &m.q).unwrap();
    let qd = (qp - qm) / (2.0 * h);
    let qdd = (qp - m.q * 2.0 + qm) / (h * h);
    assert!((m.qd - qd).amax() < 1e-6 * m.qd.amax(), "{}\n{}", m.qd, qd);
    assert!(
        (m.qdd - qdd).amax() < 1e-4 * m.qdd.amax(),
        "{}\n{}",
        m.qdd,
        qdd
    );
}

#[test]
fn limits_name_the_joint_and_the_excess() {
    let a = arm("machines/kr30-dh.toml");
    // Joint A5's range is +-119 deg: drive it to 125 deg.
    let mut q = kr30_joints(&[0.5; 6]);
    q[4] = 125f64.to_radians();
    let x = a.coords_of_joints(&q);
    let mut out = Vec::new();
    a.check_limits(&x, &q, &mut out);
    assert_eq!(out.len(), 1, "{out:?}");
    assert!(out[0].limit.contains("A5"), "{}", out[0].limit);
    assert!((out[0].excess - 6.0).abs() < 1e-9, "{}", out[0].excess);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// IK after FK over the band of the workspace, from a start 0.1 rad away.
    #[test]
    fn round_trip_over_the_workspace(u in prop::array::uniform6(0.0f64..1.0),
                                     s in prop::array::uniform6(-0.05f64..0.05)) {
        let a = arm("machines/kr30-dh.toml");
        let q = kr30_joints(&u);
        prop_assume!(regular(&a, &q));
        let x = a.coords_of_joints(&q);
        let back = a.inverse_from(&x, &(q + Vector6::from(s))).unwrap();
        prop_assert!((back - q).amax() < 1e-9);
    }
}

#[test]
fn all_inverse_solutions_include_the_wrist_flip_and_reach_the_pose() {
    use std::f64::consts::PI;
    let a = arm("machines/kr30-dh.toml");
    let q = kr30_joints(&[0.3, 0.6, 0.4, 0.7, 0.5, 0.2]);
    let x = a.coords_of_joints(&q);
    let sols = a.inverse_solutions(&x, 64);
    // A spherical wrist and the shoulder/elbow choices: 8 postures in general.
    assert!((4..=16).contains(&sols.len()), "{}", sols.len());
    for s in &sols {
        assert!((a.coords_of_joints(s) - x).amax() < 1e-9);
    }
    let same = |p: &Vector6<f64>, r: &Vector6<f64>| {
        (0..6).all(|i| {
            let d = (p[i] - r[i]).rem_euclid(2.0 * PI);
            d.min(2.0 * PI - d) < 1e-7
        })
    };
    assert!(sols.iter().any(|s| same(s, &q)), "the original posture");
    // Wrist flip of a spherical wrist: (q4 + pi, -q5, q6 + pi).
    let mut flip = q;
    flip[3] += PI;
    flip[4] = -flip[4];
    flip[5] += PI;
    assert!(sols.iter().any(|s| same(s, &flip)), "the wrist flip");
    // Beyond reach: none.
    let mut far = x;
    far[0] = 5000.0;
    assert!(a.inverse_solutions(&far, 64).is_empty());
}

/// Inverse kinematics from home once gave up on 1 in 450 poses the UR5's
/// forward kinematics had just produced (Newton stalled from home and from the first
/// eight spread starts). Over 3 000 joint vectors drawn over each robot's whole ranges,
/// the inverse from home must reach every pose (the same joints or another posture,
/// checked as a rigid motion to 1e-9 mm / rad). The campaign
/// (`examples/roundtrip_campaign.rs`) runs 10^5 per robot.
#[test]
fn inverse_from_home_reaches_every_pose_forward_kinematics_produces() {
    use rand::{Rng, SeedableRng};
    use std::f64::consts::PI;
    for file in [
        "robots/ur5-like.urdf",
        "robots/puma560-dh.toml",
        "machines/kr30-dh.toml",
    ] {
        let a = arm(file);
        let mut rng = rand::rngs::StdRng::seed_from_u64(17);
        let mut failures = Vec::new();
        for _ in 0..3000 {
            let q = Vector6::from_fn(|i, _| {
                let r = a.info().actuators()[i].range;
                let (lo, hi) = (r.min.max(-PI), r.max.min(PI));
                rng.random_range(lo..=hi)
            });
            if let Err(e) = round_trip(&a, &q, file) {
                failures.push(e);
            }
        }
        assert!(
            failures.is_empty(),
            "{file}: {} failures, e.g. {}",
            failures.len(),
            failures[0]
        );
    }
}

/// A pose whose only solutions are singular configurations (the KR 30's wrist centre
/// on axis 1: smallest singular value of J 1e-5) stalled every damped Newton start at
/// 0.02 mm (found by the round-trip campaign, 1 in 500 000 FK-generated poses); the
/// truncated pseudo-inverse from the closest point reaches it.
#[test]
fn inverse_reaches_a_singular_configuration() {
    let a = arm("machines/kr30-dh.toml");
    let q = Vector6::new(
        1.1209721409892461,
        -0.3688472257921578,
        -1.0792446475413073,
        -0.1332969250769791,
        -0.91209323162465,
        -1.623582487936938,
    );
    let (_, j) = a.pose_and_jacobian(&q);
    assert!(j.singular_values().min() < 1e-4);
    let x = a.coords_of_joints(&q);
    let back = a.inverse(&x).unwrap();
    let (t1, t2) = (
        a.tool_pose(&x).unwrap(),
        a.tool_pose(&a.coords_of_joints(&back)).unwrap(),
    );
    assert!((t1.translation.vector - t2.translation.vector).norm() < 1e-9);
    assert!(t1.rotation.angle_to(&t2.rotation) < 1e-9);
}

/// A UR's wrist singularity (axis 6 along axes 2 to 4: q5 = 0 or pi, and within
/// rounding of them) leaves the parallel axes' turn to the position: the pose
/// forward kinematics gives there is reached, where 15 of 1 000 such poses of the
/// UR5 DH table were called out of reach ("axis 4 would be 1006.550 mm from axis 2"),
/// as was `pkm fk ur5-like.urdf --actuators=0,-90,0,-90,0,0`'s.
#[test]
fn inverse_reaches_every_pose_of_a_singular_ur_wrist() {
    use rand::{Rng, SeedableRng};
    use std::f64::consts::PI;
    let fixture = crate::common::fixture("ur5-dh.toml");
    let Model::Serial(s) = fixture.model else {
        panic!()
    };
    let SerialAny::Arm(dh) = s.mechanism else {
        panic!()
    };
    for (file, a) in [
        ("robots/ur5-like.urdf", arm("robots/ur5-like.urdf")),
        ("ur5-dh.toml", dh),
    ] {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut failures = Vec::new();
        let wrist = [
            0.0,
            PI,
            -PI,
            1e-13,
            -1e-12,
            1e-10,
            -1e-9,
            1e-8,
            -1e-7,
            3e-7,
            2e-6,
            PI - 1e-9,
        ];
        let mut cases = vec![Vector6::new(0.0, -PI / 2.0, 0.0, -PI / 2.0, 0.0, 0.0)];
        for k in 0..1000 {
            let mut q = Vector6::from_fn(|_, _| rng.random_range(-PI..=PI));
            q[4] = wrist[k % wrist.len()];
            cases.push(q);
        }
        for q in cases {
            if let Err(e) = round_trip(&a, &q, file) {
                failures.push(e);
            }
        }
        assert!(
            failures.is_empty(),
            "{file}: {} failures:\n{}",
            failures.len(),
            failures.join("\n")
        );
    }
}

/// Inverse kinematics of the pose at joints `q` of `a` (from `file`) from home: the
/// pose reached within 1e-9 mm and rad (a wrong answer panics), or why it failed.
fn round_trip(a: &SerialArm, q: &Vector6<f64>, file: &str) -> Result<(), String> {
    let x = a.coords_of_joints(q);
    let back = a.inverse(&x).map_err(|e| format!("{q:?}: {e}"))?;
    let t1 = a.tool_pose(&x).unwrap();
    let t2 = a.tool_pose(&a.coords_of_joints(&back)).unwrap();
    let dp = (t1.translation.vector - t2.translation.vector).norm();
    let dr = t1.rotation.angle_to(&t2.rotation);
    assert!(
        dp < 1e-9 && dr < 1e-9,
        "{file}: q {q:?} -> {back:?}: {dp:e} mm, {dr:e} rad"
    );
    Ok(())
}

/// A robot's condition number does not depend on its size: the KR 30 scaled by 1e-4
/// (a 0.2 mm arm) has the full-size one's at every pose, where a characteristic
/// length clamped to 1 mm gave 39.3 instead of 8.05.
#[test]
fn a_robots_condition_does_not_depend_on_its_size() {
    use pkm::analysis::kinematics::inverse;
    let k = 1e-4;
    let full = crate::common::example("kr30-dh.toml");
    let small = crate::common::scaled_example("kr30-dh.toml", k, &["a", "d", "translation"]);
    for q in [
        [0.0, 0.0, 0.0, 0.0, 90.0, 0.0],
        [10.0, 20.0, -30.0, 40.0, 50.0, 60.0],
    ] {
        let q: Vec<f64> = q.iter().map(|v: &f64| v.to_radians()).collect();
        let cond = |m: &pkm::Machine| {
            let f = pkm::analysis::kinematics::forward(m, &q, &m.mechanism().home()).unwrap();
            let s = inverse(m, &f.pose).unwrap();
            (f.condition.unwrap(), s.actuators)
        };
        let ((c, qa), (cs, qb)) = (cond(&full), cond(&small));
        assert!(
            qa.iter().zip(&qb).all(|(a, b)| (a - b).abs() < 1e-9),
            "{qa:?} vs {qb:?}"
        );
        assert!((c - cs).abs() < 1e-9 * c, "{c} vs {cs}");
    }
}
