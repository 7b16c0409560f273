//! The G-code interpreter: every supported word, arcs, errors with line numbers.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use pkm::motion::gcode::{GMove, Interpreter, Motion, Plane};

const PROGRAM: &str = include_str!("../../../../examples/paths/gcode-coverage.ngc");

fn run(text: &str) -> Result<Vec<GMove>, pkm::Error> {
    let mut g = Interpreter::new([0.0, 0.0, -290.0, 0.0, 0.0, 0.0]);
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if let Some(m) = g.line(line, i as u64 + 1)? {
            out.push(m);
        }
    }
    Ok(out)
}

fn sweep(m: &GMove) -> f64 {
    match m.motion {
        Motion::Arc { sweep, .. } => sweep,
        _ => panic!("not an arc: {m:?}"),
    }
}

fn centre(m: &GMove) -> [f64; 3] {
    match m.motion {
        Motion::Arc { centre, .. } => [centre.x, centre.y, centre.z],
        _ => panic!("not an arc"),
    }
}

#[test]
fn coverage_program() {
    let moves = run(PROGRAM).unwrap();
    let by_n = |n: &str| {
        let line = PROGRAM.lines().position(|l| l.starts_with(n)).unwrap() as u64 + 1;
        *moves.iter().find(|m| m.line == line).unwrap()
    };
    assert!(matches!(by_n("N30").motion, Motion::Line { rapid: true }));
    let m = by_n("N40");
    assert!(matches!(m.motion, Motion::Line { rapid: false }));
    assert_eq!(m.feed, Some(10.0)); // 600 mm/min
    let m = by_n("N50");
    assert!((sweep(&m) + FRAC_PI_2).abs() < 1e-12);
    assert_eq!(centre(&m)[..2], [20.0, -10.0]);
    let m = by_n("N60");
    assert!((sweep(&m) - FRAC_PI_2).abs() < 1e-12);
    assert!((centre(&m)[0] - 30.0).abs() < 1e-12 && centre(&m)[1].abs() < 1e-12);
    let m = by_n("N70");
    assert!((sweep(&m) + 1.5 * PI).abs() < 1e-12, "{}", sweep(&m));
    let m = by_n("N80");
    assert!((sweep(&m) - TAU).abs() < 1e-12);
    let m = by_n("N90");
    assert!((sweep(&m) - 2.0 * TAU).abs() < 1e-12);
    assert_eq!(m.end[2], -295.0);
    let m = by_n("N100");
    match m.motion {
        Motion::Arc { plane, sweep, .. } => {
            assert_eq!(plane, Plane::ZX);
            assert!(sweep < 0.0);
        }
        _ => panic!(),
    }
    let m = by_n("N110");
    assert!(matches!(
        m.motion,
        Motion::Arc {
            plane: Plane::YZ,
            ..
        }
    ));
    let m = by_n("N120");
    assert_eq!(centre(&m)[..2], [20.0, 10.0]);
    let m = by_n("N130");
    assert_eq!(m.end[0], m.start[0] - 5.0);
    assert!(
        matches!(by_n("N140").motion, Motion::Dwell { seconds } if (seconds - 0.2).abs() < 1e-12)
    );
    let m = by_n("N150");
    assert!((m.end[2] + 289.56).abs() < 1e-9);
    assert!((m.feed.unwrap() - 508.0 / 60.0).abs() < 1e-9);
    assert_eq!(by_n("N160").end[2], -290.0);
}

#[test]
fn numbers_are_read_in_double_precision() {
    let m = run("G1 X1234.56789 F100").unwrap();
    assert_eq!(m[0].end[0], 1234.56789);
}

#[test]
fn orientation_words() {
    let m = run("G1 X1 A10 B-5 C30 F100").unwrap();
    assert!((m[0].end[3] - 10f64.to_radians()).abs() < 1e-15);
    assert!((m[0].end[5] - 30f64.to_radians()).abs() < 1e-15);
}

#[test]
fn malformed_programs_name_the_line() {
    let cases = [
        ("G1 X10 F100\nG1 Q5", 2, "unsupported word Q"),
        ("G1 X10 F100\nG1 X20\nG43 H1", 3, "unsupported code G43"),
        ("G1 X10", 1, "without a feed"),
        ("X10", 1, "without a motion mode"),
        ("G1 X10 F100\nG2 X20 Y0", 2, "without a centre"),
        ("G1 X10 F100\nG2 X20 Y0 I1 J0", 2, "differs from radius"),
        ("G2 X100 Y0 R10 F100", 1, "more than the diameter"),
        ("G2 X0 Y0 R10 F100", 1, "full circle"),
        ("G1 X10 F100\nT2 M6", 2, "unsupported code"),
        ("G1 X10 F100\nG1 X#1", 2, "malformed"),
        ("G1 X10 F100\n\nG1 X1 Y[2]", 3, "malformed"),
        ("G4", 1, "P"),
        ("G1 X1 F-3", 1, "feed must be > 0"),
    ];
    for (text, line, want) in cases {
        let e = run(text).unwrap_err().to_string();
        assert!(e.contains(&format!("G-code line {line}")), "{text:?}: {e}");
        assert!(e.contains(want), "{text:?}: {e}");
    }
}

/// Issue 17: `F1e300` said "unsupported word E300" (a word the user never wrote) and a
/// UTF-8 byte-order mark said "Unknown content"; now the exponent is explained and the
/// mark is not content.
#[test]
fn exponents_are_explained_and_a_byte_order_mark_is_ignored() {
    let mut g = pkm::motion::gcode::Interpreter::new([0.0; 6]);
    let e = g.line("G1 X10 F1e300", 1).unwrap_err().to_string();
    assert!(
        e.contains("unsupported word E300") && e.contains("no exponent"),
        "{e}"
    );
    // A real E word (an extruder axis) keeps the plain message.
    let e = g.line("G1 X10 E5 F100", 2).unwrap_err().to_string();
    assert!(
        e.contains("unsupported word E5") && !e.contains("exponent"),
        "{e}"
    );
    let mv = g.line("\u{feff}G1 X10 F100", 3).unwrap().unwrap();
    assert_eq!(mv.end[0], 10.0);
}

/// Found by fuzzing (issue 17): the gcode crate computes a code's number as
/// `major * 10 + minor` in a u32, so `G2147483649` wrapped to `G1` (a silent linear
/// move) in release builds and panicked in checked ones. Such a number is refused,
/// named, with its line.
#[test]
fn code_numbers_that_overflow_are_refused() {
    for (text, word) in [
        ("G0 X0 Y0\nG2147483649 X10\n", "G2147483649"),
        (
            "G0000000000000000001971042465\n",
            "G0000000000000000001971042465",
        ),
        ("G0 X0\nM 12345678\n", "M 12345678"),
    ] {
        let e = run(text).unwrap_err().to_string();
        assert!(e.contains(word) && e.contains("at most 6 digits"), "{e}");
    }
    // Leading zeros and comments are not numbers to refuse.
    let r = run("G0000001 X1 F100 (G123456789)\nG1 X2 ; M99999999\n");
    assert!(r.is_ok(), "{r:?}");
}
