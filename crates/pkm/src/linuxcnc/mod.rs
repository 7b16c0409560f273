//! LinuxCNC's parallel-machine and 5-axis configurations, both ways: [`import`] reads an
//! INI and the HAL files it names (genhexkins: a hexapod; pentakins: a pentapod;
//! tripodkins: a tripod whose struts meet in one point; xyzbc-trt-kins,
//! xyzac-trt-kins: a 5-axis mill with TCP coordinates) into a pkm
//! machine file; [`export`] writes a machine's geometry back as the HAL `setp` lines
//! and the INI's `[KINS]`, `[TRAJ]`, `[JOINT_n]` and `[AXIS_L]` entries, in the units
//! the controller uses (how an identified machine goes back to the controller).
//!
//! Conventions shared with the kinematics modules: genhexkins' pose is the platform
//! frame's origin with `R = Rz(C) Ry(B) Rx(A)` (`pmRpyMatConvert`), pkm's default
//! convention, so its X..C are pkm's with the tool tip at the platform origin;
//! pentakins' is the effector origin with `R = Ry(B) Rx(A)`, pkm's pentapod with C = 0;
//! tripodkins' is the point D where the struts meet, pkm's translational tripod with a
//! point platform (one platform joint shared by the three struts) and the tool tip in it.

mod export;
pub mod hal;
mod import;
pub mod ini;

pub use export::{export, Exported, LengthUnit};
pub use import::{import, import_with, Imported};

use nalgebra::Vector3;

use crate::limits::AxisLimits;

/// A kinematics module pkm reads and writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Kinematics {
    /// `genhexkins`: the hexapod.
    Genhex,
    /// `pentakins`: the pentapod.
    Penta,
    /// `tripodkins`: a tripod whose three struts meet in the controlled point.
    Tripod,
    /// `xyzbc-trt-kins`: a 5-axis mill with a table tilting about Y and turning about Z.
    XyzbcTrt,
    /// `xyzac-trt-kins`: a 5-axis mill with a table tilting about X and turning about Z.
    XyzacTrt,
}

impl Kinematics {
    /// The module named in `[KINS] KINEMATICS`.
    pub fn from_module(name: &str) -> Option<Kinematics> {
        match name {
            "genhexkins" => Some(Kinematics::Genhex),
            "pentakins" => Some(Kinematics::Penta),
            "tripodkins" => Some(Kinematics::Tripod),
            "xyzbc-trt-kins" => Some(Kinematics::XyzbcTrt),
            "xyzac-trt-kins" => Some(Kinematics::XyzacTrt),
            _ => None,
        }
    }

    /// The module's name (and its HAL prefix).
    pub fn module(self) -> &'static str {
        match self {
            Kinematics::Genhex => "genhexkins",
            Kinematics::Penta => "pentakins",
            Kinematics::Tripod => "tripodkins",
            Kinematics::XyzbcTrt => "xyzbc-trt-kins",
            Kinematics::XyzacTrt => "xyzac-trt-kins",
        }
    }

    /// pkm's machine type.
    pub fn machine_type(self) -> &'static str {
        match self {
            Kinematics::Genhex => "hexapod",
            Kinematics::Penta => "pentapod",
            Kinematics::Tripod => "tripod",
            Kinematics::XyzbcTrt | Kinematics::XyzacTrt => "serial",
        }
    }

    /// The coordinates the module controls, each with whether it is a length.
    pub fn coordinates(self) -> &'static [(&'static str, bool)] {
        match self {
            Kinematics::Genhex => &[
                ("X", true),
                ("Y", true),
                ("Z", true),
                ("A", false),
                ("B", false),
                ("C", false),
            ],
            Kinematics::Penta => &[
                ("X", true),
                ("Y", true),
                ("Z", true),
                ("A", false),
                ("B", false),
            ],
            Kinematics::Tripod => &[("X", true), ("Y", true), ("Z", true)],
            Kinematics::XyzbcTrt => &[
                ("X", true),
                ("Y", true),
                ("Z", true),
                ("B", false),
                ("C", false),
            ],
            Kinematics::XyzacTrt => &[
                ("X", true),
                ("Y", true),
                ("Z", true),
                ("A", false),
                ("C", false),
            ],
        }
    }
}

/// genhexkins.h's default base joints (world frame, the configuration's units).
pub(crate) const GENHEX_BASE: [[f64; 3]; 6] = [
    [-22.95, 13.25, 0.0],
    [22.95, 13.25, 0.0],
    [22.95, 13.25, 0.0],
    [0.0, -26.5, 0.0],
    [0.0, -26.5, 0.0],
    [-22.95, 13.25, 0.0],
];

/// genhexkins.h's default platform joints (platform frame).
pub(crate) const GENHEX_PLATFORM: [[f64; 3]; 6] = [
    [-1.0, 11.5, 0.0],
    [1.0, 11.5, 0.0],
    [10.459, -4.884, 0.0],
    [9.459, -6.616, 0.0],
    [-9.459, -6.616, 0.0],
    [-10.459, -4.884, 0.0],
];

/// pentakins.h's default base joints.
pub(crate) const PENTA_BASE: [[f64; 3]; 5] = [
    [-418.03, 324.56, 895.56],
    [417.96, 324.56, 895.56],
    [-418.03, -325.44, 895.56],
    [417.96, -325.44, 895.56],
    [-0.06, -492.96, 895.56],
];

/// pentakins.h's default rings: radius, height along the tool axis.
pub(crate) const PENTA_RING: [[f64; 2]; 5] = [
    [80.32, -185.5],
    [80.32, -159.5],
    [80.32, -67.5],
    [80.32, -41.5],
    [80.32, -14.0],
];

/// tripodkins' defaults of `Bx`, `Cx`, `Cy` (its `rtapi_app_main` sets all three to 1).
pub(crate) const TRIPOD_DEFAULT: f64 = 1.0;

/// A number as written into configuration files: 12 decimals at most, trailing zeros
/// dropped, always with a decimal point (TOML reads it as a float).
pub(crate) fn fmt_num(v: f64) -> String {
    let v = if v == 0.0 { 0.0 } else { v };
    let mut s = format!("{v:.12}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.push('0');
        }
    }
    if s == "-0.0" {
        s = "0.0".into();
    }
    s
}

/// What a controller needs of a machine: its kinematics module's geometry (relative to
/// the tool tip, which is the module's controlled point), the axis travel, the
/// calibrated zero lengths.
#[derive(Debug, Clone, PartialEq)]
pub struct ControllerModel {
    /// The geometry in mm.
    pub geometry: Geometry,
    /// Axis travel of the machine file.
    pub axes: AxisLimits,
    /// Strut lengths at the control's zero readings (`[calibration]`), if calibrated.
    pub zero_lengths: Option<Vec<f64>>,
}

/// A kinematics module's geometry (mm).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Geometry {
    /// genhexkins: base joints (world), platform joints relative to the tool tip
    /// (platform frame).
    Genhex {
        /// Base joints.
        base: [Vector3<f64>; 6],
        /// Platform joints minus the tool tip.
        platform: [Vector3<f64>; 6],
    },
    /// pentakins: base joints, ring radii, ring heights above the tool tip.
    Penta {
        /// Base joints.
        base: [Vector3<f64>; 5],
        /// Ring radii.
        radius: [f64; 5],
        /// Ring heights minus the tool tip's height.
        height: [f64; 5],
    },
    /// tripodkins: base joints A = (0, 0, 0), B = (`bx`, 0, 0), C = (`cx`, `cy`, 0); the
    /// struts meet in the controlled point D.
    Tripod {
        /// B's x.
        bx: f64,
        /// C's x.
        cx: f64,
        /// C's y.
        cy: f64,
    },
}

impl Geometry {
    /// The kinematics module of this geometry.
    pub fn kinematics(&self) -> Kinematics {
        match self {
            Geometry::Genhex { .. } => Kinematics::Genhex,
            Geometry::Penta { .. } => Kinematics::Penta,
            Geometry::Tripod { .. } => Kinematics::Tripod,
        }
    }
}

/// A translational tripod as tripodkins' geometry. At its held orientation `R` strut `i`
/// is `L_i = |p + R (c_i - t) - b_i| = |p - a_i|` with `a_i = b_i - R (c_i - t)`: a
/// tripod whose struts meet in the tool tip, from base points `a_i` (a point platform
/// with the tool tip in it has `a_i = b_i`). tripodkins fixes its world frame on them:
/// `a_0` the origin, `a_1` on the X axis, `a_2` in the XY plane; a
/// machine whose points lie otherwise is refused, naming the point and its offset.
pub(crate) fn tripod_geometry(t: &crate::tripod::TranslationalTripod) -> crate::Result<Geometry> {
    use crate::mechanism::Mechanism;
    let g = t.tripod_geometry();
    let (_, r) = crate::legs::split_pose(&t.info().home());
    let a: [Vector3<f64>; 3] =
        std::array::from_fn(|i| g.struts()[i].base - r * (g.struts()[i].platform - g.tool()));
    let scale = a.iter().map(|v| v.norm()).fold(1.0, f64::max);
    let tol = 1e-9 * scale;
    let off = [
        (
            "the first strut's base point, tripodkins' origin A",
            a[0].norm(),
        ),
        (
            "the second strut's base point B, on tripodkins' X axis (y = z = 0)",
            a[1].y.hypot(a[1].z),
        ),
        (
            "the third strut's base point C, in tripodkins' XY plane (z = 0)",
            a[2].z.abs(),
        ),
    ];
    for (what, d) in off {
        if d > tol {
            return Err(crate::Error::Unsupported {
                machine: t.info().name().to_string(),
                kind: t.info().kind().to_string(),
                analysis: "LinuxCNC export",
                reason: format!(
                    "tripodkins fixes its world frame on the struts' base points (A at the \
                     origin, B on X, C in the XY plane); {what} is {d:.6} mm off it (base \
                     points, each less its platform joint's offset from the tool tip: {})",
                    a.iter()
                        .map(|v| format!("({:.4}, {:.4}, {:.4})", v.x, v.y, v.z))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        }
    }
    Ok(Geometry::Tripod {
        bx: a[1].x,
        cx: a[2].x,
        cy: a[2].y,
    })
}
