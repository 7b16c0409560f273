//! The measurement file: a CSV a real campaign can be typed or exported into.
//!
//! ```text
//! # fixture P1 = 0, 200, 0          <- known fixture points, platform frame (mm)
//! # fixture P2 = -173.205, -100, 0
//! # fixture P3 = 173.205, -100, 0
//! state,dL1,dL2,dL3,dL4,dL5,dL6,P1_x,P1_y,P1_z,P2_x,P2_y,P2_z,P3_x,P3_y,P3_z
//! 1,0,0,0,0,0,0,0.0012,200.003,849.998,...
//! ```
//!
//! Readings are the control's increments `d<actuator>` from the zero state (mm, deg
//! for revolute drives), in the machine's actuator order; points are measured in the
//! base frame (mm). Other `#` lines are comments. Errors name the line and column.

use std::fmt::Write as _;

use nalgebra::Vector3;

use super::{Measurements, State};
use crate::error::{Error, Result};
use crate::mechanism::Actuator;

fn error(file: &str, line: usize, column: Option<usize>, field: &str, message: String) -> Error {
    Error::MachineFile {
        file: file.into(),
        line: Some(line),
        column,
        field: field.into(),
        message,
    }
}

/// Parses a measurement file for a machine with `actuators`.
pub fn parse(text: &str, file: &str, actuators: &[Actuator]) -> Result<Measurements> {
    let mut fixture_names: Vec<String> = Vec::new();
    let mut fixture = Vec::new();
    let mut header: Option<(usize, Vec<String>)> = None;
    let mut states = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let t = raw.trim();
        if t.is_empty() {
            continue;
        }
        if let Some(c) = t.strip_prefix('#') {
            let c = c.trim();
            // `# fixture NAME = x, y, z`; any other comment is free text.
            if let Some((name, xyz)) = c
                .strip_prefix("fixture ")
                .and_then(|rest| rest.split_once('='))
            {
                let v: Vec<f64> = xyz
                    .split(',')
                    .map(|s| s.trim().parse::<f64>())
                    .collect::<std::result::Result<_, _>>()
                    .map_err(|_| {
                        error(
                            file,
                            line,
                            None,
                            "fixture",
                            format!("expected three numbers (mm), found `{}`", xyz.trim()),
                        )
                    })?;
                if v.len() != 3 {
                    return Err(error(
                        file,
                        line,
                        None,
                        "fixture",
                        format!("expected three coordinates, found {}", v.len()),
                    ));
                }
                if header.is_some() {
                    return Err(error(
                        file,
                        line,
                        None,
                        "fixture",
                        "fixture points go before the header line".into(),
                    ));
                }
                fixture_names.push(name.trim().to_string());
                fixture.push(Vector3::new(v[0], v[1], v[2]));
            }
            continue;
        }
        let cells: Vec<&str> = t.split(',').map(str::trim).collect();
        match &header {
            None => {
                let expected: Vec<String> = std::iter::once("state".to_string())
                    .chain(actuators.iter().map(|a| format!("d{}", a.name)))
                    .chain(
                        fixture_names
                            .iter()
                            .flat_map(|n| ["x", "y", "z"].map(|a| format!("{n}_{a}"))),
                    )
                    .collect();
                if fixture.is_empty() {
                    return Err(error(file, line, None, "fixture", "no `# fixture NAME = x, y, z` lines before the header: the measured points' platform coordinates are needed".into()));
                }
                for (k, e) in expected.iter().enumerate() {
                    if cells.get(k) != Some(&e.as_str()) {
                        return Err(error(
                            file,
                            line,
                            Some(k + 1),
                            "header",
                            format!(
                                "expected the columns {}; column {} is `{}`",
                                expected.join(","),
                                k + 1,
                                cells.get(k).unwrap_or(&"")
                            ),
                        ));
                    }
                }
                if cells.len() != expected.len() {
                    return Err(error(
                        file,
                        line,
                        Some(expected.len() + 1),
                        "header",
                        format!("{} columns, expected {}", cells.len(), expected.len()),
                    ));
                }
                header = Some((line, expected));
            }
            Some((_, names)) => {
                if cells.len() != names.len() {
                    return Err(error(
                        file,
                        line,
                        None,
                        "row",
                        format!(
                            "{} values, expected {} ({})",
                            cells.len(),
                            names.len(),
                            names.join(",")
                        ),
                    ));
                }
                let mut v = Vec::with_capacity(cells.len());
                for (k, c) in cells.iter().enumerate() {
                    let x: f64 =
                        c.parse()
                            .ok()
                            .filter(|x: &f64| x.is_finite())
                            .ok_or_else(|| {
                                error(
                                    file,
                                    line,
                                    Some(k + 1),
                                    &names[k],
                                    format!("expected a number, found `{c}`"),
                                )
                            })?;
                    // The sane magnitudes of machine files: a reading of 1e300 is a
                    // typing error, refused at its row rather than fitted.
                    if x.abs() > crate::machine::MAX_MAGNITUDE {
                        return Err(error(
                            file,
                            line,
                            Some(k + 1),
                            &names[k],
                            format!("expected a magnitude of at most 1e6 (mm, deg), found `{c}`"),
                        ));
                    }
                    v.push(x);
                }
                let na = actuators.len();
                let readings = actuators
                    .iter()
                    .enumerate()
                    .map(|(j, a)| a.quantity.from_user(v[1 + j]))
                    .collect();
                let points = (0..fixture.len())
                    .map(|k| Vector3::new(v[1 + na + 3 * k], v[2 + na + 3 * k], v[3 + na + 3 * k]))
                    .collect();
                states.push(State { readings, points });
            }
        }
    }
    if header.is_none() {
        return Err(error(
            file,
            text.lines().count().max(1),
            None,
            "header",
            "no header line (state,d<actuator>...,<point>_x,...)".into(),
        ));
    }
    if states.is_empty() {
        return Err(error(
            file,
            text.lines().count().max(1),
            None,
            "row",
            "no measured states".into(),
        ));
    }
    Ok(Measurements { fixture, states })
}

/// Writes a measurement file (fixture points named `P1`, `P2`, ...).
pub fn write(m: &Measurements, actuators: &[Actuator], comment: &str) -> String {
    let mut s = String::new();
    for l in comment.lines() {
        let _ = writeln!(s, "# {l}");
    }
    for (k, p) in m.fixture.iter().enumerate() {
        let _ = writeln!(s, "# fixture P{} = {}, {}, {}", k + 1, p.x, p.y, p.z);
    }
    let mut head = vec!["state".to_string()];
    head.extend(actuators.iter().map(|a| format!("d{}", a.name)));
    for k in 0..m.fixture.len() {
        for a in ["x", "y", "z"] {
            head.push(format!("P{}_{a}", k + 1));
        }
    }
    let _ = writeln!(s, "{}", head.join(","));
    for (i, st) in m.states.iter().enumerate() {
        let mut row = vec![(i + 1).to_string()];
        row.extend(
            st.readings
                .iter()
                .zip(actuators)
                .map(|(v, a)| format!("{}", a.quantity.to_user(*v))),
        );
        for p in &st.points {
            row.extend(p.iter().map(|v| format!("{v}")));
        }
        let _ = writeln!(s, "{}", row.join(","));
    }
    s
}
