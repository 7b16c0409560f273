//! Tool-centre-point kinematics of 5-axis machine tools (`pose = "tcp"`): against
//! LinuxCNC's `xyzbc-trt-kins` formulas, round trips, Jacobians by finite differences,
//! the tool-axis inverse with its branches and singular direction.

use nalgebra::{SVector, Vector3};
use pkm::machine::Model;
use pkm::serial::mechanism::SerialAny;
use pkm::serial::tcp::TcpMachine;
use pkm::{Machine, Mechanism};
use rand::{Rng, SeedableRng};

/// The parameters of LinuxCNC's trt kinematics (mm).
#[derive(Debug, Clone, Copy)]
pub struct Trt {
    pub rot: [f64; 3],
    pub dx: f64,
    pub dz: f64,
    pub tool: f64,
    pub conventional: bool,
}

/// `xyzbc_inverse_math` of LinuxCNC (the version whose offsets turn with the tilt in
/// the forward's sense: `dpx = -cos(b) dx + con sin(b) dz + dx`), written out from its
/// published formulas: joints for a world pose (mm, deg).
pub fn lcnc_inverse(p: &Trt, pos: [f64; 3], b: f64, c: f64) -> [f64; 3] {
    let con = if p.conventional { 1.0 } else { -1.0 };
    let (sb, cb) = b.to_radians().sin_cos();
    let (sc, cc) = c.to_radians().sin_cos();
    let (dx, dz) = (p.dx, p.dz + p.tool);
    let [rx, ry, rz] = p.rot;
    let (x, y, z) = (pos[0] - rx, pos[1] - ry, pos[2] - rz);
    let dpx = -cb * dx + con * sb * dz + dx;
    let dpz = -con * sb * dx - cb * dz + dz;
    [
        cc * cb * x + con * sc * cb * y - con * sb * z + dpx + rx,
        -con * sc * x + cc * y + ry,
        con * cc * sb * x + sc * sb * y + cb * z + dpz + rz,
    ]
}

/// `xyzbc_forward_math`: world pose for joints.
pub fn lcnc_forward(p: &Trt, j: [f64; 3], b: f64, c: f64) -> [f64; 3] {
    let con = if p.conventional { 1.0 } else { -1.0 };
    let (sb, cb) = b.to_radians().sin_cos();
    let (sc, cc) = c.to_radians().sin_cos();
    let (dx, dz) = (p.dx, p.dz + p.tool);
    let [rx, ry, rz] = p.rot;
    let (u, v, w) = (j[0] - dx - rx, j[1] - ry, j[2] - dz - rz);
    [
        cc * cb * u - con * sc * v + con * cc * sb * w + cc * dx + rx,
        con * sc * cb * u + cc * v + sc * sb * w + con * sc * dx + ry,
        -con * sb * u + cb * w + dz + rz,
    ]
}

/// The inverse as printed in trtfuncs_math.h of 2024 (LinuxCNC commit a87837eb), whose
/// offset terms do not depend on the direction convention.
fn lcnc_inverse_2024(p: &Trt, pos: [f64; 3], b: f64, c: f64) -> [f64; 3] {
    let con = if p.conventional { 1.0 } else { -1.0 };
    let (sb, cb) = b.to_radians().sin_cos();
    let (sc, cc) = c.to_radians().sin_cos();
    let (dx, dz) = (p.dx, p.dz + p.tool);
    let [rx, ry, rz] = p.rot;
    let (x, y, z) = (pos[0] - rx, pos[1] - ry, pos[2] - rz);
    let dpx = -cb * dx + sb * dz + dx;
    let dpz = -sb * dx - cb * dz + dz;
    [
        cc * cb * x + con * sc * cb * y - con * sb * z + dpx + rx,
        -con * sc * x + cc * y + ry,
        con * cc * sb * x + sc * sb * y + cb * z + dpz + rz,
    ]
}

fn fmt(v: f64) -> String {
    format!("{v:.12}")
}

/// A pkm machine file for LinuxCNC's XYZBC trt geometry, written by hand from the
/// geometry the formulas describe (independent of `pkm import linuxcnc`): X, Y, Z
/// slides carry the tool (tip `tool` below the gauge point); the table tilts about a
/// line along Y through `rot + (dx, 0, dz)` and turns about the vertical through
/// `rot`. Default directions: table axes +Y, +Z; conventional: -Y, -Z.
pub fn trt_toml(p: &Trt) -> String {
    let [rx, ry, rz] = p.rot;
    let (dx, dz) = (p.dx, p.dz);
    let (mount, b_t, b_rot, c_t, c_rot) = if p.conventional {
        (
            "[[0.0, -1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]]",
            [-dz, dx, 0.0],
            "[[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]",
            [-rx, ry, rz],
            "[[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]",
        )
    } else {
        (
            "[[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]",
            [-dz, -dx, 0.0],
            "[[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]",
            [-rx, -ry, -rz],
            "[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]",
        )
    };
    let perm = "[[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]";
    format!(
        r#"type = "serial"
name = "xyzbc trt by hand"
pose = "tcp"

[[tool_chain]]
name = "bed"
rotation = {perm}

[[tool_chain]]
name = "x slide"
joint = {{ name = "X", type = "prismatic", range = [-200.0, 200.0] }}
rotation = {perm}

[[tool_chain]]
name = "y slide"
joint = {{ name = "Y", type = "prismatic", range = [-100.0, 100.0] }}
rotation = {perm}

[[tool_chain]]
name = "spindle"
joint = {{ name = "Z", type = "prismatic", range = [-120.0, 120.0] }}
translation = [0.0, 0.0, {tool}]

[[workpiece_chain]]
name = "table mount"
translation = [{px}, {py}, {pz}]
rotation = {mount}

[[workpiece_chain]]
name = "tilt"
joint = {{ name = "B", type = "revolute", range = [-100.0, 50.0] }}
translation = [{b0}, {b1}, {b2}]
rotation = {b_rot}

[[workpiece_chain]]
name = "rotary"
joint = {{ name = "C", type = "revolute", range = [-36000.0, 36000.0] }}
translation = [{c0}, {c1}, {c2}]
rotation = {c_rot}
"#,
        tool = fmt(-p.tool),
        px = fmt(rx + dx),
        py = fmt(ry),
        pz = fmt(rz + dz),
        b0 = fmt(b_t[0]),
        b1 = fmt(b_t[1]),
        b2 = fmt(b_t[2]),
        c0 = fmt(c_t[0]),
        c1 = fmt(c_t[1]),
        c2 = fmt(c_t[2]),
    )
}

pub fn tcp5(m: &Machine) -> &TcpMachine<5> {
    let Model::Serial(s) = &m.model else {
        panic!("not serial")
    };
    let SerialAny::Tcp5(t) = &s.mechanism else {
        panic!("not a 5-axis TCP machine")
    };
    t
}

fn params(rng: &mut rand::rngs::StdRng, conventional: bool) -> Trt {
    Trt {
        rot: [
            rng.random_range(-50.0..50.0),
            rng.random_range(-50.0..50.0),
            rng.random_range(-50.0..50.0),
        ],
        dx: rng.random_range(-80.0..80.0),
        dz: rng.random_range(-80.0..80.0),
        tool: rng.random_range(0.0..120.0),
        conventional,
    }
}

/// A LinuxCNC trt formula: joints (or world pose) from a world pose (or joints) and
/// the two rotary angles (deg).
type TrtFormula = fn(&Trt, [f64; 3], f64, f64) -> [f64; 3];

/// The largest difference (mm) between pkm's inverse kinematics and LinuxCNC's
/// `inverse` (and its forward against `forward`) over `n` random poses.
fn worst_against(
    t: &TcpMachine<5>,
    p: &Trt,
    rng: &mut rand::rngs::StdRng,
    n: usize,
    inverse: TrtFormula,
    forward: Option<TrtFormula>,
) -> f64 {
    let mut worst: f64 = 0.0;
    for _ in 0..n {
        let pos = [
            rng.random_range(-150.0..150.0),
            rng.random_range(-80.0..80.0),
            rng.random_range(-100.0..100.0),
        ];
        let (a, c) = (
            rng.random_range(-100.0..50.0),
            rng.random_range(-720.0..720.0),
        );
        let j = inverse(p, pos, a, c);
        // pkm's X, Y, Z are the tip; LinuxCNC's world Z carries the tool length on top
        // (its interpreter adds it): tip = world - tool e_z.
        let x = SVector::<f64, 5>::new(
            pos[0],
            pos[1],
            pos[2] - p.tool,
            a.to_radians(),
            c.to_radians(),
        );
        let q = t.inverse(&x).unwrap();
        for i in 0..3 {
            worst = worst.max((q[i] - j[i]).abs());
        }
        assert!((q[3] - x[3]).abs() < 1e-15 && (q[4] - x[4]).abs() < 1e-15);
        if let Some(forward) = forward {
            let f = forward(p, j, a, c);
            let back = t.forward(&q, &x).unwrap().pose;
            for i in 0..3 {
                let want = if i == 2 { f[2] - p.tool } else { f[i] };
                worst = worst.max((back[i] - want).abs());
            }
        }
    }
    worst
}

#[test]
fn inverse_and_forward_equal_linuxcnc_xyzbc_trt_kins_both_directions() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(20);
    let mut worst: f64 = 0.0;
    for conventional in [false, true] {
        // The sim's parameters first, then random ones.
        let sim = Trt {
            rot: [0.0; 3],
            dx: -20.0,
            dz: -15.0,
            tool: 0.0,
            conventional,
        };
        for k in 0..40 {
            let p = if k == 0 {
                sim
            } else {
                params(&mut rng, conventional)
            };
            let m = Machine::from_toml_str(&trt_toml(&p), "trt.toml").unwrap();
            let t = tcp5(&m);
            worst = worst.max(worst_against(
                t,
                &p,
                &mut rng,
                50,
                lcnc_inverse,
                Some(lcnc_forward),
            ));
        }
    }
    assert!(worst < 1e-9, "largest difference {worst:.3e} mm");
}

#[test]
fn the_2024_header_inverse_is_not_its_forwards_inverse_with_default_directions() {
    // trtfuncs_math.h as of LinuxCNC a87837eb: with conventional-directions = 0 and
    // non-zero x and z offsets its inverse does not undo its forward; pkm (and the
    // older trtfuncs.c, and the later header) do. Recorded in docs/five-axis.md.
    let p = Trt {
        rot: [0.0; 3],
        dx: -20.0,
        dz: -15.0,
        tool: 0.0,
        conventional: false,
    };
    let (pos, b, c) = ([10.0, 5.0, -3.0], 30.0, 40.0);
    let printed = lcnc_inverse_2024(&p, pos, b, c);
    let f = lcnc_forward(&p, printed, b, c);
    // Its offset terms have the sign of sin(B) dz and sin(B) dx flipped, so the round
    // trip misses by 2 sin(B) |(dx, dz)|: 25 mm here.
    let off = (0..3).map(|i| (f[i] - pos[i]).powi(2)).sum::<f64>().sqrt();
    let want = 2.0 * 30f64.to_radians().sin() * p.dx.hypot(p.dz);
    assert!((off - want).abs() < 1e-9, "{off} vs {want} mm");
    assert!((want - 25.0).abs() < 1e-12);
    let consistent = lcnc_inverse(&p, pos, b, c);
    let f = lcnc_forward(&p, consistent, b, c);
    let off = (0..3).map(|i| (f[i] - pos[i]).abs()).fold(0.0, f64::max);
    assert!(off < 1e-12, "{off:.3e}");
    // With conventional directions the printed one is right.
    let p = Trt {
        conventional: true,
        ..p
    };
    let printed = lcnc_inverse_2024(&p, pos, b, c);
    let f = lcnc_forward(&p, printed, b, c);
    assert!((0..3).all(|i| (f[i] - pos[i]).abs() < 1e-12));
}

fn sim(conventional: bool) -> Machine {
    let p = Trt {
        rot: [0.0; 3],
        dx: -20.0,
        dz: -15.0,
        tool: 60.0,
        conventional,
    };
    Machine::from_toml_str(&trt_toml(&p), "trt.toml").unwrap()
}

/// The Jacobian at `x` against central differences of the inverse, and q', q'' along
/// `x + v t + a t^2 / 2` against differences of q(t) (fourth order for q'').
fn check_derivatives(t: &TcpMachine<5>, x: SVector<f64, 5>, v: SVector<f64, 5>) {
    let j = t.jacobian(&x).unwrap();
    for c in 0..5 {
        let h = if c < 3 { 1e-4 } else { 1e-6 };
        let mut xp = x;
        let mut xm = x;
        xp[c] += h;
        xm[c] -= h;
        let fd = (t.inverse(&xp).unwrap() - t.inverse(&xm).unwrap()) / (2.0 * h);
        let scale = j.column(c).amax().max(1.0);
        assert!(
            (fd - j.column(c)).amax() < 1e-7 * scale,
            "column {c}: {fd} vs {}",
            j.column(c)
        );
    }
    let a = v * 0.7 + SVector::<f64, 5>::new(3.0, -2.0, 1.0, 0.3, -0.4);
    let at = |s: f64| t.inverse(&(x + v * s + a * (s * s / 2.0))).unwrap();
    let mo = t.actuator_motion(&x, &v, &a).unwrap();
    let h = 1e-3;
    let qd = (at(-2.0 * h) - at(-h) * 8.0 + at(h) * 8.0 - at(2.0 * h)) / (12.0 * h);
    let qdd = (at(-2.0 * h) * -1.0 + at(-h) * 16.0 - at(0.0) * 30.0 + at(h) * 16.0 - at(2.0 * h))
        / (12.0 * h * h);
    assert!((mo.q - at(0.0)).amax() < 1e-12);
    assert!(
        (mo.qd - qd).amax() < 1e-8 * qd.amax().max(1.0),
        "{} vs {qd}",
        mo.qd
    );
    assert!(
        (mo.qdd - qdd).amax() < 1e-6 * qdd.amax().max(1.0),
        "{} vs {qdd}",
        mo.qdd
    );
}

fn random_rates(rng: &mut rand::rngs::StdRng) -> SVector<f64, 5> {
    SVector::<f64, 5>::new(
        rng.random_range(-50.0..50.0),
        rng.random_range(-50.0..50.0),
        rng.random_range(-50.0..50.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-2.0..2.0),
    )
}

#[test]
fn jacobian_and_actuator_motion_match_finite_differences() {
    let m = sim(false);
    let t = tcp5(&m);
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    for _ in 0..200 {
        let x = SVector::<f64, 5>::new(
            rng.random_range(-100.0..100.0),
            rng.random_range(-60.0..60.0),
            rng.random_range(-60.0..60.0),
            rng.random_range(-1.5..0.8),
            rng.random_range(-7.0..7.0),
        );
        let v = random_rates(&mut rng);
        check_derivatives(t, x, v);
    }
}

/// A machine with a tilting head (A about X, in the tool chain after the slides, the
/// tool 150 mm from its axis) and a rotary table C off the origin, written by hand:
/// the slides move the head's axis, which a table machine's do not.
const HEAD: &str = r#"type = "serial"
name = "head A, table C"
pose = "tcp"

[[tool_chain]]
name = "bed"
rotation = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]

[[tool_chain]]
name = "x slide"
joint = { name = "X", type = "prismatic", range = [-500.0, 500.0] }
rotation = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]

[[tool_chain]]
name = "y slide"
joint = { name = "Y", type = "prismatic", range = [-500.0, 500.0] }
rotation = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]

[[tool_chain]]
name = "z slide"
joint = { name = "Z", type = "prismatic", range = [-500.0, 500.0] }
translation = [0.0, 0.0, 300.0]
rotation = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]

[[tool_chain]]
name = "head"
joint = { name = "A", type = "revolute", range = [-100.0, 100.0] }
translation = [0.0, -150.0, 0.0]
rotation = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]

[[workpiece_chain]]
name = "table mount"
translation = [10.0, 20.0, -50.0]

[[workpiece_chain]]
name = "table"
joint = { name = "C", type = "revolute", range = [-3600.0, 3600.0] }
"#;

#[test]
fn a_tilting_head_machine_inverts_forwards_and_differentiates_exactly() {
    let m = Machine::from_toml_str(HEAD, "head.toml").unwrap();
    let t = tcp5(&m);
    let names: Vec<&str> = t
        .info()
        .coordinates()
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(names, ["X", "Y", "Z", "A", "C"]);
    // At A = C = 0 the tool hangs 150 mm below the head's axis, which is 300 mm above
    // the Z slide's origin: tip = slides + (0, 0, 150) less the table's origin.
    let q0 = SVector::<f64, 5>::new(1.0, 2.0, 3.0, 0.0, 0.0);
    let x0 = t.forward(&q0, &q0).unwrap().pose;
    assert!(
        (x0 - SVector::<f64, 5>::new(-9.0, -18.0, 203.0, 0.0, 0.0)).amax() < 1e-12,
        "{x0}"
    );
    // A turns the tool about the head's axis (world X, 303 mm up): at A = 90 deg the
    // tip is at Rx(90) (0, 0, -150) = (0, 150, 0) from the axis.
    let q1 = SVector::<f64, 5>::new(1.0, 2.0, 3.0, std::f64::consts::FRAC_PI_2, 0.0);
    let x1 = t.forward(&q1, &q1).unwrap().pose;
    assert!(
        (x1.fixed_rows::<3>(0) - Vector3::new(-9.0, 132.0, 353.0)).amax() < 1e-9,
        "{x1}"
    );
    // Conditioning with angles counted as the lever (150 mm, the tool from A's axis) in
    // rows and columns: by hand, dq/dx at home is I with the slides' compensation of
    // A (tip 150 mm below its axis: -(0, 150, 0) / 150) and of C (tip at (-10, -20) from
    // its axis, seen from the part turning the other way: (20, -10, 0) / 150).
    assert_eq!(t.info().characteristic_length(), 150.0);
    let mut hand = nalgebra::SMatrix::<f64, 5, 5>::identity();
    hand[(1, 3)] = -1.0;
    hand[(0, 4)] = 20.0 / 150.0;
    hand[(1, 4)] = -10.0 / 150.0;
    let sv = hand.singular_values();
    let want = sv.max() / sv.min();
    let got = t.condition(&t.info().home()).unwrap();
    assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    for _ in 0..500 {
        let x = SVector::<f64, 5>::new(
            rng.random_range(-200.0..200.0),
            rng.random_range(-200.0..200.0),
            rng.random_range(-100.0..300.0),
            rng.random_range(-1.5..1.5),
            rng.random_range(-7.0..7.0),
        );
        let q = t.inverse(&x).unwrap();
        assert!((t.forward(&q, &x).unwrap().pose - x).amax() < 1e-9);
        // Through the tool axis: the branch nearest the pose's own angles is them.
        let (xa, _) = t
            .pose_for_axis(
                &Vector3::new(x[0], x[1], x[2]),
                &t.tool_axis(&q),
                Some(&[x[3], x[4]]),
            )
            .unwrap();
        assert!((xa - x).amax() < 1e-9, "{xa} vs {x}");
        check_derivatives(t, x, random_rates(&mut rng));
    }
}

#[test]
fn an_axis_beyond_the_rotary_axes_reach_is_refused_with_the_angle() {
    // The tool tilted 30 deg about Y in the head, out of the plane A turns it in: it
    // stays at 60 deg from the head's axis (X), so no turn of the table about Z brings
    // it nearer the vertical than 30 deg.
    let (s30, c30) = 30f64.to_radians().sin_cos();
    let text = HEAD.replace(
        "translation = [0.0, -150.0, 0.0]\nrotation = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]",
        &format!(
            "translation = [0.0, -150.0, 0.0]\nrotation = [[0.0, 1.0, 0.0], [{ms30}, 0.0, {c30}], [{c30}, 0.0, {s30}]]",
            ms30 = -s30
        ),
    );
    assert_ne!(text, HEAD);
    let m = Machine::from_toml_str(&text, "tilted.toml").unwrap();
    let t = tcp5(&m);
    let e = t
        .rotary_for_axis(&Vector3::new(0.0, 0.0, 1.0), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("30.0000 deg beyond"), "{e}");
    // 40 deg from the vertical is within reach, and pointed exactly.
    let (s40, c40) = 40f64.to_radians().sin_cos();
    let axis = Vector3::new(s40, 0.0, c40);
    let sol = t.rotary_for_axis(&axis, None).unwrap();
    for b in &sol.branches {
        let q = t
            .inverse(&SVector::<f64, 5>::new(0.0, 0.0, 0.0, b[0], b[1]))
            .unwrap();
        assert!((t.tool_axis(&q) - axis).amax() < 1e-12);
    }
}

#[test]
fn round_trips_over_random_tool_poses_including_near_singular_axes() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let mut worst_q: f64 = 0.0;
    let mut worst_axis: f64 = 0.0;
    let mut singular = 0;
    for conventional in [false, true] {
        let m = sim(conventional);
        let t = tcp5(&m);
        for k in 0..50_000 {
            let tip = Vector3::new(
                rng.random_range(-150.0..150.0),
                rng.random_range(-80.0..80.0),
                rng.random_range(-100.0..100.0),
            );
            // A third of the axes within 1e-6 rad of the C axis (vertical), some exactly.
            let axis = if k % 3 == 0 {
                let e = if k % 9 == 0 {
                    0.0
                } else {
                    10f64.powf(rng.random_range(-12.0..-6.0))
                };
                let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                Vector3::new(e * phi.cos(), e * phi.sin(), 1.0).normalize()
            } else {
                let th: f64 = rng.random_range(0.0..1.7);
                let phi: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                Vector3::new(th.sin() * phi.cos(), th.sin() * phi.sin(), th.cos())
            };
            let near = [rng.random_range(-1.0..0.5), rng.random_range(-6.0..6.0)];
            let (x, sol) = t.pose_for_axis(&tip, &axis, Some(&near)).unwrap();
            singular += sol.singular as usize;
            // Every branch points the tool along the axis.
            for b in &sol.branches {
                let mut xb = x;
                xb[3] = b[0];
                xb[4] = b[1];
                let q = t.inverse(&xb).unwrap();
                worst_axis = worst_axis.max((t.tool_axis(&q) - axis).amax());
            }
            // IK -> FK gives the pose back; FK -> IK the joints.
            let q = t.inverse(&x).unwrap();
            let back = t.forward(&q, &x).unwrap().pose;
            worst_q = worst_q.max((back - x).amax());
            let again = t.inverse(&back).unwrap();
            worst_q = worst_q.max((again - q).amax());
            if sol.singular {
                // C is held where it was.
                assert_eq!(x[4], near[1]);
            }
        }
    }
    assert!(singular > 5_000, "{singular} singular axes");
    assert!(worst_q < 1e-9, "round trip {worst_q:.3e}");
    assert!(worst_axis < 1e-9, "axis {worst_axis:.3e}");
}

#[test]
fn both_branches_and_the_continuity_rule() {
    let m = sim(false);
    let t = tcp5(&m);
    // A tilted axis: two branches, B of either sign, C half a turn apart.
    let axis = Vector3::new(0.3, 0.2, 0.9).normalize();
    let sol = t.rotary_for_axis(&axis, Some(&[-0.4, 0.0])).unwrap();
    assert_eq!(sol.branches.len(), 2);
    let (b0, b1) = (&sol.branches[0], &sol.branches[1]);
    assert!((b0[0] + b1[0]).abs() < 1e-12, "{b0:?} {b1:?}");
    assert!(((b0[1] - b1[1]).abs() - std::f64::consts::PI).abs() < 1e-9);
    // The chosen branch is the one nearest the previous angles, B within its range.
    assert!((sol.chosen()[0] - -0.4).abs() < (sol.branches[1 - sol.chosen][0] - -0.4).abs());
    // C is taken in the turn nearest the previous value (no jump of 360 deg).
    let far = t.rotary_for_axis(&axis, Some(&[-0.4, 20.0])).unwrap();
    assert!((far.chosen()[1] - 20.0).abs() <= std::f64::consts::PI);
    // B beyond its range (+50 deg) is not chosen when the other branch is within.
    let sol = t.rotary_for_axis(&axis, Some(&[1.0, 0.0])).unwrap();
    assert!(sol.chosen()[0] <= 50f64.to_radians() + 1e-12);
}

#[test]
fn a_zero_or_not_finite_axis_is_refused() {
    let m = sim(false);
    let t = tcp5(&m);
    let e = t
        .rotary_for_axis(&Vector3::new(0.0, 0.0, 0.0), None)
        .unwrap_err();
    assert!(e.to_string().contains("non-zero"), "{e}");
    let e = t
        .rotary_for_axis(&Vector3::new(f64::NAN, 0.0, 1.0), None)
        .unwrap_err();
    assert!(e.to_string().contains("finite"), "{e}");
}

fn fixture(path: &str) -> String {
    format!(
        "{}/../../tests/fixtures/linuxcnc/{path}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// LinuxCNC's sim INI imported (with `conventional-directions` set to `conv`, a tool
/// offset set by `sets`).
fn import_sim(conv: u8, tool: Option<f64>) -> (Machine, pkm::linuxcnc::Imported) {
    let path = fixture("xyzbc-trt/xyzbc-trt.ini");
    let mut text = std::fs::read_to_string(&path).unwrap().replace(
        "xyzbc-trt-kins.conventional-directions 0",
        &format!("xyzbc-trt-kins.conventional-directions {conv}"),
    );
    if let Some(t) = tool {
        text.push_str(&format!("\n[HAL]\nHALCMD = sets :tool-offset {t}\n"));
    }
    let imp =
        pkm::linuxcnc::import_with(&path, &text, &mut |_| Err("no HAL files here".into()), &[])
            .unwrap();
    let m = Machine::from_toml_str(&imp.toml, "xyzbc.toml").unwrap();
    (m, imp)
}

#[test]
fn the_imported_sim_equals_xyzbc_trt_kins_both_directions() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    for conv in [0u8, 1] {
        for tool in [None, Some(42.5)] {
            let (m, imp) = import_sim(conv, tool);
            assert_eq!(imp.kinematics, "xyzbc-trt-kins");
            let t = tcp5(&m);
            let names: Vec<&str> = t
                .info()
                .actuators()
                .iter()
                .map(|a| a.name.as_str())
                .collect();
            assert_eq!(names, ["X", "Y", "Z", "B", "C"]);
            assert_eq!(t.info().actuators()[3].range.max, 50f64.to_radians());
            assert_eq!(t.info().actuators()[0].max_velocity, Some(20.0));
            let p = Trt {
                rot: [0.0; 3],
                dx: -20.0,
                dz: -15.0,
                tool: tool.unwrap_or(0.0),
                conventional: conv == 1,
            };
            let worst = worst_against(t, &p, &mut rng, 2000, lcnc_inverse, None);
            assert!(worst < 1e-9, "{conv} {tool:?}: {worst:.3e} mm");
        }
    }
}

#[test]
fn import_refuses_a_joint_order_it_does_not_map() {
    let path = fixture("xyzbc-trt/xyzbc-trt.ini");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("COORDINATES = XYZBC", "COORDINATES = XYZCB");
    let e = pkm::linuxcnc::import_with(&path, &text, &mut |_| Err("none".into()), &[])
        .unwrap_err()
        .to_string();
    assert!(e.contains("xyzbc-trt.ini") && e.contains("XYZCB"), "{e}");
}

struct Keep(Vec<(Option<u64>, Vec<f64>, Vec<f64>)>);

impl pkm::analysis::motion::SampleSink for Keep {
    fn sample(&mut self, s: &pkm::analysis::motion::SampleRow) -> pkm::Result<()> {
        self.0.push((s.line, s.x.to_vec(), s.q.to_vec()));
        Ok(())
    }
}

fn boat(
    m: &Machine,
    setup: Box<pkm::analysis::motion::ProgramSetup>,
) -> (pkm::analysis::motion::MotionRun, Keep) {
    let text = std::fs::read_to_string(fixture("xyzbc-trt/boat-xyzbc.ngc")).unwrap();
    let mut keep = Keep(Vec::new());
    let run = pkm::analysis::motion::run_motion(
        m,
        pkm::analysis::motion::MotionSource::Gcode {
            reader: Box::new(std::io::Cursor::new(text)),
            from: None,
            setup,
        },
        &pkm::analysis::motion::feed_options(m),
        pkm::motion::Sampling::Rate(200.0),
        &mut keep,
    )
    .unwrap();
    (run, keep)
}

#[test]
fn linuxcncs_boat_program_runs_to_its_end_through_the_sim_and_mc300() {
    let (sim, _) = import_sim(0, None);
    let mc300 = Machine::from_path(format!(
        "{}/../../examples/machines/mc300.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    for m in [&sim, &mc300] {
        let (run, keep) = boat(m, Default::default());
        // The program's last move (line 1864, G53 Y0 B0 C0) is run.
        assert_eq!(keep.0.last().unwrap().0, Some(1864));
        assert!(run.summary.duration_s > 300.0, "{}", run.summary.duration_s);
        // M428 / M429 are noted, not errors.
        assert!(run.notes.iter().any(|n| n.1.starts_with("M428")));
        // Joint values continuous, no turn of C or flip of B between samples: no
        // rotary axis moves faster than the rapid rate (deg/s for a rotary axis) over
        // a sample (5 ms).
        let step = keep
            .0
            .windows(2)
            .map(|w| {
                (w[0].2[3] - w[1].2[3])
                    .abs()
                    .max((w[0].2[4] - w[1].2[4]).abs())
            })
            .fold(0.0, f64::max);
        let bound = pkm::analysis::motion::feed_options(m).rapid.to_radians() / 200.0;
        assert!(
            step <= bound * (1.0 + 1e-9),
            "{step} rad in a sample, bound {bound}"
        );
    }
}

#[test]
fn g43_sets_the_tool_length_from_the_table() {
    let (sim, _) = import_sim(0, None);
    let setup = Box::new(pkm::analysis::motion::ProgramSetup {
        tool_lengths: [(1, 50.0)].into_iter().collect(),
        ..Default::default()
    });
    let (run, keep) = boat(&sim, setup);
    assert!(
        run.notes.iter().any(|n| n.1.contains("tool length 50 mm")),
        "{:?}",
        run.notes
    );
    let tooled = tcp5(&sim).with_tool_length(50.0).unwrap();
    let plain = tcp5(&sim);
    // Before G43 (line 12) the machine file's tool; from it on, 50 mm longer; after
    // G49 (line 1863) none again.
    for (line, x, q) in &keep.0 {
        let x = SVector::<f64, 5>::from_column_slice(x);
        let want = match line {
            Some(l) if (12..1863).contains(l) => tooled.inverse(&x).unwrap(),
            _ => plain.inverse(&x).unwrap(),
        };
        assert!(
            (SVector::<f64, 5>::from_column_slice(q) - want).amax() < 1e-9,
            "line {line:?}"
        );
    }
    // A machine whose tool is in its file refuses G43 with a length, naming the line.
    let hexapod = Machine::from_path(format!(
        "{}/../../examples/machines/hexapod-seed001.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let e = pkm::analysis::motion::run_motion(
        &hexapod,
        pkm::analysis::motion::MotionSource::Gcode {
            reader: Box::new(std::io::Cursor::new("T1 M6\nG43 H1\n".to_string())),
            from: None,
            setup: Box::new(pkm::analysis::motion::ProgramSetup {
                tool_length: Some(10.0),
                ..Default::default()
            }),
        },
        &pkm::analysis::motion::feed_options(&hexapod),
        pkm::motion::Sampling::Rate(200.0),
        &mut pkm::analysis::motion::NoSink,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("line 2") && e.contains("G43"), "{e}");
}

/// `xyzac_inverse_math` of LinuxCNC's trtfuncs (A about X; `dx` is the y-offset here).
fn lcnc_inverse_ac(p: &Trt, pos: [f64; 3], a: f64, c: f64) -> [f64; 3] {
    let con = if p.conventional { 1.0 } else { -1.0 };
    let (sa, ca) = a.to_radians().sin_cos();
    let (sc, cc) = c.to_radians().sin_cos();
    let (dy, dz) = (p.dx, p.dz + p.tool);
    let [rx, ry, rz] = p.rot;
    let (x, y, z) = (pos[0] - rx, pos[1] - ry, pos[2] - rz);
    [
        cc * x + con * sc * y + rx,
        -con * sc * ca * x + cc * ca * y + con * sa * z - ca * dy - con * sa * dz + dy + ry,
        sc * sa * x - con * cc * sa * y + ca * z + con * sa * dy - ca * dz + dz + rz,
    ]
}

/// `xyzac_forward_math`.
fn lcnc_forward_ac(p: &Trt, j: [f64; 3], a: f64, c: f64) -> [f64; 3] {
    let con = if p.conventional { 1.0 } else { -1.0 };
    let (sa, ca) = a.to_radians().sin_cos();
    let (sc, cc) = c.to_radians().sin_cos();
    let (dy, dz) = (p.dx, p.dz + p.tool);
    let [rx, ry, rz] = p.rot;
    let (u, v, w) = (j[0] - rx, j[1] - dy - ry, j[2] - dz - rz);
    [
        cc * u - con * sc * ca * v + sc * sa * w - con * sc * dy + rx,
        con * sc * u + cc * ca * v - con * cc * sa * w + cc * dy + ry,
        con * sa * v + ca * w + dz + rz,
    ]
}

#[test]
fn an_xyzac_configuration_imports_as_xyzac_trt_kins() {
    // The sim's INI turned into an XYZAC one: the module, its coordinates, and the
    // x-offset signal joined to the module's y-offset.
    let path = fixture("xyzbc-trt/xyzbc-trt.ini");
    let base = std::fs::read_to_string(&path)
        .unwrap()
        .replace("xyzbc-trt-kins", "xyzac-trt-kins")
        .replace("xyzac-trt-kins.x-offset", "xyzac-trt-kins.y-offset")
        .replace("COORDINATES = XYZBC", "COORDINATES = XYZAC");
    let mut rng = rand::rngs::StdRng::seed_from_u64(13);
    for conv in [0u8, 1] {
        let text = base.replace(
            "xyzac-trt-kins.conventional-directions 0",
            &format!("xyzac-trt-kins.conventional-directions {conv}"),
        );
        let imp =
            pkm::linuxcnc::import_with(&path, &text, &mut |_| Err("none".into()), &[]).unwrap();
        assert_eq!(imp.kinematics, "xyzac-trt-kins");
        let m = Machine::from_toml_str(&imp.toml, "xyzac.toml").unwrap();
        let t = tcp5(&m);
        let names: Vec<&str> = t
            .info()
            .coordinates()
            .iter()
            .map(|c| c.name.as_str())
            .collect();
        assert_eq!(names, ["X", "Y", "Z", "A", "C"]);
        let p = Trt {
            rot: [0.0; 3],
            dx: -20.0,
            dz: -15.0,
            tool: 0.0,
            conventional: conv == 1,
        };
        let worst = worst_against(
            t,
            &p,
            &mut rng,
            2000,
            lcnc_inverse_ac,
            Some(lcnc_forward_ac),
        );
        assert!(worst < 1e-9, "{conv}: {worst:.3e} mm");
    }
}

#[test]
fn joint_rates_are_read_and_bad_ones_named() {
    let text = HEAD.replace(
        "range = [-100.0, 100.0] }",
        "range = [-100.0, 100.0], max_velocity = 90.0, max_acceleration = 900.0 }",
    );
    let m = Machine::from_toml_str(&text, "head.toml").unwrap();
    let a = &tcp5(&m).info().actuators()[3];
    assert_eq!(a.max_velocity, Some(90f64.to_radians()));
    assert_eq!(a.max_acceleration, Some(900f64.to_radians()));
    let bad = HEAD.replace(
        "range = [-100.0, 100.0] }",
        "range = [-100.0, 100.0], max_velocity = -1.0 }",
    );
    let e = Machine::from_toml_str(&bad, "head.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("head.toml") && e.contains("max_velocity") && e.contains("> 0"),
        "{e}"
    );
    // Three rotary axes are refused for TCP coordinates, saying why.
    let three = HEAD.replace(
        "[[workpiece_chain]]\nname = \"table mount\"",
        "[[workpiece_chain]]\nname = \"table mount\"\n\n[[workpiece_chain]]\nname = \"tilt\"\njoint = { name = \"B\", type = \"revolute\", range = [-90.0, 90.0] }\nrotation = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]\n\n[[workpiece_chain]]\nname = \"mount2\"",
    );
    let e = Machine::from_toml_str(&three, "three.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("pose") && e.contains("one or two rotary"), "{e}");
}
