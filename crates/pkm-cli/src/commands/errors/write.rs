//! The files `pkm errors --out DIR` writes beside `errors.json`: the clearance
//! surface, the series along a path, the budget, the Monte Carlo histogram and the
//! error map, each as a table and a plot.

use anyhow::Result;
use serde_json::json;

use crate::io::write_atomic;
use crate::report::plot::{bars_svg, histogram_svg};

/// DIR/surface.csv (`z_mm,lower_mm,upper_mm`; empty bounds where the tool cannot be
/// placed) and DIR/surface.svg (the bounds against z, seed 002's Fig. 4).
pub(super) fn write_surface(
    out: &std::path::Path,
    sf: &pkm::analysis::clearance::SurfaceReport,
    inputs: &[&std::path::Path],
) -> Result<()> {
    use crate::report::plot::{panels_svg_span, Series};
    let mut csv = String::from("z_mm,lower_mm,upper_mm\n");
    for p in &sf.points {
        match (p.lower, p.upper) {
            (Some(l), Some(u)) => csv.push_str(&format!("{:.6},{l:.9},{u:.9}\n", p.z)),
            _ => csv.push_str(&format!("{:.6},,\n", p.z)),
        }
    }
    write_atomic(&out.join("surface.csv"), csv.as_bytes(), inputs)?;
    let series =
        |name: &str, pick: fn(&pkm::accuracy::clearance::surface::SurfacePoint) -> Option<f64>| {
            Series {
                name: name.into(),
                points: sf
                    .points
                    .iter()
                    .filter_map(|p| pick(p).map(|v| (p.z, 1000.0 * v)))
                    .collect(),
            }
        };
    let svg = panels_svg_span(
        &format!(
            "shaping error from joint clearances over a hemisphere R = {} mm{}",
            sf.hemisphere.radius,
            if sf.unreachable > 0 {
                format!(
                    " ({} of {} heights unreachable)",
                    sf.unreachable,
                    sf.points.len()
                )
            } else {
                String::new()
            }
        ),
        "z [mm]",
        // The whole meridian, equator to pole: heights out of reach stay empty.
        Some((0.0, sf.hemisphere.radius)),
        &[(
            "bounds along the surface normal".into(),
            "error [µm]".into(),
            vec![series("upper", |p| p.upper), series("lower", |p| p.lower)],
        )],
        (760, 420),
    )?;
    write_atomic(&out.join("surface.svg"), svg.as_bytes(), inputs)
}

/// DIR/clearance-series.csv (`clearance_mm,lower_mm,upper_mm`) and .svg: the bounds
/// against the clearance (seed 002's Fig. 5).
pub(super) fn write_series(
    out: &std::path::Path,
    series: &[pkm::analysis::clearance::SeriesPoint],
    inputs: &[&std::path::Path],
) -> Result<()> {
    use crate::report::plot::{panels_svg_x, Series};
    let mut csv = String::from("clearance_mm,lower_mm,upper_mm\n");
    for p in series {
        csv.push_str(&format!(
            "{:.6},{:.9},{:.9}\n",
            p.clearance_mm, p.lower, p.upper
        ));
    }
    write_atomic(&out.join("clearance-series.csv"), csv.as_bytes(), inputs)?;
    let line = |name: &str, pick: fn(&pkm::analysis::clearance::SeriesPoint) -> f64| Series {
        name: name.into(),
        points: series
            .iter()
            .map(|p| (p.clearance_mm, 1000.0 * pick(p)))
            .collect(),
    };
    let svg = panels_svg_x(
        "bounds of the error from joint clearances against the clearance",
        "diametral clearance [mm]",
        &[(
            "bounds along the direction at the pose".into(),
            "error [µm]".into(),
            vec![line("upper", |p| p.upper), line("lower", |p| p.lower)],
        )],
        (760, 420),
    )?;
    write_atomic(&out.join("clearance-series.svg"), svg.as_bytes(), inputs)
}

/// DIR/clearance-path.csv: per bounded sample `t_s,line`, the pose coordinates (user
/// units), `lower_mm,upper_mm`.
pub(super) fn write_path(
    out: &std::path::Path,
    m: &dyn pkm::DynMechanism,
    p: &pkm::analysis::clearance_path::PathReport,
    inputs: &[&std::path::Path],
) -> Result<()> {
    let mut csv = String::from("t_s,line");
    for c in m.coordinates() {
        csv.push_str(&format!(",{}_{}", c.name, c.quantity.unit()));
    }
    csv.push_str(",lower_mm,upper_mm\n");
    for pt in &p.points {
        csv.push_str(&format!(
            "{:.6},{}",
            pt.sample.t,
            pt.sample.line.map(|l| l.to_string()).unwrap_or_default()
        ));
        for (c, v) in m.coordinates().iter().zip(&pt.sample.x) {
            csv.push_str(&format!(",{:.6}", c.quantity.to_user(*v)));
        }
        csv.push_str(&format!(",{:.9},{:.9}\n", pt.lower, pt.upper));
    }
    write_atomic(&out.join("clearance-path.csv"), csv.as_bytes(), inputs)
}

/// The budget's largest 25 lines as a bar chart, DIR/budget.svg.
pub(super) fn write_budget(
    out: &std::path::Path,
    b: &pkm::accuracy::Budget,
    inputs: &[&std::path::Path],
) -> Result<()> {
    let top: Vec<(String, f64)> = b
        .items
        .iter()
        .take(25)
        .map(|i| (i.name.clone(), 1000.0 * i.position))
        .collect();
    let svg = bars_svg(
        &format!(
            "error budget: tool-point error at each tolerance (worst case {:.2} µm, RSS {:.2} µm)",
            1000.0 * b.worst_case,
            1000.0 * b.rss
        ),
        "contribution [µm]",
        &top,
        760,
    )?;
    write_atomic(&out.join("budget.svg"), svg.as_bytes(), inputs)
}

/// The Monte Carlo histogram, DIR/monte-carlo.svg, and the JSON of its statistics.
pub(super) fn write_monte_carlo(
    out: &std::path::Path,
    mc: &pkm::accuracy::MonteCarlo,
    seed: u64,
    inputs: &[&std::path::Path],
) -> Result<serde_json::Value> {
    let bins: Vec<(f64, usize)> = mc.histogram.iter().map(|(x, c)| (1000.0 * x, *c)).collect();
    let svg = histogram_svg(
        &format!(
            "Monte Carlo, {} machines: tool-point error (mean {:.2} µm, p95 {:.2} µm)",
            mc.samples,
            1000.0 * mc.mean,
            1000.0 * mc.p95
        ),
        "|error| [µm]",
        &bins,
        (640, 400),
    )?;
    write_atomic(&out.join("monte-carlo.svg"), svg.as_bytes(), inputs)?;
    Ok(json!({
        "samples": mc.samples, "failed": mc.failed, "seed": seed,
        "mean": mc.mean, "std": mc.std, "p95": mc.p95, "p99": mc.p99, "max": mc.max,
        "mean_vector": mc.mean_vector, "std_vector": mc.std_vector,
    }))
}

/// DIR/error-map.csv and DIR/error-map.svg, and the JSON summary of the map.
pub(super) fn write_map(
    out: &std::path::Path,
    m: &dyn pkm::DynMechanism,
    base: &[f64],
    em: &pkm::accuracy::ErrorMap,
    inputs: &[&std::path::Path],
) -> Result<serde_json::Value> {
    let c = |k: usize| &m.coordinates()[em.axes[k].coordinate];
    let mut csv = format!(
        "{}_{},{}_{},rss_mm,worst_case_mm\n",
        c(0).name,
        c(0).quantity.unit(),
        c(1).name,
        c(1).quantity.unit()
    );
    for cell in &em.cells {
        let (u0, u1) = (
            c(0).quantity.to_user(cell.at[0]),
            c(1).quantity.to_user(cell.at[1]),
        );
        match cell.budget {
            Some([rss, worst]) => csv.push_str(&format!("{u0:.6},{u1:.6},{rss:.9},{worst:.9}\n")),
            None => csv.push_str(&format!("{u0:.6},{u1:.6},,\n")),
        }
    }
    write_atomic(&out.join("error-map.csv"), csv.as_bytes(), inputs)?;
    let coord = |k: usize| {
        (
            m.coordinates()[em.axes[k].coordinate].name.clone(),
            m.coordinates()[em.axes[k].coordinate].quantity,
        )
    };
    let value = |flat: usize| em.cells[flat].budget.map(|b| 1e3 * b[0]);
    let svg = crate::commands::workspace::slice_plot(
        &em.axes,
        base,
        &coord,
        (0, 1),
        "first-order RSS of the tolerances",
        crate::report::heatmap::Scale::Linear("RSS [µm]"),
        &value,
    )?;
    write_atomic(&out.join("error-map.svg"), svg.as_bytes(), inputs)?;
    Ok(json!({
        "axes": [c(0).name.clone(), c(1).name.clone()],
        "points": em.cells.len(),
        "unreachable": em.unreachable,
        "max_rss": em.max_rss,
        "file": "error-map.csv",
    }))
}
