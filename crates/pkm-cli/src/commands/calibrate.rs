//! `pkm simulate-measurements` and `pkm calibrate`: identification of a machine's
//! geometric parameters (seed 001) from a measurement campaign, real or simulated.

use std::path::Path;

use anyhow::{bail, Context, Result};
use nalgebra::SVector;
use pkm::identify::hexapod::{seed_procedure, SeedProcedure};
use pkm::identify::simulate::{simulate, triangle, Design, Experiment};
use pkm::identify::struts::StrutMachine;
use pkm::identify::{self, Identifiable, Identification, Measurements, Model};
use pkm::machine::Model as MachineModel;
use serde_json::json;

use super::load;
use crate::io::write_atomic;
use crate::report::plot::{panels_svg_x, Series};
use crate::{CalibrateArgs, SimulateArgs};

/// What identification covers, with a message for the rest.
fn unsupported(m: &pkm::Machine, path: &Path) -> anyhow::Error {
    anyhow::anyhow!(
        "{}: identification is implemented for hexapods (the 42 parameters of seed 001) and \
         translational tripods; this is a {} machine",
        path.display(),
        m.kind()
    )
}

pub fn simulate_run(a: &SimulateArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    match &machine.model {
        MachineModel::Hexapod(h) => simulate_machine(a, h.as_ref()),
        MachineModel::TranslationalTripod(t) => simulate_machine(a, t),
        _ => Err(unsupported(&machine, &a.machine)),
    }
}

fn simulate_machine<M: StrutMachine<A>, const A: usize>(a: &SimulateArgs, h: &M) -> Result<u8> {
    let zero = h.zero_readings()?;
    let design = match a.design.as_str() {
        "random" => Design::Random,
        "one-strut" => Design::OneActuator,
        d => bail!("--design: expected `random` or `one-strut`, found `{d}`"),
    };
    if a.states == 0 {
        bail!("--states: expected at least one state");
    }
    let e = Experiment {
        deviation: a.deviation,
        point_noise: a.point_noise,
        length_noise: a.length_noise,
        states: a.states + a.holdout,
        design,
        translation: a.translation,
        rotation: a.rotation.to_radians(),
        step: a.step,
        fixture: triangle(a.fixture_radius, 0.0),
        seed: a.seed,
    };
    let s = simulate(h, &zero, &e)?;
    let acts = h.actuators();
    let (used, held) = s.measurements.states.split_at(a.states);
    let part = |states: &[pkm::identify::State]| Measurements {
        fixture: s.measurements.fixture.clone(),
        states: states.to_vec(),
    };
    let comment = format!(
        "simulated by pkm simulate-measurements on {} (seed {}): deviations +-{} mm, point \
         noise {} mm, reading noise {} mm, {} design\nthe fixture is an equilateral triangle of \
         circumradius {} mm on the platform",
        a.machine.display(),
        a.seed,
        a.deviation,
        a.point_noise,
        a.length_noise,
        a.design,
        a.fixture_radius
    );
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let inputs = [a.machine.as_path()];
    write_atomic(
        &a.out.join("measurements.csv"),
        identify::csv::write(&part(used), acts, &comment).as_bytes(),
        &inputs,
    )?;
    if a.holdout > 0 {
        write_atomic(
            &a.out.join("validation.csv"),
            identify::csv::write(&part(held), acts, &format!("{comment}\nheld-out states"))
                .as_bytes(),
            &inputs,
        )?;
    }
    let text = std::fs::read_to_string(&a.machine)?;
    let toml = pkm::machine::with_strut_geometry(
        &text,
        &a.machine.display().to_string(),
        &s.truth.struts(),
        Some(s.true_zero.as_slice()),
        &format!("The TRUE machine of a simulated experiment ({comment})"),
    )?;
    write_atomic(&a.out.join("true.toml"), toml.as_bytes(), &inputs)?;
    let mut theta = s.truth.geometry();
    theta.extend(s.true_zero.iter());
    let names = identify::parameter_names(h);
    let summary = json!({
        "machine": a.machine.display().to_string(),
        "states": a.states,
        "holdout": a.holdout,
        "true_parameters": names.iter().zip(&theta).map(|(n, v)| (n.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "true_poses": s.poses.iter().map(|x| x.iter().copied().collect::<Vec<f64>>()).collect::<Vec<_>>(),
    });
    write_atomic(
        &a.out.join("truth.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
        &inputs,
    )?;
    println!(
        "{}: {} states (+{} held out) on a true machine {} mm off nominal; wrote {}",
        h.name(),
        a.states,
        a.holdout,
        a.deviation,
        a.out.display()
    );
    Ok(0)
}

fn read_measurements<M: Identifiable<P, A>, const P: usize, const A: usize>(
    path: &Path,
    h: &M,
) -> Result<Measurements> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    Ok(identify::csv::parse(
        &text,
        &path.display().to_string(),
        h.actuators(),
    )?)
}

pub fn calibrate_run(a: &CalibrateArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    match &machine.model {
        MachineModel::Hexapod(h) => calibrate_machine(a, h.as_ref()),
        MachineModel::TranslationalTripod(t) => calibrate_machine(a, t),
        _ => Err(unsupported(&machine, &a.machine)),
    }
}

/// Whether `name` matches `pattern` (`*` matches any run of characters).
fn glob(pattern: &str, name: &str) -> bool {
    let parts: Vec<&str> = pattern.split('*').collect();
    if parts.len() == 1 {
        return pattern == name;
    }
    let mut rest = name;
    for (i, p) in parts.iter().enumerate() {
        if i == 0 {
            let Some(r) = rest.strip_prefix(p) else {
                return false;
            };
            rest = r;
        } else if i == parts.len() - 1 {
            return rest.ends_with(p);
        } else {
            let Some(k) = rest.find(p) else { return false };
            rest = &rest[k + p.len()..];
        }
    }
    true
}

fn calibrate_machine<M: StrutMachine<A>, const A: usize>(a: &CalibrateArgs, h: &M) -> Result<u8> {
    let zero = h.zero_readings()?;
    let meas = read_measurements(&a.measurements, h)?;
    let names = identify::parameter_names(h);
    let mut fixed = Vec::new();
    if let Some(list) = &a.fix {
        for n in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            let hits: Vec<usize> = (0..names.len()).filter(|&i| glob(n, &names[i])).collect();
            if hits.is_empty() {
                bail!(
                    "--fix: no parameter matches `{n}`; the parameters are {}",
                    names.join(", ")
                );
            }
            fixed.extend(hits);
        }
    }
    let model = match a.model.as_str() {
        "pose" => Model::Pose,
        "points" => Model::Points,
        m => bail!("--model: expected `pose` or `points`, found `{m}`"),
    };
    let o = identify::Options {
        model,
        fixed,
        ..Default::default()
    };
    let id = identify::identify(h, &zero, &meas, &o)?;
    let seed = if a.seed_procedure {
        Some(seed_procedure(h, &zero, &meas)?)
    } else {
        None
    };
    let values = seed
        .as_ref()
        .map(|s| s.values.clone())
        .unwrap_or(id.values.clone());
    let ng = values.len() - A;
    let identified = h.with_geometry(&values[..ng])?;
    let z = SVector::<f64, A>::from_column_slice(&values[ng..]);
    let validation = match &a.validation {
        Some(p) => {
            let v = read_measurements(p, h)?;
            let before = identify::point_errors(h, &zero, &v);
            let after = identify::point_errors(&identified, &z, &v);
            Some((v.states.len(), before, after))
        }
        None => None,
    };
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let inputs = [a.machine.as_path(), a.measurements.as_path()];
    let text = std::fs::read_to_string(&a.machine)?;
    let toml = pkm::machine::with_strut_geometry(
        &text,
        &a.machine.display().to_string(),
        &identified.struts(),
        Some(z.as_slice()),
        &format!(
            "Identified by pkm calibrate from {} ({} states, {} model{}): residual RMS {:.4} -> {:.4} mm",
            a.measurements.display(),
            meas.states.len(),
            a.model,
            if a.seed_procedure { ", seed 001 procedure" } else { "" },
            id.rms_before,
            id.rms_after
        ),
    )?;
    write_atomic(&a.out.join("identified.toml"), toml.as_bytes(), &inputs)?;
    let report = report_json(&id, &values, seed.as_ref(), validation.as_ref());
    write_atomic(
        &a.out.join("report.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
        &inputs,
    )?;
    plots(&a.out, &id, &inputs)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_text(h.name(), &id, seed.as_ref(), validation.as_ref(), &a.out);
    }
    Ok(0)
}

type Validation = (usize, identify::PointErrors, identify::PointErrors);

fn report_json(
    id: &Identification,
    values: &[f64],
    seed: Option<&SeedProcedure>,
    validation: Option<&Validation>,
) -> serde_json::Value {
    let params: Vec<_> = (0..id.names.len())
        .map(|i| {
            json!({
                "name": id.names[i],
                "nominal": id.start[i],
                "identified": values[i],
                "change": values[i] - id.start[i],
                "standard_error": id.standard_errors[i],
                "free": id.free[i],
            })
        })
        .collect();
    json!({
        "parameters": params,
        "equations": id.equations,
        "residual_rms_before": id.rms_before,
        "residual_rms_after": id.rms_after,
        "state_rms_before": id.state_rms_before,
        "state_rms_after": id.state_rms_after,
        "singular_values": id.singular_values,
        "condition_number": id.condition,
        "unidentifiable": id.weak.iter().map(|w| json!({
            "relative_singular_value": w.relative_singular_value,
            "combination": w.terms.iter().map(|(n, c)| json!([n, c])).collect::<Vec<_>>(),
            "description": w.description,
        })).collect::<Vec<_>>(),
        "evaluations": id.evaluations,
        "seed_procedure": seed.map(|s| json!({
            "used_for_identified_toml": true,
            "conditions": s.conditions,
            "iterations": s.iterations,
        })),
        "validation": validation.map(|(n, b, a)| json!({
            "states": n,
            "nominal": b,
            "identified": a,
        })),
    })
}

fn plots(out: &Path, id: &Identification, inputs: &[&Path]) -> Result<()> {
    let (residuals, singular) = plot_svgs(id)?;
    write_atomic(&out.join("residuals.svg"), residuals.as_bytes(), inputs)?;
    write_atomic(
        &out.join("singular-values.svg"),
        singular.as_bytes(),
        inputs,
    )?;
    Ok(())
}

/// The residuals per state (nominal, identified) and the singular values, as SVG.
pub fn plot_svgs(id: &Identification) -> Result<(String, String)> {
    let per_state = |v: &[f64]| Series {
        name: "RMS".into(),
        points: v
            .iter()
            .enumerate()
            .map(|(i, r)| ((i + 1) as f64, 1000.0 * r))
            .collect(),
    };
    let residuals = panels_svg_x(
        "residuals per measured state",
        "state",
        &[
            (
                "nominal parameters".into(),
                "RMS [um]".into(),
                vec![per_state(&id.state_rms_before)],
            ),
            (
                "identified parameters".into(),
                "RMS [um]".into(),
                vec![per_state(&id.state_rms_after)],
            ),
        ],
        (760, 520),
    )?;
    let top = id
        .singular_values
        .first()
        .copied()
        .unwrap_or(1.0)
        .max(1e-300);
    let sv = Series {
        name: "log10(s / s_max)".into(),
        points: id
            .singular_values
            .iter()
            .enumerate()
            .map(|(i, s)| ((i + 1) as f64, (s / top).max(1e-17).log10()))
            .collect(),
    };
    let singular = panels_svg_x(
        &format!(
            "singular values of the scaled identification Jacobian (condition {:.3e})",
            id.condition
        ),
        "index (largest first)",
        &[("".into(), "log10(s / s_max)".into(), vec![sv])],
        (760, 360),
    )?;
    Ok((residuals, singular))
}

fn print_text(
    name: &str,
    id: &Identification,
    seed: Option<&SeedProcedure>,
    validation: Option<&Validation>,
    out: &Path,
) {
    println!(
        "{name}: {} parameters from {} equations",
        id.names.len(),
        id.equations
    );
    println!(
        "residual RMS     {:.4} mm (nominal) -> {:.4} mm (identified), {} evaluations",
        id.rms_before, id.rms_after, id.evaluations
    );
    println!(
        "condition        {:.3e} (scaled identification Jacobian)",
        id.condition
    );
    let mut order: Vec<usize> = (0..id.names.len()).collect();
    order.sort_by(|&a, &b| {
        (id.values[b] - id.start[b])
            .abs()
            .total_cmp(&(id.values[a] - id.start[a]).abs())
    });
    for &i in order.iter().take(6) {
        println!(
            "  largest change {:<12} {:+.4} mm  (standard error {:.4} mm)",
            id.names[i],
            id.values[i] - id.start[i],
            id.standard_errors[i]
        );
    }
    for w in &id.weak {
        println!("weak             {}", w.description);
    }
    if let Some(s) = seed {
        println!(
            "seed procedure   per-strut condition {}",
            s.conditions
                .iter()
                .map(|c| format!("{c:.2e}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if let Some((n, b, a)) = validation {
        println!(
            "validation       {n} states: point error max {:.4} / RMS {:.4} mm (nominal) -> max {:.4} / RMS {:.4} mm (identified)",
            b.max, b.rms, a.max, a.rms
        );
        if let (Some(pb), Some(pa)) = (b.pose, a.pose) {
            println!(
                "                 tool pose: position max {:.4} / RMS {:.4} mm, orientation max {:.2e} rad (nominal) -> position max {:.4} / RMS {:.4} mm, orientation max {:.2e} rad (identified)",
                pb.position_max, pb.position_rms, pb.orientation_max, pa.position_max, pa.position_rms, pa.orientation_max
            );
        }
    }
    println!("wrote {}", out.display());
}
