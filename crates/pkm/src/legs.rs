//! N variable-length struts between base joints and platform joints: the geometry
//! tripods (N = 3) and hexapods (N = 6) share.
//!
//! A strut's length is the distance between its base joint `a_i` (base frame) and its
//! platform joint, `L_i = |p + R (b_i - t) - a_i|` with `p` the tool tip, `R` the platform
//! rotation, `b_i` the platform joint and `t` the tool tip in the platform frame
//! (seed 000 eq. 7, seed 001 eq. 1).

// Parallel fixed-size arrays (struts, rows, columns) are indexed together.
#![allow(clippy::needless_range_loop)]

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::mechanism::ActuatorMotion;

/// Base joints and platform arms (platform joint minus tool tip, platform frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrutSet<const N: usize> {
    /// Base joint centres `a_i` (base frame, mm).
    pub base: [Vector3<f64>; N],
    /// `b_i - t` (platform frame, mm).
    pub arms: [Vector3<f64>; N],
}

impl<const N: usize> StrutSet<N> {
    /// From base joints, platform joints (platform frame) and the tool tip (platform frame).
    pub fn new(base: [Vector3<f64>; N], platform: [Vector3<f64>; N], tool: Vector3<f64>) -> Self {
        StrutSet {
            base,
            arms: std::array::from_fn(|i| platform[i] - tool),
        }
    }

    /// Platform joint centres in the base frame: `p + R (b_i - t)`.
    #[inline]
    pub fn platform_joints(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> [Vector3<f64>; N] {
        std::array::from_fn(|i| p + r * self.arms[i])
    }

    /// A box of tool tips (`[min, max]` per axis, base frame) holding every tip with
    /// platform rotation `r` whose struts are at most `max_length` long: strut `i`
    /// keeps the tip within `max_length[i]` of `a_i - R (b_i - t)`, so the tip lies in
    /// the intersection of those spheres and of their bounding boxes. `None` when the
    /// boxes do not meet (no tip with this rotation).
    pub fn tip_bound(&self, r: &Matrix3<f64>, max_length: &[f64; N]) -> Option<[[f64; 2]; 3]> {
        box_intersection((0..N).map(|i| (self.base[i] - r * self.arms[i], max_length[i])))
    }

    /// Strut lengths for any platform pose. Allocation-free.
    #[inline]
    pub fn lengths(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> SVector<f64, N> {
        SVector::<f64, N>::from_fn(|i, _| (p + r * self.arms[i] - self.base[i]).norm())
    }

    /// Jacobian of the strut lengths with respect to the tool twist `(v, w)` (base
    /// frame): row i is `[n_i^T, (r_i x n_i)^T]`, `n_i` the unit strut vector from base to
    /// platform joint and `r_i = R (b_i - t)`, since `L_i' = n_i . (v + w x r_i)`.
    pub fn twist_jacobian(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> SMatrix<f64, N, 6> {
        let mut j = SMatrix::<f64, N, 6>::zeros();
        for i in 0..N {
            let ri = r * self.arms[i];
            let d = p + ri - self.base[i];
            let n = d / d.norm();
            let m = ri.cross(&n);
            for k in 0..3 {
                j[(i, k)] = n[k];
                j[(i, 3 + k)] = m[k];
            }
        }
        j
    }

    /// Exact lengths, rates and accelerations for tool-tip velocity `v`, acceleration
    /// `a`, angular velocity `w` and angular acceleration `al` (base frame):
    /// `d' = v + w x r`, `d'' = a + al x r + w x (w x r)`, `L' = n . d'`,
    /// `L'' = (|d'|^2 - L'^2) / L + n . d''`.
    #[inline]
    pub fn motion(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        v: &Vector3<f64>,
        w: &Vector3<f64>,
        a: &Vector3<f64>,
        al: &Vector3<f64>,
    ) -> ActuatorMotion<N> {
        let mut out = ActuatorMotion {
            q: SVector::zeros(),
            qd: SVector::zeros(),
            qdd: SVector::zeros(),
        };
        for i in 0..N {
            let ri = r * self.arms[i];
            let d = p + ri - self.base[i];
            let l = d.norm();
            let n = d / l;
            let dd = v + w.cross(&ri);
            let ddd = a + al.cross(&ri) + w.cross(&w.cross(&ri));
            let ld = n.dot(&dd);
            out.q[i] = l;
            out.qd[i] = ld;
            out.qdd[i] = (dd.norm_squared() - ld * ld) / l + n.dot(&ddd);
        }
        out
    }
}

/// The same geometry laid out by coordinate (structure of arrays) for the hot length
/// computation: the six strut lengths of a pose vectorise over struts (SSE2 by
/// default, wider with `-C target-cpu=native`) instead of working on 3-vectors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrutSoa<const N: usize> {
    ax: [f64; N],
    ay: [f64; N],
    az: [f64; N],
    bx: [f64; N],
    by: [f64; N],
    bz: [f64; N],
}

impl<const N: usize> From<&StrutSet<N>> for StrutSoa<N> {
    fn from(s: &StrutSet<N>) -> Self {
        StrutSoa {
            ax: std::array::from_fn(|i| s.arms[i].x),
            ay: std::array::from_fn(|i| s.arms[i].y),
            az: std::array::from_fn(|i| s.arms[i].z),
            bx: std::array::from_fn(|i| s.base[i].x),
            by: std::array::from_fn(|i| s.base[i].y),
            bz: std::array::from_fn(|i| s.base[i].z),
        }
    }
}

impl<const N: usize> StrutSoa<N> {
    /// Strut lengths `|p + R arm_i - base_i|` (the same as [`StrutSet::lengths`]).
    #[inline]
    pub fn lengths(&self, p: &Vector3<f64>, r: &Matrix3<f64>) -> SVector<f64, N> {
        let mut out = [0.0; N];
        for i in 0..N {
            let (x, y, z) = (self.ax[i], self.ay[i], self.az[i]);
            let dx = r[(0, 0)] * x + r[(0, 1)] * y + r[(0, 2)] * z + (p.x - self.bx[i]);
            let dy = r[(1, 0)] * x + r[(1, 1)] * y + r[(1, 2)] * z + (p.y - self.by[i]);
            let dz = r[(2, 0)] * x + r[(2, 1)] * y + r[(2, 2)] * z + (p.z - self.bz[i]);
            out[i] = (dx * dx + dy * dy + dz * dz).sqrt();
        }
        SVector::<f64, N>::from(out)
    }

    /// [`StrutSet::motion`] laid out by coordinate: the same operations in the same
    /// order on every strut (so the same bits), as loops over struts the compiler
    /// vectorises (wider where the caller enables AVX-512, `Hexapod::motion_at`).
    /// Per strut (seed 001 eq. 1 differentiated twice): `d = p + R b'_i - a_i`,
    /// `L = |d|`, `n = d / L`, `d' = v + w x R b'_i`,
    /// `d'' = a + alpha x R b'_i + w x (w x R b'_i)`, `L' = n . d'`,
    /// `L'' = (|d'|^2 - L'^2) / L + n . d''`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub fn motion(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        v: &Vector3<f64>,
        w: &Vector3<f64>,
        a: &Vector3<f64>,
        al: &Vector3<f64>,
    ) -> ActuatorMotion<N> {
        let (mut q, mut qd, mut qdd) = ([0.0; N], [0.0; N], [0.0; N]);
        let r: [f64; 9] = std::array::from_fn(|k| r[(k / 3, k % 3)]);
        let twist = [v, w, a, al].map(|u| [u.x, u.y, u.z]);
        for i in 0..N {
            let arm = [self.ax[i], self.ay[i], self.az[i]];
            let base = [self.bx[i], self.by[i], self.bz[i]];
            let m = strut_motion(&r, &[p.x, p.y, p.z], arm, base, &twist);
            (q[i], qd[i], qdd[i]) = (m.l, m.ld, m.ldd);
        }
        ActuatorMotion {
            q: SVector::from(q),
            qd: SVector::from(qd),
            qdd: SVector::from(qdd),
        }
    }

    /// Strut lengths of many poses (tool tips `p`, rotations `r`) into `out`, computed
    /// eight poses at a time across SIMD lanes (the poses are transposed into lanes,
    /// so the arithmetic and the square roots vectorise over poses).
    ///
    /// # Panics
    /// When the three slices differ in length.
    pub fn lengths_batch(
        &self,
        p: &[Vector3<f64>],
        r: &[Matrix3<f64>],
        out: &mut [SVector<f64, N>],
    ) {
        const L: usize = 8;
        assert!(
            p.len() == r.len() && p.len() == out.len(),
            "batch slices differ in length"
        );
        let n = p.len();
        let mut k0 = 0;
        while k0 + L <= n {
            // Pose scalars by lane: 3 of p and 9 of R.
            let mut pv = [[0.0; L]; 3];
            let mut rv = [[0.0; L]; 9];
            for l in 0..L {
                let (pp, rr) = (&p[k0 + l], &r[k0 + l]);
                for c in 0..3 {
                    pv[c][l] = pp[c];
                }
                for e in 0..9 {
                    rv[e][l] = rr[(e % 3, e / 3)];
                }
            }
            for i in 0..N {
                let (x, y, z) = (self.ax[i], self.ay[i], self.az[i]);
                let (bx, by, bz) = (self.bx[i], self.by[i], self.bz[i]);
                let mut len = [0.0; L];
                for l in 0..L {
                    // rv[e] holds R(e % 3, e / 3): column-major.
                    let dx = rv[0][l] * x + rv[3][l] * y + rv[6][l] * z + (pv[0][l] - bx);
                    let dy = rv[1][l] * x + rv[4][l] * y + rv[7][l] * z + (pv[1][l] - by);
                    let dz = rv[2][l] * x + rv[5][l] * y + rv[8][l] * z + (pv[2][l] - bz);
                    len[l] = (dx * dx + dy * dy + dz * dz).sqrt();
                }
                for l in 0..L {
                    out[k0 + l][i] = len[l];
                }
            }
            k0 += L;
        }
        for k in k0..n {
            out[k] = self.lengths(&p[k], &r[k]);
        }
    }

    /// Strut lengths and the twist Jacobian (rotation columns divided by `lc`) in one
    /// pass: row i is `[n_i^T, (R arm_i x n_i)^T / lc]`, as [`StrutSet::twist_jacobian`].
    #[inline]
    pub fn lengths_and_jacobian(
        &self,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
        lc: f64,
    ) -> (SVector<f64, N>, SMatrix<f64, N, 6>) {
        let mut l = [0.0; N];
        let mut j = SMatrix::<f64, N, 6>::zeros();
        let inv_lc = 1.0 / lc;
        for i in 0..N {
            let (x, y, z) = (self.ax[i], self.ay[i], self.az[i]);
            let rx = r[(0, 0)] * x + r[(0, 1)] * y + r[(0, 2)] * z;
            let ry = r[(1, 0)] * x + r[(1, 1)] * y + r[(1, 2)] * z;
            let rz = r[(2, 0)] * x + r[(2, 1)] * y + r[(2, 2)] * z;
            let dx = rx + (p.x - self.bx[i]);
            let dy = ry + (p.y - self.by[i]);
            let dz = rz + (p.z - self.bz[i]);
            let len = (dx * dx + dy * dy + dz * dz).sqrt();
            l[i] = len;
            let inv = 1.0 / len;
            let (nx, ny, nz) = (dx * inv, dy * inv, dz * inv);
            j[(i, 0)] = nx;
            j[(i, 1)] = ny;
            j[(i, 2)] = nz;
            j[(i, 3)] = (ry * nz - rz * ny) * inv_lc;
            j[(i, 4)] = (rz * nx - rx * nz) * inv_lc;
            j[(i, 5)] = (rx * ny - ry * nx) * inv_lc;
        }
        (SVector::<f64, N>::from(l), j)
    }
}

/// The intersection of the boxes `centre +- half_width` (per axis, `[min, max]`), or
/// `None` when they do not meet or none bounds an axis.
pub fn box_intersection(
    boxes: impl IntoIterator<Item = (Vector3<f64>, f64)>,
) -> Option<[[f64; 2]; 3]> {
    let mut b = [[f64::NEG_INFINITY, f64::INFINITY]; 3];
    for (c, h) in boxes {
        for k in 0..3 {
            b[k][0] = b[k][0].max(c[k] - h);
            b[k][1] = b[k][1].min(c[k] + h);
        }
    }
    b.iter()
        .all(|x| x[0] <= x[1] && x[0].is_finite() && x[1].is_finite())
        .then_some(b)
}

/// A twist Jacobian (`N x 6`, columns v then w) turned into the Jacobian of spatial
/// coordinates `X..C`: the rotation columns times `E(A, B, C)`, the map of the A, B, C
/// rates to the angular velocity (`w = E [A', B', C']`).
pub fn twist_to_coords<const N: usize>(j: &mut SMatrix<f64, N, 6>, x: &SVector<f64, 6>) {
    let e = crate::rotation::rpy_rate_matrix([x[3], x[4], x[5]]);
    let rot = j.fixed_view::<N, 3>(0, 3) * e;
    j.fixed_view_mut::<N, 3>(0, 3).copy_from(&rot);
}

/// Tool tip and rotation of spatial pose coordinates `X, Y, Z, A, B, C`.
#[inline]
pub fn split_pose(x: &SVector<f64, 6>) -> (Vector3<f64>, Matrix3<f64>) {
    (
        Vector3::new(x[0], x[1], x[2]),
        crate::rotation::rpy_matrix(x[3], x[4], x[5]),
    )
}

/// The tool pose of spatial coordinates `X..C`.
pub fn spatial_tool_pose(x: &SVector<f64, 6>) -> crate::pose::Pose {
    let (p, r) = split_pose(x);
    crate::pose::pose_from_parts(p, &r)
}

/// Spatial coordinates `X..C` of a tool pose; without a given orientation, the angles
/// of `home` are kept (the orientation a spatial machine holds by default).
pub fn spatial_coords_from_pose(
    pose: &crate::pose::Pose,
    orientation_given: bool,
    home: &SVector<f64, 6>,
) -> SVector<f64, 6> {
    let p = pose.translation.vector;
    let a = if orientation_given {
        crate::rotation::Convention::Rpy.from_matrix(&crate::pose::rotation_matrix(pose))
    } else {
        [home[3], home[4], home[5]]
    };
    SVector::<f64, 6>::new(p.x, p.y, p.z, a[0], a[1], a[2])
}

impl<const N: usize> StrutSet<N> {
    /// `dL/dx` for spatial coordinates `X..C`: `J_twist diag(I, E(A, B, C))`.
    pub fn coords_jacobian(&self, x: &SVector<f64, 6>) -> SMatrix<f64, N, 6> {
        let (p, r) = split_pose(x);
        let mut j = self.twist_jacobian(&p, &r);
        twist_to_coords(&mut j, x);
        j
    }

    /// Exact lengths, rates and accelerations for spatial coordinates `X..C` moving
    /// with rates `xd` and accelerations `xdd`.
    #[inline]
    pub fn coords_motion(
        &self,
        x: &SVector<f64, 6>,
        xd: &SVector<f64, 6>,
        xdd: &SVector<f64, 6>,
    ) -> ActuatorMotion<N> {
        let (p, r) = split_pose(x);
        self.coords_motion_at(x, xd, xdd, &p, &r)
    }

    /// [`StrutSet::coords_motion`] with the pose already split into its position `p`
    /// and rotation `r` ([`split_pose`]).
    pub fn coords_motion_at(
        &self,
        x: &SVector<f64, 6>,
        xd: &SVector<f64, 6>,
        xdd: &SVector<f64, 6>,
        p: &Vector3<f64>,
        r: &Matrix3<f64>,
    ) -> ActuatorMotion<N> {
        let [v, w, a, al] = coords_twist(x, xd, xdd);
        self.motion(p, r, &v, &w, &a, &al)
    }
}

/// One strut's vector, length, rate and acceleration ([`StrutSoa::motion`]'s formula)
/// on any number type (`f64`, or an AVX-512 register of eight poses:
/// [`crate::lane`]), so the hexapod's motion kernel computes lane by lane what the
/// scalar code does.
pub(crate) struct StrutMotion<T> {
    /// The strut vector `d = p + R b' - a`.
    pub d: [T; 3],
    /// Its length `L = |d|`.
    pub l: T,
    /// `L' = n . d'`.
    pub ld: T,
    /// `L'' = (|d'|^2 - L'^2) / L + n . d''`.
    pub ldd: T,
}

/// [`StrutMotion`] of the strut from base joint `base` to platform arm `arm` (platform
/// frame), for the pose `p`, `r` (rotation row by row) moving with the twist
/// `[v, w, a, alpha]`: `R b'` summed as nalgebra's matrix-vector product sums it
/// (column by column), then the formula of [`StrutSoa::motion`].
#[inline(always)]
pub(crate) fn strut_motion<T: crate::lane::Lane, U: Copy + Into<T>>(
    r: &[T; 9],
    p: &[T; 3],
    arm: [U; 3],
    base: [U; 3],
    twist: &[[T; 3]; 4],
) -> StrutMotion<T> {
    let [x, y, z] = arm.map(Into::into);
    let [v, w, a, al] = twist;
    let row = |k: usize| {
        r[3 * k]
            .mul(x)
            .add(r[3 * k + 1].mul(y))
            .add(r[3 * k + 2].mul(z))
    };
    let (rx, ry, rz) = (row(0), row(1), row(2));
    let d = [
        p[0].add(rx).sub(base[0].into()),
        p[1].add(ry).sub(base[1].into()),
        p[2].add(rz).sub(base[2].into()),
    ];
    let [dx, dy, dz] = d;
    let l = dx.mul(dx).add(dy.mul(dy)).add(dz.mul(dz)).sqrt();
    let (nx, ny, nz) = (dx.div(l), dy.div(l), dz.div(l));
    // w x R b'_i, alpha x R b'_i, w x (w x R b'_i).
    let cross = |u: &[T; 3], (px, py, pz): (T, T, T)| {
        (
            u[1].mul(pz).sub(u[2].mul(py)),
            u[2].mul(px).sub(u[0].mul(pz)),
            u[0].mul(py).sub(u[1].mul(px)),
        )
    };
    let (cx, cy, cz) = cross(w, (rx, ry, rz));
    let (ex, ey, ez) = cross(al, (rx, ry, rz));
    let (fx, fy, fz) = cross(w, (cx, cy, cz));
    let (ux, uy, uz) = (v[0].add(cx), v[1].add(cy), v[2].add(cz));
    let (gx, gy, gz) = (
        a[0].add(ex).add(fx),
        a[1].add(ey).add(fy),
        a[2].add(ez).add(fz),
    );
    let ld = nx.mul(ux).add(ny.mul(uy)).add(nz.mul(uz));
    let ldd = ux
        .mul(ux)
        .add(uy.mul(uy))
        .add(uz.mul(uz))
        .sub(ld.mul(ld))
        .div(l)
        .add(nx.mul(gx).add(ny.mul(gy)).add(nz.mul(gz)));
    StrutMotion { d, l, ld, ldd }
}

/// The platform's velocity `v`, angular velocity `w`, acceleration `a` and angular
/// acceleration `alpha` (base frame) from spatial coordinates `X..C` moving with rates
/// `xd` and accelerations `xdd` ([`crate::rotation::rpy_angular_motion`]).
#[inline]
pub fn coords_twist(
    x: &SVector<f64, 6>,
    xd: &SVector<f64, 6>,
    xdd: &SVector<f64, 6>,
) -> [Vector3<f64>; 4] {
    let ad = xd.fixed_rows::<3>(3).into_owned();
    let add = xdd.fixed_rows::<3>(3).into_owned();
    let (w, al) = crate::rotation::rpy_angular_motion([x[3], x[4], x[5]], &ad, &add);
    [
        xd.fixed_rows::<3>(0).into_owned(),
        w,
        xdd.fixed_rows::<3>(0).into_owned(),
        al,
    ]
}
