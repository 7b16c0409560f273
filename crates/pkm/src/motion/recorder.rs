//! What the samples of a run add up to, taken in order on the caller's thread: each
//! actuator's and serial axis's statistics, the actuators' rate limits, stretches of
//! violated limits, passages near a singular direction, each sample continued from the
//! one before where the mechanism picks among solutions, and the sink.

use super::block::Block;
use super::follow::{follow_block, Last};
use super::run::{MotionSummary, Sample, ViolationRun};
use super::singular::{SingularTracker, DEFAULT_SINGULAR_ANGLE};
use super::stats::{ratios, AxisBank, AxisStats};
use crate::error::Result;
use crate::limits::{LimitKind, LimitName, Side, Violation};
use crate::mechanism::Mechanism;
use crate::units::Quantity;

const MAX_RUNS: usize = 10_000;

/// Where a run's samples go, and the tool lengths they are taken with: one owner for
/// the state both need (the accuracy along a path follows the tool).
pub(crate) trait RunSink<const P: usize, const A: usize> {
    /// One sample, in order; an error stops the run.
    fn sample(&mut self, s: &Sample<P, A>) -> Result<()>;
    /// The samples from here on are taken with a tool `length` mm longer than the
    /// machine file's.
    fn tool_length(&mut self, length: f64) -> Result<()>;
}

/// A [`RunSink`] of two callbacks: `sample` for the samples, `tool` for the tool
/// lengths.
pub(super) struct Callbacks<'c, F, T> {
    /// Called with every sample.
    pub(super) sample: &'c mut F,
    /// Called with every tool length.
    pub(super) tool: &'c mut T,
}

impl<F, T, const P: usize, const A: usize> RunSink<P, A> for Callbacks<'_, F, T>
where
    F: FnMut(&Sample<P, A>) -> Result<()>,
    T: FnMut(f64) -> Result<()>,
{
    #[inline]
    fn sample(&mut self, s: &Sample<P, A>) -> Result<()> {
        (self.sample)(s)
    }

    #[inline]
    fn tool_length(&mut self, length: f64) -> Result<()> {
        (self.tool)(length)
    }
}

/// What the samples add up to, taken in order.
pub(super) struct Recorder<'m, M, const P: usize, const A: usize> {
    pub(super) m: &'m M,
    act: AxisBank<A>,
    /// The serial axes in the first `serial_idx.len()` lanes (the others stay zero).
    serial: AxisBank<P>,
    pub(super) serial_idx: Vec<usize>,
    runs: Vec<ViolationRun>,
    /// The stretches still open: their limit and index in `runs`, in the order of
    /// the last sample's violations.
    open: Vec<(LimitName, usize)>,
    /// Storage for the next `open` (kept: no allocation per sample).
    spare_open: Vec<(LimitName, usize)>,
    dropped: u64,
    /// The rate limits' violations of the sample being recorded (kept: no allocation
    /// per sample).
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
    /// Per actuator, the largest |q'| and |q''| seen in the moves being added: the
    /// feed moves', swapped with `rapid_peaks` while rapids are added.
    peak_rates: [(f64, f64); A],
    /// Per actuator, the largest |q'| and |q''| seen in rapids (G0).
    rapid_peaks: [(f64, f64); A],
    pub(super) singular: SingularTracker,
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

impl<'m, M: Mechanism<P, A>, const P: usize, const A: usize> Recorder<'m, M, P, A> {
    /// What the samples of mechanism `m` add up to, with the serial axes `serial_idx`
    /// (coordinates of `m`; at most `P`).
    pub(super) fn new(m: &'m M, serial_idx: Vec<usize>) -> Result<Self> {
        Ok(Recorder {
            m,
            act: AxisBank::default(),
            serial: AxisBank::default(),
            runs: Vec::new(),
            open: Vec::new(),
            spare_open: Vec::new(),
            dropped: 0,
            buf: Vec::new(),
            act_scale: std::array::from_fn(|i| m.info().actuators()[i].quantity.user_scale()),
            serial_scale: std::array::from_fn(|j| {
                serial_idx
                    .get(j)
                    .map_or(0.0, |&k| m.info().coordinates()[k].quantity.user_scale())
            }),
            rate_limits: std::array::from_fn(|i| {
                let a = &m.info().actuators()[i];
                (
                    a.max_velocity.unwrap_or(f64::INFINITY),
                    a.max_acceleration.unwrap_or(f64::INFINITY),
                )
            }),
            rate_names: m
                .info()
                .actuators()
                .iter()
                .map(|a| {
                    ["velocity", "acceleration"]
                        .map(|what| format!("actuator {} {what}", a.name).into())
                })
                .collect(),
            peak_rates: [(0.0, 0.0); A],
            rapid_peaks: [(0.0, 0.0); A],
            serial_idx,
            singular: SingularTracker::new(m.info().actuators(), DEFAULT_SINGULAR_ANGLE)?,
            last: None,
        })
    }
}

impl<M: Mechanism<P, A>, const P: usize, const A: usize> Recorder<'_, M, P, A> {
    /// Records the samples of block `b` in order, after passing its tool length on;
    /// raises the error the block ends on, if any, after the samples before it.
    pub(super) fn record<S: RunSink<P, A>>(
        &mut self,
        b: &mut Block<M, P, A>,
        sink: &mut S,
    ) -> Result<()> {
        if let Some(length) = b.tool {
            sink.tool_length(length)?;
        }
        // Each sample continues the one before (a robot's posture and turns).
        follow_block(self.m, b, &mut self.last);
        let n = b.failed.as_ref().map_or(b.plan.len(), |f| f.0);
        // Each sample's violations are read where the compute stage left them, in
        // sample order (a 72-byte violation moved per sample through a `Peekable` was
        // a stalled store-to-load copy).
        let violations = &b.violations[..];
        let mut next = 0;
        // The samples in order, then their statistics: the statistics see the same
        // samples in the same order as if they were taken sample by sample (up to the
        // one a sink refused), in a loop of their own.
        let mut recorded = Ok(());
        let mut taken = n;
        for k in 0..n {
            let from = next;
            while violations.get(next).is_some_and(|v| v.0 as usize == k) {
                next += 1;
            }
            let rapid = b.moves[b.plan[k].0 as usize].0.rapid;
            if let Err(e) = self.record_sample(&b.samples[k], &violations[from..next], rapid, sink)
            {
                (recorded, taken) = (Err(e), k + 1);
                break;
            }
        }
        b.violations.clear();
        self.add_block_stats(b, taken);
        recorded?;
        if let Some((_, e)) = b.failed.take() {
            return Err(e);
        }
        match b.tail.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    /// Adds the first `taken` samples of block `b` to the statistics, in order: each
    /// stretch of samples of feed moves or of rapids with the peak rates of its kind
    /// (a feed override scales the feed moves, not the rapids).
    fn add_block_stats(&mut self, b: &Block<M, P, A>, taken: usize) {
        // A block without a rapid (most of them: a block holds a few moves) is one
        // stretch, its samples not looked at one by one.
        if !b.moves.iter().any(|m| m.0.rapid) {
            self.add_stats(&b.samples[..taken]);
            return;
        }
        let rapid = |k: usize| b.moves[b.plan[k].0 as usize].0.rapid;
        let mut from = 0;
        while from < taken {
            let kind = rapid(from);
            let to = (from + 1..taken)
                .find(|&k| rapid(k) != kind)
                .unwrap_or(taken);
            if kind {
                std::mem::swap(&mut self.peak_rates, &mut self.rapid_peaks);
                self.add_stats(&b.samples[from..to]);
                std::mem::swap(&mut self.peak_rates, &mut self.rapid_peaks);
            } else {
                self.add_stats(&b.samples[from..to]);
            }
            from = to;
        }
    }

    /// Records sample `s` of a move (a rapid when `rapid`) with `found`, the
    /// violations of the mechanism's own limits found with it (by sample index); the
    /// rate limits are checked here.
    fn record_sample<S: RunSink<P, A>>(
        &mut self,
        s: &Sample<P, A>,
        found: &[(u32, Violation)],
        rapid: bool,
        sink: &mut S,
    ) -> Result<()> {
        let (t, act, x) = (s.t, &s.act, &s.x);
        self.buf.clear();
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
        if !(found.is_empty() && self.buf.is_empty() && self.open.is_empty()) {
            let rate = std::mem::take(&mut self.buf);
            self.track(t, s.line, found, &rate);
            self.buf = rate;
        }
        // The singular direction does not depend on the tool length. Rapids run each
        // axis at its own rate whatever the direction: what a passage costs is the
        // feed moves'.
        if !rapid {
            if let Some(d) = self.m.tool_axis().and_then(|t| t.singular_distance(x)) {
                self.singular.add(t, s.line, d, act.qd.as_slice());
            }
        }
        sink.sample(s)
    }

    /// The violation of actuator `i`'s velocity (`order` 1) or acceleration (2) limit
    /// by `value` (internal units).
    fn rate_violation(&self, i: usize, order: u8, value: f64) -> Violation {
        let a = &self.m.info().actuators()[i];
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

    /// Extends, opens and closes the stretches of violations with the violations of
    /// the sample at time `t` on G-code line `line`: the mechanism's own, `found`, then
    /// the rate limits', `rate`, in that order.
    fn track(&mut self, t: f64, line: Option<u64>, found: &[(u32, Violation)], rate: &[Violation]) {
        let now = || found.iter().map(|(_, v)| v).chain(rate);
        // The limits of the sample before, in its order (a stretch beyond them): the
        // names compare by pointer when the mechanism names its limits once.
        if found.len() + rate.len() == self.open.len()
            && now().zip(&self.open).all(|(v, (n, _))| v.limit == *n)
        {
            for (v, &(_, idx)) in now().zip(&self.open) {
                extend_run(&mut self.runs[idx], v, t);
            }
            return;
        }
        // Otherwise: stretches whose limit is no longer violated close, the others
        // go on, new ones open; `open` then lists them in this sample's order.
        let old = std::mem::take(&mut self.open);
        let mut open = std::mem::take(&mut self.spare_open);
        open.clear();
        for v in now() {
            let tracked = open
                .iter()
                .chain(old.iter())
                .find(|(n, _)| *n == v.limit)
                .map(|&(_, idx)| idx);
            match tracked {
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
    pub(super) fn finish(self, names: Vec<String>, duration_s: f64, samples: u64) -> MotionSummary {
        let act: Vec<AxisStats> = (0..A).map(|i| self.act.axis(i)).collect();
        let serial: Vec<AxisStats> = (0..self.serial_idx.len())
            .map(|j| self.serial.axis(j))
            .collect();
        let coords = self.m.info().coordinates();
        let serial_q: Vec<Quantity> = self
            .serial_idx
            .iter()
            .map(|&k| coords[k].quantity)
            .collect();
        let act_q: Vec<Quantity> = self
            .m
            .info()
            .actuators()
            .iter()
            .map(|a| a.quantity)
            .collect();
        let ratios = ratios(&serial, &serial_q, &act, &act_q);
        MotionSummary {
            actuators: self
                .m
                .info()
                .actuators()
                .iter()
                .map(|a| a.name.clone())
                .zip(act)
                .collect(),
            serial: names.into_iter().zip(serial).collect(),
            ratios,
            violations: self.runs,
            violations_not_listed: self.dropped,
            feed_override_max: override_max(&self.peak_rates, &self.rate_limits),
            rapid_override_max: override_max(&self.rapid_peaks, &self.rate_limits),
            singular: self.singular.finish(),
            duration_s,
            samples,
        }
    }
}

/// The largest factor k by which the moves of `peaks` (per actuator, the largest
/// |q'| and |q''|) can be sped up while every actuator keeps within `limits` (its
/// velocity and acceleration limits, infinite where none): velocities scale with k,
/// accelerations with k^2, so k = min(min_i v_max / |q'|, sqrt(min_i a_max / |q''|)).
/// `None` without limits or without motion.
fn override_max<const A: usize>(peaks: &[(f64, f64); A], limits: &[(f64, f64); A]) -> Option<f64> {
    // max over samples of |q'| / limit is max |q'| / limit: a correctly rounded
    // division is monotonic in its numerator.
    let (mut v_ratio, mut a_ratio) = (0.0f64, 0.0f64);
    for (&(vp, ap), &(vm, am)) in peaks.iter().zip(limits) {
        if vm < f64::INFINITY {
            v_ratio = v_ratio.max(vp / vm);
        }
        if am < f64::INFINITY {
            a_ratio = a_ratio.max(ap / am);
        }
    }
    let k = (1.0 / v_ratio).min((1.0 / a_ratio).sqrt());
    k.is_finite().then_some(k)
}

mod statistics;
