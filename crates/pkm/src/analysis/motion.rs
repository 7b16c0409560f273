//! Motion on a loaded machine: a G-code program (streamed line by line) or a
//! point-to-point move through the mechanism, every sample handed to a sink (a front
//! end writes them where it likes), the statistics, limits and serial comparison of
//! [`crate::motion::Runner`], and decimated series for plots.

// Parallel arrays (actuators, coordinates, sample vectors) are indexed together.
#![allow(clippy::needless_range_loop)]

use std::io::BufRead;

use crate::accuracy::path::{PathOptions, PathTracker};
use crate::error::{Error, Result};
use crate::machine::{Analysable, Machine, Visitor};
use crate::mechanism::PoseSpace;
use crate::motion::gcode::{Interpreter, ToolEvent};
use crate::motion::program::{profile, to_move, FeedOptions, ProfileKind};
use crate::motion::{MotionSummary, Move, Profile, Runner, Sample, Sampling, Segment, Step};

mod circle;
pub use circle::{study_circle, StudyCircle};

/// Where the moves come from.
pub enum MotionSource<'a> {
    /// A G-code program, read line by line, starting at `from` (pose coordinates,
    /// internal units; `None`: home). Needs a machine whose pose is X, Y, Z[, A, B, C]
    /// or tool-centre-point coordinates (X, Y, Z and rotary axes named A, B, C).
    Gcode {
        /// The program text.
        reader: Box<dyn BufRead + 'a>,
        /// Start pose.
        from: Option<Vec<f64>>,
        /// Tool lengths and work offsets.
        setup: Box<ProgramSetup>,
    },
    /// Straight moves through waypoints in the machine's own coordinates (internal
    /// units), each from rest to rest at the feed of [`FeedOptions::feed`] with its
    /// profile; the line number of a sample is its move's (1 = first to second point).
    Polyline {
        /// The waypoints, at least two.
        points: Vec<Vec<f64>>,
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

/// What a program needs besides its text: the tool lengths its `G43 H` words ask for
/// and the work offsets of `G54`..`G59.3`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ProgramSetup {
    /// Tool lengths (mm) by tool number (a tool table).
    pub tool_lengths: std::collections::BTreeMap<u32, f64>,
    /// The length (mm) of every tool the table does not list.
    pub tool_length: Option<f64>,
    /// Work offsets of G54, G55, ..., G59.3 (mm, rad), added to the program's
    /// coordinates.
    pub work_offsets: [[f64; 6]; 9],
}

impl ProgramSetup {
    /// The length of tool `h`, and whether it was given (0 when not).
    fn length(&self, h: u32) -> (f64, bool) {
        match self.tool_lengths.get(&h).copied().or(self.tool_length) {
            Some(l) => (l, true),
            None => (0.0, false),
        }
    }
}

/// One sample of a run (internal units: mm, rad, s).
#[derive(Debug, Clone, Copy)]
pub struct SampleRow<'a> {
    /// Time from the start (s).
    pub t: f64,
    /// G-code line of the move.
    pub line: Option<u64>,
    /// Pose coordinates.
    pub x: &'a [f64],
    /// Actuator positions.
    pub q: &'a [f64],
    /// Actuator velocities.
    pub qd: &'a [f64],
    /// Actuator accelerations.
    pub qdd: &'a [f64],
}

/// Receives a run's samples and progress.
pub trait SampleSink {
    /// One sample; an error stops the run.
    fn sample(&mut self, s: &SampleRow) -> Result<()>;
    /// `bytes` more of the program were read (for progress bars).
    fn progress(&mut self, _bytes: u64) {}
}

/// A sink that keeps nothing (summary only).
pub struct NoSink;

impl SampleSink for NoSink {
    fn sample(&mut self, _s: &SampleRow) -> Result<()> {
        Ok(())
    }
}

pub use crate::motion::decimated::Decimated;

/// Decimated time series kept for plots (at most 4000 rows, flat memory): per row
/// `t`, then per actuator `q, q', q''`, then per serial axis `x, x', x''`, in user
/// units (mm, deg).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Traces {
    /// The rows.
    pub rows: Decimated<Vec<f64>>,
    /// Where each program line's motion starts: `(t, line)` at every change of the
    /// line (G-code segment boundaries), at most [`MAX_SEGMENTS`] (beyond, the
    /// boundaries are too dense to draw and the list is emptied).
    pub segments: Vec<(f64, u64)>,
    #[serde(skip)]
    last_line: Option<u64>,
    #[serde(skip)]
    too_many: bool,
}

impl Default for Traces {
    fn default() -> Self {
        Traces {
            rows: Decimated::new(CAP),
            segments: Vec::new(),
            last_line: None,
            too_many: false,
        }
    }
}

const CAP: usize = 4000;

/// The most segment boundaries [`Traces::segments`] keeps.
pub const MAX_SEGMENTS: usize = 200;

impl Traces {
    fn line(&mut self, t: f64, line: Option<u64>) {
        let Some(l) = line else { return };
        if self.too_many || self.last_line == Some(l) {
            return;
        }
        self.last_line = Some(l);
        if self.segments.len() >= MAX_SEGMENTS {
            self.segments.clear();
            self.too_many = true;
        } else {
            self.segments.push((t, l));
        }
    }
}

/// What a run produces besides its samples.
#[derive(Debug, Clone, serde::Serialize)]
pub struct MotionRun {
    /// Statistics, limits along the path, serial comparison, feed override.
    pub summary: MotionSummary,
    /// Decimated series for plots.
    pub traces: Traces,
    /// What the program asked for that pkm noted without acting on it, or applied with
    /// an assumption (line, text): unknown M codes, tool changes, tool lengths.
    pub notes: Vec<(u64, String)>,
    /// Notes beyond the first [`crate::motion::gcode::MAX_NOTES`].
    pub notes_dropped: u64,
    /// The accuracy along the run, when asked for.
    pub accuracy: Option<PathAccuracyRun>,
}

/// Accuracy along a run: the tolerances' budget at every sample and per G-code line,
/// and a Monte Carlo band ([`crate::accuracy::path`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PathAccuracyRequest {
    /// Which tolerances.
    pub tolerances: super::accuracy::Tolerances,
    /// Machines of the Monte Carlo band (0: none).
    pub machines: usize,
    /// The band at every `every`-th sample.
    pub every: usize,
    /// Seed of the draws.
    pub seed: u64,
}

impl Default for PathAccuracyRequest {
    /// The machine file's tolerances, 100 machines at every 10th sample, seed 1.
    fn default() -> Self {
        PathAccuracyRequest {
            tolerances: super::accuracy::Tolerances::Default,
            machines: 100,
            every: 10,
            seed: 1,
        }
    }
}

/// What the accuracy along a run found.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PathAccuracyRun {
    /// Where the tolerances came from.
    pub tolerance_source: super::accuracy::ToleranceSource,
    /// The tolerances (internal units).
    pub tolerances: Vec<crate::accuracy::Tolerance>,
    /// Budget per sample and line, Monte Carlo band.
    #[serde(flatten)]
    pub path: crate::accuracy::path::PathAccuracy,
}

/// The columns of a sample row for tables: `t_s`, `line`, the pose coordinates with
/// their units, then per actuator position, velocity and acceleration.
pub fn sample_columns(machine: &Machine) -> Vec<String> {
    let m = machine.mechanism();
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
    h
}

/// Runs `source` through `machine` with feed and sampling settings, every sample to
/// `sink`.
pub fn run_motion(
    machine: &Machine,
    source: MotionSource<'_>,
    feed: &FeedOptions,
    sampling: Sampling,
    sink: &mut dyn SampleSink,
) -> Result<MotionRun> {
    run_motion_with(machine, source, feed, sampling, None, sink)
}

/// [`run_motion`], and the accuracy along the run when `accuracy` asks for it (every
/// machine type: the tolerances' budget at each sample, [`crate::accuracy::path`]).
pub fn run_motion_with(
    machine: &Machine,
    source: MotionSource<'_>,
    feed: &FeedOptions,
    sampling: Sampling,
    accuracy: Option<&PathAccuracyRequest>,
    sink: &mut dyn SampleSink,
) -> Result<MotionRun> {
    machine.visit(Simulate {
        source,
        feed,
        sampling,
        sink,
        accuracy: accuracy.map(|a| (a, machine.tolerances())),
    })
}

struct Simulate<'a, 'b> {
    source: MotionSource<'b>,
    feed: &'a FeedOptions,
    sampling: Sampling,
    sink: &'a mut dyn SampleSink,
    accuracy: Option<(&'a PathAccuracyRequest, &'a [crate::accuracy::Tolerance])>,
}

fn invalid(what: &str, message: impl Into<String>) -> Error {
    Error::InvalidInput {
        what: what.into(),
        message: message.into(),
    }
}

impl Visitor for Simulate<'_, '_> {
    type Output = Result<MotionRun>;

    fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(
        self,
        m: &M,
    ) -> Result<MotionRun> {
        let mut runner = Runner::new(m, self.sampling)?;
        runner.set_max_samples(self.feed.max_samples);
        runner.set_singular_angle(self.feed.singular_angle)?;
        let mut notes: Vec<(u64, String)> = Vec::new();
        let mut dropped = 0;
        let serial_idx: Vec<usize> = match m.pose_space() {
            PoseSpace::Own => (0..P).collect(),
            _ => (0..3).collect(),
        };
        let mut traces = Traces::default();
        // The accuracy along the path: on the machine prepared for the tolerances.
        let prepared;
        let mut tracker = match self.accuracy {
            Some((req, file)) => {
                let params = m.parameters();
                let (source, tol) = req.tolerances.resolve(&params, &m.tolerable(), file)?;
                let mut given: Vec<usize> = tol.iter().map(|t| t.parameter).collect();
                given.sort_unstable();
                given.dedup();
                prepared = m.with_given(&given)?;
                let pm = prepared.as_ref().unwrap_or(m);
                let t = PathTracker::new(
                    pm,
                    &PathOptions {
                        tolerances: tol.clone(),
                        machines: req.machines,
                        every: req.every,
                        seed: req.seed,
                    },
                )?;
                Some((source, tol, t))
            }
            None => None,
        };
        let tracker_cell = std::cell::RefCell::new(tracker.as_mut().map(|t| &mut t.2));
        // Samples and progress go to the same sink: shared by a RefCell, borrowed
        // once per sample and once per program line.
        let out = std::cell::RefCell::new(self.sink);
        let mut sink = |s: &Sample<P, A>| -> Result<()> {
            if let Some(t) = tracker_cell.borrow_mut().as_mut() {
                t.add(s.t, s.line, &s.x, &s.act.q)?;
            }
            let act = m.actuators();
            let coords = m.coordinates();
            traces.line(s.t, s.line);
            traces.rows.push(|| {
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
            out.borrow_mut().sample(&SampleRow {
                t: s.t,
                line: s.line,
                x: s.x.as_slice(),
                q: s.act.q.as_slice(),
                qd: s.act.qd.as_slice(),
                qdd: s.act.qdd.as_slice(),
            })
        };
        let mut on_tool = |length: f64| -> Result<()> {
            match tracker_cell.borrow_mut().as_mut() {
                Some(t) => t.set_tool_length(length),
                None => Ok(()),
            }
        };
        match self.source {
            MotionSource::PointToPoint {
                from,
                to,
                duration,
                accel_time,
            } => {
                let from = crate::dynamic::fixed::<P>("--from", &from)?;
                let to = crate::dynamic::fixed::<P>("--to", &to)?;
                let q = crate::motion::run::quantities(m);
                let spatial = m.pose_space() != PoseSpace::Own;
                let segment = Segment::line(from, to, &q, spatial);
                let prof = match (duration, accel_time, self.feed.profile) {
                    (Some(d), Some(ta), ProfileKind::Trapezoid) => {
                        Profile::trapezoid_timed(segment.length, d, ta)?
                    }
                    (Some(_), Some(_), _) => {
                        return Err(invalid("--accel-time", "needs --profile trapezoid"))
                    }
                    (Some(d), None, ProfileKind::Constant) => {
                        Profile::constant(segment.length, segment.length / d)?
                    }
                    (Some(_), None, _) => {
                        return Err(invalid(
                            "--duration",
                            "with --profile trapezoid needs --accel-time; with scurve give --feed instead",
                        ))
                    }
                    (None, _, kind) => {
                        let v = self
                            .feed
                            .feed
                            .ok_or_else(|| invalid("feed", "give --feed or --duration"))?;
                        profile(kind, segment.length, v, self.feed)?
                    }
                };
                let mv = Move {
                    segment,
                    profile: prof,
                    line: None,
                    rapid: false,
                };
                let step = Step::Move { mv, last: true };
                runner.run_steps([Ok(step)], &mut sink, &mut on_tool)?;
            }
            MotionSource::Polyline { points } => {
                if points.len() < 2 {
                    return Err(invalid(
                        "path",
                        format!("expected at least 2 waypoints, got {}", points.len()),
                    ));
                }
                let v = self
                    .feed
                    .feed
                    .ok_or_else(|| invalid("feed", "a path needs a feed (mm/s or deg/s)"))?;
                let q = crate::motion::run::quantities(m);
                let spatial = m.pose_space() != PoseSpace::Own;
                let pts = points
                    .iter()
                    .enumerate()
                    .map(|(i, x)| crate::dynamic::fixed::<P>(&format!("waypoint {}", i + 1), x))
                    .collect::<Result<Vec<_>>>()?;
                // Repeated waypoints make no move.
                let moves: Vec<(usize, Segment<P>)> = pts
                    .windows(2)
                    .map(|w| Segment::line(w[0], w[1], &q, spatial))
                    .enumerate()
                    .filter(|(_, s)| s.length > 0.0)
                    .collect();
                let n = moves.len();
                let steps = moves.into_iter().enumerate().map(|(k, (i, segment))| {
                    Ok(Step::Move {
                        mv: Move {
                            profile: profile(self.feed.profile, segment.length, v, self.feed)?,
                            segment,
                            line: Some(i as u64 + 1),
                            rapid: false,
                        },
                        last: k + 1 == n,
                    })
                });
                runner.run_steps(steps, &mut sink, &mut on_tool)?;
            }
            MotionSource::Gcode {
                mut reader,
                from,
                setup,
            } => {
                if m.pose_space() == PoseSpace::Own {
                    return Err(invalid(
                        "G-code",
                        "needs a machine whose pose is X, Y, Z[, A, B, C] or tool-centre-point \
                         coordinates",
                    ));
                }
                let x = match from {
                    Some(x) => crate::dynamic::fixed::<P>("start pose", &x)?,
                    None => m.home(),
                };
                let mut interp = Interpreter::new(crate::motion::run::to_spatial(m, &x));
                interp.work_offsets = setup.work_offsets;
                // Moves are handed on one line late: the last is known at the end.
                let mut pending: Option<Move<P>> = None;
                let mut queue: std::collections::VecDeque<Step<P>> = Default::default();
                // One line at a time into one buffer (`BufRead::lines` would allocate a
                // string per line): the same lines, the same errors.
                let (mut buf, mut i) = (String::new(), 0usize);
                let mut done = false;
                let interp_ref = &mut interp;
                let mut next_line = |queue: &mut std::collections::VecDeque<Step<P>>,
                                     pending: &mut Option<Move<P>>|
                 -> Result<bool> {
                    buf.clear();
                    let read = reader
                        .read_line(&mut buf)
                        .map_err(|e| invalid("G-code", format!("reading line {}: {e}", i + 1)))?;
                    if read == 0 {
                        return Ok(false);
                    }
                    i += 1;
                    let text = match buf.strip_suffix('\n') {
                        Some(t) => t.strip_suffix('\r').unwrap_or(t),
                        None => &buf,
                    };
                    out.borrow_mut().progress(text.len() as u64 + 1);
                    if interp_ref.ended {
                        return Ok(false);
                    }
                    let g = interp_ref.line(text, i as u64)?;
                    let mv = match &g {
                        Some(g) => Some(to_move(m, g, self.feed)?),
                        None => None,
                    };
                    if let Some(ev) = interp_ref.tool_event.take() {
                        // The moves before this line run with the tool they had.
                        if let Some(p) = pending.take() {
                            queue.push_back(Step::Move { mv: p, last: false });
                        }
                        let (line, length) = match ev {
                            ToolEvent::Apply { h, line } => {
                                let (l, given) = setup.length(h);
                                let what = if given {
                                    format!("G43 H{h}: tool length {l} mm")
                                } else {
                                    format!(
                                        "G43 H{h}: no length given for tool {h} (--tool-table, \
                                         --tool-length): taken as 0, the machine file's tool"
                                    )
                                };
                                interp_ref.note(line, what);
                                (line, l)
                            }
                            ToolEvent::Cancel { line } => (line, 0.0),
                        };
                        queue.push_back(Step::ToolLength { length, line });
                    }
                    if let Some(mv) = mv {
                        if let Some(p) = pending.replace(mv) {
                            queue.push_back(Step::Move { mv: p, last: false });
                        }
                    }
                    Ok(true)
                };
                let steps = std::iter::from_fn(|| loop {
                    if let Some(s) = queue.pop_front() {
                        return Some(Ok(s));
                    }
                    if done {
                        return None;
                    }
                    match next_line(&mut queue, &mut pending) {
                        Ok(true) => {}
                        Ok(false) => {
                            done = true;
                            if let Some(p) = pending.take() {
                                return Some(Ok(Step::Move { mv: p, last: true }));
                            }
                        }
                        Err(e) => {
                            done = true;
                            return Some(Err(e));
                        }
                    }
                });
                runner.run_steps(steps, &mut sink, &mut on_tool)?;
                notes = std::mem::take(&mut interp.notes);
                dropped = interp.notes_dropped;
            }
        }
        let summary = runner.finish();
        Ok(MotionRun {
            summary,
            traces,
            notes,
            notes_dropped: dropped,
            accuracy: tracker.map(|(tolerance_source, tolerances, t)| PathAccuracyRun {
                tolerance_source,
                tolerances,
                path: t.finish(),
            }),
        })
    }
}

/// The feed settings of a run on `machine`: the defaults with the rapid rate of its
/// file's `[motion]` table.
pub fn feed_options(machine: &Machine) -> FeedOptions {
    let d = FeedOptions::default();
    FeedOptions {
        rapid: machine.rapid.unwrap_or(d.rapid),
        ..d
    }
}
