//! `pkm motion` end to end.

use serde_json::Value;

use crate::common::{ok, path, pkm};

#[test]
fn seed000_arc_through_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("arc");
    let o = pkm()
        .args([
            "motion",
            &path("examples/machines/tripod-seed000.toml"),
            "--gcode",
            &path("examples/paths/seed000-arc.ngc"),
            "--from",
            "32,-32,-290",
            "--points",
            "101",
            "--json",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let file: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(v, file);
    assert_eq!(v["samples"], 101);
    let x = &v["serial"]["X"];
    assert!((x["travel"].as_f64().unwrap() - 64.0).abs() < 0.32);
    assert!((x["peak_velocity"].as_f64().unwrap() - 166.667).abs() < 0.01);
    assert!((x["peak_acceleration"].as_f64().unwrap() - 434.03).abs() < 0.01);
    for k in [
        "travel",
        "peak_velocity",
        "mean_abs_velocity",
        "peak_acceleration",
        "mean_abs_acceleration",
    ] {
        assert!(v["actuators"]["e"][k].is_number(), "{k}");
    }
    for k in [
        "travel",
        "velocity",
        "acceleration",
        "velocity_of_mean_peaks",
        "acceleration_of_mean_peaks",
    ] {
        assert!(v["ratios"][k].as_f64().unwrap() > 1.0, "{k}");
    }
    assert!(v["feed_override_max"].as_f64().unwrap() > 1.0);
    assert!(v["violations"].as_array().unwrap().is_empty());
    assert!(v["duration_s"].as_f64().unwrap() > 0.6);
    let csv = std::fs::read_to_string(out.join("actuators.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t_s,line,X_mm,Y_mm,Z_mm,A_deg,B_deg,C_deg,e_mm,e_mm_per_s,e_mm_per_s2,f_mm,f_mm_per_s,f_mm_per_s2,g_mm,g_mm_per_s,g_mm_per_s2"
    );
    assert_eq!(lines.count(), 101);
    for f in ["actuators.svg", "serial.svg"] {
        assert!(std::fs::read_to_string(out.join(f))
            .unwrap()
            .contains("<svg"));
    }
}

#[test]
fn coverage_program_runs_on_the_tripod() {
    let dir = tempfile::tempdir().unwrap();
    for profile in ["constant", "trapezoid", "scurve"] {
        let out = dir.path().join(profile);
        let o = pkm()
            .args([
                "motion",
                &path("examples/machines/tripod-seed000.toml"),
                "--gcode",
                &path("examples/paths/gcode-coverage.ngc"),
                "--profile",
                profile,
                "--rate",
                "500",
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            o.status.code() == Some(0) || o.status.code() == Some(3),
            "{profile}: {err}"
        );
        let v: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        assert!(v["samples"].as_u64().unwrap() > 100);
    }
}

#[test]
fn violations_name_time_line_and_value() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("fast.ngc");
    std::fs::write(&g, "G17 G90\nG1 X10 F600\nG1 X40 F60000\n").unwrap();
    let out = dir.path().join("o");
    let o = pkm()
        .args([
            "motion",
            &path("examples/machines/tripod-seed000.toml"),
            "--gcode",
        ])
        .arg(&g)
        .args(["--profile", "constant", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("G-code line 3") && err.contains("velocity") && err.contains("mm/s"),
        "{err}"
    );
    let v: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let first = &v["violations"][0];
    assert_eq!(first["line"], 3);
    assert!(first["worst"].as_f64().unwrap() > first["bound"].as_f64().unwrap());
    assert!(v["feed_override_max"].as_f64().unwrap() < 1.0);
}

#[test]
fn bad_programs_and_moves() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("bad.ngc");
    std::fs::write(&g, "G1 X10 F600\nG1 X20\nG66 X1\n").unwrap();
    let o = pkm()
        .args([
            "motion",
            &path("examples/machines/tripod-seed000.toml"),
            "--gcode",
        ])
        .arg(&g)
        .arg("--out")
        .arg(dir.path().join("o"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("G-code line 3") && err.contains("G66"),
        "{err}"
    );
    assert!(
        !dir.path().join("o/actuators.csv").exists(),
        "nothing half-written"
    );
    // Point to point with a timed trapezoid.
    let out = dir.path().join("p2p");
    pkm()
        .args([
            "motion",
            &path("examples/machines/tripod-centre-leg.toml"),
            "--from",
            "0,0,-290",
            "--to",
            "30,20,-310",
            "--duration",
            "1",
            "--profile",
            "trapezoid",
            "--accel-time",
            "0.1",
            "--rate",
            "1000",
            "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    let v: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!((v["duration_s"].as_f64().unwrap() - 1.0).abs() < 1e-9);
    assert_eq!(v["samples"], 1001);
}

/// `--feed 1e300` and `--duration 1e-200` once panicked in the plots (NaN ranges) and
/// `--duration 0` wrote one sample that never moved, exit 0: each is refused, exit 1,
/// naming the option and its value, before anything is written.
#[test]
fn absurd_feeds_and_durations_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (option, value, want) in [
        (
            "--feed",
            "1e300",
            "error: feed: expected a feed in (0, 6e7] mm/min",
        ),
        (
            "--duration",
            "1e-200",
            "error: --duration: expected a finite duration",
        ),
        ("--duration", "0", "at least 1e-6 s, got 0 s"),
        ("--duration", "5e-324", "got 4.9407e-324 s"),
    ] {
        let out = dir.path().join("o");
        let o = pkm()
            .args([
                "motion",
                &path("examples/machines/hexapod-linuxcnc.toml"),
                "--from",
                "0,0,508",
                "--to",
                "1,0,508",
                option,
                value,
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{option} {value}: {err}");
        assert!(err.contains(want), "{option} {value}: {err}");
        assert!(!out.join("summary.json").exists(), "{option} {value}");
    }
}

#[test]
fn rapid_rate_comes_from_the_machine_file() {
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("rapid.ngc");
    std::fs::write(&g, "G0 X10\n").unwrap();
    let run = |extra: &[&str]| -> f64 {
        let out = dir.path().join("o");
        pkm()
            .args([
                "motion",
                &path("examples/machines/tripod-seed000.toml"),
                "--gcode",
            ])
            .arg(&g)
            .args(extra)
            .arg("--out")
            .arg(&out)
            .assert()
            .success();
        let v: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        v["duration_s"].as_f64().unwrap()
    };
    // [motion] rapid = 6000 mm/min: 10 mm in 0.1 s; --rapid overrides it.
    assert!((run(&[]) - 0.1).abs() < 1e-12);
    assert!((run(&["--rapid", "1200"]) - 0.5).abs() < 1e-12);
}

#[test]
fn seed004_move_and_report() {
    // Seed 004's fig. 7 move of the head.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p3");
    let o = pkm()
        .args([
            "motion",
            &path("examples/machines/p3rp-seed004.toml"),
            "--from",
            "200,0",
            "--to",
            "335,51.566",
            "--duration",
            "1",
            "--profile",
            "trapezoid",
            "--accel-time",
            "0.1",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let v = &s["actuators"]["V"];
    let pv = v["peak_velocity"].as_f64().unwrap();
    let pa = v["peak_acceleration"].as_f64().unwrap();
    assert!((pv / 260.0 - 1.0).abs() < 0.03, "{pv}");
    assert!((pa / 2600.0 - 1.0).abs() < 0.03, "{pa}");
    assert_eq!(s["duration_s"], 1.0);
    assert_eq!(s["profile"]["duration_s"], 1.0);
    assert_eq!(s["profile"]["accel_time_s"], 0.1);
    assert!(s["profile"].get("jerk").is_none());
    for f in ["actuators.csv", "actuators.svg", "serial.svg"] {
        assert!(out.join(f).exists(), "{f}");
    }
    // The hybrid machine runs G-code with an A word (table and head together).
    let prog = dir.path().join("a.ngc");
    std::fs::write(&prog, "G90 G1 X20 Y10 Z180 A30 F3000\nG1 X-20 A0\n").unwrap();
    let o = pkm()
        .args([
            "motion",
            &path("examples/machines/p3rp-hybrid-seed004.toml"),
            "--gcode",
        ])
        .arg(&prog)
        .arg("--out")
        .arg(dir.path().join("hy"))
        .arg("--json")
        .output()
        .unwrap();
    ok(&o);
    let s: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["type"], "p3rp/hybrid");
    assert!(
        s["violations"].as_array().unwrap().is_empty(),
        "{}",
        s["violations"]
    );
    // Table Y takes back the tool's sideways swing L sin A = 150 sin 30 = 75 mm.
    let y = &s["actuators"]["Y"];
    assert!(
        (y["min"].as_f64().unwrap() - (10.0 - 75.0)).abs() < 1e-6,
        "{y}"
    );
    // The report carries the seed-004 section for both files.
    for file in ["p3rp-seed004.toml", "p3rp-hybrid-seed004.toml"] {
        let rep = dir.path().join(format!("rep-{file}"));
        let o = pkm()
            .args([
                "report",
                &path(&format!("examples/machines/{file}")),
                "--out",
            ])
            .arg(&rep)
            .output()
            .unwrap();
        ok(&o);
        let html = std::fs::read_to_string(rep.join("index.html")).unwrap();
        assert!(html.contains("seed 004 reproduced"));
        assert!(html.contains("slider V peak velocity in the fig. 7 move"));
        assert!(html.contains("Forward workspace (fig. 5)"));
    }
}

/// The motion plots mark the G-code segment starts and the stroke
/// limits a curve comes near, with the legends beside the panels.
#[test]
fn motion_plots_mark_segments_and_near_limits() {
    let dir = tempfile::tempdir().unwrap();
    let prog = dir.path().join("down.ngc");
    // Down towards the struts' 300 mm stroke end and back, in three lines.
    std::fs::write(
        &prog,
        "G21 G90\nG1 X0 Y0 Z-360 F3000\nG1 X20 F3000\nG1 X0 Z-290 F3000\n",
    )
    .unwrap();
    let out = dir.path().join("m");
    let o = pkm()
        .args([
            "motion",
            &path("examples/machines/tripod-seed000.toml"),
            "--gcode",
        ])
        .arg(&prog)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let svg = std::fs::read_to_string(out.join("actuators.svg")).unwrap();
    assert!(svg.contains("segment start"), "segment marks");
    assert!(svg.contains("\nlimit\n"), "the 300 mm stroke end is drawn");
    assert!(svg.contains("N3") && svg.contains("N4"), "segment labels");
    // The serial machine has no limits to draw.
    let svg = std::fs::read_to_string(out.join("serial.svg")).unwrap();
    assert!(!svg.contains("\nlimit\n"));
}

/// The boat program through MC-300 with the accuracy along it (the file's
/// 39 tolerances; budget per G-code line, Monte Carlo band) and its closest approach
/// to the singular direction.
#[test]
fn accuracy_and_singular_passages_along_a_five_axis_program() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("boat");
    let o = pkm()
        .args([
            "motion",
            &path("examples/machines/mc300.toml"),
            "--gcode",
            &path("tests/fixtures/linuxcnc/xyzbc-trt/boat-xyzbc.ngc"),
            "--summary-only",
            "--rate",
            "200",
            "--accuracy",
            "--band-machines",
            "20",
        ])
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    // C's 360 deg turn at line 1081 is beyond MC-300's +-180 deg.
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("accuracy along the program (39 tolerances"),
        "{text}"
    );
    assert!(text.contains("closest 5.5450 deg"), "{text}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let a = &s["accuracy"];
    assert_eq!(a["tolerances"], 39);
    assert_eq!(a["tolerance_source"], "machine-file");
    assert_eq!(a["monte_carlo"]["machines"], 20);
    let wc = a["worst_case"]["mm"].as_f64().unwrap();
    let rss = a["rss"]["mm"].as_f64().unwrap();
    assert!(wc > rss && rss > 0.0, "{a}");
    // The program's feed moves come no nearer than |B| = 5.545 deg (its B-5.545 at
    // line 55): no passage within the default 2 deg.
    let sg = &s["singular"];
    assert!(
        (sg["closest"][0].as_f64().unwrap() - 5.545).abs() < 1e-6,
        "{sg}"
    );
    assert_eq!(sg["passages"].as_array().unwrap().len(), 0);
    // One row per G-code line with motion; the largest worst case is the summary's.
    let csv = std::fs::read_to_string(out.join("accuracy.csv")).unwrap();
    let mut lines = csv.lines();
    assert!(lines
        .next()
        .unwrap()
        .starts_with("line,start_s,end_s,samples,worst_case_mm"));
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert!(rows.len() > 1000, "{}", rows.len());
    let max = rows
        .iter()
        .map(|r| r[4].parse::<f64>().unwrap())
        .fold(0.0, f64::max);
    assert!((max - wc).abs() < 1e-6 * wc, "{max} {wc}");
    let svg = std::fs::read_to_string(out.join("accuracy.svg")).unwrap();
    assert!(svg.contains("along the tool axis"));
    // Tolerance options need --accuracy; with it, per-kind tolerances replace the
    // file's.
    let o = pkm()
        .args([
            "motion",
            &path("examples/machines/mc300.toml"),
            "--gcode",
            &path("tests/fixtures/linuxcnc/xyzbc-trt/boat-xyzbc.ngc"),
            "--angle-tolerance",
            "0.001",
        ])
        .arg("--out")
        .arg(dir.path().join("x"))
        .output()
        .unwrap();
    assert_ne!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stderr).contains("need --accuracy"));
}

/// `pkm ik --tool-axis I,J,K` on a 5-axis TCP machine: both branches, the chosen one's
/// joints equal to `pkm ik` of its angles.
#[test]
fn ik_from_a_tool_axis_vector() {
    let mc300 = path("examples/machines/mc300.toml");
    let o = pkm()
        .args([
            "ik",
            &mc300,
            "--pose=10,5,-3",
            "--tool-axis=0.3,0.2,1",
            "--json",
        ])
        .output()
        .unwrap();
    ok(&o);
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let ta = &v["tool_axis"];
    assert_eq!(ta["branches"].as_array().unwrap().len(), 2);
    let chosen = ta["chosen"].as_u64().unwrap() as usize;
    let pose = &ta["branches"][chosen]["pose"];
    // B = -atan(hypot(0.3, 0.2)) on the branch nearest home.
    let b = pose["B"].as_f64().unwrap();
    assert!(
        (b.abs() - 0.3f64.hypot(0.2).atan().to_degrees()).abs() < 1e-9,
        "{b}"
    );
    let c = pose["C"].as_f64().unwrap();
    let o2 = pkm()
        .args(["ik", &mc300, &format!("--pose=10,5,-3,{b},{c}"), "--json"])
        .output()
        .unwrap();
    ok(&o2);
    let w: Value = serde_json::from_slice(&o2.stdout).unwrap();
    for (k, a) in w["actuators"].as_object().unwrap() {
        let x = v["actuators"][k].as_f64().unwrap();
        assert!((x - a.as_f64().unwrap()).abs() < 1e-9, "{k}");
    }
    // --pose takes X,Y,Z only with --tool-axis; a hexapod takes no tool axis.
    let o = pkm()
        .args(["ik", &mc300, "--pose=10,5,-3,0,0", "--tool-axis=0,0,1"])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("expected X,Y,Z"));
    let o = pkm()
        .args([
            "ik",
            &path("examples/machines/hexapod-seed001.toml"),
            "--pose=0,0,0",
            "--tool-axis=0,0,1",
        ])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("tool axis vector"));
}

/// `pkm check` warns when a TCP machine's part frame is turned against the machine's
/// axes (a program's Z would move along another axis); the examples are not.
#[test]
fn check_warns_of_a_turned_part_frame() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(path("examples/machines/head-table-5axis.toml"))
        .unwrap()
        .replace(
            "translation = [10.0, 20.0, -50.0]   # the C axis off the world origin",
            "translation = [10.0, 20.0, -50.0]\nrotation = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]",
        );
    let f = dir.path().join("turned.toml");
    std::fs::write(&f, text).unwrap();
    let o = pkm().arg("check").arg(&f).output().unwrap();
    ok(&o);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("warning     at home the tool axis is (0.0000, 1.0000"),
        "{out}"
    );
    for m in ["mc300.toml", "head-table-5axis.toml"] {
        let o = pkm()
            .args(["check", &path(&format!("examples/machines/{m}"))])
            .output()
            .unwrap();
        ok(&o);
        assert!(
            !String::from_utf8_lossy(&o.stdout).contains("warning"),
            "{m}"
        );
    }
}

/// `--format parquet` writes actuators.parquet instead of actuators.csv: the CSV's
/// columns and rows at full precision, over several blocks and row groups (a 5 kHz run
/// of about 90 000 samples), and nothing with --summary-only.
#[test]
fn parquet_series_hold_the_csv_rows() {
    use crate::common::assert_parquet_is_csv;
    let dir = tempfile::tempdir().unwrap();
    let g = dir.path().join("wave.ngc");
    let mut prog = String::from("G21 G90 G17\nG0 X0 Y40 Z508 A0 B0 C0\nF800\n");
    for k in 0..60 {
        let a = k as f64 * 0.3;
        prog.push_str(&format!(
            "G1 X{:.4} Y{:.4} Z{:.4} A{:.3} B{:.3}\n",
            20.0 * a.sin(),
            40.0 * a.cos(),
            508.0 + 2.0 * (2.0 * a).sin(),
            3.0 * a.sin(),
            -2.0 * a.cos()
        ));
    }
    prog.push_str("M2\n");
    std::fs::write(&g, prog).unwrap();
    let run = |format: &str, extra: &[&str]| {
        let out = dir.path().join(format!("{format}{}", extra.len()));
        let o = pkm()
            .args([
                "motion",
                &path("examples/machines/hexapod-linuxcnc.toml"),
                "--rate",
                "5000",
                "--format",
                format,
                "--gcode",
            ])
            .arg(&g)
            .args(extra)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        ok(&o);
        out
    };
    let csv = run("csv", &[]);
    let pq = run("parquet", &[]);
    assert!(!pq.join("actuators.csv").exists());
    // The CSV's six decimals: half a unit of the last.
    let rows = assert_parquet_is_csv(
        &pq.join("actuators.parquet"),
        &csv.join("actuators.csv"),
        5e-7,
    );
    assert!(rows > 65_536, "{rows} rows: one row group only");
    assert_eq!(
        std::fs::read(csv.join("summary.json")).unwrap(),
        std::fs::read(pq.join("summary.json")).unwrap()
    );
    let none = run("parquet", &["--summary-only"]);
    assert!(!none.join("actuators.parquet").exists());
    assert!(none.join("summary.json").exists());
}

/// The printed table keeps its columns aligned whatever the machine's own actuator
/// names: the header and every row end at the same column (names of 1 to 24
/// characters, one with a non-ASCII letter).
#[test]
fn the_printed_table_is_aligned_for_long_actuator_names() {
    let dir = tempfile::tempdir().unwrap();
    let mut text =
        std::fs::read_to_string(path("examples/machines/hexapod-linuxcnc.toml")).unwrap();
    text.truncate(text.find("[[reference]]").unwrap());
    let names = [
        "0",
        "north-west",
        "strut-3-with-a-long-name",
        "süd",
        "e",
        "west",
    ];
    for (k, n) in names.iter().enumerate() {
        text = text.replace(&format!("name = \"{k}\""), &format!("name = \"{n}\""));
    }
    let machine = dir.path().join("named.toml");
    std::fs::write(&machine, text).unwrap();
    let program = dir.path().join("p.ngc");
    std::fs::write(
        &program,
        "G21 G90\nG0 X0 Y0 Z508 A0 B0 C0\nG1 X20 Y5 F600\n",
    )
    .unwrap();
    let o = pkm()
        .arg("motion")
        .arg(&machine)
        .arg("--gcode")
        .arg(&program)
        .arg("--summary-only")
        .arg("--out")
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    ok(&o);
    let stdout = String::from_utf8(o.stdout).unwrap();
    let table: Vec<&str> = stdout
        .lines()
        .filter(|l| {
            l.starts_with("axis ") || l.starts_with("actuator ") || l.starts_with("serial ")
        })
        .collect();
    let rows = |p: &str| table.iter().filter(|l| l.starts_with(p)).count();
    assert_eq!((rows("axis "), rows("actuator ")), (1, 6), "{stdout}");
    assert!(rows("serial ") >= 3, "{stdout}");
    for n in names {
        assert!(
            table
                .iter()
                .any(|l| l.starts_with(&format!("actuator {n} "))),
            "{n}: {stdout}"
        );
    }
    let width = table[0].chars().count();
    for l in &table {
        assert_eq!(l.chars().count(), width, "{stdout}");
    }
    // `pkm check` lists the same names with their ranges in one column, and `pkm ik`
    // its values in one column after them: `marker` starts at the same character on
    // every actuator line.
    let aligned = |args: &[&str], marker: &str| {
        let o = pkm()
            .arg(args[0])
            .arg(&machine)
            .args(&args[1..])
            .output()
            .unwrap();
        ok(&o);
        let stdout = String::from_utf8(o.stdout).unwrap();
        let at: Vec<usize> = stdout
            .lines()
            .filter(|l| l.starts_with("actuator "))
            .map(|l| l.chars().count() - l.split_once(marker).unwrap().1.chars().count())
            .collect();
        assert_eq!(at.len(), 6, "{stdout}");
        assert!(at.iter().all(|&c| c == at[0]), "{stdout}");
    };
    aligned(&["check"], " range [");
    aligned(&["ik", "--pose=0,0,508,0,0,0"], " mm   range [");
}
