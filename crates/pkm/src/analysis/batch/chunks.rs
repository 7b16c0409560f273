//! The batches' driver: rows checked, cut into chunks of [`BATCH_CHUNK`] rows and run
//! on all cores, each chunk's causes merged into one table.

use rayon::prelude::*;

use super::causes::{BatchReason, CauseRows, Causes, Interner};
use super::{BATCH_CHUNK, MAX_BATCH};
use crate::error::{Error, Result};

/// `n` copies of `v`, written on all cores when `n` is large: a million rows' columns
/// are tens of megabytes, and filling them on the calling thread (its page faults
/// included) was a sequential tenth of a batch.
pub(super) fn filled<T: Copy + Send + Sync>(n: usize, v: T) -> Vec<T> {
    if n <= BATCH_CHUNK {
        vec![v; n]
    } else {
        (0..n).into_par_iter().map(|_| v).collect()
    }
}

/// Checks a batch's shape: `values` holds whole rows of `width` and at most
/// [`MAX_BATCH`] of them; the row count.
pub(super) fn rows(values: &[f64], width: usize, what: &str) -> Result<usize> {
    if !values.len().is_multiple_of(width) || values.len() / width > MAX_BATCH {
        return Err(Error::InvalidInput {
            what: what.into(),
            message: format!(
                "expected up to {MAX_BATCH:.0e} rows of {width} values, got {} values",
                values.len()
            ),
        });
    }
    Ok(values.len() / width)
}

/// Runs `work` on matching chunks of rows of `input` (`width` values a row) and of
/// `out` (`out_width` a row): [`BATCH_CHUNK`] rows per rayon task, or the whole batch
/// on the calling thread when it is at most one chunk ([`chunked`] without causes).
pub(super) fn per_chunk<F>(input: &[f64], width: usize, out: &mut [f64], out_width: usize, work: F)
where
    F: Fn((&[f64], &mut [f64])) + Send + Sync,
{
    if input.len() <= width * BATCH_CHUNK {
        work((input, out));
    } else {
        input
            .par_chunks(width * BATCH_CHUNK)
            .zip(out.par_chunks_mut(out_width * BATCH_CHUNK))
            .for_each(work);
    }
}

/// One chunk's distinct causes and its solver messages by row within the chunk.
pub(super) type ChunkCauses = (Vec<BatchReason>, Vec<(usize, String)>);

/// One chunk's slices: input rows, value rows, flags, records, and the three cause
/// columns (as rayon's zipped chunk iterators give them).
pub(super) type Task<'a, E> = (
    (
        (
            (((&'a [f64], &'a mut [f64]), &'a mut [bool]), &'a mut [E]),
            &'a mut [i32],
        ),
        &'a mut [f64],
    ),
    &'a mut [f64],
);

/// Per-row outputs of a chunked batch: `values` (rows of `width`), a flag and a
/// record `E` per row.
pub(super) struct Outputs<'a, E> {
    pub(super) values: &'a mut [f64],
    pub(super) width: usize,
    pub(super) flags: &'a mut [bool],
    pub(super) records: &'a mut [E],
}

/// Runs `work(input rows, value rows, flags, records, cause rows)` over chunks of
/// [`BATCH_CHUNK`] rows (on the calling thread for one chunk, or for all of them in
/// order when `sequential`: rows that depend on the rows before), then merges the
/// chunks' cause tables and solver messages into `causes`.
pub(super) fn chunked<E, F>(
    input: &[f64],
    width_in: usize,
    out: Outputs<E>,
    causes: &mut Causes,
    sequential: bool,
    work: F,
) where
    E: Send,
    F: Fn(&[f64], &mut [f64], &mut [bool], &mut [E], &mut CauseRows) + Sync,
{
    let n = out.flags.len();
    let task = |((((((xs, vals), ok), rec), reason), value), bound): Task<E>| {
        let mut rows = CauseRows {
            reason,
            value,
            bound,
            table: Interner::default(),
            errors: Vec::new(),
            codes: Vec::new(),
        };
        work(xs, vals, ok, rec, &mut rows);
        (rows.table.reasons, rows.errors)
    };
    let tables: Vec<ChunkCauses> = if n <= BATCH_CHUNK {
        vec![task((
            (
                (
                    (((input, out.values), out.flags), out.records),
                    &mut causes.reason[..],
                ),
                &mut causes.value[..],
            ),
            &mut causes.bound[..],
        ))]
    } else {
        // The chunks of every column zipped, by `chunks`/`chunks_mut` (in order) or
        // rayon's `par_chunks`/`par_chunks_mut`.
        macro_rules! each_chunk {
            ($chunks:ident, $chunks_mut:ident) => {
                input
                    .$chunks(width_in * BATCH_CHUNK)
                    .zip(out.values.$chunks_mut(out.width * BATCH_CHUNK))
                    .zip(out.flags.$chunks_mut(BATCH_CHUNK))
                    .zip(out.records.$chunks_mut(BATCH_CHUNK))
                    .zip(causes.reason.$chunks_mut(BATCH_CHUNK))
                    .zip(causes.value.$chunks_mut(BATCH_CHUNK))
                    .zip(causes.bound.$chunks_mut(BATCH_CHUNK))
                    .map(task)
                    .collect()
            };
        }
        if sequential {
            each_chunk!(chunks, chunks_mut)
        } else {
            each_chunk!(par_chunks, par_chunks_mut)
        }
    };
    merge_causes(tables, causes, n);
}

/// One cause table for a batch of `n` rows from the chunks' `tables`: their codes
/// renumbered into it, their solver messages by batch row.
pub(super) fn merge_causes(tables: Vec<ChunkCauses>, causes: &mut Causes, n: usize) {
    let mut all = Interner::default();
    for (c, (reasons, errors)) in tables.into_iter().enumerate() {
        if reasons.is_empty() {
            continue;
        }
        causes.errors.extend(
            errors
                .into_iter()
                .map(|(i, text)| (c * BATCH_CHUNK + i, text)),
        );
        let map: Vec<i32> = reasons
            .into_iter()
            .map(|r| all.code(r.text, r.kind, r.unit))
            .collect();
        let range = c * BATCH_CHUNK..((c + 1) * BATCH_CHUNK).min(n);
        for code in &mut causes.reason[range] {
            if *code >= 0 {
                *code = map[*code as usize];
            }
        }
    }
    causes.reasons = all.reasons;
}
