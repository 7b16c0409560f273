//! Statistics of a stream of tool-point error vectors in constant memory: moments by
//! Welford's update, merged by Chan's formula, and quantiles and histogram from a
//! logarithmic sketch of the norms (counts in buckets of relative width `2e-4`, so a
//! quantile is within a relative `1e-4` of the exact one, as in DDSketch: Masson,
//! Rim, Lee, "DDSketch: a fast and fully-mergeable quantile sketch with
//! relative-error guarantees", VLDB 2019).
//!
//! Counts are integers and the moments of the chunks are merged in chunk order, so
//! the result does not depend on the number of threads.

use nalgebra::Vector3;

use super::monte_carlo::MonteCarlo;

/// Relative accuracy of the streamed quantiles.
pub const QUANTILE_RESOLUTION: f64 = 1e-4;
/// Norms below this (mm) fall in the sketch's first bucket, whose value is 0.
const LOW: f64 = 1e-12;
/// Norms above this (mm) fall in the last bucket (machine dimensions are refused
/// beyond 1e6 mm, so no error of a loaded machine is larger).
const HIGH: f64 = 1e7;
/// Bins of the histogram of norms.
const HISTOGRAM_BINS: usize = 40;

/// `ln(gamma)`, `gamma = (1 + r) / (1 - r)` with `r` the relative accuracy.
fn log_gamma() -> f64 {
    ((1.0 + QUANTILE_RESOLUTION) / (1.0 - QUANTILE_RESOLUTION)).ln()
}

/// Moments of the norms and of the components, by Welford's update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moments {
    n: u64,
    mean: f64,
    m2: f64,
    vmean: Vector3<f64>,
    vm2: Vector3<f64>,
    min: f64,
    max: f64,
}

impl Default for Moments {
    fn default() -> Self {
        Moments {
            n: 0,
            mean: 0.0,
            m2: 0.0,
            vmean: Vector3::zeros(),
            vm2: Vector3::zeros(),
            min: f64::INFINITY,
            max: 0.0,
        }
    }
}

impl Moments {
    /// Adds one error vector (mm).
    pub fn push(&mut self, e: &Vector3<f64>) {
        let x = e.norm();
        self.n += 1;
        let k = self.n as f64;
        let d = x - self.mean;
        self.mean += d / k;
        self.m2 += d * (x - self.mean);
        let dv = e - self.vmean;
        self.vmean += dv / k;
        self.vm2 += dv.component_mul(&(e - self.vmean));
        self.min = self.min.min(x);
        self.max = self.max.max(x);
    }

    /// Merges the moments of another sample (Chan, Golub, LeVeque 1979).
    pub fn merge(&mut self, o: &Moments) {
        if o.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *o;
            return;
        }
        let (na, nb) = (self.n as f64, o.n as f64);
        let n = na + nb;
        let d = o.mean - self.mean;
        self.mean += d * nb / n;
        self.m2 += o.m2 + d * d * na * nb / n;
        let dv = o.vmean - self.vmean;
        self.vmean += dv * (nb / n);
        self.vm2 += o.vm2 + dv.component_mul(&dv) * (na * nb / n);
        self.n += o.n;
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }
}

/// A logarithmic sketch of the norms: counts per bucket `[LOW g^(k-1), LOW g^k)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Sketch {
    counts: Vec<u64>,
    log_gamma: f64,
}

impl Default for Sketch {
    fn default() -> Self {
        let log_gamma = log_gamma();
        let buckets = ((HIGH / LOW).ln() / log_gamma).ceil() as usize + 2;
        Sketch {
            counts: vec![0; buckets],
            log_gamma,
        }
    }
}

impl Sketch {
    /// The bucket of a norm.
    pub fn bucket(&self, x: f64) -> usize {
        if !(x >= LOW) {
            return 0;
        }
        let k = 1 + ((x / LOW).ln() / self.log_gamma) as usize;
        k.min(self.counts.len() - 1)
    }

    /// Counts a norm in bucket `k` (from [`Sketch::bucket`]).
    pub fn add(&mut self, k: usize) {
        self.counts[k] += 1;
    }

    /// The value standing for bucket `k`: within a relative [`QUANTILE_RESOLUTION`] of
    /// every norm in it (0 for the first).
    fn value(&self, k: usize) -> f64 {
        if k == 0 {
            return 0.0;
        }
        let lower = LOW * ((k - 1) as f64 * self.log_gamma).exp();
        let gamma = self.log_gamma.exp();
        2.0 * lower * gamma / (1.0 + gamma)
    }

    /// The norm of rank `r` (0-based, ascending), clamped to `[min, max]`.
    fn rank(&self, r: u64, min: f64, max: f64) -> f64 {
        let mut seen = 0;
        for (k, &c) in self.counts.iter().enumerate() {
            seen += c;
            if seen > r {
                return self.value(k).clamp(min, max);
            }
        }
        max
    }
}

/// A sketch of signed values (a [`Sketch`] of the magnitudes on each side of 0), for
/// errors along a direction.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SignedSketch {
    negative: Sketch,
    positive: Sketch,
}

impl SignedSketch {
    /// The (side, bucket) of a value: side 0 below zero, 1 from zero up.
    pub fn bucket(&self, v: f64) -> (u8, u32) {
        if v < 0.0 {
            (0, self.negative.bucket(-v) as u32)
        } else {
            (1, self.positive.bucket(v) as u32)
        }
    }

    /// Counts a value by its [`SignedSketch::bucket`].
    pub fn add(&mut self, (side, k): (u8, u32)) {
        if side == 0 {
            self.negative.add(k as usize)
        } else {
            self.positive.add(k as usize)
        }
    }

    /// The value of rank `r` (0-based, ascending), clamped to `[min, max]`: within a
    /// relative [`QUANTILE_RESOLUTION`] of the exact one.
    pub fn rank(&self, r: u64, min: f64, max: f64) -> f64 {
        let mut seen = 0;
        for (k, &c) in self.negative.counts.iter().enumerate().rev() {
            seen += c;
            if seen > r {
                return (-self.negative.value(k)).clamp(min, max);
            }
        }
        let below: u64 = self.negative.counts.iter().sum();
        self.positive.rank(r - below.min(r), min, max)
    }

    /// Counts over `bins` equal bins from `min` to `max`: `(lower edge, count)`.
    pub fn histogram(&self, bins: usize, min: f64, max: f64) -> Vec<(f64, usize)> {
        let width = if max > min {
            (max - min) / bins as f64
        } else {
            1.0
        };
        let mut hist = vec![0usize; bins];
        let mut put = |v: f64, c: u64| {
            let v = v.clamp(min, max);
            hist[(((v - min) / width) as usize).min(bins - 1)] += c as usize;
        };
        for (k, &c) in self.negative.counts.iter().enumerate() {
            if c > 0 {
                put(-self.negative.value(k), c);
            }
        }
        for (k, &c) in self.positive.counts.iter().enumerate() {
            if c > 0 {
                put(self.positive.value(k), c);
            }
        }
        hist.into_iter()
            .enumerate()
            .map(|(i, c)| (min + i as f64 * width, c))
            .collect()
    }
}

/// Mean, variance, extremes of a stream of scalars (Welford), mergeable in order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScalarMoments {
    /// Count.
    pub n: u64,
    /// Mean.
    pub mean: f64,
    m2: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

impl Default for ScalarMoments {
    fn default() -> Self {
        ScalarMoments {
            n: 0,
            mean: 0.0,
            m2: 0.0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
        }
    }
}

impl ScalarMoments {
    /// Adds a value.
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
        self.min = self.min.min(x);
        self.max = self.max.max(x);
    }

    /// Merges another stream's moments (Chan, Golub, LeVeque 1979).
    pub fn merge(&mut self, o: &ScalarMoments) {
        if o.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *o;
            return;
        }
        let (na, nb) = (self.n as f64, o.n as f64);
        let d = o.mean - self.mean;
        self.mean += d * nb / (na + nb);
        self.m2 += o.m2 + d * d * na * nb / (na + nb);
        self.n += o.n;
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }

    /// Sample standard deviation (0 for fewer than two values).
    pub fn std(&self) -> f64 {
        (self.m2 / (self.n as f64 - 1.0).max(1.0)).max(0.0).sqrt()
    }
}

/// The Monte Carlo statistics of the moments and sketch of `failed + moments.n` draws.
pub fn finish(m: &Moments, sketch: &Sketch, failed: usize) -> MonteCarlo {
    let n = m.n;
    let k1 = (n as f64 - 1.0).max(1.0);
    let (min, max) = if n == 0 { (0.0, 0.0) } else { (m.min, m.max) };
    let quantile = |f: f64| {
        if n == 0 {
            return 0.0;
        }
        let r = ((n as f64 - 1.0) * f).round() as u64;
        sketch.rank(r, min, max)
    };
    let width = if max > 0.0 {
        max / HISTOGRAM_BINS as f64
    } else {
        1.0
    };
    let mut hist = vec![0usize; HISTOGRAM_BINS];
    for (k, &c) in sketch.counts.iter().enumerate() {
        if c > 0 {
            let v = sketch.value(k).clamp(min, max);
            hist[((v / width) as usize).min(HISTOGRAM_BINS - 1)] += c as usize;
        }
    }
    MonteCarlo {
        samples: n as usize,
        failed,
        mean: m.mean,
        std: (m.m2 / k1).max(0.0).sqrt(),
        p95: quantile(0.95),
        p99: quantile(0.99),
        max,
        mean_vector: [m.vmean.x, m.vmean.y, m.vmean.z],
        std_vector: [
            (m.vm2.x / k1).max(0.0).sqrt(),
            (m.vm2.y / k1).max(0.0).sqrt(),
            (m.vm2.z / k1).max(0.0).sqrt(),
        ],
        histogram: hist
            .into_iter()
            .enumerate()
            .map(|(i, c)| (i as f64 * width, c))
            .collect(),
    }
}
