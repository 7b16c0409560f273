//! Joint clearances of the P3RP head and the hybrid machine (seed 004's machines with
//! seed 002's model): the three hinges moved, the planar loop solved again, checked
//! against a hand construction of the loop.

use nalgebra::{Vector2, Vector3};
use pkm::accuracy::Rebuild;
use pkm::analysis::clearance::{clearance, ClearanceRequest};
use pkm::machine::Model;
use pkm::p3rp::P3rpHead;
use pkm::{Machine, Mechanism};

fn example(name: &str) -> String {
    format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn head() -> P3rpHead {
    match Machine::from_path(example("p3rp-seed004.toml"))
        .unwrap()
        .model
    {
        Model::P3rpHead(h) => *h,
        _ => panic!(),
    }
}

/// Rotation about X by `t` in the (Y, Z) plane.
fn turn(t: f64, v: Vector2<f64>) -> Vector2<f64> {
    let (s, c) = t.sin_cos();
    Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// The tool tip (Y, Z) of the head with readings `q` and hinges moved by `da`, `db`,
/// `dc` ((y, z) in their bodies' frames), built point by point: A on slider D, C on
/// slider E, B on the platform turned by theta about A, `|BC| = l2` solved for theta
/// by bisection near `theta0` (independent of pkm's closed form).
fn by_hand(
    h: &P3rpHead,
    q: Vector2<f64>,
    theta0: f64,
    da: Vector2<f64>,
    db: Vector2<f64>,
    dc: Vector2<f64>,
) -> Vector2<f64> {
    let g = &h.geometry();
    let a = Vector2::new(0.0, q[0]) + da;
    let c = Vector2::new(g.e, q[1]) + dc;
    let ab = Vector2::new(-g.l1 * g.delta.sin(), g.l1 * g.delta.cos()) + db;
    let f = |t: f64| (a + turn(t, ab) - c).norm() - g.l2;
    let (mut lo, mut hi) = (theta0 - 0.05, theta0 + 0.05);
    assert!(f(lo) * f(hi) < 0.0, "no root bracketed");
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(lo) * f(mid) <= 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let t = 0.5 * (lo + hi);
    a + turn(t, Vector2::new(0.0, -g.tool_length))
}

#[test]
fn moved_hinges_solve_as_the_loop_built_by_hand() {
    let h = head();
    assert_eq!(h.passive_joints().len(), 3);
    let x = Vector2::new(h.info().home()[0] + 20.0, 0.6);
    let q = h.inverse(&x).unwrap();
    let nominal = h.tool_pose(&x).unwrap().translation.vector;
    let g0 = h.geometry_values();
    // Each hinge alone, then all three, by 0.1 mm-scale displacements.
    let cases = [
        ([0.05, -0.03], [0.0, 0.0], [0.0, 0.0]),
        ([0.0, 0.0], [0.04, 0.07], [0.0, 0.0]),
        ([0.0, 0.0], [0.0, 0.0], [-0.06, 0.02]),
        ([0.03, 0.01], [-0.02, 0.05], [0.04, -0.05]),
    ];
    for (da, db, dc) in cases {
        let mut g = g0.clone();
        for (k, d) in [da, db, dc].iter().enumerate() {
            g[5 + 3 * k + 1] = d[0];
            g[5 + 3 * k + 2] = d[1];
        }
        let moved = h.with_geometry_values(&g).unwrap();
        let f = moved.forward(&q, &x).unwrap();
        let tip = moved.tool_pose(&f.pose).unwrap().translation.vector;
        let want = by_hand(
            &h,
            q,
            x[1],
            Vector2::from(da),
            Vector2::from(db),
            Vector2::from(dc),
        );
        assert!(tip.x.abs() < 1e-15);
        assert!(
            (Vector2::new(tip.y, tip.z) - want).norm() < 1e-9,
            "{da:?} {db:?} {dc:?}: {tip} vs {want}"
        );
        assert!((tip - nominal).norm() > 1e-3, "the hinges moved the tool");
    }
    // A shift along a hinge's own axis moves nothing of the planar head.
    let mut g = g0.clone();
    g[5] = 0.1;
    g[8] = 0.1;
    g[11] = 0.1;
    let moved = h.with_geometry_values(&g).unwrap();
    let f = moved.forward(&q, &x).unwrap();
    assert!((moved.tool_pose(&f.pose).unwrap().translation.vector - nominal).norm() < 1e-12);
}

#[test]
fn head_bounds_are_proportional_contain_the_monte_carlo_and_reproduce_by_hand() {
    let m = Machine::from_path(example("p3rp-seed004.toml")).unwrap();
    let h = head();
    let x = Vector2::new(h.info().home()[0] + 20.0, 0.6);
    let n = Vector3::new(0.0, 0.6f64.sin(), -0.6f64.cos());
    let req = |c: f64| ClearanceRequest {
        diametral: Some(c),
        options: pkm::accuracy::clearance::ClearanceOptions {
            direction: Some(n),
            ..Default::default()
        },
        monte_carlo: Some(20_000),
        ..Default::default()
    };
    let zero = clearance(&m, Some(x.as_slice()), &req(0.0)).unwrap();
    assert_eq!((zero.bounds.upper, zero.bounds.lower), (0.0, 0.0));
    let a = clearance(&m, Some(x.as_slice()), &req(0.02)).unwrap();
    let b = clearance(&m, Some(x.as_slice()), &req(0.04)).unwrap();
    assert!(a.bounds.upper > 1e-3);
    assert!((b.bounds.upper / a.bounds.upper - 2.0).abs() < 0.04);
    assert!((b.bounds.lower / a.bounds.lower - 2.0).abs() < 0.04);
    let mc = a.monte_carlo.as_ref().unwrap();
    assert!(mc.max <= a.bounds.upper + 1e-12 && mc.min >= a.bounds.lower - 1e-12);
    // The worst states, applied to the loop built by hand, give `upper`.
    let q = h.inverse(&x).unwrap();
    let nominal = h.tool_pose(&x).unwrap().translation.vector;
    let s = &a.bounds.worst_joint_states.upper;
    let d = |j: &str| {
        let st = s.iter().find(|w| w.joint == j).unwrap();
        Vector2::new(st.displacement[1], st.displacement[2])
    };
    let tip = by_hand(&h, q, x[1], d("A"), d("B"), d("C"));
    let e = Vector3::new(0.0, tip.x - nominal.y, tip.y - nominal.z);
    assert!(
        (n.dot(&e) - a.bounds.upper).abs() < 1e-9,
        "{} vs {}",
        n.dot(&e),
        a.bounds.upper
    );
}

#[test]
fn the_hybrid_machine_moves_the_tool_as_its_head_does() {
    // The table holds the part: a hinge moved in the hybrid machine's head moves the
    // tool relative to the part exactly as it moves the head's tool.
    let m = Machine::from_path(example("p3rp-hybrid-seed004.toml")).unwrap();
    let Model::P3rpHybrid(hy) = &m.model else {
        panic!()
    };
    let h = hy.head_mechanism();
    let x = hy.info().home();
    let xh = h.info().home();
    let mut g = hy.geometry_values();
    for (k, v) in [(6, 0.05), (7, -0.02), (9, 0.03), (13, 0.04)] {
        g[k] = v;
    }
    let moved = hy.with_geometry_values(&g).unwrap();
    let f = moved.forward(&hy.inverse(&x).unwrap(), &x).unwrap();
    let dp = moved.tool_pose(&f.pose).unwrap().translation.vector
        - hy.tool_pose(&x).unwrap().translation.vector;
    let mh = h.with_geometry_values(&g).unwrap();
    let fh = mh.forward(&h.inverse(&xh).unwrap(), &xh).unwrap();
    let dh = mh.tool_pose(&fh.pose).unwrap().translation.vector
        - h.tool_pose(&xh).unwrap().translation.vector;
    assert!(dp.norm() > 0.01);
    assert!((dp - dh).norm() < 1e-12, "{dp} vs {dh}");
    let r = clearance(
        &m,
        None,
        &ClearanceRequest {
            diametral: Some(0.02),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(r.clearances.len(), 3);
    // The hinge parameters are clearance parameters: a default budget leaves them out.
    let kinds: Vec<_> = m.parameters().iter().map(|p| p.kind).collect();
    assert_eq!(
        kinds
            .iter()
            .filter(|k| **k == pkm::accuracy::ParameterKind::Clearance)
            .count(),
        9
    );
}
