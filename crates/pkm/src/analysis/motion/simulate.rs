//! The run behind [`super::run_motion_with`]: a visitor over the machine's type that
//! feeds the program (or the point-to-point move) to a [`Runner`], the accuracy along
//! the path to its tracker, each sample to the sink and the report's traces.

use std::io::BufRead;

use super::{
    MotionRun, MotionSource, PathAccuracyRequest, PathAccuracyRun, SampleRow, SampleSink, Traces,
};
use crate::accuracy::path::{PathOptions, PathTracker};
use crate::error::{Error, Result};
use crate::machine::{Analysable, Visitor};
use crate::mechanism::PoseSpace;
use crate::motion::gcode::{Interpreter, ToolEvent};
use crate::motion::program::{profile, to_move, FeedOptions, ProfileKind};
use crate::motion::{Move, Profile, Runner, Sample, Sampling, Segment, Step};

pub(super) struct Simulate<'a, 'b> {
    pub(super) source: MotionSource<'b>,
    pub(super) feed: &'a FeedOptions,
    pub(super) sampling: Sampling,
    pub(super) sink: &'a mut dyn SampleSink,
    pub(super) accuracy: Option<(&'a PathAccuracyRequest, &'a [crate::accuracy::Tolerance])>,
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
        let serial_idx: Vec<usize> = match m.info().pose_space() {
            PoseSpace::Own => (0..P).collect(),
            _ => (0..3).collect(),
        };
        let mut traces = Traces::new(1 + 3 * A + 3 * serial_idx.len());
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
            let act = m.info().actuators();
            let coords = m.info().coordinates();
            traces.line(s.t, s.line);
            traces.rows.push(|r| {
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
                let spatial = m.info().pose_space() != PoseSpace::Own;
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
                if m.info().pose_space() == PoseSpace::Own {
                    return Err(invalid(
                        "G-code",
                        "needs a machine whose pose is X, Y, Z[, A, B, C] or tool-centre-point \
                         coordinates",
                    ));
                }
                let x = match from {
                    Some(x) => crate::dynamic::fixed::<P>("start pose", &x)?,
                    None => m.info().home(),
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
