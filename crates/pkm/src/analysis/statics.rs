//! Statics at one pose of a loaded machine: the actuator forces holding a wrench at the
//! tool, the tool's stiffness and compliance (with the load-dependent term), and its
//! deflection to first order and exactly ([`crate::statics`]).

use serde::Serialize;

use crate::error::Result;
use crate::machine::{Analysable, Machine, Visitor};
use crate::statics::{self, Wrench};

/// What [`statics()`] computes.
#[derive(Debug, Clone, PartialEq)]
pub struct StaticsOptions {
    /// Pose coordinates (internal units: mm, rad).
    pub pose: Vec<f64>,
    /// The wrench on the tool: force at the tool tip (N), moment (N mm), base frame.
    pub wrench: [f64; 6],
}

/// The tool's stiffness at the pose ([`statics::stiffness`]), rows and columns X, Y, Z
/// then rotations about X, Y, Z (base frame): N/mm, N/rad, N and N mm/rad.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StiffnessReport {
    /// Tangent stiffness under the wrench; `None` when the machine holds some
    /// coordinates rigidly (unbounded stiffness there: see `compliance`).
    pub matrix: Option<[[f64; 6]; 6]>,
    /// Its load-dependent (geometric) part; zero without a wrench.
    pub geometric: Option<[[f64; 6]; 6]>,
    /// Tangent compliance under the wrench (mm/N, rad/N, mm/(N mm), rad/(N mm)).
    pub compliance: [[f64; 6]; 6],
    /// The tool's deflection under the wrench to first order (unloaded compliance times
    /// the wrench): mm, then rad (rotation vector).
    pub deflection: [f64; 6],
    /// The exact deflection ([`statics::deflection_exact`]); `None` when it was not
    /// found (`deflection_exact_error` says why).
    pub deflection_exact: Option<[f64; 6]>,
    /// Why the exact deflection was not found (no equilibrium under the load).
    pub deflection_exact_error: Option<String>,
    /// The smallest stiffness of the tool tip against a force (N/um), unloaded
    /// ([`statics::smallest_translational`]).
    pub smallest_translational_n_per_um: f64,
    /// Its direction (unit vector, base frame).
    pub weakest_direction: [f64; 3],
}

/// [`statics()`]'s result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StaticsReport {
    /// The pose (internal units).
    pub pose: Vec<f64>,
    /// The wrench (N, N mm).
    pub wrench: [f64; 6],
    /// Actuator forces holding the wrench (N; N mm for a revolute drive), positive where
    /// the drive pushes its own coordinate to grow.
    pub actuator_forces: Vec<f64>,
    /// The stiffness; `None` when not available (`stiffness_error` says why).
    pub stiffness: Option<StiffnessReport>,
    /// Why the stiffness is not available (drives without `stiffness`, a singular
    /// pose).
    pub stiffness_error: Option<String>,
}

/// Actuator forces, stiffness and deflection of `machine` at `o.pose` under `o.wrench`.
/// Fails when the pose has no inverse solution, the forces are not defined (a
/// singularity) or the machine's coordinates are not X, Y, Z, A, B, C.
///
/// # Examples
///
/// The LinuxCNC hexapod at home, 1 kN down on the tool, drives of 112 N/um:
///
/// ```
/// use pkm::analysis::statics::{statics, StaticsOptions};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let o = StaticsOptions {
///     pose: machine.mechanism().home(),
///     wrench: [0.0, 0.0, -1000.0, 0.0, 0.0, 0.0],
/// };
/// let r = statics(&machine, &o).unwrap();
/// // The six struts share the load, each pushing.
/// assert!(r.actuator_forces.iter().all(|f| *f > 100.0));
/// let s = r.stiffness.unwrap();
/// // The tool goes down, by well under a micrometre per 100 N here.
/// assert!(s.deflection[2] < 0.0 && s.deflection[2] > -0.01);
/// let exact = s.deflection_exact.unwrap();
/// assert!((exact[2] - s.deflection[2]).abs() < 1e-3 * s.deflection[2].abs());
/// ```
pub fn statics(machine: &Machine, o: &StaticsOptions) -> Result<StaticsReport> {
    struct Job<'a>(&'a StaticsOptions);
    impl Visitor for Job<'_> {
        type Output = Result<StaticsReport>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            let x = crate::dynamic::fixed::<P>("pose", &self.0.pose)?;
            let w = Wrench::from_array(self.0.wrench);
            m.inverse(&x)?;
            let forces = statics::actuator_forces(m, &x, &w)?;
            let (stiffness, stiffness_error) = split(stiffness_report(m, &x, &w));
            Ok(StaticsReport {
                pose: self.0.pose.clone(),
                wrench: self.0.wrench,
                actuator_forces: forces.iter().copied().collect(),
                stiffness,
                stiffness_error,
            })
        }
    }
    machine.visit(Job(o))
}

/// A result as a value or the words of its error.
fn split<T>(r: Result<T>) -> (Option<T>, Option<String>) {
    match r {
        Ok(v) => (Some(v), None),
        Err(e) => (None, Some(e.to_string())),
    }
}

fn rows(m: &nalgebra::Matrix6<f64>) -> [[f64; 6]; 6] {
    std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]))
}

fn stiffness_report<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &nalgebra::SVector<f64, P>,
    w: &Wrench,
) -> Result<StiffnessReport> {
    let k = statics::drive_stiffness(m)?;
    let loaded = statics::stiffness(m, x, w, &k)?;
    let unloaded = statics::stiffness(m, x, &Wrench::default(), &k)?;
    let deflection = unloaded.compliance * w.vector();
    let (kmin, dir) = statics::smallest_translational(&unloaded.compliance);
    let (deflection_exact, deflection_exact_error) =
        split(statics::deflection_exact(m, x, w, &k).map(Into::into));
    Ok(StiffnessReport {
        matrix: loaded.matrix.as_ref().map(rows),
        geometric: loaded.geometric.as_ref().map(rows),
        compliance: rows(&loaded.compliance),
        deflection: deflection.into(),
        deflection_exact,
        deflection_exact_error,
        smallest_translational_n_per_um: kmin * 1e-3,
        weakest_direction: dir.into(),
    })
}

/// The unloaded stiffness at many poses ([`stiffness_map`]): per pose the smallest
/// stiffness of the tool tip against a force and its direction, and the 6 x 6
/// stiffness when asked for. NaN where a pose has no inverse solution, is singular, or
/// (the matrix) the machine holds coordinates rigidly.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StiffnessMap {
    /// Smallest translational stiffness per pose (N/um).
    pub smallest_n_per_um: Vec<f64>,
    /// Its direction per pose (unit vector, base frame).
    pub direction: Vec<[f64; 3]>,
    /// The 6 x 6 stiffness per pose, row after row (36 values a pose), when asked for;
    /// empty otherwise.
    pub matrices: Vec<f64>,
    /// Poses without a value (no inverse solution, singular).
    pub failed: usize,
    /// The pose with the smallest stiffness, by index (`None`: no pose has a value).
    pub weakest: Option<usize>,
}

/// [`StiffnessMap`] of `machine` at the poses `poses` (rows of the machine's pose
/// coordinates, internal units, one after another), on every core. Fails up front when
/// a drive has no stiffness or the machine's coordinates are not X, Y, Z, A, B, C.
///
/// # Examples
///
/// ```
/// use pkm::analysis::statics::stiffness_map;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// // Home, and 100 mm higher.
/// let poses = [0.0, 0.0, 508.0, 0.0, 0.0, 0.0, 0.0, 0.0, 608.0, 0.0, 0.0, 0.0];
/// let map = stiffness_map(&machine, &poses, true).unwrap();
/// assert_eq!(map.smallest_n_per_um.len(), 2);
/// assert_eq!(map.matrices.len(), 72);
/// assert!(map.smallest_n_per_um.iter().all(|k| *k > 50.0 && *k < 1000.0));
/// ```
pub fn stiffness_map(machine: &Machine, poses: &[f64], matrices: bool) -> Result<StiffnessMap> {
    struct Job<'a>(&'a [f64], bool);
    impl Visitor for Job<'_> {
        type Output = Result<StiffnessMap>;
        fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output {
            map_of(m, self.0, self.1)
        }
    }
    machine.visit(Job(poses, matrices))
}

/// One pose of a map: the smallest stiffness, its direction, the 6 x 6 stiffness.
type MapPoint = (f64, [f64; 3], Option<[f64; 36]>);

fn map_of<M: Analysable<P, A>, const P: usize, const A: usize>(
    m: &M,
    poses: &[f64],
    with_matrices: bool,
) -> Result<StiffnessMap> {
    use rayon::prelude::*;
    if !poses.len().is_multiple_of(P) {
        return Err(crate::error::Error::InvalidInput {
            what: "poses".into(),
            message: format!("expected rows of {P} values, found {} values", poses.len()),
        });
    }
    let k = statics::drive_stiffness(m)?;
    // The coordinates' check, once, before the sweep.
    statics::wrench::twist_map(m, &m.info().home())?;
    let one = |row: &[f64]| -> Option<MapPoint> {
        let x = nalgebra::SVector::<f64, P>::from_column_slice(row);
        m.inverse(&x).ok()?;
        let s = statics::stiffness(m, &x, &Wrench::default(), &k).ok()?;
        let (kmin, dir) = statics::smallest_translational(&s.compliance);
        let mat = s
            .matrix
            .filter(|_| with_matrices)
            .map(|k| std::array::from_fn(|i| k[(i / 6, i % 6)]));
        Some((kmin * 1e-3, dir.into(), mat))
    };
    let points: Vec<Option<MapPoint>> = poses.par_chunks(P).map(one).collect();
    let nan3 = [f64::NAN; 3];
    let mut map = StiffnessMap {
        smallest_n_per_um: points.iter().map(|p| p.map_or(f64::NAN, |p| p.0)).collect(),
        direction: points.iter().map(|p| p.map_or(nan3, |p| p.1)).collect(),
        matrices: Vec::new(),
        failed: points.iter().filter(|p| p.is_none()).count(),
        weakest: None,
    };
    if with_matrices {
        map.matrices = points
            .iter()
            .flat_map(|p| p.and_then(|p| p.2).unwrap_or([f64::NAN; 36]))
            .collect();
    }
    map.weakest = (0..points.len())
        .filter(|&i| map.smallest_n_per_um[i].is_finite())
        .min_by(|&a, &b| map.smallest_n_per_um[a].total_cmp(&map.smallest_n_per_um[b]));
    Ok(map)
}
