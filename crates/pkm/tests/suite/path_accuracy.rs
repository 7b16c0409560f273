//! Accuracy and singular passages along a program: the prepared sensitivity plan
//! against the general formula, the singular angle against the tool-axis inverse, the
//! passages of a program through the singular direction, and the budget along a
//! program against the budget at each of its poses.

use nalgebra::{SVector, Vector3};
use pkm::accuracy::{self, Parametric, PoseError, SensitivityScratch};
use pkm::analysis::motion::{
    run_motion_with, MotionSource, PathAccuracyRequest, SampleRow, SampleSink,
};
use pkm::machine::Model;
use pkm::serial::mechanism::SerialAny;
use pkm::{Machine, Mechanism};
use rand::{Rng, SeedableRng};

use super::tcp::tcp5;

fn example(name: &str) -> Machine {
    Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

fn mc300() -> Machine {
    example("mc300.toml")
}

/// The file's toleranced parameters, sorted.
fn given(m: &Machine) -> Vec<usize> {
    let mut g: Vec<usize> = m.tolerances().iter().map(|t| t.parameter).collect();
    g.sort_unstable();
    g.dedup();
    g
}

/// Random MC-300 joints within its travel (mm, rad).
fn mc300_joints(rng: &mut rand::rngs::StdRng) -> SVector<f64, 5> {
    SVector::<f64, 5>::from_fn(|i, _| match i {
        0..=2 => rng.random_range(-200.0..200.0),
        3 => rng.random_range(-1.8..1.8),
        _ => rng.random_range(-3.1..3.1),
    })
}

/// `a` and `b` agree to `tol` relative to the largest of them.
fn assert_close(a: &[PoseError], b: &[PoseError], tol: f64, what: &str) {
    let scale = b
        .iter()
        .map(|e| e.position.norm().max(e.orientation.norm()))
        .fold(1e-300, f64::max);
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        let d = (x.position - y.position)
            .norm()
            .max((x.orientation - y.orientation).norm());
        assert!(
            d <= tol * scale,
            "{what}: parameter {k}: {x:?} against {y:?} ({d:e} over {scale:e})"
        );
    }
}

/// The plan (frames, no 4 x 4 products, completed angles from the completion's
/// derivative) against the general formula, at random poses, for every parameter.
fn plan_matches_general<M, const P: usize, const A: usize>(
    m: &M,
    poses: &[SVector<f64, P>],
    what: &str,
) where
    M: Parametric<P, A>,
{
    let n = m.parameters().len();
    let which: Vec<usize> = (0..n).collect();
    let mut s = SensitivityScratch::default();
    let mut out = vec![PoseError::default(); n];
    for x in poses {
        let q = m.inverse(x).unwrap();
        let axis = m
            .sensitivities_into(x, &q, &which, &mut s, &mut out)
            .unwrap();
        let general = accuracy::sensitivities(m, x).unwrap();
        // Completed angles are central differences (h = 1e-6 rad) in both, of the
        // completion in the plan and of the whole pose in the general path.
        assert_close(&out, &general, 1e-8, what);
        let z = m.tool_pose(x).unwrap().rotation * Vector3::z();
        assert!(
            (axis - z).norm() < 1e-12,
            "{what}: tool axis {axis} against {z}"
        );
    }
}

#[test]
fn the_sensitivity_plan_equals_the_general_formula_on_serial_machines() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    // MC-300 in TCP coordinates, completed for its file's tolerances.
    let m = mc300();
    let t = tcp5(&m);
    // `Some`: the file's angles are completed (eq. 3).
    let prepared = t.with_given(&given(&m)).unwrap().unwrap();
    let poses: Vec<SVector<f64, 5>> = (0..200)
        .map(|_| t.coords_of_joints(&mc300_joints(&mut rng)))
        .collect();
    plan_matches_general(&prepared, &poses, "MC-300 (TCP, completed)");
    plan_matches_general(t, &poses, "MC-300 (TCP)");
    // The same machine in joint space.
    let text = std::fs::read_to_string(format!(
        "{}/../../examples/machines/mc300.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replace("pose = \"tcp\"", "");
    let joints = Machine::from_toml_str(&text, "mc300-joints.toml").unwrap();
    let Model::Serial(s) = &joints.model else {
        panic!()
    };
    let SerialAny::J5(j5) = &s.mechanism else {
        panic!("joint space expected")
    };
    let q: Vec<SVector<f64, 5>> = poses.iter().map(|x| t.inverse(x).unwrap()).collect();
    plan_matches_general(j5, &q, "MC-300 (joints)");
    // A six-axis robot (tool pose coordinates, inverse kinematics per pose).
    let kr = example("kr30-dh.toml");
    let Model::Serial(s) = &kr.model else {
        panic!()
    };
    let SerialAny::Arm(arm) = &s.mechanism else {
        panic!("a robot expected")
    };
    let poses: Vec<SVector<f64, 6>> = (0..50)
        .filter_map(|_| {
            let q = SVector::<f64, 6>::from_fn(|_, _| rng.random_range(-1.0..1.0));
            let x = arm.coords_of_joints(&q);
            arm.inverse(&x).ok().map(|_| x)
        })
        .collect();
    assert!(poses.len() > 40);
    plan_matches_general(arm, &poses, "KR 30");
}

#[test]
fn the_singular_angle_is_the_tool_axis_inverses_distance() {
    let m = mc300();
    let t = tcp5(&m);
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    for _ in 0..2000 {
        let mut q = SVector::<f64, 5>::zeros();
        q[3] = rng.random_range(-1.9..1.9);
        q[4] = rng.random_range(-3.1..3.1);
        if rng.random_bool(0.2) {
            q[3] = rng.random_range(-1e-6..1e-6);
        }
        let x = t.coords_of_joints(&q);
        let sol = t.rotary_for_axis(&t.tool_axis(&q), None).unwrap();
        let a = t.singular_angle(&x).unwrap();
        assert!((a - sol.singular_distance).abs() < 1e-9, "{a} {sol:?}");
        // MC-300's C table is on the B table: the angle to C's axis is |B|.
        assert!((a - q[3].abs().min(std::f64::consts::PI - q[3].abs())).abs() < 1e-9);
        assert_eq!(
            pkm::Mechanism::tool_axis(t).unwrap().singular_distance(&x),
            Some(a)
        );
    }
}

/// A program tilting the tool axis past C's axis at 0.57 deg (`eps` = 0.01), each move
/// taking 0.1 s (G93 F600): C turns half a revolution over the few moves nearest it.
fn through_the_pole(t: &pkm::serial::tcp::TcpMachine<5>) -> String {
    let q0 = SVector::<f64, 5>::zeros();
    let a0 = t.tool_axis(&q0);
    let u = a0.cross(&Vector3::x()).normalize();
    let v = a0.cross(&u);
    let mut g = String::from("G21 G90 G93\n");
    let mut near: Option<Vec<f64>> = None;
    for i in 0..=40 {
        let s = -0.5 + i as f64 / 40.0;
        let axis = a0 + u * s + v * 0.01;
        let (x, sol) = t
            .pose_for_axis(&Vector3::new(10.0, 0.0, 0.0), &axis, near.as_deref())
            .unwrap();
        near = Some(sol.chosen().to_vec());
        // A rapid to the first pose, then the moves.
        g.push_str(&format!(
            "{} X{:.6} Y{:.6} Z{:.6} B{:.6} C{:.6} F600\n",
            if i == 0 { "G0" } else { "G1" },
            x[0],
            x[1],
            x[2],
            x[3].to_degrees(),
            x[4].to_degrees()
        ));
    }
    g
}

fn gcode(text: String) -> MotionSource<'static> {
    MotionSource::Gcode {
        reader: Box::new(std::io::Cursor::new(text)),
        from: None,
        setup: Default::default(),
    }
}

#[test]
fn a_pass_near_the_singular_direction_is_found_with_its_lines_and_speed_up() {
    let m = mc300();
    let t = tcp5(&m);
    let run = pkm::analysis::motion::run_motion(
        &m,
        gcode(through_the_pole(t)),
        &pkm::analysis::motion::feed_options(&m),
        pkm::motion::Sampling::Rate(1000.0),
        &mut pkm::analysis::motion::NoSink,
    )
    .unwrap();
    let sg = run
        .summary
        .singular
        .expect("a TCP machine has a singular direction");
    assert_eq!(sg.passages.len(), 1, "{sg:#?}");
    let p = &sg.passages[0];
    // The moves of the program are lines 3..=42 (the rapid to the start is line 2);
    // the tool axis is nearest C's axis at s = 0 (the end of line 22), 0.573 deg away
    // (atan 0.01); sampled along lines in B, C the closest sample is within a few
    // hundredths of that.
    assert!(
        (p.closest_deg - 0.01f64.atan().to_degrees()).abs() < 0.05,
        "{}",
        p.closest_deg
    );
    let line = p.closest_line.unwrap();
    assert!((22..=23).contains(&line), "{line}");
    assert!(p.start_line.unwrap() < line && line < p.end_line.unwrap());
    // C turns about 180 deg over the moves within 2 deg (two to four moves of 0.1 s):
    // its peak there is many times its peak on the rest of the program.
    let c = p.rotary.iter().find(|r| r.axis == "C").unwrap();
    let outside = sg.peak_outside.iter().find(|o| o.0 == "C").unwrap().1;
    assert!(c.peak > 300.0 && c.peak > 5.0 * outside, "{c:?} {outside}");
    assert_eq!(sg.closest.0, p.closest_deg);
    // A smaller threshold than the closest approach finds none.
    let run = pkm::analysis::motion::run_motion(
        &m,
        gcode(through_the_pole(t)),
        &pkm::motion::program::FeedOptions {
            singular_angle: 0.5f64.to_radians(),
            ..pkm::analysis::motion::feed_options(&m)
        },
        pkm::motion::Sampling::Rate(1000.0),
        &mut pkm::analysis::motion::NoSink,
    )
    .unwrap();
    assert!(run.summary.singular.unwrap().passages.is_empty());
}

struct Keep(Vec<(f64, Option<u64>, Vec<f64>)>);

impl SampleSink for Keep {
    fn sample(&mut self, s: &SampleRow) -> pkm::Result<()> {
        self.0.push((s.t, s.line, s.x.to_vec()));
        Ok(())
    }
}

const PROGRAM: &str = "G21 G90 G94\nG0 X-50 Y20 Z-30 B0 C0\nG1 X40 Y-10 Z-60 B25 C70 F3000\n\
                       G1 X0 Y40 Z-20 B-40 C-30\nG0 X0 Y0 Z0 B0 C0\n";

#[test]
fn the_budget_along_a_program_is_the_budget_at_each_of_its_poses() {
    let m = mc300();
    let mut keep = Keep(Vec::new());
    let req = PathAccuracyRequest {
        machines: 50,
        every: 3,
        ..Default::default()
    };
    let run = run_motion_with(
        &m,
        gcode(PROGRAM.into()),
        &pkm::analysis::motion::feed_options(&m),
        pkm::motion::Sampling::Rate(200.0),
        Some(&req),
        &mut keep,
    )
    .unwrap();
    let acc = run.accuracy.expect("asked for");
    assert_eq!(acc.tolerances.len(), m.tolerances().len());
    assert_eq!(acc.path.samples, keep.0.len() as u64);
    // The general budget at every sample (evaluator-based sensitivities).
    let t = tcp5(&m);
    let prepared = t.with_given(&given(&m)).unwrap().unwrap();
    let (mut wc, mut rss) = (0.0f64, 0.0f64);
    let mut per_line = std::collections::BTreeMap::<u64, f64>::new();
    for (_, line, x) in &keep.0 {
        let x = SVector::<f64, 5>::from_column_slice(x);
        let b = accuracy::budget(&prepared, &x, &acc.tolerances).unwrap();
        wc = wc.max(b.worst_case);
        rss = rss.max(b.rss);
        let e = per_line.entry(line.unwrap()).or_default();
        *e = e.max(b.worst_case);
    }
    assert!(
        (acc.path.worst_case.0 - wc).abs() < 1e-9 * wc,
        "{:?} {wc}",
        acc.path.worst_case
    );
    assert!((acc.path.rss.0 - rss).abs() < 1e-9 * rss);
    // One row per line with motion, each the maximum over its samples.
    assert_eq!(acc.path.segments.len(), per_line.len());
    for s in &acc.path.segments {
        let w = per_line[&s.line.unwrap()];
        assert!((s.worst_case - w).abs() < 1e-9 * w, "{s:?} {w}");
        assert!(s.surface_worst_case <= s.worst_case * (1.0 + 1e-12));
        assert!(s.rss <= s.worst_case);
    }
    assert_eq!(
        acc.path.segments.iter().map(|s| s.samples).sum::<u64>(),
        acc.path.samples
    );
    // The band: 50 machines at every third sample; each machine's largest error is at
    // most the worst-case bound, and the spread is ordered.
    let mc = acc.path.monte_carlo.unwrap();
    assert_eq!(mc.machines, 50);
    assert_eq!(mc.samples, acc.path.samples.div_ceil(3));
    assert!(mc.position_max <= acc.path.worst_case.0);
    assert!(mc.surface_max <= acc.path.surface_worst_case.0);
    assert!(mc.position_p50 <= mc.position_p95 && mc.position_p95 <= mc.position_max);
    assert!(mc.surface_p50 > 0.0);
    // Same seed, same band; another seed, another.
    let again = |seed| {
        run_motion_with(
            &m,
            gcode(PROGRAM.into()),
            &pkm::analysis::motion::feed_options(&m),
            pkm::motion::Sampling::Rate(200.0),
            Some(&PathAccuracyRequest {
                seed,
                ..req.clone()
            }),
            &mut pkm::analysis::motion::NoSink,
        )
        .unwrap()
        .accuracy
        .unwrap()
        .path
        .monte_carlo
        .unwrap()
    };
    assert_eq!(again(1), mc);
    assert_ne!(again(2), mc);
}

/// The band's machines are first order in their deviations: at tolerance-sized
/// deviations the linear error equals the exact deviated pose's within 10 nm.
#[test]
fn first_order_errors_equal_exact_ones_at_tolerance_size() {
    let m = mc300();
    let t = tcp5(&m);
    let prepared = t.with_given(&given(&m)).unwrap().unwrap();
    let tol = m.tolerances();
    let which: Vec<usize> = tol.iter().map(|t| t.parameter).collect();
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    let mut s = SensitivityScratch::default();
    let mut sens = vec![PoseError::default(); which.len()];
    let (mut worst, mut largest) = (0.0f64, 0.0f64);
    for _ in 0..100 {
        let q = mc300_joints(&mut rng);
        let x = t.coords_of_joints(&q);
        prepared
            .sensitivities_into(&x, &q, &which, &mut s, &mut sens)
            .unwrap();
        let d: Vec<(usize, f64)> = tol
            .iter()
            .map(|t| (t.parameter, rng.random_range(-1.0..=1.0) * t.value))
            .collect();
        let linear = sens
            .iter()
            .zip(&d)
            .fold(Vector3::zeros(), |a, (s, (_, v))| a + s.position * *v);
        let exact = accuracy::pose_error(&prepared, &x, &d).unwrap().position;
        worst = worst.max((linear - exact).norm());
        largest = largest.max(exact.norm());
    }
    // Errors of tens of micrometres, linear to a few nanometres.
    println!("first order against exact: {worst:e} mm at errors up to {largest:e} mm");
    assert!(largest > 0.01 && worst < 1e-5, "{worst:e} {largest:e}");
}

/// The tool-axis inverse through the analysis layer: every branch points the tool
/// along the axis asked for and is checked against the limits; machines without a
/// tool-axis inverse refuse it by name.
#[test]
fn inverse_for_a_tool_axis_gives_both_branches_with_their_limits() {
    use pkm::analysis::kinematics::inverse_for_tool_axis;
    let m = mc300();
    let t = tcp5(&m);
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    for _ in 0..200 {
        let axis = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(0.2..1.0),
        );
        let tip = [
            rng.random_range(-50.0..50.0),
            rng.random_range(-50.0..50.0),
            rng.random_range(-50.0..50.0),
        ];
        let sol = inverse_for_tool_axis(&m, tip, axis.into(), None).unwrap();
        assert_eq!(sol.branches.len(), 2);
        for b in &sol.branches {
            let q = SVector::<f64, 5>::from_column_slice(&b.actuators);
            assert!((t.tool_axis(&q) - axis.normalize()).norm() < 1e-12);
            let x = t.coords_of_joints(&q);
            for k in 0..3 {
                assert!((x[k] - tip[k]).abs() < 1e-9);
            }
            let mut v = Vec::new();
            t.check_limits(&x, &q, &mut v);
            assert_eq!(v.len(), b.violations.len());
        }
        // The chosen branch is within the ranges when one is, and nearest home.
        let c = &sol.branches[sol.chosen];
        let o = &sol.branches[1 - sol.chosen];
        let d = |b: &pkm::analysis::kinematics::InverseSolution| b.pose[3].hypot(b.pose[4]);
        assert!(
            (c.violations.is_empty() && !o.violations.is_empty())
                || (c.violations.is_empty() == o.violations.is_empty() && d(c) <= d(o) + 1e-12),
            "{sol:?}"
        );
    }
    let hexapod = example("hexapod-seed001.toml");
    let e = inverse_for_tool_axis(&hexapod, [0.0; 3], [0.0, 0.0, 1.0], None).unwrap_err();
    assert!(e.to_string().contains("tool axis vector"), "{e}");
}

/// Along a path the sensitivities are taken at the joints the run solved: a robot in
/// a posture its default inverse does not choose keeps that posture (no second solve
/// per sample, which would land on another posture and give another machine's errors).
#[test]
fn sensitivities_along_a_path_are_at_the_runs_joints() {
    let kr = example("kr30-dh.toml");
    let Model::Serial(s) = &kr.model else {
        panic!()
    };
    let SerialAny::Arm(arm) = &s.mechanism else {
        panic!("a robot expected")
    };
    let machine = &arm.machine();
    let params = machine.all_parameters();
    let which: Vec<usize> = (0..params.len()).collect();
    let mut rng = rand::rngs::StdRng::seed_from_u64(21);
    let mut other_posture = 0;
    for _ in 0..200 {
        let q = SVector::<f64, 6>::from_fn(|_, _| rng.random_range(-2.5..2.5));
        let x = arm.coords_of_joints(&q);
        let Ok(q_default) = arm.inverse(&x) else {
            continue;
        };
        if (q_default - q).amax() < 1e-3 {
            continue;
        }
        other_posture += 1;
        let mut sc = SensitivityScratch::default();
        let mut out = vec![PoseError::default(); which.len()];
        arm.sensitivities_into(&x, &q, &which, &mut sc, &mut out)
            .unwrap();
        let at_q: Vec<PoseError> = machine
            .sensitivities(q.as_slice(), &[], &[], &params)
            .unwrap()
            .into_iter()
            .map(|(position, orientation)| PoseError {
                position,
                orientation,
            })
            .collect();
        assert_close(&out, &at_q, 1e-9, "KR 30 in another posture");
    }
    assert!(other_posture > 20, "{other_posture}");
}
