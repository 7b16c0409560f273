//! The machine file as it is written: the configuration's units, and a writer that
//! reads each value from the INI or HAL, converts it and notes where it came from.

use std::fmt::Write as _;

use super::super::hal::{Hal, HalValue};
use super::super::ini::{short, Ini, IniEntry};
use super::super::{fmt_num, Kinematics};
use super::Imported;
use crate::error::{Error, Result};
use crate::Machine;

/// The configuration's units: mm per length unit, degrees per angle unit.
#[derive(Debug, Clone, Copy)]
pub(super) struct Units {
    pub(super) mm: f64,
    pub(super) linear: &'static str,
    pub(super) deg: f64,
    pub(super) angular: &'static str,
}

impl Units {
    pub(super) fn read(ini: &Ini, warnings: &mut Vec<String>) -> Result<Units> {
        let (mm, linear) = match ini.get("TRAJ", "LINEAR_UNITS") {
            None => {
                warnings.push(format!(
                    "{}: no [TRAJ] LINEAR_UNITS, lengths taken as mm",
                    short(&ini.file)
                ));
                (1.0, "mm")
            }
            Some(e) => match e.value.to_ascii_lowercase().as_str() {
                "mm" | "metric" => (1.0, "mm"),
                "in" | "inch" | "imperial" => (25.4, "in"),
                "cm" => (10.0, "cm"),
                _ => {
                    return Err(ini.error(
                        e,
                        format!(
                            "unknown length unit `{}`: expected mm, metric, inch, in or imperial",
                            e.value
                        ),
                    ))
                }
            },
        };
        let (deg, angular) = match ini.get("TRAJ", "ANGULAR_UNITS") {
            None => (1.0, "deg"),
            Some(e) => match e.value.to_ascii_lowercase().as_str() {
                "deg" | "degree" | "degrees" => (1.0, "deg"),
                "rad" | "radian" | "radians" => (180.0 / std::f64::consts::PI, "rad"),
                "grad" | "gon" => (0.9, "grad"),
                _ => {
                    return Err(ini.error(
                        e,
                        format!(
                            "unknown angle unit `{}`: expected degree, radian or grad",
                            e.value
                        ),
                    ))
                }
            },
        };
        Ok(Units {
            mm,
            linear,
            deg,
            angular,
        })
    }
}

/// Largest stroke written for a joint the INI leaves unlimited (mm).
pub(super) const OPEN_STROKE: f64 = 100_000.0;

pub(super) struct Writer<'a> {
    pub(super) ini: &'a Ini,
    pub(super) hal: &'a Hal,
    pub(super) units: Units,
    pub(super) kins: Kinematics,
    pub(super) out: String,
    pub(super) warnings: Vec<String>,
}

/// A geometry value and where it came from.
pub(super) struct Param {
    pub(super) value: f64,
    pub(super) origin: String,
}

impl Writer<'_> {
    pub(super) fn line(&mut self, s: impl AsRef<str>) {
        self.out.push_str(s.as_ref());
        self.out.push('\n');
    }

    pub(super) fn header(&mut self, sources: &[String]) {
        let ini = short(&self.ini.file).to_string();
        let module = self.kins.module();
        self.line(format!(
            "# Imported by `pkm import linuxcnc` from {ini} ({module}){}.",
            if sources.is_empty() {
                String::new()
            } else {
                format!(" and {}", sources.join(", "))
            }
        ));
        let lengths = if self.units.mm == 1.0 {
            "Lengths in mm".to_string()
        } else {
            format!(
                "Lengths converted from {} to mm (x {})",
                self.units.linear,
                fmt_num(self.units.mm)
            )
        };
        let angles = if self.units.deg == 1.0 {
            "angles in deg".to_string()
        } else {
            format!("angles converted from {} to deg", self.units.angular)
        };
        self.line(format!("# {lengths}, {angles}. Comments give"));
        self.line("# each value's origin: file:line and the configuration's own value and unit.");
        self.line(format!("type = \"{}\"", self.kins.machine_type()));
        let name = self
            .ini
            .get("EMC", "MACHINE")
            .map(|e| e.value.clone())
            .unwrap_or_else(|| module.to_string());
        self.line(format!("name = {}", toml_str(&name)));
        self.line(format!(
            "description = {}",
            toml_str(&format!("LinuxCNC configuration {ini} ({module})"))
        ));
    }

    /// A kinematics parameter: its HAL value, or the module's default.
    pub(super) fn param(&mut self, name: &str, default: f64) -> Result<Param> {
        match self.hal.value(name) {
            Ok(Some(HalValue { value, at, .. })) => Ok(Param { value, origin: at }),
            Ok(None) => Ok(Param {
                value: default,
                origin: format!("{} default", self.kins.module()),
            }),
            Err((signal, at)) => {
                let hint = match self.kins {
                    _ if !name.ends_with("tool-offset") => "",
                    Kinematics::XyzbcTrt | Kinematics::XyzacTrt => {
                        " (the tool length a program's G43 H sets): give it to `pkm motion` \
                         with --tool-length or --tool-table"
                    }
                    _ => " (a tool length from the tool table): give pkm the tool in `[tool] tip`",
                };
                self.warnings.push(format!(
                    "{name} follows signal `{signal}` ({at}), which nothing sets and which \
                     changes at run time; taken as {default} here{hint}"
                ));
                Ok(Param {
                    value: default,
                    origin: format!("run-time signal {signal} ({at}), taken as {default}"),
                })
            }
        }
    }

    pub(super) fn number(&self, section: &str, key: &str) -> Result<Option<(f64, IniEntry)>> {
        Ok(self.ini.number(section, key)?.map(|(v, e)| (v, e.clone())))
    }

    /// A joint's `MAX_VELOCITY` and `MAX_ACCELERATION` of INI section `sec` that are
    /// given and positive (controller units); a non-positive one is left out with a
    /// warning naming its line.
    pub(super) fn rates(&mut self, sec: &str) -> Result<Vec<Rate>> {
        let mut out = Vec::new();
        for (key, field, per) in [
            ("MAX_VELOCITY", "max_velocity", "/s"),
            ("MAX_ACCELERATION", "max_acceleration", "/s^2"),
        ] {
            if let Some((value, e)) = self.number(sec, key)? {
                if value > 0.0 {
                    out.push(Rate {
                        key,
                        field,
                        per,
                        value,
                        at: self.ini.at(&e),
                    });
                } else {
                    self.warnings.push(format!(
                        "{}: [{sec}] {key} {value} is not > 0, left out",
                        self.ini.at(&e)
                    ));
                }
            }
        }
        Ok(out)
    }

    /// `[limits] axes` from `[AXIS_L] MIN_LIMIT / MAX_LIMIT`.
    pub(super) fn limits(&mut self) -> Result<()> {
        let mut items = Vec::new();
        let mut notes = Vec::new();
        for (c, linear) in self.kins.coordinates() {
            let sec = format!("AXIS_{c}");
            let (Some((lo, el)), Some((hi, eh))) = (
                self.number(&sec, "MIN_LIMIT")?,
                self.number(&sec, "MAX_LIMIT")?,
            ) else {
                continue;
            };
            let k = if *linear {
                self.units.mm
            } else {
                self.units.deg
            };
            let (a, b) = (lo * k, hi * k);
            if !(a < b) {
                return Err(self
                    .ini
                    .error(&eh, format!("the travel [{lo}, {hi}] of axis {c} is empty")));
            }
            if a.abs() > crate::machine::MAX_MAGNITUDE || b.abs() > crate::machine::MAX_MAGNITUDE {
                notes.push(format!(
                    "{c}: [{lo}, {hi}] ({}), unlimited here",
                    self.ini.at(&el)
                ));
                continue;
            }
            items.push(format!("{c} = [{}, {}]", fmt_num(a), fmt_num(b)));
            notes.push(format!(
                "{c}: [{}, {}] {} ({}, {})",
                fmt_num(lo),
                fmt_num(hi),
                if *linear {
                    self.units.linear
                } else {
                    self.units.angular
                },
                self.ini.at(&el),
                self.ini.at(&eh)
            ));
        }
        self.line("");
        self.line("[limits]");
        if !items.is_empty() {
            self.line("# Axis travel from [AXIS_L] MIN_LIMIT, MAX_LIMIT:");
            for n in notes {
                self.line(format!("#   {n}"));
            }
            self.line(format!("axes = {{ {} }}", items.join(", ")));
        }
        Ok(())
    }

    /// `[home]` from `[TRAJ] HOME` (X Y Z A B C order) or `[AXIS_L] HOME`.
    pub(super) fn home(&mut self) -> Result<()> {
        let coords = self.kins.coordinates();
        let traj = self.ini.get("TRAJ", "HOME").cloned();
        let mut v = vec![0.0; coords.len()];
        let origin;
        if let Some(e) = &traj {
            let words: Vec<&str> = e.value.split_whitespace().collect();
            for (k, w) in words.iter().take(coords.len()).enumerate() {
                v[k] = w
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        self.ini
                            .error(e, format!("expected numbers X Y Z A B C, found `{w}`"))
                    })?;
            }
            origin = format!("[TRAJ] HOME = {} ({})", e.value, self.ini.at(e));
        } else {
            let mut parts = Vec::new();
            for (k, (c, _)) in coords.iter().enumerate() {
                if let Some((x, e)) = self.number(&format!("AXIS_{c}"), "HOME")? {
                    v[k] = x;
                    parts.push(format!("{c} {} ({})", fmt_num(x), self.ini.at(&e)));
                }
            }
            origin = if parts.is_empty() {
                "no HOME given: 0".into()
            } else {
                format!("[AXIS_L] HOME: {}", parts.join(", "))
            };
        }
        for (k, (_, linear)) in coords.iter().enumerate() {
            v[k] *= if *linear {
                self.units.mm
            } else {
                self.units.deg
            };
        }
        self.line("");
        self.line("[home]");
        self.line(format!("# {origin}"));
        self.line(format!(
            "position = [{}, {}, {}]",
            fmt_num(v[0]),
            fmt_num(v[1]),
            fmt_num(v[2])
        ));
        if v.len() > 3 {
            let angles: Vec<String> = v[3..].iter().map(|a| fmt_num(*a)).collect();
            self.line(format!("angles = [{}]", angles.join(", ")));
        }
        Ok(())
    }

    /// The machine file written so far, loaded (an error when the configuration does
    /// not give a valid pkm machine).
    pub(super) fn load(&self) -> Result<Machine> {
        Machine::from_toml_str(&self.out, "<imported machine>").map_err(|e| Error::InvalidInput {
            what: format!("import of {}", short(&self.ini.file)),
            message: format!("the configuration does not give a valid pkm machine: {e}"),
        })
    }

    /// Loads the file written so far, compares the INI's joint HOME and HOME_OFFSET
    /// with the struts at the home pose, and adds what follows from them.
    pub(super) fn finish(mut self) -> Result<Imported> {
        let m = self.load()?;
        let mech = m.mechanism();
        let home = mech.home();
        let q = mech.inverse(&home)?;
        let n = q.len();
        let joint_home = self.joint_values("HOME", n)?;
        let joint_offset = self.joint_values("HOME_OFFSET", n)?;
        let mut tail = String::new();
        if let Some(h) = &joint_home {
            self.home_reference(h, &q, &home, &mut tail);
        }
        if let (Some(off), Kinematics::Genhex | Kinematics::Tripod) = (&joint_offset, self.kins) {
            if off.iter().all(|(v, _)| *v > 0.0) {
                let vals: Vec<String> = off.iter().map(|(v, _)| fmt_num(*v)).collect();
                let _ = writeln!(tail, "\n[calibration]");
                let _ = writeln!(
                    tail,
                    "# [JOINT_n] HOME_OFFSET ({}): the strut lengths at the home switches, where \
                     the control's readings are zeroed",
                    self.ini.at(&off[0].1)
                );
                let _ = writeln!(tail, "zero_lengths = [{}]", vals.join(", "));
            }
        }
        self.out.push_str(&tail);
        self.load()?;
        Ok(Imported {
            toml: self.out,
            kinematics: self.kins.module(),
            warnings: self.warnings,
        })
    }

    /// `[JOINT_i] key` of each of the `n` joints (mm), or `None` unless every joint
    /// has it.
    fn joint_values(&self, key: &str, n: usize) -> Result<Option<Vec<(f64, IniEntry)>>> {
        let mut v = Vec::new();
        for i in 0..n {
            match self.number(&format!("JOINT_{i}"), key)? {
                Some((x, e)) => v.push((x * self.units.mm, e)),
                None => return Ok(None),
            }
        }
        Ok(Some(v))
    }

    /// Compares the INI's joint HOME `h` with the strut lengths `q` at the home pose
    /// `home`: a `[[reference]]` into `tail` when they agree, else a warning and a note.
    fn home_reference(
        &mut self,
        h: &[(f64, IniEntry)],
        q: &[f64],
        home: &[f64],
        tail: &mut String,
    ) {
        let worst = h
            .iter()
            .zip(q)
            .map(|((a, _), b)| (a - b).abs())
            .fold(0.0, f64::max);
        if worst <= 1e-2 {
            let _ = writeln!(tail, "\n[[reference]]");
            let _ = writeln!(
                tail,
                "source = {}",
                toml_str(&format!(
                    "{}: [JOINT_n] HOME, the strut lengths LinuxCNC homes to at the home pose",
                    short(&self.ini.file)
                ))
            );
            let angles: Vec<f64> = home[3..].iter().map(|a| a.to_degrees()).collect();
            let pose: Vec<String> = home[..3]
                .iter()
                .copied()
                .chain(angles)
                .map(fmt_num)
                .collect();
            let _ = writeln!(tail, "pose = [{}]", pose.join(", "));
            let _ = writeln!(tail, "tolerance = 0.01");
            let acts: Vec<String> = h
                .iter()
                .enumerate()
                .map(|(i, (v, _))| format!("\"{i}\" = {}", fmt_num(*v)))
                .collect();
            let _ = writeln!(tail, "actuators = {{ {} }}", acts.join(", "));
        } else {
            let ik: Vec<String> = q.iter().map(|x| format!("{x:.4}")).collect();
            let vals: Vec<String> = h.iter().map(|(v, _)| format!("{v:.4}")).collect();
            let msg = format!(
                "the INI's [JOINT_n] HOME ({} mm) are not the strut lengths at the home \
                 pose ({} mm; up to {worst:.3} mm off): LinuxCNC would home to another \
                 pose; pkm uses the home pose",
                vals.join(", "),
                ik.join(", ")
            );
            self.warnings.push(msg.clone());
            tail.push_str(&format!("\n# Note: {msg}.\n"));
        }
    }
}

/// `a.hal:4, a.hal:5, a.hal:6` as `a.hal:4-6`; equal origins once.
pub(super) fn join_origins(origins: &[String]) -> String {
    if origins.iter().all(|o| *o == origins[0]) {
        return origins[0].clone();
    }
    let parsed: Option<Vec<(&str, usize)>> = origins
        .iter()
        .map(|o| {
            let (f, l) = o.rsplit_once(':')?;
            Some((f, l.parse().ok()?))
        })
        .collect();
    if let Some(p) = parsed {
        let consecutive = p
            .windows(2)
            .all(|w| w[0].0 == w[1].0 && w[1].1 == w[0].1 + 1);
        if consecutive {
            return format!("{}:{}-{}", p[0].0, p[0].1, p[p.len() - 1].1);
        }
    }
    origins.join(", ")
}

pub(super) fn toml_str(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// A joint rate read from the INI ([`Writer::rates`]).
pub(super) struct Rate {
    /// INI key.
    pub(super) key: &'static str,
    /// pkm's field.
    pub(super) field: &'static str,
    /// Unit suffix (`/s`, `/s^2`).
    pub(super) per: &'static str,
    /// Value in the controller's units.
    pub(super) value: f64,
    /// Where it was read.
    pub(super) at: String,
}
