//! Reading CSV batches of numbers with a named header.

use std::path::Path;

use anyhow::{bail, Context, Result};

use crate::io::write_atomic;
use crate::EXIT_UNREACHABLE;

/// A numeric CSV table: header names and rows with their 1-based line numbers.
pub struct Table {
    /// Header as written.
    pub header: Vec<String>,
    /// (line, values) per data row.
    pub rows: Vec<(u64, Vec<f64>)>,
}

/// Strips a unit suffix (`_mm`, `_deg`) and lowercases, for matching header names.
fn canonical(name: &str) -> String {
    let n = name.trim().to_ascii_lowercase();
    for suf in ["_mm", "_deg", "[mm]", "[deg]", " (mm)", " (deg)"] {
        if let Some(s) = n.strip_suffix(suf) {
            return s.trim().to_string();
        }
    }
    n
}

/// Reads `path`, checking that the header names one of the `accepted` column lists
/// (case-insensitive, unit suffixes allowed) and every cell is a finite number.
pub fn read_table(path: &Path, accepted: &[Vec<String>]) -> Result<Table> {
    let mut rdr = csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_path(path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let header: Vec<String> = rdr
        .headers()
        .with_context(|| format!("{}: cannot read the header row", path.display()))?
        .iter()
        .map(str::to_string)
        .collect();
    let got: Vec<String> = header.iter().map(|h| canonical(h)).collect();
    let ok = accepted.iter().any(|a| {
        a.len() == got.len()
            && a.iter()
                .zip(&got)
                .all(|(x, y)| x.to_ascii_lowercase() == *y)
    });
    if !ok {
        bail!(
            "{}:1: header `{}` does not name the expected columns; expected {}",
            path.display(),
            header.join(","),
            accepted
                .iter()
                .map(|a| format!("`{}`", a.join(",")))
                .collect::<Vec<_>>()
                .join(" or ")
        );
    }
    let mut rows = Vec::new();
    for rec in rdr.records() {
        let rec = rec.with_context(|| format!("{}: malformed CSV", path.display()))?;
        let line = rec.position().map(|p| p.line()).unwrap_or(0);
        if rec.len() != header.len() {
            bail!(
                "{}:{line}: expected {} values, found {}",
                path.display(),
                header.len(),
                rec.len()
            );
        }
        let mut vals = Vec::with_capacity(rec.len());
        for (i, cell) in rec.iter().enumerate() {
            match cell.parse::<f64>() {
                Ok(v) if v.is_finite() => vals.push(v),
                _ => bail!(
                    "{}:{line}: column `{}`: expected a finite number, found `{cell}`",
                    path.display(),
                    header[i]
                ),
            }
        }
        rows.push((line, vals));
    }
    Ok(Table { header, rows })
}

/// Formats a float for CSV output (full precision, shortest round-trip form).
pub fn num(v: f64) -> String {
    format!("{v}")
}

/// Writes a batch result whole, says on stderr how many rows were `ok_word` and how
/// many not, and returns the exit code (unreachable when any row failed).
pub fn finish_batch(
    output: &Path,
    text: &str,
    inputs: &[&Path],
    rows: usize,
    failed: usize,
    ok_word: &str,
) -> Result<u8> {
    write_atomic(output, text.as_bytes(), inputs)?;
    eprintln!(
        "wrote {rows} rows to {}: {} {ok_word}, {failed} not",
        output.display(),
        rows - failed
    );
    Ok(if failed > 0 { EXIT_UNREACHABLE } else { 0 })
}
