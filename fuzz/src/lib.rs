//! The fuzz targets' bodies: one function per parser pkm reads a user's file with.
//!
//! Each takes arbitrary bytes, parses them as the CLI would and, when the parse
//! succeeds, runs the first analysis a user would run on the result, so a value the
//! parser let through that the model cannot take is found as well. Errors are the
//! expected outcome of most inputs; a panic, a hang or an out-of-memory is the finding.
//! Besides not crashing, every target checks one invariant of what it returns
//! (round trips within tolerance, finite numbers), so a silent wrong answer is a
//! finding too.
//!
//! Built by `cargo fuzz` (nightly, `fuzz/fuzz_targets/`); the same functions replay
//! `fuzz/corpus/` and `fuzz/artifacts/` in the stable test
//! `crates/pkm/tests/fuzz_corpus.rs`.

use std::sync::OnceLock;

use pkm::analysis::accuracy::{accuracy, AccuracyOptions, Tolerances};
use pkm::analysis::identification::{calibrate, parse_measurements, CalibrateOptions};
use pkm::analysis::motion::{run_motion, MotionSource, NoSink};
use pkm::motion::program::FeedOptions;
use pkm::motion::Sampling;
use pkm::Machine;

/// Samples a fuzzed program may compute (a program over it gets the work-limit error).
const MAX_SAMPLES: u64 = 5_000;
/// Measured states above which a fuzzed measurement file is parsed but not calibrated.
const MAX_CALIBRATED_STATES: usize = 40;

fn example(name: &str, text: &'static str) -> Machine {
    Machine::from_toml_str(text, name).expect("example machine loads")
}

fn tripod() -> &'static Machine {
    static M: OnceLock<Machine> = OnceLock::new();
    M.get_or_init(|| {
        example(
            "tripod-seed000.toml",
            include_str!("../../examples/machines/tripod-seed000.toml"),
        )
    })
}

fn hexapod() -> &'static Machine {
    static M: OnceLock<Machine> = OnceLock::new();
    M.get_or_init(|| {
        example(
            "hexapod-seed001.toml",
            include_str!("../../examples/machines/hexapod-seed001.toml"),
        )
    })
}

fn mc300() -> &'static Machine {
    static M: OnceLock<Machine> = OnceLock::new();
    M.get_or_init(|| {
        example(
            "mc300.toml",
            include_str!("../../examples/machines/mc300.toml"),
        )
    })
}

/// Runs a loaded machine through its home pose: inverse, limits, Jacobian,
/// condition, skeleton, forward from home. A forward solution must reproduce its
/// actuator values.
fn exercise(machine: &Machine) {
    let m = machine.mechanism();
    let home = m.home();
    assert!(
        home.iter().all(|v| v.is_finite()),
        "a loaded machine's home is finite: {home:?}"
    );
    let _ = m.jacobian(&home);
    let _ = m.condition(&home);
    let _ = m.skeleton(&home);
    let _ = m.tool_pose(&home);
    let Ok(q) = m.inverse(&home) else { return };
    let _ = m.check_limits(&home, &q);
    if let Ok(f) = m.forward(&q, &home) {
        if let Ok(q2) = m.inverse(&f.pose) {
            let scale = q.iter().fold(1.0f64, |s, v| s.max(v.abs()));
            let off = q
                .iter()
                .zip(&q2)
                .fold(0.0f64, |s, (a, b)| s.max((a - b).abs()));
            assert!(
                off <= 1e-6 * scale,
                "forward solution does not reproduce its actuators: off by {off:e} \
                 (q = {q:?}, pose = {:?})",
                f.pose
            );
        }
    }
    let _ = machine.parameters();
}

/// A machine file (TOML, every machine type).
pub fn machine_toml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(machine) = Machine::from_toml_str(text, "fuzz.toml") {
        exercise(&machine);
    }
}

/// A LinuxCNC configuration: the INI, then after the first NUL byte the text every
/// HAL file it names reads as. An import that succeeds must give a machine file that
/// loads; a machine the export takes must come back from its own export with the
/// same actuators at home (`docs/linuxcnc.md`: importing an export gives the same
/// machine).
pub fn linuxcnc_config(data: &[u8]) {
    let (ini, hal) = match data.iter().position(|b| *b == 0) {
        Some(k) => (&data[..k], &data[k + 1..]),
        None => (data, &[][..]),
    };
    let (Ok(ini), Ok(hal)) = (std::str::from_utf8(ini), std::str::from_utf8(hal)) else {
        return;
    };
    let Ok(imp) =
        pkm::linuxcnc::import_with("fuzz.ini", ini, &mut |_f: &str| Ok(hal.to_string()), &[])
    else {
        return;
    };
    let machine = Machine::from_toml_str(&imp.toml, "imported.toml")
        .expect("an import that succeeds writes a machine file that loads");
    exercise(&machine);
    let Ok(exp) = pkm::linuxcnc::export(&machine, pkm::linuxcnc::LengthUnit::Mm) else {
        return;
    };
    let back = pkm::linuxcnc::import_with(
        "pkm.ini",
        &exp.ini,
        &mut |_f: &str| Ok(exp.hal.clone()),
        &[],
    )
    .expect("an export imports");
    let back = Machine::from_toml_str(&back.toml, "back.toml").expect("its import loads");
    let (a, b) = (machine.mechanism(), back.mechanism());
    let home = a.home();
    if let (Ok(qa), Ok(qb)) = (a.inverse(&home), b.inverse(&home)) {
        let scale = qa.iter().fold(1.0f64, |s, v| s.max(v.abs()));
        for (x, y) in qa.iter().zip(&qb) {
            assert!(
                (x - y).abs() <= 1e-6 * scale,
                "the export's import differs at home: {qa:?} vs {qb:?}"
            );
        }
    }
}

/// A LinuxCNC tool table: parsed lengths are finite and within the magnitude bound.
pub fn tool_table(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(t) = pkm::motion::tools::parse_tool_table("fuzz.tbl", text) {
        assert!(t.len() <= pkm::motion::tools::MAX_TOOLS);
        for l in t.values() {
            assert!(l.is_finite() && l.abs() <= pkm::machine::MAX_MAGNITUDE);
        }
    }
}

/// A URDF robot description.
pub fn urdf(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(machine) = Machine::from_urdf_str(text, "fuzz.urdf") {
        exercise(&machine);
    }
}

/// A G-code program, run through the tripod (X, Y, Z) and the hexapod (X..C) with a
/// small work limit.
pub fn gcode(data: &[u8]) {
    for machine in [tripod(), hexapod(), mc300()] {
        let feed = FeedOptions {
            max_samples: MAX_SAMPLES,
            ..FeedOptions::default()
        };
        let source = MotionSource::Gcode {
            reader: Box::new(data),
            from: None,
            setup: Default::default(),
        };
        if let Ok(run) = run_motion(machine, source, &feed, Sampling::Rate(1000.0), &mut NoSink) {
            assert!(
                run.summary.duration_s.is_finite() && run.summary.duration_s >= 0.0,
                "a run's duration is a finite time: {}",
                run.summary.duration_s
            );
        }
    }
}

/// A measurement CSV for the hexapod, calibrated when it parses and is small.
pub fn measurement_csv(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let machine = hexapod();
    let Ok(meas) = parse_measurements(machine, text, "fuzz.csv") else {
        return;
    };
    for s in &meas.states {
        assert!(
            s.readings.iter().all(|v| v.is_finite()),
            "parsed readings are finite: {:?}",
            s.readings
        );
    }
    if meas.states.len() <= MAX_CALIBRATED_STATES {
        let _ = calibrate(machine, &meas, None, &CalibrateOptions::default());
    }
}

/// A tolerances file and a deviations file for the hexapod and MC-300; what parses
/// goes through the accuracy analysis at home.
pub fn tolerance_file(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for machine in [hexapod(), mc300()] {
        let params = machine.parameters();
        if let Ok(t) = pkm::machine::read_tolerances(&params, text, "fuzz.toml") {
            let opt = AccuracyOptions {
                tolerances: Tolerances::Given(t),
                ..AccuracyOptions::default()
            };
            if let Ok(r) = accuracy(machine, &opt) {
                assert!(
                    r.budget.worst_case.is_finite(),
                    "a budget of refused-if-absurd tolerances is finite"
                );
            }
        }
        if let Ok(d) = pkm::machine::read_deviations(&params, text, "fuzz.toml") {
            let opt = AccuracyOptions {
                deviations: d,
                ..AccuracyOptions::default()
            };
            let _ = accuracy(machine, &opt);
        }
    }
}

/// Rows of a fuzzed batch file run through the inverse kinematics.
const MAX_SOLVED_ROWS: usize = 64;

/// A batch file (`pkm ik --input`) for the tripod: what parses has one finite value
/// per header name in every row, rows in increasing line order within the text's line
/// count (line ends: `\n`, `\r\n`, a lone `\r`); its first rows go through the
/// inverse kinematics with every limit.
pub fn batch_table(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let names = |n: &[&str]| n.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let accepted = [
        names(&["X", "Y", "Z", "A", "B", "C"]),
        names(&["X", "Y", "Z"]),
    ];
    let Ok(t) = pkm::analysis::batch_table::parse_batch_table(text, "fuzz.csv", &accepted) else {
        return;
    };
    // Lines end at \n, \r\n or a lone \r, as the reader's records do.
    let lines = text.replace("\r\n", "\n").split(['\n', '\r']).count() as u64;
    let mut last = 0;
    for (line, row) in &t.rows {
        assert_eq!(row.len(), t.header.len(), "one value per header name");
        assert!(row.iter().all(|v| v.is_finite()), "finite values: {row:?}");
        assert!(
            *line > last && *line <= lines,
            "line {line} after {last}, of {lines}"
        );
        last = *line;
    }
    let machine = tripod();
    let home = machine.mechanism().home();
    for (_, row) in t.rows.iter().take(MAX_SOLVED_ROWS) {
        let mut x = home.clone();
        x[..row.len()].copy_from_slice(row);
        let _ = pkm::analysis::kinematics::inverse(machine, &x);
    }
}
