//! Helpers shared by the CLI tests.

#![allow(dead_code)]

use std::path::PathBuf;

use assert_cmd::Command;

/// A path in the repository, from the workspace root.
pub fn path(rel: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
        .display()
        .to_string()
}

/// The `pkm` binary under test.
pub fn pkm() -> Command {
    Command::cargo_bin("pkm").unwrap()
}

/// Asserts that a run succeeded, showing its stderr otherwise.
pub fn ok(o: &std::process::Output) {
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
