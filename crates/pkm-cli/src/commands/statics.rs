//! `pkm statics`: actuator forces, stiffness and deflection under a wrench at one pose.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use pkm::analysis::statics::{statics, StaticsOptions, StaticsReport, StiffnessReport};
use pkm::{DynMechanism, Machine, Quantity};
use serde_json::{json, Map, Value};

use super::load;
use crate::out::outln;
use crate::poses::{
    clean, coords_json, coords_text, name_width, parse_list, pose_from_user, Shown,
};
use crate::{PoseOptions, EXIT_UNREACHABLE};

#[derive(Args)]
pub struct StaticsArgs {
    /// Machine file (TOML).
    pub machine: PathBuf,
    /// Pose: X,Y,Z[,A,B,C] (mm, deg); default the machine's home.
    #[arg(long, allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// The load on the tool, base frame: Fx,Fy,Fz (N, at the tool tip) and optionally
    /// Mx,My,Mz (N m). A cutting force is the workpiece's push on the tool.
    #[arg(long, allow_hyphen_values = true, default_value = "0,0,0")]
    pub wrench: String,
    #[command(flatten)]
    pub opts: PoseOptions,
}

/// A revolute drive's force is a torque: N mm inside, N m shown.
fn force_to_user(q: Quantity, f: f64) -> f64 {
    match q {
        Quantity::Angle => f * 1e-3,
        Quantity::Length => f,
    }
}

fn wrench_from_user(text: &str) -> Result<[f64; 6]> {
    let v = parse_list(text, "--wrench")?;
    if v.len() != 3 && v.len() != 6 {
        return Err(crate::poses::BadArgument(format!(
            "--wrench: expected Fx,Fy,Fz or Fx,Fy,Fz,Mx,My,Mz (N, N m), found {} values",
            v.len()
        ))
        .into());
    }
    let mut w = [0.0; 6];
    w[..3].copy_from_slice(&v[..3]);
    for k in 3..v.len() {
        w[k] = v[k] * 1e3;
    }
    Ok(w)
}

pub fn run(a: &StaticsArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let m = machine.mechanism();
    let pose = match &a.pose {
        Some(p) => pose_from_user(m, &parse_list(p, "--pose")?, a.opts.rotation)?,
        None => m.home(),
    };
    let wrench = wrench_from_user(&a.wrench)?;
    let violations = m.check_limits(&pose, &m.inverse(&pose)?)?;
    let r = statics(&machine, &StaticsOptions { pose, wrench })?;
    if a.opts.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&to_json(&machine, &r, &violations))?
        )?;
    } else {
        print_text(&machine, &r)?;
    }
    if let Some(e) = &r.stiffness_error {
        eprintln!("warning: no stiffness: {e}");
    }
    if violations.is_empty() {
        Ok(0)
    } else {
        eprintln!("error: {}", pkm::Error::Unreachable { violations });
        Ok(EXIT_UNREACHABLE)
    }
}

fn matrix_json(m: &[[f64; 6]; 6]) -> Value {
    json!(m.map(|r| r.map(clean)))
}

fn stiffness_json(s: &StiffnessReport) -> Map<String, Value> {
    let mut o = Map::new();
    o.insert(
        "stiffness".into(),
        s.matrix.as_ref().map_or(Value::Null, matrix_json),
    );
    o.insert(
        "geometric_stiffness".into(),
        s.geometric.as_ref().map_or(Value::Null, matrix_json),
    );
    o.insert("compliance".into(), matrix_json(&s.compliance));
    o.insert("deflection".into(), json!(s.deflection.map(clean)));
    match (&s.deflection_exact, &s.deflection_exact_error) {
        (Some(d), _) => o.insert("deflection_exact".into(), json!(d.map(clean))),
        (None, e) => o.insert("deflection_exact_error".into(), json!(e)),
    };
    o.insert(
        "smallest_translational_stiffness_n_per_um".into(),
        json!(s.smallest_translational_n_per_um),
    );
    o.insert(
        "weakest_direction".into(),
        json!(s.weakest_direction.map(clean)),
    );
    o
}

/// JSON of a result (the `pkm statics --json` contract).
pub fn to_json(machine: &Machine, r: &StaticsReport, violations: &[pkm::Violation]) -> Value {
    let m = machine.mechanism();
    let mut forces = Map::new();
    for (act, f) in m.actuators().iter().zip(&r.actuator_forces) {
        forces.insert(
            act.name.clone(),
            json!(clean(force_to_user(act.quantity, *f))),
        );
    }
    let w = r.wrench;
    let mut o = Map::new();
    o.insert("machine".into(), json!(m.name()));
    o.insert("type".into(), json!(m.kind()));
    o.insert("pose".into(), coords_json(m, &r.pose));
    o.insert(
        "wrench".into(),
        json!({ "force": [w[0], w[1], w[2]], "moment": [w[3] * 1e-3, w[4] * 1e-3, w[5] * 1e-3] }),
    );
    o.insert("actuator_forces".into(), Value::Object(forces));
    match &r.stiffness {
        Some(s) => o.extend(stiffness_json(s)),
        None => {
            o.insert("stiffness".into(), Value::Null);
            o.insert("stiffness_error".into(), json!(r.stiffness_error));
        }
    }
    o.insert("violations".into(), json!(violations));
    o.insert("units".into(), json!(UNITS));
    Value::Object(o)
}

const UNITS: &str =
    "wrench: force N at the tool tip, moment N m, base frame, the load on the tool; \
    actuator_forces: N (N m for a revolute drive), positive where the drive pushes its own \
    coordinate to grow; stiffness, geometric_stiffness (its load-dependent part), compliance: \
    rows and columns X, Y, Z, then rotations about X, Y, Z (base frame, moments about the tool \
    tip) in N/mm, N/rad, N and N mm/rad (compliance: the inverse units); deflection (first order) \
    and deflection_exact (large-deflection equilibrium): mm, then rad (rotation vector); \
    stiffness is null where the machine holds coordinates rigidly (compliance 0 there)";

fn print_text(machine: &Machine, r: &StaticsReport) -> Result<()> {
    let m = machine.mechanism();
    outln!("{} ({})", m.name(), m.kind())?;
    outln!("pose       {}", coords_text(m, &r.pose))?;
    let w = r.wrench;
    outln!(
        "wrench     F = ({}, {}, {}) N, M = ({}, {}, {}) N m",
        w[0],
        w[1],
        w[2],
        w[3] * 1e-3,
        w[4] * 1e-3,
        w[5] * 1e-3
    )?;
    print_forces(m, &r.actuator_forces)?;
    match (&r.stiffness, &r.stiffness_error) {
        (Some(s), _) => print_stiffness(s)?,
        (None, e) => outln!("stiffness  not available: {}", e.as_deref().unwrap_or("-"))?,
    }
    Ok(())
}

fn print_forces(m: &dyn DynMechanism, forces: &[f64]) -> Result<()> {
    let aw = name_width(m.actuators().iter().map(|a| a.name.as_str()), 8);
    for (act, f) in m.actuators().iter().zip(forces) {
        let unit = match act.quantity {
            Quantity::Angle => "N m",
            Quantity::Length => "N",
        };
        outln!(
            "force      {:<aw$} {:>12.3} {unit}",
            act.name,
            Shown(force_to_user(act.quantity, *f))
        )?;
    }
    Ok(())
}

fn print_stiffness(s: &StiffnessReport) -> Result<()> {
    let um = |v: &[f64]| {
        format!(
            "({:.4}, {:.4}, {:.4}) um, ({:.4}, {:.4}, {:.4}) urad",
            Shown(v[0] * 1e3),
            Shown(v[1] * 1e3),
            Shown(v[2] * 1e3),
            Shown(v[3] * 1e6),
            Shown(v[4] * 1e6),
            Shown(v[5] * 1e6)
        )
    };
    outln!(
        "weakest    {:.2} N/um along ({:.3}, {:.3}, {:.3})",
        s.smallest_translational_n_per_um,
        Shown(s.weakest_direction[0]),
        Shown(s.weakest_direction[1]),
        Shown(s.weakest_direction[2])
    )?;
    outln!("deflection {} (first order)", um(&s.deflection))?;
    match (&s.deflection_exact, &s.deflection_exact_error) {
        (Some(d), _) => outln!("           {} (exact)", um(d))?,
        (None, e) => outln!("           exact: {}", e.as_deref().unwrap_or("-"))?,
    }
    match &s.matrix {
        Some(k) => {
            outln!("stiffness  (N/mm, N/rad; N, N mm/rad), rows X Y Z, rotations X Y Z")?;
            for row in k {
                let cells: Vec<String> = row.iter().map(|v| format!("{:>13.4e}", v)).collect();
                outln!("           {}", cells.join(" "))?;
            }
        }
        None => outln!("stiffness  unbounded: the machine holds some coordinates rigidly")?,
    }
    Ok(())
}
