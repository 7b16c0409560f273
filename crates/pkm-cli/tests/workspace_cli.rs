//! `pkm workspace` and the hexapod through the CLI.

use std::path::PathBuf;

use assert_cmd::Command;
use serde_json::Value;

fn path(rel: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
        .display()
        .to_string()
}

fn pkm() -> Command {
    Command::cargo_bin("pkm").unwrap()
}

#[test]
fn workspace_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ws");
    let o = pkm()
        .args([
            "workspace",
            &path("examples/machines/hexapod-linuxcnc.toml"),
            "--step",
            "40",
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    for k in ["volume_mm3", "reachable_fraction"] {
        assert!(v[k].as_f64().unwrap() > 0.0, "{k}");
    }
    assert_eq!(v["bounding_box"].as_array().unwrap().len(), 3);
    assert!(v["condition"]["median"].as_f64().unwrap() >= 1.0);
    let binding: u64 = v["binding"]
        .as_object()
        .unwrap()
        .values()
        .map(|x| x.as_u64().unwrap())
        .sum();
    assert_eq!(
        binding + v["reachable"].as_u64().unwrap(),
        v["points"].as_u64().unwrap()
    );
    let csv = std::fs::read_to_string(out.join("points.csv")).unwrap();
    assert_eq!(
        csv.lines().count() as u64,
        v["points"].as_u64().unwrap() + 1
    );
    assert!(csv.starts_with("X_mm,Y_mm,Z_mm,reachable,condition,binding"));
    let ply = std::fs::read_to_string(out.join("points.ply")).unwrap();
    assert!(ply.contains(&format!("element vertex {}", v["reachable"])));
    for f in ["slice-xy.svg", "slice-xz.svg"] {
        assert!(std::fs::read_to_string(out.join(f))
            .unwrap()
            .contains("<svg"));
    }
    // Tilted constant orientation and the total orientation workspace shrink it.
    let tilted = dir.path().join("t");
    let o = pkm()
        .args([
            "workspace",
            &path("examples/machines/hexapod-linuxcnc.toml"),
            "--step",
            "40",
            "--tilt",
            "15",
            "--json",
            "--out",
        ])
        .arg(&tilted)
        .output()
        .unwrap();
    let t: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(t["reachable"].as_u64().unwrap() < v["reachable"].as_u64().unwrap());
    // Orientation workspace at a point.
    let at = dir.path().join("at");
    pkm()
        .args([
            "workspace",
            &path("examples/machines/hexapod-linuxcnc.toml"),
            "--at",
            "0,0,550",
            "--out",
        ])
        .arg(&at)
        .assert()
        .success();
    let tilt: Value =
        serde_json::from_str(&std::fs::read_to_string(at.join("tilt.json")).unwrap()).unwrap();
    assert!(tilt["reachable_tilt_all_directions_deg"].as_f64().unwrap() > 1.0);
}

#[test]
fn hexapod_ik_fk_round_trip_through_the_cli() {
    let m = path("examples/machines/hexapod-linuxcnc.toml");
    let o = pkm()
        .args(["ik", &m, "--pose=10,-20,560,3,-2,5", "--json"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    let ik: Value = serde_json::from_slice(&o.stdout).unwrap();
    let q: Vec<String> = (0..6)
        .map(|i| format!("{}", ik["actuators"][i.to_string()].as_f64().unwrap()))
        .collect();
    let o = pkm()
        .args(["fk", &m, "--actuators", &q.join(","), "--json"])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let fk: Value = serde_json::from_slice(&o.stdout).unwrap();
    let p = fk["position"].as_array().unwrap();
    for (k, e) in [10.0, -20.0, 560.0].iter().enumerate() {
        assert!((p[k].as_f64().unwrap() - e).abs() < 1e-9);
    }
    for (k, e) in [3.0, -2.0, 5.0].iter().enumerate() {
        assert!((fk["angles"][k].as_f64().unwrap() - e).abs() < 1e-9);
    }
    // A singular configuration is an error, not a pose.
    let flat: Vec<String> = ["0", "0", "0", "0", "0", "0"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let o = pkm()
        .args(["ik", &m, "--pose", &flat.join(","), "--json"])
        .output()
        .unwrap();
    let ik: Value = serde_json::from_slice(&o.stdout).unwrap();
    let q: Vec<String> = (0..6)
        .map(|i| format!("{}", ik["actuators"][i.to_string()].as_f64().unwrap()))
        .collect();
    let o = pkm()
        .args(["fk", &m, "--actuators", &q.join(","), "--from=0,0,0,0,0,0"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("singular"));
}
