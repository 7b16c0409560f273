//! The strut equations shared by every strut machine (hexapod, translational tripod):
//! `L_j = |p + R (B'_j - t) - A_j|` (seed 001 eq. 1 with the tool offset `t`), their
//! derivatives with respect to the joint centres, and the platform's points.

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3, Vector6};

use crate::error::{Error, Result};
use crate::legs::split_pose;
use crate::rotation::{rpy_rate_matrix, Convention};

/// Parameter names: `A.x, A.y, A.z` of every strut's base joint, then `B.x, ...` of
/// its platform joint, named as in the file (`name[strut]` for a joint two struts
/// share: each strut has its own parameters).
pub fn names(base: &[&str], platform: &[&str], struts: &[&str]) -> Vec<String> {
    let unique = |names: &[&str]| -> Vec<String> {
        names
            .iter()
            .enumerate()
            .map(|(i, n)| {
                if names.iter().filter(|m| *m == n).count() > 1 {
                    format!("{n}[{}]", struts[i])
                } else {
                    n.to_string()
                }
            })
            .collect()
    };
    unique(base)
        .into_iter()
        .chain(unique(platform))
        .flat_map(|n| ["x", "y", "z"].map(|a| format!("{n}.{a}")))
        .collect()
}

/// Strut lengths at pose `x` and `dL/d(A, B')` into `jac` (`N x 6N`: the base joints'
/// coordinates, then the platform joints'): `dL_j/dA_j = -n_j^T`,
/// `dL_j/dB'_j = n_j^T R`, `n_j` the unit strut vector.
pub fn lengths_with_jacobian<const N: usize>(
    base: &[Vector3<f64>; N],
    platform: &[Vector3<f64>; N],
    tool: &Vector3<f64>,
    x: &Vector6<f64>,
    jac: &mut DMatrix<f64>,
) -> Result<SVector<f64, N>> {
    let (p, r) = split_pose(x);
    jac.fill(0.0);
    let mut q = SVector::<f64, N>::zeros();
    for j in 0..N {
        let v = p + r * (platform[j] - tool) - base[j];
        let l = v.norm();
        if l <= 0.0 {
            return Err(Error::Singular {
                what: format!("strut {} of zero length", j + 1),
                rcond: 0.0,
            });
        }
        let n = v / l;
        let nb = r.transpose() * n;
        q[j] = l;
        for k in 0..3 {
            jac[(j, 3 * j + k)] = -n[k];
            jac[(j, 3 * N + 3 * j + k)] = nb[k];
        }
    }
    Ok(q)
}

/// `P = p + R (s - t)` and `dP/dx = [I, -[R (s - t)]x E(A, B, C)]`.
pub fn platform_point(
    tool: &Vector3<f64>,
    x: &Vector6<f64>,
    s: &Vector3<f64>,
) -> (Vector3<f64>, SMatrix<f64, 3, 6>) {
    let (p, r) = split_pose(x);
    let v = r * (s - tool);
    let mut d = SMatrix::<f64, 3, 6>::zeros();
    d.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&Matrix3::identity());
    let e = rpy_rate_matrix([x[3], x[4], x[5]]);
    d.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-v.cross_matrix() * e));
    (p + v, d)
}

/// Tool pose coordinates of a platform frame with origin `c` and rotation `r`.
pub fn coords_from_platform_frame(
    tool: &Vector3<f64>,
    c: &Vector3<f64>,
    r: &Matrix3<f64>,
) -> Vector6<f64> {
    let p = c + r * tool;
    let a = Convention::Rpy.from_matrix(r);
    Vector6::new(p.x, p.y, p.z, a[0], a[1], a[2])
}

/// Base joints and platform joints of `N` struts.
pub type Joints<const N: usize> = ([Vector3<f64>; N], [Vector3<f64>; N]);

/// Splits a geometry vector of `N` struts into base and platform joints.
pub fn split<const N: usize>(g: &[f64]) -> Result<Joints<N>> {
    if g.len() != 6 * N {
        return Err(Error::InvalidInput {
            what: "strut machine geometry".into(),
            message: format!("expected {} joint coordinates, got {}", 6 * N, g.len()),
        });
    }
    Ok((
        std::array::from_fn(|j| Vector3::new(g[3 * j], g[3 * j + 1], g[3 * j + 2])),
        std::array::from_fn(|j| {
            let o = 3 * N + 3 * j;
            Vector3::new(g[o], g[o + 1], g[o + 2])
        }),
    ))
}

/// Reads a combination of a strut machine's parameters (indices: `A_j` coordinates
/// `3j..3j+3`, `B'_j` coordinates `3N + 3j..`, zero readings `6N + j`), `dir_at_home[j]`
/// the unit vector of strut `j` at home (base to platform joint) and `rot_at_home` the
/// platform rotation there:
/// * one strut's joint moved along the strut against its zero reading: the strut's
///   direction hardly changes over the states;
/// * one strut's base and platform joints moved alike: the platform hardly turns.
pub fn explain<const N: usize>(
    terms: &[(usize, f64)],
    names: &[String],
    dir_at_home: &[Vector3<f64>; N],
    rot_at_home: &Matrix3<f64>,
) -> Option<String> {
    let strut_of = |i: usize| -> usize {
        if i < 3 * N {
            i / 3
        } else if i < 6 * N {
            (i - 3 * N) / 3
        } else {
            i - 6 * N
        }
    };
    let j = strut_of(terms.first()?.0);
    if terms.iter().any(|(i, _)| strut_of(*i) != j) {
        return None;
    }
    let mut da = Vector3::zeros();
    let mut db = Vector3::zeros();
    let mut dz = 0.0;
    for (i, c) in terms {
        match *i {
            i if i < 3 * N => da[i % 3] += c,
            i if i < 6 * N => db[(i - 3 * N) % 3] += c,
            _ => dz += c,
        }
    }
    let n = dir_at_home[j];
    let strut = names
        .get(6 * N + j)
        .map(|s| s.trim_start_matches("zero(").trim_end_matches(')'))
        .unwrap_or("?");
    let joint = |k: usize| {
        names[k]
            .rsplit_once('.')
            .map(|x| x.0)
            .unwrap_or(&names[k])
            .to_string()
    };
    let along = |d: &Vector3<f64>| d.norm() > 0.0 && (d.normalize().dot(&n)).abs() > 0.9;
    let dbw = rot_at_home * db;
    if dz.abs() > 0.0 && along(&da) && db.norm() < 0.2 * da.norm() {
        return Some(format!(
            "base joint {} moved along strut {strut} trades against zero({strut}): the strut's \
             direction hardly changes over the measured states",
            joint(3 * j)
        ));
    }
    if dz.abs() > 0.0 && along(&dbw) && da.norm() < 0.2 * db.norm() {
        return Some(format!(
            "platform joint {} moved along strut {strut} trades against zero({strut}): the \
             strut's direction hardly changes over the measured states",
            joint(3 * N + 3 * j)
        ));
    }
    if dz.abs() < 0.05 && da.norm() > 0.0 && (da - dbw).norm() < 0.2 * da.norm() {
        return Some(format!(
            "base joint {} and platform joint {} of strut {strut} moved alike (a translation of \
             the strut) change no length: the platform hardly turns over the measured states",
            joint(3 * j),
            joint(3 * N + 3 * j)
        ));
    }
    Some(format!(
        "the joints and zero reading of strut {strut} are poorly separated: its direction \
         and the platform's orientation vary too little over the measured states"
    ))
}
