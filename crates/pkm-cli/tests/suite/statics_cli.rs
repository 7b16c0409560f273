//! `pkm statics`: the JSON contract, units and errors.

use super::common::{ok, path, pkm};
use serde_json::Value;

fn json(args: &[&str]) -> Value {
    let o = pkm()
        .arg("statics")
        .args(args)
        .arg("--json")
        .output()
        .unwrap();
    ok(&o);
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn forces_stiffness_and_deflection_by_name_and_unit() {
    let v = json(&[
        &path("examples/machines/hexapod-linuxcnc.toml"),
        "--pose=0,0,508,0,0,0",
        "--wrench=0,0,-1200,0,0,0",
    ]);
    // The six struts of a level symmetric hexapod share a vertical load: each pushes,
    // together with their vertical components 1200 N.
    let f = v["actuator_forces"].as_object().unwrap();
    assert_eq!(f.len(), 6);
    let sum: f64 = f.values().map(|x| x.as_f64().unwrap()).sum();
    assert!(f.values().all(|x| x.as_f64().unwrap() > 0.0));
    // Struts 755.56 mm long, 508 mm high: each carries 1200 / 6 / (508 / 755.56) N.
    let each = 1200.0 / 6.0 / (508.0 / 755.56);
    assert!((sum / 6.0 - each).abs() < 0.01 * each, "{sum}");
    let k = v["stiffness"].as_array().unwrap();
    assert_eq!(k.len(), 6);
    assert!(k.iter().all(|r| r.as_array().unwrap().len() == 6));
    // A vertical force deflects the tool down by about F / K_zz here (Z hardly couples
    // with the other directions at this level pose).
    let kzz = k[2][2].as_f64().unwrap();
    let dz = v["deflection"][2].as_f64().unwrap();
    assert!(
        (dz + 1200.0 / kzz).abs() < 1e-4 * dz.abs(),
        "{dz} against {kzz}"
    );
    assert_eq!(v["deflection"].as_array().unwrap().len(), 6);
    assert_eq!(v["deflection_exact"].as_array().unwrap().len(), 6);
    assert!(v["units"].as_str().unwrap().contains("N/mm"));
}

#[test]
fn moments_are_given_in_newton_metres() {
    let m = path("examples/machines/hexapod-linuxcnc.toml");
    let a = json(&[&m, "--wrench=0,0,0,0,0,10"]);
    let b = json(&[&m, "--wrench=0,0,0,0,0,10000"]);
    let f = |v: &Value| v["actuator_forces"]["0"].as_f64().unwrap();
    assert!((f(&b) / f(&a) - 1000.0).abs() < 1e-9);
    assert_eq!(a["wrench"]["moment"][2].as_f64(), Some(10.0));
}

#[test]
fn a_machine_without_drive_stiffness_gets_its_forces_and_the_missing_data_named() {
    let o = pkm()
        .args([
            "statics",
            &path("examples/machines/tripod-seed000.toml"),
            "--wrench=0,0,100",
            "--json",
        ])
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["stiffness"].is_null());
    let e = v["stiffness_error"].as_str().unwrap();
    assert!(e.contains("no `stiffness` for drives e, f, g"), "{e}");
    assert_eq!(v["actuator_forces"].as_object().unwrap().len(), 3);
    assert!(String::from_utf8_lossy(&o.stderr).contains("warning: no stiffness"));
}

#[test]
fn bad_wrenches_and_other_coordinates_are_refused() {
    let m = path("examples/machines/hexapod-linuxcnc.toml");
    let o = pkm()
        .args(["statics", &m, "--wrench=1,2"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("expected Fx,Fy,Fz"));
    let o = pkm()
        .args(["statics", &m, "--wrench=1,2,nan"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let head = path("examples/machines/p3rp-seed004.toml");
    let o = pkm()
        .args(["statics", &head, "--wrench=0,0,-100"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not available"));
}

#[test]
fn a_workspace_stiffness_map_names_its_weakest_point_as_statics_finds_it() {
    let dir = tempfile::tempdir().unwrap();
    let m = path("examples/machines/hexapod-linuxcnc.toml");
    let o = pkm()
        .args(["workspace", &m, "--step", "60", "--stiffness", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stdout).contains("stiffness  weakest"));
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    let st = &s["stiffness"];
    assert_eq!(st["points"], s["reachable"]);
    let csv = std::fs::read_to_string(dir.path().join("stiffness.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len() as u64, st["points"].as_u64().unwrap());
    let min = rows.iter().map(|r| r[3]).fold(f64::INFINITY, f64::min);
    let weakest = &st["weakest"];
    let k = weakest["stiffness_n_per_um"].as_f64().unwrap();
    assert!((k - min).abs() < 1e-5, "{k} against the table's {min}");
    assert!(dir.path().join("stiffness-xy.svg").exists());
    // The same figure from `pkm statics` at that point (the map's orientation: home's).
    let at = &weakest["at"];
    let pose = format!(
        "--pose={},{},{},0,0,0",
        at["X"].as_f64().unwrap(),
        at["Y"].as_f64().unwrap(),
        at["Z"].as_f64().unwrap()
    );
    let v = json(&[&m, &pose]);
    let one = v["smallest_translational_stiffness_n_per_um"]
        .as_f64()
        .unwrap();
    assert!((one - k).abs() < 1e-9 * k, "{one} against {k}");
}

#[test]
fn the_report_has_a_stiffness_section_where_the_drives_have_stiffness() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    let o = pkm()
        .args(["report", &path("examples/machines/hexapod-linuxcnc.toml")])
        .args(["--sections", "stiffness", "--step", "60", "--json", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["sections"], serde_json::json!(["stiffness"]));
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("smallest stiffness, XY slice"));
    assert!(html.contains("Drive forces holding 1 kN on the tool at home"));
    // The same weakest figure as `pkm workspace --stiffness` on the same grid.
    let ws = dir.path().join("ws");
    let o = pkm()
        .args([
            "workspace",
            &path("examples/machines/hexapod-linuxcnc.toml"),
        ])
        .args(["--step", "60", "--stiffness", "--json", "--out"])
        .arg(&ws)
        .output()
        .unwrap();
    ok(&o);
    let s: Value = serde_json::from_slice(&o.stdout).unwrap();
    let k = s["stiffness"]["weakest"]["stiffness_n_per_um"]
        .as_f64()
        .unwrap();
    assert!(html.contains(&format!("weakest {k:.1} N/um")), "{k}");
    // A machine without drive stiffness has no such section.
    let o = pkm()
        .args(["report", &path("examples/machines/tripod-seed000.toml")])
        .args(["--sections", "stiffness", "--json", "--out"])
        .arg(dir.path().join("tripod"))
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&o.stdout).unwrap_or_default();
    assert!(!v["sections"]
        .as_array()
        .is_some_and(|a| a.contains(&serde_json::json!("stiffness"))));
}

#[test]
fn dynamics_prints_torques_by_joint_name_in_newton_metres() {
    let o = pkm()
        .args([
            "dynamics",
            &path("examples/robots/ur5-like.urdf"),
            "--q=0,-60,30,0,0,0",
            "--json",
        ])
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let t = v["torques"].as_object().unwrap();
    assert_eq!(t.len(), 6);
    // The vertical base joint carries no weight; the shoulder tens of N m.
    assert!(t["shoulder_pan"].as_f64().unwrap().abs() < 1e-9);
    let lift = t["shoulder_lift"].as_f64().unwrap();
    assert!(lift.abs() > 10.0 && lift.abs() < 100.0, "{lift}");
    // The same with gravity along +Z turns every sign.
    let o = pkm()
        .args([
            "dynamics",
            &path("examples/robots/ur5-like.urdf"),
            "--q=0,-60,30,0,0,0",
        ])
        .args(["--gravity=0,0,9.80665", "--json"])
        .output()
        .unwrap();
    ok(&o);
    let up: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((up["torques"]["shoulder_lift"].as_f64().unwrap() + lift).abs() < 1e-9 * lift.abs());
}

#[test]
fn dynamics_refuses_wrong_counts_and_machines_it_cannot_model() {
    let urdf = path("examples/robots/ur5-like.urdf");
    let o = pkm()
        .args(["dynamics", &urdf, "--q=0,0,0"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("expected 6 values"));
    let hex = path("examples/machines/hexapod-linuxcnc.toml");
    let o = pkm().args(["dynamics", &hex]).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("only serial machines"));
}
