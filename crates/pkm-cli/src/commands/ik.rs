//! `pkm ik`: inverse kinematics, one pose or a CSV batch.

use crate::PoseOptions;
use clap::Args;
use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::Result;
use pkm::analysis::kinematics::{
    inverse, inverse_for_tool_axis, inverse_solutions, transmission, InverseSolution,
    InverseStream, ToolAxisSolution,
};
use pkm::{DynMechanism, Machine, PoseSpace};
use serde_json::{json, Map, Value};

use super::csvio::{input_columns, read_table, BatchTable, NO_VALUES};
use super::load;
use crate::columnar::{machine_metadata, Kind};
use crate::out::{outln, Printed};
use crate::poses::{
    actuators_json, coords_json, coords_text, name_width, parse_list, pose_from_user, pose_names,
    tool_json, Shown,
};
use crate::EXIT_UNREACHABLE;
use std::fmt::Write as _;

#[derive(Args)]
pub struct IkArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// Pose: X,Y,Z[,A,B,C] (mm, deg) for spatial machines, the machine's own coordinates otherwise.
    #[arg(
        long,
        allow_hyphen_values = true,
        required_unless_present = "input",
        conflicts_with = "input"
    )]
    pub pose: Option<String>,
    /// CSV of many poses (header row naming the values; other columns, such as the
    /// rest of a `pkm fk --output` table, are left unread).
    #[arg(long, requires = "output")]
    pub input: Option<PathBuf>,
    /// File to write the batch results to: CSV, or Parquet when its name ends in
    /// `.parquet` (full precision, typed columns, nulls for empty cells).
    #[arg(long, requires = "input")]
    pub output: Option<PathBuf>,
    /// With --input: the rows are a path, each solved from the previous row's
    /// actuators (a robot keeps its posture and the whole turns of its joints, as a
    /// controller moving it does); without it every row takes the solution nearest home.
    #[arg(long, requires = "input")]
    pub continuous: bool,
    /// Six-axis robots: every inverse solution found (postures: shoulder, elbow, wrist),
    /// nearest to home first, each with its limit status.
    #[arg(long, conflicts_with = "input")]
    pub all_solutions: bool,
    /// 5-axis machines in TCP coordinates: the tool axis I,J,K (part frame, from the
    /// tip towards the spindle) instead of the rotary angles; --pose is then X,Y,Z. Both
    /// branches of the rotary axes are given, the one within the ranges nearest home
    /// chosen.
    #[arg(long, allow_hyphen_values = true, conflicts_with_all = ["input", "all_solutions"])]
    pub tool_axis: Option<String>,
    #[command(flatten)]
    pub opts: PoseOptions,
}

/// Inverse kinematics with the limit check (`pkm::analysis::kinematics::inverse`).
pub fn solve(machine: &Machine, x: Vec<f64>) -> Result<InverseSolution> {
    Ok(inverse(machine, &x)?)
}

fn transmission_json(machine: &Machine, x: &[f64]) -> Value {
    match transmission(machine, x) {
        Ok(t) => json!({
            "velocity": t.velocity,
            "angular_velocity": t.angular_velocity,
            "force": t.force,
            "moment": t.moment,
            "distance_to_singularity": t.distance_to_singularity,
            "condition": t.condition,
            "inverse_condition": t.inverse_condition,
            "characteristic_length_mm": t.characteristic_length,
            "units": "velocity: actuator mm/s (rad/s for a revolute drive) per tool mm/s; angular_velocity: the same per tool rad/s; force: actuator N (N mm) per tool N; moment: the same per tool N mm; condition: 2-norm condition number of the driven columns of dq/dx, rotations counted as characteristic_length_mm per rad (1 = isotropic, inf = singular), inverse_condition its inverse (0 = singular); distance_to_singularity: smallest singular value of those scaled columns, 0 at a parallel machine's singularity but not at a serial chain's (whose dq/dx grows without bound there): compare machines by condition",
        }),
        Err(e) => json!({ "error": e.to_string() }),
    }
}

/// JSON of a solution (the `pkm ik --json` contract).
pub fn to_json(machine: &Machine, r: &InverseSolution, conv: pkm::Convention) -> Result<Value> {
    let m = machine.mechanism();
    let mut joints = Map::new();
    for p in m.skeleton(&r.pose)?.points {
        joints.insert(p.name.clone(), json!(p.position));
    }
    Ok(json!({
        "machine": m.name(),
        "type": m.kind(),
        "pose": coords_json(m, &r.pose),
        "tool": tool_json(m, &r.pose, conv)?,
        "actuators": actuators_json(m, &r.actuators),
        "joints": joints,
        "violations": r.violations,
        "reachable": r.violations.is_empty(),
        "transmission": transmission_json(machine, &r.pose),
    }))
}

pub fn run(a: &IkArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let m = machine.mechanism();
    let conv = a.opts.rotation;
    if let (Some(input), Some(output)) = (&a.input, &a.output) {
        return batch(&machine, a, input, output);
    }
    let vals = parse_list(a.pose.as_deref().unwrap_or_default(), "--pose")?;
    let (r, axis) = match &a.tool_axis {
        Some(t) => {
            let sol = tool_axis_solution(&machine, &vals, t)?;
            (sol.branches[sol.chosen].clone(), Some(sol))
        }
        None => {
            let x = pose_from_user(m, &vals, conv)?;
            if a.all_solutions {
                return all_solutions(&machine, &x, a.opts.json);
            }
            (solve(&machine, x)?, None)
        }
    };
    if a.opts.json {
        let mut v = to_json(&machine, &r, conv)?;
        if let Some(sol) = &axis {
            v["tool_axis"] = tool_axis_json(m, sol);
        }
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else {
        print_text(&machine, &r, axis.as_ref())?;
    }
    if r.violations.is_empty() {
        Ok(0)
    } else {
        eprintln!(
            "error: {}",
            pkm::Error::Unreachable {
                violations: r.violations
            }
        );
        Ok(EXIT_UNREACHABLE)
    }
}

/// `--tool-axis`: both branches of the rotary axes for the tip `vals` (X,Y,Z) and the
/// tool axis I,J,K.
fn tool_axis_solution(machine: &Machine, vals: &[f64], axis: &str) -> Result<ToolAxisSolution> {
    let tip: [f64; 3] = vals.try_into().map_err(|_| {
        anyhow::anyhow!(
            "--pose: with --tool-axis expected X,Y,Z (mm), got {} values",
            vals.len()
        )
    })?;
    let ijk = parse_list(axis, "--tool-axis")?;
    let ijk: [f64; 3] = ijk
        .as_slice()
        .try_into()
        .map_err(|_| anyhow::anyhow!("--tool-axis: expected I,J,K, got {} values", ijk.len()))?;
    Ok(inverse_for_tool_axis(machine, tip, ijk, None)?)
}

/// The `tool_axis` entry of `pkm ik --json`: the branches and the one chosen.
fn tool_axis_json(m: &dyn DynMechanism, sol: &ToolAxisSolution) -> Value {
    json!({
        "branches": sol.branches.iter().map(|b| json!({
            "pose": coords_json(m, &b.pose),
            "reachable": b.violations.is_empty(),
        })).collect::<Vec<_>>(),
        "chosen": sol.chosen,
        "singular": sol.singular,
        "singular_distance_deg": sol.singular_distance.to_degrees(),
    })
}

/// The solution as text: pose, branches, actuators, joints, transmission, limits.
fn print_text(
    machine: &Machine,
    r: &InverseSolution,
    axis: Option<&ToolAxisSolution>,
) -> Result<()> {
    let m = machine.mechanism();
    outln!("{} ({})", m.name(), m.kind())?;
    outln!("pose       {}", coords_text(m, &r.pose))?;
    if let Some(sol) = axis {
        print_branches(m, sol)?;
    }
    // Actuator names as long as a user's file makes them stay in one column too.
    let aw = name_width(m.actuators().iter().map(|a| a.name.as_str()), 8);
    for (act, v) in m.actuators().iter().zip(&r.actuators) {
        outln!(
            "actuator   {:<aw$} {:>12.4} {}   range [{:.3}, {:.3}]",
            act.name,
            Shown(act.quantity.to_user(*v)),
            act.quantity.unit(),
            act.quantity.to_user(act.range.min),
            act.quantity.to_user(act.range.max)
        )?;
    }
    let points = m.skeleton(&r.pose)?.points;
    // Names as long as a user's file makes them stay in one column.
    let w = name_width(points.iter().map(|p| p.name.as_str()), 8);
    for p in points {
        outln!(
            "joint      {:<w$} {:>10.4} {:>10.4} {:>10.4} mm",
            p.name,
            Shown(p.position[0]),
            Shown(p.position[1]),
            Shown(p.position[2])
        )?;
    }
    print_transmission(machine, &r.pose)?;
    if r.violations.is_empty() {
        outln!("limits     all satisfied")?;
    }
    for v in &r.violations {
        outln!("limit      VIOLATED: {v}")?;
    }
    Ok(())
}

/// The branches of a `--tool-axis` solution (the chosen one starred) and the distance
/// to the singular direction.
fn print_branches(m: &dyn DynMechanism, sol: &ToolAxisSolution) -> Printed {
    for (k, b) in sol.branches.iter().enumerate() {
        outln!(
            "branch {}{}  {}{}",
            k + 1,
            if k == sol.chosen { "*" } else { " " },
            coords_text(m, &b.pose),
            if b.violations.is_empty() {
                String::new()
            } else {
                format!("  ({} limit(s) violated)", b.violations.len())
            }
        )?;
    }
    outln!(
        "tool axis  {:.4} deg from the singular direction{}",
        sol.singular_distance.to_degrees(),
        if sol.singular {
            ": along it, the first rotary angle held at home's"
        } else {
            ""
        }
    )?;
    Ok(())
}

/// Velocity and force transmission at the pose, and the distance to a singularity.
fn print_transmission(machine: &Machine, pose: &[f64]) -> Printed {
    let m = machine.mechanism();
    let t = match transmission(machine, pose) {
        Ok(t) => t,
        Err(e) => {
            outln!("transmit   {e}")?;
            return Ok(());
        }
    };
    let f = |v: Option<f64>, unit: &str| {
        v.map(|v| format!("{} {unit}", figure(v, 4)))
            .unwrap_or_else(|| "-".into())
    };
    // Actuator rates in mm/s (linear drives) or rad/s (revolute ones),
    // efforts in N or N mm.
    let angular = |a: &pkm::mechanism::Actuator| a.quantity == pkm::Quantity::Angle;
    let (rate, effort) = if m.actuators().iter().all(angular) {
        ("rad/s", "N mm")
    } else if m.actuators().iter().any(angular) {
        ("mm/s or rad/s", "N or N mm")
    } else {
        ("mm/s", "N")
    };
    outln!(
        "transmit   velocity {}, angular {}, force {}, moment {}",
        f(t.velocity, &per(rate, "mm/s")),
        f(
            t.angular_velocity.map(|v| v.to_radians()),
            &per(rate, "deg/s")
        ),
        f(t.force, &per(effort, "N")),
        f(t.moment, &per(effort, "N mm"))
    )?;
    let scale = if m
        .driven()
        .iter()
        .any(|&k| m.coordinates()[k].quantity == pkm::Quantity::Angle)
    {
        format!(", 1 rad counted as {:.3} mm", t.characteristic_length)
    } else {
        String::new()
    };
    outln!(
        "condition  {} (1 = isotropic, inf = singular; its inverse {}, 0 = singular; \
         driven columns of dq/dx, 2-norm{scale})",
        figure(t.condition, 3),
        significant(t.inverse_condition)
    )?;
    Ok(())
}

/// `{value:.digits}`, in exponent form from 1e6 on (a figure near a singularity).
fn figure(value: f64, digits: usize) -> String {
    if value.abs() >= 1e6 && value.is_finite() {
        format!("{value:.digits$e}")
    } else {
        format!("{value:.digits$}")
    }
}

/// `value` in [0, 1] to 4 significant digits (`0.6050`, `0.01684`), in exponent form
/// below 1e-4.
fn significant(value: f64) -> String {
    if value == 0.0 || !value.is_finite() {
        format!("{value}")
    } else if value < 1e-4 {
        format!("{value:.3e}")
    } else {
        let decimals = (3 - value.log10().floor() as i32).max(0) as usize;
        format!("{value:.decimals$}")
    }
}

/// The unit `num` per `den`, each in parentheses when compound (`(N mm)/N`, `N/N`).
fn per(num: &str, den: &str) -> String {
    let wrap = |u: &str| {
        if u.contains([' ', '/']) {
            format!("({u})")
        } else {
            u.to_string()
        }
    };
    format!("{}/{}", wrap(num), wrap(den))
}

fn batch(
    machine: &Machine,
    a: &IkArgs,
    input: &std::path::Path,
    output: &std::path::Path,
) -> Result<u8> {
    let m = machine.mechanism();
    let conv = a.opts.rotation;
    let names = pose_names(m, conv);
    let mut accepted = vec![names.clone()];
    if matches!(m.pose_space(), PoseSpace::Spatial | PoseSpace::Position) {
        accepted.push(names[..3].to_vec());
    }
    let table = read_table(input, &accepted)?;
    let meta = machine_metadata(
        m,
        "pkm ik batch: the input poses, the actuator values (null without a solution), \
         whether every limit holds, the violated limits",
    );
    let columns = batch_columns(m, input_columns(&table));
    let mut out = BatchTable::create(output, &[input, &a.machine], &columns, meta)?;
    let mut tally = Tally::default();
    let mut text = String::new();
    let mut stream = a.continuous.then(|| InverseStream::new(machine));
    for (line, vals) in &table.rows {
        out.input(table.header.len(), vals);
        if vals.is_empty() {
            unsolved_row(
                &mut out,
                m,
                &mut tally,
                "no values",
                &format!("line {line}: {NO_VALUES}"),
            );
            out.end_row()?;
            continue;
        }
        let res = pose_from_user(m, vals, conv)
            .map_err(anyhow::Error::from)
            .and_then(|x| match stream.as_mut() {
                Some(s) => Ok(s.next(&x)?),
                None => solve(machine, x),
            });
        text.clear();
        match res {
            Ok(r) => write_solution(&mut out, m, &r, &mut tally, &mut text),
            Err(e) => {
                let _ = write!(text, "line {line}: {e}");
                unsolved_row(&mut out, m, &mut tally, "no solution", &text);
            }
        }
        out.end_row()?;
    }
    let code = out.finish(output, tally.unreachable, "reachable")?;
    for (k, n) in &tally.counts {
        eprintln!("  {n} x {k}");
    }
    Ok(code)
}

/// The batch's columns: the input's, the actuators, `reachable`, `violations`.
fn batch_columns(m: &dyn DynMechanism, mut columns: Vec<(String, Kind)>) -> Vec<(String, Kind)> {
    columns.extend(
        m.actuators()
            .iter()
            .map(|a| (format!("{}_{}", a.name, a.quantity.unit()), Kind::OptF64)),
    );
    columns.push(("reachable".into(), Kind::Bool));
    columns.push(("violations".into(), Kind::OptText));
    columns
}

/// What a batch counts: the rows not reachable, and the rows per violated limit (or
/// without a solution).
#[derive(Default)]
struct Tally {
    unreachable: usize,
    counts: BTreeMap<String, usize>,
}

/// The cells of a row without a solution (`key` counted in the tally, `status` its
/// text): empty actuators, not reachable.
fn unsolved_row(
    out: &mut BatchTable,
    m: &dyn DynMechanism,
    tally: &mut Tally,
    key: &str,
    status: &str,
) {
    tally.unreachable += 1;
    *tally.counts.entry(key.into()).or_default() += 1;
    for _ in m.actuators() {
        out.num(None);
    }
    out.bool(false);
    out.text(Some(status));
}

/// The cells of a solved row: actuators, reachable, the violated limits (`text`, the
/// row's buffer).
fn write_solution(
    out: &mut BatchTable,
    m: &dyn DynMechanism,
    r: &InverseSolution,
    tally: &mut Tally,
    text: &mut String,
) {
    for (act, q) in m.actuators().iter().zip(&r.actuators) {
        out.num(Some(act.quantity.to_user(*q)));
    }
    out.bool(r.violations.is_empty());
    if !r.violations.is_empty() {
        tally.unreachable += 1;
        for (k, v) in r.violations.iter().enumerate() {
            *tally.counts.entry(v.limit.to_string()).or_default() += 1;
            if k > 0 {
                text.push_str("; ");
            }
            let _ = write!(text, "{v}");
        }
    }
    out.text((!text.is_empty()).then_some(text.as_str()));
}

/// Quotes a text cell for CSV.
pub fn csv_text(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `--all-solutions`: the postures of a six-axis robot reaching `x`.
fn all_solutions(machine: &Machine, x: &[f64], json_out: bool) -> Result<u8> {
    let m = machine.mechanism();
    let list: Vec<(Vec<f64>, Vec<pkm::Violation>)> = inverse_solutions(machine, x, 256)?
        .into_iter()
        .map(|s| (s.actuators, s.violations))
        .collect();
    if json_out {
        let arr: Vec<Value> = list
            .iter()
            .map(|(q, v)| {
                json!({
                    "actuators": actuators_json(m, q),
                    "within_limits": v.is_empty(),
                    "violations": v,
                })
            })
            .collect();
        outln!(
            "{}",
            serde_json::to_string_pretty(&json!({
                "machine": m.name(),
                "pose": coords_json(m, x),
                "solutions": arr,
            }))?
        )?;
    } else {
        outln!("{} ({})", m.name(), m.kind())?;
        outln!("pose       {}", coords_text(m, x))?;
        if list.is_empty() {
            outln!("no inverse solution found (256 starts)")?;
        }
        for (k, (q, v)) in list.iter().enumerate() {
            let joints: Vec<String> = m
                .actuators()
                .iter()
                .zip(q.iter())
                .map(|(a, val)| format!("{}={:.4}", a.name, Shown(a.quantity.to_user(*val))))
                .collect();
            let status = match v.first() {
                None => "within limits".to_string(),
                Some(f) => format!(
                    "{} beyond {:.3} by {:.3} {}",
                    f.limit, f.bound, f.excess, f.unit
                ),
            };
            outln!("solution {:>2} {}  ({status})", k + 1, joints.join(" "))?;
        }
    }
    Ok(if list.iter().any(|(_, v)| v.is_empty()) {
        0
    } else {
        EXIT_UNREACHABLE
    })
}
