//! `pkm calibrate`: the machine's parameters identified from a measurement campaign,
//! written as a machine file with the report of the fit.

use anyhow::{Context, Result};
use pkm::analysis::identification::{
    calibrate, identified_machine_file, parse_measurements, CalibrateOptions, Calibration,
    Validation,
};
use pkm::identify::hexapod::SeedProcedure;
use pkm::identify::{self, Identification, Measurements};
use serde_json::json;
use std::path::Path;

use super::super::load;
use super::{read, CalibrateArgs};
use crate::io::write_atomic;
use crate::out::{outln, Printed};
use crate::report::plot::{panels_svg_x, Series};

fn read_measurements(path: &Path, machine: &pkm::Machine) -> Result<Measurements> {
    Ok(parse_measurements(
        machine,
        &read(path)?,
        &path.display().to_string(),
    )?)
}

pub fn calibrate_run(a: &CalibrateArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    // Refuse a machine that cannot be identified before reading the campaign.
    machine.supports(pkm::machine::Analysis::Identification)?;
    let meas = read_measurements(&a.measurements, &machine)?;
    let validation = match &a.validation {
        Some(p) => Some(read_measurements(p, &machine)?),
        None => None,
    };
    let opt = options(a)?;
    let text = read(&a.machine)?;
    let c = fit(&machine, &meas, validation.as_ref(), &opt)?;
    // The comment's residuals are known after the fit: identify, then head the file.
    let head = format!(
        "Identified by pkm calibrate from {} ({} states, {} model{}): residual RMS {:.4} -> {:.4} mm",
        a.measurements.display(),
        meas.states.len(),
        a.model,
        if a.seed_procedure { ", seed 001 procedure" } else { "" },
        c.identification.rms_before,
        c.identification.rms_after
    );
    let toml = identified_machine_file(&machine, &text, &c, &head)?;
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let inputs = [a.machine.as_path(), a.measurements.as_path()];
    write_atomic(&a.out.join("identified.toml"), toml.as_bytes(), &inputs)?;
    let report = report_json(
        &c.identification,
        &c.values,
        c.seed_procedure.as_ref(),
        c.validation.as_ref(),
    );
    write_atomic(
        &a.out.join("report.json"),
        serde_json::to_string_pretty(&report)?.as_bytes(),
        &inputs,
    )?;
    plots(&a.out, &c.identification, &inputs)?;
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        print_text(
            machine.mechanism().name(),
            &c.identification,
            c.seed_procedure.as_ref(),
            c.validation.as_ref(),
            &a.out,
        )?;
    }
    Ok(0)
}

/// The fit's options: the measurement model, the parameters held, the procedure.
fn options(a: &CalibrateArgs) -> Result<CalibrateOptions> {
    let model: identify::MeasurementModel = a.model.parse().context("--model")?;
    Ok(CalibrateOptions {
        model,
        fix: a
            .fix
            .as_deref()
            .map(|l| l.split(',').map(String::from).collect())
            .unwrap_or_default(),
        seed_procedure: a.seed_procedure,
    })
}

/// The identification, with a spinner while it runs.
fn fit(
    machine: &pkm::Machine,
    meas: &Measurements,
    validation: Option<&Measurements>,
    opt: &CalibrateOptions,
) -> Result<Calibration> {
    let spin = crate::progress::spinner(
        true,
        &format!(
            "{{spinner}} identifying the parameters from {} states {{elapsed}}",
            meas.states.len()
        ),
    );
    let c = calibrate(machine, meas, validation, opt);
    if let Some(s) = spin {
        s.finish_and_clear();
    }
    Ok(c?)
}

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
        "standard_errors_note": id.standard_errors_note,
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
        "validation": validation.map(|v| json!({
            "states": v.states,
            "nominal": v.nominal,
            "identified": v.identified,
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
                "RMS [µm]".into(),
                vec![per_state(&id.state_rms_before)],
            ),
            (
                "identified parameters".into(),
                "RMS [µm]".into(),
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
) -> Printed {
    outln!(
        "{name}: {} parameters from {} equations",
        id.names.len(),
        id.equations
    )?;
    outln!(
        "residual RMS     {:.4} mm (nominal) -> {:.4} mm (identified), {} evaluations",
        id.rms_before,
        id.rms_after,
        id.evaluations
    )?;
    outln!(
        "condition        {:.3e} (scaled identification Jacobian)",
        id.condition
    )?;
    print_changes(id)?;
    if let Some(note) = &id.standard_errors_note {
        outln!("note             {note}")?;
    }
    for w in &id.weak {
        outln!("weak             {}", w.description)?;
    }
    if let Some(s) = seed {
        outln!(
            "seed procedure   per-strut condition {}",
            s.conditions
                .iter()
                .map(|c| format!("{c:.2e}"))
                .collect::<Vec<_>>()
                .join(", ")
        )?;
    }
    if let Some(v) = validation {
        print_validation(v)?;
    }
    outln!("wrote {}", out.display())?;
    Ok(())
}

/// The six largest parameter changes with their standard errors.
fn print_changes(id: &Identification) -> Printed {
    let mut order: Vec<usize> = (0..id.names.len()).collect();
    order.sort_by(|&a, &b| {
        (id.values[b] - id.start[b])
            .abs()
            .total_cmp(&(id.values[a] - id.start[a]).abs())
    });
    let shown = &order[..order.len().min(6)];
    let w = shown.iter().map(|&i| id.names[i].len()).max().unwrap_or(0);
    for &i in shown {
        outln!(
            "  largest change {:<w$} {:+.4} mm  (standard error {:.4} mm)",
            id.names[i],
            id.values[i] - id.start[i],
            id.standard_errors[i]
        )?;
    }
    Ok(())
}

/// The point (and tool pose) errors of both models at the held-out states.
fn print_validation(v: &Validation) -> Printed {
    let Validation {
        states: n,
        nominal: b,
        identified: a,
    } = v;
    outln!(
        "validation       {n} states: point error max {:.4} / RMS {:.4} mm (nominal) -> max {:.4} / RMS {:.4} mm (identified)",
        b.max, b.rms, a.max, a.rms
    )?;
    if let (Some(pb), Some(pa)) = (b.pose, a.pose) {
        outln!(
            "                 tool pose: position max {:.4} / RMS {:.4} mm, orientation max {:.2e} deg (nominal) -> position max {:.4} / RMS {:.4} mm, orientation max {:.2e} deg (identified)",
            pb.position_max, pb.position_rms, pb.orientation_max.to_degrees(), pa.position_max, pa.position_rms, pa.orientation_max.to_degrees()
        )?;
    }
    Ok(())
}
