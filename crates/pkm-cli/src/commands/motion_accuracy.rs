//! `pkm motion --accuracy`: the tolerances' error along the program, written as
//! `accuracy.csv` (one row per G-code line), `accuracy.svg` (the curves over time) and
//! the `accuracy` part of `summary.json`.

use std::path::Path;

use anyhow::{bail, Result};
use clap::Args;
use pkm::analysis::motion::{PathAccuracyRequest, PathAccuracyRun};
use pkm::Machine;
use serde_json::json;

use super::tolerance_args::ToleranceArgs;
use crate::io::write_atomic;
use crate::out::{outln, Printed};
use crate::report::plot::{panels_marked, Panel, Series};

/// Options of the accuracy along the program.
#[derive(Args, Debug, Clone)]
pub struct AccuracyArgs {
    /// Accuracy along the program: the tolerances' first-order error budget at every
    /// sample (tool tip relative to the part, and along the tool axis as the surface
    /// normal), per G-code line in accuracy.csv, and a Monte Carlo band of whole
    /// machines drawn from the tolerances. Tolerances: the machine file's, or the
    /// options below.
    #[arg(long)]
    pub accuracy: bool,
    #[command(flatten)]
    pub tol: ToleranceArgs,
    /// Machines of the Monte Carlo band (0: budget only).
    #[arg(long, default_value_t = PathAccuracyRequest::default().machines)]
    pub band_machines: usize,
    /// The band at every N-th sample.
    #[arg(long, default_value_t = PathAccuracyRequest::default().every)]
    pub band_every: usize,
    /// Seed of the band's machines.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl AccuracyArgs {
    /// The request, `None` without --accuracy (tolerance options without it are an
    /// error: they would be ignored).
    pub fn request(&self, machine: &Machine) -> Result<Option<PathAccuracyRequest>> {
        if !self.accuracy {
            if self.tol.given() {
                bail!("tolerance options need --accuracy");
            }
            return Ok(None);
        }
        Ok(Some(PathAccuracyRequest {
            tolerances: self.tol.tolerances(&machine.parameters())?,
            machines: self.band_machines,
            every: self.band_every,
            seed: self.seed,
        }))
    }
}

/// The `accuracy` part of summary.json (mm; the per-line rows are in accuracy.csv).
pub fn summary(r: &PathAccuracyRun) -> serde_json::Value {
    let p = &r.path;
    let at = |v: &(f64, f64, Option<u64>)| json!({"mm": v.0, "t_s": v.1, "line": v.2});
    json!({
        "tolerance_source": r.tolerance_source,
        "tolerances": p.tolerances,
        "samples": p.samples,
        "worst_case": at(&p.worst_case),
        "rss": at(&p.rss),
        "surface_worst_case": at(&p.surface_worst_case),
        "lines": p.segments.len() as u64 + p.segments_not_listed,
        "monte_carlo": p.monte_carlo,
    })
}

/// accuracy.csv: one row per G-code line (mm, s).
pub fn csv(r: &PathAccuracyRun) -> String {
    let mut s = String::from(
        "line,start_s,end_s,samples,worst_case_mm,rss_mm,surface_worst_case_mm,surface_rss_mm,\
         top_parameter,top_mm,band_min_mm,band_max_mm\n",
    );
    for g in &r.path.segments {
        let (lo, hi) = match g.band {
            Some((lo, hi)) => (format!("{lo:.6e}"), format!("{hi:.6e}")),
            None => (String::new(), String::new()),
        };
        s.push_str(&format!(
            "{},{:.6},{:.6},{},{:.6e},{:.6e},{:.6e},{:.6e},\"{}\",{:.6e},{lo},{hi}\n",
            g.line.map(|l| l.to_string()).unwrap_or_default(),
            g.start_s,
            g.end_s,
            g.samples,
            g.worst_case,
            g.rss,
            g.surface_worst_case,
            g.surface_rss,
            g.top.0.replace('"', "\"\""),
            g.top.1
        ));
    }
    s
}

/// accuracy.svg: worst case and RSS of the tool-tip error, and the surface error's
/// worst case with the Monte Carlo band, over time (um).
pub fn plot(r: &PathAccuracyRun, title: &str) -> Result<String> {
    let c = &r.path.curve;
    let um = 1000.0;
    let s = |name: &str, f: &dyn Fn(&pkm::accuracy::path::PathPoint) -> Option<f64>| Series {
        name: name.into(),
        points: c
            .iter()
            .filter_map(|p| f(p).map(|v| (p.t, v * um)))
            .collect(),
    };
    let tip = [
        s("worst case", &|p| Some(p.worst_case)),
        s("RSS", &|p| Some(p.rss)),
    ];
    let surface = [
        s("worst case", &|p| Some(p.surface_worst_case)),
        s("-worst case", &|p| Some(-p.surface_worst_case)),
        s("MC 95 %", &|p| p.band.map(|b| b[2])),
        s("MC 5 %", &|p| p.band.map(|b| b[0])),
        s("MC max", &|p| p.band.map(|b| b[4])),
        s("MC min", &|p| p.band.map(|b| b[3])),
    ];
    panels_marked(
        &format!("{title}: error along the program"),
        "t [s]",
        None,
        &[
            Panel {
                title: "tool tip relative to the part, first-order bounds",
                ylabel: "|e| [µm]",
                series: &tip,
                limits: Vec::new(),
            },
            Panel {
                title: "along the tool axis (the surface normal)",
                ylabel: "n·e [µm]",
                series: &surface,
                limits: Vec::new(),
            },
        ],
        &[],
        (1100, 700),
    )
}

/// Writes accuracy.csv and accuracy.svg.
pub fn write(out: &Path, r: &PathAccuracyRun, title: &str, inputs: &[&Path]) -> Result<()> {
    write_atomic(&out.join("accuracy.csv"), csv(r).as_bytes(), inputs)?;
    write_atomic(
        &out.join("accuracy.svg"),
        plot(r, title)?.as_bytes(),
        inputs,
    )?;
    Ok(())
}

/// The console lines.
pub fn print(r: &PathAccuracyRun) -> Printed {
    let p = &r.path;
    let line = |l: Option<u64>| l.map(|l| format!("line {l}")).unwrap_or("-".into());
    outln!(
        "accuracy along the program ({} tolerances {}; first order, tool tip relative to \
         the part or base):",
        p.tolerances,
        r.tolerance_source.describe()
    )?;
    for (what, v) in [
        ("worst case", &p.worst_case),
        ("RSS", &p.rss),
        ("along the tool axis, worst case", &p.surface_worst_case),
    ] {
        outln!(
            "  {what:<32} up to {:.2} um at t = {:.3} s ({})",
            v.0 * 1000.0,
            v.1,
            line(v.2)
        )?;
    }
    if let Some(mc) = &p.monte_carlo {
        outln!(
            "  Monte Carlo, {} machines at {} samples: largest error along the path per machine \
             median {:.2} um, 95 % {:.2} um, max {:.2} um; along the tool axis median {:.2} um, \
             95 % {:.2} um, max {:.2} um",
            mc.machines,
            mc.samples,
            mc.position_p50 * 1000.0,
            mc.position_p95 * 1000.0,
            mc.position_max * 1000.0,
            mc.surface_p50 * 1000.0,
            mc.surface_p95 * 1000.0,
            mc.surface_max * 1000.0
        )?;
    }
    let mut worst: Vec<_> = p.segments.iter().collect();
    worst.sort_by(|a, b| b.worst_case.total_cmp(&a.worst_case));
    for g in worst.into_iter().take(3) {
        outln!(
            "  {}: worst case {:.2} um, RSS {:.2} um, along the axis {:.2} um; largest share \
             {} ({:.2} um)",
            line(g.line),
            g.worst_case * 1000.0,
            g.rss * 1000.0,
            g.surface_worst_case * 1000.0,
            g.top.0,
            g.top.1 * 1000.0
        )?;
    }
    Ok(())
}
