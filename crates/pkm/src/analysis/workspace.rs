//! Workspace analyses on a loaded machine: pose grids with the binding limit and the
//! conditioning (constant or total orientation), the reachable tilt at a point, the
//! performance atlas, the forward workspace over the actuator strokes, and the
//! assembly modes of an actuator set. Results with run-time sizes, internal units.

use serde::Serialize;

use crate::dynamic::DynForward;
use crate::error::Result;
use crate::machine::{Analysable, Analysis, Machine, Visitor};
use crate::workspace::atlas::Capacity;
use crate::workspace::{GridAxis, ReachGrid, WorkspaceMap};

/// The pose grid `axes` around `base` (internal units), reachable at every orientation
/// of `orientations` (A, B, C rad; empty: the base orientation), with the binding limit
/// and the condition number per point (rayon); `progress` is told of points done.
///
/// # Examples
///
/// The LinuxCNC hexapod over X (-50, 0, 50 mm) and Z (508, 708, 908 mm), level: at
/// home height every point is reachable, at 908 mm the struts are beyond their
/// 1000 mm stroke.
///
/// ```
/// use pkm::analysis::workspace::grid;
/// use pkm::workspace::GridAxis;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let axes = [
///     GridAxis { coordinate: 0, min: -50.0, max: 50.0, step: 50.0 },
///     GridAxis { coordinate: 2, min: 508.0, max: 908.0, step: 200.0 },
/// ];
/// let wm = grid(&machine, &home, &axes, &[], &|_| {}).unwrap();
/// assert_eq!(wm.points.len(), 9); // row-major: Z varies fastest
/// for ix in 0..3 {
///     let (low, high) = (&wm.points[3 * ix], &wm.points[3 * ix + 2]);
///     assert!(low.reachable && low.condition >= 1.0);
///     assert!(!high.reachable && high.binding.is_some());
/// }
/// assert!(!wm.violated.is_empty());
/// ```
pub fn grid(
    machine: &Machine,
    base: &[f64],
    axes: &[GridAxis],
    orientations: &[[f64; 3]],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<WorkspaceMap> {
    struct Job<'a> {
        base: &'a [f64],
        axes: &'a [GridAxis],
        orientations: &'a [[f64; 3]],
        progress: &'a (dyn Fn(u64) + Sync),
    }
    impl Visitor for Job<'_> {
        type Output = Result<WorkspaceMap>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let base = crate::dynamic::fixed::<P>("base pose", self.base)?;
            crate::workspace::map(m, &base, self.axes, self.orientations, self.progress)
        }
    }
    machine.visit(Job {
        base,
        axes,
        orientations,
        progress,
    })
}

/// A grid over the machine's whole reach at `base`'s orientation, `steps` cells per
/// axis or `step` (user units) ([`crate::workspace::reach_grid`]).
///
/// # Examples
///
/// ```
/// use pkm::analysis::workspace::reach_grid;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let g = reach_grid(&machine, &home, 8, None).unwrap();
/// // X, Y and Z, each spanning the home pose.
/// assert_eq!(g.axes.iter().map(|a| a.coordinate).collect::<Vec<_>>(), [0, 1, 2]);
/// for a in &g.axes {
///     assert!(a.min < home[a.coordinate] && home[a.coordinate] < a.max);
/// }
/// ```
pub fn reach_grid(
    machine: &Machine,
    base: &[f64],
    steps: usize,
    step: Option<f64>,
) -> Result<ReachGrid> {
    struct Job<'a>(&'a [f64], usize, Option<f64>);
    impl Visitor for Job<'_> {
        type Output = Result<ReachGrid>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let base = crate::dynamic::fixed::<P>("base pose", self.0)?;
            crate::workspace::reach_grid(m, &base, self.1, self.2)
        }
    }
    machine.visit(Job(base, steps, step))
}

/// The map over the machine's whole reach at `base`'s orientation, `steps` cells per
/// axis or `step` (user units), widened where it reached its edge
/// ([`crate::workspace::map_reach`]); with how its grid was found.
///
/// # Examples
///
/// ```
/// use pkm::analysis::workspace::reach_map;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let (wm, how) = reach_map(&machine, &home, 6, None, &[], &|_| {}).unwrap();
/// let n: usize = wm.axes.iter().map(|a| a.count()).product();
/// assert_eq!(wm.points.len(), n);
/// let reachable = wm.points.iter().filter(|p| p.reachable).count();
/// assert!(reachable > 0 && reachable < n); // the grid reaches past the edge
/// assert!(!how.is_empty());
/// ```
pub fn reach_map(
    machine: &Machine,
    base: &[f64],
    steps: usize,
    step: Option<f64>,
    orientations: &[[f64; 3]],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(WorkspaceMap, String)> {
    struct Job<'a> {
        base: &'a [f64],
        steps: usize,
        step: Option<f64>,
        orientations: &'a [[f64; 3]],
        progress: &'a (dyn Fn(u64) + Sync),
    }
    impl Visitor for Job<'_> {
        type Output = Result<(WorkspaceMap, String)>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let base = crate::dynamic::fixed::<P>("base pose", self.base)?;
            crate::workspace::map_reach(
                m,
                &base,
                self.steps,
                self.step,
                self.orientations,
                self.progress,
            )
        }
    }
    machine.visit(Job {
        base,
        steps,
        step,
        orientations,
        progress,
    })
}

/// The workspace map a user asks for: over `bounds` (user units, min,max per axis;
/// [`crate::workspace::default_grid`]) when given, else over the machine's whole reach
/// ([`reach_map`], 40 cells per axis); `step` (user units) or 1/40 of each range. With
/// how the grid's bounds were found.
///
/// # Examples
///
/// A box of +-100 mm in X and Y and 450 to 550 mm in Z at 50 mm steps (user units):
/// 5 x 5 x 3 points, all within the hexapod's reach.
///
/// ```
/// use pkm::analysis::workspace::map;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let bounds = [-100.0, 100.0, -100.0, 100.0, 450.0, 550.0];
/// let (wm, how) = map(&machine, &home, Some(&bounds), Some(50.0), &[], &|_| {}).unwrap();
/// assert_eq!(how, "the given bounds");
/// assert_eq!(wm.points.len(), 75);
/// assert!(wm.points.iter().all(|p| p.reachable));
/// ```
pub fn map(
    machine: &Machine,
    base: &[f64],
    bounds: Option<&[f64]>,
    step: Option<f64>,
    orientations: &[[f64; 3]],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<(WorkspaceMap, String)> {
    match bounds {
        Some(b) => {
            let axes = crate::workspace::default_grid(machine.mechanism(), base, Some(b), step)?;
            let wm = grid(machine, base, &axes, orientations, progress)?;
            Ok((wm, "the given bounds".into()))
        }
        None => reach_map(machine, base, 40, step, orientations, progress)
            .map(|(wm, how)| (wm, format!("the machine's reach: {how}"))),
    }
}

/// The largest reachable tilt (rad) per azimuth of `azimuths` at pose `x`, searched up
/// to `max_tilt` (spatial machines).
///
/// # Examples
///
/// ```
/// use pkm::analysis::workspace::reachable_tilt;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let azimuths: Vec<f64> = (0..4).map(|k| k as f64 * std::f64::consts::FRAC_PI_2).collect();
/// let max = 60f64.to_radians();
/// let tilt = reachable_tilt(&machine, &home, &azimuths, max).unwrap();
/// assert_eq!(tilt.len(), 4);
/// // The platform tilts some degrees every way at home, not beyond the search.
/// assert!(tilt.iter().all(|t| *t > 5f64.to_radians() && *t <= max));
/// ```
pub fn reachable_tilt(
    machine: &Machine,
    x: &[f64],
    azimuths: &[f64],
    max_tilt: f64,
) -> Result<Vec<f64>> {
    struct Job<'a>(&'a [f64], &'a [f64], f64);
    impl Visitor for Job<'_> {
        type Output = Result<Vec<f64>>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let x = crate::dynamic::fixed::<P>("pose", self.0)?;
            crate::workspace::reachable_tilt(m, &x, self.1, self.2, 1e-4)
        }
    }
    machine.visit(Job(x, azimuths, max_tilt))
}

/// One atlas point with run-time sizes (internal units).
///
/// # Examples
///
/// ```
/// use pkm::analysis::workspace::AtlasRow;
/// let row = AtlasRow {
///     reachable: true,
///     q: vec![750.0, 760.0],
///     velocity: vec![120.0, 95.0],
///     acceleration: vec![900.0, 1100.0],
/// };
/// // `get` picks position (0), velocity (1) or acceleration (2) of an actuator.
/// assert_eq!(row.get(0, 1), 760.0);
/// assert_eq!(row.get(1, 0), 120.0);
/// assert_eq!(row.get(2, 1), 1100.0);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AtlasRow {
    /// Within every limit.
    pub reachable: bool,
    /// Actuator positions.
    pub q: Vec<f64>,
    /// Actuator velocities the capacities need (worst direction).
    pub velocity: Vec<f64>,
    /// Actuator accelerations the capacities need (worst direction).
    pub acceleration: Vec<f64>,
}

impl AtlasRow {
    /// Position (`sel` 0), velocity (1) or acceleration (2) of actuator `i`.
    pub fn get(&self, sel: usize, i: usize) -> f64 {
        match sel {
            0 => self.q[i],
            1 => self.velocity[i],
            _ => self.acceleration[i],
        }
    }
}

/// The performance atlas over `axes` around `base`: per point the actuator positions
/// and the actuator velocities and accelerations that pose rates up to `velocity` and
/// accelerations up to `acceleration` (one per pose coordinate) need
/// ([`crate::workspace::atlas::atlas`]).
/// `progress` is told of points done (from several threads).
///
/// # Examples
///
/// Three points along X at home height, pose rates up to 100 mm/s and 0.1 rad/s and
/// accelerations up to 1000 mm/s^2 and 1 rad/s^2: every strut moves, none faster than
/// the platform's fastest combined rate allows.
///
/// ```
/// use pkm::analysis::workspace::atlas;
/// use pkm::workspace::GridAxis;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let home = machine.mechanism().home();
/// let axes = [GridAxis { coordinate: 0, min: -50.0, max: 50.0, step: 50.0 }];
/// let (v, a) = ([100.0, 100.0, 100.0, 0.1, 0.1, 0.1], [1e3, 1e3, 1e3, 1.0, 1.0, 1.0]);
/// let rows = atlas(&machine, &home, &axes, &v, &a, &|_| {}).unwrap();
/// assert_eq!(rows.len(), 3);
/// assert!(rows.iter().all(|r| r.reachable && r.q.len() == 6));
/// // The middle point is home: its struts are home's.
/// let q_home = machine.mechanism().inverse(&home).unwrap();
/// assert!(rows[1].q.iter().zip(&q_home).all(|(a, b)| (a - b).abs() < 1e-9));
/// assert!(rows[1].velocity.iter().all(|v| *v > 0.0));
/// ```
pub fn atlas(
    machine: &Machine,
    base: &[f64],
    axes: &[GridAxis],
    velocity: &[f64],
    acceleration: &[f64],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<AtlasRow>> {
    struct Job<'a>(
        &'a [f64],
        &'a [GridAxis],
        &'a [f64],
        &'a [f64],
        &'a (dyn Fn(u64) + Sync),
    );
    impl Visitor for Job<'_> {
        type Output = Result<Vec<AtlasRow>>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let base = crate::dynamic::fixed::<P>("base pose", self.0)?;
            let cap = Capacity {
                velocity: crate::dynamic::fixed::<P>("velocity capacity", self.2)?,
                acceleration: crate::dynamic::fixed::<P>("acceleration capacity", self.3)?,
            };
            let a = crate::workspace::atlas::atlas(m, &base, self.1, &cap, self.4)?;
            Ok(a.points
                .into_iter()
                .map(|p| AtlasRow {
                    reachable: p.reachable,
                    q: p.q.as_slice().to_vec(),
                    velocity: p.velocity.as_slice().to_vec(),
                    acceleration: p.acceleration.as_slice().to_vec(),
                })
                .collect())
        }
    }
    machine.visit(Job(base, axes, velocity, acceleration, progress))
}

/// One point of a forward map (internal units).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ForwardPoint {
    /// A pose was found within every limit.
    pub reachable: bool,
    /// The limit that binds, or why no pose was found.
    pub binding: Option<crate::limits::LimitName>,
    /// The pose, when found.
    pub pose: Option<Vec<f64>>,
}

/// The forward workspace ([`Analysis::ForwardWorkspace`]): forward kinematics over the
/// grid `axes` of actuator values, every solution started from `start`; `progress` is
/// told of points done.
///
/// # Examples
///
/// The seed 000 tripod over its three strut lengths, 10 mm either side of home's:
/// 27 actuator sets, the middle one giving home back.
///
/// ```
/// use pkm::analysis::workspace::forward_map;
/// use pkm::workspace::GridAxis;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/tripod-seed000.toml"
/// ))
/// .unwrap();
/// let m = machine.mechanism();
/// let home = m.home();
/// let q = m.inverse(&home).unwrap();
/// let axes: Vec<GridAxis> = (0..3)
///     .map(|k| GridAxis { coordinate: k, min: q[k] - 10.0, max: q[k] + 10.0, step: 10.0 })
///     .collect();
/// let points = forward_map(&machine, &axes, &home, &|_| {}).unwrap();
/// assert_eq!(points.len(), 27);
/// let centre = &points[13];
/// assert!(centre.reachable && centre.binding.is_none());
/// let pose = centre.pose.as_ref().unwrap();
/// assert!(pose.iter().zip(&home).all(|(a, b)| (a - b).abs() < 1e-6));
/// ```
pub fn forward_map(
    machine: &Machine,
    axes: &[GridAxis],
    start: &[f64],
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<ForwardPoint>> {
    machine.supports(Analysis::ForwardWorkspace)?;
    struct Job<'a>(&'a [GridAxis], &'a [f64], &'a (dyn Fn(u64) + Sync));
    impl Visitor for Job<'_> {
        type Output = Result<Vec<ForwardPoint>>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let start = crate::dynamic::fixed::<P>("start pose", self.1)?;
            let base = m.inverse(&start)?;
            let f = crate::workspace::forward::forward_map(m, &base, self.0, &start, self.2)?;
            Ok(f.points
                .into_iter()
                .map(|p| ForwardPoint {
                    reachable: p.reachable,
                    binding: p.binding,
                    pose: p.pose.map(|x| x.as_slice().to_vec()),
                })
                .collect())
        }
    }
    machine.visit(Job(axes, start, progress))
}

/// The distinct forward solutions (assembly modes) of actuator set `q` found from `n`
/// starts spread around home ([`crate::mechanism::spread_starts`]).
///
/// # Examples
///
/// ```
/// use pkm::analysis::workspace::assembly_modes;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let m = machine.mechanism();
/// let home = m.home();
/// let q = m.inverse(&home).unwrap();
/// let modes = assembly_modes(&machine, &q, 8).unwrap();
/// // Home is one of them, and every mode has the struts asked for.
/// assert!(modes.iter().any(|f| f.pose.iter().zip(&home).all(|(a, b)| (a - b).abs() < 1e-6)));
/// for f in &modes {
///     let back = m.inverse(&f.pose).unwrap();
///     assert!(back.iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-6));
/// }
/// ```
pub fn assembly_modes(machine: &Machine, q: &[f64], n: usize) -> Result<Vec<DynForward>> {
    struct Job<'a>(&'a [f64], usize);
    impl Visitor for Job<'_> {
        type Output = Result<Vec<DynForward>>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let q = crate::dynamic::fixed::<A>("actuators", self.0)?;
            let starts = crate::mechanism::spread_starts(m, self.1.max(1));
            Ok(crate::mechanism::assembly_modes(m, &q, &starts, 1e-6)
                .into_iter()
                .map(|f| DynForward {
                    pose: f.pose.as_slice().to_vec(),
                    iterations: f.iterations,
                    residual: f.residual,
                })
                .collect())
        }
    }
    machine.visit(Job(q, n))
}
