//! Monte Carlo of joint states inside their clearances: every joint drawn uniformly in
//! its region, the mechanism re-solved, the error along the direction and its length
//! (seeded per chunk: the same seed gives the same result on any number of threads).

use nalgebra::{SVector, Vector3};
use serde::Serialize;

use super::{deviations_of, JointState, Region};
use crate::accuracy::streamed::{chunk_rng, in_chunks, ScalarMoments, SignedSketch};
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
/// Chunks computed (in parallel) between two merges.
const BATCH: usize = 256;

/// The most joint states a clearance Monte Carlo takes (a bound on work: each state
/// re-solves the mechanism; the statistics are streamed in constant memory).
pub const MAX_CLEARANCE_SAMPLES: usize = 100_000_000;

/// Monte Carlo of `n` random joint states at pose `x` of `m` (errors along unit
/// `direction`). Moments are streamed; the percentiles and the histogram come from a
/// logarithmic sketch, within a relative [`crate::accuracy::streamed::QUANTILE_RESOLUTION`]
/// of the order statistics; memory does not grow with `n`.
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
    if n == 0 || n > MAX_CLEARANCE_SAMPLES {
        return Err(Error::InvalidInput {
            what: "clearance Monte Carlo".into(),
            message: format!("expected 1 to {MAX_CLEARANCE_SAMPLES:.0e} samples, got {n}"),
        });
    }
    let dir = direction.normalize();
    let mut base = m.evaluator(x)?;
    base.pose_error(&[])?;
    let mut along = ScalarMoments::default();
    let mut max_norm = 0.0f64;
    let mut sketch = SignedSketch::default();
    let layout = sketch.buckets();
    in_chunks(
        n,
        CHUNK,
        BATCH,
        |c, count| {
            let mut rng = chunk_rng(seed, c);
            let mut ev = base.clone();
            let mut states: Vec<JointState> = Vec::with_capacity(regions.len());
            let mut buf = Vec::new();
            let mut mo = ScalarMoments::default();
            let mut norm = 0.0f64;
            let mut buckets = Vec::with_capacity(count);
            for _ in 0..count {
                states.clear();
                states.extend(regions.iter().map(|r| r.sample(&mut rng)));
                deviations_of(regions, &states, &mut buf);
                if let Ok(e) = ev.pose_error(&buf) {
                    let v = dir.dot(&e.position);
                    mo.push(v);
                    norm = norm.max(e.position.norm());
                    buckets.push(layout.signed(v));
                }
            }
            (mo, norm, buckets)
        },
        |(mo, norm, buckets)| {
            along.merge(&mo);
            max_norm = max_norm.max(norm);
            for b in buckets {
                sketch.add(b);
            }
        },
    );
    Ok(summary(n, dir, &along, max_norm, &sketch))
}

/// The distribution of `n` states from the streamed statistics of those solved: the
/// moments along `dir`, the largest `|e|` and the sketch.
fn summary(
    n: usize,
    dir: Vector3<f64>,
    along: &ScalarMoments,
    max_norm: f64,
    sketch: &SignedSketch,
) -> ClearanceMonteCarlo {
    let ok = along.n;
    let (min, max) = if ok == 0 {
        (0.0, 0.0)
    } else {
        (along.min, along.max)
    };
    let pick = |f: f64| {
        if ok == 0 {
            return 0.0;
        }
        sketch.rank(((ok as f64 - 1.0) * f).round() as u64, min, max)
    };
    ClearanceMonteCarlo {
        samples: ok as usize,
        failed: n - ok as usize,
        direction: dir.into(),
        min,
        max,
        mean: along.mean,
        std: along.std(),
        p01: pick(0.01),
        p99: pick(0.99),
        max_norm,
        histogram: sketch.histogram(40, min, max),
    }
}
