//! The project's scripts as a user runs them.

use super::common::path;

/// `scripts/test` runs every step even when one fails, and lists every failure at
/// the end with exit status 1: run here with a `cargo` and a `python3` that fail at
/// once (fakes first on PATH), it reports the Rust tests, the library's tests on each
/// narrower SIMD level, then the Python environment, all four.
#[cfg(unix)]
#[test]
fn the_test_script_runs_every_suite_and_reports_every_failure() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path().join("bin");
    std::fs::create_dir(&bin).unwrap();
    for fake in ["cargo", "python3"] {
        let f = bin.join(fake);
        std::fs::write(
            &f,
            format!("#!/bin/sh\necho \"fake {fake} $*\" >&2\nexit 1\n"),
        )
        .unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let o = std::process::Command::new("bash")
        .arg(path("scripts/test"))
        .env(
            "PATH",
            format!("{}:{}", bin.display(), std::env::var("PATH").unwrap()),
        )
        // A browser that "exists": nothing is installed.
        .env("PKM_CHROMIUM", "sh")
        .env("PKM_TEST_VENV", dir.path().join("venv"))
        .env_remove("PYTHON")
        .env_remove("PKM_SKIP_PYTHON")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("fake cargo test --workspace"), "{err}");
    assert!(err.contains("fake python3 -m venv"), "{err}");
    let last = err.lines().last().unwrap();
    assert!(
        last.contains("4 step(s)")
            && last.contains("cargo test --workspace")
            && last.contains("PKM_SIMD=scalar")
            && last.contains("PKM_SIMD=avx2")
            && last.contains("making the Python virtual environment"),
        "{last}"
    );
}
