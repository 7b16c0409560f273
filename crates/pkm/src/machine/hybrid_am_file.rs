//! The `type = "hybrid-am"` machine file: seed 002's hybrid additive machine (four
//! carriages on vertical guides, struts of fixed length, a platform that keeps its Y
//! axis, a rotary table).

use std::collections::BTreeMap;

use nalgebra::Vector6;
use serde::Deserialize;

use super::reference::Reference;
use super::source::{Exact, Seg, Source};
use super::{v3, Model};
use crate::error::Error;
use crate::hybrid_am::{HybridAm, Leg};
use crate::limits::Range;
use crate::mechanism::{Actuator, Mechanism};
use crate::units::Quantity;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct HybridAmFile {
    #[serde(rename = "type")]
    _kind: String,
    /// `[[clearance]]` entries, read for every machine type by `clearance_file`.
    #[serde(default, rename = "clearance")]
    _clearance: Option<serde::de::IgnoredAny>,
    /// The `[report]` table, read for every machine type by `report_file`.
    #[serde(default, rename = "report")]
    _report: Option<serde::de::IgnoredAny>,
    #[serde(default)]
    name: Option<String>,
    #[serde(default)]
    description: Option<String>,
    carriage_joints: BTreeMap<String, Exact<3>>,
    platform_joints: BTreeMap<String, Exact<3>>,
    struts: Vec<StrutFile>,
    tool: ToolFile,
    #[serde(default)]
    table: TableFile,
    #[serde(default)]
    limits: LimitsFile,
    home: HomeFile,
    #[serde(default)]
    reference: Vec<Reference>,
    #[serde(default)]
    motion: Option<super::MotionFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StrutFile {
    name: String,
    carriage: String,
    platform: String,
    length: f64,
    stroke: Exact<2>,
    #[serde(default)]
    max_velocity: Option<f64>,
    #[serde(default)]
    max_acceleration: Option<f64>,
    #[serde(default)]
    stiffness: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ToolFile {
    tip: Exact<3>,
    #[serde(default)]
    tilt: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TableFile {
    #[serde(default = "table_name")]
    name: String,
    #[serde(default)]
    centre: Exact<3>,
    #[serde(default = "table_range")]
    range: Exact<2>,
    #[serde(default)]
    max_velocity: Option<f64>,
    #[serde(default)]
    max_acceleration: Option<f64>,
    #[serde(default)]
    stiffness: Option<f64>,
}

fn table_name() -> String {
    "C".into()
}

fn table_range() -> Exact<2> {
    Exact([-360.0, 360.0])
}

impl Default for TableFile {
    fn default() -> Self {
        TableFile {
            name: table_name(),
            centre: Exact([0.0; 3]),
            range: table_range(),
            max_velocity: None,
            max_acceleration: None,
            stiffness: None,
        }
    }
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct LimitsFile {
    #[serde(default)]
    tilt: Option<Exact<2>>,
    #[serde(default)]
    carriage_joint_axis: Option<Exact<3>>,
    #[serde(default)]
    carriage_joint_max_angle: Option<f64>,
    #[serde(default)]
    platform_joint_axis: Option<Exact<3>>,
    #[serde(default)]
    platform_joint_max_angle: Option<f64>,
    #[serde(default)]
    strut_diameter: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HomeFile {
    position: Exact<3>,
    #[serde(default)]
    angles: Option<Exact<3>>,
}

fn key(k: &str) -> Seg {
    Seg::Key(k.into())
}

fn ordered(src: &Source, path: &[Seg], r: Exact<2>, unit: &str) -> Result<Range, Error> {
    if !(r[0] < r[1]) {
        return Err(src.error(
            path,
            format!(
                "expected [min, max] {unit} with min < max, found [{}, {}]",
                r[0], r[1]
            ),
        ));
    }
    Ok(Range {
        min: r[0],
        max: r[1],
    })
}

/// The four legs: each strut joins one carriage joint to one platform joint, each joint
/// used once.
fn legs(src: &Source, f: &HybridAmFile) -> Result<[Leg; 4], Error> {
    if f.struts.len() != 4 {
        return Err(src.error(
            &[key("struts")],
            format!(
                "the seed-002 machine has exactly 4 struts (one per carriage), found {}",
                f.struts.len()
            ),
        ));
    }
    let mut legs = Vec::with_capacity(4);
    for i in 0..f.struts.len() {
        legs.push(leg(src, f, i)?);
    }
    for (table, joints) in [
        ("carriage_joints", &f.carriage_joints),
        ("platform_joints", &f.platform_joints),
    ] {
        if let Some(n) = joints.keys().find(|n| {
            !f.struts
                .iter()
                .any(|s| s.carriage == **n || s.platform == **n)
        }) {
            return Err(src.error(
                &[key(table), key(n)],
                format!("joint `{n}` is joined by no strut"),
            ));
        }
    }
    Ok(legs.try_into().expect("four legs checked above"))
}

/// Reads strut `i`: its drive name, its two joints (each unused by earlier struts), its
/// length and its stroke.
fn leg(src: &Source, f: &HybridAmFile, i: usize) -> Result<Leg, Error> {
    let s = &f.struts[i];
    let p = |k: &str| vec![key("struts"), Seg::Index(i), key(k)];
    if s.name.trim().is_empty() {
        return Err(src.error(&p("name"), "expected a non-empty strut name"));
    }
    let earlier = &f.struts[..i];
    if earlier.iter().any(|o| o.name == s.name) || s.name == f.table.name {
        return Err(src.error(&p("name"), format!("drive name `{}` is used twice", s.name)));
    }
    let lookup = |joints: &BTreeMap<String, Exact<3>>, name: &str, field: &str| {
        if earlier.iter().any(|o| match field {
            "carriage" => o.carriage == name,
            _ => o.platform == name,
        }) {
            return Err(src.error(
                &p(field),
                format!("{field} joint `{name}` is used by another strut already"),
            ));
        }
        joints.get(name).map(|v| v3(*v)).ok_or_else(|| {
            src.error(
                &p(field),
                format!(
                    "unknown {field} joint `{name}`, expected one of {}",
                    joints.keys().cloned().collect::<Vec<_>>().join(", ")
                ),
            )
        })
    };
    let guide = lookup(&f.carriage_joints, &s.carriage, "carriage")?;
    let platform = lookup(&f.platform_joints, &s.platform, "platform")?;
    if !(s.length > 0.0) {
        return Err(src.error(
            &p("length"),
            format!("expected a strut length > 0 mm, found {}", s.length),
        ));
    }
    let range = ordered(src, &p("stroke"), s.stroke, "mm")?;
    super::positive_opt(src, &p("max_velocity"), s.max_velocity, "mm/s")?;
    super::positive_opt(src, &p("max_acceleration"), s.max_acceleration, "mm/s^2")?;
    super::stiffness_opt(src, &p("stiffness"), s.stiffness, "N/mm")?;
    Ok(Leg {
        actuator: Actuator {
            name: s.name.clone(),
            quantity: Quantity::Length,
            range,
            max_velocity: s.max_velocity,
            max_acceleration: s.max_acceleration,
            stiffness: s.stiffness,
        },
        carriage_name: s.carriage.clone(),
        platform_name: s.platform.clone(),
        guide,
        platform,
        length: s.length,
    })
}

pub(super) fn build(src: &Source, f: HybridAmFile) -> Result<super::Parts, Error> {
    super::distinct_joint_names_in(
        src,
        ("carriage_joints", "carriage", &f.carriage_joints),
        &f.platform_joints,
        &[],
    )?;
    let legs = legs(src, &f)?;
    let table = table(src, &f.table)?;
    if !(f.tool.tilt.abs() <= 180.0) {
        return Err(src.error(
            &[key("tool"), key("tilt")],
            format!(
                "expected an angle in [-180, 180] deg, found {}",
                f.tool.tilt
            ),
        ));
    }
    let home = home(src, &f.home)?;
    let mut m = HybridAm::new(
        f.name.clone().unwrap_or_else(|| "hybrid AM machine".into()),
        legs,
        v3(f.tool.tip),
        f.tool.tilt.to_radians(),
        v3(f.table.centre),
        table,
        home,
    );
    set_limits(src, &f.limits, &mut m)?;
    check_home(src, &m)?;
    let model = Model::HybridAm(Box::new(m));
    super::parts(src, model, f.name, f.description, f.reference, f.motion)
}

/// Reads the rotary table's drive (degrees in the file, radians in the model).
fn table(src: &Source, t: &TableFile) -> Result<Actuator, Error> {
    let tp = |k: &str| vec![key("table"), key(k)];
    if t.name.trim().is_empty() {
        return Err(src.error(&tp("name"), "expected a non-empty drive name"));
    }
    let range = ordered(src, &tp("range"), t.range, "deg")?;
    super::positive_opt(src, &tp("max_velocity"), t.max_velocity, "deg/s")?;
    super::positive_opt(src, &tp("max_acceleration"), t.max_acceleration, "deg/s^2")?;
    super::stiffness_opt(src, &tp("stiffness"), t.stiffness, "N mm/rad")?;
    Ok(Actuator {
        name: t.name.clone(),
        quantity: Quantity::Angle,
        range: Range {
            min: range.min.to_radians(),
            max: range.max.to_radians(),
        },
        max_velocity: t.max_velocity.map(f64::to_radians),
        max_acceleration: t.max_acceleration.map(f64::to_radians),
        stiffness: t.stiffness,
    })
}

/// The home pose, whose A angle must be 0.
fn home(src: &Source, h: &HomeFile) -> Result<Vector6<f64>, Error> {
    let a = h.angles.unwrap_or_default();
    if a[0] != 0.0 {
        return Err(src.error(
            &[key("home"), key("angles")],
            format!(
                "the machine has A = 0 only (the platform tilts about Y: B; the table turns: \
                 C), found A = {}",
                a[0]
            ),
        ));
    }
    let hp = h.position;
    Ok(Vector6::new(
        hp[0],
        hp[1],
        hp[2],
        0.0,
        a[1].to_radians(),
        a[2].to_radians(),
    ))
}

/// Reads `[limits]` (tilt range, joint cones, strut diameter) into `m`.
fn set_limits(src: &Source, lim: &LimitsFile, m: &mut HybridAm) -> Result<(), Error> {
    let tilt = match lim.tilt {
        Some(r) => {
            let r = ordered(src, &[key("limits"), key("tilt")], r, "deg")?;
            Some(Range {
                min: r.min.to_radians(),
                max: r.max.to_radians(),
            })
        }
        None => None,
    };
    let carriage_cone = super::joint_cone(
        src,
        lim.carriage_joint_axis,
        [0.0, 0.0, -1.0],
        lim.carriage_joint_max_angle,
        "carriage",
    )?;
    let platform_cone = super::joint_cone(
        src,
        lim.platform_joint_axis,
        [0.0, 0.0, 1.0],
        lim.platform_joint_max_angle,
        "platform",
    )?;
    super::strut_diameter(src, lim.strut_diameter)?;
    m.set_limits(tilt, carriage_cone, platform_cone, lim.strut_diameter);
    Ok(())
}

/// Checks the home pose is an assembly, and not a singular one.
fn check_home(src: &Source, m: &HybridAm) -> Result<(), Error> {
    let home_err = |e: Error| src.error(&[key("home")], format!("not a pose of the machine: {e}"));
    m.inverse(&m.info().home()).map_err(home_err)?;
    let rc = 1.0 / m.condition(&m.info().home()).map_err(home_err)?;
    if !(rc >= 1e-9) {
        return Err(src.error(
            &[key("home")],
            format!(
                "the machine is singular at its home pose (reciprocal condition {rc:.2e}): a \
                 layout symmetric in X and Y cannot tell the platform's X from its tilt; \
                 check the joints"
            ),
        ));
    }
    Ok(())
}
