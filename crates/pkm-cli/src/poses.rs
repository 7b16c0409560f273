//! Reading and writing poses and actuator values at the user boundary (mm, deg).

use anyhow::Result;
use pkm::pose::rotation_matrix;
use pkm::{Convention, DynMechanism};

pub use pkm::dynamic::{pose_from_user, pose_names};
use serde_json::{json, Map, Value};

/// A malformed command-line value: pkm exits with 2, as for any bad command line.
#[derive(Debug)]
pub struct BadArgument(pub String);

impl std::fmt::Display for BadArgument {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadArgument {}

/// Parses `v1,v2,...` (a command-line list) into finite numbers of a sane magnitude
/// (at most [`pkm::machine::MAX_MAGNITUDE`], as in machine files).
pub fn parse_list(text: &str, what: &str) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    for (i, part) in text.split(',').enumerate() {
        let part = part.trim();
        let bad = |m: String| Err(BadArgument(format!("{what}: value {} {m}", i + 1)).into());
        let v: f64 = match part.parse() {
            Ok(v) => v,
            Err(_) => return bad(format!("`{part}` is not a number")),
        };
        if !v.is_finite() {
            return bad(format!("is {part}, expected a finite number"));
        }
        if v.abs() > pkm::machine::MAX_MAGNITUDE {
            return bad(format!(
                "is {part}, beyond the largest magnitude pkm takes (1e6 mm or deg)"
            ));
        }
        out.push(v);
    }
    Ok(out)
}

/// Converts user actuator values (mm or deg) to internal ones.
pub fn actuators_from_user(m: &dyn DynMechanism, vals: &[f64]) -> Result<Vec<f64>> {
    let a = m.actuators();
    if vals.len() != a.len() {
        return Err(BadArgument(format!(
            "actuators: expected {} values ({}), got {}",
            a.len(),
            a.iter()
                .map(|a| a.name.as_str())
                .collect::<Vec<_>>()
                .join(","),
            vals.len()
        ))
        .into());
    }
    Ok(vals
        .iter()
        .zip(a)
        .map(|(v, a)| a.quantity.from_user(*v))
        .collect())
}

/// Pose coordinates as a JSON object `name -> user value`.
pub fn coords_json(m: &dyn DynMechanism, x: &[f64]) -> Value {
    let mut o = Map::new();
    for (c, v) in m.coordinates().iter().zip(x) {
        o.insert(c.name.clone(), json!(clean(c.quantity.to_user(*v))));
    }
    Value::Object(o)
}

/// Actuators as a JSON object `name -> user value`.
pub fn actuators_json(m: &dyn DynMechanism, q: &[f64]) -> Value {
    let mut o = Map::new();
    for (a, v) in m.actuators().iter().zip(q) {
        o.insert(a.name.clone(), json!(clean(a.quantity.to_user(*v))));
    }
    Value::Object(o)
}

/// Tool position (mm), rotation matrix rows and angles (deg) in `conv`.
pub fn tool_json(m: &dyn DynMechanism, x: &[f64], conv: Convention) -> Result<Value> {
    let pose = m.tool_pose(x)?;
    let r = rotation_matrix(&pose);
    let p = pose.translation.vector;
    let a = conv.from_matrix(&r).map(|v| clean(v.to_degrees()));
    Ok(json!({
        "position": [clean(p.x), clean(p.y), clean(p.z)],
        "rotation": [
            [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
            [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
            [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
        ],
        "angles": a,
        "convention": conv.name(),
    }))
}

/// `name value unit` triples of a pose for text output.
pub fn coords_text(m: &dyn DynMechanism, x: &[f64]) -> String {
    m.coordinates()
        .iter()
        .zip(x)
        .map(|(c, v)| {
            format!(
                "{}={:.4} {}",
                c.name,
                clean(c.quantity.to_user(*v)),
                c.quantity.unit()
            )
        })
        .collect::<Vec<_>>()
        .join("  ")
}

/// Turns `-0.0` into `0.0` for display.
pub fn clean(v: f64) -> f64 {
    v + 0.0
}
