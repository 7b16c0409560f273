//! A machine written as LinuxCNC configuration: the kinematics module's HAL `setp`
//! lines and the INI entries for its joints, axes and home.

use std::fmt::Write as _;

use super::{fmt_num, ControllerModel, Geometry};
use crate::error::Result;
use crate::units::Quantity;
use crate::Machine;

/// The controller's length unit (`[TRAJ] LINEAR_UNITS`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LengthUnit {
    /// Millimetres.
    Mm,
    /// Inches (25.4 mm).
    Inch,
}

impl LengthUnit {
    /// Millimetres per unit.
    fn mm(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::Inch => 25.4,
        }
    }

    /// The unit's name in an INI file.
    fn ini_name(self) -> &'static str {
        match self {
            LengthUnit::Mm => "mm",
            LengthUnit::Inch => "inch",
        }
    }
}

/// The files of an export.
#[derive(Debug, Clone, PartialEq)]
pub struct Exported {
    /// The kinematics module (`genhexkins`, `pentakins`, `tripodkins`).
    pub kinematics: &'static str,
    /// `kinematics.hal`: the module's `setp` lines.
    pub hal: String,
    /// The INI entries (`[KINS]`, `[HAL] HALFILE = kinematics.hal`, `[TRAJ]`,
    /// `[AXIS_L]`, `[JOINT_n]`), to merge into the machine's INI.
    pub ini: String,
}

/// `machine` as LinuxCNC configuration in `unit` (angles in degrees). Joint `HOME` is
/// the struts at the machine's home pose; `HOME_OFFSET` the calibrated zero lengths
/// (the lengths at the home switches, where readings are zeroed) or, uncalibrated, the
/// same as `HOME`. Importing the export gives the same machine.
pub fn export(machine: &Machine, unit: LengthUnit) -> Result<Exported> {
    let model = machine.controller_model()?;
    let module = model.geometry.kinematics().module();
    let name = machine
        .name
        .clone()
        .unwrap_or_else(|| machine.mechanism().name().to_string());
    let e = Export {
        machine,
        model: &model,
        module,
        unit,
        name,
    };
    let hal = e.hal();
    let ini = e.ini()?;
    Ok(Exported {
        kinematics: module,
        hal,
        ini,
    })
}

/// An export under way: the machine, its controller model and module, the unit.
struct Export<'a> {
    /// The machine.
    machine: &'a Machine,
    /// Its controller model.
    model: &'a ControllerModel,
    /// The kinematics module.
    module: &'static str,
    /// The controller's length unit.
    unit: LengthUnit,
    /// The machine's name.
    name: String,
}

impl Export<'_> {
    /// Length `v` (mm) in the controller's unit.
    fn len(&self, v: f64) -> String {
        fmt_num(v / self.unit.mm())
    }

    /// `kinematics.hal`: a header, then the module's `setp` lines.
    fn hal(&self) -> String {
        let (module, u) = (self.module, self.unit.ini_name());
        let mut hal = String::new();
        let _ = writeln!(
            hal,
            "# Written by `pkm export linuxcnc` from {} ({}), lengths in {u}.",
            self.name, self.machine.source
        );
        let control = match &self.model.geometry {
            Geometry::Genhex { .. } => {
                "platform frame's origin: pkm's tool tip, so the moving\n\
                                   # joints are given relative to it."
            }
            Geometry::Penta { .. } => {
                "effector frame's origin: pkm's tool tip, so the moving\n\
                                  # joints are given relative to it."
            }
            Geometry::Tripod { .. } => "point D, where the struts meet: pkm's tool tip.",
        };
        let _ = writeln!(hal, "# {module} controls its {control}\n");
        self.hal_base(&mut hal);
        self.hal_moving(&mut hal);
        hal
    }

    /// The base joints' `setp` lines (genhexkins, pentakins).
    fn hal_base(&self, hal: &mut String) {
        let module = self.module;
        let base = match &self.model.geometry {
            Geometry::Genhex { base, .. } => &base[..],
            Geometry::Penta { base, .. } => &base[..],
            Geometry::Tripod { .. } => &[],
        };
        if !base.is_empty() {
            let _ = writeln!(hal, "# Base joints in base (world) coordinates");
        }
        for (i, b) in base.iter().enumerate() {
            for (a, c) in ["x", "y", "z"].iter().zip(b.iter()) {
                let _ = writeln!(hal, "setp {module}.base.{i}.{a} {}", self.len(*c));
            }
        }
    }

    /// The moving joints' `setp` lines (the tripod's: its base triangle).
    fn hal_moving(&self, hal: &mut String) {
        let module = self.module;
        match &self.model.geometry {
            Geometry::Genhex { platform, .. } => {
                let _ = writeln!(hal, "\n# Platform joints in platform coordinates");
                for (i, p) in platform.iter().enumerate() {
                    for (a, c) in ["x", "y", "z"].iter().zip(p.iter()) {
                        let _ = writeln!(hal, "setp {module}.platform.{i}.{a} {}", self.len(*c));
                    }
                }
            }
            Geometry::Penta { radius, height, .. } => {
                let _ = writeln!(
                    hal,
                    "\n# Effector joints: ring radius, height along the tool axis"
                );
                for i in 0..5 {
                    let _ = writeln!(hal, "setp {module}.effector.{i}.r {}", self.len(radius[i]));
                    let _ = writeln!(hal, "setp {module}.effector.{i}.z {}", self.len(height[i]));
                }
            }
            Geometry::Tripod { bx, cx, cy } => {
                let _ = writeln!(
                    hal,
                    "# Base joints A = (0, 0, 0), B = (Bx, 0, 0), C = (Cx, Cy, 0); joint n is strut n"
                );
                let _ = writeln!(hal, "setp {module}.Bx {}", self.len(*bx));
                let _ = writeln!(hal, "setp {module}.Cx {}", self.len(*cx));
                let _ = writeln!(hal, "setp {module}.Cy {}", self.len(*cy));
            }
        }
    }

    /// The INI entries: `[KINS]`, `[HAL]`, `[TRAJ]`, then the axes and the joints.
    fn ini(&self) -> Result<String> {
        let module = self.module;
        let mech = self.machine.mechanism();
        let coords = self.model.geometry.kinematics().coordinates();
        let home = mech.home();
        let q_home = mech.inverse(&home)?;
        let mut ini = String::new();
        let _ = writeln!(
            ini,
            "# Written by `pkm export linuxcnc` from {} ({}): merge into the machine's INI.\n",
            self.name, self.machine.source
        );
        let _ = writeln!(
            ini,
            "[KINS]\nKINEMATICS = {module}\nJOINTS = {}\n",
            q_home.len()
        );
        let _ = writeln!(ini, "[HAL]\nHALFILE = kinematics.hal\n");
        let names: Vec<&str> = coords.iter().map(|(c, _)| *c).collect();
        let hv: Vec<String> = coords
            .iter()
            .enumerate()
            .map(|(i, (_, linear))| {
                if *linear {
                    self.len(home[i])
                } else {
                    fmt_num(home[i].to_degrees())
                }
            })
            .collect();
        let _ = writeln!(
            ini,
            "[TRAJ]\nCOORDINATES = {}\nLINEAR_UNITS = {}\nANGULAR_UNITS = degree\nHOME = {}\n",
            names.join(" "),
            self.unit.ini_name(),
            hv.join(" ")
        );
        self.ini_axes(&mut ini);
        self.ini_joints(&mut ini, q_home.as_slice());
        Ok(ini)
    }

    /// An `[AXIS_L]` section per axis with travel in the machine file.
    fn ini_axes(&self, ini: &mut String) {
        let mcoords = self.machine.mechanism().coordinates();
        for (kc, r) in &self.model.axes.ranges {
            let c = &mcoords[*kc];
            let (lo, hi) = match c.quantity {
                Quantity::Length => (self.len(r.min), self.len(r.max)),
                Quantity::Angle => (fmt_num(r.min.to_degrees()), fmt_num(r.max.to_degrees())),
            };
            let _ = writeln!(
                ini,
                "[AXIS_{}]\nMIN_LIMIT = {lo}\nMAX_LIMIT = {hi}\n",
                c.name
            );
        }
    }

    /// A `[JOINT_n]` section per strut, homed at `q_home` (the struts at home).
    fn ini_joints(&self, ini: &mut String, q_home: &[f64]) {
        for (i, a) in self.machine.mechanism().actuators().iter().enumerate() {
            let offset = self.model.zero_lengths.as_ref().map_or(q_home[i], |z| z[i]);
            let _ = writeln!(ini, "[JOINT_{i}]\n# strut {}\nTYPE = LINEAR", a.name);
            let _ = writeln!(ini, "HOME = {}", self.len(q_home[i]));
            let _ = writeln!(ini, "HOME_OFFSET = {}", self.len(offset));
            let _ = writeln!(ini, "MIN_LIMIT = {}", self.len(a.range.min));
            let _ = writeln!(ini, "MAX_LIMIT = {}", self.len(a.range.max));
            if let Some(v) = a.max_velocity {
                let _ = writeln!(ini, "MAX_VELOCITY = {}", self.len(v));
            }
            if let Some(v) = a.max_acceleration {
                let _ = writeln!(ini, "MAX_ACCELERATION = {}", self.len(v));
            }
            let _ = writeln!(ini);
        }
    }
}
