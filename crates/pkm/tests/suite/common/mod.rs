//! Helpers shared by the tests.

use nalgebra::Vector3;
use pkm::Machine;

/// The example machine file `name` (in `examples/machines/`), loaded.
pub fn example(name: &str) -> Machine {
    Machine::from_path(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// The machine file `name` in `tests/fixtures/` (users' own machines), loaded.
pub fn fixture(name: &str) -> Machine {
    Machine::from_path(format!(
        "{}/../../tests/fixtures/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// Pose errors of a model at states it all reaches
/// ([`pkm::identify::simulate::pose_errors`] with no state left out).
pub fn all_reached(
    r: pkm::Result<(pkm::identify::simulate::PoseErrors, usize)>,
) -> pkm::identify::simulate::PoseErrors {
    let (e, failed) = r.unwrap();
    assert_eq!(failed, 0, "states the model does not reach");
    e
}

/// The tool point's change after moving the named joints' centres by `d` (mm) in the
/// machine file `file` itself (lines `NAME = [x, y, z]`) and solving forward
/// kinematics at the nominal readings of `pose`: an independent path (the file's
/// text, the loader, the plain forward solver).
pub fn moved_by_hand(file: &str, pose: &[f64], moves: &[(&str, [f64; 3])]) -> Vector3<f64> {
    let text = std::fs::read_to_string(file).unwrap();
    let nominal = Machine::from_toml_str(&text, "nominal").unwrap();
    let m0 = nominal.mechanism();
    let q = m0.inverse(pose).unwrap();
    let mut moved = text.clone();
    for (joint, d) in moves {
        let prefix = format!("{joint} = [");
        let line = moved
            .lines()
            .find(|l| l.starts_with(&prefix))
            .unwrap()
            .to_string();
        let end = line.find(']').unwrap();
        let v: Vec<f64> = line[prefix.len()..end]
            .split(',')
            .map(|s| s.trim().parse().unwrap())
            .collect();
        let new = format!(
            "{joint} = [{:.12}, {:.12}, {:.12}]",
            v[0] + d[0],
            v[1] + d[1],
            v[2] + d[2]
        );
        moved = moved.replace(&line, &new);
    }
    let m = Machine::from_toml_str(&moved, "moved").unwrap();
    let dm = m.mechanism();
    let f = dm.forward(&q, pose).unwrap();
    let p = dm.tool_pose(&f.pose).unwrap().translation.vector;
    p - m0.tool_pose(pose).unwrap().translation.vector
}

/// The actuator-position violations of `m` at its home pose with every actuator
/// `by` beyond its range (past the maximum for `by > 0`, the minimum for `by < 0`),
/// checked against `name(i, actuator)`: one per actuator, in actuator order, with
/// that name, the side crossed and the value in user units (mm, deg).
pub fn check_position_names<M, const P: usize, const A: usize>(
    m: &M,
    by: f64,
    name: impl Fn(usize, &pkm::Actuator) -> String,
) where
    M: pkm::Mechanism<P, A>,
{
    let acts = m.info().actuators();
    let q = nalgebra::SVector::<f64, A>::from_fn(|i, _| {
        let r = &acts[i].range;
        if by > 0.0 {
            r.max + by
        } else {
            r.min + by
        }
    });
    let mut v = Vec::new();
    m.check_limits(&m.info().home(), &q, &mut v);
    let pos: Vec<_> = v
        .iter()
        .filter(|v| v.kind == pkm::LimitKind::ActuatorPosition)
        .collect();
    assert_eq!(pos.len(), A, "{v:?}");
    let side = if by > 0.0 {
        pkm::Side::Max
    } else {
        pkm::Side::Min
    };
    for (i, v) in pos.iter().enumerate() {
        assert_eq!(v.limit, name(i, &acts[i]));
        assert_eq!(v.side, side);
        let user = acts[i].quantity.to_user(q[i]);
        assert!(
            (v.value - user).abs() <= 1e-12 * user.abs(),
            "{} {user}",
            v.value
        );
    }
}

/// Example machine `name` with every number after `key =` scaled by `k` for the given
/// `keys` (lengths; angles and rates left), its published references left out (they
/// hold the unscaled values).
pub fn scaled_example(name: &str, k: f64, keys: &[&str]) -> Machine {
    let text = std::fs::read_to_string(format!(
        "{}/../../examples/machines/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let text = text.split("[[reference]]").next().unwrap();
    let scaled: Vec<String> = text
        .lines()
        .map(|l| match l.split_once('=') {
            Some((key, value)) if keys.contains(&key.trim()) => {
                let value = value.split('#').next().unwrap();
                format!("{key}={}", scale_numbers(value, k))
            }
            _ => l.to_string(),
        })
        .collect();
    Machine::from_toml_str(&scaled.join("\n"), &format!("{name} scaled by {k}")).unwrap()
}

/// `text` with every number in it multiplied by `k`.
fn scale_numbers(text: &str, k: f64) -> String {
    let (mut out, mut number) = (String::new(), String::new());
    for ch in text.chars().chain(std::iter::once(' ')) {
        if ch.is_ascii_digit() || ch == '.' || (ch == '-' && number.is_empty()) {
            number.push(ch);
            continue;
        }
        match number.parse::<f64>() {
            Ok(v) => out.push_str(&format!("{:?}", v * k)),
            Err(_) => out.push_str(&number),
        }
        number.clear();
        out.push(ch);
    }
    out
}
