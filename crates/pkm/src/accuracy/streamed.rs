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
use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;

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

/// Moments of error vectors: of their norms and of each component.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Moments {
    norm: ScalarMoments,
    component: [ScalarMoments; 3],
}

impl Moments {
    /// Adds one error vector (mm).
    pub fn push(&mut self, e: &Vector3<f64>) {
        self.norm.push(e.norm());
        for (m, v) in self.component.iter_mut().zip(e.iter()) {
            m.push(*v);
        }
    }

    /// Merges the moments of another sample.
    pub fn merge(&mut self, o: &Moments) {
        self.norm.merge(&o.norm);
        for (m, v) in self.component.iter_mut().zip(&o.component) {
            m.merge(v);
        }
    }
}

/// The bucket layout of a [`Sketch`]: bucket 0 below `LOW`, bucket `k >= 1` for
/// `[LOW g^(k-1), LOW g^k)`. Small and `Copy`, so the workers of a run find buckets
/// while the run's sketch is being counted into.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogBuckets {
    log_gamma: f64,
    len: usize,
}

impl Default for LogBuckets {
    fn default() -> Self {
        let log_gamma = log_gamma();
        LogBuckets {
            log_gamma,
            len: ((HIGH / LOW).ln() / log_gamma).ceil() as usize + 2,
        }
    }
}

impl LogBuckets {
    /// The bucket of a magnitude.
    pub fn of(&self, x: f64) -> usize {
        if !(x >= LOW) {
            return 0;
        }
        let k = 1 + ((x / LOW).ln() / self.log_gamma) as usize;
        k.min(self.len - 1)
    }

    /// The (side, bucket) of a signed value: side 0 below zero, 1 from zero up.
    pub fn signed(&self, v: f64) -> (u8, u32) {
        if v < 0.0 {
            (0, self.of(-v) as u32)
        } else {
            (1, self.of(v) as u32)
        }
    }
}

/// A logarithmic sketch of magnitudes: counts per bucket of [`LogBuckets`].
#[derive(Debug, Clone, PartialEq)]
pub struct Sketch {
    counts: Vec<u64>,
    buckets: LogBuckets,
}

impl Default for Sketch {
    fn default() -> Self {
        let buckets = LogBuckets::default();
        Sketch {
            counts: vec![0; buckets.len],
            buckets,
        }
    }
}

impl Sketch {
    /// Its bucket layout.
    pub fn buckets(&self) -> LogBuckets {
        self.buckets
    }

    /// The bucket of a magnitude.
    pub fn bucket(&self, x: f64) -> usize {
        self.buckets.of(x)
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
        let lower = LOW * ((k - 1) as f64 * self.buckets.log_gamma).exp();
        let gamma = self.buckets.log_gamma.exp();
        2.0 * lower * gamma / (1.0 + gamma)
    }

    /// The value of every non-empty bucket and its count.
    fn values(&self) -> impl Iterator<Item = (f64, u64)> + '_ {
        self.counts
            .iter()
            .enumerate()
            .filter(|(_, &c)| c > 0)
            .map(|(k, &c)| (self.value(k), c))
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
    /// Its bucket layout ([`LogBuckets::signed`] gives a value's bucket).
    pub fn buckets(&self) -> LogBuckets {
        self.positive.buckets
    }

    /// The (side, bucket) of a value: side 0 below zero, 1 from zero up.
    pub fn bucket(&self, v: f64) -> (u8, u32) {
        self.positive.buckets.signed(v)
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
        let negative = self.negative.values().map(|(v, c)| (-v, c));
        histogram(negative.chain(self.positive.values()), bins, min, max)
    }
}

/// Counts of `(value, count)` pairs over `bins` equal bins from `lo` to `hi` (values
/// clamped into it): `(lower edge, count)`.
fn histogram(
    values: impl Iterator<Item = (f64, u64)>,
    bins: usize,
    lo: f64,
    hi: f64,
) -> Vec<(f64, usize)> {
    let width = if hi > lo {
        (hi - lo) / bins as f64
    } else {
        1.0
    };
    let mut hist = vec![0usize; bins];
    for (v, c) in values {
        let k = ((v.clamp(lo, hi) - lo) / width) as usize;
        hist[k.min(bins - 1)] += c as usize;
    }
    hist.into_iter()
        .enumerate()
        .map(|(i, c)| (lo + i as f64 * width, c))
        .collect()
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
    let n = m.norm.n;
    let (min, max) = if n == 0 {
        (0.0, 0.0)
    } else {
        (m.norm.min, m.norm.max)
    };
    let quantile = |f: f64| {
        if n == 0 {
            return 0.0;
        }
        sketch.rank(((n as f64 - 1.0) * f).round() as u64, min, max)
    };
    MonteCarlo {
        samples: n as usize,
        failed,
        mean: m.norm.mean,
        std: m.norm.std(),
        p95: quantile(0.95),
        p99: quantile(0.99),
        max,
        mean_vector: m.component.map(|c| c.mean),
        std_vector: m.component.map(|c| c.std()),
        histogram: histogram(sketch.values(), HISTOGRAM_BINS, 0.0, max),
    }
}

/// Runs `work(chunk, count)` over the chunks of `n` items, `chunk` items each, `batch`
/// chunks at a time in parallel (rayon), and hands every result to `merge` in chunk
/// order: the outcome does not depend on the thread count and memory holds one batch.
pub(crate) fn in_chunks<T: Send>(
    n: usize,
    chunk: usize,
    batch: usize,
    work: impl Fn(usize, usize) -> T + Sync,
    mut merge: impl FnMut(T),
) {
    let chunks = n.div_ceil(chunk);
    for first in (0..chunks).step_by(batch) {
        let last = (first + batch).min(chunks);
        let parts: Vec<T> = (first..last)
            .into_par_iter()
            .map(|c| work(c, chunk.min(n - c * chunk)))
            .collect();
        parts.into_iter().for_each(&mut merge);
    }
}

/// The random generator of the samples (Monte Carlo, clearances, paths):
/// Xoshiro256++ (Blackman, Vigna, "Scrambled linear pseudorandom number generators",
/// ACM TOMS 2021), a fixed algorithm, so a seed gives the same samples on every
/// platform and release. Its statistical quality is ample for sampling; it is not
/// meant to be unpredictable. (Earlier versions used `StdRng`, ChaCha12: 12 % of a
/// hexapod's Monte Carlo, and their results per seed differ.)
pub type SampleRng = Xoshiro256PlusPlus;

/// The random generator of chunk `c` of a seeded run.
pub(crate) fn chunk_rng(seed: u64, c: usize) -> SampleRng {
    SampleRng::seed_from_u64(seed ^ (c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

#[cfg(test)]
mod tests {
    use rand::RngCore;

    use super::chunk_rng;

    /// A seed's samples do not change between releases or platforms: the first draws
    /// of two chunks of seed 42 against an independent implementation of SplitMix64
    /// seeding and Xoshiro256++ (Blackman and Vigna's reference, written in Python).
    #[test]
    fn chunk_generators_are_xoshiro256plusplus_seeded_by_splitmix64() {
        let expected: [[u64; 3]; 2] = [
            [
                0xd076_4d4f_4476_689f,
                0x519e_4174_576f_3791,
                0xfbe0_7cfb_0c24_ed8c,
            ],
            [
                0xefdb_3abe_2d00_4720,
                0x7428_5db8_cad0_1896,
                0xe602_6692_c159_33c2,
            ],
        ];
        for (c, want) in expected.iter().enumerate() {
            let mut rng = chunk_rng(42, c);
            let got = [rng.next_u64(), rng.next_u64(), rng.next_u64()];
            assert_eq!(&got, want, "chunk {c}");
        }
    }
}
