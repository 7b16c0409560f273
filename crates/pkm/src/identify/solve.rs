//! Levenberg-Marquardt over the residual equations, standard errors, and the
//! refusal of results the data cannot determine.

use levenberg_marquardt::LevenbergMarquardt;
use nalgebra::{DMatrix, DVector, SVector};

use super::identifiability::analyse;
use super::problem::Problem;
use super::*;
use crate::error::{Error, Result};

/// Identifies the parameters of `nominal` (geometry, then the actuators' zero readings
/// `zero`) from `meas`: Levenberg-Marquardt from the nominal values, with the
/// identifiability analysis. Fails with [`Error::NotIdentifiable`] naming the
/// combination when the free parameters are not all determined by the data (hold one
/// of its parameters, or measure states that move it), and with
/// [`Error::InvalidInput`] for inconsistent measurements.
pub fn identify<M: Identifiable<P, A>, const P: usize, const A: usize>(
    nominal: &M,
    zero: &SVector<f64, A>,
    meas: &Measurements,
    o: &Options,
) -> Result<Identification> {
    validate(nominal, meas, o)?;
    let names = parameter_names(nominal);
    let mut theta = nominal.geometry();
    theta.extend(zero.iter());
    let n = theta.len();
    let free: Vec<usize> = (0..n).filter(|i| !o.fixed.contains(i)).collect();
    let poses = match o.model {
        MeasurementModel::Pose => measured_poses(nominal, meas)?,
        MeasurementModel::Points => Vec::new(),
    };
    let mut problem = Problem {
        nominal,
        meas,
        model: o.model,
        poses,
        fk: warm_starts(nominal, zero, meas, o.model),
        theta: theta.clone(),
        free: free.clone(),
        eval: None,
    };
    problem.evaluate();
    let Some((r0, j0)) = problem.eval.clone() else {
        return Err(Error::InvalidInput {
            what: "identification".into(),
            message: "the nominal machine cannot reach the measured states".into(),
        });
    };
    let per_state = problem.rows_per_state();
    // Identifiability at the start: a rank-deficient problem is reported, not solved.
    let jf0 = problem.free_jacobian(&j0);
    let explain = |t: &[(usize, f64)]| nominal.explain(t);
    let (_, weak0) = analyse(&jf0, &free, &names, &explain);
    refuse_null(&weak0, o.rank_tolerance)?;
    let lm = LevenbergMarquardt::new()
        .with_ftol(1e-15)
        .with_xtol(1e-15)
        .with_gtol(1e-15)
        .with_patience(o.max_evaluations.div_ceil(n.max(1) + 1));
    let (problem, report) = lm.minimize(problem);
    let Some((r1, j1)) = problem.eval.clone() else {
        return Err(Error::NotConverged {
            solver: "identification (Levenberg-Marquardt)",
            iterations: report.number_of_evaluations,
            residual: f64::NAN,
        });
    };
    let jf = problem.free_jacobian(&j1);
    let (sv, weak) = analyse(&jf, &free, &names, &explain);
    let se = standard_errors(&jf, &r1, &free, n);
    let condition = sv.first().copied().unwrap_or(0.0) / sv.last().copied().unwrap_or(0.0);
    refuse_poorly_determined(&se, &sv, &weak, &names, o.max_standard_error)?;
    Ok(Identification {
        standard_errors_note: held_note(&names, &free, n),
        free: (0..n).map(|i| free.contains(&i)).collect(),
        names,
        start: theta,
        values: problem.theta.clone(),
        standard_errors: se,
        rms_before: rms(&r0),
        rms_after: rms(&r1),
        state_rms_before: state_rms(&r0, per_state),
        state_rms_after: state_rms(&r1, per_state),
        singular_values: sv,
        condition,
        weak,
        evaluations: report.number_of_evaluations,
        equations: r1.len(),
    })
}

/// Warm starts of the point model: the nominal machine's forward kinematics from home
/// at each state's readings (home where it fails); none for the pose model.
fn warm_starts<M: Identifiable<P, A>, const P: usize, const A: usize>(
    nominal: &M,
    zero: &SVector<f64, A>,
    meas: &Measurements,
    model: MeasurementModel,
) -> Vec<SVector<f64, P>> {
    match model {
        MeasurementModel::Points => meas
            .states
            .iter()
            .map(|st| {
                let q = SVector::<f64, A>::from_fn(|j, _| zero[j] + st.readings[j]);
                nominal
                    .forward(&q, &nominal.info().home())
                    .map(|f| f.pose)
                    .unwrap_or_else(|_| nominal.info().home())
            })
            .collect(),
        MeasurementModel::Pose => Vec::new(),
    }
}

/// The RMS of residuals `r`.
fn rms(r: &DVector<f64>) -> f64 {
    (r.norm_squared() / r.len().max(1) as f64).sqrt()
}

/// The RMS of residuals `r` per state (`per_state` rows each).
fn state_rms(r: &DVector<f64>, per_state: usize) -> Vec<f64> {
    r.as_slice()
        .chunks(per_state)
        .map(|c| (c.iter().map(|v| v * v).sum::<f64>() / c.len() as f64).sqrt())
        .collect()
}

/// Refuses a rank-deficient problem: the first combination in `weak` whose relative
/// singular value is below `tolerance`, and how many more there are.
fn refuse_null(weak: &[Combination], tolerance: f64) -> Result<()> {
    let null: Vec<&Combination> = weak
        .iter()
        .filter(|w| w.relative_singular_value < tolerance)
        .collect();
    let Some(w) = null.first() else {
        return Ok(());
    };
    let more = if null.len() > 1 {
        format!(" (and {} more such combinations)", null.len() - 1)
    } else {
        String::new()
    };
    Err(Error::NotIdentifiable {
        combination: format!("{}{more}", w.description),
        relative_singular_value: w.relative_singular_value,
    })
}

/// Standard errors of the `n` parameters (0 for the held ones) from the free
/// parameters' Jacobian `jf` and residuals `r`: `s^2 (J^T J)^-1`, `s^2 = |r|^2 / (m - n)`.
fn standard_errors(jf: &DMatrix<f64>, r: &DVector<f64>, free: &[usize], n: usize) -> Vec<f64> {
    let dof = (r.len() as f64 - free.len() as f64).max(1.0);
    let s2 = r.norm_squared() / dof;
    let jtj = jf.transpose() * jf;
    let cov = jtj
        .clone()
        .try_inverse()
        .or_else(|| jtj.pseudo_inverse(1e-300).ok());
    let mut se = vec![0.0; n];
    if let Some(c) = cov {
        for (k, &i) in free.iter().enumerate() {
            se[i] = (s2 * c[(k, k)].max(0.0)).sqrt();
        }
    }
    se
}

/// Refuses a result whose largest standard error `se` is beyond `max`, naming the
/// weakest combination (`weak`, singular values `sv`) or the parameter.
fn refuse_poorly_determined(
    se: &[f64],
    sv: &[f64],
    weak: &[Combination],
    names: &[String],
    max: f64,
) -> Result<()> {
    let (mut worst, mut worst_se) = (0, 0.0);
    for (i, &v) in se.iter().enumerate() {
        if v > worst_se {
            (worst, worst_se) = (i, v);
        }
    }
    if !(worst_se > max) {
        return Ok(());
    }
    let (what, rel) = match weak.first() {
        Some(w) => (w.description.clone(), w.relative_singular_value),
        None => (
            format!("`{}` is poorly determined by these states", names[worst]),
            sv.last().copied().unwrap_or(0.0) / sv.first().copied().unwrap_or(1.0),
        ),
    };
    Err(Error::NotIdentifiable {
        combination: format!(
            "{what}; with this data the standard error of `{}` is {worst_se:.3} (limit {max})",
            names[worst]
        ),
        relative_singular_value: rel,
    })
}

/// The note that the standard errors hold only if the held parameters (all but
/// `free` of the `n`) are exact, when any is held.
fn held_note(names: &[String], free: &[usize], n: usize) -> Option<String> {
    let held: Vec<&str> = (0..n)
        .filter(|i| !free.contains(i))
        .map(|i| names[i].as_str())
        .collect();
    (!held.is_empty()).then(|| {
        let list = if held.len() <= 6 {
            held.join(", ")
        } else {
            format!("{}, ... ({} in all)", held[..6].join(", "), held.len())
        };
        format!(
            "the standard errors are conditional on the held parameters ({list}) being \
             exactly their nominal values: an error in a held value moves the identified \
             parameters without showing in their standard errors"
        )
    })
}

/// Refuses options and measurements that cannot be identified from: a held
/// parameter that does not exist, too few fixture points, states of the wrong size,
/// fewer equations than free parameters.
fn validate<M: Identifiable<P, A>, const P: usize, const A: usize>(
    m: &M,
    meas: &Measurements,
    o: &Options,
) -> Result<()> {
    let bad = |message: String| Error::InvalidInput {
        what: "measurements".into(),
        message,
    };
    let n = m.geometry().len() + A;
    if let Some(i) = o.fixed.iter().find(|&&i| i >= n) {
        return Err(bad(format!(
            "fixed parameter {i} does not exist ({n} parameters)"
        )));
    }
    m.check_fixture(&meas.fixture)?;
    let need = match o.model {
        MeasurementModel::Pose => m.pose_points(),
        MeasurementModel::Points => 1,
    };
    if meas.fixture.len() < need {
        return Err(bad(format!(
            "the {:?} model needs at least {need} fixture points, the file gives {}",
            o.model,
            meas.fixture.len()
        )));
    }
    for (i, st) in meas.states.iter().enumerate() {
        if st.readings.len() != A || st.points.len() != meas.fixture.len() {
            return Err(bad(format!(
                "state {}: expected {A} readings and {} points, found {} and {}",
                i + 1,
                meas.fixture.len(),
                st.readings.len(),
                st.points.len()
            )));
        }
    }
    // A parameter held twice is held once.
    let held = (0..n).filter(|i| o.fixed.contains(i)).count();
    let free = n - held;
    if free == 0 {
        return Err(Error::InvalidInput {
            what: "fixed parameters".into(),
            message: format!("nothing to identify: all {n} parameters are held"),
        });
    }
    let per_state = match o.model {
        MeasurementModel::Pose => A,
        MeasurementModel::Points => 3 * meas.fixture.len(),
    };
    if meas.states.len() * per_state < free {
        return Err(bad(format!(
            "{} states give {} equations for {free} free parameters",
            meas.states.len(),
            meas.states.len() * per_state
        )));
    }
    Ok(())
}
