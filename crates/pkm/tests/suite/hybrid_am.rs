//! The hybrid additive machine of seed 002: kinematics against an independent
//! implementation and a hand construction, round trips, Jacobians and rates against
//! finite differences, limits, singular layouts and the file's errors.

use nalgebra::{SVector, Vector3, Vector6};
use pkm::accuracy::{finite_difference_sensitivities, sensitivities, Rebuild};
use pkm::hybrid_am::HybridAm;
use pkm::machine::Model;
use pkm::rotation::{ry, rz};
use pkm::verify::jacobian_error;
use pkm::{Error, LimitKind, Machine, Mechanism};
use proptest::prelude::*;

fn path() -> String {
    format!(
        "{}/../../examples/machines/hybrid-am-seed002.toml",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn machine() -> HybridAm {
    match Machine::from_path(path()).unwrap().model {
        Model::HybridAm(m) => *m,
        _ => panic!("not a hybrid-am machine"),
    }
}

fn pose(x: f64, y: f64, z: f64, b_deg: f64, c_deg: f64) -> Vector6<f64> {
    Vector6::new(x, y, z, 0.0, b_deg.to_radians(), c_deg.to_radians())
}

/// The point of the example hemisphere (R = 75 mm on the table centre) at height `z`
/// and azimuth `c` (deg), the nozzle along the outward normal.
fn on_hemisphere(z: f64, c_deg: f64) -> Vector6<f64> {
    let r = (75.0f64 * 75.0 - z * z).max(0.0).sqrt();
    let c = c_deg.to_radians();
    pose(
        r * c.cos(),
        r * c.sin(),
        z,
        (z / 75.0).acos().to_degrees(),
        c_deg,
    )
}

#[test]
fn inverse_matches_an_independent_implementation() {
    // Readings from a separate numpy implementation of the same layout (written from
    // the module's equations while choosing the layout), to 1e-9 mm.
    let m = machine();
    for (x, q) in [
        (
            pose(0.0, 0.0, 75.0, 0.0, 0.0),
            [598.296050171, 422.090072894, 502.591128819, 483.700738957],
        ),
        (
            pose(75.0, 0.0, 0.0, 90.0, 0.0),
            [318.952771559, 475.906036855, 324.684408612, 416.713250050],
        ),
        (
            pose(20.0, -15.0, 60.0, 30.0, 40.0),
            [586.443876813, 512.859279714, 546.716819342, 547.798132918],
        ),
        (
            pose(-10.0, 25.0, 50.0, 55.0, -120.0),
            [520.643400448, 569.784085009, 545.820912054, 537.963593418],
        ),
    ] {
        let got = m.inverse(&x).unwrap();
        for i in 0..4 {
            assert!((got[i] - q[i]).abs() < 2e-9, "{i}: {} vs {}", got[i], q[i]);
        }
        assert_eq!(got[4], x[5]);
    }
}

#[test]
fn hand_construction_closes_every_loop() {
    // Built point by point: the part point turned by the table, the platform from the
    // tip, each strut of its length from its carriage on its vertical guide, the
    // nozzle along the surface normal.
    let m = machine();
    for z in [0.0, 20.0, 45.0, 70.0, 75.0] {
        for c in [0.0, 35.0, -150.0] {
            let x = on_hemisphere(z, c);
            let q = m.inverse(&x).unwrap();
            let table = rz(-x[5]);
            let tip = m.table() + table * Vector3::new(x[0], x[1], x[2]);
            let platform = ry(x[4] - m.tool_tilt());
            let origin = tip - platform * m.tool();
            for (i, leg) in m.legs().iter().enumerate() {
                let joint = origin + platform * leg.platform;
                let carriage = leg.guide + Vector3::new(0.0, 0.0, q[i]);
                assert!(((joint - carriage).norm() - leg.length).abs() < 1e-9);
                assert!(carriage.z > joint.z, "carriage above its joint");
            }
            // The nozzle axis in the part frame is the hemisphere's outward normal.
            let axis = table.transpose() * platform * ry(m.tool_tilt()) * Vector3::z();
            let n = Vector3::new(x[0], x[1], x[2]) / 75.0;
            assert!((axis - n).norm() < 1e-12, "{axis} vs {n}");
            // The platform keeps its Y axis.
            assert!((platform * Vector3::y() - Vector3::y()).norm() < 1e-15);
        }
    }
}

#[test]
fn the_whole_example_hemisphere_is_reachable_within_every_limit() {
    let m = machine();
    for k in 0..=30 {
        for c in [0.0, 90.0, 200.0] {
            let x = on_hemisphere(75.0 * k as f64 / 30.0, c);
            let q = m.inverse(&x).unwrap();
            let mut v = Vec::new();
            m.check_limits(&x, &q, &mut v);
            assert!(v.is_empty(), "z = {}: {v:?}", x[2]);
            // Conditioning is worst at the equator (21.5), where the struts lean most.
            assert!(m.condition(&x).unwrap() < 25.0);
        }
    }
}

fn within_limits(m: &HybridAm, x: &Vector6<f64>) -> bool {
    let Ok(q) = m.inverse(x) else { return false };
    let mut v = Vec::new();
    m.check_limits(x, &q, &mut v);
    v.is_empty()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1500, max_global_rejects: 50000, ..ProptestConfig::default() })]

    /// IK -> FK from home and from a start nearby, over the reachable workspace away
    /// from forward singularities (near one, two assemblies of the platform come
    /// together and a start nearby may belong to the other).
    #[test]
    fn round_trip(
        x in -120.0f64..120.0, y in -120.0f64..120.0, z in -40.0f64..160.0,
        b in -10.0f64..100.0, c in -180.0f64..180.0,
        dx in -3.0f64..3.0, db in -2.0f64..2.0,
    ) {
        let m = machine();
        let p = pose(x, y, z, b, c);
        prop_assume!(within_limits(&m, &p) && m.condition(&p).unwrap() < 50.0);
        let q = m.inverse(&p).unwrap();
        for start in [m.info().home(), p + Vector6::new(dx, -dx, dx, 0.0, db.to_radians(), 0.0)] {
            let Ok(f) = m.forward(&q, &start) else {
                // A start far from the pose may fail; it must say so, never answer wrong.
                continue;
            };
            prop_assert!((f.pose - p).amax() < 1e-9, "{} vs {}", f.pose, p);
            prop_assert!(f.residual < 1e-9);
        }
        // From a start nearby the solver must succeed.
        let near = p + Vector6::new(dx, -dx, dx, 0.0, db.to_radians(), 0.0);
        prop_assert!(m.forward(&q, &near).is_ok());
        // FK -> IK.
        let back = m.inverse(&m.forward(&q, &near).unwrap().pose).unwrap();
        prop_assert!((back - q).amax() < 1e-9);
    }

    #[test]
    fn jacobian_matches_finite_differences(
        x in -100.0f64..100.0, y in -100.0f64..100.0, z in 0.0f64..120.0,
        b in 0.0f64..90.0, c in -180.0f64..180.0,
    ) {
        let m = machine();
        let p = pose(x, y, z, b, c);
        prop_assume!(within_limits(&m, &p));
        let e = jacobian_error(&m, &p).unwrap();
        prop_assert!(e < 1e-6, "{e}");
    }
}

#[test]
fn coords_from_pose_round_trips_and_refuses_a_spin() {
    let m = machine();
    for x in [
        on_hemisphere(30.0, 25.0),
        on_hemisphere(75.0, 40.0),
        on_hemisphere(0.0, -100.0),
    ] {
        let back = m.coords_from_pose(&m.tool_pose(&x).unwrap(), true).unwrap();
        assert!((back - x).amax() < 1e-9, "{back} vs {x}");
    }
    // A turn of the nozzle about its own axis is not the table's: refused, with the
    // angle off.
    let x = on_hemisphere(30.0, 0.0);
    let mut t = m.tool_pose(&x).unwrap();
    t.rotation *= nalgebra::UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.2);
    let e = m.coords_from_pose(&t, true).unwrap_err().to_string();
    assert!(e.contains("does not have"), "{e}");
}

#[test]
fn actuator_rates_equal_central_differences() {
    // A quadratic motion: finite differences are exact and test the derivatives alone.
    let m = machine();
    let x = |s: f64| {
        Vector6::new(
            40.0 * s - 10.0 * s * s,
            -20.0 * s + 15.0 * s * s,
            40.0 + 10.0 * s * s,
            0.0,
            0.6 + 0.4 * s - 0.3 * s * s,
            1.0 * s + 0.5 * s * s,
        )
    };
    let h = 1e-4;
    for i in 0..21 {
        let t = 0.05 + 0.9 * i as f64 / 20.0;
        let xd = (x(t + h) - x(t - h)) / (2.0 * h);
        let xdd = (x(t + h) - 2.0 * x(t) + x(t - h)) / (h * h);
        let mm = m.actuator_motion(&x(t), &xd, &xdd).unwrap();
        let q = |t: f64| m.inverse(&x(t)).unwrap();
        let qd = (q(t + h) - q(t - h)) / (2.0 * h);
        let qdd = (q(t + h) - 2.0 * q(t) + q(t - h)) / (h * h);
        assert!((mm.q - q(t)).amax() < 1e-12);
        assert!(
            (mm.qd - qd).amax() < 1e-6 * qd.amax().max(1.0),
            "{} vs {qd}",
            mm.qd
        );
        assert!(
            (mm.qdd - qdd).amax() < 1e-5 * qdd.amax().max(1.0),
            "{} vs {qdd}",
            mm.qdd
        );
    }
}

#[test]
fn geometry_jacobian_and_sensitivities_match_finite_differences() {
    let m = machine();
    for x in [
        on_hemisphere(0.0, 20.0),
        on_hemisphere(50.0, -70.0),
        m.info().home(),
    ] {
        let jg = m.inverse_geometry_jacobian(&x).unwrap();
        let g0 = m.geometry_values();
        let h = 1e-6;
        for k in 0..g0.len() {
            let mut gp = g0.clone();
            let mut gm = g0.clone();
            gp[k] += h;
            gm[k] -= h;
            let qp = m.with_geometry_values(&gp).unwrap().inverse(&x).unwrap();
            let qm = m.with_geometry_values(&gm).unwrap().inverse(&x).unwrap();
            let fd: SVector<f64, 5> = (qp - qm) / (2.0 * h);
            for r in 0..5 {
                assert!(
                    (jg[(r, k)] - fd[r]).abs() < 1e-6 * fd.amax().max(1.0),
                    "d q{r} / d {k}: {} vs {}",
                    jg[(r, k)],
                    fd[r]
                );
            }
        }
        // The analytic tool-pose sensitivities against differences of exact solves.
        let a = sensitivities(&m, &x).unwrap();
        let f = finite_difference_sensitivities(&m, &x).unwrap();
        assert_eq!(a.len(), 40);
        for (k, (a, f)) in a.iter().zip(&f).enumerate() {
            let scale = f.position.norm().max(1e-3);
            assert!(
                (a.position - f.position).norm() < 1e-5 * scale + 1e-6,
                "{k}: {} vs {}",
                a.position,
                f.position
            );
            // Differences of exact solves carry the solver's 1e-9 noise.
            assert!((a.orientation - f.orientation).norm() < 1e-5 * f.orientation.norm() + 1e-7);
        }
    }
}

#[test]
fn unreachable_poses_name_the_strut_and_limits_their_excess() {
    let m = machine();
    // Far outside: a strut cannot reach, and says by how much.
    let x = pose(600.0, 0.0, 0.0, 45.0, 0.0);
    let e = m.inverse(&x).unwrap_err();
    assert!(e.to_string().contains("beyond the strut's length"), "{e}");
    // The numbers are kept as numbers (words only when shown), and they are the
    // geometry's: the platform joint's distance from the strut's guide, by hand.
    let Error::NotAttainable {
        reason:
            pkm::Unattainable::StrutReach {
                strut,
                joint,
                length,
                distance,
            },
    } = &e
    else {
        panic!("{e:?}")
    };
    let i = m
        .legs()
        .iter()
        .position(|l| &l.actuator.name == strut)
        .expect("a strut of the machine");
    assert_eq!(joint, &m.legs()[i].platform_name);
    assert_eq!(*length, m.legs()[i].length);
    let d = m.placement(&x).joints[i] - m.legs()[i].guide;
    assert!((distance - d.x.hypot(d.y)).abs() < 1e-9, "{distance}");
    assert!(distance > length, "{distance} {length}");
    let shown = e.to_string();
    assert!(
        shown.contains(&format!(
            "strut {strut} (L = {length:.3} mm) cannot reach platform joint {joint}: the \
             joint is {distance:.3} mm from its guide, {:.3} mm beyond",
            distance - length
        )),
        "{shown}"
    );
    // A held A, a tilt beyond its range, a carriage beyond its stroke.
    let violated = |x: Vector6<f64>| {
        let q = m.inverse(&x).unwrap();
        let mut v = Vec::new();
        m.check_limits(&x, &q, &mut v);
        v
    };
    let mut x = m.info().home();
    x[3] = 0.1;
    let v = violated(x);
    assert!(v
        .iter()
        .any(|v| v.kind == LimitKind::Tilt && v.limit.contains("A")));
    let v = violated(pose(0.0, 0.0, 75.0, -10.0, 0.0));
    let t = v
        .iter()
        .find(|v| v.limit.contains("platform tilt"))
        .unwrap();
    assert!((t.excess - 5.0).abs() < 1e-9, "{t:?}");
    let v = violated(pose(0.0, 0.0, 200.0, 0.0, 0.0));
    assert!(v
        .iter()
        .any(|v| v.kind == LimitKind::ActuatorPosition && v.limit.contains("q1")));
}

#[test]
fn a_layout_symmetric_in_x_and_y_is_refused_as_singular() {
    // Platform joints at the same |x| on both sides: the X column and the tilt column
    // of the Jacobian are proportional at a level platform.
    let text = std::fs::read_to_string(path())
        .unwrap()
        .replace("P3 = [-40.0, -60.0, 0.0]", "P3 = [-140.0, -60.0, 0.0]")
        .replace("P4 = [40.0, -60.0, 0.0]", "P4 = [140.0, -60.0, 0.0]")
        .replace("angles = [0.0, 0.0, 0.0]", "angles = [0.0, 45.0, 0.0]");
    let e = Machine::from_toml_str(&text, "symmetric.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("singular at its home pose"), "{e}");
    // The condition number grows without bound as the trapezoid closes.
    let m = machine();
    let mut prev = 0.0;
    for a in [100.0, 130.0, 138.0, 139.9] {
        let mut g = m.geometry_values();
        g[12 + 6] = -a;
        g[12 + 9] = a;
        let s = m.with_geometry_values(&g).unwrap();
        let c = s.condition(&pose(50.0, 0.0, 60.0, 45.0, 0.0)).unwrap();
        assert!(c > prev, "{a}: {c}");
        prev = c;
    }
    assert!(prev > 100.0, "{prev}");
}

#[test]
fn file_errors_name_line_and_field() {
    let text = std::fs::read_to_string(path()).unwrap();
    for (from, to, want) in [
        (
            "length = 350.0\nstroke",
            "length = -350.0\nstroke",
            "struts[0].length",
        ),
        (
            "carriage = \"C2\"",
            "carriage = \"C1\"",
            "used by another strut",
        ),
        (
            "platform = \"P3\"",
            "platform = \"P9\"",
            "unknown platform joint `P9`",
        ),
        (
            "angles = [0.0, 0.0, 0.0]",
            "angles = [3.0, 0.0, 0.0]",
            "A = 0 only",
        ),
        (
            "tilt = [-50.0, 50.0]",
            "tilt = [50.0, -50.0]",
            "limits.tilt",
        ),
        (
            "P4 = [40.0, -60.0, 0.0]",
            "C1 = [40.0, -60.0, 0.0]",
            "names a carriage joint too",
        ),
        (
            "position = [0.0, 0.0, 75.0]",
            "position = [900.0, 0.0, 75.0]",
            "not a pose of the machine",
        ),
    ] {
        assert!(text.contains(from), "{from}");
        let bad = text.replacen(from, to, 1);
        let e = Machine::from_toml_str(&bad, "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("bad.toml:") && e.contains(want), "{want}: {e}");
    }
}

/// The carriages' and the table's position limits, named when the machine is built:
/// beyond every stroke, one violation per drive in order, in mm and degrees.
#[test]
fn position_limits_name_the_carriages_and_the_table() {
    for by in [1.0, -0.01] {
        crate::common::check_position_names(&machine(), by, |i, a| {
            let what = if i < 4 { "carriage" } else { "table" };
            format!("{what} {} position", a.name)
        });
    }
}
