//! The `[report]` table of a machine file, for every machine type: what `pkm report`
//! shows for this machine by default, and the published results its sections are
//! compared with (a seed's machine carries its paper's study and figures here, not
//! in code).
//!
//! ```toml
//! [report]
//! sections = ["workspace", "motion"]   # default: every section the machine has
//! pose = [0.0, 0.0, -290.0, 0, 0, 0]   # drawing and accuracy pose (mm, deg); default home
//! bounds = [-150, 150, -150, 150, -400, -150]   # workspace grid; default: the whole reach
//! step = 5.0                           # workspace grid step (mm or deg)
//! gcode = "../paths/seed000-arc.ngc"   # motion path, relative to this file
//! from = [32.0, -32.0, -290.0]         # where the program starts (default home)
//! feeds = [10, 100, 1000, 10000]       # mm/min: the program run at each (default: its own F)
//! points = 101                         # samples per run (default: every 1 ms)
//!
//! [[report.comparison]]
//! section = "motion"
//! source = "seed 000, section 4"
//! text = "Seed 000 reports ..."
//! ```

use serde::{Deserialize, Serialize};

use super::source::{Seg, Source};
use crate::error::Result;

/// The report's section anchors, in order ([`ReportSettings::sections`] names them).
pub const REPORT_SECTIONS: &[&str] = &[
    "machine",
    "drawing",
    "view3d",
    "checks",
    "workspace",
    "motion",
    "seed004",
    "accuracy",
    "stiffness",
    "clearance",
    "calibration",
    "references",
];

/// A published result shown beside a section of the report.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Comparison {
    /// The section it belongs to (an anchor of [`REPORT_SECTIONS`]).
    pub section: String,
    /// Where it is published.
    pub source: String,
    /// What the source reports.
    pub text: String,
}

/// The `[report]` table: defaults of `pkm report` for this machine (user units: mm,
/// deg, mm/min). Command-line options override them.
#[derive(Debug, Clone, PartialEq, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ReportSettings {
    /// Sections to show (anchors of [`REPORT_SECTIONS`]); `None`: every one the
    /// machine has.
    #[serde(default)]
    pub sections: Option<Vec<String>>,
    /// The pose of the drawing and the accuracy analysis; `None`: home.
    #[serde(default)]
    pub pose: Option<Vec<f64>>,
    /// Workspace grid bounds, min,max per axis; `None`: the machine's whole reach.
    #[serde(default)]
    pub bounds: Option<Vec<f64>>,
    /// Workspace grid step.
    #[serde(default)]
    pub step: Option<f64>,
    /// The motion section's G-code program, relative to the machine file
    /// ([`crate::Machine::resolve`]); `None`: a circle in the workspace.
    #[serde(default)]
    pub gcode: Option<String>,
    /// Where the program starts (pose coordinates); `None`: home.
    #[serde(default)]
    pub from: Option<Vec<f64>>,
    /// Feeds (mm/min) the program is run at, each replacing its F words; empty: the
    /// program's own feeds.
    #[serde(default)]
    pub feeds: Vec<f64>,
    /// Samples per run; `None`: one every millisecond.
    #[serde(default)]
    pub points: Option<usize>,
    /// Published results shown beside the sections.
    #[serde(default, rename = "comparison")]
    pub comparisons: Vec<Comparison>,
}

#[derive(Deserialize)]
struct ReportOnly {
    #[serde(default)]
    report: Option<ReportSettings>,
}

/// The file's `[report]` table, checked: known sections, finite values, feeds and a
/// step > 0, bounds as min < max pairs, at most 10^7 points.
pub(crate) fn report_settings(src: &Source) -> Result<ReportSettings> {
    let f: ReportOnly = src.deserialize()?;
    let r = f.report.unwrap_or_default();
    if let Some(s) = &r.sections {
        for (i, name) in s.iter().enumerate() {
            if !REPORT_SECTIONS.contains(&name.as_str()) {
                let mut p = at("sections");
                p.push(Seg::Index(i));
                return Err(src.error(
                    &p,
                    format!(
                        "unknown section `{name}`, expected one of: {}",
                        REPORT_SECTIONS.join(", ")
                    ),
                ));
            }
        }
    }
    check_numbers(src, &r)?;
    for (i, c) in r.comparisons.iter().enumerate() {
        if !REPORT_SECTIONS.contains(&c.section.as_str()) {
            return Err(src.error(
                &[
                    Seg::Key("report".into()),
                    Seg::Key("comparison".into()),
                    Seg::Index(i),
                    Seg::Key("section".into()),
                ],
                format!(
                    "unknown section `{}`, expected one of: {}",
                    c.section,
                    REPORT_SECTIONS.join(", ")
                ),
            ));
        }
    }
    Ok(r)
}

/// The path of field `k` of `[report]`.
fn at(k: &str) -> Vec<Seg> {
    vec![Seg::Key("report".into()), Seg::Key(k.into())]
}

/// Checks the numbers of `[report]`: finite, bounds as min < max pairs, feeds and a
/// step > 0, 2 to 10^7 points.
fn check_numbers(src: &Source, r: &ReportSettings) -> Result<()> {
    for (k, v) in [("pose", &r.pose), ("bounds", &r.bounds), ("from", &r.from)] {
        if let Some(v) = v {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                let mut p = at(k);
                p.push(Seg::Index(i));
                return Err(src.error(&p, "expected a finite number"));
            }
        }
    }
    if let Some(b) = &r.bounds {
        if b.len() % 2 != 0 || b.is_empty() || b.chunks(2).any(|c| c[0] >= c[1]) {
            return Err(src.error(
                &at("bounds"),
                format!("expected min, max pairs with min < max, found {b:?}"),
            ));
        }
    }
    if let Some(s) = r.step.filter(|s| !(*s > 0.0 && s.is_finite())) {
        return Err(src.error(&at("step"), format!("expected a step > 0, found {s}")));
    }
    if let Some(i) = r.feeds.iter().position(|f| !(*f > 0.0 && f.is_finite())) {
        let mut p = at("feeds");
        p.push(Seg::Index(i));
        return Err(src.error(
            &p,
            format!("expected a feed > 0 mm/min, found {}", r.feeds[i]),
        ));
    }
    if let Some(n) = r.points.filter(|n| !(2..=10_000_000).contains(n)) {
        return Err(src.error(
            &at("points"),
            format!("expected 2 to 10^7 samples, found {n}"),
        ));
    }
    Ok(())
}
