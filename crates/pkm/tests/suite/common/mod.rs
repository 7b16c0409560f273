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
