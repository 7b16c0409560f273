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

/// A five-axis LinuxCNC machine: the XYZBC sim imported, its joints for a TCP pose, LinuxCNC's
/// boat program run to its end (exit 3 with the violated limits listed: the sim's
/// axes are slow for the program's inverse-time feeds).
#[test]
fn the_xyzbc_sim_imported_its_joints_and_the_boat_program() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("xyzbc.toml");
    let o = pkm()
        .args([
            "import",
            "linuxcnc",
            &path("tests/fixtures/linuxcnc/xyzbc-trt/xyzbc-trt.ini"),
        ])
        .arg("--out")
        .arg(&m)
        .output()
        .unwrap();
    ok(&o);
    let o = pkm()
        .arg("ik")
        .arg(&m)
        .args(["--pose=10,5,-3,30,40", "--json"])
        .output()
        .unwrap();
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let acts = v["actuators"].as_object().unwrap();
    let names: Vec<&str> = acts.keys().map(|k| k.as_str()).collect();
    assert_eq!(names, ["X", "Y", "Z", "B", "C"]);
    // xyzbc-trt-kins with x-offset -20, z-offset -15 (trtfuncs' inverse, by hand).
    let (sb, cb) = 30f64.to_radians().sin_cos();
    let (sc, cc) = 40f64.to_radians().sin_cos();
    let (dx, dz) = (-20.0, -15.0);
    let want = [
        cc * cb * 10.0 - sc * cb * 5.0 + sb * -3.0 - cb * dx - sb * dz + dx,
        sc * 10.0 + cc * 5.0,
        -cc * sb * 10.0 + sc * sb * 5.0 + cb * -3.0 + sb * dx - cb * dz + dz,
        30.0,
        40.0,
    ];
    for ((n, a), w) in acts.iter().zip(want) {
        let got = a.as_f64().unwrap();
        assert!((got - w).abs() < 1e-9, "{n} {got} vs {w}");
    }
    let out = dir.path().join("boat");
    let o = pkm()
        .arg("motion")
        .arg(&m)
        .args([
            "--gcode",
            &path("tests/fixtures/linuxcnc/xyzbc-trt/boat-xyzbc.ngc"),
            "--summary-only",
            "--tool-length",
            "40",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("note: line 2: M428"), "{text}");
    assert!(text.contains("G43 H1: tool length 40 mm"), "{text}");
    let err = String::from_utf8_lossy(&o.stderr);
    // The first rapid runs each axis at the sim's 20 mm/s, yet the Y slide exceeds it
    // where the table turns (TCP: the slide follows the tip and the rotary axes).
    assert!(
        err.contains("actuator Y velocity beyond 20.000 mm/s"),
        "{err}"
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s["duration_s"].as_f64().unwrap() > 300.0);
    let rapid = s["rapid_override_max"].as_f64().unwrap();
    assert!(rapid > 0.5 && rapid < 0.6, "{rapid}");
}

/// A tripodkins configuration: imported, checked (its [JOINT_n] HOME reproduced), run
/// through a program, its report written, exported in inches and imported again.
#[test]
fn a_tripodkins_machine_goes_through_import_check_motion_report_and_export() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("tripod.toml");
    ok(&pkm()
        .args([
            "import",
            "linuxcnc",
            &path("tests/fixtures/linuxcnc/tripod/tripod.ini"),
        ])
        .arg("--out")
        .arg(&m)
        .output()
        .unwrap());
    let o = pkm().arg("check").arg(&m).output().unwrap();
    ok(&o);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("valid tripod/translational machine"), "{out}");
    assert!(out.contains("reproduced"), "{out}");
    let prog = dir.path().join("p.ngc");
    std::fs::write(
        &prog,
        "G21 G90\nG0 X254 Y146.6469 Z381\nG1 X354 F3000\nG2 X254 Y246.6469 I-100 J0\nM2\n",
    )
    .unwrap();
    let o = pkm()
        .arg("motion")
        .arg(&m)
        .arg("--gcode")
        .arg(&prog)
        .args(["--from", "254,146.6469,381", "--json", "--out"])
        .arg(dir.path().join("run"))
        .output()
        .unwrap();
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["samples"].as_u64().unwrap() > 10, "{v}");
    ok(&pkm()
        .arg("report")
        .arg(&m)
        .arg("--out")
        .arg(dir.path().join("rep"))
        .output()
        .unwrap());
    let lc = dir.path().join("lc");
    ok(&pkm()
        .args(["export", "linuxcnc"])
        .arg(&m)
        .args(["--units", "inch", "--out"])
        .arg(&lc)
        .output()
        .unwrap());
    let hal = std::fs::read_to_string(lc.join("kinematics.hal")).unwrap();
    assert!(hal.contains("setp tripodkins.Bx 20.0\n"), "{hal}");
    let again = dir.path().join("again.toml");
    ok(&pkm()
        .args(["import", "linuxcnc"])
        .arg(lc.join("pkm.ini"))
        .arg("--out")
        .arg(&again)
        .output()
        .unwrap());
    let o = pkm().arg("check").arg(&again).output().unwrap();
    ok(&o);
}
