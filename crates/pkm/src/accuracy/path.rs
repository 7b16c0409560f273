//! Accuracy along a path (a program's samples), written once for every machine type:
//! at every sample the first-order error budget of the tolerances (seed 003's model:
//! the nominal readings commanded, the deviated machine's tool against the nominal
//! one), kept per G-code line (the budget per segment); and a Monte Carlo band: whole
//! machines drawn once from the tolerances, each followed along the path.
//!
//! **The part-surface error.** The error that matters on the part is its component
//! along the surface normal `n`: `e_n = n . e`. pkm takes the tool axis as that normal
//! (`n` = the tool frame's Z, in the frame the errors are in): exact for a ball-end
//! tool finishing with its tip on the surface normal (no lead or tilt angle), which is
//! what a 5-axis program in TCP mode with the tool along the surface normal does, and
//! for a nozzle building normal to its layer. A program that cuts with the flank or
//! with lead/tilt angles needs the contact normal, which a G-code program does not
//! carry: the surface figures are then only the axial component.
//!
//! **Budget** at each sample, per toleranced parameter `k` with tolerance `t_k` and
//! sensitivity `S_k` (mm per unit): worst case `sum |S_k| t_k`, root sum of squares
//! `sqrt(sum (|S_k| t_k)^2)`, and along the normal `sum |n . S_k| t_k` and
//! `sqrt(sum (n . S_k t_k)^2)`.
//!
//! **Monte Carlo band.** `machines` deviation sets `d_j` are drawn once (seeded; uniform
//! in `[-t, t]` or normal with `t = 3 sigma`, as [`super::monte_carlo()`]); at every
//! `every`-th sample each machine's error is `e_j = S d_j` (first order in the
//! deviations: tolerances of micrometres and arc seconds are far inside the linear
//! range: on MC-300 with its file's tolerances the linear error is within 6 nm of the
//! exact deviated pose's at errors up to 81 um, a test holds it). Per machine the largest
//! `|e_j|` and `|n . e_j|` over the path are kept: their distribution over the machines
//! says what share of machines built to these tolerances cuts the part within a bound.

use nalgebra::{SVector, Vector3};
use rand_distr::Normal;
use serde::Serialize;

use super::monte_carlo::draw;
use super::{Parameter, Parametric, PoseError, SensitivityScratch, Tolerance};
use crate::error::{Error, Result};

/// The most machines of a path Monte Carlo.
pub const MAX_PATH_MACHINES: usize = 100_000;

/// The most G-code lines kept with their own row (the maxima cover every line).
pub const MAX_SEGMENT_ROWS: usize = 1_000_000;

/// What to compute along the path.
#[derive(Debug, Clone, PartialEq)]
pub struct PathOptions {
    /// The tolerances.
    pub tolerances: Vec<Tolerance>,
    /// Machines of the Monte Carlo band (0: none).
    pub machines: usize,
    /// Monte Carlo at every `every`-th sample (the first always).
    pub every: usize,
    /// Seed of the draws.
    pub seed: u64,
}

/// The accuracy of one G-code line's samples (mm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentAccuracy {
    /// G-code line (`None`: a move not from a program).
    pub line: Option<u64>,
    /// First and last sample's time (s).
    pub start_s: f64,
    /// Last sample's time (s).
    pub end_s: f64,
    /// Samples of the line.
    pub samples: u64,
    /// Largest worst-case bound of the tool-tip error.
    pub worst_case: f64,
    /// Largest root sum of squares.
    pub rss: f64,
    /// Largest worst-case bound along the surface normal.
    pub surface_worst_case: f64,
    /// Largest root sum of squares along the normal.
    pub surface_rss: f64,
    /// The parameter contributing most to the worst-case bound at the line's worst
    /// sample, and its share (mm).
    pub top: (String, f64),
    /// Smallest and largest surface error of the Monte Carlo machines over the line's
    /// evaluated samples (`None` without a band or when none was evaluated).
    pub band: Option<(f64, f64)>,
}

/// One point of the error curves along the path (mm), for plots.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PathPoint {
    /// Time (s).
    pub t: f64,
    /// G-code line.
    pub line: Option<u64>,
    /// Worst-case bound of the tool-tip error.
    pub worst_case: f64,
    /// Root sum of squares.
    pub rss: f64,
    /// Worst-case bound along the normal.
    pub surface_worst_case: f64,
    /// Monte Carlo surface errors at this sample: 5th, 50th and 95th percentile, least
    /// and largest over the machines (`None` when the sample had no band).
    pub band: Option<[f64; 5]>,
}

/// Distribution over the Monte Carlo machines of their largest error along the path.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MachineSpread {
    /// Machines.
    pub machines: usize,
    /// Samples each was evaluated at.
    pub samples: u64,
    /// Median over the machines of the largest `|e|` along the path (mm).
    pub position_p50: f64,
    /// 95th percentile of it (mm).
    pub position_p95: f64,
    /// Largest (mm).
    pub position_max: f64,
    /// Median of the largest `|n . e|` (mm).
    pub surface_p50: f64,
    /// 95th percentile of it (mm).
    pub surface_p95: f64,
    /// Largest (mm).
    pub surface_max: f64,
}

/// Accuracy along a whole path.
#[derive(Debug, Clone, Serialize)]
pub struct PathAccuracy {
    /// Samples evaluated.
    pub samples: u64,
    /// Tolerances used.
    pub tolerances: usize,
    /// Largest worst-case bound over the path (mm) and its time (s) and line.
    pub worst_case: (f64, f64, Option<u64>),
    /// Largest root sum of squares (mm), time, line.
    pub rss: (f64, f64, Option<u64>),
    /// Largest worst-case bound along the normal (mm), time, line.
    pub surface_worst_case: (f64, f64, Option<u64>),
    /// Per G-code line (the first [`MAX_SEGMENT_ROWS`]).
    pub segments: Vec<SegmentAccuracy>,
    /// Lines beyond those listed.
    pub segments_not_listed: u64,
    /// Decimated curves (at most 4000 points).
    pub curve: crate::motion::decimated::Decimated<PathPoint>,
    /// The Monte Carlo machines' largest errors, when a band was asked for.
    pub monte_carlo: Option<MachineSpread>,
}

/// The band's machines' deviations, parameter-major (`draws[k * machines + j]` is
/// machine `j`'s deviation of tolerance `k`), drawn with `o.seed`.
fn draw_machines(o: &PathOptions) -> Vec<f64> {
    let mut rng = super::streamed::chunk_rng(o.seed, 0);
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let mut draws = vec![0.0; o.tolerances.len() * o.machines];
    for j in 0..o.machines {
        for (i, t) in o.tolerances.iter().enumerate() {
            draws[i * o.machines + j] = draw(t, &mut rng, &normal);
        }
    }
    draws
}

/// The errors of one sample (mm): worst case, RSS, and their parts along the surface
/// normal, with the largest contribution (parameter index, mm).
struct SampleErrors {
    worst_case: f64,
    rss: f64,
    surface_worst_case: f64,
    surface_rss: f64,
    top: (usize, f64),
}

/// Follows a path sample by sample (flat memory apart from the per-line rows).
pub struct PathTracker<'m, M, const P: usize, const A: usize> {
    m: &'m M,
    tooled: Option<M>,
    names: Vec<String>,
    which: Vec<usize>,
    values: Vec<f64>,
    scratch: SensitivityScratch,
    sens: Vec<PoseError>,
    /// Machines of the band.
    machines: usize,
    /// Drawn deviations, parameter-major: `draws[k * machines + j]` is machine `j`'s
    /// deviation of parameter `k` (each parameter's row runs over the machines, so the
    /// product `S D` vectorises over them).
    draws: Vec<f64>,
    /// The machines' errors at the sample, per component.
    e3: [Vec<f64>; 3],
    every: usize,
    surface: Vec<f64>,
    max_pos: Vec<f64>,
    max_surf: Vec<f64>,
    band_samples: u64,
    samples: u64,
    report: PathAccuracy,
    open: Option<SegmentAccuracy>,
}

impl<'m, M, const P: usize, const A: usize> PathTracker<'m, M, P, A>
where
    M: Parametric<P, A>,
{
    /// A tracker for machine `m` (prepared for the tolerances' parameters:
    /// [`Parametric::with_given`]) with options `o`.
    pub fn new(m: &'m M, o: &PathOptions) -> Result<Self> {
        let params: Vec<Parameter> = m.parameters();
        super::monte_carlo::check_tolerance_indices(params.len(), &o.tolerances)?;
        if o.machines > MAX_PATH_MACHINES {
            return Err(Error::InvalidInput {
                what: "path Monte Carlo".into(),
                message: format!(
                    "expected at most {MAX_PATH_MACHINES} machines, got {}",
                    o.machines
                ),
            });
        }
        if o.every == 0 {
            return Err(Error::InvalidInput {
                what: "path Monte Carlo".into(),
                message: "expected a sample step >= 1".into(),
            });
        }
        let which: Vec<usize> = o.tolerances.iter().map(|t| t.parameter).collect();
        let n = which.len();
        let draws = draw_machines(o);
        Ok(PathTracker {
            m,
            tooled: None,
            names: which.iter().map(|&k| params[k].name.clone()).collect(),
            values: o.tolerances.iter().map(|t| t.value).collect(),
            which,
            scratch: SensitivityScratch::default(),
            sens: vec![PoseError::default(); n],
            machines: o.machines,
            draws,
            e3: std::array::from_fn(|_| vec![0.0; o.machines]),
            every: o.every,
            surface: vec![0.0; o.machines],
            max_pos: vec![0.0; o.machines],
            max_surf: vec![0.0; o.machines],
            band_samples: 0,
            samples: 0,
            report: PathAccuracy {
                samples: 0,
                tolerances: n,
                worst_case: (0.0, 0.0, None),
                rss: (0.0, 0.0, None),
                surface_worst_case: (0.0, 0.0, None),
                segments: Vec::new(),
                segments_not_listed: 0,
                curve: crate::motion::decimated::Decimated::new(4000),
                monte_carlo: None,
            },
            open: None,
        })
    }

    /// The following samples are on the machine with a tool `length` mm longer than
    /// its file's ([`crate::mechanism::Mechanism::with_tool_length`]).
    pub fn set_tool_length(&mut self, length: f64) -> Result<()> {
        self.tooled = match self.m.with_tool_length(length) {
            Some(m) => Some(m?),
            None => None,
        };
        // The plan was prepared for the other tool.
        self.scratch = SensitivityScratch::default();
        Ok(())
    }

    /// One sample at pose `x` with actuators `q` (as the run solved them), time `t`,
    /// G-code line `line`.
    pub fn add(
        &mut self,
        t: f64,
        line: Option<u64>,
        x: &SVector<f64, P>,
        q: &SVector<f64, A>,
    ) -> Result<()> {
        let m: &M = self.tooled.as_ref().unwrap_or(self.m);
        let n = m.sensitivities_into(x, q, &self.which, &mut self.scratch, &mut self.sens)?;
        let e = self.sample_errors(&n);
        let (wc, rss, swc) = (e.worst_case, e.rss, e.surface_worst_case);
        let band = if self.machines > 0 && self.samples.is_multiple_of(self.every as u64) {
            Some(self.band(&n))
        } else {
            None
        };
        self.samples += 1;
        let r = &mut self.report;
        for (best, v) in [
            (&mut r.worst_case, wc),
            (&mut r.rss, rss),
            (&mut r.surface_worst_case, swc),
        ] {
            if v > best.0 {
                *best = (v, t, line);
            }
        }
        r.curve.push(|| PathPoint {
            t,
            line,
            worst_case: wc,
            rss,
            surface_worst_case: swc,
            band,
        });
        self.add_to_segment(t, line, &e, band);
        Ok(())
    }

    /// The errors of the sample whose sensitivities are in `self.sens`, `n` the
    /// surface normal.
    fn sample_errors(&self, n: &Vector3<f64>) -> SampleErrors {
        let (mut wc, mut ss, mut swc, mut sss) = (0.0, 0.0, 0.0, 0.0);
        let mut top = (0, 0.0);
        for (k, (s, v)) in self.sens.iter().zip(&self.values).enumerate() {
            let a = s.position.norm() * v;
            let b = n.dot(&s.position) * v;
            wc += a;
            ss += a * a;
            swc += b.abs();
            sss += b * b;
            if a > top.1 {
                top = (k, a);
            }
        }
        SampleErrors {
            worst_case: wc,
            rss: ss.sqrt(),
            surface_worst_case: swc,
            surface_rss: sss.sqrt(),
            top,
        }
    }

    /// Adds a sample at time `t` of G-code line `line` to its line's segment (closing
    /// the one before on a new line).
    fn add_to_segment(
        &mut self,
        t: f64,
        line: Option<u64>,
        e: &SampleErrors,
        band: Option<[f64; 5]>,
    ) {
        if self.open.as_ref().is_some_and(|s| s.line != line) {
            self.close();
        }
        let seg = self.open.get_or_insert_with(|| SegmentAccuracy {
            line,
            start_s: t,
            end_s: t,
            samples: 0,
            worst_case: 0.0,
            rss: 0.0,
            surface_worst_case: 0.0,
            surface_rss: 0.0,
            top: (String::new(), 0.0),
            band: None,
        });
        seg.end_s = t;
        seg.samples += 1;
        if e.worst_case >= seg.worst_case {
            seg.worst_case = e.worst_case;
            seg.top = (
                self.names.get(e.top.0).cloned().unwrap_or_default(),
                e.top.1,
            );
        }
        seg.rss = seg.rss.max(e.rss);
        seg.surface_worst_case = seg.surface_worst_case.max(e.surface_worst_case);
        seg.surface_rss = seg.surface_rss.max(e.surface_rss);
        if let Some(b) = band {
            seg.band = Some(match seg.band {
                Some((lo, hi)) => (lo.min(b[3]), hi.max(b[4])),
                None => (b[3], b[4]),
            });
        }
    }

    /// The machines' errors at this sample: `E = S D`; returns the percentiles of the
    /// surface error.
    fn band(&mut self, n: &Vector3<f64>) -> [f64; 5] {
        let k = self.machines;
        for e in &mut self.e3 {
            e.fill(0.0);
        }
        for (s, d) in self.sens.iter().zip(self.draws.chunks_exact(k)) {
            for (r, e) in self.e3.iter_mut().enumerate() {
                let c = s.position[r];
                for (x, dj) in e.iter_mut().zip(d) {
                    *x += c * dj;
                }
            }
        }
        for j in 0..k {
            let e = Vector3::new(self.e3[0][j], self.e3[1][j], self.e3[2][j]);
            let s = n.dot(&e);
            self.surface[j] = s;
            self.max_pos[j] = self.max_pos[j].max(e.norm());
            self.max_surf[j] = self.max_surf[j].max(s.abs());
        }
        self.band_samples += 1;
        self.surface.sort_unstable_by(f64::total_cmp);
        let q = |f: f64| quantile(&self.surface, f);
        [q(0.05), q(0.5), q(0.95), q(0.0), q(1.0)]
    }

    fn close(&mut self) {
        if let Some(s) = self.open.take() {
            if self.report.segments.len() < MAX_SEGMENT_ROWS {
                self.report.segments.push(s);
            } else {
                self.report.segments_not_listed += 1;
            }
        }
    }

    /// The accuracy along everything added.
    pub fn finish(mut self) -> PathAccuracy {
        self.close();
        self.report.samples = self.samples;
        let k = self.machines;
        if k > 0 {
            self.max_pos.sort_unstable_by(f64::total_cmp);
            self.max_surf.sort_unstable_by(f64::total_cmp);
            self.report.monte_carlo = Some(MachineSpread {
                machines: k,
                samples: self.band_samples,
                position_p50: quantile(&self.max_pos, 0.5),
                position_p95: quantile(&self.max_pos, 0.95),
                position_max: quantile(&self.max_pos, 1.0),
                surface_p50: quantile(&self.max_surf, 0.5),
                surface_p95: quantile(&self.max_surf, 0.95),
                surface_max: quantile(&self.max_surf, 1.0),
            });
        }
        self.report
    }
}

/// The `f` quantile of sorted values (nearest rank; 0 for none).
fn quantile(sorted: &[f64], f: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    sorted[((sorted.len() - 1) as f64 * f).round() as usize]
}
