//! Bad input, awkward machines and closed pipes: pkm answers or ends quietly, never
//! with a panic.

use crate::common;
use crate::common::path;

/// A reader that has gone away (`pkm ... | head`): the command ends without a panic
/// (by SIGPIPE, as a Unix tool does, or normally if it wrote before the pipe closed).
#[test]
fn a_closed_pipe_ends_the_command_quietly() {
    use std::process::{Command, Stdio};
    let bin = assert_cmd::cargo::cargo_bin("pkm");
    for args in [
        vec![
            "check".to_string(),
            path("examples/machines/hexapod-seed001.toml"),
        ],
        vec![
            "ik".to_string(),
            path("examples/machines/hybrid-am-seed002.toml"),
            "--pose".into(),
            "75,0,0,0,90,0".into(),
            "--json".into(),
        ],
    ] {
        let mut child = Command::new(&bin)
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Close the reading end before the command writes.
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_ne!(out.status.code(), Some(101), "{args:?}: {stderr}");
        #[cfg(unix)]
        {
            use std::os::unix::process::ExitStatusExt;
            assert!(
                out.status.success() || out.status.signal() == Some(libc_sigpipe()),
                "{args:?}: {:?}",
                out.status
            );
        }
    }
}

/// Standard output that cannot be written (a full disk: `/dev/full`) is an error, exit
/// code 1 as any other failed write, never a panic or a success with the answer lost:
/// a command's text and JSON, and clap's help and version.
#[cfg(target_os = "linux")]
#[test]
fn a_full_standard_output_is_an_error() {
    let machine = path("examples/machines/hexapod-linuxcnc.toml");
    for args in [
        vec!["check", &machine],
        vec!["check", &machine, "--json"],
        vec!["--help"],
        vec!["--version"],
        vec!["motion", "--help"],
    ] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let o = std::process::Command::new(assert_cmd::cargo::cargo_bin("pkm"))
            .args(&args)
            .stdout(full)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("error: writing to standard output: No space left on device"),
            "{args:?}: {stderr}"
        );
    }
}

/// SIGPIPE's number on Linux and the BSDs.
#[cfg(unix)]
fn libc_sigpipe() -> i32 {
    13
}

/// A robot whose zero pose is singular (`pkm check` once failed on the UR5 with
/// "singular configuration") is a valid file with a warning.
#[test]
fn a_singular_robot_home_is_a_warning() {
    let o = common::pkm()
        .args(["check", &path("examples/robots/ur5-like.urdf")])
        .output()
        .unwrap();
    common::ok(&o);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("valid serial machine"), "{out}");
    assert!(
        out.contains("warning     the home pose is singular"),
        "{out}"
    );
    let o = common::pkm()
        .args(["check", &path("examples/robots/ur5-like.urdf"), "--json"])
        .output()
        .unwrap();
    common::ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["home"]["singular"], serde_json::Value::Bool(true));
}

/// Grid steps of zero, negative, NaN or absurdly fine (`--step 0` once overflowed
/// into a panic) are refused with what was expected.
#[test]
fn bad_grid_steps_are_refused() {
    let tripod = path("examples/machines/tripod-seed000.toml");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().display().to_string();
    for (flag, want) in [
        ("--step=0", "expected a step > 0"),
        ("--step=-1", "expected a step > 0"),
        ("--step=nan", "expected a step > 0, found NaN"),
        ("--step=1e-9", "points; give a larger --step"),
        ("--forward-step=0", "expected a step > 0"),
    ] {
        let mut args = vec!["workspace", tripod.as_str(), flag, "--out", out.as_str()];
        if flag.starts_with("--forward") {
            args.push("--forward");
        }
        let o = common::pkm().args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{flag}");
        assert!(!stderr.contains("panicked"), "{flag}: {stderr}");
        assert!(stderr.contains(want), "{flag}: {stderr}");
    }
}

/// Every command takes `--json` (`report` and `simulate-measurements` once did
/// not).
#[test]
fn report_and_simulate_measurements_take_json() {
    let dir = tempfile::tempdir().unwrap();
    let o = common::pkm()
        .args([
            "report",
            &path("examples/machines/hybrid-am-seed002.toml"),
            "--json",
            "--out",
        ])
        .arg(dir.path().join("r"))
        .output()
        .unwrap();
    common::ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let sections: Vec<&str> = v["sections"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    let html = std::fs::read_to_string(dir.path().join("r/index.html")).unwrap();
    for s in &sections {
        assert!(html.contains(&format!("<h2 id=\"{s}\"")), "{s}");
    }
    assert!(sections.contains(&"clearance"), "{sections:?}");
    let o = common::pkm()
        .args([
            "simulate-measurements",
            &path("examples/machines/hexapod-seed001.toml"),
            "--states",
            "20",
            "--json",
            "--out",
        ])
        .arg(dir.path().join("s"))
        .output()
        .unwrap();
    common::ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["states"], 20);
    assert_eq!(v["true_parameters"].as_object().unwrap().len(), 42);
}

/// A reading of 1e300 in a measurement file (it once surfaced as an
/// identifiability failure naming no row) is refused at its row and column.
#[test]
fn an_absurd_measurement_names_its_row() {
    let dir = tempfile::tempdir().unwrap();
    let hex = path("examples/machines/hexapod-seed001.toml");
    let o = common::pkm()
        .args(["simulate-measurements", &hex, "--states", "12", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    common::ok(&o);
    let file = dir.path().join("measurements.csv");
    let text = std::fs::read_to_string(&file).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let row = lines.iter().position(|l| l.starts_with("5,")).unwrap();
    let mut cells: Vec<String> = lines[row].split(',').map(str::to_string).collect();
    cells[3] = "1e300".into();
    let bad_row = cells.join(",");
    let mut bad: Vec<&str> = lines.clone();
    bad[row] = &bad_row;
    std::fs::write(&file, bad.join("\n")).unwrap();
    let o = common::pkm()
        .args(["calibrate", &hex, "--measurements"])
        .arg(&file)
        .arg("--out")
        .arg(dir.path().join("cal"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains(&format!(":{}:4", row + 1)) && stderr.contains("magnitude"),
        "{stderr}"
    );
}
