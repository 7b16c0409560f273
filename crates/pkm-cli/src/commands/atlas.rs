//! `pkm workspace --atlas-velocity/--atlas-acceleration` (performance atlas) and
//! `pkm workspace --forward` (forward workspace over the actuator strokes).

use anyhow::{bail, Result};
use pkm::workspace::GridAxis;
use pkm::{DynMechanism, Machine};
use serde_json::json;

use super::workspace::{slice_pairs, slice_plot};
use crate::report::heatmap::Scale;

/// One atlas point (the library's row, here in user units).
pub use pkm::analysis::workspace::AtlasRow;

/// Atlas results with run-time sizes, user units.
pub struct DynAtlas {
    /// One row per grid point.
    pub points: Vec<AtlasRow>,
}

/// What an atlas or forward map writes: CSV text, plots (file name, SVG) and its part
/// of summary.json.
pub struct Outputs {
    /// The CSV table.
    pub csv: String,
    /// Plots.
    pub plots: Vec<(String, String)>,
    /// Summary.
    pub summary: serde_json::Value,
}

/// The atlas of a grid (`pkm::analysis::workspace::atlas`), in user units.
pub fn run_atlas(
    machine: &Machine,
    base: &[f64],
    axes: &[GridAxis],
    velocity: &[f64],
    acceleration: &[f64],
) -> Result<DynAtlas> {
    let bar = crate::progress::spinner(true, "{spinner} {pos} atlas points {elapsed}");
    let tick = |n: u64| {
        if let Some(b) = &bar {
            b.inc(n);
        }
    };
    let rows = pkm::analysis::workspace::atlas(machine, base, axes, velocity, acceleration, &tick);
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let rows = rows?;
    let acts = machine.mechanism().actuators();
    let user = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .zip(acts)
            .map(|(x, a)| a.quantity.to_user(*x))
            .collect()
    };
    Ok(DynAtlas {
        points: rows
            .into_iter()
            .map(|p| AtlasRow {
                reachable: p.reachable,
                q: user(&p.q),
                velocity: user(&p.velocity),
                acceleration: user(&p.acceleration),
            })
            .collect(),
    })
}

/// Forward-map results with run-time sizes.
pub struct DynForwardMap {
    /// Points in row-major order of the actuator axes.
    pub points: Vec<ForwardPoint>,
}

/// One point of a forward map.
pub struct ForwardPoint {
    /// Whether the pose was found within every limit.
    pub reachable: bool,
    /// The limit that binds where it is not.
    pub binding: Option<pkm::LimitName>,
    /// The pose (user units) when found.
    pub pose: Option<Vec<f64>>,
}

/// The forward map (`pkm::analysis::workspace::forward_map`), poses in user units.
pub fn run_forward(machine: &Machine, axes: &[GridAxis], start: &[f64]) -> Result<DynForwardMap> {
    let c = machine.mechanism().coordinates();
    let bar = crate::progress::spinner(true, "{spinner} {pos} forward solutions {elapsed}");
    let tick = |n: u64| {
        if let Some(b) = &bar {
            b.inc(n);
        }
    };
    let points = pkm::analysis::workspace::forward_map(machine, axes, start, &tick);
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let points = points?
        .into_iter()
        .map(|p| {
            let pose = p.pose.map(|x| {
                x.iter()
                    .zip(c)
                    .map(|(v, c)| c.quantity.to_user(*v))
                    .collect()
            });
            ForwardPoint {
                reachable: p.reachable,
                binding: p.binding,
                pose,
            }
        })
        .collect();
    Ok(DynForwardMap { points })
}

/// Converts a list of per-coordinate capacities from user units.
pub fn capacity(m: &dyn DynMechanism, list: Option<&[f64]>, flag: &str) -> Result<Vec<f64>> {
    let n = m.coordinates().len();
    match list {
        None => Ok(vec![0.0; n]),
        Some(v) if v.len() != n => bail!(
            "{flag}: expected {n} values (one per coordinate: {}), got {}",
            m.coordinates()
                .iter()
                .map(|c| c.name.as_str())
                .collect::<Vec<_>>()
                .join(","),
            v.len()
        ),
        Some(v) => {
            if let Some(x) = v.iter().find(|x| !x.is_finite() || **x < 0.0) {
                bail!("{flag}: expected magnitudes >= 0, found {x}");
            }
            Ok(v.iter()
                .zip(m.coordinates())
                .map(|(x, c)| c.quantity.from_user(*x))
                .collect())
        }
    }
}

/// Atlas outputs: CSV text, plots (file, SVG) and the summary JSON.
pub fn atlas_outputs(
    m: &dyn DynMechanism,
    axes: &[GridAxis],
    base: &[f64],
    a: &DynAtlas,
    coords_user: &dyn Fn(usize) -> Vec<f64>,
) -> Result<Outputs> {
    let coord = |i: usize| {
        let c = &m.coordinates()[axes[i].coordinate];
        (c.name.clone(), c.quantity)
    };
    let csv = atlas_csv(m, axes, a, coords_user);
    let mut plots = Vec::new();
    let mut summary = serde_json::Map::new();
    for (i, x) in m.actuators().iter().enumerate() {
        summary.insert(x.name.clone(), actuator_summary(a, i, x));
        plots.extend(actuator_plots(axes, base, &coord, a, i, x)?);
    }
    Ok(Outputs {
        csv,
        plots,
        summary: serde_json::Value::Object(summary),
    })
}

/// `atlas.csv`: per point its axis coordinates, whether reachable, and per actuator
/// the position, velocity and acceleration (empty where not finite).
fn atlas_csv(
    m: &dyn DynMechanism,
    axes: &[GridAxis],
    a: &DynAtlas,
    coords_user: &dyn Fn(usize) -> Vec<f64>,
) -> String {
    let acts = m.actuators();
    let mut head: Vec<String> = axes
        .iter()
        .map(|x| {
            let c = &m.coordinates()[x.coordinate];
            format!("{}_{}", c.name, c.quantity.unit())
        })
        .collect();
    head.push("reachable".into());
    for x in acts {
        let q = x.quantity;
        head.push(format!("{}_{}", x.name, q.unit()));
        head.push(format!("{}_velocity_{}", x.name, q.rate_unit(1)));
        head.push(format!("{}_acceleration_{}", x.name, q.rate_unit(2)));
    }
    let mut csv = head.join(",") + "\n";
    for (k, p) in a.points.iter().enumerate() {
        let mut row: Vec<String> = coords_user(k).iter().map(|v| format!("{v:.6}")).collect();
        row.push(p.reachable.to_string());
        for i in 0..acts.len() {
            for x in [p.q[i], p.velocity[i], p.acceleration[i]] {
                row.push(if x.is_finite() {
                    format!("{x:.6}")
                } else {
                    String::new()
                });
            }
        }
        csv.push_str(&row.join(","));
        csv.push('\n');
    }
    csv
}

/// The summary of actuator `x` (the `i`-th): its reachable range and the largest rates
/// needed.
fn actuator_summary(a: &DynAtlas, i: usize, x: &pkm::Actuator) -> serde_json::Value {
    let q = x.quantity;
    let peak = |sel: usize, sign: f64| {
        a.points
            .iter()
            .filter(|p| p.reachable)
            .map(|p| sign * p.get(sel, i))
            .fold(f64::NAN, f64::max)
            * sign
    };
    let range = [peak(0, -1.0), peak(0, 1.0)];
    json!({
        "unit": q.unit(),
        "range_reachable": range,
        "max_velocity_needed": peak(1, 1.0),
        "velocity_unit": q.rate_unit(1),
        "max_acceleration_needed": peak(2, 1.0),
        "acceleration_unit": q.rate_unit(2),
    })
}

/// The slice maps of actuator `x` (the `i`-th): position, velocity and acceleration
/// needed, per standard slice.
fn actuator_plots(
    axes: &[GridAxis],
    base: &[f64],
    coord: &dyn Fn(usize) -> (String, pkm::Quantity),
    a: &DynAtlas,
    i: usize,
    x: &pkm::Actuator,
) -> Result<Vec<(String, String)>> {
    let q = x.quantity;
    let mut plots = Vec::new();
    for (ha, va) in slice_pairs(axes.len()) {
        for (what, unit, sel) in [
            ("position", q.unit(), 0usize),
            ("velocity", q.rate_unit(1), 1),
            ("acceleration", q.rate_unit(2), 2),
        ] {
            let value = |k: usize| {
                let p = &a.points[k];
                let v = p.get(sel, i);
                (p.reachable && v.is_finite()).then_some(v)
            };
            let title = if sel == 0 {
                format!("{} {what}", x.name)
            } else {
                format!("{} {what} needed", x.name)
            };
            let label = format!("{} {what} [{unit}]", x.name);
            let svg = slice_plot(
                axes,
                base,
                coord,
                (ha, va),
                &title,
                Scale::Linear(&label),
                &value,
            )?;
            plots.push((
                format!("atlas-{}-{what}-{}{}.svg", x.name, coord(ha).0, coord(va).0)
                    .to_lowercase(),
                svg,
            ));
        }
    }
    Ok(plots)
}

/// Grid axes over the actuator strokes (at most 3 actuators).
pub fn forward_axes(m: &dyn DynMechanism, step: Option<f64>) -> Result<Vec<GridAxis>> {
    let acts = m.actuators();
    if acts.len() > 3 {
        bail!(
            "--forward grids every actuator stroke: this machine has {} actuators (at most 3)",
            acts.len()
        );
    }
    Ok(acts
        .iter()
        .enumerate()
        .map(|(i, x)| GridAxis {
            coordinate: i,
            min: x.range.min,
            max: x.range.max,
            step: step
                .map(|s| x.quantity.from_user(s))
                .unwrap_or((x.range.max - x.range.min) / 40.0),
        })
        .collect())
}

/// Forward-map outputs: CSV text, plots and the summary JSON.
pub fn forward_outputs(
    m: &dyn DynMechanism,
    axes: &[GridAxis],
    base_q: &[f64],
    f: &DynForwardMap,
) -> Result<Outputs> {
    let acts = m.actuators();
    let act = |i: usize| (acts[i].name.clone(), acts[i].quantity);
    let csv = forward_csv(m, axes, f);
    let mut plots = Vec::new();
    let mut ranges = serde_json::Map::new();
    for (j, c) in m.coordinates().iter().enumerate() {
        let vals: Vec<f64> = f
            .points
            .iter()
            .filter(|p| p.reachable)
            .filter_map(|p| p.pose.as_ref().map(|x| x[j]))
            .collect();
        let lo = vals.iter().copied().fold(f64::NAN, f64::min);
        let hi = vals.iter().copied().fold(f64::NAN, f64::max);
        ranges.insert(
            c.name.clone(),
            json!({"unit": c.quantity.unit(), "range": [lo, hi]}),
        );
        if (hi - lo).is_nan() || hi - lo <= 1e-9 {
            continue; // a coordinate the actuators do not move
        }
        plots.extend(coordinate_plots(axes, base_q, &act, f, j, c)?);
    }
    let reachable = f.points.iter().filter(|p| p.reachable).count();
    let summary = json!({
        "points": f.points.len(),
        "reachable": reachable,
        "reachable_fraction": reachable as f64 / f.points.len().max(1) as f64,
        "pose_ranges": ranges,
    });
    Ok(Outputs {
        csv,
        plots,
        summary,
    })
}

/// The slice maps of pose coordinate `c` (the `j`-th) over the actuator strokes.
fn coordinate_plots(
    axes: &[GridAxis],
    base_q: &[f64],
    act: &dyn Fn(usize) -> (String, pkm::Quantity),
    f: &DynForwardMap,
    j: usize,
    c: &pkm::mechanism::Coordinate,
) -> Result<Vec<(String, String)>> {
    let mut plots = Vec::new();
    for (ha, va) in slice_pairs(axes.len()) {
        let value = |k: usize| {
            let p = &f.points[k];
            if p.reachable {
                p.pose.as_ref().map(|x| x[j])
            } else {
                None
            }
        };
        let label = format!("{} [{}]", c.name, c.quantity.unit());
        let svg = slice_plot(
            axes,
            base_q,
            act,
            (ha, va),
            &format!("forward workspace: {}", c.name),
            Scale::Linear(&label),
            &value,
        )?;
        plots.push((
            format!("forward-{}-{}{}.svg", c.name, act(ha).0, act(va).0).to_lowercase(),
            svg,
        ));
    }
    Ok(plots)
}

/// `forward.csv`: per grid point the actuator values, whether reachable, the limit
/// that binds, and the pose (empty where none was found).
fn forward_csv(m: &dyn DynMechanism, axes: &[GridAxis], f: &DynForwardMap) -> String {
    let acts = m.actuators();
    let coords = m.coordinates();
    let mut head: Vec<String> = acts
        .iter()
        .map(|x| format!("{}_{}", x.name, x.quantity.unit()))
        .collect();
    head.push("reachable".into());
    head.push("binding".into());
    head.extend(
        coords
            .iter()
            .map(|c| format!("{}_{}", c.name, c.quantity.unit())),
    );
    let mut csv = head.join(",") + "\n";
    let counts: Vec<usize> = axes.iter().map(|a| a.count()).collect();
    for (k, p) in f.points.iter().enumerate() {
        let mut rem = k;
        let mut q = vec![0.0; axes.len()];
        for (i, n) in counts.iter().enumerate().rev() {
            q[i] = acts[i].quantity.to_user(axes[i].value(rem % n));
            rem /= n;
        }
        let mut row: Vec<String> = q.iter().map(|v| format!("{v:.6}")).collect();
        row.push(p.reachable.to_string());
        row.push(super::ik::csv_text(p.binding.as_deref().unwrap_or("")));
        match &p.pose {
            Some(p) => row.extend(p.iter().map(|v| format!("{v:.6}"))),
            None => row.extend(coords.iter().map(|_| String::new())),
        }
        csv.push_str(&row.join(","));
        csv.push('\n');
    }
    csv
}
