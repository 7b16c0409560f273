//! Identifiability: singular values of the column-scaled residual Jacobian, the
//! null space in reduced row echelon form, and the combinations named in words.

use nalgebra::{DMatrix, DVector};

use super::*;

/// Singular values of the column-scaled Jacobian (largest first) and its weak
/// directions (relative singular value below 1e-3), named. The directions of the
/// numerical null space (relative singular value below 1e-9) are put in reduced row
/// echelon form, so that each names a few parameters (e.g. a base joint coordinate and
/// the platform joint coordinate that trades against it) instead of a mix of all.
pub(super) fn analyse(
    j: &DMatrix<f64>,
    free: &[usize],
    names: &[String],
    explain: &Explain,
) -> (Vec<f64>, Vec<Combination>) {
    let norms: Vec<f64> = (0..j.ncols())
        .map(|c| j.column(c).norm().max(1e-300))
        .collect();
    let mut js = j.clone();
    for (c, nrm) in norms.iter().enumerate() {
        js.column_mut(c).scale_mut(1.0 / nrm);
    }
    // SVD of the scaled Jacobian itself (not of J^T J, whose eigenvalues square the
    // condition number and lose the small singular values to rounding).
    let svd = js.clone().svd(false, true);
    let vt = svd.v_t.expect("v_t requested");
    let values = svd.singular_values;
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[b].total_cmp(&values[a]));
    let mut sv: Vec<f64> = order.iter().map(|&k| values[k]).collect();
    // A Jacobian with fewer rows than columns has that many zero singular values more.
    sv.resize(j.ncols(), 0.0);
    let top = sv.first().copied().unwrap_or(0.0).max(1e-300);
    let rel = |k: usize| values[k] / top;
    let null: Vec<usize> = order
        .iter()
        .rev()
        .copied()
        .filter(|&k| rel(k) < 1e-9)
        .collect();
    let weak: Vec<usize> = order
        .iter()
        .rev()
        .copied()
        .filter(|&k| (1e-9..1e-3).contains(&rel(k)))
        .collect();
    // Directions in physical units (undo the column scaling).
    let physical = |v: DVector<f64>| -> DVector<f64> {
        DVector::from_iterator(v.len(), v.iter().zip(&norms).map(|(x, n)| x / n))
    };
    let mut dirs: Vec<(f64, DVector<f64>)> = Vec::new();
    if !null.is_empty() {
        let rows: Vec<DVector<f64>> = null
            .iter()
            .map(|&k| physical(vt.row(k).transpose()))
            .collect();
        for v in echelon(rows) {
            dirs.push((0.0, v));
        }
    }
    for &k in &weak {
        dirs.push((rel(k), physical(vt.row(k).transpose())));
    }
    let out = dirs
        .into_iter()
        .map(|(r, v)| combination(r, &v, free, names, explain))
        .collect();
    (sv, out)
}

/// Direction `v` (physical units, relative singular value `r`) as a combination: its
/// terms of at least 5 % of the largest, largest first and positive, named.
fn combination(
    r: f64,
    v: &DVector<f64>,
    free: &[usize],
    names: &[String],
    explain: &Explain,
) -> Combination {
    let big = v.amax().max(1e-300);
    let mut indexed: Vec<(usize, f64)> = v
        .iter()
        .enumerate()
        .filter(|(_, c)| c.abs() >= 0.05 * big)
        .map(|(c, x)| (free[c], x / big))
        .collect();
    indexed.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
    // Sign convention: the largest term positive.
    if indexed.first().is_some_and(|t| t.1 < 0.0) {
        indexed.iter_mut().for_each(|t| t.1 = -t.1);
    }
    let terms: Vec<(String, f64)> = indexed
        .iter()
        .map(|(i, c)| (names[*i].clone(), *c))
        .collect();
    let description = describe(&terms, explain(&indexed), r);
    Combination {
        relative_singular_value: r,
        terms,
        description,
    }
}

/// Reduced row echelon form of a set of directions (Gauss-Jordan with partial
/// pivoting): a sparse basis of the space they span.
fn echelon(rows: Vec<DVector<f64>>) -> Vec<DVector<f64>> {
    let k = rows.len();
    let n = rows.first().map(|r| r.len()).unwrap_or(0);
    let mut m = DMatrix::from_fn(k, n, |r, c| rows[r][c]);
    let scale = m.amax().max(1e-300);
    let mut row = 0;
    for col in 0..n {
        if row == k {
            break;
        }
        let (p, best) = (row..k)
            .map(|r| (r, m[(r, col)].abs()))
            .fold((row, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        if best <= 1e-8 * scale {
            continue;
        }
        m.swap_rows(row, p);
        let pivot = m[(row, col)];
        m.row_mut(row).scale_mut(1.0 / pivot);
        for r in 0..k {
            if r != row {
                let f = m[(r, col)];
                if f != 0.0 {
                    for c in 0..n {
                        m[(r, c)] -= f * m[(row, c)];
                    }
                }
            }
        }
        row += 1;
    }
    (0..row)
        .map(|r| {
            DVector::from_iterator(
                n,
                m.row(r)
                    .iter()
                    .map(|v| if v.abs() < 1e-10 { 0.0 } else { *v }),
            )
        })
        .collect()
}

fn describe(terms: &[(String, f64)], reading: Option<String>, relative: f64) -> String {
    let sum: Vec<String> = terms.iter().map(|(n, c)| format!("{c:+.3} {n}")).collect();
    let effect = if relative == 0.0 {
        "does not change any measured quantity".to_string()
    } else {
        format!("changes the measurements little (relative singular value {relative:.1e})")
    };
    let what = if let Some(r) = reading {
        r
    } else if terms.len() == 1 {
        format!("`{}` {effect}", terms[0].0)
    } else {
        format!(
            "these parameters trade against each other: changing them together along this \
             direction {effect}"
        )
    };
    format!(
        "{} ({what}; hold one of them or measure states that separate them)",
        sum.join(" ")
    )
}

/// A mechanism's reading of a combination ([`Identifiable::explain`]).
pub(super) type Explain<'a> = dyn Fn(&[(usize, f64)]) -> Option<String> + 'a;
