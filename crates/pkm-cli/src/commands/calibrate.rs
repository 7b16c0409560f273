//! `pkm simulate-measurements` and `pkm calibrate`: identification of a machine's
//! geometric parameters (seed 001) from a measurement campaign, real or simulated
//! (`pkm::analysis::identification`).

use clap::Args;
use std::path::Path;
use std::path::PathBuf;

use anyhow::{Context, Result};
use pkm::analysis::identification::{
    self, calibrate, identified_machine_file, parse_design, parse_measurements,
    simulate_measurements, write_measurements, CalibrateOptions, Calibration, SimulateOptions,
    Validation,
};
use pkm::identify::hexapod::SeedProcedure;
use pkm::identify::simulate::Experiment;
use pkm::identify::{self, Identification, Measurements};
use serde_json::json;

use super::load;
use crate::io::write_atomic;
use crate::report::plot::{panels_svg_x, Series};

#[derive(Args)]
pub struct SimulateArgs {
    /// Machine file (TOML, type = "hexapod"): the nominal machine.
    pub machine: PathBuf,
    /// Half-width of the uniform deviations of every joint coordinate and zero length of
    /// the true machine (mm) [default: 1, times the campaign's scale].
    #[arg(long)]
    pub deviation: Option<f64>,
    /// Standard deviation of the measured point coordinates (mm).
    #[arg(long, default_value_t = 0.005)]
    pub point_noise: f64,
    /// Standard deviation of the strut length readings (mm).
    #[arg(long, default_value_t = 0.001)]
    pub length_noise: f64,
    /// Number of states for identification.
    #[arg(long, default_value_t = 50)]
    pub states: usize,
    /// Further states on the same true machine, written to validation.csv.
    #[arg(long, default_value_t = 0)]
    pub holdout: usize,
    /// `random` (poses around home within every limit) or `one-strut` (seed 001: the
    /// zero state, then one more strut changed per state).
    #[arg(long, default_value = "random")]
    pub design: String,
    /// Half-width of the random poses' translations (mm) [default: 100, times the
    /// campaign's scale].
    #[arg(long)]
    pub translation: Option<f64>,
    /// Half-width of the random poses' angles (deg) [default: 10, halved while fewer
    /// than a fifth of the random poses are within the limits].
    #[arg(long)]
    pub rotation: Option<f64>,
    /// Largest condition number of a random state, as a multiple of the home pose's:
    /// states nearer a singularity are drawn again (`inf`: none refused).
    #[arg(long, default_value_t = pkm::identify::simulate::CONDITION_RATIO)]
    pub condition_ratio: f64,
    /// Strut change per state of the one-strut design (mm) [default: 40, times the
    /// campaign's scale].
    #[arg(long)]
    pub step: Option<f64>,
    /// Size of the fixture (mm): the circumradius of a strut machine's triangle, the
    /// spacing of a pentapod's two points on its tool axis [default: 200, times the
    /// campaign's scale].
    ///
    /// The campaign's scale is 1 unless fewer than a fifth of the random poses within
    /// +-100 mm and +-10 deg of home are within the machine's limits and the condition
    /// ratio (a machine much smaller than 100 mm: then it halves until they are) or the
    /// struts average more than 1 m at home (then it doubles while the span stays
    /// within a fifth of them and a fifth of the poses within the limits), so the
    /// defaults fit a micro-positioner and a hexapod of metres as well as a machine
    /// tool.
    #[arg(long)]
    pub fixture_radius: Option<f64>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Print truth.json (the true parameters and poses) and the files written to stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct CalibrateArgs {
    /// Machine file (TOML, type = "hexapod"): the nominal machine, start of the fit.
    pub machine: PathBuf,
    /// Measurement file (CSV, see `pkm simulate-measurements --help`).
    #[arg(long)]
    pub measurements: PathBuf,
    /// `pose` (full pose per state from >= 3 fixture points) or `points` (points only,
    /// e.g. one laser-tracker target).
    #[arg(long, default_value = "pose")]
    pub model: String,
    /// Parameters held at their nominal values (names as in report.json, e.g. A1.z).
    #[arg(long)]
    pub fix: Option<String>,
    /// Write the seed 001 procedure's solution (first seven states, six systems of seven
    /// equations) to identified.toml instead of Levenberg-Marquardt's.
    #[arg(long)]
    pub seed_procedure: bool,
    /// States not used for identification: point errors of the nominal and identified
    /// models.
    #[arg(long)]
    pub validation: Option<PathBuf>,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Print report.json to stdout.
    #[arg(long)]
    pub json: bool,
}

fn read(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

pub fn simulate_run(a: &SimulateArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let sized = identification::sized_experiment(&machine)?;
    let fixture = match a.fixture_radius {
        Some(r) => identification::fixture(&machine, r)?,
        None => pkm::identify::Fixture {
            points: sized.experiment.fixture.clone(),
            description: sized.fixture.clone(),
        },
    };
    let d = &sized.experiment;
    let deviation = a.deviation.unwrap_or(d.deviation);
    let comment = format!(
        "simulated by pkm simulate-measurements on {} (seed {}): deviations +-{} mm, point \
         noise {} mm, reading noise {} mm, {} design\nthe fixture is {}",
        a.machine.display(),
        a.seed,
        deviation,
        a.point_noise,
        a.length_noise,
        a.design,
        fixture.description
    );
    let opt = SimulateOptions {
        experiment: Experiment {
            deviation,
            point_noise: a.point_noise,
            length_noise: a.length_noise,
            states: a.states,
            design: parse_design(&a.design)?,
            translation: a.translation.unwrap_or(d.translation),
            rotation: a.rotation.map_or(d.rotation, f64::to_radians),
            condition_ratio: a.condition_ratio,
            step: a.step.unwrap_or(d.step),
            fixture: fixture.points,
            seed: a.seed,
        },
        holdout: a.holdout,
        comment: comment.clone(),
    };
    let text = read(&a.machine)?;
    let s = simulate_measurements(&machine, Some(&text), &opt)?;
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let inputs = [a.machine.as_path()];
    write_atomic(
        &a.out.join("measurements.csv"),
        write_measurements(&machine, &s.measurements, &comment).as_bytes(),
        &inputs,
    )?;
    if a.holdout > 0 {
        write_atomic(
            &a.out.join("validation.csv"),
            write_measurements(
                &machine,
                &s.validation,
                &format!("{comment}\nheld-out states"),
            )
            .as_bytes(),
            &inputs,
        )?;
    }
    if let Some(toml) = &s.true_machine_file {
        write_atomic(&a.out.join("true.toml"), toml.as_bytes(), &inputs)?;
    }
    let summary = json!({
        "machine": a.machine.display().to_string(),
        "states": a.states,
        "holdout": a.holdout,
        "experiment": {
            "deviation": opt.experiment.deviation,
            "point_noise": a.point_noise,
            "length_noise": a.length_noise,
            "design": a.design,
            "translation": opt.experiment.translation,
            "rotation_deg": opt.experiment.rotation.to_degrees(),
            // `inf` as JSON has it not: the string.
            "condition_ratio": if opt.experiment.condition_ratio.is_finite() {
                json!(opt.experiment.condition_ratio)
            } else {
                json!("inf")
            },
            "step": opt.experiment.step,
            "fixture": fixture.description,
            "default_scale": sized.sizing.scale,
            "default_rotation_scale": sized.sizing.rotation_scale,
        },
        "true_parameters": s.names.iter().zip(&s.true_parameters).map(|(n, v)| (n.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "true_poses": s.true_poses,
    });
    write_atomic(
        &a.out.join("truth.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
        &inputs,
    )?;
    if a.json {
        let mut v = summary;
        v["out"] = json!(a.out.display().to_string());
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        println!(
            "{}: {} states (+{} held out) on a true machine {} mm off nominal; wrote {}",
            machine.mechanism().name(),
            a.states,
            a.holdout,
            deviation,
            a.out.display()
        );
    }
    Ok(0)
}

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
    let model: identify::MeasurementModel = a.model.parse().context("--model")?;
    let opt = CalibrateOptions {
        model,
        fix: a
            .fix
            .as_deref()
            .map(|l| l.split(',').map(String::from).collect())
            .unwrap_or_default(),
        seed_procedure: a.seed_procedure,
    };
    let text = read(&a.machine)?;
    // The comment's residuals are known after the fit: identify, then head the file.
    let head = |c: &Calibration| {
        format!(
            "Identified by pkm calibrate from {} ({} states, {} model{}): residual RMS {:.4} -> {:.4} mm",
            a.measurements.display(),
            meas.states.len(),
            a.model,
            if a.seed_procedure { ", seed 001 procedure" } else { "" },
            c.identification.rms_before,
            c.identification.rms_after
        )
    };
    let spin = crate::progress::spinner(
        true,
        &format!(
            "{{spinner}} identifying the parameters from {} states {{elapsed}}",
            meas.states.len()
        ),
    );
    let c = calibrate(&machine, &meas, validation.as_ref(), &opt);
    if let Some(s) = spin {
        s.finish_and_clear();
    }
    let c = c?;
    let toml = identified_machine_file(&machine, &text, &c, &head(&c))?;
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
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_text(
            machine.mechanism().name(),
            &c.identification,
            c.seed_procedure.as_ref(),
            c.validation.as_ref(),
            &a.out,
        );
    }
    Ok(0)
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
    let shown = &order[..order.len().min(6)];
    let w = shown.iter().map(|&i| id.names[i].len()).max().unwrap_or(0);
    for &i in shown {
        println!(
            "  largest change {:<w$} {:+.4} mm  (standard error {:.4} mm)",
            id.names[i],
            id.values[i] - id.start[i],
            id.standard_errors[i]
        );
    }
    if let Some(note) = &id.standard_errors_note {
        println!("note             {note}");
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
    if let Some(Validation {
        states: n,
        nominal: b,
        identified: a,
    }) = validation
    {
        println!(
            "validation       {n} states: point error max {:.4} / RMS {:.4} mm (nominal) -> max {:.4} / RMS {:.4} mm (identified)",
            b.max, b.rms, a.max, a.rms
        );
        if let (Some(pb), Some(pa)) = (b.pose, a.pose) {
            println!(
                "                 tool pose: position max {:.4} / RMS {:.4} mm, orientation max {:.2e} deg (nominal) -> position max {:.4} / RMS {:.4} mm, orientation max {:.2e} deg (identified)",
                pb.position_max, pb.position_rms, pb.orientation_max.to_degrees(), pa.position_max, pa.position_rms, pa.orientation_max.to_degrees()
            );
        }
    }
    println!("wrote {}", out.display());
}
