//! The point cloud of `pkm workspace --out DIR`: every point's table (`points.csv`,
//! streamed, or `points.parquet`) and, for a map over three axes, `points.ply`.

use anyhow::Result;
use pkm::workspace::WorkspaceMap;
use pkm::DynMechanism;
use std::path::Path;

use crate::columnar::{machine_metadata, Kind, SeriesFormat, Table, GROUP_ROWS};
use crate::io::AtomicFile;

/// The point cloud: the table of every point (points.csv, streamed, six decimals; or
/// points.parquet, full precision), and for a map over three axes points.ply with the
/// reachable ones and their condition number (binary little-endian doubles: 32 bytes a
/// point, read by MeshLab, CloudCompare, Open3D and ParaView). The two files are
/// written by two threads at once.
pub(super) fn write_points(
    m: &dyn DynMechanism,
    wm: &WorkspaceMap,
    out: &Path,
    format: SeriesFormat,
    inputs: &[&Path],
) -> Result<()> {
    let table = AxisTable::new(m, wm);
    std::thread::scope(|scope| {
        let csv = scope.spawn(|| match format {
            SeriesFormat::Csv => write_points_csv(m, wm, &table, out, inputs),
            SeriesFormat::Parquet => write_points_parquet(m, wm, &table, out, inputs),
        });
        let ply = if wm.axes.len() == 3 {
            write_points_ply(m, wm, &table, out, inputs)
        } else {
            Ok(())
        };
        let csv = csv
            .join()
            .unwrap_or_else(|_| Err(anyhow::anyhow!("the point table's writer panicked")));
        csv.and(ply)
    })
}

/// The grid values of every map axis in user units, so that a point's coordinates
/// come from its index without allocation.
struct AxisTable {
    /// Per axis, its values in user units.
    values: Vec<Vec<f64>>,
}

impl AxisTable {
    fn new(m: &dyn DynMechanism, wm: &WorkspaceMap) -> Self {
        let values = wm
            .axes
            .iter()
            .map(|ax| {
                let q = m.coordinates()[ax.coordinate].quantity;
                (0..ax.count()).map(|i| q.to_user(ax.value(i))).collect()
            })
            .collect();
        AxisTable { values }
    }

    /// The axis values of point `k` into `out` (the last axis varies fastest, as
    /// [`WorkspaceMap::coords`]).
    fn point(&self, k: usize, out: &mut [f64]) {
        let mut rem = k;
        for (a, v) in self.values.iter().enumerate().rev() {
            out[a] = v[rem % v.len()];
            rem /= v.len();
        }
    }
}

/// The point table's axis columns: `X_mm`, `A_deg`, ... per map axis.
fn axis_columns(m: &dyn DynMechanism, wm: &WorkspaceMap) -> Vec<String> {
    wm.axes
        .iter()
        .map(|x| {
            let c = &m.coordinates()[x.coordinate];
            format!("{}_{}", c.name, c.quantity.unit())
        })
        .collect()
}

/// points.parquet: the columns of points.csv (the axes in user units, `reachable`,
/// `status`, `condition` null where unreachable, `binding` null where no limit binds),
/// at full precision, in row groups written as they fill; the machine in its metadata.
fn write_points_parquet(
    m: &dyn DynMechanism,
    wm: &WorkspaceMap,
    table: &AxisTable,
    out: &Path,
    inputs: &[&Path],
) -> Result<()> {
    let n = wm.axes.len();
    let mut columns: Vec<(String, Kind)> = axis_columns(m, wm)
        .into_iter()
        .map(|c| (c, Kind::F64))
        .collect();
    for (c, k) in [
        ("reachable", Kind::Bool),
        ("status", Kind::OptText),
        ("condition", Kind::OptF64),
        ("binding", Kind::OptText),
    ] {
        columns.push((c.to_string(), k));
    }
    let meta = machine_metadata(
        m,
        "pkm workspace grid points: axes (units in the column names), reachable, status, \
         condition number, binding limit",
    );
    let mut file = AtomicFile::create(&out.join("points.parquet"), inputs)?;
    // Row groups found by the grid axes.
    let axes: Vec<usize> = (0..n).collect();
    let mut t = Table::create(&mut file, &columns, &axes, meta, GROUP_ROWS)?;
    let mut x = vec![0.0; n];
    for (k, p) in wm.points.iter().enumerate() {
        table.point(k, &mut x);
        for (c, v) in x.iter().enumerate() {
            t.f64(c, *v);
        }
        t.bool(n, p.reachable);
        t.opt_text(n + 1, Some(p.status.name()));
        t.opt_f64(n + 2, p.reachable.then_some(p.condition));
        t.opt_text(n + 3, p.binding.as_deref());
        t.end_row()?;
    }
    t.finish()?;
    file.commit()
}

fn write_points_csv(
    m: &dyn DynMechanism,
    wm: &WorkspaceMap,
    table: &AxisTable,
    out: &Path,
    inputs: &[&Path],
) -> Result<()> {
    use crate::fixed::push_fixed6;
    use std::io::Write as _;
    let names = axis_columns(m, wm);
    let mut csv = AtomicFile::create(&out.join("points.csv"), inputs)?;
    let mut row = format!("{},reachable,status,condition,binding\n", names.join(",")).into_bytes();
    let mut x = vec![0.0; wm.axes.len()];
    for (k, p) in wm.points.iter().enumerate() {
        table.point(k, &mut x);
        for v in &x {
            push_fixed6(&mut row, *v);
            row.push(b',');
        }
        row.extend_from_slice(if p.reachable { b"true," } else { b"false," });
        row.extend_from_slice(p.status.name().as_bytes());
        row.push(b',');
        if p.reachable {
            push_fixed6(&mut row, p.condition);
        }
        row.push(b',');
        let binding = p.binding.as_deref().unwrap_or("");
        if binding.contains([',', '"', '\n']) {
            row.extend_from_slice(crate::commands::ik::csv_text(binding).as_bytes());
        } else {
            row.extend_from_slice(binding.as_bytes());
        }
        row.push(b'\n');
        if row.len() > 1 << 16 {
            csv.write_all(&row)?;
            row.clear();
        }
    }
    csv.write_all(&row)?;
    csv.commit()
}

fn write_points_ply(
    m: &dyn DynMechanism,
    wm: &WorkspaceMap,
    table: &AxisTable,
    out: &Path,
    inputs: &[&Path],
) -> Result<()> {
    use std::io::Write as _;
    let reachable = wm.points.iter().filter(|p| p.reachable).count();
    let mut ply = AtomicFile::create(&out.join("points.ply"), inputs)?;
    write!(
        ply,
        "ply\nformat binary_little_endian 1.0\ncomment pkm workspace: reachable points of {}, mm\nelement vertex {reachable}\nproperty double x\nproperty double y\nproperty double z\nproperty double condition\nend_header\n",
        m.name().replace('\n', " ")
    )?;
    let mut buf = Vec::with_capacity(1 << 16);
    let mut x = [0.0; 3];
    for (k, p) in wm.points.iter().enumerate() {
        if p.reachable {
            table.point(k, &mut x);
            for v in x.into_iter().chain([p.condition]) {
                buf.extend_from_slice(&v.to_le_bytes());
            }
            if buf.len() >= 1 << 16 {
                ply.write_all(&buf)?;
                buf.clear();
            }
        }
    }
    ply.write_all(&buf)?;
    ply.commit()
}
