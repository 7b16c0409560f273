//! Seed 002's machine (`hybrid-am-seed002.toml`) through the commands a user runs:
//! check, ik, fk, motion with the hemisphere program, errors over the hemisphere,
//! report.

use serde_json::Value;

use crate::common::{ok, path, pkm};

fn machine() -> String {
    path("examples/machines/hybrid-am-seed002.toml")
}

#[test]
fn check_ik_and_fk_agree_on_the_equator() {
    let o = pkm().args(["check", &machine()]).output().unwrap();
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("valid hybrid-am machine"));
    // The equator of the hemisphere, nozzle horizontal (B = 90 deg).
    let o = pkm()
        .args(["ik", &machine(), "--pose", "75,0,0,0,90,0", "--json"])
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["reachable"], Value::Bool(true));
    let q: Vec<String> = ["q1", "q2", "q3", "q4", "C"]
        .iter()
        .map(|k| format!("{:.12}", v["actuators"][k].as_f64().unwrap()))
        .collect();
    assert!((v["actuators"]["q1"].as_f64().unwrap() - 318.952771559).abs() < 1e-8);
    let o = pkm()
        .args(["fk", &machine(), "--actuators", &q.join(","), "--json"])
        .output()
        .unwrap();
    ok(&o);
    let f: Value = serde_json::from_slice(&o.stdout).unwrap();
    for (k, want) in [("X", 75.0), ("Y", 0.0), ("Z", 0.0), ("B", 90.0), ("C", 0.0)] {
        let got = f["pose"][k].as_f64().unwrap();
        assert!((got - want).abs() < 1e-8, "{k}: {got}");
    }
    // An unreachable pose names the strut.
    let o = pkm()
        .args(["ik", &machine(), "--pose", "600,0,0,0,45,0"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("beyond the strut's length"));
}

#[test]
fn the_hemisphere_program_runs_through_the_mechanism() {
    let dir = tempfile::tempdir().unwrap();
    let o = pkm()
        .args([
            "motion",
            &machine(),
            "--gcode",
            &path("examples/paths/seed002-hemisphere.ngc"),
            "--json",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    ok(&o);
    let csv = std::fs::read_to_string(dir.path().join("actuators.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    for a in ["q1", "q2", "q3", "q4", "C"] {
        assert!(header.contains(a), "{header}");
    }
    // Three full turns of the table, back and forth, and back to the pole.
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let travel = v["actuators"]["C"]["travel"].as_f64().unwrap();
    assert!((travel - 1080.0).abs() < 1e-9, "{travel}");
    // No carriage leaves its stroke (250..700 mm) on the way.
    for a in ["q1", "q2", "q3", "q4"] {
        let (min, max) = (
            v["actuators"][a]["min"].as_f64().unwrap(),
            v["actuators"][a]["max"].as_f64().unwrap(),
        );
        assert!(min > 250.0 && max < 700.0, "{a}: {min} {max}");
    }
}

#[test]
fn errors_over_the_hemisphere_answer_the_designers_question() {
    let dir = tempfile::tempdir().unwrap();
    let o = pkm()
        .args([
            "errors",
            &machine(),
            "--surface",
            "hemisphere:75",
            "--surface-centre",
            "0,0,0",
            "--surface-points",
            "16",
            "--tolerance",
            "0.3",
            "--json",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let c = &v["clearance"];
    // Every height reachable; the largest at the equator (the paper's Fig. 4).
    assert_eq!(c["surface"]["unreachable"].as_u64(), Some(0));
    assert_eq!(c["surface"]["worst_z"].as_f64(), Some(0.0));
    let csv = std::fs::read_to_string(dir.path().join("surface.csv")).unwrap();
    assert_eq!(csv.lines().count(), 17);
    assert!(csv.lines().skip(1).all(|l| !l.ends_with(',')));
    let classes = c["largest_per_class"].as_array().unwrap();
    assert_eq!(classes.len(), 2);
    for k in classes {
        let mm = k["largest_mm"].as_f64().unwrap();
        assert!(mm > 0.0 && mm < 0.1, "{k}");
    }
    let uniform = c["largest_clearance_mm"].as_f64().unwrap();
    assert!(uniform > 0.04 && uniform < 0.07, "{uniform}");
}

#[test]
fn the_report_has_a_clearance_section() {
    let dir = tempfile::tempdir().unwrap();
    let o = pkm()
        .args(["report", &machine(), "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    ok(&o);
    let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
    assert!(html.contains("Joint clearances") && html.contains("carriage"));
}
