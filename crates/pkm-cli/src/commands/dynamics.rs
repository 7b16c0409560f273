//! `pkm dynamics`: the joint forces and torques of a serial machine or robot for joint
//! positions, rates and accelerations (recursive Newton-Euler).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use pkm::analysis::dynamics::{inverse_dynamics, DynamicsOptions};
use pkm::Quantity;
use serde_json::{json, Map, Value};

use super::load;
use crate::out::outln;
use crate::poses::{clean, name_width, parse_list, BadArgument, Shown};

#[derive(Args)]
pub struct DynamicsArgs {
    /// Machine file (TOML) or URDF robot; its links need mass properties (URDF
    /// `<inertial>`).
    pub machine: PathBuf,
    /// Joint positions (deg; mm for a slide), one per joint; default home.
    #[arg(long, allow_hyphen_values = true)]
    pub q: Option<String>,
    /// Joint rates (deg/s, mm/s); default 0.
    #[arg(long, allow_hyphen_values = true)]
    pub qd: Option<String>,
    /// Joint accelerations (deg/s^2, mm/s^2); default 0.
    #[arg(long, allow_hyphen_values = true)]
    pub qdd: Option<String>,
    /// Gravity gx,gy,gz (m/s^2, base frame); default 0,0,-9.80665.
    #[arg(long, allow_hyphen_values = true)]
    pub gravity: Option<String>,
    /// Load on the tool Fx,Fy,Fz[,Mx,My,Mz] (N, N m; base frame).
    #[arg(long, allow_hyphen_values = true)]
    pub wrench: Option<String>,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// One value per joint from `text` (user units), default `fill`.
fn joint_values(
    text: Option<&str>,
    what: &str,
    quantities: &[Quantity],
    fill: &[f64],
) -> Result<Vec<f64>> {
    let Some(t) = text else {
        return Ok(fill.to_vec());
    };
    let v = parse_list(t, what)?;
    if v.len() != quantities.len() {
        return Err(BadArgument(format!(
            "{what}: expected {} values (one per joint), found {}",
            quantities.len(),
            v.len()
        ))
        .into());
    }
    Ok(v.iter()
        .zip(quantities)
        .map(|(x, q)| q.from_user(*x))
        .collect())
}

fn options(a: &DynamicsArgs) -> Result<DynamicsOptions> {
    let mut o = DynamicsOptions::default();
    if let Some(g) = &a.gravity {
        let v = parse_list(g, "--gravity")?;
        if v.len() != 3 {
            return Err(BadArgument(format!(
                "--gravity: expected gx,gy,gz (m/s^2), found {} values",
                v.len()
            ))
            .into());
        }
        o.gravity = nalgebra::Vector3::new(v[0], v[1], v[2]) * 1e3;
    }
    if let Some(w) = &a.wrench {
        let v = parse_list(w, "--wrench")?;
        if v.len() != 3 && v.len() != 6 {
            return Err(BadArgument(format!(
                "--wrench: expected Fx,Fy,Fz or Fx,Fy,Fz,Mx,My,Mz (N, N m), found {} values",
                v.len()
            ))
            .into());
        }
        for (k, x) in v.iter().enumerate() {
            o.wrench[k] = if k < 3 { *x } else { x * 1e3 };
        }
    }
    Ok(o)
}

pub fn run(a: &DynamicsArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    let m = machine.mechanism();
    let acts = m.actuators();
    let kinds: Vec<Quantity> = acts.iter().map(|x| x.quantity).collect();
    let home = m.inverse(&m.home())?;
    let zero = vec![0.0; acts.len()];
    let q = joint_values(a.q.as_deref(), "--q", &kinds, &home)?;
    let qd = joint_values(a.qd.as_deref(), "--qd", &kinds, &zero)?;
    let qdd = joint_values(a.qdd.as_deref(), "--qdd", &kinds, &zero)?;
    let t = inverse_dynamics(&machine, &q, &qd, &qdd, &options(a)?)?;
    let shown: Vec<(String, f64, &str)> = acts
        .iter()
        .zip(&t)
        .map(|(act, v)| match act.quantity {
            Quantity::Angle => (act.name.clone(), v * 1e-3, "N m"),
            Quantity::Length => (act.name.clone(), *v, "N"),
        })
        .collect();
    if a.json {
        let mut torques = Map::new();
        for (name, v, _) in &shown {
            torques.insert(name.clone(), json!(clean(*v)));
        }
        let v: Value = json!({
            "machine": m.name(),
            "torques": torques,
            "units": "torques: N m for a revolute joint, N for a slide; the drive's force or torque \
                      on its joint, positive along the joint's coordinate; q, qd, qdd in deg \
                      (mm), per s, per s^2; gravity 9.80665 m/s^2 along -Z unless --gravity",
        });
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
        return Ok(0);
    }
    outln!("{} ({})", m.name(), m.kind())?;
    let w = name_width(shown.iter().map(|s| s.0.as_str()), 8);
    for (name, v, unit) in &shown {
        outln!("torque     {name:<w$} {:>12.4} {unit}", Shown(*v))?;
    }
    Ok(0)
}
