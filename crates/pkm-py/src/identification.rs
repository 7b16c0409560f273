//! Identification (seed 001): `pkm.simulate_measurements` and `pkm.calibrate`, on
//! `pkm::analysis::identification`. Measurements travel as the CSV text pkm reads and
//! writes (`pkm calibrate --measurements`), so a campaign can be saved, edited or
//! replaced by a real one.

use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{self, vec1};
use crate::errors::{invalid, to_py};
use crate::machine::Machine;

/// The text of a measurement CSV given as text or as a path.
fn csv_text(v: &Bound<'_, PyAny>, what: &str) -> PyResult<(String, String)> {
    if let Ok(s) = v.extract::<String>() {
        return Ok((s, format!("<{what}>")));
    }
    let f: std::path::PathBuf = v
        .extract()
        .map_err(|_| invalid(what, "expected the CSV's text or a path"))?;
    let text = std::fs::read_to_string(&f)
        .map_err(|e| invalid(what, format!("cannot read {}: {e}", f.display())))?;
    Ok((text, f.display().to_string()))
}

/// Simulates a measurement campaign on a machine (pkm simulate-measurements): a true
/// machine drawn around the nominal one, `states` poses measured with noise.
///
/// `deviation` (mm): half-width of the uniform deviations of every joint coordinate
/// and zero reading; `point_noise`, `length_noise` (mm): standard deviations of the
/// measured points and readings; `design`: `random` (poses within `translation` mm
/// and `rotation` rad of home, within every limit and `condition_ratio` times the home
/// pose's condition number, default 4) or `one-strut` (seed 001: one more strut changed
/// by `step` mm per state); `fixture_radius` (mm): the fixture's size
/// (a strut machine's triangle's circumradius, a pentapod's two points on its axis
/// apart); `holdout`: further states for validation. Left out, they are
/// `pkm simulate-measurements`' defaults fitted to the machine (1 mm, 100 mm, 10 deg,
/// 40 mm, 200 mm, halved on a machine where fewer than a fifth of such random poses
/// are within its limits and the condition bound, doubled on one whose struts average
/// more than 1 m).
///
/// Returns a dict: `measurements` and `validation` (CSV text for `calibrate`),
/// `names` and `true_parameters` (array), `true_poses` ((states, 6) array, mm and
/// rad), `true_machine` (the true machine file's text, when the machine came from
/// TOML).
#[pyfunction]
#[pyo3(signature = (machine, *, states = None, holdout = 0, deviation = None,
    point_noise = None, length_noise = None, design = "random", translation = None,
    rotation = None, condition_ratio = None, step = None, fixture_radius = None, seed = 1))]
#[allow(clippy::too_many_arguments)]
pub fn simulate_measurements<'py>(
    py: Python<'py>,
    machine: &Machine,
    states: Option<usize>,
    holdout: usize,
    deviation: Option<f64>,
    point_noise: Option<f64>,
    length_noise: Option<f64>,
    design: &str,
    translation: Option<f64>,
    rotation: Option<f64>,
    condition_ratio: Option<f64>,
    step: Option<f64>,
    fixture_radius: Option<f64>,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    use pkm::analysis::identification::{parse_design, SimulateOptions};
    // The defaults fitted to the machine, as `pkm simulate-measurements`'.
    let mut e = pkm::analysis::identification::sized_experiment(&machine.inner)
        .map_err(to_py)?
        .experiment;
    set_non_negative(&mut e.deviation, deviation, "deviation")?;
    set_non_negative(&mut e.point_noise, point_noise, "point_noise")?;
    set_non_negative(&mut e.length_noise, length_noise, "length_noise")?;
    set_non_negative(&mut e.translation, translation, "translation")?;
    set_non_negative(&mut e.rotation, rotation, "rotation")?;
    set_non_negative(&mut e.step, step, "step")?;
    // Checked (>= 1, inf allowed) by the library.
    if let Some(r) = condition_ratio {
        e.condition_ratio = r;
    }
    if let Some(r) = fixture_radius {
        if !(r > 0.0 && r.is_finite()) {
            return Err(invalid("fixture_radius", "expected a positive number"));
        }
        e.fixture = pkm::analysis::identification::fixture(&machine.inner, r)
            .map_err(to_py)?
            .points;
    }
    e.states = states.unwrap_or(e.states);
    e.design = parse_design(design).map_err(to_py)?;
    e.seed = seed;
    let opt = SimulateOptions {
        experiment: e,
        holdout,
        comment: format!("simulated by pkm.simulate_measurements (seed {seed})"),
    };
    let inner = machine.inner.clone();
    let text = machine.text.clone();
    let s = py
        .detach(|| {
            pkm::analysis::identification::simulate_measurements(&inner, text.as_deref(), &opt)
        })
        .map_err(to_py)?;
    simulation_dict(py, &inner, s, &opt.comment)
}

/// `*dst = v` when given, a number `>= 0`.
fn set_non_negative(dst: &mut f64, v: Option<f64>, what: &str) -> PyResult<()> {
    if let Some(x) = v {
        if !(x >= 0.0 && x.is_finite()) {
            return Err(invalid(what, format!("expected a number >= 0, got {x}")));
        }
        *dst = x;
    }
    Ok(())
}

/// The simulated campaign `s` on `inner` as `simulate_measurements` returns it, its
/// CSV texts headed by `comment`.
fn simulation_dict<'py>(
    py: Python<'py>,
    inner: &pkm::Machine,
    s: pkm::analysis::identification::SimulatedCampaign,
    comment: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let write = |m: &pkm::identify::Measurements| {
        pkm::analysis::identification::write_measurements(inner, m, comment)
    };
    let d = PyDict::new(py);
    d.set_item("measurements", write(&s.measurements))?;
    d.set_item(
        "validation",
        (!s.validation.states.is_empty()).then(|| write(&s.validation)),
    )?;
    d.set_item("names", s.names)?;
    d.set_item("true_parameters", vec1(py, s.true_parameters))?;
    let flat: Vec<f64> = s.true_poses.iter().flatten().copied().collect();
    d.set_item("true_poses", convert::vec2(py, flat, 6)?)?;
    d.set_item("true_machine", s.true_machine_file)?;
    Ok(d)
}

/// Identifies a machine's geometric parameters from measurements (pkm calibrate):
/// Levenberg-Marquardt on the measurement equations, with standard errors and
/// identifiability, validated on held-out states when given.
///
/// `measurements`, `validation`: a measurement CSV's text or path (as
/// `simulate_measurements` returns and `pkm calibrate` reads); `model`: `pose` (full
/// pose per state from the fixture points: 3 on a platform, 2 on a pentapod's axis)
/// or `points`; `fix`: parameter names held at nominal (`*` matches any run of
/// characters: `A1.z`, `B*.z`); `seed_procedure`: take seed 001's procedure's solution.
///
/// Returns a dict: `identification` (names, values, standard errors, residuals,
/// identifiability), `values`, `validation`, `seed_procedure`, `identified_toml`
/// (the identified machine file, when the machine came from TOML) and `machine`
/// (the identified `pkm.Machine`).
#[pyfunction]
#[pyo3(signature = (machine, measurements, *, validation = None, model = "pose",
    fix = Vec::new(), seed_procedure = false))]
pub fn calibrate<'py>(
    py: Python<'py>,
    machine: &Machine,
    measurements: &Bound<'py, PyAny>,
    validation: Option<&Bound<'py, PyAny>>,
    model: &str,
    fix: Vec<String>,
    seed_procedure: bool,
) -> PyResult<Bound<'py, PyDict>> {
    use pkm::analysis::identification::{
        calibrate, identified_machine_file, parse_measurements, CalibrateOptions,
    };
    let inner = machine.inner.clone();
    let (text, file) = csv_text(measurements, "measurements")?;
    let meas = parse_measurements(&inner, &text, &file).map_err(to_py)?;
    let val = match validation {
        Some(v) => {
            let (t, f) = csv_text(v, "validation")?;
            Some(parse_measurements(&inner, &t, &f).map_err(to_py)?)
        }
        None => None,
    };
    let opt = CalibrateOptions {
        model: model.parse().map_err(to_py)?,
        fix,
        seed_procedure,
    };
    let c = py
        .detach(|| calibrate(&inner, &meas, val.as_ref(), &opt))
        .map_err(to_py)?;
    let d = convert::to_py(py, &c)?.cast_into::<PyDict>()?;
    let (toml, identified) = match &machine.text {
        Some(src) => {
            let t = identified_machine_file(&inner, src, &c, "identified by pkm.calibrate")
                .map_err(to_py)?;
            let m = pkm::Machine::from_toml_str(&t, "<identified>").map_err(to_py)?;
            (Some(t.clone()), Some(Machine::new(m, Some(t))))
        }
        None => (None, None),
    };
    d.set_item("identified_toml", toml)?;
    d.set_item("machine", identified)?;
    Ok(d)
}
