//! Machines described by a TOML file, and the dispatch from a machine of any type to
//! code generic over [`Mechanism`].
//!
//! The file format is documented in `docs/machine-file.md`. Every file has a `type`
//! field; unknown keys are rejected; errors name the file, line, column and field.

mod clearance_file;
mod hexapod_file;
mod hybrid_am_file;
mod p3rp_file;
mod pentapod_file;
mod reference;
mod registry;
mod report_file;
mod serial_file;
mod source;
mod strut_writer;
mod tolerance_file;
mod tripod_file;
mod urdf_file;

use std::path::Path;

use crate::error::{Error, Result};
use crate::mechanism::Mechanism;
use source::Exact;

pub use reference::Reference;
pub use registry::{Analysis, CalibratableVisitor, FileType, Model, FILE_TYPES};
pub use report_file::{Comparison, ReportSettings, REPORT_SECTIONS};
pub use source::{line_col, MAX_MAGNITUDE};
pub use strut_writer::{with_pentapod_geometry, with_strut_geometry, StrutGeometry};
pub use tolerance_file::{read_deviations, read_tolerances};

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
) -> Result<crate::mechanism::Actuator> {
    use source::Seg;
    let p = |k: &str| vec![Seg::Key("struts".into()), Seg::Index(i), Seg::Key(k.into())];
    let range = length_range(src, &p("length"), length)?;
    positive_opt(src, &p("max_velocity"), max_velocity, "mm/s")?;
    positive_opt(src, &p("max_acceleration"), max_acceleration, "mm/s^2")?;
    Ok(crate::mechanism::Actuator {
        name: name.to_string(),
        quantity: crate::units::Quantity::Length,
        range,
        max_velocity,
        max_acceleration,
    })
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

/// What a machine-type loader returns.
pub(crate) struct Parts {
    model: Model,
    name: Option<String>,
    description: Option<String>,
    references: Vec<Reference>,
    rapid: Option<f64>,
}

/// The `[motion]` table: motion settings of the machine.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct MotionFile {
    /// Rapid (G0) rate, mm/min.
    #[serde(default)]
    rapid: Option<f64>,
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

/// What every machine type implements: the kinematics ([`Mechanism`]) and the
/// accuracy engine's parameters ([`crate::accuracy::Parametric`]). Generic analyses
/// take `M: Analysable<P, A>`.
pub trait Analysable<const P: usize, const A: usize>:
    Mechanism<P, A> + crate::accuracy::Parametric<P, A>
{
}

impl<M, const P: usize, const A: usize> Analysable<P, A> for M where
    M: Mechanism<P, A> + crate::accuracy::Parametric<P, A>
{
}

/// Code generic over any mechanism, run on a machine whose type is known at run time
/// by [`Machine::visit`].
pub trait Visitor {
    /// What the visit returns.
    type Output;
    /// Called with the concrete mechanism.
    fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(self, m: &M) -> Self::Output;
}

/// A machine loaded from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    /// Where it was read from (file name, or `<string>`).
    pub source: String,
    /// Name from the file.
    pub name: Option<String>,
    /// Description from the file.
    pub description: Option<String>,
    /// The mechanism.
    pub model: Model,
    /// Reference poses with published values to reproduce.
    pub references: Vec<Reference>,
    /// Rapid (G0) rate from the file's `[motion]` table (mm/s).
    pub rapid: Option<f64>,
    /// Clearances of its passive joints from the file's `[[clearance]]` entries.
    pub clearances: Vec<crate::accuracy::clearance::JointClearance>,
    /// What `pkm report` shows for it by default, from the file's `[report]` table.
    pub report: ReportSettings,
}

impl Machine {
    /// Reads and validates a machine file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Machine> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| Error::MachineFile {
            file: name.clone(),
            line: None,
            column: None,
            field: String::new(),
            message: format!("cannot read: {e}"),
        })?;
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
        {
            return Machine::from_urdf_str(&text, &name);
        }
        Machine::from_toml_str(&text, &name)
    }

    /// `path` as written in this machine's file (a `[report]` program): relative
    /// paths are taken from the machine file's directory, as a reader of the file
    /// expects; absolute ones as they are.
    pub fn resolve(&self, path: &str) -> std::path::PathBuf {
        let p = Path::new(path);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        match Path::new(&self.source).parent() {
            Some(dir) => dir.join(p),
            None => p.to_path_buf(),
        }
    }

    /// Reads a robot from URDF text: the serial chain from the root link to the
    /// deepest leaf, in millimetres (see `docs/serial.md`).
    pub fn from_urdf_str(text: &str, file: &str) -> Result<Machine> {
        let parts = urdf_file::build(text, file)?;
        Ok(Machine {
            source: file.into(),
            name: parts.name,
            description: parts.description,
            model: parts.model,
            references: parts.references,
            rapid: parts.rapid,
            clearances: Vec::new(),
            report: ReportSettings::default(),
        })
    }

    /// Parses and validates a machine description; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Machine> {
        let src = source::Source::parse(file, text)?;
        src.check_numbers()?;
        let kind = src
            .root()
            .iter()
            .find(|(k, _)| k.get_ref().as_ref() == "type")
            .map(|(_, v)| v.get_ref().as_str().map(str::to_string));
        let kind = match kind {
            None => {
                return Err(Error::MachineFile {
                    file: file.into(),
                    line: None,
                    column: None,
                    field: "type".into(),
                    message: format!(
                        "missing field `type`, expected one of: {}",
                        registry::type_names()
                    ),
                })
            }
            Some(None) => {
                return Err(src.error(
                    &[source::Seg::Key("type".into())],
                    "expected a string naming the machine type",
                ))
            }
            Some(Some(k)) => k,
        };
        let parts = match registry::file_type(&kind) {
            Some(t) => (t.load)(&src)?,
            None => {
                return Err(src.error(
                    &[source::Seg::Key("type".into())],
                    format!(
                        "unknown machine type `{kind}`, expected one of: {}",
                        registry::type_names()
                    ),
                ))
            }
        };
        let mut machine = Machine {
            source: file.into(),
            name: parts.name,
            description: parts.description,
            model: parts.model,
            references: parts.references,
            rapid: parts.rapid,
            clearances: Vec::new(),
            report: report_file::report_settings(&src)?,
        };
        machine.clearances = clearance_file::clearances(&src, &machine.passive_joints())?;
        // A reference pose has the values a pose takes on this machine, no more.
        let m = machine.mechanism();
        let counts: Vec<usize> = match m.pose_space() {
            crate::mechanism::PoseSpace::Own => vec![m.coordinates().len()],
            _ => vec![3, 6],
        };
        let axes = match m.pose_space() {
            crate::mechanism::PoseSpace::Own => m.coordinates().len().min(3),
            _ => 3,
        };
        let r = &machine.report;
        let report_arrays = [
            ("pose", r.pose.as_ref().map(|v| v.len()), counts.clone()),
            ("from", r.from.as_ref().map(|v| v.len()), counts.clone()),
            ("bounds", r.bounds.as_ref().map(|v| v.len()), vec![2 * axes]),
        ];
        for (key, len, want) in report_arrays {
            if let Some(n) = len.filter(|n| !want.contains(n)) {
                return Err(src.error(
                    &[
                        source::Seg::Key("report".into()),
                        source::Seg::Key(key.into()),
                    ],
                    format!(
                        "expected {} values, found {n}",
                        want.iter()
                            .map(|c| c.to_string())
                            .collect::<Vec<_>>()
                            .join(" or ")
                    ),
                ));
            }
        }
        for (i, r) in machine.references.iter().enumerate() {
            if !counts.contains(&r.pose.len()) {
                return Err(src.error(
                    &[
                        source::Seg::Key("reference".into()),
                        source::Seg::Index(i),
                        source::Seg::Key("pose".into()),
                    ],
                    format!(
                        "expected {} values, found {}",
                        counts
                            .iter()
                            .map(|c| c.to_string())
                            .collect::<Vec<_>>()
                            .join(" or "),
                        r.pose.len()
                    ),
                ));
            }
        }
        Ok(machine)
    }

    /// The passive joints whose centres are parameters of the machine (those a
    /// clearance can be given for).
    pub fn passive_joints(&self) -> Vec<crate::accuracy::clearance::PassiveJoint> {
        struct Joints;
        impl Visitor for Joints {
            type Output = Vec<crate::accuracy::clearance::PassiveJoint>;
            fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(
                self,
                m: &M,
            ) -> Self::Output {
                m.passive_joints()
            }
        }
        self.visit(Joints)
    }

    /// The machine's geometric parameters (the accuracy engine's list).
    pub fn parameters(&self) -> Vec<crate::accuracy::Parameter> {
        struct Params;
        impl Visitor for Params {
            type Output = Vec<crate::accuracy::Parameter>;
            fn visit<M: Analysable<P, A>, const P: usize, const A: usize>(
                self,
                m: &M,
            ) -> Self::Output {
                m.parameters()
            }
        }
        self.visit(Params)
    }

    /// The machine type as written in the `type` field plus its variant.
    pub fn kind(&self) -> &'static str {
        self.mechanism().kind()
    }
}
