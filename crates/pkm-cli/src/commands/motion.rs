//! `pkm motion`: a tool path or G-code program through the machine: actuator position,
//! velocity and acceleration over time, the serial comparison and limits.

use crate::parse_convention;
use clap::Args;
use pkm::Convention;
use std::fs::File;
use std::io::{BufReader, Write};
use std::path::{Path, PathBuf};

use crate::out::outln;
use anyhow::{Context, Result};
use pkm::analysis::motion::{run_motion_with, MotionRun, MotionSource, ProgramSetup};
use pkm::motion::program::FeedOptions;
use pkm::motion::tools::parse_tool_table;
use pkm::motion::{MotionSummary, Sampling};
use pkm::{DynMechanism, Machine};
use serde_json::json;

mod plots;
mod text;
pub use plots::plots;

use super::load;
use super::motion_series::SeriesSink;
use crate::columnar::SeriesFormat;
use crate::io::{write_atomic, AtomicFile};
use crate::poses::{parse_list, pose_from_user};

#[derive(Args)]
pub struct MotionArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// G-code program.
    #[arg(long, conflicts_with = "to")]
    pub gcode: Option<PathBuf>,
    /// Start pose (as `pkm ik --pose`); default: the home pose.
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<String>,
    /// End pose of a point-to-point move.
    #[arg(long, allow_hyphen_values = true)]
    pub to: Option<String>,
    /// Feed (mm/min), replacing the program's F words.
    #[arg(long)]
    pub feed: Option<f64>,
    /// Velocity profile of each move.
    #[arg(long, value_enum, default_value = "constant")]
    pub profile: ProfileArg,
    /// Path acceleration for trapezoid and scurve (mm/s^2).
    #[arg(long, default_value_t = 1000.0)]
    pub accel: f64,
    /// Path jerk for scurve (mm/s^3).
    #[arg(long, default_value_t = 20000.0)]
    pub jerk: f64,
    /// Rapid (G0) rate (mm/min); default: the machine file's `[motion] rapid`, else 10000.
    #[arg(long)]
    pub rapid: Option<f64>,
    /// Duration of a point-to-point move (s), instead of --feed.
    #[arg(long)]
    pub duration: Option<f64>,
    /// Acceleration (and deceleration) time of a timed trapezoid (s).
    #[arg(long)]
    pub accel_time: Option<f64>,
    /// Sampling rate (Hz); default 1000.
    #[arg(long, conflicts_with = "points")]
    pub rate: Option<f64>,
    /// Points per move instead of a rate (seed 000: 101).
    #[arg(long)]
    pub points: Option<usize>,
    /// Work limit: the most samples the run may make; a move that would cross it is
    /// refused before it is sampled (a dwell of years, a feed of 1e-6 mm/min).
    #[arg(long, default_value_t = pkm::motion::run::DEFAULT_MAX_SAMPLES)]
    pub max_samples: u64,
    /// Tool length (mm) for every G43 H of the program the tool table does not list.
    #[arg(long)]
    pub tool_length: Option<f64>,
    /// LinuxCNC tool table (`T1 P1 Z50.0 ...`, lengths in mm) for the program's G43 H.
    #[arg(long)]
    pub tool_table: Option<PathBuf>,
    /// Work offset of G54..G59.3: `G55=X,Y,Z[,A,B,C]` (mm, deg); repeatable.
    #[arg(long, allow_hyphen_values = true)]
    pub work_offset: Vec<String>,
    /// Threshold (deg) of a passage near the singular direction of a 5-axis machine
    /// (tool axis along the rotary axis nearer the part), listed with the rotary axes'
    /// peak speeds in it.
    #[arg(long, default_value_t = pkm::motion::singular::DEFAULT_SINGULAR_ANGLE.to_degrees())]
    pub singular_angle: f64,
    /// Convention of angles in --from/--to.
    #[arg(long, default_value = "rpy", value_parser = parse_convention)]
    pub rotation: Convention,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub accuracy: super::motion_accuracy::AccuracyArgs,
    /// Skip the sample series (summary and plots only), for very long programs.
    #[arg(long)]
    pub summary_only: bool,
    /// Format of the sample series: actuators.csv (six decimals) or actuators.parquet
    /// (full precision, typed columns; pandas.read_parquet, polars, DuckDB).
    #[arg(long, value_enum, default_value = "csv")]
    pub format: SeriesFormat,
    /// Print summary.json to stdout.
    #[arg(long)]
    pub json: bool,
}

/// Velocity profile names on the command line.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum ProfileArg {
    /// Constant feed.
    Constant,
    /// Trapezoidal velocity.
    Trapezoid,
    /// Jerk-limited S-curve.
    Scurve,
}

impl From<ProfileArg> for pkm::motion::program::ProfileKind {
    fn from(p: ProfileArg) -> Self {
        match p {
            ProfileArg::Constant => Self::Constant,
            ProfileArg::Trapezoid => Self::Trapezoid,
            ProfileArg::Scurve => Self::Scurve,
        }
    }
}

/// Tool lengths and work offsets from the options.
fn program_setup(a: &MotionArgs) -> Result<ProgramSetup> {
    let mut setup = ProgramSetup {
        tool_length: a.tool_length,
        ..Default::default()
    };
    if let Some(l) = a.tool_length {
        anyhow::ensure!(
            l.is_finite() && l.abs() <= pkm::machine::MAX_MAGNITUDE,
            "--tool-length {l}: expected a length in mm"
        );
    }
    if let Some(t) = &a.tool_table {
        let text =
            std::fs::read_to_string(t).with_context(|| format!("cannot read {}", t.display()))?;
        setup.tool_lengths = parse_tool_table(&t.display().to_string(), &text)?;
    }
    for w in &a.work_offset {
        let (code, vals) = w
            .split_once('=')
            .with_context(|| format!("--work-offset {w}: expected G54=X,Y,Z[,A,B,C]"))?;
        let names = [
            "G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3",
        ];
        let k = names
            .iter()
            .position(|n| n.eq_ignore_ascii_case(code.trim()))
            .with_context(|| format!("--work-offset {w}: expected one of {}", names.join(", ")))?;
        let v = parse_list(vals, "--work-offset")?;
        anyhow::ensure!(
            v.len() == 3 || v.len() == 6,
            "--work-offset {w}: expected 3 or 6 values (X,Y,Z[,A,B,C] in mm, deg)"
        );
        for (i, x) in v.iter().enumerate() {
            setup.work_offsets[k][i] = if i < 3 { *x } else { x.to_radians() };
        }
    }
    Ok(setup)
}

/// `summary.json` of a run.
pub fn summary_json(machine: &Machine, s: &MotionSummary, feed: &FeedOptions) -> serde_json::Value {
    let axes = |v: &[(String, pkm::motion::AxisStats)]| {
        let mut o = serde_json::Map::new();
        for (n, st) in v {
            o.insert(n.clone(), json!(st));
        }
        serde_json::Value::Object(o)
    };
    json!({
        "machine": machine.mechanism().name(),
        "type": machine.kind(),
        "actuators": axes(&s.actuators),
        "serial": axes(&s.serial),
        "ratios": s.ratios,
        "violations": s.violations,
        "violations_not_listed": s.violations_not_listed,
        "feed_override_max": s.feed_override_max,
        "rapid_override_max": s.rapid_override_max,
        "singular": s.singular,
        "duration_s": s.duration_s,
        "samples": s.samples,
        "profile": feed,
    })
}

/// Feed options of the run: the options over the machine file's.
fn feed_options(a: &MotionArgs, machine: &Machine) -> FeedOptions {
    FeedOptions {
        profile: a.profile.into(),
        acceleration: a.accel,
        jerk: a.jerk,
        rapid: a
            .rapid
            .map(|r| r / 60.0)
            .unwrap_or(pkm::analysis::motion::feed_options(machine).rapid),
        feed: a.feed.map(|f| f / 60.0),
        max_samples: a.max_samples,
        singular_angle: a.singular_angle.to_radians(),
    }
}

/// Sampling of the run: points per move, else a rate (default 1000 Hz).
fn sampling(a: &MotionArgs) -> Sampling {
    match (a.rate, a.points) {
        (_, Some(n)) => Sampling::Points(n),
        (Some(r), None) => Sampling::Rate(r),
        (None, None) => Sampling::Rate(1000.0),
    }
}

/// What the run moves through: the G-code program (and its size in bytes, for the
/// progress bar), or the point-to-point move (0 bytes).
fn motion_source(a: &MotionArgs, machine: &Machine) -> Result<(MotionSource<'static>, u64)> {
    let m = machine.mechanism();
    let conv = a.rotation;
    let from = match &a.from {
        Some(s) => Some(pose_from_user(m, &parse_list(s, "--from")?, conv)?),
        None => None,
    };
    if let Some(g) = &a.gcode {
        let f = File::open(g).with_context(|| format!("cannot read {}", g.display()))?;
        let bytes = f.metadata().map(|x| x.len()).unwrap_or(0);
        let source = MotionSource::Gcode {
            reader: Box::new(BufReader::new(f)),
            from,
            setup: Box::new(program_setup(a)?),
        };
        return Ok((source, bytes));
    }
    let to =
        a.to.as_ref()
            .context("give --gcode FILE, or --from POSE --to POSE")?;
    let source = MotionSource::PointToPoint {
        from: from.unwrap_or_else(|| m.home()),
        to: pose_from_user(m, &parse_list(to, "--to")?, conv)?,
        duration: a.duration,
        accel_time: a.accel_time,
    };
    Ok((source, 0))
}

/// The files the outputs are made from: the machine, the program, the tolerances.
fn inputs(a: &MotionArgs) -> Vec<&Path> {
    let mut inputs: Vec<&Path> = vec![&a.machine];
    if let Some(g) = &a.gcode {
        inputs.push(g);
    }
    if let Some(t) = &a.accuracy.tol.tolerances {
        inputs.push(t);
    }
    inputs
}

/// What a run takes besides its source.
struct RunPlan<'a> {
    feed: &'a FeedOptions,
    sampling: Sampling,
    accuracy: Option<&'a pkm::analysis::motion::PathAccuracyRequest>,
    /// Program size, for the progress bar.
    bytes: u64,
}

/// Runs the motion, the sample series written to `DIR/actuators.*` (unless
/// `--summary-only`) while it goes on.
fn run_with_series(
    a: &MotionArgs,
    machine: &Machine,
    source: MotionSource,
    plan: &RunPlan,
    inputs: &[&Path],
) -> Result<MotionRun> {
    let series = a.out.join(a.format.file("actuators"));
    let mut writer = if a.summary_only {
        None
    } else {
        Some(AtomicFile::create(&series, inputs)?)
    };
    let outcome = std::thread::scope(|scope| -> Result<MotionRun> {
        let (mut sink, csv) = SeriesSink::start(
            scope,
            machine,
            writer.as_mut().map(|w| w as &mut (dyn Write + Send)),
            a.format,
            plan.bytes,
        )?;
        let run = run_motion_with(
            machine,
            source,
            plan.feed,
            plan.sampling,
            plan.accuracy,
            &mut sink,
        );
        // A failed write stops the run: its error is the one to report.
        let written = sink.finish(csv);
        written.with_context(|| format!("cannot write {}", series.display()))?;
        Ok(run?)
    })?;
    if let Some(w) = writer {
        w.commit()?;
    }
    Ok(outcome)
}

/// `summary.json` of the run with its notes, what timed a `--duration` move and the
/// accuracy along the path.
fn run_summary(
    a: &MotionArgs,
    machine: &Machine,
    outcome: &MotionRun,
    feed: &FeedOptions,
) -> serde_json::Value {
    let mut summary = summary_json(machine, &outcome.summary, feed);
    if !outcome.notes.is_empty() {
        summary["notes"] = json!(outcome
            .notes
            .iter()
            .map(|(l, t)| json!({"line": l, "note": t}))
            .collect::<Vec<_>>());
        summary["notes_not_listed"] = json!(outcome.notes_dropped);
    }
    // A move timed by --duration (and --accel-time) is not shaped by the path
    // acceleration/jerk options: say what timed it instead.
    if let Some(d) = a.duration {
        summary["profile"] = json!({
            "profile": summary["profile"]["profile"],
            "duration_s": d,
            "accel_time_s": a.accel_time,
        });
    }
    if let Some(acc) = &outcome.accuracy {
        summary["accuracy"] = super::motion_accuracy::summary(acc);
    }
    summary
}

/// Writes the accuracy files, `summary.json` and the plots to `DIR`.
fn write_outputs(
    a: &MotionArgs,
    m: &dyn DynMechanism,
    outcome: &MotionRun,
    summary: &serde_json::Value,
    inputs: &[&Path],
) -> Result<()> {
    if let Some(acc) = &outcome.accuracy {
        super::motion_accuracy::write(&a.out, acc, m.name(), inputs)?;
    }
    write_atomic(
        &a.out.join("summary.json"),
        serde_json::to_string_pretty(summary)?.as_bytes(),
        inputs,
    )?;
    let (act_svg, ser_svg) = plots(m, outcome, m.name())?;
    write_atomic(&a.out.join("actuators.svg"), act_svg.as_bytes(), inputs)?;
    write_atomic(&a.out.join("serial.svg"), ser_svg.as_bytes(), inputs)?;
    Ok(())
}

pub fn run(a: &MotionArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let m = machine.mechanism();
    let feed = feed_options(a, &machine);
    let sampling = sampling(a);
    let (source, bytes) = motion_source(a, &machine)?;
    let accuracy = a.accuracy.request(&machine)?;
    let inputs = inputs(a);
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let plan = RunPlan {
        feed: &feed,
        sampling,
        accuracy: accuracy.as_ref(),
        bytes,
    };
    let outcome = run_with_series(a, &machine, source, &plan, &inputs)?;
    let summary = run_summary(a, &machine, &outcome, &feed);
    write_outputs(a, m, &outcome, &summary, &inputs)?;
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&summary)?)?;
    } else {
        text::print_text(m, &outcome, a.profile)?;
        outln!("wrote {}", a.out.display())?;
    }
    Ok(text::exit_code(&outcome.summary))
}
