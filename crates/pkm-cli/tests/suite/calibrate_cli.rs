//! `pkm simulate-measurements` and `pkm calibrate` end to end.

use serde_json::Value;

use crate::common::{ok, path, pkm};

#[test]
fn simulate_then_calibrate_gives_a_machine_file_and_a_report() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    let hex = path("examples/machines/hexapod-seed001.toml");
    let o = pkm()
        .args([
            "simulate-measurements",
            &hex,
            "--deviation",
            "1",
            "--point-noise",
            "0.005",
        ])
        .args([
            "--length-noise",
            "0.001",
            "--states",
            "50",
            "--holdout",
            "20",
            "--seed",
            "7",
        ])
        .arg("--out")
        .arg(&sim)
        .output()
        .unwrap();
    ok(&o);
    for f in [
        "measurements.csv",
        "validation.csv",
        "true.toml",
        "truth.json",
    ] {
        assert!(sim.join(f).exists(), "{f}");
    }
    let cal = dir.path().join("cal");
    let o = pkm()
        .args(["calibrate", &hex, "--measurements"])
        .arg(sim.join("measurements.csv"))
        .arg("--validation")
        .arg(sim.join("validation.csv"))
        .arg("--json")
        .arg("--out")
        .arg(&cal)
        .output()
        .unwrap();
    ok(&o);
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["parameters"].as_array().unwrap().len(), 42);
    assert!(r["residual_rms_before"].as_f64().unwrap() > 0.3);
    assert!(r["residual_rms_after"].as_f64().unwrap() < 0.01);
    assert!(r["condition_number"].as_f64().unwrap() > 1.0);
    assert_eq!(r["singular_values"].as_array().unwrap().len(), 42);
    // Held-out states: millimetres with the nominal model, the noise level after.
    let v = &r["validation"];
    assert!(v["nominal"]["rms"].as_f64().unwrap() > 0.5, "{v}");
    assert!(v["identified"]["rms"].as_f64().unwrap() < 0.02, "{v}");
    // The tool pose against the measured (best-fit) pose: position and orientation.
    assert!(
        v["nominal"]["pose"]["position_rms"].as_f64().unwrap() > 0.5,
        "{v}"
    );
    assert!(
        v["identified"]["pose"]["position_rms"].as_f64().unwrap() < 0.02,
        "{v}"
    );
    assert!(
        v["identified"]["pose"]["orientation_max"].as_f64().unwrap() < 2e-4,
        "{v}"
    );
    // The identified parameters are near the truth (within 4 standard errors).
    let truth: Value =
        serde_json::from_slice(&std::fs::read(sim.join("truth.json")).unwrap()).unwrap();
    for p in r["parameters"].as_array().unwrap() {
        let name = p["name"].as_str().unwrap();
        let t = truth["true_parameters"][name].as_f64().unwrap();
        let (v, se) = (
            p["identified"].as_f64().unwrap(),
            p["standard_error"].as_f64().unwrap(),
        );
        assert!(
            (v - t).abs() < 4.0 * se + 1e-9,
            "{name}: {v} vs {t} (se {se})"
        );
    }
    for f in [
        "identified.toml",
        "report.json",
        "residuals.svg",
        "singular-values.svg",
    ] {
        assert!(cal.join(f).exists(), "{f}");
    }
    // identified.toml is a machine file every command takes.
    let o = pkm()
        .arg("check")
        .arg(cal.join("identified.toml"))
        .output()
        .unwrap();
    ok(&o);
    // Re-calibrating from the identified machine changes nothing (it is the optimum).
    let o = pkm()
        .arg("calibrate")
        .arg(cal.join("identified.toml"))
        .arg("--measurements")
        .arg(sim.join("measurements.csv"))
        .args(["--json", "--out"])
        .arg(dir.path().join("again"))
        .output()
        .unwrap();
    ok(&o);
    let r2: Value = serde_json::from_slice(&o.stdout).unwrap();
    let (a, b) = (
        r["residual_rms_after"].as_f64().unwrap(),
        r2["residual_rms_before"].as_f64().unwrap(),
    );
    assert!((a - b).abs() < 1e-9, "{a} {b}");
}

#[test]
fn bad_measurements_and_unidentifiable_designs_are_named() {
    let dir = tempfile::tempdir().unwrap();
    let hex = path("examples/machines/hexapod-seed001.toml");
    let bad = dir.path().join("bad.csv");
    std::fs::write(
        &bad,
        "# fixture P1 = 0, 200, 0\n# fixture P2 = -173.2, -100, 0\n# fixture P3 = 173.2, -100, 0\n\
         state,dL1,dL2,dL3,dL4,dL5,dL6,P1_x,P1_y,P1_z,P2_x,P2_y,P2_z,P3_x,P3_y,P3_z\n\
         1,0,0,0,0,0,0,0,200,700,-173.2,-100,700,173.2,-100,7o0\n",
    )
    .unwrap();
    let o = pkm()
        .args(["calibrate", &hex, "--measurements"])
        .arg(&bad)
        .arg("--out")
        .arg(dir.path().join("c"))
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.csv:5:16") && err.contains("P3_z") && err.contains("`7o0`"),
        "{err}"
    );
    // Pure translations cannot separate a base joint from its platform joint.
    let sim = dir.path().join("tr");
    ok(&pkm()
        .args([
            "simulate-measurements",
            &hex,
            "--rotation",
            "0",
            "--states",
            "30",
            "--out",
        ])
        .arg(&sim)
        .output()
        .unwrap());
    let o = pkm()
        .args(["calibrate", &hex, "--measurements"])
        .arg(sim.join("measurements.csv"))
        .arg("--out")
        .arg(dir.path().join("c2"))
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("not identifiable")
            && err.contains("moved alike (a translation of the strut)"),
        "{err}"
    );
}

#[test]
fn hexapod_report_has_a_calibration_section() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    ok(&pkm()
        .args([
            "report",
            &path("examples/machines/hexapod-seed001.toml"),
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap());
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("id=\"calibration\""));
    assert!(html.contains("id=\"accuracy\""));
    assert!(html.contains("Accuracy from geometric tolerances"));
    assert!(html.contains("one-strut design"));
    assert!(html.contains("singular values of the scaled identification Jacobian"));
}

#[test]
fn tripod_calibrates_with_its_platform_joints_held() {
    let dir = tempfile::tempdir().unwrap();
    let tri = path("examples/machines/tripod-seed000.toml");
    let sim = dir.path().join("sim");
    ok(&pkm()
        .args([
            "simulate-measurements",
            &tri,
            "--translation",
            "30",
            "--fixture-radius",
            "40",
        ])
        .args(["--states", "30", "--holdout", "10", "--out"])
        .arg(&sim)
        .output()
        .unwrap());
    // Without holding anything: a base joint trades against its platform joint.
    let o = pkm()
        .args(["calibrate", &tri, "--measurements"])
        .arg(sim.join("measurements.csv"))
        .arg("--out")
        .arg(dir.path().join("c0"))
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not identifiable"));
    let cal = dir.path().join("cal");
    let o = pkm()
        .args([
            "calibrate",
            &tri,
            "--fix",
            "C.*,D.*,E.*",
            "--json",
            "--measurements",
        ])
        .arg(sim.join("measurements.csv"))
        .arg("--validation")
        .arg(sim.join("validation.csv"))
        .arg("--out")
        .arg(&cal)
        .output()
        .unwrap();
    ok(&o);
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    let params = r["parameters"].as_array().unwrap();
    assert_eq!(params.len(), 21);
    assert_eq!(params.iter().filter(|p| p["free"] == false).count(), 9);
    let v = &r["validation"];
    assert!(v["nominal"]["rms"].as_f64().unwrap() > 1.0, "{v}");
    assert!(v["identified"]["rms"].as_f64().unwrap() < 0.03, "{v}");
    ok(&pkm()
        .arg("check")
        .arg(cal.join("identified.toml"))
        .output()
        .unwrap());
    let fixing = |fix: &str| {
        pkm()
            .args(["calibrate", &tri, "--fix", fix, "--measurements"])
            .arg(sim.join("measurements.csv"))
            .arg("--out")
            .arg(dir.path().join("c1"))
            .output()
            .unwrap()
    };
    // An unknown --fix pattern lists the parameters.
    let o = fixing("Q.*");
    assert!(String::from_utf8_lossy(&o.stderr).contains("no parameter matches `Q.*`"));
    // Holding every parameter leaves nothing to identify (it once panicked in the SVD).
    let o = fixing("*");
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        String::from_utf8_lossy(&o.stderr),
        "error: fixed parameters: nothing to identify: every parameter is fixed by --fix '*'\n"
    );
}

/// A pentapod is identified from points on its tool axis, and its identified
/// file goes back to LinuxCNC with the zero lengths as HOME_OFFSET.
#[test]
fn a_pentapod_calibrates_and_goes_back_to_linuxcnc() {
    let dir = tempfile::tempdir().unwrap();
    let pen = path("examples/machines/pentapod-linuxcnc.toml");
    let sim = dir.path().join("sim");
    ok(&pkm()
        .args([
            "simulate-measurements",
            &pen,
            "--states",
            "40",
            "--holdout",
            "10",
        ])
        .arg("--out")
        .arg(&sim)
        .output()
        .unwrap());
    let csv = std::fs::read_to_string(sim.join("measurements.csv")).unwrap();
    assert!(csv.contains("two points on the tool axis"), "{csv}");
    assert!(csv.contains("# fixture P2 = 0, 0, 200"), "{csv}");
    let cal = dir.path().join("cal");
    let o = pkm()
        .args(["calibrate", &pen, "--json", "--measurements"])
        .arg(sim.join("measurements.csv"))
        .arg("--validation")
        .arg(sim.join("validation.csv"))
        .arg("--out")
        .arg(&cal)
        .output()
        .unwrap();
    ok(&o);
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["parameters"].as_array().unwrap().len(), 30);
    let v = &r["validation"];
    assert!(v["identified"]["rms"].as_f64().unwrap() < 0.05, "{v}");
    let lc = dir.path().join("lc");
    ok(&pkm()
        .args(["export", "linuxcnc"])
        .arg(cal.join("identified.toml"))
        .arg("--out")
        .arg(&lc)
        .output()
        .unwrap());
    let ini = std::fs::read_to_string(lc.join("pkm.ini")).unwrap();
    let text = std::fs::read_to_string(cal.join("identified.toml")).unwrap();
    assert!(text.contains("zero_lengths"), "{text}");
    assert_eq!(ini.matches("HOME_OFFSET = ").count(), 5, "{ini}");
    // The seed 001 procedure does not apply to it: a clear error, not a crash.
    let o = pkm()
        .args(["calibrate", &pen, "--seed-procedure", "--measurements"])
        .arg(sim.join("measurements.csv"))
        .arg("--out")
        .arg(dir.path().join("sp"))
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("least squares"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A 15 mm micro-hexapod with the defaults: the campaign is fitted to the machine
/// (1/16 of the machine-tool defaults, recorded in truth.json), options given on the
/// command line are used as given, and the campaign identifies the machine.
#[test]
fn the_default_campaign_fits_a_micro_hexapod() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    let micro = path("tests/fixtures/micro-hexapod.toml");
    let o = pkm()
        .args(["simulate-measurements", &micro, "--holdout", "20", "--out"])
        .arg(&sim)
        .output()
        .unwrap();
    ok(&o);
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(sim.join("truth.json")).unwrap()).unwrap();
    let e = &truth["experiment"];
    assert_eq!(e["default_scale"], 0.0625, "{e}");
    assert_eq!(e["translation"], 6.25);
    assert_eq!(e["deviation"], 0.0625);
    assert_eq!(e["step"], 2.5);
    assert!(e["fixture"].as_str().unwrap().contains("12.5 mm"), "{e}");
    let csv = std::fs::read_to_string(sim.join("measurements.csv")).unwrap();
    assert!(csv.contains("# fixture P1 = 0, 12.5, 0"), "{csv}");
    // The true machine is within 0.0625 mm of the nominal joints.
    let d = truth["true_parameters"]["B1.x"].as_f64().unwrap() - 29.3444;
    assert!(d.abs() <= 0.0625, "{d}");
    let o = pkm()
        .args(["calibrate", &micro, "--measurements"])
        .arg(sim.join("measurements.csv"))
        .arg("--validation")
        .arg(sim.join("validation.csv"))
        .arg("--json")
        .arg("--out")
        .arg(dir.path().join("cal"))
        .output()
        .unwrap();
    ok(&o);
    let r: Value = serde_json::from_slice(&o.stdout).unwrap();
    let v = &r["validation"];
    assert!(
        v["identified"]["rms"].as_f64().unwrap() < v["nominal"]["rms"].as_f64().unwrap() / 5.0,
        "{v}"
    );
    // Given spans are used as given: the default span does not fit this machine.
    let o = pkm()
        .args([
            "simulate-measurements",
            &micro,
            "--translation",
            "100",
            "--out",
        ])
        .arg(dir.path().join("sim2"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("poses within the limits"), "{err}");
}

/// `--condition-ratio`: recorded in truth.json (`inf` as a string), a bound below 1
/// refused naming it, and nothing written.
#[test]
fn the_condition_bound_of_random_states_is_an_option() {
    let dir = tempfile::tempdir().unwrap();
    let tri = path("tests/fixtures/micro-tripod.toml");
    for (ratio, recorded) in [("4", serde_json::json!(4.0)), ("inf", "inf".into())] {
        let sim = dir.path().join(format!("sim-{ratio}"));
        ok(&pkm()
            .args(["simulate-measurements", &tri, "--condition-ratio", ratio])
            .arg("--out")
            .arg(&sim)
            .output()
            .unwrap());
        let t: Value =
            serde_json::from_str(&std::fs::read_to_string(sim.join("truth.json")).unwrap())
                .unwrap();
        assert_eq!(t["experiment"]["condition_ratio"], recorded, "{t}");
    }
    let sim = dir.path().join("sim-bad");
    let o = pkm()
        .args(["simulate-measurements", &tri, "--condition-ratio", "0.5"])
        .arg("--out")
        .arg(&sim)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("condition ratio: expected a number >= 1"),
        "{err}"
    );
    assert!(!sim.exists());
}
