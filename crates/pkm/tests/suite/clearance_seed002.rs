//! Joint clearances on seed 002's own machine (`hybrid-am-seed002.toml`): the paper's
//! example part, a hemisphere of radius 75 mm built with the nozzle normal to it,
//! struts of 350 mm, clearance 0.1 mm in every joint (the file's `[[clearance]]`).

use nalgebra::Vector3;
use pkm::analysis::clearance::{clearance, ClearanceRequest, SurfaceRequest};
use pkm::Machine;

use crate::common;

fn file() -> String {
    format!(
        "{}/../../examples/machines/hybrid-am-seed002.toml",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn machine() -> Machine {
    Machine::from_path(file()).unwrap()
}

/// The hemisphere's point at height `z` and azimuth `c` (deg), nozzle along the normal.
fn on_hemisphere(z: f64, c_deg: f64) -> Vec<f64> {
    let r = (75.0f64 * 75.0 - z * z).max(0.0).sqrt();
    let c = c_deg.to_radians();
    vec![r * c.cos(), r * c.sin(), z, 0.0, (z / 75.0).acos(), c]
}

fn normal(x: &[f64]) -> Vector3<f64> {
    Vector3::new(x[0], x[1], x[2]) / 75.0
}

fn along_normal(x: &[f64], diametral: Option<f64>) -> ClearanceRequest {
    ClearanceRequest {
        diametral,
        options: pkm::accuracy::clearance::ClearanceOptions {
            direction: Some(normal(x)),
            ..Default::default()
        },
        ..Default::default()
    }
}

#[test]
fn the_file_gives_every_joint_the_papers_clearance() {
    let m = machine();
    let r = clearance(
        &m,
        Some(&on_hemisphere(0.0, 0.0)),
        &along_normal(&on_hemisphere(0.0, 0.0), None),
    )
    .unwrap();
    assert_eq!(r.clearances.len(), 8);
    assert!(r.clearances.iter().all(|c| c.diametral == 0.1));
    let joints = m.passive_joints();
    let bodies: Vec<&str> = joints.iter().map(|j| j.body.as_str()).collect();
    assert_eq!(bodies.iter().filter(|b| **b == "carriage").count(), 4);
    assert_eq!(bodies.iter().filter(|b| **b == "platform").count(), 4);
}

#[test]
fn worst_joint_states_moved_by_hand_reproduce_the_bounds() {
    let m = machine();
    for x in [on_hemisphere(0.0, 0.0), on_hemisphere(40.0, 130.0)] {
        let r = clearance(&m, Some(&x), &along_normal(&x, None)).unwrap();
        let n = normal(&x);
        for (states, value) in [
            (&r.bounds.worst_joint_states.upper, r.bounds.upper),
            (&r.bounds.worst_joint_states.lower, r.bounds.lower),
        ] {
            assert_eq!(states.len(), 8);
            for s in states.iter() {
                let d = Vector3::from(s.displacement);
                assert!((d.norm() - 0.05).abs() < 1e-12, "{}: {}", s.joint, d.norm());
            }
            let moves: Vec<(&str, [f64; 3])> = states
                .iter()
                .map(|s| (s.joint.as_str(), s.displacement))
                .collect();
            let e = common::moved_by_hand(&file(), &x, &moves);
            assert!((n.dot(&e) - value).abs() < 1e-9, "{} vs {value}", n.dot(&e));
        }
        // A point joint on a strut only matters along the strut: the carriage and the
        // platform joint of one strut share its contribution.
        let c = &r.bounds.contributions;
        for (a, b) in [("C1", "P1"), ("C2", "P2"), ("C3", "P3"), ("C4", "P4")] {
            let v = |j: &str| c.iter().find(|k| k.joint == j).unwrap().first_order;
            assert!((v(a) - v(b)).abs() < 1e-9 * v(a), "{a} {b}");
        }
    }
}

#[test]
fn monte_carlo_stays_within_the_bounds_and_they_scale_with_the_clearance() {
    let m = machine();
    let x = on_hemisphere(20.0, -40.0);
    let mut req = along_normal(&x, Some(0.1));
    req.monte_carlo = Some(20_000);
    let r = clearance(&m, Some(&x), &req).unwrap();
    let mc = r.monte_carlo.unwrap();
    assert!(mc.max <= r.bounds.upper + 1e-12 && mc.min >= r.bounds.lower - 1e-12);
    assert!(mc.max > 0.3 * r.bounds.upper);
    let half = clearance(&m, Some(&x), &along_normal(&x, Some(0.05))).unwrap();
    assert!((r.bounds.upper / half.bounds.upper - 2.0).abs() < 0.04);
    assert!((r.bounds.lower / half.bounds.lower - 2.0).abs() < 0.04);
    let zero = clearance(&m, Some(&x), &along_normal(&x, Some(0.0))).unwrap();
    assert_eq!((zero.bounds.upper, zero.bounds.lower), (0.0, 0.0));
}

#[test]
fn figure_4_the_largest_deviation_is_at_the_equator() {
    // The paper: over the hemisphere the bounds are largest at z = 0. pkm's layout
    // (docs/seed-002.md): every height reachable, the largest at z = 0, the smallest
    // near z = 71 mm, and a second rise at the pole where the tilt B changes fastest
    // with z.
    let m = machine();
    let req = ClearanceRequest {
        tolerance: Some(0.05),
        surface: Some(SurfaceRequest {
            radius: 75.0,
            centre: Some([0.0, 0.0, 0.0]),
            azimuth: 0.0,
            heights: 76,
        }),
        ..Default::default()
    };
    let r = clearance(&m, None, &req).unwrap();
    let s = r.surface.as_ref().unwrap();
    assert_eq!(s.unreachable, 0);
    assert_eq!(s.worst_z, Some(0.0));
    let worst = |p: &pkm::accuracy::clearance::surface::SurfacePoint| {
        p.upper.unwrap().max(-p.lower.unwrap())
    };
    let w: Vec<f64> = s.points.iter().map(worst).collect();
    assert!(w[0] > 0.5 && w[0] < 0.56, "{}", w[0]);
    assert!(w.iter().all(|v| *v <= w[0]));
    let (imin, _) = w
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .unwrap();
    assert!((68..=73).contains(&imin), "{imin}");
    // The largest clearance that keeps the whole surface within 0.05 mm meets it there.
    let c = s.largest_clearance_mm.unwrap();
    assert!((c / (0.1 * 0.05 / w[0]) - 1.0).abs() < 0.05, "{c}");
}

#[test]
fn figure_5_the_bounds_at_the_equator_grow_with_the_clearance() {
    let m = machine();
    let x = on_hemisphere(0.0, 0.0);
    let mut req = along_normal(&x, None);
    req.series = vec![0.02, 0.05, 0.1, 0.2];
    let r = clearance(&m, Some(&x), &req).unwrap();
    let s = r.series;
    assert_eq!(s.len(), 4);
    for w in s.windows(2) {
        assert!(w[1].upper > w[0].upper && w[1].lower < w[0].lower);
    }
    // In proportion, within 2 % up to 0.2 mm.
    for p in &s {
        let k = p.clearance_mm / 0.02;
        assert!((p.upper / (k * s[0].upper) - 1.0).abs() < 0.02, "{p:?}");
    }
}

#[test]
fn the_largest_clearance_of_each_class_meets_the_tolerance_over_the_surface() {
    // Carriage joints 0.05 mm, platform joints 0.1 mm; tolerance 0.3 mm over the
    // hemisphere: each class's largest clearance, the other class as given, brings the
    // worst height to the tolerance, and with the class free of play the worst is
    // `others_alone_mm`.
    let text = std::fs::read_to_string(file()).unwrap();
    let with = |carriage: f64, platform: f64| {
        let t = text.replace(
            "[[clearance]]\njoints = [\"all\"]\ndiametral = 0.1              # the paper's example clearance",
            &format!(
                "[[clearance]]\njoints = [\"carriage\"]\ndiametral = {carriage}\n\n\
                 [[clearance]]\njoints = [\"platform\"]\ndiametral = {platform}"
            ),
        );
        assert_ne!(t, text);
        Machine::from_toml_str(&t, "classes.toml").unwrap()
    };
    let surface = Some(SurfaceRequest {
        radius: 75.0,
        centre: Some([0.0, 0.0, 0.0]),
        azimuth: 0.0,
        heights: 21,
    });
    let req = ClearanceRequest {
        tolerance: Some(0.3),
        surface,
        ..Default::default()
    };
    let r = clearance(&with(0.05, 0.1), None, &req).unwrap();
    assert_eq!(r.largest_per_class.len(), 2);
    let worst = |m: &Machine| {
        let plain = ClearanceRequest {
            surface,
            ..Default::default()
        };
        clearance(m, None, &plain)
            .unwrap()
            .surface
            .unwrap()
            .worst
            .unwrap()
    };
    for k in &r.largest_per_class {
        let (c, p) = match k.class.as_str() {
            "carriage" => ((k.largest_mm.unwrap(), 0.1), (0.0, 0.1)),
            "platform" => ((0.05, k.largest_mm.unwrap()), (0.05, 0.0)),
            other => panic!("{other}"),
        };
        assert_eq!(k.joints.len(), 4);
        assert!((worst(&with(c.0, c.1)) - 0.3).abs() < 1e-8, "{k:?}");
        assert!((worst(&with(p.0, p.1)) - k.others_alone_mm).abs() < 1e-12);
    }
    // A tolerance the other class alone exceeds has no answer, and says so.
    let tight = ClearanceRequest {
        tolerance: Some(0.05),
        surface,
        ..Default::default()
    };
    let r = clearance(&with(0.05, 0.1), None, &tight).unwrap();
    let p = r
        .largest_per_class
        .iter()
        .find(|k| k.class == "carriage")
        .unwrap();
    assert!(p.largest_scale.is_none() && p.others_alone_mm > 0.05);
}
