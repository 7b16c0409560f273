//! Rewriting a strut machine's file (hexapod, tripod: `[base_joints]`,
//! `[platform_joints]`, `[[struts]]`) with identified joint coordinates.

use nalgebra::Vector3;

use super::source::{Seg, Source};
use crate::error::Error;

/// One strut's identified geometry.
#[derive(Debug, Clone, PartialEq)]
pub struct StrutGeometry {
    /// Strut (actuator) name.
    pub name: String,
    /// Its base joint's name in the file.
    pub base_name: String,
    /// Its platform joint's name in the file.
    pub platform_name: String,
    /// Base joint centre (mm).
    pub base: Vector3<f64>,
    /// Platform joint centre, platform frame (mm).
    pub platform: Vector3<f64>,
}

/// The machine file `text` rewritten with the joints of `struts` and the zero lengths
/// (`[calibration] zero_lengths`), everything else kept; `comment` lines go on top.
/// Struts that shared a joint get a joint each where identification moved it per strut
/// (`A1_L1`, ...), per-joint cone axes following; where their centres still agree
/// (held parameters, a point platform) the joint stays shared. The file's own comments
/// are not kept.
pub fn with_strut_geometry(
    text: &str,
    file: &str,
    struts: &[StrutGeometry],
    zero_lengths: Option<&[f64]>,
    comment: &str,
) -> Result<String, Error> {
    let src = Source::parse(file, text)?;
    let mut doc: toml::Table = toml::from_str(text).map_err(|e| src.error(&[], e.to_string()))?;
    for (table, role, axes) in [
        ("base_joints", "base", "base_joint_axes"),
        ("platform_joints", "platform", "platform_joint_axes"),
    ] {
        let renamed = write_joints(&src, &mut doc, struts, table, role)?;
        rename_joint_axes(&mut doc, axes, &renamed);
    }
    finish(&src, doc, zero_lengths, comment)
}

/// A vector as a TOML array.
fn xyz(v: &Vector3<f64>) -> toml::Value {
    toml::Value::Array(v.iter().map(|c| toml::Value::Float(*c)).collect())
}

/// Writes the `role` (`base` or `platform`) joints of `struts` as `table`: a joint
/// the struts share stays one where they still agree on its centre (held, or a point
/// platform), and splits where identification moved it per strut, the struts' entries
/// renamed to theirs. Returns the joints split, `(old name, new name)`.
fn write_joints(
    src: &Source,
    doc: &mut toml::Table,
    struts: &[StrutGeometry],
    table: &str,
    role: &str,
) -> Result<Vec<(String, String)>, Error> {
    let names: Vec<&str> = struts
        .iter()
        .map(|s| {
            if role == "base" {
                s.base_name.as_str()
            } else {
                s.platform_name.as_str()
            }
        })
        .collect();
    let centre = |s: &StrutGeometry| if role == "base" { s.base } else { s.platform };
    let mut joints = toml::Table::new();
    let mut renamed: Vec<(String, String)> = Vec::new();
    for (j, s) in struts.iter().enumerate() {
        let sharing = || (0..struts.len()).filter(|&k| names[k] == names[j]);
        let shared = sharing().count() > 1 && sharing().any(|k| centre(&struts[k]) != centre(s));
        let name = if shared {
            let n = format!("{}_{}", names[j], s.name);
            renamed.push((names[j].to_string(), n.clone()));
            n
        } else {
            names[j].to_string()
        };
        joints.insert(
            name.clone(),
            xyz(if role == "base" { &s.base } else { &s.platform }),
        );
        if shared {
            let list = doc
                .get_mut("struts")
                .and_then(|v| v.as_array_mut())
                .ok_or_else(|| {
                    src.error(&[Seg::Key("struts".into())], "expected an array of tables")
                })?;
            if let Some(t) = list.get_mut(j).and_then(|v| v.as_table_mut()) {
                t.insert(role.into(), toml::Value::String(name));
            }
        }
    }
    doc.insert(table.into(), toml::Value::Table(joints));
    Ok(renamed)
}

/// The per-joint cone axes (`[limits]` table `axes`) following the joints `renamed`.
fn rename_joint_axes(doc: &mut toml::Table, axes: &str, renamed: &[(String, String)]) {
    if let Some(ax) = doc
        .get_mut("limits")
        .and_then(|v| v.as_table_mut())
        .and_then(|l| l.get_mut(axes))
        .and_then(|v| v.as_table_mut())
    {
        for (old, new) in renamed {
            if let Some(v) = ax.get(old).cloned() {
                ax.insert(new.clone(), v);
            }
        }
        for (old, _) in renamed {
            ax.remove(old);
        }
    }
}

/// `[calibration] zero_lengths`, the comment on top, the text.
fn finish(
    src: &Source,
    mut doc: toml::Table,
    zero_lengths: Option<&[f64]>,
    comment: &str,
) -> Result<String, Error> {
    if let Some(z) = zero_lengths {
        let mut c = toml::Table::new();
        c.insert(
            "zero_lengths".into(),
            toml::Value::Array(z.iter().map(|v| toml::Value::Float(*v)).collect()),
        );
        doc.insert("calibration".into(), toml::Value::Table(c));
    }
    let body = toml::to_string(&doc).map_err(|e| src.error(&[], e.to_string()))?;
    let mut out = String::new();
    for l in comment.lines() {
        out.push_str("# ");
        out.push_str(l);
        out.push('\n');
    }
    out.push_str(&body);
    Ok(out)
}

/// The pentapod file `text` rewritten with the geometry of `m` (base joints, ring radii
/// and heights, tool tip) and the zero lengths, everything else kept; `comment` lines go
/// on top. Struts that shared a base joint get a joint each (`B0_L1`, ...) where their
/// centres differ, as [`with_strut_geometry`] does.
pub fn with_pentapod_geometry(
    text: &str,
    file: &str,
    m: &crate::pentapod::Pentapod,
    zero_lengths: Option<&[f64]>,
    comment: &str,
) -> Result<String, Error> {
    let src = Source::parse(file, text)?;
    let mut doc: toml::Table = toml::from_str(text).map_err(|e| src.error(&[], e.to_string()))?;
    let f = |v: f64| toml::Value::Float(v);
    let names: Vec<&str> = m
        .penta_struts()
        .iter()
        .map(|s| s.base_name.as_str())
        .collect();
    let mut joints = toml::Table::new();
    let list = doc
        .get_mut("struts")
        .and_then(|v| v.as_array_mut())
        .filter(|l| l.len() == m.penta_struts().len())
        .ok_or_else(|| src.error(&[Seg::Key("struts".into())], "expected 5 tables"))?;
    for (j, s) in m.penta_struts().iter().enumerate() {
        let sharing = || (0..names.len()).filter(|&k| names[k] == names[j]);
        let shared = sharing().count() > 1 && sharing().any(|k| m.penta_struts()[k].base != s.base);
        let name = if shared {
            format!("{}_{}", names[j], s.actuator.name)
        } else {
            names[j].to_string()
        };
        joints.insert(
            name.clone(),
            toml::Value::Array(s.base.iter().map(|c| f(*c)).collect()),
        );
        if let Some(t) = list[j].as_table_mut() {
            t.insert("base".into(), toml::Value::String(name));
            t.insert("ring_radius".into(), f(s.ring_radius));
            t.insert("ring_height".into(), f(s.ring_height));
        }
    }
    doc.insert("base_joints".into(), toml::Value::Table(joints));
    let mut tool = toml::Table::new();
    tool.insert(
        "tip".into(),
        toml::Value::Array(vec![f(0.0), f(0.0), f(m.tool_height())]),
    );
    doc.insert("tool".into(), toml::Value::Table(tool));
    finish(&src, doc, zero_lengths, comment)
}
