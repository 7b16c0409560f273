//! Monte Carlo of joint states inside their clearances: every joint drawn uniformly in
//! its region, the mechanism re-solved, the error along the direction and its length
//! (seeded per chunk: the same seed gives the same result on any number of threads).

use nalgebra::{SVector, Vector3};
use rand::SeedableRng;
use rayon::prelude::*;
use serde::Serialize;

use super::{deviations_of, JointState, Region};
use crate::accuracy::{Evaluate, Parametric};
use crate::error::{Error, Result};

/// Distribution of the error over random joint states (mm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClearanceMonteCarlo {
    /// States evaluated.
    pub samples: usize,
    /// States whose mechanism could not be solved (not in the statistics).
    pub failed: usize,
    /// Unit direction.
    pub direction: [f64; 3],
    /// Smallest error along the direction.
    pub min: f64,
    /// Largest error along the direction.
    pub max: f64,
    /// Mean along the direction.
    pub mean: f64,
    /// Standard deviation along the direction.
    pub std: f64,
    /// 1st and 99th percentiles along the direction.
    pub p01: f64,
    /// See `p01`.
    pub p99: f64,
    /// Largest `|e|`.
    pub max_norm: f64,
    /// Histogram along the direction: `(lower edge, count)`, 40 bins from `min` to `max`.
    pub histogram: Vec<(f64, usize)>,
}

const CHUNK: usize = 1024;

/// Monte Carlo of `n` random joint states at pose `x` of `m` (errors along unit
/// `direction`).
pub fn clearance_monte_carlo<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    regions: &[Region],
    direction: &Vector3<f64>,
    n: usize,
    seed: u64,
) -> Result<ClearanceMonteCarlo>
where
    M: Parametric<P, A>,
{
    if n == 0 {
        return Err(Error::InvalidInput {
            what: "clearance Monte Carlo".into(),
            message: "expected a number of samples > 0".into(),
        });
    }
    let dir = direction.normalize();
    let mut base = m.evaluator(x)?;
    base.pose_error(&[])?;
    let results: Vec<Option<(f64, f64)>> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .flat_map_iter(|c| {
            let mut rng = rand::rngs::StdRng::seed_from_u64(
                seed ^ (c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
            );
            let count = CHUNK.min(n - c * CHUNK);
            let mut ev = base.clone();
            let mut states: Vec<JointState> = Vec::with_capacity(regions.len());
            let mut buf = Vec::new();
            let mut out = Vec::with_capacity(count);
            for _ in 0..count {
                states.clear();
                states.extend(regions.iter().map(|r| r.sample(&mut rng)));
                deviations_of(regions, &states, &mut buf);
                out.push(
                    ev.pose_error(&buf)
                        .ok()
                        .map(|e| (dir.dot(&e.position), e.position.norm())),
                );
            }
            out
        })
        .collect();
    let ok: Vec<(f64, f64)> = results.iter().flatten().copied().collect();
    let k = ok.len().max(1) as f64;
    let mut along: Vec<f64> = ok.iter().map(|v| v.0).collect();
    along.sort_by(|a, b| a.total_cmp(b));
    let mean = along.iter().sum::<f64>() / k;
    let std = (along.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (k - 1.0).max(1.0)).sqrt();
    let pick = |f: f64| {
        along
            .get(((along.len() as f64 - 1.0) * f).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    let (min, max) = (pick(0.0), pick(1.0));
    let bins = 40;
    let width = if max > min {
        (max - min) / bins as f64
    } else {
        1.0
    };
    let mut hist = vec![0usize; bins];
    for v in &along {
        hist[(((v - min) / width) as usize).min(bins - 1)] += 1;
    }
    Ok(ClearanceMonteCarlo {
        samples: ok.len(),
        failed: n - ok.len(),
        direction: dir.into(),
        min,
        max,
        mean,
        std,
        p01: pick(0.01),
        p99: pick(0.99),
        max_norm: ok.iter().map(|v| v.1).fold(0.0, f64::max),
        histogram: hist
            .into_iter()
            .enumerate()
            .map(|(i, c)| (min + i as f64 * width, c))
            .collect(),
    })
}
