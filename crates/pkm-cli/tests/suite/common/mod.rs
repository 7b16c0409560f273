//! Helpers shared by the CLI tests.

#![allow(dead_code)]

use std::path::PathBuf;

use assert_cmd::Command;

/// A path in the repository, from the workspace root.
pub fn path(rel: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
        .display()
        .to_string()
}

/// The `pkm` binary under test.
pub fn pkm() -> Command {
    Command::cargo_bin("pkm").unwrap()
}

/// Asserts that a run succeeded, showing its stderr otherwise.
pub fn ok(o: &std::process::Output) {
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A cell of a table read back from a CSV or Parquet file: a number, a text, or
/// nothing (an empty CSV field, a Parquet null).
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    Num(f64),
    Text(String),
    Null,
}

/// A Parquet file's column names and rows, read by the parquet crate's record reader
/// (integers and booleans as numbers and texts as they would print in a CSV).
pub fn parquet_rows(file: &std::path::Path) -> (Vec<String>, Vec<Vec<Cell>>) {
    use parquet::file::reader::{FileReader, SerializedFileReader};
    use parquet::record::Field;
    let r = SerializedFileReader::new(std::fs::File::open(file).unwrap()).unwrap();
    let names = r
        .metadata()
        .file_metadata()
        .schema_descr()
        .columns()
        .iter()
        .map(|c| c.name().to_string())
        .collect();
    let rows = r
        .get_row_iter(None)
        .unwrap()
        .map(|row| {
            row.unwrap()
                .get_column_iter()
                .map(|(_, f)| match f {
                    Field::Double(v) => Cell::Num(*v),
                    Field::Long(v) => Cell::Num(*v as f64),
                    Field::Bool(b) => Cell::Text(b.to_string()),
                    Field::Str(s) => Cell::Text(s.clone()),
                    Field::Null => Cell::Null,
                    o => panic!("unexpected Parquet field {o:?}"),
                })
                .collect()
        })
        .collect();
    (names, rows)
}

/// A CSV file's header and rows (numbers where a field parses as one).
pub fn csv_rows(file: &std::path::Path) -> (Vec<String>, Vec<Vec<Cell>>) {
    let mut r = csv::Reader::from_path(file).unwrap();
    let names = r.headers().unwrap().iter().map(String::from).collect();
    let rows = r
        .records()
        .map(|rec| {
            rec.unwrap()
                .iter()
                .map(|f| match f.parse::<f64>() {
                    _ if f.is_empty() => Cell::Null,
                    Ok(v) => Cell::Num(v),
                    Err(_) => Cell::Text(f.to_string()),
                })
                .collect()
        })
        .collect();
    (names, rows)
}

/// Asserts that a Parquet table holds a CSV table's columns and rows: numbers within
/// `tol` (plus 1e-9 relative), texts and nulls equal; the rows compared.
pub fn assert_parquet_is_csv(parquet: &std::path::Path, csv: &std::path::Path, tol: f64) -> usize {
    let (pn, pr) = parquet_rows(parquet);
    let (cn, cr) = csv_rows(csv);
    assert_eq!(pn, cn, "columns");
    assert_eq!(pr.len(), cr.len(), "rows");
    for (k, (p, c)) in pr.iter().zip(&cr).enumerate() {
        for (j, (a, b)) in p.iter().zip(c).enumerate() {
            let same = match (a, b) {
                (Cell::Num(a), Cell::Num(b)) => (a - b).abs() <= tol + 5e-16 * a.abs(),
                _ => a == b,
            };
            assert!(same, "row {k}, column {}: {a:?} vs {b:?}", pn[j]);
        }
    }
    pr.len()
}
