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
use crate::serial::{Chain, Joint, JointKind, Link, SerialModel};

fn err(file: &str, message: String) -> Error {
    Error::MachineFile {
        file: file.into(),
        line: None,
        column: None,
        field: String::new(),
        message,
    }
}

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

fn link(name: &str, joint: Option<Joint>, t: &Matrix4<f64>) -> Link {
    Link {
        name: name.into(),
        joint,
        translation: Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)]),
        rotation: t.fixed_view::<3, 3>(0, 0).into_owned(),
    }
}

/// Parses a URDF text into the machine parts (`file` names it in errors).
pub(super) fn build(text: &str, file: &str) -> Result<super::Parts, Error> {
    let robot = urdf_rs::read_from_string(text)
        .map_err(|e| err(file, format!("not a readable URDF: {e}")))?;
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
    let movable = |j: &urdf_rs::Joint| {
        matches!(
            j.joint_type,
            urdf_rs::JointType::Revolute
                | urdf_rs::JointType::Continuous
                | urdf_rs::JointType::Prismatic
        )
    };
    // Longest branch (movable joints) below each link, by depth-first search.
    fn depth<'a>(
        robot: &'a urdf_rs::Robot,
        link: &str,
        movable: &dyn Fn(&urdf_rs::Joint) -> bool,
        seen: usize,
    ) -> (usize, Vec<&'a urdf_rs::Joint>) {
        if seen > robot.joints.len() {
            return (0, Vec::new());
        }
        let mut best = (0, Vec::new());
        for j in robot.joints.iter().filter(|j| j.parent.link == link) {
            let (d, mut path) = depth(robot, &j.child.link, movable, seen + 1);
            let d = d + movable(j) as usize;
            if d > best.0 || best.1.is_empty() {
                path.insert(0, j);
                best = (d, path);
            }
        }
        best
    }
    let (n, path) = depth(&robot, root, &movable, 0);
    if n == 0 || n > 8 {
        return Err(err(
            file,
            format!("expected a chain of 1 to 8 movable joints from `{root}`, found {n}"),
        ));
    }
    for j in &path {
        if matches!(
            j.joint_type,
            urdf_rs::JointType::Floating
                | urdf_rs::JointType::Planar
                | urdf_rs::JointType::Spherical
        ) {
            return Err(err(file, format!("joint `{}`: only revolute, continuous, prismatic and fixed joints form a serial chain", j.name)));
        }
    }
    // The same sane magnitudes as machine files (metres and radians here: 1e3 m, 1e4
    // rad), before any of them is computed with.
    for j in &path {
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
    let mut links = Vec::new();
    let mut acc = Matrix4::identity();
    let mut pending: Option<(String, Option<Joint>)> = Some((root.to_string(), None));
    for j in &path {
        acc *= origin(&j.origin);
        if !movable(j) {
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
        let (name, joint) = pending.take().expect("a pending link");
        links.push(link(&name, joint, &acc));
        acc = r4.transpose();
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
                    min: j.limit.lower,
                    max: j.limit.upper,
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
        pending = Some((
            j.child.link.clone(),
            Some(Joint {
                name: j.name.clone(),
                kind,
                range,
                max_velocity: None,
                max_acceleration: None,
            }),
        ));
    }
    let (name, joint) = pending.take().expect("a pending link");
    links.push(link(&name, joint, &acc));
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
