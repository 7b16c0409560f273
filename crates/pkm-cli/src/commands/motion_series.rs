//! `pkm motion`'s sample series: actuators.csv or actuators.parquet, written on a
//! thread of its own while the run goes on.

use std::io::Write;
use std::sync::mpsc::{sync_channel, Receiver, SyncSender};

use anyhow::Result;
use indicatif::ProgressBar;
use pkm::analysis::motion::{sample_columns, SampleRow, SampleSink};
use pkm::Machine;

use crate::columnar::{machine_metadata, Kind, SeriesFormat, Table, GROUP_ROWS};
use crate::fixed::{push_fixed6, push_u64};

/// Rows per block handed from the run to the writer thread.
const BLOCK_ROWS: usize = 4096;

/// A block of rows in user units: per row `t`, the coordinates, then per actuator
/// `q, q', q''` (`width` numbers), and the row's G-code line.
struct Block {
    values: Vec<f64>,
    lines: Vec<Option<u64>>,
}

/// Writes samples as rows (user units) of a CSV or Parquet file and drives the
/// progress bar.
///
/// The run only converts each sample to user units and appends it to a block; a
/// writer thread formats full blocks (or transposes them into Parquet columns) and
/// writes them while the run goes on (the formatting of 26 numbers per sample had cost
/// more than the kinematics). Three blocks circulate between the threads, so memory
/// stays flat and no block is allocated per row; rows reach the file in the order of
/// the samples.
pub struct SeriesSink {
    /// Full blocks to the writer; `None` when no rows are written.
    tx: Option<SyncSender<Block>>,
    /// Blocks the writer has written, for reuse.
    back: Option<Receiver<Block>>,
    block: Block,
    /// Coordinate and actuator quantities, for the units (read once, not per sample).
    coords: Vec<pkm::Quantity>,
    acts: Vec<pkm::Quantity>,
    bar: Option<ProgressBar>,
}

/// The writer thread of a [`SeriesSink`]; `finish` returns what writing gave.
pub struct SeriesWriter<'scope> {
    handle: Option<std::thread::ScopedJoinHandle<'scope, Result<()>>>,
}

impl SeriesSink {
    /// A sink writing `format` rows to `out` (a CSV's header row now), and the writer
    /// thread of the rows in `scope`; a progress bar over `bytes` of program when that
    /// is large.
    pub fn start<'scope, 'env>(
        scope: &'scope std::thread::Scope<'scope, 'env>,
        machine: &Machine,
        out: Option<&'env mut (dyn Write + Send)>,
        format: SeriesFormat,
        bytes: u64,
    ) -> Result<(Self, SeriesWriter<'scope>)> {
        let m = machine.mechanism();
        let width = 1 + m.coordinates().len() + 3 * m.actuators().len();
        let new_block = || Block {
            values: Vec::with_capacity(BLOCK_ROWS * width),
            lines: Vec::with_capacity(BLOCK_ROWS),
        };
        let writing = out.is_some();
        let (tx, back, handle) = match out {
            Some(w) => {
                let (tx, rx) = sync_channel::<Block>(1);
                let (back_tx, back) = sync_channel::<Block>(2);
                for _ in 0..2 {
                    back_tx.send(new_block()).ok();
                }
                let handle = match format {
                    SeriesFormat::Csv => {
                        writeln!(w, "{}", sample_columns(machine).join(","))?;
                        scope.spawn(move || write_csv(rx, back_tx, w, width))
                    }
                    SeriesFormat::Parquet => {
                        let table = parquet_table(machine, w, GROUP_ROWS)?;
                        scope.spawn(move || write_parquet(rx, back_tx, table, width))
                    }
                };
                (Some(tx), Some(back), Some(handle))
            }
            None => (None, None, None),
        };
        let bar = crate::progress::bar(bytes, 1_000_000, "{bar:40} {bytes}/{total_bytes} {eta}");
        Ok((
            SeriesSink {
                tx,
                back,
                // Without a file (--summary-only) the block stays empty: nothing held.
                block: if writing {
                    new_block()
                } else {
                    Block {
                        values: Vec::new(),
                        lines: Vec::new(),
                    }
                },
                coords: m.coordinates().iter().map(|c| c.quantity).collect(),
                acts: m.actuators().iter().map(|a| a.quantity).collect(),
                bar,
            },
            SeriesWriter { handle },
        ))
    }

    /// Hands the current block to the writer and takes a written one back.
    fn flush(&mut self) -> pkm::Result<()> {
        let (Some(tx), Some(back)) = (&self.tx, &self.back) else {
            return Ok(());
        };
        let stopped = || pkm::Error::InvalidInput {
            what: "actuators".into(),
            message: "writing stopped".into(),
        };
        let next = back.recv().map_err(|_| stopped())?;
        let full = std::mem::replace(&mut self.block, next);
        tx.send(full).map_err(|_| stopped())
    }

    /// Writes the last rows, ends the writer thread and clears the progress bar: what
    /// writing gave (an error of the file system, the first one).
    pub fn finish(mut self, writer: SeriesWriter<'_>) -> Result<()> {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
        let flushed = if self.block.lines.is_empty() {
            Ok(())
        } else {
            self.flush()
        };
        // Closing the channel ends the writer's loop.
        self.tx = None;
        let written = match writer.handle {
            Some(h) => h
                .join()
                .unwrap_or_else(|_| Err(anyhow::anyhow!("the writer thread panicked"))),
            None => Ok(()),
        };
        written?;
        Ok(flushed?)
    }
}

/// The CSV writer thread: formats each block (six decimals, as `{:.6}`) and writes it,
/// then returns the block for reuse.
fn write_csv(
    rx: Receiver<Block>,
    back: SyncSender<Block>,
    w: &mut (dyn Write + Send),
    width: usize,
) -> Result<()> {
    let mut buf: Vec<u8> = Vec::with_capacity(BLOCK_ROWS * width * 12);
    for mut block in rx {
        buf.clear();
        for (row, line) in block.values.chunks_exact(width).zip(&block.lines) {
            push_fixed6(&mut buf, row[0]);
            buf.push(b',');
            if let Some(l) = line {
                push_u64(&mut buf, *l);
            }
            for v in &row[1..] {
                buf.push(b',');
                push_fixed6(&mut buf, *v);
            }
            buf.push(b'\n');
        }
        w.write_all(&buf)?;
        block.values.clear();
        block.lines.clear();
        // The run may have finished and gone: nothing more to hand back then.
        let _ = back.send(block);
    }
    Ok(())
}

/// The Parquet table of a run's samples: the CSV's columns (`t_s`, `line`, the
/// coordinates, each actuator's `q, q', q''`, user units in the names), doubles at full
/// precision, `line` an integer or null; the machine in the file's metadata.
fn parquet_table<'w>(
    machine: &Machine,
    w: &'w mut (dyn Write + Send),
    group_rows: usize,
) -> Result<Table<&'w mut (dyn Write + Send)>> {
    let m = machine.mechanism();
    let columns: Vec<(String, Kind)> = sample_columns(machine)
        .into_iter()
        .enumerate()
        .map(|(i, n)| (n, if i == 1 { Kind::OptI64 } else { Kind::F64 }))
        .collect();
    let meta = machine_metadata(
        m,
        "pkm motion samples: time, G-code line, pose coordinates, per actuator position, \
         velocity, acceleration (units in the column names)",
    );
    // Row groups found by time and G-code line.
    Table::create(w, &columns, &[0, 1], meta, group_rows)
}

/// The Parquet writer thread: transposes each block into the table's columns (a row
/// group is written every [`GROUP_ROWS`] rows), then returns the block for reuse.
fn write_parquet(
    rx: Receiver<Block>,
    back: SyncSender<Block>,
    mut table: Table<&mut (dyn Write + Send)>,
    width: usize,
) -> Result<()> {
    for mut block in rx {
        let rows = block.lines.len();
        table.f64_strided(0, &block.values, width);
        for l in &block.lines {
            table.opt_i64(1, l.map(|l| l as i64));
        }
        for c in 1..width {
            table.f64_strided(c + 1, &block.values[c..], width);
        }
        table.end_rows(rows)?;
        block.values.clear();
        block.lines.clear();
        let _ = back.send(block);
    }
    table.finish()?;
    Ok(())
}

impl SampleSink for SeriesSink {
    fn sample(&mut self, s: &SampleRow) -> pkm::Result<()> {
        if self.tx.is_none() {
            return Ok(());
        }
        let b = &mut self.block;
        b.lines.push(s.line);
        b.values.push(s.t);
        for (qn, x) in self.coords.iter().zip(s.x) {
            b.values.push(qn.to_user(*x));
        }
        for (i, qn) in self.acts.iter().enumerate() {
            for v in [s.q[i], s.qd[i], s.qdd[i]] {
                b.values.push(qn.to_user(v));
            }
        }
        if b.lines.len() == BLOCK_ROWS {
            self.flush()?;
        }
        Ok(())
    }

    fn progress(&mut self, bytes: u64) {
        if let Some(b) = &self.bar {
            b.inc(bytes);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::commands::load;
    use parquet::file::reader::FileReader;
    use parquet::record::Field;
    use std::path::Path;

    fn hexapod() -> Machine {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/machines");
        load(&dir.join("hexapod-linuxcnc.toml")).unwrap()
    }

    /// The pose and actuator values of sample `k` fed by [`feed`].
    fn values(k: usize) -> ([f64; 6], [f64; 6]) {
        let v = k as f64;
        let x = [v * 1e-3, -v, 0.25, 0.01 * v, -0.02, 1e-7 * v];
        let q = [v + 0.5e-6, 1.0, 2.0, 3.0, 4.0, -v];
        (x, q)
    }

    /// Feeds `n` samples (some without a line) to a sink writing `format` into `w`.
    fn feed(
        machine: &Machine,
        w: &mut (dyn Write + Send),
        format: SeriesFormat,
        n: usize,
    ) -> (pkm::Result<()>, Result<()>) {
        std::thread::scope(|scope| {
            let (mut sink, csv) = SeriesSink::start(scope, machine, Some(w), format, 0).unwrap();
            let mut fed = Ok(());
            for k in 0..n {
                let (x, q) = values(k);
                fed = sink.sample(&SampleRow {
                    t: k as f64 * 1e-3,
                    line: (k % 3 != 0).then_some(k as u64),
                    x: &x,
                    q: &q,
                    qd: &q,
                    qdd: &x,
                });
                if fed.is_err() {
                    break;
                }
            }
            (fed, sink.finish(csv))
        })
    }

    /// The rows the writer thread formats, in blocks, are the rows formatted one by one
    /// with `{:.6}`, in the order of the samples.
    #[test]
    fn rows_are_written_in_order_as_formatted_one_by_one() {
        let machine = hexapod();
        let m = machine.mechanism();
        let n = 3 * BLOCK_ROWS + 17;
        let mut out: Vec<u8> = Vec::new();
        let (fed, written) = feed(&machine, &mut out, SeriesFormat::Csv, n);
        fed.unwrap();
        written.unwrap();
        let text = String::from_utf8(out).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), sample_columns(&machine).join(","));
        let mut rows = 0;
        for (k, row) in lines.enumerate() {
            let (x, q) = values(k);
            let mut want = vec![format!("{:.6}", k as f64 * 1e-3)];
            want.push(if k % 3 != 0 {
                k.to_string()
            } else {
                String::new()
            });
            for (c, x) in m.coordinates().iter().zip(x) {
                want.push(format!("{:.6}", c.quantity.to_user(x)));
            }
            for (i, a) in m.actuators().iter().enumerate() {
                for v in [q[i], q[i], x[i]] {
                    want.push(format!("{:.6}", a.quantity.to_user(v)));
                }
            }
            assert_eq!(row, want.join(","), "row {k}");
            rows += 1;
        }
        assert_eq!(rows, n);
    }

    /// The Parquet file holds the same rows as the CSV at full precision: every value
    /// the user-unit conversion of the sample's, bit for bit, `line` null where the
    /// sample has none, in order over several blocks and row groups; the columns are
    /// the CSV's header, the machine is in the metadata.
    #[test]
    fn parquet_rows_are_the_samples_bit_for_bit() {
        let machine = hexapod();
        let m = machine.mechanism();
        // Two full row groups and a part: 2 * 16 blocks + 5 rows.
        let n = 2 * GROUP_ROWS + 5;
        let mut out: Vec<u8> = Vec::new();
        let (fed, written) = feed(&machine, &mut out, SeriesFormat::Parquet, n);
        fed.unwrap();
        written.unwrap();
        let r = crate::columnar::tests::reader(&out);
        let meta = r.metadata();
        assert_eq!(meta.num_row_groups(), 3);
        assert_eq!(meta.file_metadata().num_rows(), n as i64);
        let kv = meta.file_metadata().key_value_metadata().unwrap();
        assert!(kv
            .iter()
            .any(|k| k.key == "pkm.machine" && k.value.as_deref() == Some(m.name())));
        let names: Vec<String> = meta
            .file_metadata()
            .schema_descr()
            .columns()
            .iter()
            .map(|c| c.name().to_string())
            .collect();
        assert_eq!(names, sample_columns(&machine));
        let mut k = 0;
        for row in r.get_row_iter(None).unwrap() {
            let row = row.unwrap();
            let f: Vec<&Field> = row.get_column_iter().map(|(_, f)| f).collect();
            let (x, q) = values(k);
            let mut want = vec![k as f64 * 1e-3];
            for (c, x) in m.coordinates().iter().zip(x) {
                want.push(c.quantity.to_user(x));
            }
            for (i, a) in m.actuators().iter().enumerate() {
                for v in [q[i], q[i], x[i]] {
                    want.push(a.quantity.to_user(v));
                }
            }
            match f[1] {
                Field::Long(l) => assert_eq!(*l, k as i64, "row {k}"),
                Field::Null => assert_eq!(k % 3, 0, "row {k}"),
                o => panic!("row {k}: line {o:?}"),
            }
            let got: Vec<u64> = f
                .iter()
                .enumerate()
                .filter(|(c, _)| *c != 1)
                .map(|(c, v)| match v {
                    Field::Double(d) => d.to_bits(),
                    o => panic!("row {k} column {c}: {o:?}"),
                })
                .collect();
            let want: Vec<u64> = want.iter().map(|v| v.to_bits()).collect();
            assert_eq!(got, want, "row {k}");
            k += 1;
        }
        assert_eq!(k, n);
    }

    /// A writer that fails after `left` bytes.
    struct Failing {
        left: usize,
    }

    impl Write for Failing {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            if b.len() > self.left {
                return Err(std::io::Error::other("disk full"));
            }
            self.left -= b.len();
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// A failing file system stops the run (no hang, no lost error): the sink refuses
    /// further samples and `finish` returns the writer's error.
    #[test]
    fn a_write_error_stops_the_run_and_is_reported() {
        let machine = hexapod();
        for format in [SeriesFormat::Csv, SeriesFormat::Parquet] {
            let mut w = Failing { left: 100_000 };
            let (fed, written) = feed(&machine, &mut w, format, 2 * GROUP_ROWS);
            assert!(
                fed.is_err(),
                "{format:?}: the run went on after the writer failed"
            );
            let e = format!("{:#}", written.unwrap_err());
            assert!(e.contains("disk full"), "{format:?}: {e}");
        }
    }
}
