//! The `pkm` command end to end: JSON contracts, batches, errors and the report.

use std::path::PathBuf;

use assert_cmd::Command;
use serde_json::Value;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn seed000() -> String {
    root()
        .join("examples/machines/tripod-seed000.toml")
        .display()
        .to_string()
}

fn centre_leg() -> String {
    root()
        .join("examples/machines/tripod-centre-leg.toml")
        .display()
        .to_string()
}

fn pkm() -> Command {
    Command::cargo_bin("pkm").unwrap()
}

fn json(args: &[&str]) -> (Value, i32) {
    let out = pkm().args(args).output().unwrap();
    let v: Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&out.stdout)));
    (v, out.status.code().unwrap())
}

fn stderr_of(args: &[&str]) -> (String, i32) {
    let out = pkm().args(args).output().unwrap();
    (
        String::from_utf8_lossy(&out.stderr).into_owned(),
        out.status.code().unwrap(),
    )
}

#[test]
fn table1_through_the_cli() {
    let m = seed000();
    let (v, code) = json(&["ik", &m, "--pose=-20,45.54,-286.25,15,0,0", "--json"]);
    assert_eq!(code, 0);
    let expect = [
        ("C", [-70.00, -5.64, -206.79]),
        ("E", [-20.00, 78.02, -184.38]),
        ("D", [30.00, -5.64, -206.79]),
    ];
    for (n, e) in expect {
        let j = &v["joints"][n];
        for k in 0..3 {
            let d = (j[k].as_f64().unwrap() - e[k]).abs();
            assert!(d <= 0.02, "{n}[{k}]: {} vs {}", j[k], e[k]);
        }
    }
    for n in ["F", "H", "G"] {
        assert!(v["joints"][n].is_array());
    }
    assert_eq!(v["reachable"], true);
    assert_eq!(v["violations"].as_array().unwrap().len(), 0);
    for a in ["e", "f", "g"] {
        assert!(v["actuators"][a].as_f64().unwrap() > 150.0);
    }
}

#[test]
fn fk_json_contract_and_round_trip() {
    let m = seed000();
    let (ik, _) = json(&["ik", &m, "--pose=10,-5,-300,4,-3,20", "--json"]);
    let q: Vec<String> = ["e", "f", "g"]
        .iter()
        .map(|a| format!("{}", ik["actuators"][a].as_f64().unwrap()))
        .collect();
    let (fk, code) = json(&[
        "fk",
        &m,
        "--actuators",
        &q.join(","),
        "--from=0,0,-290,4,-3,20",
        "--json",
    ]);
    assert_eq!(code, 0);
    let p = fk["position"].as_array().unwrap();
    for (k, e) in [10.0, -5.0, -300.0].iter().enumerate() {
        assert!((p[k].as_f64().unwrap() - e).abs() < 1e-9);
    }
    let a = fk["angles"].as_array().unwrap();
    for (k, e) in [4.0, -3.0, 20.0].iter().enumerate() {
        assert!((a[k].as_f64().unwrap() - e).abs() < 1e-9);
    }
    let r = fk["rotation"].as_array().unwrap();
    assert_eq!(r.len(), 3);
    assert_eq!(r[0].as_array().unwrap().len(), 3);
    // Angles in another convention describe the same rotation.
    let (z, _) = json(&[
        "fk",
        &m,
        "--actuators",
        &q.join(","),
        "--from=0,0,-290,20,-3,4",
        "--rotation",
        "zyx",
        "--json",
    ]);
    assert_eq!(z["rotation"], fk["rotation"]);
}

#[test]
fn check_json_contract() {
    let (v, code) = json(&["check", &seed000(), "--json"]);
    assert_eq!(code, 0);
    assert_eq!(v["type"], "tripod/translational");
    let acts = v["actuators"].as_array().unwrap();
    assert_eq!(acts.len(), 3);
    assert_eq!(acts[0]["name"], "e");
    assert_eq!(acts[0]["min"], 150.0);
    assert_eq!(acts[0]["max"], 300.0);
    assert_eq!(v["home"]["position"][2], -290.0);
    assert_eq!(v["home"]["angles"].as_array().unwrap().len(), 3);
    assert_eq!(v["references"][0]["pass"], true);
    let (v, code) = json(&["check", &centre_leg(), "--json"]);
    assert_eq!(code, 0);
    assert_eq!(v["type"], "tripod/centre-leg");
}

#[test]
fn unreachable_poses_name_the_limit() {
    let m = seed000();
    let cases = [
        (
            "--pose=0,0,-420",
            "strut e length",
            "above its maximum 300.000 mm",
        ),
        (
            "--pose=0,0,-200",
            "strut e length",
            "below its minimum 150.000 mm",
        ),
        (
            "--pose=0,0,-290,35,0,0",
            "spindle tilt 35.000 deg",
            "by 5.000 deg",
        ),
        (
            "--pose=0,0,-290,25,0,0",
            "strut e/spindle collision",
            "below its minimum 0.000 deg",
        ),
    ];
    for (pose, limit, detail) in cases {
        let (err, code) = stderr_of(&["ik", &m, pose]);
        assert_eq!(code, 3, "{pose}: {err}");
        assert!(err.contains(limit) && err.contains(detail), "{pose}: {err}");
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        // The JSON output says the same.
        let (v, code) = json(&["ik", &m, pose, "--json"]);
        assert_eq!(code, 3);
        assert_eq!(v["reachable"], false);
        assert!(!v["violations"].as_array().unwrap().is_empty());
    }
    // Centre-leg: an orientation the leg cannot give.
    let (err, code) = stderr_of(&["ik", &centre_leg(), "--pose=30,0,-300,0,0,0"]);
    assert_eq!(code, 3);
    assert!(err.contains("centre leg sets the orientation"), "{err}");
}

#[test]
fn bad_files_give_located_errors() {
    let dir = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(seed000()).unwrap();
    let cases = [
        (
            "malformed",
            good.replace("max_tilt = 30.0", "max_tilt = = 30"),
            ":60:",
        ),
        (
            "missing",
            good.replace("tip = [0.0, 0.0, -90.0]", ""),
            "field `tool`: missing field `tip`",
        ),
        (
            "type",
            good.replacen("length = [150.0, 300.0]", "length = 3", 1),
            "field `struts[0].length`",
        ),
        (
            "unknown",
            good.replace("max_tilt = 30.0", "max_tilt = 30.0\nspeed = 1"),
            "unknown field `speed`",
        ),
        (
            "nan",
            good.replace("max_tilt = 30.0", "max_tilt = nan"),
            "expected a finite number",
        ),
        (
            "negative",
            good.replacen("length = [150.0, 300.0]", "length = [-1.0, 300.0]", 1),
            "expected lengths >= 0",
        ),
    ];
    for (name, text, want) in cases {
        let p = dir.path().join(format!("{name}.toml"));
        std::fs::write(&p, text).unwrap();
        let ps = p.display().to_string();
        for args in [
            vec!["check", ps.as_str()],
            vec!["ik", ps.as_str(), "--pose", "0,0,-290"],
        ] {
            let (err, code) = stderr_of(&args);
            assert_eq!(code, 1, "{name}: {err}");
            assert!(err.starts_with(&format!("error: {ps}:")), "{name}: {err}");
            assert!(err.contains(want), "{name}: {err}");
            assert_eq!(err.lines().count(), 1, "{name}: {err}");
            assert!(!err.contains("panicked"));
        }
    }
}

/// A malformed value on the command line exits with 2, the documented code for a bad
/// command line (these once exited with 1), and names the value; a pose the
/// machine cannot take exits with 3.
#[test]
fn bad_command_line_values() {
    let m = seed000();
    let (err, code) = stderr_of(&["ik", &m, "--pose", "1,2"]);
    assert_eq!(code, 2);
    assert!(err.contains("expected 3 or 6 values"), "{err}");
    let (err, code) = stderr_of(&["ik", &m, "--pose", "1,2,nan"]);
    assert_eq!(code, 2);
    assert!(err.contains("finite"), "{err}");
    let (err, code) = stderr_of(&["ik", &m, "--pose=1e308,0,0"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("value 1 is 1e308, beyond the largest magnitude"),
        "{err}"
    );
    let (err, code) = stderr_of(&["ik", &m, "--pose", "1,x,3"]);
    assert_eq!(code, 2);
    assert!(err.contains("value 2 `x` is not a number"), "{err}");
    let (err, code) = stderr_of(&["fk", &m, "--actuators", "200,200"]);
    assert_eq!(code, 2);
    assert!(err.contains("expected 3 values (e,f,g)"), "{err}");
    let (err, code) = stderr_of(&["fk", &m, "--actuators", "10,10,400"]);
    assert_eq!(code, 3);
    assert!(err.contains("no platform position"), "{err}");
}

#[test]
fn csv_batches() {
    let dir = tempfile::tempdir().unwrap();
    let m = seed000();
    let input = dir.path().join("poses.csv");
    std::fs::write(
        &input,
        "X,Y,Z,A,B,C\n0,0,-290,0,0,0\n10,5,-300,2,0,0\n0,0,-420,0,0,0\n",
    )
    .unwrap();
    let output = dir.path().join("out.csv");
    let out = pkm()
        .args(["ik", &m, "--input"])
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3), "one unreachable row");
    let text = std::fs::read_to_string(&output).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "X,Y,Z,A,B,C,e_mm,f_mm,g_mm,reachable,violations");
    assert_eq!(lines.len(), 4);
    assert!(lines[1].contains(",true,"));
    assert!(lines[3].contains(",false,") && lines[3].contains("strut e length"));

    // FK batch of the lengths just computed, each row from the previous solution.
    let lengths = dir.path().join("lengths.csv");
    let mut l = String::from("e,f,g\n");
    for line in &lines[1..3] {
        let c: Vec<&str> = line.split(',').collect();
        l.push_str(&format!("{},{},{}\n", c[6], c[7], c[8]));
    }
    std::fs::write(&lengths, l).unwrap();
    let poses = dir.path().join("fk.csv");
    pkm()
        .args(["fk", &m, "--input"])
        .arg(&lengths)
        .arg("--output")
        .arg(&poses)
        .assert()
        .success();
    let text = std::fs::read_to_string(&poses).unwrap();
    let row: Vec<f64> = text
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .take(6)
        .map(|c| c.parse().unwrap())
        .collect();
    assert!(
        (row[3]).abs() < 1e-9 && (row[4]).abs() < 1e-9 && (row[5] + 290.0).abs() < 1e-9,
        "{text}"
    );

    // A malformed row is an error with its line number, and nothing is written.
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "X,Y,Z\n0,0,-290\n0,abc,-290\n").unwrap();
    let fresh = dir.path().join("fresh.csv");
    let out = pkm()
        .args(["ik", &m, "--input"])
        .arg(&bad)
        .arg("--output")
        .arg(&fresh)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1));
    assert!(
        err.contains("bad.csv:3: field `Y`: expected a finite number"),
        "{err}"
    );
    assert!(!fresh.exists());

    // Never over an input.
    let out = pkm()
        .args(["ik", &m, "--input"])
        .arg(&input)
        .arg("--output")
        .arg(&input)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("refusing to write"));
    assert!(std::fs::read_to_string(&input)
        .unwrap()
        .starts_with("X,Y,Z,A,B,C\n0,0,-290"));
}

#[test]
fn report_writes_a_self_contained_page() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    // No machine argument: the bundled seed-000 tripod, from any working directory.
    pkm()
        .current_dir(dir.path())
        .args(["report", "--out"])
        .arg(&out)
        .assert()
        .success();
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert!(html.contains("Seed 000 tripod"));
    // The translational tripod is identified with its platform joints held (they trade
    // against the base joints: the platform never turns), and no section failed.
    assert!(html.contains("Held at nominal"));
    assert!(!html.contains("could not be computed"));
    assert_eq!(
        html.matches("<svg").count(),
        14,
        "three views at home, two workspace slices, two motion plots, three at Table 1, \
         budget and Monte Carlo of the geometric tolerances, residuals and singular values \
         of the calibration study"
    );
    assert!(html.contains("Accuracy from geometric tolerances"));
    // The paper's study and figures come from the bundled file's [report] table (its
    // program embedded, as the working directory has no examples/).
    assert!(html.contains("seed000-arc.ngc"));
    assert!(html.contains("Published (seed 000, section 4"));
    assert!(html.contains("Kinematic checks"));
    assert!(html.contains("Top view") && html.contains("Front view") && html.contains("Side view"));
    assert!(
        !html.contains("http://") || !html.contains("<script src"),
        "no network resources"
    );
    assert!(
        !html.contains("class=\"bad\""),
        "every check passes on the default machine"
    );
    // The default output directory is pkm-report/.
    pkm()
        .current_dir(dir.path())
        .arg("report")
        .assert()
        .success();
    assert!(dir.path().join("pkm-report/index.html").exists());
    // Any machine.
    pkm()
        .args(["report", &centre_leg(), "--out"])
        .arg(dir.path().join("cl"))
        .assert()
        .success();
    let html = std::fs::read_to_string(dir.path().join("cl/index.html")).unwrap();
    assert!(html.contains("centre leg"));
}

#[test]
fn help_has_examples() {
    for cmd in ["ik", "fk", "check", "report"] {
        let out = pkm().args([cmd, "--help"]).output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            text.contains("Examples") || text.contains("Example:"),
            "{cmd}: {text}"
        );
    }
}

/// A closed-form forward solution says so instead of "0 iterations";
/// an iterative one gives its count.
#[test]
fn fk_names_its_solver() {
    let kr30 = root()
        .join("examples/machines/kr30-dh.toml")
        .display()
        .to_string();
    let out = pkm()
        .args(["fk", &kr30, "--actuators", "0,0,0,0,90,0"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("solver     closed form, residual"), "{text}");
    let (v, _) = json(&["fk", &kr30, "--actuators", "0,0,0,0,90,0", "--json"]);
    assert_eq!(v["solver"], "closed-form");
    let (v, _) = json(&["fk", &centre_leg(), "--actuators", "300,300,300", "--json"]);
    assert_eq!(v["solver"], "iterative", "{v}");
    assert!(v["iterations"].as_u64().unwrap() > 0, "{v}");
}

/// A batch FK of a machine in joint coordinates carries its tool pose after its
/// coordinates (`tool_X_mm` ... `tool_C_deg`): the KR 30 in joint coordinates gives
/// the same tool poses as the KR 30 in tool coordinates, whose pose columns are its
/// own forward kinematics (the robot's closed-form class, another mechanism).
#[test]
fn fk_batch_of_a_joint_space_machine_has_its_tool_pose() {
    let dir = tempfile::tempdir().unwrap();
    let kr30 = root().join("examples/machines/kr30-dh.toml");
    let joints = dir.path().join("kr30-joints.toml");
    let text = std::fs::read_to_string(&kr30).unwrap();
    std::fs::write(&joints, format!("pose = \"joints\"\n{text}")).unwrap();
    let q = dir.path().join("q.csv");
    std::fs::write(
        &q,
        "A1,A2,A3,A4,A5,A6\n10,20,-30,40,50,60\n-100,60,-150,170,-80,-20\n0,0,0,0,90,0\n",
    )
    .unwrap();
    let run = |machine: &std::path::Path, out: &str| {
        let out = dir.path().join(out);
        pkm()
            .args(["fk"])
            .arg(machine)
            .arg("--input")
            .arg(&q)
            .arg("--output")
            .arg(&out)
            .assert()
            .success();
        let text = std::fs::read_to_string(&out).unwrap();
        let mut lines = text.lines();
        let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
        let rows: Vec<Vec<String>> = lines
            .map(|l| l.split(',').map(String::from).collect())
            .collect();
        (header, rows)
    };
    let (h, rows) = run(&joints, "joints.csv");
    let tool: Vec<usize> = ["X_mm", "Y_mm", "Z_mm", "A_deg", "B_deg", "C_deg"]
        .iter()
        .map(|c| h.iter().position(|x| *x == format!("tool_{c}")).expect(c))
        .collect();
    assert_eq!(h[6], "A1_deg", "{h:?}");
    assert_eq!(tool[0], 12, "the tool pose follows the coordinates: {h:?}");
    let (hs, spatial) = run(&kr30, "spatial.csv");
    assert_eq!(hs[6], "X_mm", "{hs:?}");
    assert_eq!(rows.len(), 3);
    for (a, b) in rows.iter().zip(&spatial) {
        for (k, &c) in tool.iter().enumerate() {
            let (x, y): (f64, f64) = (a[c].parse().unwrap(), b[6 + k].parse().unwrap());
            assert!((x - y).abs() < 1e-9, "{k}: {x} vs {y}");
        }
    }
}

/// A reference whose expected value is the project's correction of
/// its source is printed as a discrepancy with the paper's and pkm's values, never as
/// reproduced; references quoting the same source are told apart by their pose.
#[test]
fn a_corrected_reference_is_a_discrepancy_not_reproduced() {
    let p3rp = root()
        .join("examples/machines/p3rp-seed004.toml")
        .display()
        .to_string();
    let out = pkm().args(["check", &p3rp]).output().unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    let lines: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("reference"))
        .collect();
    assert_eq!(lines.len(), 4);
    let mut unique = lines.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), 4, "{lines:?}");
    let d: Vec<&&str> = lines.iter().filter(|l| l.contains("DISCREPANCY")).collect();
    assert_eq!(d.len(), 1, "{lines:?}");
    assert!(
        d[0].contains("V: the source prints 600 mm, pkm's value is 660 mm"),
        "{}",
        d[0]
    );
    assert!(!d[0].contains("reproduced ("), "{}", d[0]);
    let (v, _) = json(&["check", &p3rp, "--json"]);
    let refs = v["references"].as_array().unwrap();
    assert_eq!(refs.iter().filter(|r| r["discrepancy"] == true).count(), 1);
}

/// A published value needs the project's value beside it and a note.
#[test]
fn a_published_value_without_its_correction_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("examples/machines/p3rp-seed004.toml"))
        .unwrap()
        .replace(
            "published_actuators = { V = 600.0 }",
            "published_actuators = { W = 600.0 }",
        );
    let f = dir.path().join("p.toml");
    std::fs::write(&f, text).unwrap();
    let (e, code) = stderr_of(&["check", f.to_str().unwrap()]);
    assert_eq!(code, 1, "{e}");
    assert!(
        e.contains("published_actuators") && e.contains("`W`"),
        "{e}"
    );
}

/// Near the P3RP head's singular configuration Q the forward
/// solution is returned with its conditioning, flagged; at home it is not flagged.
#[test]
fn fk_reports_the_conditioning_of_its_solution() {
    let p3rp = root()
        .join("examples/machines/p3rp-seed004.toml")
        .display()
        .to_string();
    let (v, _) = json(&[
        "fk",
        &p3rp,
        "--actuators",
        "300,785.0783",
        "--from",
        "300,125",
        "--json",
    ]);
    let c = v["condition"].as_f64().unwrap();
    assert!(c > 1e3, "{v}");
    assert_eq!(v["near_singular"], true);
    let out = pkm()
        .args([
            "fk",
            &p3rp,
            "--actuators",
            "300,785.0783",
            "--from",
            "300,125",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("NEAR A SINGULAR CONFIGURATION"), "{text}");
    let (v, _) = json(&["fk", &p3rp, "--actuators", "200,506.545", "--json"]);
    assert_eq!(v["near_singular"], false, "{v}");
    assert!(v["condition"].as_f64().unwrap() < 10.0);
}

/// Every example of every command's `--help` that names only files in the repository
/// runs as printed (from the repository root, its outputs in a temporary directory):
/// exit 0, or 3 where it says a limit is violated along a path.
#[test]
fn every_help_example_runs_as_printed() {
    let dir = tempfile::tempdir().unwrap();
    let placeholders = [
        "MACHINE",
        "ROBOT",
        "POSE",
        "my-",
        "devs.toml",
        "tight.toml",
        "part.ngc",
        "sim/",
        "poses.csv",
        "lengths.csv",
        "tracker.csv",
        "m.csv",
    ];
    let mut ran = 0;
    for cmd in [
        "ik",
        "fk",
        "check",
        "motion",
        "workspace",
        "errors",
        "report",
        "calibrate",
        "import",
        "export",
    ] {
        let o = pkm().args([cmd, "--help"]).output().unwrap();
        assert!(o.status.success());
        let help = String::from_utf8_lossy(&o.stdout).to_string();
        for line in help.lines().filter(|l| l.starts_with("  pkm ")) {
            // A trailing comment is separated by spaces and `#`.
            let line = line.split("   #").next().unwrap().trim();
            if placeholders.iter().any(|p| line.contains(p)) {
                continue;
            }
            let mut args: Vec<String> = line.split_whitespace().skip(1).map(String::from).collect();
            // Outputs go to the temporary directory, never into the repository.
            let out = dir.path().join(format!("out{ran}")).display().to_string();
            match args.iter().position(|a| a == "--out") {
                Some(k) => args[k + 1] = out,
                None if cmd == "report" => args.extend(["--out".into(), out]),
                None => {}
            }
            let o = pkm().current_dir(root()).args(&args).output().unwrap();
            assert!(
                matches!(o.status.code(), Some(0) | Some(3)),
                "`{line}`: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            ran += 1;
        }
    }
    assert!(ran >= 15, "{ran} examples ran");
}

/// An ik or fk batch written to `*.parquet` holds the rows of the same batch written
/// as CSV, value for value (the CSV's numbers are exact: shortest round-trip form):
/// reachable rows, a row beyond a limit with its violations, a row without a solution
/// with its message, nulls where the CSV is empty.
#[test]
fn batches_written_as_parquet_hold_the_csv_rows() {
    use crate::common::{assert_parquet_is_csv, parquet_rows, Cell};
    let dir = tempfile::tempdir().unwrap();
    let m = seed000();
    let run = |cmd: &str, input: &std::path::Path, out: &str| {
        let output = dir.path().join(out);
        let o = pkm()
            .args([cmd, &m, "--input"])
            .arg(input)
            .arg("--output")
            .arg(&output)
            .output()
            .unwrap();
        assert!(
            matches!(o.status.code(), Some(0) | Some(3)),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        output
    };
    let poses = dir.path().join("poses.csv");
    std::fs::write(
        &poses,
        "X,Y,Z,A,B,C\n0,0,-290,0,0,0\n10,5,-300,2,0,0\n0,0,-420,0,0,0\n-3.25,1e-3,-288.125,0,0,0\n",
    )
    .unwrap();
    let n = assert_parquet_is_csv(
        &run("ik", &poses, "q.parquet"),
        &run("ik", &poses, "q.csv"),
        0.0,
    );
    assert_eq!(n, 4);
    let lengths = dir.path().join("lengths.csv");
    // A set the tripod assembles (beyond a collision limit at the held orientation),
    // then one it cannot.
    std::fs::write(&lengths, "e,f,g\n215.35,189.2,224.45\n150,150,600\n").unwrap();
    let fk = run("fk", &lengths, "fk.parquet");
    assert_parquet_is_csv(&fk, &run("fk", &lengths, "fk.csv"), 0.0);
    let (names, rows) = parquet_rows(&fk);
    let col = |c: &str| names.iter().position(|n| n == c).unwrap();
    assert_eq!(rows[1][col("X_mm")], Cell::Null);
    assert_eq!(rows[1][col("iterations")], Cell::Null);
    assert!(matches!(&rows[1][col("status")], Cell::Text(t) if t.starts_with("line 3: ")));
    assert!(matches!(rows[0][col("iterations")], Cell::Num(_)));
    assert!(matches!(rows[0][col("X_mm")], Cell::Num(_)));
}

/// Actuator names longer than the usual column (a user's own `left-front-upper`) keep
/// `pkm ik`'s values in one column.
#[test]
fn ik_keeps_long_actuator_names_in_one_column() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/fixtures/own-hexapod.toml"
    ))
    .unwrap()
    .replace("name = \"L3\"", "name = \"left-front-upper\"");
    let file = dir.path().join("long-names.toml");
    std::fs::write(&file, text).unwrap();
    let out = pkm()
        .arg("ik")
        .arg(&file)
        .arg("--pose")
        .arg("0,0,600,0,0,0")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let columns: Vec<usize> = text
        .lines()
        .filter(|l| l.starts_with("actuator "))
        .map(|l| l.find(" mm").unwrap())
        .collect();
    assert_eq!(columns.len(), 6, "{text}");
    assert!(columns.iter().all(|c| *c == columns[0]), "{text}");
}

/// Runs `pkm CMD MACHINE --input INPUT --output OUTPUT`; its exit code and stderr.
fn batch_run(
    cmd: &str,
    machine: &str,
    input: &std::path::Path,
    output: &std::path::Path,
) -> (i32, String) {
    let out = pkm()
        .args([cmd, machine, "--input"])
        .arg(input)
        .arg("--output")
        .arg(output)
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn batches_chain_each_command_reads_what_the_other_writes() {
    use crate::common::{assert_parquet_is_csv, csv_rows, Cell};
    let dir = tempfile::tempdir().unwrap();
    let m = root()
        .join("examples/machines/kr30-dh.toml")
        .display()
        .to_string();
    let poses = dir.path().join("poses.csv");
    // A reachable pose, one beyond the links' reach (no solution: empty joints).
    std::fs::write(
        &poses,
        "X,Y,Z,A,B,C\n1200,100,1400,180,0,0\n9000,0,0,0,0,0\n",
    )
    .unwrap();
    let joints = dir.path().join("joints.csv");
    let (code, err) = batch_run("ik", &m, &poses, &joints);
    assert_eq!(code, 3, "{err}");
    assert!(
        err.contains("wrote 2 rows") && err.contains("1 reachable, 1 not"),
        "{err}"
    );
    // pkm fk reads the joints pkm ik wrote (A1_deg..A6_deg among the other columns);
    // the row without a solution stays a row, without values.
    let back = dir.path().join("back.csv");
    let (code, err) = batch_run("fk", &m, &joints, &back);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("1 solved within limits, 1 not"), "{err}");
    let (names, rows) = csv_rows(&back);
    assert_eq!(
        names[..7],
        ["A1_deg", "A2_deg", "A3_deg", "A4_deg", "A5_deg", "A6_deg", "X_mm"]
    );
    assert_eq!(rows.len(), 2);
    let x = names.iter().position(|n| n == "X_mm").unwrap();
    let status = names.iter().position(|n| n == "status").unwrap();
    for (k, want) in [1200.0, 100.0, 1400.0].into_iter().enumerate() {
        match rows[0][x + k] {
            Cell::Num(v) => assert!((v - want).abs() < 1e-9, "{v} vs {want}"),
            ref c => panic!("{c:?}"),
        }
    }
    assert!(
        rows[1][..status - 1].iter().all(|c| *c == Cell::Null),
        "{:?}",
        rows[1]
    );
    match &rows[1][status] {
        Cell::Text(t) => assert!(t.starts_with("line 3: no values"), "{t}"),
        c => panic!("{c:?}"),
    }
    // And pkm ik reads what pkm fk wrote (X_mm..C_deg among the other columns), as
    // CSV and as Parquet (the empty row's input cells nulls).
    let again = dir.path().join("again.csv");
    let (code, err) = batch_run("ik", &m, &back, &again);
    assert_eq!(code, 3, "{err}");
    let (names, rows) = csv_rows(&again);
    assert_eq!(
        names[..6],
        ["X_mm", "Y_mm", "Z_mm", "A_deg", "B_deg", "C_deg"]
    );
    assert_eq!(rows[0][names.len() - 2], Cell::Text("true".into()));
    let pq = dir.path().join("again.parquet");
    assert_eq!(batch_run("ik", &m, &back, &pq).0, 3);
    assert_parquet_is_csv(&pq, &again, 0.0);
    // A misspelt column is refused, not read as another list of values.
    std::fs::write(&poses, "X,Y,Z,A,B,CC\n1200,100,1400,180,0,0\n").unwrap();
    let (code, err) = batch_run("ik", &m, &poses, &again);
    assert_eq!(code, 1);
    assert!(
        err.contains("names `A,B` of `X,Y,Z,A,B,C` but not `C`"),
        "{err}"
    );
}
