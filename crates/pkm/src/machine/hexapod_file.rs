//! The `type = "hexapod"` machine file.

use std::collections::BTreeMap;

use nalgebra::Vector6;
use serde::Deserialize;

use super::reference::Reference;
use super::source::{Exact, Seg, Source};
use super::{v3, Model};
use crate::error::Error;
use crate::hexapod::{HexStrut, Hexapod, JointCone};
use crate::mechanism::Mechanism;
use crate::rotation::Convention;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct HexapodFile {
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
    platform_joints: BTreeMap<String, Exact<3>>,
    struts: Vec<super::StrutFile>,
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
    platform_joint_axis: Option<Exact<3>>,
    #[serde(default)]
    platform_joint_max_angle: Option<f64>,
    #[serde(default)]
    base_joint_axes: BTreeMap<String, Exact<3>>,
    #[serde(default)]
    platform_joint_axes: BTreeMap<String, Exact<3>>,
    #[serde(default)]
    strut_diameter: Option<f64>,
    #[serde(default)]
    axes: BTreeMap<String, Exact<2>>,
}

/// Result of an identification (`pkm calibrate`): the strut lengths at the control's
/// zero readings.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CalibrationFile {
    zero_lengths: [f64; 6],
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

pub(super) fn build(src: &Source, f: HexapodFile) -> Result<super::Parts, Error> {
    if f.struts.len() != 6 {
        return Err(src.error(
            &[key("struts")],
            format!("a hexapod has exactly 6 struts, found {}", f.struts.len()),
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
    let plat_cone = super::joint_cone(
        src,
        lim.platform_joint_axis,
        [0.0, 0.0, -1.0],
        lim.platform_joint_max_angle,
        "platform",
    )?;
    super::strut_diameter(src, lim.strut_diameter)?;
    let base = JointCones {
        common: base_cone,
        per_joint: per_joint_axes(src, "base", &lim.base_joint_axes, &f.base_joints, base_cone)?,
    };
    let platform = JointCones {
        common: plat_cone,
        per_joint: per_joint_axes(
            src,
            "platform",
            &lim.platform_joint_axes,
            &f.platform_joints,
            plat_cone,
        )?,
    };
    super::distinct_joint_names(src, &f.base_joints, &f.platform_joints, &[])?;
    let struts = struts(src, &f, &base, &platform)?;
    let a = f.home.angles.unwrap_or_default().0.map(f64::to_radians);
    let a = Convention::Rpy.from_matrix(&Convention::Rpy.to_matrix(a));
    let hp = f.home.position;
    let mut h = Hexapod::new(
        f.name.clone().unwrap_or_else(|| "hexapod".into()),
        struts,
        v3(f.tool.tip),
        lim.strut_diameter,
        Vector6::new(hp[0], hp[1], hp[2], a[0], a[1], a[2]),
    );
    h.set_axes(super::axis_limits(
        src,
        &lim.axes,
        &crate::mechanism::spatial_coordinates(),
    )?);
    if let Some(c) = &f.calibration {
        h.set_zero_lengths(Some(zero_lengths(src, c)?));
    }
    check_regular_at_home(src, &h)?;
    let model = Model::Hexapod(Box::new(h));
    super::parts(src, model, f.name, f.description, f.reference, f.motion)
}

/// Reads the identified zero lengths of `[calibration]`, which must be positive.
fn zero_lengths(src: &Source, c: &CalibrationFile) -> Result<Vector6<f64>, Error> {
    if c.zero_lengths.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(src.error(
            &[key("calibration"), key("zero_lengths")],
            "expected six positive strut lengths (mm)",
        ));
    }
    Ok(Vector6::from(c.zero_lengths))
}

/// The joint cones on one side: the common one and the per-joint overrides.
struct JointCones {
    common: Option<JointCone>,
    per_joint: BTreeMap<String, JointCone>,
}

impl JointCones {
    /// The cone of joint `name`: its own axis if given, else the common one.
    fn of(&self, name: &str) -> Option<JointCone> {
        self.per_joint.get(name).copied().or(self.common)
    }
}

/// Reads the per-joint axes of the `which` side. Per-joint axes (a universal joint is
/// mounted along its own axis on a real machine) override the common one; they need
/// the angle and a known joint.
fn per_joint_axes(
    src: &Source,
    which: &str,
    axes: &BTreeMap<String, Exact<3>>,
    joints: &BTreeMap<String, Exact<3>>,
    common: Option<JointCone>,
) -> Result<BTreeMap<String, JointCone>, Error> {
    let field = format!("{which}_joint_axes");
    let mut out = BTreeMap::new();
    for (name, a) in axes {
        let at = [key("limits"), key(&field), key(name)];
        let Some(c) = common else {
            return Err(src.error(
                &at,
                format!("a joint axis needs `limits.{which}_joint_max_angle`"),
            ));
        };
        if !joints.contains_key(name) {
            return Err(src.error(
                &at,
                format!(
                    "unknown {which} joint `{name}`, expected one of {}",
                    joints.keys().cloned().collect::<Vec<_>>().join(", ")
                ),
            ));
        }
        let v = v3(*a);
        if v.norm() < 1e-12 {
            return Err(src.error(&at, "expected a non-zero vector"));
        }
        out.insert(name.clone(), JointCone::new(v.normalize(), c.max_angle));
    }
    Ok(out)
}

/// Reads the six struts with their joint cones, refusing two on the same joint pair.
fn struts(
    src: &Source,
    f: &HexapodFile,
    base_cones: &JointCones,
    platform_cones: &JointCones,
) -> Result<[HexStrut; 6], Error> {
    let mut struts = Vec::with_capacity(6);
    for (i, s) in f.struts.iter().enumerate() {
        let (actuator, base, platform) =
            super::strut_entry(src, &f.struts, i, &f.base_joints, &f.platform_joints)?;
        if f.struts[..i]
            .iter()
            .any(|o| o.base == s.base && o.platform == s.platform)
        {
            return Err(src.error(
                &[key("struts"), Seg::Index(i), key("platform")],
                "two struts join the same pair of joints",
            ));
        }
        struts.push(HexStrut {
            actuator,
            base_name: s.base.clone(),
            platform_name: s.platform.clone(),
            base,
            platform,
            base_cone: base_cones.of(&s.base),
            platform_cone: platform_cones.of(&s.platform),
        });
    }
    Ok(struts.try_into().expect("six struts checked above"))
}

/// Checks the six struts fix the platform: a regular Jacobian at home.
fn check_regular_at_home(src: &Source, h: &Hexapod) -> Result<(), Error> {
    let (p, r) = crate::legs::split_pose(&h.info().home());
    let rc = crate::linalg::rcond1(&h.scaled_twist_jacobian(&p, &r));
    if rc < 1e-9 {
        return Err(src.error(&[key("home")], format!("the hexapod is singular at its home pose (reciprocal condition {rc:.2e}): check the joints")));
    }
    Ok(())
}
