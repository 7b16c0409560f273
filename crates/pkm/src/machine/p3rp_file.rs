//! The `type = "p3rp"` machine file: the P3RP spindle head of seed 004, alone or with
//! an XY cross table (`[table]`) as the 4-axis hybrid machine.

use std::collections::BTreeMap;

use nalgebra::{Vector2, Vector6};
use serde::Deserialize;

use super::reference::Reference;
use super::source::{Exact, Seg, Source};
use super::Model;
use crate::error::Error;
use crate::limits::Range;
use crate::mechanism::{Actuator, Mechanism};
use crate::p3rp::{Branch, HeadGeometry, HybridMachine, P3rpHead};
use crate::units::Quantity;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct P3rpFile {
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
    head: HeadFile,
    sliders: BTreeMap<String, AxisFile>,
    #[serde(default)]
    table: Option<BTreeMap<String, AxisFile>>,
    #[serde(default)]
    limits: LimitsFile,
    home: HomeFile,
    #[serde(default)]
    reference: Vec<Reference>,
    #[serde(default)]
    motion: Option<super::MotionFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HeadFile {
    l1: f64,
    l2: f64,
    e: f64,
    delta: f64,
    #[serde(default)]
    tool_length: f64,
    #[serde(default)]
    branch: Option<Branch>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AxisFile {
    stroke: Exact<2>,
    #[serde(default)]
    max_velocity: Option<f64>,
    #[serde(default)]
    max_acceleration: Option<f64>,
    /// Axial stiffness (N/mm).
    #[serde(default)]
    stiffness: Option<f64>,
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct LimitsFile {
    #[serde(default)]
    theta: Option<Exact<2>>,
    #[serde(default)]
    rod_angle: Option<Exact<2>>,
    #[serde(default)]
    min_transmission_angle: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct HomeFile {
    z: f64,
    theta: f64,
    #[serde(default)]
    x: Option<f64>,
    #[serde(default)]
    y: Option<f64>,
}

impl<'de> Deserialize<'de> for Branch {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let s = String::deserialize(d)?;
        match s.as_str() {
            "positive" => Ok(Branch::Positive),
            "negative" => Ok(Branch::Negative),
            other => Err(serde::de::Error::custom(format!(
                "unknown branch `{other}`, expected `positive` or `negative`"
            ))),
        }
    }
}

fn key(k: &str) -> Seg {
    Seg::Key(k.into())
}

/// Checks the named axes of `[sliders]` or `[table]`: exactly `names`, in that order.
fn axes<const N: usize>(
    src: &Source,
    table: &str,
    map: &BTreeMap<String, AxisFile>,
    names: [&str; N],
) -> Result<[Actuator; N], Error> {
    if let Some(k) = map.keys().find(|k| !names.contains(&k.as_str())) {
        return Err(src.error(
            &[key(table), key(k)],
            format!("unknown axis `{k}`, expected {}", names.join(" and ")),
        ));
    }
    let mut out = Vec::with_capacity(N);
    for n in names {
        let Some(a) = map.get(n) else {
            return Err(src.error(
                &[key(table)],
                format!("missing axis `{n}`: expected {}", names.join(" and ")),
            ));
        };
        let p = |f: &str| vec![key(table), key(n), key(f)];
        if a.stroke[0] >= a.stroke[1] {
            return Err(src.error(
                &p("stroke"),
                format!(
                    "expected [min, max] with min < max, found [{}, {}]",
                    a.stroke[0], a.stroke[1]
                ),
            ));
        }
        super::positive_opt(src, &p("max_velocity"), a.max_velocity, "mm/s")?;
        super::positive_opt(src, &p("max_acceleration"), a.max_acceleration, "mm/s^2")?;
        super::stiffness_opt(src, &p("stiffness"), a.stiffness, "N/mm")?;
        out.push(Actuator {
            name: n.into(),
            quantity: Quantity::Length,
            range: Range {
                min: a.stroke[0],
                max: a.stroke[1],
            },
            max_velocity: a.max_velocity,
            max_acceleration: a.max_acceleration,
            stiffness: a.stiffness,
        });
    }
    Ok(out.try_into().expect("N axes pushed"))
}

fn angle_range(src: &Source, field: &str, r: Option<Exact<2>>) -> Result<Option<Range>, Error> {
    let Some(r) = r else { return Ok(None) };
    if !(r[0] < r[1]) || r[0] < -180.0 || r[1] > 180.0 {
        return Err(src.error(
            &[key("limits"), key(field)],
            format!(
                "expected [min, max] deg with -180 <= min < max <= 180, found [{}, {}]",
                r[0], r[1]
            ),
        ));
    }
    Ok(Some(Range {
        min: r[0].to_radians(),
        max: r[1].to_radians(),
    }))
}

pub(super) fn build(src: &Source, f: P3rpFile) -> Result<super::Parts, Error> {
    let geometry = head_geometry(src, &f.head, &f.limits)?;
    let sliders = axes(src, "sliders", &f.sliders, ["U", "V"])?;
    let name = f.name.clone().unwrap_or_else(|| "P3RP head".into());
    let head_home = Vector2::new(f.home.z, f.home.theta.to_radians());
    // The home pose must be an assembly of the head on its branch.
    let home_err = |e: Error| src.error(&[key("home")], format!("not a pose of the head: {e}"));
    let branch = geometry.branch_of(head_home[1]).map_err(home_err)?;
    if branch != geometry.branch {
        return Err(src.error(
            &[key("home")],
            format!(
                "the home pose lies on the {branch:?} branch, the head is assembled on the {:?} \
                 branch (`[head] branch`)",
                geometry.branch
            ),
        ));
    }
    let model = match &f.table {
        None => {
            if f.home.x.is_some() || f.home.y.is_some() {
                return Err(src.error(
                    &[key("home")],
                    "`x` and `y` are the table axes: they need a `[table]`",
                ));
            }
            let m = P3rpHead::new(name, geometry, sliders, head_home);
            m.inverse(&m.info().home()).map_err(home_err)?;
            Model::P3rpHead(Box::new(m))
        }
        Some(t) => {
            let [x, y] = axes(src, "table", t, ["X", "Y"])?;
            let home = hybrid_home(&f.home, geometry.tool_length, &head_home);
            let [u, v] = sliders;
            let m = HybridMachine::new(name, geometry, [x, y, u, v], home);
            m.inverse(&m.info().home()).map_err(home_err)?;
            Model::P3rpHybrid(Box::new(m))
        }
    };
    super::parts(src, model, f.name, f.description, f.reference, f.motion)
}

/// The head's geometry from `[head]` and `[limits]`, lengths and angles checked.
fn head_geometry(src: &Source, h: &HeadFile, lim: &LimitsFile) -> Result<HeadGeometry, Error> {
    for (field, v) in [("l1", h.l1), ("l2", h.l2)] {
        if !(v > 0.0) {
            return Err(src.error(
                &[key("head"), key(field)],
                format!("expected a length > 0 mm, found {v}"),
            ));
        }
    }
    if h.tool_length < 0.0 {
        return Err(src.error(
            &[key("head"), key("tool_length")],
            format!("expected a length >= 0 mm, found {}", h.tool_length),
        ));
    }
    let min_mu = match lim.min_transmission_angle {
        Some(a) if !(0.0..90.0).contains(&a) => {
            return Err(src.error(
                &[key("limits"), key("min_transmission_angle")],
                format!("expected an angle in [0, 90) deg, found {a}"),
            ))
        }
        a => a.map(f64::to_radians),
    };
    Ok(HeadGeometry {
        l1: h.l1,
        l2: h.l2,
        e: h.e,
        delta: h.delta.to_radians(),
        tool_length: h.tool_length,
        theta_range: angle_range(src, "theta", lim.theta)?,
        rod_angle_range: angle_range(src, "rod_angle", lim.rod_angle)?,
        min_transmission_angle: min_mu,
        branch: h.branch.unwrap_or(Branch::Positive),
        offsets: Default::default(),
    })
}

/// The hybrid machine's home pose: the table's `x`, `y` and the tool tip of the head
/// at `head_home` (slider height, tilt) with tool length `l`.
fn hybrid_home(home: &HomeFile, l: f64, head_home: &Vector2<f64>) -> Vector6<f64> {
    let (s, c) = head_home[1].sin_cos();
    Vector6::new(
        home.x.unwrap_or(0.0),
        home.y.unwrap_or(0.0) + l * s,
        head_home[0] - l * c,
        head_home[1],
        0.0,
        0.0,
    )
}
