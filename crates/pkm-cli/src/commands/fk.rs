//! `pkm fk`: forward kinematics, one actuator set or a CSV batch.

use crate::PoseOptions;
use clap::Args;
use std::path::Path;
use std::path::PathBuf;

use anyhow::Result;
use pkm::analysis::kinematics::ForwardSolution;
use pkm::dynamic::DynForward;
use pkm::pose::rotation_matrix;
use pkm::{Convention, DynMechanism, PoseSpace};
use serde_json::json;

use super::csvio::{input_columns, read_table, BatchTable, NO_VALUES};
use super::load;
use crate::columnar::{machine_metadata, Kind};
use crate::out::outln;
use crate::poses::{
    actuators_from_user, actuators_json, coords_json, coords_text, parse_list, pose_from_user,
    tool_json, Shown,
};
use crate::EXIT_UNREACHABLE;
use std::fmt::Write as _;

#[derive(Args)]
pub struct FkArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// Actuator values v1,v2,... (mm for linear, deg for revolute drives).
    #[arg(
        long,
        allow_hyphen_values = true,
        required_unless_present = "input",
        conflicts_with = "input"
    )]
    pub actuators: Option<String>,
    /// Starting pose (same form as `pkm ik --pose`); default: the home pose.
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<String>,
    /// Also search for other assembly modes: solve from this many starting poses spread
    /// around home (and mirrored through the base plane) and list every distinct pose.
    #[arg(long, conflicts_with = "input")]
    pub assembly_modes: Option<usize>,
    /// CSV of many actuator sets (header row naming the actuators; other columns, such
    /// as the rest of a `pkm ik --output` table, are left unread).
    #[arg(long, requires = "output")]
    pub input: Option<PathBuf>,
    /// File to write the batch results to: CSV, or Parquet when its name ends in
    /// `.parquet` (full precision, typed columns, nulls for empty cells).
    #[arg(long, requires = "input")]
    pub output: Option<PathBuf>,
    #[command(flatten)]
    pub opts: PoseOptions,
}

fn start_pose(m: &dyn DynMechanism, a: &FkArgs) -> Result<Vec<f64>> {
    match &a.from {
        Some(s) => Ok(pose_from_user(
            m,
            &parse_list(s, "--from")?,
            a.opts.rotation,
        )?),
        None => Ok(m.home()),
    }
}

pub fn run(a: &FkArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let m = machine.mechanism();
    let conv = a.opts.rotation;
    let start = start_pose(m, a)?;
    if let (Some(input), Some(output)) = (&a.input, &a.output) {
        return batch(&machine, a, start, input, output);
    }
    let vals = parse_list(a.actuators.as_deref().unwrap_or_default(), "--actuators")?;
    let q = actuators_from_user(m, &vals)?;
    let f = pkm::analysis::kinematics::forward(&machine, &q, &start)?;
    let modes = match a.assembly_modes {
        Some(n) => Some(pkm::analysis::workspace::assembly_modes(&machine, &q, n)?),
        None => None,
    };
    if a.opts.json {
        let v = solution_json(m, &q, &f, modes.as_deref(), conv)?;
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else {
        print_text(m, &f, conv)?;
        if let Some(modes) = &modes {
            print_modes(m, &q, modes, a.assembly_modes.unwrap_or(0))?;
        }
    }
    let violations = f.violations;
    if violations.is_empty() {
        Ok(0)
    } else {
        eprintln!("error: {}", pkm::Error::Unreachable { violations });
        Ok(EXIT_UNREACHABLE)
    }
}

/// The `pkm fk --json` document: the tool pose, the pose, the solver's figures, the
/// limits, and the assembly modes when searched.
fn solution_json(
    m: &dyn DynMechanism,
    q: &[f64],
    f: &ForwardSolution,
    modes: Option<&[DynForward]>,
    conv: Convention,
) -> Result<serde_json::Value> {
    let violations = &f.violations;
    let mut v = tool_json(m, &f.pose, conv)?;
    let o = v.as_object_mut().expect("object");
    o.insert("machine".into(), json!(m.name()));
    o.insert("type".into(), json!(m.kind()));
    o.insert("pose".into(), coords_json(m, &f.pose));
    o.insert("actuators".into(), actuators_json(m, q));
    o.insert(
        "solver".into(),
        json!(if f.closed_form {
            "closed-form"
        } else {
            "iterative"
        }),
    );
    o.insert("iterations".into(), json!(f.iterations));
    o.insert("residual".into(), json!(f.residual));
    o.insert("condition".into(), json!(f.condition));
    o.insert("near_singular".into(), json!(f.near_singular));
    o.insert("violations".into(), json!(violations));
    o.insert("reachable".into(), json!(violations.is_empty()));
    if let Some(modes) = modes {
        let mut list = Vec::new();
        for f in modes {
            let mut t = tool_json(m, &f.pose, conv)?;
            let viol = m.check_limits(&f.pose, q)?;
            let to = t.as_object_mut().expect("object");
            to.insert("pose".into(), coords_json(m, &f.pose));
            to.insert("reachable".into(), json!(viol.is_empty()));
            to.insert("violations".into(), json!(viol));
            list.push(t);
        }
        o.insert("assembly_modes".into(), json!(list));
    }
    Ok(v)
}

/// The solution as text: pose, tool pose, solver, conditioning, limits.
fn print_text(m: &dyn DynMechanism, f: &ForwardSolution, conv: Convention) -> Result<()> {
    let pose = m.tool_pose(&f.pose)?;
    let r = rotation_matrix(&pose);
    let ang = conv.from_matrix(&r).map(|v| Shown(v.to_degrees()));
    let names = conv.angle_names();
    outln!("{} ({})", m.name(), m.kind())?;
    outln!("pose       {}", coords_text(m, &f.pose))?;
    let p = pose.translation.vector;
    outln!(
        "tool       X={:.4} Y={:.4} Z={:.4} mm",
        Shown(p.x),
        Shown(p.y),
        Shown(p.z)
    )?;
    outln!(
        "angles     {}={:.4} {}={:.4} {}={:.4} deg ({conv})",
        names[0],
        ang[0],
        names[1],
        ang[1],
        names[2],
        ang[2]
    )?;
    if f.closed_form {
        outln!("solver     closed form, residual {:.3e}", f.residual)?;
    } else {
        outln!(
            "solver     {} iterations, residual {:.3e}",
            f.iterations,
            f.residual
        )?;
    }
    match f.condition {
        Some(c) if !f.near_singular => outln!("condition  {c:.3} (driven columns, 2-norm)")?,
        Some(c) => outln!(
            "condition  {c:.4e}: NEAR A SINGULAR CONFIGURATION, the pose is poorly \
             determined by the actuators (their errors are magnified up to this factor)"
        )?,
        None => outln!("condition  none: the pose is singular, the actuators do not determine it")?,
    }
    if f.violations.is_empty() {
        outln!("limits     all satisfied")?;
    }
    for v in &f.violations {
        outln!("limit      VIOLATED: {v}")?;
    }
    Ok(())
}

/// `--assembly-modes`: every distinct pose found for the actuators `q` from `starts`.
fn print_modes(m: &dyn DynMechanism, q: &[f64], modes: &[DynForward], starts: usize) -> Result<()> {
    outln!(
        "assembly   {} distinct poses with these actuators from {} starts:",
        modes.len(),
        starts
    )?;
    for (i, f) in modes.iter().enumerate() {
        let viol = m.check_limits(&f.pose, q)?;
        let status = if viol.is_empty() {
            "within limits".to_string()
        } else {
            format!("{} limits violated (first: {})", viol.len(), viol[0].limit)
        };
        outln!("  mode {:<3} {}  {status}", i + 1, coords_text(m, &f.pose))?;
    }
    Ok(())
}

/// The batch's output columns after the input's: the pose (a machine in its own
/// coordinates: its coordinates, then its tool pose as `tool_*`), the solver's
/// figures, `reachable`, `status`.
struct BatchColumns {
    /// Whether the pose is the tool pose (else the machine's own coordinates first).
    spatial: bool,
    /// Columns of the tool pose.
    tool: usize,
    /// Columns of the pose, the tool pose's included.
    pose: usize,
}

impl BatchColumns {
    fn new(m: &dyn DynMechanism, conv: Convention, columns: &mut Vec<(String, Kind)>) -> Self {
        // Spatial machines' poses are their tool poses; a machine in its own coordinates
        // (a serial machine in joint coordinates, the P3RP head) gets its coordinates and
        // then its tool pose (its forward kinematics).
        let spatial = m.pose_space() != PoseSpace::Own;
        let tool_names: Vec<String> = ["X_mm", "Y_mm", "Z_mm"]
            .map(String::from)
            .into_iter()
            .chain(conv.angle_names().map(|n| format!("{n}_deg")))
            .map(|c| if spatial { c } else { format!("tool_{c}") })
            .collect();
        let mut pose_names: Vec<String> = if spatial {
            Vec::new()
        } else {
            m.coordinates()
                .iter()
                .map(|c| format!("{}_{}", c.name, c.quantity.unit()))
                .collect()
        };
        let tool = tool_names.len();
        pose_names.extend(tool_names);
        let pose = pose_names.len();
        columns.extend(pose_names.into_iter().map(|c| (c, Kind::OptF64)));
        columns.push(("iterations".into(), Kind::OptI64));
        columns.push(("residual".into(), Kind::OptF64));
        columns.push(("reachable".into(), Kind::Bool));
        columns.push(("status".into(), Kind::OptText));
        BatchColumns {
            spatial,
            tool,
            pose,
        }
    }
}

fn batch(
    machine: &pkm::Machine,
    a: &FkArgs,
    start: Vec<f64>,
    input: &Path,
    output: &Path,
) -> Result<u8> {
    let m = machine.mechanism();
    let conv = a.opts.rotation;
    let names: Vec<String> = m.actuators().iter().map(|a| a.name.clone()).collect();
    let table = read_table(input, &[names])?;
    let mut columns = input_columns(&table);
    let cols = BatchColumns::new(m, conv, &mut columns);
    let meta = machine_metadata(
        m,
        "pkm fk batch: the input actuator values, the pose (null without a solution; a \
         machine in its own coordinates: its coordinates, then its tool pose as tool_*), \
         the solver's iterations and residual, whether every limit holds, the violated \
         limits",
    );
    let mut out = BatchTable::create(output, &[input, &a.machine], &columns, meta)?;
    // Rows are a stream: each solved from the last (hexapods keep a tracking solver).
    let mut stream = pkm::analysis::kinematics::ForwardStream::new(machine, &start)?;
    let mut failed = 0usize;
    let mut text = String::new();
    for (line, vals) in &table.rows {
        out.input(table.header.len(), vals);
        text.clear();
        let res = if vals.is_empty() {
            Err(anyhow::anyhow!(NO_VALUES))
        } else {
            actuators_from_user(m, vals).and_then(|q| Ok(stream.next(&q)?))
        };
        let ok = match res {
            Ok((f, v)) => write_solution(&mut out, m, conv, &cols, &f, &v, &mut text),
            Err(e) => {
                for _ in 0..cols.pose {
                    out.num(None);
                }
                out.int(None);
                out.num(None);
                out.bool(false);
                let _ = write!(text, "line {line}: {e}");
                out.text(Some(&text));
                false
            }
        };
        if !ok {
            failed += 1;
        }
        out.end_row()?;
    }
    out.finish(output, failed, "solved within limits")
}

/// The cells of a solved row (`v` its violated limits, `text` the row's buffer);
/// whether it counts as solved within limits.
fn write_solution(
    out: &mut BatchTable,
    m: &dyn DynMechanism,
    conv: Convention,
    cols: &BatchColumns,
    f: &DynForward,
    v: &[pkm::Violation],
    text: &mut String,
) -> bool {
    if !cols.spatial {
        for (c, x) in m.coordinates().iter().zip(&f.pose) {
            out.num(Some(c.quantity.to_user(*x)));
        }
    }
    // A row without a tool pose keeps its row: empty cells and the reason
    // in its status (the batch goes on), and it counts as failed.
    let tool = m.tool_pose(&f.pose);
    match &tool {
        Ok(pose) => {
            let p = pose.translation.vector;
            let ang = conv.from_matrix(&rotation_matrix(pose));
            for x in [p.x, p.y, p.z].into_iter().chain(ang.map(f64::to_degrees)) {
                out.num(Some(x));
            }
        }
        Err(e) => {
            for _ in 0..cols.tool {
                out.num(None);
            }
            let _ = write!(text, "tool pose: {e}");
        }
    }
    out.int(Some(f.iterations as u64));
    out.num(Some(f.residual));
    out.bool(v.is_empty());
    for x in v {
        if !text.is_empty() {
            text.push_str("; ");
        }
        let _ = write!(text, "{x}");
    }
    out.text((!text.is_empty()).then_some(text.as_str()));
    v.is_empty() && tool.is_ok()
}
