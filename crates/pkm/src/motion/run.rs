//! Running moves through a mechanism: sampling, exact actuator kinematics, serial
//! comparison, limits along the path and the largest feed override.

use nalgebra::SVector;
use serde::Serialize;

use super::block::Block;
use super::path::Segment;
use super::plan::{drive, run_inline, Planner, Step};
use super::profile::Profile;
use super::recorder::{Callbacks, Recorder, RunSink};
use super::singular::{SingularReport, SingularTracker};
use super::stats::{AxisStats, Ratios};
use crate::error::{Error, Result};
use crate::limits::LimitKind;
use crate::mechanism::{ActuatorMotion, Mechanism, PoseSpace};
use crate::units::Quantity;

/// One move: a segment with its time law and its G-code line, if any.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move<const P: usize> {
    /// The geometry.
    pub segment: Segment<P>,
    /// The time law along it.
    pub profile: Profile,
    /// G-code line (1-based), when the move comes from a program.
    pub line: Option<u64>,
    /// A rapid (G0): each axis at its own rate, not a programmed feed.
    pub rapid: bool,
}

/// How to sample time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sampling {
    /// A fixed rate (Hz) over the whole program.
    Rate(f64),
    /// A number of points per move, evenly spaced in time (seed 000: 101 on the arc).
    Points(usize),
}

/// One sample: time, pose coordinates with derivatives, actuator motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample<const P: usize, const A: usize> {
    /// Time from the program start (s).
    pub t: f64,
    /// G-code line of the move.
    pub line: Option<u64>,
    /// Pose coordinates (mm, rad).
    pub x: SVector<f64, P>,
    /// Their rates.
    pub xd: SVector<f64, P>,
    /// Their accelerations.
    pub xdd: SVector<f64, P>,
    /// Actuator positions, velocities, accelerations.
    pub act: ActuatorMotion<A>,
}

/// A stretch of time over which one limit was violated.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViolationRun {
    /// The limit (`strut e velocity`).
    pub limit: String,
    /// Its family.
    pub kind: LimitKind,
    /// G-code line where it started.
    pub line: Option<u64>,
    /// First violating sample (s).
    pub start_s: f64,
    /// Last violating sample (s).
    pub end_s: f64,
    /// Worst value (user units).
    pub worst: f64,
    /// The bound (user units).
    pub bound: f64,
    /// Unit.
    pub unit: String,
}

/// What a run of a program reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MotionSummary {
    /// Per actuator (name, statistics), user units.
    pub actuators: Vec<(String, AxisStats)>,
    /// Per serial (Cartesian) axis, the same path on a serial machine.
    pub serial: Vec<(String, AxisStats)>,
    /// Serial over PKM ratios (seed 000's definitions); `None` when an actuator or a
    /// serial axis is an angle (a ratio of mm to deg means nothing), or when no serial
    /// axis moves.
    pub ratios: Option<Ratios>,
    /// Violated limits along the path (the first 10 000 stretches).
    pub violations: Vec<ViolationRun>,
    /// Stretches beyond the first 10 000, not listed.
    pub violations_not_listed: u64,
    /// Largest factor by which every feed (and so the time scale of the feed moves)
    /// can be multiplied while the actuators keep within their velocity and
    /// acceleration limits in the feed moves (velocities scale with it,
    /// accelerations with its square); `None` when the machine gives no rate limits
    /// or no feed move moves. Rapids are left out: a feed override does not scale
    /// them (LinuxCNC has a rapid override of its own).
    pub feed_override_max: Option<f64>,
    /// The same factor for the rapids (G0) alone: above 1, the rapids could run
    /// faster within the actuators' limits; below 1, they exceed them unless slowed
    /// by that rapid override. `None` without rate limits or without a rapid.
    pub rapid_override_max: Option<f64>,
    /// Passages near the mechanism's singular direction with the rotary axes' speeds
    /// in them; `None` for mechanisms without one.
    pub singular: Option<SingularReport>,
    /// Program duration (s).
    pub duration_s: f64,
    /// Samples taken.
    pub samples: u64,
}

/// Runs moves through a mechanism (streaming: memory stays flat): plans their sample
/// instants, computes them in blocks ([`super::plan`], across the rayon pool when it
/// has more than one thread) and records every sample in order: statistics, rate
/// limits, stretches of violations, passages near a singular direction, the sink.
pub struct Runner<'m, M, const P: usize, const A: usize> {
    plan: Planner<'m, M, P, A>,
    rec: Recorder<'m, M, P, A>,
    /// The block [`Runner::run_move`] plans into, kept between calls (its buffers stay
    /// allocated: a caller running moves one by one allocates once).
    spare: Block<M, P, A>,
}

/// The default work limit of a run: 2e7 samples (about 10 s on one core for a hexapod;
/// a 100 000-line program at 1 kHz takes about 2e6).
pub const DEFAULT_MAX_SAMPLES: u64 = 20_000_000;

impl<'m, M: Mechanism<P, A>, const P: usize, const A: usize> Runner<'m, M, P, A> {
    /// A runner for mechanism `m`.
    pub fn new(m: &'m M, sampling: Sampling) -> Result<Self> {
        match sampling {
            Sampling::Rate(r) if !(r > 0.0 && r.is_finite()) => {
                return Err(Error::InvalidInput {
                    what: "sampling rate".into(),
                    message: format!("expected a rate > 0 Hz, got {r}"),
                })
            }
            Sampling::Points(n) if n < 2 => {
                return Err(Error::InvalidInput {
                    what: "points per move".into(),
                    message: format!("expected at least 2, got {n}"),
                })
            }
            _ => {}
        }
        let serial_idx: Vec<usize> = match m.info().pose_space() {
            PoseSpace::Own => (0..P).collect(),
            _ => (0..3).collect(),
        };
        Ok(Runner {
            spare: Block::new(),
            plan: Planner::new(m, sampling),
            rec: Recorder::new(m, serial_idx)?,
        })
    }

    /// Names of the serial axes (`X`, `Y`, `Z`, or the machine's own coordinates).
    pub fn serial_names(&self) -> Vec<String> {
        let m = self.rec.m;
        self.rec
            .serial_idx
            .iter()
            .map(|&k| m.info().coordinates()[k].name.clone())
            .collect()
    }

    /// Runs the following moves with a tool `length` mm longer than the machine file's
    /// ([`Mechanism::with_tool_length`]; a program's `G43 H`, 0 for `G49`).
    pub fn set_tool_length(&mut self, length: f64) -> Result<()> {
        self.plan.set_tool_length(length)
    }

    /// Sets the threshold (rad, 0 to pi/2) of a passage near the singular direction
    /// ([`SingularTracker`]); default [`super::singular::DEFAULT_SINGULAR_ANGLE`].
    pub fn set_singular_angle(&mut self, angle: f64) -> Result<()> {
        self.rec.singular = SingularTracker::new(self.rec.m.info().actuators(), angle)?;
        Ok(())
    }

    /// Sets the work limit: at most `n` samples over the run. A move whose samples
    /// would cross it is refused before any is computed: a dwell of years, a feed of a
    /// micrometre per minute, a hundred million full turns or a billion points per move
    /// end there with the cost.
    pub fn set_max_samples(&mut self, n: u64) {
        self.plan.max_samples = n;
    }

    /// Samples one move and passes every sample to `sink`, on the caller's thread.
    /// `last` marks the program's final move (its end instant is sampled).
    pub fn run_move<F>(&mut self, mv: &Move<P>, last: bool, sink: &mut F) -> Result<()>
    where
        F: FnMut(&Sample<P, A>) -> Result<()>,
    {
        let Runner { plan, rec, spare } = self;
        let step = Ok(Step::Move { mv: *mv, last });
        let mut to = Callbacks {
            sample: sink,
            tool: &mut |_| Ok(()),
        };
        run_inline(plan, [step], spare, &mut |b: &mut Block<M, P, A>| {
            rec.record(b, &mut to)
        })
    }

    /// Runs `steps` (moves and tool changes, in order; an error ends them), passing
    /// every sample to `sink` in order and every tool length to `tool` before the
    /// samples taken with it. Blocks of samples are computed across the rayon pool
    /// while this thread plans and records ([`super::plan`]); the results are those of
    /// [`Runner::run_move`] move after move, whatever the thread count.
    pub fn run_steps<I, F, T>(&mut self, steps: I, sink: &mut F, tool: &mut T) -> Result<()>
    where
        I: IntoIterator<Item = Result<Step<P>>>,
        F: FnMut(&Sample<P, A>) -> Result<()>,
        T: FnMut(f64) -> Result<()>,
    {
        self.run_steps_into(steps, &mut Callbacks { sample: sink, tool })
    }

    /// [`Runner::run_steps`] into one sink of the samples and the tool lengths.
    pub(crate) fn run_steps_into<I, S>(&mut self, steps: I, sink: &mut S) -> Result<()>
    where
        I: IntoIterator<Item = Result<Step<P>>>,
        S: RunSink<P, A>,
    {
        let Runner { plan, rec, .. } = self;
        drive(plan, steps, &mut |b: &mut Block<M, P, A>| {
            rec.record(b, sink)
        })
    }

    /// The summary of everything run so far.
    pub fn finish(self) -> MotionSummary {
        let names = self.serial_names();
        let Runner { plan, rec, .. } = self;
        rec.finish(names, plan.t0, plan.samples)
    }
}

/// Where coordinate `k` of `m` sits in a G-code position `[X, Y, Z, A, B, C]`: all six
/// for a spatial machine, X, Y, Z for a position machine; X, Y, Z and the rotary axes
/// by their letters for a TCP machine. `None` for a coordinate no letter addresses.
fn gcode_slot<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    k: usize,
) -> Option<usize> {
    match (m.info().pose_space(), P) {
        (PoseSpace::Spatial, 6) | (PoseSpace::Position, 3) => Some(k),
        (PoseSpace::Tcp, _) if k < 3 => Some(k),
        (PoseSpace::Tcp, _) => match m.info().coordinates()[k].name.as_str() {
            "A" => Some(3),
            "B" => Some(4),
            "C" => Some(5),
            _ => None,
        },
        _ => None,
    }
}

/// Pose coordinates of a mechanism from a G-code position `[X, Y, Z, A, B, C]` (mm,
/// rad): all six for a spatial machine, X, Y, Z for a position machine, X, Y, Z and the
/// rotary axes by their letters for a TCP machine.
pub fn from_spatial<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    v: &[f64; 6],
) -> Result<SVector<f64, P>> {
    let mut x = SVector::<f64, P>::zeros();
    for k in 0..P {
        match gcode_slot(m, k) {
            Some(i) => x[k] = v[i],
            None => {
                return Err(Error::InvalidInput {
                    what: "tool path".into(),
                    message: match m.info().pose_space() {
                        PoseSpace::Tcp => format!(
                            "the rotary axis `{}` has no G-code letter (A, B or C)",
                            m.info().coordinates()[k].name
                        ),
                        _ => "this machine's pose is not X, Y, Z[, A, B, C]; give moves in its \
                              own coordinates"
                            .into(),
                    },
                })
            }
        }
    }
    Ok(x)
}

/// The G-code position `[X, Y, Z, A, B, C]` of pose coordinates `x` (letters the
/// machine has no coordinate for at 0), the inverse of [`from_spatial`].
pub fn to_spatial<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> [f64; 6] {
    let mut v = [0.0; 6];
    for k in 0..P {
        if let Some(i) = gcode_slot(m, k) {
            v[i] = x[k];
        }
    }
    v
}

/// G-code letters a TCP machine has no axis for (`A` on an XYZBC machine), by index
/// 3..6 of the G-code position: a move that changes one is refused.
pub fn missing_letters<M: Mechanism<P, A>, const P: usize, const A: usize>(m: &M) -> Vec<usize> {
    if m.info().pose_space() != PoseSpace::Tcp {
        return Vec::new();
    }
    (3..6)
        .filter(|i| !(0..P).any(|k| gcode_slot(m, k) == Some(*i)))
        .collect()
}

/// Quantities of the coordinates, for [`Segment::line`].
pub fn quantities<M: Mechanism<P, A>, const P: usize, const A: usize>(m: &M) -> [Quantity; P] {
    std::array::from_fn(|k| m.info().coordinates()[k].quantity)
}
