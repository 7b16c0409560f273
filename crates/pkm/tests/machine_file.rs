//! Bad machine files: each gives an error naming file, line, field and what was expected.

use pkm::{Error, Machine};

const GOOD: &str = include_str!("../../../examples/machines/tripod-seed000.toml");

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

    let text = GOOD.replace("type = \"tripod\"", "type = \"pentapod\"");
    let (_, field, msg) = parts(&err(&text));
    assert_eq!(field, "type");
    assert!(msg.contains("unknown machine type `pentapod`"), "{msg}");

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
