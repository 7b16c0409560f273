//! The `type = "serial"` machine file: a tool chain and an optional workpiece chain of
//! links with seed 003's two frames per link, and tolerances of primary deviations.

use nalgebra::Matrix3;
use serde::Deserialize;

use super::reference::Reference;
use super::source::{Exact, Seg, Source};
use super::{v3, Model};
use crate::error::Error;
use crate::limits::Range;
use crate::serial::machine::SerialMachine;
use crate::serial::mechanism::SerialAny;
use crate::serial::{Chain, Joint, JointKind, Link};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SerialFile {
    #[serde(rename = "type")]
    _kind: String,
    /// `[[clearance]]` entries, read for every machine type by `clearance_file`.
    #[serde(default, rename = "clearance")]
    _clearance: Option<serde::de::IgnoredAny>,
    /// The `[report]` table, read for every machine type by `report_file`.
    #[serde(default, rename = "report")]
    _report: Option<serde::de::IgnoredAny>,
    #[serde(default)]
    name: Option<String>,
    #[serde(default)]
    description: Option<String>,
    #[serde(default)]
    tool_chain: Vec<LinkFile>,
    /// Standard Denavit-Hartenberg rows for the tool chain, instead of `tool_chain`.
    #[serde(default)]
    dh: Vec<DhFile>,
    /// Fixed transform from the last DH frame to the tool (flange -> tool tip).
    #[serde(default)]
    dh_tool: Option<DhToolFile>,
    #[serde(default)]
    workpiece_chain: Vec<LinkFile>,
    #[serde(default)]
    home: Option<HomeFile>,
    /// Pose coordinates: `tool` (X..C of the tool, six-joint robots) or `joints`.
    #[serde(default)]
    pose: Option<String>,
    #[serde(default)]
    tolerance: Vec<super::tolerance_file::ToleranceFile>,
    #[serde(default)]
    reference: Vec<Reference>,
    #[serde(default)]
    motion: Option<super::MotionFile>,
}

/// Three rows of three direction cosines, exactly.
type Rotation = Exact<3, Exact<3>>;

#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
struct LinkFile {
    name: String,
    #[serde(default)]
    joint: Option<JointFile>,
    #[serde(default)]
    translation: Exact<3>,
    #[serde(default)]
    rotation: Option<Rotation>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DhFile {
    joint: JointFile,
    a: f64,
    alpha: f64,
    d: f64,
    #[serde(default)]
    theta: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct DhToolFile {
    #[serde(default)]
    translation: Exact<3>,
    #[serde(default)]
    rotation: Option<Rotation>,
}

/// Standard Denavit-Hartenberg rows as seed-003 links: joint `i` turns about (or slides
/// along) Z, then `Rz(theta) Tz(d) Tx(a) Rx(alpha)` is the link's fixed transform
/// (`theta` the joint's zero offset, `d` the offset of a prismatic joint): block
/// `Rz(theta) Rx(alpha)`, translation `(a cos theta, a sin theta, d)`.
fn dh_links(rows: &[DhFile], tool: Option<&DhToolFile>) -> Vec<LinkFile> {
    let mut links = vec![LinkFile {
        name: "base".into(),
        joint: None,
        translation: Exact([0.0; 3]),
        rotation: None,
    }];
    for (i, r) in rows.iter().enumerate() {
        let (st, ct) = r.theta.to_radians().sin_cos();
        let (sa, ca) = r.alpha.to_radians().sin_cos();
        let rot = [
            [ct, -st * ca, st * sa],
            [st, ct * ca, -ct * sa],
            [0.0, sa, ca],
        ];
        links.push(LinkFile {
            name: format!("link {}", i + 1),
            joint: Some(JointFile {
                name: r.joint.name.clone(),
                kind: r.joint.kind.clone(),
                range: r.joint.range,
                max_velocity: r.joint.max_velocity,
                max_acceleration: r.joint.max_acceleration,
                stiffness: r.joint.stiffness,
            }),
            translation: Exact([r.a * ct, r.a * st, r.d]),
            rotation: Some(Exact(rot.map(Exact))),
        });
    }
    if let Some(t) = tool {
        links.push(LinkFile {
            name: "tool".into(),
            joint: None,
            translation: t.translation,
            rotation: t.rotation,
        });
    }
    links
}

#[derive(Debug, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
struct JointFile {
    name: String,
    #[serde(rename = "type")]
    kind: String,
    range: Exact<2>,
    /// Largest speed (mm/s or deg/s).
    #[serde(default)]
    max_velocity: Option<f64>,
    /// Largest acceleration (mm/s^2 or deg/s^2).
    #[serde(default)]
    max_acceleration: Option<f64>,
    /// Stiffness of the joint's drive (N/mm, or N mm/rad for a revolute joint).
    #[serde(default)]
    stiffness: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HomeFile {
    joints: Vec<f64>,
}

fn key(k: &str) -> Seg {
    Seg::Key(k.into())
}

/// Checks and builds a chain; `skip` leading links have no entry of their own in the
/// file (the base link DH rows get), so entry `i` of the file is link `i + skip`.
fn chain(
    src: &Source,
    field: &str,
    links: &[LinkFile],
    names: &mut Vec<String>,
    skip: usize,
) -> Result<Chain, Error> {
    let mut out = Vec::new();
    for (li, l) in links.iter().enumerate() {
        let i = li.saturating_sub(skip);
        let at = |k: &str| vec![key(field), Seg::Index(i), key(k)];
        let rotation = match l.rotation {
            None => Matrix3::identity(),
            Some(r) => link_rotation(src, &at("rotation"), r)?,
        };
        let joint = match &l.joint {
            None => None,
            Some(j) => {
                if li == 0 {
                    // The type is checked first.
                    joint_kind(src, &[key(field), Seg::Index(i)], j)?;
                    return Err(src.error(
                        &at("joint"),
                        "the first link of a chain is fixed (the bed or the chain's mount): no joint",
                    ));
                }
                Some(joint(src, &[key(field), Seg::Index(i)], j, names)?)
            }
        };
        out.push(Link {
            name: l.name.clone(),
            joint,
            translation: v3(l.translation),
            rotation,
            inertial: None,
        });
    }
    Ok(Chain {
        name: field.trim_end_matches("_chain").into(),
        links: out,
    })
}

/// A link's `rotation` (direction cosines), which must be a proper rotation.
fn link_rotation(src: &Source, at: &[Seg], r: Rotation) -> Result<Matrix3<f64>, Error> {
    let m = Matrix3::from_fn(|a, b| r[a][b]);
    let err = (m.transpose() * m - Matrix3::identity()).amax();
    if err > 1e-9 || m.determinant() < 0.0 {
        return Err(src.error(
            at,
            format!(
                "expected a proper rotation (direction cosines, rows: axes of S, columns: axes of S*); |R^T R - I| = {err:.2e}, det = {:.4}",
                m.determinant()
            ),
        ));
    }
    Ok(m)
}

/// The kind of joint `j` of the link at `link` (its path in the file).
fn joint_kind(src: &Source, link: &[Seg], j: &JointFile) -> Result<JointKind, Error> {
    match j.kind.as_str() {
        "revolute" => Ok(JointKind::Revolute),
        "prismatic" => Ok(JointKind::Prismatic),
        other => Err(src.error(
            &[link, &[key("joint"), key("type")]].concat(),
            format!("unknown joint type `{other}`, expected `revolute` or `prismatic`"),
        )),
    }
}

/// Joint `j` of the link at `link` (its path in the file): a name not in `names`
/// (added to it), an ordered range, rates > 0; mm and deg in the file, mm and rad out.
fn joint(
    src: &Source,
    link: &[Seg],
    j: &JointFile,
    names: &mut Vec<String>,
) -> Result<Joint, Error> {
    let at = |k: &str| [link, &[key("joint"), key(k)]].concat();
    let kind = joint_kind(src, link, j)?;
    if names.contains(&j.name) {
        return Err(src.error(
            &at("name"),
            format!("joint name `{}` is used twice", j.name),
        ));
    }
    names.push(j.name.clone());
    if !(j.range[0] < j.range[1]) {
        return Err(src.error(
            &at("range"),
            format!(
                "expected [min, max] with min < max, found [{}, {}]",
                j.range[0], j.range[1]
            ),
        ));
    }
    let conv = |v: f64| match kind {
        JointKind::Revolute => v.to_radians(),
        JointKind::Prismatic => v,
    };
    let rate = |v: Option<f64>, k: &str| match v {
        Some(r) if !(r > 0.0 && r <= super::MAX_MAGNITUDE) => Err(src.error(
            &at(k),
            format!("expected a rate > 0 (mm or deg per s, per s^2), found {r}"),
        )),
        v => Ok(v.map(conv)),
    };
    Ok(Joint {
        name: j.name.clone(),
        kind,
        range: Range {
            min: conv(j.range[0]),
            max: conv(j.range[1]),
        },
        max_velocity: rate(j.max_velocity, "max_velocity")?,
        max_acceleration: rate(j.max_acceleration, "max_acceleration")?,
        stiffness: {
            let unit = match kind {
                JointKind::Revolute => "N mm/rad",
                JointKind::Prismatic => "N/mm",
            };
            super::stiffness_opt(src, &at("stiffness"), j.stiffness, unit)?;
            j.stiffness
        },
    })
}

/// The machine parts of a serial machine file `f` (`src`: its text, for errors).
pub(super) fn build(src: &Source, f: SerialFile) -> Result<super::Parts, Error> {
    let machine = machine(src, &f)?;
    let kinds: Vec<JointKind> = machine
        .tool
        .joints()
        .chain(machine.workpiece.iter().flat_map(|w| w.joints()))
        .map(|j| j.kind)
        .collect();
    let home = home_joints(src, f.home.as_ref(), &kinds)?;
    if kinds.is_empty() || kinds.len() > 8 {
        return Err(src.error(
            &[key("tool_chain")],
            format!(
                "a serial machine needs 1 to 8 joints, found {}",
                kinds.len()
            ),
        ));
    }
    let tolerances = super::tolerance_file::tolerances(
        src,
        &crate::accuracy::serial_parameters(&machine),
        &f.tolerance,
    )?;
    // Each toleranced deviation must mean something: refused with the reason when it
    // cannot be given (an angle between aligned axes, a fourth angle of a link, ...).
    let given: Vec<usize> = tolerances.iter().map(|t| t.parameter).collect();
    crate::accuracy::serial_completions(&machine, &given)
        .map_err(|e| src.error(&[key("tolerance")], e.to_string()))?;
    let mechanism = mechanism(src, f.pose.as_deref(), machine, &home)?;
    let model = Model::Serial(Box::new(crate::serial::SerialModel {
        mechanism,
        tolerances,
    }));
    super::parts(src, model, f.name, f.description, f.reference, f.motion)
}

/// The chains of file `f`: the tool chain from `tool_chain` links or `dh` rows (one
/// of the two), and the workpiece chain when given.
fn machine(src: &Source, f: &SerialFile) -> Result<SerialMachine, Error> {
    if !f.dh.is_empty() && !f.tool_chain.is_empty() {
        return Err(src.error(
            &[key("dh")],
            "give the tool chain as `tool_chain` links or as `dh` rows, not both",
        ));
    }
    if f.tool_chain.is_empty() && f.dh.is_empty() {
        return Err(src.error(
            &[key("tool_chain")],
            "expected at least one link (or `dh` rows)",
        ));
    }
    let mut names = Vec::new();
    let tool = if f.dh.is_empty() {
        chain(src, "tool_chain", &f.tool_chain, &mut names, 0)?
    } else {
        let links = dh_links(&f.dh, f.dh_tool.as_ref());
        let mut c = chain(src, "dh", &links, &mut names, 1)?;
        c.name = "tool".into();
        c
    };
    let workpiece = if f.workpiece_chain.is_empty() {
        None
    } else {
        Some(chain(
            src,
            "workpiece_chain",
            &f.workpiece_chain,
            &mut names,
            0,
        )?)
    };
    Ok(SerialMachine {
        name: f.name.clone().unwrap_or_else(|| "serial machine".into()),
        tool,
        workpiece,
    })
}

/// The home joint values (mm, rad) of `[home] joints` (mm, deg), one per joint of
/// `kinds`; zero when not given.
fn home_joints(
    src: &Source,
    home: Option<&HomeFile>,
    kinds: &[JointKind],
) -> Result<Vec<f64>, Error> {
    let Some(h) = home else {
        return Ok(vec![0.0; kinds.len()]);
    };
    if h.joints.len() != kinds.len() {
        return Err(src.error(
            &[key("home"), key("joints")],
            format!(
                "expected {} joint values (mm, deg), found {}",
                kinds.len(),
                h.joints.len()
            ),
        ));
    }
    Ok(h.joints
        .iter()
        .zip(kinds)
        .map(|(v, k)| match k {
            JointKind::Revolute => v.to_radians(),
            JointKind::Prismatic => *v,
        })
        .collect())
}

/// The mechanism of `machine` at `home` in the coordinates `pose` names: `tool` (six
/// tool-chain joints), `tcp`, `joints`, or by default `tool` where it can be.
fn mechanism(
    src: &Source,
    pose: Option<&str>,
    machine: SerialMachine,
    home: &[f64],
) -> Result<SerialAny, Error> {
    let tcp = pose == Some("tcp");
    let spatial = match pose {
        None => SerialAny::can_be_spatial(&machine),
        Some("tcp") => false,
        Some("tool") => {
            if !SerialAny::can_be_spatial(&machine) {
                return Err(src.error(
                    &[key("pose")],
                    "`tool` coordinates need six tool-chain joints and no workpiece joints"
                        .to_string(),
                ));
            }
            true
        }
        Some("joints") => false,
        Some(other) => {
            return Err(src.error(
                &[key("pose")],
                format!("expected \"tool\", \"tcp\" or \"joints\", found \"{other}\""),
            ))
        }
    };
    if tcp {
        SerialAny::tcp(machine, home).map_err(|e| src.error(&[key("pose")], e.to_string()))
    } else if spatial {
        SerialAny::spatial(machine, home).map_err(|e| src.error(&[key("home")], e.to_string()))
    } else {
        SerialAny::new(machine, home).map_err(|e| src.error(&[key("home")], e.to_string()))
    }
}
