//! What the samples of a run add up to, taken in order on the caller's thread: each
//! actuator's and serial axis's statistics, the actuators' rate limits, stretches of
//! violated limits, passages near a singular direction, each sample continued from the
//! one before where the mechanism picks among solutions, and the sink.

use nalgebra::SVector;

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
    /// Per actuator, the largest |q'| and |q''| seen.
    peak_rates: [(f64, f64); A],
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
        })
    }
}

impl<M: Mechanism<P, A>, const P: usize, const A: usize> Recorder<'_, M, P, A> {
    /// Records the samples of block `b` in order, after passing its tool length on;
    /// raises the error the block ends on, if any, after the samples before it.
    pub(super) fn record<F, T>(
        &mut self,
        b: &mut Block<M, P, A>,
        sink: &mut F,
        tool: &mut T,
    ) -> Result<()>
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

    /// Records sample `s` of a move (a rapid when `rapid`) with `found`, the
    /// violations of the mechanism's own limits found with it (by sample index); the
    /// rate limits are checked here.
    fn record_sample<F>(
        &mut self,
        s: &Sample<P, A>,
        found: &[(u32, Violation)],
        rapid: bool,
        sink: &mut F,
    ) -> Result<()>
    where
        F: FnMut(&Sample<P, A>) -> Result<()>,
    {
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
        if A <= 8 && P <= 8 && std::arch::is_x86_feature_detected!("avx512f") {
            // SAFETY: the CPU has AVX-512F; A, P <= 8.
            unsafe { self.add_stats_avx512(samples) };
            return;
        }
        self.add_stats_plain(samples);
    }

    /// [`Self::add_stats_plain`] with each bank in AVX-512 registers
    /// ([`super::stats::avx512::Bank`]: the same bits) and both in one pass.
    ///
    /// # Safety
    /// The CPU must have AVX-512F, and `A, P <= 8`.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f")]
    unsafe fn add_stats_avx512(&mut self, samples: &[Sample<P, A>]) {
        use std::arch::x86_64::*;

        use super::stats::avx512::{lanes, load, Bank};
        // SAFETY (whole body): every load reads the A or P f64 of a vector or array
        // of that length (A, P <= 8, the caller's promise), every store the A f64 of
        // an array; the feature is this function's.
        unsafe {
            let (mut act, mut serial) = (Bank::of(&self.act), Bank::of(&self.serial));
            let c = load(self.act_scale.as_ptr(), A);
            let cs = load(self.serial_scale.as_ptr(), P);
            let (pv, pa): ([f64; A], [f64; A]) = (
                std::array::from_fn(|i| self.peak_rates[i].0),
                std::array::from_fn(|i| self.peak_rates[i].1),
            );
            let (mut pv, mut pa) = (load(pv.as_ptr(), A), load(pa.as_ptr(), A));
            // Serial lane j is coordinate serial_idx[j] scaled (zero past the serial
            // axes, where the scale is zero too).
            let idx: [i64; 8] =
                std::array::from_fn(|j| self.serial_idx.get(j).map_or(0, |&k| k as i64));
            let idx = _mm512_loadu_si512(idx.as_ptr().cast());
            let keep = lanes(self.serial_idx.len());
            let lane = |v: &SVector<f64, P>| {
                _mm512_mul_pd(
                    _mm512_maskz_permutexvar_pd(keep, idx, load(v.as_ptr(), P)),
                    cs,
                )
            };
            for s in samples {
                let a = &s.act;
                let (q, qd, qdd) = (
                    load(a.q.as_ptr(), A),
                    load(a.qd.as_ptr(), A),
                    load(a.qdd.as_ptr(), A),
                );
                act.add(
                    _mm512_mul_pd(q, c),
                    _mm512_mul_pd(qd, c),
                    _mm512_mul_pd(qdd, c),
                );
                pv = _mm512_max_pd(_mm512_abs_pd(qd), pv);
                pa = _mm512_max_pd(_mm512_abs_pd(qdd), pa);
                serial.add(lane(&s.x), lane(&s.xd), lane(&s.xdd));
            }
            act.store(&mut self.act);
            serial.store(&mut self.serial);
            let (mut v, mut w) = ([0.0; A], [0.0; A]);
            _mm512_mask_storeu_pd(v.as_mut_ptr(), lanes(A), pv);
            _mm512_mask_storeu_pd(w.as_mut_ptr(), lanes(A), pa);
            self.peak_rates = std::array::from_fn(|i| (v[i], w[i]));
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanism::ActuatorMotion;
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
        // X, Y, Z as the serial axes, as a runner sets them for a spatial machine; and
        // coordinates in another order, some left out.
        for serial in [vec![0, 1, 2], vec![5, 0, 3, 1]] {
            check_statistics_loop(m, &samples, serial);
        }
    }

    fn check_statistics_loop(
        m: &crate::hexapod::Hexapod,
        samples: &[Sample<6, 6>],
        serial: Vec<usize>,
    ) {
        let new = || Recorder::new(m, serial.clone()).unwrap();
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
