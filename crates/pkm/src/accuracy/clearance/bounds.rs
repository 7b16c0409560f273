//! Bounds on the tool-point error that joint clearances allow, along a direction and
//! as a length: the paper's enumeration of extreme joint states, and the first-order
//! bound that scales (support functions through the sensitivities), each re-solved
//! exactly.

use nalgebra::{Matrix3, SVector, Vector3};
use serde::Serialize;

mod enumeration;

use super::{deviations_of, JointState, Region};
use crate::accuracy::{sensitivities, Evaluate, Parametric};
use crate::error::{Error, Result};

/// The largest enumeration [`bounds()`] runs (re-solves).
pub const MAX_ENUMERATION: u64 = 1 << 20;

/// How the bounds are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ClearanceMethod {
    /// Support functions of each joint's region through the sensitivity of the tool
    /// point to its centre; the maximising states re-solved exactly, refined where
    /// first order is not enough. `2 + 2 k` exact solves at most per refinement step.
    FirstOrder,
    /// Seed 002's method: every combination of the joints' extreme states (`+-` the
    /// limit along each axis), re-solved: `prod n_j` solves (6 per ball, 4 per disc).
    Enumeration,
}

impl std::str::FromStr for ClearanceMethod {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "first-order" => Ok(ClearanceMethod::FirstOrder),
            "enumeration" => Ok(ClearanceMethod::Enumeration),
            _ => Err(format!(
                "unknown method `{s}`, expected first-order or enumeration"
            )),
        }
    }
}

/// What [`bounds()`] computes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClearanceOptions {
    /// The direction (base or workpiece frame; normalised). `None`: the tool axis.
    pub direction: Option<Vector3<f64>>,
    /// The method.
    pub method: ClearanceMethod,
    /// Refine the first-order states when the exact error differs from the first-order
    /// bound by more than this fraction of it (0: always; infinity: never).
    pub refine_above: f64,
}

impl Default for ClearanceOptions {
    fn default() -> Self {
        ClearanceOptions {
            direction: None,
            method: ClearanceMethod::FirstOrder,
            refine_above: 1e-3,
        }
    }
}

/// One joint's state in a worst case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WorstJointState {
    /// Joint name.
    pub joint: String,
    /// The body whose frame the displacement is in.
    pub body: String,
    /// Displacement of the joint centre (mm).
    pub displacement: [f64; 3],
    /// Shift of the centre in its clearance (mm).
    pub shift: [f64; 3],
    /// Tilt of its axis (rad, rotation vector).
    pub tilt: [f64; 3],
}

/// The joint states of the two bounds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WorstStates {
    /// The states that give `upper`.
    pub upper: Vec<WorstJointState>,
    /// The states that give `lower`.
    pub lower: Vec<WorstJointState>,
}

/// What one joint contributes to the first-order bound along the direction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointContribution {
    /// Joint name.
    pub joint: String,
    /// Its support `(c / 2 + |h| sin theta) |P g|` (mm).
    pub first_order: f64,
    /// Its share of the first-order bound (0 to 1).
    pub share: f64,
}

/// The largest length of the error, found from the first-order maximiser re-solved.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Deviation3d {
    /// `|e|` of the re-solved states (mm).
    pub norm: f64,
    /// The error vector (mm).
    pub vector: [f64; 3],
    /// The first-order bound of `|e|` (mm).
    pub first_order: f64,
    /// The joint states.
    pub states: Vec<WorstJointState>,
}

/// Bounds of the error that the clearances allow at one pose (mm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClearanceBounds {
    /// Unit direction of the bounds (base or workpiece frame).
    pub direction: [f64; 3],
    /// Largest error along the direction (exact, of the reported states).
    pub upper: f64,
    /// Smallest (most negative) error along the direction.
    pub lower: f64,
    /// The first-order bounds `+-sum_j support_j`.
    pub first_order_upper: f64,
    /// See `first_order_upper`.
    pub first_order_lower: f64,
    /// The method.
    pub method: ClearanceMethod,
    /// Whether the first-order states were refined by re-linearising at them.
    pub refined: bool,
    /// Exact solves of the mechanism the bounds took.
    pub solves: u64,
    /// The joint states that give `upper` and `lower`.
    pub worst_joint_states: WorstStates,
    /// Each joint's first-order share, largest first.
    pub contributions: Vec<JointContribution>,
    /// The largest length of the error.
    pub deviation_3d: Deviation3d,
}

/// Solves of the enumeration for `regions`, saturating.
pub fn enumeration_size(regions: &[Region]) -> u64 {
    regions.iter().fold(1u64, |a, r| {
        a.saturating_mul(if r.axis.is_some() { 4 } else { 6 })
    })
}

fn report(regions: &[Region], states: &[JointState]) -> Vec<WorstJointState> {
    regions
        .iter()
        .zip(states)
        .map(|(r, s)| WorstJointState {
            joint: r.joint.name.clone(),
            body: r.joint.body.clone(),
            displacement: s.displacement,
            shift: s.shift,
            tilt: s.tilt,
        })
        .collect()
}

/// The exact error vector with every region in its state.
fn solve<E: Evaluate>(
    ev: &mut E,
    regions: &[Region],
    states: &[JointState],
    buf: &mut Vec<(usize, f64)>,
) -> Result<Vector3<f64>> {
    deviations_of(regions, states, buf);
    Ok(ev.pose_error(buf)?.position)
}

/// `d e / d c_j` (3 x 3, columns: the centre's x, y, z) for every region, from the
/// sensitivities of all parameters (a joint shared by struts: the sum).
fn centre_sensitivities(
    regions: &[Region],
    s: &[crate::accuracy::PoseError],
) -> Result<Vec<Matrix3<f64>>> {
    regions
        .iter()
        .map(|r| {
            let mut g = Matrix3::zeros();
            for c in &r.joint.centres {
                for (k, &p) in c.iter().enumerate() {
                    let col = s.get(p).ok_or_else(|| Error::InvalidInput {
                        what: "clearance".into(),
                        message: format!("parameter index {p} beyond the machine's"),
                    })?;
                    let cur = g.column(k) + col.position;
                    g.set_column(k, &cur);
                }
            }
            Ok(g)
        })
        .collect()
}

/// `d e / d c_j` at the states `at`, by central differences of exact solves.
fn centre_sensitivities_at<E: Evaluate>(
    ev: &mut E,
    regions: &[Region],
    at: &[JointState],
    buf: &mut Vec<(usize, f64)>,
) -> Result<Vec<Matrix3<f64>>> {
    let h = 1e-4;
    let mut states = at.to_vec();
    let mut out = Vec::with_capacity(regions.len());
    for j in 0..regions.len() {
        let mut g = Matrix3::zeros();
        for k in 0..3 {
            let d0 = at[j].displacement[k];
            states[j].displacement[k] = d0 + h;
            let plus = solve(ev, regions, &states, buf)?;
            states[j].displacement[k] = d0 - h;
            let minus = solve(ev, regions, &states, buf)?;
            states[j].displacement[k] = d0;
            g.set_column(k, &((plus - minus) / (2.0 * h)));
        }
        out.push(g);
    }
    Ok(out)
}

/// First-order bound along `n` and its maximising states.
fn first_order(regions: &[Region], g: &[Matrix3<f64>], n: &Vector3<f64>) -> (f64, Vec<JointState>) {
    let mut total = 0.0;
    let states = regions
        .iter()
        .zip(g)
        .map(|(r, gj)| {
            let v = gj.transpose() * n;
            total += r.support(&v);
            r.argmax(&v)
        })
        .collect();
    (total, states)
}

/// The direction `n` (unit) of largest first-order `sum_j support_j(G_j^T n)`: ascent
/// by the fixed point `n <- sum_j G_j d_j(n)` (`d_j` joint `j`'s maximising
/// displacement for `G_j^T n`), which cannot decrease it (a convex function lies above
/// its linearisation), started from the dominant eigenvector of
/// `sum_j reach_j^2 G_j G_j^T` (the direction the joints move the tool most, jointly).
fn largest_direction(regions: &[Region], g: &[Matrix3<f64>]) -> (f64, Vector3<f64>) {
    let m = regions.iter().zip(g).fold(Matrix3::zeros(), |a, (r, gj)| {
        a + gj * gj.transpose() * r.reach().powi(2)
    });
    let eig = m.symmetric_eigen();
    let mut n: Vector3<f64> = eig.eigenvectors.column(eig.eigenvalues.imax()).into_owned();
    let mut value = first_order(regions, g, &n).0;
    for _ in 0..100 {
        let mut next = Vector3::zeros();
        for (r, gj) in regions.iter().zip(g) {
            next += gj * Vector3::from(r.argmax(&(gj.transpose() * n)).displacement);
        }
        let norm = next.norm();
        if norm == 0.0 {
            break;
        }
        let next = next / norm;
        let v = first_order(regions, g, &next).0;
        if v <= value * (1.0 + 1e-12) {
            if v > value {
                (value, n) = (v, next);
            }
            break;
        }
        (value, n) = (v, next);
    }
    (value, n)
}

/// The direction of the bounds at `x`: the option's, normalised, or the tool axis.
fn direction_at<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    opt: &ClearanceOptions,
) -> Result<Vector3<f64>>
where
    M: Parametric<P, A>,
{
    match opt.direction {
        Some(d) if d.norm() > 1e-12 && d.iter().all(|v| v.is_finite()) => Ok(d.normalize()),
        Some(d) => Err(Error::InvalidInput {
            what: "clearance direction".into(),
            message: format!("expected a non-zero finite vector, found {d:?}"),
        }),
        None => Ok(m.tool_pose(x)?.rotation * Vector3::z()),
    }
}

/// The bounds along `n`: the exact errors of the states that give them, the states,
/// the first-order bound, whether they were refined, and the solves it took.
struct Along {
    upper: f64,
    lower: f64,
    up: Vec<JointState>,
    low: Vec<JointState>,
    first_order: f64,
    refined: bool,
    solves: u64,
}

/// The bounds along unit `n` by `opt.method`, with `g` the centre sensitivities at the
/// evaluator's pose.
fn along<E: Evaluate + Clone + Send + Sync>(
    ev: &mut E,
    regions: &[Region],
    g: &[Matrix3<f64>],
    n: &Vector3<f64>,
    opt: &ClearanceOptions,
) -> Result<Along> {
    let first = first_order(regions, g, n);
    match opt.method {
        ClearanceMethod::FirstOrder => along_first_order(ev, regions, g, n, opt, first),
        ClearanceMethod::Enumeration => enumeration::along(ev, regions, n, first.0),
    }
}

/// [`along`] by the first-order maximisers (`first`: the bound and the maximising
/// states along `n`), each side solved exactly and re-linearised while that gains.
fn along_first_order<E: Evaluate>(
    ev: &mut E,
    regions: &[Region],
    g: &[Matrix3<f64>],
    n: &Vector3<f64>,
    opt: &ClearanceOptions,
    (fo, up_states): (f64, Vec<JointState>),
) -> Result<Along> {
    let mut buf = Vec::with_capacity(6 * regions.len());
    let (_, low_states) = first_order(regions, g, &-n);
    let mut refined = false;
    let mut solves = 0u64;
    let mut side = |sign: f64, mut states: Vec<JointState>| -> Result<(f64, Vec<JointState>)> {
        let mut v = sign * n.dot(&solve(ev, regions, &states, &mut buf)?);
        solves += 1;
        if (v - fo).abs() > opt.refine_above * fo {
            refined = true;
            // Re-linearise at the states and pick the maximiser again, while
            // that gains.
            for _ in 0..6 {
                let gj = centre_sensitivities_at(ev, regions, &states, &mut buf)?;
                solves += 6 * regions.len() as u64;
                let (_, next) = first_order(regions, &gj, &(n * sign));
                let w = sign * n.dot(&solve(ev, regions, &next, &mut buf)?);
                solves += 1;
                if w <= v + 1e-12 * (1.0 + v.abs()) {
                    break;
                }
                (v, states) = (w, next);
            }
        }
        Ok((sign * v, states))
    };
    let (upper, up) = side(1.0, up_states)?;
    let (lower, low) = side(-1.0, low_states)?;
    Ok(Along {
        upper,
        lower,
        up,
        low,
        first_order: fo,
        refined,
        solves,
    })
}

/// The bounds along the direction alone (`(direction, upper, lower)`, mm): what sweeps
/// over surfaces, paths and clearances need, without the length, the shares and the
/// reported states of [`bounds()`].
pub fn bounds_along<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    regions: &[Region],
    opt: &ClearanceOptions,
) -> Result<([f64; 3], f64, f64)>
where
    M: Parametric<P, A>,
{
    let n = direction_at(m, x, opt)?;
    let mut ev = m.evaluator(x)?;
    let g = centre_sensitivities(regions, &sensitivities(m, x)?)?;
    let a = along(&mut ev, regions, &g, &n, opt)?;
    Ok((n.into(), a.upper, a.lower))
}

/// Bounds of the error the clearances of `regions` allow at pose `x` of `m`: along the
/// direction (the tool axis unless given) and as a length.
pub fn bounds<M, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    regions: &[Region],
    opt: &ClearanceOptions,
) -> Result<ClearanceBounds>
where
    M: Parametric<P, A>,
{
    let n = direction_at(m, x, opt)?;
    let mut ev = m.evaluator(x)?;
    let g = centre_sensitivities(regions, &sensitivities(m, x)?)?;
    let a = along(&mut ev, regions, &g, &n, opt)?;
    let fo = a.first_order;
    let mut contributions: Vec<JointContribution> = regions
        .iter()
        .zip(&g)
        .map(|(r, gj)| {
            let v = r.support(&(gj.transpose() * n));
            JointContribution {
                joint: r.joint.name.clone(),
                first_order: v,
                share: if fo > 0.0 { v / fo } else { 0.0 },
            }
        })
        .collect();
    contributions.sort_by(|a, b| b.first_order.total_cmp(&a.first_order));
    // The length: the first-order direction of largest reach, re-solved.
    let (fo3, n3) = largest_direction(regions, &g);
    let (_, states3) = first_order(regions, &g, &n3);
    let e3 = solve(&mut ev, regions, &states3, &mut Vec::new())?;
    Ok(ClearanceBounds {
        direction: n.into(),
        upper: a.upper,
        lower: a.lower,
        first_order_upper: fo,
        first_order_lower: -fo,
        method: opt.method,
        refined: a.refined,
        solves: a.solves + 1,
        worst_joint_states: WorstStates {
            upper: report(regions, &a.up),
            lower: report(regions, &a.low),
        },
        contributions,
        deviation_3d: Deviation3d {
            norm: e3.norm(),
            vector: e3.into(),
            first_order: fo3,
            states: report(regions, &states3),
        },
    })
}
