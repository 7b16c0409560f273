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
