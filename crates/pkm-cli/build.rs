//! Bundles the report's 3D view: three.js (from the npm registry, pinned by
//! `web/package-lock.json`; no third-party code is committed) and `web/src/view3d.js`
//! into one script, `$OUT_DIR/view3d.js`, that `pkm report` inlines so the report stays
//! one self-contained file.
//!
//! The work is done in a copy of `web/` under `$OUT_DIR` (`npm ci`, then esbuild), so
//! the source tree is not written. Without Node and npm, or offline with an empty npm
//! cache, the build goes on with an empty bundle and a warning: the report then says
//! that this build has no 3D view. `PKM_VIEW3D_BUNDLE=FILE` takes a prebuilt bundle.

use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let manifest = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets it"));
    let web = manifest.join("../../web");
    let out = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets it"));
    let bundle = out.join("view3d.js");
    for f in ["package.json", "package-lock.json", "src/view3d.js"] {
        println!("cargo:rerun-if-changed={}", web.join(f).display());
    }
    println!("cargo:rerun-if-env-changed=PKM_VIEW3D_BUNDLE");
    println!("cargo:rustc-env=PKM_VIEW3D={}", bundle.display());
    if let Ok(prebuilt) = std::env::var("PKM_VIEW3D_BUNDLE") {
        std::fs::copy(&prebuilt, &bundle)
            .unwrap_or_else(|e| panic!("PKM_VIEW3D_BUNDLE={prebuilt}: {e}"));
        return;
    }
    if let Err(why) = build(&web, &out.join("web"), &bundle) {
        println!(
            "cargo:warning=the report's 3D view is not built ({why}); pkm report will say so. \
             It needs Node and npm and, once, the npm registry."
        );
        std::fs::write(&bundle, "").expect("OUT_DIR is writable");
    }
}

fn build(web: &Path, work: &Path, bundle: &Path) -> Result<(), String> {
    std::fs::create_dir_all(work.join("src")).map_err(|e| e.to_string())?;
    for f in ["package.json", "package-lock.json", "src/view3d.js"] {
        let (from, to) = (web.join(f), work.join(f));
        // Copy only what changed, so an unchanged lockfile keeps node_modules.
        let same = std::fs::read(&from).ok() == std::fs::read(&to).ok();
        if !same {
            std::fs::copy(&from, &to).map_err(|e| format!("{}: {e}", from.display()))?;
        }
    }
    let npm = if cfg!(windows) { "npm.cmd" } else { "npm" };
    if !work.join("node_modules/three/package.json").exists()
        || !work.join("node_modules/.bin/esbuild").exists()
    {
        run(
            Command::new(npm)
                .args(["ci", "--no-audit", "--no-fund", "--loglevel=error"])
                .current_dir(work),
            "npm ci",
        )?;
    }
    run(
        Command::new(npm)
            .args(["run", "--silent", "build"])
            .current_dir(work),
        "npm run build",
    )?;
    std::fs::copy(work.join("dist/view3d.js"), bundle).map_err(|e| e.to_string())?;
    Ok(())
}

fn run(c: &mut Command, what: &str) -> Result<(), String> {
    match c.output() {
        Ok(o) if o.status.success() => Ok(()),
        Ok(o) => Err(format!(
            "{what} failed: {}",
            String::from_utf8_lossy(&o.stderr)
                .lines()
                .filter(|l| !l.contains("nodedir"))
                .take(3)
                .collect::<Vec<_>>()
                .join(" / ")
        )),
        Err(e) => Err(format!("{what}: {e}")),
    }
}
