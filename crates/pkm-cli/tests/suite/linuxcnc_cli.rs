//! `pkm import linuxcnc` and `pkm export linuxcnc` end to end: the simulator
//! configurations imported, checked, run through a program, exported and imported back.

use super::common::{ok, path, pkm};

#[test]
fn import_check_run_export_and_import_again() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("pentapod.toml");
    let o = pkm()
        .args([
            "import",
            "linuxcnc",
            &path("tests/fixtures/linuxcnc/pentapod/pentapod.ini"),
        ])
        .arg("--out")
        .arg(&m)
        .output()
        .unwrap();
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("warning: the INI's [JOINT_n] HOME"), "{err}");
    let o = pkm().arg("check").arg(&m).output().unwrap();
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("valid pentapod machine"));
    // Strut speeds of a 5-axis program on the imported machine.
    let out = dir.path().join("run");
    let o = pkm()
        .arg("motion")
        .arg(&m)
        .args([
            "--gcode",
            &path("examples/paths/pentapod-tilt.ngc"),
            "--json",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["feed_override_max"].as_f64().unwrap() > 1.0, "{v}");
    // Back to the controller, in inches, and imported again.
    let lc = dir.path().join("lc");
    let o = pkm()
        .args(["export", "linuxcnc"])
        .arg(&m)
        .args(["--units", "inch", "--out"])
        .arg(&lc)
        .output()
        .unwrap();
    ok(&o);
    let hal = std::fs::read_to_string(lc.join("kinematics.hal")).unwrap();
    assert!(
        hal.contains("setp pentakins.effector.0.r 3.161417322835"),
        "{hal}"
    );
    let ini = std::fs::read_to_string(lc.join("pkm.ini")).unwrap();
    assert!(ini.contains("KINEMATICS = pentakins") && ini.contains("LINEAR_UNITS = inch"));
    let again = dir.path().join("again.toml");
    let o = pkm()
        .args(["import", "linuxcnc"])
        .arg(lc.join("pkm.ini"))
        .arg("--out")
        .arg(&again)
        .arg("--json")
        .output()
        .unwrap();
    ok(&o);
    let ik = |file: &std::path::Path| {
        let o = pkm()
            .arg("ik")
            .arg(file)
            .args(["--pose", "10,20,30,5,3", "--json"])
            .output()
            .unwrap();
        ok(&o);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["actuators"].clone()
    };
    let (a, b) = (ik(&m), ik(&again));
    let vals = |v: &serde_json::Value| -> Vec<f64> {
        (0..5).map(|i| v[i.to_string()].as_f64().unwrap()).collect()
    };
    for (x, y) in vals(&a).iter().zip(vals(&b)) {
        assert!((x - y).abs() < 1e-8, "{x} vs {y}");
    }
}

#[test]
fn import_never_writes_over_its_input_and_errors_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let ini = dir.path().join("m.ini");
    std::fs::write(&ini, "[KINS]\nKINEMATICS = trivkins\n").unwrap();
    let o = pkm()
        .args(["import", "linuxcnc"])
        .arg(&ini)
        .arg("--out")
        .arg(dir.path().join("m.toml"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("m.ini:2: field `[KINS] KINEMATICS`: unsupported kinematics `trivkins`"),
        "{err}"
    );
    let good = path("tests/fixtures/linuxcnc/hexapod-sim/hexapod.ini");
    let o = pkm()
        .args(["import", "linuxcnc", &good, "--out", &good])
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stderr).contains("refusing to write"));
    let o = pkm()
        .args([
            "export",
            "linuxcnc",
            &path("examples/machines/mc300.toml"),
            "--out",
        ])
        .arg(dir.path().join("x"))
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stderr)
        .contains("LinuxCNC export is not available for a serial"));
}
