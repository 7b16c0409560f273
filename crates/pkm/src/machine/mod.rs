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
