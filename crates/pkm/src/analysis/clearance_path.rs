//! Clearance bounds along a G-code path: the program run through the mechanism
//! ([`super::motion::run_motion`]), and at its samples the bounds of the error from the
//! joint clearances along the tool axis (a nozzle kept normal to the surface being
//! built: the tool axis is that surface's normal) or a given direction.

use serde::Serialize;

use super::motion::{run_motion, MotionSource, SampleRow, SampleSink};
use crate::error::{Error, Result};
use crate::machine::Machine;
use crate::motion::program::FeedOptions;
use crate::motion::Sampling;

/// The most path samples the bounds are computed at.
pub const MAX_PATH_SAMPLES: usize = 100_000;

/// A G-code path to bound the clearance error along.
///
/// # Examples
///
/// 10 mm along X at 600 mm/min from home, sampled at 20 Hz, bounds at every 4th
/// sample.
///
/// ```
/// use pkm::analysis::clearance::{clearance, ClearanceRequest};
/// use pkm::analysis::clearance_path::PathRequest;
/// use pkm::motion::Sampling;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hybrid-am-seed002.toml"
/// ))
/// .unwrap();
/// let req = PathRequest {
///     program: "G21 G90\nG1 X10 F600\n".into(),
///     from: None,
///     feed: Default::default(),
///     sampling: Sampling::Rate(20.0),
///     every: 4,
/// };
/// let with_path = ClearanceRequest { path: Some(req), ..Default::default() };
/// let r = clearance(&machine, None, &with_path).unwrap();
/// let path = r.path.unwrap();
/// assert_eq!(path.samples, 21); // 1 s at 20 Hz
/// assert_eq!(path.points.len(), 6); // samples 0, 4, ..., 20
/// let worst = &path.points[path.worst.unwrap()];
/// assert!(path.points.iter().all(|p| p.upper.max(-p.lower) <= worst.upper.max(-worst.lower)));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct PathRequest {
    /// The program text.
    pub program: String,
    /// Start pose (internal units); `None`: home.
    pub from: Option<Vec<f64>>,
    /// Feed and profile.
    pub feed: FeedOptions,
    /// Sampling of the run.
    pub sampling: Sampling,
    /// Bounds at every `every`-th sample (the first and last always).
    pub every: usize,
}

/// One pose of the path (internal units).
///
/// # Examples
///
/// See [`path_samples`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathSample {
    /// Time (s).
    pub t: f64,
    /// G-code line.
    pub line: Option<u64>,
    /// Pose coordinates.
    pub x: Vec<f64>,
}

/// The bounds at one sample of the path (mm).
///
/// # Examples
///
/// See [`PathRequest`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathPoint {
    /// The sample.
    #[serde(flatten)]
    pub sample: PathSample,
    /// Direction of the bounds (unit).
    pub direction: [f64; 3],
    /// Largest error along it.
    pub upper: f64,
    /// Smallest error along it.
    pub lower: f64,
}

/// The bounds along a path.
///
/// # Examples
///
/// See [`PathRequest`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathReport {
    /// Every bounded sample.
    pub points: Vec<PathPoint>,
    /// Samples of the run (all, before keeping every `every`-th).
    pub samples: u64,
    /// Index into `points` of the largest `max(upper, -lower)`.
    pub worst: Option<usize>,
    /// The factor on every clearance that keeps every bounded sample within the
    /// tolerance.
    pub largest_clearance_scale: Option<f64>,
    /// The same as a uniform diametral clearance (mm).
    pub largest_clearance_mm: Option<f64>,
}

struct Keep {
    every: usize,
    seen: u64,
    kept: Vec<PathSample>,
    last: Option<PathSample>,
}

impl SampleSink for Keep {
    fn sample(&mut self, s: &SampleRow) -> Result<()> {
        let row = PathSample {
            t: s.t,
            line: s.line,
            x: s.x.to_vec(),
        };
        if self.seen.is_multiple_of(self.every as u64) {
            if self.kept.len() >= MAX_PATH_SAMPLES {
                return Err(Error::InvalidInput {
                    what: "clearance path".into(),
                    message: format!(
                        "more than {MAX_PATH_SAMPLES} samples to bound: keep fewer (a larger \
                         `every`, a lower sampling rate)"
                    ),
                });
            }
            self.kept.push(row);
            self.last = None;
        } else {
            self.last = Some(row);
        }
        self.seen += 1;
        Ok(())
    }
}

/// Runs the program through `machine` and keeps the samples to bound: every
/// `every`-th, and the last.
///
/// # Examples
///
/// ```
/// use pkm::analysis::clearance_path::{path_samples, PathRequest};
/// use pkm::motion::Sampling;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hybrid-am-seed002.toml"
/// ))
/// .unwrap();
/// let req = PathRequest {
///     program: "G21 G90\nG1 X10 F600\n".into(),
///     from: None,
///     feed: Default::default(),
///     sampling: Sampling::Rate(20.0),
///     every: 4,
/// };
/// let (samples, run) = path_samples(&machine, &req).unwrap();
/// assert_eq!(run, 21);
/// assert_eq!(samples.len(), 6);
/// assert_eq!(samples[0].line, Some(2));
/// // The last sample is at the end of the move: 10 mm on in X, at one second.
/// let last = samples.last().unwrap();
/// let home = machine.mechanism().home();
/// assert!((last.t - 1.0).abs() < 1e-9 && (last.x[0] - home[0] - 10.0).abs() < 1e-9);
/// ```
pub fn path_samples(machine: &Machine, req: &PathRequest) -> Result<(Vec<PathSample>, u64)> {
    if req.every == 0 {
        return Err(Error::InvalidInput {
            what: "clearance path".into(),
            message: "expected a sample step `every` >= 1".into(),
        });
    }
    let mut keep = Keep {
        every: req.every,
        seen: 0,
        kept: Vec::new(),
        last: None,
    };
    run_motion(
        machine,
        MotionSource::Gcode {
            reader: Box::new(std::io::Cursor::new(req.program.as_bytes())),
            from: req.from.clone(),
            setup: Default::default(),
        },
        &req.feed,
        req.sampling,
        &mut keep,
    )?;
    let mut kept = keep.kept;
    kept.extend(keep.last);
    if kept.is_empty() {
        return Err(Error::InvalidInput {
            what: "clearance path".into(),
            message: "the program has no motion".into(),
        });
    }
    Ok((kept, keep.seen))
}

/// The bounds along the direction of `options` (or each sample's tool axis) at every
/// sample (rayon).
pub(crate) fn path_points<M, const P: usize, const A: usize>(
    m: &M,
    samples: &[PathSample],
    regions: &[crate::accuracy::clearance::Region],
    options: &crate::accuracy::clearance::ClearanceOptions,
) -> Result<Vec<PathPoint>>
where
    M: crate::machine::Analysable<P, A>,
{
    use rayon::prelude::*;
    samples
        .par_iter()
        .map(|s| {
            let x = crate::dynamic::fixed::<P>("path sample", &s.x)?;
            let (direction, upper, lower) =
                crate::accuracy::clearance::bounds_along(m, &x, regions, options)?;
            Ok(PathPoint {
                sample: s.clone(),
                direction,
                upper,
                lower,
            })
        })
        .collect()
}

/// The index and value of the largest `max(upper, -lower)` of `points`.
pub(crate) fn path_worst(points: &[PathPoint]) -> Option<(usize, f64)> {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| (i, p.upper.max(-p.lower)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}
