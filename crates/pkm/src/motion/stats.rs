//! Online statistics of axis motion (flat memory for any program length).

use serde::Serialize;

use crate::units::Quantity;

/// Motion statistics of one axis (actuator or serial axis), user units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AxisStats {
    /// Total travel: sum of |position change| between samples (mm or deg).
    pub travel: f64,
    /// Smallest position.
    pub min: f64,
    /// Largest position.
    pub max: f64,
    /// Largest |velocity| (mm/s or deg/s).
    pub peak_velocity: f64,
    /// Mean |velocity| over the samples.
    pub mean_abs_velocity: f64,
    /// Largest |acceleration| (mm/s^2 or deg/s^2).
    pub peak_acceleration: f64,
    /// Mean |acceleration| over the samples.
    pub mean_abs_acceleration: f64,
    #[serde(skip)]
    last: f64,
    #[serde(skip)]
    n: u64,
    #[serde(skip)]
    sum_v: f64,
    #[serde(skip)]
    sum_a: f64,
}

impl Default for AxisStats {
    fn default() -> Self {
        AxisStats {
            travel: 0.0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            peak_velocity: 0.0,
            mean_abs_velocity: 0.0,
            peak_acceleration: 0.0,
            mean_abs_acceleration: 0.0,
            last: f64::NAN,
            n: 0,
            sum_v: 0.0,
            sum_a: 0.0,
        }
    }
}

impl AxisStats {
    /// Adds one sample.
    #[inline]
    pub fn add(&mut self, q: f64, v: f64, a: f64) {
        if self.n > 0 {
            self.travel += (q - self.last).abs();
        }
        self.last = q;
        self.n += 1;
        self.min = self.min.min(q);
        self.max = self.max.max(q);
        self.peak_velocity = self.peak_velocity.max(v.abs());
        self.peak_acceleration = self.peak_acceleration.max(a.abs());
        self.sum_v += v.abs();
        self.sum_a += a.abs();
    }

    /// Sets the means from the accumulated sums (call once, after the last sample).
    pub fn finalize(&mut self) {
        let n = self.n.max(1) as f64;
        self.mean_abs_velocity = self.sum_v / n;
        self.mean_abs_acceleration = self.sum_a / n;
    }

    /// Every reported figure's bits, for tests that compare results bit for bit.
    #[cfg(test)]
    pub(crate) fn bits(&self) -> [u64; 7] {
        [
            self.travel,
            self.min,
            self.max,
            self.peak_velocity,
            self.mean_abs_velocity,
            self.peak_acceleration,
            self.mean_abs_acceleration,
        ]
        .map(f64::to_bits)
    }
}

/// [`AxisStats`] of `N` axes sampled together, laid out by field (one array per
/// statistic), so that adding a sample is a few vector operations over the axes instead
/// of one struct per axis: the motion engine adds every sample to two of these. Each
/// axis's statistics are [`AxisStats::add`]'s, the same operations in the same order
/// (tested bit for bit).
#[derive(Debug, Clone, Copy)]
pub struct AxisBank<const N: usize> {
    travel: [f64; N],
    min: [f64; N],
    max: [f64; N],
    peak_v: [f64; N],
    peak_a: [f64; N],
    sum_v: [f64; N],
    sum_a: [f64; N],
    last: [f64; N],
    n: u64,
}

impl<const N: usize> Default for AxisBank<N> {
    fn default() -> Self {
        AxisBank {
            travel: [0.0; N],
            min: [f64::INFINITY; N],
            max: [f64::NEG_INFINITY; N],
            peak_v: [0.0; N],
            peak_a: [0.0; N],
            sum_v: [0.0; N],
            sum_a: [0.0; N],
            last: [f64::NAN; N],
            n: 0,
        }
    }
}

impl<const N: usize> AxisBank<N> {
    /// Adds one sample of every axis: positions `q`, velocities `v`, accelerations `a`.
    #[inline]
    #[allow(clippy::needless_range_loop)] // the fields are indexed together
    pub fn add(&mut self, q: &[f64; N], v: &[f64; N], a: &[f64; N]) {
        if self.n > 0 {
            for i in 0..N {
                self.travel[i] += (q[i] - self.last[i]).abs();
            }
        }
        self.last = *q;
        self.n += 1;
        for i in 0..N {
            self.min[i] = self.min[i].min(q[i]);
            self.max[i] = self.max[i].max(q[i]);
            self.peak_v[i] = self.peak_v[i].max(v[i].abs());
            self.peak_a[i] = self.peak_a[i].max(a[i].abs());
            self.sum_v[i] += v[i].abs();
            self.sum_a[i] += a[i].abs();
        }
    }

    /// The statistics of axis `i`, finalised (means set).
    pub fn axis(&self, i: usize) -> AxisStats {
        let mut s = AxisStats {
            travel: self.travel[i],
            min: self.min[i],
            max: self.max[i],
            peak_velocity: self.peak_v[i],
            mean_abs_velocity: 0.0,
            peak_acceleration: self.peak_a[i],
            mean_abs_acceleration: 0.0,
            last: self.last[i],
            n: self.n,
            sum_v: self.sum_v[i],
            sum_a: self.sum_a[i],
        };
        s.finalize();
        s
    }
}

/// [`AxisBank::add`] on AVX-512 registers, for banks of up to eight axes: the bank is
/// loaded into eight registers for a run of samples and stored back once, and each
/// sample is a dozen register operations. The same operations in the same order as
/// the plain code, so the same bits: `_mm512_min_pd(q, acc)` returns `acc` when `q` is
/// NaN and when both are zeros, as `f64::min(acc, q)` compiles on x86, and `acc` is
/// never NaN (tested against the plain bank, NaN, zeros and infinities included).
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx512 {
    use std::arch::x86_64::*;

    use super::AxisBank;

    /// Lanes `0..n` of the `n` contiguous f64 at `p`, the others zero.
    ///
    /// # Safety
    /// `p` must point to `n <= 8` readable f64, and the CPU must have AVX-512F.
    #[target_feature(enable = "avx512f")]
    #[inline]
    pub(crate) unsafe fn load(p: *const f64, n: usize) -> __m512d {
        // SAFETY: the mask selects lanes 0..n only, the n f64 the caller vouches for.
        unsafe { _mm512_maskz_loadu_pd(lanes(n), p) }
    }

    /// The mask of lanes `0..n` (`n <= 8`).
    #[inline(always)]
    pub(crate) fn lanes(n: usize) -> u8 {
        ((1u16 << n.min(8)) - 1) as u8
    }

    /// A bank in registers.
    pub(crate) struct Bank {
        travel: __m512d,
        min: __m512d,
        max: __m512d,
        peak_v: __m512d,
        peak_a: __m512d,
        sum_v: __m512d,
        sum_a: __m512d,
        last: __m512d,
        n: u64,
    }

    impl Bank {
        /// The bank `b` in registers.
        ///
        /// # Safety
        /// `N <= 8`, and the CPU must have AVX-512F.
        #[target_feature(enable = "avx512f")]
        #[inline]
        pub(crate) unsafe fn of<const N: usize>(b: &AxisBank<N>) -> Bank {
            // SAFETY: every array holds N <= 8 f64.
            let ld = |a: &[f64; N]| unsafe { load(a.as_ptr(), N) };
            Bank {
                travel: ld(&b.travel),
                min: ld(&b.min),
                max: ld(&b.max),
                peak_v: ld(&b.peak_v),
                peak_a: ld(&b.peak_a),
                sum_v: ld(&b.sum_v),
                sum_a: ld(&b.sum_a),
                last: ld(&b.last),
                n: b.n,
            }
        }

        /// Writes the registers back into `b`.
        ///
        /// # Safety
        /// `N <= 8`, and the CPU must have AVX-512F.
        #[target_feature(enable = "avx512f")]
        #[inline]
        pub(crate) unsafe fn store<const N: usize>(&self, b: &mut AxisBank<N>) {
            // SAFETY: the mask selects lanes 0..N, the N f64 of each array.
            let st = |a: &mut [f64; N], v: __m512d| unsafe {
                _mm512_mask_storeu_pd(a.as_mut_ptr(), lanes(N), v)
            };
            st(&mut b.travel, self.travel);
            st(&mut b.min, self.min);
            st(&mut b.max, self.max);
            st(&mut b.peak_v, self.peak_v);
            st(&mut b.peak_a, self.peak_a);
            st(&mut b.sum_v, self.sum_v);
            st(&mut b.sum_a, self.sum_a);
            st(&mut b.last, self.last);
            b.n = self.n;
        }

        /// [`AxisBank::add`] of positions `q`, velocities `v`, accelerations `a`.
        #[target_feature(enable = "avx512f")]
        #[inline]
        pub(crate) fn add(&mut self, q: __m512d, v: __m512d, a: __m512d) {
            if self.n > 0 {
                self.travel =
                    _mm512_add_pd(self.travel, _mm512_abs_pd(_mm512_sub_pd(q, self.last)));
            }
            self.last = q;
            self.n += 1;
            // `_mm512_abs_pd` clears the sign bit, as `f64::abs`.
            let (av, aa) = (_mm512_abs_pd(v), _mm512_abs_pd(a));
            self.min = _mm512_min_pd(q, self.min);
            self.max = _mm512_max_pd(q, self.max);
            self.peak_v = _mm512_max_pd(av, self.peak_v);
            self.peak_a = _mm512_max_pd(aa, self.peak_a);
            self.sum_v = _mm512_add_pd(self.sum_v, av);
            self.sum_a = _mm512_add_pd(self.sum_a, aa);
        }
    }
}

/// Serial over PKM ratios of seed 000, by the paper's definitions: "struts travel on
/// average 3.6x less" is the mean travel of the moving serial axes over the
/// actuators' mean travel; "3.4x less" velocity and "3.3x less" acceleration are the
/// largest serial peak over the largest actuator peak (166.7 / 49 and 434 / 131 mm/s,
/// mm/s^2 at 10 000 mm/min). The ratios of mean peaks, which pkm printed before, are
/// kept under their own names.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Ratios {
    /// Mean travel of the moving serial axes over the actuators' mean travel.
    pub travel: f64,
    /// Largest serial peak |velocity| over the largest actuator peak |velocity|;
    /// `None` when no sample caught the machine moving (every move shorter than the
    /// sampling period: its samples are its ends, at rest), where the quotient would
    /// be 0 / 0.
    pub velocity: Option<f64>,
    /// Largest serial peak |acceleration| over the largest actuator peak; `None` when
    /// no moving serial axis accelerates: straight moves under the constant profile
    /// (each move at its feed from its first sample to its last; the velocity steps
    /// at the corners are not samples), where "0" would say the serial machine needs
    /// no acceleration.
    pub acceleration: Option<f64>,
    /// Mean peak |velocity| of the moving serial axes over the actuators' mean peak
    /// |velocity| (not the paper's definition); `None` as [`Ratios::velocity`].
    pub velocity_of_mean_peaks: Option<f64>,
    /// Mean peak |acceleration| of the moving serial axes over the actuators' mean
    /// peak (not the paper's definition); `None` as [`Ratios::acceleration`].
    pub acceleration_of_mean_peaks: Option<f64>,
}

/// Computes [`Ratios`]; serial axes that do not move are left out. `None` unless every
/// serial axis and every actuator is a length (a ratio of mm to deg means nothing:
/// robots, turning drives), and `None` when no serial axis moves (a run without
/// samples, a dwell: nothing over nothing is not a ratio).
pub fn ratios(
    serial: &[AxisStats],
    serial_quantities: &[Quantity],
    actuators: &[AxisStats],
    actuator_quantities: &[Quantity],
) -> Option<Ratios> {
    let lengths = |q: &[Quantity]| q.iter().all(|&q| q == Quantity::Length);
    if !lengths(serial_quantities) || !lengths(actuator_quantities) {
        return None;
    }
    let moving: Vec<&AxisStats> = serial.iter().filter(|s| s.travel > 1e-9).collect();
    if moving.is_empty() {
        return None;
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let largest = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    let over = |s: f64, p: f64| if p > 0.0 { s / p } else { f64::INFINITY };
    let col =
        |v: &[&AxisStats], g: fn(&AxisStats) -> f64| v.iter().map(|x| g(x)).collect::<Vec<_>>();
    let acts: Vec<&AxisStats> = actuators.iter().collect();
    let by_mean = |g: fn(&AxisStats) -> f64| over(mean(&col(&moving, g)), mean(&col(&acts, g)));
    let by_largest =
        |g: fn(&AxisStats) -> f64| over(largest(&col(&moving, g)), largest(&col(&acts, g)));
    // A peak ratio needs the moving serial axes to have one at a sample: otherwise it
    // would read 0 (or 0 / 0) where nothing was measured.
    let sampled = |g: fn(&AxisStats) -> f64| largest(&col(&moving, g)) > 0.0;
    let (moves, accelerates) = (
        sampled(|x| x.peak_velocity),
        sampled(|x| x.peak_acceleration),
    );
    Some(Ratios {
        travel: by_mean(|x| x.travel),
        velocity: moves.then(|| by_largest(|x| x.peak_velocity)),
        acceleration: accelerates.then(|| by_largest(|x| x.peak_acceleration)),
        velocity_of_mean_peaks: moves.then(|| by_mean(|x| x.peak_velocity)),
        acceleration_of_mean_peaks: accelerates.then(|| by_mean(|x| x.peak_acceleration)),
    })
}

#[cfg(test)]
mod tests {
    use super::{AxisBank, AxisStats};

    /// The AVX-512 bank equals the plain bank bit for bit: random samples with signs,
    /// zeros of both signs, infinities and NaN, five and eight axes, added in runs of
    /// varying length (loaded and stored between runs), from the empty bank.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx512_bank_equals_the_plain_bank() {
        if !std::arch::is_x86_feature_detected!("avx512f") {
            return;
        }
        fn check<const N: usize>(seed: u64) {
            use rand::{Rng, SeedableRng};
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            let mut plain = AxisBank::<N>::default();
            let mut lanes = AxisBank::<N>::default();
            let draw = |rng: &mut rand::rngs::StdRng| match rng.random_range(0..25) {
                0 => 0.0,
                1 => -0.0,
                2 => f64::INFINITY,
                3 => f64::NEG_INFINITY,
                4 => f64::NAN,
                _ => rng.random_range(-1e3..1e3),
            };
            for run in 0..300 {
                let k = rng.random_range(0..12);
                let samples: Vec<[[f64; N]; 3]> = (0..k)
                    .map(|_| std::array::from_fn(|_| std::array::from_fn(|_| draw(&mut rng))))
                    .collect();
                for [q, v, a] in &samples {
                    plain.add(q, v, a);
                }
                // SAFETY: the CPU has AVX-512F (checked above); N <= 8; each load reads
                // the N f64 of an array.
                unsafe {
                    let mut b = super::avx512::Bank::of(&lanes);
                    for [q, v, a] in &samples {
                        let ld = |x: &[f64; N]| super::avx512::load(x.as_ptr(), N);
                        b.add(ld(q), ld(v), ld(a));
                    }
                    b.store(&mut lanes);
                }
                for i in 0..N {
                    assert_eq!(
                        (lanes.axis(i).bits(), lanes.last[i].to_bits(), lanes.n),
                        (plain.axis(i).bits(), plain.last[i].to_bits(), plain.n),
                        "axis {i} of {N} after run {run}"
                    );
                }
            }
        }
        check::<5>(11);
        check::<8>(12);
        check::<1>(13);
    }

    /// The bank's statistics are each axis's `AxisStats`, bit for bit, over random
    /// samples with signs, zeros, repeated values and infinities.
    #[test]
    fn bank_equals_one_stats_per_axis() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut bank = AxisBank::<5>::default();
        let mut one = [AxisStats::default(); 5];
        for k in 0..2000 {
            let mut draw = || match rng.random_range(0..20) {
                0 => 0.0,
                1 => -0.0,
                2 => f64::INFINITY,
                _ => rng.random_range(-1e3..1e3),
            };
            let q: [f64; 5] = std::array::from_fn(|_| draw());
            let v: [f64; 5] = std::array::from_fn(|_| draw());
            let a: [f64; 5] = std::array::from_fn(|_| draw());
            bank.add(&q, &v, &a);
            for i in 0..5 {
                one[i].add(q[i], v[i], a[i]);
            }
            if k % 500 == 0 || k == 1999 {
                for (i, s) in one.iter().enumerate() {
                    let mut s = *s;
                    s.finalize();
                    let b = bank.axis(i);
                    assert_eq!(b.bits(), s.bits(), "axis {i} after {k} samples");
                }
            }
        }
        // Empty: the defaults.
        let e = AxisBank::<2>::default().axis(1);
        assert_eq!(
            (e.travel, e.min, e.max),
            (0.0, f64::INFINITY, f64::NEG_INFINITY)
        );
    }
}
