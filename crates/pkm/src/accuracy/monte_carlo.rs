//! Monte Carlo of tolerances: whole machines drawn with every toleranced parameter
//! from its distribution, the exact tool-point error of each (seeded per chunk, so the
//! same seed gives the same result on any number of threads; rayon).

use nalgebra::{SVector, Vector3};
use rand::Rng;
use rand_distr::{Distribution as _, Normal};
use serde::Serialize;

use super::streamed::{chunk_rng, finish, in_chunks, Moments, Sketch};
use super::{Distribution, Evaluate, Parametric, Tolerance};
use crate::error::{Error, Result};

/// Monte Carlo results: statistics of the tool-point error norm (mm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MonteCarlo {
    /// Machines evaluated (drawn minus failed).
    pub samples: usize,
    /// Machines whose pose could not be evaluated (forward kinematics failed: the drawn
    /// machine cannot reach the commanded readings); not in the statistics.
    pub failed: usize,
    /// Mean of `|e|`.
    pub mean: f64,
    /// Standard deviation of `|e|`.
    pub std: f64,
    /// 95th percentile.
    pub p95: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest.
    pub max: f64,
    /// Mean error vector (mm), base or workpiece frame.
    pub mean_vector: [f64; 3],
    /// Standard deviation of each error component (mm).
    pub std_vector: [f64; 3],
    /// Histogram of `|e|`: `(lower edge, count)` over 40 equal bins up to `max`.
    pub histogram: Vec<(f64, usize)>,
}

/// Machines per seeded chunk.
const CHUNK: usize = 4096;
/// Chunks computed (in parallel) between two merges.
const BATCH: usize = 64;

/// The most samples a Monte Carlo of geometric deviations takes (1e9, minutes on two
/// cores: the statistics are streamed in constant memory, the work is what grows).
pub const MAX_MONTE_CARLO: usize = 1_000_000_000;

/// Monte Carlo of `n` machines at pose `x` with the parameters of `tol` drawn from
/// their distributions, the others nominal: the statistics of the exact tool-point
/// error against the nominal tool point. At most [`MAX_MONTE_CARLO`] samples.
///
/// Uniform tolerances draw from `[-t, t]`; normal ones from `N(0, (t/3)^2)`. Memory is
/// constant in `n`: moments are streamed and the percentiles and histogram come from a
/// logarithmic sketch, within a relative [`super::streamed::QUANTILE_RESOLUTION`] of
/// the exact order statistics ([`statistics`] computes those from a stored sample).
pub fn monte_carlo<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    tol: &[Tolerance],
    n: usize,
    seed: u64,
) -> Result<MonteCarlo>
where
    M: Parametric<P, A>,
{
    monte_carlo_with_progress(m, x, tol, n, seed, &|_| {})
}

/// Checks every tolerance of `tol` is on one of a machine's `np` parameters.
pub(crate) fn check_tolerance_indices(np: usize, tol: &[Tolerance]) -> Result<()> {
    if let Some(t) = tol.iter().find(|t| t.parameter >= np) {
        return Err(Error::InvalidInput {
            what: "tolerance".into(),
            message: format!(
                "parameter index {} beyond the machine's {np} parameters",
                t.parameter
            ),
        });
    }
    Ok(())
}

/// Checks a Monte Carlo of `n` machines over tolerances `tol` of a machine with `np`
/// parameters before any work.
fn check_request(np: usize, tol: &[Tolerance], n: usize) -> Result<()> {
    check_tolerance_indices(np, tol)?;
    if n == 0 || n > MAX_MONTE_CARLO {
        return Err(Error::InvalidInput {
            what: "Monte Carlo".into(),
            message: format!("expected 1 to {MAX_MONTE_CARLO:.0e} samples, got {n}"),
        });
    }
    Ok(())
}

/// [`monte_carlo`], telling `progress` of the machines done (every 4 096).
pub fn monte_carlo_with_progress<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    tol: &[Tolerance],
    n: usize,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<MonteCarlo>
where
    M: Parametric<P, A>,
{
    check_request(m.parameters().len(), tol, n)?;
    // Prepared once (a failure here is the nominal machine's, reported as such).
    let mut base = m.evaluator(x)?;
    base.pose_error(&[])?;
    let mut moments = Moments::default();
    let mut sketch = Sketch::default();
    let mut failed = 0;
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let layout = sketch.buckets();
    in_chunks(
        n,
        CHUNK,
        BATCH,
        |c, count| {
            let mut rng = chunk_rng(seed, c);
            let mut ev = base.clone();
            let mut d: Vec<(usize, f64)> = tol.iter().map(|t| (t.parameter, 0.0)).collect();
            let mut mo = Moments::default();
            let mut buckets = Vec::with_capacity(count);
            for _ in 0..count {
                for (slot, t) in d.iter_mut().zip(tol) {
                    slot.1 = draw(t, &mut rng, &normal);
                }
                if let Ok(e) = ev.pose_error(&d) {
                    mo.push(&e.position);
                    buckets.push(layout.of(e.position.norm()) as u32);
                }
            }
            (mo, buckets, count)
        },
        |(mo, buckets, count)| {
            moments.merge(&mo);
            failed += count - buckets.len();
            for k in buckets {
                sketch.add(k as usize);
            }
            progress(count as u64);
        },
    );
    Ok(finish(&moments, &sketch, failed))
}

/// One deviation drawn within tolerance `t`: uniform in `[-t, t]`, or normal with
/// `t` as three standard deviations (`normal` the unit normal).
pub(crate) fn draw(t: &Tolerance, rng: &mut impl Rng, normal: &Normal<f64>) -> f64 {
    match t.distribution {
        Distribution::Uniform => rng.random_range(-1.0..=1.0) * t.value,
        Distribution::Normal => normal.sample(rng) * t.value / 3.0,
    }
}

/// Statistics of a stored sample of tool-point error vectors (mm): mean, standard
/// deviation, exact percentiles (order statistics) and histogram of their norms, mean
/// and spread of the components. [`monte_carlo`] streams the same statistics.
pub fn statistics(errors: &[Vector3<f64>]) -> MonteCarlo {
    let mut norms: Vec<f64> = errors.iter().map(|e| e.norm()).collect();
    let k = norms.len().max(1) as f64;
    let mean = norms.iter().sum::<f64>() / k;
    let std = (norms.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (k - 1.0).max(1.0)).sqrt();
    let mv = errors.iter().fold(Vector3::zeros(), |a, e| a + e) / k;
    let sv = errors
        .iter()
        .fold(Vector3::zeros(), |a, e| {
            a + (e - mv).component_mul(&(e - mv))
        })
        .map(|x| (x / (k - 1.0).max(1.0)).sqrt());
    norms.sort_by(|a, b| a.total_cmp(b));
    let pick = |f: f64| {
        norms
            .get(((norms.len() as f64 - 1.0) * f).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    let max = norms.last().copied().unwrap_or(0.0);
    let bins = 40;
    let width = if max > 0.0 { max / bins as f64 } else { 1.0 };
    let mut hist = vec![0usize; bins];
    for x in &norms {
        hist[((x / width) as usize).min(bins - 1)] += 1;
    }
    MonteCarlo {
        samples: norms.len(),
        failed: 0,
        mean,
        std,
        p95: pick(0.95),
        p99: pick(0.99),
        max,
        mean_vector: [mv.x, mv.y, mv.z],
        std_vector: [sv.x, sv.y, sv.z],
        histogram: hist
            .into_iter()
            .enumerate()
            .map(|(i, c)| (i as f64 * width, c))
            .collect(),
    }
}
