//! Seed 003's completion (eq. 3) inside the accuracy engine: angular deviations given
//! for a link turn it rigidly, per evaluation; deviations that mean nothing alone are
//! refused with the reason.

use nalgebra::{Matrix3, Rotation3, SVector, Vector3};
use pkm::accuracy::{budget, pose_error, Parametric};
use pkm::machine::Model;
use pkm::serial::completion::{complete, TripleCompletion};
use pkm::serial::mechanism::SerialAny;
use pkm::Machine;

fn mc300_text() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/machines/mc300.toml"
    ))
    .unwrap()
}

fn mc300() -> pkm::serial::mechanism::SerialMechanism<5> {
    // In joint coordinates (the example file takes TCP coordinates).
    let text = mc300_text().replace("pose = \"tcp\"", "pose = \"joints\"");
    let m = Machine::from_toml_str(&text, "mc300.toml").unwrap();
    let Model::Serial(s) = m.model else { panic!() };
    let SerialAny::J5(j) = s.mechanism else {
        panic!()
    };
    j
}

fn index(m: &impl Parametric<5, 5>, name: &str) -> usize {
    m.parameters().iter().position(|p| p.name == name).unwrap()
}

#[test]
fn the_papers_literal_mc300_rows_are_refused_with_the_reason() {
    // Seed 003 lists alpha_xx, alpha_xy, alpha_xz of the linear axes: in the spindle's
    // frames alpha_xx is an aligned entry.
    let aligned = mc300_text().replace("alpha_yz(3 spindle)", "alpha_xx(3 spindle)");
    let e = Machine::from_toml_str(&aligned, "m.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("m.toml:")
            && e.contains("alpha_xx is the angle between two nominally aligned axes"),
        "{e}"
    );
    // The installation angles with a workpiece chain.
    let inst = format!(
        "{}\n[[tolerance]]\ndeviation = \"theta_x0\"\nvalue = 0.001\n",
        mc300_text()
    );
    let e = Machine::from_toml_str(&inst, "m.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("theta_x0 cannot be given") && e.contains("tool and part alike"),
        "{e}"
    );
    // Two angles measuring the same rotation component (xy and yx: both the turn about z).
    let twice = mc300_text().replace("alpha_yz(3 spindle)", "alpha_yx(3 spindle)");
    let e = Machine::from_toml_str(&twice, "m.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("do not determine the link's rotation"), "{e}");
}

#[test]
fn a_completed_angle_turns_the_link_rigidly() {
    // The X slide's block N is a permutation; alpha_xx (cos(90 deg + a) = -sin a) with
    // alpha_xy = alpha_yy = 0 measured is a turn of S_1* about its y axis by a. Hand
    // construction: the same machine with the slide's block replaced by N Ry(a).
    let m = mc300();
    let (qt, qw) = ([100.0, -50.0, -80.0], [0.5, 0.8]);
    let x = SVector::<f64, 5>::from_column_slice(&[qt[0], qt[1], qt[2], qw[0], qw[1]]);
    let triple = [
        index(&m, "alpha_xx(1 slide)"),
        index(&m, "alpha_xy(1 slide)"),
        index(&m, "alpha_yy(1 slide)"),
    ];
    let prepared = m.with_given(&triple).unwrap().expect("completions");
    let nominal = m.machine().pose(&qt, &qw, &[]).unwrap();
    for a in [1e-4, -3e-3, 0.05] {
        let e = pose_error(&prepared, &x, &[(triple[0], a)]).unwrap();
        let mut turned = m.machine().clone();
        let n = turned.tool.links[1].rotation;
        turned.tool.links[1].rotation =
            n * Rotation3::from_axis_angle(&Vector3::y_axis(), a).matrix();
        let hand = turned.pose(&qt, &qw, &[]).unwrap();
        let dp = hand.fixed_view::<3, 1>(0, 3) - nominal.fixed_view::<3, 1>(0, 3);
        let dr = hand.fixed_view::<3, 3>(0, 0) * nominal.fixed_view::<3, 3>(0, 0).transpose();
        // The engine reads a serial machine's rotation from the skew part of
        // R_dev R_nom^T (exact to first order, defined for the paper's blocks).
        let w = Vector3::new(
            0.5 * (dr[(2, 1)] - dr[(1, 2)]),
            0.5 * (dr[(0, 2)] - dr[(2, 0)]),
            0.5 * (dr[(1, 0)] - dr[(0, 1)]),
        );
        assert!(dp.norm() > 1e-3 * a.abs(), "the turn moves the tool");
        assert!(
            (e.position - dp).amax() < 1e-9,
            "{a}: {} vs {dp}",
            e.position
        );
        assert!(
            (e.orientation - w).amax() < 1e-12,
            "{a}: {} vs {w}",
            e.orientation
        );
    }
    // Without completion the lone entry shears the block (not a rotation): the
    // first-order effects differ.
    let lone = pose_error(&m, &x, &[(triple[0], 1e-4)]).unwrap();
    let rigid = pose_error(&prepared, &x, &[(triple[0], 1e-4)]).unwrap();
    assert!((lone.orientation - rigid.orientation).norm() > 1e-6);
}

#[test]
fn the_fast_completion_agrees_with_the_general_solver() {
    // A permutation block (the MC-300 slides'), a completable crossed triple.
    let n = Matrix3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
    let pos = [(0, 0), (0, 1), (1, 1)];
    let t = TripleCompletion::new(&n, pos).unwrap();
    // Tolerance-sized angles, both sides of the Rodrigues series' switch (|w| = 1e-3),
    // and large ones (the Newton fallback).
    for a in [
        [1e-4, -2e-4, 3e-4],
        [3.5e-5, 1e-5, -2e-5],
        [6e-4, -5e-4, 4e-4],
        [9e-4, -8e-4, 7e-4],
        [0.02, 0.01, -0.03],
        [-0.1, 0.05, 0.08],
    ] {
        let fast = t.complete(a).unwrap();
        let b = t.complete_block(a).unwrap();
        for (i, &(r, c)) in pos.iter().enumerate() {
            let want = (n[(r, c)].clamp(-1.0, 1.0).acos() + a[i]).cos();
            assert!(
                (b[(r, c)] - want).abs() < 1e-14,
                "{a:?}: {}",
                b[(r, c)] - want
            );
        }
        assert!(
            (b.transpose() * b - Matrix3::identity()).amax() < 1e-14,
            "{a:?}"
        );
        let general = complete(&n, &[(pos[0], a[0]), (pos[1], a[1]), (pos[2], a[2])]).unwrap();
        let phi = n.map(|c: f64| c.clamp(-1.0, 1.0).acos());
        let block = Matrix3::from_fn(|r, c| (phi[(r, c)] + fast[(r, c)]).cos());
        assert!((block - general.block).amax() < 1e-9, "{a:?}");
        assert!((block.transpose() * block - Matrix3::identity()).amax() < 1e-12);
        assert!(block.determinant() > 0.0);
    }
    // The reasons: an aligned entry, a whole row.
    let e = TripleCompletion::new(&n, [(0, 2), (0, 0), (0, 1)]).unwrap_err();
    assert!(
        e.contains("alpha_xz is the angle between two nominally aligned axes"),
        "{e}"
    );
    let e = TripleCompletion::new(&Matrix3::identity(), [(0, 1), (1, 0), (0, 2)]).unwrap_err();
    assert!(e.contains("do not determine the link's rotation"), "{e}");
}

#[test]
fn every_mc300_budget_row_means_something() {
    let m = mc300();
    let x = SVector::<f64, 5>::from_column_slice(&[
        100.0,
        -50.0,
        -80.0,
        30f64.to_radians(),
        45f64.to_radians(),
    ]);
    let machine = Machine::from_toml_str(&mc300_text(), "mc300.toml").unwrap();
    let tol = machine.tolerances().to_vec();
    assert_eq!(tol.len(), 39);
    let given: Vec<usize> = tol.iter().map(|t| t.parameter).collect();
    let prepared = m.with_given(&given).unwrap().expect("completions");
    let b = budget(&prepared, &x, &tol).unwrap();
    for i in &b.items {
        assert!(
            i.position > 0.0 || i.orientation > 0.0,
            "{} has no effect",
            i.name
        );
    }
    // The default tolerances (one per kind) pick per link a triple that can be
    // completed, and the preparation accepts them.
    let tolerable = m.tolerable();
    let chosen: Vec<usize> = (0..tolerable.len()).filter(|&k| tolerable[k]).collect();
    assert!(m.with_given(&chosen).is_ok());
    assert_eq!(
        m.parameters()
            .iter()
            .zip(&tolerable)
            .filter(|(p, t)| **t && p.name.starts_with("alpha_"))
            .count(),
        3 * (m.machine().tool.links.len()
            + m.machine().workpiece.as_ref().map_or(0, |w| w.links.len())),
        "three angles per link"
    );
}
