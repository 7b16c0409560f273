//! Motion on a loaded machine: a G-code program (streamed line by line) or a
//! point-to-point move through the mechanism, every sample handed to a sink (a front
//! end writes them where it likes), the statistics, limits and serial comparison of
//! [`crate::motion::Runner`], and decimated series for plots.

// Parallel arrays (actuators, coordinates, sample vectors) are indexed together.
#![allow(clippy::needless_range_loop)]

use std::io::BufRead;

use crate::error::Result;
use crate::machine::Machine;
use crate::motion::program::FeedOptions;
use crate::motion::{MotionSummary, Sampling};

mod circle;
mod simulate;
pub use circle::{study_circle, StudyCircle};
use simulate::Simulate;

/// Where the moves come from.
///
/// # Examples
///
/// Out 10 mm along X and back as a polyline at 5 mm/s: two moves of 2 s each.
///
/// ```
/// use pkm::analysis::motion::{feed_options, run_motion, MotionSource, NoSink};
/// use pkm::motion::program::FeedOptions;
/// use pkm::motion::Sampling;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let mut out = home.clone();
/// out[0] += 10.0;
/// let source = MotionSource::Polyline { points: vec![home.clone(), out, home] };
/// let feed = FeedOptions { feed: Some(5.0), ..feed_options(&machine) };
/// let run = run_motion(&machine, source, &feed, Sampling::Rate(50.0), &mut NoSink).unwrap();
/// assert!((run.summary.duration_s - 4.0).abs() < 1e-9);
/// // The struts come back where they started: none moved further than the X travel.
/// let mut travel = run.summary.actuators.iter().map(|(_, s)| s.travel);
/// assert!(travel.all(|t| t > 0.0 && t <= 20.0 + 1e-9));
/// ```
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
///
/// # Examples
///
/// ```
/// use pkm::analysis::motion::ProgramSetup;
/// let mut setup = ProgramSetup { tool_length: Some(50.0), ..Default::default() };
/// setup.tool_lengths.insert(1, 120.0); // T1 / G43 H1: 120 mm
/// setup.work_offsets[1] = [100.0, 0.0, 0.0, 0.0, 0.0, 0.0]; // G55: X + 100 mm
/// assert_eq!(setup.tool_lengths[&1], 120.0);
/// assert_eq!(setup.work_offsets[0], [0.0; 6]); // G54 left at zero
/// ```
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
///
/// # Examples
///
/// See [`SampleSink`].
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
///
/// # Examples
///
/// A sink keeping the time and the first actuator's position of every sample.
///
/// ```
/// use pkm::analysis::motion::{run_motion, MotionSource, SampleRow, SampleSink};
/// use pkm::motion::program::FeedOptions;
/// use pkm::motion::Sampling;
/// struct Keep(Vec<(f64, f64)>);
/// impl SampleSink for Keep {
///     fn sample(&mut self, s: &SampleRow) -> pkm::Result<()> {
///         self.0.push((s.t, s.q[0]));
///         Ok(())
///     }
/// }
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let m = machine.mechanism();
/// let from = m.home();
/// let mut to = from.clone();
/// to[2] += 20.0;
/// let source = MotionSource::PointToPoint {
///     from: from.clone(),
///     to: to.clone(),
///     duration: Some(2.0),
///     accel_time: None,
/// };
/// let mut keep = Keep(Vec::new());
/// run_motion(&machine, source, &FeedOptions::default(), Sampling::Points(11), &mut keep).unwrap();
/// assert_eq!(keep.0.len(), 11);
/// let (t_end, q_end) = *keep.0.last().unwrap();
/// assert!((t_end - 2.0).abs() < 1e-12);
/// assert!((q_end - m.inverse(&to).unwrap()[0]).abs() < 1e-9);
/// ```
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

pub use crate::motion::decimated::{Decimated, DecimatedRows};

/// Decimated time series kept for plots (at most 4000 rows, flat memory): per row
/// `t`, then per actuator `q, q', q''`, then per serial axis `x, x', x''`, in user
/// units (mm, deg).
///
/// # Examples
///
/// ```
/// use pkm::analysis::motion::{run_motion, MotionSource, NoSink};
/// use pkm::motion::program::FeedOptions;
/// use pkm::motion::Sampling;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/tripod-seed000.toml"
/// ))
/// .unwrap();
/// let program = "G21 G90\nG1 X5 Y2 F600\nG1 X-3 Y4\n";
/// let source = MotionSource::Gcode {
///     reader: Box::new(program.as_bytes()),
///     from: None,
///     setup: Default::default(),
/// };
/// let feed = FeedOptions::default();
/// let run = run_motion(&machine, source, &feed, Sampling::Rate(100.0), &mut NoSink).unwrap();
/// let traces = &run.traces;
/// // Every sample is kept below the cap; each row is t, then q, q', q'' per strut,
/// // then x, x', x'' per serial axis (X, Y, Z).
/// assert_eq!(traces.rows.len() as u64, run.summary.samples);
/// assert!(traces.rows.iter().all(|row| row.len() == 1 + 3 * 3 + 3 * 3));
/// // The two G1 lines start where the segments say.
/// assert_eq!(traces.segments.iter().map(|s| s.1).collect::<Vec<_>>(), [2, 3]);
/// ```
#[derive(Debug, Clone, serde::Serialize)]
pub struct Traces {
    /// The rows.
    pub rows: DecimatedRows,
    /// Where each program line's motion starts: `(t, line)` at every change of the
    /// line (G-code segment boundaries), at most [`MAX_SEGMENTS`] (beyond, the
    /// boundaries are too dense to draw and the list is emptied).
    pub segments: Vec<(f64, u64)>,
    #[serde(skip)]
    last_line: Option<u64>,
    #[serde(skip)]
    too_many: bool,
}

const CAP: usize = 4000;

/// The most segment boundaries [`Traces::segments`] keeps.
pub const MAX_SEGMENTS: usize = 200;

impl Traces {
    /// No rows yet; each will hold `width` numbers.
    fn new(width: usize) -> Self {
        Traces {
            rows: DecimatedRows::new(CAP, width),
            segments: Vec::new(),
            last_line: None,
            too_many: false,
        }
    }

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
///
/// # Examples
///
/// ```
/// use pkm::analysis::motion::{run_motion, MotionSource, NoSink};
/// use pkm::motion::program::FeedOptions;
/// use pkm::motion::Sampling;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/tripod-seed000.toml"
/// ))
/// .unwrap();
/// // A tool change is noted, not acted on.
/// let program = "G21 G90\nT2 M6\nG1 X10 F600\n";
/// let source = MotionSource::Gcode {
///     reader: Box::new(program.as_bytes()),
///     from: None,
///     setup: Default::default(),
/// };
/// let feed = FeedOptions::default();
/// let run = run_motion(&machine, source, &feed, Sampling::Rate(100.0), &mut NoSink).unwrap();
/// assert!((run.summary.duration_s - 1.0).abs() < 1e-9); // 10 mm at 600 mm/min
/// assert!(run.summary.violations.is_empty());
/// assert!(run.notes.iter().any(|(line, _)| *line == 2), "{:?}", run.notes);
/// assert!(run.accuracy.is_none()); // not asked for
/// ```
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
///
/// # Examples
///
/// ```
/// use pkm::analysis::motion::PathAccuracyRequest;
/// use pkm::analysis::Tolerances;
/// let r = PathAccuracyRequest::default();
/// assert_eq!(r.tolerances, Tolerances::Default); // the machine file's, else by kind
/// assert_eq!((r.machines, r.every, r.seed), (100, 10, 1));
/// // The budget along the path only, no Monte Carlo band.
/// let budget_only = PathAccuracyRequest { machines: 0, ..r };
/// assert_eq!(budget_only.machines, 0);
/// ```
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
///
/// # Examples
///
/// See [`run_motion_with`].
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
///
/// # Examples
///
/// ```
/// use pkm::analysis::motion::sample_columns;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/tripod-seed000.toml"
/// ))
/// .unwrap();
/// let c = sample_columns(&machine);
/// assert_eq!(&c[..3], ["t_s", "line", "X_mm"]);
/// // Time and line, six pose coordinates, three per strut.
/// assert_eq!(c.len(), 2 + 6 + 3 * 3);
/// assert_eq!(&c[c.len() - 3..], ["g_mm", "g_mm_per_s", "g_mm_per_s2"]);
/// ```
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
///
/// # Examples
///
/// A G-code line on the seed 000 tripod from home: 10 mm along X at 600 mm/min takes
/// one second; at 100 Hz that is 101 samples.
///
/// ```
/// use pkm::analysis::motion::{feed_options, run_motion, MotionSource, NoSink};
/// use pkm::motion::Sampling;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/tripod-seed000.toml"
/// ))
/// .unwrap();
/// let source = MotionSource::Gcode {
///     reader: Box::new("G21 G90\nG1 X10 F600\n".as_bytes()),
///     from: None,
///     setup: Default::default(),
/// };
/// let feed = feed_options(&machine);
/// let run = run_motion(&machine, source, &feed, Sampling::Rate(100.0), &mut NoSink).unwrap();
/// assert!((run.summary.duration_s - 1.0).abs() < 1e-9);
/// assert!(run.summary.samples >= 100 && run.summary.samples <= 102);
/// assert_eq!(run.summary.actuators.len(), 3);
/// ```
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
///
/// # Examples
///
/// ```
/// use pkm::analysis::motion::{run_motion_with, MotionSource, NoSink, PathAccuracyRequest};
/// use pkm::motion::program::FeedOptions;
/// use pkm::motion::Sampling;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let from = machine.mechanism().home();
/// let mut to = from.clone();
/// to[0] += 50.0;
/// let source = MotionSource::PointToPoint { from, to, duration: Some(1.0), accel_time: None };
/// let request = PathAccuracyRequest { machines: 20, every: 5, ..Default::default() };
/// let feed = FeedOptions::default();
/// let sampling = Sampling::Points(21);
/// let run = run_motion_with(&machine, source, &feed, sampling, Some(&request), &mut NoSink)
///     .unwrap();
/// let acc = run.accuracy.unwrap();
/// assert_eq!(acc.path.samples, 21);
/// assert!(acc.path.tolerances > 0 && acc.path.tolerances == acc.tolerances.len());
/// // The worst case bounds the root sum of squares, all along the path.
/// assert!(acc.path.worst_case.0 >= acc.path.rss.0 && acc.path.rss.0 > 0.0);
/// assert!(acc.path.monte_carlo.is_some());
/// ```
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

/// The feed settings of a run on `machine`: the defaults with the rapid rate of its
/// file's `[motion]` table.
///
/// # Examples
///
/// ```
/// use pkm::analysis::motion::feed_options;
/// use pkm::motion::program::FeedOptions;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/tripod-seed000.toml"
/// ))
/// .unwrap();
/// // The file's `[motion] rapid = 6000.0` (mm/min) is 100 mm/s; the rest are defaults.
/// let f = feed_options(&machine);
/// assert_eq!(f.rapid, 100.0);
/// assert_eq!(f.acceleration, FeedOptions::default().acceleration);
/// ```
pub fn feed_options(machine: &Machine) -> FeedOptions {
    let d = FeedOptions::default();
    FeedOptions {
        rapid: machine.rapid.unwrap_or(d.rapid),
        ..d
    }
}
