//! The plots of `pkm motion` and of the report's motion section: the actuators'
//! position, velocity and acceleration over time beside the serial machine's axes.

use anyhow::Result;
use pkm::analysis::motion::MotionRun;
use pkm::DynMechanism;

use crate::report::plot::{panels_marked, Panel, Series};

/// The plots of a run: actuators (position, velocity, acceleration) and serial axes.
pub fn plots(m: &dyn DynMechanism, o: &MotionRun, title: &str) -> Result<(String, String)> {
    let a = m.actuators();
    let serial: Vec<(String, &'static str)> = o
        .summary
        .serial
        .iter()
        .map(|(n, _)| {
            let unit = m
                .coordinates()
                .iter()
                .find(|c| &c.name == n)
                .map(|c| c.quantity.unit())
                .unwrap_or("mm");
            (n.clone(), unit)
        })
        .collect();
    let col =
        |c: usize| -> Vec<(f64, f64)> { o.traces.rows.iter().map(|r| (r[0], r[c])).collect() };
    let marks: Vec<(f64, String)> = o
        .traces
        .segments
        .iter()
        .skip(1)
        .map(|(t, l)| (*t, format!("N{l}")))
        .collect();
    // Limits per kind (position, velocity, acceleration) of actuator `x`, in user
    // units; only the actuators have them.
    let limits = |x: &pkm::Actuator, k: usize| -> Vec<(f64, String)> {
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
    };
    // Axes drawn: name, unit, first column (position; velocity and acceleration
    // follow), the actuator whose limits are drawn. Lengths and angles get panels of
    // their own (a 5-axis machine's B, C in deg beside X, Y, Z in mm).
    type Axis<'a> = (String, &'static str, usize, Option<&'a pkm::Actuator>);
    let panel = |axes: &[Axis], title: &str| -> Result<String> {
        let kinds = [
            ("position", ""),
            ("velocity", "/s"),
            ("acceleration", "/s²"),
        ];
        let mut units: Vec<&str> = Vec::new();
        for x in axes {
            if !units.contains(&x.1) {
                units.push(x.1);
            }
        }
        let mut series: Vec<Vec<Series>> = Vec::new();
        let mut labels: Vec<(String, String)> = Vec::new();
        let mut lims: Vec<Vec<(f64, String)>> = Vec::new();
        for unit in &units {
            let group: Vec<&Axis> = axes.iter().filter(|x| x.1 == *unit).collect();
            for (k, (kind, suffix)) in kinds.iter().enumerate() {
                series.push(
                    group
                        .iter()
                        .map(|(n, _, c, _)| Series {
                            name: n.clone(),
                            points: col(c + k),
                        })
                        .collect(),
                );
                let t = if units.len() > 1 {
                    let group = match *unit {
                        "deg" => "rotary axes",
                        "mm" => "linear axes",
                        u => u,
                    };
                    format!("{kind}, {group}")
                } else {
                    kind.to_string()
                };
                labels.push((t, format!("{kind} [{unit}{suffix}]")));
                lims.push(
                    group
                        .iter()
                        .filter_map(|x| x.3)
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
            &marks,
            (700, 760 * units.len().max(1) as u32),
        )
    };
    let act_axes: Vec<Axis> = a
        .iter()
        .enumerate()
        .map(|(i, x)| (x.name.clone(), x.quantity.unit(), 1 + 3 * i, Some(x)))
        .collect();
    let ser_axes: Vec<Axis> = serial
        .iter()
        .enumerate()
        .map(|(i, (n, u))| (n.clone(), *u, 1 + 3 * a.len() + 3 * i, None))
        .collect();
    let act = panel(&act_axes, &format!("{title}: actuators"))?;
    let ser = panel(&ser_axes, &format!("{title}: serial machine"))?;
    Ok((act, ser))
}
