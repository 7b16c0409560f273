//! The recorder's statistics pass: each block's samples added, in order, to the
//! actuators' and the serial axes' statistics and the actuators' peak rates, in
//! AVX-512 registers where the CPU has them (the same bits as the plain loop).

use nalgebra::SVector;

use super::Recorder;
use crate::mechanism::Mechanism;
use crate::motion::run::Sample;

impl<M: Mechanism<P, A>, const P: usize, const A: usize> Recorder<'_, M, P, A> {
    /// Adds `samples`, in order, to the actuators' and the serial axes' statistics and
    /// the actuators' peak rates. The banks are held in locals for the loop: stored
    /// back once per block, not once per sample around the sink's call.
    pub(super) fn add_stats(&mut self, samples: &[Sample<P, A>]) {
        #[cfg(target_arch = "x86_64")]
        if A <= 8 && P <= 8 && crate::simd::level() >= crate::simd::Level::Avx512 {
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

        use crate::motion::stats::avx512::{lanes, load, Bank};
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
