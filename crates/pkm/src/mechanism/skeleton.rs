//! The drawing of a mechanism at one pose: named points (joints, platform centre,
//! tool) and the links between them, as [`super::Mechanism::skeleton`] gives them for
//! the report's figures, the 3D view and the joint reports.

use serde::Serialize;

/// A named point of the mechanism at a pose, for drawings and joint reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SkeletonPoint {
    /// Joint or point name (`F`, `C`, `tool`).
    pub name: String,
    /// What it belongs to.
    pub role: PointRole,
    /// Position in the base frame (mm).
    pub position: [f64; 3],
}

/// What a skeleton point belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PointRole {
    /// A joint fixed to the base.
    BaseJoint,
    /// A joint on the moving platform.
    PlatformJoint,
    /// The centre of the moving platform.
    PlatformCentre,
    /// The tool tip.
    Tool,
    /// Any other point (passive joints, ...).
    Other,
}

/// A segment of the mechanism between two skeleton points.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SkeletonLink {
    /// Name (`e` for a strut), may be empty.
    pub name: String,
    /// What kind of body it is.
    pub kind: LinkKind,
    /// Index of the first point.
    pub from: usize,
    /// Index of the second point.
    pub to: usize,
}

/// Kind of a skeleton link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LinkKind {
    /// An actuated strut or leg.
    Strut,
    /// An edge of the fixed base.
    Base,
    /// An edge of the moving platform.
    Platform,
    /// The tool / spindle.
    Tool,
    /// A passive leg or link.
    Passive,
}

/// Points and links of a mechanism at one pose.
#[derive(Debug, Clone, PartialEq, Default, Serialize)]
pub struct Skeleton {
    /// Named points.
    pub points: Vec<SkeletonPoint>,
    /// Segments between points.
    pub links: Vec<SkeletonLink>,
}

impl Skeleton {
    /// Adds a point and returns its index.
    pub fn point(&mut self, name: &str, role: PointRole, p: &nalgebra::Vector3<f64>) -> usize {
        self.points.push(SkeletonPoint {
            name: name.into(),
            role,
            position: [p.x, p.y, p.z],
        });
        self.points.len() - 1
    }

    /// Adds a link between two point indices.
    pub fn link(&mut self, name: &str, kind: LinkKind, from: usize, to: usize) {
        self.links.push(SkeletonLink {
            name: name.into(),
            kind,
            from,
            to,
        });
    }
}
