//! `[[clearance]]` entries of a machine file, for every machine type with passive
//! joints: which joints (by name, or the classes `base`, `platform`, `all`; the
//! seed-002 machine's `carriage` joints instead of `base`), their
//! type, diametral clearance, bearing length, axis and lever (mm).
//!
//! ```toml
//! [[clearance]]
//! joints = ["base"]          # or names: ["A1", "A2"]; "all"
//! type = "universal"         # spherical (default), revolute, universal
//! diametral = 0.02           # mm
//! bearing_length = 40.0      # mm: the axis tilts by up to atan(c / b)
//! axis = [0.0, 0.0, 1.0]     # in the joint's body frame (revolute, universal)
//! lever = 0.0                # mm from the bearing's middle to the joint centre
//! ```

use serde::Deserialize;

use super::source::{Exact, Seg, Source};
use crate::accuracy::clearance::{JointClearance, JointType, PassiveJoint};
use crate::error::Result;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ClearanceEntry {
    joints: Vec<String>,
    #[serde(default, rename = "type")]
    kind: Option<String>,
    diametral: f64,
    #[serde(default)]
    bearing_length: Option<f64>,
    #[serde(default)]
    axis: Option<Exact<3>>,
    #[serde(default)]
    lever: Option<f64>,
}

#[derive(Debug, Deserialize)]
struct ClearanceOnly {
    #[serde(default)]
    clearance: Vec<ClearanceEntry>,
}

/// The classes of `joints`: the bodies that carry them (`base`, `platform`,
/// `carriage`), in order of first appearance.
fn classes(joints: &[PassiveJoint]) -> Vec<&str> {
    let mut v: Vec<&str> = Vec::new();
    for j in joints {
        if !v.contains(&j.body.as_str()) {
            v.push(&j.body);
        }
    }
    v
}

/// The file's `[[clearance]]` entries resolved against the machine's passive `joints`;
/// errors name the file, line and field.
pub(crate) fn clearances(src: &Source, joints: &[PassiveJoint]) -> Result<Vec<JointClearance>> {
    let f: ClearanceOnly = src.deserialize()?;
    let mut out: Vec<JointClearance> = Vec::new();
    for (i, e) in f.clearance.iter().enumerate() {
        let at = |k: &str| {
            vec![
                Seg::Key("clearance".into()),
                Seg::Index(i),
                Seg::Key(k.into()),
            ]
        };
        if joints.is_empty() {
            return Err(src.error(&at("joints"), crate::accuracy::clearance::NO_PASSIVE_JOINTS));
        }
        let kind = match e.kind.as_deref() {
            None => JointType::Spherical,
            Some(k) => k
                .parse::<JointType>()
                .map_err(|m| src.error(&at("type"), m))?,
        };
        if e.joints.is_empty() {
            return Err(src.error(
                &at("joints"),
                format!(
                    "expected joint names or a class ({}, all)",
                    classes(joints).join(", ")
                ),
            ));
        }
        let names = matched_joints(src, &at("joints"), &e.joints, joints)?;
        for name in names {
            if out.iter().any(|c| c.joint == name) {
                return Err(src.error(
                    &at("joints"),
                    format!("joint `{name}` has a clearance already"),
                ));
            }
            let c = JointClearance {
                joint: name.to_string(),
                kind,
                diametral: e.diametral,
                bearing_length: e.bearing_length,
                axis: e.axis.map(super::v3),
                lever: e.lever.unwrap_or(0.0),
            };
            c.check()
                .map_err(|(field, message)| src.error(&at(field), message))?;
            out.push(c);
        }
    }
    Ok(out)
}

/// The passive joints an entry's `names` select (`at` its field): by name, by class,
/// or `all`; each name must select one at least.
fn matched_joints<'a>(
    src: &Source,
    at: &[Seg],
    names: &[String],
    joints: &'a [PassiveJoint],
) -> Result<Vec<&'a str>> {
    let mut out: Vec<&str> = Vec::new();
    for n in names {
        let matched: Vec<&str> = joints
            .iter()
            .filter(|j| n == "all" || j.body == *n || j.name == *n)
            .map(|j| j.name.as_str())
            .collect();
        if matched.is_empty() {
            return Err(src.error(
                at,
                format!(
                    "unknown joint `{n}`, expected {}, all or one of {}",
                    classes(joints).join(", "),
                    joints
                        .iter()
                        .map(|j| j.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        out.extend(matched);
    }
    Ok(out)
}
