//! The subcommands.

pub mod atlas;
pub mod calibrate;
pub mod check;
pub mod csvio;
pub mod dynamics;
pub mod errors;
pub mod fk;
pub mod ik;
pub mod linuxcnc;
pub mod motion;
pub mod motion_accuracy;
pub mod motion_series;
pub mod statics;
pub mod tolerance_args;
pub mod workspace;

use std::path::Path;

use anyhow::Result;
use pkm::Machine;

/// Loads a machine file; the error already names file, line and field.
pub fn load(path: &Path) -> Result<Machine> {
    Ok(Machine::from_path(path)?)
}
