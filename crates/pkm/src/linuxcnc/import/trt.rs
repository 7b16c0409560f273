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

use super::writer::Param;
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

/// A vector as a TOML array.
fn row3(v: &Vector3<f64>) -> String {
    format!("[{}, {}, {}]", fmt_num(v.x), fmt_num(v.y), fmt_num(v.z))
}

/// A matrix as a TOML array of rows.
fn block(m: &Matrix3<f64>) -> String {
    let rows: Vec<String> = (0..3)
        .map(|r| row3(&m.row(r).transpose().into_owned()))
        .collect();
    format!("[{}]", rows.join(", "))
}

/// The geometry of a trt module, from its parameters (mm): where the table turns
/// and tilts, and the directions of its joints.
struct Trt {
    /// The tilt axis' letter (`A` or `B`).
    tilt: char,
    /// The world axis of the tilt's offset (0: X for XYZBC, 1: Y for XYZAC).
    offset_axis: usize,
    /// The joints' letters, in joint order.
    letters: [char; 5],
    /// `x/y/z-rot-point`.
    rot: [Param; 3],
    /// The name of the tilt's offset parameter (`x-offset` or `y-offset`).
    off_name: &'static str,
    /// The tilt's offset.
    off: Param,
    /// `z-offset`.
    zoff: Param,
    /// `tool-offset`.
    tool: Param,
    /// `conventional-directions`.
    conv: Param,
    /// The rotation point `r` (mm).
    r: Vector3<f64>,
    /// The offsets `d` from it to the tilt axis (mm).
    d: Vector3<f64>,
    /// The tilt joint's axis.
    tilt_axis: Vector3<f64>,
    /// The rotary joint's axis.
    rotary_axis: Vector3<f64>,
}

impl Writer<'_> {
    /// The TCP machine of a trt module.
    pub(super) fn trt(&mut self) -> Result<()> {
        let (tilt, offset_axis) = match self.kins {
            Kinematics::XyzacTrt => ('A', 1),
            _ => ('B', 0),
        };
        let letters = ['X', 'Y', 'Z', tilt, 'C'];
        self.check_coordinates(&letters)?;
        let t = self.trt_geometry(tilt, offset_axis, letters)?;
        self.warn_identity_first();
        self.trt_comments(&t);
        self.trt_tool_chain(&t)?;
        self.trt_workpiece_chain(&t)?;
        self.trt_home(&letters)
    }

    /// Refuses `[TRAJ] COORDINATES` other than `letters` in order.
    fn check_coordinates(&self, letters: &[char; 5]) -> Result<()> {
        let module = self.kins.module();
        let Some(e) = self.ini.get("TRAJ", "COORDINATES") else {
            return Ok(());
        };
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
        Ok(())
    }

    /// The module's parameters and the geometry they give.
    fn trt_geometry(&mut self, tilt: char, offset_axis: usize, letters: [char; 5]) -> Result<Trt> {
        let module = self.kins.module();
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
        Ok(Trt {
            tilt,
            offset_axis,
            letters,
            rot,
            off_name,
            off,
            zoff,
            tool,
            conv,
            r,
            d,
            tilt_axis,
            rotary_axis,
        })
    }

    /// Warns when the configuration starts in identity kinematics.
    fn warn_identity_first(&mut self) {
        let module = self.kins.module();
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
    }

    /// The pose line and the comments on the module's geometry and its parameters.
    fn trt_comments(&mut self, t: &Trt) {
        let module = self.kins.module();
        self.line(
            "pose = \"tcp\"  # X, Y, Z of the tool tip in the part frame, then the rotary axes",
        );
        self.line("");
        self.line(format!(
            "# {module}: table rotary axis C about the vertical through the rotation point,"
        ));
        self.line(format!(
            "# tilt axis {} about a line along {} through rotation point + offsets.",
            t.tilt,
            if t.offset_axis == 0 { "Y" } else { "X" }
        ));
        for (c, prm) in ["x", "y", "z"].iter().zip(&t.rot) {
            self.line(format!(
                "#   {c}-rot-point = {} {}: {}",
                fmt_num(prm.value),
                self.units.linear,
                prm.origin
            ));
        }
        for (n, prm) in [
            (t.off_name, &t.off),
            ("z-offset", &t.zoff),
            ("tool-offset", &t.tool),
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
            fmt_num(t.conv.value),
            t.conv.origin,
            row3(&t.tilt_axis),
            row3(&t.rotary_axis)
        ));
    }

    /// The tool chain: X, Y, Z slides; the tool tip tool-offset below the gauge point.
    fn trt_tool_chain(&mut self, t: &Trt) -> Result<()> {
        let k = self.units.mm;
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
                self.joint_line(i - 1, t.letters[i - 1], "prismatic")?;
            }
            if i == 3 {
                let tip = prev.transpose() * Vector3::new(0.0, 0.0, -t.tool.value * k);
                self.line(format!(
                    "translation = {}  # the tool tip tool-offset below the gauge point",
                    row3(&tip)
                ));
            }
            self.line(format!("rotation = {}", block(&(prev.transpose() * next))));
            prev = next;
        }
        Ok(())
    }

    /// The workpiece chain: mount at `r + d`, tilt, rotary at `r`, part frame.
    fn trt_workpiece_chain(&mut self, t: &Trt) -> Result<()> {
        let (r, d) = (t.r, t.d);
        let (ft, fc) = (frame(t.tilt_axis), frame(t.rotary_axis));
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
        self.joint_line(3, t.tilt, "revolute")?;
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
        Ok(())
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
