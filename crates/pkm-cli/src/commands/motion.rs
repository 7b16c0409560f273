//! `pkm motion`: a tool path or G-code program through the machine: actuator position,
//! velocity and acceleration over time, the serial comparison and limits.

// Parallel arrays (actuators, coordinates, sample vectors) are indexed together.
#![allow(clippy::needless_range_loop)]

use std::fs::File;
use std::io::{BufRead, BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use pkm::motion::gcode::Interpreter;
use pkm::motion::program::{profile, to_move, FeedOptions, ProfileKind};
use pkm::motion::{MotionSummary, Move, Profile, Runner, Sample, Sampling, Segment};
use pkm::{DynMechanism, Machine, Mechanism, PoseSpace, Visitor};
use serde_json::json;

use super::load;
use crate::io::{refuse_overwrite, write_atomic};
use crate::poses::{parse_list, pose_from_user};
use crate::report::plot::{panels_svg, Series};
use crate::{MotionArgs, EXIT_UNREACHABLE};

/// Where the moves come from.
pub enum Source {
    /// A G-code program (streamed line by line) starting at `start` (mm, rad).
    Gcode {
        /// Reader of the program text.
        reader: Box<dyn BufRead>,
        /// Total bytes, for the progress bar.
        bytes: u64,
        /// Start `[X, Y, Z, A, B, C]`.
        start: [f64; 6],
    },
    /// One straight move in the machine's own coordinates (internal units).
    PointToPoint {
        /// Start pose coordinates.
        from: Vec<f64>,
        /// End pose coordinates.
        to: Vec<f64>,
        /// Duration (s), instead of a feed.
        duration: Option<f64>,
        /// Acceleration time of a timed trapezoid (s).
        accel_time: Option<f64>,
    },
}

/// Decimated time series kept for plots (at most `CAP` rows, flat memory).
#[derive(Default)]
pub struct Traces {
    /// Rows: t, then per actuator q, qd, qdd, then per serial axis x, xd, xdd (user units).
    pub rows: Vec<Vec<f64>>,
    stride: u64,
    seen: u64,
}

const CAP: usize = 4000;

impl Traces {
    fn push(&mut self, row: impl FnOnce() -> Vec<f64>) {
        if self.stride == 0 {
            self.stride = 1;
        }
        if self.seen.is_multiple_of(self.stride) {
            if self.rows.len() >= CAP {
                let kept: Vec<Vec<f64>> = self.rows.drain(..).step_by(2).collect();
                self.rows = kept;
                self.stride *= 2;
            }
            if self.seen.is_multiple_of(self.stride) {
                self.rows.push(row());
            }
        }
        self.seen += 1;
    }
}

/// Everything a run produces besides the CSV.
pub struct Outcome {
    /// The summary.
    pub summary: MotionSummary,
    /// Decimated series for plots.
    pub traces: Traces,
}

/// Generic simulation, run through [`Machine::visit`].
pub struct Simulate<'a> {
    /// Moves.
    pub source: Source,
    /// Timing.
    pub feed: FeedOptions,
    /// Sampling.
    pub sampling: Sampling,
    /// CSV sink (header and rows), if any.
    pub csv: Option<&'a mut dyn Write>,
    /// Show a progress bar.
    pub progress: bool,
}

fn csv_header<M: Mechanism<P, A>, const P: usize, const A: usize>(m: &M) -> String {
    let mut h = vec!["t_s".to_string(), "line".to_string()];
    for c in m.coordinates() {
        h.push(format!("{}_{}", c.name, c.quantity.unit()));
    }
    for a in m.actuators() {
        let u = a.quantity.unit();
        h.push(format!("{}_{u}", a.name));
        h.push(format!("{}_{u}_per_s", a.name));
        h.push(format!("{}_{u}_per_s2", a.name));
    }
    h.join(",")
}

impl Visitor for Simulate<'_> {
    type Output = Result<Outcome>;

    fn visit<M: Mechanism<P, A>, const P: usize, const A: usize>(
        mut self,
        m: &M,
    ) -> Result<Outcome> {
        let mut runner = Runner::new(m, self.sampling)?;
        let serial_idx: Vec<usize> = match m.pose_space() {
            PoseSpace::Own => (0..P).collect(),
            _ => (0..3).collect(),
        };
        let mut traces = Traces::default();
        if let Some(w) = self.csv.as_deref_mut() {
            writeln!(w, "{}", csv_header(m))?;
        }
        let mut csv = self.csv;
        let mut line_buf = String::with_capacity(256);
        let mut sink = |s: &Sample<P, A>| -> pkm::Result<()> {
            let act = m.actuators();
            let coords = m.coordinates();
            traces.push(|| {
                let mut r = Vec::with_capacity(1 + 3 * A + 3 * serial_idx.len());
                r.push(s.t);
                for i in 0..A {
                    let qn = act[i].quantity;
                    r.extend([
                        qn.to_user(s.act.q[i]),
                        qn.to_user(s.act.qd[i]),
                        qn.to_user(s.act.qdd[i]),
                    ]);
                }
                for &k in &serial_idx {
                    let qn = coords[k].quantity;
                    r.extend([
                        qn.to_user(s.x[k]),
                        qn.to_user(s.xd[k]),
                        qn.to_user(s.xdd[k]),
                    ]);
                }
                r
            });
            if let Some(w) = csv.as_deref_mut() {
                use std::fmt::Write as _;
                line_buf.clear();
                let _ = write!(line_buf, "{:.6}", s.t);
                match s.line {
                    Some(l) => {
                        let _ = write!(line_buf, ",{l}");
                    }
                    None => line_buf.push(','),
                }
                for k in 0..P {
                    let _ = write!(line_buf, ",{:.6}", coords[k].quantity.to_user(s.x[k]));
                }
                for i in 0..A {
                    let qn = act[i].quantity;
                    let _ = write!(
                        line_buf,
                        ",{:.6},{:.6},{:.6}",
                        qn.to_user(s.act.q[i]),
                        qn.to_user(s.act.qd[i]),
                        qn.to_user(s.act.qdd[i])
                    );
                }
                line_buf.push('\n');
                w.write_all(line_buf.as_bytes())
                    .map_err(|e| pkm::Error::InvalidInput {
                        what: "actuators.csv".into(),
                        message: e.to_string(),
                    })?;
            }
            Ok(())
        };
        match self.source {
            Source::PointToPoint {
                from,
                to,
                duration,
                accel_time,
            } => {
                let from = pkm::dynamic::fixed::<P>("--from", &from)?;
                let to = pkm::dynamic::fixed::<P>("--to", &to)?;
                let q = pkm::motion::run::quantities(m);
                let spatial = m.pose_space() != PoseSpace::Own;
                let segment = Segment::line(from, to, &q, spatial);
                let prof = match (duration, accel_time, self.feed.profile) {
                    (Some(d), Some(ta), ProfileKind::Trapezoid) => Profile::trapezoid_timed(segment.length, d, ta)?,
                    (Some(_), Some(_), _) => bail!("--accel-time needs --profile trapezoid"),
                    (Some(d), None, ProfileKind::Constant) => Profile::constant(segment.length, segment.length / d)?,
                    (Some(_), None, _) => bail!("--duration with --profile trapezoid needs --accel-time; with scurve give --feed instead"),
                    (None, _, kind) => {
                        let v = self.feed.feed.context("give --feed or --duration")?;
                        profile(kind, segment.length, v, &self.feed)?
                    }
                };
                runner.run_move(
                    &Move {
                        segment,
                        profile: prof,
                        line: None,
                    },
                    true,
                    &mut sink,
                )?;
            }
            Source::Gcode {
                reader,
                bytes,
                start,
            } => {
                let bar = if self.progress && bytes > 1_000_000 {
                    let b = ProgressBar::new(bytes);
                    b.set_style(
                        ProgressStyle::with_template("{bar:40} {bytes}/{total_bytes} {eta}")
                            .unwrap_or_else(|_| ProgressStyle::default_bar()),
                    );
                    Some(b)
                } else {
                    None
                };
                let mut interp = Interpreter::new(start);
                let mut pending: Option<Move<P>> = None;
                for (i, line) in reader.lines().enumerate() {
                    let text = line.with_context(|| format!("reading G-code line {}", i + 1))?;
                    if let Some(b) = &bar {
                        b.inc(text.len() as u64 + 1);
                    }
                    if interp.ended {
                        break;
                    }
                    if let Some(g) = interp.line(&text, i as u64 + 1)? {
                        let mv = to_move(m, &g, &self.feed)?;
                        if let Some(p) = pending.take() {
                            runner.run_move(&p, false, &mut sink)?;
                        }
                        pending = Some(mv);
                    }
                }
                if let Some(p) = pending.take() {
                    runner.run_move(&p, true, &mut sink)?;
                }
                if let Some(b) = bar {
                    b.finish_and_clear();
                }
            }
        }
        Ok(Outcome {
            summary: runner.finish(),
            traces,
        })
    }
}

/// The plots of a run: actuators (position, velocity, acceleration) and serial axes.
pub fn plots(m: &dyn DynMechanism, o: &Outcome, title: &str) -> Result<(String, String)> {
    let a = m.actuators();
    let serial: Vec<(String, &'static str)> = o
        .summary
        .serial
        .iter()
        .map(|(n, _)| {
            let unit = m
                .coordinates()
                .iter()
                .find(|c| &c.name == n)
                .map(|c| c.quantity.unit())
                .unwrap_or("mm");
            (n.clone(), unit)
        })
        .collect();
    let col =
        |c: usize| -> Vec<(f64, f64)> { o.traces.rows.iter().map(|r| (r[0], r[c])).collect() };
    let panel = |names: &[(String, &str)], base: usize, title: &str| -> Result<String> {
        let kinds = [
            ("position", ""),
            ("velocity", "/s"),
            ("acceleration", "/s²"),
        ];
        let unit = names.first().map(|n| n.1).unwrap_or("mm");
        let panels: Vec<(String, String, Vec<Series>)> = kinds
            .iter()
            .enumerate()
            .map(|(k, (kind, suffix))| {
                let series = names
                    .iter()
                    .enumerate()
                    .map(|(i, (n, _))| Series {
                        name: n.clone(),
                        points: col(base + 3 * i + k),
                    })
                    .collect();
                (kind.to_string(), format!("{kind} [{unit}{suffix}]"), series)
            })
            .collect();
        panels_svg(title, &panels, (620, 760))
    };
    let anames: Vec<(String, &str)> = a
        .iter()
        .map(|x| (x.name.clone(), x.quantity.unit()))
        .collect();
    let act = panel(&anames, 1, &format!("{title}: actuators"))?;
    let ser = panel(
        &serial,
        1 + 3 * a.len(),
        &format!("{title}: serial machine"),
    )?;
    Ok((act, ser))
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
            .or(machine.rapid)
            .unwrap_or(10_000.0 / 60.0),
        feed: a.feed.map(|f| f / 60.0),
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
    let source = if let Some(g) = &a.gcode {
        let start = match m.pose_space() {
            PoseSpace::Own => bail!("G-code needs a machine whose pose is X, Y, Z[, A, B, C]"),
            _ => {
                let x = from.clone().unwrap_or_else(|| m.home());
                let mut s = [0.0; 6];
                s[..x.len()].copy_from_slice(&x);
                s
            }
        };
        let f = File::open(g).with_context(|| format!("cannot read {}", g.display()))?;
        let bytes = f.metadata().map(|x| x.len()).unwrap_or(0);
        Source::Gcode {
            reader: Box::new(BufReader::new(f)),
            bytes,
            start,
        }
    } else {
        let to =
            a.to.as_ref()
                .context("give --gcode FILE, or --from POSE --to POSE")?;
        Source::PointToPoint {
            from: from.unwrap_or_else(|| m.home()),
            to: pose_from_user(m, &parse_list(to, "--to")?, conv)?,
            duration: a.duration,
            accel_time: a.accel_time,
        }
    };
    let mut inputs: Vec<&Path> = vec![&a.machine];
    if let Some(g) = &a.gcode {
        inputs.push(g);
    }
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let csv_path = a.out.join("actuators.csv");
    refuse_overwrite(&csv_path, &inputs)?;
    let tmp: PathBuf = a
        .out
        .join(format!(".actuators.csv.tmp-{}", std::process::id()));
    let mut writer = if a.summary_only {
        None
    } else {
        Some(BufWriter::with_capacity(
            1 << 20,
            File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?,
        ))
    };
    let outcome = machine.visit(Simulate {
        source,
        feed,
        sampling,
        csv: writer.as_mut().map(|w| w as &mut dyn Write),
        progress: true,
    });
    let outcome = match outcome {
        Ok(o) => o,
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
    };
    if let Some(mut w) = writer {
        w.flush()?;
        drop(w);
        std::fs::rename(&tmp, &csv_path)
            .with_context(|| format!("cannot write {}", csv_path.display()))?;
    }
    let s = &outcome.summary;
    let mut summary = summary_json(&machine, s, &feed);
    // A move timed by --duration (and --accel-time) is not shaped by the path
    // acceleration/jerk options: say what timed it instead.
    if let Some(d) = a.duration {
        summary["profile"] = json!({
            "profile": summary["profile"]["profile"],
            "duration_s": d,
            "accel_time_s": a.accel_time,
        });
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
        println!(
            "{:<10} {:>12} {:>14} {:>14} {:>16} {:>16}",
            "axis", "travel", "peak |v|", "mean |v|", "peak |a|", "mean |a|"
        );
        for (kind, list) in [("actuator", &s.actuators), ("serial", &s.serial)] {
            for (n, st) in list.iter() {
                println!(
                    "{:<10} {:>12.4} {:>14.4} {:>14.4} {:>16.4} {:>16.4}",
                    format!("{kind} {n}"),
                    st.travel,
                    st.peak_velocity,
                    st.mean_abs_velocity,
                    st.peak_acceleration,
                    st.mean_abs_acceleration
                );
            }
        }
        println!(
            "ratios serial/PKM: travel {:.3}, peak velocity {:.3}, peak acceleration {:.3}",
            s.ratios.travel, s.ratios.velocity, s.ratios.acceleration
        );
        match s.feed_override_max {
            Some(k) => println!(
                "largest feed override within the actuator rate limits: {:.4}",
                k
            ),
            None => println!("largest feed override: no rate limits in the machine file"),
        }
        println!("wrote {}", a.out.display());
    }
    if s.violations.is_empty() {
        Ok(0)
    } else {
        let v = &s.violations[0];
        eprintln!(
            "error: {} limit violations along the path; first: {} {:.3} {} beyond {:.3} {} at t = {:.4} s{}",
            s.violations.len() as u64 + s.violations_not_listed,
            v.limit,
            v.worst,
            v.unit,
            v.bound,
            v.unit,
            v.start_s,
            v.line.map(|l| format!(" (G-code line {l})")).unwrap_or_default()
        );
        Ok(EXIT_UNREACHABLE)
    }
}
