//! `pkm check`: validate a machine file and summarise it.

use anyhow::Result;
use clap::Args;
use pkm::verify::{check_references, ReferenceCheck};
use pkm::{Convention, DynMechanism, Machine};
use serde_json::json;
use std::path::PathBuf;

use super::load;
use crate::out::{outln, Printed};
use crate::poses::{actuators_json, coords_text, name_width, tool_json, Shown};

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The machine at its home pose.
struct Home {
    pose: Vec<f64>,
    /// Actuator values at home.
    q: Vec<f64>,
    violations: Vec<pkm::Violation>,
    /// The tool pose (`tool_json`).
    tool: serde_json::Value,
    /// Condition number of the driven Jacobian.
    condition: f64,
    /// Characteristic length (mm) scaling rotations in the condition number.
    length: f64,
    /// Indices of the driven coordinates.
    driven: Vec<usize>,
}

impl Home {
    fn new(m: &dyn DynMechanism) -> Result<Home> {
        let pose = m.home();
        let q = m.inverse(&pose)?;
        let violations = m.check_limits(&pose, &q)?;
        let tool = tool_json(m, &pose, Convention::Rpy)?;
        let condition = m.condition(&pose)?;
        Ok(Home {
            length: m.characteristic_length(),
            driven: m.driven(),
            pose,
            q,
            violations,
            tool,
            condition,
        })
    }
}

pub fn run(a: &CheckArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let m = machine.mechanism();
    let home = Home::new(m)?;
    let references = check_references(&machine);
    if a.json {
        let v = check_json(&machine, &home, &references);
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else {
        print_text(&machine, &home)?;
        for r in &references {
            print_reference(m, r)?;
        }
    }
    Ok(exit_code(&machine, &references, &home.violations))
}

/// The `pkm check --json` document.
fn check_json(machine: &Machine, home: &Home, references: &[ReferenceCheck]) -> serde_json::Value {
    let m = machine.mechanism();
    let actuators: Vec<_> = m
        .actuators()
        .iter()
        .map(|x| {
            let u = |v: f64| x.quantity.to_user(v);
            json!({
                "name": x.name,
                "unit": x.quantity.unit(),
                "min": u(x.range.min),
                "max": u(x.range.max),
                "max_velocity": x.max_velocity.map(u),
                "max_acceleration": x.max_acceleration.map(u),
            })
        })
        .collect();
    let coords: Vec<_> = m
        .coordinates()
        .iter()
        .enumerate()
        .map(|(i, c)| {
            json!({
                "name": c.name,
                "unit": c.quantity.unit(),
                "driven": home.driven.contains(&i),
            })
        })
        .collect();
    let cond = home.condition;
    json!({
        "file": machine.source,
        "name": m.name(),
        "description": machine.description,
        "type": m.kind(),
        "pose_space": m.pose_space(),
        "coordinates": coords,
        "actuators": actuators,
        "home": {
            "position": home.tool["position"],
            "angles": home.tool["angles"],
            "actuators": actuators_json(m, &home.q),
            "violations": home.violations,
            "jacobian_condition": cond,
            "singular": !cond.is_finite(),
            "characteristic_length_mm": home.length,
        },
        "inverse_method": m.inverse_method(),
        "references": references,
    })
}

/// The summary as text: name, coordinates, actuators, home, conditioning, limits.
fn print_text(machine: &Machine, home: &Home) -> Printed {
    let m = machine.mechanism();
    outln!("{}: valid {} machine", machine.source, m.kind())?;
    outln!("name        {}", m.name())?;
    if let Some(d) = &machine.description {
        outln!("description {d}")?;
    }
    let c: Vec<String> = m
        .coordinates()
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let held = if home.driven.contains(&i) {
                ""
            } else {
                " (held)"
            };
            format!("{} [{}]{held}", c.name, c.quantity.unit())
        })
        .collect();
    outln!("coordinates {}", c.join(", "))?;
    print_actuators(m, &home.q)?;
    outln!("home        {}", coords_text(m, &home.pose))?;
    print_conditioning(m, home)?;
    if m.pose_space() == pkm::PoseSpace::Tcp {
        warn_turned_part_frame(m, &home.pose)?;
    }
    if home.violations.is_empty() {
        outln!("home limits all satisfied")?;
    } else {
        for v in &home.violations {
            outln!("home limit  VIOLATED: {v}")?;
        }
    }
    Ok(())
}

/// One line per actuator: range, value at home, rate limits.
fn print_actuators(m: &dyn DynMechanism, q: &[f64]) -> Printed {
    let width = name_width(m.actuators().iter().map(|x| x.name.as_str()), 6);
    for (x, v) in m.actuators().iter().zip(q) {
        let u = |v: f64| x.quantity.to_user(v);
        let unit = x.quantity.unit();
        let mut line = format!(
            "actuator    {:<width$} range [{:.3}, {:.3}] {unit}, at home {:.4} {unit}",
            x.name,
            u(x.range.min),
            u(x.range.max),
            Shown(u(*v))
        );
        if let Some(vm) = x.max_velocity {
            line.push_str(&format!(", max velocity {:.1} {unit}/s", u(vm)));
        }
        if let Some(am) = x.max_acceleration {
            line.push_str(&format!(", max acceleration {:.1} {unit}/s^2", u(am)));
        }
        outln!("{line}")?;
    }
    Ok(())
}

/// The Jacobian's condition number at home, the inverse method, and a singular home.
fn print_conditioning(m: &dyn DynMechanism, home: &Home) -> Printed {
    let (cond, lc) = (home.condition, home.length);
    let angles = home
        .driven
        .iter()
        .any(|&k| m.coordinates()[k].quantity == pkm::Quantity::Angle);
    let scale = if angles {
        format!("; 1 rad counted as {lc:.3} mm")
    } else {
        String::new()
    };
    outln!("jacobian    condition number {cond:.3} at home (driven columns, 2-norm{scale})")?;
    outln!("inverse     {}", m.inverse_method())?;
    if !cond.is_finite() {
        outln!(
            "warning     the home pose is singular: the Jacobian loses rank there (a robot's \
             stretched zero pose often is); the file is valid, but poses near home need \
             fast joint motion"
        )?;
    }
    Ok(())
}

/// TCP coordinates are in the part frame, the workpiece chain's last frame: a file
/// whose last link leaves that frame turned makes a program's Z move along another
/// machine axis.
fn warn_turned_part_frame(m: &dyn DynMechanism, home: &[f64]) -> Printed {
    let Ok(p) = m.tool_pose(home) else {
        return Ok(());
    };
    let z = p.rotation * nalgebra::Vector3::z();
    if z.z < 1.0 - 1e-9 {
        outln!(
            "warning     at home the tool axis is ({:.4}, {:.4}, {:.4}) in the part \
             frame, not +Z: a program's X, Y, Z are along the axes of the workpiece \
             chain's last frame; end the chain with a link turning them onto the \
             machine's (as the tilting table link of examples/machines/mc300.toml does)",
            z.x,
            z.y,
            z.z
        )?;
    }
    Ok(())
}

/// One reproduced reference: where, and whether it is reproduced.
fn print_reference(m: &dyn DynMechanism, r: &ReferenceCheck) -> Printed {
    let worst = r
        .items
        .iter()
        .filter_map(|i| i.deviation)
        .fold(0.0, f64::max);
    // The pose tells apart references quoting the same source.
    let at = m
        .coordinates()
        .iter()
        .zip(&r.pose)
        .map(|(c, v)| format!("{}={v}", c.name))
        .collect::<Vec<_>>()
        .join(" ");
    let status = match (r.pass, r.discrepancy) {
        (true, false) => format!(
            "reproduced (largest deviation {worst:.4}, tolerance {})",
            r.tolerance
        ),
        (false, _) => format!(
            "NOT REPRODUCED (largest deviation {worst:.4}, tolerance {})",
            r.tolerance
        ),
        (true, true) => discrepancy(r),
    };
    outln!("reference   {} [{at}]: {status}", r.source)?;
    Ok(())
}

/// A reference that passes with pkm's values where the source prints others.
fn discrepancy(r: &ReferenceCheck) -> String {
    let items = r
        .items
        .iter()
        .filter_map(|i| {
            let p = i.published.as_ref()?;
            let got = i.computed.as_ref().map(|c| c[0]).unwrap_or(f64::NAN);
            Some(format!(
                "{}: the source prints {} {u}, pkm's value is {} {u} (computed {got:.3} {u})",
                i.name,
                p[0],
                i.expected[0],
                u = i.unit
            ))
        })
        .collect::<Vec<_>>()
        .join("; ");
    let note = r
        .note
        .as_deref()
        .map(|n| format!(". Note: {n}"))
        .unwrap_or_default();
    format!("DISCREPANCY with the source, not reproduced: {items}{note}")
}

/// 1 for a reference not reproduced, [`crate::EXIT_UNREACHABLE`] for a home pose
/// beyond the limits (each said on stderr), else 0.
fn exit_code(
    machine: &Machine,
    references: &[ReferenceCheck],
    violations: &[pkm::Violation],
) -> u8 {
    if let Some(r) = references.iter().find(|r| !r.pass) {
        let detail = r.error.clone().unwrap_or_else(|| {
            r.items
                .iter()
                .filter(|i| !i.pass)
                .map(|i| match i.deviation {
                    Some(d) => format!("{} {} off by {d:.4} {}", i.what, i.name, i.unit),
                    None => format!("{} {} does not exist", i.what, i.name),
                })
                .collect::<Vec<_>>()
                .join(", ")
        });
        eprintln!(
            "error: {}: reference `{}` is not reproduced: {detail}",
            machine.source, r.source
        );
        return 1;
    }
    if violations.is_empty() {
        0
    } else {
        eprintln!(
            "error: {}: the home pose violates the machine's own limits",
            machine.source
        );
        crate::EXIT_UNREACHABLE
    }
}
