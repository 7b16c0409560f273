//! LinuxCNC import and export: the simulator configurations against the controller's
//! own numbers, round trips through the export, and errors that name file and line.

#![allow(clippy::needless_range_loop)]

use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Vector3, Vector6};
use pkm::linuxcnc::{export, import, import_with, LengthUnit};
use pkm::{Error, Machine};
use rand::{Rng, SeedableRng};

pub(super) fn shared(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/fixtures/linuxcnc")
        .join(rel)
}

pub(super) fn example(name: &str) -> Machine {
    Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

pub(super) fn imported(rel: &str) -> (Machine, Vec<String>, String) {
    let imp = import(&shared(rel), &[]).unwrap();
    let m = Machine::from_toml_str(&imp.toml, "imported.toml").unwrap();
    (m, imp.warnings, imp.toml)
}

/// The hexapod sim's kinematics.hal (inch): base joints, platform joints.
const SIM_BASE: [[f64; 3]; 6] = [
    [-22.95, 13.25, 0.0],
    [22.95, 13.25, 0.0],
    [22.95, 13.25, 0.0],
    [0.0, -26.5, 0.0],
    [0.0, -26.5, 0.0],
    [-22.95, 13.25, 0.0],
];
const SIM_PLATFORM: [[f64; 3]; 6] = [
    [-1.0, 11.5, 0.0],
    [1.0, 11.5, 0.0],
    [10.459, -4.884, 0.0],
    [9.459, -6.616, 0.0],
    [-9.459, -6.616, 0.0],
    [-10.459, -4.884, 0.0],
];

/// genhexkins' inverse, in the configuration's inches, from the sim's kinematics.hal:
/// `L = |p + R a - b|` with `R = Rz(c) Ry(b) Rx(a)` (pmRpyMatConvert).
fn genhexkins_inverse(pose: &[f64; 6]) -> [f64; 6] {
    let (a, b) = (SIM_PLATFORM, SIM_BASE);
    let (sa, ca) = pose[3].to_radians().sin_cos();
    let (sb, cb) = pose[4].to_radians().sin_cos();
    let (sc, cc) = pose[5].to_radians().sin_cos();
    let rx = Matrix3::new(1.0, 0.0, 0.0, 0.0, ca, -sa, 0.0, sa, ca);
    let ry = Matrix3::new(cb, 0.0, sb, 0.0, 1.0, 0.0, -sb, 0.0, cb);
    let rz = Matrix3::new(cc, -sc, 0.0, sc, cc, 0.0, 0.0, 0.0, 1.0);
    let r = rz * ry * rx;
    let p = Vector3::new(pose[0], pose[1], pose[2]);
    std::array::from_fn(|i| (p + r * Vector3::from(a[i]) - Vector3::from(b[i])).norm())
}

#[test]
fn the_hexapod_sim_agrees_with_genhexkins() {
    let (m, warnings, toml) = imported("hexapod-sim/hexapod.ini");
    let mech = m.mechanism();
    assert_eq!(mech.kind(), "hexapod");
    // LinuxCNC's numbers: every strut 29.7466 in at the home pose, Z = 20 in.
    let home = mech.home();
    assert_eq!(home, vec![0.0, 0.0, 508.0, 0.0, 0.0, 0.0]);
    let q = mech.inverse(&home).unwrap();
    for l in &q {
        // HOME has 4 decimals of an inch; the default geometry's struts differ by 2e-4 in.
        assert!(
            (l / 25.4 - 29.7466).abs() < 3e-4,
            "{l} mm = {} in",
            l / 25.4
        );
    }
    // The controller's formula, in its own units, for any pose.
    let mut rng = rand::rngs::StdRng::seed_from_u64(1);
    for _ in 0..1000 {
        let pin: [f64; 6] = [
            rng.random_range(-5.0..5.0),
            rng.random_range(-5.0..5.0),
            rng.random_range(15.0..25.0),
            rng.random_range(-20.0..20.0),
            rng.random_range(-20.0..20.0),
            rng.random_range(-30.0..30.0),
        ];
        let x = [
            pin[0] * 25.4,
            pin[1] * 25.4,
            pin[2] * 25.4,
            pin[3].to_radians(),
            pin[4].to_radians(),
            pin[5].to_radians(),
        ];
        let q = mech.inverse(&x).unwrap();
        let r = genhexkins_inverse(&pin);
        for i in 0..6 {
            assert!(
                (q[i] - r[i] * 25.4).abs() < 1e-9,
                "strut {i}: {} vs {}",
                q[i],
                r[i] * 25.4
            );
        }
    }
    // Where each value came from, the reference from [JOINT_n] HOME, the calibration from
    // HOME_OFFSET, the tool offset that follows the tool table.
    assert!(toml.contains("kinematics.hal:4-6"), "{toml}");
    assert!(toml.contains("[JOINT_0] MIN_LIMIT -1000.0 in (hexapod.ini:81) is below 0"));
    assert_eq!(m.references.len(), 1);
    assert!(pkm::verify::check_references(&m)[0].pass);
    assert!(toml.contains("zero_lengths = [755.56364"), "{toml}");
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("genhexkins.tool-offset follows signal `tool-offset`")),
        "{warnings:?}"
    );
    // The shared base joints are one joint each (B0, B1, B3).
    assert!(toml.contains("# strut 2's joint is B1"));
}

#[test]
fn the_pentapod_sim_agrees_with_pentakins_and_its_home_joints_are_flagged() {
    let (m, warnings, _) = imported("pentapod/pentapod.ini");
    let mech = m.mechanism();
    assert_eq!(mech.kind(), "pentapod");
    let mut rng = rand::rngs::StdRng::seed_from_u64(2);
    for _ in 0..1000 {
        let x = [
            rng.random_range(-250.0..250.0),
            rng.random_range(-250.0..250.0),
            rng.random_range(-250.0..250.0),
            rng.random_range(-50f64..50.0).to_radians(),
            rng.random_range(-15f64..15.0).to_radians(),
        ];
        let q = mech.inverse(&[x[0], x[1], x[2], x[3], x[4], 0.0]).unwrap();
        let r = super::pentapod::pentakins_inverse(&x);
        for i in 0..5 {
            assert!((q[i] - r[i]).abs() < 1e-9);
        }
    }
    // The same machine as the bundled example (geometry, strokes, rates, travel).
    let ex = example("pentapod-linuxcnc.toml");
    let e = ex.mechanism();
    for (a, b) in mech.actuators().iter().zip(e.actuators()) {
        assert_eq!(
            (a.range, a.max_velocity, a.max_acceleration),
            (b.range, b.max_velocity, b.max_acceleration)
        );
    }
    let x = [12.0, -30.0, 40.0, 0.3, -0.1, 0.0];
    assert_eq!(mech.inverse(&x).unwrap(), e.inverse(&x).unwrap());
    let far = [0.0, 0.0, 0.0, 0.0, 20f64.to_radians(), 0.0];
    let v = mech
        .check_limits(&far, &mech.inverse(&far).unwrap())
        .unwrap();
    assert!(v.iter().any(|v| v.limit == "axis B travel"), "{v:?}");
    // Its [JOINT_n] HOME values are not the struts at the axis home: said, not used.
    assert!(m.references.is_empty());
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("598.5792") && w.contains("614.8469")),
        "{warnings:?}"
    );
}

/// Export in `unit`, import the export, compare.
pub(super) fn round_trip(m: &Machine, unit: LengthUnit) -> Machine {
    let exp = export(m, unit).unwrap();
    let hal = exp.hal.clone();
    let imp = import_with(
        "out/pkm.ini",
        &exp.ini,
        &mut |f: &str| {
            if f == "kinematics.hal" {
                Ok(hal.clone())
            } else {
                Err(format!("no file {f}"))
            }
        },
        &[],
    )
    .unwrap();
    let back = Machine::from_toml_str(&imp.toml, "back.toml").unwrap();
    let (a, b) = (m.mechanism(), back.mechanism());
    assert_eq!(a.kind(), b.kind());
    let same = |u: Option<f64>, v: Option<f64>| match (u, v) {
        (Some(u), Some(v)) => (u - v).abs() < 1e-8,
        (None, None) => true,
        _ => false,
    };
    for (x, y) in a.actuators().iter().zip(b.actuators()) {
        assert!((x.range.min - y.range.min).abs() < 1e-8);
        assert!((x.range.max - y.range.max).abs() < 1e-8);
        assert!(same(x.max_velocity, y.max_velocity), "{x:?} vs {y:?}");
        assert!(
            same(x.max_acceleration, y.max_acceleration),
            "{x:?} vs {y:?}"
        );
    }
    let (ha, hb) = (a.home(), b.home());
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    for _ in 0..200 {
        let mut x = ha.clone();
        for k in 0..3 {
            x[k] += rng.random_range(-30.0..30.0);
        }
        for k in 3..6 {
            x[k] += rng.random_range(-0.1..0.1);
        }
        let (qa, qb) = (a.inverse(&x).unwrap(), b.inverse(&x).unwrap());
        for i in 0..qa.len() {
            assert!((qa[i] - qb[i]).abs() < 1e-8, "{} vs {}", qa[i], qb[i]);
        }
    }
    for k in 0..ha.len() {
        assert!((ha[k] - hb[k]).abs() < 1e-9);
    }
    back
}

#[test]
fn importing_an_export_gives_the_same_machine() {
    for unit in [LengthUnit::Mm, LengthUnit::Inch] {
        let (m, _, _) = imported("hexapod-sim/hexapod.ini");
        round_trip(&m, unit);
        round_trip(&example("pentapod-linuxcnc.toml"), unit);
        // A machine with a tool tip off the platform origin: genhexkins controls the
        // platform origin, so the joints go out relative to the tip.
        round_trip(&example("hexapod-seed001.toml"), unit);
        // Axis travel survives.
        let (m, _, _) = imported("pentapod/pentapod.ini");
        let b2 = round_trip(&m, unit);
        let x = [0.0, 0.0, 0.0, 0.0, 16f64.to_radians(), 0.0];
        let v = b2
            .mechanism()
            .check_limits(&x, &b2.mechanism().inverse(&x).unwrap())
            .unwrap();
        assert!(v.iter().any(|v| v.limit == "axis B travel"));
    }
}

#[test]
fn a_calibrated_hexapod_goes_back_with_its_zero_lengths_as_home_offsets() {
    let text = std::fs::read_to_string(format!(
        "{}/../../examples/machines/hexapod-linuxcnc.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let z = [755.1, 755.2, 755.3, 755.4, 755.5, 755.6];
    let cal = format!(
        "{text}\n[calibration]\nzero_lengths = [{}]\n",
        z.map(|v| v.to_string()).join(", ")
    );
    let m = Machine::from_toml_str(&cal, "cal.toml").unwrap();
    let exp = export(&m, LengthUnit::Inch).unwrap();
    assert!(
        exp.ini
            .contains(&format!("HOME_OFFSET = {}", pkm_num(755.1 / 25.4))),
        "{}",
        exp.ini
    );
    let back = round_trip(&m, LengthUnit::Inch);
    let model = back.controller_model().unwrap();
    let zl = model.zero_lengths.unwrap();
    for i in 0..6 {
        assert!((zl[i] - z[i]).abs() < 1e-8);
    }
}

fn pkm_num(v: f64) -> String {
    let s = format!("{v:.12}");
    s.trim_end_matches('0').to_string()
}

fn import_err(ini: &str, hal: &str) -> String {
    let hal = hal.to_string();
    match import_with(
        "m.ini",
        ini,
        &mut |f: &str| {
            if f == "k.hal" {
                Ok(hal.clone())
            } else {
                Err("No such file or directory".into())
            }
        },
        &[],
    ) {
        Ok(_) => panic!("expected an error"),
        Err(e) => e.to_string(),
    }
}

const MIN_INI: &str = "[KINS]\nKINEMATICS = genhexkins\nJOINTS = 6\n[HAL]\nHALFILE = k.hal\n[TRAJ]\nLINEAR_UNITS = inch\nHOME = 0 0 20 0 0 0\n";

#[test]
fn errors_name_the_file_the_line_and_what_was_expected() {
    let e = import_err("[KINS]\nKINEMATICS = trivkins\n", "");
    assert!(
        e.starts_with("m.ini:2: field `[KINS] KINEMATICS`: unsupported kinematics `trivkins`"),
        "{e}"
    );
    let e = import_err("[EMC]\nMACHINE = x\n", "");
    assert!(
        e.contains("[KINS] KINEMATICS") && e.contains("no kinematics module"),
        "{e}"
    );
    let e = import_err(&MIN_INI.replace("k.hal", "missing.hal"), "");
    assert!(
        e.starts_with("m.ini:5: field `[HAL] HALFILE`: cannot read the HAL file `missing.hal`"),
        "{e}"
    );
    let e = import_err(MIN_INI, "# geometry\nsetp genhexkins.base.0.x twelve\n");
    assert!(
        e.starts_with("k.hal:2: expected a finite number, found `twelve`"),
        "{e}"
    );
    let e = import_err(MIN_INI, "setp genhexkins.screw-lead 5\n");
    assert!(
        e.starts_with("k.hal:1: field `genhexkins.screw-lead`"),
        "{e}"
    );
    let e = import_err(&MIN_INI.replace("inch", "furlong"), "");
    assert!(
        e.contains("m.ini:7") && e.contains("unknown length unit `furlong`"),
        "{e}"
    );
    let e = import_err(&format!("{MIN_INI}[JOINT_0]\nTYPE = ANGULAR\n"), "");
    assert!(
        e.contains("m.ini:10") && e.contains("LINEAR, found `ANGULAR`"),
        "{e}"
    );
    let e = import_err(
        &format!("{MIN_INI}[JOINT_0]\nMIN_LIMIT = 30\nMAX_LIMIT = 10\n"),
        "",
    );
    assert!(e.contains("m.ini:11") && e.contains("stroke"), "{e}");
    let e = import_err("KINEMATICS = genhexkins\n", "");
    assert!(
        e.starts_with("m.ini:1:") && e.contains("before any `[SECTION]`"),
        "{e}"
    );
    let e = import_err(MIN_INI, "setp genhexkins.base.0.x [JOINT_9]SCALE\n");
    assert!(e.contains("INI reference `[JOINT_9]SCALE`"), "{e}");
}

#[test]
fn unset_parameters_take_the_module_defaults_and_signals_their_sets_value() {
    // No HAL geometry at all: genhexkins.h's defaults, which the sim repeats.
    let imp = import_with("m.ini", MIN_INI, &mut |_f: &str| Ok(String::new()), &[]).unwrap();
    assert!(imp.toml.contains("genhexkins default"));
    let m = Machine::from_toml_str(&imp.toml, "d.toml").unwrap();
    let (sim, _, _) = imported("hexapod-sim/hexapod.ini");
    let x = [10.0, -20.0, 500.0, 0.1, 0.05, -0.2];
    assert_eq!(
        m.mechanism().inverse(&x).unwrap(),
        sim.mechanism().inverse(&x).unwrap()
    );
    // A spindle offset through a signal set by `sets`, and an INI reference as a value.
    let ini = format!(
        "{MIN_INI}[GEOM]\nX0 = -23.0\n[HAL]\nHALCMD = net :so genhexkins.spindle-offset\nHALCMD = sets :so 2.0\n"
    );
    let imp = import_with(
        "m.ini",
        &ini,
        &mut |_f: &str| Ok("setp genhexkins.base.0.x [GEOM]X0\n".into()),
        &[],
    )
    .unwrap();
    let m = Machine::from_toml_str(&imp.toml, "s.toml").unwrap();
    let model = m.controller_model().unwrap();
    match model.geometry {
        pkm::linuxcnc::Geometry::Genhex { base, platform } => {
            assert!((base[0] - Vector3::new(-23.0 * 25.4, 13.25 * 25.4, 2.0 * 25.4)).amax() < 1e-9);
            assert!((platform[3].z - 2.0 * 25.4).abs() < 1e-12);
        }
        _ => panic!(),
    }
}

#[test]
fn export_refuses_other_machine_types() {
    let m = example("mc300.toml");
    match export(&m, LengthUnit::Mm) {
        Err(Error::Unsupported { analysis, .. }) => assert_eq!(analysis, "LinuxCNC export"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_pentapod_pose_of_five_values_is_linuxcncs_x_y_z_a_b() {
    let m = example("pentapod-linuxcnc.toml");
    let x = pkm::dynamic::pose_from_user(
        m.mechanism(),
        &[1.0, 2.0, 3.0, 10.0, -5.0],
        pkm::Convention::Rpy,
    )
    .unwrap();
    let want = Vector6::new(1.0, 2.0, 3.0, 10f64.to_radians(), -5f64.to_radians(), 0.0);
    assert!((Vector6::from_column_slice(&x) - want).amax() < 1e-15);
}

/// genhexkins' forward kinematics as its source describes it (for the comparison in
/// docs/linuxcnc.md): Newton with the twist Jacobian `[u, (R a) x u]`, the angular step
/// subtracted from the roll, pitch, yaw angles as if it were their rates; stops when
/// every strut is within `1e-9` (inch), fails after 120 iterations or when the summed
/// error exceeds 500. Returns the pose (inch, rad) and the iterations.
fn genhexkins_forward(q: &[f64; 6], start: &[f64; 6]) -> Result<([f64; 6], usize), i32> {
    let (a, b) = (SIM_PLATFORM, SIM_BASE);
    let mut x = *start;
    let mut conv_err: f64 = 1.0;
    for iteration in 1.. {
        if conv_err.abs() > 500.0 {
            return Err(-2);
        }
        if iteration > 120 {
            return Err(-5);
        }
        let r = pkm::rotation::rpy_matrix(x[3], x[4], x[5]);
        let p = Vector3::new(x[0], x[1], x[2]);
        let mut j = nalgebra::Matrix6::<f64>::zeros();
        let mut diff = nalgebra::Vector6::<f64>::zeros();
        for i in 0..6 {
            let ra = r * Vector3::from(a[i]);
            let s = p + ra - Vector3::from(b[i]);
            let l = s.norm();
            let u = s / l;
            let m = ra.cross(&u);
            for k in 0..3 {
                j[(i, k)] = u[k];
                j[(i, 3 + k)] = m[k];
            }
            diff[i] = l - q[i];
        }
        let delta = j.try_inverse().ok_or(-1)? * diff;
        for k in 0..6 {
            x[k] -= delta[k];
        }
        conv_err = diff.iter().map(|d| d.abs()).sum();
        if diff.iter().all(|d| d.abs() <= 1e-9) {
            return Ok((x, iteration));
        }
    }
    unreachable!()
}

#[test]
fn forward_kinematics_against_genhexkins_algorithm() {
    let (m, _, _) = imported("hexapod-sim/hexapod.ini");
    let mech = m.mechanism();
    let mut rng = rand::rngs::StdRng::seed_from_u64(4);
    let (mut ours, mut theirs, mut failed) = (Vec::new(), Vec::new(), 0);
    for _ in 0..500 {
        let pin: [f64; 6] = [
            rng.random_range(-4.0..4.0),
            rng.random_range(-4.0..4.0),
            rng.random_range(16.0..24.0),
            rng.random_range(-20f64..20.0).to_radians(),
            rng.random_range(-20f64..20.0).to_radians(),
            rng.random_range(-20f64..20.0).to_radians(),
        ];
        let q = genhexkins_inverse(&[
            pin[0],
            pin[1],
            pin[2],
            pin[3].to_degrees(),
            pin[4].to_degrees(),
            pin[5].to_degrees(),
        ]);
        let home = [0.0, 0.0, 20.0, 0.0, 0.0, 0.0];
        let qmm: Vec<f64> = q.iter().map(|l| l * 25.4).collect();
        let f = mech.forward(&qmm, &mech.home()).unwrap();
        let want = [
            pin[0] * 25.4,
            pin[1] * 25.4,
            pin[2] * 25.4,
            pin[3],
            pin[4],
            pin[5],
        ];
        for k in 0..6 {
            assert!(
                (f.pose[k] - want[k]).abs() < 1e-9,
                "{:?} vs {want:?}",
                f.pose
            );
        }
        ours.push(f.iterations);
        match genhexkins_forward(&q, &home) {
            Ok((x, it)) => {
                for k in 0..3 {
                    assert!((x[k] - pin[k]).abs() < 1e-8);
                }
                theirs.push(it);
            }
            Err(_) => failed += 1,
        }
    }
    ours.sort();
    theirs.sort();
    let med = |v: &[usize]| v[v.len() / 2];
    eprintln!(
        "FK from home, 500 poses tilted up to 20 deg: pkm median {} max {} iterations; \
         genhexkins median {} max {}, {failed} failed",
        med(&ours),
        ours[ours.len() - 1],
        med(&theirs),
        theirs[theirs.len() - 1]
    );
    assert!(med(&ours) <= med(&theirs));
}
