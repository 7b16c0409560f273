//! Strut machines (hexapod, translational tripod): their identifiable parameters and
//! the strut equations `L_j = |p + R (B'_j - t) - A_j|` (seed 001 eq. 1 with the tool
//! offset `t`), written once. A machine implements [`StrutMachine`] (its joints, tool
//! offset, calibrated zero lengths, and how to rebuild itself with other joints) and
//! gets [`Identifiable`] from it.

use nalgebra::{DMatrix, Matrix3, SMatrix, SVector, Vector3, Vector6};

use super::Identifiable;
use crate::error::{Error, Result};
use crate::legs::split_pose;
use crate::machine::StrutGeometry;
use crate::mechanism::Mechanism;
use crate::rotation::{rpy_rate_matrix, Convention};

/// A machine of `A` struts between base joints and platform joints, pose X..C.
pub trait StrutMachine<const A: usize>: Mechanism<6, A> + Sized + Sync {
    /// Each strut's name, joint names and joint centres (base frame, platform frame).
    fn struts(&self) -> [StrutGeometry; A];

    /// The tool tip in the platform frame (mm).
    fn tool(&self) -> Vector3<f64>;

    /// The same machine with other joint centres (names, limits and home kept).
    fn with_struts(&self, struts: &[StrutGeometry; A]) -> Self;

    /// Strut lengths at the control's zero readings from the file's `[calibration]`.
    fn calibrated_zero(&self) -> Option<SVector<f64, A>>;

    /// Parameters that trade exactly against others for every measurement this
    /// machine can give and must be held for an identification to be determined
    /// (indices of [`super::parameter_names`]); none by default.
    fn must_hold(&self) -> Vec<usize> {
        Vec::new()
    }

    /// Moves the joint centres in place (see [`StrutMachine::with_struts`]); a type can
    /// do it without allocating.
    fn set_joints(&mut self, base: &[Vector3<f64>; A], platform: &[Vector3<f64>; A]) {
        let mut s = self.struts();
        for (st, (b, p)) in s.iter_mut().zip(base.iter().zip(platform)) {
            st.base = *b;
            st.platform = *p;
        }
        *self = self.with_struts(&s);
    }

    /// Whether the platform turns over a campaign's states (a hexapod's does; a
    /// translational tripod's never does, which decides what a weak combination of
    /// its parameters means).
    fn platform_turns(&self) -> bool {
        true
    }

    /// The joint centres as arrays.
    fn joints(&self) -> Joints<A> {
        let s = self.struts();
        (
            std::array::from_fn(|j| s[j].base),
            std::array::from_fn(|j| s[j].platform),
        )
    }
}

impl<M: StrutMachine<A>, const A: usize> Identifiable<6, A> for M {
    /// `A.x, A.y, A.z` of every strut's base joint, then `B.x, ...` of its platform joint
    /// (named as in the file).
    fn geometry_names(&self) -> Vec<String> {
        let s = self.struts();
        let b: Vec<&str> = s.iter().map(|s| s.base_name.as_str()).collect();
        let p: Vec<&str> = s.iter().map(|s| s.platform_name.as_str()).collect();
        let n: Vec<&str> = s.iter().map(|s| s.name.as_str()).collect();
        names(&b, &p, &n)
    }

    fn geometry(&self) -> Vec<f64> {
        let s = self.struts();
        let a = s.iter().flat_map(|s| s.base.iter().copied());
        let b = s.iter().flat_map(|s| s.platform.iter().copied());
        a.chain(b).collect()
    }

    fn with_geometry(&self, g: &[f64]) -> Result<Self> {
        let (base, platform) = split::<A>(g)?;
        let mut s = self.struts();
        for (j, st) in s.iter_mut().enumerate() {
            st.base = base[j];
            st.platform = platform[j];
        }
        Ok(self.with_struts(&s))
    }

    fn inverse_with_geometry_jacobian(
        &self,
        x: &Vector6<f64>,
        jac: &mut DMatrix<f64>,
    ) -> Result<SVector<f64, A>> {
        let (base, platform) = self.joints();
        lengths_with_jacobian(&base, &platform, &self.tool(), x, jac)
    }

    fn platform_point(
        &self,
        x: &Vector6<f64>,
        s: &Vector3<f64>,
    ) -> (Vector3<f64>, SMatrix<f64, 3, 6>) {
        platform_point(&self.tool(), x, s)
    }

    fn coords_from_platform_frame(&self, c: &Vector3<f64>, r: &Matrix3<f64>) -> Vector6<f64> {
        coords_from_platform_frame(&self.tool(), c, r)
    }

    fn explain(&self, terms: &[(usize, f64)]) -> Option<String> {
        let (p, r) = split_pose(&self.info().home());
        let (base, platform) = self.joints();
        let t = self.tool();
        let dirs: [Vector3<f64>; A] =
            std::array::from_fn(|j| (p + r * (platform[j] - t) - base[j]).normalize());
        explain(
            terms,
            &super::parameter_names(self),
            &dirs,
            &r,
            self.platform_turns(),
        )
    }

    /// The file's `[calibration] zero_lengths`, else the strut lengths at home.
    fn zero_readings(&self) -> Result<SVector<f64, A>> {
        match self.calibrated_zero() {
            Some(z) => Ok(z),
            None => self.inverse(&self.info().home()),
        }
    }
}

/// Length of one strut at tool pose `(p, r)` and its gradients with respect to the base
/// joint `a` and the platform joint `b`: `-n` and `R^T n`, `n` the unit strut vector.
#[inline]
pub fn strut_length(
    p: &Vector3<f64>,
    r: &Matrix3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    tool: &Vector3<f64>,
) -> (f64, Vector3<f64>, Vector3<f64>) {
    let v = p + r * (b - tool) - a;
    let l = v.norm();
    let n = v / l;
    (l, -n, r.transpose() * n)
}

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
        let (l, da, db) = strut_length(&p, &r, &base[j], &platform[j], tool);
        if !(l > 0.0) {
            return Err(Error::Singular {
                what: format!("strut {} of zero length", j + 1),
                rcond: 0.0,
            });
        }
        q[j] = l;
        for k in 0..3 {
            jac[(j, 3 * j + k)] = da[k];
            jac[(j, 3 * N + 3 * j + k)] = db[k];
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
    platform_turns: bool,
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
    let mut t = StrutTerms::<N> {
        j,
        da: Vector3::zeros(),
        db: Vector3::zeros(),
        dz: 0.0,
        strut: names
            .get(6 * N + j)
            .map(|s| s.trim_start_matches("zero(").trim_end_matches(')'))
            .unwrap_or("?"),
        names,
    };
    for (i, c) in terms {
        match *i {
            i if i < 3 * N => t.da[i % 3] += c,
            i if i < 6 * N => t.db[(i - 3 * N) % 3] += c,
            _ => t.dz += c,
        }
    }
    let reason = t.trade_off(&dir_at_home[j], &(rot_at_home * t.db), platform_turns);
    Some(reason.unwrap_or_else(|| t.poorly_separated(platform_turns)))
}

/// The terms of a combination of one strut `j`'s parameters: its base joint's and
/// platform joint's moves and its zero reading's, and the strut's name.
struct StrutTerms<'a, const N: usize> {
    j: usize,
    da: Vector3<f64>,
    db: Vector3<f64>,
    dz: f64,
    strut: &'a str,
    names: &'a [String],
}

impl<const N: usize> StrutTerms<'_, N> {
    /// The name of the joint whose first coordinate is parameter `k`.
    fn joint(&self, k: usize) -> String {
        self.names[k]
            .rsplit_once('.')
            .map(|x| x.0)
            .unwrap_or(&self.names[k])
            .to_string()
    }

    /// The known trade-offs (`n` the strut's direction at home, `dbw` the platform
    /// joint's move in the base frame): a joint along the strut against the zero
    /// reading, or both joints moved alike.
    fn trade_off(
        &self,
        n: &Vector3<f64>,
        dbw: &Vector3<f64>,
        platform_turns: bool,
    ) -> Option<String> {
        let (j, da, db, dz, strut) = (self.j, &self.da, &self.db, self.dz, self.strut);
        let along = |d: &Vector3<f64>| d.norm() > 0.0 && (d.normalize().dot(n)).abs() > 0.9;
        if dz.abs() > 0.0 && along(da) && db.norm() < 0.2 * da.norm() {
            return Some(format!(
                "base joint {} moved along strut {strut} trades against zero({strut}): the strut's \
                 direction hardly changes over the measured states",
                self.joint(3 * j)
            ));
        }
        if dz.abs() > 0.0 && along(dbw) && da.norm() < 0.2 * db.norm() {
            return Some(format!(
                "platform joint {} moved along strut {strut} trades against zero({strut}): the \
                 strut's direction hardly changes over the measured states",
                self.joint(3 * N + 3 * j)
            ));
        }
        if dz.abs() < 0.05 && da.norm() > 0.0 && (da - dbw).norm() < 0.2 * da.norm() {
            let why = if platform_turns {
                "the platform hardly turns over the measured states"
            } else {
                "the platform never turns, so no measurement tells them apart"
            };
            return Some(format!(
                "base joint {} and platform joint {} of strut {strut} moved alike (a translation of \
                 the strut) change no length: {why}",
                self.joint(3 * j),
                self.joint(3 * N + 3 * j)
            ));
        }
        None
    }

    /// The reason for any other combination: the parameters it holds are poorly
    /// separated.
    fn poorly_separated(&self, platform_turns: bool) -> String {
        let (j, strut) = (self.j, self.strut);
        // Name only what the combination holds (a held parameter is not in it).
        let mut parts = Vec::new();
        if self.da.norm() > 0.0 {
            parts.push(format!("base joint {}", self.joint(3 * j)));
        }
        if self.db.norm() > 0.0 {
            parts.push(format!("platform joint {}", self.joint(3 * N + 3 * j)));
        }
        if self.dz != 0.0 {
            parts.push(format!("the zero reading zero({strut})"));
        }
        let why = if platform_turns {
            "its direction and the platform's orientation vary too little over the measured states"
        } else {
            "its direction varies too little over the measured states (the platform never turns)"
        };
        format!(
            "{} of strut {strut} {} poorly separated: {why}",
            parts.join(" and "),
            if parts.len() > 1 { "are" } else { "is" }
        )
    }
}
