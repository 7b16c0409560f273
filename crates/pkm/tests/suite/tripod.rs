//! Tripod kinematics: round trips over the workspace, Jacobians against finite
//! differences, a second FK method, and every limit.

use nalgebra::{Vector3, Vector6};
use pkm::machine::Model;
use pkm::tripod::{CentreLegTripod, TranslationalTripod};
use pkm::verify::{jacobian_error, round_trip};
use pkm::{newton_forward, Error, LimitKind, Machine, Mechanism, NewtonOptions};
use proptest::prelude::*;

fn load(name: &str) -> Machine {
    Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

fn translational() -> TranslationalTripod {
    match load("tripod-seed000.toml").model {
        Model::TranslationalTripod(t) => t,
        _ => panic!("expected a translational tripod"),
    }
}

fn centre_leg() -> CentreLegTripod {
    match load("tripod-centre-leg.toml").model {
        Model::CentreLegTripod(t) => t,
        _ => panic!("expected a centre-leg tripod"),
    }
}

fn within_limits<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &nalgebra::SVector<f64, P>,
) -> bool {
    let Ok(q) = m.inverse(x) else { return false };
    let mut v = Vec::new();
    m.check_limits(x, &q, &mut v);
    v.is_empty()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, max_global_rejects: 20000, ..ProptestConfig::default() })]

    /// FK(IK(x)) = x within 1e-9 mm and 1e-9 rad over the reachable workspace, with
    /// the held orientation taken from the start (any tilt the limits allow).
    #[test]
    fn translational_round_trip(
        x in -70.0f64..70.0, y in -70.0f64..70.0, z in -350.0f64..-230.0,
        a in -0.2f64..0.2, b in -0.2f64..0.2, c in -0.5f64..0.5,
    ) {
        let t = translational();
        let pose = Vector6::new(x, y, z, a, b, c);
        prop_assume!(within_limits(&t, &pose));
        let mut start = t.info().home();
        start.fixed_rows_mut::<3>(3).copy_from(&pose.fixed_rows::<3>(3));
        let r = round_trip(&t, &pose, &start).unwrap();
        prop_assert!(r.position_error < 1e-9, "{:?}", r);
        prop_assert!(r.orientation_error < 1e-9, "{:?}", r);
    }

    /// The same for the centre-leg tripod, by Newton from the home pose.
    #[test]
    fn centre_leg_round_trip(x in -80.0f64..80.0, y in -80.0f64..80.0, z in -380.0f64..-220.0) {
        let t = centre_leg();
        let pose = Vector3::new(x, y, z);
        prop_assume!(within_limits(&t, &pose));
        let r = round_trip(&t, &pose, &t.info().home()).unwrap();
        prop_assert!(r.position_error < 1e-9, "{:?}", r);
        prop_assert!(r.orientation_error < 1e-9, "{:?}", r);
        prop_assert!(r.iterations <= 10, "{:?}", r);
    }

    /// Analytic Jacobians equal central finite differences (relative 1e-6).
    #[test]
    fn jacobians_match_finite_differences(
        x in -60.0f64..60.0, y in -60.0f64..60.0, z in -340.0f64..-240.0,
        a in -0.3f64..0.3, b in -0.3f64..0.3, c in -0.5f64..0.5,
    ) {
        let t = translational();
        let e = jacobian_error(&t, &Vector6::new(x, y, z, a, b, c)).unwrap();
        prop_assert!(e < 1e-6, "translational: {}", e);
        let t = centre_leg();
        let e = jacobian_error(&t, &Vector3::new(x, y, z)).unwrap();
        prop_assert!(e < 1e-6, "centre leg: {}", e);
    }

    /// Second method: the closed-form trilateration and generic Newton agree.
    #[test]
    fn closed_form_and_newton_agree(
        x in -60.0f64..60.0, y in -60.0f64..60.0, z in -340.0f64..-240.0,
        a in -0.2f64..0.2, b in -0.2f64..0.2,
    ) {
        let t = translational();
        let pose = Vector6::new(x, y, z, a, b, 0.0);
        let q = t.inverse(&pose).unwrap();
        let mut start = t.info().home();
        start[3] = a;
        start[4] = b;
        let closed = t.forward(&q, &start).unwrap();
        let newton = newton_forward(&t, &q, &start, &NewtonOptions::default()).unwrap();
        prop_assert!((closed.pose - newton.pose).amax() < 1e-9);
        prop_assert!(newton.iterations > 0 && closed.iterations == 0);
    }
}

#[test]
fn centre_leg_holds_the_tool_on_the_leg_axis() {
    // Hand construction: with the tool on the platform Z axis, the tool tip, the platform
    // centre and the leg joint O are collinear and |OB| is the leg length.
    let t = centre_leg();
    let p = Vector3::new(40.0, -25.0, -300.0);
    let st = t.leg_state(&p).unwrap();
    let b = t.leg().base + st.rotation * Vector3::new(0.0, 0.0, -st.length);
    let ob = b - t.leg().base;
    let ap = p - t.leg().base;
    assert!(ob.cross(&ap).norm() < 1e-9);
    assert!((ap.norm() - st.length - 90.0).abs() < 1e-9);
    // The universal joint never spins the platform about the leg: R = Rx Ry.
    let r = st.rotation;
    assert!(r[(0, 1)].abs() < 1e-15);
}

#[test]
fn translational_fk_picks_the_assembly_mode_near_the_start() {
    let t = translational();
    let pose = t.info().home();
    let q = t.inverse(&pose).unwrap();
    let f = t.forward(&q, &pose).unwrap();
    assert!((f.pose - pose).amax() < 1e-9);
    // Mirror mode: start above the base plane.
    let mut above = pose;
    above[2] = 200.0;
    let f = t.forward(&q, &above).unwrap();
    assert!(f.pose[2] > 0.0, "{}", f.pose);
    assert!((t.inverse(&f.pose).unwrap() - q).amax() < 1e-9);
}

#[test]
fn inconsistent_lengths_are_not_attainable() {
    let t = translational();
    let r = t.forward(&Vector3::new(10.0, 10.0, 400.0), &t.info().home());
    assert!(matches!(r, Err(Error::NotAttainable { .. })), "{r:?}");
}

fn violations<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &nalgebra::SVector<f64, P>,
) -> Vec<pkm::Violation> {
    let q = m.inverse(x).unwrap();
    let mut v = Vec::new();
    m.check_limits(x, &q, &mut v);
    v
}

#[test]
fn strut_too_long_and_too_short() {
    let t = translational();
    let v = violations(&t, &Vector6::new(0.0, 0.0, -420.0, 0.0, 0.0, 0.0));
    assert_eq!(v.len(), 3);
    assert!(v.iter().all(|x| x.kind == LimitKind::ActuatorPosition));
    assert_eq!(v[0].limit, "strut e length");
    assert_eq!(v[0].bound, 300.0);
    let expect = (57.735f64.powi(2) + 330f64.powi(2)).sqrt() - 300.0;
    assert!((v[0].excess - expect).abs() < 0.01, "{}", v[0]);
    let v = violations(&t, &Vector6::new(0.0, 0.0, -200.0, 0.0, 0.0, 0.0));
    assert_eq!(v.len(), 3);
    assert!(v.iter().all(|x| x.bound == 150.0 && x.value < 150.0));
}

#[test]
fn tilt_and_strut_spindle_collision() {
    let t = translational();
    // 25 deg about X at home: within the 30 deg tilt limit, but the spindle leans past
    // the struts e and g (inclination ~16 deg): phi > lambda.
    let v = violations(
        &t,
        &Vector6::new(0.0, 0.0, -290.0, 25f64.to_radians(), 0.0, 0.0),
    );
    let names: Vec<_> = v.iter().map(|x| x.limit.as_str()).collect();
    assert_eq!(v.len(), 2, "{names:?}");
    assert!(v.iter().all(|x| x.kind == LimitKind::StrutSpindleCollision));
    assert!(names[0].contains("strut e") && names[1].contains("strut g"));
    // 35 deg: also above the tilt limit, by 5 deg.
    let v = violations(
        &t,
        &Vector6::new(0.0, 0.0, -290.0, 35f64.to_radians(), 0.0, 0.0),
    );
    let tilt = v.iter().find(|x| x.kind == LimitKind::Tilt).unwrap();
    assert!((tilt.excess - 5.0).abs() < 1e-9 && tilt.unit == "deg");
    // Untilted: each strut leans lambda = atan(57.7 / 200) ~ 16.1 deg away from the spindle.
    let ang = t.tripod_geometry().strut_spindle_angles(
        &Vector3::new(0.0, 0.0, -290.0),
        &nalgebra::Matrix3::identity(),
    );
    for a in ang {
        assert!((a.to_degrees() - (57.735f64 / 200.0).atan().to_degrees()).abs() < 0.01);
    }
    // Tilting by phi towards a strut in its plane leaves lambda - phi: strut f lies in
    // the YZ plane, a tilt about X by -phi turns the spindle top towards +Y (strut f).
    let phi = 10f64.to_radians();
    let r = pkm::rotation::rx(-phi);
    let p = Vector3::new(0.0, 0.0, -290.0);
    let before = t
        .tripod_geometry()
        .strut_spindle_angles(&p, &nalgebra::Matrix3::identity());
    // Keep the platform centre where it was, so the strut geometry only rotates.
    let b = p - t.tripod_geometry().tool();
    let p_tilted = b + r * t.tripod_geometry().tool();
    let after = t.tripod_geometry().strut_spindle_angles(&p_tilted, &r);
    let lambda_f = {
        let plat = b + r * t.tripod_geometry().struts()[1].platform;
        let s = (t.tripod_geometry().struts()[1].base - plat).normalize();
        s.y.atan2(s.z)
    };
    assert!(before[1] > after[1]);
    assert!(
        (after[1] - (lambda_f - phi)).abs() < 1e-12,
        "{} vs {}",
        after[1],
        lambda_f - phi
    );
}

#[test]
fn centre_leg_orientation_is_checked() {
    let t = centre_leg();
    let p = Vector3::new(30.0, 10.0, -300.0);
    let st = t.leg_state(&p).unwrap();
    let good = pkm::pose::pose_from_parts(p, &st.rotation);
    assert!(t.coords_from_pose(&good, true).is_ok());
    let bad = pkm::pose::pose_from_parts(p, &nalgebra::Matrix3::identity());
    let e = t.coords_from_pose(&bad, true).unwrap_err();
    assert!(matches!(e, Error::NotAttainable { .. }));
    assert!(
        e.to_string().contains("centre leg sets the orientation"),
        "{e}"
    );
    assert!(t.coords_from_pose(&bad, false).is_ok());
}

#[test]
fn centre_leg_stroke_is_checked() {
    let t = centre_leg();
    let v = violations(&t, &Vector3::new(0.0, 0.0, -180.0));
    assert!(
        v.iter()
            .any(|x| x.limit == "centre leg length" && x.bound == 120.0),
        "{v:?}"
    );
}

#[test]
fn singular_newton_is_reported() {
    // A degenerate start where the driven Jacobian vanishes: the tool tip at the leg
    // joint itself is not attainable at all.
    let t = centre_leg();
    let r = t.inverse(&t.leg().base);
    assert!(matches!(r, Err(Error::NotAttainable { .. })), "{r:?}");
}

/// Both tripods' strut length limits, named when the machine is built: beyond every
/// stroke, one violation per strut in strut order, named as before.
#[test]
fn strut_length_limits_are_named_in_strut_order() {
    let name = |_: usize, a: &pkm::Actuator| format!("strut {} length", a.name);
    for by in [1.0, -2.5] {
        crate::common::check_position_names(&translational(), by, name);
        crate::common::check_position_names(&centre_leg(), by, name);
    }
}

/// Seed 000's tripod scaled down to struts of micrometres (by 1e-5: 1.5 to 3 um) is a
/// tripod, refused as collinear before (an absolute micrometre in the check), and
/// solves as the full-size one does, scaled.
#[test]
fn a_micrometre_tripod_is_a_tripod() {
    use pkm::analysis::kinematics::{forward, inverse};
    let keys = ["F", "G", "H", "C", "D", "E", "length", "tip", "position"];
    let full = crate::common::example("tripod-seed000.toml");
    let k = 1e-5;
    let small = crate::common::scaled_example("tripod-seed000.toml", k, &keys);
    let x = [-20.0, 45.54, -286.25, 0.0, 0.0, 0.0];
    let xs: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(i, v)| if i < 3 { v * k } else { *v })
        .collect();
    let (a, b) = (inverse(&full, &x).unwrap(), inverse(&small, &xs).unwrap());
    for (l, ls) in a.actuators.iter().zip(&b.actuators) {
        assert!((l * k - ls).abs() < 1e-12 * l * k, "{l} {ls}");
    }
    let f = forward(&small, &b.actuators, &small.mechanism().home()).unwrap();
    for i in 0..3 {
        assert!(
            (f.pose[i] - xs[i]).abs() < 1e-12 * 300.0 * k,
            "{:?} vs {xs:?}",
            f.pose
        );
    }
}
