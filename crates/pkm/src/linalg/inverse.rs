//! The inverse of a small square matrix by nalgebra's own arithmetic, written for a
//! constant size so that it runs from registers.

use nalgebra::SMatrix;

/// `m^-1` by Gaussian elimination with partial pivoting, the operations of nalgebra's
/// `try_inverse` (and of `lu().try_inverse()`) for `N >= 5`, in the same order, so
/// equal to it bit for bit (tested against it, with ties between pivots, zero pivots,
/// infinities and signed zeros; a NaN as a NaN, whose sign Rust leaves unspecified),
/// in 64 ns instead of 174 ns for a 6 x 6 (EPYC): nalgebra's steps go through
/// strided views whose bounds it cannot know, these through fixed arrays.
///
/// Step `i`: the pivot is the first entry of column `i` at or below the diagonal with
/// the largest absolute value (`|a| > max`, so NaN is never chosen after the first);
/// its row is swapped into row `i` (and in the identity the inverse starts from); the
/// multipliers are `l_r = a_ri * (1 / a_ii)`, and every entry right of the pivot
/// column below it becomes `(-a_ik) * l_r + a_rk`. Then the unit lower and the upper
/// triangular solves, column by column: `b_r = (-b_i) * l_ri + b_r`, and `b_i = b_i /
/// u_ii`, `b_r = (-b_i) * u_ri + b_r` upward. `None` when a pivot is zero (exactly:
/// the matrix is singular as rounded).
pub fn inverse_lu<const N: usize>(m: &SMatrix<f64, N, N>) -> Option<SMatrix<f64, N, N>> {
    // Row-major copies: `a[r][c]`; `b` the identity the inverse is solved from.
    let mut a: [[f64; N]; N] = std::array::from_fn(|r| std::array::from_fn(|c| m[(r, c)]));
    let mut b: [[f64; N]; N] =
        std::array::from_fn(|r| std::array::from_fn(|c| if r == c { 1.0 } else { 0.0 }));
    // Up to 8 x 8 the steps are written out (as in `SmallLu::new`): constant row
    // indices, so the rows stay in registers.
    let ok = if N <= 8 {
        let mut step = |i: usize| i >= N || eliminate(&mut a, &mut b, i);
        step(0) && step(1) && step(2) && step(3) && step(4) && step(5) && step(6) && step(7)
    } else {
        (0..N).all(|i| eliminate(&mut a, &mut b, i))
    };
    if !ok {
        return None;
    }
    // L y = P (identity): unit diagonal (nalgebra divides by 1, which is exact).
    for i in 0..N.saturating_sub(1) {
        let bi = b[i];
        for r in i + 1..N {
            let l = a[r][i];
            for (y, c) in b[r].iter_mut().zip(bi) {
                *y += -c * l;
            }
        }
    }
    // U x = y, from the last row up.
    for i in (0..N).rev() {
        let d = a[i][i];
        if d == 0.0 {
            return None;
        }
        for c in b[i].iter_mut() {
            *c /= d;
        }
        let bi = b[i];
        for r in 0..i {
            let u = a[r][i];
            for (y, c) in b[r].iter_mut().zip(bi) {
                *y += -c * u;
            }
        }
    }
    Some(SMatrix::from_fn(|r, c| b[r][c]))
}

/// Step `i` of [`inverse_lu`]'s elimination; `false` when the pivot is zero.
#[inline(always)]
fn eliminate<const N: usize>(a: &mut [[f64; N]; N], b: &mut [[f64; N]; N], i: usize) -> bool {
    let mut piv = i;
    let mut max = a[i][i].abs();
    for (r, row) in a.iter().enumerate().skip(i + 1) {
        if row[i].abs() > max {
            max = row[i].abs();
            piv = r;
        }
    }
    // Rows `i` and `piv` swapped by selects over the rows below `i` (a swap at the
    // index `piv` goes through memory).
    let (old_a, old_b) = (a[i], b[i]);
    for r in i + 1..N {
        let here = r == piv;
        let (row_a, row_b) = (a[r], b[r]);
        for c in 0..N {
            a[i][c] = if here { row_a[c] } else { a[i][c] };
            a[r][c] = if here { old_a[c] } else { row_a[c] };
            b[i][c] = if here { row_b[c] } else { b[i][c] };
            b[r][c] = if here { old_b[c] } else { row_b[c] };
        }
    }
    let pivot_row = a[i];
    let diag = pivot_row[i];
    if diag == 0.0 {
        return false;
    }
    let inv_diag = 1.0 / diag;
    for row in a.iter_mut().skip(i + 1) {
        let l = row[i] * inv_diag;
        row[i] = l;
        for k in i + 1..N {
            row[k] += -pivot_row[k] * l;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Bits of an optional matrix (`None` as an empty list), every NaN as one value:
    /// the sign and payload of a NaN are unspecified in Rust (the compiler may swap
    /// the operands of a product, and x86 returns the first NaN operand).
    fn bits<const N: usize>(m: Option<SMatrix<f64, N, N>>) -> Vec<u64> {
        m.map_or_else(Vec::new, |m| {
            m.iter()
                .map(|v| if v.is_nan() { u64::MAX } else { v.to_bits() })
                .collect()
        })
    }

    /// `lu` is nalgebra's `lu().try_inverse()` at size `N` (not callable for a
    /// generic size).
    fn compare<const N: usize>(
        rng: &mut impl Rng,
        cases: usize,
        lu: fn(&SMatrix<f64, N, N>) -> Option<SMatrix<f64, N, N>>,
    ) -> (usize, usize) {
        let (mut inverted, mut refused) = (0, 0);
        for case in 0..cases {
            let m: SMatrix<f64, N, N> = match case % 5 {
                // Random, and near one another (a Newton's Jacobians).
                0 => SMatrix::from_fn(|_, _| rng.random_range(-1.0..1.0)),
                1 => SMatrix::from_fn(|r, c| {
                    (r * N + c) as f64 * 0.1 + 1e-6 * rng.random_range(-1.0..1.0)
                }),
                // Small integers: exact ties between pivots, zero pivots, singular.
                2 | 3 => SMatrix::from_fn(|_, _| rng.random_range(-2i32..=2) as f64),
                // Scaled rows (a Jacobian's angular rows times a length).
                _ => SMatrix::from_fn(|r, _| {
                    rng.random_range(-1.0..1.0) * if r >= 3 { 1e3 } else { 1.0 }
                }),
            };
            let mut m = m;
            match case % 97 {
                7 => m[rng.random_range(0..N * N)] = f64::NAN,
                11 => m[rng.random_range(0..N * N)] = f64::INFINITY,
                13 => m[rng.random_range(0..N * N)] = -0.0,
                17 => m.fill(0.0),
                _ => {}
            }
            let ours = inverse_lu(&m);
            let theirs = m.try_inverse();
            assert_eq!(bits(ours), bits(theirs), "size {N} case {case}: {m}");
            assert_eq!(bits(ours), bits(lu(&m)), "size {N} case {case}");
            if ours.is_some() {
                inverted += 1;
            } else {
                refused += 1;
            }
        }
        (inverted, refused)
    }

    /// Equal bit for bit to nalgebra's `try_inverse` and `lu().try_inverse()` at sizes
    /// 5, 6 and 7 (steps written out) and 9 (the loop; below 5 nalgebra uses closed
    /// forms): random matrices, matrices near
    /// one another, small integers (ties between pivots, zero pivots, singular), rows
    /// of very different scales, NaN, infinity, -0 and the zero matrix. Both outcomes
    /// occur.
    ///
    /// Mutations tried that fail it: `>=` in the pivot search, the multiplier by
    /// division instead of the reciprocal, the identity's row not swapped down, the upper
    /// solve by the reciprocal of the pivot. Skipping the lower solve's zero
    /// right-hand sides passes: it would differ only in the sign of a zero.
    #[test]
    fn equals_nalgebra_bit_for_bit() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        for (inverted, refused) in [
            compare::<5>(&mut rng, 4000, |m| m.lu().try_inverse()),
            compare::<6>(&mut rng, 20_000, |m| m.lu().try_inverse()),
            compare::<7>(&mut rng, 4000, |m| m.lu().try_inverse()),
            compare::<9>(&mut rng, 1000, |m| m.lu().try_inverse()),
        ] {
            assert!(
                inverted > 100 && refused > 10,
                "{inverted} inverted, {refused} refused"
            );
        }
    }
}
