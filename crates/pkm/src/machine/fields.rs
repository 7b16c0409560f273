//! What the machine types' loaders share: the checks and conversions of strokes,
//! joint cones, `[[struts]]` entries, axis travel, joint names, `[motion]` and the
//! `[[reference]]` entries, each error naming the file, line, column and field.

use super::source::{self, Exact};
use super::{Model, MotionFile, Parts, Reference};
use crate::error::Result;

pub(crate) fn v3(a: impl Into<[f64; 3]>) -> nalgebra::Vector3<f64> {
    let a: [f64; 3] = a.into();
    nalgebra::Vector3::new(a[0], a[1], a[2])
}

/// Checks a `[min, max]` pair of lengths: non-negative, ordered.
pub(crate) fn length_range(
    src: &source::Source,
    path: &[source::Seg],
    r: impl Into<[f64; 2]>,
) -> Result<crate::limits::Range> {
    let r: [f64; 2] = r.into();
    if r[0] < 0.0 || r[1] < 0.0 {
        return Err(src.error(
            path,
            format!(
                "expected lengths >= 0 mm as [min, max], found [{}, {}]",
                r[0], r[1]
            ),
        ));
    }
    if r[0] >= r[1] {
        return Err(src.error(
            path,
            format!(
                "expected [min, max] with min < max, found [{}, {}]",
                r[0], r[1]
            ),
        ));
    }
    Ok(crate::limits::Range {
        min: r[0],
        max: r[1],
    })
}

pub(crate) fn positive_opt(
    src: &source::Source,
    path: &[source::Seg],
    v: Option<f64>,
    unit: &str,
) -> Result<()> {
    match v {
        Some(x) if x <= 0.0 => {
            Err(src.error(path, format!("expected a value > 0 {unit}, found {x}")))
        }
        _ => Ok(()),
    }
}

/// A joint's cone from `[limits] {which}_joint_axis` (default `default_axis`) and
/// `{which}_joint_max_angle` (deg): none without an angle; an axis without one is an
/// error.
pub(crate) fn joint_cone(
    src: &source::Source,
    axis: Option<Exact<3>>,
    default_axis: [f64; 3],
    angle: Option<f64>,
    which: &str,
) -> Result<Option<crate::hexapod::JointCone>> {
    let Some(a) = angle else {
        if axis.is_some() {
            return Err(src.error(
                &[
                    source::Seg::Key("limits".into()),
                    source::Seg::Key(format!("{which}_joint_axis")),
                ],
                format!("a joint axis needs `limits.{which}_joint_max_angle`"),
            ));
        }
        return Ok(None);
    };
    if !(a > 0.0 && a <= 180.0) {
        return Err(src.error(
            &[
                source::Seg::Key("limits".into()),
                source::Seg::Key(format!("{which}_joint_max_angle")),
            ],
            format!("expected an angle in (0, 180] deg, found {a}"),
        ));
    }
    let ax = v3(axis.map_or(default_axis, |a| a.0));
    if !(ax.norm() > 1e-12) {
        return Err(src.error(
            &[
                source::Seg::Key("limits".into()),
                source::Seg::Key(format!("{which}_joint_axis")),
            ],
            "expected a non-zero vector",
        ));
    }
    Ok(Some(crate::hexapod::JointCone::new(
        ax.normalize(),
        a.to_radians(),
    )))
}

/// One `[[struts]]` entry (tripods and hexapods).
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct StrutFile {
    pub(crate) name: String,
    pub(crate) base: String,
    pub(crate) platform: String,
    pub(crate) length: Exact<2>,
    #[serde(default)]
    pub(crate) max_velocity: Option<f64>,
    #[serde(default)]
    pub(crate) max_acceleration: Option<f64>,
    /// Axial stiffness (N/mm).
    #[serde(default)]
    pub(crate) stiffness: Option<f64>,
}

type Joints = std::collections::BTreeMap<String, Exact<3>>;

/// Checks strut `i` of `struts` (unique non-empty name, known joints, stroke, rate
/// limits) and returns its actuator and its base and platform joint centres.
pub(crate) fn strut_entry(
    src: &source::Source,
    struts: &[StrutFile],
    i: usize,
    base_joints: &Joints,
    platform_joints: &Joints,
) -> Result<(
    crate::mechanism::Actuator,
    nalgebra::Vector3<f64>,
    nalgebra::Vector3<f64>,
)> {
    use source::Seg;
    let s = &struts[i];
    let p = |k: &str| vec![Seg::Key("struts".into()), Seg::Index(i), Seg::Key(k.into())];
    strut_name(src, i, &s.name, struts[..i].iter().map(|o| o.name.as_str()))?;
    let lookup = |joints: &Joints, name: &str, field: &str, what: &str| {
        joints.get(name).map(|v| v3(*v)).ok_or_else(|| {
            src.error(
                &p(field),
                format!(
                    "unknown {what} joint `{name}`, expected one of {}",
                    joints.keys().cloned().collect::<Vec<_>>().join(", ")
                ),
            )
        })
    };
    let base = lookup(base_joints, &s.base, "base", "base")?;
    let plat = lookup(platform_joints, &s.platform, "platform", "platform")?;
    let actuator = strut_actuator(
        src,
        i,
        &s.name,
        s.length,
        s.max_velocity,
        s.max_acceleration,
        s.stiffness,
    )?;
    Ok((actuator, base, plat))
}

/// Checks the name of strut `i`: not empty, not among the `earlier` struts' names.
pub(crate) fn strut_name<'a>(
    src: &source::Source,
    i: usize,
    name: &str,
    mut earlier: impl Iterator<Item = &'a str>,
) -> Result<()> {
    use source::Seg;
    let at = [
        Seg::Key("struts".into()),
        Seg::Index(i),
        Seg::Key("name".into()),
    ];
    if name.trim().is_empty() {
        return Err(src.error(&at, "expected a non-empty strut name"));
    }
    if earlier.any(|o| o == name) {
        return Err(src.error(&at, format!("strut name `{name}` is used twice")));
    }
    Ok(())
}

/// Checks `[limits] strut_diameter`: positive when given.
pub(crate) fn strut_diameter(src: &source::Source, d: Option<f64>) -> Result<()> {
    match d {
        Some(d) if !(d > 0.0) => Err(src.error(
            &[
                source::Seg::Key("limits".into()),
                source::Seg::Key("strut_diameter".into()),
            ],
            format!("expected a diameter > 0 mm, found {d}"),
        )),
        _ => Ok(()),
    }
}

/// The linear actuator of strut `i` (`[[struts]]` entry): its stroke `length` and
/// rate limits checked.
pub(crate) fn strut_actuator(
    src: &source::Source,
    i: usize,
    name: &str,
    length: Exact<2>,
    max_velocity: Option<f64>,
    max_acceleration: Option<f64>,
    stiffness: Option<f64>,
) -> Result<crate::mechanism::Actuator> {
    use source::Seg;
    let p = |k: &str| vec![Seg::Key("struts".into()), Seg::Index(i), Seg::Key(k.into())];
    let range = length_range(src, &p("length"), length)?;
    positive_opt(src, &p("max_velocity"), max_velocity, "mm/s")?;
    positive_opt(src, &p("max_acceleration"), max_acceleration, "mm/s^2")?;
    stiffness_opt(src, &p("stiffness"), stiffness, "N/mm")?;
    Ok(crate::mechanism::Actuator {
        name: name.to_string(),
        quantity: crate::units::Quantity::Length,
        range,
        max_velocity,
        max_acceleration,
        stiffness,
    })
}

/// Checks a drive's `stiffness` (`unit`: N/mm or N mm/rad): finite and > 0 when given.
pub(crate) fn stiffness_opt(
    src: &source::Source,
    path: &[source::Seg],
    v: Option<f64>,
    unit: &str,
) -> Result<()> {
    match v {
        Some(k) if !(k > 0.0 && k <= 1e12) => Err(src.error(
            path,
            format!("expected a stiffness > 0 {unit} (at most 1e12), found {k}"),
        )),
        _ => Ok(()),
    }
}

/// `[limits] axes`: the travel `[min, max]` of pose coordinates by name (mm, deg),
/// e.g. `axes = { X = [-250, 250], A = [-50, 50] }` (LinuxCNC's `[AXIS_n]` limits).
pub(crate) fn axis_limits(
    src: &source::Source,
    axes: &std::collections::BTreeMap<String, Exact<2>>,
    coordinates: &[crate::mechanism::Coordinate],
) -> Result<crate::limits::AxisLimits> {
    use source::Seg;
    let mut out = crate::limits::AxisLimits::default();
    for (name, r) in axes {
        let at = [
            Seg::Key("limits".into()),
            Seg::Key("axes".into()),
            Seg::Key(name.clone()),
        ];
        let Some(k) = coordinates.iter().position(|c| c.name == *name) else {
            return Err(src.error(
                &at,
                format!(
                    "unknown axis `{name}`, expected one of {}",
                    coordinates
                        .iter()
                        .map(|c| c.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        };
        if !(r[0] < r[1]) {
            return Err(src.error(
                &at,
                format!(
                    "expected [min, max] with min < max, found [{}, {}]",
                    r[0], r[1]
                ),
            ));
        }
        let q = coordinates[k].quantity;
        out.ranges.push((
            k,
            crate::limits::Range {
                min: q.from_user(r[0]),
                max: q.from_user(r[1]),
            },
        ));
    }
    out.ranges.sort_by_key(|(k, _)| *k);
    Ok(out)
}

/// Checks that no joint name is used in both `[base_joints]` and `[platform_joints]`, nor
/// is one of `reserved` (other joints of the machine): parameters, tolerances and
/// clearances are named after the joints and must name one each.
pub(crate) fn distinct_joint_names(
    src: &source::Source,
    base: &Joints,
    platform: &Joints,
    reserved: &[&str],
) -> Result<()> {
    distinct_joint_names_in(src, ("base_joints", "base", base), platform, reserved)
}

/// [`distinct_joint_names`] with the first table named `first.0`, its joints called
/// `first.1` joints (a machine whose joints on the fixed side are not on its base:
/// `carriage_joints`, `carriage`).
pub(crate) fn distinct_joint_names_in(
    src: &source::Source,
    first: (&str, &str, &Joints),
    platform: &Joints,
    reserved: &[&str],
) -> Result<()> {
    use source::Seg;
    let (first_table, what, base) = first;
    for (table, names) in [(first_table, base), ("platform_joints", platform)] {
        if let Some(n) = names.keys().find(|n| reserved.contains(&n.as_str())) {
            return Err(src.error(
                &[Seg::Key(table.into()), Seg::Key(n.clone())],
                format!("joint name `{n}` is reserved for another joint of this machine"),
            ));
        }
    }
    if let Some(n) = platform.keys().find(|n| base.contains_key(*n)) {
        return Err(src.error(
            &[Seg::Key("platform_joints".into()), Seg::Key(n.clone())],
            format!(
                "joint name `{n}` names a {what} joint too: give the two joints different names \
                 (parameters, tolerances and clearances are named after them)"
            ),
        ));
    }
    Ok(())
}

/// Joins a built `model` to its file's name, description, checked `[[reference]]`
/// entries and `[motion]` rapid rate.
pub(crate) fn parts(
    src: &source::Source,
    model: Model,
    name: Option<String>,
    description: Option<String>,
    references: Vec<Reference>,
    motion: Option<MotionFile>,
) -> Result<Parts> {
    check_references(src, &references)?;
    let rapid = check_motion(src, motion.as_ref())?;
    Ok(Parts {
        model,
        name,
        description,
        references,
        rapid,
    })
}

/// Checks `[motion]`; returns the rapid rate in mm/s.
pub(crate) fn check_motion(src: &source::Source, m: Option<&MotionFile>) -> Result<Option<f64>> {
    match m.and_then(|m| m.rapid) {
        Some(r) if !(r > 0.0) => Err(src.error(
            &[
                source::Seg::Key("motion".into()),
                source::Seg::Key("rapid".into()),
            ],
            format!("expected a rate > 0 mm/min, found {r}"),
        )),
        Some(r) => Ok(Some(r / 60.0)),
        None => Ok(None),
    }
}

/// Checks the `[[reference]]` entries' own values (tolerance, finiteness).
pub(crate) fn check_references(src: &source::Source, refs: &[Reference]) -> Result<()> {
    use source::Seg;
    for (i, r) in refs.iter().enumerate() {
        let at = |k: &str| {
            vec![
                Seg::Key("reference".into()),
                Seg::Index(i),
                Seg::Key(k.into()),
            ]
        };
        if !(r.tolerance > 0.0) {
            return Err(src.error(
                &at("tolerance"),
                format!("expected a tolerance > 0, found {}", r.tolerance),
            ));
        }
        if r.joints.is_empty() && r.actuators.is_empty() {
            return Err(src.error(
                &at("source"),
                "a reference needs expected `joints` or `actuators`",
            ));
        }
        if let Some(name) = r
            .published_actuators
            .keys()
            .find(|k| !r.actuators.contains_key(*k))
        {
            return Err(src.error(
                &at("published_actuators"),
                format!(
                    "`{name}`: a published value corrects an expected one; give the \
                     project's value for `{name}` in `actuators` too"
                ),
            ));
        }
        if !r.published_actuators.is_empty() && r.note.is_none() {
            return Err(src.error(
                &at("published_actuators"),
                "a value that differs from its source needs the reason in `note`",
            ));
        }
    }
    Ok(())
}
