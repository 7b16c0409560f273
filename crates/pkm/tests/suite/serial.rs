//! Serial chains with primary deviations (seed 003).

use nalgebra::{Matrix3, Matrix4, Rotation3, Vector3};
use pkm::serial::completion::complete;
use pkm::serial::{Chain, Joint, JointKind, Link, LinkDeviation};
use pkm::{Error, Mechanism, Range};

fn small_rotation(w: [f64; 3]) -> Matrix3<f64> {
    *Rotation3::new(Vector3::from(w)).matrix()
}

/// Homogeneous rotations and translations for hand-built chains.
fn rz4(t: f64) -> Matrix4<f64> {
    let (s, c) = t.sin_cos();
    Matrix4::new(
        c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    )
}

fn rx4(t: f64) -> Matrix4<f64> {
    let (s, c) = t.sin_cos();
    Matrix4::new(
        1.0, 0.0, 0.0, 0.0, 0.0, c, -s, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 0.0, 1.0,
    )
}

fn tr4(x: f64, y: f64, z: f64) -> Matrix4<f64> {
    let mut m = Matrix4::identity();
    m[(0, 3)] = x;
    m[(1, 3)] = y;
    m[(2, 3)] = z;
    m
}

#[test]
fn completion_recovers_a_true_block_from_three_angles() {
    // Nominal blocks with 90 deg angles at the measured positions (signed: unique).
    let perm = Matrix3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    for w in [
        [1e-3, -2e-3, 5e-4],
        [3e-2, 1e-2, -2e-2],
        [-1e-4, 2e-4, 3e-4],
    ] {
        let truth = perm * small_rotation(w);
        let phi = perm.map(|c: f64| c.clamp(-1.0, 1.0).acos());
        let alpha = |r: usize, c: usize| truth[(r, c)].clamp(-1.0, 1.0).acos() - phi[(r, c)];
        // Positions whose nominal angle is 90 deg: (0,0), (1,1), (2,2) of a permutation.
        let meas = [
            ((0, 0), alpha(0, 0)),
            ((1, 1), alpha(1, 1)),
            ((0, 1), alpha(0, 1)),
        ];
        let c = complete(&perm, &meas).unwrap();
        assert!(c.residual < 1e-12, "{}", c.residual);
        assert!(
            (c.block - truth).amax() < 1e-9,
            "{w:?}: {} vs {truth}",
            c.block
        );
        for r in 0..3 {
            for k in 0..3 {
                assert!((c.alpha[(r, k)] - alpha(r, k)).abs() < 1e-9);
            }
        }
    }
}

#[test]
fn completion_with_aligned_axes_is_orthonormal_and_flags_the_sign() {
    // The paper's example: the angles of X* with X and Y, and of Z* with Z, for a link
    // whose frames are nominally parallel. The X*-X and Z*-Z angles carry no sign.
    let truth = small_rotation([2e-3, -1e-3, 3e-3]);
    let id = Matrix3::identity();
    let phi = id.map(|c: f64| c.acos());
    let alpha = |r: usize, c: usize| truth[(r, c)].clamp(-1.0, 1.0).acos() - phi[(r, c)];
    let c = complete(
        &id,
        &[
            ((0, 0), alpha(0, 0)),
            ((1, 0), alpha(1, 0)),
            ((2, 2), alpha(2, 2)),
        ],
    )
    .unwrap();
    assert!(c.residual < 1e-12);
    assert!((c.block.determinant() - 1.0).abs() < 1e-12);
    // The measured angles are reproduced by the completed block.
    for (r, k) in [(0, 0), (1, 0), (2, 2)] {
        assert!((c.block[(r, k)] - truth[(r, k)]).abs() < 1e-12);
    }
    // Either the true block or a mirror root at the same distance, flagged.
    assert!(
        (c.block - truth).amax() < 1e-9 || c.ambiguous,
        "{}",
        c.block
    );
}

#[test]
fn completion_rejects_inconsistent_measurements() {
    let id = Matrix3::identity();
    // X* at 0 deg from X but 60 deg (not 90) from Y: no unit vector has both.
    let e = complete(
        &id,
        &[
            ((0, 0), 0.0),
            ((1, 0), -std::f64::consts::FRAC_PI_6),
            ((2, 2), 0.0),
        ],
    )
    .unwrap_err();
    assert!(matches!(e, Error::NotAttainable { .. }), "{e}");
    let e = complete(&id, &[((0, 0), 0.0), ((0, 0), 0.1), ((2, 2), 0.0)]).unwrap_err();
    assert!(matches!(e, Error::InvalidInput { .. }), "{e}");
}

fn prismatic(name: &str) -> Option<Joint> {
    Some(Joint {
        name: name.into(),
        kind: JointKind::Prismatic,
        range: Range {
            min: -500.0,
            max: 500.0,
        },
        max_velocity: None,
        max_acceleration: None,
        stiffness: None,
    })
}

/// A Cartesian X, Y, Z chain: each link turns the next joint's Z onto the next axis.
fn xyz_chain() -> Chain {
    // Link 0 (bed) orients S_0* so that the first joint slides along world X:
    // columns of the block = axes of S_0* in S_0; Z* = world X.
    let to_x = Matrix3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0); // x*=Y, y*=Z, z*=X
    let to_next = Matrix3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    Chain {
        name: "tool".into(),
        links: vec![
            Link {
                name: "bed".into(),
                joint: None,
                translation: Vector3::new(0.0, 0.0, 100.0),
                rotation: to_x,
                inertial: None,
            },
            Link {
                name: "1 slide".into(),
                joint: prismatic("X"),
                translation: Vector3::new(0.0, 0.0, 0.0),
                rotation: to_next,
                inertial: None,
            },
            Link {
                name: "2 column".into(),
                joint: prismatic("Y"),
                translation: Vector3::zeros(),
                rotation: to_next,
                inertial: None,
            },
            Link {
                name: "3 spindle".into(),
                joint: prismatic("Z"),
                translation: Vector3::new(0.0, 0.0, -50.0),
                rotation: Matrix3::identity(),
                inertial: None,
            },
        ],
    }
}

#[test]
fn zero_deviations_give_the_nominal_pose_and_each_kind_moves_the_tool_as_expected() {
    let c = xyz_chain();
    let q = [10.0, 20.0, 30.0];
    let t = c.pose(&q, &[], &[]).unwrap();
    let t0 = c
        .pose(&q, &[0.0; 3], &vec![LinkDeviation::default(); 4])
        .unwrap();
    assert_eq!(t, t0);
    // Hand construction: the slides move along world X, Y, Z.
    let p = t.fixed_view::<3, 1>(0, 3).into_owned();
    let p_home = c
        .pose(&[0.0; 3], &[], &[])
        .unwrap()
        .fixed_view::<3, 1>(0, 3)
        .into_owned();
    assert!(
        (p - p_home - Vector3::new(10.0, 20.0, 30.0)).amax() < 1e-12,
        "{p} {p_home}"
    );
    // A positioning deviation dq of the Y axis moves the tool by dq along Y.
    let t1 = c.pose(&q, &[0.0, 0.01, 0.0], &[]).unwrap();
    let d = (t1 - t).fixed_view::<3, 1>(0, 3).into_owned();
    assert!((d - Vector3::new(0.0, 0.01, 0.0)).amax() < 1e-12);
    // A linear deviation delta_z of link 1 (along its Z*, world X after the bed turn)
    // moves the tool by the same amount along world X... through link 1's S_1 frame.
    let mut dev = vec![LinkDeviation::default(); 4];
    dev[1].delta = Vector3::new(0.0, 0.0, 0.02);
    let t2 = c.pose(&q, &[], &dev).unwrap();
    let d = (t2 - t).fixed_view::<3, 1>(0, 3).into_owned();
    // S_1 axes in world: the bed's block maps S_0* (= S_1 at q) z to world X.
    assert!((d - Vector3::new(0.02, 0.0, 0.0)).amax() < 1e-12, "{d}");
    // A small angular deviation (a consistent rotation by e about its own X*) of link
    // 2 turns everything after S_2*: the tool, 30 - 50 = -20 mm along S_2* Z from its
    // origin, moves by 20 e. (An angular deviation of the last link turns the tool
    // frame only: the tool point is that frame's origin.)
    let e = 1e-4;
    let nominal = c.links[2].rotation;
    let rot = nominal * small_rotation([e, 0.0, 0.0]);
    let phi = c.links[2].angles();
    dev = vec![LinkDeviation::default(); 4];
    dev[2].alpha = Matrix3::from_fn(|r, k| rot[(r, k)].clamp(-1.0, 1.0).acos() - phi[(r, k)]);
    let t3 = c.pose(&q, &[], &dev).unwrap();
    let d = (t3 - t).fixed_view::<3, 1>(0, 3).into_owned();
    assert!((d.norm() - 20.0 * e).abs() < 1e-9, "{d}");
    let mut dev3 = vec![LinkDeviation::default(); 4];
    dev3[3].alpha = dev[2].alpha;
    let t4 = c.pose(&q, &[], &dev3).unwrap();
    assert!((t4 - t).fixed_view::<3, 1>(0, 3).amax() < 1e-15);
    assert!((t4 - t).fixed_view::<3, 3>(0, 0).amax() > 0.5 * e);
}

fn revolute(name: &str) -> Option<Joint> {
    Some(Joint {
        name: name.into(),
        kind: JointKind::Revolute,
        range: Range {
            min: -3.2,
            max: 3.2,
        },
        max_velocity: None,
        max_acceleration: None,
        stiffness: None,
    })
}

/// A 5-axis machine like seed 003's MC-300: tool chain X, Y, Z; workpiece chain B, C.
fn five_axis() -> pkm::serial::machine::SerialMachine {
    let to_y = Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0); // z* = world Y
    let back = to_y.transpose();
    pkm::serial::machine::SerialMachine {
        name: "5-axis".into(),
        tool: xyz_chain(),
        workpiece: Some(Chain {
            name: "workpiece".into(),
            links: vec![
                Link {
                    name: "table mount".into(),
                    joint: None,
                    translation: Vector3::new(0.0, 0.0, -200.0),
                    rotation: to_y,
                    inertial: None,
                },
                Link {
                    name: "4 tilting table".into(),
                    joint: revolute("B"),
                    translation: Vector3::new(0.0, 80.0, 0.0),
                    rotation: back,
                    inertial: None,
                },
                Link {
                    name: "5 face plate".into(),
                    joint: revolute("C"),
                    translation: Vector3::new(0.0, 0.0, 40.0),
                    rotation: Matrix3::identity(),
                    inertial: None,
                },
            ],
        }),
    }
}

#[test]
fn sensitivities_equal_central_differences() {
    use pkm::serial::machine::{ChainDeviations, Parameter};
    let m = five_axis();
    let (qt, qw) = ([35.0, -20.0, 60.0], [0.4, -1.1]);
    // A deviated state (derivatives are checked there, not only at nominal).
    let mut dev = vec![
        ChainDeviations {
            links: vec![LinkDeviation::default(); 4],
            dq: vec![0.01, -0.02, 0.005],
            ..Default::default()
        },
        ChainDeviations {
            links: vec![LinkDeviation::default(); 3],
            dq: vec![1e-4, -2e-4],
            ..Default::default()
        },
    ];
    for (c, d) in dev.iter_mut().enumerate() {
        for (l, ld) in d.links.iter_mut().enumerate() {
            ld.delta = Vector3::new(0.01 * (l + 1) as f64, -0.02, 0.005 * c as f64);
            ld.alpha = Matrix3::from_fn(|r, k| 1e-4 * ((r * 3 + k + l) % 5) as f64 - 2e-4);
        }
    }
    let params = m.all_parameters();
    assert_eq!(params.len(), 4 * 12 + 3 + 3 * 12 + 2 + 3);
    let s = m.sensitivities(&qt, &qw, &dev, &params).unwrap();
    let perturb = |p: &Parameter, h: f64| {
        let mut d = dev.clone();
        match *p {
            Parameter::Delta { chain, link, axis } => d[chain].links[link].delta[axis] += h,
            Parameter::Alpha {
                chain,
                link,
                row,
                col,
            } => d[chain].links[link].alpha[(row, col)] += h,
            Parameter::Dq { chain, joint } => d[chain].dq[joint] += h,
            Parameter::Installation { axis } => d[0].installation[axis] += h,
        }
        m.pose(&qt, &qw, &d).unwrap()
    };
    let t0 = m.pose(&qt, &qw, &dev).unwrap();
    let r0 = t0.fixed_view::<3, 3>(0, 0).into_owned();
    for (p, (dp, w)) in params.iter().zip(&s) {
        let h = 1e-6;
        let (a, b) = (perturb(p, h), perturb(p, -h));
        let fd = (a - b) / (2.0 * h);
        let fdp = fd.fixed_view::<3, 1>(0, 3).into_owned();
        let dr = fd.fixed_view::<3, 3>(0, 0) * r0.transpose();
        let fdw = Vector3::new(
            0.5 * (dr[(2, 1)] - dr[(1, 2)]),
            0.5 * (dr[(0, 2)] - dr[(2, 0)]),
            0.5 * (dr[(1, 0)] - dr[(0, 1)]),
        );
        let name = m.parameter_name(p);
        assert!(
            (dp - fdp).amax() <= 1e-6 * fdp.amax().max(1.0),
            "{name}: {dp} vs {fdp}"
        );
        assert!(
            (w - fdw).amax() <= 1e-6 * fdw.amax().max(1.0),
            "{name}: {w} vs {fdw}"
        );
    }
    // Names in seed 003's notation.
    assert_eq!(m.parameter_name(&params[0]), "delta_x(bed)");
    assert!(params
        .iter()
        .any(|p| m.parameter_name(p) == "alpha_xz(4 tilting table)"));
    assert!(params.iter().any(|p| m.parameter_name(p) == "dq(C)"));
    // A positioning deviation of X moves the tool 1:1 along the workpiece's frame X
    // at B = C = 0.
    let s0 = m
        .sensitivities(
            &qt,
            &[0.0, 0.0],
            &[],
            &[Parameter::Dq { chain: 0, joint: 0 }],
        )
        .unwrap();
    assert!((s0[0].0.norm() - 1.0).abs() < 1e-12 && s0[0].1.norm() < 1e-12);
}

#[test]
fn monte_carlo_converges_to_the_first_order_prediction() {
    use pkm::accuracy::{budget, monte_carlo, Distribution, Tolerance};
    use pkm::serial::machine::Parameter;
    let m = five_axis();
    let (qt, qw) = ([35.0, -20.0, 60.0], [0.4, -1.1]);
    // The generic engine runs on the machine as a joint-space mechanism; its
    // parameters are `all_parameters()` in order.
    let mech = pkm::serial::mechanism::SerialMechanism::<5>::new(
        m.clone(),
        nalgebra::SVector::<f64, 5>::from_column_slice(&[qt[0], qt[1], qt[2], qw[0], qw[1]]),
    )
    .unwrap();
    let x = mech.info().home();
    let all = m.all_parameters();
    let tol: Vec<Tolerance> = all
        .iter()
        .enumerate()
        .map(|(i, p)| Tolerance {
            parameter: i,
            value: match p {
                Parameter::Alpha { .. } => 2e-5,
                _ => 5e-3,
            },
            distribution: if i % 2 == 0 {
                Distribution::Uniform
            } else {
                Distribution::Normal
            },
        })
        .collect();
    let s = m.sensitivities(&qt, &qw, &[], &all).unwrap();
    let mut var = Vector3::zeros();
    for (t, (dp, _)) in tol.iter().zip(&s) {
        var += dp.component_mul(dp) * t.std().powi(2);
    }
    let predicted = var.map(f64::sqrt);
    let n = 40_000;
    let mc = monte_carlo(&mech, &x, &tol, n, 7).unwrap();
    for k in 0..3 {
        let rel = mc.std_vector[k] / predicted[k] - 1.0;
        assert!(
            rel.abs() < 0.03,
            "component {k}: {} vs {}",
            mc.std_vector[k],
            predicted[k]
        );
        assert!(mc.mean_vector[k].abs() < 4.0 * predicted[k] / (n as f64).sqrt() + 1e-9);
    }
    assert!(mc.p95 <= mc.p99 && mc.p99 <= mc.max && mc.mean > 0.0);
    assert_eq!(mc.histogram.iter().map(|h| h.1).sum::<usize>(), n);
    // Seeded: the same result again.
    assert_eq!(
        monte_carlo(&mech, &x, &tol, 5000, 7).unwrap(),
        monte_carlo(&mech, &x, &tol, 5000, 7).unwrap()
    );
    // Budget: each item is |dp/dd| times its tolerance, from the chain's own
    // sensitivities computed above; sorted; worst case and RSS of the items.
    let b = budget(&mech, &x, &tol).unwrap();
    assert_eq!(b.items.len(), tol.len());
    for (t, (dp, w)) in tol.iter().zip(&s) {
        let item = b
            .items
            .iter()
            .find(|i| i.name == m.parameter_name(&all[t.parameter]))
            .unwrap();
        assert!(
            (item.position - dp.norm() * t.value).abs() < 1e-15,
            "{}",
            item.name
        );
        assert!(
            (item.orientation - w.norm() * t.value).abs() < 1e-15,
            "{}",
            item.name
        );
    }
    assert!(b.items.windows(2).all(|w| w[0].position >= w[1].position));
    let sum: f64 = b.items.iter().map(|i| i.position).sum();
    assert!((b.worst_case - sum).abs() < 1e-15);
    let dq_x = b.items.iter().find(|i| i.name == "dq(X)").unwrap();
    assert!((dq_x.position - 5e-3).abs() < 1e-12, "{}", dq_x.position);
}

#[test]
fn prepared_chain_equals_the_general_pose() {
    use pkm::serial::PreparedChain;
    // A 6R arm with deviations on every link.
    let links: Vec<Link> = (0..7)
        .map(|i| Link {
            name: format!("{i}"),
            joint: if i == 0 {
                None
            } else {
                revolute(&format!("A{i}"))
            },
            translation: Vector3::new(10.0 * i as f64, -5.0, 100.0 + 20.0 * i as f64),
            rotation: if i % 2 == 0 {
                Matrix3::identity()
            } else {
                Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0)
            },
            inertial: None,
        })
        .collect();
    let c = Chain {
        name: "arm".into(),
        links,
    };
    let dev: Vec<LinkDeviation> = (0..7)
        .map(|i| LinkDeviation {
            delta: Vector3::new(0.01, -0.02 * i as f64, 0.003),
            alpha: Matrix3::from_fn(|r, k| 1e-4 * ((r + 2 * k + i) % 4) as f64),
            ..Default::default()
        })
        .collect();
    let dq = [1e-3, -2e-3, 5e-4, 0.0, 1e-4, -1e-4];
    let p = PreparedChain::new(&c, &dq, &dev);
    for k in 0..20 {
        let q: Vec<f64> = (0..6).map(|j| 0.3 * (k as f64) - 0.7 * j as f64).collect();
        let a = c.pose(&q, &dq, &dev).unwrap();
        let b = p.pose(&q);
        assert!((a - b).amax() < 1e-12, "{}", (a - b).amax());
    }
}

#[test]
fn dh_table_equals_the_hand_built_product() {
    let m = pkm::Machine::from_path(format!(
        "{}/../../examples/machines/kr30-dh.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let pkm::machine::Model::Serial(s) = &m.model else {
        panic!()
    };
    let chain = &s.mechanism.machine().tool;
    // (a, alpha, d, theta) from the file.
    let dh = [
        (350.0f64, -90.0f64, 815.0f64, 0.0f64),
        (850.0, 0.0, 0.0, -90.0),
        (145.0, -90.0, 0.0, 0.0),
        (0.0, 90.0, 820.0, 0.0),
        (0.0, -90.0, 0.0, 0.0),
        (0.0, 0.0, 170.0, 0.0),
    ];
    for k in 0..50 {
        let q: Vec<f64> = (0..6)
            .map(|j| ((k * 7 + j * 3) % 11) as f64 * 0.3 - 1.5)
            .collect();
        let mut t = Matrix4::identity();
        for (j, (a, al, d, th)) in dh.iter().enumerate() {
            t = t
                * rz4(q[j] + f64::to_radians(*th))
                * tr4(0.0, 0.0, *d)
                * tr4(*a, 0.0, 0.0)
                * rx4(f64::to_radians(*al));
        }
        t *= tr4(0.0, 0.0, 100.0); // dh_tool
        let p = chain.pose(&q, &[], &[]).unwrap();
        assert!((p - t).amax() < 1e-9, "{k}: {}", (p - t).amax());
    }
    // Zero is the home posture: upper arm up, forearm forward.
    let p = chain.pose(&[0.0; 6], &[], &[]).unwrap();
    assert!((p[(0, 3)] - 1440.0).abs() < 1e-9 && (p[(2, 3)] - 1810.0).abs() < 1e-9);
}

fn kr30() -> pkm::serial::machine::SerialMachine {
    let m = pkm::Machine::from_path(format!(
        "{}/../../examples/machines/kr30-dh.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let pkm::machine::Model::Serial(s) = &m.model else {
        panic!()
    };
    s.mechanism.machine().clone()
}

#[test]
fn tool_jacobian_equals_finite_differences() {
    let m = kr30();
    for k in 0..20 {
        let q: Vec<f64> = (0..6)
            .map(|j| ((k * 5 + j * 7) % 13) as f64 * 0.2 - 1.2)
            .collect();
        let j = m.tool_jacobian(&q, &[]).unwrap();
        let t0 = m.pose(&q, &[], &[]).unwrap();
        let r0 = t0.fixed_view::<3, 3>(0, 0).into_owned();
        for c in 0..6 {
            let h = 1e-7;
            let mut qp = q.clone();
            let mut qm = q.clone();
            qp[c] += h;
            qm[c] -= h;
            let fd = (m.pose(&qp, &[], &[]).unwrap() - m.pose(&qm, &[], &[]).unwrap()) / (2.0 * h);
            let dr = fd.fixed_view::<3, 3>(0, 0) * r0.transpose();
            let w = Vector3::new(dr[(2, 1)], dr[(0, 2)], dr[(1, 0)]);
            for r in 0..3 {
                assert!(
                    (j[(r, c)] - fd[(r, 3)]).abs()
                        < 1e-5 * fd.fixed_view::<3, 1>(0, 3).amax().max(1.0),
                    "{k} {c}"
                );
                assert!((j[(r + 3, c)] - w[r]).abs() < 1e-6, "{k} {c}");
            }
        }
    }
}

#[test]
fn urdf_import_equals_the_hand_built_chain() {
    let m = pkm::Machine::from_path(format!(
        "{}/../../examples/robots/ur5-like.urdf",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let pkm::machine::Model::Serial(s) = &m.model else {
        panic!()
    };
    let sm = s.mechanism.machine();
    assert_eq!(sm.tool.dof(), 6);
    // Standard DH of the same arm in mm: (a, alpha, d).
    let dh = [
        (0.0f64, std::f64::consts::FRAC_PI_2, 89.159f64),
        (-425.0, 0.0, 0.0),
        (-392.25, 0.0, 0.0),
        (0.0, std::f64::consts::FRAC_PI_2, 109.15),
        (0.0, -std::f64::consts::FRAC_PI_2, 94.65),
        (0.0, 0.0, 82.3),
    ];
    for k in 0..50 {
        let q: Vec<f64> = (0..6)
            .map(|j| ((k * 3 + j * 5) % 9) as f64 * 0.5 - 2.0)
            .collect();
        let mut t = Matrix4::identity();
        for (j, (a, al, d)) in dh.iter().enumerate() {
            // The URDF writes joint 2 about -Y with rotated origins: the same motion
            // as DH's joint 2 about its Z.
            t = t * rz4(q[j]) * tr4(0.0, 0.0, *d) * tr4(*a, 0.0, 0.0) * rx4(*al);
        }
        let p = sm.pose(&q, &[], &[]).unwrap();
        assert!((p - t).amax() < 1e-9, "{k}: {}", (p - t).amax());
    }
    // Limits converted, names kept; the tool Jacobian equals differences there too.
    let j = sm.tool.joints().nth(2).unwrap();
    assert_eq!(j.name, "elbow");
    // The file says 3.1416 (rad): 180 deg rounded to its four decimals, read as 180.
    assert!((j.range.max.to_degrees() - 180.0).abs() < 1e-12);
    let written: f64 = "3.1416".parse().unwrap();
    assert!((j.range.max - written).abs() < 0.5e-4);
    let q = [0.3, -0.8, 1.2, -0.4, 0.9, 0.2];
    let jac = sm.tool_jacobian(&q, &[]).unwrap();
    let h = 1e-7;
    for c in 0..6 {
        let mut qp = q.to_vec();
        let mut qm = q.to_vec();
        qp[c] += h;
        qm[c] -= h;
        let fd = (sm.pose(&qp, &[], &[]).unwrap() - sm.pose(&qm, &[], &[]).unwrap()) / (2.0 * h);
        for r in 0..3 {
            assert!((jac[(r, c)] - fd[(r, 3)]).abs() < 1e-4, "{c}");
        }
    }
}

#[test]
fn prepared_jacobian_equals_the_tool_jacobian() {
    use pkm::serial::PreparedChain;
    let m = kr30();
    let p = PreparedChain::new(&m.tool, &[], &[]);
    for k in 0..20 {
        let q: [f64; 6] = std::array::from_fn(|j| ((k * 5 + j * 3) % 11) as f64 * 0.3 - 1.4);
        let (t, j) = p.jacobian(&q);
        let reference = m.tool_jacobian(&q, &[]).unwrap();
        assert!((t - m.pose(&q, &[], &[]).unwrap()).amax() < 1e-9);
        for r in 0..6 {
            for c in 0..6 {
                assert!(
                    (j[(r, c)] - reference[(r, c)]).abs() < 1e-9,
                    "{k} ({r},{c})"
                );
            }
        }
    }
}

#[test]
fn installation_angles_cancel_relative_to_the_part_and_turn_a_robot_about_the_world() {
    use pkm::serial::deviations::{deviations_from, pose_error};
    use pkm::serial::machine::{ChainDeviations, Parameter};
    // Two chains: the installation turns both alike, the tool relative to the part
    // does not move (exactly zero sensitivity, and no change of the exact pose).
    let m = five_axis();
    let (qt, qw) = ([35.0, -20.0, 60.0], [0.4, -1.1]);
    let inst: Vec<Parameter> = (0..3)
        .map(|axis| Parameter::Installation { axis })
        .collect();
    let names: Vec<String> = inst.iter().map(|p| m.parameter_name(p)).collect();
    assert_eq!(names, ["theta_x0", "theta_y0", "theta_z0"]);
    assert_eq!(m.parameter_by_name("theta_z0"), Ok(inst[2]));
    for (dp, w) in m.sensitivities(&qt, &qw, &[], &inst).unwrap() {
        assert_eq!((dp.norm(), w.norm()), (0.0, 0.0));
    }
    let d = deviations_from(&m, &[(inst[0], 0.01), (inst[2], -0.02)]);
    let (dp, dw) = pose_error(&m, &qt, &qw, &d).unwrap();
    assert_eq!((dp.norm(), dw.norm()), (0.0, 0.0));
    // A robot (no workpiece chain): theta_z0 turns the tool point about the world Z:
    // dp = e_z x p, exactly in the sensitivities, to first order in the exact pose;
    // checked against central differences at a tilted installation.
    let r = kr30();
    let q = [0.3, 0.2, -0.4, 0.5, 1.0, -0.3];
    let t = r.pose(&q, &[], &[]).unwrap();
    let s = r.sensitivities(&q, &[], &[], &inst).unwrap();
    let p = nalgebra::Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]);
    assert!((s[2].0 - nalgebra::Vector3::z().cross(&p)).norm() < 1e-9);
    let base = ChainDeviations {
        installation: nalgebra::Vector3::new(0.02, -0.01, 0.03),
        ..Default::default()
    };
    let s = r
        .sensitivities(&q, &[], std::slice::from_ref(&base), &inst)
        .unwrap();
    let t0 = r.pose(&q, &[], std::slice::from_ref(&base)).unwrap();
    for (axis, (dp, w)) in s.iter().enumerate() {
        let h = 1e-6;
        let at = |v: f64| {
            let mut d = base.clone();
            d.installation[axis] += v;
            r.pose(&q, &[], &[d]).unwrap()
        };
        let fd = (at(h) - at(-h)) / (2.0 * h);
        let fdp = fd.fixed_view::<3, 1>(0, 3).into_owned();
        let dr = fd.fixed_view::<3, 3>(0, 0) * t0.fixed_view::<3, 3>(0, 0).transpose();
        let fdw = Vector3::new(dr[(2, 1)], dr[(0, 2)], dr[(1, 0)]);
        assert!((dp - fdp).amax() < 1e-6 * fdp.amax(), "{axis}: {dp} {fdp}");
        assert!((w - fdw).amax() < 1e-8, "{axis}: {w} {fdw}");
    }
}

/// The chain's pose by the book: the 4 x 4 product of eq. 4's joint transforms and
/// eq. 2's link transforms with all nine `cos(phi + alpha)`, written out here.
fn pose_by_the_book(c: &Chain, q: &[f64], dq: &[f64], dev: &[LinkDeviation]) -> Matrix4<f64> {
    let mut t = Matrix4::identity();
    let mut k = 0;
    for (link, d) in c.links.iter().zip(dev) {
        if let Some(j) = &link.joint {
            let v = q[k] + dq[k];
            t *= match j.kind {
                JointKind::Revolute => rz4(v),
                JointKind::Prismatic => tr4(0.0, 0.0, v),
            };
            k += 1;
        }
        let phi = link.rotation.map(|x| x.clamp(-1.0, 1.0).acos());
        let mut a = Matrix4::identity();
        for r in 0..3 {
            for col in 0..3 {
                a[(r, col)] = (phi[(r, col)] + d.alpha[(r, col)]).cos();
            }
            a[(r, 3)] = link.translation[r] + d.delta[r];
        }
        t *= a;
    }
    t
}

proptest::proptest! {
    /// `Chain::pose` (affine products, joints as column operations, only deviated
    /// entries through `acos`/`cos`) is the book's product of 4 x 4 transforms, for any
    /// joints and any sparse or dense deviations, on both chains of a 5-axis machine.
    #[test]
    fn chain_pose_is_the_product_of_the_transforms(
        q in proptest::collection::vec(-3.0f64..3.0, 3),
        dq in proptest::collection::vec(-0.01f64..0.01, 3),
        alpha in proptest::collection::vec(
            proptest::prop_oneof![proptest::strategy::Just(0.0), -2e-3f64..2e-3], 36),
        delta in proptest::collection::vec(-0.05f64..0.05, 12),
    ) {
        let m = five_axis();
        for c in [&m.tool, m.workpiece.as_ref().unwrap()] {
            let n = c.dof();
            let q: Vec<f64> = q[..n].iter().map(|x| x * 40.0).collect();
            let dev: Vec<LinkDeviation> = (0..c.links.len())
                .map(|i| LinkDeviation {
                    delta: Vector3::from_column_slice(&delta[3 * i..3 * i + 3]),
                    alpha: Matrix3::from_column_slice(&alpha[9 * i..9 * i + 9]),
                    block: None,
                })
                .collect();
            let fast = c.pose(&q, &dq[..n], &dev).unwrap();
            let book = pose_by_the_book(c, &q, &dq[..n], &dev);
            // Rounding only: translations of some 100 mm, blocks of unit size.
            let err = (fast - book).abs();
            proptest::prop_assert!(err.fixed_view::<3, 3>(0, 0).max() < 1e-13, "{fast} {book}");
            proptest::prop_assert!(err.fixed_view::<3, 1>(0, 3).max() < 1e-10, "{fast} {book}");
        }
    }
}

/// The deviated block without `acos` equals the paper's `cos(acos(c) + alpha)` entry
/// by entry within 1e-15 (the paper form's own roundings: `acos`, the sum, `cos`; plus
/// the `acos`'s ill-conditioning near `c = +-1`): random
/// rotations, the identity and permutations, deviations from 1e-9 to 0.3 rad, sparse
/// ones (undeviated entries exactly the nominal ones).
#[test]
fn deviated_block_equals_the_acos_cos_form() {
    use pkm::serial::deviated_block;
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(31);
    let mut worst: f64 = 0.0;
    for case in 0..20_000 {
        let rotation = match case % 4 {
            0 => Matrix3::identity(),
            1 => Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0),
            _ => small_rotation([
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
            ]),
        };
        let scale = 10f64.powf(rng.random_range(-9.0..-0.5));
        let alpha = Matrix3::from_fn(|_, _| {
            if rng.random_bool(0.3) {
                0.0
            } else {
                scale * rng.random_range(-1.0..1.0)
            }
        });
        let link = Link {
            name: "l".into(),
            joint: None,
            translation: Vector3::zeros(),
            rotation,
            inertial: None,
        };
        let dev = LinkDeviation {
            alpha,
            ..Default::default()
        };
        let b = deviated_block(&link, &dev);
        for k in 0..9 {
            let c = rotation[k];
            if alpha[k] == 0.0 {
                assert_eq!(b[k].to_bits(), c.to_bits(), "undeviated entry {k} changed");
                continue;
            }
            let phi = c.clamp(-1.0, 1.0).acos();
            let paper = (phi + alpha[k]).cos();
            // acos is ill-conditioned near +-1: its rounding moves the paper's value by
            // up to eps |alpha| / sqrt(1 - c^2).
            let slack = f64::EPSILON * alpha[k].abs() / (1.0 - c * c).max(1e-300).sqrt();
            let d = (b[k] - paper).abs() - slack.min(1.0);
            worst = worst.max(d);
            assert!(d <= 1e-15, "case {case} entry {k}: {} vs {paper}", b[k]);
        }
    }
    eprintln!("worst difference beyond the acos rounding: {worst:e}");
}

/// `J' q'` in closed form equals the derivative of the geometric Jacobian along `q'`
/// by central differences (Richardson-extrapolated: error O(h^4) plus rounding), on
/// the KR 30's arm, a chain of skew turns and slides, and a 5-axis machine's tilting
/// table, at random joints and rates.
#[test]
fn jacobian_rate_equals_central_differences_of_the_jacobian() {
    use pkm::serial::{jacobian_of_axes, jacobian_rate_times_rates, PreparedChain};
    use rand::{Rng, SeedableRng};

    fn check<const N: usize>(c: &Chain, rng: &mut rand::rngs::StdRng) -> f64 {
        let pc = PreparedChain::new(c, &[], &[]);
        let jac = |q: &[f64; N]| {
            let (t, axes) = pc.axes::<N>(q);
            let p = Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]);
            (jacobian_of_axes(&p, &axes), p, axes)
        };
        let mut worst: f64 = 0.0;
        for _ in 0..300 {
            let q: [f64; N] = std::array::from_fn(|_| rng.random_range(-2.5..2.5));
            let qd: [f64; N] = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
            let (j, p, axes) = jac(&q);
            let exact = jacobian_rate_times_rates(&p, &axes, &qd);
            let qdv = nalgebra::SVector::<f64, N>::from(qd);
            let d = |h: f64| {
                let at = |s: f64| jac(&std::array::from_fn(|k| q[k] + s * qd[k])).0;
                (at(h) - at(-h)) * qdv / (2.0 * h)
            };
            let h = 1e-3;
            let fd = (d(h / 2.0) * 4.0 - d(h)) / 3.0;
            let scale = j.amax() * qdv.amax() * qdv.amax();
            worst = worst.max((exact - fd).amax() / scale);
        }
        worst
    }
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let kr = kr30();
    let m = five_axis();
    // Turns and slides alternating, axes skew to each other.
    let joints = [
        None,
        revolute("A1"),
        prismatic("S2"),
        revolute("A3"),
        prismatic("S4"),
        revolute("A5"),
    ];
    let mixed = Chain {
        name: "mixed".into(),
        links: joints
            .into_iter()
            .enumerate()
            .map(|(i, joint)| Link {
                name: format!("{i}"),
                joint,
                translation: Vector3::new(40.0 * i as f64, -25.0, 60.0 + 15.0 * i as f64),
                rotation: small_rotation([0.7 * i as f64, -0.4, 0.9 - 0.3 * i as f64]),
                inertial: None,
            })
            .collect(),
    };
    let errs = [
        check::<6>(&kr.tool, &mut rng),
        check::<5>(&mixed, &mut rng),
        check::<2>(m.workpiece.as_ref().unwrap(), &mut rng),
    ];
    for e in errs {
        assert!(e < 1e-9, "{errs:?}");
    }
}

/// Tool poses of `mech` (joint coordinates) against `SerialMachine::pose` (the walk
/// per call, the workpiece frame inverted as a general 4 x 4 matrix) at random joint
/// values: positions within 1e-12 of the machine's size, rotations within 1e-12.
fn check_joint_space_tool_poses<const N: usize>(
    mech: &pkm::serial::mechanism::SerialMechanism<N>,
    size: f64,
    seed: u64,
) {
    use pkm::Mechanism;
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let nt = mech.machine().tool.dof();
    for _ in 0..2000 {
        let x = nalgebra::SVector::<f64, N>::from_fn(|_, _| rng.random_range(-3.0..3.0));
        let (qt, qw) = x.as_slice().split_at(nt);
        let by_walk = mech.machine().pose(qt, qw, &[]).unwrap();
        let prepared = mech.tool_pose(&x).unwrap().to_homogeneous();
        let dp = (prepared.fixed_view::<3, 1>(0, 3) - by_walk.fixed_view::<3, 1>(0, 3)).amax();
        let dr = (prepared.fixed_view::<3, 3>(0, 0) - by_walk.fixed_view::<3, 3>(0, 0)).amax();
        assert!(dp < 1e-12 * size, "{dp:e} mm at {x:?}");
        assert!(dr < 1e-12, "{dr:e} at {x:?}");
    }
}

/// A machine in joint coordinates asks its prepared chains for its tool pose (no walk
/// of the link deviations, no allocation): the same pose as the general path, on a
/// 5-axis machine with a workpiece chain and on the KR 30 robot.
#[test]
fn joint_space_tool_poses_equal_the_machines_pose() {
    use pkm::serial::mechanism::SerialMechanism;
    let five = SerialMechanism::<5>::new(five_axis(), nalgebra::SVector::zeros()).unwrap();
    assert!(five.machine().workpiece.is_some());
    check_joint_space_tool_poses(&five, 300.0, 1);
    let kr30 = crate::common::example("kr30-dh.toml");
    let pkm::machine::Model::Serial(s) = &kr30.model else {
        panic!("the KR 30 is a serial machine")
    };
    let robot =
        SerialMechanism::<6>::new(s.mechanism.machine().clone(), nalgebra::SVector::zeros())
            .unwrap();
    check_joint_space_tool_poses(&robot, 2000.0, 2);
    // Any value without panicking (the batches read arrays a caller may fill with
    // anything): a pose or an error, NaN where the input is.
    use pkm::Mechanism;
    for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300, -1e300] {
        for k in 0..6 {
            let mut x = nalgebra::SVector::<f64, 6>::zeros();
            x[k] = v;
            if let Ok(p) = robot.tool_pose(&x) {
                let h = p.to_homogeneous();
                assert!(h.iter().all(|e| e.is_finite()) || h.iter().any(|e| e.is_nan()));
            }
        }
    }
}
