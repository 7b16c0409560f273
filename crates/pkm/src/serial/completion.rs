//! Completion of a link's angular deviations (seed 003 eq. 3): from three measured
//! angular deviations, the six others that keep the direction-cosine block
//! orthonormal.
//!
//! The unknowns are the six cosines `m_ab = cos(phi_ab + alpha_ab)`; the equations are
//! the independent orthonormality conditions of the block's columns — three unit norms
//! and three mutual orthogonalities (the paper prints one orthogonality twice and mixes
//! a row norm in; `M^T M = I` is the set used here). They are solved by damped Newton
//! from starts around the nominal block; every root found is kept and the one nearest
//! the nominal (smallest `sum alpha^2`) is returned.
//!
//! Two properties of the paper's parametrisation a user should know:
//! * the angle between two nominally aligned axes (`phi = 0` or `180 deg`) is not
//!   signed: `cos(phi + alpha) = cos(phi - alpha)`, so pkm reports such a deviation as
//!   `alpha >= 0` (aligned) or `alpha <= 0` (opposed), i.e. `acos(m) - phi`;
//! * for the same reason three measured angles can leave a sign open (two mirror roots
//!   at the same distance from nominal): the root with the larger cosines first, in
//!   row-major order, is chosen, and [`Completion::ambiguous`] says so.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

use crate::error::{Error, Result};
use crate::linalg::SmallLu;

/// A completed block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Completion {
    /// All nine angular deviations (rad), the measured ones as given.
    pub alpha: Matrix3<f64>,
    /// The orthonormal block `cos(phi + alpha)`.
    pub block: Matrix3<f64>,
    /// Largest `|M^T M - I|` entry.
    pub residual: f64,
    /// Another root lies as near the nominal as this one (see the module text).
    pub ambiguous: bool,
}

fn equations(m: &Matrix3<f64>) -> SVector<f64, 6> {
    let c = |j: usize| m.column(j).into_owned();
    let (c0, c1, c2) = (c(0), c(1), c(2));
    SVector::<f64, 6>::from([
        c0.dot(&c0) - 1.0,
        c1.dot(&c1) - 1.0,
        c2.dot(&c2) - 1.0,
        c0.dot(&c1),
        c0.dot(&c2),
        c1.dot(&c2),
    ])
}

/// `d equations / d m_ab` for the unknown entries.
fn jacobian(m: &Matrix3<f64>, unknown: &[(usize, usize); 6]) -> SMatrix<f64, 6, 6> {
    let pairs = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
    SMatrix::<f64, 6, 6>::from_fn(|e, u| {
        let (a, b) = unknown[u];
        let (j, k) = pairs[e];
        // d (c_j . c_k) / d m_ab = [b == j] c_k[a] + [b == k] c_j[a]
        let mut v = 0.0;
        if b == j {
            v += m[(a, k)];
        }
        if b == k {
            v += m[(a, j)];
        }
        v
    })
}

/// Completes the angular deviations of a link whose nominal direction cosines are
/// `nominal`, given the deviations at the three `measured` positions (row: axis of
/// `S_i`, column: axis of `S_i*`), e.g. the angles of `X*` with `X` and `Y` and of
/// `Z*` with `Z`: `[((0, 0), a1), ((1, 0), a2), ((2, 2), a3)]`.
///
/// Fails with [`Error::InvalidInput`] for repeated positions and with
/// [`Error::NotAttainable`] when no orthonormal block has those angles (inconsistent
/// measurements, e.g. a column whose two measured cosines already exceed unit length).
pub fn complete(
    nominal: &Matrix3<f64>,
    measured: &[((usize, usize), f64); 3],
) -> Result<Completion> {
    let (known, unknown) = positions(measured)?;
    let phi = nominal.map(|c| c.clamp(-1.0, 1.0).acos());
    let mut m0 = *nominal;
    for ((r, c), a) in measured {
        m0[(*r, *c)] = (phi[(*r, *c)] + a).cos();
    }
    let mut roots = roots(&m0, measured, &unknown);
    let dist = |m: &Matrix3<f64>| (m - nominal).norm_squared();
    roots.sort_by(|a, b| {
        dist(a).total_cmp(&dist(b)).then_with(|| {
            b.as_slice()
                .partial_cmp(a.as_slice())
                .unwrap_or(std::cmp::Ordering::Equal)
        })
    });
    let Some(best) = roots.first().copied() else {
        return Err(Error::NotAttainable {
            reason: format!(
                "no orthonormal direction-cosine block has the measured angular deviations \
                 {:?} (inconsistent measurements)",
                measured
                    .iter()
                    .map(|(p, a)| (*p, a.to_degrees()))
                    .collect::<Vec<_>>()
            )
            .into(),
        });
    };
    let ambiguous = roots
        .get(1)
        .is_some_and(|m| (dist(m) - dist(&best)).abs() <= 1e-12 * (1.0 + dist(&best)));
    let residual = (best.transpose() * best - Matrix3::identity()).amax();
    Ok(Completion {
        alpha: alpha_of(&best, &known, measured, &phi),
        block: best,
        residual,
        ambiguous,
    })
}

/// Which of the nine entries are measured.
type Known = [[bool; 3]; 3];

/// The six entries not measured, row-major.
type Unknown = [(usize, usize); 6];

/// Checks the measured positions are distinct and in range; returns which entries are
/// known and the six unknown ones in row-major order.
fn positions(measured: &[((usize, usize), f64); 3]) -> Result<(Known, Unknown)> {
    let mut known = [[false; 3]; 3];
    for ((r, c), _) in measured {
        if *r > 2 || *c > 2 || known[*r][*c] {
            return Err(Error::InvalidInput {
                what: "measured angular deviations".into(),
                message: "three distinct positions (row, column) in 0..3 are needed".into(),
            });
        }
        known[*r][*c] = true;
    }
    let mut unknown = [(0, 0); 6];
    let free = (0..9)
        .map(|e| (e / 3, e % 3))
        .filter(|&(r, c)| !known[r][c]);
    for (slot, rc) in unknown.iter_mut().zip(free) {
        *slot = rc;
    }
    Ok((known, unknown))
}

/// Damped Newton on the `unknown` entries from `start` to an orthonormal block.
fn solve_block(start: Matrix3<f64>, unknown: &Unknown) -> Option<Matrix3<f64>> {
    let mut m = start;
    let mut f = equations(&m);
    for _ in 0..60 {
        if f.amax() < 1e-15 {
            return Some(m);
        }
        let j = jacobian(&m, unknown);
        // Levenberg-Marquardt damping: the Jacobian is singular at the nominal
        // block when a measured axis pair is aligned.
        let jt = j.transpose();
        let mut a = jt * j;
        let lambda = 1e-12 + 1e-3 * f.norm_squared();
        for d in 0..6 {
            a[(d, d)] += lambda;
        }
        let step = SmallLu::new(&a)?.solve(&(jt * f));
        let mut t = 1.0;
        let mut ok = false;
        for _ in 0..20 {
            let mut mn = m;
            for (u, (r, c)) in unknown.iter().enumerate() {
                mn[(*r, *c)] = (m[(*r, *c)] - t * step[u]).clamp(-1.0, 1.0);
            }
            let fnew = equations(&mn);
            if fnew.norm() < f.norm() {
                m = mn;
                f = fnew;
                ok = true;
                break;
            }
            t *= 0.5;
        }
        if !ok {
            break;
        }
    }
    (f.amax() < 1e-13).then_some(m)
}

/// Every distinct proper-rotation root found from starts around `m0`, the nominal block
/// with the measured cosines.
fn roots(
    m0: &Matrix3<f64>,
    measured: &[((usize, usize), f64); 3],
    unknown: &Unknown,
) -> Vec<Matrix3<f64>> {
    // Starts: the nominal block with the measured cosines, nudged both ways on every
    // unknown (a root can sit on either side of a nominal zero).
    let mut roots: Vec<Matrix3<f64>> = Vec::new();
    let nudge = (1.0 - m0.iter().fold(1.0f64, |a, v| a.min(v.abs().max(1e-300)))).max(1e-6);
    let size = measured
        .iter()
        .map(|(_, a)| a.abs())
        .fold(1e-6, f64::max)
        .max(nudge.min(1e-3));
    for pattern in 0..(1u32 << 6) {
        let mut s = *m0;
        for (u, (r, c)) in unknown.iter().enumerate() {
            let sign = if pattern >> u & 1 == 1 { -1.0 } else { 1.0 };
            s[(*r, *c)] = (s[(*r, *c)] + sign * size).clamp(-1.0, 1.0);
        }
        if let Some(m) = solve_block(s, unknown) {
            // M^T M = I also has reflections: keep proper rotations only.
            if m.determinant() > 0.0 && !roots.iter().any(|x| (x - m).amax() < 1e-9) {
                roots.push(m);
            }
        }
    }
    roots
}

/// The nine angular deviations of block `m`: the measured ones as given, the others
/// `acos(m) - phi`.
fn alpha_of(
    m: &Matrix3<f64>,
    known: &Known,
    measured: &[((usize, usize), f64); 3],
    phi: &Matrix3<f64>,
) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| {
        if known[r][c] {
            measured
                .iter()
                .find(|((a, b), _)| *a == r && *b == c)
                .map(|x| x.1)
                .unwrap_or(0.0)
        } else {
            m[(r, c)].clamp(-1.0, 1.0).acos() - phi[(r, c)]
        }
    })
}

/// The rotation-preserving completion used by the accuracy engine: a link whose three
/// angular deviations at `positions` are measured or toleranced turns rigidly, its block
/// `M = N exp([w]x)` (`N` the nominal block, `w` a small rotation in the link's output
/// frame) with the three measured entries `M_rc = cos(phi_rc + alpha_rc)`; the six
/// others follow (eq. 3, orthonormality, solved for the root nearest the nominal).
///
/// The triple must determine `w` to first order: the 3 x 3 matrix
/// `d M_rc / d w = (N [e_j]x)_rc` must be regular. It is not when a position is an
/// aligned entry (`N_rc = +-1`: `cos(0 + alpha)` has no first-order effect and no sign)
/// or when two positions measure the same rotation component (a full row or column of
/// the block is such a triple: it leaves the rotation about that axis open).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TripleCompletion {
    nominal: Matrix3<f64>,
    phi: Matrix3<f64>,
    positions: [(usize, usize); 3],
    /// Inverse of `d M_rc / d w` at the nominal block.
    j0_inv: Matrix3<f64>,
}

fn skew_basis(j: usize) -> Matrix3<f64> {
    let mut e = nalgebra::Vector3::zeros();
    e[j] = 1.0;
    nalgebra::Matrix3::new(0.0, -e.z, e.y, e.z, 0.0, -e.x, -e.y, e.x, 0.0)
}

const AXIS: [char; 3] = ['x', 'y', 'z'];

impl TripleCompletion {
    /// Prepares the completion of a link with nominal block `nominal` from the
    /// deviations at `positions` (row: axis of `S_i`, column: axis of `S_i*`); the error
    /// says why a triple cannot determine the link's rotation.
    pub fn new(
        nominal: &Matrix3<f64>,
        positions: [(usize, usize); 3],
    ) -> std::result::Result<Self, String> {
        let name = |(r, c): (usize, usize)| format!("alpha_{}{}", AXIS[r], AXIS[c]);
        for (i, &(r, c)) in positions.iter().enumerate() {
            if r > 2 || c > 2 || positions[..i].contains(&(r, c)) {
                return Err("three distinct positions (row, column) in 0..3 are needed".into());
            }
            if (nominal[(r, c)].abs() - 1.0).abs() < 1e-9 {
                return Err(format!(
                    "{} is the angle between two nominally aligned axes: cos(0 + alpha) has no \
                     first-order effect and no sign, so it cannot be measured or toleranced; \
                     give the angles of the crossed axes instead",
                    name((r, c))
                ));
            }
        }
        let j0 = Matrix3::from_fn(|i, j| {
            let (r, c) = positions[i];
            (nominal * skew_basis(j))[(r, c)]
        });
        let j0_inv = match j0.try_inverse() {
            Some(inv) if j0.determinant().abs() > 1e-6 => inv,
            _ => {
                return Err(format!(
                    "{}, {} and {} do not determine the link's rotation (two of them measure \
                     the same rotation component, e.g. a whole row or column of the block, \
                     which leaves the rotation about that axis open)",
                    name(positions[0]),
                    name(positions[1]),
                    name(positions[2])
                ))
            }
        };
        Ok(TripleCompletion {
            nominal: *nominal,
            phi: nominal.map(|c| c.clamp(-1.0, 1.0).acos()),
            positions,
            j0_inv,
        })
    }

    /// The positions of the triple.
    pub fn positions(&self) -> [(usize, usize); 3] {
        self.positions
    }

    /// All nine angular deviations (rad) of the link whose three measured deviations
    /// are `measured` (in the order of the positions): `alpha = acos(M) - phi` (the
    /// measured ones exactly as given), so `cos(phi + alpha)` is the rigid block `M`.
    /// A chord iteration on `w` with the nominal Jacobian (its error shrinks by a
    /// factor of about `|w|` per step), then Newton with a difference Jacobian when
    /// deviations are large.
    pub fn complete(&self, measured: [f64; 3]) -> Result<Matrix3<f64>> {
        let m = self.complete_block(measured)?;
        let mut alpha =
            Matrix3::from_fn(|r, c| m[(r, c)].clamp(-1.0, 1.0).acos() - self.phi[(r, c)]);
        for (i, &(r, c)) in self.positions.iter().enumerate() {
            alpha[(r, c)] = measured[i];
        }
        Ok(alpha)
    }

    /// The rigid block `M = N exp([w]x)` whose entries at the positions are
    /// `cos(phi + measured)` (see [`TripleCompletion::complete`]).
    ///
    /// Per iteration only the three entries at the positions are evaluated (row `r` of
    /// `N` times column `c` of `exp([w]x)`, Rodrigues' formula with its series for small
    /// `|w|`, no trigonometry); the iteration stops when the residual is at rounding
    /// level or no longer falls.
    pub fn complete_block(&self, measured: [f64; 3]) -> Result<Matrix3<f64>> {
        let target = nalgebra::Vector3::from_fn(|i, _| {
            let (r, c) = self.positions[i];
            (self.phi[(r, c)] + measured[i]).cos()
        });
        let (w, f) = self.chord_steps(&target);
        let (w, f) = self.newton_steps(&target, w, f);
        if !(f.amax() < 1e-12) {
            return Err(Error::NotAttainable {
                reason: format!(
                    "no rigid turn of the link has the angular deviations {:?} deg at {:?} \
                     (residual {:.3e})",
                    measured.map(f64::to_degrees),
                    self.positions,
                    f.amax()
                )
                .into(),
            });
        }
        let (a, b) = rodrigues_coefficients(&w);
        let k = w.cross_matrix();
        let r = Matrix3::identity() + k * a + k * k * b;
        Ok(self.nominal * r)
    }

    /// The entries at the positions of `N exp([w]x)` less their `target`s.
    #[inline]
    fn residual(&self, w: &Vector3<f64>, target: &Vector3<f64>) -> Vector3<f64> {
        let (a, b) = rodrigues_coefficients(w);
        let diag = 1.0 - b * w.norm_squared();
        Vector3::from_fn(|i, _| {
            let (r, c) = self.positions[i];
            // Column c of exp([w]x) = diag e_c + a (w x e_c) + b w_c w.
            let e = Vector3::from_fn(|k, _| {
                let cross = match (c, k) {
                    (0, 1) => w.z,
                    (0, 2) => -w.y,
                    (1, 0) => -w.z,
                    (1, 2) => w.x,
                    (2, 0) => w.y,
                    (2, 1) => -w.x,
                    _ => 0.0,
                };
                let d = if k == c { diag } else { 0.0 };
                d + a * cross + b * w[c] * w[k]
            });
            self.nominal.row(r).transpose().dot(&e) - target[i]
        })
    }

    /// Chord steps from `w = 0` with the nominal Jacobian (the error shrinks by about
    /// `|w|` a step): the turn and its residual.
    #[inline]
    fn chord_steps(&self, target: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        // At w = 0 the block is the nominal one: the first residual needs no exponential.
        let mut w = Vector3::zeros();
        let mut f = Vector3::from_fn(|i, _| {
            let (r, c) = self.positions[i];
            self.nominal[(r, c)] - target[i]
        });
        for _ in 0..8 {
            if f.amax() < 1e-15 {
                break;
            }
            let wn = w - self.j0_inv * f;
            let fn_ = self.residual(&wn, target);
            if fn_.amax() >= f.amax() {
                break; // rounding level reached, or too large for the chord
            }
            (w, f) = (wn, fn_);
        }
        (w, f)
    }

    /// Newton with a difference Jacobian from turn `w` (residual `f`), for large
    /// deviations: the turn and its residual.
    #[inline]
    fn newton_steps(
        &self,
        target: &Vector3<f64>,
        mut w: Vector3<f64>,
        mut f: Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let mut it = 0;
        while f.amax() >= 1e-14 && it < 30 {
            let h = 1e-7;
            let mut j = Matrix3::zeros();
            for k in 0..3 {
                let mut wp = w;
                wp[k] += h;
                let col = (self.residual(&wp, target) - f) / h;
                j.set_column(k, &col);
            }
            let Some(inv) = j.try_inverse() else { break };
            let wn = w - inv * f;
            let fn_ = self.residual(&wn, target);
            if fn_.amax() >= f.amax() {
                break;
            }
            (w, f) = (wn, fn_);
            it += 1;
        }
        (w, f)
    }
}

/// `(sin t / t, (1 - cos t) / t^2)` for `t = |w|`, so that
/// `exp([w]x) = I + a [w]x + b [w]x^2` (Rodrigues); their series below `t = 1e-3`
/// (truncation below `t^6 / 5040`, under 1e-21).
#[inline]
fn rodrigues_coefficients(w: &nalgebra::Vector3<f64>) -> (f64, f64) {
    let t2 = w.norm_squared();
    if t2 < 1e-6 {
        (
            1.0 - t2 / 6.0 + t2 * t2 / 120.0,
            0.5 - t2 / 24.0 + t2 * t2 / 720.0,
        )
    } else {
        let t = t2.sqrt();
        let (s, c) = t.sin_cos();
        (s / t, (1.0 - c) / t2)
    }
}
