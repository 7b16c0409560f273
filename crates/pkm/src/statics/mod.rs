//! Statics and stiffness of any mechanism, from its inverse Jacobian and the drives'
//! stiffness: the actuator forces that hold a wrench at the tool, the 6 x 6 stiffness
//! and compliance at the tool, and the tool's deflection.
//!
//! With `J = dq/dx` over the driven coordinates, `T` the coordinates' map to the tool
//! twist and `w` the wrench on the tool ([`wrench`]), the principle of virtual work
//! balances the actuator forces `tau` (each positive where it pushes its own
//! coordinate to grow) against the wrench's generalised force `Q = T^T w`:
//!
//! `J^T tau + Q = 0`, so `tau = -J^-T Q`.
//!
//! With each drive a spring of stiffness `k_i` along its coordinate, the change of that
//! balance with the pose is the tangent stiffness in pose coordinates (the
//! conservative congruence transformation of Quennouelle and Gosselin, Meccanica 46,
//! 2011, with the wrench's own term):
//!
//! `K_x = J^T diag(k) J - sum_i tau_i H_i - G`,
//!
//! `H_i` the Hessian of actuator `i`'s coordinate in the pose coordinates
//! ([`actuator_hessians`]), `G = dQ/dx` at a fixed wrench. The first term is the
//! unloaded stiffness, the others the load-dependent (geometric) stiffness. At the tool
//! (`dp = T dx`): compliance `C = T K_x^-1 T^T` and stiffness `K = T^-T K_x T^-1`.
//! Coordinates the mechanism holds rigidly (a translational tripod's orientation) do
//! not deflect: their compliance is 0 and the tool's stiffness is unbounded, so only
//! `C` is given. A tool that spins freely (a pentapod's spindle) does not resist a
//! moment about its axis: the spindle takes it, and `K` has no stiffness there.
//!
//! Passive joints and links are rigid in this model; only the drives give way.

mod equilibrium;
mod hessian;
pub mod wrench;

use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, Vector3, Vector6};

use crate::error::{Error, Result};
use crate::linalg::SmallLu;
use crate::mechanism::{driven_jacobian, Mechanism};

pub use equilibrium::{deflection_exact, EQUILIBRIUM_TOLERANCE};
pub use hessian::actuator_hessians;
pub use wrench::Wrench;

/// The actuator forces (N, or N mm for a revolute drive) that hold wrench `w` on the
/// tool at pose `x`: `tau = -J^-T T^T w` over the driven coordinates. An
/// [`Error::Singular`] at a singularity, where some wrench cannot be held.
///
/// ```
/// use pkm::statics::{actuator_forces, Wrench};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// let pkm::machine::Model::Hexapod(h) = &machine.model else { panic!() };
/// let x = pkm::Mechanism::info(&**h).home();
/// // 1 kN pressing down on the tool: every strut pushes, together 1 kN upwards.
/// let w = Wrench::from_array([0.0, 0.0, -1000.0, 0.0, 0.0, 0.0]);
/// let tau = actuator_forces(&**h, &x, &w).unwrap();
/// assert!(tau.iter().all(|f| *f > 0.0));
/// ```
pub fn actuator_forces<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    w: &Wrench,
) -> Result<SVector<f64, A>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let j = m.jacobian(x)?;
    forces_from(m, &j, x, w)
}

fn forces_from<M, const P: usize, const A: usize>(
    m: &M,
    j: &SMatrix<f64, A, P>,
    x: &SVector<f64, P>,
    w: &Wrench,
) -> Result<SVector<f64, A>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let d = m.info().driven();
    let jd = driven_jacobian(j, &d);
    let q = wrench::generalised_force(m, x, w)?;
    let qd = SVector::<f64, A>::from_fn(|i, _| q[d[i]]);
    let lu = lu_of(&jd.transpose(), "inverse Jacobian (static forces)")?;
    Ok(-lu.solve(&qd))
}

/// The drives' stiffness along their coordinates (N/mm, N mm/rad), or an
/// [`Error::InvalidInput`] naming the drives the machine file gives none for.
pub fn drive_stiffness<M, const P: usize, const A: usize>(m: &M) -> Result<SVector<f64, A>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let acts = m.info().actuators();
    let missing: Vec<&str> = acts
        .iter()
        .filter(|a| a.stiffness.is_none())
        .map(|a| a.name.as_str())
        .collect();
    if !missing.is_empty() {
        return Err(Error::InvalidInput {
            what: format!("{}: drive stiffness", m.info().name()),
            message: format!(
                "no `stiffness` for {} {} in the machine file (axial N/mm for a strut or \
                 slide, N mm/rad for a revolute joint)",
                if missing.len() == 1 {
                    "drive"
                } else {
                    "drives"
                },
                missing.join(", ")
            ),
        });
    }
    Ok(SVector::<f64, A>::from_fn(|i, _| {
        acts[i].stiffness.expect("checked above")
    }))
}

/// Stiffness of a mechanism at one pose under one wrench ([`stiffness`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stiffness<const A: usize> {
    /// The actuator forces holding the wrench (N, N mm).
    pub forces: SVector<f64, A>,
    /// Tangent stiffness in the driven pose coordinates, `K_x` (`A x A`).
    pub pose_stiffness: SMatrix<f64, A, A>,
    /// Its load-dependent part, `-sum tau_i H_i - G`.
    pub pose_geometric: SMatrix<f64, A, A>,
    /// Tangent compliance at the tool, `C = T K_x^-1 T^T`: the tool twist (mm, rad)
    /// per unit change of the wrench (N, N mm), rows and columns X Y Z then rotations
    /// about X Y Z.
    pub compliance: Matrix6<f64>,
    /// Tangent stiffness at the tool, `K = T^-T K_x T^-1` (N/mm, N/rad, N, N mm/rad);
    /// `None` when the mechanism holds some coordinates rigidly (their stiffness is
    /// unbounded; the compliance is 0 there).
    pub matrix: Option<Matrix6<f64>>,
    /// The load-dependent part of `matrix`.
    pub geometric: Option<Matrix6<f64>>,
}

/// The tangent stiffness of mechanism `m` at pose `x` under wrench `w`, its drives
/// springs of stiffness `k` ([`drive_stiffness`]). An [`Error::Singular`] where the
/// driven Jacobian or the stiffness cannot be inverted.
pub fn stiffness<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    w: &Wrench,
    k: &SVector<f64, A>,
) -> Result<Stiffness<A>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let j = m.jacobian(x)?;
    let forces = forces_from(m, &j, x, w)?;
    let (pose_stiffness, pose_geometric) = pose_stiffness(m, x, &j, &forces, w, k)?;
    let elastic = pose_stiffness - pose_geometric;
    let t = wrench::twist_map(m, x)?;
    let compliance = tool_compliance(m, x, &t, &pose_stiffness)?;
    let matrix = tool_stiffness(m, x, &t, &pose_stiffness)?;
    let geometric = match (matrix, tool_stiffness(m, x, &t, &elastic)?) {
        (Some(loaded), Some(unloaded)) => Some(loaded - unloaded),
        _ => None,
    };
    Ok(Stiffness {
        forces,
        pose_stiffness,
        pose_geometric,
        compliance,
        matrix,
        geometric,
    })
}

/// `K_x` and its load-dependent part at pose `x` with actuator forces `tau`.
pub(crate) fn pose_stiffness<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    j: &SMatrix<f64, A, P>,
    tau: &SVector<f64, A>,
    w: &Wrench,
    k: &SVector<f64, A>,
) -> Result<(SMatrix<f64, A, A>, SMatrix<f64, A, A>)>
where
    M: Mechanism<P, A> + ?Sized,
{
    let d = m.info().driven();
    let jd = driven_jacobian(j, &d);
    let elastic = jd.transpose() * SMatrix::<f64, A, A>::from_diagonal(k) * jd;
    let g = wrench::generalised_force_gradient(m, x, w)?;
    let mut geometric = SMatrix::<f64, A, A>::from_fn(|r, c| -g[(d[r], d[c])]);
    if tau.iter().any(|t| *t != 0.0) {
        let h = actuator_hessians(m, x)?;
        for (i, hi) in h.iter().enumerate() {
            geometric -= hi * tau[i];
        }
    }
    Ok((elastic + geometric, geometric))
}

/// The unit twist of a free spin about the tool axis (`None`: the tool does not spin
/// freely).
fn spin_twist<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<Option<Vector6<f64>>>
where
    M: Mechanism<P, A> + ?Sized,
{
    if !m.info().free_spin() {
        return Ok(None);
    }
    let a = m.tool_pose(x)?.rotation * Vector3::z();
    Ok(Some(Vector6::new(0.0, 0.0, 0.0, a.x, a.y, a.z)))
}

/// `C = T K_x^-1 T^T` over the driven coordinates, without a freely spinning tool's
/// turn about its axis (`P C P`, `P` the projection off the spin).
fn tool_compliance<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    t: &SMatrix<f64, 6, P>,
    kx: &SMatrix<f64, A, A>,
) -> Result<Matrix6<f64>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let d = m.info().driven();
    let td = SMatrix::<f64, 6, A>::from_fn(|r, c| t[(r, d[c])]);
    let c = td * lu_of(kx, "stiffness in pose coordinates")?.inverse() * td.transpose();
    Ok(match spin_twist(m, x)? {
        Some(s) => {
            let p = Matrix6::identity() - s * s.transpose();
            p * c * p
        }
        None => c,
    })
}

/// The stiffness at the tool for `K_x`: `T^-T K_x T^-1` when every coordinate is
/// driven; where the tool spins freely about its axis `s`, the inverse of the compliance
/// on the twists without spin, `(C + c s s^T)^-1 - s s^T / c` (`c` a scale of the
/// rotational compliance); `None` when an undriven coordinate is held rigidly.
fn tool_stiffness<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    t: &SMatrix<f64, 6, P>,
    kx: &SMatrix<f64, A, A>,
) -> Result<Option<Matrix6<f64>>>
where
    M: Mechanism<P, A> + ?Sized,
{
    if A == P && P == 6 {
        let d = m.info().driven();
        let mut full = Matrix6::<f64>::zeros();
        for r in 0..A {
            for c in 0..A {
                full[(d[r], d[c])] = kx[(r, c)];
            }
        }
        let t6 = Matrix6::<f64>::from_fn(|r, c| t[(r, c)]);
        let ti = lu_of(&t6, "rotation-rate map of the angles (gimbal lock)")?.inverse();
        return Ok(Some(ti.transpose() * full * ti));
    }
    match spin_twist(m, x)? {
        Some(s) if A + 1 == P => {
            let c = tool_compliance(m, x, t, kx)?;
            let scale = c
                .fixed_view::<3, 3>(3, 3)
                .trace()
                .abs()
                .max(f64::MIN_POSITIVE);
            let ss = s * s.transpose();
            let inv = lu_of(&(c + ss * scale), "compliance without the spin")?.inverse();
            Ok(Some(inv - ss / scale))
        }
        _ => Ok(None),
    }
}

/// The smallest stiffness of the tool tip against a force (N/mm) and its direction:
/// the inverse of the largest eigenvalue of the translational block of the compliance
/// (its symmetric part), the tool free to turn as the machine lets it.
pub fn smallest_translational(compliance: &Matrix6<f64>) -> (f64, Vector3<f64>) {
    let c = compliance.fixed_view::<3, 3>(0, 0);
    let sym: Matrix3<f64> = (c + c.transpose()) * 0.5;
    let e = sym.symmetric_eigen();
    let i = e.eigenvalues.imax();
    let mut dir: Vector3<f64> = e.eigenvectors.column(i).into();
    // One sign for the direction: its largest component positive.
    if dir[dir.iamax()] < 0.0 {
        dir = -dir;
    }
    (1.0 / e.eigenvalues[i], dir)
}

/// The tool's deflection under `w` from the unloaded machine, to first order:
/// `C_0 w`, with `C_0` the compliance without load (mm, rad; X Y Z then rotations).
pub fn deflection<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    w: &Wrench,
    k: &SVector<f64, A>,
) -> Result<Vector6<f64>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let unloaded = stiffness(m, x, &Wrench::default(), k)?;
    Ok(unloaded.compliance * w.vector())
}

fn lu_of<const N: usize>(a: &SMatrix<f64, N, N>, what: &str) -> Result<SmallLu<N>> {
    let rcond = crate::linalg::rcond1(a);
    match SmallLu::new(a) {
        Some(lu) if rcond > 1e-14 => Ok(lu),
        _ => Err(Error::Singular {
            what: what.into(),
            rcond,
        }),
    }
}
