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
        ("G1 X10 F100\nG1 X20\nG41 D1", 3, "unsupported code G41"),
        ("G1 X10", 1, "without a feed"),
        ("X10", 1, "without a motion mode"),
        ("G1 X10 F100\nG2 X20 Y0", 2, "without a centre"),
        ("G1 X10 F100\nG2 X20 Y0 I1 J0", 2, "differs from radius"),
        ("G2 X100 Y0 R10 F100", 1, "more than the diameter"),
        ("G2 X0 Y0 R10 F100", 1, "full circle"),
        ("G1 X10 F100\nM6", 2, "without a tool selected"),
        (
            "G1 X10 F100\nG1 X#1",
            2,
            "`X#1` is a variable: G-code variables are not supported",
        ),
        (
            "G1 X10 F100\nG1 Y2 Z#<depth>",
            2,
            "`Z#<depth>` is a variable",
        ),
        ("G1 X10 F100\nG1 (depth) Z#2(z)", 2, "`Z#2` is a variable"),
        ("G1 X10 F100\n\nG1 X1 Y[2]", 3, "malformed"),
        ("G4", 1, "P"),
        ("G1 X1 F-3", 1, "feed must be > 0"),
    ];
    for (text, line, want) in cases {
        let e = run(text).unwrap_err().to_string();
        assert!(e.contains(&format!("G-code line {line}")), "{text:?}: {e}");
        assert!(e.contains(want), "{text:?}: {e}");
    }
    // A `#` in a comment, or not after a letter, is not a variable.
    for text in [
        "G1 X10 F100 $ (see #1)",
        "G1 X10 F100 $ (X#1)",
        "G1 X10 F100 $ ; X#1",
        "G1 X10 # F100",
    ] {
        let e = run(text).unwrap_err().to_string();
        assert!(
            e.contains("malformed") && !e.contains("variables"),
            "{text:?}: {e}"
        );
    }
}

/// A line a controller refuses was read with the last word winning: an axis or any
/// other word twice, two codes of one modal group, a comment left open. Each is an
/// error with its line and the column of the second word (of the `(`), worded as
/// LinuxCNC's rs274ngc words it.
#[test]
fn words_twice_codes_of_one_group_and_open_comments_are_refused() {
    let cases = [
        (
            "G1 X1 X2 F100",
            "1, column 7",
            "multiple X words on one line",
        ),
        (
            "G1 X1 F60 F6000",
            "1, column 11",
            "multiple F words on one line",
        ),
        (
            "G1 X1 (a) Y2 (b) Y3 F100",
            "1, column 18",
            "multiple Y words",
        ),
        ("g1 x1 f100 i2 I3", "1, column 15", "multiple I words"),
        ("T1 T2 M6", "1, column 4", "multiple T words"),
        (
            "G0 X0\nG1 G0 X1 F100",
            "2, column 4",
            "G1 and G0: two G codes used from the same modal group (group 1, motion: G0 G1 G2 G3)",
        ),
        ("G2 G3 X1 R5 F100", "1, column 4", "G2 and G3: two G codes"),
        (
            "G21 G20 X1 F100",
            "1, column 5",
            "G21 and G20: two G codes used from the same modal group (group 6, units: G20 G21)",
        ),
        ("G17 G19", "1, column 5", "(group 2, plane selection"),
        ("G90 G91", "1, column 5", "(group 3, distance mode"),
        ("G90.1 G91.1", "1, column 7", "(group 4, arc IJK"),
        ("G93 G94", "1, column 5", "(group 5, feed rate mode"),
        ("G43 H1 G49", "1, column 8", "(group 8, tool length offset"),
        ("G59.1 G54", "1, column 7", "(group 12, coordinate system"),
        ("G4 G53 P1", "1, column 4", "(group 0, non-modal: G4 G53)"),
        (
            "M3 M5",
            "1, column 4",
            "M3 and M5: two M codes used from the same modal group (group 7, spindle: M3 M4 M5)",
        ),
        ("M7 M9", "1, column 4", "(group 8, coolant"),
        ("M0 M30", "1, column 4", "(group 4, stopping"),
        ("G1 X1 F100 (feed", "1, column 12", "unclosed comment found"),
        (
            "G1 X1 (ok) F100 (feed",
            "1, column 17",
            "unclosed comment found",
        ),
    ];
    for (text, at, want) in cases {
        let e = run(text).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("G-code line {at}: ")),
            "{text:?}: {e}"
        );
        assert!(e.contains(want), "{text:?}: {e}");
    }
    // Codes of different groups, a closed comment, a `(` inside a `;` comment, the same
    // letter in a comment, and codes pkm notes without a group: each line is read.
    for text in [
        "N5 G17 G90 G91.1 G21 G94 G40 G49 G54 M3 S1000 M8 G1 X1 F100",
        "G1 X2 (X3 as well) F100 ; (unclosed here is a comment)",
        "G4 P1 M5 M9",
        "M428 M429 G0 X1",
    ] {
        assert!(run(text).is_ok(), "{text:?}: {:?}", run(text));
    }
}

/// `F1e300` once said "unsupported word E300" (a word the user never wrote) and a
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

/// Found by fuzzing: the gcode crate computes a code's number as
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

#[test]
fn five_axis_program_words() {
    let text = "%\nM428 ;TCP on\nT1 M6\nG0 G54 G17 G40 G90 G94\nG43 H1 Z5.0 M08\nG93\n\
                G1 X1 Y2 Z3 B-5.5 C64.4 F60\nX2 F30\nG94\nG1 X3 F600\nG49\n%\nG1 X100 F600\n";
    let mut g = Interpreter::new([0.0; 6]);
    g.work_offsets[0] = [10.0, 20.0, 30.0, 0.0, 0.0, 0.0];
    let mut moves = Vec::new();
    let mut events = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if g.ended {
            break;
        }
        if let Some(m) = g.line(line, i as u64 + 1).unwrap() {
            moves.push(m);
        }
        if let Some(e) = g.tool_event {
            events.push(e);
        }
    }
    // The second `%` ends the program: the G1 X100 after it is not read.
    assert_eq!(moves.len(), 4);
    // G43 H1 with the Z move on its line; G49 cancels.
    assert_eq!(
        events,
        [
            pkm::motion::gcode::ToolEvent::Apply { h: 1, line: 5 },
            pkm::motion::gcode::ToolEvent::Cancel { line: 11 }
        ]
    );
    assert_eq!(g.tool, Some(1));
    // G54's offset is added to the program's coordinates.
    assert_eq!(moves[0].end[2], 35.0);
    assert_eq!(moves[1].end[..3], [11.0, 22.0, 33.0]);
    assert!((moves[1].end[4] - (-5.5f64).to_radians()).abs() < 1e-15);
    // G93: F60 is 1/60 min = 1 s; F30 2 s; no feed rate.
    assert_eq!((moves[1].duration, moves[1].feed), (Some(1.0), None));
    assert_eq!(moves[2].duration, Some(2.0));
    // G94 again: F per minute.
    assert_eq!((moves[3].duration, moves[3].feed), (None, Some(10.0)));
    // The unknown M428 and the tool change are noted, not errors.
    let notes: Vec<&str> = g.notes.iter().map(|n| n.1.as_str()).collect();
    assert!(notes[0].starts_with("M428"), "{notes:?}");
    assert!(notes.iter().any(|n| n.contains("tool 1")), "{notes:?}");
}

#[test]
fn five_axis_word_errors_name_the_line() {
    for (text, want) in [
        ("G93\nG1 X1 F10\nX2\n", "line 3"),
        ("G93\nG1 X1 F10\nX2\n", "own F"),
        ("G43\n", "no tool in the spindle"),
        ("G1 X1 H2 F10\n", "H without G43"),
        ("M6\n", "without a tool selected"),
        ("G43 H1.5\n", "tool number"),
        ("G41 X1\n", "unsupported code G41"),
    ] {
        let e = run(text).unwrap_err().to_string();
        assert!(e.contains(want), "{text:?}: {e}");
    }
}

#[test]
fn a_linuxcnc_tool_table_gives_lengths() {
    let t = pkm::motion::tools::parse_tool_table(
        "sim.tbl",
        "T1 P1 Z50.0 D10.0 ;end mill\n\nT2 P2 D3 Z-1.5\n",
    )
    .unwrap();
    assert_eq!(t.get(&1), Some(&50.0));
    assert_eq!(t.get(&2), Some(&-1.5));
    for (text, want) in [
        ("T1 Z1\nT1 Z2\n", "sim.tbl:2"),
        ("P1 Z5\n", "needs T"),
        ("T1 Zx\n", "length"),
        ("T1 K5\n", "not a tool table word"),
    ] {
        let e = pkm::motion::tools::parse_tool_table("sim.tbl", text)
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "{text:?}: {e}");
    }
}
