//! The report's 3D view in a real browser: headless Chromium loads
//! the report of a user's own hexapod offline, with the page's self-test
//! (`index.html#selftest`): no script or console error, the scene holds the machine's
//! joints and links, the workspace cloud and the animated path, the canvas is not
//! blank; a screenshot of the page is taken and is not blank either.
//!
//! `.ci/run` installs Chromium from Debian's packages and sets `PKM_BROWSER_TESTS=1`,
//! which makes a missing browser a failure; elsewhere the test says it was skipped.
//! `PKM_CHROMIUM` names another browser binary.

use crate::common::{path, pkm};
use serde_json::Value;
use std::process::Command;

fn chromium() -> Option<String> {
    if let Ok(c) = std::env::var("PKM_CHROMIUM") {
        return Some(c);
    }
    ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|c| {
            Command::new(c)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .map(String::from)
}

/// Runs the browser headless on `url` with `extra` arguments, at most two minutes;
/// returns stdout and stderr.
fn browse(browser: &str, profile: &std::path::Path, url: &str, extra: &[&str]) -> (String, String) {
    let o = Command::new("timeout")
        .arg("120")
        .arg(browser)
        .args([
            "--headless=new",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-extensions",
            "--enable-logging=stderr",
            "--v=0",
            "--window-size=1280,2400",
            "--virtual-time-budget=8000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .args(extra)
        .arg(url)
        .output()
        .expect("runs the browser");
    assert!(
        o.status.success(),
        "the browser failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn the_3d_view_works_in_a_real_browser() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var("PKM_BROWSER_TESTS").is_err(),
            "PKM_BROWSER_TESTS is set but no Chromium was found"
        );
        eprintln!("skipped: no Chromium (set PKM_BROWSER_TESTS=1 to require it)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rep");
    let o = pkm()
        .args([
            "report",
            &path("tests/fixtures/own-hexapod.toml"),
            "--sections",
            "drawing,view3d,workspace,motion",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let page = out.join("index.html");
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        html.contains("id=\"pkm-view3d\""),
        "this build has no 3D view (npm missing when it was compiled?)"
    );
    assert!(
        !html.contains("<script src"),
        "no external scripts: the page opens offline"
    );
    let url = format!("file://{}", page.display());
    let (dom, log) = browse(
        &browser,
        &dir.path().join("profile"),
        &format!("{url}#selftest"),
        &["--dump-dom"],
    );
    let start = dom
        .find("<pre id=\"pkm-selftest\">")
        .expect("the self-test ran")
        + 23;
    let end = start + dom[start..].find("</pre>").unwrap();
    let json = dom[start..end]
        .replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    let t: Value = serde_json::from_str(&json).unwrap_or_else(|e| panic!("{e}: {json}"));
    assert_eq!(t["webgl"], true, "{t}");
    assert_eq!(t["errors"].as_array().unwrap().len(), 0, "page errors: {t}");
    // The browser's own log: no uncaught error, no console error from the page.
    for line in log.lines().filter(|l| l.contains(":CONSOLE")) {
        assert!(
            !line.contains("Uncaught") && !line.contains("Error"),
            "console: {line}"
        );
    }
    // 6 base and 6 platform joints, the platform centre and the tool; 6 struts, the
    // base and platform outlines (6 + 6) and the tool.
    let objects = &t["objects"];
    assert_eq!(objects["joints"], 14, "{t}");
    assert_eq!(objects["links"], 19, "{t}");
    assert!(objects["cloud"].as_u64().unwrap() > 1000, "{t}");
    assert!(objects["path"].as_u64().unwrap() > 10, "{t}");
    assert!(objects["frames"].as_u64().unwrap() > 10, "{t}");
    let names: Vec<&str> = t["names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n.as_str().unwrap())
        .collect();
    for n in [
        "joint A1",
        "joint B6",
        "joint tool",
        "strut A1-B6",
        "workspace",
        "path",
    ] {
        assert!(names.contains(&n), "{n}: {names:?}");
    }
    // Not blank: the canvas is drawn, in many colours (the cloud's ramp), and the
    // machine alone (cloud, path and axes hidden) covers part of it. Measured at this
    // window size: 5.2 % drawn in 287 colours, the machine alone 2.1 %; a blank canvas
    // is 0 % in one colour. The bounds are about half the measured shares.
    assert!(t["drawn"].as_f64().unwrap() > 0.025, "{t}");
    assert!(t["colours"].as_u64().unwrap() > 20, "{t}");
    assert!(t["machine_drawn"].as_f64().unwrap() > 0.01, "{t}");
    // The animation moved the machine to the middle of the path and shows its struts.
    assert!(t["readout"].as_str().unwrap().contains("L1 "), "{t}");
    // A screenshot of the whole page.
    let png = dir.path().join("page.png");
    browse(
        &browser,
        &dir.path().join("profile2"),
        &url,
        &[&format!("--screenshot={}", png.display())],
    );
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG"), "a PNG");
    // A blank 1280 x 2400 page compresses to a few kB.
    assert!(bytes.len() > 60_000, "{} bytes", bytes.len());
}
