//! The contract of the analysis layer: every machine file in `examples/machines/` and
//! `examples/robots/` (found by listing the folders, so a new example is covered by
//! adding it) runs through every analysis its type supports, with the results'
//! invariants checked, and every other analysis answers `Error::Unsupported`.

use pkm::analysis::identification::{
    calibrate, fixture, simulate_measurements, CalibrateOptions, SimulateOptions,
};
use pkm::analysis::kinematics::{inverse, inverse_solutions, transmission, ForwardStream};
use pkm::analysis::motion::{run_motion, MotionSource, NoSink};
use pkm::analysis::{accuracy, workspace, AccuracyOptions, KindTolerances, Tolerances};
use pkm::identify::simulate::{Design, Experiment};
use pkm::machine::Analysis;
use pkm::motion::program::{FeedOptions, ProfileKind};
use pkm::motion::Sampling;
use pkm::workspace::GridAxis;
use pkm::{Error, Machine, Quantity};

fn examples() -> Vec<std::path::PathBuf> {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");
    let mut v: Vec<_> = ["machines", "robots"]
        .iter()
        .flat_map(|d| std::fs::read_dir(format!("{root}/{d}")).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| {
            matches!(
                p.extension().and_then(|e| e.to_str()),
                Some("toml" | "urdf")
            )
        })
        .collect();
    v.sort();
    assert!(v.len() >= 9, "{v:?}");
    v
}

/// A pose near home that is not home and not singular (a robot's stretched home is):
/// each driven length coordinate 1 % of the characteristic length off and angles 2
/// degrees; failing that, every actuator 5 % of its stroke off home, through forward
/// kinematics.
fn near_home(machine: &Machine) -> Vec<f64> {
    let x = shifted_pose(machine);
    if transmission(machine, &x).is_ok_and(|t| t.condition < 1e3) {
        return x;
    }
    let m = machine.mechanism();
    let q: Vec<f64> = m
        .inverse(&m.home())
        .unwrap()
        .iter()
        .zip(m.actuators())
        .map(|(q, a)| q + 0.05 * (a.range.max - a.range.min))
        .collect();
    let x = m.forward(&q, &m.home()).unwrap().pose;
    assert!(
        transmission(machine, &x).is_ok(),
        "no regular pose near home"
    );
    x
}

fn shifted_pose(machine: &Machine) -> Vec<f64> {
    let m = machine.mechanism();
    let home = m.home();
    let d = m.driven();
    let mut x = home.clone();
    for (i, c) in m.coordinates().iter().enumerate() {
        if !d.contains(&i) {
            continue;
        }
        x[i] += match c.quantity {
            Quantity::Length => 0.01 * m.characteristic_length().max(10.0),
            Quantity::Angle => 2f64.to_radians(),
        };
    }
    match inverse(machine, &x) {
        Ok(s) if s.violations.is_empty() => x,
        _ => home,
    }
}

fn kinematics(name: &str, machine: &Machine) {
    let m = machine.mechanism();
    let x = near_home(machine);
    // IK then FK from home reproduces the pose.
    let ik = inverse(machine, &x).unwrap();
    assert!(ik.violations.is_empty(), "{name}: {:?}", ik.violations);
    let f = m.forward(&ik.actuators, &m.home()).unwrap();
    let (a, b) = (m.tool_pose(&x).unwrap(), m.tool_pose(&f.pose).unwrap());
    assert!(
        (a.translation.vector - b.translation.vector).norm() < 1e-8
            && a.rotation.angle_to(&b.rotation) < 1e-9,
        "{name}: FK(IK(x)) != x"
    );
    // The analytic Jacobian against central differences, at every pose of the check
    // table away from singular configurations (a robot's stretched home: differences of
    // a numeric inverse there say nothing).
    for row in pkm::verify::machine_check_table(machine, 5.0, 2f64.to_radians()) {
        if let (Some(e), Some(c)) = (row.jacobian_error, row.condition) {
            if c > 1e3 {
                continue;
            }
            assert!(
                e < 1e-5,
                "{name} {}: Jacobian vs differences {e}",
                row.label
            );
        }
    }
    // A stream of forward solves along a small move returns the poses it was given.
    let mut stream = ForwardStream::new(machine, &m.home()).unwrap();
    for k in 0..=4 {
        let t = k as f64 / 4.0;
        let xk: Vec<f64> = m
            .home()
            .iter()
            .zip(&x)
            .map(|(h, v)| h + t * (v - h))
            .collect();
        let q = m.inverse(&xk).unwrap();
        let (f, _) = stream.next(&q).unwrap();
        let (a, b) = (m.tool_pose(&xk).unwrap(), m.tool_pose(&f.pose).unwrap());
        assert!(
            (a.translation.vector - b.translation.vector).norm() < 1e-8,
            "{name}"
        );
    }
    let t = transmission(machine, &x).unwrap();
    assert!(
        t.condition >= 1.0 && t.distance_to_singularity > 0.0,
        "{name}"
    );
}

fn motion_and_workspace(name: &str, machine: &Machine) {
    let m = machine.mechanism();
    // A small move from a regular pose near home: the first driven coordinate 1 mm or
    // 0.5 degree on.
    let home = near_home(machine);
    let mut x = home.clone();
    let k = m.driven()[0];
    x[k] += match m.coordinates()[k].quantity {
        Quantity::Length => 1.0,
        Quantity::Angle => 0.5f64.to_radians(),
    };
    let run = run_motion(
        machine,
        MotionSource::PointToPoint {
            from: home.clone(),
            to: x.clone(),
            duration: Some(0.5),
            accel_time: None,
        },
        &FeedOptions {
            profile: ProfileKind::Constant,
            ..Default::default()
        },
        Sampling::Points(21),
        &mut NoSink,
    )
    .unwrap();
    assert_eq!(run.summary.samples, 21, "{name}");
    assert_eq!(run.summary.actuators.len(), m.actuators().len(), "{name}");
    // The actuators travel what inverse kinematics says between the two poses (the
    // move is straight in the pose coordinates; travel is at least the difference).
    let (q0, q1) = (m.inverse(&home).unwrap(), m.inverse(&x).unwrap());
    for (i, (n, st)) in run.summary.actuators.iter().enumerate() {
        let d = m.actuators()[i].quantity.to_user((q1[i] - q0[i]).abs());
        assert!(st.travel >= d - 1e-6, "{name} {n}: {} < {d}", st.travel);
    }
    // The same out and back as a polyline at a feed: every sample of the first move
    // equals the point-to-point move's at that feed; the run ends back at home.
    struct Keep(Vec<(f64, Option<u64>, Vec<f64>)>);
    impl pkm::analysis::motion::SampleSink for Keep {
        fn sample(&mut self, s: &pkm::analysis::motion::SampleRow) -> pkm::Result<()> {
            self.0.push((s.t, s.line, s.q.to_vec()));
            Ok(())
        }
    }
    let feed = FeedOptions {
        profile: ProfileKind::Trapezoid,
        feed: Some(2.0),
        ..Default::default()
    };
    let mut poly = Keep(Vec::new());
    run_motion(
        machine,
        MotionSource::Polyline {
            points: vec![home.clone(), x.clone(), x.clone(), home.clone()],
        },
        &feed,
        Sampling::Rate(200.0),
        &mut poly,
    )
    .unwrap();
    let mut single = Keep(Vec::new());
    run_motion(
        machine,
        MotionSource::PointToPoint {
            from: home.clone(),
            to: x.clone(),
            duration: None,
            accel_time: None,
        },
        &feed,
        Sampling::Rate(200.0),
        &mut single,
    )
    .unwrap();
    let out: Vec<_> = poly.0.iter().filter(|s| s.1 == Some(1)).collect();
    assert_eq!(
        out.len() + 1,
        single.0.len(),
        "{name}: the first move's samples"
    );
    for (a, b) in out.iter().zip(&single.0) {
        assert!((a.0 - b.0).abs() < 1e-12, "{name}");
        for (u, v) in a.2.iter().zip(&b.2) {
            assert!((u - v).abs() < 1e-9 * (1.0 + u.abs()), "{name}");
        }
    }
    // The repeated waypoint makes no move; the way back is line 3 and ends at home.
    assert!(poly.0.iter().all(|s| s.1 != Some(2)), "{name}");
    let (_, line, q_end) = poly.0.last().unwrap();
    assert_eq!(*line, Some(3), "{name}");
    for (u, v) in q_end.iter().zip(q0.iter()) {
        assert!((u - v).abs() < 1e-9 * (1.0 + u.abs()), "{name}: {u} vs {v}");
    }
    assert!(run_motion(
        machine,
        MotionSource::Polyline {
            points: vec![home.clone()]
        },
        &feed,
        Sampling::Rate(200.0),
        &mut NoSink,
    )
    .is_err());
    // A small grid around that pose: the pose itself is reachable.
    let axes: Vec<GridAxis> = pkm::workspace::default_grid(m, &home, None, None)
        .unwrap()
        .into_iter()
        .map(|a| {
            let mid = home[a.coordinate];
            let h = 2.0 * a.step;
            GridAxis {
                coordinate: a.coordinate,
                min: mid - h,
                max: mid + h,
                step: a.step,
            }
        })
        .collect();
    let wm = workspace::grid(machine, &home, &axes, &[], &|_| {}).unwrap();
    let n: usize = axes.iter().map(|a| a.count()).product();
    assert_eq!(wm.points.len(), n, "{name}");
    let centre = wm.points[n / 2].clone();
    assert!(
        centre.reachable,
        "{name}: the centre of the grid is not reachable"
    );
}

fn accuracy_checks(name: &str, machine: &Machine) {
    let tol = KindTolerances {
        angle: 2e-5,
        ..KindTolerances::default()
    };
    let r = accuracy(
        machine,
        &AccuracyOptions {
            pose: Some(near_home(machine)),
            tolerances: Tolerances::ByKind(tol),
            monte_carlo: Some(20_000),
            seed: 5,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(!r.budget.items.is_empty(), "{name}");
    assert_eq!(r.sensitivities.len(), r.parameters.len());
    // Monte Carlo spread per component against the budget's first order.
    let mc = r.monte_carlo.as_ref().unwrap();
    assert_eq!(mc.failed, 0, "{name}");
    for c in 0..3 {
        let predicted = r
            .tolerances
            .iter()
            .map(|t| (r.sensitivities[t.parameter].position[c] * t.std()).powi(2))
            .sum::<f64>()
            .sqrt();
        if predicted < 1e-7 {
            continue;
        }
        let ratio = mc.std_vector[c] / predicted;
        assert!(
            (ratio - 1.0).abs() < 0.05,
            "{name}: component {c} Monte Carlo std {} vs first order {predicted}",
            mc.std_vector[c]
        );
    }
    assert!(mc.max <= r.budget.worst_case * 1.001, "{name}");
}

fn identification(name: &str, machine: &Machine) {
    let e = Experiment {
        deviation: 0.5,
        point_noise: 0.0,
        length_noise: 0.0,
        states: 30,
        design: Design::Random,
        translation: 30.0,
        rotation: 5f64.to_radians(),
        condition_ratio: pkm::identify::simulate::CONDITION_RATIO,
        step: 20.0,
        // The machine's own fixture: a triangle on a platform, points on a pentapod's
        // tool axis.
        fixture: fixture(machine, 100.0).unwrap().points,
        seed: 3,
    };
    let s = simulate_measurements(
        machine,
        None,
        &SimulateOptions {
            experiment: e,
            holdout: 5,
            comment: String::new(),
        },
    )
    .unwrap();
    assert_eq!(s.measurements.states.len(), 30);
    assert_eq!(s.validation.states.len(), 5);
    // Hold what trades exactly for this machine (a translational tripod's platform
    // joints): the fit is then exact on noise-free data and on held-out states.
    let trading = if machine.kind() == "tripod/translational" {
        vec!["C.*".into(), "D.*".into(), "E.*".into()]
    } else {
        Vec::new()
    };
    let c = calibrate(
        machine,
        &s.measurements,
        Some(&s.validation),
        &CalibrateOptions {
            fix: trading,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(
        c.identification.rms_after < 1e-6,
        "{name}: {}",
        c.identification.rms_after
    );
    let v = c.validation.unwrap();
    assert!(
        v.identified.rms < 1e-5 && v.nominal.rms > 1e-2,
        "{name}: {v:?}"
    );
}

fn all_solutions(name: &str, machine: &Machine) {
    let m = machine.mechanism();
    let x = near_home(machine);
    let sols = inverse_solutions(machine, &x, 64).unwrap();
    assert!(!sols.is_empty(), "{name}");
    let p0 = m.tool_pose(&x).unwrap();
    for s in &sols {
        // Every posture reaches the pose: FK of its joints from the posture itself.
        let f = m.forward(&s.actuators, &x).unwrap();
        let p = m.tool_pose(&f.pose).unwrap();
        assert!(
            (p.translation.vector - p0.translation.vector).norm() < 1e-6,
            "{name}"
        );
    }
}

#[test]
fn every_example_runs_every_analysis_it_supports() {
    for path in examples() {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let machine = Machine::from_path(&path).unwrap();
        kinematics(&name, &machine);
        motion_and_workspace(&name, &machine);
        accuracy_checks(&name, &machine);
        let caps = machine.capabilities();
        for a in Analysis::ALL {
            let supported = caps.contains(&a);
            let r: Result<(), Error> = match a {
                Analysis::Identification if supported => {
                    identification(&name, &machine);
                    Ok(())
                }
                Analysis::Identification => calibrate(
                    &machine,
                    &Default::default(),
                    None,
                    &CalibrateOptions::default(),
                )
                .map(|_| ()),
                Analysis::InverseSolutions if supported => {
                    all_solutions(&name, &machine);
                    Ok(())
                }
                Analysis::InverseSolutions => {
                    inverse_solutions(&machine, &machine.mechanism().home(), 4).map(|_| ())
                }
                Analysis::ForwardWorkspace => {
                    let m = machine.mechanism();
                    let axes: Vec<GridAxis> = m
                        .actuators()
                        .iter()
                        .enumerate()
                        .map(|(k, a)| GridAxis {
                            coordinate: k,
                            min: a.range.min,
                            max: a.range.max,
                            step: (a.range.max - a.range.min) / 3.0,
                        })
                        .collect();
                    workspace::forward_map(&machine, &axes, &m.home(), &|_| {}).map(|p| {
                        assert_eq!(p.len(), 4usize.pow(axes.len() as u32), "{name}");
                    })
                }
                Analysis::Seed004 => pkm::analysis::seed004::reproduction(&machine).map(|rows| {
                    assert!(!rows.is_empty());
                }),
                Analysis::Clearance => pkm::analysis::clearance::clearance(
                    &machine,
                    None,
                    &pkm::analysis::clearance::ClearanceRequest {
                        diametral: Some(0.02),
                        monte_carlo: Some(500),
                        ..Default::default()
                    },
                )
                .map(|r| {
                    // Bounds hold the samples, and grow with the clearance.
                    let b = &r.bounds;
                    let mc = r.monte_carlo.as_ref().unwrap();
                    assert!(b.upper > 0.0 && b.lower < 0.0, "{name}: {b:?}");
                    assert!(
                        mc.max <= b.upper + 1e-12 && mc.min >= b.lower - 1e-12,
                        "{name}"
                    );
                    assert_eq!(r.clearances.len(), machine.passive_joints().len());
                }),
                _ => Ok(()),
            };
            match (supported, r) {
                (true, r) => r.unwrap_or_else(|e| panic!("{name}: {a:?}: {e}")),
                (false, Err(Error::Unsupported { analysis, .. })) => {
                    assert_eq!(analysis, a.name())
                }
                (false, other) => panic!("{name}: {a:?} should be unsupported, got {other:?}"),
            }
        }
    }
}

/// The batch inverse and forward (rayon, chunks) equal the single calls with their limit
/// check on every example machine, row by row, across chunk boundaries; a ragged
/// array is refused.
#[test]
fn batch_kinematics_equal_single_calls_on_every_example() {
    use pkm::analysis::batch::{condition_batch, forward_batch, tool_pose_batch};
    use pkm::analysis::kinematics::{forward, inverse, inverse_batch};
    use rand::{Rng, SeedableRng};
    for path in examples() {
        let machine = Machine::from_path(&path).unwrap();
        let m = machine.mechanism();
        let p = m.coordinates().len();
        let a = m.actuators().len();
        let home = m.home();
        let scale = m.characteristic_length().max(1.0);
        let driven = m.driven();
        let mut rng = rand::rngs::StdRng::seed_from_u64(9);
        // 9 000 poses about home (held coordinates at home's value) (over two chunks of 4 096), some far out of reach.
        let n = 9000;
        let poses: Vec<f64> = (0..n * p)
            .map(|i| {
                let k = i % p;
                // Every third row near home, the others spread wide.
                let f = if !driven.contains(&k) {
                    0.0
                } else if (i / p).is_multiple_of(3) {
                    0.01
                } else {
                    0.3
                };
                let spread = match m.coordinates()[k].quantity {
                    Quantity::Length => f * scale,
                    Quantity::Angle => f,
                };
                home[k] + rng.random_range(-1.0..1.0) * spread
            })
            .collect();
        let b = inverse_batch(&machine, &poses).unwrap();
        assert_eq!(b.actuators.len(), n * a);
        let mut reachable = 0;
        for r in (0..n).step_by(3) {
            let x = &poses[r * p..(r + 1) * p];
            match inverse(&machine, x) {
                Ok(s) => {
                    for (u, v) in s.actuators.iter().zip(&b.actuators[r * a..(r + 1) * a]) {
                        assert!((u - v).abs() <= 1e-9 * (1.0 + u.abs()), "{path:?} row {r}");
                    }
                    assert_eq!(b.reachable[r], s.violations.is_empty(), "{path:?} row {r}");
                    assert_eq!(
                        b.causes.message(r),
                        s.violations.first().map(|v| v.to_string()),
                        "{path:?} row {r}"
                    );
                    assert_eq!(b.causes.violation(r).as_ref(), s.violations.first());
                    reachable += usize::from(b.reachable[r]);
                }
                Err(e) => {
                    assert!(!b.reachable[r]);
                    assert_eq!(b.causes.message(r), Some(e.to_string()));
                    // The table keeps the kind of failure, not one entry per residual.
                    let code = usize::try_from(b.causes.reason[r]).unwrap();
                    assert_eq!(b.causes.reasons[code].text, e.category());
                    assert!(b.causes.violation(r).is_none() && b.causes.value[r].is_nan());
                    assert!(b.actuators[r * a].is_nan());
                }
            }
        }
        assert!(reachable > 0, "{path:?}: no reachable pose drawn");
        // Limit names and kinds of failure: a few dozen causes at most, however many
        // rows fail (solver messages with their numbers stay per row).
        assert!(
            b.causes.reasons.len() <= 64,
            "{path:?}: {} causes",
            b.causes.reasons.len()
        );
        assert!(inverse_batch(&machine, &poses[..p + 1]).is_err());
        // Forward kinematics of the batch's actuators from home: row by row the
        // single-set call's pose, iterations, residual and limit check.
        let qs: Vec<f64> = (0..n)
            .filter(|r| !b.actuators[r * a].is_nan())
            .flat_map(|r| b.actuators[r * a..(r + 1) * a].to_vec())
            .collect();
        let f = forward_batch(&machine, &qs, None).unwrap();
        let nq = qs.len() / a;
        assert_eq!(f.solved.len(), nq);
        for r in (0..nq).step_by(7) {
            let q = &qs[r * a..(r + 1) * a];
            match forward(&machine, q, &home) {
                Ok(s) => {
                    assert!(f.solved[r], "{path:?} row {r}");
                    assert_eq!(
                        &f.poses[r * p..(r + 1) * p],
                        &s.pose[..],
                        "{path:?} row {r}"
                    );
                    assert_eq!(f.iterations[r] as usize, s.iterations);
                    assert_eq!(f.residual[r], s.residual);
                    assert_eq!(f.reachable[r], s.violations.is_empty(), "{path:?} row {r}");
                    assert_eq!(f.causes.violation(r).as_ref(), s.violations.first());
                }
                Err(e) => {
                    assert!(!f.solved[r] && !f.reachable[r]);
                    assert_eq!(f.causes.message(r), Some(e.to_string()));
                }
            }
        }
        assert!(forward_batch(&machine, &qs[..a + 1], None).is_err());
        // Condition numbers of the poses: the single call's where it answers.
        let c = condition_batch(&machine, &poses).unwrap();
        for r in (0..n).step_by(11) {
            match m.condition(&poses[r * p..(r + 1) * p]) {
                Ok(k) => assert_eq!(c[r].to_bits(), k.to_bits(), "{path:?} row {r}"),
                Err(_) => assert!(c[r].is_nan(), "{path:?} row {r}"),
            }
        }
        // Tool poses: the single call's 4 x 4 matrix bit for bit, NaN where it fails.
        let t = tool_pose_batch(&machine, &poses).unwrap();
        assert_eq!(t.len(), 16 * n);
        let mut posed = 0;
        for r in (0..n).step_by(13) {
            let row = &t[16 * r..16 * (r + 1)];
            match m.tool_pose(&poses[r * p..(r + 1) * p]) {
                Ok(pose) => {
                    let h = pose.to_homogeneous();
                    for (k, v) in row.iter().enumerate() {
                        assert_eq!(v.to_bits(), h[(k / 4, k % 4)].to_bits(), "{path:?} row {r}");
                    }
                    posed += 1;
                }
                Err(_) => assert!(row.iter().all(|v| v.is_nan()), "{path:?} row {r}"),
            }
        }
        assert!(posed > 0, "{path:?}: no tool pose");
        assert!(tool_pose_batch(&machine, &poses[..p + 1]).is_err());
    }
}

/// Batches take any value without panicking (front ends validate their input, but the
/// Python binding reads numpy arrays in place while another thread could write to
/// them): NaN, infinities and absurd magnitudes give rows without solution or out of
/// limits, and the rows around them are unaffected.
#[test]
fn batches_take_any_value_without_panicking() {
    use pkm::analysis::batch::{
        condition_batch, forward_batch, inverse_batch_with, tool_pose_batch,
    };
    for path in examples() {
        let machine = Machine::from_path(&path).unwrap();
        let m = machine.mechanism();
        let (p, a) = (m.coordinates().len(), m.actuators().len());
        let home = m.home();
        let bad = [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1e300,
            -1e300,
            0.0,
        ];
        let mut poses = Vec::new();
        for (r, v) in bad.iter().enumerate() {
            for (k, h) in home.iter().enumerate() {
                poses.push(if k == r % p { *v } else { *h });
            }
        }
        // Whole blocks of eight and a ragged tail, home rows between.
        for _ in 0..10 {
            poses.extend(home.iter());
        }
        for check in [true, false] {
            let b = inverse_batch_with(&machine, &poses, check).unwrap();
            let rows = poses.len() / p;
            assert_eq!(b.reachable.len(), rows);
            let q_home = m.inverse(&home).unwrap();
            for r in bad.len()..rows {
                assert!(b.reachable[r], "{path:?} row {r}");
                for (u, v) in b.actuators[r * a..(r + 1) * a].iter().zip(q_home.iter()) {
                    assert!((u - v).abs() <= 1e-9 * (1.0 + v.abs()), "{path:?} row {r}");
                }
            }
        }
        let qs: Vec<f64> = bad
            .iter()
            .flat_map(|v| std::iter::repeat_n(*v, a))
            .collect();
        let f = forward_batch(&machine, &qs, None).unwrap();
        assert_eq!(f.solved.len(), bad.len());
        let c = condition_batch(&machine, &poses).unwrap();
        assert_eq!(c.len(), poses.len() / p);
        let t = tool_pose_batch(&machine, &poses).unwrap();
        assert_eq!(t.len(), 16 * (poses.len() / p));
    }
}

/// The optional abilities' functions agree with the core on every example: where a
/// type has no block kernels, `inverse_screened` and `motion_screened` write nothing
/// and `inverse_first_limit` returns the first violation of `check_limits`; where it
/// has them, the code stands for that same violation. Batch condition numbers equal
/// one pose at a time, bit for bit, with or without a type's own batch.
#[test]
fn abilities_fall_back_to_the_core_on_every_example() {
    use pkm::limits::FirstLimit;
    use pkm::machine::{Analysable, Visitor};
    use pkm::mechanism::abilities;
    struct Check(String);
    impl Visitor for Check {
        type Output = ();
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) {
            let name = self.0;
            let home = m.info().home();
            let mut x = home;
            for (k, c) in m.info().driven().iter().enumerate() {
                x[*c] += 0.3 + 0.1 * k as f64;
            }
            let xs: Vec<f64> = [home, x].iter().flat_map(|x| x.iter().copied()).collect();
            let (mut qs, mut clear) = (vec![0.0; 2 * A], vec![false; 2]);
            let screened = abilities::inverse_screened(m, &xs, &mut qs, &mut clear, true);
            // A type with block kernels screens at every SIMD level that has its
            // kernel (the hexapod's: AVX2 and up); without one it never does.
            if m.block_kernels().is_none() || pkm::simd::level() >= pkm::simd::Level::Avx2 {
                assert_eq!(screened, m.block_kernels().is_some(), "{name}");
            }
            let mut buf = Vec::new();
            for x in [home, x] {
                let Ok(q) = m.inverse(&x) else { continue };
                let mut all = Vec::new();
                m.check_limits(&x, &q, &mut all);
                let (q2, first) = abilities::inverse_first_limit(m, &x, &mut buf).unwrap();
                assert_eq!(q, q2, "{name}");
                if m.block_kernels().is_none() {
                    assert!(!matches!(first, Some(FirstLimit::Code(_))), "{name}");
                }
                let v = first.map(|f| abilities::first_violation(m, f));
                assert_eq!(v.as_ref(), all.first(), "{name} {x:?}");
            }
            let poses = [home, x];
            let mut batch = [0.0; 2];
            abilities::conditions(m, &poses, &[], &mut batch);
            for (x, b) in poses.iter().zip(batch) {
                let one = m.condition(x).unwrap_or(f64::NAN);
                assert!(
                    one.to_bits() == b.to_bits() || (one.is_nan() && b.is_nan()),
                    "{name}: {one} {b}"
                );
            }
        }
    }
    for path in examples() {
        let machine = Machine::from_path(&path).unwrap();
        machine.visit(Check(path.display().to_string()));
    }
}

/// A configuration exactly on a limit is within it both ways: forward kinematics of
/// the home actuators with one of them at its bound, and inverse kinematics of the
/// pose found, name the same violated limits (the actuator at its bound not among
/// them), on every example machine. Before one tolerance rule, `fk` said "limits all
/// satisfied" and `ik` of its pose "strut 0 length 1000.000 mm is above its maximum
/// 1000.000 mm by 0.000 mm".
#[test]
fn a_configuration_on_a_limit_is_within_it_both_ways() {
    use pkm::analysis::kinematics::{forward, inverse};
    let names = |v: &[pkm::limits::Violation]| {
        let mut n: Vec<String> = v.iter().map(|x| x.limit.to_string()).collect();
        n.sort();
        n
    };
    let mut compared = 0;
    for path in examples() {
        let machine = Machine::from_path(&path).unwrap();
        let m = machine.mechanism();
        let home = m.home();
        let Ok(at_home) = inverse(&machine, &home) else {
            continue;
        };
        for (i, a) in m.actuators().iter().enumerate() {
            for bound in [a.range.min, a.range.max] {
                if !bound.is_finite() {
                    continue;
                }
                let mut q = at_home.actuators.clone();
                q[i] = bound;
                let Ok(f) = forward(&machine, &q, &home) else {
                    continue;
                };
                let Ok(back) = inverse(&machine, &f.pose) else {
                    continue;
                };
                // Another posture of the same pose has limits of its own.
                let same = back
                    .actuators
                    .iter()
                    .zip(&q)
                    .all(|(b, q)| (b - q).abs() < 1e-6);
                if !same {
                    continue;
                }
                let name = &a.name;
                assert!(
                    !f.violations
                        .iter()
                        .any(|v| v.limit.contains(&format!(" {name} "))),
                    "{path:?}: {name} at {bound}: {:?}",
                    f.violations
                );
                assert_eq!(
                    names(&f.violations),
                    names(&back.violations),
                    "{path:?}: {name} at {bound}"
                );
                compared += 1;
            }
        }
    }
    assert!(
        compared >= 40,
        "{compared} configurations on a limit compared"
    );
}
