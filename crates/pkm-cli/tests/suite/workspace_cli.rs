//! `pkm workspace` and the hexapod through the CLI.

use serde_json::Value;

use crate::common::{ok, path, pkm};

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
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    for k in ["volume_mm3", "measure", "reachable_fraction"] {
        assert!(v[k].as_f64().unwrap() > 0.0, "{k}");
    }
    assert_eq!(v["measure_unit"], "mm^3");
    assert_eq!(v["volume_mm3"], v["measure"]);
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
    assert!(csv.starts_with("X_mm,Y_mm,Z_mm,reachable,status,condition,binding"));
    // Every point in one outcome; every violated limit counted at least as often as
    // it binds first; the default grid holds the whole reach.
    let outcomes: u64 = v["outcomes"]
        .as_object()
        .unwrap()
        .values()
        .map(|x| x.as_u64().unwrap())
        .sum();
    assert_eq!(outcomes, v["points"].as_u64().unwrap());
    for (k, n) in v["binding"].as_object().unwrap() {
        if let Some(all) = v["violated"][k].as_u64() {
            assert!(all >= n.as_u64().unwrap(), "{k}");
        }
    }
    assert_eq!(v["cut"].as_array().unwrap().len(), 0, "{}", v["cut"]);
    assert!(v["grid_bounds"].as_str().unwrap().contains("reach"));
    // The PLY: binary doubles x, y, z, condition of the reachable points, the same
    // values as the CSV's reachable rows (to its six decimals).
    let ply = std::fs::read(out.join("points.ply")).unwrap();
    let end = b"end_header\n";
    let at = ply.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = std::str::from_utf8(&ply[..at]).unwrap();
    assert!(
        header.starts_with("ply\nformat binary_little_endian 1.0\n"),
        "{header}"
    );
    assert!(header.contains(&format!("element vertex {}\n", v["reachable"])));
    let body: Vec<f64> = ply[at..]
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    assert_eq!(body.len() as u64, 4 * v["reachable"].as_u64().unwrap());
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|r| r[3] == "true")
        .collect();
    assert_eq!(rows.len() * 4, body.len());
    for (r, p) in rows.iter().zip(body.chunks_exact(4)) {
        for (cell, v) in [r[0], r[1], r[2], r[5]].iter().zip(p) {
            assert_eq!(*cell, format!("{v:.6}"));
        }
    }
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
    ok(&o);
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

#[test]
fn atlas_and_forward_maps_of_the_p3rp_head() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p3");
    let o = pkm()
        .args([
            "workspace",
            &path("examples/machines/p3rp-seed004.toml"),
            "--bounds",
            "200,520,0,90",
            "--step",
            "5",
            "--atlas-velocity",
            "150,57.29577951308232",
            "--atlas-acceleration",
            "9806.65,0",
            "--forward",
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let s: Value = serde_json::from_slice(&o.stdout).unwrap();
    let v = &s["atlas"]["actuators"]["V"];
    // V' = z' + g'(theta) theta': 150 mm/s plus the largest g' (about 110 mm/rad at
    // theta near 0.9 rad) at 1 rad/s — the paper's 0.26 m/s peak.
    let vmax = v["max_velocity_needed"].as_f64().unwrap();
    assert!((vmax / 260.0 - 1.0).abs() < 0.01, "{vmax}");
    // No theta acceleration: only 1 g plus the velocity term g'' theta'^2.
    let amax = v["max_acceleration_needed"].as_f64().unwrap();
    assert!(amax > 9806.65 && amax < 9806.65 + 100.0, "{amax}");
    assert_eq!(s["atlas"]["actuators"]["U"]["max_velocity_needed"], 150.0);
    let f = &s["forward"];
    assert_eq!(f["points"], 41 * 41);
    let th = f["pose_ranges"]["theta"]["range"].as_array().unwrap();
    assert!(th[0].as_f64().unwrap() >= 0.0 && th[1].as_f64().unwrap() <= 90.0);
    for name in [
        "atlas.csv",
        "forward.csv",
        "atlas-v-velocity-ztheta.svg",
        "atlas-u-position-ztheta.svg",
        "forward-theta-uv.svg",
        "forward-z-uv.svg",
    ] {
        assert!(out.join(name).exists(), "{name}");
    }
    let csv = std::fs::read_to_string(out.join("atlas.csv")).unwrap();
    assert!(csv
        .starts_with("z_mm,theta_deg,reachable,U_mm,U_velocity_mm/s,U_acceleration_mm/s^2,V_mm,"));
    // Wrong counts and machines with too many actuators are named errors.
    let o = pkm()
        .args([
            "workspace",
            &path("examples/machines/p3rp-seed004.toml"),
            "--atlas-velocity",
            "1,2,3",
            "--out",
        ])
        .arg(dir.path().join("bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr)
        .contains("expected 2 values (one per coordinate: z,theta)"));
    let o = pkm()
        .args([
            "workspace",
            &path("examples/machines/hexapod-linuxcnc.toml"),
            "--step",
            "100",
            "--forward",
            "--out",
        ])
        .arg(dir.path().join("hex"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("6 actuators"));
}

#[test]
fn hexapod_assembly_modes_and_transmission() {
    let o = pkm()
        .args([
            "fk",
            &path("examples/machines/hexapod-linuxcnc.toml"),
            "--actuators",
            "755.56,755.56,755.56,755.56,755.56,755.56",
            "--assembly-modes",
            "200",
            "--json",
        ])
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let modes = v["assembly_modes"].as_array().unwrap();
    assert!(modes.len() >= 2, "{}", modes.len());
    assert_eq!(modes[0]["reachable"], true);
    // The mirror image through the base plane is among them, beyond the limits.
    assert!(modes
        .iter()
        .any(|m| m["position"][2].as_f64().unwrap() < -500.0 && m["reachable"] == false));
    let o = pkm()
        .args([
            "ik",
            &path("examples/machines/hexapod-linuxcnc.toml"),
            "--pose",
            "10,0,520,0,5,0",
            "--json",
        ])
        .output()
        .unwrap();
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let t = &v["transmission"];
    assert!(t["velocity"].as_f64().unwrap() > 0.4);
    assert!(t["distance_to_singularity"].as_f64().unwrap() > 0.1);
    assert!(t["condition"].as_f64().unwrap() >= 1.0);
}

#[test]
fn hexapod_csv_round_trip_through_the_tracking_fk() {
    // IK of a 1 kHz stretch of a path, then FK of the lengths as a batch (rows are a
    // stream: the hexapod batch uses the tracking solver).
    let dir = tempfile::tempdir().unwrap();
    let m = path("examples/machines/hexapod-linuxcnc.toml");
    let mut poses = String::from("X,Y,Z,A,B,C\n");
    for k in 0..200 {
        let t = k as f64 * 1e-3;
        poses.push_str(&format!(
            "{},{},{},{},{},0\n",
            20.0 * (3.0 * t).sin(),
            0.1 * k as f64,
            520.0 + 5.0 * t,
            2.0 * t,
            -t
        ));
    }
    let pin = dir.path().join("poses.csv");
    std::fs::write(&pin, &poses).unwrap();
    let lout = dir.path().join("lengths.csv");
    pkm()
        .args(["ik", &m, "--input"])
        .arg(&pin)
        .arg("--output")
        .arg(&lout)
        .assert()
        .success();
    let text = std::fs::read_to_string(&lout).unwrap();
    let mut lengths = String::new();
    for (i, line) in text.lines().enumerate() {
        let c: Vec<&str> = line.split(',').collect();
        lengths.push_str(&c[6..12].join(","));
        lengths.push('\n');
        if i == 0 {
            assert!(c[6].ends_with("_mm"), "{line}");
        }
    }
    let lin = dir.path().join("l.csv");
    // Header: the actuator names without units.
    let lengths = lengths.replacen("_mm", "", 6);
    std::fs::write(&lin, lengths).unwrap();
    let fout = dir.path().join("fk.csv");
    let o = pkm()
        .args(["fk", &m, "--input"])
        .arg(&lin)
        .arg("--output")
        .arg(&fout)
        .output()
        .unwrap();
    ok(&o);
    let back = std::fs::read_to_string(&fout).unwrap();
    for (a, b) in poses.lines().skip(1).zip(back.lines().skip(1)) {
        let x: Vec<f64> = a.split(',').map(|v| v.parse().unwrap()).collect();
        let y: Vec<f64> = b
            .split(',')
            .skip(6)
            .take(6)
            .map(|v| v.parse().unwrap())
            .collect();
        for k in 0..6 {
            assert!((x[k] - y[k]).abs() < 1e-6, "{a} vs {b}");
        }
    }
}

/// `pkm workspace --format parquet`: points.parquet holds points.csv's rows (axes,
/// reachable, status, condition, binding limit; nulls where the CSV is empty) on a grid
/// reaching past the hexapod's limits, so that unreachable points name their limit.
#[test]
fn parquet_points_hold_the_csv_rows() {
    use crate::common::{assert_parquet_is_csv, parquet_rows, Cell};
    let dir = tempfile::tempdir().unwrap();
    let run = |format: &str| {
        let out = dir.path().join(format);
        let o = pkm()
            .args([
                "workspace",
                &path("examples/machines/hexapod-linuxcnc.toml"),
                "--step",
                "40",
                "--format",
                format,
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        ok(&o);
        out
    };
    let (csv, pq) = (run("csv"), run("parquet"));
    assert!(!pq.join("points.csv").exists());
    let n = assert_parquet_is_csv(&pq.join("points.parquet"), &csv.join("points.csv"), 5e-7);
    let (names, rows) = parquet_rows(&pq.join("points.parquet"));
    let col = |c: &str| names.iter().position(|n| n == c).unwrap();
    let unreachable: Vec<&Vec<Cell>> = rows
        .iter()
        .filter(|r| r[col("reachable")] == Cell::Text("false".into()))
        .collect();
    assert!(!unreachable.is_empty() && unreachable.len() < n);
    for r in unreachable {
        assert_eq!(r[col("condition")], Cell::Null);
        assert!(matches!(&r[col("binding")], Cell::Text(t) if !t.is_empty()));
    }
    assert_eq!(
        std::fs::read(csv.join("points.ply")).unwrap(),
        std::fs::read(pq.join("points.ply")).unwrap()
    );
}
