//! The workspace engine against direct evaluation.

use nalgebra::Vector6;
use pkm::machine::Model;
use pkm::mechanism::abilities;
use pkm::workspace::{flat_index, map, reachable_tilt, GridAxis};
use pkm::{inverse_checked, Machine, Mechanism};

fn machine(name: &str) -> Machine {
    Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

#[test]
fn grid_points_agree_with_direct_evaluation() {
    let Model::TranslationalTripod(t) = machine("tripod-seed000.toml").model else {
        panic!()
    };
    let axes = [
        GridAxis {
            coordinate: 0,
            min: -100.0,
            max: 100.0,
            step: 20.0,
        },
        GridAxis {
            coordinate: 1,
            min: -100.0,
            max: 100.0,
            step: 25.0,
        },
        GridAxis {
            coordinate: 2,
            min: -360.0,
            max: -220.0,
            step: 35.0,
        },
    ];
    let wm = map(&t, &t.info().home(), &axes, &[], &|_| {}).unwrap();
    assert_eq!(wm.points.len(), 11 * 9 * 5);
    let mut reachable = 0;
    let mut every: std::collections::BTreeMap<String, usize> = Default::default();
    for i in 0..11 {
        for j in 0..9 {
            for k in 0..5 {
                let x = Vector6::new(
                    axes[0].value(i),
                    axes[1].value(j),
                    axes[2].value(k),
                    0.0,
                    0.0,
                    0.0,
                );
                let p = &wm.points[flat_index(&axes, &[i, j, k])];
                let direct = inverse_checked(&t, &x);
                assert_eq!(p.reachable, direct.is_ok(), "{x}");
                if let Err(pkm::Error::Unreachable { violations }) = direct {
                    assert_eq!(p.binding.as_deref(), Some(violations[0].limit.as_str()));
                    assert_eq!(p.status, pkm::workspace::PointStatus::Limits);
                    let mut names: Vec<&str> =
                        violations.iter().map(|v| v.limit.as_str()).collect();
                    names.dedup();
                    for n in names {
                        *every.entry(n.to_string()).or_default() += 1;
                    }
                } else {
                    reachable += 1;
                    assert!((p.condition - t.condition(&x).unwrap()).abs() < 1e-12);
                    assert_eq!(wm.coords(flat_index(&axes, &[i, j, k])), x.as_slice());
                }
            }
        }
    }
    let s = wm.summary_of(pkm::Mechanism::info(&t).coordinates());
    assert_eq!(s.reachable, reachable);
    // Every violated limit counted, not only the first: the tally equals a direct
    // count, and a point beyond several limits counts for each.
    let tally: std::collections::BTreeMap<String, usize> = s.violated.iter().cloned().collect();
    assert_eq!(tally, every);
    assert!(
        s.violated.iter().map(|b| b.1).sum::<usize>() > s.binding.iter().map(|b| b.1).sum(),
        "some points violate more than one limit: {:?}",
        s.violated
    );
    assert!(reachable > 0 && reachable < wm.points.len());
    assert_eq!(
        s.binding.iter().map(|b| b.1).sum::<usize>() + s.reachable,
        s.points
    );
    assert!((s.volume_mm3.unwrap() - reachable as f64 * 17500.0).abs() < 1e-6);
    assert_eq!(
        (s.measure_unit.as_str(), s.measure_name.as_str()),
        ("mm^3", "volume")
    );
}

/// A grid over a length and an angle (the P3RP head's z, theta)
/// has a measure in mm·deg, not a volume in mm^3.
#[test]
fn a_grid_over_a_length_and_an_angle_has_no_volume() {
    let m = pkm::Machine::from_path(format!(
        "{}/../../examples/machines/p3rp-seed004.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let dm = m.mechanism();
    let home = dm.home();
    let axes = pkm::workspace::default_grid(dm, &home, None, None).unwrap();
    let wm = pkm::analysis::workspace::grid(&m, &home, &axes, &[], &|_| {}).unwrap();
    let s = wm.summary_of(dm.coordinates());
    assert_eq!(s.measure_unit, "mm·deg");
    assert_eq!(s.measure_name, "measure");
    assert!(s.volume_mm3.is_none());
    // Cell = step_z (mm) times step_theta (deg).
    let cell = axes[0].step * axes[1].step.to_degrees();
    assert!((s.measure - s.reachable as f64 * cell).abs() < 1e-9 * s.measure.max(1.0));
}

#[test]
fn hexapod_conditioning_is_consistent() {
    let Model::Hexapod(h) = machine("hexapod-linuxcnc.toml").model else {
        panic!()
    };
    // The symmetric home pose is well conditioned; the condition number is that of the
    // twist Jacobian with rotations scaled by the characteristic length.
    let c = h.condition(&h.info().home()).unwrap();
    assert!(c > 1.0 && c < 3.0, "{c}");
    let (p, r) = pkm::legs::split_pose(&h.info().home());
    let sv = pkm::linalg::singular_values(&h.scaled_twist_jacobian(&p, &r));
    assert!((sv[0] / sv[5] - c).abs() < 1e-9 * c);
    // Orientation workspace at home: every returned tilt is reachable, a bit more is not.
    let az = [0.0, 1.0, 2.0, 3.0];
    let tilts = reachable_tilt(h.as_ref(), &h.info().home(), &az, 1.0, 1e-6).unwrap();
    for (a, t) in az.iter().zip(&tilts) {
        assert!(*t > 0.05 && *t < 1.0, "{t}");
        let ok = |tt: f64| {
            let axis =
                nalgebra::Unit::new_normalize(nalgebra::Vector3::new(-a.sin(), a.cos(), 0.0));
            let ang = pkm::Convention::Rpy
                .from_matrix(nalgebra::Rotation3::from_axis_angle(&axis, tt).matrix());
            let x = Vector6::new(
                h.info().home()[0],
                h.info().home()[1],
                h.info().home()[2],
                ang[0],
                ang[1],
                ang[2],
            );
            inverse_checked(h.as_ref(), &x).is_ok()
        };
        assert!(ok(t - 1e-5) && !ok(t + 1e-5));
    }
}

/// The condition number from the root-free QL equals the one from the QL with square
/// roots (the plain version) and nalgebra's SVD, over random poses of both example
/// hexapods, singular-ish ones included: within 1e-12 relative where the matrix
/// `J^T J` is conditioned below 1e4, and within the eigen-solvers' backward error
/// (`1e-14 kappa^2` relative) beyond.
#[test]
fn hexapod_condition_numbers_agree_with_the_plain_ql_and_an_svd() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(19);
    let mut seen = 0;
    for file in ["hexapod-linuxcnc.toml", "hexapod-seed001.toml"] {
        let Model::Hexapod(h) = machine(file).model else {
            panic!()
        };
        let mut worst: f64 = 0.0;
        for k in 0..20_000 {
            let spread = if k % 2 == 0 { 100.0 } else { 400.0 };
            let tilt = if k % 2 == 0 { 0.17 } else { 1.2 };
            let x = Vector6::new(
                h.info().home()[0] + rng.random_range(-spread..spread),
                h.info().home()[1] + rng.random_range(-spread..spread),
                h.info().home()[2] + rng.random_range(-spread..spread),
                rng.random_range(-tilt..tilt),
                rng.random_range(-tilt..tilt),
                rng.random_range(-tilt..tilt),
            );
            let c = h.condition(&x).unwrap();
            let (p, r) = pkm::legs::split_pose(&x);
            let j = h.scaled_twist_jacobian(&p, &r);
            let ev = pkm::linalg::symmetric_eigenvalues_ql(&(j.transpose() * j)).unwrap();
            let plain = (ev.max() / ev.min()).sqrt();
            let sv = j.singular_values();
            let svd = sv.max() / sv.min();
            if !(c.is_finite() && plain.is_finite()) || c > 1e6 {
                continue;
            }
            seen += 1;
            let tol = 1e-12f64.max(1e-14 * c * c);
            let rel = (c - plain).abs() / plain;
            worst = worst.max(rel / tol);
            assert!(rel <= tol, "{file} {x:?}: {c} vs {plain} ({rel:e})");
            assert!(
                (c - svd).abs() <= 10.0 * tol * svd,
                "{file} {x:?}: {c} vs SVD {svd}"
            );
        }
        eprintln!("{file}: worst difference {worst:.3} of the tolerance");
    }
    assert!(seen > 20_000, "{seen}");
}

/// A hexapod's map, whose condition numbers run eight poses across SIMD lanes a chunk
/// at a time, gives every point what it gives one pose at a time: with an orientation
/// set (the total orientation workspace of `--tilt 12`), a point is reachable when
/// every orientation is, and its condition is the largest of theirs, bit for bit; a
/// point beyond a limit names the first orientation's first violated limit.
/// `abilities::conditions` equals `condition` pose by pose, bit for bit.
#[test]
fn hexapod_map_conditions_equal_those_of_single_poses() {
    let Model::Hexapod(h) = machine("hexapod-linuxcnc.toml").model else {
        panic!()
    };
    let axes = [
        GridAxis {
            coordinate: 0,
            min: -300.0,
            max: 300.0,
            step: 50.0,
        },
        GridAxis {
            coordinate: 1,
            min: -300.0,
            max: 300.0,
            step: 60.0,
        },
        GridAxis {
            coordinate: 2,
            min: 300.0,
            max: 800.0,
            step: 50.0,
        },
    ];
    let tilts = pkm::workspace::tilt_orientations(12f64.to_radians());
    let wm = map(h.as_ref(), &h.info().home(), &axes, &tilts, &|_| {}).unwrap();
    let base = pkm::Convention::Rpy.to_matrix([
        h.info().home()[3],
        h.info().home()[4],
        h.info().home()[5],
    ]);
    let (mut reachable, mut beyond) = (0, 0);
    let mut xs = Vec::new();
    for (k, p) in wm.points.iter().enumerate() {
        let c = wm.coords(k);
        let mut worst: f64 = 0.0;
        let mut first = None;
        for o in &tilts {
            let a = pkm::Convention::Rpy.from_matrix(&(pkm::Convention::Rpy.to_matrix(*o) * base));
            let x = Vector6::new(c[0], c[1], c[2], a[0], a[1], a[2]);
            xs.push(x);
            match inverse_checked(h.as_ref(), &x) {
                Ok(_) => worst = worst.max(h.condition(&x).unwrap()),
                Err(e) => {
                    first = Some(e);
                    break;
                }
            }
        }
        match first {
            None => {
                reachable += 1;
                assert!(p.reachable, "{c:?}");
                assert_eq!(p.condition.to_bits(), worst.to_bits(), "{c:?}");
            }
            Some(pkm::Error::Unreachable { violations }) => {
                beyond += 1;
                assert!(!p.reachable);
                assert_eq!(p.binding.as_deref(), Some(violations[0].limit.as_str()));
            }
            Some(e) => panic!("{c:?}: {e}"),
        }
    }
    assert!(reachable > 30 && beyond > 300, "{reachable} {beyond}");
    // Any count, not a multiple of eight.
    xs.truncate(8 * 40 + 5);
    let mut out = vec![0.0; xs.len()];
    abilities::conditions(&*h, &xs, &[], &mut out);
    for (x, c) in xs.iter().zip(&out) {
        assert_eq!(c.to_bits(), h.condition(x).unwrap().to_bits(), "{x}");
    }
}

#[test]
fn total_orientation_workspace_is_smaller() {
    let Model::Hexapod(h) = machine("hexapod-linuxcnc.toml").model else {
        panic!()
    };
    let axes = [
        GridAxis {
            coordinate: 0,
            min: -300.0,
            max: 300.0,
            step: 30.0,
        },
        GridAxis {
            coordinate: 1,
            min: -300.0,
            max: 300.0,
            step: 30.0,
        },
        GridAxis {
            coordinate: 2,
            min: 350.0,
            max: 750.0,
            step: 40.0,
        },
    ];
    let plain = map(h.as_ref(), &h.info().home(), &axes, &[], &|_| {}).unwrap();
    let tilt = 10f64.to_radians();
    let set: Vec<[f64; 3]> = (0..8)
        .map(|k| {
            let az = k as f64 * std::f64::consts::FRAC_PI_4;
            let axis =
                nalgebra::Unit::new_normalize(nalgebra::Vector3::new(-az.sin(), az.cos(), 0.0));
            pkm::Convention::Rpy
                .from_matrix(nalgebra::Rotation3::from_axis_angle(&axis, tilt).matrix())
        })
        .collect();
    let total = map(h.as_ref(), &h.info().home(), &axes, &set, &|_| {}).unwrap();
    let n = |w: &pkm::workspace::WorkspaceMap| w.points.iter().filter(|p| p.reachable).count();
    assert!(
        n(&total) < n(&plain) && n(&total) > 0,
        "{} vs {}",
        n(&total),
        n(&plain)
    );
    for (a, b) in total.points.iter().zip(&plain.points) {
        assert!(!a.reachable || b.reachable);
    }
}

fn axis(coordinate: usize, min: f64, max: f64, step: f64) -> GridAxis {
    GridAxis {
        coordinate,
        min,
        max,
        step,
    }
}

#[test]
fn atlas_rates_are_the_worst_case_over_the_capacity_box() {
    use nalgebra::Vector2;
    use pkm::workspace::atlas::{atlas, Capacity};
    let Model::P3rpHead(h) = machine("p3rp-seed004.toml").model else {
        panic!()
    };
    let cap = Capacity {
        velocity: Vector2::new(150.0, 1.0),
        acceleration: Vector2::new(9806.65, 30.0),
    };
    let axes = [axis(0, 200.0, 520.0, 40.0), axis(1, 0.0, 1.57, 0.157)];
    let a = atlas(h.as_ref(), &h.info().home(), &axes, &cap, &|_| {}).unwrap();
    assert_eq!(a.points.len(), 9 * 11);
    for (k, p) in a.points.iter().enumerate() {
        let x = Vector2::new(axes[0].value(k / 11), axes[1].value(k % 11));
        // Brute force over the vertices of both boxes (the worst case is at one).
        let (mut v, mut acc) = (Vector2::<f64>::zeros(), Vector2::<f64>::zeros());
        for s in 0..16 {
            let sg = |b: u32| if s >> b & 1 == 1 { -1.0 } else { 1.0 };
            let xd = Vector2::new(sg(0) * 150.0, sg(1) * 1.0);
            let xdd = Vector2::new(sg(2) * 9806.65, sg(3) * 30.0);
            let m = h.actuator_motion(&x, &xd, &xdd).unwrap();
            v = v.sup(&m.qd.abs());
            acc = acc.sup(&m.qdd.abs());
        }
        assert!((p.velocity - v).amax() < 1e-9, "{x:?}");
        assert!((p.acceleration - acc).amax() < 1e-9, "{x:?}");
        assert!((p.q - h.inverse(&x).unwrap()).amax() < 1e-12);
        // Slider U follows z: its needs are the z capacity itself.
        assert!((p.velocity[0] - 150.0).abs() < 1e-12);
        assert!((p.acceleration[0] - 9806.65).abs() < 1e-9);
        let mut viol = Vec::new();
        h.check_limits(&x, &p.q, &mut viol);
        assert_eq!(p.reachable, viol.is_empty());
    }
}

#[test]
fn forward_map_poses_close_the_loop() {
    use nalgebra::{Vector2, Vector3};
    use pkm::workspace::forward::forward_map;
    let Model::P3rpHead(h) = machine("p3rp-seed004.toml").model else {
        panic!()
    };
    let axes = [axis(0, 190.0, 530.0, 10.0), axis(1, 480.0, 840.0, 10.0)];
    let f = forward_map(
        h.as_ref(),
        &Vector2::zeros(),
        &axes,
        &h.info().home(),
        &|_| {},
    )
    .unwrap();
    let mut reachable = 0;
    for (k, p) in f.points.iter().enumerate() {
        let q = Vector2::new(axes[0].value(k / 37), axes[1].value(k % 37));
        match &p.pose {
            Some(x) => {
                assert!((h.inverse(x).unwrap() - q).amax() < 1e-9);
                let mut v = Vec::new();
                h.check_limits(x, &q, &mut v);
                assert_eq!(p.reachable, v.is_empty());
                reachable += p.reachable as usize;
            }
            None => assert!(!p.reachable && p.binding.is_some()),
        }
    }
    // The reachable slider region is the band V - U in [g(0), g(1.57)] inside the
    // strokes: a substantial part of the grid, not all of it.
    assert!(
        reachable > 200 && reachable < f.points.len() - 200,
        "{reachable}"
    );
    // Generic: a spatial tripod over its three strut lengths.
    let Model::TranslationalTripod(t) = machine("tripod-seed000.toml").model else {
        panic!()
    };
    let q0 = t.inverse(&t.info().home()).unwrap();
    let axes: Vec<GridAxis> = (0..3)
        .map(|i| axis(i, q0[i] - 20.0, q0[i] + 20.0, 10.0))
        .collect();
    let f = forward_map(&t, &Vector3::zeros(), &axes, &t.info().home(), &|_| {}).unwrap();
    assert_eq!(f.points.len(), 125);
    for (k, p) in f.points.iter().enumerate() {
        let q = Vector3::new(
            axes[0].value(k / 25),
            axes[1].value(k / 5 % 5),
            axes[2].value(k % 5),
        );
        let x = p.pose.unwrap();
        assert!((t.inverse(&x).unwrap() - q).amax() < 1e-9, "{q:?}");
    }
}

/// A user's own Gough-Stewart platform (`tests/fixtures/own-hexapod.toml`).
fn own_hexapod() -> pkm::Machine {
    pkm::Machine::from_path(format!(
        "{}/../../tests/fixtures/own-hexapod.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// The default map covers the whole reach of every example machine
/// and of a user's own hexapod: no reachable point on a face of the grid that is not a
/// bound of the reach, and every outcome counted once.
#[test]
fn default_maps_hold_the_whole_reach() {
    let dir = format!("{}/../../examples/machines", env!("CARGO_MANIFEST_DIR"));
    let mut machines: Vec<pkm::Machine> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        // The robots' maps take seconds each (numeric IK on every unreachable point):
        // their bound is tested below.
        .filter(|p| !p.to_string_lossy().contains("kr30"))
        .map(|p| pkm::Machine::from_path(p).unwrap())
        .collect();
    machines.push(own_hexapod());
    for m in &machines {
        let home = m.mechanism().home();
        let (wm, how) =
            pkm::analysis::workspace::reach_map(m, &home, 20, None, &[], &|_| {}).unwrap();
        let s = wm.summary_of(m.mechanism().coordinates());
        assert!(s.reachable > 0, "{}: nothing reachable ({how})", m.source);
        assert!(s.cut.is_empty(), "{}: cut at {:?} ({how})", m.source, s.cut);
        assert_eq!(
            s.outcomes.iter().map(|o| o.1).sum::<usize>(),
            s.points,
            "{}",
            m.source
        );
        // A reachable region that fills less than a tenth of its grid wastes the map.
        assert!(
            s.reachable_fraction > 0.1,
            "{}: {:.3} of the grid reachable ({how})",
            m.source,
            s.reachable_fraction
        );
    }
}

/// The old default box (home +- 0.6 of the longest stroke) cut the own hexapod's
/// region at Z = -30 mm: the reach map goes below it, down to where the platform
/// reaches the base plane (the tool hangs 150 mm below the platform, so its region at
/// the home orientation ends just above Z = -150 mm) and no further: the mirror region
/// below the base is another assembly mode, separate.
#[test]
fn the_own_hexapod_map_reaches_below_the_old_box() {
    let m = own_hexapod();
    let home = m.mechanism().home();
    let (wm, _) = pkm::analysis::workspace::reach_map(&m, &home, 20, None, &[], &|_| {}).unwrap();
    let s = wm.summary_of(m.mechanism().coordinates());
    let old_z_min = 600.0 - 0.6 * 1050.0;
    let z_min = s.bounding_box[2][0];
    assert!(
        z_min < old_z_min - 50.0 && z_min > -150.0,
        "{:?}",
        s.bounding_box
    );
}

/// A grid over both sides of seed 000's tripod base: the points above the base are
/// within every limit (inverse kinematics and limits say so point by point) but the
/// platform cannot get there without passing its base plane, a singular
/// configuration: they are a separate region, not counted as reachable.
#[test]
fn a_mirror_assembly_mode_is_a_separate_region() {
    use pkm::workspace::PointStatus;
    let m = machine("tripod-seed000.toml");
    let home = m.mechanism().home();
    let bounds = [-100.0, 100.0, -100.0, 100.0, -400.0, 400.0];
    let (wm, how) =
        pkm::analysis::workspace::map(&m, &home, Some(&bounds), Some(20.0), &[], &|_| {}).unwrap();
    assert_eq!(how, "the given bounds");
    let mut separate = 0;
    for (k, p) in wm.points.iter().enumerate() {
        let x = wm.coords(k);
        if p.reachable {
            assert!(x[2] < 0.0, "{x:?}");
        }
        if p.status == PointStatus::Separate {
            separate += 1;
            assert!(x[2] > 0.0, "{x:?}");
            let q = m.mechanism().inverse(&x).unwrap();
            assert!(m.mechanism().check_limits(&x, &q).unwrap().is_empty());
        }
    }
    assert!(separate > 10, "{separate}");
}

/// `Mechanism::position_bound` bounds: every pose within the strokes (strut machines)
/// or of any joint values (robots) has its tool point inside the box.
#[test]
fn position_bounds_hold_every_reachable_tool_point() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(16);
    let own = own_hexapod();
    let Model::Hexapod(h) = &own.model else {
        panic!()
    };
    let inside = |b: [[f64; 2]; 3], p: [f64; 3]| {
        (0..3).all(|k| b[k][0] - 1e-9 <= p[k] && p[k] <= b[k][1] + 1e-9)
    };
    let mut hits = 0;
    for _ in 0..20_000 {
        let x = Vector6::new(
            rng.random_range(-900.0..900.0),
            rng.random_range(-900.0..900.0),
            rng.random_range(-900.0..1300.0),
            rng.random_range(-0.3..0.3),
            rng.random_range(-0.3..0.3),
            rng.random_range(-0.3..0.3),
        );
        let q = h.inverse(&x).unwrap();
        let b = h.position_bound(&x).unwrap();
        if q.iter().all(|l| *l <= 1050.0) {
            hits += 1;
            assert!(inside(b, [x[0], x[1], x[2]]), "{x} outside {b:?}");
        }
    }
    assert!(hits > 100, "{hits}");
    // Seed 000's translational tripod (platform orientation held): struts within their
    // 300 mm stroke end.
    let Model::TranslationalTripod(t) = machine("tripod-seed000.toml").model else {
        panic!()
    };
    let mut hits = 0;
    for _ in 0..20_000 {
        let x = Vector6::new(
            rng.random_range(-400.0..400.0),
            rng.random_range(-400.0..400.0),
            rng.random_range(-500.0..100.0),
            0.0,
            0.0,
            0.0,
        );
        let q = t.inverse(&x).unwrap();
        let b = t.position_bound(&x).unwrap();
        if q.iter().all(|l| *l <= 300.0) {
            hits += 1;
            assert!(inside(b, [x[0], x[1], x[2]]), "{x} outside {b:?}");
        }
    }
    assert!(hits > 100, "{hits}");
    // A robot: any joint values.
    let ur5 = pkm::Machine::from_path(format!(
        "{}/../../examples/robots/ur5-like.urdf",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let Model::Serial(s) = &ur5.model else {
        panic!()
    };
    let pkm::serial::mechanism::SerialAny::Arm(arm) = &s.mechanism else {
        panic!()
    };
    let b = arm.position_bound(&arm.info().home()).unwrap();
    for _ in 0..20_000 {
        let q = Vector6::from_fn(|_, _| rng.random_range(-6.3..6.3));
        let x = arm.coords_of_joints(&q);
        assert!(inside(b, [x[0], x[1], x[2]]), "{x} outside {b:?}");
    }
}

/// The UR5 a user writes from its standard DH table was once mapped up to
/// X = 173 mm (a box around home) though it reaches ~850 mm; the default map now holds
/// its whole reach at the home orientation (the links' sphere bounds it), nothing cut.
#[test]
fn a_ur5_map_holds_its_whole_reach() {
    let m = pkm::Machine::from_path(format!(
        "{}/../../tests/fixtures/ur5-dh.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let home = m.mechanism().home();
    let (wm, how) = pkm::analysis::workspace::reach_map(&m, &home, 8, None, &[], &|_| {}).unwrap();
    let s = wm.summary_of(m.mechanism().coordinates());
    assert!(how.contains("bound"), "{how}");
    assert!(s.cut.is_empty(), "{:?}", s.cut);
    assert!(
        s.bounding_box[0][1] > 700.0 && s.bounding_box[0][0] < -700.0,
        "{:?}",
        s.bounding_box
    );
    // Points beyond the links' sphere are proven out of reach, not solver failures;
    // within it the parallel-axes closed form proves the rest: every point is solved
    // or proven out of reach (with Newton, half of this grid "solver failed").
    let count = |status| s.outcomes.iter().find(|o| o.0 == status).map_or(0, |o| o.1);
    assert!(
        count(pkm::workspace::PointStatus::NoSolution) > 0,
        "{:?}",
        s.outcomes
    );
    assert_eq!(
        count(pkm::workspace::PointStatus::SolverFailed),
        0,
        "{:?}",
        s.outcomes
    );
    assert!(
        count(pkm::workspace::PointStatus::Reachable) > 100,
        "{:?}",
        s.outcomes
    );
}

/// The tilt set: the base orientation and eight rotations by the tilt about horizontal
/// axes 45 degrees apart, each turning the tool axis by exactly the tilt towards its
/// azimuth (built back from the RPY angles).
#[test]
fn tilt_orientations_tilt_the_tool_axis_by_the_tilt_all_around() {
    let t = 15f64.to_radians();
    let o = pkm::workspace::tilt_orientations(t);
    assert_eq!(o.len(), 9);
    assert_eq!(o[0], [0.0; 3]);
    let mut azimuths = Vec::new();
    for a in &o[1..] {
        let r = pkm::Convention::Rpy.to_matrix(*a);
        let z = r * nalgebra::Vector3::z();
        assert!((z.z.acos() - t).abs() < 1e-12, "{a:?}");
        azimuths.push(z.y.atan2(z.x).to_degrees().rem_euclid(360.0));
    }
    azimuths.sort_by(f64::total_cmp);
    for (k, az) in azimuths.iter().enumerate() {
        assert!((az - 45.0 * k as f64).abs() < 1e-9, "{azimuths:?}");
    }
}

#[test]
fn point_status_names_are_their_serialised_names() {
    use pkm::workspace::PointStatus;
    for s in PointStatus::ALL {
        assert_eq!(serde_json::to_value(s).unwrap(), s.name());
    }
}

/// A 6R robot's condition numbers run eight poses across SIMD lanes in a map, as the
/// hexapod's: the map's values equal `condition` pose by pose, bit for bit;
/// `conditions` with and without the solved joints equals `condition_at` and
/// `condition`; each agrees with nalgebra's SVD of the scaled `dq/dx` (1e-12 relative
/// where `kappa < 1e2`, the eigen-solver's backward error `1e-14 kappa^2` beyond); a
/// pose out of reach is NaN, a singular one infinite.
#[test]
fn serial_arm_conditions_equal_single_poses_and_an_svd() {
    let m = machine("kr30-dh.toml");
    let Model::Serial(s) = &m.model else { panic!() };
    let pkm::serial::mechanism::SerialAny::Arm(arm) = &s.mechanism else {
        panic!()
    };
    let home = arm.info().home();
    let axes = [
        GridAxis {
            coordinate: 0,
            min: 200.0,
            max: 2200.0,
            step: 250.0,
        },
        GridAxis {
            coordinate: 1,
            min: -1500.0,
            max: 1500.0,
            step: 300.0,
        },
        GridAxis {
            coordinate: 2,
            min: -500.0,
            max: 2000.0,
            step: 250.0,
        },
    ];
    let wm = map(arm, &home, &axes, &[], &|_| {}).unwrap();
    let mut xs = Vec::new();
    let mut reachable = 0;
    for (k, p) in wm.points.iter().enumerate() {
        let c = wm.coords(k);
        let x = Vector6::new(c[0], c[1], c[2], home[3], home[4], home[5]);
        xs.push(x);
        if p.reachable {
            reachable += 1;
            assert_eq!(
                p.condition.to_bits(),
                arm.condition(&x).unwrap().to_bits(),
                "{x}"
            );
        }
    }
    assert!(reachable > 100, "{reachable}");
    // A singular pose (the wrist straight: axis 5 at zero) and poses beyond reach.
    let mut q = Vector6::new(0.3, -1.2, 1.0, 0.0, 0.0, 0.4);
    xs.push(arm.coords_of_joints(&q));
    q[4] = 0.5;
    xs.push(arm.coords_of_joints(&q));
    xs.push(Vector6::new(9000.0, 0.0, 0.0, 0.0, 0.0, 0.0));
    let mut out = vec![0.0; xs.len()];
    abilities::conditions(arm, &xs, &[], &mut out);
    let (mut compared, mut beyond, mut singular) = (0, 0, 0);
    let mut solved = Vec::new();
    let mut with_q = Vec::new();
    for (x, c) in xs.iter().zip(&out) {
        match arm.condition(x) {
            Ok(single) => {
                assert_eq!(c.to_bits(), single.to_bits(), "{x}");
                if single.is_infinite() {
                    singular += 1;
                    continue;
                }
                let q = arm.inverse(x).unwrap();
                solved.push(*x);
                with_q.push(q);
                let k = pkm::mechanism::scale_driven_columns(arm, &arm.jacobian(x).unwrap());
                let sv = k.singular_values();
                let svd = sv.max() / sv.min();
                let tol = 1e-12f64.max(1e-14 * svd * svd);
                assert!((c - svd).abs() <= tol * svd, "{x}: {c} vs SVD {svd}");
                compared += 1;
            }
            Err(_) => {
                assert!(c.is_nan(), "{x}: {c}");
                beyond += 1;
            }
        }
    }
    assert!(
        compared > 100 && beyond > 0 && singular > 0,
        "{compared} {beyond} {singular}"
    );
    let mut by_q = vec![0.0; solved.len()];
    abilities::conditions(arm, &solved, &with_q, &mut by_q);
    for ((x, q), c) in solved.iter().zip(&with_q).zip(&by_q) {
        assert_eq!(
            c.to_bits(),
            arm.condition_at(x, q).unwrap().to_bits(),
            "{x}"
        );
    }
}
