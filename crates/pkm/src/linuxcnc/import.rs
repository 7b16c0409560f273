//! A LinuxCNC configuration (INI and the HAL files it names) as a pkm machine file.
//!
//! The kinematics module (`[KINS] KINEMATICS`) decides the machine type: `genhexkins`
//! a hexapod, `pentakins` a pentapod. Its geometry comes from the HAL parameters
//! (`genhexkins.base.N.x`, ...; the module's compiled-in defaults for what the HAL
//! leaves unset, as in LinuxCNC), its strokes, rates and home from `[JOINT_n]`, the
//! axis travel from `[AXIS_L]`, the home pose from `[TRAJ] HOME` (or `[AXIS_L] HOME`);
//! lengths are converted from `[TRAJ] LINEAR_UNITS` to mm, angles from
//! `ANGULAR_UNITS` to degrees. The file written says where every value came from.

// Struts and their joint names are indexed together.
#![allow(clippy::needless_range_loop)]

mod struts;
mod trt;
mod writer;

use std::path::Path;

use super::hal::Hal;
use super::ini::{file_error, short, Ini};
use super::{fmt_num, Kinematics};
use crate::error::Result;
use writer::{join_origins, Units, Writer, OPEN_STROKE};

/// A LinuxCNC configuration converted to a pkm machine file.
#[derive(Debug, Clone, PartialEq)]
pub struct Imported {
    /// The machine file (TOML, commented).
    pub toml: String,
    /// The kinematics module (`genhexkins`, `pentakins`, `tripodkins`, ...).
    pub kinematics: &'static str,
    /// What the user should know: values that were adjusted, HOME values that do not
    /// match the geometry, parameters that follow run-time signals.
    pub warnings: Vec<String>,
}

/// Imports the configuration of `ini` (HAL files it names are read relative to its
/// directory; `LIB:` files and Tcl files hold no geometry and are skipped), then the
/// `extra_hal` files, whose `setp` lines override the INI's.
pub fn import(ini: &Path, extra_hal: &[std::path::PathBuf]) -> Result<Imported> {
    let name = ini.display().to_string();
    let text = read(ini, &name, None)?;
    let dir = ini.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut extra = Vec::new();
    for h in extra_hal {
        extra.push((
            h.display().to_string(),
            read(h, &h.display().to_string(), None)?,
        ));
    }
    import_with(
        &name,
        &text,
        &mut |f: &str| std::fs::read_to_string(dir.join(f)).map_err(|e| e.to_string()),
        &extra,
    )
}

fn read(path: &Path, name: &str, line: Option<usize>) -> Result<String> {
    let meta = std::fs::metadata(path)
        .map_err(|e| file_error(name, line, "", format!("cannot read: {e}")))?;
    if meta.len() > super::ini::MAX_TEXT as u64 {
        return Err(file_error(
            name,
            line,
            "",
            format!("{} bytes is not a LinuxCNC configuration file", meta.len()),
        ));
    }
    std::fs::read_to_string(path)
        .map_err(|e| file_error(name, line, "", format!("cannot read: {e}")))
}

/// [`import`] on texts: the INI `ini_text` (named `ini_file`), the HAL files it names
/// read by `read_named`, then `extra_hal` (name, text) pairs.
pub fn import_with(
    ini_file: &str,
    ini_text: &str,
    read_named: &mut dyn FnMut(&str) -> std::result::Result<String, String>,
    extra_hal: &[(String, String)],
) -> Result<Imported> {
    let ini = Ini::parse(ini_file, ini_text)?;
    let kins_entry = ini.get("KINS", "KINEMATICS").ok_or_else(|| {
        file_error(
            ini_file,
            None,
            "[KINS] KINEMATICS",
            "no kinematics module named: expected `[KINS] KINEMATICS = genhexkins`, `pentakins`, `tripodkins`, `xyzbc-trt-kins` or `xyzac-trt-kins`",
        )
    })?;
    let module = kins_entry.value.split_whitespace().next().unwrap_or("");
    let kins = Kinematics::from_module(module).ok_or_else(|| {
        ini.error(
            kins_entry,
            format!(
                "unsupported kinematics `{module}`: pkm imports genhexkins (hexapod), \
                 pentakins (pentapod), tripodkins (tripod), xyzbc-trt-kins and \
                 xyzac-trt-kins (5-axis mills)"
            ),
        )
    })?;
    let mut hal = Hal::default();
    let mut sources = Vec::new();
    let mut warnings = Vec::new();
    for e in ini.all("HAL", "HALFILE") {
        let f = e.value.as_str();
        if f.starts_with("LIB:") || f.ends_with(".tcl") {
            continue;
        }
        let text = read_named(f)
            .map_err(|m| ini.error(e, format!("cannot read the HAL file `{f}` it names: {m}")))?;
        hal.read(f, &text, 1, &ini)?;
        sources.push(f.to_string());
    }
    for e in ini.all("HAL", "HALCMD") {
        hal.read(ini_file, &e.value, e.line, &ini)?;
    }
    for (f, text) in extra_hal {
        hal.read(f, text, 1, &ini)?;
        sources.push(short(f).to_string());
    }
    let units = Units::read(&ini, &mut warnings)?;
    let mut w = Writer {
        ini: &ini,
        hal: &hal,
        units,
        kins,
        out: String::new(),
        warnings,
    };
    w.header(&sources);
    match kins {
        Kinematics::Genhex => w.genhex()?,
        Kinematics::Penta => w.penta()?,
        Kinematics::Tripod => w.tripod()?,
        Kinematics::XyzbcTrt | Kinematics::XyzacTrt => {
            w.trt()?;
            return w.trt_finish();
        }
    }
    w.finish()
}
