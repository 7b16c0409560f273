//! Online statistics of axis motion (flat memory for any program length).

use serde::Serialize;

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
}

/// Serial over PKM ratios of seed 000: each is the mean over the moving serial axes
/// divided by the mean over the actuators of travel, peak |velocity| and peak
/// |acceleration|. Seed 000 reports 3.6 (travel), 3.4 (velocity), 3.3 (acceleration).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Ratios {
    /// Travel ratio.
    pub travel: f64,
    /// Peak velocity ratio.
    pub velocity: f64,
    /// Peak acceleration ratio.
    pub acceleration: f64,
}

/// Computes [`Ratios`]; serial axes that do not move are left out.
pub fn ratios(serial: &[AxisStats], actuators: &[AxisStats]) -> Ratios {
    let moving: Vec<&AxisStats> = serial.iter().filter(|s| s.travel > 1e-9).collect();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let f = |g: fn(&AxisStats) -> f64| {
        let s = mean(&moving.iter().map(|x| g(x)).collect::<Vec<_>>());
        let p = mean(&actuators.iter().map(g).collect::<Vec<_>>());
        if p > 0.0 {
            s / p
        } else {
            f64::INFINITY
        }
    };
    Ratios {
        travel: f(|x| x.travel),
        velocity: f(|x| x.peak_velocity),
        acceleration: f(|x| x.peak_acceleration),
    }
}
