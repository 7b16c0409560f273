//! A run split across threads (`motion/plan.rs`: blocks of samples computed on the
//! rayon pool while the caller plans and records) gives what the same run gives on one
//! thread: every sample bit for bit, the summary, the accuracy along the path, and the
//! same error after the same samples when a move is refused, a pose is out of reach or
//! the sink fails.
//!
//! The one-thread run is the run inside a rayon pool of one thread; the other uses the
//! global pool (as many threads as cores: on a one-core machine both take the one-thread
//! path and the test still checks the results against each other).

use pkm::analysis::motion::{
    feed_options, run_motion_with, MotionRun, MotionSource, PathAccuracyRequest, ProgramSetup,
    SampleRow, SampleSink,
};
use pkm::motion::Sampling;
use pkm::Machine;

fn load(name: &str) -> Machine {
    Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// Every sample as its bits: t, line, pose, q, q', q''.
#[derive(Default)]
struct Rows {
    rows: Vec<Vec<u64>>,
    /// Fails on this sample (0-based), when set.
    fail_at: Option<usize>,
    /// Samples offered after the failure (the run should have stopped).
    after_failure: usize,
}

impl SampleSink for Rows {
    fn sample(&mut self, s: &SampleRow) -> pkm::Result<()> {
        if Some(self.rows.len()) == self.fail_at {
            self.after_failure += 1;
            return Err(pkm::Error::InvalidInput {
                what: "sink".into(),
                message: format!("refused sample {}", self.rows.len()),
            });
        }
        let mut r = vec![s.t.to_bits(), s.line.unwrap_or(u64::MAX)];
        for v in [s.x, s.q, s.qd, s.qdd] {
            r.extend(v.iter().map(|x| x.to_bits()));
        }
        self.rows.push(r);
        Ok(())
    }
}

struct Outcome {
    rows: Rows,
    result: pkm::Result<MotionRun>,
}

fn run(
    m: &Machine,
    program: &str,
    setup: ProgramSetup,
    rate: f64,
    accuracy: Option<&PathAccuracyRequest>,
    fail_at: Option<usize>,
    one_thread: bool,
) -> Outcome {
    let go = || {
        let mut rows = Rows {
            fail_at,
            ..Default::default()
        };
        let result = run_motion_with(
            m,
            MotionSource::Gcode {
                reader: Box::new(std::io::Cursor::new(program.to_string())),
                from: None,
                setup: Box::new(setup.clone()),
            },
            &feed_options(m),
            Sampling::Rate(rate),
            accuracy,
            &mut rows,
        );
        Outcome { rows, result }
    };
    if one_thread {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(go)
    } else {
        go()
    }
}

/// The run on one thread and on many, checked equal.
fn both(
    m: &Machine,
    program: &str,
    setup: ProgramSetup,
    rate: f64,
    accuracy: Option<&PathAccuracyRequest>,
    fail_at: Option<usize>,
) -> (Outcome, Outcome) {
    let one = run(m, program, setup.clone(), rate, accuracy, fail_at, true);
    let many = run(m, program, setup, rate, accuracy, fail_at, false);
    same(&one, &many);
    (one, many)
}

fn same(a: &Outcome, b: &Outcome) {
    assert_eq!(a.rows.rows.len(), b.rows.rows.len());
    for (k, (x, y)) in a.rows.rows.iter().zip(&b.rows.rows).enumerate() {
        assert_eq!(x, y, "sample {k}");
    }
    match (&a.result, &b.result) {
        (Ok(x), Ok(y)) => {
            assert_eq!(x.summary, y.summary);
            assert_eq!(x.notes, y.notes);
            let json = |r: &MotionRun| serde_json::to_string(&r.accuracy).unwrap();
            assert_eq!(json(x), json(y));
            let traces = |r: &MotionRun| serde_json::to_string(&r.traces).unwrap();
            assert_eq!(traces(x), traces(y));
        }
        (Err(x), Err(y)) => assert_eq!(x.to_string(), y.to_string()),
        (x, y) => panic!("{:?} against {:?}", x.is_ok(), y.is_ok()),
    }
}

/// A hexapod program of many blocks whose path leaves the struts' range for a while.
fn hexapod_program(lines: usize) -> String {
    let mut s = String::from("G21 G90 G17\nG0 X0 Y40 Z508 A0 B0 C0\nF2400\n");
    for i in 0..lines {
        let t = i as f64 * 0.01;
        // Z dips below the struts' range around the middle of the program.
        let dip = if (lines / 2..lines / 2 + 40).contains(&i) {
            320.0
        } else {
            0.0
        };
        s += &format!(
            "G1 X{:.4} Y{:.4} Z{:.4} A{:.4} B{:.4}\n",
            40.0 * (t * 0.7).sin(),
            40.0 * (t * 0.53).cos(),
            508.0 + 5.0 * (t * 1.3).sin() - dip,
            3.0 * (t * 0.2).sin(),
            3.0 * (t * 0.17).cos()
        );
    }
    s + "M2\n"
}

#[test]
fn a_hexapod_run_is_the_same_on_one_thread_and_many() {
    let m = load("hexapod-linuxcnc.toml");
    let text = hexapod_program(1500);
    let accuracy = PathAccuracyRequest {
        machines: 4,
        every: 50,
        ..Default::default()
    };
    let (one, _) = both(&m, &text, Default::default(), 1000.0, Some(&accuracy), None);
    let r = one.result.as_ref().unwrap();
    // Several blocks, and the dip is reported as a stretch of strut violations.
    assert!(one.rows.rows.len() > 5 * 4096, "{}", one.rows.rows.len());
    assert!(
        r.summary
            .violations
            .iter()
            .any(|v| v.limit.contains("strut")),
        "{:?}",
        r.summary.violations
    );

    // A sink that fails stops the run at once, with its error, whatever the threads.
    for k in [0, 511, 512, 4095, 4096, 9000] {
        let (_, many) = both(&m, &text, Default::default(), 1000.0, None, Some(k));
        assert_eq!((many.rows.rows.len(), many.rows.after_failure), (k, 1));
        let e = many.result.as_ref().err().unwrap().to_string();
        assert!(e.contains(&format!("refused sample {k}")), "{e}");
    }

    // A move refused while planning (here a bad word on line 900) comes after every
    // sample of the moves before it, as on one thread.
    let mut lines: Vec<&str> = text.lines().collect();
    lines[899] = "G1 X1 Q";
    let bad = lines.join("\n");
    let (_, many) = both(&m, &bad, Default::default(), 1000.0, None, None);
    let e = many.result.as_ref().err().unwrap().to_string();
    assert!(e.contains("900"), "{e}");
    assert!(many.rows.rows.len() > 4096, "{}", many.rows.rows.len());
}

#[test]
fn a_robot_run_out_of_reach_fails_after_the_same_samples() {
    // The KR 30 along X: the arm cannot reach 3 m out; the run fails at the first
    // sample beyond its reach, after every sample before it.
    let m = load("kr30-dh.toml");
    let text = "G21 G90\nG0 X1170 Y0 Z1400 A180 B0 C0\nG1 X1300 F6000\nG1 X3000\nG1 X1200\n";
    let (one, _) = both(&m, text, Default::default(), 1000.0, None, None);
    let e = one.result.as_ref().err().unwrap().to_string();
    assert!(e.contains("line 4"), "{e}");
    assert!(one.rows.rows.len() > 4096, "{}", one.rows.rows.len());
}

/// The KR 30 turning its wrist past half a turn and beyond A6's range: blocks computed
/// apart, then continued in order (`motion/follow.rs`), give the same samples and
/// limit stretches on one thread and many.
#[test]
fn a_robot_run_carrying_its_turns_on_is_the_same_on_one_thread_and_many() {
    let m = load("kr30-dh.toml");
    let text = "G21 G90\nG1 C300 F3000\nG1 X1000 C-40\nG1 C400\nG1 X1170 Z1400 C100\n";
    let (one, _) = both(&m, text, Default::default(), 1000.0, None, None);
    let summary = &one.result.as_ref().unwrap().summary;
    assert!(one.rows.rows.len() > 5 * 4096, "{}", one.rows.rows.len());
    assert_eq!(summary.violations.len(), 1, "{:?}", summary.violations);
    assert!(summary.actuators[5].1.min < -350.0);
}

#[test]
fn a_five_axis_run_with_tool_changes_is_the_same_on_one_thread_and_many() {
    // LinuxCNC's boat program through the MC 300: G43 H1 at line 12, G49 at 1863; the
    // tool length reaches the samples after it and the accuracy along the path.
    let m = load("mc300.toml");
    let text = std::fs::read_to_string(format!(
        "{}/../../tests/fixtures/linuxcnc/xyzbc-trt/boat-xyzbc.ngc",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let setup = ProgramSetup {
        tool_lengths: [(1, 50.0)].into_iter().collect(),
        ..Default::default()
    };
    let accuracy = PathAccuracyRequest {
        machines: 3,
        every: 200,
        ..Default::default()
    };
    let (one, _) = both(&m, &text, setup, 100.0, Some(&accuracy), None);
    assert!(one.result.is_ok());
    assert!(one.rows.rows.len() > 3 * 4096, "{}", one.rows.rows.len());
}

/// A hexapod program sweeping in and out of every limit family: strut range, joint
/// cones, strut interference, axis travel.
fn wild_program(lines: usize) -> String {
    let mut s = String::from("G21 G90 G17\nG0 X0 Y0 Z508 A0 B0 C0\nF6000\n");
    for i in 0..lines {
        let t = i as f64 * 0.05;
        s += &format!(
            "G1 X{:.4} Y{:.4} Z{:.4} A{:.4} B{:.4} C{:.4}\n",
            160.0 * (t * 0.7).sin(),
            160.0 * (t * 0.53).cos(),
            520.0 + 140.0 * (t * 1.3).sin(),
            25.0 * (t * 0.9).sin(),
            25.0 * (t * 0.61).cos(),
            50.0 * (t * 0.37).sin()
        );
    }
    s + "M2\n"
}

#[test]
fn the_screened_motion_equals_the_checked_call_sample_by_sample() {
    // Poses the hexapod's block screen clears take `actuator_motion` alone: every
    // sample's q, q', q'' must be the bits of `actuator_motion_checked`, and the
    // stretches of violations those rebuilt from a checked call per sample.
    use pkm::limits::LimitKind;
    use pkm::machine::Model;
    use pkm::motion::program::to_move;
    use pkm::motion::{gcode::Interpreter, Runner};
    use pkm::Mechanism;
    // LinuxCNC's hexapod with an X travel and thick struts, so every family is met.
    let text = std::fs::read_to_string(format!(
        "{}/../../examples/machines/hexapod-linuxcnc.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .replacen(
        "[limits]\n",
        "[limits]\naxes = { X = [-150.0, 150.0] }\n",
        1,
    )
    .replacen("strut_diameter = 25.0", "strut_diameter = 90.0", 1);
    let Model::Hexapod(h) = Machine::from_toml_str(&text, "hex.toml").unwrap().model else {
        panic!()
    };
    let h = *h;
    let o = pkm::motion::program::FeedOptions::default();
    let mut g = Interpreter::new([0.0; 6]);
    let moves: Vec<_> = wild_program(400)
        .lines()
        .enumerate()
        .filter_map(|(i, l)| g.line(l, i as u64 + 1).unwrap())
        .map(|gm| to_move(&h, &gm, &o).unwrap())
        .collect();
    let mut r = Runner::new(&h, Sampling::Rate(1000.0)).unwrap();
    // Per limit (rates aside): its stretches of consecutive violating samples (start,
    // end, worst value), built here by name from the per-sample violations.
    type Stretch = (String, u64, u64, u64);
    let mut open: std::collections::HashMap<String, usize> = Default::default();
    let mut stretches: Vec<Stretch> = Vec::new();
    let mut worst_excess: Vec<f64> = Vec::new();
    let mut samples = 0;
    let n = moves.len();
    for (k, mv) in moves.iter().enumerate() {
        r.run_move(mv, k + 1 == n, &mut |s| {
            let mut v = Vec::new();
            let act = h.actuator_motion_checked(&s.x, &s.xd, &s.xdd, &mut v)?;
            for (a, b) in [(act.q, s.act.q), (act.qd, s.act.qd), (act.qdd, s.act.qdd)] {
                assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "t = {}", s.t);
            }
            open.retain(|name, _| v.iter().any(|x| x.limit == *name));
            for x in &v {
                let t = s.t.to_bits();
                match open.get(x.limit.as_str()) {
                    Some(&k) => {
                        stretches[k].2 = t;
                        if x.excess > worst_excess[k] {
                            (stretches[k].3, worst_excess[k]) = (x.value.to_bits(), x.excess);
                        }
                    }
                    None => {
                        open.insert(x.limit.to_string(), stretches.len());
                        stretches.push((x.limit.to_string(), t, t, x.value.to_bits()));
                        worst_excess.push(x.excess);
                    }
                }
            }
            samples += 1;
            Ok(())
        })
        .unwrap();
    }
    let summary = r.finish();
    let rates = [LimitKind::ActuatorVelocity, LimitKind::ActuatorAcceleration];
    let mut runs: Vec<Stretch> = summary
        .violations
        .iter()
        .filter(|v| !rates.contains(&v.kind))
        .map(|v| {
            let (a, b, w) = (v.start_s, v.end_s, v.worst);
            (v.limit.clone(), a.to_bits(), b.to_bits(), w.to_bits())
        })
        .collect();
    let kinds: std::collections::BTreeSet<String> = summary
        .violations
        .iter()
        .map(|v| format!("{:?}", v.kind))
        .collect();
    assert!(samples > 8 * 4096, "{samples}");
    assert_eq!(kinds.len(), 4, "{kinds:?}");
    assert!(stretches.len() > 20, "{} stretches", stretches.len());
    stretches.sort();
    runs.sort();
    assert_eq!(stretches, runs);
}

#[test]
fn run_move_stops_at_a_failing_sink() {
    // One move of ~10 000 samples (about twenty blocks) through `Runner::run_move`: a
    // sink failing at sample k sees no sample after it.
    use pkm::machine::Model;
    use pkm::motion::{Move, Profile, Runner, Segment};
    let Model::Hexapod(h) = load("hexapod-linuxcnc.toml").model else {
        panic!()
    };
    let h = *h;
    let home = pkm::Mechanism::info(&h).home();
    let mut to = home;
    to[0] += 50.0;
    let q = [pkm::Quantity::Length; 6];
    let seg = Segment::line(home, to, &q, true);
    let mv = Move {
        profile: Profile::constant(seg.length, 5.0).unwrap(),
        segment: seg,
        line: Some(1),
        rapid: false,
    };
    for k in [0usize, 511, 512, 4095, 4096, 9000] {
        let mut r = Runner::new(&h, Sampling::Rate(1000.0)).unwrap();
        let mut calls = 0usize;
        let e = r
            .run_move(&mv, false, &mut |_| {
                calls += 1;
                if calls > k {
                    return Err(pkm::Error::InvalidInput {
                        what: "sink".into(),
                        message: "full".into(),
                    });
                }
                Ok(())
            })
            .unwrap_err();
        assert!(e.to_string().contains("full"), "{e}");
        assert_eq!(calls, k + 1);
    }
    // Whole, the move has its 10 001 samples.
    let mut r = Runner::new(&h, Sampling::Rate(1000.0)).unwrap();
    let mut n = 0;
    r.run_move(&mv, true, &mut |_| {
        n += 1;
        Ok(())
    })
    .unwrap();
    assert_eq!(n, 10_001);
}
