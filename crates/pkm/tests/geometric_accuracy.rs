#![allow(clippy::needless_range_loop)]
//! Accuracy of strut machines from tolerances on their joints and zero lengths.

use nalgebra::{Vector3, Vector6};
use pkm::accuracy::{budget, monte_carlo, sensitivities, GeometricTolerances};
use pkm::identify::Identifiable;
use pkm::machine::Model;
use pkm::mechanism::Mechanism;
use pkm::serial::tolerance::Distribution;

fn machine(name: &str) -> Model {
    pkm::Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .model
}

/// Tool-point position and rotation of the machine with parameters `theta` at the
/// readings the nominal machine needs for `x`.
fn exact<M: Identifiable<6, A>, const A: usize>(
    m: &M,
    zero: &nalgebra::SVector<f64, A>,
    x: &Vector6<f64>,
    theta: &[f64],
) -> (Vector3<f64>, nalgebra::UnitQuaternion<f64>) {
    let readings = m.inverse(x).unwrap() - zero;
    let ng = theta.len() - A;
    let mm = m.with_geometry(&theta[..ng]).unwrap();
    let z = nalgebra::SVector::<f64, A>::from_column_slice(&theta[ng..]);
    let f = mm.forward(&(z + readings), x).unwrap();
    let p = mm.tool_pose(&f.pose).unwrap();
    (p.translation.vector, p.rotation)
}

fn check_against_differences<M: Identifiable<6, A>, const A: usize>(
    m: &M,
    zero: &nalgebra::SVector<f64, A>,
    x: &Vector6<f64>,
) {
    let s = sensitivities(m, x).unwrap();
    let mut theta = m.geometry();
    theta.extend(zero.iter());
    assert_eq!(s.len(), theta.len());
    for (k, (dp, w)) in s.iter().enumerate() {
        let h = 1e-5;
        let mut tp = theta.clone();
        let mut tm = theta.clone();
        tp[k] += h;
        tm[k] -= h;
        let (pp, rp) = exact(m, zero, x, &tp);
        let (pm, rm) = exact(m, zero, x, &tm);
        let fdp = (pp - pm) / (2.0 * h);
        let fdw = (rp * rm.inverse()).scaled_axis() / (2.0 * h);
        assert!(
            (dp - fdp).amax() < 1e-6 * fdp.amax().max(1.0),
            "{k}: {dp} vs {fdp}"
        );
        assert!((w - fdw).amax() < 1e-7, "{k}: {w} vs {fdw}");
    }
}

#[test]
fn sensitivities_equal_exact_differences_on_hexapod_and_tripod() {
    let Model::Hexapod(h) = machine("hexapod-seed001.toml") else {
        panic!()
    };
    let z = h.zero_readings().unwrap();
    let x = Vector6::new(30.0, -20.0, h.home[2] + 40.0, 0.1, -0.05, 0.2);
    check_against_differences(h.as_ref(), &z, &x);
    let Model::TranslationalTripod(t) = machine("tripod-seed000.toml") else {
        panic!()
    };
    let z = t.zero_readings().unwrap();
    let mut x = t.home;
    x[0] += 20.0;
    x[1] -= 10.0;
    check_against_differences(&t, &z, &x);
}

#[test]
fn a_zero_length_error_moves_the_tool_by_the_inverse_jacobian_column() {
    let Model::Hexapod(h) = machine("hexapod-seed001.toml") else {
        panic!()
    };
    let x = h.home;
    let s = sensitivities(h.as_ref(), &x).unwrap();
    let jinv = h.jacobian(&x).unwrap().try_inverse().unwrap();
    // zero(L1) longer by 1 mm: the strut is 1 mm longer at the same reading.
    let (dp, _) = s[36];
    let col = jinv.column(0);
    assert!((dp - Vector3::new(col[0], col[1], col[2])).amax() < 1e-12);
}

#[test]
fn monte_carlo_converges_to_the_first_order_prediction() {
    let Model::Hexapod(h) = machine("hexapod-seed001.toml") else {
        panic!()
    };
    let z = h.zero_readings().unwrap();
    let x = Vector6::new(30.0, -20.0, h.home[2] + 40.0, 0.1, -0.05, 0.2);
    let tol = GeometricTolerances {
        joint: 0.01,
        zero: 0.02,
        distribution: Distribution::Normal,
    };
    let s = sensitivities(h.as_ref(), &x).unwrap();
    let predicted = (0..3)
        .map(|c| {
            s.iter()
                .enumerate()
                .map(|(k, (dp, _))| {
                    let sd = if k < 36 { tol.joint } else { tol.zero } / 3.0;
                    (dp[c] * sd).powi(2)
                })
                .sum::<f64>()
                .sqrt()
        })
        .collect::<Vec<_>>();
    let mc = monte_carlo(h.as_ref(), &x, &z, &tol, 40_000, 3).unwrap();
    for c in 0..3 {
        let r = mc.std_vector[c] / predicted[c];
        assert!(
            (r - 1.0).abs() < 0.03,
            "component {c}: {} vs {}",
            mc.std_vector[c],
            predicted[c]
        );
        assert!(
            mc.mean_vector[c].abs() < 0.05 * predicted[c] + 1e-6,
            "{:?}",
            mc.mean_vector
        );
    }
    let b = budget(h.as_ref(), &x, &tol).unwrap();
    assert_eq!(b.items.len(), 42);
    assert!(mc.p99 <= b.worst_case, "{} {}", mc.p99, b.worst_case);
    let rss = predicted.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(
        (b.rss / 3.0 - rss).abs() < 1e-12 * rss.max(1.0),
        "{} {}",
        b.rss,
        rss
    );
}
