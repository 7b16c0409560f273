//! A machine written as LinuxCNC configuration: the kinematics module's HAL `setp`
//! lines and the INI entries for its joints, axes and home.

use std::fmt::Write as _;

use super::{fmt_num, Geometry};
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
    fn mm(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::Inch => 25.4,
        }
    }

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
    let kins = model.geometry.kinematics();
    let module = kins.module();
    let k = unit.mm();
    let u = unit.ini_name();
    let len = |v: f64| fmt_num(v / k);
    let mech = machine.mechanism();
    let name = machine
        .name
        .clone()
        .unwrap_or_else(|| mech.name().to_string());
    let mut hal = String::new();
    let _ = writeln!(
        hal,
        "# Written by `pkm export linuxcnc` from {} ({}), lengths in {u}.",
        name, machine.source
    );
    let control = match &model.geometry {
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
    let base = match &model.geometry {
        Geometry::Genhex { base, .. } => &base[..],
        Geometry::Penta { base, .. } => &base[..],
        Geometry::Tripod { .. } => &[],
    };
    if !base.is_empty() {
        let _ = writeln!(hal, "# Base joints in base (world) coordinates");
    }
    for (i, b) in base.iter().enumerate() {
        for (a, c) in ["x", "y", "z"].iter().zip(b.iter()) {
            let _ = writeln!(hal, "setp {module}.base.{i}.{a} {}", len(*c));
        }
    }
    match &model.geometry {
        Geometry::Genhex { platform, .. } => {
            let _ = writeln!(hal, "\n# Platform joints in platform coordinates");
            for (i, p) in platform.iter().enumerate() {
                for (a, c) in ["x", "y", "z"].iter().zip(p.iter()) {
                    let _ = writeln!(hal, "setp {module}.platform.{i}.{a} {}", len(*c));
                }
            }
        }
        Geometry::Penta { radius, height, .. } => {
            let _ = writeln!(
                hal,
                "\n# Effector joints: ring radius, height along the tool axis"
            );
            for i in 0..5 {
                let _ = writeln!(hal, "setp {module}.effector.{i}.r {}", len(radius[i]));
                let _ = writeln!(hal, "setp {module}.effector.{i}.z {}", len(height[i]));
            }
        }
        Geometry::Tripod { bx, cx, cy } => {
            let _ = writeln!(
                hal,
                "# Base joints A = (0, 0, 0), B = (Bx, 0, 0), C = (Cx, Cy, 0); joint n is strut n"
            );
            let _ = writeln!(hal, "setp {module}.Bx {}", len(*bx));
            let _ = writeln!(hal, "setp {module}.Cx {}", len(*cx));
            let _ = writeln!(hal, "setp {module}.Cy {}", len(*cy));
        }
    }
    let coords = kins.coordinates();
    let home = mech.home();
    let q_home = mech.inverse(&home)?;
    let mut ini = String::new();
    let _ = writeln!(
        ini,
        "# Written by `pkm export linuxcnc` from {} ({}): merge into the machine's INI.\n",
        name, machine.source
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
                len(home[i])
            } else {
                fmt_num(home[i].to_degrees())
            }
        })
        .collect();
    let _ = writeln!(
        ini,
        "[TRAJ]\nCOORDINATES = {}\nLINEAR_UNITS = {}\nANGULAR_UNITS = degree\nHOME = {}\n",
        names.join(" "),
        unit.ini_name(),
        hv.join(" ")
    );
    let mcoords = mech.coordinates();
    for (kc, r) in &model.axes.ranges {
        let c = &mcoords[*kc];
        let (lo, hi) = match c.quantity {
            Quantity::Length => (len(r.min), len(r.max)),
            Quantity::Angle => (fmt_num(r.min.to_degrees()), fmt_num(r.max.to_degrees())),
        };
        let _ = writeln!(
            ini,
            "[AXIS_{}]\nMIN_LIMIT = {lo}\nMAX_LIMIT = {hi}\n",
            c.name
        );
    }
    for (i, a) in mech.actuators().iter().enumerate() {
        let offset = model.zero_lengths.as_ref().map_or(q_home[i], |z| z[i]);
        let _ = writeln!(ini, "[JOINT_{i}]\n# strut {}\nTYPE = LINEAR", a.name);
        let _ = writeln!(ini, "HOME = {}", len(q_home[i]));
        let _ = writeln!(ini, "HOME_OFFSET = {}", len(offset));
        let _ = writeln!(ini, "MIN_LIMIT = {}", len(a.range.min));
        let _ = writeln!(ini, "MAX_LIMIT = {}", len(a.range.max));
        if let Some(v) = a.max_velocity {
            let _ = writeln!(ini, "MAX_VELOCITY = {}", len(v));
        }
        if let Some(v) = a.max_acceleration {
            let _ = writeln!(ini, "MAX_ACCELERATION = {}", len(v));
        }
        let _ = writeln!(ini);
    }
    Ok(Exported {
        kinematics: module,
        hal,
        ini,
    })
}
