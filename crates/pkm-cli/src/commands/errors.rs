//! `pkm errors`: the accuracy of a serial machine (seed 003) at one axis position — the
//! deviated tool pose, the sensitivity to every deviation, the error budget and the
//! Monte Carlo distribution of the tool-point error.

use anyhow::{bail, Context, Result};
use nalgebra::SVector;
use pkm::accuracy::GeometricTolerances;
use pkm::identify::Identifiable;
use pkm::machine::Model;
use pkm::serial::accuracy::Parameter;
use pkm::serial::tolerance::Distribution;
use pkm::serial::tolerance::{budget, deviations_from, monte_carlo, pose_error};
use serde_json::json;

use super::load;
use crate::io::write_atomic;
use crate::poses::parse_list;
use crate::report::plot::{bars_svg, histogram_svg};
use crate::ErrorsArgs;

pub fn run(a: &ErrorsArgs) -> Result<u8> {
    let machine = load(&a.machine)?;
    match &machine.model {
        Model::Hexapod(h) => {
            let z = h.zero_readings()?;
            return strut_errors(a, &machine, h.as_ref(), z);
        }
        Model::TranslationalTripod(t) => {
            let z = t.zero_readings()?;
            return strut_errors(a, &machine, t, z);
        }
        _ => {}
    }
    let Model::Serial(s) = &machine.model else {
        bail!(
            "{}: `pkm errors` needs a serial machine (seed 003's deviations), a hexapod or a translational tripod (joint and zero-length tolerances); this is a {} machine",
            a.machine.display(),
            machine.kind()
        );
    };
    let mech = machine.mechanism();
    let m = s.mechanism.machine();
    let vals = match &a.actuators {
        Some(v) => parse_list(v, "--actuators")?,
        None => s
            .mechanism
            .home_joints()
            .iter()
            .zip(mech.actuators())
            .map(|(v, a)| a.quantity.to_user(*v))
            .collect(),
    };
    let x = crate::poses::actuators_from_user(mech, &vals)?;
    let (qt, qw) = s.mechanism.split_joints(&x);
    let devs = match &a.deviations {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read {}", p.display()))?;
            pkm::machine::read_deviations(m, &text, &p.display().to_string())?
        }
        None => Vec::new(),
    };
    let dev = deviations_from(m, &devs);
    let (dp, dw) = pose_error(m, qt, qw, &dev)?;
    let own;
    let tol = match &a.tolerances {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("cannot read {}", p.display()))?;
            own = pkm::machine::read_tolerances(m, &text, &p.display().to_string())?;
            &own
        }
        None => &s.tolerances,
    };
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let inputs: Vec<&std::path::Path> = std::iter::once(a.machine.as_path())
        .chain(a.deviations.as_deref())
        .chain(a.tolerances.as_deref())
        .collect();
    // Sensitivity table of every toleranced deviation (or every deviation).
    let params: Vec<Parameter> = if tol.is_empty() {
        m.all_parameters()
    } else {
        tol.iter().map(|t| t.parameter).collect()
    };
    let sens = m.sensitivities(qt, qw, &dev, &params)?;
    let unit = |p: &Parameter| if m.is_angular(p) { "deg" } else { "mm" };
    let per_user = |p: &Parameter, v: f64| if m.is_angular(p) { v.to_radians() } else { v };
    let sens_json: Vec<_> = params
        .iter()
        .zip(&sens)
        .map(|(p, (d, w))| {
            let k = per_user(p, 1.0);
            json!({
                "deviation": m.parameter_name(p),
                "unit": unit(p),
                "position_mm_per_unit": [d.x * k, d.y * k, d.z * k],
                "orientation_rad_per_unit": [w.x * k, w.y * k, w.z * k],
            })
        })
        .collect();
    let mut out = json!({
        "machine": m.name,
        "axes": mech.coordinates().iter().zip(&vals).map(|(c, v)| json!({"name": c.name, "value": v, "unit": c.quantity.unit()})).collect::<Vec<_>>(),
        "deviations_given": devs.len(),
        "position_error": [dp.x, dp.y, dp.z],
        "position_error_norm": dp.norm(),
        "orientation_error": [dw.x, dw.y, dw.z],
        "sensitivities": sens_json,
    });
    let o = out.as_object_mut().expect("object");
    if !tol.is_empty() {
        let b = budget(m, qt, qw, tol)?;
        let mut map = serde_json::Map::new();
        for i in &b.items {
            map.insert(i.name.clone(), json!(i.position));
        }
        o.insert("budget".into(), serde_json::Value::Object(map));
        o.insert("budget_worst_case".into(), json!(b.worst_case));
        o.insert("budget_rss".into(), json!(b.rss));
        write_budget(&a.out, &b, &inputs)?;
        if let Some(n) = a.monte_carlo {
            if n == 0 {
                bail!("--monte-carlo: expected a number of samples > 0");
            }
            let mc = monte_carlo(m, qt, qw, tol, n, a.seed)?;
            o.insert(
                "monte_carlo".into(),
                write_monte_carlo(&a.out, &mc, a.seed, &inputs)?,
            );
        }
    } else if a.monte_carlo.is_some() || a.map.is_some() {
        bail!("--monte-carlo and --map need tolerances: add [[tolerance]] entries to the machine file");
    }
    if let Some(spec) = &a.map {
        // The map runs over joint travel: the axes are the machine's joints.
        let axes: Vec<MapAxis> = mech
            .actuators()
            .iter()
            .map(|c| MapAxis {
                name: c.name.clone(),
                quantity: c.quantity,
                range: (c.range.min, c.range.max),
            })
            .collect();
        let map = error_map(a, spec, &axes, &x, &inputs, |y| {
            let (yt, yw) = s.mechanism.split_joints(y);
            Ok(Some(budget(m, yt, yw, tol)?))
        })?;
        o.insert("error_map".into(), map);
    }
    let text = serde_json::to_string_pretty(&out)?;
    write_atomic(&a.out.join("errors.json"), text.as_bytes(), &inputs)?;
    if a.json {
        println!("{text}");
    } else {
        println!("{} (serial)", m.name);
        println!(
            "position error   dx={:+.6} dy={:+.6} dz={:+.6} mm (|e| = {:.6} mm, workpiece frame)",
            dp.x,
            dp.y,
            dp.z,
            dp.norm()
        );
        println!(
            "orientation      rx={:+.3e} ry={:+.3e} rz={:+.3e} rad",
            dw.x, dw.y, dw.z
        );
        if let Some(b) = out.get("budget_worst_case") {
            println!(
                "budget           worst case {:.4} mm, RSS {:.4} mm ({} toleranced deviations)",
                b.as_f64().unwrap_or(0.0),
                out["budget_rss"].as_f64().unwrap_or(0.0),
                tol.len()
            );
            if let Some(items) = out["budget"].as_object() {
                let mut v: Vec<(&String, f64)> = items
                    .iter()
                    .map(|(k, x)| (k, x.as_f64().unwrap_or(0.0)))
                    .collect();
                v.sort_by(|a, b| b.1.total_cmp(&a.1));
                for (k, x) in v.iter().take(5) {
                    println!("  largest        {k:<28} {:.4} mm", x);
                }
            }
        }
        if let Some(mc) = out.get("monte_carlo") {
            println!(
                "monte carlo      {} samples: mean {:.4}, std {:.4}, p95 {:.4}, p99 {:.4}, max {:.4} mm",
                mc["samples"], mc["mean"].as_f64().unwrap_or(0.0), mc["std"].as_f64().unwrap_or(0.0),
                mc["p95"].as_f64().unwrap_or(0.0), mc["p99"].as_f64().unwrap_or(0.0), mc["max"].as_f64().unwrap_or(0.0)
            );
        }
        println!("wrote {}", a.out.display());
    }
    Ok(0)
}

/// `pkm errors` for strut machines: the tool-point error budget and Monte Carlo of
/// tolerances on the joint centres and zero lengths (`pkm::accuracy`).
fn strut_errors<M: Identifiable<6, A>, const A: usize>(
    a: &ErrorsArgs,
    machine: &pkm::Machine,
    m: &M,
    zero: SVector<f64, A>,
) -> Result<u8> {
    if a.actuators.is_some() || a.deviations.is_some() || a.tolerances.is_some() {
        bail!(
            "{}: --actuators, --deviations and --tolerances are for serial machines; \
             a {} takes --pose, --joint-tolerance, --length-tolerance (and --map, --monte-carlo)",
            a.machine.display(),
            machine.kind()
        );
    }
    let dm = machine.mechanism();
    let x: Vec<f64> = match &a.pose {
        Some(p) => {
            pkm::dynamic::pose_from_user(dm, &parse_list(p, "--pose")?, pkm::Convention::Rpy)?
        }
        None => dm.home(),
    };
    let x = SVector::<f64, 6>::from_column_slice(&x);
    let distribution = match a.distribution.as_str() {
        "uniform" => Distribution::Uniform,
        "normal" => Distribution::Normal,
        d => bail!("--distribution: expected `uniform` or `normal`, found `{d}`"),
    };
    if !(a.joint_tolerance >= 0.0 && a.length_tolerance >= 0.0) {
        bail!("--joint-tolerance, --length-tolerance: expected values >= 0 (mm)");
    }
    let tol = GeometricTolerances {
        joint: a.joint_tolerance,
        zero: a.length_tolerance,
        distribution,
    };
    let names = pkm::identify::parameter_names(m);
    let sens = pkm::accuracy::sensitivities(m, &x)?;
    let b = pkm::accuracy::budget(m, &x, &tol)?;
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("cannot create {}", a.out.display()))?;
    let inputs = [a.machine.as_path()];
    let mut map = serde_json::Map::new();
    for i in &b.items {
        map.insert(i.name.clone(), json!(i.position));
    }
    let mut out = json!({
        "machine": m.name(),
        "pose": crate::poses::coords_json(dm, x.as_slice()),
        "tolerances": {"joint_mm": tol.joint, "zero_length_mm": tol.zero, "distribution": a.distribution},
        "sensitivities": names.iter().zip(&sens).map(|(n, (d, w))| json!({
            "parameter": n, "unit": "mm",
            "position_mm_per_unit": [d.x, d.y, d.z],
            "orientation_rad_per_unit": [w.x, w.y, w.z],
        })).collect::<Vec<_>>(),
        "budget": map,
        "budget_worst_case": b.worst_case,
        "budget_rss": b.rss,
    });
    write_budget(&a.out, &b, &inputs)?;
    let mut mc_line = String::new();
    if let Some(n) = a.monte_carlo {
        if n == 0 {
            bail!("--monte-carlo: expected a number of samples > 0");
        }
        let mc = pkm::accuracy::monte_carlo(m, &x, &zero, &tol, n, a.seed)?;
        out.as_object_mut().expect("object").insert(
            "monte_carlo".into(),
            write_monte_carlo(&a.out, &mc, a.seed, &inputs)?,
        );
        mc_line = format!(
            "monte carlo      {} samples: mean {:.4}, std {:.4}, p95 {:.4}, p99 {:.4}, max {:.4} mm\n",
            mc.samples, mc.mean, mc.std, mc.p95, mc.p99, mc.max
        );
    }
    if let Some(spec) = &a.map {
        // Over two pose coordinates: the workspace command's default span around the
        // pose; unreachable poses are left blank.
        let grid = super::workspace::default_axes(dm, x.as_slice(), None, None)?;
        let axes: Vec<MapAxis> = dm
            .coordinates()
            .iter()
            .enumerate()
            .map(|(k, c)| MapAxis {
                name: c.name.clone(),
                quantity: c.quantity,
                range: grid
                    .iter()
                    .find(|g| g.coordinate == k)
                    .map(|g| (g.min, g.max))
                    .unwrap_or((x[k], x[k])),
            })
            .collect();
        let map = error_map(a, spec, &axes, x.as_slice(), &inputs, |y| {
            let y = SVector::<f64, 6>::from_column_slice(y);
            let Ok(q) = m.inverse(&y) else {
                return Ok(None);
            };
            let mut v = Vec::new();
            m.check_limits(&y, &q, &mut v);
            if !v.is_empty() {
                return Ok(None);
            }
            Ok(pkm::accuracy::budget(m, &y, &tol).ok())
        })?;
        out.as_object_mut()
            .expect("object")
            .insert("error_map".into(), map);
    }
    let text = serde_json::to_string_pretty(&out)?;
    write_atomic(&a.out.join("errors.json"), text.as_bytes(), &inputs)?;
    if a.json {
        println!("{text}");
    } else {
        println!("{} ({})", m.name(), machine.kind());
        println!(
            "tolerances       joints +-{} mm, zero lengths +-{} mm ({})",
            tol.joint, tol.zero, a.distribution
        );
        println!(
            "budget           worst case {:.4} mm, RSS {:.4} mm ({} parameters)",
            b.worst_case,
            b.rss,
            b.items.len()
        );
        for i in b.items.iter().take(5) {
            println!("  largest        {:<28} {:.4} mm", i.name, i.position);
        }
        print!("{mc_line}");
        println!("wrote {}", a.out.display());
    }
    Ok(0)
}

/// The budget's largest 25 lines as a bar chart, DIR/budget.svg.
fn write_budget(
    out: &std::path::Path,
    b: &pkm::serial::tolerance::Budget,
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
            "error budget: tool-point error at each tolerance (worst case {:.2} um, RSS {:.2} um)",
            1000.0 * b.worst_case,
            1000.0 * b.rss
        ),
        "contribution [um]",
        &top,
        760,
    )?;
    write_atomic(&out.join("budget.svg"), svg.as_bytes(), inputs)
}

/// The Monte Carlo histogram, DIR/monte-carlo.svg, and the JSON of its statistics.
fn write_monte_carlo(
    out: &std::path::Path,
    mc: &pkm::serial::tolerance::MonteCarlo,
    seed: u64,
    inputs: &[&std::path::Path],
) -> Result<serde_json::Value> {
    let bins: Vec<(f64, usize)> = mc.histogram.iter().map(|(x, c)| (1000.0 * x, *c)).collect();
    let svg = histogram_svg(
        &format!(
            "Monte Carlo, {} machines: tool-point error (mean {:.2} um, p95 {:.2} um)",
            mc.samples,
            1000.0 * mc.mean,
            1000.0 * mc.p95
        ),
        "|error| [um]",
        &bins,
        (640, 400),
    )?;
    write_atomic(&out.join("monte-carlo.svg"), svg.as_bytes(), inputs)?;
    Ok(json!({
        "samples": mc.samples, "seed": seed,
        "mean": mc.mean, "std": mc.std, "p95": mc.p95, "p99": mc.p99, "max": mc.max,
        "mean_vector": mc.mean_vector, "std_vector": mc.std_vector,
    }))
}

/// One axis an error map can run over.
struct MapAxis {
    name: String,
    quantity: pkm::Quantity,
    /// Travel (internal units).
    range: (f64, f64),
}

/// `--map A,B`: the first-order RSS and worst case of the tolerances over a grid of two
/// axes (the others at `base`), DIR/error-map.csv and DIR/error-map.svg; `budget_at`
/// gives `None` where the machine cannot be (left blank).
fn error_map(
    a: &ErrorsArgs,
    spec: &str,
    axes_all: &[MapAxis],
    base: &[f64],
    inputs: &[&std::path::Path],
    budget_at: impl Fn(&[f64]) -> Result<Option<pkm::serial::tolerance::Budget>>,
) -> Result<serde_json::Value> {
    let names: Vec<&str> = spec.split(',').map(str::trim).collect();
    let idx: Vec<usize> = names
        .iter()
        .map(|n| {
            axes_all.iter().position(|c| c.name == *n).with_context(|| {
                format!(
                    "--map: unknown axis `{n}`, expected two of {}",
                    axes_all
                        .iter()
                        .map(|c| c.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            })
        })
        .collect::<Result<_>>()?;
    if idx.len() != 2 || idx[0] == idx[1] {
        bail!("--map: expected two different axes, e.g. X,Y");
    }
    if a.map_points < 2 || a.map_points > 401 {
        bail!("--map-points: expected 2 to 401");
    }
    let n = a.map_points;
    let axis = |k: usize| {
        let (lo, hi) = axes_all[idx[k]].range;
        pkm::workspace::GridAxis {
            coordinate: idx[k],
            min: lo,
            max: hi,
            step: (hi - lo) / (n - 1) as f64,
        }
    };
    let axes = [axis(0), axis(1)];
    let (c0, c1) = (&axes_all[idx[0]], &axes_all[idx[1]]);
    let mut csv = format!(
        "{}_{},{}_{},rss_mm,worst_case_mm\n",
        c0.name,
        c0.quantity.unit(),
        c1.name,
        c1.quantity.unit()
    );
    let mut rss = Vec::with_capacity(n * n);
    let mut worst_all: f64 = 0.0;
    let mut blank = 0;
    for i in 0..axes[0].count() {
        for k in 0..axes[1].count() {
            let mut y = base.to_vec();
            y[idx[0]] = axes[0].value(i);
            y[idx[1]] = axes[1].value(k);
            let (u0, u1) = (
                c0.quantity.to_user(y[idx[0]]),
                c1.quantity.to_user(y[idx[1]]),
            );
            match budget_at(&y)? {
                Some(b) => {
                    worst_all = worst_all.max(b.rss);
                    csv.push_str(&format!(
                        "{u0:.6},{u1:.6},{:.9},{:.9}\n",
                        b.rss, b.worst_case
                    ));
                    rss.push(Some(b.rss));
                }
                None => {
                    blank += 1;
                    csv.push_str(&format!("{u0:.6},{u1:.6},,\n"));
                    rss.push(None);
                }
            }
        }
    }
    write_atomic(&a.out.join("error-map.csv"), csv.as_bytes(), inputs)?;
    let coord = |k: usize| {
        (
            axes_all[axes[k].coordinate].name.clone(),
            axes_all[axes[k].coordinate].quantity,
        )
    };
    let value = |flat: usize| rss[flat].map(|v| 1e3 * v);
    let svg = super::workspace::slice_plot(
        &axes,
        base,
        &coord,
        (0, 1),
        "first-order RSS of the tolerances over the travel",
        crate::report::heatmap::Scale::Linear("RSS [µm]"),
        &value,
    )?;
    write_atomic(&a.out.join("error-map.svg"), svg.as_bytes(), inputs)?;
    Ok(
        json!({"axes": names, "points": n * n, "unreachable": blank, "max_rss": worst_all, "file": "error-map.csv"}),
    )
}
