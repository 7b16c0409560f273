//! Running moves through a mechanism: sampling, exact actuator kinematics, serial
//! comparison, limits along the path and the largest feed override.

use nalgebra::SVector;
use serde::Serialize;

use super::path::Segment;
use super::profile::Profile;
use super::singular::{SingularReport, SingularTracker, DEFAULT_SINGULAR_ANGLE};
use super::stats::{ratios, AxisStats, Ratios};
use crate::error::{Error, Result};
use crate::limits::{LimitKind, Side, Violation};
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
    /// serial axis is an angle (a ratio of mm to deg means nothing).
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

/// Runs moves through a mechanism one at a time (streaming: memory stays flat).
pub struct Runner<'m, M, const P: usize, const A: usize> {
    m: &'m M,
    /// The mechanism with the program's tool length, when it has one.
    tooled: Option<Box<M>>,
    tool_length: f64,
    sampling: Sampling,
    t0: f64,
    k: u64,
    samples: u64,
    first: bool,
    act: [AxisStats; A],
    serial: Vec<AxisStats>,
    serial_idx: Vec<usize>,
    runs: Vec<ViolationRun>,
    open: Vec<(String, usize)>,
    dropped: u64,
    buf: Vec<Violation>,
    /// Largest |q'| / limit and |q''| / limit seen.
    v_ratio: f64,
    a_ratio: f64,
    /// The work limit (samples).
    max_samples: u64,
    singular: SingularTracker,
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
            m,
            tooled: None,
            tool_length: 0.0,
            sampling,
            t0: 0.0,
            k: 0,
            samples: 0,
            first: true,
            act: [AxisStats::default(); A],
            serial: vec![AxisStats::default(); serial_idx.len()],
            serial_idx,
            runs: Vec::new(),
            open: Vec::new(),
            dropped: 0,
            buf: Vec::new(),
            v_ratio: 0.0,
            a_ratio: 0.0,
            max_samples: DEFAULT_MAX_SAMPLES,
            singular: SingularTracker::new(m.actuators(), DEFAULT_SINGULAR_ANGLE)?,
        })
    }

    /// Names of the serial axes (`X`, `Y`, `Z`, or the machine's own coordinates).
    pub fn serial_names(&self) -> Vec<String> {
        self.serial_idx
            .iter()
            .map(|&k| self.m.coordinates()[k].name.clone())
            .collect()
    }

    /// Runs the following moves with a tool `length` mm longer than the machine file's
    /// ([`Mechanism::with_tool_length`]; a program's `G43 H`, 0 for `G49`).
    pub fn set_tool_length(&mut self, length: f64) -> Result<()> {
        if length == self.tool_length {
            return Ok(());
        }
        match self.m.with_tool_length(length) {
            Some(m) => {
                self.tooled = Some(Box::new(m?));
            }
            None if length == 0.0 => self.tooled = None,
            None => {
                return Err(Error::Unsupported {
                    machine: self.m.name().into(),
                    kind: self.m.kind().into(),
                    analysis: "a tool length from the program (G43)",
                    reason: "its tool is set in the machine file".into(),
                })
            }
        }
        self.tool_length = length;
        Ok(())
    }

    /// Sets the threshold (rad, 0 to pi/2) of a passage near the singular direction
    /// ([`SingularTracker`]); default [`DEFAULT_SINGULAR_ANGLE`].
    pub fn set_singular_angle(&mut self, angle: f64) -> Result<()> {
        self.singular = SingularTracker::new(self.m.actuators(), angle)?;
        Ok(())
    }

    /// Sets the work limit: at most `n` samples over the run.
    pub fn set_max_samples(&mut self, n: u64) {
        self.max_samples = n;
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

    /// Samples one move and passes every sample to `sink`. `last` marks the program's
    /// final move (its end instant is sampled).
    pub fn run_move<F>(&mut self, mv: &Move<P>, last: bool, sink: &mut F) -> Result<()>
    where
        F: FnMut(&Sample<P, A>) -> Result<()>,
    {
        self.check_work(mv)?;
        let driven = self.m.driven();
        for k in 0..P {
            if !driven.contains(&k) && (mv.segment.end[k] - mv.segment.start[k]).abs() > 1e-12 {
                let c = &self.m.coordinates()[k];
                return Err(Error::NotAttainable {
                    reason: format!(
                        "{}the move changes {} from {:.4} to {:.4} {}, which the mechanism holds constant",
                        mv.line.map(|l| format!("line {l}: ")).unwrap_or_default(),
                        c.name,
                        c.quantity.to_user(mv.segment.start[k]),
                        c.quantity.to_user(mv.segment.end[k]),
                        c.quantity.unit()
                    ),
                });
            }
        }
        let dur = mv.profile.duration;
        match self.sampling {
            Sampling::Rate(rate) => {
                loop {
                    let t = self.k as f64 / rate;
                    if t > self.t0 + dur + 1e-12 {
                        break;
                    }
                    self.sample(mv, t - self.t0, sink)?;
                    self.k += 1;
                }
                if last && (self.t0 + dur) > (self.k as f64 - 1.0) / rate + 1e-12 {
                    self.sample(mv, dur, sink)?;
                }
            }
            Sampling::Points(n) => {
                let from = if self.first { 0 } else { 1 };
                for i in from..n {
                    self.sample(mv, dur * i as f64 / (n - 1) as f64, sink)?;
                }
            }
        }
        self.first = false;
        self.t0 += dur;
        Ok(())
    }

    fn sample<F>(&mut self, mv: &Move<P>, tl: f64, sink: &mut F) -> Result<()>
    where
        F: FnMut(&Sample<P, A>) -> Result<()>,
    {
        let (s, sd, sdd) = mv.profile.eval(tl);
        let (x, xs, xss) = mv.segment.eval(s);
        let xd = xs * sd;
        let xdd = xss * (sd * sd) + xs * sdd;
        let m: &M = match &self.tooled {
            Some(b) => b,
            None => self.m,
        };
        // Limits: positions (and the mechanism's own) with the motion, rates below.
        self.buf.clear();
        let act = m.actuator_motion_checked(&x, &xd, &xdd, &mut self.buf)?;
        let t = self.t0 + tl;
        self.samples += 1;
        for i in 0..A {
            let qn = self.m.actuators()[i].quantity;
            self.act[i].add(
                qn.to_user(act.q[i]),
                qn.to_user(act.qd[i]),
                qn.to_user(act.qdd[i]),
            );
        }
        for (j, &k) in self.serial_idx.iter().enumerate() {
            let qn = self.m.coordinates()[k].quantity;
            self.serial[j].add(qn.to_user(x[k]), qn.to_user(xd[k]), qn.to_user(xdd[k]));
        }
        for i in 0..A {
            let a = &self.m.actuators()[i];
            if let Some(vm) = a.max_velocity {
                let v = act.qd[i].abs();
                if v > vm {
                    let mut x = Violation::new(
                        format!("actuator {} velocity", a.name),
                        LimitKind::ActuatorVelocity,
                        Side::Max,
                        a.quantity,
                        v,
                        vm,
                    );
                    x.unit = a.quantity.rate_unit(1);
                    self.buf.push(x);
                }
                self.v_ratio = self.v_ratio.max(v / vm);
            }
            if let Some(am) = a.max_acceleration {
                let acc = act.qdd[i].abs();
                if acc > am {
                    let mut x = Violation::new(
                        format!("actuator {} acceleration", a.name),
                        LimitKind::ActuatorAcceleration,
                        Side::Max,
                        a.quantity,
                        acc,
                        am,
                    );
                    x.unit = a.quantity.rate_unit(2);
                    self.buf.push(x);
                }
                self.a_ratio = self.a_ratio.max(acc / am);
            }
        }
        self.track(t, mv.line);
        // The singular direction does not depend on the tool length. Rapids run each
        // axis at its rapid rate whatever the direction: what a passage costs is the
        // feed moves'.
        if !mv.rapid {
            if let Some(d) = self.m.singular_distance(&x) {
                self.singular.add(t, mv.line, d, act.qd.as_slice());
            }
        }
        sink(&Sample {
            t,
            line: mv.line,
            x,
            xd,
            xdd,
            act,
        })
    }

    fn track(&mut self, t: f64, line: Option<u64>) {
        // Close stretches whose limit is no longer violated.
        let buf = &self.buf;
        self.open
            .retain(|(name, _)| buf.iter().any(|v| &v.limit == name));
        for v in &self.buf {
            match self.open.iter().find(|(n, _)| n == &v.limit) {
                Some(&(_, idx)) => {
                    let r = &mut self.runs[idx];
                    r.end_s = t;
                    if v.excess > (r.worst - r.bound).abs() {
                        r.worst = v.value;
                    }
                }
                None => {
                    if self.runs.len() >= MAX_RUNS {
                        self.dropped += 1;
                        continue;
                    }
                    self.runs.push(ViolationRun {
                        limit: v.limit.clone(),
                        kind: v.kind,
                        line,
                        start_s: t,
                        end_s: t,
                        worst: v.value,
                        bound: v.bound,
                        unit: v.unit.to_string(),
                    });
                    self.open.push((v.limit.clone(), self.runs.len() - 1));
                }
            }
        }
    }

    /// The summary of everything run so far.
    pub fn finish(mut self) -> MotionSummary {
        let names = self.serial_names();
        for s in self.act.iter_mut().chain(self.serial.iter_mut()) {
            s.finalize();
        }
        let act: Vec<AxisStats> = self.act.to_vec();
        let coords = self.m.coordinates();
        let serial_q: Vec<Quantity> = self
            .serial_idx
            .iter()
            .map(|&k| coords[k].quantity)
            .collect();
        let act_q: Vec<Quantity> = self.m.actuators().iter().map(|a| a.quantity).collect();
        let ratios = ratios(&self.serial, &serial_q, &act, &act_q);
        MotionSummary {
            actuators: self
                .m
                .actuators()
                .iter()
                .map(|a| a.name.clone())
                .zip(act)
                .collect(),
            serial: names.into_iter().zip(self.serial).collect(),
            ratios,
            violations: self.runs,
            violations_not_listed: self.dropped,
            feed_override_max: {
                // Velocities scale with the override k, accelerations with k^2.
                let k = (1.0 / self.v_ratio).min((1.0 / self.a_ratio).sqrt());
                k.is_finite().then_some(k)
            },
            singular: self.singular.finish(),
            duration_s: self.t0,
            samples: self.samples,
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
