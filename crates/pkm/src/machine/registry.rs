//! The registry: the one place that lists pkm's machine types (their name in files,
//! loader and one-line description), holds the loaded model of each, dispatches from a
//! loaded [`Machine`] to code generic over its concrete type, and answers what each
//! type can do ([`Analysis`], [`Machine::supports`]).
//!
//! A new machine type is added here (a [`FILE_TYPES`] row, a [`Model`] variant, its
//! arms in `dispatch!` and `impl_dyn_mechanism!`, and its capabilities), beside its
//! module and its file loader.

use serde::Serialize;

use super::source::Source;
use super::{Analysable, Machine, Parts, Visitor};
use crate::error::{Error, Result};
use crate::identify::Calibratable;
use crate::mechanism::Mechanism;
use crate::tripod::{CentreLegTripod, TranslationalTripod};

/// One machine type as written in a file's `type` field.
pub struct FileType {
    /// The `type` value.
    pub name: &'static str,
    /// What it describes (docs, `pkm check`).
    pub summary: &'static str,
    /// The loader.
    pub(crate) load: fn(&Source) -> Result<Parts>,
}

/// Every machine type pkm reads from TOML files (URDF robots load as `serial`).
pub const FILE_TYPES: &[FileType] = &[
    FileType {
        name: "tripod",
        summary: "three struts between base and platform (seed 000): translational, or with a passive centre leg (Tricept-like)",
        load: |s| super::tripod_file::build(s, s.deserialize()?),
    },
    FileType {
        name: "hexapod",
        summary: "six struts (Gough-Stewart platform, LinuxCNC genhexkins, seed 001)",
        load: |s| super::hexapod_file::build(s, s.deserialize()?),
    },
    FileType {
        name: "pentapod",
        summary: "five struts to rings around the spindle (LinuxCNC pentakins): tool tip X, Y, Z and axis A, B",
        load: |s| super::pentapod_file::build(s, s.deserialize()?),
    },
    FileType {
        name: "p3rp",
        summary: "the 2-DOF P3RP spindle head of seed 004, alone or on an XY table (4-axis hybrid machine)",
        load: |s| super::p3rp_file::build(s, s.deserialize()?),
    },
    FileType {
        name: "hybrid-am",
        summary: "seed 002's hybrid additive machine: four carriages on vertical guides, struts of fixed length, a platform tilting about Y, a rotary table",
        load: |s| super::hybrid_am_file::build(s, s.deserialize()?),
    },
    FileType {
        name: "serial",
        summary: "serial chains with seed 003's primary deviations: machine tools (tool and workpiece chains), robots from DH tables",
        load: |s| super::serial_file::build(s, s.deserialize()?),
    },
];

/// The file type named `name`.
pub(crate) fn file_type(name: &str) -> Option<&'static FileType> {
    FILE_TYPES.iter().find(|t| t.name == name)
}

/// The file types' names, comma separated (for messages).
pub(crate) fn type_names() -> String {
    FILE_TYPES
        .iter()
        .map(|t| t.name)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The loaded machine of each type, each a [`crate::Mechanism`] (and [`Analysable`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Model {
    /// `type = "tripod"`, `constraint = "translational"`.
    TranslationalTripod(TranslationalTripod),
    /// `type = "tripod"`, `constraint = "centre-leg"`.
    CentreLegTripod(CentreLegTripod),
    /// `type = "hexapod"`.
    Hexapod(Box<crate::hexapod::Hexapod>),
    /// `type = "pentapod"`: LinuxCNC's pentakins machine.
    Pentapod(Box<crate::pentapod::Pentapod>),
    /// `type = "p3rp"` without `[table]`: the P3RP spindle head of seed 004.
    P3rpHead(Box<crate::p3rp::P3rpHead>),
    /// `type = "p3rp"` with `[table]`: the 4-axis hybrid machine of seed 004.
    P3rpHybrid(Box<crate::p3rp::HybridMachine>),
    /// `type = "hybrid-am"`: the hybrid additive machine of seed 002.
    HybridAm(Box<crate::hybrid_am::HybridAm>),
    /// `type = "serial"`: tool and workpiece chains with primary deviations (seed 003).
    Serial(Box<crate::serial::SerialModel>),
}

/// Runs `$body` with `$m` bound to the concrete mechanism of a [`Model`].
macro_rules! dispatch {
    ($model:expr, $m:ident => $body:expr) => {
        match $model {
            Model::TranslationalTripod($m) => $body,
            Model::CentreLegTripod($m) => $body,
            Model::Hexapod(b) => {
                let $m = b.as_ref();
                $body
            }
            Model::Pentapod(b) => {
                let $m = b.as_ref();
                $body
            }
            Model::P3rpHead(b) => {
                let $m = b.as_ref();
                $body
            }
            Model::P3rpHybrid(b) => {
                let $m = b.as_ref();
                $body
            }
            Model::HybridAm(b) => {
                let $m = b.as_ref();
                $body
            }
            Model::Serial(s) => crate::with_serial!(&s.mechanism, $m => $body),
        }
    };
}

crate::impl_dyn_mechanism!(TranslationalTripod, 6, 3);
crate::impl_dyn_mechanism!(CentreLegTripod, 3, 3);
crate::impl_dyn_mechanism!(crate::hexapod::Hexapod, 6, 6);
crate::impl_dyn_mechanism!(crate::pentapod::Pentapod, 6, 5);
crate::impl_dyn_mechanism!(crate::p3rp::P3rpHead, 2, 2);
crate::impl_dyn_mechanism!(crate::p3rp::HybridMachine, 6, 4);
crate::impl_dyn_mechanism!(crate::hybrid_am::HybridAm, 6, 5);
crate::impl_dyn_mechanism!(crate::serial::mechanism::SerialMechanism<1>, 1, 1);
crate::impl_dyn_mechanism!(crate::serial::mechanism::SerialMechanism<2>, 2, 2);
crate::impl_dyn_mechanism!(crate::serial::mechanism::SerialMechanism<3>, 3, 3);
crate::impl_dyn_mechanism!(crate::serial::mechanism::SerialMechanism<4>, 4, 4);
crate::impl_dyn_mechanism!(crate::serial::mechanism::SerialMechanism<5>, 5, 5);
crate::impl_dyn_mechanism!(crate::serial::mechanism::SerialMechanism<6>, 6, 6);
crate::impl_dyn_mechanism!(crate::serial::mechanism::SerialMechanism<7>, 7, 7);
crate::impl_dyn_mechanism!(crate::serial::mechanism::SerialMechanism<8>, 8, 8);
crate::impl_dyn_mechanism!(crate::serial::arm::SerialArm, 6, 6);
crate::impl_dyn_mechanism!(crate::serial::tcp::TcpMachine<4>, 4, 4);
crate::impl_dyn_mechanism!(crate::serial::tcp::TcpMachine<5>, 5, 5);

/// Code generic over the machines [`crate::identify`] identifies (hexapods, translational
/// tripods, pentapods: [`Calibratable`]), run by [`Machine::visit_calibratable`].
pub trait CalibratableVisitor {
    /// What the visit returns.
    type Output;
    /// Called with the concrete machine.
    fn visit<M: Calibratable<A> + Analysable<6, A>, const A: usize>(self, m: &M) -> Self::Output;
}

/// The analyses that only some machine types can run (every machine runs the
/// kinematics, motion, workspace and accuracy analyses).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Analysis {
    /// Identification of geometric parameters from measurements (seed 001).
    Identification,
    /// Every inverse solution (postures) of a pose.
    InverseSolutions,
    /// Forward workspace over a grid of the actuator strokes (at most 3 actuators).
    ForwardWorkspace,
    /// Seed 004's reproduction (the P3RP head's published numbers and figures).
    Seed004,
    /// Bounds of the error from joint clearances (seed 002).
    Clearance,
}

impl Analysis {
    /// Every analysis of this list.
    pub const ALL: [Analysis; 5] = [
        Analysis::Identification,
        Analysis::InverseSolutions,
        Analysis::ForwardWorkspace,
        Analysis::Seed004,
        Analysis::Clearance,
    ];

    /// Its name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Analysis::Identification => "identification",
            Analysis::InverseSolutions => "all inverse solutions",
            Analysis::ForwardWorkspace => "the forward workspace",
            Analysis::Seed004 => "seed 004's reproduction",
            Analysis::Clearance => "joint clearances",
        }
    }
}

impl Machine {
    /// The mechanism behind a dynamic (run-time sized) interface.
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
    /// let home = m.home();
    /// let q = m.inverse(&home).unwrap();
    /// let f = m.forward(&q, &home).unwrap();
    /// assert!(f.pose.iter().zip(&home).all(|(a, b)| (a - b).abs() < 1e-9));
    /// assert!(m.check_limits(&home, &q).unwrap().is_empty());
    /// assert_eq!(m.actuators()[0].name, "0");
    /// ```
    pub fn mechanism(&self) -> &dyn crate::dynamic::DynMechanism {
        dispatch!(&self.model, m => m)
    }

    /// Runs generic code on the concrete mechanism.
    ///
    /// # Examples
    ///
    /// Code written once against [`crate::Mechanism`] with its compile-time sizes, run on
    /// a machine whose type is read from a file.
    ///
    /// ```
    /// use pkm::machine::{Analysable, Visitor};
    /// use pkm::Mechanism;
    /// struct HomeActuators;
    /// impl Visitor for HomeActuators {
    ///     type Output = (usize, usize, Vec<f64>);
    ///     fn visit<M, const P: usize, const A: usize>(self, m: &M) -> Self::Output
    ///     where
    ///         M: Analysable<P, A>,
    ///     {
    ///         let q = m.inverse(&m.info().home()).unwrap();
    ///         (P, A, q.as_slice().to_vec())
    ///     }
    /// }
    /// let machine = pkm::Machine::from_path(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/machines/pentapod-linuxcnc.toml"
    /// ))
    /// .unwrap();
    /// let (p, a, q) = machine.visit(HomeActuators);
    /// assert_eq!((p, a), (6, 5)); // pose X..C, five struts
    /// // pentakins' strut lengths at the axis home.
    /// let want = [614.847, 625.522, 615.710, 635.227, 624.308];
    /// assert!(q.iter().zip(want).all(|(l, w)| (l - w).abs() < 1e-3));
    /// ```
    pub fn visit<V: Visitor>(&self, v: V) -> V::Output {
        dispatch!(&self.model, m => v.visit(m))
    }

    /// Runs code generic over the machines pkm identifies, or says why this machine is
    /// not one.
    pub fn visit_calibratable<V: CalibratableVisitor>(&self, v: V) -> Result<V::Output> {
        match &self.model {
            Model::Hexapod(h) => Ok(v.visit(h.as_ref())),
            Model::TranslationalTripod(t) => Ok(v.visit(t)),
            Model::Pentapod(p) => Ok(v.visit(p.as_ref())),
            _ => Err(self.unsupported(Analysis::Identification)),
        }
    }

    /// Whether the machine can run `analysis`: `Ok`, or [`Error::Unsupported`] saying
    /// why not.
    ///
    /// # Examples
    ///
    /// ```
    /// use pkm::machine::Analysis;
    /// let machine = pkm::Machine::from_path(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/machines/hexapod-linuxcnc.toml"
    /// ))
    /// .unwrap();
    /// assert!(machine.supports(Analysis::Identification).is_ok());
    /// let e = machine.supports(Analysis::Seed004).unwrap_err();
    /// assert!(matches!(e, pkm::Error::Unsupported { .. }));
    /// ```
    pub fn supports(&self, analysis: Analysis) -> Result<()> {
        let ok = match analysis {
            Analysis::Identification => matches!(
                self.model,
                Model::Hexapod(_) | Model::TranslationalTripod(_) | Model::Pentapod(_)
            ),
            Analysis::InverseSolutions => self.robot_arm().is_ok(),
            Analysis::ForwardWorkspace => self.mechanism().actuators().len() <= 3,
            Analysis::Seed004 => matches!(self.model, Model::P3rpHead(_) | Model::P3rpHybrid(_)),
            Analysis::Clearance => !self.passive_joints().is_empty(),
        };
        if ok {
            Ok(())
        } else {
            Err(self.unsupported(analysis))
        }
    }

    /// The analyses of [`Analysis::ALL`] this machine runs.
    ///
    /// # Examples
    ///
    /// ```
    /// use pkm::machine::Analysis;
    /// let machine = pkm::Machine::from_path(concat!(
    ///     env!("CARGO_MANIFEST_DIR"),
    ///     "/../../examples/machines/kr30-dh.toml"
    /// ))
    /// .unwrap();
    /// // A six-axis robot: every posture of a pose, no identification.
    /// let caps = machine.capabilities();
    /// assert!(caps.contains(&Analysis::InverseSolutions));
    /// assert!(!caps.contains(&Analysis::Identification));
    /// ```
    pub fn capabilities(&self) -> Vec<Analysis> {
        Analysis::ALL
            .into_iter()
            .filter(|a| self.supports(*a).is_ok())
            .collect()
    }

    fn unsupported(&self, analysis: Analysis) -> Error {
        let reason = match analysis {
            Analysis::Identification => {
                "identification is implemented for hexapods (the 42 parameters of seed 001), \
                 translational tripods and pentapods"
                    .to_string()
            }
            Analysis::InverseSolutions => {
                "every inverse solution is searched for six-axis robots (tool-pose coordinates); \
                 this machine's inverse kinematics has one solution per pose here"
                    .to_string()
            }
            Analysis::ForwardWorkspace => format!(
                "the forward workspace grids the actuator strokes of machines with at most 3 \
                 actuators; this one has {}",
                self.mechanism().actuators().len()
            ),
            Analysis::Seed004 => "seed 004's reproduction is for P3RP heads".to_string(),
            Analysis::Clearance => crate::accuracy::clearance::NO_PASSIVE_JOINTS.to_string(),
        };
        let m = self.mechanism();
        Error::Unsupported {
            machine: m.name().to_string(),
            kind: m.kind().to_string(),
            analysis: analysis.name(),
            reason,
        }
    }

    /// The six-axis robot of a machine whose inverse has several solutions
    /// ([`Analysis::InverseSolutions`]).
    pub(crate) fn robot_arm(&self) -> Result<&crate::serial::arm::SerialArm> {
        match &self.model {
            Model::Serial(s) => match &s.mechanism {
                crate::serial::mechanism::SerialAny::Arm(a) => Ok(a),
                _ => Err(self.unsupported(Analysis::InverseSolutions)),
            },
            _ => Err(self.unsupported(Analysis::InverseSolutions)),
        }
    }

    /// What a LinuxCNC controller needs of this machine ([`crate::linuxcnc::export`]):
    /// hexapods (genhexkins) and pentapods (pentakins); other types answer
    /// [`Error::Unsupported`].
    pub fn controller_model(&self) -> Result<crate::linuxcnc::ControllerModel> {
        use crate::linuxcnc::{ControllerModel, Geometry};
        match &self.model {
            Model::Hexapod(h) => Ok(ControllerModel {
                geometry: Geometry::Genhex {
                    base: std::array::from_fn(|i| h.hex_struts()[i].base),
                    platform: std::array::from_fn(|i| h.hex_struts()[i].platform - h.tool()),
                },
                axes: h.axes().clone(),
                zero_lengths: h.zero_lengths().map(|z| z.iter().copied().collect()),
            }),
            Model::Pentapod(p) => Ok(ControllerModel {
                geometry: Geometry::Penta {
                    base: std::array::from_fn(|i| p.penta_struts()[i].base),
                    radius: std::array::from_fn(|i| p.penta_struts()[i].ring_radius),
                    height: std::array::from_fn(|i| {
                        p.penta_struts()[i].ring_height - p.tool_height()
                    }),
                },
                axes: p.axes().clone(),
                zero_lengths: p.zero_lengths().map(|z| z.iter().copied().collect()),
            }),
            Model::TranslationalTripod(t) => Ok(ControllerModel {
                geometry: crate::linuxcnc::tripod_geometry(t)?,
                axes: t.tripod_geometry().axes.clone(),
                zero_lengths: t
                    .tripod_geometry()
                    .zero_lengths
                    .map(|z| z.iter().copied().collect()),
            }),
            _ => {
                let m = self.mechanism();
                Err(Error::Unsupported {
                    machine: m.name().to_string(),
                    kind: m.kind().to_string(),
                    analysis: "LinuxCNC export",
                    reason: "LinuxCNC configurations are written for hexapods (genhexkins), \
                             pentapods (pentakins) and translational tripods (tripodkins)"
                        .into(),
                })
            }
        }
    }

    /// The hexapod, for the stream solver that tracks it ([`crate::hexapod::FkTracker`]).
    pub(crate) fn tracked_hexapod(&self) -> Option<&crate::hexapod::Hexapod> {
        match &self.model {
            Model::Hexapod(h) => Some(h),
            _ => None,
        }
    }

    /// Tolerances of the machine's parameters given in its file (`[[tolerance]]`),
    /// indices into its [`crate::accuracy::Parametric::parameters`]; empty when none.
    pub fn tolerances(&self) -> &[crate::accuracy::Tolerance] {
        match &self.model {
            Model::Serial(s) => &s.tolerances,
            _ => &[],
        }
    }

    /// The P3RP head of a P3RP machine as a machine of its own (the head alone, or the
    /// hybrid machine's head at its home configuration), for seed 004's analyses.
    pub fn p3rp_head_machine(&self) -> Result<Machine> {
        let head = self.p3rp_head()?;
        Ok(Machine {
            source: self.source.clone(),
            name: Some(head.info().name().to_string()),
            description: None,
            model: Model::P3rpHead(Box::new(head)),
            references: Vec::new(),
            rapid: self.rapid,
            clearances: Vec::new(),
            report: Default::default(),
        })
    }

    /// The P3RP head of a P3RP machine (the head alone, or the hybrid machine's head at
    /// its home configuration), for seed 004's analyses.
    pub fn p3rp_head(&self) -> Result<crate::p3rp::P3rpHead> {
        match &self.model {
            Model::P3rpHead(h) => Ok(h.as_ref().clone()),
            Model::P3rpHybrid(m) => Ok(m.head_mechanism()),
            _ => Err(self.unsupported(Analysis::Seed004)),
        }
    }
}
