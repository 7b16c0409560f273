//! `pkm errors` end to end on the MC-300-like example.

use serde_json::Value;

use crate::common::{ok, path, pkm};

#[test]
fn errors_json_contract_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let devs = dir.path().join("devs.toml");
    // dq of X moves the tool 1:1 along the part's X at B = C = 0; delta_z of the
    // spindle link (its S* origin along its Z, world Z) lifts the tool tip.
    std::fs::write(&devs, "\"dq(X)\" = 0.01\n\"delta_z(3 spindle)\" = 0.02\n").unwrap();
    let out = dir.path().join("err");
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/mc300.toml"),
            "--actuators",
            "100,-50,-80,0,0",
            "--deviations",
        ])
        .arg(&devs)
        .args(["--monte-carlo", "20000", "--json", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let e: Vec<f64> = v["position_error"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(
        (e[0] - 0.01).abs() < 1e-12 && e[1].abs() < 1e-12 && (e[2] - 0.02).abs() < 1e-12,
        "{e:?}"
    );
    assert_eq!(v["orientation_error_deg"].as_array().unwrap().len(), 3);
    let budget = v["budget"].as_object().unwrap();
    // Seed 003's deviation set as pkm carries it: 39 rows, each with an effect (the
    // installation angles, which cannot move the tool relative to the part, and the
    // angles between aligned axes are refused; docs/serial.md).
    assert_eq!(budget.len(), 39);
    assert!(budget.get("theta_x0").is_none());
    for item in v["budget_items"].as_array().unwrap() {
        assert!(
            item["position_mm"].as_f64().unwrap() > 0.0
                || item["orientation_deg"].as_f64().unwrap() > 0.0,
            "{item}"
        );
    }
    assert!((budget["dq(X)"].as_f64().unwrap() - 0.004).abs() < 1e-12);
    let mc = &v["monte_carlo"];
    for k in ["mean", "std", "p95", "p99", "max"] {
        assert!(mc[k].as_f64().unwrap() > 0.0, "{k}");
    }
    assert!(mc["p95"].as_f64().unwrap() <= v["budget_worst_case"].as_f64().unwrap());
    for f in ["errors.json", "budget.svg", "monte-carlo.svg"] {
        assert!(out.join(f).exists(), "{f}");
    }
    // Named errors.
    std::fs::write(&devs, "\"delta_q(9 arm)\" = 0.01\n").unwrap();
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/mc300.toml"),
            "--deviations",
        ])
        .arg(&devs)
        .arg("--out")
        .arg(dir.path().join("bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("unknown deviation `delta_q(9 arm)`") && e.contains("devs.toml:1:"),
        "{e}"
    );
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/p3rp-seed004.toml"),
            "--out",
        ])
        .arg(dir.path().join("bad2"))
        .output()
        .unwrap();
    // Every machine type has an accuracy model now (the P3RP head's link dimensions and
    // drives, central-difference sensitivities).
    ok(&o);
}

#[test]
fn every_example_machine_gets_a_budget() {
    let dir = tempfile::tempdir().unwrap();
    for f in [
        "examples/machines/tripod-seed000.toml",
        "examples/machines/tripod-centre-leg.toml",
        "examples/machines/hexapod-seed001.toml",
        "examples/machines/hexapod-linuxcnc.toml",
        "examples/machines/p3rp-seed004.toml",
        "examples/machines/p3rp-hybrid-seed004.toml",
        "examples/machines/mc300.toml",
        "examples/machines/kr30-dh.toml",
        "examples/robots/ur5-like.urdf",
    ] {
        let out = dir.path().join(f.replace('/', "_"));
        let o = pkm()
            .args([
                "errors",
                &path(f),
                "--json",
                "--monte-carlo",
                "500",
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        ok(&o);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let b = v["budget"].as_object().unwrap();
        assert!(!b.is_empty(), "{f}");
        assert!(v["budget_rss"].as_f64().unwrap() > 0.0, "{f}");
        let mc = &v["monte_carlo"];
        assert_eq!(
            mc["samples"].as_u64().unwrap() + mc["failed"].as_u64().unwrap(),
            500
        );
        assert!(
            mc["max"].as_f64().unwrap() <= v["budget_worst_case"].as_f64().unwrap() * 1.01,
            "{f}"
        );
        // Each budget row is |sensitivity| x tolerance of its parameter, and the RSS is
        // the root sum of squares of the rows.
        let sens = v["sensitivities"].as_array().unwrap();
        let mut sum2 = 0.0;
        for item in v["budget_items"].as_array().unwrap() {
            let name = item["parameter"].as_str().unwrap();
            let s = sens.iter().find(|s| s["parameter"] == name).unwrap();
            let t = v["tolerances"]
                .as_array()
                .unwrap()
                .iter()
                .find(|t| t["parameter"] == name)
                .unwrap();
            let per_unit: f64 = s["position_mm_per_unit"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap().powi(2))
                .sum::<f64>()
                .sqrt();
            let row = item["position_mm"].as_f64().unwrap();
            assert!(
                (row - per_unit * t["value"].as_f64().unwrap()).abs() < 1e-12,
                "{f} {name}"
            );
            sum2 += row * row;
        }
        assert!(
            (sum2.sqrt() - v["budget_rss"].as_f64().unwrap()).abs() < 1e-12,
            "{f}"
        );
    }
}

#[test]
fn report_has_an_accuracy_section_for_serial_machines() {
    let dir = tempfile::tempdir().unwrap();
    let o = pkm()
        .args(["report", &path("examples/machines/mc300.toml"), "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    ok(&o);
    let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
    assert!(html.contains("Accuracy from geometric tolerances"));
    assert!(html.contains("machine file's <code>[[tolerance]]</code> entries"));
    assert!(html.contains("delta_z(1 slide)"));
}

#[test]
fn fk_works_directly_on_a_urdf_file() {
    let o = pkm()
        .args([
            "fk",
            &path("examples/robots/ur5-like.urdf"),
            "--actuators",
            "0,0,0,0,0,0",
            "--json",
        ])
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    // The UR5's zero pose: x = a2 + a3, y = -(d4 + d6), z = d1 - d5 (mm).
    let p: Vec<f64> = v["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(
        (p[0] + 817.25).abs() < 1e-9 && (p[1] + 191.45).abs() < 1e-9 && (p[2] + 5.491).abs() < 1e-9,
        "{p:?}"
    );
    // A broken URDF names the file.
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.urdf");
    std::fs::write(&bad, "<robot name=\"x\"><link name=\"a\"/></robot>").unwrap();
    let o = pkm()
        .args(["fk"])
        .arg(&bad)
        .args(["--actuators", "0"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("bad.urdf"));
}

#[test]
fn error_map_over_two_axes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map");
    // Mapped over the joints X and B (the example file takes TCP coordinates).
    let joints = dir.path().join("mc300-joints.toml");
    std::fs::write(
        &joints,
        std::fs::read_to_string(path("examples/machines/mc300.toml"))
            .unwrap()
            .replace("pose = \"tcp\"", "pose = \"joints\""),
    )
    .unwrap();
    let joints = joints.display().to_string();
    let o = pkm()
        .args([
            "errors",
            &joints,
            "--actuators",
            "0,0,-100,30,45",
            "--map",
            "X,B",
            "--map-points",
            "11",
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["error_map"]["points"], 121);
    let csv = std::fs::read_to_string(out.join("error-map.csv")).unwrap();
    assert_eq!(csv.lines().count(), 122);
    assert!(csv.starts_with("X_mm,B_deg,rss_mm,worst_case_mm"));
    // Each row's RSS is the budget's RSS at that point: the centre row equals a
    // direct `pkm errors` there.
    let centre: Vec<f64> = csv
        .lines()
        .nth(1 + 5 * 11 + 5)
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    let o = pkm()
        .args(["errors", &joints, "--actuators"])
        .arg(format!("{},0,-100,{},45", centre[0], centre[1]))
        .args(["--json", "--out"])
        .arg(dir.path().join("one"))
        .output()
        .unwrap();
    let w: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((w["budget_rss"].as_f64().unwrap() - centre[2]).abs() < 1e-8);
    assert!(out.join("error-map.svg").exists());
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/mc300.toml"),
            "--map",
            "X,Q",
            "--out",
        ])
        .arg(dir.path().join("bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown axis `Q`"));
}

#[test]
fn tolerances_from_a_separate_file() {
    let dir = tempfile::tempdir().unwrap();
    let tol = dir.path().join("tight.toml");
    std::fs::write(&tol, "[[tolerance]]\ndeviation = \"dq(X)\"\nvalue = 0.001\n[[tolerance]]\ndeviation = \"dq(B)\"\nvalue = 0.001\ndistribution = \"normal\"\n").unwrap();
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/mc300.toml"),
            "--tolerances",
        ])
        .arg(&tol)
        .args(["--json", "--out"])
        .arg(dir.path().join("t"))
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let b = v["budget"].as_object().unwrap();
    assert_eq!(b.len(), 2);
    assert!((b["dq(X)"].as_f64().unwrap() - 0.001).abs() < 1e-12);
    std::fs::write(&tol, "[[tolerance]]\ndeviation = \"dq(X)\"\nvalue = -1\n").unwrap();
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/mc300.toml"),
            "--tolerances",
        ])
        .arg(&tol)
        .arg("--out")
        .arg(dir.path().join("t2"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("tight.toml:3:") && e.contains("tolerance[0].value"),
        "{e}"
    );
}

#[test]
fn six_axis_robot_takes_tool_poses_through_ik_fk_and_motion() {
    let kr30 = path("examples/machines/kr30-dh.toml");
    let run = |args: &[&str]| -> Value {
        let o = pkm().args(args).output().unwrap();
        ok(&o);
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let ik = run(&["ik", &kr30, "--pose", "1200,100,1400,180,0,0", "--json"]);
    let q: Vec<String> = ["A1", "A2", "A3", "A4", "A5", "A6"]
        .iter()
        .map(|n| ik["actuators"][n].as_f64().unwrap().to_string())
        .collect();
    // The wrist stays bent down (the branch of the home posture), A1 = A6 = atan(100/1200).
    let a1 = ik["actuators"]["A1"].as_f64().unwrap();
    assert!(
        (a1 - (100f64 / 1200.0).atan().to_degrees()).abs() < 1e-9,
        "{a1}"
    );
    assert!(ik["actuators"]["A5"].as_f64().unwrap() > 0.0);
    let fk = run(&["fk", &kr30, "--actuators", &q.join(","), "--json"]);
    let p: Vec<f64> = fk["position"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    for (a, b) in p.iter().zip([1200.0, 100.0, 1400.0]) {
        assert!((a - b).abs() < 1e-6, "{p:?}");
    }
    // A straight move: the joints follow, the summary names them.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m");
    let o = pkm()
        .args([
            "motion",
            &kr30,
            "--from",
            "1200,100,1400,180,0,0",
            "--to",
            "1300,-100,1300,180,0,0",
            "--duration",
            "1",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let s: Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    // A1 turns from atan(100/1200) to atan(-100/1300).
    let a1 = &s["actuators"]["A1"];
    let expect = (100f64 / 1200.0).atan().to_degrees() + (100f64 / 1300.0).atan().to_degrees();
    assert!(
        (a1["travel"].as_f64().unwrap() - expect).abs() < 1e-6,
        "{a1}"
    );
}

#[test]
fn strut_machines_get_a_budget_and_monte_carlo_of_their_geometry() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("hex");
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/hexapod-seed001.toml"),
            "--pose",
            "10,-20,560,5,0,0",
            "--joint-tolerance",
            "0.01",
            "--length-tolerance",
            "0.005",
            "--monte-carlo",
            "20000",
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let budget = v["budget"].as_object().unwrap();
    assert_eq!(budget.len(), 42);
    // A zero length at its tolerance moves the tool by about that much (struts are
    // steep, not vertical): between 0.3x and 2x the 5 um.
    let z1 = budget["zero(L1)"].as_f64().unwrap();
    assert!((0.0015..0.01).contains(&z1), "{z1}");
    let mc = &v["monte_carlo"];
    assert!(mc["p95"].as_f64().unwrap() < v["budget_worst_case"].as_f64().unwrap());
    assert!(mc["mean"].as_f64().unwrap() > 0.0);
    for f in ["errors.json", "budget.svg", "monte-carlo.svg"] {
        assert!(out.join(f).exists(), "{f}");
    }
    // --actuators: the pose by forward kinematics; lengths no pose has fail with
    // exit code 3; --pose and --actuators together are refused.
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/tripod-seed000.toml"),
            "--actuators",
            "1,2,3",
            "--out",
        ])
        .arg(dir.path().join("t"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3));
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/tripod-seed000.toml"),
            "--actuators",
            "208.1673,208.1673,208.1673",
            "--pose",
            "0,0,-290",
            "--out",
        ])
        .arg(dir.path().join("t"))
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("give one of them"));
}

#[test]
fn all_inverse_solutions_of_a_robot_with_their_limits() {
    let o = pkm()
        .args([
            "ik",
            &path("examples/machines/kr30-dh.toml"),
            "--pose",
            "1200,100,1400,180,0,0",
            "--all-solutions",
            "--json",
        ])
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let s = v["solutions"].as_array().unwrap();
    // Elbow up/down x wrist flipped or not (reaching backwards is beyond the arm here);
    // the elbow-down postures bend A5 beyond its +-119 deg.
    assert_eq!(s.len(), 4, "{v}");
    assert_eq!(s.iter().filter(|x| x["within_limits"] == true).count(), 2);
    // Hand values: A1 points at the target, atan(100 / 1200); the two postures within
    // limits are each other's wrist flip (A4 + 180, -A5, A6 + 180).
    let q = |k: usize, n: &str| s[k]["actuators"][n].as_f64().unwrap();
    let a1 = (100f64 / 1200.0).atan().to_degrees();
    assert!(s
        .iter()
        .all(|x| (x["actuators"]["A1"].as_f64().unwrap() - a1).abs() < 1e-9));
    let ok: Vec<usize> = (0..4).filter(|&k| s[k]["within_limits"] == true).collect();
    let (i, j) = (ok[0], ok[1]);
    assert!((q(i, "A5") + q(j, "A5")).abs() < 1e-9);
    assert!(((q(i, "A4") - q(j, "A4")).abs() - 180.0).abs() < 1e-9);
    assert!(((q(i, "A6") - q(j, "A6")).abs() - 180.0).abs() < 1e-9);
    // Not a robot: refused.
    let o = pkm()
        .args([
            "ik",
            &path("examples/machines/hexapod-seed001.toml"),
            "--pose",
            "0,0,550",
            "--all-solutions",
        ])
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stderr).contains("for six-axis robots"));
}

#[test]
fn strut_machine_error_map_over_two_pose_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map");
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/hexapod-seed001.toml"),
            "--map",
            "X,Y",
            "--map-points",
            "21",
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let map = &v["error_map"];
    assert_eq!(map["points"], 21 * 21);
    // The default span reaches beyond the workspace: those cells are blank.
    let blank = map["unreachable"].as_u64().unwrap();
    assert!(blank > 0 && blank < 21 * 21, "{map}");
    // Home (the centre of the map) is where the tolerances matter least here.
    assert!(map["max_rss"].as_f64().unwrap() > v["budget_rss"].as_f64().unwrap());
    let csv = std::fs::read_to_string(out.join("error-map.csv")).unwrap();
    assert!(csv.starts_with("X_mm,Y_mm,rss_mm,worst_case_mm\n"));
    assert_eq!(csv.lines().count(), 1 + 21 * 21);
    assert!(out.join("error-map.svg").exists());
}

#[test]
fn per_kind_tolerances_are_checked_and_the_distribution_alone_selects_them() {
    let dir = tempfile::tempdir().unwrap();
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/p3rp-seed004.toml"),
            "--length-tolerance",
            "-1",
            "--out",
        ])
        .arg(dir.path().join("a"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("expected a value from 0 to 100 mm, found -1"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // `--distribution normal` alone: the default per-kind values, drawn normally.
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/mc300.toml"),
            "--distribution",
            "normal",
            "--json",
            "--out",
        ])
        .arg(dir.path().join("b"))
        .output()
        .unwrap();
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["tolerance_source"], "by-kind");
    assert!(v["tolerances"]
        .as_array()
        .unwrap()
        .iter()
        .all(|t| t["distribution"] == "normal"));
}

#[test]
fn clearance_bounds_in_errors_json() {
    let dir = tempfile::tempdir().unwrap();
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/hexapod-seed001.toml"),
            "--pose",
            "0,0,550,5,0,0",
            "--clearance",
            "0.02",
            "--direction",
            "0,0,1",
            "--clearance-samples",
            "2000",
            "--tolerance",
            "0.01",
            "--json",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let c = &v["clearance"];
    assert_eq!(c["direction"], serde_json::json!([0.0, 0.0, 1.0]));
    let (upper, lower) = (c["upper"].as_f64().unwrap(), c["lower"].as_f64().unwrap());
    assert!(upper > 0.0 && lower < 0.0, "{c}");
    assert_eq!(c["method"], "first-order");
    let states = c["worst_joint_states"]["upper"].as_array().unwrap();
    assert_eq!(states.len(), 12);
    for s in states {
        assert!(s["joint"].is_string());
        let d: Vec<f64> = s["displacement"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(d.len(), 3);
        assert!((d.iter().map(|x| x * x).sum::<f64>().sqrt() - 0.01).abs() < 1e-12);
    }
    let mc = &c["monte_carlo"];
    assert_eq!(mc["samples"], 2000);
    assert!(mc["max"].as_f64().unwrap() <= upper + 1e-12);
    let largest = c["largest_clearance_mm"].as_f64().unwrap();
    assert!(largest > 0.0 && largest < 0.02, "{largest}");
    // The file on disk is the same document.
    let on_disk: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("errors.json")).unwrap()).unwrap();
    assert_eq!(on_disk["clearance"], v["clearance"]);
    // A serial machine has no modelled passive joints: a named refusal, exit != 0.
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/mc300.toml"),
            "--clearance",
            "0.02",
            "--out",
        ])
        .arg(dir.path().join("mc"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("joint clearances"), "{err}");
}

#[test]
fn clearance_over_a_hemisphere_writes_surface_csv_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/hexapod-seed001.toml"),
            "--clearance",
            "0.02",
            "--surface",
            "hemisphere:75",
            "--surface-points",
            "31",
            "--tolerance",
            "0.01",
            "--json",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .unwrap();
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let csv = std::fs::read_to_string(dir.path().join("surface.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("z_mm,lower_mm,upper_mm"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 31);
    let reachable: Vec<&Vec<&str>> = rows.iter().filter(|r| !r[2].is_empty()).collect();
    assert!(!reachable.is_empty() && reachable.len() < 31);
    for r in &reachable {
        let (l, u): (f64, f64) = (r[1].parse().unwrap(), r[2].parse().unwrap());
        assert!(l < 0.0 && u > 0.0);
    }
    let svg = std::fs::read_to_string(dir.path().join("surface.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("upper") && svg.contains("lower"));
    let largest = v["clearance"]["largest_clearance_mm"].as_f64().unwrap();
    assert_eq!(
        largest,
        v["clearance"]["surface"]["largest_clearance_mm"]
            .as_f64()
            .unwrap()
    );
    // Fig. 5: the bounds against the clearance.
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/hexapod-seed001.toml"),
            "--clearance-series",
            "0.02,0.05,0.1",
            "--out",
        ])
        .arg(dir.path().join("series"))
        .output()
        .unwrap();
    ok(&o);
    let csv = std::fs::read_to_string(dir.path().join("series/clearance-series.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "clearance_mm,lower_mm,upper_mm");
    assert_eq!(lines.len(), 4);
    assert!(lines[3].starts_with("0.100000,-"));
    assert!(dir.path().join("series/clearance-series.svg").exists());
    // Along a G-code path.
    let ngc = dir.path().join("p.ngc");
    std::fs::write(&ngc, "G21 G90\nG0 X0 Y0 Z550\nG1 X20 Y10 Z540 F1200\n").unwrap();
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/hexapod-seed001.toml"),
            "--clearance",
            "0.02",
            "--path",
        ])
        .arg(&ngc)
        .args(["--path-rate", "20", "--out"])
        .arg(dir.path().join("path"))
        .output()
        .unwrap();
    ok(&o);
    let csv = std::fs::read_to_string(dir.path().join("path/clearance-path.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("t_s,line,X_mm,Y_mm,Z_mm,A_deg,B_deg,C_deg,lower_mm,upper_mm")
    );
    let rows: Vec<&str> = lines.collect();
    assert!(rows.len() > 10);
    for r in rows {
        let v: Vec<&str> = r.split(',').collect();
        assert_eq!(v.len(), 10);
        assert!(v[8].parse::<f64>().unwrap() < 0.0 && v[9].parse::<f64>().unwrap() > 0.0);
    }
    // Malformed surface specs are refused with what is expected.
    let o = pkm()
        .args([
            "errors",
            &path("examples/machines/hexapod-seed001.toml"),
            "--clearance",
            "0.02",
            "--surface",
            "sphere:75",
            "--out",
        ])
        .arg(dir.path().join("bad"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("hemisphere:R"));
}

#[test]
fn report_has_a_clearance_section_when_the_file_gives_clearances() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(path("examples/machines/hexapod-seed001.toml")).unwrap();
    let file = dir.path().join("hex-clearances.toml");
    std::fs::write(
        &file,
        format!(
            "{text}\n[[clearance]]\njoints = [\"base\"]\ntype = \"universal\"\ndiametral = 0.02\n\
             bearing_length = 40.0\naxis = [0.0, 0.0, 1.0]\nlever = 20.0\n\
             [[clearance]]\njoints = [\"platform\"]\ndiametral = 0.015\n"
        ),
    )
    .unwrap();
    let out = dir.path().join("rep");
    ok(&pkm()
        .arg("report")
        .arg(&file)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap());
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("id=\"clearance\""), "no clearance section");
    assert!(html.contains("Joint clearances"));
    assert!(html.contains("The joint states that give the upper bound"));
    assert!(html.contains("universal") && html.contains("spherical"));
    // Without clearances in the file there is no such section.
    let plain = dir.path().join("plain");
    ok(&pkm()
        .args([
            "report",
            &path("examples/machines/hexapod-seed001.toml"),
            "--out",
        ])
        .arg(&plain)
        .output()
        .unwrap());
    let html = std::fs::read_to_string(plain.join("index.html")).unwrap();
    assert!(!html.contains("id=\"clearance\""));
}

/// Orientation errors in deg, like every other angle pkm prints:
/// the JSON and text equal the library's radians converted.
#[test]
fn orientation_errors_are_in_degrees() {
    let dir = tempfile::tempdir().unwrap();
    let devs = dir.path().join("devs.toml");
    std::fs::write(&devs, "\"A1.x\" = 0.05\n\"B4.y\" = -0.03\n").unwrap();
    let file = path("examples/machines/hexapod-seed001.toml");
    let o = pkm()
        .args(["errors", &file, "--deviations"])
        .arg(&devs)
        .args(["--json", "--out"])
        .arg(dir.path().join("e"))
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let machine = pkm::Machine::from_path(&file).unwrap();
    let params = machine.parameters();
    let d = pkm::machine::read_deviations(
        &params,
        &std::fs::read_to_string(&devs).unwrap(),
        "devs.toml",
    )
    .unwrap();
    let r = pkm::analysis::accuracy(
        &machine,
        &pkm::analysis::AccuracyOptions {
            deviations: d,
            ..Default::default()
        },
    )
    .unwrap();
    let w = r.pose_error.orientation;
    assert!(w.norm() > 1e-6);
    for k in 0..3 {
        let got = v["orientation_error_deg"][k].as_f64().unwrap();
        assert!((got - w[k].to_degrees()).abs() < 1e-15, "{got} {}", w[k]);
    }
    let item = &v["budget_items"][0];
    let b = &r.budget.items[0];
    assert!((item["orientation_deg"].as_f64().unwrap() - b.orientation.to_degrees()).abs() < 1e-15);
    let o = pkm()
        .args(["errors", &file, "--deviations"])
        .arg(&devs)
        .args(["--out"])
        .arg(dir.path().join("t"))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text.lines().find(|l| l.starts_with("orientation")).unwrap();
    assert!(line.ends_with(" deg"), "{line}");
}
