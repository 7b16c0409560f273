//! The clearance bounds by enumeration: every combination of the joints' extreme
//! states solved exactly.

use nalgebra::Vector3;
use rayon::prelude::*;

use super::{enumeration_size, solve, Along, JointState, Region, MAX_ENUMERATION};
use crate::accuracy::Evaluate;
use crate::error::{Error, Result};

/// [`super::along`] by solving every combination of the joints' extreme states (in parallel),
/// `fo` the first-order bound reported with them.
pub(super) fn along<E: Evaluate + Clone + Send + Sync>(
    ev: &E,
    regions: &[Region],
    n: &Vector3<f64>,
    fo: f64,
) -> Result<Along> {
    let size = enumeration_size(regions);
    if size > MAX_ENUMERATION {
        return Err(too_many(regions.len(), size));
    }
    let extremes: Vec<Vec<JointState>> = regions.iter().map(Region::extremes).collect();
    let states_of = |mut i: u64, out: &mut Vec<JointState>| {
        out.clear();
        out.extend(extremes.iter().map(|e| {
            let k = (i % e.len() as u64) as usize;
            i /= e.len() as u64;
            e[k]
        }));
    };
    let base = ev.clone();
    let (hi, lo) = (0..size)
        .into_par_iter()
        .map_init(
            || (base.clone(), Vec::new(), Vec::new()),
            |(ev, buf, states), i| {
                states_of(i, states);
                let v = solve(ev, regions, states, buf).map(|e| n.dot(&e));
                v.map(|v| ((v, i), (v, i)))
            },
        )
        .try_reduce(
            || ((f64::NEG_INFINITY, 0), (f64::INFINITY, 0)),
            |a, b| {
                Ok((
                    if b.0 .0 > a.0 .0 { b.0 } else { a.0 },
                    if b.1 .0 < a.1 .0 { b.1 } else { a.1 },
                ))
            },
        )?;
    let (mut up, mut low) = (Vec::new(), Vec::new());
    states_of(hi.1, &mut up);
    states_of(lo.1, &mut low);
    Ok(Along {
        upper: hi.0,
        lower: lo.0,
        up,
        low,
        first_order: fo,
        refined: false,
        solves: size,
    })
}

/// The refusal of an enumeration of `size` combinations of the extreme states of
/// `joints` joints.
fn too_many(joints: usize, size: u64) -> Error {
    Error::InvalidInput {
        what: "clearance enumeration".into(),
        message: format!(
            "the extreme states of {} joints make {} combinations, each one \
             solve of the mechanism (more than the {MAX_ENUMERATION} pkm runs): \
             use the first-order bound, which scales",
            joints,
            if size == u64::MAX {
                "over 1.8e19".to_string()
            } else {
                size.to_string()
            }
        ),
    }
}
