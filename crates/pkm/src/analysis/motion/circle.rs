//! The circle of the report's motion study: the
//! largest horizontal circle around a pose that stays within every limit, found by
//! doubling and bisection, with a margin, or around the best-conditioned points of the
//! reach when no circle fits around the pose.

use nalgebra::SVector;

use crate::error::{Error, Result};
use crate::machine::{Analysable, Machine, Visitor};
use crate::mechanism::PoseSpace;

/// A circle for a machine's motion study: centre (pose coordinates, internal units)
/// and radius (mm), in the XY plane through the centre.
///
/// # Examples
///
/// ```
/// use pkm::analysis::motion::StudyCircle;
/// let c = StudyCircle {
///     centre: vec![0.0, 0.0, -290.0],
///     radius: 25.0,
///     largest: 61.2,
///     moved: false,
/// };
/// assert_eq!(c.start(), [25.0, 0.0, -290.0]);
/// // One counter-clockwise turn back to the start, centre 25 mm in -X from it.
/// assert_eq!(c.program(600.0), "G17 G21 G90 G91.1\nG3 X25 Y0 I-25 J0 F600\n");
/// ```
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StudyCircle {
    /// Centre pose (its orientation is held along the circle).
    pub centre: Vec<f64>,
    /// Radius (mm).
    pub radius: f64,
    /// The largest radius found whose whole circle is reachable (mm).
    pub largest: f64,
    /// The centre is not the pose asked for (no circle fitted around it).
    pub moved: bool,
}

impl StudyCircle {
    /// Where the circle starts: the centre moved by the radius along X.
    pub fn start(&self) -> Vec<f64> {
        let mut x = self.centre.clone();
        x[0] += self.radius;
        x
    }

    /// The circle as a G-code program to run from [`StudyCircle::start`]: one full
    /// counter-clockwise turn (G3 with incremental centre I) at `feed` mm/min.
    pub fn program(&self, feed: f64) -> String {
        let s = self.start();
        format!(
            "G17 G21 G90 G91.1\nG3 X{} Y{} I{} J0 F{feed}\n",
            s[0], s[1], -self.radius
        )
    }
}

/// Three significant digits (a radius a reader can take in).
fn round3(v: f64) -> f64 {
    if v <= 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(2 - v.log10().floor() as i32);
    (v * scale).floor() / scale
}

/// Points tested on a circle by [`study_circle`].
const CIRCLE_POINTS: usize = 72;

/// The circle of a motion study scaled to the machine's reach around `centre`: the
/// largest radius (doubling from 1 mm, then 20 bisections) for which all 72 points of
/// the horizontal circle through `centre`, at its orientation, are within every limit,
/// times `fraction` (a margin), rounded down to three significant digits. When no circle of 1 mm fits around `centre` (a pose on
/// the edge of the reach), the centre is the one of the twelve best-conditioned
/// reachable points of a 9-point-per-axis map of the reach that takes the largest
/// circle. Machines whose pose is X, Y, Z[, A, B, C] only; fails with
/// [`Error::NotAttainable`] when no circle of 1 mm fits anywhere.
///
/// # Examples
///
/// ```
/// use pkm::analysis::motion::study_circle;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let c = study_circle(&machine, &home, 0.5).unwrap();
/// // Around home, half the largest circle, rounded down to three digits.
/// assert!(!c.moved && c.centre == home);
/// assert!(c.radius > 1.0 && c.radius <= 0.5 * c.largest);
/// assert!(c.radius >= 0.99 * 0.5 * c.largest);
/// ```
pub fn study_circle(machine: &Machine, centre: &[f64], fraction: f64) -> Result<StudyCircle> {
    struct Job<'a>(&'a [f64], f64);
    impl Visitor for Job<'_> {
        type Output = Result<StudyCircle>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            if m.info().pose_space() == PoseSpace::Own || P < 3 {
                return Err(Error::Unsupported {
                    machine: m.info().name().into(),
                    kind: m.info().kind().into(),
                    analysis: "a circle in the workspace",
                    reason: "its pose is not X, Y, Z[, A, B, C]".into(),
                });
            }
            let c0 = crate::dynamic::fixed::<P>("circle centre", self.0)?;
            // The pose itself, else (a robot's stretched zero pose is on the edge of
            // its reach) the best-conditioned reachable points of a coarse map of the
            // reach at its orientation.
            let best = match largest_circle(m, &c0) {
                Some(r) => Some((c0, r)),
                None => best_conditioned_circle(m, &c0)?,
            };
            let Some((c, lo)) = best else {
                return Err(Error::NotAttainable {
                    reason: "no horizontal circle of 1 mm is within every limit around the \
                             pose nor around the best-conditioned points of the reach"
                        .into(),
                });
            };
            Ok(StudyCircle {
                centre: c.as_slice().to_vec(),
                radius: round3(lo * self.1),
                largest: lo,
                moved: c != c0,
            })
        }
    }
    machine.visit(Job(centre, fraction))
}

/// Whether all [`CIRCLE_POINTS`] points of the horizontal circle of radius `r` around
/// `c` are within every limit of `m`.
fn fits<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    c: &SVector<f64, P>,
    r: f64,
) -> bool {
    (0..CIRCLE_POINTS).all(|k| {
        let t = std::f64::consts::TAU * k as f64 / CIRCLE_POINTS as f64;
        let mut x = *c;
        x[0] += r * t.cos();
        x[1] += r * t.sin();
        crate::mechanism::inverse_checked(m, &x).is_ok()
    })
}

/// The largest radius that [`fits`] around `c` (doubling from 1 mm, then 20
/// bisections), or `None` when 1 mm does not.
fn largest_circle<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    c: &SVector<f64, P>,
) -> Option<f64> {
    let mut hi = 1.0;
    if !fits(m, c, hi) {
        return None;
    }
    while fits(m, c, 2.0 * hi) && hi < 1e5 {
        hi *= 2.0;
    }
    let mut lo = hi;
    hi *= 2.0;
    for _ in 0..20 {
        let mid = 0.5 * (lo + hi);
        if fits(m, c, mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// Of the twelve best-conditioned reachable points of a coarse map of the reach at
/// `c0`'s orientation, the one with the largest circle, and its radius.
fn best_conditioned_circle<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    c0: &SVector<f64, P>,
) -> Result<Option<(SVector<f64, P>, f64)>> {
    let g = crate::workspace::reach_grid(m, c0, 8, None)?;
    let wm = crate::workspace::map(m, c0, &g.axes, &[], &|_| {})?;
    let mut cands: Vec<(f64, usize)> = wm
        .points
        .iter()
        .enumerate()
        .filter(|(_, p)| p.reachable)
        .map(|(k, p)| (p.condition, k))
        .collect();
    cands.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best: Option<(SVector<f64, P>, f64)> = None;
    for (_, k) in cands.into_iter().take(12) {
        let c = crate::dynamic::fixed::<P>("circle centre", &wm.coords(k))?;
        if let Some(r) = largest_circle(m, &c) {
            if best.is_none_or(|b| r > b.1) {
                best = Some((c, r));
            }
        }
    }
    Ok(best)
}
