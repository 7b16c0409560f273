//! The library's integration tests, one binary (each file a module: compiled and linked once).
//! Run one file's tests with `cargo test -p pkm --test suite FILE::`.

mod common;

mod accuracy;
mod clearance;
mod clearance_p3rp;
mod clearance_seed002;
mod completion;
mod contract;
mod dynamics;
mod fuzz_corpus;
mod gcode;
mod hexapod;
mod hybrid_am;
mod identify;
mod identify_pentapod;
mod identify_sizing;
mod linuxcnc;
mod linuxcnc_tripod;
mod machine_file;
mod motion;
mod motion_robot;
mod motion_threads;
mod p3rp;
mod path_accuracy;
mod pentapod;
mod pose;
mod rotation;
mod seed000;
mod serial;
mod serial_arm;
mod setters;
mod spherical_wrist;
mod statics;
mod tcp;
mod tripod;
mod workspace;
