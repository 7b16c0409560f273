//! Machines described by a TOML file, and the dispatch from a machine of any type to
//! code generic over [`Mechanism`].
//!
//! The file format is documented in `docs/machine-file.md`. Every file has a `type`
//! field; unknown keys are rejected; errors name the file, line, column and field.

mod clearance_file;
mod fields;
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

pub(crate) use fields::*;
pub use reference::Reference;
pub use registry::{Analysis, CalibratableVisitor, FileType, Model, FILE_TYPES};
pub use report_file::{Comparison, ReportSettings, REPORT_SECTIONS};
pub use source::{line_col, MAX_MAGNITUDE};
pub use strut_writer::{with_pentapod_geometry, with_strut_geometry, StrutGeometry};
pub use tolerance_file::{read_deviations, read_tolerances};

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
///
/// Every analysis takes one ([`crate::analysis`]); [`Machine::mechanism`] is its
/// kinematics with run-time sizes, [`Machine::visit`] runs code generic over
/// [`Mechanism`] on its concrete type.
///
/// # Examples
///
/// ```
/// use pkm::machine::Model;
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hexapod-linuxcnc.toml"
/// ))
/// .unwrap();
/// assert_eq!(machine.name.as_deref(), Some("LinuxCNC genhexkins default hexapod (mm)"));
/// assert!(matches!(machine.model, Model::Hexapod(_)));
/// assert_eq!(machine.kind(), "hexapod");
/// // The file's reference pose: every strut 755.56 mm at home.
/// let r = &machine.references[0];
/// assert_eq!(r.pose, machine.mechanism().home());
/// // No `[motion]` rapid rate, no `[[clearance]]` entries in this file.
/// assert!(machine.rapid.is_none() && machine.clearances.is_empty());
/// ```
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
    ///
    /// # Examples
    ///
    /// ```
    /// let machine = pkm::Machine::from_path(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/machines/hexapod-linuxcnc.toml"
    /// ))
    /// .unwrap();
    /// let m = machine.mechanism();
    /// assert_eq!((m.coordinates().len(), m.actuators().len()), (6, 6));
    /// assert!(machine.source.ends_with("hexapod-linuxcnc.toml"));
    /// // A `.urdf` file is read as a robot.
    /// let robot = pkm::Machine::from_path(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/robots/ur5-like.urdf"
    /// ))
    /// .unwrap();
    /// assert_eq!(robot.mechanism().actuators().len(), 6);
    /// let e = pkm::Machine::from_path("no/such/machine.toml").unwrap_err();
    /// assert!(e.to_string().contains("cannot read"));
    /// ```
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
    ///
    /// # Examples
    ///
    /// ```
    /// let machine = pkm::Machine::from_path(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/machines/tripod-seed000.toml"
    /// ))
    /// .unwrap();
    /// // The file's `[report] gcode = "../paths/seed000-arc.ngc"`, from the file's folder.
    /// let program = machine.resolve(machine.report.gcode.as_deref().unwrap());
    /// assert!(program.ends_with("examples/machines/../paths/seed000-arc.ngc"));
    /// assert!(program.exists());
    /// assert_eq!(machine.resolve("/abs/p.ngc"), std::path::PathBuf::from("/abs/p.ngc"));
    /// ```
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
    ///
    /// # Examples
    ///
    /// ```
    /// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/robots/ur5-like.urdf");
    /// let text = std::fs::read_to_string(path).unwrap();
    /// let robot = pkm::Machine::from_urdf_str(&text, "ur5-like.urdf").unwrap();
    /// assert_eq!(robot.kind(), pkm::Machine::from_path(path).unwrap().kind());
    /// assert_eq!(robot.mechanism().actuators().len(), 6);
    /// ```
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
    ///
    /// # Examples
    ///
    /// ```
    /// let text = std::fs::read_to_string(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/machines/tripod-seed000.toml"
    /// ))
    /// .unwrap();
    /// let machine = pkm::Machine::from_toml_str(&text, "tripod-seed000.toml").unwrap();
    /// assert_eq!(machine.kind(), "tripod/translational");
    /// assert_eq!(machine.rapid, Some(100.0)); // `[motion] rapid = 6000.0` mm/min, in mm/s
    /// // Errors name the file and the field.
    /// let e = pkm::Machine::from_toml_str("type = \"crane\"\n", "crane.toml").unwrap_err();
    /// let e = e.to_string();
    /// assert!(e.contains("crane.toml") && e.contains("unknown machine type `crane`"), "{e}");
    /// ```
    pub fn from_toml_str(text: &str, file: &str) -> Result<Machine> {
        let src = source::Source::parse(file, text)?;
        src.check_numbers()?;
        let kind = machine_type(&src, file)?;
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
        machine.check_pose_lengths(&src)?;
        Ok(machine)
    }

    /// Checks that the poses of the file's `[report]` table and references have the
    /// values a pose takes on this machine, no more.
    fn check_pose_lengths(&self, src: &source::Source) -> Result<()> {
        let m = self.mechanism();
        let counts: Vec<usize> = match m.pose_space() {
            crate::mechanism::PoseSpace::Own => vec![m.coordinates().len()],
            _ => vec![3, 6],
        };
        let axes = match m.pose_space() {
            crate::mechanism::PoseSpace::Own => m.coordinates().len().min(3),
            _ => 3,
        };
        let r = &self.report;
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
                    format!("expected {} values, found {n}", one_of(&want)),
                ));
            }
        }
        for (i, r) in self.references.iter().enumerate() {
            if !counts.contains(&r.pose.len()) {
                return Err(src.error(
                    &[
                        source::Seg::Key("reference".into()),
                        source::Seg::Index(i),
                        source::Seg::Key("pose".into()),
                    ],
                    format!(
                        "expected {} values, found {}",
                        one_of(&counts),
                        r.pose.len()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The passive joints whose centres are parameters of the machine (those a
    /// clearance can be given for).
    ///
    /// # Examples
    ///
    /// ```
    /// let machine = pkm::Machine::from_path(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/machines/hexapod-linuxcnc.toml"
    /// ))
    /// .unwrap();
    /// // Three base joints shared by two struts each, six platform joints.
    /// let joints = machine.passive_joints();
    /// assert_eq!(joints.iter().filter(|j| j.body == "base").count(), 3);
    /// assert_eq!(joints.iter().filter(|j| j.body == "platform").count(), 6);
    /// ```
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
    ///
    /// # Examples
    ///
    /// ```
    /// let machine = pkm::Machine::from_path(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/machines/hexapod-linuxcnc.toml"
    /// ))
    /// .unwrap();
    /// let p = machine.parameters();
    /// // Seed 001's 42: each strut's base joint centre, the platform joint centres, the
    /// // six zero lengths.
    /// assert_eq!(p.len(), 42);
    /// assert_eq!(p[0].name, "B1[0].x"); // base joint B1 as strut 0 uses it
    /// assert_eq!(p[18].name, "P1.x");
    /// assert_eq!(p[41].name, "zero(5)");
    /// ```
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

/// The machine type the file's `type` names (`file` names it in errors).
fn machine_type(src: &source::Source, file: &str) -> Result<String> {
    let kind = src
        .root()
        .iter()
        .find(|(k, _)| k.get_ref().as_ref() == "type")
        .map(|(_, v)| v.get_ref().as_str().map(str::to_string));
    match kind {
        None => Err(Error::MachineFile {
            file: file.into(),
            line: None,
            column: None,
            field: "type".into(),
            message: format!(
                "missing field `type`, expected one of: {}",
                registry::type_names()
            ),
        }),
        Some(None) => Err(src.error(
            &[source::Seg::Key("type".into())],
            "expected a string naming the machine type",
        )),
        Some(Some(k)) => Ok(k),
    }
}

/// Counts as `3 or 6`.
fn one_of(counts: &[usize]) -> String {
    counts
        .iter()
        .map(|c| c.to_string())
        .collect::<Vec<_>>()
        .join(" or ")
}
