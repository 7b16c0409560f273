//! `[[reference]]` entries of a machine file: poses with values published elsewhere
//! (a paper's table, a CAD model, a measurement) that pkm must reproduce.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// One reference pose with expected values, in user units (mm, deg).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// Where the expected values come from.
    pub source: String,
    /// The pose, as `pkm ik --pose` takes it (default convention for angles).
    pub pose: Vec<f64>,
    /// Largest accepted deviation of each expected value (mm or deg).
    pub tolerance: f64,
    /// Remarks (printing errors of the source, ...).
    #[serde(default)]
    pub note: Option<String>,
    /// Expected joint positions (base frame, mm) by name.
    #[serde(default, deserialize_with = "exact_points")]
    pub joints: BTreeMap<String, [f64; 3]>,
    /// Expected actuator values (mm or deg) by name.
    #[serde(default)]
    pub actuators: BTreeMap<String, f64>,
    /// What the source prints, by actuator name, where the project's expected value
    /// (`actuators`) differs from it (a printing or reading error of the source, the
    /// reason in `note`): such a reference is reported as a discrepancy with its
    /// source, never as reproduced.
    #[serde(default)]
    pub published_actuators: BTreeMap<String, f64>,
}

/// Points of exactly three coordinates (a fourth is refused, not dropped).
fn exact_points<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<BTreeMap<String, [f64; 3]>, D::Error> {
    let m = BTreeMap::<String, super::source::Exact<3>>::deserialize(d)?;
    Ok(m.into_iter().map(|(k, v)| (k, v.0)).collect())
}
