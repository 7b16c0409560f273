//! LinuxCNC's tripodkins: a tripod whose three struts meet in the controlled point D,
//! imported as a translational tripod with a point platform, checked against the
//! module's own formulas (tripodkins.c, re-implemented here in the configuration's
//! inches), and exported back.

use pkm::linuxcnc::{export, import_with, LengthUnit};
use pkm::{Error, Machine};
use rand::{Rng, SeedableRng};

use super::linuxcnc::{example, imported, round_trip};

/// The fixture's kinematics.hal: Bx, Cx, Cy (inches).
const G: [f64; 3] = [20.0, 10.0, 17.3205];

/// tripodkins' inverse: `AD`, `BD`, `CD` with A = 0, B = (Bx, 0, 0), C = (Cx, Cy, 0).
fn tripodkins_inverse(d: [f64; 3], g: [f64; 3]) -> [f64; 3] {
    let [x, y, z] = d;
    [
        (x * x + y * y + z * z).sqrt(),
        ((x - g[0]).powi(2) + y * y + z * z).sqrt(),
        ((x - g[1]).powi(2) + (y - g[2]).powi(2) + z * z).sqrt(),
    ]
}

/// tripodkins' forward with its default flag (D above the XY plane): `x = (Q - P)/s`,
/// `y = (R - Q - (t - s) x)/u`, `z = sqrt(P - x^2 - y^2)`.
fn tripodkins_forward(q: [f64; 3], g: [f64; 3]) -> Option<[f64; 3]> {
    let p = q[0] * q[0];
    let qq = q[1] * q[1] - g[0] * g[0];
    let r = q[2] * q[2] - g[1] * g[1] - g[2] * g[2];
    let (s, t, u) = (-2.0 * g[0], -2.0 * g[1], -2.0 * g[2]);
    let x = (qq - p) / s;
    let y = (r - qq - (t - s) * x) / u;
    let z2 = p - x * x - y * y;
    (z2 >= 0.0).then(|| [x, y, z2.sqrt()])
}

#[test]
fn a_tripodkins_configuration_agrees_with_tripodkins() {
    let (m, warnings, toml) = imported("tripod/tripod.ini");
    assert!(warnings.is_empty(), "{warnings:?}");
    let mech = m.mechanism();
    assert_eq!(mech.kind(), "tripod/translational");
    // [TRAJ] HOME = 10 5.7735 15 in; the INI's joint HOME values are its struts.
    let home = mech.home();
    for (h, e) in home
        .iter()
        .zip([254.0, 5.7735 * 25.4, 381.0, 0.0, 0.0, 0.0])
    {
        assert!((h - e).abs() < 1e-9, "{home:?}");
    }
    assert_eq!(m.references.len(), 1);
    assert!(pkm::verify::check_references(&m)[0].pass);
    // Where each value came from.
    assert!(
        toml.contains("tripodkins.Bx = 20.0 in: kinematics.hal:3"),
        "{toml}"
    );
    assert!(toml.contains("platform = \"D\""), "{toml}");

    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    for _ in 0..2000 {
        let d = [
            rng.random_range(-5.0..25.0),
            rng.random_range(-10.0..20.0),
            rng.random_range(2.0..30.0),
        ];
        // Any orientation: tripodkins computes none, and a point platform has none.
        let x = [
            d[0] * 25.4,
            d[1] * 25.4,
            d[2] * 25.4,
            rng.random_range(-0.5..0.5),
            rng.random_range(-0.5..0.5),
            rng.random_range(-0.5..0.5),
        ];
        let q = mech.inverse(&x).unwrap();
        let r = tripodkins_inverse(d, G);
        for i in 0..3 {
            assert!((q[i] - r[i] * 25.4).abs() < 1e-9, "{q:?} vs {r:?}");
        }
        // The forward from home (above the base plane, tripodkins' default flag).
        let f = mech.forward(&q, &home).unwrap();
        let e = tripodkins_forward(r, G).unwrap();
        for k in 0..3 {
            assert!(
                (f.pose[k] - e[k] * 25.4).abs() < 1e-8,
                "{:?} vs {e:?}",
                f.pose
            );
        }
    }
    // The axis travel of [AXIS_L] and the strokes of [JOINT_n] are checked.
    let x = [26.0 * 25.4, 5.0 * 25.4, 15.0 * 25.4, 0.0, 0.0, 0.0];
    let v = mech.check_limits(&x, &mech.inverse(&x).unwrap()).unwrap();
    assert!(v.iter().any(|v| v.limit == "axis X travel"), "{v:?}");
    let x = [10.0 * 25.4, 5.0 * 25.4, 40.0 * 25.4, 0.0, 0.0, 0.0];
    let v = mech.check_limits(&x, &mech.inverse(&x).unwrap()).unwrap();
    assert!(v.iter().any(|v| v.limit == "strut 0 length"), "{v:?}");
}

const MIN_INI: &str = "[KINS]\nKINEMATICS = tripodkins\n[TRAJ]\nLINEAR_UNITS = inch\n\
                       HOME = 0.5 0.3 1\n[HAL]\nHALFILE = k.hal\n";

#[test]
fn tripodkins_defaults_apply_to_what_the_hal_leaves_unset() {
    let imp = import_with(
        "m.ini",
        MIN_INI,
        &mut |_f: &str| Ok("setp tripodkins.Bx 2.0\n".into()),
        &[],
    )
    .unwrap();
    // LinuxCNC's rtapi_app_main sets Bx = Cx = Cy = 1; the HAL sets Bx only.
    for p in ["Cx", "Cy"] {
        assert!(
            imp.warnings
                .iter()
                .any(|w| w.contains(&format!("tripodkins.{p} is not set"))),
            "{:?}",
            imp.warnings
        );
    }
    assert!(!imp.warnings.iter().any(|w| w.contains("tripodkins.Bx")));
    let m = Machine::from_toml_str(&imp.toml, "m.toml").unwrap();
    let q = m.mechanism().inverse(&m.mechanism().home()).unwrap();
    let r = tripodkins_inverse([0.5, 0.3, 1.0], [2.0, 1.0, 1.0]);
    for i in 0..3 {
        assert!((q[i] - r[i] * 25.4).abs() < 1e-9, "{q:?} vs {r:?}");
    }
    // A and B coincide when Bx = 0: tripodkins' forward fails (s == 0), and the import
    // says the configuration is not a machine.
    let e = import_with(
        "m.ini",
        MIN_INI,
        &mut |_f: &str| Ok("setp tripodkins.Bx 0\n".into()),
        &[],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("collinear or coincide"), "{e}");
}

#[test]
fn a_tripod_exported_to_tripodkins_imports_as_the_same_machine() {
    let (m, _, _) = imported("tripod/tripod.ini");
    for unit in [LengthUnit::Mm, LengthUnit::Inch] {
        let back = round_trip(&m, unit);
        let exp = export(&m, unit).unwrap();
        assert!(exp.hal.contains("setp tripodkins.Cy "), "{}", exp.hal);
        // The travel of every axis goes out and comes back.
        let x = [26.0 * 25.4, 5.0 * 25.4, 15.0 * 25.4, 0.0, 0.0, 0.0];
        let v = back
            .mechanism()
            .check_limits(&x, &back.mechanism().inverse(&x).unwrap())
            .unwrap();
        assert!(v.iter().any(|v| v.limit == "axis X travel"), "{v:?}");
    }
    let exp = export(&m, LengthUnit::Inch).unwrap();
    assert!(exp.hal.contains("setp tripodkins.Bx 20.0\n"), "{}", exp.hal);
    assert!(exp.ini.contains("COORDINATES = X Y Z\n"), "{}", exp.ini);
}

/// A translational tripod with a platform of its own goes out as the tripodkins machine
/// it is at its held orientation (base points less the platform joints' offsets from
/// the tool tip), when those points are where tripodkins puts A, B and C.
#[test]
fn a_translational_tripod_goes_out_as_its_equivalent_point_tripod() {
    let text = "type = \"tripod\"\nconstraint = \"translational\"\n\
        [base_joints]\nF = [-50.0, 30.0, 40.0]\nG = [450.0, 30.0, 40.0]\nH = [200.0, 430.0, 40.0]\n\
        [platform_joints]\nP = [-50.0, 30.0, 0.0]\nQ = [50.0, 30.0, 0.0]\nR = [0.0, 80.0, 0.0]\n\
        [[struts]]\nname = \"a\"\nbase = \"F\"\nplatform = \"P\"\nlength = [100.0, 900.0]\n\
        [[struts]]\nname = \"b\"\nbase = \"G\"\nplatform = \"Q\"\nlength = [100.0, 900.0]\n\
        [[struts]]\nname = \"c\"\nbase = \"H\"\nplatform = \"R\"\nlength = [100.0, 900.0]\n\
        [tool]\ntip = [0.0, 0.0, -40.0]\n[home]\nposition = [200.0, 150.0, 400.0]\n";
    let m = Machine::from_toml_str(text, "own.toml").unwrap();
    let exp = export(&m, LengthUnit::Mm).unwrap();
    // a_i = b_i - (c_i - t): (0, 0, 0), (400, 0, 0), (200, 350, 0).
    assert!(
        exp.hal.contains("setp tripodkins.Bx 400.0\n"),
        "{}",
        exp.hal
    );
    assert!(
        exp.hal.contains("setp tripodkins.Cx 200.0\n"),
        "{}",
        exp.hal
    );
    assert!(
        exp.hal.contains("setp tripodkins.Cy 350.0\n"),
        "{}",
        exp.hal
    );
    // At the held orientation, the point tripod the controller gets has the same struts.
    let back = import_with(
        "pkm.ini",
        &exp.ini,
        &mut |_f: &str| Ok(exp.hal.clone()),
        &[],
    )
    .unwrap();
    let back = Machine::from_toml_str(&back.toml, "back.toml").unwrap();
    let (a, b) = (m.mechanism(), back.mechanism());
    let mut rng = rand::rngs::StdRng::seed_from_u64(8);
    for _ in 0..200 {
        let mut x = a.home();
        for v in x.iter_mut().take(3) {
            *v += rng.random_range(-100.0..100.0);
        }
        let (qa, qb) = (a.inverse(&x).unwrap(), b.inverse(&x).unwrap());
        for i in 0..3 {
            assert!((qa[i] - qb[i]).abs() < 1e-9, "{qa:?} vs {qb:?}");
        }
    }

    // Seed 000's tripod has its base centred on the origin: tripodkins cannot say it.
    let e = export(&example("tripod-seed000.toml"), LengthUnit::Mm).unwrap_err();
    match &e {
        Error::Unsupported { reason, .. } => {
            assert!(reason.contains("tripodkins' origin A"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
    // A centre-leg tripod turns its platform: not tripodkins.
    let e = export(&example("tripod-centre-leg.toml"), LengthUnit::Mm).unwrap_err();
    assert!(
        matches!(e, Error::Unsupported { ref reason, .. } if reason.contains("tripodkins")),
        "{e}"
    );
}

/// Only a translational tripod's three struts may meet in one platform joint.
#[test]
fn struts_share_a_platform_joint_only_all_three_on_a_translational_tripod() {
    let (_, _, toml) = imported("tripod/tripod.ini");
    // Two struts sharing, the third on its own joint.
    let two = toml.replacen(
        "D = [0.0, 0.0, 0.0]",
        "D = [0.0, 0.0, 0.0]\nE = [10.0, 0.0, 0.0]",
        1,
    );
    let pos = two.rfind("platform = \"D\"").unwrap();
    let two = format!("{}platform = \"E\"{}", &two[..pos], &two[pos + 14..]);
    let e = Machine::from_toml_str(&two, "two.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("already used by another strut"), "{e}");
    assert!(e.contains("all three"), "{e}");
    // A centre-leg tripod's platform turns: its joints must span a triangle.
    let leg = toml
        .replace(
            "constraint = \"translational\"",
            "constraint = \"centre-leg\"",
        )
        .replace(
            "[tool]",
            "[centre_leg]\nbase = [254.0, 146.0, 0.0]\n\n[tool]",
        );
    let e = Machine::from_toml_str(&leg, "leg.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("already used by another strut"), "{e}");
}

/// A tripodkins machine identified with its platform joint held (it trades against the
/// base joints: the platform never turns) keeps its point platform: the identified file
/// loads and goes back to the controller.
#[test]
fn an_identified_point_tripod_keeps_its_point_platform() {
    use pkm::analysis::identification::{
        calibrate, fixture, identified_machine_file, simulate_measurements, CalibrateOptions,
        SimulateOptions,
    };
    use pkm::identify::simulate::Experiment;
    let (m, _, text) = imported("tripod/tripod.ini");
    let opt = SimulateOptions {
        experiment: Experiment {
            fixture: fixture(&m, 40.0).unwrap().points,
            translation: 50.0,
            states: 30,
            ..Experiment::default()
        },
        holdout: 0,
        comment: "test".into(),
    };
    let s = simulate_measurements(&m, Some(&text), &opt).unwrap();
    let c = calibrate(
        &m,
        &s.measurements,
        None,
        &CalibrateOptions {
            fix: vec!["D*".into()],
            ..Default::default()
        },
    )
    .unwrap();
    let out = identified_machine_file(&m, &text, &c, "identified").unwrap();
    let back = Machine::from_toml_str(&out, "identified.toml").unwrap();
    assert!(out.contains("platform = \"D\""), "{out}");
    assert!(back.mechanism().inverse(&back.mechanism().home()).is_ok());
    // tripodkins has three numbers for the base (Bx, Cx, Cy) and its world frame is the
    // base triangle's: an identified base that moved in the world cannot be written
    // without moving the world frame, and the export says by how much instead.
    match export(&back, LengthUnit::Inch) {
        Err(Error::Unsupported { reason, .. }) => {
            assert!(reason.contains("tripodkins' origin A is"), "{reason}")
        }
        other => panic!("{other:?}"),
    }
}
