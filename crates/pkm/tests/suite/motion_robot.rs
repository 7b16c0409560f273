//! A six-axis robot along a path: a program's move "to" a pose that differs from the
//! current one only by rounding is no motion (`motion/path.rs`, `MIN_MOVE`), and the
//! joints of a run continue from sample to sample (`Mechanism::follow`): whole turns
//! and the posture are carried on, not taken afresh nearest the home joints.

use nalgebra::{SVector, Vector6};
use pkm::analysis::motion::{run_motion_with, MotionSource, SampleRow, SampleSink};
use pkm::motion::program::FeedOptions;
use pkm::motion::{Sampling, Segment, MIN_MOVE};
use pkm::{Machine, Quantity};

use super::common::example as load;

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

/// A straight move whose change is rounding (a forward-kinematics pose's 2e-14 mm and
/// 4e-27 rad) has length zero and no rates; one at [`MIN_MOVE`] or above is a move;
/// a reorientation with a tip change below it is fed in deg along the angles.
#[test]
fn a_change_below_the_shortest_move_is_no_motion() {
    let q = [
        Quantity::Length,
        Quantity::Length,
        Quantity::Length,
        Quantity::Angle,
        Quantity::Angle,
        Quantity::Angle,
    ];
    let start = Vector6::new(
        1170.0,
        2.234980408443919e-14,
        1540.0,
        -std::f64::consts::PI,
        3.5e-27,
        0.0,
    );
    let end = Vector6::new(1170.0, 0.0, 1540.0, -std::f64::consts::PI, 0.0, 0.0);
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
