//! Statics and stiffness: every formula of `pkm::statics` against something built
//! without it (forward kinematics, finite differences of the analytic Jacobian and of
//! the tool pose, the struts' lines by hand, a cubic hexapod's closed form).

use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, Vector3, Vector6};
use pkm::machine::{Analysable, Visitor};
use pkm::mechanism::{driven_jacobian, LinkKind};
use pkm::statics::{self, wrench, Wrench};
use pkm::Machine;
use rand::{rngs::StdRng, Rng, SeedableRng};

use super::common::{example, fixture};

/// Machines whose pose coordinates are X, Y, Z, A, B, C: every type with a spatial
/// tool (struts, the hybrid machine, a robot).
const SPATIAL: &[&str] = &[
    "hexapod-linuxcnc.toml",
    "hexapod-seed001.toml",
    "pentapod-linuxcnc.toml",
    "tripod-seed000.toml",
    "hybrid-am-seed002.toml",
    "kr30-dh.toml",
    "p3rp-hybrid-seed004.toml",
];

/// A pose near home: `dx` mm and `da` rad at most off it on every driven coordinate,
/// with an inverse solution.
fn pose_near<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    rng: &mut StdRng,
    dx: f64,
    da: f64,
) -> SVector<f64, P> {
    let home = m.info().home();
    for _ in 0..100 {
        let mut x = home;
        for k in m.info().driven() {
            let r = if k < 3 { dx } else { da };
            x[k] += rng.random_range(-r..r);
        }
        if m.inverse(&x).is_ok() && m.jacobian(&x).is_ok() {
            return x;
        }
    }
    panic!("{}: no pose near home", m.info().name())
}

fn random_wrench(rng: &mut StdRng) -> Wrench {
    let mut v = || rng.random_range(-1.0..1.0);
    Wrench {
        force: Vector3::new(v(), v(), v()) * 1000.0,
        moment: Vector3::new(v(), v(), v()) * 1e5,
    }
}

/// The tool twist between two tool poses: tip displacement, rotation vector.
fn twist(a: &pkm::pose::Pose, b: &pkm::pose::Pose) -> Vector6<f64> {
    let dr = b.translation.vector - a.translation.vector;
    let th = (b.rotation * a.rotation.inverse()).scaled_axis();
    Vector6::new(dr.x, dr.y, dr.z, th.x, th.y, th.z)
}

fn rel(a: f64, scale: f64) -> f64 {
    a / scale.max(f64::MIN_POSITIVE)
}

/// Runs `check` on the machine's concrete type.
fn on<F>(machine: &Machine, check: F)
where
    F: Check,
{
    struct Job<F>(F);
    impl<F: Check> Visitor for Job<F> {
        type Output = ();
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            self.0.run(m)
        }
    }
    machine.visit(Job(check))
}

trait Check {
    fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M);
}

#[test]
fn the_twist_map_equals_differences_of_the_tool_pose() {
    struct C;
    impl Check for C {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let mut rng = StdRng::seed_from_u64(7);
            for _ in 0..20 {
                let x = pose_near(m, &mut rng, 20.0, 0.2);
                let t = wrench::twist_map(m, &x).unwrap();
                let h = 1e-5;
                for c in 0..P {
                    let mut a = x;
                    let mut b = x;
                    a[c] -= h;
                    b[c] += h;
                    let d = twist(&m.tool_pose(&a).unwrap(), &m.tool_pose(&b).unwrap()) / (2.0 * h);
                    let err = (d - t.column(c)).amax();
                    assert!(err < 1e-6, "{}: column {c} off by {err:e}", m.info().name());
                }
            }
        }
    }
    for name in SPATIAL {
        on(&example(name), C);
    }
}

#[test]
fn static_forces_equal_virtual_work_through_forward_kinematics() {
    // tau_i = -w . dp/dq_i, dp/dq_i by central differences of the forward kinematics:
    // no Jacobian, no twist map.
    struct C;
    impl Check for C {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let mut rng = StdRng::seed_from_u64(11);
            let mut worst = 0.0f64;
            for _ in 0..20 {
                let x = pose_near(m, &mut rng, 20.0, 0.15);
                let w = random_wrench(&mut rng);
                let tau = statics::actuator_forces(m, &x, &w).unwrap();
                let q = m.inverse(&x).unwrap();
                let h = 1e-5;
                let scale = tau.amax();
                for i in 0..A {
                    let tool = |s: f64| {
                        let mut qs = q;
                        qs[i] += s;
                        m.forward_tool_pose(&qs, &x).unwrap()
                    };
                    let dp = twist(&tool(-h), &tool(h)) / (2.0 * h);
                    let mut wv = w.vector();
                    if m.info().free_spin() {
                        // The spindle takes the moment about the tool axis; the
                        // machine's tool frame does not turn about it.
                        let axis = m.tool_pose(&x).unwrap().rotation * Vector3::z();
                        let mo = w.moment - axis * axis.dot(&w.moment);
                        wv.fixed_rows_mut::<3>(3).copy_from(&mo);
                    }
                    let virtual_work = -wv.dot(&dp);
                    worst = worst.max(rel((virtual_work - tau[i]).abs(), scale));
                }
            }
            assert!(
                worst < 1e-6,
                "{}: relative error {worst:e}",
                m.info().name()
            );
        }
    }
    for name in SPATIAL {
        on(&example(name), C);
    }
}

#[test]
fn actuator_hessians_equal_differences_of_the_jacobian() {
    struct C;
    impl Check for C {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let mut rng = StdRng::seed_from_u64(3);
            let d = m.info().driven();
            for _ in 0..10 {
                let x = pose_near(m, &mut rng, 20.0, 0.15);
                let hs = statics::actuator_hessians(m, &x).unwrap();
                let h = 1e-5;
                for c in 0..A {
                    let jd = |s: f64| {
                        let mut xs = x;
                        xs[d[c]] += s;
                        driven_jacobian(&m.jacobian(&xs).unwrap(), &d)
                    };
                    let dj = (jd(h) - jd(-h)) / (2.0 * h);
                    for i in 0..A {
                        let scale = hs[i].amax().max(1e-3);
                        for r in 0..A {
                            let err = (hs[i][(r, c)] - dj[(i, r)]).abs();
                            assert!(
                                err < 1e-6 * scale,
                                "{}: H_{i}[{r},{c}] = {} by polarisation, {} by differences",
                                m.info().name(),
                                hs[i][(r, c)],
                                dj[(i, r)]
                            );
                        }
                    }
                }
            }
        }
    }
    for name in SPATIAL {
        on(&example(name), C);
    }
}

#[test]
fn the_load_dependent_stiffness_equals_differences_of_the_balance() {
    // K_x's load-dependent part is -d/dx (J^T tau + T^T w) at fixed tau and w; its
    // elastic part -J^T k dq/dx; both by differences of the analytic Jacobian and twist
    // map, with the drives' forces those holding a wrench with large moments.
    struct C;
    impl Check for C {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let mut rng = StdRng::seed_from_u64(5);
            let d = m.info().driven();
            let k = SVector::<f64, A>::from_fn(|i, _| 5e4 + 1e4 * i as f64);
            for _ in 0..10 {
                let x = pose_near(m, &mut rng, 20.0, 0.15);
                let w = random_wrench(&mut rng);
                let s = statics::stiffness(m, &x, &w, &k).unwrap();
                let q0 = m.inverse(&x).unwrap();
                let balance = |xs: &SVector<f64, P>, springs: bool| -> SVector<f64, A> {
                    let jd = driven_jacobian(&m.jacobian(xs).unwrap(), &d);
                    let tau = if springs {
                        s.forces - k.component_mul(&(m.inverse(xs).unwrap() - q0))
                    } else {
                        s.forces
                    };
                    let qf = wrench::generalised_force(m, xs, &w).unwrap();
                    jd.transpose() * tau + SVector::<f64, A>::from_fn(|i, _| qf[d[i]])
                };
                let h = 1e-5;
                let fd = |springs: bool| {
                    SMatrix::<f64, A, A>::from_fn(|r, c| {
                        let mut a = x;
                        let mut b = x;
                        a[d[c]] -= h;
                        b[d[c]] += h;
                        -(balance(&b, springs)[r] - balance(&a, springs)[r]) / (2.0 * h)
                    })
                };
                let geo = fd(false);
                let err = (geo - s.pose_geometric).amax();
                assert!(
                    err < 1e-6 * s.pose_geometric.amax(),
                    "{}: load-dependent stiffness off by {err:e} of {:e}",
                    m.info().name(),
                    s.pose_geometric.amax()
                );
                let all = fd(true);
                let err = (all - s.pose_stiffness).amax();
                assert!(
                    err < 1e-7 * s.pose_stiffness.amax(),
                    "{}: tangent stiffness off by {err:e}",
                    m.info().name()
                );
            }
        }
    }
    for name in SPATIAL {
        on(&example(name), C);
    }
}

/// The unloaded stiffness of a strut machine by hand: each strut a spring along its
/// line, `K = sum k_i s_i s_i^T` with `s_i = (u_i, (p_i - r) x u_i)`, `p_i` its
/// platform joint and `r` the tool tip, from the skeleton's points.
fn struts_by_hand<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    k: &SVector<f64, A>,
) -> Matrix6<f64> {
    let sk = m.skeleton(x).unwrap();
    let r = m.tool_pose(x).unwrap().translation.vector;
    let at = |i: usize| Vector3::from(sk.points[i].position);
    let mut out = Matrix6::zeros();
    let struts: Vec<_> = sk
        .links
        .iter()
        .filter(|l| l.kind == LinkKind::Strut)
        .collect();
    assert_eq!(struts.len(), A, "{}", m.info().name());
    for (i, l) in struts.iter().enumerate() {
        let (b, p) = (at(l.from), at(l.to));
        let u = (p - b).normalize();
        let mo = (p - r).cross(&u);
        let s = Vector6::new(u.x, u.y, u.z, mo.x, mo.y, mo.z);
        out += s * s.transpose() * k[i];
    }
    out
}

#[test]
fn a_hexapods_stiffness_equals_its_struts_lines_by_hand() {
    struct C;
    impl Check for C {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let mut rng = StdRng::seed_from_u64(9);
            let k = statics::drive_stiffness(m).unwrap();
            for _ in 0..20 {
                let x = pose_near(m, &mut rng, 50.0, 0.2);
                let s = statics::stiffness(m, &x, &Wrench::default(), &k).unwrap();
                let kk = s.matrix.unwrap();
                let hand = struts_by_hand(m, &x, &k);
                let err = (kk - hand).amax();
                assert!(
                    err < 1e-8 * hand.amax(),
                    "{}: off by {err:e}",
                    m.info().name()
                );
                assert!((kk * s.compliance - Matrix6::identity()).amax() < 1e-8);
                assert!(s.geometric.unwrap().amax() == 0.0);
            }
        }
    }
    on(&example("hexapod-linuxcnc.toml"), C);
    on(&example("hexapod-seed001.toml"), C);
}

#[test]
fn a_cubic_hexapod_is_2k_stiff_and_uncoupled_at_the_cube_centre() {
    struct C;
    impl Check for C {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let k = statics::drive_stiffness(m).unwrap();
            let kv = k[0];
            let x = m.info().home();
            let s = statics::stiffness(m, &x, &Wrench::default(), &k).unwrap();
            let kk = s.matrix.unwrap();
            let tt = kk.fixed_view::<3, 3>(0, 0);
            assert!(
                (tt - Matrix3::identity() * 2.0 * kv).amax() < 1e-9 * kv,
                "{tt}"
            );
            assert!(kk.fixed_view::<3, 3>(0, 3).amax() < 1e-9 * kv * 200.0);
            assert!(kk.fixed_view::<3, 3>(3, 0).amax() < 1e-9 * kv * 200.0);
            // Rotations: each pair of parallel edges 2 k (s x u)(s x u)^T, half-side 200.
            let rot = Matrix3::new(2.0, 1.0, 1.0, 1.0, 2.0, 1.0, 1.0, 1.0, 2.0) * 2.0 * kv * 4e4;
            assert!((kk.fixed_view::<3, 3>(3, 3) - rot).amax() < 1e-9 * rot.amax());
            let (kmin, _) = statics::smallest_translational(&s.compliance);
            assert!((kmin - 2.0 * kv).abs() < 1e-9 * kv);

            // The deflection under a wrench: forward kinematics of the struts shortened
            // by tau / k, to first order.
            let mut rng = StdRng::seed_from_u64(1);
            for _ in 0..10 {
                let w = random_wrench(&mut rng);
                let lin = statics::deflection(m, &x, &w, &k).unwrap();
                let tau = statics::actuator_forces(m, &x, &w).unwrap();
                let q = m.inverse(&x).unwrap() - tau.component_div(&k);
                let fk = twist(
                    &m.tool_pose(&x).unwrap(),
                    &m.forward_tool_pose(&q, &x).unwrap(),
                );
                let size = lin.amax();
                assert!((fk - lin).amax() < 1e-3 * size, "{fk} against {lin}");
                let exact = statics::deflection_exact(m, &x, &w, &k).unwrap();
                assert!((exact - lin).amax() < 1e-3 * size, "{exact} against {lin}");
            }
        }
    }
    on(&fixture("cubic-hexapod.toml"), C);
}

#[test]
fn the_exact_deflection_tends_to_the_linear_one_as_the_load_shrinks() {
    // Second order: the gap shrinks 100-fold for a 10-fold smaller load.
    struct C;
    impl Check for C {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let k = statics::drive_stiffness(m).unwrap();
            let x = m.info().home();
            let mut rng = StdRng::seed_from_u64(2);
            let w = random_wrench(&mut rng);
            let gap = |s: f64| {
                let ws = Wrench {
                    force: w.force * s,
                    moment: w.moment * s,
                };
                let lin = statics::deflection(m, &x, &ws, &k).unwrap();
                let ex = statics::deflection_exact(m, &x, &ws, &k).unwrap();
                (ex - lin).amax()
            };
            let (big, small) = (gap(100.0), gap(10.0));
            assert!(big > 0.0 && small < big / 50.0, "{big:e} then {small:e}");
        }
    }
    on(&example("hexapod-linuxcnc.toml"), C);
    on(&example("pentapod-linuxcnc.toml"), C);
}

#[test]
fn held_and_free_coordinates_shape_the_stiffness() {
    // A translational tripod holds its orientation rigidly: no finite 6 x 6 stiffness,
    // no rotation in the compliance. A pentapod's spindle spins freely: no stiffness
    // about the tool axis.
    let tripod = pkm::Machine::from_toml_str(
        &std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/machines/tripod-seed000.toml"
        ))
        .unwrap()
        .replace(
            "max_acceleration = ",
            "stiffness = 1e5\nmax_acceleration = ",
        ),
        "tripod",
    )
    .unwrap();
    struct Tripod;
    impl Check for Tripod {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let k = statics::drive_stiffness(m).unwrap();
            let s = statics::stiffness(m, &m.info().home(), &Wrench::default(), &k).unwrap();
            assert!(s.matrix.is_none());
            assert!(s.compliance.fixed_view::<3, 3>(3, 3).amax() == 0.0);
            assert!(s.compliance.fixed_view::<3, 3>(0, 0).amax() > 0.0);
        }
    }
    on(&tripod, Tripod);
    struct Penta;
    impl Check for Penta {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let k = statics::drive_stiffness(m).unwrap();
            let mut rng = StdRng::seed_from_u64(4);
            for _ in 0..10 {
                let x = pose_near(m, &mut rng, 20.0, 0.2);
                let w = random_wrench(&mut rng);
                let s = statics::stiffness(m, &x, &w, &k).unwrap();
                let kk = s.matrix.unwrap();
                let axis = m.tool_pose(&x).unwrap().rotation * Vector3::z();
                let spin = Vector6::new(0.0, 0.0, 0.0, axis.x, axis.y, axis.z);
                assert!((kk * spin).amax() < 1e-9 * kk.amax());
                assert!((spin.transpose() * kk).amax() < 1e-9 * kk.amax());
                assert!((s.compliance * spin).amax() < 1e-12 * s.compliance.amax());
                // K C is the identity on the twists without spin.
                let p = Matrix6::identity() - spin * spin.transpose();
                assert!((kk * s.compliance - p).amax() < 1e-8);
            }
        }
    }
    on(&example("pentapod-linuxcnc.toml"), Penta);
}

#[test]
fn missing_data_and_other_coordinates_are_named() {
    let r = pkm::analysis::statics::statics(
        &example("tripod-seed000.toml"),
        &pkm::analysis::statics::StaticsOptions {
            pose: example("tripod-seed000.toml").mechanism().home(),
            wrench: [0.0, 0.0, -100.0, 0.0, 0.0, 0.0],
        },
    )
    .unwrap();
    assert!(r.stiffness.is_none());
    let e = r.stiffness_error.unwrap();
    assert!(e.contains("no `stiffness` for drives"), "{e}");
    let head = example("p3rp-seed004.toml");
    let e = pkm::analysis::statics::statics(
        &head,
        &pkm::analysis::statics::StaticsOptions {
            pose: head.mechanism().home(),
            wrench: [0.0; 6],
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("statics and stiffness is not available"), "{e}");
}

#[test]
fn the_deflection_is_the_forward_kinematics_of_the_shortened_drives() {
    // Each drive gives way by tau_i / k_i under the wrench; the tool then sits where
    // forward kinematics puts it (first order). No compliance matrix involved.
    struct C;
    impl Check for C {
        fn run<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let k = statics::drive_stiffness(m).unwrap();
            let mut rng = StdRng::seed_from_u64(6);
            for _ in 0..10 {
                let x = pose_near(m, &mut rng, 30.0, 0.2);
                // Small enough for the second-order terms to stay below 1e-3.
                let big = random_wrench(&mut rng);
                let w = Wrench {
                    force: big.force * 0.1,
                    moment: big.moment * 0.1,
                };
                let lin = statics::deflection(m, &x, &w, &k).unwrap();
                let tau = statics::actuator_forces(m, &x, &w).unwrap();
                let q = m.inverse(&x).unwrap() - tau.component_div(&k);
                let p0 = m.tool_pose(&x).unwrap();
                let mut fk = twist(&p0, &m.forward_tool_pose(&q, &x).unwrap());
                if m.info().free_spin() {
                    let a = p0.rotation * Vector3::z();
                    let th = fk.fixed_rows::<3>(3).into_owned();
                    fk.fixed_rows_mut::<3>(3).copy_from(&(th - a * a.dot(&th)));
                }
                let err = (fk - lin).component_div(&lin.map(|v| v.abs().max(1e-3 * lin.amax())));
                assert!(err.amax() < 1e-2, "{}: {fk} against {lin}", m.info().name());
                assert!(
                    (fk - lin).amax() < 1e-3 * lin.amax(),
                    "{}: {fk} against {lin}",
                    m.info().name()
                );
            }
        }
    }
    for name in [
        "hexapod-linuxcnc.toml",
        "hexapod-seed001.toml",
        "pentapod-linuxcnc.toml",
    ] {
        on(&example(name), C);
    }
}
