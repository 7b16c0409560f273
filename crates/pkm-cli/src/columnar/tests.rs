//! Tests of the Parquet table writer: every kind of column read back by the parquet
//! crate's own reader.

use super::*;
use parquet::file::reader::{FileReader, SerializedFileReader};
use parquet::record::Field;

/// A reader of a file holding `bytes`.
pub fn reader(bytes: &[u8]) -> SerializedFileReader<std::fs::File> {
    let mut f = tempfile::tempfile().unwrap();
    f.write_all(bytes).unwrap();
    SerializedFileReader::new(f).unwrap()
}

/// Every kind of column round-trips through the parquet crate's own reader, over
/// several row groups and a short last one; nulls stay nulls, doubles keep their
/// bits, repeated texts are stored once (dictionary).
#[test]
fn every_kind_round_trips_across_row_groups() {
    let cols = vec![
        ("x_mm".to_string(), Kind::F64),
        ("c".to_string(), Kind::OptF64),
        ("line".to_string(), Kind::OptI64),
        ("ok".to_string(), Kind::Bool),
        ("why".to_string(), Kind::OptText),
    ];
    let meta = vec![("pkm.machine".to_string(), "test".to_string())];
    let mut t = Table::create(Vec::new(), &cols, &[0, 2], meta, 7).unwrap();
    let n = 30;
    let x = |k: usize| (k as f64).sqrt() * std::f64::consts::PI - 1e-300;
    let why = ["strut 1 length max", "joint 3 angle", "a, \"quoted\"\ntext"];
    for k in 0..n {
        t.f64(0, x(k));
        t.opt_f64(1, (k % 3 == 0).then(|| -x(k)));
        t.opt_i64(2, (k % 4 != 1).then_some(k as i64 * 1_000_000_007));
        t.bool(3, k % 2 == 0);
        t.opt_text(4, (k % 5 != 0).then(|| why[k % 3]));
        t.end_row().unwrap();
    }
    let (bytes, rows) = t.finish().unwrap();
    assert_eq!(rows, n as u64);
    let r = reader(&bytes);
    let meta = r.metadata();
    assert_eq!(meta.num_row_groups(), 5, "row groups of 7: 7+7+7+7+2");
    check_statistics(meta.row_group(0), &x);
    let kv = meta.file_metadata().key_value_metadata().unwrap();
    assert!(kv
        .iter()
        .any(|k| k.key == "pkm.machine" && k.value.as_deref() == Some("test")));
    check_rows(&r, n, &x, &why);
}

/// Statistics where asked for: the first group's x spans rows 0..7; the line column
/// has them, the optional doubles not.
fn check_statistics(g: &parquet::file::metadata::RowGroupMetaData, x: &dyn Fn(usize) -> f64) {
    match g.column(0).statistics() {
        Some(parquet::file::statistics::Statistics::Double(s)) => {
            assert_eq!((s.min_opt(), s.max_opt()), (Some(&x(0)), Some(&x(6))));
        }
        o => panic!("x statistics: {o:?}"),
    }
    assert!(g.column(2).statistics().is_some());
    assert!(g.column(1).statistics().is_none());
}

/// The `n` rows read back are the ones written: doubles to the bit, nulls where none
/// was given.
fn check_rows(
    r: &SerializedFileReader<std::fs::File>,
    n: usize,
    x: &dyn Fn(usize) -> f64,
    why: &[&str; 3],
) {
    let mut k = 0;
    for row in r.get_row_iter(None).unwrap() {
        let row = row.unwrap();
        let f: Vec<&Field> = row.get_column_iter().map(|(_, f)| f).collect();
        assert_eq!(f[0], &Field::Double(x(k)), "row {k}");
        match f[1] {
            Field::Double(v) => assert_eq!(v.to_bits(), (-x(k)).to_bits()),
            Field::Null => assert!(k % 3 != 0),
            o => panic!("row {k}: {o:?}"),
        }
        match f[2] {
            Field::Long(v) => assert_eq!(*v, k as i64 * 1_000_000_007),
            Field::Null => assert_eq!(k % 4, 1),
            o => panic!("row {k}: {o:?}"),
        }
        assert_eq!(f[3], &Field::Bool(k % 2 == 0));
        match f[4] {
            Field::Str(s) => assert_eq!(s, why[k % 3]),
            Field::Null => assert_eq!(k % 5, 0),
            o => panic!("row {k}: {o:?}"),
        }
        k += 1;
    }
    assert_eq!(k, n);
}

/// Texts that are all different (messages with numbers) round-trip, and the map of
/// distinct texts kept in memory stops at [`MAX_INTERNED`] and is emptied with each
/// row group.
#[test]
fn many_distinct_texts_are_not_all_kept() {
    let cols = vec![("why".to_string(), Kind::OptText)];
    let mut t = Table::create(Vec::new(), &cols, &[], Vec::new(), 5000).unwrap();
    let text = |k: usize| format!("line {k}: strut 3 length {:.3} mm", k as f64 * 0.1);
    for k in 0..4000 {
        t.opt_text(0, Some(&text(k)));
        t.end_row().unwrap();
    }
    let Buf::OptText(_, _, seen) = &t.bufs[0] else {
        panic!()
    };
    assert_eq!(seen.len(), MAX_INTERNED);
    for k in 4000..6000 {
        t.opt_text(0, Some(&text(k)));
        t.end_row().unwrap();
    }
    let Buf::OptText(_, _, seen) = &t.bufs[0] else {
        panic!()
    };
    assert_eq!(
        seen.len(),
        1000,
        "emptied by the row group written at 5000 rows"
    );
    let (bytes, rows) = t.finish().unwrap();
    assert_eq!(rows, 6000);
    let r = reader(&bytes);
    for (k, row) in r.get_row_iter(None).unwrap().enumerate() {
        let row = row.unwrap();
        let (_, f) = row.get_column_iter().next().unwrap();
        assert_eq!(f, &Field::Str(text(k)), "row {k}");
    }
}

/// A row missing a column's value, or a value of the wrong type, is refused at the
/// row's end with the column named (not written shifted).
#[test]
fn a_missing_or_mistyped_value_is_refused() {
    let cols = vec![("a".to_string(), Kind::F64), ("b".to_string(), Kind::Bool)];
    let mut t = Table::create(Vec::new(), &cols, &[], Vec::new(), 8).unwrap();
    t.f64(0, 1.0);
    let e = t.end_row().unwrap_err().to_string();
    assert!(
        e.contains("column b") && e.contains("0 values for 1 rows"),
        "{e}"
    );
    let mut t = Table::create(Vec::new(), &cols, &[], Vec::new(), 8).unwrap();
    t.f64(0, 1.0);
    t.f64(1, 2.0);
    let e = t.end_row().unwrap_err().to_string();
    assert!(e.contains("column b: a value of another type"), "{e}");
}
