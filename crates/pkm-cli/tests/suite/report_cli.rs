//! `pkm report` on a user's own machine: every section written or its error
//! shown in its place, options and the `[report]` table, content that fits the machine.

use crate::common::{path, pkm};
use serde_json::Value;

/// The Gough-Stewart platform a new user writes from the docs
/// (`tests/fixtures/own-hexapod.toml`), with `extra` appended.
fn own_hexapod(extra: &str) -> String {
    let file = path("tests/fixtures/own-hexapod.toml");
    std::fs::read_to_string(file).unwrap() + extra
}

fn report(args: &[&str]) -> (i32, Value, String) {
    let o = pkm()
        .arg("report")
        .args(args)
        .arg("--json")
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&o.stdout).unwrap_or(Value::Null);
    (
        o.status.code().unwrap_or(-1),
        v,
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// That hexapod: the whole report, every section, no error; the motion path is
/// a circle scaled to its reach, and no paper's figures appear in it.
#[test]
fn the_report_of_an_own_hexapod_has_every_section() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("own.toml");
    std::fs::write(&file, own_hexapod("")).unwrap();
    let out = dir.path().join("rep");
    let (code, v, err) = report(&[file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["failed"].as_array().unwrap().len(), 0, "{v}");
    let sections: Vec<&str> = v["sections"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    for s in [
        "machine",
        "drawing",
        "checks",
        "workspace",
        "motion",
        "accuracy",
        "calibration",
    ] {
        assert!(sections.contains(&s), "{s}: {sections:?}");
    }
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(!html.contains("could not be computed"));
    assert!(html.contains("A full circle of radius"));
    // The machine-tool-sized calibration campaign fits it as it is.
    assert!(html.contains("random states (±100 mm, ±10°)"));
    assert!(!html.contains("is shrunk"));
    assert!(!html.to_lowercase().contains("seed 000 reports"));
    assert!(!html.contains("Published ("));
    // The workspace map holds the whole reach: no warning that it was cut.
    assert!(html.contains("the type's bound on the tool position"));
    assert!(!html.contains("lie on the grid's faces"));
    // Every violated limit counted, first ones beside.
    assert!(html.contains("points violating it"));
    // Every anchor once (the machine section wrote its heading twice).
    let mut ids: Vec<&str> = html
        .split(" id=\"")
        .skip(1)
        .filter_map(|r| r.split('"').next())
        .collect();
    let n = ids.len();
    ids.sort();
    ids.dedup();
    assert_eq!(ids.len(), n, "an id written twice");
    assert_eq!(html.matches(">Machine</h2>").count(), 1);
}

/// A section that cannot be computed shows its error in its place; the others are
/// written; the exit code (4) and stderr say which failed.
#[test]
fn a_failing_section_does_not_take_the_report_down() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("own.toml");
    std::fs::write(&file, own_hexapod("")).unwrap();
    // A program the G-code reader refuses on its third line.
    let prog = dir.path().join("bad.ngc");
    std::fs::write(&prog, "G21 G90\nG1 X10 Y0 Z600 F1000\nG12345678 X0\n").unwrap();
    let out = dir.path().join("rep");
    let (code, v, err) = report(&[
        file.to_str().unwrap(),
        "--gcode",
        prog.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 4, "{err}");
    assert_eq!(v["failed"][0]["section"], "motion", "{v}");
    assert!(
        err.contains("section `motion` could not be computed"),
        "{err}"
    );
    assert!(err.contains("line 3"), "{err}");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("This section could not be computed"));
    assert!(html.contains("Accuracy from geometric tolerances"));
    assert!(html.contains("Workspace and conditioning"));
}

/// `--sections`, `--pose`, `--bounds`/`--step` and the `[report]` table; unknown
/// sections are refused, a section the machine has not is named.
#[test]
fn report_options_and_the_report_table() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("own.toml");
    std::fs::write(
        &file,
        own_hexapod("[report]\nsections = [\"drawing\", \"workspace\"]\nstep = 50.0\n"),
    )
    .unwrap();
    let out = dir.path().join("rep");
    let (code, v, err) = report(&[file.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["sections"], serde_json::json!(["drawing", "workspace"]));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("Drawing at home"));
    // The command line wins over the table.
    let (code, v, err) = report(&[
        file.to_str().unwrap(),
        "--sections",
        "drawing,workspace,accuracy",
        "--pose",
        "10,0,650,0,0,5",
        "--bounds=-200,200,-200,200,400,800",
        "--step",
        "40",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["sections"].as_array().unwrap().len(), 3);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("Drawing at the pose 10, 0, 650, 0, 0, 5"));
    assert!(html.contains("At the pose 10, 0, 650, 0, 0, 5"));
    assert!(html.contains("bounds from the given bounds"));
    // 11 x 11 x 11 points over the given bounds.
    assert!(html.contains("A grid of 1331 points"), "grid");
    // Unknown sections: refused on the command line and in the file.
    let (code, _, err) = report(&[file.to_str().unwrap(), "--sections", "wrkspace"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("unknown section `wrkspace`"), "{err}");
    std::fs::write(&file, own_hexapod("[report]\nsections = [\"motoin\"]\n")).unwrap();
    let (code, _, err) = report(&[file.to_str().unwrap()]);
    assert_eq!(code, 1);
    assert!(
        err.contains("report.sections[0]") && err.contains("unknown section `motoin`"),
        "{err}"
    );
    // A section the machine has not (a hexapod has no seed 004 analysis).
    std::fs::write(&file, own_hexapod("")).unwrap();
    let (code, v, err) = report(&[
        file.to_str().unwrap(),
        "--sections",
        "drawing,seed004",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["missing"], serde_json::json!(["seed004"]));
}

/// A robot whose zero pose is a stretched, singular configuration on the edge of its
/// reach: the motion circle is centred at a well-conditioned point instead.
#[test]
fn a_robots_motion_circle_moves_off_its_singular_home() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    let (code, v, err) = report(&[
        &path("examples/robots/ur5-like.urdf"),
        "--sections",
        "motion",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err} {v}");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("no circle fits about home"), "circle");
}

/// A planar mechanism is drawn in its plane, not in three views of which one shows a
/// line.
#[test]
fn a_planar_head_is_drawn_in_its_plane() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    let (code, _, err) = report(&[
        &path("examples/machines/p3rp-seed004.toml"),
        "--sections",
        "drawing",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("In its plane"));
    assert!(!html.contains("Top view"));
}

/// A 15 mm micro-hexapod (`tests/fixtures/micro-hexapod.toml`): every section,
/// the calibration campaign fitted to its size and saying so with the values used
/// (the machine-tool defaults found no poses within its limits).
#[test]
fn the_report_of_a_micro_hexapod_fits_its_size() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    let micro = path("tests/fixtures/micro-hexapod.toml");
    let (code, v, err) = report(&[&micro, "--out", out.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["failed"].as_array().unwrap().len(), 0, "{v}");
    assert!(v["sections"]
        .as_array()
        .unwrap()
        .contains(&Value::from("calibration")));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(!html.contains("could not be computed"));
    for s in [
        "deviate uniformly by up to ±0.0625 mm",
        "circumradius 12.5 mm",
        "random states (±6.25 mm, ±10°)",
        "is shrunk to fit this machine",
    ] {
        assert!(html.contains(s), "{s}");
    }
}

/// The report's calibration section alone for the machine file `fixture` (in
/// `tests/fixtures/`): computed without a failure, its HTML.
fn calibration_section(fixture: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    let file = path(&format!("tests/fixtures/{fixture}"));
    let (code, v, err) = report(&[
        &file,
        "--sections",
        "calibration",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(v["failed"].as_array().unwrap().len(), 0, "{v}");
    std::fs::read_to_string(out.join("index.html")).unwrap()
}

/// A micro tripod (`tests/fixtures/micro-tripod.toml`): the campaign is shrunk to 1/16
/// and keeps away from the plane of its base joints, so every held-out state is within
/// both models' reach (the sentence counting those beyond it is tested in
/// `report::calibration`).
#[test]
fn the_calibration_of_a_micro_tripod_is_shrunk() {
    let html = calibration_section("micro-tripod.toml");
    assert!(!html.contains("model's reach"));
    // Its platform does not turn: no rotation span is claimed for its campaign.
    assert!(html.contains("random states (±6.25 mm)."));
    assert!(html.contains("is shrunk to fit this machine"));
}

/// A giant hexapod (`tests/fixtures/giant-hexapod.toml`, struts of metres): the
/// calibration campaign is enlarged to its size and says so.
#[test]
fn the_calibration_of_a_giant_hexapod_is_enlarged() {
    let html = calibration_section("giant-hexapod.toml");
    for s in [
        "random states (±800 mm, ±10°)",
        "is scaled ×8 to this machine's size",
        "circumradius 1600 mm",
    ] {
        assert!(html.contains(s), "{s}");
    }
}
