//! `pkm motion`: a tool path or G-code program through the machine: actuator position,
//! velocity and acceleration over time, the serial comparison and limits.

use crate::parse_convention;
use clap::Args;
use pkm::Convention;
use std::fs::File;
use std::io::{BufReader, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use pkm::analysis::motion::{run_motion_with, MotionRun, MotionSource, ProgramSetup};
use pkm::motion::program::FeedOptions;
use pkm::motion::tools::parse_tool_table;
use pkm::motion::{MotionSummary, Sampling};
use pkm::Machine;
use serde_json::json;

mod plots;
pub use plots::plots;

use super::load;
use super::motion_series::SeriesSink;
use crate::columnar::SeriesFormat;
use crate::io::{write_atomic, AtomicFile};
use crate::poses::{parse_list, pose_from_user};
use crate::EXIT_UNREACHABLE;

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
        "singular": s.singular,
        "duration_s": s.duration_s,
        "samples": s.samples,
        "profile": feed,
    })
}

pub fn run(a: &MotionArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let m = machine.mechanism();
    let conv = a.rotation;
    let feed = FeedOptions {
        profile: a.profile.into(),
        acceleration: a.accel,
        jerk: a.jerk,
        rapid: a
            .rapid
            .map(|r| r / 60.0)
            .unwrap_or(pkm::analysis::motion::feed_options(&machine).rapid),
        feed: a.feed.map(|f| f / 60.0),
        max_samples: a.max_samples,
        singular_angle: a.singular_angle.to_radians(),
    };
    let sampling = match (a.rate, a.points) {
        (_, Some(n)) => Sampling::Points(n),
        (Some(r), None) => Sampling::Rate(r),
        (None, None) => Sampling::Rate(1000.0),
    };
    let from = match &a.from {
        Some(s) => Some(pose_from_user(m, &parse_list(s, "--from")?, conv)?),
        None => None,
    };
    let mut bytes = 0;
    let source = if let Some(g) = &a.gcode {
        let f = File::open(g).with_context(|| format!("cannot read {}", g.display()))?;
        bytes = f.metadata().map(|x| x.len()).unwrap_or(0);
        MotionSource::Gcode {
            reader: Box::new(BufReader::new(f)),
            from: from.clone(),
            setup: Box::new(program_setup(a)?),
        }
    } else {
        let to =
            a.to.as_ref()
                .context("give --gcode FILE, or --from POSE --to POSE")?;
        MotionSource::PointToPoint {
            from: from.unwrap_or_else(|| m.home()),
            to: pose_from_user(m, &parse_list(to, "--to")?, conv)?,
            duration: a.duration,
            accel_time: a.accel_time,
        }
    };
    let accuracy = a.accuracy.request(&machine)?;
    let mut inputs: Vec<&Path> = vec![&a.machine];
    if let Some(g) = &a.gcode {
        inputs.push(g);
    }
    if let Some(t) = &a.accuracy.tol.tolerances {
        inputs.push(t);
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let series = a.out.join(a.format.file("actuators"));
    let mut writer = if a.summary_only {
        None
    } else {
        Some(AtomicFile::create(&series, &inputs)?)
    };
    let outcome = std::thread::scope(|scope| -> Result<MotionRun> {
        let (mut sink, csv) = SeriesSink::start(
            scope,
            &machine,
            writer.as_mut().map(|w| w as &mut (dyn Write + Send)),
            a.format,
            bytes,
        )?;
        let run = run_motion_with(
            &machine,
            source,
            &feed,
            sampling,
            accuracy.as_ref(),
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
    let s = &outcome.summary;
    let mut summary = summary_json(&machine, s, &feed);
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
        super::motion_accuracy::write(&a.out, acc, m.name(), &inputs)?;
    }
    write_atomic(
        &a.out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
        &inputs,
    )?;
    let (act_svg, ser_svg) = plots(m, &outcome, m.name())?;
    write_atomic(&a.out.join("actuators.svg"), act_svg.as_bytes(), &inputs)?;
    write_atomic(&a.out.join("serial.svg"), ser_svg.as_bytes(), &inputs)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        println!(
            "{} ({}): {} samples over {:.4} s",
            m.name(),
            m.kind(),
            s.samples,
            s.duration_s
        );
        // The first column as wide as the longest axis label (a machine's own
        // actuator names, `actuator north-west`, keep the columns aligned).
        let lists = [("actuator", &s.actuators), ("serial", &s.serial)];
        let w = lists
            .iter()
            .flat_map(|(kind, list)| {
                list.iter()
                    .map(move |(n, _)| kind.len() + 1 + n.chars().count())
            })
            .fold(10, usize::max);
        println!(
            "{:<w$} {:>12} {:>14} {:>14} {:>16} {:>16}",
            "axis", "travel", "peak |v|", "mean |v|", "peak |a|", "mean |a|"
        );
        for (kind, list) in lists {
            for (n, st) in list.iter() {
                println!(
                    "{:<w$} {:>12.4} {:>14.4} {:>14.4} {:>16.4} {:>16.4}",
                    format!("{kind} {n}"),
                    st.travel,
                    st.peak_velocity,
                    st.mean_abs_velocity,
                    st.peak_acceleration,
                    st.mean_abs_acceleration
                );
            }
        }
        let ratio = |r: Option<f64>| r.map_or("n/a".to_string(), |r| format!("{r:.3}"));
        match &s.ratios {
            Some(r) => {
                println!(
                    "ratios serial/PKM (seed 000's): travel {:.3} (mean over mean), peak \
                     velocity {}, peak acceleration {} (largest over largest); of mean \
                     peaks: velocity {}, acceleration {}",
                    r.travel,
                    ratio(r.velocity),
                    ratio(r.acceleration),
                    ratio(r.velocity_of_mean_peaks),
                    ratio(r.acceleration_of_mean_peaks)
                );
                if r.velocity.is_none() {
                    println!(
                        "  (n/a: no sample caught the machine moving: every move is shorter \
                         than the sampling period, so its samples are its ends, at rest; \
                         a higher --rate samples it)"
                    );
                } else if r.acceleration.is_none() {
                    println!(
                        "  (acceleration n/a: no sample caught a serial axis accelerating{})",
                        match a.profile {
                            ProfileArg::Constant =>
                                ": under `--profile constant` the serial axes keep their \
                                 speed along each straight move, and the speed steps at the \
                                 corners are not samples; `--profile trapezoid` or `scurve` \
                                 gives the ramps",
                            _ => "",
                        }
                    );
                }
            }
            None => println!(
                "ratios serial/PKM: none (no serial axis moved, or an actuator or axis turns: \
                 mm over deg means nothing)"
            ),
        }
        match s.feed_override_max {
            Some(k) => println!(
                "largest feed override within the actuator rate limits: {:.4}",
                k
            ),
            None => println!("largest feed override: no rate limits in the machine file"),
        }
        if let Some(sg) = &s.singular {
            print_singular(sg);
        }
        if let Some(acc) = &outcome.accuracy {
            super::motion_accuracy::print(acc);
        }
        for (l, t) in outcome.notes.iter().take(20) {
            println!("note: line {l}: {t}");
        }
        let more = outcome.notes.len().saturating_sub(20) as u64 + outcome.notes_dropped;
        if more > 0 {
            println!("note: {more} more in summary.json");
        }
        println!("wrote {}", a.out.display());
    }
    if s.violations.is_empty() {
        Ok(0)
    } else {
        // The first stretch: where it starts, and the worst value in it (not the
        // value at its start).
        let v = &s.violations[0];
        let n = s.violations.len() as u64 + s.violations_not_listed;
        eprintln!(
            "error: {n} limit violation{} along the path; first: {} beyond {:.3} {} from t = {:.4} s{}, worst {:.3} {}",
            if n == 1 { "" } else { "s" },
            v.limit,
            v.bound,
            v.unit,
            v.start_s,
            v.line.map(|l| format!(" (G-code line {l})")).unwrap_or_default(),
            v.worst,
            v.unit,
        );
        Ok(EXIT_UNREACHABLE)
    }
}

/// The closest approach to the singular direction and the worst passages near it.
fn print_singular(sg: &pkm::motion::singular::SingularReport) {
    let line = |l: Option<u64>| l.map(|l| format!("line {l}")).unwrap_or("-".into());
    let (deg, t, l) = sg.closest;
    println!(
        "singular direction (tool axis along the rotary axis nearer the part), feed moves: \
         closest {deg:.4} deg at t = {t:.3} s ({}); {} passage(s) within {:.3} deg{}",
        line(l),
        sg.passages.len() as u64 + sg.passages_not_listed,
        sg.threshold_deg,
        if sg.passages.is_empty() {
            ""
        } else {
            ", largest speed-ups:"
        }
    );
    for p in sg.worst().into_iter().take(5) {
        let peaks: Vec<String> = p
            .rotary
            .iter()
            .zip(&sg.peak_outside)
            .map(|(r, o)| {
                format!(
                    "{} {:.2} deg/s ({}{}; {:.2} elsewhere)",
                    r.axis,
                    r.peak,
                    line(r.line),
                    r.limit
                        .map(|lim| format!(", limit {lim:.2}"))
                        .unwrap_or_default(),
                    o.1
                )
            })
            .collect();
        println!(
            "  {} to {} (t {:.3}-{:.3} s), closest {:.4} deg: {}",
            line(p.start_line),
            line(p.end_line),
            p.start_s,
            p.end_s,
            p.closest_deg,
            peaks.join(", ")
        );
    }
}
