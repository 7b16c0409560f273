//! The in-register transposes of a block of eight poses (AVX-512): rows of six
//! coordinates or strut values into six vectors of eight lanes and back, shared by the
//! block kernel (`block.rs`) and the motion kernel (`block_motion.rs`).

// Columns and lanes are indexed together.
#![allow(clippy::needless_range_loop)]

use std::arch::x86_64::*;

use super::block::LANES;

/// The in-register transposes of a block (48 doubles, row-major, six per row, in
/// six vectors `v_0..v_5` of eight). Column `k` (coordinate or strut `k` of every
/// row) takes element `e = 6 l + k` into lane `l`: from the pair `(v_0, v_1)`,
/// `(v_2, v_3)` or `(v_4, v_5)` holding it, at index `e mod 16` of the pair.
const fn column_index(k: usize) -> [i64; LANES] {
    let mut idx = [0; LANES];
    let mut l = 0;
    while l < LANES {
        idx[l] = ((6 * l + k) % 16) as i64;
        l += 1;
    }
    idx
}

/// Lanes of column `k` whose element lies at or past `from`.
const fn column_mask(k: usize, from: usize) -> u8 {
    let mut m = 0;
    let mut l = 0;
    while l < LANES {
        if 6 * l + k >= from {
            m |= 1 << l;
        }
        l += 1;
    }
    m
}

/// The way back: lane `m` of row-major vector `j` is element `e = 8 j + m`, strut
/// `e mod 6` of row `e / 6`, found in the column pair `(e mod 6) / 2` at index
/// `8 ((e mod 6) mod 2) + e / 6`.
const fn row_index(j: usize) -> [i64; LANES] {
    let mut idx = [0; LANES];
    let mut m = 0;
    while m < LANES {
        let e = 8 * j + m;
        idx[m] = (8 * (e % 6 % 2) + e / 6) as i64;
        m += 1;
    }
    idx
}

/// Lanes of row-major vector `j` taken from column pair `pair`.
const fn row_mask(j: usize, pair: usize) -> u8 {
    let mut mask = 0;
    let mut m = 0;
    while m < LANES {
        if (8 * j + m) % 6 / 2 == pair {
            mask |= 1 << m;
        }
        m += 1;
    }
    mask
}

const COLUMN_INDEX: [[i64; LANES]; 6] = [
    column_index(0),
    column_index(1),
    column_index(2),
    column_index(3),
    column_index(4),
    column_index(5),
];
const COLUMN_MASK: [[u8; 2]; 6] = [
    [column_mask(0, 16), column_mask(0, 32)],
    [column_mask(1, 16), column_mask(1, 32)],
    [column_mask(2, 16), column_mask(2, 32)],
    [column_mask(3, 16), column_mask(3, 32)],
    [column_mask(4, 16), column_mask(4, 32)],
    [column_mask(5, 16), column_mask(5, 32)],
];
const ROW_INDEX: [[i64; LANES]; 6] = [
    row_index(0),
    row_index(1),
    row_index(2),
    row_index(3),
    row_index(4),
    row_index(5),
];
const ROW_MASK: [[u8; 2]; 6] = [
    [row_mask(0, 1), row_mask(0, 2)],
    [row_mask(1, 1), row_mask(1, 2)],
    [row_mask(2, 1), row_mask(2, 2)],
    [row_mask(3, 1), row_mask(3, 2)],
    [row_mask(4, 1), row_mask(4, 2)],
    [row_mask(5, 1), row_mask(5, 2)],
];

/// The columns of a block (48 doubles, row-major, six per row): coordinate or
/// strut `k` of the eight rows in the lanes of vector `k`.
#[target_feature(enable = "avx512f")]
#[inline]
pub(super) fn columns(xs: &[f64; 6 * LANES]) -> [__m512d; 6] {
    // SAFETY: unaligned loads of 8 f64 at offsets 0..40 step 8 of the 48 of `xs`,
    // and of the 8 i64 of an index table.
    let v: [__m512d; 6] =
        std::array::from_fn(|j| unsafe { _mm512_loadu_pd(xs.as_ptr().add(8 * j)) });
    let index = |t: &[i64; LANES]| unsafe { _mm512_loadu_si512(t.as_ptr().cast()) };
    std::array::from_fn(|k| {
        let idx = index(&COLUMN_INDEX[k]);
        let [m16, m32] = COLUMN_MASK[k];
        let lo = _mm512_permutex2var_pd(v[0], idx, v[1]);
        let mid = _mm512_permutex2var_pd(v[2], idx, v[3]);
        let hi = _mm512_permutex2var_pd(v[4], idx, v[5]);
        _mm512_mask_blend_pd(m32, _mm512_mask_blend_pd(m16, lo, mid), hi)
    })
}

/// [`columns`] undone: the six column vectors written back as eight rows of six.
#[target_feature(enable = "avx512f")]
#[inline]
pub(super) fn rows(cols: &[__m512d; 6], out: &mut [f64; 6 * LANES]) {
    // SAFETY: loads of the 8 i64 of an index table.
    let index = |t: &[i64; LANES]| unsafe { _mm512_loadu_si512(t.as_ptr().cast()) };
    for j in 0..6 {
        let idx = index(&ROW_INDEX[j]);
        let [m1, m2] = ROW_MASK[j];
        let p0 = _mm512_permutex2var_pd(cols[0], idx, cols[1]);
        let p1 = _mm512_permutex2var_pd(cols[2], idx, cols[3]);
        let p2 = _mm512_permutex2var_pd(cols[4], idx, cols[5]);
        let row = _mm512_mask_blend_pd(m2, _mm512_mask_blend_pd(m1, p0, p1), p2);
        // SAFETY: 8 f64 at offset 8 j < 48 of the 48 of `out`.
        unsafe { _mm512_storeu_pd(out.as_mut_ptr().add(8 * j), row) };
    }
}
