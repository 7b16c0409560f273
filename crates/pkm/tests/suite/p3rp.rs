//! The P3RP spindle head and hybrid machine of seed 004.

use std::f64::consts::PI;

use nalgebra::{Vector2, Vector6};
use pkm::machine::Model;
use pkm::motion::{Move, Profile, Runner, Sampling, Segment};
use pkm::p3rp::{Branch, HeadGeometry, HybridMachine, P3rpHead};
use pkm::verify::{jacobian_error, numeric_jacobian};
use pkm::{Error, LimitKind, Machine, Mechanism, Quantity};
use proptest::prelude::*;

fn load(name: &str) -> Machine {
    Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

fn head() -> P3rpHead {
    match load("p3rp-seed004.toml").model {
        Model::P3rpHead(h) => *h,
        _ => panic!("not a head"),
    }
}

fn hybrid() -> HybridMachine {
    match load("p3rp-hybrid-seed004.toml").model {
        Model::P3rpHybrid(h) => *h,
        _ => panic!("not a hybrid machine"),
    }
}

/// The design workspace: z in [200, 520] mm, theta in [0, 1.57] rad.
fn workspace_grid() -> impl Iterator<Item = Vector2<f64>> {
    (0..=16).flat_map(|i| {
        (0..=20).map(move |k| Vector2::new(200.0 + 20.0 * i as f64, 1.57 * k as f64 / 20.0))
    })
}

#[test]
fn hand_construction_closes_the_loop() {
    // A CAD-like construction from the points: |AB| = l1, |BC| = l2, C on the line
    // Y = e, the angle from the spindle axis (vertical at theta = 0, turned by theta)
    // to AB is delta, and C lies above B.
    let h = head();
    let g = &h.geometry();
    for x in workspace_grid() {
        let [a, b, c, tool] = g.points(x[0], x[1]).unwrap();
        let q = h.inverse(&x).unwrap();
        assert!(((b - a).norm() - g.l1).abs() < 1e-9);
        assert!(((c - b).norm() - g.l2).abs() < 1e-9);
        assert!((c.y - g.e).abs() < 1e-12 && (c.z - q[1]).abs() < 1e-12);
        assert!((a.z - q[0]).abs() < 1e-12 && c.z > b.z);
        // Platform axis from A upwards (opposite to the tool), turned by theta.
        let axis = -(tool - a) / g.tool_length;
        let ab = (b - a) / g.l1;
        let ang = (axis.y * ab.z - axis.z * ab.y).atan2(axis.dot(&ab));
        assert!((ang - g.delta).abs() < 1e-9, "{ang} vs {}", g.delta);
    }
}

#[test]
fn round_trip_on_both_branches() {
    let h = head();
    let g = &h.geometry();
    let mut other = 0;
    for x in workspace_grid() {
        let q = h.inverse(&x).unwrap();
        let f = h.forward(&q, &h.info().home()).unwrap();
        assert!((f.pose - x).amax() < 1e-9, "{x:?} -> {:?}", f.pose);
        assert_eq!(f.iterations, 0);
        // The other branch is also an assembly with the same sliders.
        if let Ok(y) = g.forward(q[0], q[1], Branch::Negative) {
            other += 1;
            assert!((h.inverse(&y).unwrap() - q).amax() < 1e-9);
            assert_eq!(g.branch_of(y[1]).unwrap(), Branch::Negative);
            // Starting from a pose on that branch, FK stays on it.
            let f2 = h.forward(&q, &y).unwrap();
            assert!((f2.pose - y).amax() < 1e-9);
        }
    }
    assert!(
        other > 300,
        "the other branch exists over the workspace ({other})"
    );
}

#[test]
fn branch_rule_of_the_paper() {
    let h = head();
    let g = &h.geometry();
    for x in workspace_grid() {
        let q = h.inverse(&x).unwrap();
        let [pos, neg] = g.forward_branches(q[0], q[1]);
        // The kept branch is the one in the design range [0, pi/2]...
        let t = pos.unwrap()[1];
        assert!((-1e-12..=1.5700001).contains(&t));
        assert_eq!(HeadGeometry::paper_branch_rule(t), Some(t));
        // ... and the other branch never is.
        let u = neg.unwrap()[1];
        assert!(!(0.0..=PI / 2.0).contains(&u), "{u}");
        // The literal "pi + theta" correction of an angle <= -pi/2 gives a pose that
        // does not close the loop (the paper's formula must have fixed theta modulo pi).
        if let Some(c) = HeadGeometry::paper_branch_rule(u) {
            if u <= -PI / 2.0 {
                let back = h.inverse(&Vector2::new(x[0], c)).unwrap();
                assert!((back - q).amax() > 1.0, "{c}: {:?} vs {:?}", back, q);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    #[test]
    fn fk_of_ik_is_identity(z in 150.0..600.0f64, theta in -0.5..2.0f64) {
        let h = head();
        let x = Vector2::new(z, theta);
        let q = h.inverse(&x).unwrap();
        let f = h.forward(&q, &h.info().home()).unwrap();
        prop_assert!((f.pose - x).amax() < 1e-9);
        prop_assert!(f.residual < 1e-9);
    }

    #[test]
    fn hybrid_fk_of_ik_is_identity(
        x in -200.0..200.0f64, y in -150.0..150.0f64, z in 0.0..300.0f64, a in 0.0..1.57f64
    ) {
        let m = hybrid();
        let p = Vector6::new(x, y, z, a, 0.0, 0.0);
        let q = m.inverse(&p).unwrap();
        let f = m.forward(&q, &m.info().home()).unwrap();
        prop_assert!((f.pose - p).amax() < 1e-9);
    }
}

#[test]
fn jacobians_equal_finite_differences() {
    let h = head();
    let m = hybrid();
    for x in workspace_grid() {
        assert!(jacobian_error(&h, &x).unwrap() < 1e-6);
        let p = Vector6::new(12.0, -30.0, x[0] - 200.0, x[1], 0.0, 0.0);
        assert!(jacobian_error(&m, &p).unwrap() < 1e-6);
    }
    // J_t' against central differences of J_t along theta(t) = theta0 + w t.
    for x in workspace_grid().step_by(5) {
        let w = 0.7;
        let d = 1e-6;
        let g = &h.geometry();
        let jd =
            (g.jacobian(x[1] + w * d).unwrap() - g.jacobian(x[1] - w * d).unwrap()) / (2.0 * d);
        let an = g.jacobian_derivative(x[1], w).unwrap();
        assert!((jd - an).amax() < 1e-6 * an.amax().max(1.0), "{jd} {an}");
    }
    // g' and g'' against central differences of g.
    let g = &h.geometry();
    for k in 0..=30 {
        let t = -0.3 + 0.07 * k as f64;
        let s = g.separation(t).unwrap();
        let d = 1e-5;
        let (gp, gm) = (g.separation(t + d).unwrap(), g.separation(t - d).unwrap());
        assert!(((gp.g - gm.g) / (2.0 * d) - s.dg).abs() < 1e-6 * s.dg.abs().max(1.0));
        assert!(((gp.dg - gm.dg) / (2.0 * d) - s.ddg).abs() < 1e-6 * s.ddg.abs().max(1.0));
    }
}

/// `q' = J x'` and `q'' = J x'' + J' x'` against central differences of IK along a
/// curve `x(t)` with non-zero rates and accelerations.
fn check_motion<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x0: nalgebra::SVector<f64, P>,
    v: nalgebra::SVector<f64, P>,
    a: nalgebra::SVector<f64, P>,
) {
    let x = |t: f64| x0 + v * t + a * (0.5 * t * t);
    let ik = |t: f64| m.inverse(&x(t)).unwrap();
    let mo = m.actuator_motion(&x0, &v, &a).unwrap();
    let h = 1e-4;
    let qd = (ik(h) - ik(-h)) / (2.0 * h);
    let qdd = (ik(h) - 2.0 * ik(0.0) + ik(-h)) / (h * h);
    assert!((mo.q - ik(0.0)).amax() < 1e-12);
    assert!(
        (mo.qd - qd).amax() < 1e-6 * qd.amax().max(1.0),
        "{mo:?} {qd:?}"
    );
    assert!(
        (mo.qdd - qdd).amax() < 1e-4 * qdd.amax().max(1.0),
        "{mo:?} {qdd:?}"
    );
    // And the Jacobian is the velocity map.
    let j = numeric_jacobian(m, &x0, 1e-4, 1e-6).unwrap();
    assert!((j * v - mo.qd).amax() < 1e-5 * qd.amax().max(1.0));
}

#[test]
fn slider_motion_equals_finite_differences() {
    let h = head();
    let m = hybrid();
    for x in workspace_grid().step_by(7) {
        check_motion(&h, x, Vector2::new(150.0, 1.0), Vector2::new(-1500.0, 10.0));
        let p = Vector6::new(10.0, 20.0, x[0] - 180.0, x[1], 0.0, 0.0);
        check_motion(
            &m,
            p,
            Vector6::new(50.0, -80.0, 150.0, 1.0, 0.0, 0.0),
            Vector6::new(900.0, 300.0, -1500.0, 10.0, 0.0, 0.0),
        );
    }
}

#[test]
fn singular_configuration_q_is_reported_not_returned() {
    let h = head();
    let g = &h.geometry();
    // At Q (rod stretched along the crank) the slider separation is largest.
    let dq = g.singular_separation();
    let err = g.forward(300.0, 300.0 + dq, Branch::Positive).unwrap_err();
    assert!(matches!(err, Error::Singular { .. }), "{err}");
    assert!(h
        .forward(&Vector2::new(300.0, 300.0 + dq), &h.info().home())
        .is_err());
    // Beyond it there is no assembly at all.
    let err = g
        .forward(300.0, 300.0 + dq + 0.01, Branch::Positive)
        .unwrap_err();
    assert!(matches!(err, Error::NotAttainable { .. }), "{err}");
    // Near Q, g' -> 0: the pose is found but the limit check flags the transmission
    // angle, and the conditioning blows up.
    let theta_q = (0..=20000)
        .map(|k| 1.6 + 1e-4 * k as f64)
        .min_by(|a, b| {
            let f = |t: f64| g.transmission_angle(t).unwrap().abs();
            f(*a).total_cmp(&f(*b))
        })
        .unwrap();
    assert!(g.separation(theta_q).unwrap().dg.abs() < 0.1);
    let x = Vector2::new(300.0, theta_q);
    let q = h.inverse(&x).unwrap();
    let mut v = Vec::new();
    h.check_limits(&x, &q, &mut v);
    assert!(v
        .iter()
        .any(|v| v.kind == LimitKind::PassiveJoint && v.limit.starts_with("transmission angle")));
    assert!(h.condition(&x).unwrap() > 1e3);
    // Q lies outside the design workspace, as the paper says.
    assert!(theta_q > 1.57 + 0.3);
}

#[test]
fn limits_name_what_binds() {
    let h = head();
    let mut v = Vec::new();
    let x = Vector2::new(530.0, 0.0);
    h.check_limits(&x, &h.inverse(&x).unwrap(), &mut v);
    let names: Vec<_> = v.iter().map(|v| v.limit.as_str()).collect();
    assert_eq!(names, ["slider U position", "slider V position"]);
    assert!((v[0].excess - 10.0).abs() < 1e-9);
    let x = Vector2::new(300.0, -0.1);
    v.clear();
    h.check_limits(&x, &h.inverse(&x).unwrap(), &mut v);
    assert_eq!(v[0].limit, "hinge A deflection theta");
    assert!((v[0].excess - 0.1f64.to_degrees()).abs() < 1e-9);
    assert_eq!(v[0].unit, Quantity::Angle.unit());
}

#[test]
fn paper_ranges_of_fig4() {
    // Slider ranges over the design z range at theta = 0 and 1.57 rad, from the
    // stroke limits alone: D [200, 518.5] and E [506.5, 825] at 0; D [200, 365] at 1.57.
    let h = head();
    for (theta, d_max, e_min) in [(0.0, 518.5, 506.5), (1.57, 365.0, 660.0)] {
        let ok = |z: f64| {
            let x = Vector2::new(z, theta);
            let mut v = Vec::new();
            h.check_limits(&x, &h.inverse(&x).unwrap(), &mut v);
            v.is_empty()
        };
        let mut z = 200.0;
        while ok(z + 0.01) {
            z += 0.01;
        }
        assert!((z - d_max).abs() < 0.1, "theta {theta}: D max {z}");
        let q = h.inverse(&Vector2::new(200.0, theta)).unwrap();
        assert!((q[1] - e_min).abs() < 0.1, "theta {theta}: E min {}", q[1]);
    }
}

#[test]
fn paper_move_reproduces_slider_v_peaks() {
    // (z, theta) from (200 mm, 0) to (335 mm, 0.9 rad) in 1 s, 0.1 s ramps (fig. 7):
    // slider V peaks at 0.26 m/s and 2.6 m/s^2 (within 3 %).
    let h = head();
    let seg = Segment::line(
        Vector2::new(200.0, 0.0),
        Vector2::new(335.0, 0.9),
        &[Quantity::Length, Quantity::Angle],
        false,
    );
    let mv = Move {
        profile: Profile::trapezoid_timed(seg.length, 1.0, 0.1).unwrap(),
        segment: seg,
        line: None,
        rapid: false,
    };
    let mut r = Runner::new(&h, Sampling::Rate(1000.0)).unwrap();
    r.run_move(&mv, true, &mut |_| Ok(())).unwrap();
    let s = r.finish();
    let (name, v) = &s.actuators[1];
    assert_eq!(name, "V");
    assert!(
        (v.peak_velocity / 260.0 - 1.0).abs() < 0.03,
        "{}",
        v.peak_velocity
    );
    assert!(
        (v.peak_acceleration / 2600.0 - 1.0).abs() < 0.03,
        "{}",
        v.peak_acceleration
    );
    // Slider D follows z: 150 mm/s cruise, 1500 mm/s^2 ramps.
    let (_, d) = &s.actuators[0];
    assert!((d.peak_velocity - 150.0).abs() < 1e-6);
    assert!((d.peak_acceleration - 1500.0).abs() < 1e-6);
    assert!(s.violations.is_empty(), "{:?}", s.violations);
}

#[test]
fn hybrid_machine_compensates_the_tool_tilt() {
    let m = hybrid();
    let l = m.head().tool_length;
    let p = Vector6::new(40.0, 25.0, 60.0, 0.5, 0.0, 0.0);
    let q = m.inverse(&p).unwrap();
    // Table X follows X; table Y takes back the tip's sideways swing L sin A; U lifts
    // the head by L (1 - cos A) relative to the untilted tool.
    assert!((q[0] - 40.0).abs() < 1e-12);
    assert!((q[1] - (25.0 - l * 0.5f64.sin())).abs() < 1e-12);
    assert!((q[2] - (60.0 + l * 0.5f64.cos())).abs() < 1e-12);
    // The tool pose relative to the part: the head's tool tip minus the table position.
    let t = m.tool_pose(&p).unwrap();
    let sk = m.skeleton(&p).unwrap();
    let tip = sk
        .points
        .iter()
        .find(|s| s.name == "tool")
        .unwrap()
        .position;
    let part = sk
        .points
        .iter()
        .find(|s| s.name == "part origin")
        .unwrap()
        .position;
    for k in 0..3 {
        assert!((t.translation.vector[k] - (tip[k] - part[k])).abs() < 1e-9);
    }
    // B and C cannot be set: held at 0, any other value is a named violation.
    let bad = Vector6::new(0.0, 0.0, 60.0, 0.2, 0.1f64.to_radians(), 0.0);
    match pkm::inverse_checked(&m, &bad) {
        Err(Error::Unreachable { violations }) => {
            assert_eq!(violations.len(), 1);
            assert!(violations[0].limit.starts_with("spindle angle B"));
            assert!((violations[0].excess - 0.1).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn machine_file_errors_name_the_field() {
    let text = std::fs::read_to_string(format!(
        "{}/../../examples/machines/p3rp-seed004.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let cases = [
        (
            "V = { stroke = [500.0, 825.0] }",
            "W = { stroke = [500.0, 825.0] }",
            "sliders.W",
        ),
        ("V = { stroke = [500.0, 825.0] }", "", "missing axis `V`"),
        (
            "U = { stroke = [200.0, 520.0] }",
            "U = { stroke = [520.0, 200.0] }",
            "min < max",
        ),
        ("l2 = 378.3 ", "l2 = -378.3 ", "head.l2"),
        ("branch = \"positive\"", "branch = \"negative\"", "branch"),
        (
            "branch = \"positive\"",
            "branch = \"left\"",
            "unknown branch",
        ),
        (
            "theta = [0.0, 90.0] ",
            "theta = [90.0, 0.0] ",
            "limits.theta",
        ),
    ];
    for (from, to, want) in cases {
        assert!(text.contains(from), "{from}");
        let bad = text.replacen(from, to, 1);
        let e = Machine::from_toml_str(&bad, "head.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "{from} -> {to}: {e}");
        assert!(e.starts_with("head.toml:"), "{e}");
    }
}

#[test]
fn reproduction_table() {
    let h = head();
    let rows = pkm::p3rp::seed004::reproduction(&h).unwrap();
    assert_eq!(rows.len(), 10);
    for r in &rows {
        if r.quantity.starts_with("slider E range at theta = 1.57") {
            // The paper's 600 mm is a plot reading that contradicts its D range.
            assert!((r.pkm[0] - 660.0).abs() < 0.1 && (r.pkm[1] - 825.0).abs() < 0.1);
            assert!(r.note.is_some());
        } else if r.unit == "mm" {
            for (a, b) in r.paper.iter().zip(&r.pkm) {
                assert!((a - b).abs() < 0.1, "{}: {a} vs {b}", r.quantity);
            }
        } else if !r.paper.is_empty() {
            assert!(r.deviation < 0.03, "{}: {:?}", r.quantity, r.pkm);
        }
    }
    let q = rows.last().unwrap();
    assert!(q.quantity.starts_with("singular configuration Q"));
    assert!(q.pkm[0] > 100.0 && q.pkm[0] < 180.0, "{:?}", q.pkm);
}

#[test]
fn assembly_modes_are_the_two_branches() {
    use pkm::mechanism::{assembly_modes, spread_starts};
    let h = head();
    let q = h.inverse(&Vector2::new(300.0, 0.6)).unwrap();
    let modes = assembly_modes(&h, &q, &spread_starts(&h, 50), 1e-9);
    assert_eq!(modes.len(), 2);
    assert!((modes[0].pose - Vector2::new(300.0, 0.6)).amax() < 1e-9);
    let g = &h.geometry();
    assert_eq!(g.branch_of(modes[1].pose[1]).unwrap(), Branch::Negative);
}

#[test]
fn transmission_figures_of_the_head() {
    // J = [[1, 0], [1, g']]: a tool speed along z moves both sliders (sqrt 2 per unit),
    // a deflection rate moves V by g'; a vertical tool force loads slider U only
    // (J^-T = [[1, -1/g'], [0, 1/g']]), a moment both by 1/g'.
    let h = head();
    for x in workspace_grid().step_by(11) {
        let t = pkm::transmission::transmission(&h, &x).unwrap();
        let dg = h.geometry().separation(x[1]).unwrap().dg;
        assert!((t.velocity.unwrap() - 2f64.sqrt()).abs() < 1e-12);
        assert!((t.angular_velocity.unwrap() - dg.abs()).abs() < 1e-9);
        assert!((t.force.unwrap() - 1.0).abs() < 1e-12);
        assert!((t.moment.unwrap() - 2f64.sqrt() / dg.abs()).abs() < 1e-12);
        assert!((t.condition - h.condition(&x).unwrap()).abs() < 1e-9 * t.condition);
        assert!(t.distance_to_singularity > 0.0);
    }
}

/// The head's and the hybrid machine's position limits, named when the machine is
/// built, give the violations the names formatted per call gave: the same names,
/// kinds, sides, values, bounds and units, in the same order, over a grid of poses and
/// slider values within and beyond every stroke, deflection and rod-angle limit.
#[test]
fn position_limits_named_once_give_the_formatted_violations() {
    use pkm::Range;
    let h = head();
    let acts = h.info().actuators().clone();
    let m = hybrid();
    let macts = m.info().actuators().clone();
    let (mut seen_head, mut seen_hybrid) = (0, 0);
    for i in 0..=20 {
        for k in 0..=20 {
            let (s, t) = (i as f64 / 20.0, k as f64 / 20.0);
            let x = Vector2::new(100.0 + 500.0 * s, -0.5 + 2.5 * t);
            let q = Vector2::new(-100.0 + 900.0 * t, 800.0 - 900.0 * s);
            let (mut named, mut formatted) = (Vec::new(), Vec::new());
            Mechanism::check_limits(&h, &x, &q, &mut named);
            h.geometry()
                .check_limits(&acts, x[1], q.as_slice(), &mut formatted);
            assert_eq!(named, formatted, "head at {x:?}, {q:?}");
            seen_head += named.len();

            // The hybrid machine: table axes, then the head (sliders, joints), then
            // the spindle's B and C, as before the names were made once.
            let xm = Vector6::new(-900.0 + 1800.0 * s, 900.0 - 1800.0 * t, 0.0, x[1], 0.0, t);
            let qm = nalgebra::Vector4::new(-900.0 + 1800.0 * t, 900.0 - 1800.0 * s, q[0], q[1]);
            let mut named = Vec::new();
            Mechanism::check_limits(&m, &xm, &qm, &mut named);
            let mut expected = Vec::new();
            for j in 0..2 {
                macts[j].range.check(
                    || format!("table axis {} position", macts[j].name),
                    LimitKind::ActuatorPosition,
                    Quantity::Length,
                    qm[j],
                    &mut expected,
                );
            }
            m.head()
                .check_limits(&macts[2..], xm[3], &qm.as_slice()[2..], &mut expected);
            for (j, n) in [(4, "B"), (5, "C")] {
                Range { min: 0.0, max: 0.0 }.check(
                    || format!("spindle angle {n} (the head turns about X only)"),
                    LimitKind::Tilt,
                    Quantity::Angle,
                    xm[j],
                    &mut expected,
                );
            }
            assert_eq!(named, expected, "hybrid at {xm:?}, {qm:?}");
            seen_hybrid += named.len();
        }
    }
    // Not vacuous: most of the grid is beyond some limit.
    assert!(
        seen_head > 300 && seen_hybrid > 600,
        "{seen_head} {seen_hybrid}"
    );
}
