//! URDF robots as serial machines: the chain from the root link to the deepest leaf
//! (most movable joints), metres converted to millimetres.
//!
//! A URDF joint turns about (or slides along) an arbitrary unit `axis` of its frame,
//! placed by `origin` (xyz, rpy = `Rz(y) Ry(p) Rx(r)`) in the parent link's frame.
//! Seed 003's chain turns about Z: with `R_a` the smallest rotation taking Z to the
//! axis, the joint's motion is `R_a J_z(q) R_a^T`, so each link's fixed transform is
//! `R_a(prev)^T * origins up to the next joint * R_a(next)`.

use nalgebra::{Matrix3, Matrix4, Rotation3, Unit, Vector3};

use super::Model;
use crate::error::Error;
use crate::limits::Range;
use crate::serial::machine::SerialMachine;
use crate::serial::mechanism::SerialAny;
use crate::serial::{Chain, Inertial, Joint, JointKind, Link, SerialModel};

/// A machine-file error of `file` with `message`.
fn err(file: &str, message: String) -> Error {
    Error::MachineFile {
        file: file.into(),
        line: None,
        column: None,
        field: String::new(),
        message,
    }
}

/// The transform of a URDF origin (metres to millimetres).
fn origin(o: &urdf_rs::Pose) -> Matrix4<f64> {
    let r = crate::rotation::rpy_matrix(o.rpy[0], o.rpy[1], o.rpy[2]);
    let mut m = Matrix4::identity();
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
    for k in 0..3 {
        m[(k, 3)] = 1000.0 * o.xyz[k];
    }
    m
}

/// The smallest rotation taking Z to `a` (unit).
fn align_z(a: &Vector3<f64>) -> Matrix3<f64> {
    Rotation3::rotation_between(&Vector3::z(), a)
        .unwrap_or_else(|| {
            Rotation3::from_axis_angle(&Unit::new_normalize(Vector3::x()), std::f64::consts::PI)
        })
        .into_inner()
}

/// A chain link named `name`, moved by `joint`, with the fixed transform `t`.
fn link(name: &str, joint: Option<Joint>, t: &Matrix4<f64>) -> Link {
    Link {
        name: name.into(),
        joint,
        translation: Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]),
        rotation: t.fixed_view::<3, 3>(0, 0).into_owned(),
        inertial: None,
    }
}

/// Parses a URDF text into the machine parts (`file` names it in errors).
pub(super) fn build(text: &str, file: &str) -> Result<super::Parts, Error> {
    let robot = urdf_rs::read_from_string(text)
        .map_err(|e| err(file, format!("not a readable URDF: {e}")))?;
    let root = root_link(&robot, file)?;
    let Branch { movable: n, joints } = longest_branch(&robot, root, 0);
    if n == 0 || n > 8 {
        return Err(err(
            file,
            format!("expected a chain of 1 to 8 movable joints from `{root}`, found {n}"),
        ));
    }
    check_joint_kinds(&joints, file)?;
    check_magnitudes(&joints, file)?;
    let links = chain_links(&robot, root, &joints, file)?;
    let machine = SerialMachine {
        name: if robot.name.is_empty() {
            "URDF robot".into()
        } else {
            robot.name.clone()
        },
        tool: Chain {
            name: "tool".into(),
            links,
        },
        workpiece: None,
    };
    let home: Vec<f64> = machine
        .tool
        .joints()
        .map(|j| 0.0f64.clamp(j.range.min, j.range.max))
        .collect();
    // A six-joint robot takes tool poses; other chains their joint values.
    let mechanism = if SerialAny::can_be_spatial(&machine) {
        SerialAny::spatial(machine, &home)
    } else {
        SerialAny::new(machine, &home)
    }
    .map_err(|e| err(file, e.to_string()))?;
    Ok(super::Parts {
        model: Model::Serial(Box::new(SerialModel {
            mechanism,
            tolerances: Vec::new(),
        })),
        name: Some(robot.name.clone()),
        description: Some(format!(
            "URDF robot `{}`: chain from `{root}`, {n} movable joints (mm, from metres)",
            robot.name
        )),
        references: Vec::new(),
        rapid: None,
    })
}

/// The robot's one root link: the one no joint has as its child.
fn root_link<'a>(robot: &'a urdf_rs::Robot, file: &str) -> Result<&'a str, Error> {
    let children: std::collections::BTreeSet<&str> =
        robot.joints.iter().map(|j| j.child.link.as_str()).collect();
    let roots: Vec<&str> = robot
        .links
        .iter()
        .map(|l| l.name.as_str())
        .filter(|n| !children.contains(n))
        .collect();
    let [root] = roots.as_slice() else {
        return Err(err(
            file,
            format!("expected one root link, found {}: {:?}", roots.len(), roots),
        ));
    };
    Ok(root)
}

/// Whether joint `j` moves (revolute, continuous or prismatic).
fn movable(j: &urdf_rs::Joint) -> bool {
    matches!(
        j.joint_type,
        urdf_rs::JointType::Revolute
            | urdf_rs::JointType::Continuous
            | urdf_rs::JointType::Prismatic
    )
}

/// A branch of joints below a link: how many of them move, and the joints in order.
struct Branch<'a> {
    /// Movable joints.
    movable: usize,
    /// The joints from the link down.
    joints: Vec<&'a urdf_rs::Joint>,
}

/// The longest branch (most movable joints; the first of equals) below `link`, by
/// depth-first search; `seen` joints above it (a cycle ends past all of them).
fn longest_branch<'a>(robot: &'a urdf_rs::Robot, link: &str, seen: usize) -> Branch<'a> {
    let mut best = Branch {
        movable: 0,
        joints: Vec::new(),
    };
    if seen > robot.joints.len() {
        return best;
    }
    for j in robot.joints.iter().filter(|j| j.parent.link == link) {
        let mut below = longest_branch(robot, &j.child.link, seen + 1);
        let d = below.movable + movable(j) as usize;
        if d > best.movable || best.joints.is_empty() {
            below.joints.insert(0, j);
            best = Branch {
                movable: d,
                joints: below.joints,
            };
        }
    }
    best
}

/// Refuses joints that do not form a serial chain (floating, planar, spherical).
fn check_joint_kinds(joints: &[&urdf_rs::Joint], file: &str) -> Result<(), Error> {
    for j in joints {
        if matches!(
            j.joint_type,
            urdf_rs::JointType::Floating
                | urdf_rs::JointType::Planar
                | urdf_rs::JointType::Spherical
        ) {
            return Err(err(file, format!("joint `{}`: only revolute, continuous, prismatic and fixed joints form a serial chain", j.name)));
        }
    }
    Ok(())
}

/// The same sane magnitudes as machine files (metres and radians here: 1e3 m, 1e4
/// rad), before any of them is computed with.
fn check_magnitudes(joints: &[&urdf_rs::Joint], file: &str) -> Result<(), Error> {
    for j in joints {
        let values = [
            ("origin xyz", &j.origin.xyz[..], 1e3),
            ("origin rpy", &j.origin.rpy[..], 1e4),
            ("axis", &j.axis.xyz[..], 1e6),
            ("limit", &[j.limit.lower, j.limit.upper][..], 1e4),
        ];
        for (what, v, max) in values {
            if let Some(x) = v.iter().find(|x| !(x.abs() <= max)) {
                return Err(err(
                    file,
                    format!(
                        "joint `{}`: {what} value {x:e} is beyond +-{max:e}, the largest \
                         pkm takes (no robot has it)",
                        j.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// A link whose fixed transform is still being accumulated: its name and the joint
/// that moves it (none for the root).
struct PendingLink {
    /// Link name.
    name: String,
    /// Its joint.
    joint: Option<Joint>,
    /// Its mass properties so far, in its URDF link frame (mm, kg mm^2): the link's
    /// own and those of the links fixed to it.
    body: Option<Inertial>,
    /// The URDF frame reached from it through fixed joints (mm).
    at: Matrix4<f64>,
}

impl PendingLink {
    fn new(name: &str, joint: Option<Joint>, robot: &urdf_rs::Robot) -> Self {
        let mut p = PendingLink {
            name: name.to_string(),
            joint,
            body: None,
            at: Matrix4::identity(),
        };
        p.add(robot, name);
        p
    }

    /// Joins the mass properties of URDF link `name` (at the frame `at`).
    fn add(&mut self, robot: &urdf_rs::Robot, name: &str) {
        let Some(b) = robot
            .links
            .iter()
            .find(|l| l.name == name)
            .and_then(inertial)
        else {
            return;
        };
        let r = self.at.fixed_view::<3, 3>(0, 0).into_owned();
        let p = Vector3::new(self.at[(0, 3)], self.at[(1, 3)], self.at[(2, 3)]);
        let b = b.transformed(&r, &p);
        self.body = Some(self.body.map_or(b, |a| a.joined(&b)));
    }

    /// The finished link: mass properties in the chain's frame `S_i`, whose rotation
    /// from the URDF link frame is `ra` (the joint's Z turned onto its axis).
    fn link(self, ra: &Matrix3<f64>, t: &Matrix4<f64>) -> Link {
        let mut l = link(&self.name, self.joint, t);
        l.inertial = self
            .body
            .map(|b| b.transformed(&ra.transpose(), &Vector3::zeros()));
        l
    }
}

/// A URDF link's `<inertial>` in its frame (mm, kg, kg mm^2); `None` without mass.
fn inertial(l: &urdf_rs::Link) -> Option<Inertial> {
    let i = &l.inertial;
    if !(i.mass.value > 0.0) {
        return None;
    }
    let t = origin(&i.origin);
    let c = &i.inertia;
    let local = Matrix3::new(
        c.ixx, c.ixy, c.ixz, c.ixy, c.iyy, c.iyz, c.ixz, c.iyz, c.izz,
    ) * 1e6;
    let r = t.fixed_view::<3, 3>(0, 0).into_owned();
    Some(Inertial {
        mass: i.mass.value,
        com: Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]),
        inertia: r * local * r.transpose(),
    })
}

/// The links of the chain from `root` through `joints`: each movable joint's motion
/// about its link's Z, the fixed joints and origins folded into the transforms, the
/// mass properties of every link on the way in the frame of the moving link they are
/// fixed to.
fn chain_links(
    robot: &urdf_rs::Robot,
    root: &str,
    joints: &[&urdf_rs::Joint],
    file: &str,
) -> Result<Vec<Link>, Error> {
    let mut links = Vec::new();
    let mut acc = Matrix4::identity();
    let mut pending = PendingLink::new(root, None, robot);
    let mut ra_prev = Matrix3::identity();
    for j in joints {
        acc *= origin(&j.origin);
        if !movable(j) {
            pending.at *= origin(&j.origin);
            pending.add(robot, &j.child.link);
            continue;
        }
        let a = Vector3::new(j.axis.xyz[0], j.axis.xyz[1], j.axis.xyz[2]);
        if !(a.norm() > 1e-12) {
            return Err(err(file, format!("joint `{}`: zero axis", j.name)));
        }
        let ra = align_z(&a.normalize());
        let mut r4 = Matrix4::identity();
        r4.fixed_view_mut::<3, 3>(0, 0).copy_from(&ra);
        acc *= r4;
        let next = PendingLink::new(&j.child.link, Some(chain_joint(j, file)?), robot);
        links.push(std::mem::replace(&mut pending, next).link(&ra_prev, &acc));
        ra_prev = ra;
        acc = r4.transpose();
    }
    links.push(pending.link(&ra_prev, &acc));
    Ok(links)
}

/// An angle limit `v` (rad) as the file states it: a URDF writes radians rounded to a
/// few decimals (`6.2832` for a joint that turns a whole turn either way), which
/// printed in degrees reads 360.001. When a whole, tenth, hundredth or thousandth of
/// a degree lies within half a unit of the last decimal written, and says the angle
/// in fewer significant digits than the radians do, that degree value is the limit
/// (6.2832: 360 deg; 1.5708: 90 deg); otherwise `v` as written (1.5 stays 1.5 rad,
/// not 86 deg). The change is below the precision the file states.
pub(crate) fn stated_angle(v: f64) -> f64 {
    if !v.is_finite() || v == 0.0 {
        return v;
    }
    // The shortest decimal that reads back as `v` (Rust prints no exponent).
    let text = format!("{}", v.abs());
    let (int, frac) = text.split_once('.').unwrap_or((&text, ""));
    let significant = |s: String| s.trim_start_matches('0').trim_end_matches('0').len();
    let written = significant(format!("{int}{frac}"));
    let half = (0.5 * 10f64.powi(-(frac.len() as i32))).to_degrees();
    let deg = v.to_degrees();
    for per_degree in [1.0, 10.0, 100.0, 1000.0] {
        let snapped = (deg * per_degree).round() / per_degree;
        let digits = significant(format!("{}", (snapped * per_degree).round().abs()));
        if (snapped - deg).abs() <= half && digits < written {
            return snapped.to_radians();
        }
    }
    v
}

/// The chain joint of movable URDF joint `j`: its kind and range (mm or rad; a
/// continuous joint turns two turns either way).
fn chain_joint(j: &urdf_rs::Joint, file: &str) -> Result<Joint, Error> {
    let (kind, range) = match j.joint_type {
        urdf_rs::JointType::Prismatic => (
            JointKind::Prismatic,
            Range {
                min: 1000.0 * j.limit.lower,
                max: 1000.0 * j.limit.upper,
            },
        ),
        urdf_rs::JointType::Continuous => (
            JointKind::Revolute,
            Range {
                min: -2.0 * std::f64::consts::PI,
                max: 2.0 * std::f64::consts::PI,
            },
        ),
        _ => (
            JointKind::Revolute,
            Range {
                min: stated_angle(j.limit.lower),
                max: stated_angle(j.limit.upper),
            },
        ),
    };
    if !(range.min < range.max) {
        return Err(err(
            file,
            format!(
                "joint `{}`: limits lower {} >= upper {}",
                j.name, j.limit.lower, j.limit.upper
            ),
        ));
    }
    Ok(Joint {
        name: j.name.clone(),
        kind,
        range,
        max_velocity: None,
        max_acceleration: None,
        stiffness: None,
    })
}

#[cfg(test)]
mod tests {
    use super::stated_angle;

    /// A limit written as radians rounded to a few decimals is the degree value it
    /// stands for; one that is round in radians stays as written.
    // The literals are the rounded radians a URDF writes, not approximations of pi.
    #[allow(clippy::approx_constant)]
    #[test]
    fn angle_limits_read_as_the_file_states_them() {
        let deg = |v: f64| stated_angle(v).to_degrees();
        for (written, meant) in [
            (6.2832, 360.0),
            (-6.2832, -360.0),
            (3.1416, 180.0),
            (1.5708, 90.0),
            (0.7854, 45.0),
            (2.0944, 120.0),
            (6.283185307179586, 360.0),
            (-2.967, -170.0),
        ] {
            assert!(
                (deg(written) - meant).abs() < 1e-12,
                "{written}: {}",
                deg(written)
            );
            // Within half a unit of the last decimal written.
            assert!(
                (stated_angle(written) - written).abs() <= 0.5e-3,
                "{written}"
            );
        }
        for round in [1.5, 2.0, 0.5, -1.0, 0.0, 1.2345678, 3.0] {
            assert_eq!(stated_angle(round), round, "{round}");
        }
    }
}
