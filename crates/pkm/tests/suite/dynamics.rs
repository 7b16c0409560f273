//! Inverse dynamics of serial chains (recursive Newton-Euler) against what is built
//! without it: the potential energy's gradient from forward kinematics, the symmetry
//! and positivity of the mass matrix, the power balance along a motion, a tool load
//! through the Jacobian's transpose. Pinocchio's RNEA is the peer in the Python tests
//! (`crates/pkm-py/tests/test_dynamics.py`).

use nalgebra::{DMatrix, DVector, Matrix4, Vector3};
use pkm::analysis::dynamics::{inverse_dynamics, DynamicsOptions};
use pkm::machine::Model;
use pkm::serial::{joint_transform, link_transform, Chain, LinkDeviation};
use pkm::Machine;
use rand::{rngs::StdRng, Rng, SeedableRng};

fn robots() -> Vec<Machine> {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
    [
        "examples/robots/ur5-like.urdf",
        "tests/fixtures/urdf/scara-tool.urdf",
    ]
    .iter()
    .map(|p| Machine::from_path(format!("{root}/{p}")).unwrap())
    .collect()
}

fn chain(m: &Machine) -> &Chain {
    let Model::Serial(s) = &m.model else { panic!() };
    &s.mechanism.machine().tool
}

/// The base-frame pose of each link frame `S_i` at `q`, by the chain's own transforms.
fn frames(c: &Chain, q: &[f64]) -> Vec<Matrix4<f64>> {
    let none = LinkDeviation::default();
    let mut t = link_transform(&c.links[0], &none);
    let mut out = vec![Matrix4::identity()];
    let mut k = 0;
    for l in &c.links[1..] {
        if let Some(j) = &l.joint {
            t *= joint_transform(j.kind, q[k]);
            k += 1;
        }
        out.push(t);
        t *= link_transform(l, &none);
    }
    out
}

/// Potential energy (J) at `q` under gravity `g` (mm/s^2): `-sum m_i g . c_i`.
fn potential(c: &Chain, q: &[f64], g: &Vector3<f64>) -> f64 {
    let f = frames(c, q);
    c.links
        .iter()
        .zip(&f)
        .filter_map(|(l, t)| l.inertial.map(|b| (b, t)))
        .map(|(b, t)| {
            let com = (t * b.com.push(1.0)).xyz();
            -b.mass * g.dot(&com) * 1e-6
        })
        .sum()
}

fn random_state(rng: &mut StdRng, n: usize) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(-1.5..1.5)).collect()
}

/// The joints' forces and torques per unit of their internal coordinate in J: a
/// revolute joint's N mm is 1e-3 J per rad, a slide's N is 1e-3 J per mm.
fn si(_c: &Chain, t: &[f64]) -> Vec<f64> {
    t.iter().map(|v| v * 1e-3).collect()
}

#[test]
fn held_still_the_torques_are_the_potentials_gradient() {
    // tau(q, 0, 0) = dV/dq: N m per rad; for a slide N per m = 1e-3 N per mm (so both
    // rows compare as N mm per unit of the joint's internal coordinate, times 1e-3).
    let mut rng = StdRng::seed_from_u64(1);
    for m in robots() {
        let c = chain(&m);
        let n = c.dof();
        let o = DynamicsOptions::default();
        for _ in 0..50 {
            let q = random_state(&mut rng, n);
            let t = si(
                c,
                &inverse_dynamics(&m, &q, &vec![0.0; n], &vec![0.0; n], &o).unwrap(),
            );
            let h = 1e-6;
            for k in 0..n {
                let mut a = q.clone();
                let mut b = q.clone();
                a[k] -= h;
                b[k] += h;
                let grad =
                    (potential(c, &b, &o.gravity) - potential(c, &a, &o.gravity)) / (2.0 * h);
                let scale = t.iter().fold(1e-3f64, |s, v| s.max(v.abs()));
                assert!(
                    (grad - t[k]).abs() < 1e-6 * scale,
                    "{}: joint {k}: {grad} against {}",
                    m.mechanism().name(),
                    t[k]
                );
            }
        }
    }
}

/// The mass matrix by columns: `M e_j = tau(q, 0, e_j)` without gravity.
fn mass_matrix(m: &Machine, q: &[f64]) -> DMatrix<f64> {
    let n = q.len();
    let o = DynamicsOptions {
        gravity: Vector3::zeros(),
        ..Default::default()
    };
    let mut mm = DMatrix::zeros(n, n);
    for j in 0..n {
        let mut e = vec![0.0; n];
        e[j] = 1.0;
        let col = inverse_dynamics(m, q, &vec![0.0; n], &e, &o).unwrap();
        for i in 0..n {
            mm[(i, j)] = col[i];
        }
    }
    mm
}

#[test]
fn the_mass_matrix_is_symmetric_and_positive_definite() {
    let mut rng = StdRng::seed_from_u64(2);
    for m in robots() {
        let n = chain(&m).dof();
        for _ in 0..50 {
            let q = random_state(&mut rng, n);
            let mm = mass_matrix(&m, &q);
            let asym = (&mm - mm.transpose()).amax();
            assert!(
                asym < 1e-9 * mm.amax(),
                "{}: {asym:e}",
                m.mechanism().name()
            );
            let sym = (&mm + mm.transpose()) * 0.5;
            assert!(sym.symmetric_eigenvalues().min() > 0.0);
        }
    }
}

#[test]
fn along_a_motion_the_drives_power_is_the_energys_rate() {
    // q(t) = q0 + v t + a t^2 / 2: power tau . q' = d/dt (q'^T M q' / 2 + V), the
    // energy from the mass matrix and the potential, its rate by central differences.
    let mut rng = StdRng::seed_from_u64(3);
    for m in robots() {
        let c = chain(&m);
        let n = c.dof();
        let o = DynamicsOptions::default();
        for _ in 0..20 {
            let (q0, v, a) = (
                random_state(&mut rng, n),
                random_state(&mut rng, n),
                random_state(&mut rng, n),
            );
            let at = |t: f64| -> (Vec<f64>, Vec<f64>) {
                let q = (0..n)
                    .map(|k| q0[k] + v[k] * t + 0.5 * a[k] * t * t)
                    .collect();
                let qd = (0..n).map(|k| v[k] + a[k] * t).collect();
                (q, qd)
            };
            let energy = |t: f64| {
                let (q, qd) = at(t);
                let qd = DVector::from_vec(qd);
                // M in N mm per (unit/s^2): kinetic energy in N mm, then J.
                let kin = 0.5 * qd.dot(&(mass_matrix(&m, &q) * &qd)) * 1e-3;
                kin + potential(c, &q, &o.gravity)
            };
            let h = 1e-5;
            let rate = (energy(h) - energy(-h)) / (2.0 * h);
            let (q, qd) = at(0.0);
            let tau = inverse_dynamics(&m, &q, &qd, &a, &o).unwrap();
            let power: f64 = tau.iter().zip(&qd).map(|(t, w)| t * w).sum::<f64>() * 1e-3;
            assert!(
                (power - rate).abs() < 1e-5 * power.abs().max(1.0),
                "{}: {power} W against {rate} W",
                m.mechanism().name()
            );
        }
    }
}

#[test]
fn a_tool_load_reaches_the_joints_through_the_jacobians_transpose() {
    // Without gravity or motion, tau = -J^T w, J the tool twist per joint rate, by
    // differences of the chain's tool pose.
    let mut rng = StdRng::seed_from_u64(4);
    for m in robots() {
        let c = chain(&m);
        let n = c.dof();
        let w = [30.0, -20.0, 50.0, 2e3, -1e3, 3e3];
        let o = DynamicsOptions {
            gravity: Vector3::zeros(),
            wrench: w,
        };
        for _ in 0..20 {
            let q = random_state(&mut rng, n);
            let tau = inverse_dynamics(&m, &q, &vec![0.0; n], &vec![0.0; n], &o).unwrap();
            let pose = |q: &[f64]| c.pose(q, &[], &[]).unwrap();
            for k in 0..n {
                // Truncation h^2 ~ 1e-8 against the walk's rounding over 1 m of arm.
                let h = 1e-4;
                let mut a = q.clone();
                let mut b = q.clone();
                a[k] -= h;
                b[k] += h;
                let (pa, pb) = (pose(&a), pose(&b));
                let dr = (pb.fixed_view::<3, 1>(0, 3) - pa.fixed_view::<3, 1>(0, 3)) / (2.0 * h);
                let rot = pb.fixed_view::<3, 3>(0, 0) * pa.fixed_view::<3, 3>(0, 0).transpose();
                let th = nalgebra::Rotation3::from_matrix_unchecked(rot.into_owned()).scaled_axis()
                    / (2.0 * h);
                let work = -(w[0] * dr[0]
                    + w[1] * dr[1]
                    + w[2] * dr[2]
                    + w[3] * th.x
                    + w[4] * th.y
                    + w[5] * th.z);
                let scale = tau.iter().fold(1.0f64, |s, v| s.max(v.abs()));
                assert!(
                    (work - tau[k]).abs() < 1e-6 * scale,
                    "{}: joint {k}: {work} against {}",
                    m.mechanism().name(),
                    tau[k]
                );
            }
        }
    }
}

#[test]
fn machines_without_masses_or_a_serial_chain_are_refused() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/machines");
    let kr = Machine::from_path(format!("{root}/kr30-dh.toml")).unwrap();
    let e = inverse_dynamics(
        &kr,
        &[0.0; 6],
        &[0.0; 6],
        &[0.0; 6],
        &DynamicsOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("no link has mass properties"), "{e}");
    let hex = Machine::from_path(format!("{root}/hexapod-linuxcnc.toml")).unwrap();
    let e = inverse_dynamics(
        &hex,
        &[0.0; 6],
        &[0.0; 6],
        &[0.0; 6],
        &DynamicsOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("only serial machines"), "{e}");
}

#[test]
fn a_batch_gives_each_rows_single_call_and_refuses_ragged_rows() {
    use pkm::analysis::dynamics::inverse_dynamics_batch;
    let mut rng = StdRng::seed_from_u64(5);
    for m in robots() {
        let n = chain(&m).dof();
        let rows = 100;
        let mut draw = || random_state(&mut rng, n * rows);
        let (q, qd, qdd) = (draw(), draw(), draw());
        let o = DynamicsOptions {
            wrench: [1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            ..Default::default()
        };
        let all = inverse_dynamics_batch(&m, &q, &qd, &qdd, &o).unwrap();
        for r in 0..rows {
            let s = r * n..(r + 1) * n;
            let one =
                inverse_dynamics(&m, &q[s.clone()], &qd[s.clone()], &qdd[s.clone()], &o).unwrap();
            assert_eq!(one, all[s]);
        }
        assert!(inverse_dynamics_batch(&m, &q[1..], &qd[1..], &qdd[1..], &o).is_err());
    }
}
