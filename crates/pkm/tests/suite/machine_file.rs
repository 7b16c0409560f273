//! Bad machine files: each gives an error naming file, line, field and what was expected.

use pkm::{Error, Machine};

const GOOD: &str = include_str!("../../../../examples/machines/tripod-seed000.toml");

fn err(text: &str) -> Error {
    Machine::from_toml_str(text, "bad.toml").unwrap_err()
}

/// (line, field, message) of a machine-file error.
fn parts(e: &Error) -> (Option<usize>, String, String) {
    match e {
        Error::MachineFile {
            file,
            line,
            field,
            message,
            ..
        } => {
            assert_eq!(file, "bad.toml");
            (*line, field.clone(), message.clone())
        }
        other => panic!("expected a machine-file error, got {other:?}"),
    }
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn good_files_load() {
    for f in ["tripod-seed000.toml", "tripod-centre-leg.toml"] {
        Machine::from_path(format!(
            "{}/../../examples/machines/{f}",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap();
    }
}

#[test]
fn malformed_toml() {
    let text = GOOD.replace("max_tilt = 30.0", "max_tilt = = 30.0");
    let e = err(&text);
    let (line, field, msg) = parts(&e);
    assert_eq!(line, Some(line_of(&text, "max_tilt = =")));
    assert!(field.is_empty());
    assert!(msg.contains("invalid TOML"), "{msg}");
    assert!(
        e.to_string()
            .starts_with(&format!("bad.toml:{}:", line.unwrap())),
        "{e}"
    );
}

#[test]
fn missing_field() {
    let text = GOOD.replace("tip = [0.0, 0.0, -90.0]", "");
    let (line, field, msg) = parts(&err(&text));
    assert_eq!(field, "tool");
    assert!(msg.contains("missing field `tip`"), "{msg}");
    assert_eq!(line, Some(line_of(&text, "[tool]")));
}

#[test]
fn wrong_type() {
    let text = GOOD.replacen("length = [150.0, 300.0]", "length = \"long\"", 1);
    let (line, field, msg) = parts(&err(&text));
    assert_eq!(field, "struts[0].length");
    assert!(msg.contains("expected"), "{msg}");
    assert_eq!(line, Some(line_of(&text, "length = \"long\"")));
}

#[test]
fn unknown_key() {
    let text = GOOD.replace("max_tilt = 30.0", "max_tilt = 30.0\nmax_tilte = 3.0");
    let (line, field, msg) = parts(&err(&text));
    assert!(msg.contains("unknown field `max_tilte`"), "{msg}");
    assert!(msg.contains("max_tilt"), "names what is expected: {msg}");
    assert!(field.starts_with("limits"), "{field}");
    assert_eq!(line, Some(line_of(&text, "max_tilte")));
}

#[test]
fn nan_and_inf() {
    for bad in ["nan", "inf", "-inf"] {
        let text = GOOD.replace("max_tilt = 30.0", &format!("max_tilt = {bad}"));
        let (line, field, msg) = parts(&err(&text));
        assert_eq!(field, "limits.max_tilt");
        assert!(msg.contains("finite"), "{msg}");
        assert_eq!(line, Some(line_of(&text, &format!("max_tilt = {bad}"))));
    }
    let text = GOOD.replace("G = [0.0, 115.4701, 0.0]", "G = [0.0, nan, 0.0]");
    let (_, field, _) = parts(&err(&text));
    assert_eq!(field, "base_joints.G[1]");
}

#[test]
fn negative_and_unordered_lengths() {
    let text = GOOD.replacen("length = [150.0, 300.0]", "length = [-150.0, 300.0]", 1);
    let (line, field, msg) = parts(&err(&text));
    assert_eq!(field, "struts[0].length");
    assert!(msg.contains(">= 0"), "{msg}");
    assert_eq!(line, Some(line_of(&text, "[-150.0, 300.0]")));
    let text = GOOD.replacen("length = [150.0, 300.0]", "length = [300.0, 150.0]", 1);
    let (_, field, msg) = parts(&err(&text));
    assert_eq!(field, "struts[0].length");
    assert!(msg.contains("min < max"), "{msg}");
}

#[test]
fn semantic_errors() {
    let text = GOOD.replacen("base = \"F\"", "base = \"Q\"", 1);
    let (line, field, msg) = parts(&err(&text));
    assert_eq!(field, "struts[0].base");
    assert!(
        msg.contains("unknown base joint `Q`") && msg.contains("F, G, H"),
        "{msg}"
    );
    assert_eq!(line, Some(line_of(&text, "base = \"Q\"")));

    let text = GOOD.replacen("base = \"G\"", "base = \"F\"", 1);
    let (_, field, msg) = parts(&err(&text));
    assert_eq!(field, "struts[1].base");
    assert!(msg.contains("already used"), "{msg}");

    let text = GOOD.replace("type = \"tripod\"", "type = \"octopod\"");
    let (_, field, msg) = parts(&err(&text));
    assert_eq!(field, "type");
    assert!(msg.contains("unknown machine type `octopod`"), "{msg}");

    let text = GOOD.replace("type = \"tripod\"", "");
    let (_, field, _) = parts(&err(&text));
    assert_eq!(field, "type");

    let text = GOOD.replace("constraint = \"translational\"", "constraint = \"rigid\"");
    let (_, field, msg) = parts(&err(&text));
    assert_eq!(field, "constraint");
    assert!(
        msg.contains("translational") && msg.contains("centre-leg"),
        "{msg}"
    );

    let text = GOOD.replace("max_tilt = 30.0", "max_tilt = -5.0");
    let (_, field, _) = parts(&err(&text));
    assert_eq!(field, "limits.max_tilt");

    let text = GOOD
        .replace("H = [100.0, -57.74, 0.0]", "H = [0.0, 0.0, 0.0]")
        .replace("G = [0.0, 115.4701, 0.0]", "G = [100.0, 57.74, 0.0]");
    let (_, field, msg) = parts(&err(&text));
    assert_eq!(field, "base_joints");
    assert!(msg.contains("collinear"), "{msg}");

    let text = GOOD.replace(
        "constraint = \"translational\"",
        "constraint = \"centre-leg\"",
    );
    let (_, field, msg) = parts(&err(&text));
    assert_eq!(field, "constraint");
    assert!(msg.contains("[centre_leg]"), "{msg}");
}

#[test]
fn unreadable_file_names_the_file() {
    let e = Machine::from_path("/nonexistent/machine.toml").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("/nonexistent/machine.toml: cannot read"),
        "{e}"
    );
}

/// Every example machine file with one line replaced in turn by each line `mutate`
/// gives for it: the file must be refused at that line, and `check` sees the bad line
/// and the error. Returns how many were tried.
fn each_mutated_example(
    mutate: impl Fn(&str) -> Vec<String>,
    check: impl Fn(&str, &Error),
) -> usize {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/machines");
    let mut tried = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            for bad_line in mutate(line) {
                let mut bad_lines = lines.clone();
                bad_lines[i] = &bad_line;
                let e = Machine::from_toml_str(&bad_lines.join("\n"), "bad.toml").unwrap_err();
                assert_eq!(
                    parts(&e).0,
                    Some(i + 1),
                    "{}: {bad_line}: {e}",
                    path.display()
                );
                check(&bad_line, &e);
                tried += 1;
            }
        }
    }
    tried
}

/// Absurd magnitudes (a value of 1e300 once made `pkm report` run for ever) are
/// refused at load, naming the field and its line, in every example machine file and
/// every numeric field tried; a URDF too.
#[test]
fn absurd_magnitudes_are_refused_with_their_field() {
    let tried = each_mutated_example(
        |line| {
            let Some((key, value)) = line.split_once(" = ") else {
                return vec![];
            };
            let value = value.trim_start_matches('[').trim_start();
            if key.trim_start().starts_with('#')
                || !value.starts_with(|c: char| c.is_ascii_digit() || c == '-')
            {
                return vec![];
            }
            let end = value
                .find(|c: char| !(c.is_ascii_digit() || ".-+eE_".contains(c)))
                .unwrap_or(value.len());
            let start = line.find(value).unwrap();
            vec![format!("{}1e300{}", &line[..start], &line[start + end..])]
        },
        |bad, e| {
            let (_, field, message) = parts(e);
            assert!(message.contains("magnitude of at most 1e6"), "{bad}: {e}");
            assert!(!field.is_empty(), "{e}");
        },
    );
    assert!(tried > 100, "{tried}");
    // Integers too; the bound itself is accepted.
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/machines");
    let text = std::fs::read_to_string(format!("{dir}/hexapod-seed001.toml")).unwrap();
    assert!(text.contains("rapid = 30000.0"));
    let at = Machine::from_toml_str(&text.replace("rapid = 30000.0", "rapid = 1000000"), "ok");
    assert!(at.is_ok(), "{at:?}");
    let e = err(&text.replace("rapid = 30000.0", "rapid = 10_000_000"));
    assert!(parts(&e).2.contains("found 10000000"), "{e}");
    // A URDF's joint origin.
    let urdf = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/robots/ur5-like.urdf"
    ))
    .unwrap()
    .replacen("xyz=\"0 0 0.089159\"", "xyz=\"0 0 1e300\"", 1);
    let dir = tempfile_dir();
    let p = dir.join("bad.urdf");
    std::fs::write(&p, urdf).unwrap();
    let e = Machine::from_path(&p).unwrap_err().to_string();
    assert!(e.contains("1e300") && e.contains("beyond"), "{e}");
}

fn tempfile_dir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("pkm-magnitudes-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Arrays with a value too many or too few (`F = [-100, -57.74, 0, 1]` and
/// `length = [150, 300, 1]` once passed `check`) are refused, naming the field and line, on
/// every numeric array of every example machine file.
#[test]
fn arrays_with_more_or_fewer_values_are_refused() {
    let tried = each_mutated_example(
        |line| {
            let Some((key, value)) = line.split_once(" = [") else {
                return vec![];
            };
            // One-line arrays of numbers (not of strings, not nested), of a fixed length
            // (a report's feeds are a list of any length).
            let Some(close) = value.find(']') else {
                return vec![];
            };
            let inner = &value[..close];
            if key.trim_start().starts_with('#')
                || key.trim() == "feeds"
                || inner.contains('[')
                || inner.contains('"')
                || !inner.contains(',')
            {
                return vec![];
            }
            let fewer = &inner[..inner.rfind(',').unwrap()];
            [format!("{inner}, 1.0"), fewer.to_string()]
                .into_iter()
                .map(|b| format!("{key} = [{b}{}", &value[close..]))
                .collect()
        },
        |bad, e| {
            let message = parts(e).2;
            assert!(
                message.contains("invalid length")
                    || message.contains("values, found")
                    || message.contains("values (mm, deg), found"),
                "{bad}: {e}"
            );
        },
    );
    assert!(tried > 100, "{tried}");
}

/// Three exactly coincident joints (the relative area test's bound once underflowed
/// to zero and passed them) are refused on both tripods, for base and platform.
#[test]
fn coincident_tripod_joints_are_refused() {
    let centre_leg = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/machines/tripod-centre-leg.toml"
    ))
    .unwrap();
    for text in [GOOD.to_string(), centre_leg] {
        for table in ["[base_joints]", "[platform_joints]"] {
            let start = text.find(table).unwrap();
            let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
            let first = text[..start].lines().count() + 1;
            for l in lines.iter_mut().skip(first).take(3) {
                let (k, _) = l.split_once(" = ").unwrap();
                *l = format!("{k} = [5.0, 5.0, 5.0]");
            }
            let e = err(&lines.join("\n"));
            let (_, field, msg) = parts(&e);
            assert_eq!(format!("[{field}]"), table, "{e}");
            assert!(msg.contains("coincide"), "{msg}");
        }
    }
}

/// The serial file's rotation blocks are nested arrays (the one-line mutation above
/// leaves them alone): a fourth row or a fourth column is refused too, not dropped.
#[test]
fn rotation_blocks_with_a_row_or_column_too_many_are_refused() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/machines/mc300.toml"
    ))
    .unwrap();
    let good = "rotation = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]";
    assert!(text.contains(good));
    for bad in [
        "rotation = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0]]",
        "rotation = [[0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]",
        "rotation = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]",
    ] {
        let e = pkm::Machine::from_toml_str(&text.replacen(good, bad, 1), "bad.toml").unwrap_err();
        let message = parts(&e).2;
        assert!(message.contains("invalid length"), "{bad}: {e}");
        assert!(e.to_string().contains("rotation"), "{bad}: {e}");
    }
}

/// The `[report]` table is read for every machine type and checked, with
/// the file, line and field of a bad value.
#[test]
fn report_tables_are_read_and_checked() {
    let tripod = std::fs::read_to_string(format!(
        "{}/../../examples/machines/tripod-seed000.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let m = pkm::Machine::from_toml_str(&tripod, "t.toml").unwrap();
    assert_eq!(m.report.feeds, vec![10.0, 100.0, 1000.0, 10000.0]);
    assert_eq!(m.report.gcode.as_deref(), Some("../paths/seed000-arc.ngc"));
    assert_eq!(m.report.comparisons[0].section, "motion");
    let base = tripod.split("[report]").next().unwrap().to_string();
    for (table, field, want) in [
        (
            "[report]\nfeeds = [100.0, -5.0]\n",
            "report.feeds[1]",
            "expected a feed > 0",
        ),
        (
            "[report]\nstep = 0.0\n",
            "report.step",
            "expected a step > 0",
        ),
        (
            "[report]\nbounds = [1.0, 0.0]\n",
            "report.bounds",
            "min < max",
        ),
        (
            "[report]\npoints = 1\n",
            "report.points",
            "expected 2 to 10^7",
        ),
        (
            "[report]\nsections = [\"motion\", \"x\"]\n",
            "report.sections[1]",
            "unknown section `x`",
        ),
        ("[report]\ngcod = \"a.ngc\"\n", "report", "gcod"),
        (
            "[[report.comparison]]\nsection = \"nowhere\"\nsource = \"s\"\ntext = \"t\"\n",
            "report.comparison[0].section",
            "unknown section",
        ),
    ] {
        let e = pkm::Machine::from_toml_str(&format!("{base}{table}"), "t.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("t.toml") && e.contains(field) && e.contains(want),
            "{table}: {e}"
        );
    }
    // Every machine type lets the table through.
    for f in [
        "hexapod-seed001.toml",
        "p3rp-seed004.toml",
        "hybrid-am-seed002.toml",
        "mc300.toml",
    ] {
        let text = std::fs::read_to_string(format!(
            "{}/../../examples/machines/{f}",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap();
        let m = pkm::Machine::from_toml_str(&format!("{text}\n[report]\nstep = 2.0\n"), f).unwrap();
        assert_eq!(m.report.step, Some(2.0), "{f}");
    }
}

#[test]
fn a_drive_stiffness_must_be_positive_and_finite() {
    for (bad, shown) in [("-5.0", "-5"), ("0.0", "0"), ("nan", "NaN"), ("inf", "inf")] {
        let text = GOOD.replacen(
            "max_acceleration = ",
            &format!("stiffness = {bad}\nmax_acceleration = "),
            1,
        );
        let (line, field, message) = parts(&err(&text));
        assert_eq!(line, Some(line_of(&text, "stiffness =")), "{bad}");
        assert_eq!(field, "struts[0].stiffness");
        // The reader itself refuses a value that is not finite, naming the same place.
        let expected = if bad == "nan" || bad == "inf" {
            "expected a finite number".to_string()
        } else {
            format!("expected a stiffness > 0 N/mm (at most 1e12), found {shown}")
        };
        assert!(message.contains(&expected), "{message}");
    }
    // A robot joint's is torsional: N mm/rad.
    let robot = include_str!("../../../../examples/machines/kr30-dh.toml");
    let text = robot.replacen(
        "range = [-185.0, 185.0] }",
        "range = [-185.0, 185.0], stiffness = -1.0 }",
        1,
    );
    assert_ne!(text, robot);
    let m = Machine::from_toml_str(&text, "bad.toml")
        .unwrap_err()
        .to_string();
    assert!(m.contains("stiffness > 0 N mm/rad"), "{m}");
}
