//! The `type = "pentapod"` machine file (LinuxCNC's pentakins geometry).

use std::collections::BTreeMap;

use nalgebra::Vector6;
use serde::Deserialize;

use super::reference::Reference;
use super::source::{Exact, Seg, Source};
use super::{v3, Model};
use crate::error::Error;
use crate::hexapod::JointCone;
use crate::mechanism::Mechanism;
use crate::pentapod::{PentaStrut, Pentapod};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PentapodFile {
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
    base_joints: BTreeMap<String, Exact<3>>,
    struts: Vec<StrutFile>,
    tool: ToolFile,
    #[serde(default)]
    limits: LimitsFile,
    home: HomeFile,
    #[serde(default)]
    calibration: Option<CalibrationFile>,
    #[serde(default)]
    reference: Vec<Reference>,
    #[serde(default)]
    motion: Option<super::MotionFile>,
}

/// Result of an identification (`pkm calibrate`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CalibrationFile {
    zero_lengths: Exact<5>,
}

/// One `[[struts]]` entry: a base joint and the ring of the effector joint.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StrutFile {
    name: String,
    base: String,
    ring_radius: f64,
    ring_height: f64,
    length: Exact<2>,
    #[serde(default)]
    max_velocity: Option<f64>,
    #[serde(default)]
    max_acceleration: Option<f64>,
    /// Axial stiffness (N/mm).
    #[serde(default)]
    stiffness: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ToolFile {
    tip: Exact<3>,
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct LimitsFile {
    #[serde(default)]
    base_joint_axis: Option<Exact<3>>,
    #[serde(default)]
    base_joint_max_angle: Option<f64>,
    #[serde(default)]
    strut_diameter: Option<f64>,
    #[serde(default)]
    axes: BTreeMap<String, Exact<2>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HomeFile {
    position: Exact<3>,
    /// A and B (deg); C is 0 (the spin about the tool axis is free).
    #[serde(default)]
    angles: Option<Exact<2>>,
}

fn key(k: &str) -> Seg {
    Seg::Key(k.into())
}

pub(super) fn build(src: &Source, f: PentapodFile) -> Result<super::Parts, Error> {
    if f.struts.len() != 5 {
        return Err(src.error(
            &[key("struts")],
            format!("a pentapod has exactly 5 struts, found {}", f.struts.len()),
        ));
    }
    let lim = &f.limits;
    let base_cone = super::joint_cone(
        src,
        lim.base_joint_axis,
        [0.0, 0.0, 1.0],
        lim.base_joint_max_angle,
        "base",
    )?;
    super::strut_diameter(src, lim.strut_diameter)?;
    let tip = f.tool.tip;
    check_tip_on_axis(src, &tip)?;
    let struts = struts(src, &f, base_cone)?;
    let a = f.home.angles.unwrap_or_default().0.map(f64::to_radians);
    let hp = f.home.position;
    let coordinates = crate::mechanism::spatial_coordinates();
    let axes = super::axis_limits(src, &lim.axes, &coordinates)?;
    if axes.ranges.iter().any(|(k, _)| *k == 5) {
        return Err(src.error(
            &[key("limits"), key("axes"), key("C")],
            "a pentapod holds C (the spin about the tool axis is free): limit X, Y, Z, A, B",
        ));
    }
    let mut m = Pentapod::new(
        f.name.clone().unwrap_or_else(|| "pentapod".into()),
        struts,
        tip[2],
        lim.strut_diameter,
        axes,
        Vector6::new(hp[0], hp[1], hp[2], a[0], a[1], 0.0),
    );
    if let Some(c) = &f.calibration {
        if c.zero_lengths.iter().any(|l| !(*l > 0.0)) {
            return Err(src.error(
                &[key("calibration"), key("zero_lengths")],
                "expected five positive strut lengths (mm)",
            ));
        }
        m.set_zero_lengths(Some(nalgebra::SVector::<f64, 5>::from(c.zero_lengths.0)));
    }
    check_regular_at_home(src, &m)?;
    let model = Model::Pentapod(Box::new(m));
    super::parts(src, model, f.name, f.description, f.reference, f.motion)
}

/// Checks the tool tip lies on the spindle axis.
fn check_tip_on_axis(src: &Source, tip: &Exact<3>) -> Result<(), Error> {
    if tip[0] != 0.0 || tip[1] != 0.0 {
        return Err(src.error(
            &[key("tool"), key("tip")],
            format!(
                "a pentapod's tool tip lies on the spindle axis (the struts leave the spin \
                 about it free): expected [0, 0, z], found [{}, {}, {}]",
                tip[0], tip[1], tip[2]
            ),
        ));
    }
    Ok(())
}

/// Reads the five struts: name, base joint, platform ring and actuator of each.
fn struts(
    src: &Source,
    f: &PentapodFile,
    base_cone: Option<JointCone>,
) -> Result<[PentaStrut; 5], Error> {
    let mut struts = Vec::with_capacity(5);
    for (i, s) in f.struts.iter().enumerate() {
        let at = |k: &str| [key("struts"), Seg::Index(i), key(k)];
        super::strut_name(
            src,
            i,
            &s.name,
            f.struts[..i].iter().map(|o| o.name.as_str()),
        )?;
        let base = f.base_joints.get(&s.base).map(|v| v3(*v)).ok_or_else(|| {
            src.error(
                &at("base"),
                format!(
                    "unknown base joint `{}`, expected one of {}",
                    s.base,
                    f.base_joints.keys().cloned().collect::<Vec<_>>().join(", ")
                ),
            )
        })?;
        if !(s.ring_radius >= 0.0) {
            return Err(src.error(
                &at("ring_radius"),
                format!("expected a radius >= 0 mm, found {}", s.ring_radius),
            ));
        }
        let actuator = super::strut_actuator(
            src,
            i,
            &s.name,
            s.length,
            s.max_velocity,
            s.max_acceleration,
            s.stiffness,
        )?;
        struts.push(PentaStrut {
            actuator,
            base_name: s.base.clone(),
            base,
            ring_radius: s.ring_radius,
            ring_height: s.ring_height,
            base_cone,
        });
    }
    Ok(struts.try_into().expect("five struts checked above"))
}

/// Checks the five struts fix the tool axis: a regular driven Jacobian at home.
fn check_regular_at_home(src: &Source, m: &Pentapod) -> Result<(), Error> {
    let rc = match crate::mechanism::scaled_driven_jacobian(m, &m.info().home()) {
        Ok(j) => crate::linalg::rcond1(&j),
        Err(e) => return Err(src.error(&[key("home")], e.to_string())),
    };
    if rc < 1e-9 {
        return Err(src.error(
            &[key("home")],
            format!(
                "the pentapod is singular at its home pose (reciprocal condition {rc:.2e}): \
                 check the joints"
            ),
        ));
    }
    Ok(())
}
