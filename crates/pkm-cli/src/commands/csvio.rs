//! Batches of poses or actuator values: reading CSV tables of numbers with a named
//! header, writing the results as CSV or, for an output named `*.parquet`, as Parquet.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use pkm::analysis::batch_table::{parse_batch_table, BatchTable as InputTable};

use crate::columnar::{Kind, Table as Columns, GROUP_ROWS};
use crate::io::AtomicFile;
use crate::EXIT_UNREACHABLE;

/// Reads the batch file `path` ([`pkm::analysis::batch_table`]): its header names one of
/// the `accepted` column lists, every cell is a finite number.
pub fn read_table(path: &Path, accepted: &[Vec<String>]) -> Result<InputTable> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    Ok(parse_batch_table(
        &text,
        &path.display().to_string(),
        accepted,
    )?)
}

/// The output's copy of the input's columns: doubles, or doubles or nothing when a
/// row has no values (an earlier batch's row without a solution).
pub fn input_columns(table: &InputTable) -> Vec<(String, Kind)> {
    let empty = table.rows.iter().any(|(_, v)| v.is_empty());
    let kind = if empty { Kind::OptF64 } else { Kind::F64 };
    table.header.iter().map(|h| (h.clone(), kind)).collect()
}

/// Why a row without values has no result.
pub const NO_VALUES: &str =
    "no values (the row's cells are empty: an earlier batch's row without a solution)";

/// A batch's result table being written: CSV (numbers in full precision, the
/// shortest form that reads back to the same double; texts quoted where needed), or
/// Parquet (typed columns: nulls where the CSV has empty fields) when the output's
/// name ends in `.parquet`. Cells are given in column order, row by row, without an
/// allocation per cell; the file is put in place whole by [`BatchTable::finish`].
pub struct BatchTable {
    out: Out,
    /// The next cell's column.
    col: usize,
    rows: usize,
}

enum Out {
    /// The file and the rows not yet written to it.
    Csv(AtomicFile, Vec<u8>),
    Parquet(Box<Columns<AtomicFile>>),
}

impl BatchTable {
    /// A table of `columns` (name, kind) to be written to `output` (never over one of
    /// `inputs`), with `metadata` (key, value) in a Parquet file's footer.
    pub fn create(
        output: &Path,
        inputs: &[&Path],
        columns: &[(String, Kind)],
        metadata: Vec<(String, String)>,
    ) -> Result<BatchTable> {
        let file = AtomicFile::create(output, inputs)?;
        let parquet = output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("parquet"));
        let out = if parquet {
            Out::Parquet(Box::new(Columns::create(
                file,
                columns,
                &[],
                metadata,
                GROUP_ROWS,
            )?))
        } else {
            let mut head = Vec::new();
            for (k, (name, _)) in columns.iter().enumerate() {
                if k > 0 {
                    head.push(b',');
                }
                push_text(&mut head, name);
            }
            head.push(b'\n');
            Out::Csv(file, head)
        };
        Ok(BatchTable {
            out,
            col: 0,
            rows: 0,
        })
    }

    /// The separator before a CSV cell; the cell's column, advanced.
    fn next(&mut self) -> usize {
        let c = self.col;
        if let Out::Csv(_, buf) = &mut self.out {
            if c > 0 {
                buf.push(b',');
            }
        }
        self.col += 1;
        c
    }

    /// A number, or an empty cell.
    pub fn num(&mut self, v: Option<f64>) {
        let c = self.next();
        match (&mut self.out, v) {
            (Out::Csv(_, buf), Some(v)) => {
                let _ = write!(buf, "{v}");
            }
            (Out::Csv(..), None) => {}
            (Out::Parquet(t), v) => match v {
                Some(v) => t.f64(c, v),
                None => t.opt_f64(c, None),
            },
        }
    }

    /// The row's copy of the input's `width` values: `vals`, or empty cells for a row
    /// without values.
    pub fn input(&mut self, width: usize, vals: &[f64]) {
        if vals.is_empty() {
            (0..width).for_each(|_| self.num(None));
        } else {
            vals.iter().for_each(|v| self.num(Some(*v)));
        }
    }

    /// An integer, or an empty cell.
    pub fn int(&mut self, v: Option<u64>) {
        let c = self.next();
        match (&mut self.out, v) {
            (Out::Csv(_, buf), Some(v)) => {
                let _ = write!(buf, "{v}");
            }
            (Out::Csv(..), None) => {}
            (Out::Parquet(t), v) => t.opt_i64(c, v.map(|v| v as i64)),
        }
    }

    /// A boolean (`true`, `false`).
    pub fn bool(&mut self, v: bool) {
        let c = self.next();
        match &mut self.out {
            Out::Csv(_, buf) => buf.extend_from_slice(if v { b"true" } else { b"false" }),
            Out::Parquet(t) => t.bool(c, v),
        }
    }

    /// A text, or an empty cell (a Parquet null).
    pub fn text(&mut self, v: Option<&str>) {
        let c = self.next();
        match &mut self.out {
            Out::Csv(_, buf) => push_text(buf, v.unwrap_or("")),
            Out::Parquet(t) => t.opt_text(c, v),
        }
    }

    /// Ends a row (every column given a cell).
    pub fn end_row(&mut self) -> Result<()> {
        self.col = 0;
        self.rows += 1;
        match &mut self.out {
            Out::Csv(file, buf) => {
                buf.push(b'\n');
                if buf.len() >= 1 << 16 {
                    file.write_all(buf)?;
                    buf.clear();
                }
                Ok(())
            }
            Out::Parquet(t) => t.end_row(),
        }
    }

    /// Writes the last rows and puts the file in place; says on stderr how many rows
    /// were `ok_word` and how many not, and returns the exit code (unreachable when any
    /// row failed).
    pub fn finish(self, output: &Path, failed: usize, ok_word: &str) -> Result<u8> {
        let rows = self.rows;
        match self.out {
            Out::Csv(mut file, buf) => {
                file.write_all(&buf)?;
                file.commit()?;
            }
            Out::Parquet(t) => t.finish()?.0.commit()?,
        }
        eprintln!(
            "wrote {rows} rows to {}: {} {ok_word}, {failed} not",
            output.display(),
            rows - failed
        );
        Ok(if failed > 0 { EXIT_UNREACHABLE } else { 0 })
    }
}

/// Appends a CSV text cell, quoted where it holds a comma, a quote or a line break.
fn push_text(buf: &mut Vec<u8>, s: &str) {
    if s.contains([',', '"', '\n']) {
        buf.push(b'"');
        for b in s.bytes() {
            if b == b'"' {
                buf.push(b'"');
            }
            buf.push(b);
        }
        buf.push(b'"');
    } else {
        buf.extend_from_slice(s.as_bytes());
    }
}
