//! The designer's question per class of joints (seed 002's conclusion: choose the
//! clearances so that the shaping accuracy is met): for each class (the joints one body
//! carries: `base`, `platform`, `carriage`), the largest clearance of its joints that
//! keeps the error within a tolerance while the other classes keep theirs.

use serde::Serialize;

use crate::accuracy::clearance::Region;
use crate::error::Result;

/// The largest clearance of one class of joints.
///
/// # Examples
///
/// ```
/// use pkm::analysis::clearance::{clearance, ClearanceRequest};
/// let machine = pkm::Machine::from_path(concat!(
///     env!("CARGO_MANIFEST_DIR"),
///     "/../../examples/machines/hybrid-am-seed002.toml"
/// ))
/// .unwrap();
/// let req = ClearanceRequest { tolerance: Some(0.05), ..Default::default() };
/// let r = clearance(&machine, None, &req).unwrap();
/// let classes: Vec<&str> = r.largest_per_class.iter().map(|c| c.class.as_str()).collect();
/// assert!(classes.contains(&"carriage") && classes.contains(&"platform"));
/// for c in &r.largest_per_class {
///     assert_eq!(c.joints.len(), 4);
///     assert_eq!(c.given_mm, Some(0.1));
///     // What the other classes leave is below the whole machine's worst error.
///     assert!(c.others_alone_mm < r.bounds.upper.max(-r.bounds.lower));
/// }
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClassClearance {
    /// The class: the body that carries its joints.
    pub class: String,
    /// Its joints.
    pub joints: Vec<String>,
    /// Their diametral clearance as given, when they share one (mm).
    pub given_mm: Option<f64>,
    /// The worst error with this class's joints free of play and the others as given
    /// (mm): no clearance of this class can bring the error below it.
    pub others_alone_mm: f64,
    /// The factor on this class's clearances that brings the worst error to the
    /// tolerance; `None` when the others alone reach it, or when this class moves
    /// nothing.
    pub largest_scale: Option<f64>,
    /// `largest_scale` times the class's shared clearance (mm).
    pub largest_mm: Option<f64>,
}

/// Each class's largest clearance for tolerance `t`, `worst` giving the largest
/// `max(upper, -lower)` (mm) of a set of regions and `worst_as_given` its value for `regions`
/// as they are (computed by the caller already). The worst error grows about linearly
/// with a class's clearance, `w(s) = w(0) + s (w(1) - w(0))`; the secant method from
/// `s = 0` and `s = 1` finds `w(s) = t` on exact bounds (to 1e-9 relative, at most 12
/// steps).
pub(crate) fn per_class(
    regions: &[Region],
    t: f64,
    worst_as_given: f64,
    worst: impl Fn(&[Region]) -> Result<f64>,
) -> Result<Vec<ClassClearance>> {
    let mut classes: Vec<&str> = Vec::new();
    for r in regions {
        if !classes.contains(&r.joint.body.as_str()) {
            classes.push(&r.joint.body);
        }
    }
    let with = |class: &str, s: f64| -> Result<Vec<Region>> {
        regions
            .iter()
            .map(|r| {
                let c = if r.joint.body == class {
                    r.clearance.with_diametral(r.clearance.diametral * s)
                } else {
                    r.clearance.clone()
                };
                Region::new(r.joint.clone(), c)
            })
            .collect()
    };
    let mut out = Vec::with_capacity(classes.len());
    for class in classes {
        let members: Vec<&Region> = regions.iter().filter(|r| r.joint.body == class).collect();
        let given = members[0].clearance.diametral;
        let given_mm = members
            .iter()
            .all(|r| r.clearance.diametral == given)
            .then_some(given);
        let w0 = worst(&with(class, 0.0)?)?;
        let w1 = worst_as_given;
        let scale = if w0 >= t || !(w1 > w0) {
            None
        } else {
            let (mut a, mut wa, mut b, mut wb) = (0.0, w0, 1.0, w1);
            for _ in 0..12 {
                if (wb - t).abs() <= 1e-9 * t || wb == wa {
                    break;
                }
                let s = (b + (t - wb) * (b - a) / (wb - wa)).max(0.0);
                (a, wa) = (b, wb);
                b = s;
                wb = worst(&with(class, s)?)?;
            }
            Some(b)
        };
        out.push(ClassClearance {
            class: class.to_string(),
            joints: members.iter().map(|r| r.joint.name.clone()).collect(),
            given_mm,
            others_alone_mm: w0,
            largest_scale: scale,
            largest_mm: scale.zip(given_mm).map(|(s, c)| s * c),
        });
    }
    Ok(out)
}
