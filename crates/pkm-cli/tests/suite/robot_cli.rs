//! A robot's path through `pkm ik --input ... --continuous`: each row solved from the
//! previous row's joints, so a wrist turned past half a turn from home keeps turning.

use super::common::{csv_rows, ok, path, pkm, Cell};

/// The KR 30 turning its tool 0 -> 300 deg about Z in 10 deg rows: A6 = -C. Without
/// `--continuous` every row takes the solution nearest home, so A6 comes back within
/// half a turn of it (+160 deg at C = 200); with it A6 reaches -300 deg, within its
/// +-350 deg range, and every row is reachable.
#[test]
fn continuous_rows_keep_a_robot_joint_turning() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("path.csv");
    let mut text = String::from("X,Y,Z,A,B,C\n");
    for k in 0..=30 {
        text.push_str(&format!("1170,0,1540,-180,0,{}\n", 10 * k));
    }
    std::fs::write(&input, text).unwrap();
    let machine = path("examples/machines/kr30-dh.toml");
    let a6 = |continuous: bool| -> Vec<f64> {
        let output = dir.path().join(format!("joints-{continuous}.csv"));
        let mut cmd = pkm();
        cmd.args(["ik", &machine, "--input"])
            .arg(&input)
            .arg("--output")
            .arg(&output);
        if continuous {
            cmd.arg("--continuous");
        }
        ok(&cmd.output().unwrap());
        let (names, rows) = csv_rows(&output);
        let col = names.iter().position(|n| n == "A6_deg").unwrap();
        let reach = names.iter().position(|n| n == "reachable").unwrap();
        rows.iter()
            .map(|r| {
                assert_eq!(r[reach], Cell::Text("true".into()));
                match r[col] {
                    Cell::Num(v) => v,
                    ref c => panic!("{c:?}"),
                }
            })
            .collect()
    };
    let cont = a6(true);
    let home = a6(false);
    for (k, (c, h)) in cont.iter().zip(&home).enumerate() {
        let expected = -10.0 * k as f64;
        assert!(
            (c - expected).abs() < 1e-6,
            "row {k}: {c} against {expected}"
        );
        // Nearest home: the same angle, within half a turn of 0 (at C = 180 either
        // end of it).
        let d = (h - expected).rem_euclid(360.0);
        assert!(
            d.min(360.0 - d) < 1e-6 && h.abs() <= 180.0 + 1e-9,
            "row {k}: {h}"
        );
    }
    assert!((home[20] - 160.0).abs() < 1e-6, "{}", home[20]);
}

/// `--continuous` needs rows to continue: it is refused without `--input`.
#[test]
fn continuous_needs_an_input() {
    let machine = path("examples/machines/kr30-dh.toml");
    let out = pkm()
        .args([
            "ik",
            &machine,
            "--pose",
            "1170,0,1540,-180,0,0",
            "--continuous",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--input"), "{err}");
}

/// `pkm motion` turning the KR 30's A6 past its -350 deg (C to 400 deg, A6 = -C):
/// exit 3 and one violation named with where it starts and its worst value, which
/// the joints' continuation brings (each sample solved nearest home never left the
/// range).
#[test]
fn a_joint_turned_beyond_its_range_is_reported_with_its_start_and_worst() {
    let dir = tempfile::tempdir().unwrap();
    let program = dir.path().join("turn.ngc");
    std::fs::write(&program, "G90 G21\nG1 C400 F3000\n").unwrap();
    let out = pkm()
        .args(["motion", &path("examples/machines/kr30-dh.toml"), "--gcode"])
        .arg(&program)
        .arg("--summary-only")
        .arg("--out")
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(
            "error: 1 limit violation along the path; first: joint A6 position beyond \
             -350.000 deg from t = 7.0010 s (G-code line 2), worst -400.000 deg"
        ),
        "{err}"
    );
}

/// `pkm check` says how a robot's inverse kinematics is solved: in closed form for a
/// spherical wrist (the KR 30) and for three parallel axes (the UR5-like URDF), by
/// Newton for other geometry (the UR5 with axis 6 moved 20 mm off axis 5); a hexapod's
/// in closed form. The same in `--json`.
#[test]
fn check_names_the_inverse_kinematics_method() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(path("tests/fixtures/ur5-dh.toml")).unwrap();
    let offset = text.replacen("a = 0.0\nalpha = -90.0", "a = 20.0\nalpha = -90.0", 1);
    assert_ne!(offset, text);
    let off = dir.path().join("ur5-offset.toml");
    std::fs::write(&off, offset).unwrap();
    for (file, method) in [
        (
            path("examples/machines/kr30-dh.toml"),
            "closed form (spherical wrist, axes 2 and 3 parallel)",
        ),
        (
            path("examples/robots/ur5-like.urdf"),
            "closed form (axes 2, 3, 4 parallel, axes 5 and 6 meeting)",
        ),
        (
            off.to_string_lossy().into_owned(),
            "numeric (Newton on SE(3) from the start, 32 spread restarts)",
        ),
        (
            path("examples/machines/hexapod-linuxcnc.toml"),
            "closed form",
        ),
    ] {
        let o = pkm().args(["check", &file]).output().unwrap();
        ok(&o);
        let stdout = String::from_utf8(o.stdout).unwrap();
        assert!(
            stdout.lines().any(|l| l == format!("inverse     {method}")),
            "{file}: {stdout}"
        );
        let o = pkm().args(["check", &file, "--json"]).output().unwrap();
        ok(&o);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["inverse_method"], method, "{file}");
    }
}

/// The KR 30 at its home pose: joints and coordinates that are zero up to rounding
/// (A2, A4, C, the arm's Y) print as `0.0000`, never `-0.0000`, in `pkm check`,
/// `pkm ik` (one solution and all of them) and `pkm fk`; signed values keep their sign.
#[test]
fn text_outputs_show_no_negative_zero() {
    let machine = path("examples/machines/kr30-dh.toml");
    let pose = "--pose=1170,0,1540,-180,0,0";
    for args in [
        vec!["check", &machine],
        vec!["ik", &machine, pose],
        vec![
            "ik",
            &machine,
            "--pose=1200,100,1400,180,0,0",
            "--all-solutions",
        ],
        vec!["fk", &machine, "--actuators=0,0,0,0,90,0"],
    ] {
        let out = pkm().args(&args).output().unwrap();
        ok(&out);
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            !text
                .split(|c: char| c.is_whitespace() || c == '=')
                .any(|w| w.strip_prefix('-').is_some_and(|r| {
                    !r.is_empty() && r.bytes().all(|b| b == b'0' || b == b'.')
                })),
            "{args:?}:\n{text}"
        );
        // Negative values keep their sign (A = -180 deg; A3 of the second posture).
        assert!(text.contains("=-1"), "{args:?}:\n{text}");
    }
}

/// `pkm ik` reads its conditioning as one measure: the condition number and its
/// inverse (0 = singular), the same on a robot and on a hexapod, where it printed a
/// robot's smallest singular value of dq/dx (0.0003 rad per tool mm on a KR 30 far
/// from any singularity) as a "singular distance" beside a condition of 7.5.
#[test]
fn ik_reads_its_conditioning_as_one_measure() {
    for (machine, pose) in [
        ("examples/machines/kr30-dh.toml", "1200,100,1400,10,80,5"),
        ("examples/machines/hexapod-linuxcnc.toml", "10,20,520,3,2,1"),
    ] {
        let run = |json: bool| {
            let mut c = pkm();
            c.args(["ik", &path(machine), &format!("--pose={pose}")]);
            if json {
                c.arg("--json");
            }
            let o = c.output().unwrap();
            ok(&o);
            String::from_utf8(o.stdout).unwrap()
        };
        let text = run(false);
        assert!(!text.contains("distance"), "{text}");
        let line = text.lines().find(|l| l.starts_with("condition  ")).unwrap();
        let words: Vec<&str> = line.split_whitespace().collect();
        let cond: f64 = words[1].parse().unwrap();
        let k = words.iter().position(|w| *w == "inverse").unwrap();
        let inv: f64 = words[k + 1].trim_end_matches(',').parse().unwrap();
        // Both printed rounded: 3 and 4 decimals.
        assert!(cond > 1.0 && (inv * cond - 1.0).abs() < 1e-3, "{line}");
        let v: serde_json::Value = serde_json::from_str(&run(true)).unwrap();
        let t = &v["transmission"];
        let (c, i) = (
            t["condition"].as_f64().unwrap(),
            t["inverse_condition"].as_f64().unwrap(),
        );
        assert!((c * i - 1.0).abs() < 1e-12, "{t}");
        assert!((c - cond).abs() < 1e-3, "{t} vs {line}");
    }
}
