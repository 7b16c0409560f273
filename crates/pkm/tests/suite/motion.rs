//! Motion: profiles, path derivatives, exact actuator velocity and acceleration, and
//! seed 000's arc study.

use nalgebra::{SVector, Vector3, Vector6};
use pkm::machine::Model;
use pkm::motion::gcode::Interpreter;
use pkm::motion::program::{to_move, FeedOptions, ProfileKind};
use pkm::motion::{Move, Profile, Runner, Sampling, Segment};
use pkm::tripod::{CentreLegTripod, TranslationalTripod};
use pkm::{Machine, Mechanism, Quantity};

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
        _ => panic!(),
    }
}

fn centre_leg() -> CentreLegTripod {
    match load("tripod-centre-leg.toml").model {
        Model::CentreLegTripod(t) => t,
        _ => panic!(),
    }
}

fn check_profile(p: &Profile, vmax: f64, amax: f64) {
    let (s_end, v_end, _) = p.eval(p.duration);
    assert!(
        (s_end - p.length).abs() < 1e-9 * p.length.max(1.0),
        "{s_end} vs {}",
        p.length
    );
    assert!(v_end.abs() < 1e-9 * vmax.max(1.0), "ends at rest: {v_end}");
    let h = 1e-6 * p.duration;
    let n = 400;
    for i in 1..n {
        let t = p.duration * i as f64 / n as f64;
        let (s, v, a) = p.eval(t);
        assert!(v <= vmax * (1.0 + 1e-9) && a.abs() <= amax * (1.0 + 1e-9));
        assert!(s >= -1e-12 && s <= p.length + 1e-9);
        let (sp, vp, _) = p.eval(t + h);
        let (sm, vm, _) = p.eval(t - h);
        assert!(((sp - sm) / (2.0 * h) - v).abs() < 1e-5 * vmax, "v at {t}");
        // Acceleration may jump at phase ends (trapezoid); compare away from them.
        let fd = (vp - vm) / (2.0 * h);
        if (fd - a).abs() > 1e-3 * amax {
            let (_, _, ap) = p.eval(t + 2.0 * h);
            let (_, _, am) = p.eval(t - 2.0 * h);
            assert!((ap - am).abs() > 1e-3 * amax, "a at {t}: {fd} vs {a}");
        }
    }
}

#[test]
fn profiles_reach_the_end_with_bounded_rates() {
    check_profile(
        &Profile::trapezoid(100.0, 50.0, 500.0).unwrap(),
        50.0,
        500.0,
    );
    check_profile(&Profile::trapezoid(2.0, 50.0, 500.0).unwrap(), 50.0, 500.0); // triangular
    check_profile(
        &Profile::scurve(100.0, 50.0, 500.0, 10_000.0).unwrap(),
        50.0,
        500.0,
    );
    check_profile(
        &Profile::scurve(1.0, 50.0, 500.0, 10_000.0).unwrap(),
        50.0,
        500.0,
    ); // short
    check_profile(
        &Profile::scurve(100.0, 50.0, 500.0, 1000.0).unwrap(),
        50.0,
        500.0,
    ); // no const-a phase
    let p = Profile::trapezoid_timed(135.0, 1.0, 0.1).unwrap();
    check_profile(&p, 150.0, 1500.0);
    assert!((p.duration - 1.0).abs() < 1e-12);
    assert!((p.eval(0.5).1 - 150.0).abs() < 1e-9);
    let c = Profile::constant(64.0, 10.0).unwrap();
    assert!((c.duration - 6.4).abs() < 1e-12);
    assert_eq!(c.eval(3.0), (30.0, 10.0, 0.0));
    assert!(Profile::trapezoid_timed(1.0, 1.0, 0.6).is_err());
    assert!(Profile::constant(1.0, 0.0).is_err());
}

#[test]
fn segment_derivatives_equal_finite_differences() {
    let q = [
        Quantity::Length,
        Quantity::Length,
        Quantity::Length,
        Quantity::Angle,
        Quantity::Angle,
        Quantity::Angle,
    ];
    let a = Vector6::new(10.0, 0.0, -290.0, 0.0, 0.05, 0.0);
    let b = Vector6::new(0.0, 10.0, -280.0, 0.1, 0.0, 0.0);
    let segs = [
        Segment::line(a, b, &q, true),
        Segment::arc(
            a,
            b,
            Vector3::new(0.0, 0.0, -290.0),
            Vector3::x(),
            Vector3::y(),
            std::f64::consts::FRAC_PI_2,
        )
        .unwrap(),
        Segment::arc(
            a,
            b,
            Vector3::new(0.0, 0.0, -290.0),
            Vector3::x(),
            Vector3::y(),
            -1.5 * std::f64::consts::PI,
        )
        .unwrap(),
    ];
    for seg in segs {
        let (x0, _, _) = seg.eval(0.0);
        let (x1, _, _) = seg.eval(seg.length);
        assert!(
            (x0 - a).amax() < 1e-9 && (x1 - b).amax() < 1e-9,
            "{x1} vs {b}"
        );
        let h = 1e-4;
        for i in 1..20 {
            let s = seg.length * i as f64 / 20.0;
            let (_, d1, d2) = seg.eval(s);
            let (xp, dp, _) = seg.eval(s + h);
            let (xm, dm, _) = seg.eval(s - h);
            assert!(((xp - xm) / (2.0 * h) - d1).amax() < 1e-7);
            assert!(((dp - dm) / (2.0 * h) - d2).amax() < 1e-6);
            // Unit speed of the tool tip along the path.
            assert!((d1.fixed_rows::<3>(0).norm() - 1.0).abs() < 1e-12);
        }
    }
}

/// Analytic actuator velocity and acceleration against central differences of IK
/// positions along a smooth motion x(t), relative 1e-6.
fn check_actuator_motion<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: impl Fn(f64) -> SVector<f64, P>,
) {
    let h = 1e-4;
    for i in 0..25 {
        let t = 0.05 + 0.9 * i as f64 / 24.0;
        let xd = (x(t + h) - x(t - h)) / (2.0 * h);
        let xdd = (x(t + h) - 2.0 * x(t) + x(t - h)) / (h * h);
        let mm = m.actuator_motion(&x(t), &xd, &xdd).unwrap();
        let q = |t: f64| m.inverse(&x(t)).unwrap();
        let qd_fd = (q(t + h) - q(t - h)) / (2.0 * h);
        let qdd_fd = (q(t + h) - 2.0 * q(t) + q(t - h)) / (h * h);
        let sv = qd_fd.amax().max(1e-3);
        let sa = qdd_fd.amax().max(1e-3);
        assert!((mm.q - q(t)).amax() < 1e-12);
        assert!(
            (mm.qd - qd_fd).amax() / sv < 1e-6,
            "velocity at {t}: {} vs {}",
            mm.qd,
            qd_fd
        );
        assert!(
            (mm.qdd - qdd_fd).amax() / sa < 1e-6,
            "acceleration at {t}: {} vs {}",
            mm.qdd,
            qdd_fd
        );
    }
}

#[test]
fn exact_actuator_rates_equal_central_differences() {
    // x(t) is a polynomial of degree 2, so its finite differences are exact and the
    // comparison tests the mechanism's derivatives alone.
    let t = translational();
    check_actuator_motion(&t, |s| {
        Vector6::new(
            20.0 * s - 10.0 * s * s,
            -15.0 * s + 30.0 * s * s,
            -290.0 + 12.0 * s * s,
            0.1 * s - 0.05 * s * s,
            -0.08 * s + 0.1 * s * s,
            0.3 * s * s,
        )
    });
    let c = centre_leg();
    check_actuator_motion(&c, |s| {
        Vector3::new(
            30.0 * s - 10.0 * s * s,
            -20.0 * s + 25.0 * s * s,
            -300.0 + 15.0 * s * s,
        )
    });
}

fn arc_program(feed: f64) -> Vec<Move<6>> {
    // Seed 000's study: a quarter arc of radius 64 mm in the XY plane (G17) at constant
    // feed, from (32, -32) about the centre (-32, -32) to (-32, 32), at Z = -290.
    let t = translational();
    let mut g = Interpreter::new([32.0, -32.0, -290.0, 0.0, 0.0, 0.0]);
    let gm = g
        .line(&format!("G17 G90 G3 X-32 Y32 I-64 J0 F{feed}"), 1)
        .unwrap()
        .unwrap();
    vec![to_move(
        &t,
        &gm,
        &FeedOptions {
            profile: ProfileKind::Constant,
            ..Default::default()
        },
    )
    .unwrap()]
}

fn run_arc(feed: f64) -> pkm::motion::MotionSummary {
    let t = translational();
    let mut r = Runner::new(&t, Sampling::Points(101)).unwrap();
    for mv in arc_program(feed) {
        r.run_move(&mv, true, &mut |_| Ok(())).unwrap();
    }
    r.finish()
}

#[test]
fn seed000_arc_study_serial_side() {
    for feed in [10.0, 100.0, 1000.0, 10_000.0] {
        let s = run_arc(feed);
        assert_eq!(s.samples, 101);
        let v = feed / 60.0;
        let (x, y, z) = (&s.serial[0].1, &s.serial[1].1, &s.serial[2].1);
        for axis in [x, y] {
            assert!((axis.travel - 64.0).abs() < 0.005 * 64.0, "{}", axis.travel);
            assert!((axis.peak_velocity - v).abs() < 0.005 * v);
            assert!((axis.peak_acceleration - v * v / 64.0).abs() < 0.005 * v * v / 64.0);
        }
        assert!(z.travel < 1e-9);
        assert!((s.duration_s - 64.0 * std::f64::consts::FRAC_PI_2 / v).abs() < 1e-9);
    }
    let s = run_arc(10_000.0);
    assert!((s.serial[0].1.peak_velocity - 166.667).abs() < 0.01);
    assert!((s.serial[0].1.peak_acceleration - 434.03).abs() < 0.01);
}

#[test]
fn seed000_arc_study_scaling_with_feed() {
    let base = run_arc(10.0);
    for feed in [100.0, 1000.0, 10_000.0] {
        let s = run_arc(feed);
        let k = feed / 10.0;
        for ((_, a), (_, b)) in base.actuators.iter().zip(&s.actuators) {
            assert!((b.travel - a.travel).abs() < 1e-9);
            assert!(
                (b.peak_velocity - k * a.peak_velocity).abs() < 1e-9 * k * a.peak_velocity.max(1.0)
            );
            assert!(
                (b.peak_acceleration - k * k * a.peak_acceleration).abs()
                    < 1e-8 * k * k * a.peak_acceleration.max(1.0)
            );
        }
        let (r, rb) = (s.ratios.unwrap(), base.ratios.unwrap());
        assert!((r.travel - rb.travel).abs() < 1e-9);
    }
    // The struts travel less than the serial axes (seed 000's point).
    let r = base.ratios.unwrap();
    assert!(r.travel > 1.0 && r.velocity.unwrap() > 1.0);
}

/// The ratios are seed 000's. Its "3.4x" and "3.3x" are the serial
/// peak over the largest strut peak (166.7 / 49, 434 / 131), its "3.6x" travel the mean
/// serial travel over the struts' mean travel; recomputed here from the axes'
/// statistics by hand.
#[test]
fn seed000_ratios_are_the_papers_definitions() {
    let s = run_arc(10_000.0);
    let r = s.ratios.unwrap();
    let acts: Vec<_> = s.actuators.iter().map(|(_, a)| *a).collect();
    let moving: Vec<_> = s
        .serial
        .iter()
        .map(|(_, a)| *a)
        .filter(|a| a.travel > 1e-9)
        .collect();
    assert_eq!(moving.len(), 2);
    let max = |v: &[pkm::motion::AxisStats], f: fn(&pkm::motion::AxisStats) -> f64| {
        v.iter().map(f).fold(0.0, f64::max)
    };
    let mean = |v: &[pkm::motion::AxisStats], f: fn(&pkm::motion::AxisStats) -> f64| {
        v.iter().map(f).sum::<f64>() / v.len() as f64
    };
    let vel = max(&moving, |a| a.peak_velocity) / max(&acts, |a| a.peak_velocity);
    let acc = max(&moving, |a| a.peak_acceleration) / max(&acts, |a| a.peak_acceleration);
    let travel = mean(&moving, |a| a.travel) / mean(&acts, |a| a.travel);
    let (r_acc, r_acc_mean) = (
        r.acceleration.unwrap(),
        r.acceleration_of_mean_peaks.unwrap(),
    );
    let r_vel = r.velocity.unwrap();
    assert!((r_vel - vel).abs() < 1e-12 && (r_acc - acc).abs() < 1e-12);
    assert!((r.travel - travel).abs() < 1e-12);
    // The bundled tripod (docs/motion.md): 166.667 / 67.51 and 434.03 / 204.27.
    assert!((r_vel - 2.469).abs() < 0.002, "{r_vel}");
    assert!((r_acc - 2.125).abs() < 0.002, "{r_acc}");
    assert!((r.travel - 3.77).abs() < 0.005, "{}", r.travel);
    // The means of peaks, labelled as such.
    assert!((r.velocity_of_mean_peaks.unwrap() - 3.50).abs() < 0.005);
    assert!((r_acc_mean - 3.12).abs() < 0.005);
}

/// A robot's joints turn: a ratio of the tool's mm to the joints' deg is not given.
#[test]
fn ratios_are_not_given_for_turning_drives() {
    let m = pkm::Machine::from_path(format!(
        "{}/../../examples/machines/kr30-dh.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let s = summary_at_100_hz(&m, "G91 G1 X10 Y5 F600\n");
    assert!(s.ratios.is_none());
}

/// The summary of `program` run through `m` from its home at 100 Hz, default feeds.
fn summary_at_100_hz(m: &pkm::Machine, program: &str) -> pkm::motion::MotionSummary {
    run_at_100_hz(m, program).summary
}

/// The program is read line by line into one buffer: CRLF and LF endings and a last
/// line without an ending give the same run, a lone CR at the end does no harm, and
/// bytes that are not UTF-8 name their line.
#[test]
fn program_lines_are_read_as_lines_reads_them() {
    let m = load("tripod-seed000.toml");
    let run = |bytes: &[u8]| {
        pkm::analysis::motion::run_motion(
            &m,
            pkm::analysis::motion::MotionSource::Gcode {
                reader: Box::new(std::io::Cursor::new(bytes.to_vec())),
                from: None,
                setup: Default::default(),
            },
            &pkm::motion::program::FeedOptions::default(),
            Sampling::Rate(100.0),
            &mut pkm::analysis::motion::NoSink,
        )
    };
    let lf = run(b"G21 G90\nG1 X5 Y2 F600\nG1 X-3 Y4\n").unwrap().summary;
    let crlf = run(b"G21 G90\r\nG1 X5 Y2 F600\r\nG1 X-3 Y4")
        .unwrap()
        .summary;
    assert!(lf.samples > 10);
    assert_eq!(format!("{lf:?}"), format!("{crlf:?}"));
    // A CR with no LF after it stays in the line (as `BufRead::lines` leaves it); the
    // parser takes it for a space.
    let cr = run(b"G21 G90\nG1 X5 Y2 F600\nG1 X-3 Y4\r").unwrap().summary;
    assert_eq!(format!("{lf:?}"), format!("{cr:?}"));
    let e = run(b"G21 G90\nG1 X5 F600\n(\xff)\nG1 X6\n")
        .unwrap_err()
        .to_string();
    assert!(e.contains("reading line 3") && e.contains("UTF-8"), "{e}");
}

/// Straight moves under the constant profile never accelerate the serial axes: the
/// acceleration ratios are not given (they read 0, "the serial machine needs none").
/// An arc at the same constant feed, or the same lines with a trapezoid, has them. A
/// move no sample catches in motion has no velocity ratios either.
#[test]
fn acceleration_ratios_need_a_serial_acceleration() {
    let m = load("tripod-seed000.toml");
    let lines = "G21 G90\nG1 X5 Y2 F600\nG1 X-3 Y4\nG1 X0 Y0\n";
    let r = summary_at_100_hz(&m, lines).ratios.unwrap();
    assert!(r.travel > 0.0 && r.velocity.unwrap() > 0.0, "{r:?}");
    assert_eq!((r.acceleration, r.acceleration_of_mean_peaks), (None, None));
    let arc = "G21 G90 G17\nG1 X5 Y0 F600\nG3 X-5 Y0 I-5 J0\n";
    let r = summary_at_100_hz(&m, arc).ratios.unwrap();
    assert!(r.acceleration.unwrap() > 0.0 && r.acceleration_of_mean_peaks.unwrap() > 0.0);
    let trapezoid = |program: &str| {
        let feed = pkm::motion::program::FeedOptions {
            profile: pkm::motion::program::ProfileKind::Trapezoid,
            ..Default::default()
        };
        pkm::analysis::motion::run_motion(
            &m,
            pkm::analysis::motion::MotionSource::Gcode {
                reader: Box::new(std::io::Cursor::new(program.as_bytes().to_vec())),
                from: None,
                setup: Default::default(),
            },
            &feed,
            Sampling::Rate(100.0),
            &mut pkm::analysis::motion::NoSink,
        )
        .unwrap()
        .summary
        .ratios
        .unwrap()
    };
    let r = trapezoid(lines);
    assert!(r.velocity.unwrap() > 0.0 && r.acceleration.unwrap() > 0.0);
    // A move shorter than the 10 ms period: sampled at its ends, at rest. Its velocity
    // ratios are not given (they read 0 / 0, printed as `inf`); the trapezoid's first
    // sample accelerates, so that ratio is.
    let r = trapezoid("G21 G90\nG1 X0.002 F600\n");
    assert!(r.travel > 0.0, "{r:?}");
    assert_eq!((r.velocity, r.velocity_of_mean_peaks), (None, None));
    assert!(r.acceleration.unwrap() > 0.0);
}

/// A program without motion (no samples, or a dwell) has no ratios: nothing over
/// nothing, where `inf` was reported.
#[test]
fn ratios_are_not_given_when_nothing_moves() {
    let m = load("tripod-seed000.toml");
    for program in ["G21 G90\nM2\n", "G21 G90\nG4 P0.5\nM2\n"] {
        let s = summary_at_100_hz(&m, program);
        // The dwell has samples: the case of a run that stands still.
        assert_eq!(s.samples > 0, program.contains("G4"), "{program}");
        assert!(s.ratios.is_none(), "{program}: {:?}", s.ratios);
    }
}

#[test]
fn limits_and_feed_override_along_the_path() {
    let t = translational();
    // At 10 000 mm/min the struts stay below 200 mm/s and 2000 mm/s^2.
    let s = run_arc(10_000.0);
    let k = s.feed_override_max.unwrap();
    assert!(k > 1.0, "{k}");
    // Scaled by the override the program just meets a limit; a bit more violates it.
    let s = run_arc(10_000.0 * k * 1.01);
    assert!(!s.violations.is_empty());
    assert!(s.violations[0].limit.contains("actuator"));
    assert_eq!(s.violations[0].line, Some(1));
    let s = run_arc(10_000.0 * k * 0.99);
    assert!(s.violations.is_empty(), "{:?}", s.violations);
    // A move that changes the held orientation is refused.
    let mut g = Interpreter::new([0.0, 0.0, -290.0, 0.0, 0.0, 0.0]);
    let gm = g.line("G1 X1 A5 F100", 7).unwrap().unwrap();
    let mv = to_move(&t, &gm, &FeedOptions::default()).unwrap();
    let mut r = Runner::new(&t, Sampling::Rate(100.0)).unwrap();
    let e = r.run_move(&mv, true, &mut |_| Ok(())).unwrap_err();
    assert!(
        e.to_string().contains("line 7") && e.to_string().contains("holds"),
        "{e}"
    );
}

/// A dwell of 30 years, a feed of a micrometre per minute, 1e8 full turns
/// and 1e11 points per move once ran for hours. Each move's samples are now counted before
/// it is sampled and a run beyond the work limit is refused at once, naming the line;
/// the limit is the caller's to raise.
#[test]
fn motion_work_is_bounded_before_it_is_done() {
    use pkm::analysis::motion::{run_motion, MotionSource, NoSink};
    let m = load("tripod-seed000.toml");
    let run = |program: &str, sampling: Sampling, max: u64| {
        let t = std::time::Instant::now();
        let r = run_motion(
            &m,
            MotionSource::Gcode {
                reader: Box::new(std::io::Cursor::new(program.to_string())),
                from: Some(vec![32.0, -32.0, -290.0, 0.0, 0.0, 0.0]),
                setup: Default::default(),
            },
            &FeedOptions {
                max_samples: max,
                ..Default::default()
            },
            sampling,
            &mut NoSink,
        );
        // Refused before any work: well under a second even in a debug build.
        assert!(t.elapsed().as_secs_f64() < 5.0);
        r
    };
    let default = pkm::motion::run::DEFAULT_MAX_SAMPLES;
    for (program, sampling, line) in [
        ("G4 P1000000000\n", Sampling::Rate(1000.0), 1),
        ("G1 X33 F0.000001\n", Sampling::Rate(1000.0), 1),
        (
            "G17 G90 G91.1\nG3 X32 Y-32 I-64 J0 P100000000 F1000\n",
            Sampling::Rate(1000.0),
            2,
        ),
        ("G1 X33 F1000\n", Sampling::Points(100_000_000_000), 1),
    ] {
        let e = run(program, sampling, default).unwrap_err().to_string();
        assert!(
            e.contains(&format!("line {line}:")) && e.contains("beyond the limit"),
            "{program}: {e}"
        );
    }
    // The limit counts the whole run: a short program passes, and fails under a limit
    // lower than its samples, at its second move.
    let ok = run("G1 X33 F600\nG1 X34\n", Sampling::Rate(1000.0), default).unwrap();
    let n = ok.summary.samples;
    assert!(n > 100, "{n}");
    let e = run("G1 X33 F600\nG1 X34\n", Sampling::Rate(1000.0), n - 10)
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 2:"), "{e}");
    // The estimate rounds each move up by at most two samples.
    assert!(run("G1 X33 F600\nG1 X34\n", Sampling::Rate(1000.0), n + 4).is_ok());
}

/// A feed or rapid rate beyond 1e6 mm/s (`--feed 1e300` once failed in the plots on
/// NaN velocities), and a duration that is not positive and finite or too short to
/// sample (`--duration 0` once gave one sample at the end pose, travel 0, exit 0), are
/// refused before the run, naming the option, the value and the range.
#[test]
fn absurd_feeds_and_durations_are_refused() {
    use pkm::analysis::motion::{run_motion, MotionSource, NoSink};
    let m = load("hexapod-linuxcnc.toml");
    let run = |feed: &FeedOptions, duration: Option<f64>| {
        let source = MotionSource::PointToPoint {
            from: vec![0.0, 0.0, 508.0, 0.0, 0.0, 0.0],
            to: vec![1.0, 0.0, 508.0, 0.0, 0.0, 0.0],
            duration,
            accel_time: None,
        };
        run_motion(&m, source, feed, Sampling::Rate(1000.0), &mut NoSink)
    };
    let at = |v: f64| FeedOptions {
        feed: Some(v),
        ..Default::default()
    };
    for v in [1e300 / 60.0, f64::INFINITY, f64::NAN, 0.0, -1.0, 2e6] {
        let e = run(&at(v), None).unwrap_err().to_string();
        assert!(
            e.starts_with("feed: expected a feed in (0, 6e7] mm/min (1e6 mm/s), got "),
            "{v}: {e}"
        );
    }
    assert!(run(&at(1e6), None).is_ok());
    let rapid = FeedOptions {
        rapid: 1e300,
        ..at(10.0)
    };
    let e = run(&rapid, None).unwrap_err().to_string();
    assert!(
        e.starts_with("rapid: expected a rapid rate in (0, 6e7]"),
        "{e}"
    );
    let e = run(&at(1e300), None).unwrap_err().to_string();
    assert!(e.contains("got 6e301 mm/min (1e300 mm/s)"), "{e}");
    for d in [0.0, 5e-324, 1e-200, 1e-7, -1.0, f64::NAN, f64::INFINITY] {
        let e = run(&FeedOptions::default(), Some(d))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("--duration: expected a finite duration of at least 1e-6 s, got "),
            "{d}: {e}"
        );
    }
    // Long enough to sample, but a millimetre in 1e-6 s is 1e6 mm/s: the fastest taken.
    let ok = run(&FeedOptions::default(), Some(1e-6)).unwrap();
    assert!(ok.summary.samples >= 2);
    let far = MotionSource::PointToPoint {
        from: vec![0.0, 0.0, 508.0, 0.0, 0.0, 0.0],
        to: vec![10.0, 0.0, 508.0, 0.0, 0.0, 0.0],
        duration: Some(1e-6),
        accel_time: None,
    };
    let e = run_motion(
        &m,
        far,
        &FeedOptions::default(),
        Sampling::Rate(1e3),
        &mut NoSink,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("makes 1e7 mm/s, beyond the fastest accepted"),
        "{e}"
    );
    assert!(e.ends_with("expected at least 1e-5 s"), "{e}");
    // A program's own feed, per minute or in inverse time, is held to the same range.
    for program in ["G1 X1 F99999999999\n", "G93 G1 X1 F99999999999\n"] {
        let source = MotionSource::Gcode {
            reader: Box::new(std::io::Cursor::new(program.to_string())),
            from: Some(vec![0.0, 0.0, 508.0, 0.0, 0.0, 0.0]),
            setup: Default::default(),
        };
        let feed = FeedOptions::default();
        let e = run_motion(&m, source, &feed, Sampling::Rate(1e3), &mut NoSink)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("G-code line 1: expected a"), "{program}: {e}");
        assert!(
            e.contains(" in (0, 6e7] mm/min (1e6 mm/s), got "),
            "{program}: {e}"
        );
    }
}

/// `Decimated` keeps at most its cap, evenly spaced, the first item always.
#[test]
fn decimated_streams_keep_evenly_spaced_items() {
    use pkm::analysis::motion::Decimated;
    for n in [1usize, 99, 100, 101, 1000, 12_345] {
        let mut d = Decimated::new(100);
        for i in 0..n {
            d.push(|| i);
        }
        assert!(d.len() <= 100 && !d.is_empty(), "{n}: {}", d.len());
        assert_eq!(d[0], 0);
        let gaps: Vec<usize> = d.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps.windows(2).all(|g| g[0] == g[1]), "{n}: {gaps:?}");
        // Enough kept: more than half the cap once the stream is longer than it.
        assert!(d.len() > n.min(100) / 2, "{n}: {}", d.len());
    }
}

/// The study circle: every point of the circle the report runs is within
/// every limit, checked at ten times the points the search used; a circle 3 % larger
/// than the largest one found leaves the limits; its program runs to its end with no
/// violation and the tool travels 2 pi r.
#[test]
fn the_study_circle_fits_and_a_larger_one_does_not() {
    use pkm::analysis::motion::{feed_options, run_motion, study_circle, MotionSource, NoSink};
    let m = crate::common::fixture("own-hexapod.toml");
    let home = m.mechanism().home();
    let c = study_circle(&m, &home, 0.8).unwrap();
    assert!(!c.moved);
    assert!(
        c.radius <= 0.8 * c.largest && c.radius > 0.79 * c.largest,
        "{c:?}"
    );
    let within = |r: f64| {
        (0..720).all(|k| {
            let t = std::f64::consts::TAU * k as f64 / 720.0;
            let mut x = home.clone();
            x[0] += r * t.cos();
            x[1] += r * t.sin();
            let q = m.mechanism().inverse(&x).unwrap();
            m.mechanism().check_limits(&x, &q).unwrap().is_empty()
        })
    };
    assert!(within(c.radius));
    assert!(!within(1.03 * c.largest), "{c:?}");
    let out = run_motion(
        &m,
        MotionSource::Gcode {
            reader: Box::new(std::io::Cursor::new(c.program(1000.0).into_bytes())),
            from: Some(c.start()),
            setup: Default::default(),
        },
        &feed_options(&m),
        Sampling::Rate(1000.0),
        &mut NoSink,
    )
    .unwrap();
    assert!(out.summary.violations.is_empty());
    let expected = std::f64::consts::TAU * c.radius / (1000.0 / 60.0);
    assert!(
        (out.summary.duration_s - expected).abs() < 1e-6,
        "{}",
        out.summary.duration_s
    );
}

/// A rapid runs each axis of a 5-axis machine at most at its own rate, all arriving
/// together, as a controller runs G0: the head's A (limit 50 deg/s here) and the
/// table's C (180 deg/s) within their limits, the move as long as its slowest axis
/// (A's 90 deg at 50 deg/s: 1.8 s), not the tip's rapid rate read as deg/s
/// (166.7 deg/s, past A's limit). And a feed override scales the feed moves, not
/// the rapids: the largest feed override is the feed move's.
#[test]
fn rapids_run_each_axis_at_its_own_rate_and_are_not_feed_overridden() {
    let path = format!(
        "{}/../../examples/machines/head-table-5axis.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("max_velocity = 90.0", "max_velocity = 50.0");
    assert!(text.contains("max_velocity = 50.0"));
    let m = Machine::from_toml_str(&text, "head-table-a50.toml").unwrap();
    let s = summary_at_100_hz(&m, "G21 G90\nG0 A90 C180\nM2\n");
    assert!(s.violations.is_empty(), "{:?}", s.violations);
    // 1.8 s of motion (the samples are taken at 100 Hz, the last at the end).
    assert!((s.duration_s - 1.8).abs() < 1e-9, "{}", s.duration_s);
    let peak = |name: &str| {
        s.actuators
            .iter()
            .find(|(n, _)| n == name)
            .unwrap()
            .1
            .peak_velocity
    };
    assert!((peak("A") - 50.0).abs() < 1e-9, "{}", peak("A"));
    assert!((peak("C") - 100.0).abs() < 1e-9, "{}", peak("C"));
    // Only rapids: no feed override, the rapids' own just 1 (A at its limit).
    assert_eq!(s.feed_override_max, None);
    let k = s.rapid_override_max.unwrap();
    assert!((k - 1.0).abs() < 1e-9, "{k}");
    // A feed move at 1000 mm/min beside the rapids: its override is its own
    // (the slides' 300-400 mm/s over 16.7 mm/s of tip feed, far above 1).
    let s = summary_at_100_hz(&m, "G21 G90\nG0 A90 C180\nG1 X20 F1000\nG0 A0 C0\nM2\n");
    assert!(s.violations.is_empty(), "{:?}", s.violations);
    let k = s.feed_override_max.unwrap();
    assert!(k > 5.0, "{k}");
    assert!((s.rapid_override_max.unwrap() - 1.0).abs() < 1e-9);
}

/// On a machine whose pose coordinates are not its axes (a hexapod's struts), a
/// rapid takes the tip's rapid rate, the rotary coordinates at that rate in deg/s:
/// the duration is the larger of the tip's distance and the largest turn over it.
#[test]
fn rapids_of_a_hexapod_take_the_rapid_rate() {
    let m = load("hexapod-linuxcnc.toml");
    let program = "G21 G91\nG0 X100 A10\nM2\n";
    let s = summary_at_100_hz(&m, program);
    // 100 mm at 10 000 mm/min: 0.6 s (the A turn of 10 deg would take 0.06 s).
    assert!((s.duration_s - 0.6).abs() < 1e-9, "{}", s.duration_s);
}

/// The run of `program` through `m` from its home at 100 Hz, default feeds.
fn run_at_100_hz(m: &pkm::Machine, program: &str) -> pkm::analysis::motion::MotionRun {
    pkm::analysis::motion::run_motion(
        m,
        pkm::analysis::motion::MotionSource::Gcode {
            reader: Box::new(std::io::Cursor::new(program.as_bytes().to_vec())),
            from: None,
            setup: Default::default(),
        },
        &FeedOptions::default(),
        Sampling::Rate(100.0),
        &mut pkm::analysis::motion::NoSink,
    )
    .unwrap()
}

/// A robot whose home orientation reads A = -180 deg, given the same orientation as
/// A180: the move turns A through 360 deg (A, B, C interpolated linearly, as LinuxCNC
/// does), and the run says so with a note naming the nearer angle. A machine tool's
/// rotary table told to turn a whole turn turns it, without a note.
#[test]
fn a_whole_turn_of_an_orientation_angle_is_noted() {
    let m = crate::common::fixture("ur5-dh.toml");
    let home = m.mechanism().home();
    assert!((home[3].to_degrees() + 180.0).abs() < 1e-9, "{home:?}");
    let run = run_at_100_hz(&m, "G21 G90\nG1 A180 F1000\nM2\n");
    let notes: Vec<_> = run
        .notes
        .iter()
        .filter(|(_, n)| n.contains("turns"))
        .collect();
    assert_eq!(notes.len(), 1, "{:?}", run.notes);
    let (line, text) = notes[0];
    assert_eq!(*line, 2);
    assert!(
        text.starts_with("A turns 360.000 deg, from -180.000 to 180.000 deg: A-180.000"),
        "{text}"
    );
    // Less than half a turn: no note.
    let run = run_at_100_hz(&m, "G21 G91\nG1 A170 F1000\nM2\n");
    assert!(
        !run.notes.iter().any(|(_, n)| n.contains("turns")),
        "{:?}",
        run.notes
    );
    // A rotary table's whole turn is a whole turn.
    let t = load("head-table-5axis.toml");
    let run = run_at_100_hz(&t, "G21 G90\nG0 C360\nM2\n");
    assert!(run.notes.is_empty(), "{:?}", run.notes);
}
