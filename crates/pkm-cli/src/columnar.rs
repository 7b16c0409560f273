//! Parquet tables for the long series (`pkm motion`'s actuators, `pkm workspace`'s
//! points): typed columns at full double precision, filled row by row and written in
//! row groups as they fill, so memory stays flat whatever the length.
//!
//! Layout chosen for what readers do with these files (pandas, polars, DuckDB, Arrow):
//! PLAIN doubles without compression (doubles with full mantissas: Snappy saved nothing
//! on such a series, byte-stream split plus Snappy 19 % at 3.5 times the writing
//! time), text columns dictionary-encoded (a
//! handful of distinct limit names over 10^6 rows), min/max statistics per row group on
//! the columns a reader filters by (time, G-code line, grid axes: computing them on
//! every column took a quarter of the writing), and the file's context (machine, pkm
//! version) as key-value metadata.

use std::collections::HashMap;
use std::io::Write;
use std::sync::Arc;

use anyhow::{bail, Context, Result};
use parquet::basic::{LogicalType, Repetition, Type as Physical};
use parquet::data_type::{BoolType, ByteArray, ByteArrayType, DoubleType, Int64Type};
use parquet::file::metadata::KeyValue;
use parquet::file::properties::{EnabledStatistics, WriterProperties};
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::types::{ColumnPath, Type};

/// Format of a command's series file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SeriesFormat {
    /// Comma-separated text, six decimals (spreadsheets, any tool).
    Csv,
    /// Apache Parquet: columnar, full double precision, typed (pandas, polars, DuckDB).
    Parquet,
}

impl SeriesFormat {
    /// The file name `stem.csv` or `stem.parquet`.
    pub fn file(self, stem: &str) -> String {
        match self {
            SeriesFormat::Csv => format!("{stem}.csv"),
            SeriesFormat::Parquet => format!("{stem}.parquet"),
        }
    }
}

/// The key-value metadata of a table about machine `m`: its name and type, and what
/// the table holds.
pub fn machine_metadata(m: &dyn pkm::DynMechanism, content: &str) -> Vec<(String, String)> {
    vec![
        ("pkm.machine".to_string(), m.name().to_string()),
        ("pkm.type".to_string(), m.kind().to_string()),
        ("pkm.content".to_string(), content.to_string()),
    ]
}

/// What a column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A double in every row.
    F64,
    /// A double or nothing.
    OptF64,
    /// A 64-bit integer or nothing.
    OptI64,
    /// A boolean in every row.
    Bool,
    /// UTF-8 text or nothing (dictionary-encoded).
    OptText,
}

/// Values of one column in the row group being filled; `def` holds the definition
/// level of every row of an optional column (1: a value, 0: null).
enum Buf {
    F64(Vec<f64>),
    OptF64(Vec<f64>, Vec<i16>),
    OptI64(Vec<i64>, Vec<i16>),
    Bool(Vec<bool>),
    /// Values, levels, and each distinct text once (a value is a shared reference).
    OptText(Vec<ByteArray>, Vec<i16>, HashMap<Box<str>, ByteArray>),
}

impl Buf {
    /// An empty buffer of a column of `kind` (a required double column's for
    /// `group_rows` rows).
    fn new(kind: Kind, group_rows: usize) -> Buf {
        match kind {
            Kind::F64 => Buf::F64(Vec::with_capacity(group_rows)),
            Kind::OptF64 => Buf::OptF64(Vec::new(), Vec::new()),
            Kind::OptI64 => Buf::OptI64(Vec::new(), Vec::new()),
            Kind::Bool => Buf::Bool(Vec::new()),
            Kind::OptText => Buf::OptText(Vec::new(), Vec::new(), HashMap::new()),
        }
    }

    /// Rows held (values of a required column, levels of an optional one).
    fn rows(&self) -> usize {
        match self {
            Buf::F64(v) => v.len(),
            Buf::Bool(v) => v.len(),
            Buf::OptF64(_, d) | Buf::OptI64(_, d) | Buf::OptText(_, d, _) => d.len(),
        }
    }

    fn clear(&mut self) {
        match self {
            Buf::F64(v) => v.clear(),
            Buf::Bool(v) => v.clear(),
            Buf::OptF64(v, d) => (v.clear(), d.clear()).1,
            Buf::OptI64(v, d) => (v.clear(), d.clear()).1,
            Buf::OptText(v, d, seen) => (v.clear(), d.clear(), seen.clear()).2,
        }
    }
}

/// Distinct texts of a column kept per row group, so that a repeated one (a limit's
/// name) is stored once in memory.
pub const MAX_INTERNED: usize = 1024;

/// Rows per row group by default: 65 536 rows of 27 doubles are 14 MB.
pub const GROUP_ROWS: usize = 1 << 16;

/// A Parquet file being written row by row.
pub struct Table<W: Write + Send> {
    writer: SerializedFileWriter<W>,
    names: Vec<String>,
    bufs: Vec<Buf>,
    /// Rows of the current row group completed by [`Table::end_row`].
    rows: usize,
    group_rows: usize,
    /// Rows written in earlier row groups.
    written: u64,
    /// The first column given a value of the wrong kind, if any.
    misuse: Option<usize>,
}

/// The Parquet type of column `name` of `kind`.
fn column_type(name: &str, kind: Kind) -> Result<Type> {
    let (physical, rep) = match kind {
        Kind::F64 => (Physical::DOUBLE, Repetition::REQUIRED),
        Kind::OptF64 => (Physical::DOUBLE, Repetition::OPTIONAL),
        Kind::OptI64 => (Physical::INT64, Repetition::OPTIONAL),
        Kind::Bool => (Physical::BOOLEAN, Repetition::REQUIRED),
        Kind::OptText => (Physical::BYTE_ARRAY, Repetition::OPTIONAL),
    };
    let mut t = Type::primitive_type_builder(name, physical).with_repetition(rep);
    if kind == Kind::OptText {
        t = t.with_logical_type(Some(LogicalType::String));
    }
    t.build().with_context(|| format!("Parquet column {name}"))
}

impl<W: Write + Send> Table<W> {
    /// A table of `columns` (name, kind) written to `out`, with `metadata` (key,
    /// value) in the file footer, row groups of `group_rows` rows, and min/max
    /// statistics per row group for the columns numbered in `indexed`.
    pub fn create(
        out: W,
        columns: &[(String, Kind)],
        indexed: &[usize],
        metadata: Vec<(String, String)>,
        group_rows: usize,
    ) -> Result<Self> {
        let mut fields = Vec::with_capacity(columns.len());
        let mut props = WriterProperties::builder()
            .set_dictionary_enabled(false)
            .set_statistics_enabled(EnabledStatistics::None)
            .set_created_by(format!("pkm {}", env!("CARGO_PKG_VERSION")))
            .set_key_value_metadata(Some(
                metadata
                    .into_iter()
                    .map(|(k, v)| KeyValue::new(k, v))
                    .collect(),
            ));
        let mut bufs = Vec::with_capacity(columns.len());
        for (c, (name, kind)) in columns.iter().enumerate() {
            if indexed.contains(&c) {
                props = props.set_column_statistics_enabled(
                    ColumnPath::from(name.as_str()),
                    EnabledStatistics::Chunk,
                );
            }
            if *kind == Kind::OptText {
                props = props.set_column_dictionary_enabled(ColumnPath::from(name.as_str()), true);
            }
            fields.push(Arc::new(column_type(name, *kind)?));
            bufs.push(Buf::new(*kind, group_rows));
        }
        let schema = Type::group_type_builder("schema")
            .with_fields(fields)
            .build()
            .context("Parquet schema")?;
        let writer = SerializedFileWriter::new(out, Arc::new(schema), Arc::new(props.build()))
            .context("cannot start the Parquet file")?;
        Ok(Table {
            writer,
            names: columns.iter().map(|c| c.0.clone()).collect(),
            bufs,
            rows: 0,
            group_rows: group_rows.max(1),
            written: 0,
            misuse: None,
        })
    }

    /// Appends a double to column `c` (a [`Kind::F64`] or [`Kind::OptF64`] column).
    pub fn f64(&mut self, c: usize, x: f64) {
        match &mut self.bufs[c] {
            Buf::F64(v) => v.push(x),
            Buf::OptF64(v, d) => {
                v.push(x);
                d.push(1);
            }
            _ => self.misuse = self.misuse.or(Some(c)),
        }
    }

    /// Appends the doubles of a block of rows to column `c`: every `stride`-th value of
    /// `values`, from the first.
    pub fn f64_strided(&mut self, c: usize, values: &[f64], stride: usize) {
        match &mut self.bufs[c] {
            Buf::F64(v) => v.extend(values.iter().step_by(stride.max(1))),
            _ => self.misuse = self.misuse.or(Some(c)),
        }
    }

    /// Appends a double or a null to column `c` (a [`Kind::OptF64`] column).
    pub fn opt_f64(&mut self, c: usize, x: Option<f64>) {
        match (&mut self.bufs[c], x) {
            (Buf::OptF64(v, d), Some(x)) => {
                v.push(x);
                d.push(1);
            }
            (Buf::OptF64(_, d), None) => d.push(0),
            _ => self.misuse = self.misuse.or(Some(c)),
        }
    }

    /// Appends an integer or a null to column `c` (a [`Kind::OptI64`] column).
    pub fn opt_i64(&mut self, c: usize, x: Option<i64>) {
        match (&mut self.bufs[c], x) {
            (Buf::OptI64(v, d), Some(x)) => {
                v.push(x);
                d.push(1);
            }
            (Buf::OptI64(_, d), None) => d.push(0),
            _ => self.misuse = self.misuse.or(Some(c)),
        }
    }

    /// Appends a boolean to column `c` (a [`Kind::Bool`] column).
    pub fn bool(&mut self, c: usize, x: bool) {
        match &mut self.bufs[c] {
            Buf::Bool(v) => v.push(x),
            _ => self.misuse = self.misuse.or(Some(c)),
        }
    }

    /// Appends a text or a null to column `c` (a [`Kind::OptText`] column); each of
    /// the first [`MAX_INTERNED`] distinct texts of a row group is copied once.
    pub fn opt_text(&mut self, c: usize, x: Option<&str>) {
        match (&mut self.bufs[c], x) {
            (Buf::OptText(v, d, seen), Some(s)) => {
                let b = match seen.get(s) {
                    Some(b) => b.clone(),
                    // Texts that are all different (messages with numbers) are not
                    // kept: the map stays small.
                    None if seen.len() >= MAX_INTERNED => ByteArray::from(s),
                    None => {
                        let b = ByteArray::from(s);
                        seen.insert(s.into(), b.clone());
                        b
                    }
                };
                v.push(b);
                d.push(1);
            }
            (Buf::OptText(_, d, _), None) => d.push(0),
            _ => self.misuse = self.misuse.or(Some(c)),
        }
    }

    /// Ends `n` rows: every column must have been given exactly a value (or null) per
    /// row; a full row group is written.
    pub fn end_rows(&mut self, n: usize) -> Result<()> {
        if let Some(c) = self.misuse {
            bail!(
                "Parquet column {}: a value of another type was given",
                self.names[c]
            );
        }
        self.rows += n;
        for (b, name) in self.bufs.iter().zip(&self.names) {
            if b.rows() != self.rows {
                bail!(
                    "Parquet column {name}: {} values for {} rows (row {})",
                    b.rows(),
                    self.rows,
                    self.written + self.rows as u64
                );
            }
        }
        if self.rows >= self.group_rows {
            self.write_group()?;
        }
        Ok(())
    }

    /// Ends one row.
    pub fn end_row(&mut self) -> Result<()> {
        self.end_rows(1)
    }

    /// Writes the rows held as one row group.
    fn write_group(&mut self) -> Result<()> {
        if self.rows == 0 {
            return Ok(());
        }
        let mut group = self.writer.next_row_group()?;
        for b in &mut self.bufs {
            let mut col = group
                .next_column()?
                .context("Parquet: fewer columns in the schema than buffers")?;
            match b {
                Buf::F64(v) => {
                    col.typed::<DoubleType>().write_batch(v, None, None)?;
                }
                Buf::OptF64(v, d) => {
                    col.typed::<DoubleType>().write_batch(v, Some(d), None)?;
                }
                Buf::OptI64(v, d) => {
                    col.typed::<Int64Type>().write_batch(v, Some(d), None)?;
                }
                Buf::Bool(v) => {
                    col.typed::<BoolType>().write_batch(v, None, None)?;
                }
                Buf::OptText(v, d, _) => {
                    col.typed::<ByteArrayType>().write_batch(v, Some(d), None)?;
                }
            }
            col.close()?;
            b.clear();
        }
        group.close()?;
        self.written += self.rows as u64;
        self.rows = 0;
        Ok(())
    }

    /// Writes the last rows and the footer: the sink back, and the rows written.
    pub fn finish(mut self) -> Result<(W, u64)> {
        self.write_group()?;
        let rows = self.written;
        let out = self.writer.into_inner()?;
        Ok((out, rows))
    }
}

#[cfg(test)]
pub(crate) mod tests;
