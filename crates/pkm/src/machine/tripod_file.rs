//! The `type = "tripod"` machine file.

use std::collections::BTreeMap;

use nalgebra::{Vector3, Vector6};
use serde::Deserialize;

use super::reference::Reference;
use super::source::{Exact, Seg, Source};
use super::{length_range, v3, Model};
use crate::error::Error;
use crate::mechanism::Mechanism;
use crate::rotation::Convention;
use crate::tripod::{CentreLeg, CentreLegTripod, Strut, TranslationalTripod, TripodGeometry};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TripodFile {
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
    constraint: Constraint,
    base_joints: BTreeMap<String, Exact<3>>,
    platform_joints: BTreeMap<String, Exact<3>>,
    struts: Vec<super::StrutFile>,
    tool: ToolFile,
    #[serde(default)]
    limits: LimitsFile,
    home: HomeFile,
    #[serde(default)]
    centre_leg: Option<CentreLegFile>,
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
    zero_lengths: Exact<3>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "kebab-case")]
enum Constraint {
    Translational,
    CentreLeg,
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
    max_tilt: Option<f64>,
    #[serde(default)]
    min_strut_spindle_angle: Option<f64>,
    #[serde(default)]
    axes: BTreeMap<String, Exact<2>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HomeFile {
    position: Exact<3>,
    #[serde(default)]
    angles: Option<Exact<3>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CentreLegFile {
    base: Exact<3>,
    #[serde(default)]
    length: Option<Exact<2>>,
}

fn key(k: &str) -> Seg {
    Seg::Key(k.into())
}

fn check_triangle(
    src: &Source,
    path: &[Seg],
    pts: [Vector3<f64>; 3],
    what: &str,
) -> Result<(), Error> {
    let area2 = (pts[1] - pts[0]).cross(&(pts[2] - pts[0])).norm();
    let scale = (pts[1] - pts[0])
        .norm()
        .max((pts[2] - pts[0]).norm())
        .max((pts[2] - pts[1]).norm());
    // Relative to the triangle's size, as a ratio (`1e-9 * scale^2` underflows to 0
    // for joints 1e-200 mm apart, which coinciding joints would pass): a tripod of
    // micrometres is a tripod.
    if !(scale > 0.0 && area2 / scale / scale >= 1e-9) {
        return Err(src.error(
            path,
            if what == "platform" {
                "the three platform joints are collinear or coincide; they must span a \
                 triangle (struts meeting in one point, as in LinuxCNC's tripodkins, share one \
                 platform joint)"
                    .to_string()
            } else {
                format!(
                    "the three {what} joints are collinear or coincide; they must span a triangle"
                )
            },
        ));
    }
    Ok(())
}

pub(super) fn build(src: &Source, f: TripodFile) -> Result<super::Parts, Error> {
    if f.struts.len() != 3 {
        return Err(src.error(
            &[key("struts")],
            format!("a tripod has exactly 3 struts, found {}", f.struts.len()),
        ));
    }
    // The centre leg's joint is named `leg` (its parameters `leg.x`, ...).
    let reserved: &[&str] = if f.centre_leg.is_some() {
        &["leg"]
    } else {
        &[]
    };
    super::distinct_joint_names(src, &f.base_joints, &f.platform_joints, reserved)?;
    let point_platform = f.constraint == Constraint::Translational
        && f.struts.iter().all(|s| s.platform == f.struts[0].platform);
    let struts = struts(src, &f, point_platform)?;
    check_triangle(
        src,
        &[key("base_joints")],
        [0, 1, 2].map(|i| struts[i].base),
        "base",
    )?;
    if !point_platform {
        check_triangle(
            src,
            &[key("platform_joints")],
            [0, 1, 2].map(|i| struts[i].platform),
            "platform",
        )?;
    }
    check_limits(src, &f.limits)?;
    let lim = &f.limits;
    let mut geometry = TripodGeometry::new(
        f.name.clone().unwrap_or_else(|| "tripod".into()),
        struts,
        v3(f.tool.tip),
        lim.max_tilt.map(f64::to_radians),
        lim.min_strut_spindle_angle.map(f64::to_radians),
    );
    if let Some(c) = &f.calibration {
        geometry.zero_lengths = Some(zero_lengths(src, c)?);
    }
    let model = match f.constraint {
        Constraint::Translational => translational(src, &f, geometry)?,
        Constraint::CentreLeg => centre_leg(src, &f, geometry)?,
    };
    super::parts(src, model, f.name, f.description, f.reference, f.motion)
}

/// Reads the three struts, refusing a joint that two struts share (but a point platform).
fn struts(src: &Source, f: &TripodFile, point_platform: bool) -> Result<[Strut; 3], Error> {
    let mut struts = Vec::with_capacity(3);
    for (i, s) in f.struts.iter().enumerate() {
        let p = |k: &str| vec![key("struts"), Seg::Index(i), key(k)];
        let (actuator, base, platform) =
            super::strut_entry(src, &f.struts, i, &f.base_joints, &f.platform_joints)?;
        // A tripod uses each joint once.
        if f.struts[..i].iter().any(|o| o.base == s.base) {
            return Err(src.error(
                &p("base"),
                format!("base joint `{}` already used by another strut", s.base),
            ));
        }
        // A point platform (LinuxCNC's tripodkins): the three struts of a translational
        // tripod meet in one platform joint. Any other sharing is refused.
        if f.struts[..i].iter().any(|o| o.platform == s.platform) && !point_platform {
            return Err(src.error(
                &p("platform"),
                format!(
                    "platform joint `{}` already used by another strut: each strut has its \
                     own platform joint, or (constraint = \"translational\" only) all three \
                     meet in one, a point platform",
                    s.platform
                ),
            ));
        }
        struts.push(Strut {
            actuator,
            base_name: s.base.clone(),
            platform_name: s.platform.clone(),
            base,
            platform,
        });
    }
    Ok(struts.try_into().expect("three struts checked above"))
}

/// Checks the `[limits]` angles are in range.
fn check_limits(src: &Source, lim: &LimitsFile) -> Result<(), Error> {
    if let Some(t) = lim.max_tilt {
        if !(t > 0.0 && t <= 180.0) {
            return Err(src.error(
                &[key("limits"), key("max_tilt")],
                format!("expected an angle in (0, 180] deg, found {t}"),
            ));
        }
    }
    if let Some(a) = lim.min_strut_spindle_angle {
        if !(-90.0..=90.0).contains(&a) {
            return Err(src.error(
                &[key("limits"), key("min_strut_spindle_angle")],
                format!("expected an angle in [-90, 90] deg, found {a}"),
            ));
        }
    }
    Ok(())
}

/// Reads the identified zero lengths of `[calibration]`, which must be positive.
fn zero_lengths(src: &Source, c: &CalibrationFile) -> Result<Vector3<f64>, Error> {
    if c.zero_lengths.iter().any(|l| !(l.is_finite() && *l > 0.0)) {
        return Err(src.error(
            &[key("calibration"), key("zero_lengths")],
            "expected three positive strut lengths (mm)",
        ));
    }
    Ok(nalgebra::Vector3::from(c.zero_lengths.0))
}

/// Builds a translational tripod: its home pose and axis limits.
fn translational(
    src: &Source,
    f: &TripodFile,
    mut geometry: TripodGeometry,
) -> Result<Model, Error> {
    if f.centre_leg.is_some() {
        return Err(src.error(
            &[key("centre_leg")],
            "a `translational` tripod has no centre leg; set constraint = \"centre-leg\" or remove this table",
        ));
    }
    let a = f.home.angles.unwrap_or_default().0;
    let a = a.map(f64::to_radians);
    let p = f.home.position;
    // Home angles are in the default convention; normalise through the matrix so
    // that the stored angles are canonical.
    let a = Convention::Rpy.from_matrix(&Convention::Rpy.to_matrix(a));
    geometry.axes = super::axis_limits(
        src,
        &f.limits.axes,
        &crate::mechanism::spatial_coordinates(),
    )?;
    Ok(Model::TranslationalTripod(TranslationalTripod::new(
        geometry,
        Vector6::new(p[0], p[1], p[2], a[0], a[1], a[2]),
    )))
}

/// Builds a centre-leg tripod: its leg, axis limits, and a check that home is attainable.
fn centre_leg(src: &Source, f: &TripodFile, geometry: TripodGeometry) -> Result<Model, Error> {
    let Some(leg) = &f.centre_leg else {
        return Err(src.error(
            &[key("constraint")],
            "constraint = \"centre-leg\" needs a [centre_leg] table with `base` (and optionally `length`)",
        ));
    };
    if f.home.angles.is_some() {
        return Err(src.error(
            &[key("home"), key("angles")],
            "a centre-leg tripod's orientation follows from its position: give home.position only",
        ));
    }
    let length = match leg.length {
        Some(r) => Some(length_range(src, &[key("centre_leg"), key("length")], r)?),
        None => None,
    };
    let mut t = CentreLegTripod::new(
        geometry,
        CentreLeg {
            base: v3(leg.base),
            length,
        },
        v3(f.home.position),
    );
    let axes = super::axis_limits(src, &f.limits.axes, t.info().coordinates())?;
    t.set_axes(axes);
    if let Err(e) = t.leg_state(&t.info().home()) {
        return Err(src.error(
            &[key("home"), key("position")],
            format!("home is not attainable: {e}"),
        ));
    }
    Ok(Model::CentreLegTripod(t))
}
