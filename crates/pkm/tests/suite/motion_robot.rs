//! A six-axis robot along a path: a program's move "to" a pose that differs from the
//! current one only by rounding is no motion (`motion/path.rs`, `MIN_MOVE`), and the
//! joints of a run continue from sample to sample (`Follow::follow`): whole turns
//! and the posture are carried on, not taken afresh nearest the home joints.

use nalgebra::{SVector, Vector6};
use pkm::analysis::batch::inverse_path;
use pkm::analysis::kinematics::InverseStream;
use pkm::analysis::motion::{run_motion_with, MotionSource, SampleRow, SampleSink};
use pkm::machine::Model;
use pkm::motion::program::FeedOptions;
use pkm::motion::run::quantities;
use pkm::motion::{Sampling, Segment, MIN_MOVE};
use pkm::rotation::wrap_angle;
use pkm::serial::arm::SerialArm;
use pkm::serial::mechanism::SerialAny;
use pkm::{Machine, Mechanism, Quantity};

use super::common::example as load;

/// The six-axis robot of machine `m` (tool-pose coordinates).
fn arm_of(m: &Machine) -> &SerialArm {
    let Model::Serial(s) = &m.model else {
        panic!("not a serial machine")
    };
    let SerialAny::Arm(a) = &s.mechanism else {
        panic!("not a six-axis robot")
    };
    a
}

/// One sample's t, pose, q, q', q'' (internal units).
type Row = (f64, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

/// Every sample.
#[derive(Default)]
struct Keep {
    rows: Vec<Row>,
}

impl SampleSink for Keep {
    fn sample(&mut self, s: &SampleRow) -> pkm::Result<()> {
        self.rows.push((
            s.t,
            s.x.to_vec(),
            s.q.to_vec(),
            s.qd.to_vec(),
            s.qdd.to_vec(),
        ));
        Ok(())
    }
}

fn gcode_run(m: &Machine, program: &str, sampling: Sampling) -> (Keep, pkm::motion::MotionSummary) {
    let mut keep = Keep::default();
    let run = run_motion_with(
        m,
        MotionSource::Gcode {
            reader: Box::new(std::io::Cursor::new(program.as_bytes().to_vec())),
            from: None,
            setup: Default::default(),
        },
        &FeedOptions::default(),
        sampling,
        None,
        &mut keep,
    )
    .unwrap();
    (keep, run.summary)
}

/// A straight move whose change is rounding (the KR 30's home pose by forward
/// kinematics against the same pose as a program prints it, to 1e-4 mm and deg) has
/// length zero and no rates; one at [`MIN_MOVE`] or above is a move; a reorientation
/// with a tip change below it is fed in deg along the angles.
#[test]
fn a_change_below_the_shortest_move_is_no_motion() {
    let m = load("kr30-dh.toml");
    let a = arm_of(&m);
    let q = quantities(a);
    let start = a.info().home();
    let end = Vector6::from_fn(|k, _| {
        let user = (q[k].to_user(start[k]) * 1e4).round() / 1e4;
        match q[k] {
            Quantity::Angle => user.to_radians(),
            Quantity::Length => user,
        }
    });
    assert!(start != end, "the test needs the rounding: {start:?}");
    let s = Segment::line(start, end, &q, true);
    assert_eq!(s.length, 0.0);
    let (x, xd, xdd) = s.eval(0.0);
    assert_eq!((x, xd, xdd), (start, SVector::zeros(), SVector::zeros()));

    // At the threshold: a move (mm).
    let mut e = start;
    e[0] += 1.5 * MIN_MOVE;
    let l = Segment::line(start, e, &q, true).length;
    // X = 1170 mm carries 2.3e-13 mm of rounding.
    assert!((l - 1.5 * MIN_MOVE).abs() < 1e-12, "{l}");

    // Ten degrees of C with a 1e-7 mm tip change: fed along the angle, the tip's rate
    // per unit of path is 1e-8 mm/deg, not 1e-7 / 1e-7.
    let mut e = start;
    e[1] += 0.1 * MIN_MOVE;
    e[5] += 10f64.to_radians();
    let s = Segment::line(start, e, &q, true);
    assert!((s.length - 10.0).abs() < 1e-12);
    let (_, xd, _) = s.eval(1.0);
    assert!((xd[1] - 0.1 * MIN_MOVE / 10.0).abs() < 1e-20);
    assert!((xd[5] - 1f64.to_radians()).abs() < 1e-15);

    // The machine's own coordinates: the Euclidean change, zero below the threshold.
    let own = Segment::line(start, start + Vector6::repeat(1e-9), &q, false);
    assert_eq!(own.length, 0.0);
}

/// The KR 30's program starting with a move to its home pose as printed (`Y0` where
/// forward kinematics gives 2.2e-14 mm): no sample turns a joint faster than the
/// program asks. Before `MIN_MOVE` the first sample turned A1 and A6 at 2.7e11 deg/s.
#[test]
fn a_move_to_the_pose_already_reached_turns_no_joint() {
    let m = load("kr30-dh.toml");
    let home = m.mechanism().home();
    assert!(home[1] != 0.0, "the test needs the rounding: {home:?}");
    let program = "G90 G21\nG1 X1170 Y0 Z1540 A-180 B0 C0 F3000\nG1 C10\n";
    let (keep, summary) = gcode_run(&m, program, Sampling::Rate(1000.0));
    // 10 deg at 3000 deg/min: 0.2 s; A6 turns at 50 deg/s, nothing else moves.
    assert_eq!(keep.rows.len(), 201);
    for (t, _, _, qd, _) in &keep.rows {
        let fastest = qd.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(
            fastest < 50f64.to_radians() * (1.0 + 1e-9),
            "{fastest} rad/s at {t}"
        );
    }
    let a6 = &summary.actuators[5].1;
    assert!(
        (a6.peak_velocity - 50.0).abs() < 1e-6,
        "{}",
        a6.peak_velocity
    );
    assert!((a6.travel - 10.0).abs() < 1e-6, "{}", a6.travel);
}

/// Turning the tool about Z by 300 deg and back to -40 deg turns A6 through 300 deg
/// and back, continuously: each joint moves between two samples no more than its rate
/// allows. The inverse alone keeps A6 within half a turn of home: it jumped by 360 deg
/// at C = 180 and its travel read 1359.8 deg instead of 640 (two jumps of 360).
#[test]
fn a_joint_turned_past_half_a_turn_from_home_keeps_turning() {
    let m = load("kr30-dh.toml");
    let program = "G90 G21\nG1 C300 F3000\nG1 C-40\n";
    let (keep, summary) = gcode_run(&m, program, Sampling::Rate(1000.0));
    // 300 + 340 deg of C at 3000 deg/min, sampled at 1 kHz with both ends.
    assert_eq!(keep.rows.len(), (640.0 / 50.0 * 1000.0) as usize + 1);
    continuous(&keep, 1e-3);
    // A6 turns against C (the tool points down): 0 -> -300 -> +40 deg.
    let a6 = |r: &Row| r.2[5].to_degrees();
    let at = |t: f64| &keep.rows[(t * 1000.0).round() as usize];
    assert!((a6(at(6.0)) + 300.0).abs() < 1e-9, "{}", a6(at(6.0)));
    assert!((a6(keep.rows.last().unwrap()) - 40.0).abs() < 1e-9);
    let s = &summary.actuators[5].1;
    assert!((s.travel - 640.0).abs() < 1e-6, "{}", s.travel);
    assert!((s.min + 300.0).abs() < 1e-9 && (s.max - 40.0).abs() < 1e-9);
    // Within the +-350 deg range: no violation.
    assert!(summary.violations.is_empty(), "{:?}", summary.violations);

    // On to C = 400: A6 would pass -350 deg. The limit is reported from C = 350 on
    // (t = 7 s) to the end, worst -400 deg; the inverse alone never saw it.
    let (keep, summary) = gcode_run(&m, "G90 G21\nG1 C400 F3000\n", Sampling::Rate(1000.0));
    continuous(&keep, 1e-3);
    assert_eq!(summary.violations.len(), 1, "{:?}", summary.violations);
    let v = &summary.violations[0];
    assert!(v.limit.contains("A6"), "{}", v.limit);
    assert!(
        (v.start_s - 7.001).abs() < 1e-9 && (v.end_s - 8.0).abs() < 1e-9,
        "{v:?}"
    );
    assert!(
        (v.worst + 400.0).abs() < 1e-6 && (v.bound + 350.0).abs() < 1e-9,
        "{v:?}"
    );

    // A6 limited to [-350, 100] deg and C to 250: the continuing A6 (-250 deg) is
    // within its range; the inverse alone gives +110 deg past C = 180 (> 100), a
    // violation checked on the first solution and dropped with it.
    let path = format!(
        "{}/../../examples/machines/kr30-dh.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let from = r#"name = "A6", type = "revolute", range = [-350.0, 350.0]"#;
    assert!(text.contains(from));
    let text = text.replace(
        from,
        r#"name = "A6", type = "revolute", range = [-350.0, 100.0]"#,
    );
    let m = Machine::from_toml_str(&text, &path).unwrap();
    let (keep, summary) = gcode_run(&m, "G90 G21\nG1 C250 F3000\n", Sampling::Rate(1000.0));
    continuous(&keep, 1e-3);
    assert!((keep.rows.last().unwrap().2[5].to_degrees() + 250.0).abs() < 1e-9);
    assert!(summary.violations.is_empty(), "{:?}", summary.violations);
}

/// No joint moves between two samples by more than `slack` (rad) beyond what its
/// velocity over the interval explains (the trapezoid rule on q').
fn continuous(keep: &Keep, slack: f64) {
    for w in keep.rows.windows(2) {
        let (t0, _, q0, qd0, _) = &w[0];
        let (t1, _, q1, qd1, _) = &w[1];
        let dt = t1 - t0;
        for i in 0..q0.len() {
            let expected = 0.5 * dt * (qd0[i] + qd1[i]);
            assert!(
                (q1[i] - q0[i] - expected).abs() < slack,
                "joint {} jumps {} -> {} at t = {t1}",
                i + 1,
                q0[i],
                q1[i]
            );
        }
    }
}

/// Tool poses along a joint-space curve `q(s) = q0 + s dq`, `s` in `[0, 1]` at `n + 1`
/// points, by forward kinematics, their angles unwrapped from one point to the next
/// (a straight move between two poses then turns the short way).
fn poses_along(a: &SerialArm, q0: &Vector6<f64>, dq: &Vector6<f64>, n: usize) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = Vec::new();
    for k in 0..=n {
        let q = q0 + dq * (k as f64 / n as f64);
        let mut x = a.coords_of_joints(&q);
        if let Some(p) = out.last() {
            for i in 3..6 {
                x[i] = p[i] + wrap_angle(x[i] - p[i]);
            }
        }
        out.push(x.iter().copied().collect());
    }
    out
}

/// A path whose joints follow a known curve: straight moves through its poses, three
/// points per move (start, middle, end; the end is the next move's start), so every
/// other sample is one of the curve's points. The run returns the curve's joints there (1e-9 rad), although the solution nearest home
/// changes posture along the way (checked: the curve leaves it); so does an inverse
/// kinematics stream of the poses ([`InverseStream`]). `points`: how many moves.
fn follows_the_curve(m: &Machine, q0: Vector6<f64>, dq: Vector6<f64>, points: usize) {
    let a = arm_of(m);
    // The curve starts where the run starts: the home rule's solution at its first
    // pose (a robot whose home rule lands in another posture there starts in it).
    let q0 = a.inverse(&a.coords_of_joints(&q0)).unwrap();
    let poses = poses_along(a, &q0, &dq, points);
    let left_home_posture = (0..=points).any(|k| {
        let q = q0 + dq * (k as f64 / points as f64);
        let x = Vector6::from_column_slice(&poses[k]);
        a.inverse(&x).map_or(true, |h| (h - q).amax() > 1e-3)
    });
    assert!(
        left_home_posture,
        "the curve never leaves the home rule's posture"
    );
    let mut keep = Keep::default();
    let feed = FeedOptions {
        feed: Some(100.0),
        ..Default::default()
    };
    run_motion_with(
        m,
        MotionSource::Polyline {
            points: poses.clone(),
        },
        &feed,
        Sampling::Points(3),
        None,
        &mut keep,
    )
    .unwrap();
    assert_eq!(keep.rows.len(), 2 * points + 1);
    for k in 0..=points {
        let q = q0 + dq * (k as f64 / points as f64);
        let got = Vector6::from_column_slice(&keep.rows[2 * k].2);
        assert!((got - q).amax() < 1e-9, "point {k}: {got:?} against {q:?}");
    }
    // The same poses as rows of an inverse-kinematics stream (`pkm ik --continuous`)
    // and of a batch along a path (Python's `ik(..., continuous=True)`).
    let mut stream = InverseStream::new(m);
    let flat: Vec<f64> = poses.iter().flatten().copied().collect();
    let batch = inverse_path(m, &flat, true).unwrap();
    assert!(batch.reachable.iter().all(|r| *r));
    for (k, x) in poses.iter().enumerate() {
        let q = q0 + dq * (k as f64 / points as f64);
        let got = Vector6::from_column_slice(&stream.next(x).unwrap().actuators);
        assert!((got - q).amax() < 1e-9, "row {k}: {got:?} against {q:?}");
        let row = Vector6::from_column_slice(&batch.actuators[6 * k..6 * k + 6]);
        assert_eq!(row, got, "row {k}");
    }
}

/// The KR 30 (closed form): the wrist turns 150 deg at A4 and A6 while A5 opens to
/// 60 deg, the shoulder and elbow move too. Past some point the wrist-flipped posture
/// (A4 - 180, -A5, A6 - 180) lies nearer home; the run stays in the posture it started
/// in.
#[test]
fn a_robot_keeps_its_posture_along_a_path() {
    let d = std::f64::consts::PI / 180.0;
    let home = Vector6::new(0.0, 0.0, 0.0, 0.0, 90.0, 0.0) * d;
    let dq = Vector6::new(30.0, 10.0, -20.0, 150.0, -30.0, 150.0) * d;
    follows_the_curve(&load("kr30-dh.toml"), home, dq, 150);
}

/// A UR5-like robot (no spherical wrist: Newton's inverse from home, with restarts):
/// along a curve clear of its singular configurations (elbow and wrist 2 away from 0
/// and 180 deg), the run continues from each sample (Newton from the previous joints)
/// where the home rule lands in other postures.
#[test]
fn a_robot_without_closed_form_keeps_its_posture_along_a_path() {
    let m = Machine::from_path(format!(
        "{}/../../examples/robots/ur5-like.urdf",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let d = std::f64::consts::PI / 180.0;
    let q0 = Vector6::new(0.0, -60.0, 80.0, -100.0, 60.0, 0.0) * d;
    let dq = Vector6::new(120.0, -40.0, 50.0, 150.0, 90.0, 200.0) * d;
    follows_the_curve(&m, q0, dq, 200);
}

/// A path longer than a batch chunk (`BATCH_CHUNK` rows): the chunks run in order and
/// each continues the last row of the one before, row for row as the stream does;
/// A6 turns on to -300 deg across the chunk boundaries. Without `continuous` the rows
/// come back within half a turn of home.
#[test]
fn a_long_path_continues_across_batch_chunks() {
    let m = load("kr30-dh.toml");
    let n = 3 * pkm::analysis::batch::BATCH_CHUNK + 17;
    let c = |k: usize| (300.0 * k as f64 / (n - 1) as f64).to_radians();
    let flat: Vec<f64> = (0..n)
        .flat_map(|k| [1170.0, 0.0, 1540.0, -std::f64::consts::PI, 0.0, c(k)])
        .collect();
    let path = inverse_path(&m, &flat, true).unwrap();
    let mut stream = InverseStream::new(&m);
    for k in 0..n {
        let s = stream.next(&flat[6 * k..6 * k + 6]).unwrap();
        assert_eq!(
            &path.actuators[6 * k..6 * k + 6],
            &s.actuators[..],
            "row {k}"
        );
        assert!((s.actuators[5] + c(k)).abs() < 1e-9, "row {k}");
    }
    assert!(path.reachable.iter().all(|r| *r));
    let each = pkm::analysis::batch::inverse_batch(&m, &flat).unwrap();
    let a6: Vec<f64> = each.actuators.chunks(6).map(|q| q[5]).collect();
    assert!(a6.iter().all(|v| v.abs() <= std::f64::consts::PI + 1e-12));
    assert!((a6[n - 1] - 60f64.to_radians()).abs() < 1e-9);
}

/// The KR 30's curve of `a_robot_keeps_its_posture_along_a_path` in a few long moves,
/// sampled only at their ends (`Points(2)`): the rates over seconds between samples
/// cannot tell a posture from another, so each sample takes the posture nearest the
/// one before. In two or more moves that is the curve's to its end (the home rule
/// ends wrist-flipped); in one move the flipped posture is the nearer one to home's
/// start and is taken (continuity is judged from the samples alone).
#[test]
fn coarse_samples_take_the_posture_nearest_the_previous() {
    let m = load("kr30-dh.toml");
    let a = arm_of(&m);
    let d = std::f64::consts::PI / 180.0;
    let home = Vector6::new(0.0, 0.0, 0.0, 0.0, 90.0, 0.0) * d;
    let dq = Vector6::new(30.0, 10.0, -20.0, 150.0, -30.0, 150.0) * d;
    let end = |moves: usize| {
        let mut keep = Keep::default();
        run_motion_with(
            &m,
            MotionSource::Polyline {
                points: poses_along(a, &home, &dq, moves),
            },
            &FeedOptions {
                feed: Some(100.0),
                ..Default::default()
            },
            Sampling::Points(2),
            None,
            &mut keep,
        )
        .unwrap();
        assert_eq!(keep.rows.len(), moves + 1);
        Vector6::from_column_slice(&keep.rows[moves].2)
    };
    let curve = home + dq;
    let flipped = Vector6::new(
        curve[0],
        curve[1],
        curve[2],
        curve[3] - std::f64::consts::PI,
        -curve[4],
        curve[5] - std::f64::consts::PI,
    );
    for moves in [2, 3, 5] {
        let q = end(moves);
        assert!((q - curve).amax() < 1e-9, "{moves} moves: {q:?}");
    }
    let q = end(1);
    assert!((q - flipped).amax() < 1e-9, "one move: {q:?}");
}

/// A machine with one inverse solution per pose has no path to continue: its
/// `inverse_path` is `inverse_batch`'s, row for row (the hexapod's: rows within and
/// beyond its struts' range, more than one batch chunk, its block kernel and causes).
#[test]
fn a_path_of_a_machine_with_one_solution_is_the_batch() {
    let m = load("hexapod-linuxcnc.toml");
    let n = pkm::analysis::batch::BATCH_CHUNK + 500;
    let flat: Vec<f64> = (0..n)
        .flat_map(|k| {
            let t = k as f64 / n as f64;
            // Z from 300 to 900 mm leaves the struts' range at both ends.
            [
                30.0 * t,
                -20.0 * t,
                300.0 + 600.0 * t,
                0.1 * t,
                -0.05 * t,
                0.2 * t,
            ]
        })
        .collect();
    let path = inverse_path(&m, &flat, true).unwrap();
    let batch = pkm::analysis::batch::inverse_batch(&m, &flat).unwrap();
    assert_eq!(path.reachable, batch.reachable);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&path.actuators), bits(&batch.actuators));
    let reachable = batch.reachable.iter().filter(|r| **r).count();
    assert!(reachable > 100 && reachable < n - 100, "{reachable} of {n}");
    for i in (0..n).step_by(97) {
        assert_eq!(path.causes.message(i), batch.causes.message(i), "row {i}");
    }
}
