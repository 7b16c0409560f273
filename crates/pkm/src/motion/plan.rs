//! Planning a run: the sample instants of each move, gathered in blocks whose actuator
//! motion is computed apart from the bookkeeping, on a worker thread and the rayon
//! pool when there is more than one thread.
//!
//! A run has three stages. The *planner* (the caller's thread) reads the moves and lays
//! out their sample instants, exactly as a one-sample-at-a-time loop would: at a fixed
//! rate `t_k = k / rate` over the whole program, or `n` points per move. The *compute*
//! stage evaluates each instant: time law, geometry, exact `q, q', q''` and the
//! mechanism's own limits ([`Mechanism::actuator_motion_checked`]); samples do not
//! depend on each other, so blocks are computed on several cores at once. The *recorder*
//! ([`super::Runner`], the caller's thread again) takes the blocks back in order for
//! the statistics, the rate limits, the stretches of violations and the sink. Every
//! sample is computed by the same code in the same way whichever stage runs where, so
//! the results do not depend on the thread count.

use std::sync::Arc;

use super::block::Block;
use super::run::{Move, Sampling};
use crate::error::{Error, Result};
use crate::mechanism::Mechanism;

/// Samples per block: large enough to amortise a hand-over between threads (a few
/// microseconds) over a tenth of a millisecond of a hexapod's work (most of a
/// millisecond of a serial robot's), small enough for the block's samples and the
/// compute stage's rows (about 300 kB for a hexapod) to stay in the second-level
/// cache from one stage to the next. Measured on a hexapod's and a 6R robot's
/// programs (`docs/performance.md`): 512 beat 256, 1024 and 4096 on one
/// thread and on two.
pub(crate) const BLOCK: usize = 512;

/// Blocks in flight between the planner and the recorder.
const IN_FLIGHT: usize = 3;

/// What a run is given, in order.
// A move is a few hundred bytes and steps pass one at a time: boxing it would allocate
// per move for nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Step<const P: usize> {
    /// A move; `last` marks the program's final move (its end instant is sampled).
    Move {
        /// The move.
        mv: Move<P>,
        /// The program's final move.
        last: bool,
    },
    /// The tool is `length` mm longer than the machine file's from here on (a
    /// program's `G43 H`, 0 for `G49`); `line` is the G-code line, for messages.
    ToolLength {
        /// Tool length (mm).
        length: f64,
        /// G-code line.
        line: u64,
    },
}

/// The planner's state: where the run is in time, the work done, the tool.
pub(crate) struct Planner<'m, M, const P: usize, const A: usize> {
    pub m: &'m M,
    /// The mechanism with the program's tool length, when it has one.
    pub tooled: Option<Arc<M>>,
    pub tool_length: f64,
    pub sampling: Sampling,
    /// Start of the next move (s): the run's duration at the end.
    pub t0: f64,
    /// Index of the next fixed-rate instant.
    k: u64,
    /// Samples planned.
    pub samples: u64,
    /// No move was planned yet.
    first: bool,
    /// Serial number of the next move.
    serial: u64,
    /// The work limit (samples).
    pub max_samples: u64,
    _actuators: std::marker::PhantomData<[(); A]>,
}

impl<'m, M: Mechanism<P, A>, const P: usize, const A: usize> Planner<'m, M, P, A> {
    pub(crate) fn new(m: &'m M, sampling: Sampling) -> Self {
        Planner {
            m,
            tooled: None,
            tool_length: 0.0,
            sampling,
            t0: 0.0,
            k: 0,
            samples: 0,
            first: true,
            serial: 0,
            max_samples: super::run::DEFAULT_MAX_SAMPLES,
            _actuators: std::marker::PhantomData,
        }
    }

    /// Plans the following moves with a tool `length` mm longer than the machine
    /// file's ([`Mechanism::with_tool_length`]).
    pub(crate) fn set_tool_length(&mut self, length: f64) -> Result<()> {
        if length == self.tool_length {
            return Ok(());
        }
        match self.m.with_tool_length(length) {
            Some(m) => self.tooled = Some(Arc::new(m?)),
            None if length == 0.0 => self.tooled = None,
            None => {
                return Err(Error::Unsupported {
                    machine: self.m.info().name().into(),
                    kind: self.m.info().kind().into(),
                    analysis: "a tool length from the program (G43)",
                    reason: "its tool is set in the machine file".into(),
                })
            }
        }
        self.tool_length = length;
        Ok(())
    }

    /// Refuses move `mv` when its samples would take the run beyond the work limit,
    /// before any is computed: a dwell of years, a feed of a micrometre per minute, a
    /// hundred million full turns or a billion points per move end here with the cost.
    fn check_work(&self, mv: &Move<P>) -> Result<()> {
        let dur = mv.profile.duration;
        let estimate = match self.sampling {
            Sampling::Rate(rate) => (dur * rate).ceil() + 1.0,
            Sampling::Points(n) => n as f64,
        };
        let total = self.samples as f64 + estimate;
        if !(total <= self.max_samples as f64) {
            return Err(Error::InvalidInput {
                what: "motion".into(),
                message: format!(
                    "{}the move takes {dur:.6e} s and would make {total:.3e} samples, beyond \
                     the limit of {:.3e} (raise the work limit: `pkm motion --max-samples`, \
                     `max_samples=` in Python; or sample less densely)",
                    mv.line.map(|l| format!("line {l}: ")).unwrap_or_default(),
                    self.max_samples as f64
                ),
            });
        }
        Ok(())
    }

    /// Refuses a move that changes a coordinate the mechanism holds constant.
    fn check_driven(&self, mv: &Move<P>) -> Result<()> {
        let driven = self.m.info().driven();
        for k in 0..P {
            if !driven.contains(&k) && (mv.segment.end[k] - mv.segment.start[k]).abs() > 1e-12 {
                let c = &self.m.info().coordinates()[k];
                return Err(Error::NotAttainable {
                    reason: format!(
                        "{}the move changes {} from {:.4} to {:.4} {}, which the mechanism holds constant",
                        mv.line.map(|l| format!("line {l}: ")).unwrap_or_default(),
                        c.name,
                        c.quantity.to_user(mv.segment.start[k]),
                        c.quantity.to_user(mv.segment.end[k]),
                        c.quantity.unit()
                    ).into(),
                });
            }
        }
        Ok(())
    }

    /// Plans `step` into `blk`, handing full blocks to `dispatch` (which leaves an
    /// empty block in their place).
    pub(crate) fn plan<D>(
        &mut self,
        step: Step<P>,
        blk: &mut Block<M, P, A>,
        dispatch: &mut D,
    ) -> Result<()>
    where
        D: FnMut(&mut Block<M, P, A>) -> Result<()>,
    {
        match step {
            Step::ToolLength { length, line } => {
                self.set_tool_length(length)
                    .map_err(|e| Error::InvalidInput {
                        what: format!("G-code line {line}"),
                        message: e.to_string(),
                    })?;
                // The samples before run with the tool they had.
                if !blk.is_empty() {
                    dispatch(blk)?;
                }
                blk.tool = Some(length);
                blk.tooled = self.tooled.clone();
                Ok(())
            }
            Step::Move { mv, last } => self.plan_move(&mv, last, blk, dispatch),
        }
    }

    fn plan_move<D>(
        &mut self,
        mv: &Move<P>,
        last: bool,
        blk: &mut Block<M, P, A>,
        dispatch: &mut D,
    ) -> Result<()>
    where
        D: FnMut(&mut Block<M, P, A>) -> Result<()>,
    {
        self.check_work(mv)?;
        self.check_driven(mv)?;
        let serial = self.serial;
        self.serial += 1;
        let t0 = self.t0;
        let dur = mv.profile.duration;
        let mut push = |this: &mut Self, tl: f64| -> Result<()> {
            if blk.plan.len() >= BLOCK {
                dispatch(blk)?;
            }
            if blk.plan.is_empty() {
                blk.tooled = this.tooled.clone();
            }
            if blk.moves.last().map(|m| m.2) != Some(serial) {
                blk.moves.push((*mv, t0, serial));
            }
            blk.plan.push(((blk.moves.len() - 1) as u32, tl));
            this.samples += 1;
            Ok(())
        };
        match self.sampling {
            Sampling::Rate(rate) => {
                loop {
                    let t = self.k as f64 / rate;
                    if t > t0 + dur + 1e-12 {
                        break;
                    }
                    push(self, t - t0)?;
                    self.k += 1;
                }
                if last && (t0 + dur) > (self.k as f64 - 1.0) / rate + 1e-12 {
                    push(self, dur)?;
                }
            }
            Sampling::Points(n) => {
                let from = if self.first { 0 } else { 1 };
                for i in from..n {
                    push(self, dur * i as f64 / (n - 1) as f64)?;
                }
            }
        }
        self.first = false;
        self.t0 += dur;
        Ok(())
    }
}

/// Plans `steps` into `blk`, handing each full block and the last one to `hand_over`.
/// A planning error ends the steps and is the last block's tail (raised after its
/// samples); an error of `hand_over` (a record that failed) is returned at once.
fn plan_all<M, I, const P: usize, const A: usize>(
    planner: &mut Planner<'_, M, P, A>,
    steps: I,
    blk: &mut Block<M, P, A>,
    hand_over: &mut dyn FnMut(&mut Block<M, P, A>) -> Result<()>,
) -> Result<()>
where
    M: Mechanism<P, A>,
    I: IntoIterator<Item = Result<Step<P>>>,
{
    let stopped = std::cell::Cell::new(false);
    let mut dispatch = |b: &mut Block<M, P, A>| {
        let r = hand_over(b);
        stopped.set(r.is_err());
        r
    };
    for step in steps {
        if let Err(e) = step.and_then(|s| planner.plan(s, blk, &mut dispatch)) {
            if stopped.get() {
                return Err(e);
            }
            blk.tail = Some(e);
            break;
        }
    }
    dispatch(blk)
}

/// [`drive`] on the caller's thread alone, planning into `blk` (left empty).
pub(crate) fn run_inline<M, I, R, const P: usize, const A: usize>(
    planner: &mut Planner<'_, M, P, A>,
    steps: I,
    blk: &mut Block<M, P, A>,
    record: &mut R,
) -> Result<()>
where
    M: Mechanism<P, A>,
    I: IntoIterator<Item = Result<Step<P>>>,
    R: FnMut(&mut Block<M, P, A>) -> Result<()>,
{
    let base = planner.m;
    let mut dispatch = |b: &mut Block<M, P, A>| -> Result<()> {
        b.compute(base);
        let r = record(b);
        b.clear();
        r
    };
    let r = plan_all(planner, steps, blk, &mut dispatch);
    blk.clear();
    r
}

/// Runs `steps` through the planner, the compute stage and `record`, which takes the
/// computed blocks in order.
///
/// With one rayon thread, or when called from a rayon worker (a sweep already keeps the
/// cores busy), everything runs on the caller's thread. Otherwise each full block is
/// handed to the rayon pool (and spread over it) while the caller plans and records,
/// at most [`IN_FLIGHT`] blocks ahead; a record that fails stops the run at once, a
/// planning error is raised after the samples planned before it are recorded.
pub(crate) fn drive<M, I, R, const P: usize, const A: usize>(
    planner: &mut Planner<'_, M, P, A>,
    steps: I,
    record: &mut R,
) -> Result<()>
where
    M: Mechanism<P, A>,
    I: IntoIterator<Item = Result<Step<P>>>,
    R: FnMut(&mut Block<M, P, A>) -> Result<()>,
{
    let base = planner.m;
    if rayon::current_num_threads() <= 1 || rayon::current_thread_index().is_some() {
        return run_inline(planner, steps, &mut Block::new(), record);
    }
    rayon::in_place_scope(|scope| {
        let (done_tx, done_rx) = std::sync::mpsc::channel::<(u64, Block<M, P, A>)>();
        let mut queue = Queue {
            done_rx,
            sent: 0,
            next: 0,
            early: Vec::new(),
            made: 1,
        };
        let mut dispatch = |b: &mut Block<M, P, A>| -> Result<()> {
            // An empty block to fill next: a new one while fewer than IN_FLIGHT + 1
            // exist, else the oldest in flight, once recorded.
            let next = if queue.made <= IN_FLIGHT {
                queue.made += 1;
                Block::new()
            } else {
                let mut done = queue.recv();
                let r = record(&mut done);
                done.clear();
                r?;
                done
            };
            let mut full = std::mem::replace(b, next);
            let (seq, tx) = (queue.sent, done_tx.clone());
            queue.sent += 1;
            scope.spawn(move |_| {
                full.compute(base);
                // The receiver is gone only when the run stopped on an error.
                let _ = tx.send((seq, full));
            });
            Ok(())
        };
        plan_all(planner, steps, &mut Block::new(), &mut dispatch)?;
        while queue.next < queue.sent {
            let mut done = queue.recv();
            record(&mut done)?;
        }
        Ok(())
    })
}

/// The computed blocks coming back from the pool, handed out in planning order.
struct Queue<B> {
    done_rx: std::sync::mpsc::Receiver<(u64, B)>,
    /// Blocks handed to the pool.
    sent: u64,
    /// The next block to hand out.
    next: u64,
    /// Blocks that came back before their turn.
    early: Vec<(u64, B)>,
    /// Blocks allocated.
    made: usize,
}

impl<B> Queue<B> {
    fn recv(&mut self) -> B {
        loop {
            if let Some(i) = self.early.iter().position(|(s, _)| *s == self.next) {
                self.next += 1;
                return self.early.swap_remove(i).1;
            }
            let got = self
                .done_rx
                .recv()
                .expect("a block in flight is sent back before its task ends");
            self.early.push(got);
        }
    }
}
