//! Identification of the pentapod: 25 geometric parameters and 5 zero
//! readings from points measured on its tool axis (its spin about the axis is free),
//! with both measurement models; the identified machine as a file and back to the
//! controller.

use nalgebra::{SVector, Vector3};
use pkm::identify::simulate::{pose_errors, simulate, simulate_on, Design, Experiment};
use pkm::identify::{
    identify, parameter_names, residuals, Calibratable, Identifiable, MeasurementModel, Options,
};
use pkm::machine::Model;
use pkm::pentapod::Pentapod;
use pkm::Machine;

fn path() -> String {
    format!(
        "{}/../../examples/machines/pentapod-linuxcnc.toml",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn pentapod() -> Pentapod {
    let Model::Pentapod(p) = Machine::from_path(path()).unwrap().model else {
        panic!()
    };
    *p
}

/// Noise-free random states measured on the pentapod's axis.
fn experiment(p: &Pentapod, states: usize, seed: u64) -> Experiment {
    Experiment {
        fixture: p.fixture(200.0).points,
        ..experiment_base(states, seed)
    }
}

#[test]
fn a_pose_measured_on_the_tool_axis_is_the_true_pose() {
    let p = pentapod();
    let s = simulate(&p, &p.zero_readings().unwrap(), &experiment(&p, 40, 2)).unwrap();
    for (st, x) in s.measurements.states.iter().zip(&s.poses) {
        let m = s
            .truth
            .measured_pose(&s.measurements.fixture, &st.points)
            .unwrap();
        assert!((m - x).amax() < 1e-9, "{m:?} vs {x:?}");
    }
    // Off the axis, a point has no position: refused, naming it.
    let e = p
        .check_fixture(&[Vector3::new(0.0, 0.0, 0.0), Vector3::new(50.0, 0.0, 10.0)])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("point 2") && e.contains("off the pentapod's tool axis"),
        "{e}"
    );
    let mut off = experiment(&p, 5, 2);
    off.fixture = pkm::identify::simulate::triangle(200.0, 0.0);
    assert!(simulate(&p, &p.zero_readings().unwrap(), &off).is_err());
    // Two points at one height give no direction.
    let one = [Vector3::new(0.0, 0.0, 5.0), Vector3::new(0.0, 0.0, 5.0)];
    assert!(p.measured_pose(&one, &[Vector3::zeros(); 2]).is_err());
}

#[test]
fn pentapod_residual_jacobians_equal_finite_differences() {
    let p = pentapod();
    let zero = p.zero_readings().unwrap();
    let s = simulate(&p, &zero, &experiment(&p, 8, 3)).unwrap();
    let mut theta = s.truth.geometry();
    theta.extend(s.true_zero.iter());
    // The tool length trades against every ring height: not identified.
    assert_eq!(theta.len(), 30);
    let names = parameter_names(&p);
    assert_eq!(names.len(), 30);
    assert!(!names.iter().any(|n| n == "tool.z"), "{names:?}");
    for model in [MeasurementModel::Pose, MeasurementModel::Points] {
        let (_, j) = residuals(&p, &s.measurements, model, &theta).unwrap();
        let mut worst: f64 = 0.0;
        for c in 0..30 {
            let step = 1e-5;
            let (mut tp, mut tm) = (theta.clone(), theta.clone());
            tp[c] += step;
            tm[c] -= step;
            let (rp, _) = residuals(&p, &s.measurements, model, &tp).unwrap();
            let (rm, _) = residuals(&p, &s.measurements, model, &tm).unwrap();
            worst = worst.max((j.column(c) - (rp - rm) / (2.0 * step)).amax());
        }
        assert!(worst < 1e-6, "{model:?}: {worst}");
    }
}

#[test]
fn noise_free_axis_measurements_recover_the_pentapod() {
    let p = pentapod();
    let zero = p.zero_readings().unwrap();
    let s = simulate(&p, &zero, &experiment(&p, 30, 11)).unwrap();
    let mut truth = s.truth.geometry();
    truth.extend(s.true_zero.iter());
    assert!(p.must_hold().is_empty());
    for model in [MeasurementModel::Pose, MeasurementModel::Points] {
        let o = Options {
            model,
            ..Default::default()
        };
        let id = identify(&p, &zero, &s.measurements, &o).unwrap();
        assert!(
            id.rms_before > 0.1 && id.rms_after < 1e-9,
            "{model:?}: {id:?}"
        );
        let err = id
            .values
            .iter()
            .zip(&truth)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(err < 1e-6, "{model:?}: parameter error {err} mm");
        // The identified machine predicts held-out states as the truth does.
        let v = simulate_on(s.truth.clone(), s.true_zero, &experiment(&p, 10, 99)).unwrap();
        let model_m = p.with_geometry(&id.values[..25]).unwrap();
        let z = SVector::<f64, 5>::from_column_slice(&id.values[25..]);
        let readings = v.measurements.readings();
        let before = crate::common::all_reached(pose_errors(&p, &zero, &readings, &v.poses));
        let after = crate::common::all_reached(pose_errors(&model_m, &z, &readings, &v.poses));
        assert!(before.position_max > 0.5, "{before:?}");
        assert!(
            after.position_max < 1e-6 && after.orientation_max < 1e-9,
            "{after:?}"
        );
    }
}

/// The analysis layer end to end: a simulated campaign with its true machine file, the
/// identification, the identified file (loads, carries the zero lengths) and its
/// LinuxCNC export (HOME_OFFSET = the identified zero lengths).
#[test]
fn a_calibrated_pentapod_goes_back_to_the_controller() {
    use pkm::analysis::identification::{
        calibrate, fixture, identified_machine_file, parse_measurements, simulate_measurements,
        write_measurements, CalibrateOptions, SimulateOptions,
    };
    let text = std::fs::read_to_string(path()).unwrap();
    let m = Machine::from_toml_str(&text, "pentapod.toml").unwrap();
    m.supports(pkm::machine::Analysis::Identification).unwrap();
    let f = fixture(&m, 150.0).unwrap();
    assert_eq!(f.points.len(), 2);
    assert!(f.description.contains("tool axis"), "{}", f.description);
    let opt = SimulateOptions {
        experiment: Experiment {
            fixture: f.points,
            states: 40,
            ..Experiment::default()
        },
        holdout: 10,
        comment: "test".into(),
    };
    let s = simulate_measurements(&m, Some(&text), &opt).unwrap();
    let truth = Machine::from_toml_str(s.true_machine_file.as_ref().unwrap(), "true.toml").unwrap();
    let csv = write_measurements(&m, &s.measurements, "c");
    let meas = parse_measurements(&m, &csv, "m.csv").unwrap();
    let val = parse_measurements(&m, &write_measurements(&m, &s.validation, "v"), "v.csv").unwrap();
    let c = calibrate(&m, &meas, Some(&val), &CalibrateOptions::default()).unwrap();
    let v = c.validation.clone().unwrap();
    assert!(v.identified.rms < 0.05 && v.nominal.rms > 1.0, "{v:?}");
    let out = identified_machine_file(&m, &text, &c, "identified").unwrap();
    let back = Machine::from_toml_str(&out, "identified.toml").unwrap();
    let Model::Pentapod(bp) = &back.model else {
        panic!()
    };
    let z = bp.zero_lengths().unwrap();
    for i in 0..5 {
        assert!((z[i] - c.values[25 + i]).abs() < 1e-12);
    }
    // The readings it predicts for a pose (struts less zero lengths, what the control
    // counts) are the true machine's.
    let Model::Pentapod(tp) = &truth.model else {
        panic!()
    };
    let zt = tp.zero_lengths().unwrap();
    let (a, t) = (back.mechanism(), truth.mechanism());
    let mut x = a.home();
    x[0] += 40.0;
    x[3] += 0.05;
    let (qa, qt) = (a.inverse(&x).unwrap(), t.inverse(&x).unwrap());
    for i in 0..5 {
        let (ra, rt) = (qa[i] - z[i], qt[i] - zt[i]);
        assert!((ra - rt).abs() < 0.02, "strut {i}: reading {ra} vs {rt}");
    }
    let exp = pkm::linuxcnc::export(&back, pkm::linuxcnc::LengthUnit::Mm).unwrap();
    let offset = format!("HOME_OFFSET = {}", pkm_num(z[0]));
    assert!(exp.ini.contains(&offset), "{offset} in {}", exp.ini);
    // Seed 001's procedure does not apply to a pentapod, and says why.
    let e = calibrate(
        &m,
        &meas,
        None,
        &CalibrateOptions {
            seed_procedure: true,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, pkm::Error::Unsupported { .. }), "{e}");
}

fn pkm_num(v: f64) -> String {
    let mut s = format!("{v:.12}");
    while s.ends_with('0') {
        s.pop();
    }
    s
}

/// The point model inverts the Jacobian over the driven coordinates: a translational
/// tripod (3 struts, X, Y, Z driven, A, B, C held) is identified from points too.
#[test]
fn the_point_model_takes_a_translational_tripod() {
    let Model::TranslationalTripod(t) = Machine::from_path(format!(
        "{}/../../examples/machines/tripod-seed000.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
    .model
    else {
        panic!()
    };
    let zero = t.zero_readings().unwrap();
    let e = Experiment {
        translation: 30.0,
        fixture: pkm::identify::simulate::triangle(40.0, 0.0),
        ..experiment_base(20, 4)
    };
    let s = simulate(&t, &zero, &e).unwrap();
    let mut truth = s.truth.geometry();
    truth.extend(s.true_zero.iter());
    let (_, j) = residuals(&t, &s.measurements, MeasurementModel::Points, &truth).unwrap();
    assert_eq!(j.ncols(), 21);
    let o = Options {
        model: MeasurementModel::Points,
        fixed: t.must_hold(),
        ..Default::default()
    };
    let id = identify(&t, &zero, &s.measurements, &o).unwrap();
    assert!(id.rms_before > 0.1 && id.rms_after < 1e-9, "{id:?}");
}

fn experiment_base(states: usize, seed: u64) -> Experiment {
    Experiment {
        deviation: 1.0,
        point_noise: 0.0,
        length_noise: 0.0,
        states,
        design: Design::Random,
        seed,
        ..Experiment::default()
    }
}

/// The report's study on a pentapod (a user's, with a tool below the effector) says
/// why seed 001's one-strut design does not apply, whether or not that design's states
/// could be simulated (with a 120 mm tool they cannot: the study called it "singular").
#[test]
fn the_calibration_study_says_seed_001_does_not_apply_to_a_pentapod() {
    use pkm::analysis::identification::{calibration_study, fixture};
    let text = std::fs::read_to_string(path())
        .unwrap()
        .replace("tip = [0.0, 0.0, 0.0]", "tip = [0.0, 0.0, -120.0]");
    let text = match text.find("[[reference]]") {
        Some(i) => text[..i].to_string(),
        None => text,
    };
    let m = Machine::from_toml_str(&text, "mine.toml").unwrap();
    let e = Experiment {
        fixture: fixture(&m, 200.0).unwrap().points,
        ..Experiment::default()
    };
    let st = calibration_study(&m, &e, 5).unwrap();
    assert!(st.one_strut_condition.is_none());
    assert!(
        st.one_strut_note
            .as_deref()
            .unwrap_or("")
            .contains("least squares"),
        "{:?}",
        st.one_strut_note
    );
}
