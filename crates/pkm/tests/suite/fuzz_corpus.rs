//! Replays the fuzz corpus (`fuzz/corpus/TARGET`) and the crashers the fuzzer found
//! and the project fixed (`fuzz/artifacts/TARGET`) through the same target bodies
//! cargo-fuzz runs (`fuzz/src/lib.rs`), on the stable toolchain: a regression of any of
//! them fails here.

#[allow(dead_code)]
#[path = "../../../../fuzz/src/lib.rs"]
mod targets;

use std::path::PathBuf;

fn replay(target: &str, body: fn(&[u8])) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fuzz");
    let mut n = 0;
    for dir in ["corpus", "artifacts"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir).join(target)) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries.map(|e| e.unwrap().path()).collect();
        files.sort();
        for f in files {
            let data = std::fs::read(&f).unwrap();
            let r = std::panic::catch_unwind(|| body(&data));
            assert!(r.is_ok(), "{} panics", f.display());
            n += 1;
        }
    }
    assert!(n > 0, "no corpus for {target}");
}

#[test]
fn machine_files() {
    replay("machine_toml", targets::machine_toml);
}

#[test]
fn urdf_files() {
    replay("urdf", targets::urdf);
}

#[test]
fn gcode_programs() {
    replay("gcode", targets::gcode);
}

#[test]
fn measurement_files() {
    replay("measurement_csv", targets::measurement_csv);
}

#[test]
fn tolerance_files() {
    replay("tolerance_file", targets::tolerance_file);
}

#[test]
fn tool_tables() {
    replay("tool_table", targets::tool_table);
}

#[test]
fn linuxcnc_configurations() {
    replay("linuxcnc_config", targets::linuxcnc_config);
}

#[test]
fn batch_tables() {
    replay("batch_table", targets::batch_table);
}
