//! Running moves through a mechanism: sampling, exact actuator kinematics, serial
//! comparison, limits along the path and the largest feed override.

use nalgebra::SVector;
use serde::Serialize;

use super::follow::{follow_block, Last};
use super::path::Segment;
use super::plan::{drive, run_inline, Block, Planner, Step};
use super::profile::Profile;
use super::singular::{SingularReport, SingularTracker, DEFAULT_SINGULAR_ANGLE};
use super::stats::{ratios, AxisBank, AxisStats, Ratios};
use crate::error::{Error, Result};
use crate::limits::{LimitKind, LimitName, Side, Violation};
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
    /// Largest factor by which every feed (and so the time scale) can be multiplied
    /// while the actuators keep within their velocity and acceleration limits
    /// (velocities scale with it, accelerations with its square); `None` when the
    /// machine gives no rate limits or nothing moves.
    pub feed_override_max: Option<f64>,
    /// Passages near the mechanism's singular direction with the rotary axes' speeds
    /// in them; `None` for mechanisms without one.
    pub singular: Option<SingularReport>,
    /// Program duration (s).
    pub duration_s: f64,
    /// Samples taken.
    pub samples: u64,
}

const MAX_RUNS: usize = 10_000;

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

/// What the samples add up to, taken in order.
struct Recorder<'m, M, const P: usize, const A: usize> {
    m: &'m M,
    act: AxisBank<A>,
    /// The serial axes in the first `serial_idx.len()` lanes (the others stay zero).
    serial: AxisBank<P>,
    serial_idx: Vec<usize>,
    runs: Vec<ViolationRun>,
    /// The stretches still open: their limit and index in `runs`, in the order of
    /// the last sample's violations.
    open: Vec<(LimitName, usize)>,
    /// Storage for the next `open` (kept: no allocation per sample).
    spare_open: Vec<(LimitName, usize)>,
    dropped: u64,
    buf: Vec<Violation>,
    /// Per actuator, `Quantity::to_user`'s factor.
    act_scale: [f64; A],
    /// Per serial axis, the same (zero past the serial axes).
    serial_scale: [f64; P],
    /// Per actuator, the velocity and acceleration limits (infinite where none).
    rate_limits: [(f64, f64); A],
    /// Per actuator, the names of its velocity and acceleration limits (`actuator 3
    /// velocity`), named once: a program beyond one clones them per sample.
    rate_names: Vec<[LimitName; 2]>,
    /// Per actuator, the largest |q'| and |q''| seen.
    peak_rates: [(f64, f64); A],
    singular: SingularTracker,
    /// The last sample recorded, which the next continues ([`super::follow`]).
    last: Last<A>,
}

/// Extends stretch `r` to time `t` with violation `v` of its limit (its worst value
/// kept).
fn extend_run(r: &mut ViolationRun, v: &Violation, t: f64) {
    r.end_s = t;
    if v.excess > (r.worst - r.bound).abs() {
        r.worst = v.value;
    }
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
        let serial_idx: Vec<usize> = match m.pose_space() {
            PoseSpace::Own => (0..P).collect(),
            _ => (0..3).collect(),
        };
        Ok(Runner {
            spare: Block::new(),
            plan: Planner::new(m, sampling),
            rec: Recorder {
                m,
                act: AxisBank::default(),
                serial: AxisBank::default(),
                runs: Vec::new(),
                open: Vec::new(),
                spare_open: Vec::new(),
                dropped: 0,
                buf: Vec::new(),
                act_scale: std::array::from_fn(|i| m.actuators()[i].quantity.user_scale()),
                serial_scale: std::array::from_fn(|j| {
                    serial_idx
                        .get(j)
                        .map_or(0.0, |&k| m.coordinates()[k].quantity.user_scale())
                }),
                rate_limits: std::array::from_fn(|i| {
                    let a = &m.actuators()[i];
                    (
                        a.max_velocity.unwrap_or(f64::INFINITY),
                        a.max_acceleration.unwrap_or(f64::INFINITY),
                    )
                }),
                rate_names: m
                    .actuators()
                    .iter()
                    .map(|a| {
                        ["velocity", "acceleration"]
                            .map(|what| format!("actuator {} {what}", a.name).into())
                    })
                    .collect(),
                peak_rates: [(0.0, 0.0); A],
                serial_idx,
                singular: SingularTracker::new(m.actuators(), DEFAULT_SINGULAR_ANGLE)?,
                last: None,
            },
        })
    }

    /// Names of the serial axes (`X`, `Y`, `Z`, or the machine's own coordinates).
    pub fn serial_names(&self) -> Vec<String> {
        let m = self.rec.m;
        self.rec
            .serial_idx
            .iter()
            .map(|&k| m.coordinates()[k].name.clone())
            .collect()
    }

    /// Runs the following moves with a tool `length` mm longer than the machine file's
    /// ([`Mechanism::with_tool_length`]; a program's `G43 H`, 0 for `G49`).
    pub fn set_tool_length(&mut self, length: f64) -> Result<()> {
        self.plan.set_tool_length(length)
    }

    /// Sets the threshold (rad, 0 to pi/2) of a passage near the singular direction
    /// ([`SingularTracker`]); default [`DEFAULT_SINGULAR_ANGLE`].
    pub fn set_singular_angle(&mut self, angle: f64) -> Result<()> {
        self.rec.singular = SingularTracker::new(self.rec.m.actuators(), angle)?;
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
        run_inline(plan, [step], spare, &mut |b: &mut Block<M, P, A>| {
            rec.record(b, sink, &mut |_| Ok(()))
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
        let Runner { plan, rec, .. } = self;
        drive(plan, steps, &mut |b: &mut Block<M, P, A>| {
            rec.record(b, sink, tool)
        })
    }

    /// The summary of everything run so far.
    pub fn finish(self) -> MotionSummary {
        let names = self.serial_names();
        let Runner { plan, rec, .. } = self;
        rec.finish(names, plan.t0, plan.samples)
    }
}

impl<M: Mechanism<P, A>, const P: usize, const A: usize> Recorder<'_, M, P, A> {
    /// Records the samples of block `b` in order, after passing its tool length on;
    /// raises the error the block ends on, if any, after the samples before it.
    fn record<F, T>(&mut self, b: &mut Block<M, P, A>, sink: &mut F, tool: &mut T) -> Result<()>
    where
        F: FnMut(&Sample<P, A>) -> Result<()>,
        T: FnMut(f64) -> Result<()>,
    {
        if let Some(length) = b.tool {
            tool(length)?;
        }
        // Each sample continues the one before (a robot's posture and turns).
        follow_block(self.m, b, &mut self.last);
        let n = b.failed.as_ref().map_or(b.plan.len(), |f| f.0);
        let mut violations = b.violations.drain(..).peekable();
        // The samples in order, then their statistics: the statistics see the same
        // samples in the same order as if they were taken sample by sample (up to the
        // one a sink refused), in a loop of their own.
        let mut recorded = Ok(());
        let mut taken = n;
        for k in 0..n {
            self.buf.clear();
            while let Some((_, v)) = violations.next_if(|v| v.0 as usize == k) {
                self.buf.push(v);
            }
            let rapid = b.moves[b.plan[k].0 as usize].0.rapid;
            if let Err(e) = self.record_sample(&b.samples[k], rapid, sink) {
                (recorded, taken) = (Err(e), k + 1);
                break;
            }
        }
        self.add_stats(&b.samples[..taken]);
        recorded?;
        if let Some((_, e)) = b.failed.take() {
            return Err(e);
        }
        match b.tail.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Records sample `s` of a move (a rapid when `rapid`); `self.buf` holds the
    /// violations of the mechanism's own limits found with it, the rate limits are
    /// checked here.
    fn record_sample<F>(&mut self, s: &Sample<P, A>, rapid: bool, sink: &mut F) -> Result<()>
    where
        F: FnMut(&Sample<P, A>) -> Result<()>,
    {
        let (t, act, x) = (s.t, &s.act, &s.x);
        // Rate limits (infinite where none is given): a violation is rare. One pass over
        // the actuators for whether any limit is exceeded, then (rarely) the violations
        // in order; the peaks are the statistics' ([`Self::add_stats`]).
        let mut over = false;
        for i in 0..A {
            let (vm, am) = self.rate_limits[i];
            over |= (act.qd[i].abs() > vm) | (act.qdd[i].abs() > am);
        }
        if over {
            for i in 0..A {
                let (v, acc) = (act.qd[i].abs(), act.qdd[i].abs());
                if v > self.rate_limits[i].0 {
                    self.buf.push(self.rate_violation(i, 1, v));
                }
                if acc > self.rate_limits[i].1 {
                    self.buf.push(self.rate_violation(i, 2, acc));
                }
            }
        }
        self.track(t, s.line);
        // The singular direction does not depend on the tool length. Rapids run each
        // axis at its rapid rate whatever the direction: what a passage costs is the
        // feed moves'.
        if !rapid {
            if let Some(d) = self.m.singular_distance(x) {
                self.singular.add(t, s.line, d, act.qd.as_slice());
            }
        }
        sink(s)
    }

    /// Adds `samples`, in order, to the actuators' and the serial axes' statistics and
    /// the actuators' peak rates. The banks are held in locals for the loop: stored
    /// back once per block, not once per sample around the sink's call.
    fn add_stats(&mut self, samples: &[Sample<P, A>]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has AVX-512F.
            unsafe { self.add_stats_avx512(samples) };
            return;
        }
        self.add_stats_plain(samples);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn add_stats_avx512(&mut self, samples: &[Sample<P, A>]) {
        self.add_stats_plain(samples);
    }

    #[inline(always)]
    fn add_stats_plain(&mut self, samples: &[Sample<P, A>]) {
        // Two passes, the actuators' then the serial axes': each bank's statistics see
        // the samples in order, as in one pass, and each loop keeps its bank in
        // registers (one loop with both spilled, and its code changed with unrelated
        // changes elsewhere: 9 to 12 % of a hexapod's run). The two passes read
        // different parts of each sample, so no more memory than one.
        let (mut act, mut peaks) = (self.act, self.peak_rates);
        // `v * scale` is `Quantity::to_user(v)` bit for bit (1 or 180 / pi).
        let c = self.act_scale;
        for s in samples {
            let a = &s.act;
            act.add(
                &std::array::from_fn(|i| a.q[i] * c[i]),
                &std::array::from_fn(|i| a.qd[i] * c[i]),
                &std::array::from_fn(|i| a.qdd[i] * c[i]),
            );
            for (i, peak) in peaks.iter_mut().enumerate() {
                *peak = (peak.0.max(a.qd[i].abs()), peak.1.max(a.qdd[i].abs()));
            }
        }
        (self.act, self.peak_rates) = (act, peaks);
        let mut serial = self.serial;
        let (cs, idx) = (self.serial_scale, &self.serial_idx);
        for s in samples {
            let lane = |v: &SVector<f64, P>, j: usize| idx.get(j).map_or(0.0, |&k| v[k] * cs[j]);
            serial.add(
                &std::array::from_fn(|j| lane(&s.x, j)),
                &std::array::from_fn(|j| lane(&s.xd, j)),
                &std::array::from_fn(|j| lane(&s.xdd, j)),
            );
        }
        self.serial = serial;
    }

    /// The violation of actuator `i`'s velocity (`order` 1) or acceleration (2) limit
    /// by `value` (internal units).
    fn rate_violation(&self, i: usize, order: u8, value: f64) -> Violation {
        let a = &self.m.actuators()[i];
        let (kind, bound) = match order {
            1 => (LimitKind::ActuatorVelocity, self.rate_limits[i].0),
            _ => (LimitKind::ActuatorAcceleration, self.rate_limits[i].1),
        };
        let mut x = Violation::new(
            self.rate_names[i][usize::from(order != 1)].clone(),
            kind,
            Side::Max,
            a.quantity,
            value,
            bound,
        );
        x.unit = a.quantity.rate_unit(order);
        x
    }

    fn track(&mut self, t: f64, line: Option<u64>) {
        if self.buf.is_empty() && self.open.is_empty() {
            return;
        }
        // The limits of the sample before, in its order (a stretch beyond them): the
        // names compare by pointer when the mechanism names its limits once.
        if self.buf.len() == self.open.len()
            && self
                .buf
                .iter()
                .zip(&self.open)
                .all(|(v, (n, _))| v.limit == *n)
        {
            for (v, &(_, idx)) in self.buf.iter().zip(&self.open) {
                extend_run(&mut self.runs[idx], v, t);
            }
            return;
        }
        // Otherwise: stretches whose limit is no longer violated close, the others
        // go on, new ones open; `open` then lists them in this sample's order.
        let old = std::mem::take(&mut self.open);
        let mut open = std::mem::take(&mut self.spare_open);
        open.clear();
        for v in &self.buf {
            let found = open
                .iter()
                .chain(old.iter())
                .find(|(n, _)| *n == v.limit)
                .map(|&(_, idx)| idx);
            match found {
                Some(idx) => {
                    extend_run(&mut self.runs[idx], v, t);
                    if !open.iter().any(|(_, i)| *i == idx) {
                        open.push((v.limit.clone(), idx));
                    }
                }
                None => {
                    if self.runs.len() >= MAX_RUNS {
                        self.dropped += 1;
                        continue;
                    }
                    self.runs.push(ViolationRun {
                        limit: v.limit.to_string(),
                        kind: v.kind,
                        line,
                        start_s: t,
                        end_s: t,
                        worst: v.value,
                        bound: v.bound,
                        unit: v.unit.to_string(),
                    });
                    open.push((v.limit.clone(), self.runs.len() - 1));
                }
            }
        }
        self.open = open;
        self.spare_open = old;
    }

    /// The summary, with the serial axes' `names`, the run's duration and samples.
    fn finish(self, names: Vec<String>, duration_s: f64, samples: u64) -> MotionSummary {
        let act: Vec<AxisStats> = (0..A).map(|i| self.act.axis(i)).collect();
        let serial: Vec<AxisStats> = (0..self.serial_idx.len())
            .map(|j| self.serial.axis(j))
            .collect();
        let coords = self.m.coordinates();
        let serial_q: Vec<Quantity> = self
            .serial_idx
            .iter()
            .map(|&k| coords[k].quantity)
            .collect();
        let act_q: Vec<Quantity> = self.m.actuators().iter().map(|a| a.quantity).collect();
        let ratios = ratios(&serial, &serial_q, &act, &act_q);
        MotionSummary {
            actuators: self
                .m
                .actuators()
                .iter()
                .map(|a| a.name.clone())
                .zip(act)
                .collect(),
            serial: names.into_iter().zip(serial).collect(),
            ratios,
            violations: self.runs,
            violations_not_listed: self.dropped,
            feed_override_max: {
                // Velocities scale with the override k, accelerations with k^2.
                // max over samples of |q'| / limit is max |q'| / limit: a correctly
                // rounded division is monotonic in its numerator.
                let (mut v_ratio, mut a_ratio) = (0.0f64, 0.0f64);
                for (&(vp, ap), &(vm, am)) in self.peak_rates.iter().zip(&self.rate_limits) {
                    if vm < f64::INFINITY {
                        v_ratio = v_ratio.max(vp / vm);
                    }
                    if am < f64::INFINITY {
                        a_ratio = a_ratio.max(ap / am);
                    }
                }
                let k = (1.0 / v_ratio).min((1.0 / a_ratio).sqrt());
                k.is_finite().then_some(k)
            },
            singular: self.singular.finish(),
            duration_s,
            samples,
        }
    }
}

/// Where coordinate `k` of `m` sits in a G-code position `[X, Y, Z, A, B, C]`: all six
/// for a spatial machine, X, Y, Z for a position machine; X, Y, Z and the rotary axes
/// by their letters for a TCP machine. `None` for a coordinate no letter addresses.
fn gcode_slot<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    k: usize,
) -> Option<usize> {
    match (m.pose_space(), P) {
        (PoseSpace::Spatial, 6) | (PoseSpace::Position, 3) => Some(k),
        (PoseSpace::Tcp, _) if k < 3 => Some(k),
        (PoseSpace::Tcp, _) => match m.coordinates()[k].name.as_str() {
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
                    message: match m.pose_space() {
                        PoseSpace::Tcp => format!(
                            "the rotary axis `{}` has no G-code letter (A, B or C)",
                            m.coordinates()[k].name
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
    if m.pose_space() != PoseSpace::Tcp {
        return Vec::new();
    }
    (3..6)
        .filter(|i| !(0..P).any(|k| gcode_slot(m, k) == Some(*i)))
        .collect()
}

/// Quantities of the coordinates, for [`Segment::line`].
pub fn quantities<M: Mechanism<P, A>, const P: usize, const A: usize>(m: &M) -> [Quantity; P] {
    std::array::from_fn(|k| m.coordinates()[k].quantity)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The statistics' loop compiled for AVX-512 (where the CPU has it) gives the
    /// plain build's bits: the same minima, maxima, peaks and sums over samples with
    /// signed zeros, infinities and NaN among ordinary values.
    #[test]
    fn statistics_loop_is_the_same_in_every_build() {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../examples/machines/hexapod-linuxcnc.toml"
        ))
        .unwrap();
        let machine = crate::Machine::from_toml_str(&text, "hexapod-linuxcnc.toml").unwrap();
        let crate::machine::Model::Hexapod(m) = &machine.model else {
            panic!("a hexapod")
        };
        let mut rng = rand::rngs::StdRng::seed_from_u64(19);
        // Ordinary values and signed zeros, then infinities too, then NaN too: an
        // infinity or a NaN stays in a sum from there on.
        let mut draw = |k: usize| match rng.random_range(0..24) {
            0 => 0.0,
            1 => -0.0,
            2 if k >= 2000 => f64::INFINITY,
            3 if k >= 2000 => f64::NEG_INFINITY,
            4 if k >= 2900 => f64::NAN,
            _ => rng.random_range(-1e3..1e3),
        };
        let samples: Vec<Sample<6, 6>> = (0..3000)
            .map(|k| Sample {
                t: k as f64,
                line: None,
                x: SVector::from_fn(|_, _| draw(k)),
                xd: SVector::from_fn(|_, _| draw(k)),
                xdd: SVector::from_fn(|_, _| draw(k)),
                act: ActuatorMotion {
                    q: SVector::from_fn(|_, _| draw(k)),
                    qd: SVector::from_fn(|_, _| draw(k)),
                    qdd: SVector::from_fn(|_, _| draw(k)),
                },
            })
            .collect();
        let m: &crate::hexapod::Hexapod = m;
        let new = || Runner::new(m, Sampling::Rate(100.0)).unwrap().rec;
        let bits = |r: &Recorder<'_, crate::hexapod::Hexapod, 6, 6>| {
            let stats = (0..6).flat_map(|i| [r.act.axis(i), r.serial.axis(i)]);
            let mut v: Vec<u64> = stats.flat_map(|s| s.bits()).collect();
            v.extend(
                r.peak_rates
                    .iter()
                    .flat_map(|p| [p.0.to_bits(), p.1.to_bits()]),
            );
            v
        };
        let (mut plain, mut fast) = (new(), new());
        let mut finite = 0;
        for (range, step) in [(0..2000, 300), (2000..2900, 200), (2900..3000, 30)] {
            for part in samples[range].chunks(step) {
                plain.add_stats_plain(part);
                fast.add_stats(part);
            }
            assert_eq!(bits(&plain), bits(&fast));
            // Not vacuous: sums of ordinary values before the infinities.
            if plain.act.axis(0).travel.is_finite() {
                assert!(plain.act.axis(0).travel > 1e5);
                finite += 1;
            }
        }
        assert!(finite >= 1);
    }
}
