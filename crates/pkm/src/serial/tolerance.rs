//! Tolerances of primary deviations: the error budget (first order) and Monte Carlo
//! (exact poses, seeded, in parallel).

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution as _, Normal};
use rayon::prelude::*;
use serde::Serialize;

use super::accuracy::{ChainDeviations, Parameter, SerialMachine};
use super::LinkDeviation;
use crate::error::Result;

/// How a deviation is distributed within its tolerance `t`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Distribution {
    /// Uniform in `[-t, t]` (standard deviation `t / sqrt 3`).
    Uniform,
    /// Normal with `t` as three standard deviations.
    Normal,
}

/// A tolerance on one deviation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tolerance {
    /// The deviation.
    pub parameter: Parameter,
    /// Its tolerance (mm or rad): the bound of a uniform distribution, three standard
    /// deviations of a normal one.
    pub value: f64,
    /// Distribution in Monte Carlo.
    pub distribution: Distribution,
}

impl Tolerance {
    /// Standard deviation of the deviation.
    pub fn std(&self) -> f64 {
        match self.distribution {
            Distribution::Uniform => self.value / 3f64.sqrt(),
            Distribution::Normal => self.value / 3.0,
        }
    }
}

/// One line of an error budget.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BudgetItem {
    /// Name in seed 003's notation.
    pub name: String,
    /// Tolerance (mm or rad).
    pub tolerance: f64,
    /// Tool-point error at the tolerance, first order (mm): `|dp/dd| t`.
    pub position: f64,
    /// Tool-frame rotation at the tolerance, first order (rad).
    pub orientation: f64,
}

/// An error budget at one machine state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Budget {
    /// Items, largest position contribution first.
    pub items: Vec<BudgetItem>,
    /// Sum of the position contributions (mm): every deviation at its worst.
    pub worst_case: f64,
    /// Root sum of squares of the position contributions (mm).
    pub rss: f64,
}

/// The error budget at joints `qt`, `qw` (nominal machine).
pub fn budget(m: &SerialMachine, qt: &[f64], qw: &[f64], tol: &[Tolerance]) -> Result<Budget> {
    let params: Vec<Parameter> = tol.iter().map(|t| t.parameter).collect();
    let s = m.sensitivities(qt, qw, &[], &params)?;
    let items: Vec<BudgetItem> = tol
        .iter()
        .zip(&s)
        .map(|(t, (dp, w))| BudgetItem {
            name: m.parameter_name(&t.parameter),
            tolerance: t.value,
            position: dp.norm() * t.value,
            orientation: w.norm() * t.value,
        })
        .collect();
    Ok(Budget::from_items(items))
}

impl Budget {
    /// A budget of these items: sorted, largest position contribution first, with their
    /// worst-case sum and root sum of squares.
    pub fn from_items(mut items: Vec<BudgetItem>) -> Self {
        items.sort_by(|a, b| b.position.total_cmp(&a.position));
        let worst_case = items.iter().map(|i| i.position).sum();
        let rss = items
            .iter()
            .map(|i| i.position * i.position)
            .sum::<f64>()
            .sqrt();
        Budget {
            items,
            worst_case,
            rss,
        }
    }
}

/// Monte Carlo results: statistics of the tool-point error norm (mm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MonteCarlo {
    /// Samples.
    pub samples: usize,
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
    /// Mean error vector (mm), workpiece frame.
    pub mean_vector: [f64; 3],
    /// Standard deviation of each error component (mm).
    pub std_vector: [f64; 3],
    /// Histogram of `|e|`: `(lower edge, count)` over 40 equal bins up to `max`.
    pub histogram: Vec<(f64, usize)>,
}

/// Zero deviations for every link and joint of a machine's chains.
pub fn zero_deviations(m: &SerialMachine) -> Vec<ChainDeviations> {
    let mut v = vec![ChainDeviations {
        links: vec![LinkDeviation::default(); m.tool.links.len()],
        dq: vec![0.0; m.tool.dof()],
        ..Default::default()
    }];
    if let Some(w) = &m.workpiece {
        v.push(ChainDeviations {
            links: vec![LinkDeviation::default(); w.links.len()],
            dq: vec![0.0; w.dof()],
            ..Default::default()
        });
    }
    v
}

/// Deviations with the given values (internal units) and every other deviation zero.
pub fn deviations_from(m: &SerialMachine, values: &[(Parameter, f64)]) -> Vec<ChainDeviations> {
    let mut d = zero_deviations(m);
    for (p, v) in values {
        apply(&mut d, p, *v);
    }
    d
}

/// Tool-point displacement (mm) and tool-frame rotation (small rotation vector, rad)
/// of the deviated machine against the nominal one, in the workpiece frame, at joints
/// `qt`, `qw`: exact poses, the rotation from the skew part of `R_dev R_nom^T`.
pub fn pose_error(
    m: &SerialMachine,
    qt: &[f64],
    qw: &[f64],
    dev: &[ChainDeviations],
) -> Result<(Vector3<f64>, Vector3<f64>)> {
    let a = m.pose(qt, qw, &[])?;
    let b = m.pose(qt, qw, dev)?;
    let dp = b.fixed_view::<3, 1>(0, 3) - a.fixed_view::<3, 1>(0, 3);
    let dr = b.fixed_view::<3, 3>(0, 0) * a.fixed_view::<3, 3>(0, 0).transpose();
    let w = Vector3::new(
        0.5 * (dr[(2, 1)] - dr[(1, 2)]),
        0.5 * (dr[(0, 2)] - dr[(2, 0)]),
        0.5 * (dr[(1, 0)] - dr[(0, 1)]),
    );
    Ok((dp.into_owned(), w))
}

fn apply(d: &mut [ChainDeviations], p: &Parameter, v: f64) {
    match *p {
        Parameter::Delta { chain, link, axis } => d[chain].links[link].delta[axis] += v,
        Parameter::Alpha {
            chain,
            link,
            row,
            col,
        } => d[chain].links[link].alpha[(row, col)] += v,
        Parameter::Dq { chain, joint } => d[chain].dq[joint] += v,
        Parameter::Installation { axis } => d[0].installation[axis.min(2)] += v,
    }
}

/// Monte Carlo of the tool-point error at joints `qt`, `qw`: `n` machines with every
/// toleranced deviation drawn from its distribution (seeded: the same `seed` gives the
/// same result on any number of threads), the exact tool pose of each against the
/// nominal one.
pub fn monte_carlo(
    m: &SerialMachine,
    qt: &[f64],
    qw: &[f64],
    tol: &[Tolerance],
    n: usize,
    seed: u64,
) -> Result<MonteCarlo> {
    let nominal = m.pose(qt, qw, &[])?;
    let p0 = nominal.fixed_view::<3, 1>(0, 3).into_owned();
    let empty = zero_deviations(m);
    // Validate the parameters once (a bad index fails here, not in a worker).
    let params: Vec<Parameter> = tol.iter().map(|t| t.parameter).collect();
    m.sensitivities(qt, qw, &[], &params)?;
    const CHUNK: usize = 4096;
    let chunks = n.div_ceil(CHUNK);
    let errors: Vec<Vector3<f64>> = (0..chunks)
        .into_par_iter()
        .flat_map_iter(|c| {
            let mut rng = rand::rngs::StdRng::seed_from_u64(
                seed ^ (c as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
            );
            let normal = Normal::new(0.0, 1.0).expect("unit normal");
            let count = CHUNK.min(n - c * CHUNK);
            let mut d = empty.clone();
            let mut out = Vec::with_capacity(count);
            for _ in 0..count {
                for cd in d.iter_mut() {
                    cd.links
                        .iter_mut()
                        .for_each(|l| *l = LinkDeviation::default());
                    cd.dq.iter_mut().for_each(|x| *x = 0.0);
                    cd.installation = Vector3::zeros();
                }
                for t in tol {
                    let v = match t.distribution {
                        Distribution::Uniform => rng.random_range(-1.0..=1.0) * t.value,
                        Distribution::Normal => normal.sample(&mut rng) * t.value / 3.0,
                    };
                    apply(&mut d, &t.parameter, v);
                }
                let e = m
                    .pose(qt, qw, &d)
                    .map(|p| p.fixed_view::<3, 1>(0, 3).into_owned() - p0)
                    .unwrap_or_else(|_| Vector3::repeat(f64::NAN));
                out.push(e);
            }
            out
        })
        .collect();
    Ok(statistics(&errors))
}

/// Statistics of a sample of tool-point error vectors (mm): mean, standard deviation,
/// percentiles and histogram of their norms, mean and spread of the components.
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
