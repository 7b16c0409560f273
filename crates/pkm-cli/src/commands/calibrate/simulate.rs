//! `pkm simulate-measurements`: a simulated identification campaign (seed 001) written
//! as the files `pkm calibrate` reads, with the true machine beside them.

use anyhow::{Context, Result};
use pkm::analysis::identification::{
    self, parse_design, simulate_measurements, write_measurements, SimulateOptions,
    SimulatedCampaign, SizedExperiment,
};
use pkm::identify::simulate::Experiment;
use pkm::identify::Fixture;
use serde_json::json;

use super::super::load;
use super::{read, SimulateArgs};
use crate::io::write_atomic;
use crate::out::outln;

pub fn simulate_run(a: &SimulateArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let sized = identification::sized_experiment(&machine)?;
    let Fixture {
        points,
        description,
    } = match a.fixture_radius {
        Some(r) => identification::fixture(&machine, r)?,
        None => Fixture {
            points: sized.experiment.fixture.clone(),
            description: sized.fixture.clone(),
        },
    };
    let deviation = a.deviation.unwrap_or(sized.experiment.deviation);
    let comment = format!(
        "simulated by pkm simulate-measurements on {} (seed {}): deviations +-{} mm, point \
         noise {} mm, reading noise {} mm, {} design\nthe fixture is {}",
        a.machine.display(),
        a.seed,
        deviation,
        a.point_noise,
        a.length_noise,
        a.design,
        description
    );
    let opt = SimulateOptions {
        experiment: experiment(a, &sized.experiment, deviation, points)?,
        holdout: a.holdout,
        comment: comment.clone(),
    };
    let text = read(&a.machine)?;
    let s = simulate_measurements(&machine, Some(&text), &opt)?;
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let inputs = [a.machine.as_path()];
    write_campaign(a, &machine, &s, &comment, &inputs)?;
    let summary = truth_json(a, &opt.experiment, &description, &sized, &s);
    write_atomic(
        &a.out.join("truth.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
        &inputs,
    )?;
    if a.json {
        let mut v = summary;
        v["out"] = json!(a.out.display().to_string());
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else {
        outln!(
            "{}: {} states (+{} held out) on a true machine {} mm off nominal; wrote {}",
            machine.mechanism().name(),
            a.states,
            a.holdout,
            deviation,
            a.out.display()
        )?;
    }
    Ok(0)
}

/// The campaign of the options over the machine's sized default `d`, measured with
/// the fixture's `points`.
fn experiment(
    a: &SimulateArgs,
    d: &Experiment,
    deviation: f64,
    points: Vec<nalgebra::Vector3<f64>>,
) -> Result<Experiment> {
    Ok(Experiment {
        deviation,
        point_noise: a.point_noise,
        length_noise: a.length_noise,
        states: a.states,
        design: parse_design(&a.design)?,
        translation: a.translation.unwrap_or(d.translation),
        rotation: a.rotation.map_or(d.rotation, f64::to_radians),
        condition_ratio: a.condition_ratio,
        step: a.step.unwrap_or(d.step),
        fixture: points,
        seed: a.seed,
    })
}

/// `measurements.csv`, `validation.csv` (with `--holdout`) and `true.toml`.
fn write_campaign(
    a: &SimulateArgs,
    machine: &pkm::Machine,
    s: &SimulatedCampaign,
    comment: &str,
    inputs: &[&std::path::Path],
) -> Result<()> {
    write_atomic(
        &a.out.join("measurements.csv"),
        write_measurements(machine, &s.measurements, comment).as_bytes(),
        inputs,
    )?;
    if a.holdout > 0 {
        write_atomic(
            &a.out.join("validation.csv"),
            write_measurements(
                machine,
                &s.validation,
                &format!("{comment}\nheld-out states"),
            )
            .as_bytes(),
            inputs,
        )?;
    }
    if let Some(toml) = &s.true_machine_file {
        write_atomic(&a.out.join("true.toml"), toml.as_bytes(), inputs)?;
    }
    Ok(())
}

/// `truth.json`: the campaign and the true machine's parameters and poses.
fn truth_json(
    a: &SimulateArgs,
    e: &Experiment,
    fixture: &str,
    sized: &SizedExperiment,
    s: &SimulatedCampaign,
) -> serde_json::Value {
    json!({
        "machine": a.machine.display().to_string(),
        "states": a.states,
        "holdout": a.holdout,
        "experiment": {
            "deviation": e.deviation,
            "point_noise": a.point_noise,
            "length_noise": a.length_noise,
            "design": a.design,
            "translation": e.translation,
            "rotation_deg": e.rotation.to_degrees(),
            // `inf` as JSON has it not: the string.
            "condition_ratio": if e.condition_ratio.is_finite() {
                json!(e.condition_ratio)
            } else {
                json!("inf")
            },
            "step": e.step,
            "fixture": fixture,
            "default_scale": sized.sizing.scale,
            "default_rotation_scale": sized.sizing.rotation_scale,
        },
        "true_parameters": s.names.iter().zip(&s.true_parameters).map(|(n, v)| (n.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "true_poses": s.true_poses,
    })
}
