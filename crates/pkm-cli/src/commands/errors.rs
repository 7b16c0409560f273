//! `pkm errors`: the accuracy of any machine at one pose (`pkm::analysis::accuracy`):
//! the exact error of given deviations, the sensitivity to every parameter, the error
//! budget of the tolerances, a Monte Carlo of them and an error map.

use crate::parse_convention;
use anyhow::{bail, Context, Result};
use clap::Args;
use pkm::analysis::{accuracy_with_progress, AccuracyOptions, AccuracyReport, MapRequest};
use pkm::{Convention, DynMechanism};
use std::path::PathBuf;

use super::load;
use crate::io::write_atomic;
use crate::out::outln;
use crate::poses::{parse_list, pose_from_user};

mod text;
mod write;
use text::{print_text, report_json};
use write::{write_budget, write_map, write_monte_carlo, write_path, write_series, write_surface};

#[derive(Args)]
pub struct ErrorsArgs {
    /// Machine file (TOML or URDF): any machine type.
    pub machine: PathBuf,
    /// Pose (as `pkm ik --pose`); default: home.
    #[arg(long, allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// Actuator values instead of a pose (mm, deg; forward kinematics from home).
    #[arg(long, allow_hyphen_values = true)]
    pub actuators: Option<String>,
    /// Convention of the angles in --pose.
    #[arg(long, default_value = "rpy", value_parser = parse_convention)]
    pub rotation: Convention,
    #[command(flatten)]
    pub tol: super::tolerance_args::ToleranceArgs,
    /// TOML file of deviation values by parameter name (mm; deg for angles): their
    /// exact tool-pose error.
    #[arg(long)]
    pub deviations: Option<PathBuf>,
    /// Monte Carlo of the tolerances with this many machines.
    #[arg(long)]
    pub monte_carlo: Option<usize>,
    /// Seed of the Monte Carlo.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Error map over two pose coordinates (names, e.g. X,Y; a joint-space machine's
    /// joints over their travel), the others at the pose: RSS and worst case per point.
    #[arg(long)]
    pub map: Option<String>,
    /// Points per axis of the error map.
    #[arg(long, default_value_t = 41)]
    pub map_points: usize,
    /// Joint clearances (seed 002): one diametral clearance (mm) for every passive
    /// joint (the file's joint types, bearing lengths and axes kept). Without it the
    /// machine file's `[[clearance]]` entries are used when there are any.
    #[arg(long, allow_negative_numbers = true)]
    pub clearance: Option<f64>,
    /// Direction of the clearance bounds (X,Y,Z in the base or workpiece frame, e.g. the
    /// surface normal); default: the tool axis.
    #[arg(long, allow_hyphen_values = true)]
    pub direction: Option<String>,
    /// Method of the clearance bounds: `first-order` (support functions re-solved
    /// exactly; scales) or `enumeration` (seed 002: every combination of extreme joint
    /// states, 6 per ball and 4 per disc; refused above 2^20 solves).
    #[arg(long, default_value = "first-order")]
    pub clearance_method: String,
    /// Monte Carlo of this many joint states inside their clearances.
    #[arg(long)]
    pub clearance_samples: Option<usize>,
    /// Tolerance on the error along the direction (mm): the largest clearance within it.
    #[arg(long, allow_negative_numbers = true)]
    pub tolerance: Option<f64>,
    /// Clearance bounds over a part surface along its normal (seed 002's Figs. 4, 5):
    /// `hemisphere:R` (mm), swept by the height z above its equator. Writes
    /// DIR/surface.csv (z_mm,lower_mm,upper_mm) and DIR/surface.svg.
    #[arg(long)]
    pub surface: Option<String>,
    /// Centre of the surface (X,Y,Z mm); default: R below the home tool point.
    #[arg(long, allow_hyphen_values = true)]
    pub surface_centre: Option<String>,
    /// Heights of the surface sweep.
    #[arg(long, default_value_t = 101)]
    pub surface_points: usize,
    /// Bounds at the pose for each of these diametral clearances (mm, e.g.
    /// 0.05,0.1,0.2; seed 002's Fig. 5): DIR/clearance-series.csv and .svg.
    #[arg(long)]
    pub clearance_series: Option<String>,
    /// Clearance bounds along a G-code path (the tool axis as the surface normal, or
    /// --direction): DIR/clearance-path.csv. The program runs from home with a constant
    /// feed profile.
    #[arg(long)]
    pub path: Option<PathBuf>,
    /// Sampling rate of the path (Hz).
    #[arg(long, default_value_t = 100.0)]
    pub path_rate: f64,
    /// Bounds at every N-th path sample.
    #[arg(long, default_value_t = 1)]
    pub path_every: usize,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Print errors.json to stdout.
    #[arg(long)]
    pub json: bool,
}

pub fn run(a: &ErrorsArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let m = machine.mechanism();
    let options = accuracy_options(a, &machine)?;
    let bar = crate::progress::bar(
        a.monte_carlo.unwrap_or(0) as u64,
        1_000_000,
        "{bar:40} {pos}/{len} machines {eta}",
    );
    let r = accuracy_with_progress(&machine, &options, &|n| {
        if let Some(b) = &bar {
            b.inc(n)
        }
    })?;
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let inputs: Vec<&std::path::Path> = std::iter::once(a.machine.as_path())
        .chain(a.deviations.as_deref())
        .chain(a.tol.tolerances.as_deref())
        .collect();
    let out = write_outputs(a, m, &r, &inputs)?;
    let text = serde_json::to_string_pretty(&out)?;
    write_atomic(&a.out.join("errors.json"), text.as_bytes(), &inputs)?;
    if a.json {
        outln!("{text}")?;
    } else {
        print_text(m, &r)?;
        outln!("wrote {}", a.out.display())?;
    }
    Ok(0)
}

/// What the options ask of the accuracy analysis.
fn accuracy_options(a: &ErrorsArgs, machine: &pkm::Machine) -> Result<AccuracyOptions> {
    let params = machine.parameters();
    let pose = pose(a, machine.mechanism())?;
    let deviations = match &a.deviations {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read {}", p.display()))?;
            pkm::machine::read_deviations(&params, &text, &p.display().to_string())?
        }
        None => Vec::new(),
    };
    let tolerances = a.tol.tolerances(&params)?;
    let map = match &a.map {
        None => None,
        Some(spec) => Some(map_request(machine.mechanism(), spec, a.map_points)?),
    };
    let clearance = clearance_request(a, machine)?;
    Ok(AccuracyOptions {
        pose,
        deviations,
        tolerances,
        monte_carlo: a.monte_carlo,
        seed: a.seed,
        map,
        clearance,
    })
}

/// The pose of `--pose`, or of `--actuators` (forward kinematics from home); `None`:
/// home.
fn pose(a: &ErrorsArgs, m: &dyn DynMechanism) -> Result<Option<Vec<f64>>> {
    Ok(match (&a.pose, &a.actuators) {
        (Some(_), Some(_)) => bail!("--pose and --actuators: give one of them"),
        (Some(p), None) => Some(pose_from_user(m, &parse_list(p, "--pose")?, a.rotation)?),
        (None, Some(q)) => {
            let q = crate::poses::actuators_from_user(m, &parse_list(q, "--actuators")?)?;
            Some(m.forward(&q, &m.home())?.pose)
        }
        (None, None) => None,
    })
}

/// `--map X,Y`: the error map over two pose coordinates, `points` per axis.
fn map_request(m: &dyn DynMechanism, spec: &str, points: usize) -> Result<MapRequest> {
    let names: Vec<&str> = spec.split(',').map(str::trim).collect();
    let idx = names
        .iter()
        .map(|n| {
            m.coordinates()
                .iter()
                .position(|c| c.name == *n)
                .with_context(|| {
                    format!(
                        "--map: unknown axis `{n}`, expected two of {}",
                        m.coordinates()
                            .iter()
                            .map(|c| c.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )
                })
        })
        .collect::<Result<Vec<usize>>>()?;
    if idx.len() != 2 || idx[0] == idx[1] {
        bail!("--map: expected two different axes, e.g. X,Y");
    }
    Ok(MapRequest {
        coordinates: [idx[0], idx[1]],
        points,
    })
}

/// Writes the budget, Monte Carlo, map and clearance files; the `errors.json` document.
fn write_outputs(
    a: &ErrorsArgs,
    m: &dyn DynMechanism,
    r: &AccuracyReport,
    inputs: &[&std::path::Path],
) -> Result<serde_json::Value> {
    let mut out = report_json(m, r);
    write_budget(&a.out, &r.budget, inputs)?;
    let o = out.as_object_mut().expect("object");
    if let Some(mc) = &r.monte_carlo {
        o.insert(
            "monte_carlo".into(),
            write_monte_carlo(&a.out, mc, a.seed, inputs)?,
        );
    }
    if let Some(em) = &r.map {
        o.insert(
            "error_map".into(),
            write_map(&a.out, m, &r.pose, em, inputs)?,
        );
    }
    if let Some(c) = &r.clearance {
        o.insert("clearance".into(), serde_json::to_value(c)?);
        if let Some(sf) = &c.surface {
            write_surface(&a.out, sf, inputs)?;
        }
        if !c.series.is_empty() {
            write_series(&a.out, &c.series, inputs)?;
        }
        if let Some(p) = &c.path {
            write_path(&a.out, m, p, inputs)?;
        }
    }
    Ok(out)
}

/// The clearance request of the arguments: asked for by `--clearance`, or by the
/// machine file's `[[clearance]]` entries.
fn clearance_request(
    a: &ErrorsArgs,
    machine: &pkm::Machine,
) -> Result<Option<pkm::analysis::clearance::ClearanceRequest>> {
    let asked = a.clearance.is_some()
        || a.direction.is_some()
        || a.clearance_samples.is_some()
        || a.tolerance.is_some()
        || a.surface.is_some()
        || a.clearance_series.is_some()
        || a.path.is_some();
    if !asked && machine.clearances.is_empty() {
        return Ok(None);
    }
    let direction = match &a.direction {
        None => None,
        Some(d) => {
            let v = three(d, "--direction")?;
            Some(nalgebra::Vector3::new(v[0], v[1], v[2]))
        }
    };
    let surface = match &a.surface {
        None => None,
        Some(spec) => Some(surface_request(a, spec)?),
    };
    let method = a
        .clearance_method
        .parse()
        .map_err(|e: String| anyhow::anyhow!("--clearance-method: {e}"))?;
    Ok(Some(pkm::analysis::clearance::ClearanceRequest {
        diametral: a.clearance,
        options: pkm::accuracy::clearance::ClearanceOptions {
            direction,
            method,
            ..Default::default()
        },
        monte_carlo: a.clearance_samples,
        seed: a.seed,
        tolerance: a.tolerance,
        surface,
        series: match &a.clearance_series {
            Some(list) => parse_list(list, "--clearance-series")?,
            None => Vec::new(),
        },
        path: match &a.path {
            None => None,
            Some(p) => Some(path_request(a, machine, p)?),
        },
    }))
}

/// Three values X,Y,Z of option `flag`.
fn three(s: &str, flag: &str) -> Result<[f64; 3]> {
    let v = parse_list(s, flag)?;
    if v.len() != 3 {
        bail!("{flag}: expected X,Y,Z, got {} values", v.len());
    }
    Ok([v[0], v[1], v[2]])
}

/// `--surface hemisphere:R` about `--surface-centre`.
fn surface_request(a: &ErrorsArgs, spec: &str) -> Result<pkm::analysis::clearance::SurfaceRequest> {
    let radius = spec
        .strip_prefix("hemisphere:")
        .and_then(|r| r.trim().parse::<f64>().ok())
        .with_context(|| format!("--surface: expected hemisphere:R (R in mm), found `{spec}`"))?;
    let centre = match &a.surface_centre {
        None => None,
        Some(c) => Some(three(c, "--surface-centre")?),
    };
    Ok(pkm::analysis::clearance::SurfaceRequest {
        radius,
        centre,
        azimuth: 0.0,
        heights: a.surface_points,
    })
}

/// `--path FILE`: the program from home at the machine's feeds, sampled at
/// `--path-rate`.
fn path_request(
    a: &ErrorsArgs,
    machine: &pkm::Machine,
    p: &std::path::Path,
) -> Result<pkm::analysis::clearance_path::PathRequest> {
    if !(a.path_rate > 0.0 && a.path_rate <= 1e6) {
        bail!(
            "--path-rate: expected 0 < rate <= 1e6 Hz, got {}",
            a.path_rate
        );
    }
    let feed = pkm::analysis::motion::feed_options(machine);
    Ok(pkm::analysis::clearance_path::PathRequest {
        program: std::fs::read_to_string(p)
            .with_context(|| format!("cannot read {}", p.display()))?,
        from: None,
        feed,
        sampling: pkm::motion::Sampling::Rate(a.path_rate),
        every: a.path_every,
    })
}
