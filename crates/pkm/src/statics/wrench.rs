//! A wrench at the tool and how it acts on a mechanism's pose coordinates.
//!
//! A twist of the tool, `(dr, dtheta)` (tool tip displacement in mm, rotation vector in
//! rad, base frame), follows the pose coordinates' rates by `dp = T(x) dx`. For the
//! spatial coordinates X, Y, Z, A, B, C (`R = Rz(C) Ry(B) Rx(A)`):
//!
//! `T = [I 0; 0 E(A, B, C)]`, `E = [Rz(C) Ry(B) e_x, Rz(C) e_y, e_z]`
//! ([`crate::rotation::rpy_rate_matrix`]),
//!
//! so a wrench `w = (f, m)` at the tool tip does the virtual work `w . dp = (T^T w) . dx`:
//! its generalised force on the coordinates is `Q = T^T w`. Its change with the pose at
//! a fixed wrench, `G = dQ/dx`, is the wrench's part of the load-dependent stiffness
//! (Quennouelle and Gosselin, "Kinematostatic modeling of compliant parallel
//! mechanisms", Meccanica 46, 2011): a constant moment turns with the angles' axes,
//!
//! `dQ_A/dB = m . (-c_C s_B, -s_C s_B, -c_B)`, `dQ_A/dC = m . (-s_C c_B, c_C c_B, 0)`,
//! `dQ_B/dC = m . (-c_C, -s_C, 0)`, every other entry 0 (a force at the tip does no
//! work on the angles).

use nalgebra::{SMatrix, SVector, Vector3};
use serde::Serialize;

use crate::error::{Error, Result};
use crate::mechanism::{Mechanism, PoseSpace};

/// An external load on the tool: a force at the tool tip and a moment, both in the
/// base frame, acting on the tool (a cutting force is the workpiece's push on the
/// tool). Units N and N mm.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Wrench {
    /// Force at the tool tip (N, base frame).
    pub force: Vector3<f64>,
    /// Moment (N mm, base frame).
    pub moment: Vector3<f64>,
}

impl Wrench {
    /// `[fx, fy, fz, mx, my, mz]` in N and N mm.
    pub fn from_array(w: [f64; 6]) -> Self {
        Wrench {
            force: Vector3::new(w[0], w[1], w[2]),
            moment: Vector3::new(w[3], w[4], w[5]),
        }
    }

    /// The six components, force first (N, N mm).
    pub fn to_array(&self) -> [f64; 6] {
        [
            self.force.x,
            self.force.y,
            self.force.z,
            self.moment.x,
            self.moment.y,
            self.moment.z,
        ]
    }

    /// The six components as a vector, force first.
    pub fn vector(&self) -> SVector<f64, 6> {
        SVector::<f64, 6>::from(self.to_array())
    }
}

/// The pose coordinates' map to the tool twist, `T` (`6 x P`), at `x`; an
/// [`Error::Unsupported`] for a mechanism whose coordinates are not X, Y, Z, A, B, C.
pub fn twist_map<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<SMatrix<f64, 6, P>>
where
    M: Mechanism<P, A> + ?Sized,
{
    spatial(m)?;
    let e = crate::rotation::rpy_rate_matrix([x[3], x[4], x[5]]);
    let mut t = SMatrix::<f64, 6, P>::zeros();
    for i in 0..3 {
        t[(i, i)] = 1.0;
        for j in 0..3 {
            t[(3 + i, 3 + j)] = e[(i, j)];
        }
    }
    Ok(t)
}

/// The unit tool axis at `x` when the tool spins freely about it
/// ([`crate::mechanism::MechanismInfo::free_spin`]): the spindle, not the machine,
/// takes the wrench's moment about it.
fn spin_axis<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
) -> Result<Option<Vector3<f64>>>
where
    M: Mechanism<P, A> + ?Sized,
{
    if !m.info().free_spin() {
        return Ok(None);
    }
    Ok(Some(m.tool_pose(x)?.rotation * Vector3::z()))
}

/// The part of wrench `w` the machine takes at `x`: all of it, or without the moment
/// about a freely spinning tool's axis.
pub fn carried<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    w: &Wrench,
) -> Result<Wrench>
where
    M: Mechanism<P, A> + ?Sized,
{
    Ok(match spin_axis(m, x)? {
        Some(a) => Wrench {
            force: w.force,
            moment: w.moment - a * a.dot(&w.moment),
        },
        None => *w,
    })
}

/// The wrench's generalised force `Q = T^T w` on the pose coordinates at `x` (of the
/// part the machine takes: [`carried`]).
pub fn generalised_force<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    w: &Wrench,
) -> Result<SVector<f64, P>>
where
    M: Mechanism<P, A> + ?Sized,
{
    Ok(twist_map(m, x)?.transpose() * carried(m, x, w)?.vector())
}

/// `G = dQ/dx` at a fixed wrench (`P x P`, row: the force's coordinate, column: the
/// coordinate moved). Where the tool spins freely about its axis `a`, the moment the
/// machine takes, `m_p = m - a (a . m)`, turns with the axis too:
/// `dm_p/dx_j = -((w_j x a)(a . m) + a ((w_j x a) . m))`, `w_j` column `j` of `T`'s
/// rotation rows.
pub fn generalised_force_gradient<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    w: &Wrench,
) -> Result<SMatrix<f64, P, P>>
where
    M: Mechanism<P, A> + ?Sized,
{
    let t = twist_map(m, x)?;
    let (sb, cb) = x[4].sin_cos();
    let (sc, cc) = x[5].sin_cos();
    let axis = spin_axis(m, x)?;
    let mo = carried(m, x, w)?.moment;
    let mut g = SMatrix::<f64, P, P>::zeros();
    g[(3, 4)] = mo.dot(&Vector3::new(-cc * sb, -sc * sb, -cb));
    g[(3, 5)] = mo.dot(&Vector3::new(-sc * cb, cc * cb, 0.0));
    g[(4, 5)] = mo.dot(&Vector3::new(-cc, -sc, 0.0));
    if let Some(a) = axis {
        for j in 3..6 {
            let wj = Vector3::new(t[(3, j)], t[(4, j)], t[(5, j)]);
            let da = wj.cross(&a);
            let dm = -(da * a.dot(&w.moment) + a * da.dot(&w.moment));
            for i in 3..6 {
                let ei = Vector3::new(t[(3, i)], t[(4, i)], t[(5, i)]);
                g[(i, j)] += ei.dot(&dm);
            }
        }
    }
    Ok(g)
}

fn spatial<M, const P: usize, const A: usize>(m: &M) -> Result<()>
where
    M: Mechanism<P, A> + ?Sized,
{
    if P == 6 && m.info().pose_space() == PoseSpace::Spatial {
        return Ok(());
    }
    Err(Error::Unsupported {
        machine: m.info().name().into(),
        kind: m.info().kind().into(),
        analysis: "statics and stiffness",
        reason: "its pose coordinates are not the tool's X, Y, Z, A, B, C, so a wrench at \
                 the tool has no generalised force on them yet"
            .into(),
    })
}
