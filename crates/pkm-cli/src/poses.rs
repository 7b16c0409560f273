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

/// The width of a text column holding `names`: the longest name in characters (what
/// `{:<w$}` pads by), at least `at_least`. A user's names (`wrist 1`, `north-west`,
/// `Säule`) then keep the columns after them in line.
pub fn name_width<'a>(names: impl IntoIterator<Item = &'a str>, at_least: usize) -> usize {
    names
        .into_iter()
        .map(|n| n.chars().count())
        .fold(at_least, usize::max)
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
                Shown(c.quantity.to_user(*v)),
                c.quantity.unit()
            )
        })
        .collect::<Vec<_>>()
        .join("  ")
}

/// Turns `-0.0` into `0.0` (JSON values).
pub fn clean(v: f64) -> f64 {
    v + 0.0
}

/// A number for text: formatted with the precision, width, fill and alignment asked
/// for (right-aligned unless told otherwise, as a number), without the minus sign of
/// a value that shows as zero. `-3e-15` at four decimals is `0.0000`, not `-0.0000`: a
/// robot's joint at home or a coordinate on an axis is zero to the digits shown, and
/// a sign there reads as a result.
#[derive(Debug, Clone, Copy)]
pub struct Shown(pub f64);

impl std::fmt::Display for Shown {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use std::fmt::Write;
        let s = match f.precision() {
            Some(p) => format!("{:.*}", p, self.0),
            None => format!("{}", self.0),
        };
        let s = match s.strip_prefix('-') {
            Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest,
            _ => &s,
        };
        let pad = f.width().unwrap_or(0).saturating_sub(s.chars().count());
        let (before, after) = match f.align() {
            Some(std::fmt::Alignment::Left) => (0, pad),
            Some(std::fmt::Alignment::Center) => (pad / 2, pad - pad / 2),
            _ => (pad, 0),
        };
        for _ in 0..before {
            f.write_char(f.fill())?;
        }
        f.write_str(s)?;
        for _ in 0..after {
            f.write_char(f.fill())?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::Shown;

    /// A value that shows as zero loses its sign; every other value, width, fill and
    /// alignment is formatted exactly as std formats the number.
    #[test]
    fn shown_drops_only_the_sign_of_a_shown_zero() {
        assert_eq!(format!("{:.4}", Shown(-3e-15)), "0.0000");
        assert_eq!(format!("{:>10.4}", Shown(-3e-15)), "    0.0000");
        assert_eq!(format!("{:<8.2}|", Shown(-0.004)), "0.00    |");
        assert_eq!(format!("{:*^9.1}", Shown(-0.04)), "***0.0***");
        assert_eq!(format!("{:.3}", Shown(-0.0)), "0.000");
        assert_eq!(format!("{:.4}", Shown(-0.00006)), "-0.0001");
        assert_eq!(format!("{:.0}", Shown(-0.4)), "0");
        assert_eq!(format!("{}", Shown(-1e-300)), format!("{}", -1e-300));
        let mut x = 0.123_456_789_f64;
        for k in 0..2_000 {
            // Values over many magnitudes, both signs, ties and non-finite ones.
            x = (x * 7.31 + 0.17).fract();
            let v = match k % 7 {
                0 => -x * 1e-6,
                1 => x * 1e3,
                2 => -x * 1e6,
                3 => -(k as f64) * 5e-5,
                4 => f64::NAN,
                5 => f64::NEG_INFINITY,
                _ => -x,
            };
            // (ours, std's, std's of the text without its sign, aligned as a number).
            let unsigned = |t: String| t.strip_prefix('-').map(str::to_string).unwrap_or(t);
            let cases = [
                (
                    format!("{:.4}", Shown(v)),
                    format!("{v:.4}"),
                    unsigned(format!("{v:.4}")),
                ),
                (
                    format!("{:>12.4}", Shown(v)),
                    format!("{v:>12.4}"),
                    format!("{:>12}", unsigned(format!("{v:.4}"))),
                ),
                (
                    format!("{:<12.2}", Shown(v)),
                    format!("{v:<12.2}"),
                    format!("{:<12}", unsigned(format!("{v:.2}"))),
                ),
                (
                    format!("{:^11.1}", Shown(v)),
                    format!("{v:^11.1}"),
                    format!("{:^11}", unsigned(format!("{v:.1}"))),
                ),
                (
                    format!("{:9}", Shown(v)),
                    format!("{v:9}"),
                    format!("{:>9}", unsigned(format!("{v}"))),
                ),
            ];
            for (ours, std, zero) in cases {
                let shows_zero = std
                    .trim()
                    .strip_prefix('-')
                    .is_some_and(|r| r.bytes().all(|b| b == b'0' || b == b'.'));
                assert_eq!(ours, if shows_zero { zero } else { std }, "{v}");
            }
        }
    }
}
