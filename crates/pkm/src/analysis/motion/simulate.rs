//! The run behind [`super::run_motion_with`]: a visitor over the machine's type that
//! feeds the program (or the point-to-point move) to a [`Runner`], the accuracy along
//! the path to its tracker, each sample to the sink and the report's traces.

use std::cell::RefCell;

use super::{
    MotionRun, MotionSource, PathAccuracyRequest, PathAccuracyRun, SampleRow, SampleSink, Traces,
};
use crate::accuracy::path::{PathOptions, PathTracker};
use crate::analysis::accuracy::ToleranceSource;
use crate::error::{Error, Result};
use crate::machine::{Analysable, Visitor};
use crate::mechanism::PoseSpace;
use crate::motion::program::{check_duration, profile, FeedOptions, ProfileKind};
use crate::motion::{Move, Profile, RunSink, Runner, Sample, Sampling, Segment, Step};

mod program;
use program::ProgramSteps;

/// A run of a motion source on the machine visited, with its settings and sink.
pub(super) struct Simulate<'a, 'b> {
    pub(super) source: MotionSource<'b>,
    pub(super) feed: &'a FeedOptions,
    pub(super) sampling: Sampling,
    pub(super) sink: &'a mut dyn SampleSink,
    pub(super) accuracy: Option<(&'a PathAccuracyRequest, &'a [crate::accuracy::Tolerance])>,
}

/// An invalid-input error about `what`.
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
        self.feed.validate()?;
        let mut runner = Runner::new(m, self.sampling)?;
        runner.set_max_samples(self.feed.max_samples);
        runner.set_singular_angle(self.feed.singular_angle)?;
        let serial_idx: Vec<usize> = match m.info().pose_space() {
            PoseSpace::Own => (0..P).collect(),
            _ => (0..3).collect(),
        };
        let traces = Traces::new(1 + 3 * A + 3 * serial_idx.len());
        let prepared = match self.accuracy {
            Some((req, file)) => Some(Prepared::new(m, req, file)?),
            None => None,
        };
        let tracker = match &prepared {
            Some(p) => Some(PathTracker::new(
                p.machine.as_ref().unwrap_or(m),
                &p.options,
            )?),
            None => None,
        };
        // Samples and a program's progress go to the same sink: shared by the
        // recording and the program's steps (the runner reads steps while it records),
        // borrowed once per sample and once per program line.
        let out = RefCell::new(self.sink);
        let mut rec = Recording {
            m,
            serial_idx,
            traces,
            tracker,
            out: &out,
        };
        let (notes, notes_dropped) = match self.source {
            MotionSource::PointToPoint {
                from,
                to,
                duration,
                accel_time,
            } => {
                let step = point_to_point(m, self.feed, &from, &to, duration, accel_time)?;
                runner.run_steps_into([Ok(step)], &mut rec)?;
                (Vec::new(), 0)
            }
            MotionSource::Polyline { points } => {
                runner.run_steps_into(polyline(m, self.feed, &points)?, &mut rec)?;
                (Vec::new(), 0)
            }
            MotionSource::Gcode {
                reader,
                from,
                setup,
            } => {
                let mut steps = ProgramSteps::new(m, self.feed, reader, from, setup, &out)?;
                runner.run_steps_into(&mut steps, &mut rec)?;
                steps.into_notes()
            }
        };
        let Recording {
            traces, tracker, ..
        } = rec;
        let summary = runner.finish();
        let path = tracker.map(PathTracker::finish);
        Ok(MotionRun {
            summary,
            traces,
            notes,
            notes_dropped,
            accuracy: prepared.zip(path).map(|(p, path)| PathAccuracyRun {
                tolerance_source: p.source,
                tolerances: p.options.tolerances,
                path,
            }),
        })
    }
}

/// The accuracy along the path, before the run: the tolerances, where they came from,
/// and the machine prepared for them.
struct Prepared<M> {
    /// Where the tolerances came from.
    source: ToleranceSource,
    /// The tracker's settings, with the tolerances.
    options: PathOptions,
    /// The machine with the toleranced parameters given, when it differs from the
    /// one visited.
    machine: Option<M>,
}

impl<M> Prepared<M> {
    /// Resolves the tolerances of `req` (`file`: the machine file's) on `m` and
    /// prepares `m` for them.
    fn new<const P: usize, const A: usize>(
        m: &M,
        req: &PathAccuracyRequest,
        file: &[crate::accuracy::Tolerance],
    ) -> Result<Self>
    where
        M: Analysable<P, A>,
    {
        let params = m.parameters();
        let (source, tol) = req.tolerances.resolve(&params, &m.tolerable(), file)?;
        let mut given: Vec<usize> = tol.iter().map(|t| t.parameter).collect();
        given.sort_unstable();
        given.dedup();
        let machine = m.with_given(&given)?;
        Ok(Prepared {
            source,
            options: PathOptions {
                tolerances: tol,
                machines: req.machines,
                every: req.every,
                seed: req.seed,
            },
            machine,
        })
    }
}

/// Where a run's samples go: the tracker of the accuracy along the path (which
/// follows the tool lengths too), the traces and the caller's sink.
struct Recording<'r, 'p, 's, M, const P: usize, const A: usize> {
    /// The machine run.
    m: &'r M,
    /// The coordinates traced as serial axes.
    serial_idx: Vec<usize>,
    /// The decimated series.
    traces: Traces,
    /// The accuracy along the path, when asked for.
    tracker: Option<PathTracker<'p, M, P, A>>,
    /// The caller's sink.
    out: &'r RefCell<&'s mut dyn SampleSink>,
}

impl<M: Analysable<P, A>, const P: usize, const A: usize> Recording<'_, '_, '_, M, P, A> {
    /// Adds sample `s` to the traces: `t`, per actuator `q, q', q''`, per serial axis
    /// `x, x', x''`, in user units.
    fn trace(&mut self, s: &Sample<P, A>) {
        let act = self.m.info().actuators();
        let coords = self.m.info().coordinates();
        let serial_idx = &self.serial_idx;
        self.traces.line(s.t, s.line);
        self.traces.rows.push(|r| {
            r[0] = s.t;
            for i in 0..A {
                let qn = act[i].quantity;
                r[1 + 3 * i..4 + 3 * i].copy_from_slice(&[
                    qn.to_user(s.act.q[i]),
                    qn.to_user(s.act.qd[i]),
                    qn.to_user(s.act.qdd[i]),
                ]);
            }
            for (j, &k) in serial_idx.iter().enumerate() {
                let qn = coords[k].quantity;
                let at = 1 + 3 * A + 3 * j;
                r[at..at + 3].copy_from_slice(&[
                    qn.to_user(s.x[k]),
                    qn.to_user(s.xd[k]),
                    qn.to_user(s.xdd[k]),
                ]);
            }
        });
    }
}

impl<M: Analysable<P, A>, const P: usize, const A: usize> RunSink<P, A>
    for Recording<'_, '_, '_, M, P, A>
{
    fn sample(&mut self, s: &Sample<P, A>) -> Result<()> {
        if let Some(t) = &mut self.tracker {
            t.add(s.t, s.line, &s.x, &s.act.q)?;
        }
        self.trace(s);
        self.out.borrow_mut().sample(&SampleRow {
            t: s.t,
            line: s.line,
            x: s.x.as_slice(),
            q: s.act.q.as_slice(),
            qd: s.act.qd.as_slice(),
            qdd: s.act.qdd.as_slice(),
        })
    }

    fn tool_length(&mut self, length: f64) -> Result<()> {
        match &mut self.tracker {
            Some(t) => t.set_tool_length(length),
            None => Ok(()),
        }
    }
}

/// The one step of a point-to-point move from `from` to `to`, timed by `duration`
/// (and `accel_time`) or at the feed.
fn point_to_point<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    feed: &FeedOptions,
    from: &[f64],
    to: &[f64],
    duration: Option<f64>,
    accel_time: Option<f64>,
) -> Result<Step<P>> {
    let from = crate::dynamic::fixed::<P>("--from", from)?;
    let to = crate::dynamic::fixed::<P>("--to", to)?;
    let q = crate::motion::run::quantities(m);
    let spatial = m.info().pose_space() != PoseSpace::Own;
    let segment = Segment::line(from, to, &q, spatial);
    let prof = timed_profile(segment.length, duration, accel_time, feed)?;
    let mv = Move {
        segment,
        profile: prof,
        line: None,
        rapid: false,
    };
    Ok(Step::Move { mv, last: true })
}

/// The time law of a point-to-point move of `length`: over `duration` (with
/// `accel_time` for a trapezoid) when given, else at the feed.
fn timed_profile(
    length: f64,
    duration: Option<f64>,
    accel_time: Option<f64>,
    feed: &FeedOptions,
) -> Result<Profile> {
    if let Some(d) = duration {
        check_duration(length, d)?;
    }
    match (duration, accel_time, feed.profile) {
        (Some(d), Some(ta), ProfileKind::Trapezoid) => Profile::trapezoid_timed(length, d, ta),
        (Some(_), Some(_), _) => Err(invalid("--accel-time", "needs --profile trapezoid")),
        (Some(d), None, ProfileKind::Constant) => Profile::constant(length, length / d),
        (Some(_), None, _) => Err(invalid(
            "--duration",
            "with --profile trapezoid needs --accel-time; with scurve give --feed instead",
        )),
        (None, _, kind) => {
            let v = feed
                .feed
                .ok_or_else(|| invalid("feed", "give --feed or --duration"))?;
            profile(kind, length, v, feed)
        }
    }
}

/// The steps through waypoints `points`: a straight move from rest to rest at the
/// feed between each two that differ, its line the number of its first point.
fn polyline<'f, M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    feed: &'f FeedOptions,
    points: &[Vec<f64>],
) -> Result<impl Iterator<Item = Result<Step<P>>> + 'f> {
    if points.len() < 2 {
        return Err(invalid(
            "path",
            format!("expected at least 2 waypoints, got {}", points.len()),
        ));
    }
    let v = feed
        .feed
        .ok_or_else(|| invalid("feed", "a path needs a feed (mm/s or deg/s)"))?;
    let q = crate::motion::run::quantities(m);
    let spatial = m.info().pose_space() != PoseSpace::Own;
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
    Ok(moves.into_iter().enumerate().map(move |(k, (i, segment))| {
        Ok(Step::Move {
            mv: Move {
                profile: profile(feed.profile, segment.length, v, feed)?,
                segment,
                line: Some(i as u64 + 1),
                rapid: false,
            },
            last: k + 1 == n,
        })
    }))
}
