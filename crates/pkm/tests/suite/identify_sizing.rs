//! The default simulated campaign fitted to the machine
//! (`pkm::analysis::identification::sized_experiment`): the examples keep
//! `Experiment::default()`, a micro-hexapod fifteen times smaller gets a campaign of
//! its own size that identifies it.

use pkm::analysis::identification::{calibration_study, fixture, sized_experiment};
use pkm::identify::simulate::{Experiment, DEFAULT_FIXTURE_SIZE, SIZING_SHARE};
use pkm::Error;

/// The default campaign on machine `m`: `Experiment::default()` with the default
/// fixture placed on it.
fn default_campaign(m: &pkm::machine::Machine) -> Experiment {
    Experiment {
        fixture: fixture(m, DEFAULT_FIXTURE_SIZE).unwrap().points,
        ..Experiment::default()
    }
}

/// Every identifiable example (and the own-hexapod fixture) fits the default
/// campaign: nothing is shrunk, so the README's and report's figures stay those of
/// `Experiment::default()`.
#[test]
fn the_examples_keep_the_default_campaign() {
    let mut n = 0;
    let machines = [
        "hexapod-linuxcnc.toml",
        "hexapod-seed001.toml",
        "pentapod-linuxcnc.toml",
        "tripod-seed000.toml",
        "tripod-centre-leg.toml",
        "kr30-dh.toml",
    ]
    .map(crate::common::example);
    for m in machines
        .iter()
        .chain([&crate::common::fixture("own-hexapod.toml")])
    {
        let s = match sized_experiment(m) {
            Err(Error::Unsupported { .. }) => continue,
            r => r.unwrap(),
        };
        n += 1;
        assert_eq!(s.sizing.scale, 1.0, "{}", m.source);
        assert_eq!(s.sizing.rotation_scale, 1.0, "{}", m.source);
        assert!(s.sizing.share >= SIZING_SHARE, "{}", m.source);
        assert_eq!(s.experiment, default_campaign(m));
        assert_eq!(
            s.fixture,
            fixture(m, DEFAULT_FIXTURE_SIZE).unwrap().description
        );
        assert_eq!(s.fixture_size, DEFAULT_FIXTURE_SIZE);
    }
    assert_eq!(n, 5, "hexapods x3, pentapod, translational tripod");
}

/// A 15 mm micro-hexapod: the default +-100 mm campaign cannot find its poses; the
/// sized one is 1/16 of it (a 12.5 mm fixture, +-6.25 mm, +-62.5 um deviations) and
/// identifies the machine down to the measurement noise.
#[test]
fn a_micro_hexapod_gets_a_campaign_of_its_size() {
    let m = crate::common::fixture("micro-hexapod.toml");
    let plain = default_campaign(&m);
    match calibration_study(&m, &plain, 20) {
        Err(Error::InvalidInput { message, .. }) => {
            assert!(message.contains("poses within the limits"), "{message}")
        }
        r => panic!("the default campaign should not fit: {r:?}"),
    }
    let s = sized_experiment(&m).unwrap();
    let k = s.sizing.scale;
    assert_eq!(k, 1.0 / 16.0, "{:?}", s.sizing);
    assert!(s.sizing.share >= SIZING_SHARE);
    let e = &s.experiment;
    assert_eq!(e.translation, 100.0 * k);
    assert_eq!(e.deviation, k);
    assert_eq!(e.step, 40.0 * k);
    assert_eq!(e.rotation, 10f64.to_radians() * s.sizing.rotation_scale);
    assert_eq!(s.fixture_size, DEFAULT_FIXTURE_SIZE * k);
    assert_eq!(e.fixture, fixture(&m, 12.5).unwrap().points);
    // The noise is the instrument's, not the machine's: unchanged.
    assert_eq!(e.point_noise, Experiment::default().point_noise);
    assert_eq!(e.length_noise, Experiment::default().length_noise);
    let st = calibration_study(&m, e, 20).unwrap();
    let id = &st.identification;
    // Residual at the noise level (5 um per coordinate), 10x below the nominal's.
    assert!(id.rms_after < 0.006, "{}", id.rms_after);
    assert!(
        id.rms_before > 10.0 * id.rms_after,
        "{} {}",
        id.rms_before,
        id.rms_after
    );
    // Held-out tool position: the identified model 5x better than the nominal one.
    assert!(
        st.identified.position_max < st.nominal.position_max / 5.0,
        "{:?} vs {:?}",
        st.identified,
        st.nominal
    );
}

/// A micro tripod (seed 000's / 20) at 1/8 of the default spans (+-12.5 mm, a 25 mm
/// fixture, +-125 um deviations): its random states reach the plane of its base joints,
/// where the three spheres of its forward kinematics meet at a grazing angle.
fn micro_tripod_edge_campaign(m: &pkm::machine::Machine, condition_ratio: f64) -> Experiment {
    let k = 1.0 / 8.0;
    let points = fixture(m, DEFAULT_FIXTURE_SIZE * k).unwrap().points;
    Experiment {
        condition_ratio,
        ..Experiment::default().scaled(k, 1.0, points)
    }
}

/// The micro tripod's fitted campaign: 1/16 of the default spans, where at least a
/// fifth of the random poses are within its limits and 4 times its home pose's
/// condition number (at 1/8 about 15 % of 20 000 are, 21 % of the first 256: the
/// sizing's 1024 draws keep it off that edge).
#[test]
fn a_micro_tripod_gets_a_campaign_of_its_size() {
    let m = crate::common::fixture("micro-tripod.toml");
    let s = sized_experiment(&m).unwrap();
    assert_eq!(s.sizing.scale, 1.0 / 16.0, "{:?}", s.sizing);
    assert!(s.sizing.share >= SIZING_SHARE);
    let st = calibration_study(&m, &s.experiment, 20).unwrap();
    assert_eq!((st.nominal_failed, st.identified_failed), (0, 0));
    // Identified to the noise (5 um per coordinate): held-out RMS within 10 um.
    assert!(st.identified.position_rms < 0.010, "{:?}", st.identified);
}

/// Random states nearer a singularity than [`Experiment::condition_ratio`] times the
/// home pose's condition number are drawn again: without the bound the micro tripod's
/// campaign at 1/8 of the default spans draws states of more than 20 times its home's
/// and identifies it to ~20-90 um; with it every state (campaign and held out) is
/// within the bound and the identified model is within 12 um RMS.
#[test]
fn random_states_keep_away_from_singularities() {
    use pkm::identify::simulate::{simulate, CONDITION_RATIO};
    use pkm::machine::Model;
    use pkm::Mechanism;
    let m = crate::common::fixture("micro-tripod.toml");
    let Model::TranslationalTripod(t) = &m.model else {
        panic!("a translational tripod")
    };
    let z = pkm::identify::Identifiable::zero_readings(t).unwrap();
    let ratios = |e: &Experiment| {
        let sim = simulate(t, &z, e).unwrap();
        let home = sim.truth.condition(&sim.truth.info().home()).unwrap();
        let r: Vec<f64> = sim
            .poses
            .iter()
            .map(|x| sim.truth.condition(x).unwrap() / home)
            .collect();
        r.iter().copied().fold(0.0, f64::max)
    };
    let (free, bound) = (
        micro_tripod_edge_campaign(&m, f64::INFINITY),
        micro_tripod_edge_campaign(&m, CONDITION_RATIO),
    );
    assert!(ratios(&free) > 20.0, "{}", ratios(&free));
    assert!(ratios(&bound) <= CONDITION_RATIO);
    let (a, b) = (
        calibration_study(&m, &free, 20).unwrap(),
        calibration_study(&m, &bound, 20).unwrap(),
    );
    assert!(a.identified.position_rms > 0.015, "{:?}", a.identified);
    assert!(b.identified.position_rms < 0.012, "{:?}", b.identified);
    assert_eq!(b.identified_failed, 0);
    // A bound no pose meets (below 1: none is better conditioned than 1/1000 of home)
    // refuses every pose within the limits, and the error says so.
    let none = Experiment {
        states: 5,
        condition_ratio: 1e-3,
        ..bound
    };
    match simulate(t, &z, &none) {
        Err(Error::InvalidInput { message, .. }) => assert!(
            message.contains("found only 0 poses within the limits in 5000 tries (")
                && message.contains("more within them refused beyond 0.001 times the home pose's")
                && message.ends_with("or raise the condition ratio"),
            "{message}"
        ),
        r => panic!("{:?}", r.map(|s| s.poses)),
    }
}

/// The micro tripod's campaign at 1/8 of the default spans without the condition bound:
/// held-out states at the edge of the true machine's workspace lie beyond the nominal
/// model's reach; they are counted and left out instead of failing the study, and the
/// model that reaches none of them fails naming its forward kinematics.
#[test]
fn held_out_states_beyond_a_models_reach_are_counted() {
    use pkm::identify::simulate::{pose_errors, simulate};
    use pkm::identify::Identifiable;
    use pkm::machine::Model;
    use pkm::Mechanism;
    let m = crate::common::fixture("micro-tripod.toml");
    let e = micro_tripod_edge_campaign(&m, f64::INFINITY);
    let st = calibration_study(&m, &e, 20).unwrap();
    assert!(
        st.nominal_failed > 0 && st.nominal_failed < 20,
        "{}",
        st.nominal_failed
    );
    assert!(st.identified_failed < 20);
    assert!(st.identified.position_rms < st.nominal.position_rms);
    // The same count by hand: forward kinematics of the nominal model per state.
    let Model::TranslationalTripod(t) = &m.model else {
        panic!("a translational tripod")
    };
    let sim = simulate(t, &t.zero_readings().unwrap(), &e).unwrap();
    let readings = sim.measurements.readings();
    let z = t.zero_readings().unwrap();
    let (_, failed) = pose_errors(t, &z, &readings, &sim.poses).unwrap();
    let by_hand = readings
        .iter()
        .zip(&sim.poses)
        .filter(|(r, x)| {
            let q = nalgebra::Vector3::from_fn(|j, _| z[j] + r[j]);
            t.forward(&q, x).is_err()
        })
        .count();
    assert!(by_hand > 0);
    assert_eq!(failed, by_hand);
    // No state reached (one strut 100 mm longer: its sphere misses the others'): the
    // forward kinematics' error.
    let far: Vec<Vec<f64>> = readings
        .iter()
        .map(|r| vec![r[0] + 100.0, r[1], r[2]])
        .collect();
    match pose_errors(t, &z, &far, &sim.poses) {
        Err(e) => assert!(e.to_string().contains("spheres"), "{e}"),
        r => panic!("{r:?}"),
    }
}

/// A giant hexapod (the micro one x200: struts 4.4-8.4 m): the default campaign
/// (+-100 mm) hardly turns its struts and leaves it not identifiable; the fitted one is
/// 8 times larger (within a fifth of the 6.55 m struts) and identifies it.
#[test]
fn a_giant_hexapod_gets_a_campaign_of_its_size() {
    use pkm::identify::simulate::SIZING_FRACTION;
    let m = crate::common::fixture("giant-hexapod.toml");
    let plain = default_campaign(&m);
    match calibration_study(&m, &plain, 20) {
        Err(Error::NotIdentifiable { combination, .. }) => {
            assert!(combination.contains("standard error"), "{combination}")
        }
        r => panic!("the default campaign should not identify it: {r:?}"),
    }
    let s = sized_experiment(&m).unwrap();
    let z = s.sizing;
    assert_eq!(z.scale, 8.0, "{z:?}");
    assert!((z.home_length - 6551.0).abs() < 1.0, "{z:?}");
    // The largest power of two within the fraction (the next doubling would pass it),
    // and the share kept.
    let t = Experiment::default().translation;
    assert!(t * z.scale <= SIZING_FRACTION * z.home_length);
    assert!(2.0 * t * z.scale > SIZING_FRACTION * z.home_length);
    assert!(z.share >= SIZING_SHARE);
    assert_eq!(s.experiment.translation, 800.0);
    assert_eq!(s.experiment.deviation, 8.0);
    assert_eq!(s.fixture_size, 1600.0);
    let st = calibration_study(&m, &s.experiment, 20).unwrap();
    assert!(st.identification.rms_after < 0.01);
    assert!(st.identified.position_max < st.nominal.position_max / 100.0);
}
