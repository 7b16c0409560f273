//! `pkm workspace`: reachable workspace, binding limits and conditioning on a grid.

use crate::parse_convention;
use anyhow::{bail, Context, Result};
use clap::Args;
use pkm::workspace::{flat_index, GridAxis, WorkspaceMap, WorkspaceSummary};
use pkm::Convention;
use pkm::{DynMechanism, Machine, PoseSpace};
use serde_json::json;
use std::path::{Path, PathBuf};

use super::load;
use crate::columnar::SeriesFormat;
use crate::io::write_atomic;
use crate::out::outln;
use crate::poses::{parse_list, pose_from_user};
use crate::report::heatmap::{slice_svg, Cell, Scale};

mod extra;
mod points;
pub mod stiffness;
mod summary;
use points::write_points;

#[derive(Args)]
pub struct WorkspaceArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// Constant orientation A,B,C (deg) of the map; default: the home orientation.
    #[arg(long, allow_hyphen_values = true)]
    pub orientation: Option<String>,
    /// Grid bounds min,max per axis (X,Y,Z in mm for spatial machines).
    #[arg(long, allow_hyphen_values = true)]
    pub bounds: Option<String>,
    /// Grid step (mm, or deg for angle axes); default: 1/40 of each range.
    #[arg(long)]
    pub step: Option<f64>,
    /// Total orientation workspace: reachable only if reachable at tilts of this many
    /// degrees in 8 directions as well as untilted.
    #[arg(long)]
    pub tilt: Option<f64>,
    /// Orientation workspace at a point X,Y,Z: the largest reachable tilt per direction.
    #[arg(long, allow_hyphen_values = true)]
    pub at: Option<String>,
    /// Largest tilt searched with --at (deg).
    #[arg(long, default_value_t = 60.0)]
    pub max_tilt: f64,
    /// Convention of --orientation.
    #[arg(long, default_value = "rpy", value_parser = parse_convention)]
    pub rotation: Convention,
    /// Performance atlas: largest rate of every pose coordinate (mm/s, deg/s), one value
    /// per coordinate; writes atlas.csv and maps of the actuator positions and of the
    /// actuator velocities and accelerations these capacities need.
    #[arg(long, allow_hyphen_values = true)]
    pub atlas_velocity: Option<String>,
    /// Performance atlas: largest acceleration of every pose coordinate (mm/s^2, deg/s^2).
    #[arg(long, allow_hyphen_values = true)]
    pub atlas_acceleration: Option<String>,
    /// Forward workspace: forward kinematics over a grid of the actuator strokes
    /// (machines with at most 3 actuators); writes forward.csv and maps of the pose.
    #[arg(long)]
    pub forward: bool,
    /// Step of the --forward grid (mm or deg); default 1/40 of each stroke.
    #[arg(long)]
    pub forward_step: Option<f64>,
    /// Stiffness map: the smallest stiffness of the tool tip against a force (N/um) at
    /// every reachable point, from the drives' `stiffness` in the machine file; writes
    /// stiffness.csv and stiffness slice maps, the weakest point in summary.json.
    #[arg(long)]
    pub stiffness: bool,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
    /// Format of the point table: points.csv (six decimals) or points.parquet (full
    /// precision, typed columns; pandas.read_parquet, polars, DuckDB).
    #[arg(long, value_enum, default_value = "csv")]
    pub format: SeriesFormat,
    /// Print summary.json to stdout.
    #[arg(long)]
    pub json: bool,
}

/// [`pkm::analysis::workspace::map`] with a spinner when `progress`.
pub fn run_map(
    machine: &Machine,
    base: &[f64],
    bounds: Option<&[f64]>,
    step: Option<f64>,
    orientations: &[[f64; 3]],
    progress: bool,
) -> Result<(WorkspaceMap, String)> {
    let bar = crate::progress::spinner(progress, "{spinner} {pos} points mapped {elapsed}");
    let tick = |n: u64| {
        if let Some(b) = &bar {
            b.inc(n);
        }
    };
    let r = pkm::analysis::workspace::map(machine, base, bounds, step, orientations, &tick);
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    Ok(r?)
}

/// Summary with user units.
pub fn summarise(m: &dyn DynMechanism, wm: &WorkspaceMap) -> WorkspaceSummary {
    wm.summary_of(m.coordinates())
}

/// The (horizontal, vertical) axis pairs of the standard slices: the first two axes,
/// and for 3D grids also the first and last.
pub fn slice_pairs(n: usize) -> Vec<(usize, usize)> {
    match n {
        0 | 1 => Vec::new(),
        3 => vec![(0, 1), (0, 2)],
        _ => vec![(0, 1)],
    }
}

/// Cells of the slice of a grid over axes `ha`, `va` through `base` (other axes fixed at
/// the grid value nearest the base), with the value of each flat grid index, and the
/// "at ..." text naming the fixed axes. `coord` gives each axis' name and quantity.
pub fn slice_cells(
    axes: &[GridAxis],
    base: &[f64],
    coord: &dyn Fn(usize) -> (String, pkm::Quantity),
    ha: usize,
    va: usize,
    value: &dyn Fn(usize) -> Option<f64>,
) -> (Vec<Cell>, String) {
    let n = axes.len();
    let fixed: Vec<usize> = (0..n).filter(|i| *i != ha && *i != va).collect();
    let fix_idx: Vec<usize> = fixed
        .iter()
        .map(|&i| {
            let a = &axes[i];
            (((base[a.coordinate] - a.min) / a.step).round().max(0.0) as usize).min(a.count() - 1)
        })
        .collect();
    let mut cells = Vec::new();
    for ih in 0..axes[ha].count() {
        for iv in 0..axes[va].count() {
            let mut idx = vec![0; n];
            idx[ha] = ih;
            idx[va] = iv;
            for (f, fi) in fixed.iter().zip(&fix_idx) {
                idx[*f] = *fi;
            }
            cells.push(Cell {
                h: coord(ha).1.to_user(axes[ha].value(ih)),
                v: coord(va).1.to_user(axes[va].value(iv)),
                value: value(flat_index(axes, &idx)),
            });
        }
    }
    let at = fixed
        .iter()
        .zip(&fix_idx)
        .map(|(&f, &fi)| {
            let (name, q) = coord(f);
            // Rounded first: a grid value a rounding below zero would read "-0.00".
            let v = (q.to_user(axes[f].value(fi)) * 100.0).round() / 100.0 + 0.0;
            format!("{name} = {v:.2} {}", q.unit())
        })
        .collect::<Vec<_>>()
        .join(", ");
    (cells, at)
}

/// Draws one slice heat map: name of the file, SVG.
#[allow(clippy::too_many_arguments)]
pub fn slice_plot(
    axes: &[GridAxis],
    base: &[f64],
    coord: &dyn Fn(usize) -> (String, pkm::Quantity),
    (ha, va): (usize, usize),
    what: &str,
    scale: Scale,
    value: &dyn Fn(usize) -> Option<f64>,
) -> Result<String> {
    let (cells, at) = slice_cells(axes, base, coord, ha, va, value);
    let (hn, hq) = coord(ha);
    let (vn, vq) = coord(va);
    let title = if at.is_empty() {
        what.to_string()
    } else {
        format!("{what} at {at}")
    };
    slice_svg(
        &title,
        &format!("{hn} [{}]", hq.unit()),
        &format!("{vn} [{}]", vq.unit()),
        scale,
        &cells,
        hq.to_user(axes[ha].step),
        vq.to_user(axes[va].step),
        (580, 480),
    )
}

/// The standard condition-number slices (through the base pose): file name, SVG.
pub fn slices(m: &dyn DynMechanism, wm: &WorkspaceMap) -> Result<Vec<(String, String)>> {
    let coord = |i: usize| {
        let c = &m.coordinates()[wm.axes[i].coordinate];
        (c.name.clone(), c.quantity)
    };
    let mut out = Vec::new();
    for (ha, va) in slice_pairs(wm.axes.len()) {
        let value = |k: usize| {
            let p = &wm.points[k];
            p.reachable.then_some(p.condition)
        };
        let what = format!("{}{} slice", coord(ha).0, coord(va).0);
        let svg = slice_plot(
            &wm.axes,
            &wm.base,
            &coord,
            (ha, va),
            &what,
            Scale::Log10("condition"),
            &value,
        )?;
        out.push((
            format!("slice-{}{}.svg", coord(ha).0, coord(va).0).to_lowercase(),
            svg,
        ));
    }
    Ok(out)
}

/// The map's pose: home, or home's position at `--orientation`.
fn base_pose(a: &WorkspaceArgs, m: &dyn DynMechanism) -> Result<Vec<f64>> {
    let mut base = m.home();
    if let Some(o) = &a.orientation {
        if m.pose_space() != PoseSpace::Spatial {
            bail!("--orientation needs a machine with X, Y, Z, A, B, C");
        }
        let v = parse_list(o, "--orientation")?;
        let mut pose = vec![base[0], base[1], base[2]];
        pose.extend(v);
        base = pose_from_user(m, &pose, a.rotation)?;
    }
    Ok(base)
}

/// `--at`: the orientation workspace at a point, to `DIR/tilt.json`.
fn tilt_at(
    a: &WorkspaceArgs,
    machine: &Machine,
    base: &[f64],
    at: &str,
    inputs: &[&Path],
) -> Result<u8> {
    let m = machine.mechanism();
    let p = parse_list(at, "--at")?;
    let mut x = pose_from_user(m, &p[..3.min(p.len())], a.rotation)?;
    if x.len() == 6 {
        x[3..6].copy_from_slice(&base[3..6]);
    }
    let az: Vec<f64> = (0..36).map(|k| (k as f64 * 10.0).to_radians()).collect();
    let tilts =
        pkm::analysis::workspace::reachable_tilt(machine, &x, &az, a.max_tilt.to_radians())?;
    let min = tilts.iter().copied().fold(f64::INFINITY, f64::min);
    let v = json!({
        "position": &p[..3.min(p.len())],
        "azimuth_deg": az.iter().map(|a| a.to_degrees()).collect::<Vec<_>>(),
        "max_tilt_deg": tilts.iter().map(|t| t.to_degrees()).collect::<Vec<_>>(),
        "reachable_tilt_all_directions_deg": min.to_degrees(),
    });
    write_atomic(
        &a.out.join("tilt.json"),
        serde_json::to_string_pretty(&v)?.as_bytes(),
        inputs,
    )?;
    outln!(
        "reachable tilt in every direction at this point: {:.3} deg (search up to {} deg)",
        min.to_degrees(),
        a.max_tilt
    )?;
    Ok(0)
}

/// The map over `--bounds` (else the machine's reach), at every tilt of `--tilt`.
fn map(a: &WorkspaceArgs, machine: &Machine, base: &[f64]) -> Result<(WorkspaceMap, String)> {
    let bounds = match &a.bounds {
        Some(b) => Some(parse_list(b, "--bounds")?),
        None => None,
    };
    let orientations: Vec<[f64; 3]> = a
        .tilt
        .map(|t| pkm::workspace::tilt_orientations(t.to_radians()))
        .unwrap_or_default();
    run_map(
        machine,
        base,
        bounds.as_deref(),
        a.step,
        &orientations,
        true,
    )
}

/// The point files and the slice heat maps; the point files are written while the
/// slices are drawn.
fn write_points_and_slices(
    a: &WorkspaceArgs,
    m: &dyn DynMechanism,
    wm: &WorkspaceMap,
    inputs: &[&Path],
) -> Result<()> {
    std::thread::scope(|scope| -> Result<()> {
        let points = scope.spawn(|| write_points(m, wm, &a.out, a.format, inputs));
        let drawn = slices(m, wm).and_then(|list| {
            list.iter()
                .try_for_each(|(name, svg)| write_atomic(&a.out.join(name), svg.as_bytes(), inputs))
        });
        points
            .join()
            .unwrap_or_else(|_| Err(anyhow::anyhow!("the point-cloud writer panicked")))?;
        drawn
    })
}

pub fn run(a: &WorkspaceArgs) -> Result<u8> {
    let machine: Machine = load(&a.machine)?;
    let m = machine.mechanism();
    let base = base_pose(a, m)?;
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let inputs = [a.machine.as_path()];
    if let Some(at) = &a.at {
        return tilt_at(a, &machine, &base, at, &inputs);
    }
    let start = std::time::Instant::now();
    let (wm, grid_bounds) = map(a, &machine, &base)?;
    let secs = start.elapsed().as_secs_f64();
    let s = summarise(m, &wm);
    let mapped = Mapped {
        wm: &wm,
        summary: &s,
        base: &base,
        grid_bounds: &grid_bounds,
        seconds: secs,
    };
    let mut summary = summary::summary_json(m, &mapped, a.tilt)?;
    let extra = extra::write_extras(a, &machine, &mapped, &inputs)?;
    if let Some(o) = summary.as_object_mut() {
        o.extend(extra);
    }
    write_atomic(
        &a.out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
        &inputs,
    )?;
    write_points_and_slices(a, m, &wm, &inputs)?;
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&summary)?)?;
    } else {
        summary::print_text(m, &mapped)?;
        if let Some(w) = summary
            .pointer("/stiffness/weakest")
            .filter(|w| !w.is_null())
        {
            let at: Vec<String> = w["at"]
                .as_object()
                .into_iter()
                .flatten()
                .map(|(k, v)| format!("{k}={:.2}", v.as_f64().unwrap_or(f64::NAN)))
                .collect();
            outln!(
                "stiffness  weakest {:.2} N/um at {} (median {:.2} N/um)",
                w["stiffness_n_per_um"].as_f64().unwrap_or(f64::NAN),
                at.join(" "),
                summary
                    .pointer("/stiffness/median_n_per_um")
                    .and_then(|v| v.as_f64())
                    .unwrap_or(f64::NAN)
            )?;
        }
        outln!("wrote {}", a.out.display())?;
    }
    Ok(0)
}

/// A map made: what the summary, the text and the extra outputs are made of.
struct Mapped<'a> {
    wm: &'a WorkspaceMap,
    summary: &'a WorkspaceSummary,
    /// The map's pose.
    base: &'a [f64],
    /// What the grid's bounds are ("the machine's reach", the options).
    grid_bounds: &'a str,
    /// Time the map took.
    seconds: f64,
}
