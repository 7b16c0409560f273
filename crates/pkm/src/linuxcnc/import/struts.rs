//! The strut machines' modules: `genhexkins` (hexapod), `pentakins` (pentapod) and
//! `tripodkins` (tripod). Each writes its joints from the HAL's geometry parameters (the
//! module's compiled-in defaults for what the HAL leaves unset), then each strut's
//! stroke and rates from `[JOINT_n]`.

use super::{fmt_num, join_origins, Writer, OPEN_STROKE};
use crate::error::Result;
use crate::linuxcnc::ini::{file_error, IniEntry};

impl Writer<'_> {
    fn point(
        &mut self,
        prefix: &str,
        i: usize,
        default: [f64; 3],
        z_offset: f64,
    ) -> Result<([f64; 3], String)> {
        let mut v = [0.0; 3];
        let mut origins = Vec::new();
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            let p = self.param(
                &format!("{}.{prefix}.{i}.{axis}", self.kins.module()),
                default[k],
            )?;
            v[k] = p.value;
            origins.push(p.origin);
        }
        v[2] += z_offset;
        let origin = join_origins(&origins);
        let comment = format!(
            "{}.{prefix}.{i} = ({}, {}, {}) {}{}: {origin}",
            self.kins.module(),
            fmt_num(v[0]),
            fmt_num(v[1]),
            fmt_num(v[2] - z_offset),
            self.units.linear,
            if z_offset != 0.0 {
                format!(" + offset {} on z", fmt_num(z_offset))
            } else {
                String::new()
            }
        );
        Ok((v.map(|c| c * self.units.mm), comment))
    }

    pub(super) fn genhex(&mut self) -> Result<()> {
        let lead = self.param("genhexkins.screw-lead", 0.0)?;
        if lead.value != 0.0 {
            let line = self
                .hal
                .setp
                .get("genhexkins.screw-lead")
                .map(|v| (v.file.clone(), v.line));
            let (file, line) = line.unwrap_or((self.ini.file.clone(), 0));
            return Err(file_error(
                &file,
                (line > 0).then_some(line),
                "genhexkins.screw-lead",
                format!(
                    "screw-lead {} corrects strut lengths for non-captive screws turning with \
                     the joints; pkm's hexapod has no such correction (set it to 0 to import \
                     the geometry alone)",
                    lead.value
                ),
            ));
        }
        let spindle = self.param("genhexkins.spindle-offset", 0.0)?;
        let tool = self.param("genhexkins.tool-offset", 0.0)?;
        let off = spindle.value + tool.value;
        let mut base = Vec::new();
        let mut plat = Vec::new();
        for i in 0..6 {
            base.push(self.point("base", i, crate::linuxcnc::GENHEX_BASE[i], off)?);
            plat.push(self.point("platform", i, crate::linuxcnc::GENHEX_PLATFORM[i], off)?);
        }
        if off != 0.0 {
            self.line(format!(
                "# genhexkins adds spindle-offset ({}, {}) + tool-offset ({}, {}) to every joint's z.",
                fmt_num(spindle.value),
                spindle.origin,
                fmt_num(tool.value),
                tool.origin
            ));
        }
        let base_names = self.joint_table("base_joints", "B", &base);
        let plat_names = self.joint_table("platform_joints", "P", &plat);
        for i in 0..6 {
            self.line("");
            self.line("[[struts]]");
            self.line(format!("name = \"{i}\""));
            self.line(format!("base = \"{}\"", base_names[i]));
            self.line(format!("platform = \"{}\"", plat_names[i]));
            self.joint(i)?;
        }
        self.line("");
        self.line("[tool]");
        self.line("tip = [0.0, 0.0, 0.0]  # genhexkins controls the platform frame's origin");
        self.limits()?;
        self.home()?;
        Ok(())
    }

    pub(super) fn penta(&mut self) -> Result<()> {
        let tool = self.param("pentakins.tool-offset", 0.0)?;
        let mut base = Vec::new();
        for i in 0..5 {
            base.push(self.point("base", i, crate::linuxcnc::PENTA_BASE[i], tool.value)?);
        }
        if tool.value != 0.0 {
            self.line(format!(
                "# pentakins adds tool-offset ({}, {}) to the base joints' z and the rings' heights.",
                fmt_num(tool.value),
                tool.origin
            ));
        }
        let names = self.joint_table("base_joints", "B", &base);
        for i in 0..5 {
            let r = self.param(
                &format!("pentakins.effector.{i}.r"),
                crate::linuxcnc::PENTA_RING[i][0],
            )?;
            let z = self.param(
                &format!("pentakins.effector.{i}.z"),
                crate::linuxcnc::PENTA_RING[i][1],
            )?;
            self.line("");
            self.line("[[struts]]");
            self.line(format!("name = \"{i}\""));
            self.line(format!("base = \"{}\"", names[i]));
            self.line(format!(
                "ring_radius = {}  # pentakins.effector.{i}.r = {} {}: {}",
                fmt_num(r.value * self.units.mm),
                fmt_num(r.value),
                self.units.linear,
                r.origin
            ));
            self.line(format!(
                "ring_height = {}  # pentakins.effector.{i}.z = {} {}: {}",
                fmt_num((z.value + tool.value) * self.units.mm),
                fmt_num(z.value),
                self.units.linear,
                z.origin
            ));
            self.joint(i)?;
        }
        self.line("");
        self.line("[tool]");
        self.line("tip = [0.0, 0.0, 0.0]  # pentakins controls the effector frame's origin");
        self.limits()?;
        self.home()?;
        Ok(())
    }

    /// tripodkins: base joints A = (0, 0, 0), B = (Bx, 0, 0), C = (Cx, Cy, 0) and the
    /// controlled point D, where the three struts meet: a translational tripod with one
    /// platform joint shared by the struts and the tool tip in it.
    pub(super) fn tripod(&mut self) -> Result<()> {
        let k = self.units.mm;
        let u = self.units.linear;
        let mut v = Vec::new();
        for name in ["Bx", "Cx", "Cy"] {
            let p = self.param(
                &format!("tripodkins.{name}"),
                crate::linuxcnc::TRIPOD_DEFAULT,
            )?;
            if p.origin.ends_with(" default") {
                self.warnings.push(format!(
                    "tripodkins.{name} is not set by the HAL: tripodkins' default {} {u} is \
                     used, as in LinuxCNC",
                    fmt_num(p.value)
                ));
            }
            v.push(p);
        }
        let [bx, cx, cy] = [0, 1, 2].map(|i| v[i].value);
        self.line("# tripodkins' struts meet in the controlled point D; nothing turns it, so");
        self.line(
            "# the tripod is translational with one platform joint D and the tool tip in it.",
        );
        self.line("constraint = \"translational\"");
        self.line("");
        self.line("[base_joints]");
        self.line("A = [0.0, 0.0, 0.0]  # tripodkins' origin");
        self.line(format!(
            "B = [{}, 0.0, 0.0]  # tripodkins.Bx = {} {u}: {}",
            fmt_num(bx * k),
            fmt_num(bx),
            v[0].origin
        ));
        self.line(format!(
            "C = [{}, {}, 0.0]  # tripodkins.Cx = {} {u}: {}; tripodkins.Cy = {} {u}: {}",
            fmt_num(cx * k),
            fmt_num(cy * k),
            fmt_num(cx),
            v[1].origin,
            fmt_num(cy),
            v[2].origin
        ));
        self.line("");
        self.line("[platform_joints]");
        self.line("D = [0.0, 0.0, 0.0]  # the controlled point, where the struts meet");
        for (i, base) in ["A", "B", "C"].iter().enumerate() {
            self.line("");
            self.line("[[struts]]");
            self.line(format!("name = \"{i}\"  # joint {i}: strut {base}D"));
            self.line(format!("base = \"{base}\""));
            self.line("platform = \"D\"");
            self.joint(i)?;
        }
        self.line("");
        self.line("[tool]");
        self.line("tip = [0.0, 0.0, 0.0]  # tripodkins controls D itself");
        self.limits()?;
        self.home()?;
        Ok(())
    }

    /// Writes joints `[table]`, one per distinct point (struts sharing a point share
    /// the joint, named after the first: `B0`, `B1`, `B3`); returns each strut's joint.
    fn joint_table(
        &mut self,
        table: &str,
        prefix: &str,
        points: &[([f64; 3], String)],
    ) -> Vec<String> {
        self.line("");
        self.line(format!("[{table}]"));
        let mut names: Vec<String> = Vec::new();
        for (i, (p, comment)) in points.iter().enumerate() {
            if let Some(k) = (0..i).find(|k| points[*k].0 == *p) {
                let n = names[k].clone();
                self.line(format!("# strut {i}'s joint is {n}: {comment}"));
                names.push(n);
                continue;
            }
            let n = format!("{prefix}{i}");
            self.line(format!(
                "{n} = [{}, {}, {}]  # {comment}",
                fmt_num(p[0]),
                fmt_num(p[1]),
                fmt_num(p[2])
            ));
            names.push(n);
        }
        names
    }

    /// Stroke and rates of joint `i` (`[JOINT_i]`, lengths in the linear unit).
    fn joint(&mut self, i: usize) -> Result<()> {
        let sec = format!("JOINT_{i}");
        if let Some(t) = self.ini.get(&sec, "TYPE") {
            if !t.value.eq_ignore_ascii_case("LINEAR") {
                return Err(self
                    .ini
                    .error(t, format!("a strut's joint is LINEAR, found `{}`", t.value)));
            }
        }
        let k = self.units.mm;
        let u = self.units.linear;
        let min = self.number(&sec, "MIN_LIMIT")?;
        let max = self.number(&sec, "MAX_LIMIT")?;
        let (lo, lo_note) = self.stroke_min(min.as_ref());
        let (hi, hi_note) = self.stroke_max(&sec, max.as_ref());
        if !(hi > lo) {
            let e = max.as_ref().map(|m| m.1.clone());
            let msg = format!("the stroke [{}, {}] mm is empty", fmt_num(lo), fmt_num(hi));
            return Err(match e {
                Some(e) => self.ini.error(&e, msg),
                None => file_error(&self.ini.file, None, &format!("[{sec}] MAX_LIMIT"), msg),
            });
        }
        self.line(format!(
            "length = [{}, {}]  # [{sec}] {lo_note}, {hi_note}",
            fmt_num(lo),
            fmt_num(hi)
        ));
        for r in self.rates(&sec)? {
            self.line(format!(
                "{} = {}  # [{sec}] {} = {} {u}{} ({})",
                r.field,
                fmt_num(r.value * k),
                r.key,
                fmt_num(r.value),
                r.per,
                r.at
            ));
        }
        Ok(())
    }

    /// The stroke's lower end (mm) from `MIN_LIMIT` (0 when absent or below 0), and
    /// the note saying where it came from.
    fn stroke_min(&self, min: Option<&(f64, IniEntry)>) -> (f64, String) {
        let (k, u) = (self.units.mm, self.units.linear);
        match min {
            Some((v, e)) if *v >= 0.0 => (
                v * k,
                format!("MIN_LIMIT {} {u} ({})", fmt_num(*v), self.ini.at(e)),
            ),
            Some((v, e)) => (
                0.0,
                format!(
                    "MIN_LIMIT {} {u} ({}) is below 0: a strut is never shorter than 0",
                    fmt_num(*v),
                    self.ini.at(e)
                ),
            ),
            None => (0.0, "no MIN_LIMIT".into()),
        }
    }

    /// The stroke's upper end (mm) from `[sec] MAX_LIMIT` (at most [`OPEN_STROKE`], a
    /// warning when absent), and the note saying where it came from.
    fn stroke_max(&mut self, sec: &str, max: Option<&(f64, IniEntry)>) -> (f64, String) {
        let (k, u) = (self.units.mm, self.units.linear);
        match max {
            Some((v, e)) if v * k <= OPEN_STROKE => (
                v * k,
                format!("MAX_LIMIT {} {u} ({})", fmt_num(*v), self.ini.at(e)),
            ),
            Some((v, e)) => (
                OPEN_STROKE,
                format!(
                    "MAX_LIMIT {} {u} ({}) taken as {} mm",
                    fmt_num(*v),
                    self.ini.at(e),
                    fmt_num(OPEN_STROKE)
                ),
            ),
            None => {
                self.warnings.push(format!(
                    "[{sec}] has no MAX_LIMIT: the stroke is open up to {} mm",
                    fmt_num(OPEN_STROKE)
                ));
                (OPEN_STROKE, "no MAX_LIMIT".into())
            }
        }
    }
}
