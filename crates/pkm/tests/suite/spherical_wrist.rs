//! Closed-form inverse kinematics of spherical-wrist robots (`pkm report` on
//! the KR 30 within 2 s) and of robots with three parallel axes (the Universal Robots' geometry,
//! `serial/parallel_axes.rs`), checked against forward kinematics and against the
//! numeric solver.

use super::serial_arm::arm;
use nalgebra::Vector6;
use pkm::mechanism::Mechanism;
use pkm::serial::arm::SerialArm;
use rand::{Rng, SeedableRng};
use std::f64::consts::{PI, TAU};

/// Spherical wrists (the KR 30, the PUMA 560) and parallel axes 2, 3, 4 (a UR5 from its
/// published DH table, and the UR5-like URDF whose joint 2 turns about -Y).
const WRISTS: [&str; 4] = [
    "machines/kr30-dh.toml",
    "robots/puma560-dh.toml",
    "../tests/fixtures/ur5-dh.toml",
    "robots/ur5-like.urdf",
];

/// Joint values uniform over each joint's range (clipped to one turn).
fn random_joints(a: &SerialArm, rng: &mut impl Rng) -> Vector6<f64> {
    Vector6::from_fn(|i, _| {
        let r = a.info().actuators()[i].range;
        rng.random_range(r.min.max(-PI)..=r.max.min(PI))
    })
}

/// Equal modulo whole turns, to `tol` rad.
fn same_posture(p: &Vector6<f64>, q: &Vector6<f64>, tol: f64) -> bool {
    (0..6).all(|i| {
        let d = (p[i] - q[i]).rem_euclid(TAU);
        d.min(TAU - d) < tol
    })
}

/// The tool poses of `x` and of joints `q` as a rigid motion: (mm, rad).
fn pose_gap(a: &SerialArm, x: &Vector6<f64>, q: &Vector6<f64>) -> (f64, f64) {
    let t1 = a.tool_pose(x).unwrap();
    let t2 = a.tool_pose(&a.coords_of_joints(q)).unwrap();
    (
        (t1.translation.vector - t2.translation.vector).norm(),
        t1.rotation.angle_to(&t2.rotation),
    )
}

#[test]
fn the_closed_form_applies_to_spherical_wrists_and_parallel_axes() {
    for f in WRISTS {
        assert!(arm(f).closed_form_inverse(), "{f}");
    }
    // The UR5 with axis 6 at 60 deg to axis 5 instead of 90 (the axes still meet:
    // still the parallel-axes form), and with axis 6 moved 20 mm off axis 5 (a5 = 20:
    // neither form, Newton).
    let text = std::fs::read_to_string(format!(
        "{}/../../tests/fixtures/ur5-dh.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let load = |t: &str| {
        let m = pkm::Machine::from_toml_str(t, "ur5-variant.toml").unwrap();
        let pkm::machine::Model::Serial(s) = m.model else {
            panic!()
        };
        let pkm::serial::mechanism::SerialAny::Arm(a) = s.mechanism else {
            panic!()
        };
        a
    };
    let tilted = text.replacen("alpha = -90.0", "alpha = -60.0", 1);
    assert_ne!(tilted, text);
    assert!(load(&tilted).closed_form_inverse());
    let offset = text.replacen("a = 0.0\nalpha = -90.0", "a = 20.0\nalpha = -90.0", 1);
    assert_ne!(offset, text);
    assert!(!load(&offset).closed_form_inverse());
}

/// Forward kinematics of random joints over the whole ranges: every posture the
/// closed form finds reaches the pose to 1e-9 mm / rad, one of them is the joints the
/// pose came from (to 1e-8 rad), and none is missing: Newton from random starts lands
/// only on postures of the set.
#[test]
fn every_posture_is_found_and_reaches_the_pose() {
    for f in WRISTS {
        let a = arm(f);
        let mut rng = rand::rngs::StdRng::seed_from_u64(19);
        let mut counts = [0usize; 9];
        for k in 0..2000 {
            let q = random_joints(&a, &mut rng);
            let x = a.coords_of_joints(&q);
            let sols = a.inverse_solutions(&x, 1);
            counts[sols.len()] += 1;
            assert!(
                sols.iter().any(|s| same_posture(s, &q, 1e-8)),
                "{f}: {q:?} not among {} solutions",
                sols.len()
            );
            for s in &sols {
                let (dp, dr) = pose_gap(&a, &x, s);
                assert!(dp < 1e-9 && dr < 1e-9, "{f}: {s:?}: {dp:e} mm {dr:e} rad");
            }
            let (_, j) = a.pose_and_jacobian(&q);
            if k % 10 != 0 || j.singular_values().min() < 1e-3 {
                continue;
            }
            for _ in 0..20 {
                let start = random_joints(&a, &mut rng);
                if let Ok(n) = a.inverse_numeric_from(&x, &start) {
                    assert!(
                        sols.iter().any(|s| same_posture(s, &n, 1e-7)),
                        "{f}: Newton found {n:?}, not among {sols:?}"
                    );
                }
            }
        }
        // Generic poses of a spherical wrist have four postures (shoulder on one
        // side, elbow, wrist flip) or eight; a UR's an even number up to eight (each
        // shoulder and wrist flip with its two elbows or none), mostly eight.
        if f.contains("ur5") {
            let odd: usize = counts.iter().skip(1).step_by(2).sum();
            assert!(
                odd == 0 && counts[0] == 0 && counts[8] > 1400,
                "{f}: solutions per pose {counts:?}"
            );
        } else {
            assert!(
                counts[4] + counts[8] > 1900,
                "{f}: solutions per pose {counts:?}"
            );
        }
    }
}

/// `inverse_from` returns the posture nearest its start, so a start close to the
/// joints a pose came from gives those joints back.
#[test]
fn inverse_from_returns_the_posture_nearest_the_start() {
    for f in WRISTS {
        let a = arm(f);
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        for _ in 0..1000 {
            let q = random_joints(&a, &mut rng);
            let x = a.coords_of_joints(&q);
            let start = random_joints(&a, &mut rng);
            let got = a.inverse_from(&x, &start).unwrap();
            let (dp, dr) = pose_gap(&a, &x, &got);
            assert!(dp < 1e-9 && dr < 1e-9, "{f}: {dp:e} mm {dr:e} rad");
            // Every revolute joint within half a turn of the start ...
            assert!((got - start).amax() <= PI + 1e-12);
            // ... and no other posture nearer.
            let d = (got - start).norm();
            for s in a.inverse_solutions(&x, 1) {
                let s = s.zip_map(&start, |v, s0| v - TAU * ((v - s0) / TAU).round());
                assert!(d <= (s - start).norm() + 1e-9, "{f}: {got:?} vs {s:?}");
            }
            let near = q + Vector6::from_fn(|_, _| rng.random_range(-0.01..0.01));
            let back = a.inverse_from(&x, &near).unwrap();
            let (_, j) = a.pose_and_jacobian(&q);
            if j.singular_values().min() > 0.05 {
                assert!((back - q).amax() < 1e-9, "{f}: {back:?} vs {q:?}");
            }
        }
    }
}

/// The closed form against the numeric solver on poses spread over and beyond the
/// reach (random positions in the reach's bounding cube, random orientations): where
/// the closed form proves a pose out of reach, Newton from 33 starts finds nothing
/// either; where Newton finds a solution, so does the closed form.
#[test]
fn out_of_reach_agrees_with_the_numeric_solver() {
    for f in WRISTS {
        let a = arm(f);
        let b = a.position_bound(&a.info().home()).unwrap();
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let (mut out, mut both) = (0, 0);
        for _ in 0..300 {
            let x = Vector6::from_fn(|i, _| {
                if i < 3 {
                    // The inner 60 % of the cube: beyond it everything is refused at once.
                    let (lo, hi) = (b[i][0], b[i][1]);
                    let m = 0.5 * (lo + hi);
                    m + 0.6 * rng.random_range(lo - m..hi - m)
                } else {
                    rng.random_range(-PI..PI)
                }
            });
            let closed = a.inverse(&x);
            let numeric = a.inverse_numeric_from(&x, &a.home_joints());
            match (&closed, &numeric) {
                (Err(pkm::Error::NotAttainable { .. }), Err(_)) => out += 1,
                (Ok(q), _) => {
                    let (dp, dr) = pose_gap(&a, &x, q);
                    assert!(dp < 1e-9 && dr < 1e-9, "{f}: {dp:e} mm {dr:e} rad");
                    both += usize::from(numeric.is_ok());
                }
                _ => panic!("{f}: {x:?}: closed form {closed:?}, numeric {numeric:?}"),
            }
        }
        // The sample has both kinds.
        assert!(
            out > 30 && both > 30,
            "{f}: {out} out of reach, {both} reached"
        );
    }
}

#[test]
fn out_of_reach_names_the_distances() {
    // The KR 30 stretched beyond its elbow: 2500 mm ahead at the height of axis 2.
    let a = arm("machines/kr30-dh.toml");
    let x = Vector6::new(2500.0, 0.0, 815.0, PI, 0.0, 0.0);
    match a.inverse(&x) {
        Err(pkm::Error::NotAttainable { reason }) => {
            let reason = reason.to_string();
            assert!(reason.contains("from axis 2, outside the"), "{reason}");
            assert!(reason.contains("the elbow spans"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    // A UR5 reaching 1000 mm ahead at the height of axis 2, tool down: axis 4 beyond
    // the elbow's two links (425 + 392.25 mm).
    let a = arm("../tests/fixtures/ur5-dh.toml");
    let x = Vector6::new(1000.0, 0.0, 89.159, PI, 0.0, 0.0);
    match a.inverse(&x) {
        Err(pkm::Error::NotAttainable { reason }) => {
            let reason = reason.to_string();
            assert!(reason.contains("axis 4 would be"), "{reason}");
            assert!(reason.contains("to 817.250 mm the elbow spans"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    // The PUMA's arm plane is 150.05 mm off axis 1: a wrist centre on the axis is out
    // of reach. Tool frame = wrist frame (no tool), so the wrist centre is the point.
    let a = arm("robots/puma560-dh.toml");
    let x = Vector6::new(0.0, 0.0, 900.0, 0.0, 0.0, 0.0);
    match a.inverse(&x) {
        Err(pkm::Error::NotAttainable { reason }) => {
            let reason = reason.to_string();
            assert!(reason.contains("0.000 mm from axis 1"), "{reason}");
            assert!(reason.contains("the 150.050 mm"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    // The numbers are kept as numbers (words only when shown).
    match a.inverse(&x) {
        Err(pkm::Error::NotAttainable {
            reason:
                pkm::Unattainable::ShoulderOffset {
                    distance, offset, ..
                },
        }) => {
            assert!(distance.abs() < 1e-9, "{distance}");
            assert!((offset - 150.05).abs() < 1e-9, "{offset}");
        }
        other => panic!("{other:?}"),
    }
}
