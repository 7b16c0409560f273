//! `pkm report`: a self-contained HTML report (inline SVG, no network needed) of any
//! machine file. Each section is computed on its own: one that fails shows its error
//! in its place and the others are written.

mod accuracy;
mod calibration;
mod clearance;
mod context;
mod drawing;
pub mod heatmap;
mod html;
mod machine;
mod motion;
mod p3rp;
pub mod plot;
mod references;
mod stiffness;
pub mod ticks;
mod view3d;
mod workspace;

use anyhow::{bail, Context as _, Result};
use clap::Args;
use pkm::machine::REPORT_SECTIONS;
use pkm::Machine;
use std::path::PathBuf;

use crate::io::write_atomic;
use crate::out::outln;
pub use context::Context;
use html::{esc, Html};

#[derive(Args)]
pub struct ReportArgs {
    /// Machine file (TOML or URDF); default: the bundled seed-000 tripod.
    pub machine: Option<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "pkm-report")]
    pub out: PathBuf,
    /// The motion section's G-code program (default: the machine file's `[report]
    /// gcode`, else a circle scaled to the machine's reach).
    #[arg(long)]
    pub gcode: Option<PathBuf>,
    /// Where the program starts, pose coordinates (mm, deg); default: the machine
    /// file's `[report] from`, else home.
    #[arg(long, allow_hyphen_values = true)]
    pub from: Option<String>,
    /// Feeds (mm/min, comma separated) the path is run at, each replacing the
    /// program's F words.
    #[arg(long)]
    pub feeds: Option<String>,
    /// The pose of the drawing, the workspace map's orientation, the motion circle's
    /// centre and the accuracy analysis (mm, deg); default: the machine file's
    /// `[report] pose`, else home.
    #[arg(long, allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// Workspace grid bounds, min,max per axis (default: the machine's whole reach).
    #[arg(long, allow_hyphen_values = true)]
    pub bounds: Option<String>,
    /// Workspace grid step (mm or deg; default 1/40 of each range).
    #[arg(long)]
    pub step: Option<f64>,
    /// Sections to write, comma separated (machine, drawing, checks, workspace, motion,
    /// seed004, accuracy, stiffness, clearance, calibration, references); default: every one the
    /// machine has.
    #[arg(long)]
    pub sections: Option<String>,
    /// Print where the report went and its sections as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The bundled default machine: seed 000's tripod.
pub const DEFAULT_MACHINE: &str = include_str!("../../../../examples/machines/tripod-seed000.toml");
/// Name under which the bundled machine appears in messages.
pub const DEFAULT_MACHINE_NAME: &str = "examples/machines/tripod-seed000.toml (bundled)";
/// Exit code of a report written with sections that could not be computed.
pub const EXIT_PARTIAL: u8 = 4;

/// One section of the report.
struct Section {
    /// Anchor (one of [`REPORT_SECTIONS`]).
    id: &'static str,
    /// Title in the navigation.
    title: &'static str,
    /// Whether the machine has it.
    shown: fn(&Machine) -> bool,
    /// Writes it.
    render: fn(&mut Html, &Machine, &Context) -> Result<()>,
}

/// The report's sections, in order.
const SECTIONS: &[Section] = &[
    Section {
        id: "machine",
        title: "Machine",
        shown: |_| true,
        render: machine::summary,
    },
    Section {
        id: "drawing",
        title: "Drawing",
        shown: |_| true,
        render: machine::drawing_section,
    },
    Section {
        id: "view3d",
        title: "3D view",
        shown: |_| true,
        render: view3d::section,
    },
    Section {
        id: "checks",
        title: "Kinematic checks",
        shown: |_| true,
        render: machine::checks,
    },
    Section {
        id: "workspace",
        title: "Workspace",
        shown: |_| true,
        render: workspace::section,
    },
    Section {
        id: "motion",
        title: "Motion",
        shown: |m| m.mechanism().pose_space() != pkm::PoseSpace::Own,
        render: motion::section,
    },
    Section {
        id: "seed004",
        title: "Seed 004",
        shown: |m| m.supports(pkm::machine::Analysis::Seed004).is_ok(),
        render: p3rp::section,
    },
    Section {
        id: "accuracy",
        title: "Accuracy",
        shown: |_| true,
        render: accuracy::section,
    },
    Section {
        id: "stiffness",
        title: "Stiffness",
        shown: stiffness::shown,
        render: stiffness::section,
    },
    Section {
        id: "clearance",
        title: "Clearances",
        shown: |m| !m.clearances.is_empty(),
        render: clearance::section,
    },
    Section {
        id: "calibration",
        title: "Calibration",
        shown: |m| m.supports(pkm::machine::Analysis::Identification).is_ok(),
        render: calibration::section,
    },
    Section {
        id: "references",
        title: "Reproduced references",
        shown: |m| !m.references.is_empty(),
        render: references::section,
    },
];

/// The sections asked for (`--sections`, else the file's `[report] sections`, else
/// all) that `machine` has, in report order; and the ones asked for that it has not.
fn chosen(machine: &Machine, asked: Option<&[String]>) -> (Vec<&'static Section>, Vec<String>) {
    let mut missing = Vec::new();
    if let Some(a) = asked {
        for id in a {
            if !SECTIONS.iter().any(|s| s.id == id && (s.shown)(machine)) {
                missing.push(id.clone());
            }
        }
    }
    let v = SECTIONS
        .iter()
        .filter(|s| (s.shown)(machine))
        .filter(|s| asked.is_none_or(|a| a.iter().any(|x| x == s.id)))
        .collect();
    (v, missing)
}

/// A written report: the page and the sections that could not be computed.
pub struct Built {
    /// The HTML document.
    pub html: String,
    /// The sections shown.
    pub sections: Vec<&'static str>,
    /// `(section, error)` of each section that failed.
    pub failed: Vec<(&'static str, String)>,
    /// Sections asked for that this machine has not.
    pub missing: Vec<String>,
}

/// The whole report as one HTML document; `asked` the sections wanted (`None`: the
/// file's, else all); `progress` is told each section's title as it starts.
pub fn build(
    machine: &Machine,
    ctx: &Context,
    asked: Option<&[String]>,
    progress: &dyn Fn(&str),
) -> Built {
    let m = machine.mechanism();
    let asked = asked.or(machine.report.sections.as_deref());
    let (shown, missing) = chosen(machine, asked);
    let mut h = Html::new(&format!("pkm report: {}", m.name()));
    head(&mut h, machine, &shown, &missing);
    let mut failed = Vec::new();
    for s in &shown {
        progress(s.title);
        if let Err(msg) = render(&mut h, s, machine, ctx) {
            failed.push((s.id, msg));
        }
        for c in ctx.comparisons.iter().filter(|c| c.section == s.id) {
            h.raw(&format!(
                "<blockquote class=\"published\"><b>Published ({}):</b> {}</blockquote>",
                esc(&c.source),
                esc(&c.text)
            ));
        }
    }
    let mut html = h.finish();
    if html.contains(view3d::PLACEHOLDER) {
        let view = view3d::html(machine, ctx).unwrap_or_else(|e| {
            let msg = format!("{e:#}");
            failed.push(("view3d", msg.clone()));
            format!(
                "<p><span class=\"bad\">This section could not be computed for this machine: {}</span></p>",
                esc(&msg)
            )
        });
        html = html.replacen(view3d::PLACEHOLDER, &view, 1);
    }
    if !failed.is_empty() {
        let note = format!(
            "<p><span class=\"bad\">Sections that could not be computed: {}.</span></p>\n</body>",
            esc(&failed.iter().map(|f| f.0).collect::<Vec<_>>().join(", "))
        );
        html = html.replacen("</body>", &note, 1);
    }
    Built {
        html,
        sections: shown.iter().map(|s| s.id).collect(),
        failed,
        missing,
    }
}

/// The report's title, what made it, the machine's description and the navigation.
fn head(h: &mut Html, machine: &Machine, shown: &[&Section], missing: &[String]) {
    let m = machine.mechanism();
    h.h1(&format!("pkm report: {}", m.name()));
    h.p(&format!(
        "Machine file <code>{}</code>, type <code>{}</code>. Generated by pkm {}. \
         Units: mm and degrees.",
        esc(&machine.source),
        m.kind(),
        env!("CARGO_PKG_VERSION")
    ));
    if let Some(d) = &machine.description {
        h.p(&esc(d));
    }
    let nav: Vec<String> = shown
        .iter()
        .map(|s| format!("<a href=\"#{}\">{}</a>", s.id, s.title))
        .collect();
    h.raw(&format!("<nav>{}</nav>", nav.join(" · ")));
    if !missing.is_empty() {
        h.p(&format!(
            "Sections asked for that this machine has not: {}.",
            esc(&missing.join(", "))
        ));
    }
}

/// Section `s`, or in its place the error it gave (returned).
fn render(h: &mut Html, s: &Section, machine: &Machine, ctx: &Context) -> Result<(), String> {
    let mut part = Html::new("");
    match (s.render)(&mut part, machine, ctx) {
        Ok(()) => {
            h.raw(&part.body());
            Ok(())
        }
        Err(e) => {
            let msg = format!("{e:#}");
            h.h2_id(s.id, s.title);
            h.p(&format!(
                "<span class=\"bad\">This section could not be computed for this machine: {}</span>",
                esc(&msg)
            ));
            Err(msg)
        }
    }
}

pub fn run(a: &ReportArgs) -> Result<u8> {
    let machine = match &a.machine {
        Some(p) => Machine::from_path(p)?,
        None => Machine::from_toml_str(DEFAULT_MACHINE, DEFAULT_MACHINE_NAME)?,
    };
    let asked = match &a.sections {
        Some(s) => Some(sections(s)?),
        None => None,
    };
    let ctx = Context::new(a, &machine, a.machine.is_none())?;
    let built = build_with_progress(&machine, &ctx, asked.as_deref());
    let path = a.out.join("index.html");
    let inputs: Vec<&std::path::Path> = a
        .machine
        .iter()
        .map(|p| p.as_path())
        .chain(a.gcode.as_deref())
        .collect();
    write_atomic(&path, built.html.as_bytes(), &inputs)
        .with_context(|| format!("writing the report to {}", path.display()))?;
    if a.json {
        let v = serde_json::json!({
            "machine": machine.source,
            "report": path.display().to_string(),
            "bytes": built.html.len(),
            "sections": built.sections,
            "failed": built.failed.iter().map(|(s, e)| serde_json::json!({"section": s, "error": e})).collect::<Vec<_>>(),
            "missing": built.missing,
        });
        outln!("{}", serde_json::to_string_pretty(&v)?)?;
    }
    Ok(outcome(&built, &path))
}

/// `--sections`: the names, each one of [`REPORT_SECTIONS`].
fn sections(s: &str) -> Result<Vec<String>> {
    let v: Vec<String> = s
        .split(',')
        .map(|x| x.trim().to_string())
        .filter(|x| !x.is_empty())
        .collect();
    if let Some(x) = v.iter().find(|x| !REPORT_SECTIONS.contains(&x.as_str())) {
        bail!(
            "--sections: unknown section `{x}`, expected some of: {}",
            REPORT_SECTIONS.join(", ")
        );
    }
    Ok(v)
}

/// [`build`] with a progress bar over the sections.
fn build_with_progress(machine: &Machine, ctx: &Context, asked: Option<&[String]>) -> Built {
    let total = chosen(machine, asked.or(machine.report.sections.as_deref()))
        .0
        .len();
    let bar = crate::progress::bar(total as u64, 0, "{bar:30} {pos}/{len} {msg} {elapsed}");
    if let Some(b) = &bar {
        b.enable_steady_tick(std::time::Duration::from_millis(100));
    }
    let tick = |title: &str| {
        if let Some(b) = &bar {
            if !b.message().is_empty() {
                b.inc(1);
            }
            b.set_message(title.to_string());
        }
    };
    let built = build(machine, ctx, asked, &tick);
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    built
}

/// Says on stderr what was written and what could not be: the exit code.
fn outcome(built: &Built, path: &std::path::Path) -> u8 {
    for m in &built.missing {
        eprintln!("warning: this machine has no `{m}` section");
    }
    eprintln!("wrote {}", path.display());
    if built.failed.is_empty() {
        return 0;
    }
    for (s, e) in &built.failed {
        eprintln!("error: section `{s}` could not be computed: {e}");
    }
    eprintln!(
        "the report was written without {} of its {} sections (exit code {EXIT_PARTIAL})",
        built.failed.len(),
        built.sections.len()
    );
    EXIT_PARTIAL
}

/// Four significant digits, for values spanning several decades (feeds 10 to 10 000).
fn sig(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.digits$}")
}

fn mark(ok: bool) -> &'static str {
    if ok {
        "<span class=\"ok\">✔</span>"
    } else {
        "<span class=\"bad\">✘</span>"
    }
}
