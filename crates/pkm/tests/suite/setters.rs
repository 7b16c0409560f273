//! Model types keep their geometry private: a change through a setter rebuilds what
//! derives from it, so the kinematics follow. Each case compares the changed machine
//! with one built anew from the changed geometry, and checks that the change moved the
//! answer at all (so the test cannot pass on a setter that does nothing).

use nalgebra::{Vector2, Vector3, Vector6};
use pkm::hexapod::Hexapod;
use pkm::machine::Model;
use pkm::Mechanism;

use super::common::example;

fn hexapod(file: &str) -> Hexapod {
    match example(file).model {
        Model::Hexapod(h) => *h,
        _ => panic!("{file} is a hexapod"),
    }
}

#[test]
fn a_hexapods_tool_moved_by_its_setter_moves_its_inverse() {
    for file in ["hexapod-linuxcnc.toml", "hexapod-seed001.toml"] {
        let mut h = hexapod(file);
        let x = h.info().home() + Vector6::new(5.0, -3.0, 2.0, 0.05, -0.04, 0.1);
        let before = h.inverse(&x).unwrap();
        let tool = h.tool() + Vector3::new(0.0, 0.0, -40.0);
        h.set_tool(tool);
        let rebuilt = Hexapod::new(
            h.info().name().to_string(),
            h.hex_struts().clone(),
            tool,
            h.strut_diameter(),
            h.info().home(),
        );
        let after = h.inverse(&x).unwrap();
        assert!((after - before).norm() > 1.0, "{file}: {before} {after}");
        assert_eq!(after, rebuilt.inverse(&x).unwrap(), "{file}");
        let (mut a, mut b) = (Vec::new(), Vec::new());
        h.check_limits(&x, &after, &mut a);
        rebuilt.check_limits(&x, &after, &mut b);
        assert_eq!(a, b, "{file}");
        assert_eq!(
            h.info().characteristic_length(),
            rebuilt.info().characteristic_length(),
            "{file}"
        );
        // The block kernel follows the tool too (a whole block of eight poses: a shorter
        // tail is left to the per-pose path).
        let xs: Vec<f64> = (0..8).flat_map(|_| x.iter().copied()).collect();
        let (mut q, mut clear) = (vec![0.0; 48], vec![false; 8]);
        let screened =
            pkm::mechanism::abilities::inverse_screened(&h, &xs, &mut q, &mut clear, false);
        // The kernel runs at the AVX2 level and up (`pkm::simd`); below, nothing to check.
        if pkm::simd::level() < pkm::simd::Level::Avx2 {
            assert!(!screened);
            continue;
        }
        assert!(screened, "{file}");
        assert!(
            clear.iter().all(|c| *c),
            "{file}: poses near home have a solution"
        );
        for (k, v) in q.iter().enumerate() {
            assert!((v - after[k % 6]).abs() < 1e-9, "{file}: {q:?} {after}");
        }
    }
}

#[test]
fn a_hexapods_struts_replaced_by_its_setter_change_its_limits_and_actuators() {
    let mut h = hexapod("hexapod-linuxcnc.toml");
    let x = h.info().home();
    let q = h.inverse(&x).unwrap();
    let mut struts = h.hex_struts().clone();
    struts[2].actuator.range.max = q[2] - 1.0;
    struts[2].actuator.name = "renamed".into();
    h.set_struts(struts.clone());
    assert_eq!(h.info().actuators()[2].name, "renamed");
    assert_eq!(h.info().actuators()[2].range.max, q[2] - 1.0);
    let mut v = Vec::new();
    h.check_limits(&x, &q, &mut v);
    assert_eq!(v.len(), 1, "{v:?}");
    assert!(v[0].to_string().contains("renamed"), "{}", v[0]);
    let (_, first) =
        pkm::mechanism::abilities::inverse_first_violation(&h, &x, &mut Vec::new()).unwrap();
    assert_eq!(first.as_ref(), v.first());
}

#[test]
fn a_p3rp_heads_geometry_set_moves_its_inverse_and_characteristic_length() {
    let machine = example("p3rp-seed004.toml");
    let Model::P3rpHead(h) = &machine.model else {
        panic!("p3rp-seed004.toml is a P3RP head")
    };
    let mut h = (**h).clone();
    let x: Vector2<f64> = h.info().home();
    let before = h.inverse(&x).unwrap();
    let mut g = h.geometry().clone();
    g.l1 += 10.0;
    h.set_geometry(g.clone());
    assert_eq!(h.info().characteristic_length(), g.l1);
    let after = h.inverse(&x).unwrap();
    assert!((after - before).norm() > 1e-3, "{before} {after}");
    let rebuilt = pkm::p3rp::P3rpHead::new(
        h.info().name().to_string(),
        g,
        h.info().actuators().clone(),
        x,
    );
    assert_eq!(after, rebuilt.inverse(&x).unwrap());
}

#[test]
fn a_pentapods_geometry_set_moves_its_inverse_and_characteristic_length() {
    let machine = example("pentapod-linuxcnc.toml");
    let Model::Pentapod(p) = &machine.model else {
        panic!("pentapod-linuxcnc.toml is a pentapod")
    };
    let mut p = (**p).clone();
    let x = p.info().home() + Vector6::new(4.0, -2.0, 3.0, 0.03, -0.02, 0.0);
    let before = p.inverse(&x).unwrap();
    let l_before = p.info().characteristic_length();
    let mut struts = p.penta_struts().clone();
    struts[1].ring_radius += 5.0;
    p.set_geometry(struts.clone(), p.tool_height() - 30.0);
    let rebuilt = pkm::pentapod::Pentapod::new(
        p.info().name().to_string(),
        struts,
        p.tool_height(),
        p.strut_diameter(),
        p.axes().clone(),
        p.info().home(),
    );
    let after = p.inverse(&x).unwrap();
    assert!((after - before).norm() > 1.0, "{before} {after}");
    assert_eq!(after, rebuilt.inverse(&x).unwrap());
    assert_ne!(p.info().characteristic_length(), l_before);
    assert_eq!(
        p.info().characteristic_length(),
        rebuilt.info().characteristic_length()
    );
}

#[test]
fn the_p3rp_hybrids_head_set_moves_its_inverse_and_characteristic_length() {
    let machine = example("p3rp-hybrid-seed004.toml");
    let Model::P3rpHybrid(h) = &machine.model else {
        panic!("p3rp-hybrid-seed004.toml is the P3RP hybrid machine")
    };
    let mut h = (**h).clone();
    let x = h.info().home();
    let before = h.inverse(&x).unwrap();
    let mut g = h.head().clone();
    g.l1 += 10.0;
    h.set_head(g.clone());
    assert_eq!(h.info().characteristic_length(), g.l1);
    let after = h.inverse(&x).unwrap();
    assert!((after - before).norm() > 1e-3, "{before} {after}");
    let rebuilt = pkm::p3rp::HybridMachine::new(
        h.info().name().to_string(),
        g,
        h.info().actuators().clone(),
        x,
    );
    assert_eq!(after, rebuilt.inverse(&x).unwrap());
}

#[test]
fn a_tripods_travel_set_is_checked() {
    use pkm::limits::{AxisLimits, Range};
    let machine = example("tripod-seed000.toml");
    let Model::TranslationalTripod(t) = &machine.model else {
        panic!("tripod-seed000.toml is a translational tripod")
    };
    let mut t = t.clone();
    let x = t.info().home();
    let q = t.inverse(&x).unwrap();
    let mut v = Vec::new();
    t.check_limits(&x, &q, &mut v);
    assert!(v.is_empty(), "{v:?}");
    t.set_axes(AxisLimits {
        ranges: vec![(
            2,
            Range {
                min: x[2] + 1.0,
                max: x[2] + 2.0,
            },
        )],
    });
    t.check_limits(&x, &q, &mut v);
    assert_eq!(v.len(), 1, "{v:?}");
    assert!(v[0].to_string().contains("axis Z"), "{}", v[0]);
}
