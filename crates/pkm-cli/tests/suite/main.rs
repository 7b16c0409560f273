//! The `pkm` command end to end, one binary (each file a module: compiled and linked once).
//! Run one file's tests with `cargo test -p pkm-cli --test suite FILE::`.

mod common;

mod browser;
mod calibrate_cli;
mod cli;
mod errors_cli;
mod linuxcnc_cli;
mod motion_cli;
mod pipes_cli;
mod readme_cli;
mod report_cli;
mod robot_cli;
mod scripts;
mod seed002_cli;
mod statics_cli;
mod workspace_cli;
