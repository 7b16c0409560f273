//! Pentapod (LinuxCNC pentakins): strut lengths against pentakins' own formula, the
//! Jacobian and the exact motion against finite differences, FK round trips,
//! sensitivities, limits and file errors.

use nalgebra::{Matrix3, SVector, Vector3, Vector6};
use pkm::accuracy::{Parametric, Rebuild};
use pkm::machine::Model;
use pkm::pentapod::Pentapod;
use pkm::verify::{jacobian_error, round_trip};
use pkm::{Error, LimitKind, Machine, Mechanism};
use rand::{Rng, SeedableRng};

fn example() -> Pentapod {
    match Machine::from_path(format!(
        "{}/../../examples/machines/pentapod-linuxcnc.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .model
    {
        Model::Pentapod(p) => *p,
        _ => panic!("not a pentapod"),
    }
}

/// A pose within the sim's axis travel (X, Y, Z within 250 mm, A within 50 deg, B within
/// 15 deg), C = 0.
fn random_pose(rng: &mut rand::rngs::StdRng) -> Vector6<f64> {
    Vector6::new(
        rng.random_range(-250.0..250.0),
        rng.random_range(-250.0..250.0),
        rng.random_range(-250.0..250.0),
        rng.random_range(-50f64..50.0).to_radians(),
        rng.random_range(-15f64..15.0).to_radians(),
        0.0,
    )
}

/// pentakins.c `InvKins`, written the way the controller computes it: the base joint
/// `b` moved into the effector frame by the inverse of `R = Ry(b) Rx(a)`
/// (`pmRpyMatConvert(a, b, 0)`), then the distance to the ring in that frame. The ring
/// data are the sim's `kinematics.hal`.
pub(crate) fn pentakins_inverse(pose: &[f64; 5]) -> [f64; 5] {
    let base = [
        [-418.0, 500.0, -140.0],
        [418.0, 500.0, -140.0],
        [0.0, 500.0, -310.0],
        [418.0, 500.0, 510.0],
        [-418.0, 500.0, 510.0],
    ];
    let ra = [80.3; 5];
    let za = [87.0, 114.5, 140.5, 232.5, 258.5];
    let (sa, ca) = pose[3].sin_cos();
    let (sb, cb) = pose[4].sin_cos();
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, ca, -sa, 0.0, sa, ca);
    let ry = Matrix3::new(cb, 0.0, sb, 0.0, 1.0, 0.0, -sb, 0.0, cb);
    let inv = (ry * rx).try_inverse().unwrap();
    std::array::from_fn(|i| {
        let t = Vector3::from(base[i]) - Vector3::new(pose[0], pose[1], pose[2]);
        let xyz = inv * t;
        ((xyz.z - za[i]).powi(2) + ((xyz.x * xyz.x + xyz.y * xyz.y).sqrt() - ra[i]).powi(2)).sqrt()
    })
}

#[test]
fn strut_lengths_equal_pentakins_for_any_pose() {
    let m = example();
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let mut worst: f64 = 0.0;
    for _ in 0..2000 {
        let x = random_pose(&mut rng);
        let q = m.inverse(&x).unwrap();
        let r = pentakins_inverse(&[x[0], x[1], x[2], x[3], x[4]]);
        for i in 0..5 {
            worst = worst.max((q[i] - r[i]).abs());
        }
    }
    assert!(
        worst < 1e-9,
        "largest difference from pentakins {worst:.3e} mm"
    );
}

#[test]
fn jacobian_matches_finite_differences() {
    let m = example();
    let mut rng = rand::rngs::StdRng::seed_from_u64(6);
    for _ in 0..200 {
        let mut x = random_pose(&mut rng);
        // C is held, but its column must be right too (the tool axis turns with it).
        x[5] = rng.random_range(-0.5..0.5);
        let e = jacobian_error(&m, &x).unwrap();
        assert!(e < 1e-6, "relative Jacobian error {e:.2e} at {x:?}");
    }
}

#[test]
fn actuator_motion_matches_finite_differences_of_the_inverse() {
    let m = example();
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    for _ in 0..100 {
        let x0 = random_pose(&mut rng);
        let xd = Vector6::from_fn(|k, _| {
            if k < 3 {
                rng.random_range(-100.0..100.0)
            } else {
                rng.random_range(-0.5..0.5)
            }
        });
        let xdd = Vector6::from_fn(|k, _| {
            if k < 3 {
                rng.random_range(-1000.0..1000.0)
            } else {
                rng.random_range(-2.0..2.0)
            }
        });
        let at = |t: f64| x0 + xd * t + xdd * (0.5 * t * t);
        // Central differences: q' with h = 1e-4 s (error ~ h^2 times the third
        // derivative), q'' with h = 1e-3 s (rounding ~ L eps / h^2 ~ 1e-7 mm/s^2 for
        // 600 mm struts).
        let q = |t: f64| m.inverse(&at(t)).unwrap();
        let h = 1e-4;
        let qd = (q(h) - q(-h)) / (2.0 * h);
        let h = 1e-3;
        let qdd = (q(h) - q(0.0) * 2.0 + q(-h)) / (h * h);
        let mo = m.actuator_motion(&x0, &xd, &xdd).unwrap();
        assert!((mo.q - q(0.0)).amax() < 1e-9);
        assert!(
            (mo.qd - qd).amax() < 1e-6 * qd.amax().max(1.0),
            "q' {} vs {}",
            mo.qd,
            qd
        );
        assert!(
            (mo.qdd - qdd).amax() < 1e-4 * qdd.amax().max(1.0),
            "q'' {} vs {}",
            mo.qdd,
            qdd
        );
    }
}

#[test]
fn forward_kinematics_round_trips_from_home_and_from_a_nearby_start() {
    let m = example();
    let mut rng = rand::rngs::StdRng::seed_from_u64(8);
    for _ in 0..500 {
        let x = random_pose(&mut rng);
        let q = m.inverse(&x).unwrap();
        // Over the sim's whole travel (as large as its struts, across singular
        // surfaces: the condition number passes 1e4 inside it), the branch through home
        // need not be the pose's; whatever FK returns must have these strut lengths.
        let f = m.forward(&q, &m.info().home()).unwrap();
        assert!((m.inverse(&f.pose).unwrap() - q).amax() < 1e-9, "{f:?}");
        // From a start near the pose (a controller's last position, one servo period
        // away), the pose itself. Near the travel's edge (A = 50 deg) the condition
        // reaches ~500 and two assembly modes lie a few mm apart, so "near" is near.
        let near = x + Vector6::new(0.05, -0.03, 0.04, 3e-4, -2e-4, 0.0);
        let rt = round_trip(&m, &x, &near).unwrap();
        assert!(
            rt.coordinate_error < 1e-9,
            "from nearby: {rt:?} at {x:?} (condition {:?})",
            m.condition(&x)
        );
    }
    // In the middle of the travel, FK from home is the pose itself.
    for _ in 0..500 {
        let x = Vector6::new(
            rng.random_range(-100.0..100.0),
            rng.random_range(-100.0..100.0),
            rng.random_range(-100.0..100.0),
            rng.random_range(-10f64..10.0).to_radians(),
            rng.random_range(-10f64..10.0).to_radians(),
            0.0,
        );
        let rt = round_trip(&m, &x, &m.info().home()).unwrap();
        assert!(
            rt.position_error < 1e-9 && rt.orientation_error < 1e-9,
            "from home: {rt:?} at {x:?} (condition {:?})",
            m.condition(&x)
        );
    }
}

#[test]
fn a_tool_pose_gives_back_its_coordinates() {
    let m = example();
    let mut rng = rand::rngs::StdRng::seed_from_u64(9);
    for _ in 0..200 {
        let x = random_pose(&mut rng);
        let pose = m.tool_pose(&x).unwrap();
        let back = m.coords_from_pose(&pose, true).unwrap();
        assert!((back - x).amax() < 1e-12, "{back:?} vs {x:?}");
    }
}

#[test]
fn a_tool_tip_below_the_effector_origin_moves_the_origin_up_the_axis() {
    // A 100 mm tool: the tip at p means the effector origin at p + 100 k (t = -100).
    let m = example();
    let mut long = m.clone();
    long.set_geometry(long.penta_struts().clone(), -100.0);
    let x = Vector6::new(10.0, -20.0, 30.0, 0.2, -0.1, 0.0);
    let k = pkm::rotation::rpy_matrix(x[3], x[4], x[5])
        .column(2)
        .into_owned();
    let mut shifted = x;
    for a in 0..3 {
        shifted[a] += 100.0 * k[a];
    }
    let d = (long.inverse(&x).unwrap() - m.inverse(&shifted).unwrap()).amax();
    assert!(d < 1e-9, "{d:.3e}");
}

#[test]
fn geometry_sensitivities_match_finite_differences() {
    let m = example();
    let mut rng = rand::rngs::StdRng::seed_from_u64(10);
    let g0 = m.geometry_values();
    for _ in 0..20 {
        let x = random_pose(&mut rng);
        let jg = m.inverse_geometry_jacobian(&x).unwrap();
        for k in 0..g0.len() {
            let h = 1e-5;
            let mut gp = g0.clone();
            gp[k] += h;
            let mut gm = g0.clone();
            gm[k] -= h;
            let qp = m.with_geometry_values(&gp).unwrap().inverse(&x).unwrap();
            let qm = m.with_geometry_values(&gm).unwrap().inverse(&x).unwrap();
            let fd = (qp - qm) / (2.0 * h);
            for i in 0..5 {
                assert!(
                    (jg[(i, k)] - fd[i]).abs() < 1e-6,
                    "dL{i}/d{} analytic {} vs {}",
                    m.geometry_parameters()[k].name,
                    jg[(i, k)],
                    fd[i]
                );
            }
        }
        // The analytic pose sensitivities against the rebuilt machine's FK.
        let analytic = m.analytic_sensitivities(&x).unwrap().unwrap();
        let mut ev = m.evaluator(&x).unwrap();
        for k in [0, 4, 17, 22, 25, 26, 30] {
            use pkm::accuracy::Evaluate;
            let h = 1e-4;
            let e = ev.pose_error(&[(k, h)]).unwrap();
            let d = (e.position / h - analytic[k].position).amax();
            assert!(
                d < 1e-3 * analytic[k].position.amax().max(1e-3),
                "parameter {k}: {d:.3e}"
            );
        }
    }
}

/// The spin about the tool axis is free (the rings turn), so it is no error of
/// the pentapod. Orientation errors keep only the tilt of the tool axis: none along the
/// axis, and `w x k` equals the change of the deviated machine's tool axis (central
/// differences of exact forward kinematics), both analytic and exact.
#[test]
fn orientation_errors_are_the_tool_axis_tilt_without_the_free_spin() {
    use pkm::accuracy::Evaluate;
    let m = example();
    assert!(m.info().free_spin());
    let mut rng = rand::rngs::StdRng::seed_from_u64(12);
    let n = m.parameters().len();
    for _ in 0..10 {
        let x = random_pose(&mut rng);
        let k = m.tool_pose(&x).unwrap().rotation * Vector3::z();
        let analytic = m.analytic_sensitivities(&x).unwrap().unwrap();
        let mut ev = m.evaluator(&x).unwrap();
        let q = m.inverse(&x).unwrap();
        let g0 = m.geometry_values();
        for p in 0..n {
            let w = analytic[p].orientation;
            assert!(w.dot(&k).abs() < 1e-12 * w.norm().max(1e-9), "{p}: {w:?}");
            let exact = ev.pose_error(&[(p, 1e-4)]).unwrap().orientation;
            assert!(exact.dot(&k).abs() < 1e-12, "{p}: {exact:?}");
            // The tool axis of the deviated machines, at the same readings.
            let axis = |h: f64| {
                let (mm, dq) = if p < g0.len() {
                    let mut g = g0.clone();
                    g[p] += h;
                    (
                        m.with_geometry_values(&g).unwrap(),
                        SVector::<f64, 5>::zeros(),
                    )
                } else {
                    let mut dq = SVector::<f64, 5>::zeros();
                    dq[p - g0.len()] = h;
                    (m.clone(), dq)
                };
                let f = mm.forward(&(q + dq), &x).unwrap();
                mm.tool_pose(&f.pose).unwrap().rotation * Vector3::z()
            };
            let h = 1e-4;
            let dk = (axis(h) - axis(-h)) / (2.0 * h);
            let d = (w.cross(&k) - dk).amax();
            assert!(d < 1e-7 + 1e-5 * dk.amax(), "{p}: {d:.3e} ({dk:?})");
        }
    }
}

#[test]
fn axis_travel_names_the_axis_and_the_excess() {
    let m = example();
    let x = Vector6::new(0.0, 0.0, 0.0, 0.0, 20f64.to_radians(), 0.0);
    let q = m.inverse(&x).unwrap();
    let mut v = Vec::new();
    m.check_limits(&x, &q, &mut v);
    let b = v
        .iter()
        .find(|v| v.kind == LimitKind::AxisTravel)
        .expect("B travel");
    assert_eq!(b.limit, "axis B travel");
    assert!((b.value - 20.0).abs() < 1e-9 && (b.excess - 5.0).abs() < 1e-9);
    let text = b.to_string();
    assert!(
        text.contains("above its maximum 15.000 deg by 5.000 deg"),
        "{text}"
    );
}

#[test]
fn a_base_joint_on_the_tool_axis_is_reported_singular() {
    let m = example();
    // Base joint B2 at (0, 500, -310): put the tool axis through it (A = -90 deg turns the
    // axis to +Y; the origin below it on that line).
    let x = Vector6::new(0.0, 0.0, -310.0, -std::f64::consts::FRAC_PI_2, 0.0, 0.0);
    match m.jacobian(&x) {
        Err(Error::Singular { what, .. }) => assert!(what.contains("B2"), "{what}"),
        other => panic!("expected a singular strut, got {other:?}"),
    }
}

fn load_err(text: &str) -> String {
    match Machine::from_toml_str(text, "bad.toml") {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

fn example_text() -> String {
    std::fs::read_to_string(format!(
        "{}/../../examples/machines/pentapod-linuxcnc.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

#[test]
fn file_errors_name_the_field() {
    let t = example_text().replace("tip = [0.0, 0.0, 0.0]", "tip = [1.0, 0.0, 0.0]");
    let e = load_err(&t);
    assert!(e.contains("tool.tip") && e.contains("[0, 0, z]"), "{e}");
    let t = example_text().replace("A = [-50.0, 50.0]", "C = [-50.0, 50.0]");
    let e = load_err(&t);
    assert!(e.contains("limits.axes.C") && e.contains("holds C"), "{e}");
    let t = example_text().replace("A = [-50.0, 50.0]", "Q = [-50.0, 50.0]");
    let e = load_err(&t);
    assert!(e.contains("unknown axis `Q`"), "{e}");
    let t = example_text().replace(
        "ring_radius = 80.3\nring_height = 87.0",
        "ring_radius = -1.0\nring_height = 87.0",
    );
    let e = load_err(&t);
    assert!(e.contains("struts[0].ring_radius"), "{e}");
    let cut = example_text();
    let first = cut.find("[[struts]]").unwrap();
    let second = first + 1 + cut[first + 1..].find("[[struts]]").unwrap();
    let t = format!("{}{}", &cut[..first], &cut[second..]);
    let e = load_err(&t);
    assert!(e.contains("exactly 5 struts, found 4"), "{e}");
}

#[test]
fn the_sim_home_joint_values_are_not_the_inverse_of_its_axis_home() {
    // What the INI ships as [JOINT_n] HOME, against the struts of the axis home (0, ..., 0):
    // the importer must not take them as home lengths.
    let m = example();
    let q = m.inverse(&m.info().home()).unwrap();
    let ini = SVector::<f64, 5>::from([598.5792, 697.1982, 682.785, 787.9175, 806.0397]);
    assert!((q - ini).amax() > 100.0);
    // And no pose near home has them: Newton from home does not reach them.
    assert!(m.forward(&ini, &m.info().home()).is_err());
}

/// The struts' length limits, named when the machine is built: beyond every stroke,
/// one violation per strut in strut order, named as when the names were formatted per
/// call.
#[test]
fn strut_length_limits_are_named_in_strut_order() {
    for by in [1.0, -2.5] {
        crate::common::check_position_names(&example(), by, |_, a| {
            format!("strut {} length", a.name)
        });
    }
}
