//! `xyzbc-trt-kins` and `xyzac-trt-kins` (LinuxCNC's table-rotary-tilting 5-axis mills)
//! as a serial machine with tool-centre-point coordinates.
//!
//! The modules' forward kinematics (trtfuncs) with `conventional-directions = 0` read,
//! for XYZBC, `world = Rz(-C) [Ry(-B) (J - d - r) + d] + r` with the joints `J`, the
//! rotation point `r` (`x/y/z-rot-point`) and `d = (x-offset, 0, z-offset +
//! tool-offset)`; XYZAC the same with `Rx(-A)` and `d = (0, y-offset, z-offset +
//! tool-offset)`; `conventional-directions = 1` turns the other way. So the table turns
//! about the vertical through `r` (C) and tilts about a line through `r + d` along Y
//! (B) or X (A), and the spindle carries the tool `tool-offset` below its gauge point.
//! The chains written: X, Y, Z slides carrying the tool; the table mount at `r + d`,
//! the tilt joint, the rotary joint at `r` and the part frame (world-aligned at zero).
//! A table joint turns the table about its axis by the joint value: axes +Y (+X), +Z by
//! default, -Y (-X), -Z with conventional directions ([`crate::serial::tcp`]).
//! LinuxCNC's world Z carries the tool length on top of the tip (its interpreter adds
//! the offset); pkm's X, Y, Z are the tool tip's.

use nalgebra::{Matrix3, Vector3};

use super::{fmt_num, Imported, Kinematics, Writer};
use crate::error::Result;

/// A right-handed frame whose Z is the unit `z` (columns x, y, z): X the next world
/// axis after `z`'s dominant one.
fn frame(z: Vector3<f64>) -> Matrix3<f64> {
    let i = z.iamax();
    let mut x = Vector3::zeros();
    x[(i + 1) % 3] = 1.0;
    let x = (x - z * z.dot(&x)).normalize();
    Matrix3::from_columns(&[x, z.cross(&x), z])
}

fn row3(v: &Vector3<f64>) -> String {
    format!("[{}, {}, {}]", fmt_num(v.x), fmt_num(v.y), fmt_num(v.z))
}

fn block(m: &Matrix3<f64>) -> String {
    let rows: Vec<String> = (0..3)
        .map(|r| row3(&m.row(r).transpose().into_owned()))
        .collect();
    format!("[{}]", rows.join(", "))
}

impl Writer<'_> {
    /// The TCP machine of a trt module.
    pub(super) fn trt(&mut self) -> Result<()> {
        let module = self.kins.module();
        let (tilt, offset_axis) = match self.kins {
            Kinematics::XyzacTrt => ('A', 1),
            _ => ('B', 0),
        };
        let letters = ['X', 'Y', 'Z', tilt, 'C'];
        if let Some(e) = self.ini.get("TRAJ", "COORDINATES") {
            let given: String = e
                .value
                .chars()
                .filter(|c| !c.is_whitespace())
                .collect::<String>()
                .to_ascii_uppercase();
            if given != letters.iter().collect::<String>() {
                return Err(self.ini.error(
                    e,
                    format!(
                        "pkm maps {module}'s joints 0-4 to {}: COORDINATES `{}` (other orders \
                         or doubled letters) are not imported",
                        letters.iter().collect::<String>(),
                        e.value
                    ),
                ));
            }
        }
        let k = self.units.mm;
        let p = |s: &mut Self, name: &str| s.param(&format!("{module}.{name}"), 0.0);
        let rot = [
            p(self, "x-rot-point")?,
            p(self, "y-rot-point")?,
            p(self, "z-rot-point")?,
        ];
        let off_name = if offset_axis == 0 {
            "x-offset"
        } else {
            "y-offset"
        };
        let off = p(self, off_name)?;
        let zoff = p(self, "z-offset")?;
        let tool = p(self, "tool-offset")?;
        let conv = p(self, "conventional-directions")?;
        let conventional = conv.value != 0.0;
        let r = Vector3::new(rot[0].value, rot[1].value, rot[2].value) * k;
        let mut d = Vector3::zeros();
        d[offset_axis] = off.value * k;
        d.z = zoff.value * k;
        let sign = if conventional { -1.0 } else { 1.0 };
        let mut tilt_axis = Vector3::zeros();
        tilt_axis[1 - offset_axis] = sign;
        let rotary_axis = Vector3::new(0.0, 0.0, sign);
        if let Some(e) = self.ini.get("KINS", "KINEMATICS") {
            if e.value.contains("identityfirst") {
                self.warnings.push(format!(
                    "{}: the configuration starts in identity kinematics (sparm=identityfirst); \
                     the machine written is the {module} TCP kinematics its programs switch to \
                     (M428 in LinuxCNC's sim)",
                    self.ini.at(e)
                ));
            }
        }
        self.line(
            "pose = \"tcp\"  # X, Y, Z of the tool tip in the part frame, then the rotary axes",
        );
        self.line("");
        self.line(format!(
            "# {module}: table rotary axis C about the vertical through the rotation point,"
        ));
        self.line(format!(
            "# tilt axis {tilt} about a line along {} through rotation point + offsets.",
            if offset_axis == 0 { "Y" } else { "X" }
        ));
        for (c, prm) in ["x", "y", "z"].iter().zip(&rot) {
            self.line(format!(
                "#   {c}-rot-point = {} {}: {}",
                fmt_num(prm.value),
                self.units.linear,
                prm.origin
            ));
        }
        for (n, prm) in [
            (off_name, &off),
            ("z-offset", &zoff),
            ("tool-offset", &tool),
        ] {
            self.line(format!(
                "#   {n} = {} {}: {}",
                fmt_num(prm.value),
                self.units.linear,
                prm.origin
            ));
        }
        self.line(format!(
            "#   conventional-directions = {}: {} (table joints turn the table about {} and {})",
            fmt_num(conv.value),
            conv.origin,
            row3(&tilt_axis),
            row3(&rotary_axis)
        ));
        // Tool chain: X, Y, Z slides; the tool tip tool-offset below the gauge point.
        let world = Matrix3::identity();
        let slides = [Vector3::x(), Vector3::y(), Vector3::z()].map(frame);
        let mut prev = world;
        let names = ["bed", "x slide", "y slide", "spindle"];
        for (i, name) in names.iter().enumerate() {
            let next = if i < 3 { slides[i] } else { world };
            self.line("");
            self.line("[[tool_chain]]");
            self.line(format!("name = \"{name}\""));
            if i > 0 {
                self.joint_line(i - 1, letters[i - 1], "prismatic")?;
            }
            if i == 3 {
                let t = prev.transpose() * Vector3::new(0.0, 0.0, -tool.value * k);
                self.line(format!(
                    "translation = {}  # the tool tip tool-offset below the gauge point",
                    row3(&t)
                ));
            }
            self.line(format!("rotation = {}", block(&(prev.transpose() * next))));
            prev = next;
        }
        // Workpiece chain: mount at r + d, tilt, rotary at r, part frame.
        let (ft, fc) = (frame(tilt_axis), frame(rotary_axis));
        self.line("");
        self.line("[[workpiece_chain]]");
        self.line("name = \"table mount\"");
        self.line(format!(
            "translation = {}  # the tilt axis' point: rotation point + offsets",
            row3(&(r + d))
        ));
        self.line(format!("rotation = {}", block(&ft)));
        self.line("");
        self.line("[[workpiece_chain]]");
        self.line("name = \"tilting table\"");
        self.joint_line(3, tilt, "revolute")?;
        self.line(format!(
            "translation = {}  # from the tilt axis to the rotary axis' point",
            row3(&(ft.transpose() * -d))
        ));
        self.line(format!("rotation = {}", block(&(ft.transpose() * fc))));
        self.line("");
        self.line("[[workpiece_chain]]");
        self.line("name = \"rotary table\"");
        self.joint_line(4, 'C', "revolute")?;
        self.line(format!(
            "translation = {}  # the part frame's origin",
            row3(&(fc.transpose() * -r))
        ));
        self.line(format!("rotation = {}", block(&fc.transpose())));
        self.trt_home(&letters)
    }

    /// One `joint = {...}` line from `[JOINT_i]`.
    fn joint_line(&mut self, i: usize, letter: char, kind: &str) -> Result<()> {
        let sec = format!("JOINT_{i}");
        let linear = kind == "prismatic";
        if let Some(t) = self.ini.get(&sec, "TYPE") {
            let want = if linear { "LINEAR" } else { "ANGULAR" };
            if !t.value.eq_ignore_ascii_case(want) {
                return Err(self.ini.error(
                    t,
                    format!(
                        "joint {i} is axis {letter}: expected TYPE = {want}, found `{}`",
                        t.value
                    ),
                ));
            }
        }
        let k = if linear {
            self.units.mm
        } else {
            self.units.deg
        };
        let unit = if linear {
            self.units.linear
        } else {
            self.units.angular
        };
        let lo = self.number(&sec, "MIN_LIMIT")?;
        let hi = self.number(&sec, "MAX_LIMIT")?;
        let (Some((lo, el)), Some((hi, eh))) = (lo, hi) else {
            return Err(super::file_error(
                &self.ini.file,
                None,
                &format!("[{sec}] MIN_LIMIT, MAX_LIMIT"),
                format!("axis {letter}'s travel is needed"),
            ));
        };
        if !(lo < hi) {
            return Err(self.ini.error(
                &eh,
                format!("the travel [{lo}, {hi}] of joint {i} is empty"),
            ));
        }
        let mut fields = vec![
            format!("name = \"{letter}\""),
            format!("type = \"{kind}\""),
            format!("range = [{}, {}]", fmt_num(lo * k), fmt_num(hi * k)),
        ];
        let mut notes = vec![format!(
            "[{sec}] MIN_LIMIT {} ({}), MAX_LIMIT {} {unit} ({})",
            fmt_num(lo),
            self.ini.at(&el),
            fmt_num(hi),
            self.ini.at(&eh)
        )];
        for r in self.rates(&sec)? {
            fields.push(format!("{} = {}", r.field, fmt_num(r.value * k)));
            notes.push(format!(
                "{} {} {unit}{} ({})",
                r.key,
                fmt_num(r.value),
                r.per,
                r.at
            ));
        }
        self.line(format!("# {}", notes.join(", ")));
        self.line(format!("joint = {{ {} }}", fields.join(", ")));
        Ok(())
    }

    /// `[home] joints` from `[JOINT_n] HOME`; then the file is checked by loading it.
    fn trt_home(&mut self, letters: &[char; 5]) -> Result<()> {
        let mut v = Vec::new();
        let mut notes = Vec::new();
        for (i, l) in letters.iter().enumerate() {
            let k = if i < 3 { self.units.mm } else { self.units.deg };
            match self.number(&format!("JOINT_{i}"), "HOME")? {
                Some((h, e)) => {
                    v.push(fmt_num(h * k));
                    notes.push(format!("{l} {} ({})", fmt_num(h), self.ini.at(&e)));
                }
                None => {
                    v.push("0.0".into());
                    notes.push(format!("{l} 0 (no HOME)"));
                }
            }
        }
        self.line("");
        self.line("[home]");
        self.line(format!("# [JOINT_n] HOME: {}", notes.join(", ")));
        self.line(format!("joints = [{}]", v.join(", ")));
        Ok(())
    }

    /// Checks the file written by loading it.
    pub(super) fn trt_finish(self) -> Result<Imported> {
        self.load()?;
        Ok(Imported {
            toml: self.out,
            kinematics: self.kins.module(),
            warnings: self.warnings,
        })
    }
}
