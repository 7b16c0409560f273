//! What the report's sections are computed with: the command line over the machine
//! file's `[report]` table over the defaults.

use anyhow::{bail, Context as _, Result};
use pkm::machine::Comparison;
use pkm::{Convention, Machine};

use super::{view3d, ReportArgs};
use crate::poses::{parse_list, pose_from_user};

/// The bundled machine's `[report]` program (its file names it relative to itself).
const DEFAULT_PROGRAM: (&str, &str) = (
    "../paths/seed000-arc.ngc",
    include_str!("../../../../examples/paths/seed000-arc.ngc"),
);

/// A G-code program: its name for the text and its contents.
pub struct Program {
    pub name: String,
    pub text: String,
}

/// What the sections are computed with: the command line over the machine file's
/// `[report]` table over the defaults (internal units).
pub struct Context {
    /// Pose of the drawing, the map's orientation, the circle's centre, the accuracy.
    pub pose: Vec<f64>,
    /// How the text names it (`home`, `the pose X... Y...`).
    pub pose_label: String,
    /// Workspace grid bounds (user units).
    pub bounds: Option<Vec<f64>>,
    /// Workspace grid step (user units).
    pub step: Option<f64>,
    /// The motion section's program.
    pub program: Option<Program>,
    /// Where it starts.
    pub from: Option<Vec<f64>>,
    /// Feeds (mm/min).
    pub feeds: Vec<f64>,
    /// Samples per move.
    pub points: Option<usize>,
    /// Published results shown beside the sections.
    pub comparisons: Vec<Comparison>,
    /// What the workspace and motion sections leave for the 3D view.
    pub scene: std::cell::RefCell<view3d::Scene>,
}

impl Context {
    /// The settings of `a` over `machine`'s `[report]` table.
    pub fn new(a: &ReportArgs, machine: &Machine, bundled: bool) -> Result<Context> {
        let m = machine.mechanism();
        let r = &machine.report;
        let user_pose = |v: &[f64]| pose_from_user(m, v, Convention::Rpy);
        let (pose, pose_label) = match (&a.pose, &r.pose) {
            (Some(s), _) => {
                let v = parse_list(s, "--pose")?;
                (user_pose(&v)?, format!("the pose {}", v_text(&v)))
            }
            (None, Some(v)) => (
                user_pose(v).context("the machine file's [report] pose")?,
                format!("the pose {}", v_text(v)),
            ),
            (None, None) => (m.home(), "home".to_string()),
        };
        let bounds = match &a.bounds {
            Some(b) => Some(parse_list(b, "--bounds")?),
            None => r.bounds.clone(),
        };
        // The file's start, feeds and sampling belong to the file's program: a program
        // from the command line runs from home at its own feeds unless told otherwise.
        let own_program = a.gcode.is_some();
        let from = match (&a.from, &r.from) {
            (Some(s), _) => Some(user_pose(&parse_list(s, "--from")?)?),
            (None, Some(v)) if !own_program => {
                Some(user_pose(v).context("the machine file's [report] from")?)
            }
            _ => None,
        };
        let feeds = match &a.feeds {
            Some(f) => feeds(f)?,
            None if own_program => Vec::new(),
            None => r.feeds.clone(),
        };
        Ok(Context {
            pose,
            pose_label,
            bounds,
            step: a.step.or(r.step),
            program: program(a, machine, bundled)?,
            from,
            feeds,
            points: if own_program { None } else { r.points },
            comparisons: r.comparisons.clone(),
            scene: Default::default(),
        })
    }
}

/// `--feeds`: feeds > 0 mm/min.
fn feeds(f: &str) -> Result<Vec<f64>> {
    let v = parse_list(f, "--feeds")?;
    if let Some(x) = v.iter().find(|x| !(**x > 0.0 && x.is_finite())) {
        bail!("--feeds: expected feeds > 0 mm/min, found {x}");
    }
    Ok(v)
}

/// The motion section's program: `--gcode`, else the machine file's `[report] gcode`
/// (the bundled machine's own when its file is not beside it).
fn program(a: &ReportArgs, machine: &Machine, bundled: bool) -> Result<Option<Program>> {
    Ok(match (&a.gcode, &machine.report.gcode) {
        (Some(p), _) => Some(Program {
            name: p.display().to_string(),
            text: std::fs::read_to_string(p)
                .with_context(|| format!("cannot read the program {}", p.display()))?,
        }),
        (None, Some(p)) => {
            let path = machine.resolve(p);
            let text = match std::fs::read_to_string(&path) {
                Ok(t) => t,
                Err(_) if bundled && p == DEFAULT_PROGRAM.0 => DEFAULT_PROGRAM.1.to_string(),
                Err(e) => bail!(
                    "cannot read {} (the machine file's [report] gcode): {e}",
                    path.display()
                ),
            };
            Some(Program {
                name: p.clone(),
                text,
            })
        }
        (None, None) => None,
    })
}

fn v_text(v: &[f64]) -> String {
    v.iter()
        .map(|x| format!("{x}"))
        .collect::<Vec<_>>()
        .join(", ")
}
