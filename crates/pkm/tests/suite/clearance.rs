//! Joint clearances (seed 002) on the generic engine: bounds, worst states, Monte Carlo,
//! enumeration, the designer's question, checked against re-solving by hand.

use nalgebra::Vector3;
use pkm::accuracy::clearance::{ClearanceMethod, ClearanceOptions, JointType};
use pkm::analysis::clearance::{clearance, ClearanceReport, ClearanceRequest};
use pkm::{Error, Machine};

use crate::common;

fn example(name: &str) -> String {
    format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn hexapod() -> Machine {
    Machine::from_path(example("hexapod-seed001.toml")).unwrap()
}

/// Seed 001's hexapod at (0, 0, 550, 5 deg, 0, 0).
fn pose() -> Vec<f64> {
    vec![0.0, 0.0, 550.0, 5f64.to_radians(), 0.0, 0.0]
}

fn request(c: f64) -> ClearanceRequest {
    ClearanceRequest {
        diametral: Some(c),
        ..Default::default()
    }
}

fn run(m: &Machine, req: &ClearanceRequest) -> ClearanceReport {
    clearance(m, Some(&pose()), req).unwrap()
}

/// The tool point of seed 001's hexapod at [`pose`] after moving joints by hand
/// ([`common::moved_by_hand`]).
fn moved_by_hand(moves: &[(&str, [f64; 3])]) -> Vector3<f64> {
    common::moved_by_hand(&example("hexapod-seed001.toml"), &pose(), moves)
}

#[test]
fn zero_clearance_gives_zero_error() {
    let mut req = request(0.0);
    req.monte_carlo = Some(200);
    let r = run(&hexapod(), &req);
    assert_eq!(r.bounds.upper, 0.0);
    assert_eq!(r.bounds.lower, 0.0);
    assert_eq!(r.bounds.first_order_upper, 0.0);
    assert_eq!(r.bounds.deviation_3d.norm, 0.0);
    let mc = r.monte_carlo.unwrap();
    assert_eq!((mc.min, mc.max, mc.max_norm), (0.0, 0.0, 0.0));
}

#[test]
fn bounds_grow_in_proportion_to_small_clearances() {
    let m = hexapod();
    let a = run(&m, &request(0.01));
    let b = run(&m, &request(0.02));
    assert!(a.bounds.upper > 1e-4, "{}", a.bounds.upper);
    for (x, y) in [
        (a.bounds.upper, b.bounds.upper),
        (a.bounds.lower, b.bounds.lower),
        (a.bounds.deviation_3d.norm, b.bounds.deviation_3d.norm),
    ] {
        assert!((y / x - 2.0).abs() < 0.02 * 2.0, "{x} {y}");
    }
    // The exact value of the first-order states is the first-order bound to second
    // order: (c / L)^2 relative, far below 1e-3 here.
    assert!((a.bounds.upper - a.bounds.first_order_upper).abs() < 1e-3 * a.bounds.upper);
}

#[test]
fn no_monte_carlo_sample_lies_outside_the_bounds() {
    let m = hexapod();
    for direction in [None, Some(Vector3::new(1.0, 0.3, -0.2))] {
        let req = ClearanceRequest {
            diametral: Some(0.05),
            options: ClearanceOptions {
                direction,
                ..Default::default()
            },
            monte_carlo: Some(20_000),
            ..Default::default()
        };
        let r = run(&m, &req);
        let mc = r.monte_carlo.unwrap();
        assert_eq!(mc.samples, 20_000);
        assert!(
            mc.max <= r.bounds.upper + 1e-12,
            "{} > {}",
            mc.max,
            r.bounds.upper
        );
        assert!(
            mc.min >= r.bounds.lower - 1e-12,
            "{} < {}",
            mc.min,
            r.bounds.lower
        );
        assert!(mc.max_norm <= r.bounds.deviation_3d.first_order * (1.0 + 1e-3));
        // The samples fill a good part of the range (not a degenerate draw).
        assert!(
            mc.max > 0.3 * r.bounds.upper,
            "{} {}",
            mc.max,
            r.bounds.upper
        );
    }
}

#[test]
fn worst_joint_states_reapplied_by_hand_reproduce_upper() {
    let m = hexapod();
    let r = run(&m, &request(0.04));
    let n = Vector3::from(r.bounds.direction);
    for (states, value) in [
        (&r.bounds.worst_joint_states.upper, r.bounds.upper),
        (&r.bounds.worst_joint_states.lower, r.bounds.lower),
    ] {
        assert_eq!(states.len(), 12);
        for s in states.iter() {
            // Each joint at the edge of its ball (radius c/2).
            let d = Vector3::from(s.displacement);
            assert!((d.norm() - 0.02).abs() < 1e-12, "{}: {}", s.joint, d.norm());
        }
        let moves: Vec<(&str, [f64; 3])> = states
            .iter()
            .map(|s| (s.joint.as_str(), s.displacement))
            .collect();
        let e = moved_by_hand(&moves);
        assert!((n.dot(&e) - value).abs() < 1e-9, "{} vs {value}", n.dot(&e));
    }
}

#[test]
fn first_order_bound_of_one_joint_matches_moving_it_by_hand() {
    // One joint, A1, with a clearance: the first-order bound along the tool axis is
    // (c/2) |g|, g the tool point's sensitivity to A1 projected on the axis; by hand,
    // moving A1 by +-h along each axis gives g by differences of forward solutions.
    let m = Machine::from_toml_str(
        &format!(
            "{}\n[[clearance]]\njoints = [\"A1\"]\ndiametral = 0.03\n",
            std::fs::read_to_string(example("hexapod-seed001.toml")).unwrap()
        ),
        "one-joint",
    )
    .unwrap();
    let r = run(&m, &ClearanceRequest::default());
    let n = Vector3::from(r.bounds.direction);
    let h = 1e-3;
    let g = Vector3::from_fn(|k, _| {
        let mut d = [0.0; 3];
        d[k] = h;
        let plus = moved_by_hand(&[("A1", d)]);
        d[k] = -h;
        let minus = moved_by_hand(&[("A1", d)]);
        n.dot(&(plus - minus)) / (2.0 * h)
    });
    let by_hand = 0.015 * g.norm();
    assert!(
        (r.bounds.first_order_upper - by_hand).abs() < 1e-6 * by_hand,
        "{} vs {by_hand}",
        r.bounds.first_order_upper
    );
    assert_eq!(r.bounds.contributions.len(), 1);
    assert_eq!(r.bounds.worst_joint_states.upper[0].joint, "A1");
    // The worst state is A1 moved along g.
    let d = Vector3::from(r.bounds.worst_joint_states.upper[0].displacement);
    assert!((d.normalize() - g.normalize()).norm() < 1e-6);
}

#[test]
fn enumeration_agrees_with_the_first_order_bound_where_it_must() {
    let text = std::fs::read_to_string(example("hexapod-seed001.toml")).unwrap();
    let m = Machine::from_toml_str(
        &format!("{text}\n[[clearance]]\njoints = [\"B2\"]\ndiametral = 0.03\n"),
        "one-joint",
    )
    .unwrap();
    // Along the tool axis: enumeration visits +-c/2 along x, y, z only, so it cannot
    // exceed the first-order maximum (along g)...
    let fo = run(&m, &ClearanceRequest::default());
    let en = run(
        &m,
        &ClearanceRequest {
            options: ClearanceOptions {
                method: ClearanceMethod::Enumeration,
                ..Default::default()
            },
            ..Default::default()
        },
    );
    assert_eq!(en.bounds.solves, 1 + 6);
    assert!(en.bounds.upper <= fo.bounds.upper + 1e-12);
    assert!(en.bounds.upper >= fo.bounds.upper / 3f64.sqrt() - 1e-12);
    // ...and, one joint answering linearly, it finds exactly the best of its axis
    // extremes: (c/2) max_k |g_k| against the first-order (c/2) |g|, g along the
    // first-order worst displacement (for a strut's joint, the strut's direction).
    let g = Vector3::from(fo.bounds.worst_joint_states.upper[0].displacement).normalize();
    let expected = fo.bounds.upper * g.amax();
    // (To first order: the second-order terms are about (c/2) / L = 2e-5 relative.)
    assert!(
        (en.bounds.upper - expected).abs() < 1e-4 * expected,
        "{} vs {expected}",
        en.bounds.upper
    );
    let expected_low = fo.bounds.lower * g.amax();
    assert!(
        (en.bounds.lower - expected_low).abs() < 1e-4 * expected,
        "{} vs {expected_low}",
        en.bounds.lower
    );
}

#[test]
fn enumeration_of_many_joints_is_refused_with_its_cost() {
    let r = clearance(
        &hexapod(),
        Some(&pose()),
        &ClearanceRequest {
            diametral: Some(0.02),
            options: ClearanceOptions {
                method: ClearanceMethod::Enumeration,
                ..Default::default()
            },
            ..Default::default()
        },
    );
    let e = r.unwrap_err().to_string();
    assert!(e.contains("2176782336 combinations"), "{e}");
    assert!(e.contains("first-order"), "{e}");
}

#[test]
fn revolute_joints_move_in_a_disc_and_tilt_through_their_lever() {
    let text = std::fs::read_to_string(example("hexapod-seed001.toml")).unwrap();
    let file = |lever: f64| {
        format!(
            "{text}\n[[clearance]]\njoints = [\"base\"]\ntype = \"universal\"\ndiametral = 0.04\n\
             bearing_length = 20.0\naxis = [0.0, 0.0, 1.0]\nlever = {lever}\n\
             [[clearance]]\njoints = [\"platform\"]\ndiametral = 0.04\n"
        )
    };
    let m0 = Machine::from_toml_str(&file(0.0), "universal").unwrap();
    let m1 = Machine::from_toml_str(&file(30.0), "universal").unwrap();
    assert_eq!(m0.clearances.len(), 12);
    assert_eq!(m0.clearances[0].kind, JointType::Universal);
    let mut req = ClearanceRequest {
        monte_carlo: Some(5000),
        ..Default::default()
    };
    req.options.direction = Some(Vector3::new(1.0, 0.0, 0.0));
    let (r0, r1) = (run(&m0, &req), run(&m1, &req));
    // Base joints in discs normal to z: their worst displacement has no z part; with
    // lever 0 the tilt moves nothing.
    for s in &r0.bounds.worst_joint_states.upper[..6] {
        assert!(s.displacement[2].abs() < 1e-15);
        assert!((Vector3::from(s.displacement).norm() - 0.02).abs() < 1e-12);
    }
    // With a 30 mm lever the tilt atan(0.04 / 20) adds 30 sin(theta) = 0.06 mm.
    let theta = (0.04f64 / 20.0).atan();
    for s in &r1.bounds.worst_joint_states.upper[..6] {
        let d = Vector3::from(s.displacement);
        let planar = (d.x * d.x + d.y * d.y).sqrt();
        assert!(
            (planar - (0.02 + 30.0 * theta.sin())).abs() < 1e-9,
            "{planar}"
        );
        // The lever's end also drops by h (1 - cos theta), second order.
        assert!((d.z + 30.0 * (1.0 - theta.cos())).abs() < 1e-12, "{}", d.z);
    }
    assert!(r1.bounds.upper > r0.bounds.upper);
    for r in [&r0, &r1] {
        let mc = r.monte_carlo.as_ref().unwrap();
        assert!(mc.max <= r.bounds.upper + 1e-12 && mc.min >= r.bounds.lower - 1e-12);
    }
}

#[test]
fn the_largest_clearance_within_a_tolerance_meets_it() {
    let m = hexapod();
    let mut req = request(0.02);
    req.tolerance = Some(0.01);
    let r = run(&m, &req);
    let c = r.largest_clearance_mm.unwrap();
    let check = run(&m, &request(c));
    let worst = check.bounds.upper.max(-check.bounds.lower);
    assert!((worst - 0.01).abs() < 1e-8, "{worst}");
    assert!((r.largest_clearance_scale.unwrap() * 0.02 - c).abs() < 1e-15);
}

#[test]
fn machines_without_modelled_passive_joints_say_so() {
    let m = Machine::from_path(example("mc300.toml")).unwrap();
    match clearance(&m, None, &request(0.01)) {
        Err(Error::Unsupported {
            analysis, reason, ..
        }) => {
            assert_eq!(analysis, "joint clearances");
            assert!(reason.contains("serial chain"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    // A file giving clearances to such a machine names the entry.
    let text = std::fs::read_to_string(example("mc300.toml")).unwrap();
    let e = Machine::from_toml_str(
        &format!("{text}\n[[clearance]]\njoints = [\"all\"]\ndiametral = 0.01\n"),
        "mc300-clearance.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("mc300-clearance.toml") && e.contains("clearance"),
        "{e}"
    );
    assert!(e.contains("no passive joints"), "{e}");
}

#[test]
fn clearance_entries_are_checked_with_file_line_and_field() {
    let text = std::fs::read_to_string(example("hexapod-seed001.toml")).unwrap();
    let lines = text.lines().count();
    for (entry, field, words) in [
        (
            "joints = [\"A9\"]\ndiametral = 0.01",
            "joints",
            "unknown joint `A9`",
        ),
        (
            "joints = [\"A1\"]\ntype = \"revolute\"\ndiametral = 0.01",
            "axis",
            "needs its `axis`",
        ),
        (
            "joints = [\"A1\"]\ndiametral = -0.01",
            "diametral",
            "from 0 to 100 mm",
        ),
        // A gap of a kilometre was once taken (a range per kind of quantity).
        (
            "joints = [\"A1\"]\ndiametral = 1e5",
            "diametral",
            "from 0 to 100 mm",
        ),
        (
            "joints = [\"A1\"]\ntype = \"ball\"\ndiametral = 0.01",
            "type",
            "spherical, revolute or universal",
        ),
        (
            "joints = [\"A1\"]\ndiametral = 0.01\nbearing_length = 0.0",
            "bearing_length",
            "> 0",
        ),
    ] {
        let e = Machine::from_toml_str(&format!("{text}\n[[clearance]]\n{entry}\n"), "m.toml")
            .unwrap_err();
        match &e {
            Error::MachineFile {
                file,
                line,
                field: f,
                message,
                ..
            } => {
                assert_eq!(file, "m.toml");
                assert!(line.unwrap() > lines, "{e}");
                assert!(f.contains(field), "{f} {e}");
                assert!(message.contains(words), "{message}");
            }
            other => panic!("{other:?}"),
        }
    }
    // A joint given twice.
    let e = Machine::from_toml_str(
        &format!(
            "{text}\n[[clearance]]\njoints = [\"base\"]\ndiametral = 0.01\n\
             [[clearance]]\njoints = [\"A3\"]\ndiametral = 0.02\n"
        ),
        "m.toml",
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("`A3` has a clearance already"),
        "{e}"
    );
}

#[test]
fn a_joint_name_names_one_joint() {
    // A platform joint named like a base joint would make two parameters `A1.x` and an
    // ambiguous clearance: the file is refused at that joint.
    let text = std::fs::read_to_string(example("hexapod-seed001.toml")).unwrap();
    let clash = text
        .replace("B1 = [", "A1 = [")
        .replace("platform = \"B1\"", "platform = \"A1\"");
    let e = Machine::from_toml_str(&clash, "clash.toml").unwrap_err();
    match &e {
        Error::MachineFile {
            line,
            field,
            message,
            ..
        } => {
            assert!(field.contains("platform_joints.A1"), "{e}");
            assert!(message.contains("names a base joint too"), "{e}");
            // The line of the platform table's A1 (the second `A1 = [`).
            let lines: Vec<usize> = clash
                .lines()
                .enumerate()
                .filter(|(_, l)| l.starts_with("A1 = ["))
                .map(|(i, _)| i + 1)
                .collect();
            assert_eq!(*line, Some(lines[1]), "{e}");
        }
        other => panic!("{other:?}"),
    }
    // The centre-leg tripod's leg joint is `leg`; no file joint may take the name.
    let tri = std::fs::read_to_string(example("tripod-centre-leg.toml")).unwrap();
    let first = tri
        .lines()
        .skip_while(|l| !l.starts_with("[base_joints]"))
        .nth(1)
        .unwrap()
        .split('=')
        .next()
        .unwrap()
        .trim()
        .to_string();
    let renamed = tri
        .replace(&format!("{first} = ["), "leg = [")
        .replace(&format!("base = \"{first}\""), "base = \"leg\"");
    let e = Machine::from_toml_str(&renamed, "leg.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("reserved"), "{e}");
    // The example's passive joints: strut joints and the leg, each once, the leg's
    // centre its `leg.x, leg.y, leg.z` parameters.
    let m = Machine::from_path(example("tripod-centre-leg.toml")).unwrap();
    let j = m.passive_joints();
    assert_eq!(j.len(), 7);
    assert_eq!(j[6].name, "leg");
    let params = m.parameters();
    assert_eq!(
        j[6].centres[0].map(|k| params[k].name.clone()),
        ["leg.x", "leg.y", "leg.z"]
    );
}

#[test]
fn hemisphere_points_normals_and_tool_poses() {
    use pkm::accuracy::clearance::surface::{pose_on_surface, Hemisphere};
    let h = Hemisphere {
        radius: 75.0,
        centre: [10.0, -5.0, 400.0],
        azimuth: 0.5,
    };
    let (p0, n0) = h.at(0.0);
    assert!(
        (p0 - Vector3::new(
            10.0 + 75.0 * 0.5f64.cos(),
            -5.0 + 75.0 * 0.5f64.sin(),
            400.0
        ))
        .norm()
            < 1e-12
    );
    assert!((n0 - (p0 - Vector3::new(10.0, -5.0, 400.0)) / 75.0).norm() < 1e-15);
    let (p1, n1) = h.at(75.0);
    assert!(
        (p1 - Vector3::new(10.0, -5.0, 475.0)).norm() < 1e-12 && (n1 - Vector3::z()).norm() < 1e-15
    );
    for z in [0.0, 20.0, 60.0] {
        let (p, n) = h.at(z);
        assert!(((p - Vector3::new(10.0, -5.0, 400.0)).norm() - 75.0).abs() < 1e-12);
        // The home orientation turned so that its z (here the tool axis) is the normal.
        let home = pkm::Pose::from_parts(
            Vector3::new(0.0, 0.0, 500.0).into(),
            nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3),
        );
        let t = pose_on_surface(&home, &p, &n);
        assert!((t.rotation * Vector3::z() - n).norm() < 1e-12);
        assert!((t.translation.vector - p).norm() < 1e-12);
    }
}

#[test]
fn bounds_over_a_hemisphere_agree_with_each_pose_and_meet_the_tolerance() {
    let m = hexapod();
    let req = ClearanceRequest {
        diametral: Some(0.02),
        tolerance: Some(0.01),
        surface: Some(pkm::analysis::clearance::SurfaceRequest {
            radius: 75.0,
            centre: None,
            azimuth: 0.0,
            heights: 41,
        }),
        ..Default::default()
    };
    let r = clearance(&m, None, &req).unwrap();
    let sf = r.surface.as_ref().unwrap();
    assert_eq!(sf.points.len(), 41);
    // The pole is the home tool point, where the hexapod is: reachable.
    let pole = sf.points.last().unwrap();
    assert!(pole.upper.is_some(), "{pole:?}");
    // Seed 001's hexapod cannot tilt its tool 90 degrees: the equator is out of reach,
    // with the reason.
    let eq = &sf.points[0];
    assert!(eq.upper.is_none() && eq.unreachable.is_some());
    assert!(sf.unreachable > 0 && sf.unreachable < 41);
    // Each reachable row is the bound at that pose along the normal, computed alone.
    let dm = m.mechanism();
    let home = dm.tool_pose(&dm.home()).unwrap();
    for p in sf.points.iter().filter(|p| p.upper.is_some()).step_by(2) {
        let pose = pkm::accuracy::clearance::surface::pose_on_surface(
            &home,
            &Vector3::from(p.point),
            &Vector3::from(p.normal),
        );
        let x = dm.coords_from_pose(&pose, true).unwrap();
        let alone = clearance(
            &m,
            Some(&x),
            &ClearanceRequest {
                diametral: Some(0.02),
                options: ClearanceOptions {
                    direction: Some(Vector3::from(p.normal)),
                    ..Default::default()
                },
                ..Default::default()
            },
        )
        .unwrap();
        assert!((alone.bounds.upper - p.upper.unwrap()).abs() < 1e-12);
        assert!((alone.bounds.lower - p.lower.unwrap()).abs() < 1e-12);
    }
    // The largest clearance over the surface keeps every reachable height within the
    // tolerance, the worst one at it.
    let c = r.largest_clearance_mm.unwrap();
    assert_eq!(Some(c), sf.largest_clearance_mm);
    assert!(c <= r.largest_clearance_at_pose_mm.unwrap() + 1e-15);
    let mut check = req.clone();
    check.diametral = Some(c);
    check.tolerance = None;
    let again = clearance(&m, None, &check).unwrap();
    let worst = again.surface.unwrap().worst.unwrap();
    assert!((worst - 0.01).abs() < 1e-8, "{worst}");
}

#[test]
fn large_clearances_are_refined_beyond_first_order() {
    // Millimetre clearances on a hexapod: the first-order states, solved exactly, are
    // off the first-order bound by more than 1e-3; re-linearising at them must not lose
    // and the Monte Carlo must stay inside.
    let m = hexapod();
    let run_with = |refine_above: f64| {
        clearance(
            &m,
            Some(&pose()),
            &ClearanceRequest {
                diametral: Some(8.0),
                options: ClearanceOptions {
                    direction: Some(Vector3::new(0.3, 0.2, 1.0)),
                    refine_above,
                    ..Default::default()
                },
                monte_carlo: Some(5000),
                ..Default::default()
            },
        )
        .unwrap()
    };
    let plain = run_with(f64::INFINITY);
    let refined = run_with(0.0);
    assert!(!plain.bounds.refined && refined.bounds.refined);
    // (At 8 mm on this pose: 16.068 mm first-order states, 16.104 mm refined.)
    assert!(refined.bounds.upper > plain.bounds.upper + 1e-3);
    assert!(refined.bounds.lower <= plain.bounds.lower + 1e-12);
    assert!(refined.bounds.solves > plain.bounds.solves);
    let rel = (plain.bounds.upper - plain.bounds.first_order_upper).abs()
        / plain.bounds.first_order_upper;
    assert!(rel > 1e-3, "first order is still enough at 8 mm: {rel}");
    let mc = refined.monte_carlo.unwrap();
    assert!(mc.max <= refined.bounds.upper + 1e-9 && mc.min >= refined.bounds.lower - 1e-9);
    // The refined states are still inside their balls.
    for s in &refined.bounds.worst_joint_states.upper {
        assert!(Vector3::from(s.displacement).norm() <= 4.0 + 1e-12);
    }
}

#[test]
fn a_clearance_series_gives_each_clearance_its_bounds() {
    let m = hexapod();
    let series = vec![0.0, 0.01, 0.05, 0.1];
    let r = run(
        &m,
        &ClearanceRequest {
            series: series.clone(),
            ..Default::default()
        },
    );
    assert_eq!(r.series.len(), 4);
    // Without --clearance the series' first value stands for it.
    assert_eq!(r.clearances[0].diametral, 0.0);
    assert_eq!((r.series[0].upper, r.series[0].lower), (0.0, 0.0));
    for (p, c) in r.series.iter().zip(&series).skip(1) {
        let alone = run(&m, &request(*c));
        assert_eq!(p.clearance_mm, *c);
        assert_eq!((p.upper, p.lower), (alone.bounds.upper, alone.bounds.lower));
    }
    // Growing with the clearance (Fig. 5), about in proportion.
    assert!(r
        .series
        .windows(2)
        .all(|w| w[1].upper > w[0].upper && w[1].lower < w[0].lower));
    assert!((r.series[3].upper / r.series[1].upper - 10.0).abs() < 0.01);
}

#[test]
fn bounds_along_a_gcode_path_agree_with_each_pose_and_meet_the_tolerance() {
    use pkm::analysis::clearance_path::PathRequest;
    let m = hexapod();
    let program = "G21 G90\nG0 X0 Y0 Z550\nG1 X20 Y10 Z540 F1200\nG1 X-20 Y10 Z545\n";
    let path = |every| PathRequest {
        program: program.into(),
        from: None,
        feed: Default::default(),
        sampling: pkm::motion::Sampling::Rate(50.0),
        every,
    };
    let req = ClearanceRequest {
        diametral: Some(0.02),
        tolerance: Some(0.01),
        path: Some(path(1)),
        ..Default::default()
    };
    let r = clearance(&m, None, &req).unwrap();
    let p = r.path.as_ref().unwrap();
    assert_eq!(p.points.len() as u64, p.samples);
    assert!(p.samples > 50);
    // Along the tool axis at each sample: the bound computed alone at that pose.
    for pt in p.points.iter().step_by(17) {
        let alone = clearance(&m, Some(&pt.sample.x), &request(0.02)).unwrap();
        assert_eq!(
            (pt.upper, pt.lower),
            (alone.bounds.upper, alone.bounds.lower)
        );
        assert_eq!(pt.direction, alone.bounds.direction);
    }
    // The largest clearance along the path brings its worst sample to the tolerance.
    let c = r.largest_clearance_mm.unwrap();
    let mut check = req.clone();
    check.diametral = Some(c);
    check.tolerance = None;
    let again = clearance(&m, None, &check).unwrap();
    let pa = again.path.unwrap();
    let worst = pa.points[pa.worst.unwrap()]
        .upper
        .max(-pa.points[pa.worst.unwrap()].lower);
    assert!((worst - 0.01).abs() < 1e-8, "{worst}");
    // Every 10th sample, and the last.
    let mut sparse = req.clone();
    sparse.path = Some(path(10));
    sparse.tolerance = None;
    let s = clearance(&m, None, &sparse).unwrap().path.unwrap();
    assert_eq!(
        s.points.len() as u64,
        p.samples.div_ceil(10) + u64::from(!(p.samples - 1).is_multiple_of(10))
    );
    assert_eq!(
        s.points.last().unwrap().sample.t,
        p.points.last().unwrap().sample.t
    );
    // A program without motion, and a zero step, are refused.
    let mut bad = req.clone();
    bad.path = Some(PathRequest {
        program: "G21\n".into(),
        ..path(1)
    });
    assert!(clearance(&m, None, &bad)
        .unwrap_err()
        .to_string()
        .contains("no motion"));
    bad.path = Some(path(0));
    assert!(clearance(&m, None, &bad).is_err());
}
