//! `pkm import linuxcnc` and `pkm export linuxcnc`: a LinuxCNC configuration to a
//! machine file and back (the conversion is `pkm::linuxcnc`'s).

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::{Args, Subcommand, ValueEnum};
use serde_json::json;

use super::load;
use crate::io::write_atomic;
use crate::out::outln;

/// Where `pkm import` reads from.
#[derive(Subcommand, Debug)]
pub enum ImportFrom {
    /// A LinuxCNC configuration: the INI and the HAL files it names.
    #[command(after_help = "Examples:\n  \
        pkm import linuxcnc ../shared/linuxcnc/hexapod-sim/hexapod.ini --out hexapod.toml\n  \
        pkm import linuxcnc my-machine/pentapod.ini --hal my-machine/calibrated.hal --out pentapod.toml\n\n\
        Reads [KINS] KINEMATICS (genhexkins: a hexapod; pentakins: a pentapod; tripodkins: a\n\
        tripod whose struts meet in one point; xyzbc-/xyzac-trt-kins: a 5-axis mill), the setp lines\n\
        of the HAL files the INI names (module defaults for what they leave unset), [TRAJ]\n\
        units and HOME, [JOINT_n] limits, rates, HOME and HOME_OFFSET, [AXIS_L] travel. Lengths\n\
        become mm, angles deg; the file written says where every value came from.")]
    Linuxcnc(ImportLinuxcncArgs),
}

/// Where `pkm export` writes to.
#[derive(Subcommand, Debug)]
pub enum ExportTo {
    /// LinuxCNC: the kinematics module's HAL setp lines and the INI's entries.
    #[command(after_help = "Examples:\n  \
        pkm export linuxcnc examples/machines/hexapod-linuxcnc.toml --units inch --out lcnc\n  \
        pkm export linuxcnc cal/identified.toml --out lcnc       # a calibrated machine back to the controller\n\n\
        Writes DIR/kinematics.hal (setp lines of genhexkins, pentakins or tripodkins) and DIR/pkm.ini\n\
        ([KINS], [HAL] HALFILE, [TRAJ], [AXIS_L], [JOINT_n] to merge into the machine's INI).\n\
        Joint HOME is the struts at the home pose, HOME_OFFSET the calibrated zero lengths.\n\
        `pkm import linuxcnc DIR/pkm.ini` gives the same machine back.")]
    Linuxcnc(ExportLinuxcncArgs),
}

#[derive(Args, Debug)]
pub struct ImportLinuxcncArgs {
    /// The machine's INI file.
    pub ini: PathBuf,
    /// More HAL files, read after the INI's (their setp lines override).
    #[arg(long, num_args = 1..)]
    pub hal: Vec<PathBuf>,
    /// The machine file to write.
    #[arg(long)]
    pub out: PathBuf,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Units {
    Mm,
    Inch,
}

#[derive(Args, Debug)]
pub struct ExportLinuxcncArgs {
    /// Machine file (a hexapod or a pentapod).
    pub machine: PathBuf,
    /// Length unit of the controller ([TRAJ] LINEAR_UNITS).
    #[arg(long, value_enum, default_value = "mm")]
    pub units: Units,
    /// Directory for kinematics.hal and pkm.ini.
    #[arg(long)]
    pub out: PathBuf,
    /// Print machine-readable JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn import_run(from: &ImportFrom) -> Result<u8> {
    let ImportFrom::Linuxcnc(a) = from;
    let imp = pkm::linuxcnc::import(&a.ini, &a.hal)?;
    let mut inputs: Vec<&Path> = vec![a.ini.as_path()];
    inputs.extend(a.hal.iter().map(PathBuf::as_path));
    write_atomic(&a.out, imp.toml.as_bytes(), &inputs)?;
    for w in &imp.warnings {
        eprintln!("warning: {w}");
    }
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&json!({
                "ini": a.ini,
                "kinematics": imp.kinematics,
                "machine": a.out,
                "warnings": imp.warnings,
            }))?
        )?;
    } else {
        outln!(
            "imported {} ({}) into {}",
            a.ini.display(),
            imp.kinematics,
            a.out.display()
        )?;
    }
    Ok(0)
}

pub fn export_run(to: &ExportTo) -> Result<u8> {
    let ExportTo::Linuxcnc(a) = to;
    let machine = load(&a.machine)?;
    let unit = match a.units {
        Units::Mm => pkm::linuxcnc::LengthUnit::Mm,
        Units::Inch => pkm::linuxcnc::LengthUnit::Inch,
    };
    let exp = pkm::linuxcnc::export(&machine, unit)?;
    let hal = a.out.join("kinematics.hal");
    let ini = a.out.join("pkm.ini");
    write_atomic(&hal, exp.hal.as_bytes(), &[a.machine.as_path()])?;
    write_atomic(&ini, exp.ini.as_bytes(), &[a.machine.as_path()])?;
    if a.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&json!({
                "machine": a.machine,
                "kinematics": exp.kinematics,
                "hal": hal,
                "ini": ini,
            }))?
        )?;
    } else {
        outln!(
            "wrote {} and {} ({})",
            hal.display(),
            ini.display(),
            exp.kinematics
        )?;
    }
    Ok(0)
}
