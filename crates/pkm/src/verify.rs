//! Self-checks of a mechanism's kinematics, generic over [`Mechanism`]: central
//! finite-difference Jacobians, IK/FK round trips and the kinematic check table the
//! report shows for any machine.

use nalgebra::{SMatrix, SVector};
use serde::Serialize;

use crate::error::Result;
use crate::limits::Violation;
use crate::mechanism::Mechanism;
use crate::pose::rotation_matrix;
use crate::rotation::angle_between;
use crate::units::Quantity;
use crate::Visitor;

/// Central finite-difference inverse Jacobian `dq/dx` with steps `h_len` (mm) for
/// length coordinates and `h_ang` (rad) for angles: `(IK(x + h e_k) - IK(x - h e_k)) / 2h`,
/// each side solved from `IK(x)` ([`Mechanism::inverse_near`]: the branch at `x`).
pub fn numeric_jacobian<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    h_len: f64,
    h_ang: f64,
) -> Result<SMatrix<f64, A, P>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let mut j = SMatrix::<f64, A, P>::zeros();
    // The differences of the solution branch at `x`: each side solved from it. A
    // robot's inverse (the solution nearest home) may change posture between two
    // nearby poses where two postures are equally near home; the Jacobian is that of
    // one branch.
    let q = m.inverse(x)?;
    for k in 0..P {
        let h = match m.info().coordinates()[k].quantity {
            Quantity::Length => h_len,
            Quantity::Angle => h_ang,
        };
        let mut xp = *x;
        let mut xm = *x;
        xp[k] += h;
        xm[k] -= h;
        let d = (m.inverse_near(&xp, &q)? - m.inverse_near(&xm, &q)?) / (2.0 * h);
        j.set_column(k, &d);
    }
    Ok(j)
}

/// Largest difference between the analytic and the finite-difference Jacobian,
/// relative to the largest entry of the analytic one.
pub fn jacobian_error<M, const P: usize, const A: usize>(m: &M, x: &SVector<f64, P>) -> Result<f64>
where
    M: Mechanism<P, A> + ?Sized,
{
    let ja = m.jacobian(x)?;
    let jn = numeric_jacobian(m, x, 1e-4, 1e-6)?;
    Ok((ja - jn).amax() / ja.amax().max(1e-300))
}

/// Result of FK(IK(x)) started from `start`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RoundTrip {
    /// Distance between the tool tips of `x` and of the FK solution (mm).
    pub position_error: f64,
    /// Angle between the tool frames of `x` and of the FK solution (rad).
    pub orientation_error: f64,
    /// Largest difference of any pose coordinate (mm or rad).
    pub coordinate_error: f64,
    /// FK iterations.
    pub iterations: usize,
}

/// Solves IK at `x`, then FK from `start`, and compares the poses.
pub fn round_trip<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    start: &SVector<f64, P>,
) -> Result<RoundTrip>
where
    M: Mechanism<P, A> + ?Sized,
{
    let q = m.inverse(x)?;
    let f = m.forward(&q, start)?;
    let a = m.tool_pose(x)?;
    let b = m.tool_pose(&f.pose)?;
    Ok(RoundTrip {
        position_error: (a.translation.vector - b.translation.vector).norm(),
        orientation_error: angle_between(&rotation_matrix(&a), &rotation_matrix(&b)),
        coordinate_error: (f.pose - x).amax(),
        iterations: f.iterations,
    })
}

/// One row of the kinematic check table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckRow {
    /// What the pose is (`home`, `X + 20 mm`, ...).
    pub label: String,
    /// Pose coordinates in user units (mm, deg).
    pub pose: Vec<f64>,
    /// Actuator values in user units, when IK has a solution.
    pub actuators: Option<Vec<f64>>,
    /// FK(IK) round trip from the home pose (held coordinates from the pose).
    pub round_trip: Option<RoundTrip>,
    /// Relative difference of analytic and finite-difference Jacobians.
    pub jacobian_error: Option<f64>,
    /// 2-norm condition number of the driven columns of the Jacobian.
    pub condition: Option<f64>,
    /// Violated limits.
    pub violations: Vec<Violation>,
    /// Error text when a step failed.
    pub error: Option<String>,
}

/// Condition number (2-norm) of the driven columns of the Jacobian, dimensionally
/// consistent ([`Mechanism::condition`]: angle columns divided by the mechanism's
/// characteristic length).
pub fn driven_condition<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<f64>
where
    M: Mechanism<P, A> + ?Sized,
{
    m.condition(x)
}

/// The check table: the home pose, then each driven coordinate moved by +-`step_len`
/// mm (or +-`step_ang` rad), then each held coordinate moved by +`step_ang` /
/// +`step_len`. For every pose: IK, limits, FK round trip from home, the Jacobian
/// against finite differences, and the conditioning.
pub fn check_table<M, const P: usize, const A: usize>(
    m: &M,
    step_len: f64,
    step_ang: f64,
) -> Vec<CheckRow>
where
    M: Mechanism<P, A> + ?Sized,
{
    check_poses(m, step_len, step_ang)
        .into_iter()
        .map(|(label, x)| check_row(m, label, &x))
        .collect()
}

/// The poses of [`check_table`], labelled: home, each driven coordinate moved both
/// ways, each held one moved up.
fn check_poses<M, const P: usize, const A: usize>(
    m: &M,
    step_len: f64,
    step_ang: f64,
) -> Vec<(String, SVector<f64, P>)>
where
    M: Mechanism<P, A> + ?Sized,
{
    let home = m.info().home();
    let driven = m.info().driven();
    let mut poses = vec![("home".to_string(), home)];
    for k in 0..P {
        let c = &m.info().coordinates()[k];
        let h = match c.quantity {
            Quantity::Length => step_len,
            Quantity::Angle => step_ang,
        };
        let signs: &[f64] = if driven.contains(&k) {
            &[1.0, -1.0]
        } else {
            &[1.0]
        };
        for s in signs {
            let mut x = home;
            x[k] += s * h;
            let sign = if *s > 0.0 { "+" } else { "-" };
            let held = if driven.contains(&k) { "" } else { " (held)" };
            poses.push((
                format!(
                    "{} {sign} {:.4} {}{held}",
                    c.name,
                    c.quantity.to_user(h),
                    c.quantity.unit()
                ),
                x,
            ));
        }
    }
    poses
}

/// The checks of [`check_table`] at pose `x`: IK, limits, FK round trip from home,
/// the Jacobian against finite differences, and the conditioning.
fn check_row<M, const P: usize, const A: usize>(
    m: &M,
    label: String,
    x: &SVector<f64, P>,
) -> CheckRow
where
    M: Mechanism<P, A> + ?Sized,
{
    let pose = (0..P)
        .map(|k| m.info().coordinates()[k].quantity.to_user(x[k]))
        .collect();
    let mut row = CheckRow {
        label,
        pose,
        actuators: None,
        round_trip: None,
        jacobian_error: None,
        condition: None,
        violations: Vec::new(),
        error: None,
    };
    let q = match m.inverse(x) {
        Ok(q) => q,
        Err(e) => {
            row.error = Some(e.to_string());
            return row;
        }
    };
    row.actuators = Some(
        (0..A)
            .map(|i| m.info().actuators()[i].quantity.to_user(q[i]))
            .collect(),
    );
    m.check_limits(x, &q, &mut row.violations);
    // Start FK from home, with the held coordinates of this pose.
    let driven = m.info().driven();
    let mut start = m.info().home();
    for k in 0..P {
        if !driven.contains(&k) {
            start[k] = x[k];
        }
    }
    let mut errors = Vec::new();
    match round_trip(m, x, &start) {
        Ok(r) => row.round_trip = Some(r),
        Err(e) => errors.push(format!("FK: {e}")),
    }
    match jacobian_error(m, x) {
        Ok(e) => row.jacobian_error = Some(e),
        Err(e) => errors.push(format!("Jacobian: {e}")),
    }
    match driven_condition(m, x) {
        Ok(c) => row.condition = Some(c),
        Err(e) => errors.push(format!("conditioning: {e}")),
    }
    if !errors.is_empty() {
        row.error = Some(errors.join("; "));
    }
    row
}

/// [`check_table`] on a loaded machine.
pub fn machine_check_table(
    machine: &crate::Machine,
    step_len: f64,
    step_ang: f64,
) -> Vec<CheckRow> {
    struct Job(f64, f64);
    impl Visitor for Job {
        type Output = Vec<CheckRow>;
        fn visit<M: Mechanism<P, A>, const P: usize, const A: usize>(self, m: &M) -> Vec<CheckRow> {
            check_table(m, self.0, self.1)
        }
    }
    machine.visit(Job(step_len, step_ang))
}

/// One expected value of a reference and what pkm computes for it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReferenceItem {
    /// Joint or actuator name.
    pub name: String,
    /// `joint` or `actuator`.
    pub what: &'static str,
    /// Expected value(s), user units.
    pub expected: Vec<f64>,
    /// Computed value(s), user units, when available.
    pub computed: Option<Vec<f64>>,
    /// Largest absolute difference of any component.
    pub deviation: Option<f64>,
    /// Unit of the values.
    pub unit: &'static str,
    /// Within the reference's tolerance.
    pub pass: bool,
    /// What the source prints when the project's expected value differs from it
    /// (`published_actuators` of the file); `expected` is then the project's value.
    pub published: Option<Vec<f64>>,
}

/// A reference pose checked against pkm's kinematics.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReferenceCheck {
    /// Where the expected values come from.
    pub source: String,
    /// Remarks from the machine file.
    pub note: Option<String>,
    /// The pose as written (user units).
    pub pose: Vec<f64>,
    /// Tolerance (mm or deg).
    pub tolerance: f64,
    /// Every expected value.
    pub items: Vec<ReferenceItem>,
    /// Why the pose could not be evaluated, if so.
    pub error: Option<String>,
    /// Every item within tolerance and no error.
    pub pass: bool,
    /// Some expected value is the project's correction of what the source prints: the
    /// source is not reproduced there, whatever `pass` says of the corrected value.
    pub discrepancy: bool,
}

/// Evaluates every `[[reference]]` of a machine: inverse kinematics at its pose, then
/// each expected joint position and actuator value against the computed one.
pub fn check_references(machine: &crate::Machine) -> Vec<ReferenceCheck> {
    let m = machine.mechanism();
    machine
        .references
        .iter()
        .map(|r| {
            let mut out = ReferenceCheck {
                source: r.source.clone(),
                note: r.note.clone(),
                pose: r.pose.clone(),
                tolerance: r.tolerance,
                items: Vec::new(),
                error: None,
                pass: false,
                discrepancy: !r.published_actuators.is_empty(),
            };
            let solved = crate::dynamic::pose_from_user(m, &r.pose, crate::Convention::Rpy)
                .and_then(|x| {
                    let q = m.inverse(&x)?;
                    let sk = m.skeleton(&x)?;
                    Ok((q, sk))
                });
            match solved {
                Ok((q, sk)) => {
                    out.items = reference_items(m, r, &q, &sk);
                    out.pass = out.items.iter().all(|i| i.pass);
                }
                Err(e) => out.error = Some(e.to_string()),
            }
            out
        })
        .collect()
}

/// The expected joint positions and actuator values of reference `r` against those
/// computed at its pose (actuators `q`, joints in `sk`).
fn reference_items(
    m: &dyn crate::DynMechanism,
    r: &crate::machine::Reference,
    q: &[f64],
    sk: &crate::Skeleton,
) -> Vec<ReferenceItem> {
    let mut items = Vec::new();
    for (name, e) in &r.joints {
        let got = sk
            .points
            .iter()
            .find(|p| &p.name == name)
            .map(|p| p.position);
        let dev = got.map(|g| (0..3).map(|k| (g[k] - e[k]).abs()).fold(0.0, f64::max));
        items.push(ReferenceItem {
            name: name.clone(),
            what: "joint",
            expected: e.to_vec(),
            computed: got.map(|g| g.to_vec()),
            deviation: dev,
            unit: "mm",
            pass: dev.is_some_and(|d| d <= r.tolerance),
            published: None,
        });
    }
    for (name, e) in &r.actuators {
        let idx = m.actuators().iter().position(|a| &a.name == name);
        let got = idx.map(|i| m.actuators()[i].quantity.to_user(q[i]));
        let dev = got.map(|g| (g - e).abs());
        items.push(ReferenceItem {
            name: name.clone(),
            what: "actuator",
            expected: vec![*e],
            computed: got.map(|g| vec![g]),
            deviation: dev,
            unit: idx.map(|i| m.actuators()[i].quantity.unit()).unwrap_or(""),
            pass: dev.is_some_and(|d| d <= r.tolerance),
            published: r.published_actuators.get(name).map(|v| vec![*v]),
        });
    }
    items
}
