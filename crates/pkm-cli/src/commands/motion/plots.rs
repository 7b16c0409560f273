//! The plots of `pkm motion` and of the report's motion section: the actuators'
//! position, velocity and acceleration over time beside the serial machine's axes.

use anyhow::Result;
use pkm::analysis::motion::MotionRun;
use pkm::DynMechanism;

use crate::report::plot::{panels_marked, Panel, Series};

/// An axis drawn. Lengths and angles get panels of their own (a 5-axis machine's B, C
/// in deg beside X, Y, Z in mm).
struct Axis<'a> {
    name: String,
    unit: &'static str,
    /// Column of its position in the run's traces; velocity and acceleration follow.
    column: usize,
    /// The actuator whose limits are drawn (the serial axes have none).
    actuator: Option<&'a pkm::Actuator>,
}

/// What is drawn of each axis: kind, and the suffix of its unit.
const KINDS: [(&str, &str); 3] = [
    ("position", ""),
    ("velocity", "/s"),
    ("acceleration", "/s²"),
];

/// The plots of a run: actuators (position, velocity, acceleration) and serial axes.
pub fn plots(m: &dyn DynMechanism, o: &MotionRun, title: &str) -> Result<(String, String)> {
    let a = m.actuators();
    let marks: Vec<(f64, String)> = o
        .traces
        .segments
        .iter()
        .skip(1)
        .map(|(t, l)| (*t, format!("N{l}")))
        .collect();
    let act_axes: Vec<Axis> = a
        .iter()
        .enumerate()
        .map(|(i, x)| Axis {
            name: x.name.clone(),
            unit: x.quantity.unit(),
            column: 1 + 3 * i,
            actuator: Some(x),
        })
        .collect();
    let ser_axes: Vec<Axis> = o
        .summary
        .serial
        .iter()
        .enumerate()
        .map(|(i, (n, _))| Axis {
            name: n.clone(),
            unit: m
                .coordinates()
                .iter()
                .find(|c| &c.name == n)
                .map(|c| c.quantity.unit())
                .unwrap_or("mm"),
            column: 1 + 3 * a.len() + 3 * i,
            actuator: None,
        })
        .collect();
    let act = panel_svg(o, &act_axes, &marks, &format!("{title}: actuators"))?;
    let ser = panel_svg(o, &ser_axes, &marks, &format!("{title}: serial machine"))?;
    Ok((act, ser))
}

/// Limits of kind `k` (position, velocity, acceleration) of actuator `x`, in user
/// units; only the actuators have them.
fn limits(x: &pkm::Actuator, k: usize) -> Vec<(f64, String)> {
    let u = |q: f64| x.quantity.to_user(q);
    match k {
        0 => vec![
            (u(x.range.min), format!("{} min", x.name)),
            (u(x.range.max), format!("{} max", x.name)),
        ],
        1 => x
            .max_velocity
            .map(|m| vec![(u(m), "max".into()), (-u(m), "-max".into())])
            .unwrap_or_default(),
        _ => x
            .max_acceleration
            .map(|m| vec![(u(m), "max".into()), (-u(m), "-max".into())])
            .unwrap_or_default(),
    }
}

/// One plot of `axes`: per unit, a panel of each kind.
fn panel_svg(o: &MotionRun, axes: &[Axis], marks: &[(f64, String)], title: &str) -> Result<String> {
    let col =
        |c: usize| -> Vec<(f64, f64)> { o.traces.rows.iter().map(|r| (r[0], r[c])).collect() };
    let mut units: Vec<&str> = Vec::new();
    for x in axes {
        if !units.contains(&x.unit) {
            units.push(x.unit);
        }
    }
    let mut series: Vec<Vec<Series>> = Vec::new();
    let mut labels: Vec<(String, String)> = Vec::new();
    let mut lims: Vec<Vec<(f64, String)>> = Vec::new();
    for unit in &units {
        let group: Vec<&Axis> = axes.iter().filter(|x| x.unit == *unit).collect();
        for (k, (kind, suffix)) in KINDS.iter().enumerate() {
            series.push(
                group
                    .iter()
                    .map(|x| Series {
                        name: x.name.clone(),
                        points: col(x.column + k),
                    })
                    .collect(),
            );
            labels.push((
                panel_title(kind, unit, units.len() > 1),
                format!("{kind} [{unit}{suffix}]"),
            ));
            lims.push(
                group
                    .iter()
                    .filter_map(|x| x.actuator)
                    .flat_map(|x| limits(x, k))
                    .collect(),
            );
        }
    }
    let panels: Vec<Panel> = series
        .iter()
        .zip(&labels)
        .zip(lims)
        .map(|((s, (t, y)), l)| Panel {
            title: t,
            ylabel: y,
            series: s,
            limits: l,
        })
        .collect();
    panels_marked(
        title,
        "t [s]",
        None,
        &panels,
        marks,
        (700, 760 * units.len().max(1) as u32),
    )
}

/// The title of the `kind` panel of the axes in `unit`: the group named when the plot
/// has `several` units.
fn panel_title(kind: &str, unit: &str, several: bool) -> String {
    if !several {
        return kind.to_string();
    }
    let group = match unit {
        "deg" => "rotary axes",
        "mm" => "linear axes",
        u => u,
    };
    format!("{kind}, {group}")
}
