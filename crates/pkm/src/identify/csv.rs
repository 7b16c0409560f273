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

/// An error of `file` at `line` (and `column`), in `field`.
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
    let mut p = Parser {
        file,
        actuators,
        fixture_names: Vec::new(),
        fixture: Vec::new(),
        columns: None,
        states: Vec::new(),
    };
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let t = raw.trim();
        if t.is_empty() {
            continue;
        }
        if let Some(c) = t.strip_prefix('#') {
            p.comment(c.trim(), line)?;
            continue;
        }
        let cells: Vec<&str> = t.split(',').map(str::trim).collect();
        match &p.columns {
            None => p.header(&cells, line)?,
            Some(names) => {
                let state = p.row(&cells, names, line)?;
                p.states.push(state);
            }
        }
    }
    p.finish(text)
}

/// A measurement file read so far.
struct Parser<'a> {
    /// The file's name, for errors.
    file: &'a str,
    /// The machine's actuators.
    actuators: &'a [Actuator],
    /// The fixture points' names.
    fixture_names: Vec<String>,
    /// The fixture points (platform frame, mm).
    fixture: Vec<Vector3<f64>>,
    /// The header's columns, once read.
    columns: Option<Vec<String>>,
    /// The measured states.
    states: Vec<State>,
}

impl Parser<'_> {
    /// The error of line `line` (column `column`, in `field`).
    fn error(&self, line: usize, column: Option<usize>, field: &str, message: String) -> Error {
        error(self.file, line, column, field, message)
    }

    /// A comment `c` (after `#`) on line `line`: `fixture NAME = x, y, z` adds a
    /// fixture point; any other comment is free text.
    fn comment(&mut self, c: &str, line: usize) -> Result<()> {
        let Some((name, xyz)) = c
            .strip_prefix("fixture ")
            .and_then(|rest| rest.split_once('='))
        else {
            return Ok(());
        };
        let v: Vec<f64> = xyz
            .split(',')
            .map(|s| s.trim().parse::<f64>())
            .collect::<std::result::Result<_, _>>()
            .map_err(|_| {
                self.error(
                    line,
                    None,
                    "fixture",
                    format!("expected three numbers (mm), found `{}`", xyz.trim()),
                )
            })?;
        if v.len() != 3 {
            return Err(self.error(
                line,
                None,
                "fixture",
                format!("expected three coordinates, found {}", v.len()),
            ));
        }
        if self.columns.is_some() {
            return Err(self.error(
                line,
                None,
                "fixture",
                "fixture points go before the header line".into(),
            ));
        }
        self.fixture_names.push(name.trim().to_string());
        self.fixture.push(Vector3::new(v[0], v[1], v[2]));
        Ok(())
    }

    /// The header line `cells` (line `line`): `state`, the actuators' readings, the
    /// fixture points' coordinates, in that order.
    fn header(&mut self, cells: &[&str], line: usize) -> Result<()> {
        let expected: Vec<String> = std::iter::once("state".to_string())
            .chain(self.actuators.iter().map(|a| format!("d{}", a.name)))
            .chain(
                self.fixture_names
                    .iter()
                    .flat_map(|n| ["x", "y", "z"].map(|a| format!("{n}_{a}"))),
            )
            .collect();
        if self.fixture.is_empty() {
            return Err(self.error(line, None, "fixture", "no `# fixture NAME = x, y, z` lines before the header: the measured points' platform coordinates are needed".into()));
        }
        for (k, e) in expected.iter().enumerate() {
            if cells.get(k) != Some(&e.as_str()) {
                return Err(self.error(
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
            return Err(self.error(
                line,
                Some(expected.len() + 1),
                "header",
                format!("{} columns, expected {}", cells.len(), expected.len()),
            ));
        }
        self.columns = Some(expected);
        Ok(())
    }

    /// The state of row `cells` (line `line`) under the header's columns `names`.
    fn row(&self, cells: &[&str], names: &[String], line: usize) -> Result<State> {
        if cells.len() != names.len() {
            return Err(self.error(
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
            v.push(self.value(c, &names[k], line, k + 1)?);
        }
        let na = self.actuators.len();
        let readings = self
            .actuators
            .iter()
            .enumerate()
            .map(|(j, a)| a.quantity.from_user(v[1 + j]))
            .collect();
        let points = (0..self.fixture.len())
            .map(|k| Vector3::new(v[1 + na + 3 * k], v[2 + na + 3 * k], v[3 + na + 3 * k]))
            .collect();
        Ok(State { readings, points })
    }

    /// The number in cell `c` of column `name` (line `line`, column `column`).
    fn value(&self, c: &str, name: &str, line: usize, column: usize) -> Result<f64> {
        let x: f64 = c
            .parse()
            .ok()
            .filter(|x: &f64| x.is_finite())
            .ok_or_else(|| {
                self.error(
                    line,
                    Some(column),
                    name,
                    format!("expected a number, found `{c}`"),
                )
            })?;
        // The sane magnitudes of machine files: a reading of 1e300 is a typing error,
        // refused at its row rather than fitted.
        if x.abs() > crate::machine::MAX_MAGNITUDE {
            return Err(self.error(
                line,
                Some(column),
                name,
                format!("expected a magnitude of at most 1e6 (mm, deg), found `{c}`"),
            ));
        }
        Ok(x)
    }

    /// The measurements, once the whole `text` is read: a header and a state needed.
    fn finish(self, text: &str) -> Result<Measurements> {
        if self.columns.is_none() {
            return Err(self.error(
                text.lines().count().max(1),
                None,
                "header",
                "no header line (state,d<actuator>...,<point>_x,...)".into(),
            ));
        }
        if self.states.is_empty() {
            return Err(self.error(
                text.lines().count().max(1),
                None,
                "row",
                "no measured states".into(),
            ));
        }
        Ok(Measurements {
            fixture: self.fixture,
            states: self.states,
        })
    }
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
