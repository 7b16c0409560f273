//! What one grid point is found to be: inverse kinematics, every limit, then the
//! condition number (one point at a time, or a chunk's conditions folded in at once),
//! and the tally of violated limits.

use nalgebra::SVector;

use super::{PointResult, PointStatus};
use crate::error::{Error, Result};
use crate::limits::{LimitName, Violation};
use crate::mechanism::Mechanism;

/// The category and the text ([`Error::category`]: one key per kind, not one per
/// residual) of an inverse-kinematics failure; the commonest, a pose out of reach,
/// shares one text (a robot's map has millions).
fn classify(e: &Error) -> (PointStatus, LimitName) {
    static NO_SOLUTION: std::sync::LazyLock<LimitName> =
        std::sync::LazyLock::new(|| crate::error::NO_SOLUTION.into());
    let status = match e {
        Error::NotConverged { .. } => PointStatus::SolverFailed,
        Error::Singular { .. } => PointStatus::Singular,
        _ => PointStatus::NoSolution,
    };
    let name = match e {
        Error::NotAttainable { .. } => NO_SOLUTION.clone(),
        _ => e.category().into(),
    };
    (status, name)
}

/// Inverse kinematics and every limit at `x`: the actuator values when the pose is
/// within every limit, else the name of what binds (`no solution`, the first violated
/// limit) beside the actuator values when they exist. `v` holds every violation.
pub(crate) fn reach<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    v: &mut Vec<Violation>,
) -> (Option<SVector<f64, A>>, Option<LimitName>) {
    v.clear();
    match m.inverse(x) {
        Ok(q) => limits_at(m, x, q, v),
        Err(e) => (None, Some(classify(&e).1)),
    }
}

fn limits_at<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    q: SVector<f64, A>,
    v: &mut Vec<Violation>,
) -> (Option<SVector<f64, A>>, Option<LimitName>) {
    v.clear();
    m.check_limits(x, &q, v);
    (Some(q), v.first().map(|f| f.limit.clone()))
}

/// The point result at `x` once inverse kinematics has answered `q`; `v` is left with
/// every violated limit.
fn judge<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    q: Result<SVector<f64, A>>,
    v: &mut Vec<Violation>,
) -> PointResult {
    match admit(m, x, q, v) {
        Ok(q) => conditioned(m.condition_at(x, &q).unwrap_or(f64::NAN)),
        Err(r) => r,
    }
}

/// [`judge`] up to the condition number: the actuator positions when inverse
/// kinematics answered `q` within every limit, else the point's result.
pub(super) fn admit<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    q: Result<SVector<f64, A>>,
    v: &mut Vec<Violation>,
) -> std::result::Result<SVector<f64, A>, PointResult> {
    v.clear();
    let q = match q {
        Ok(q) => q,
        Err(e) => {
            let (status, why) = classify(&e);
            return Err(PointResult::unreachable(status, why));
        }
    };
    if let (_, Some(b)) = limits_at(m, x, q, v) {
        return Err(PointResult::unreachable(PointStatus::Limits, b));
    }
    Ok(q)
}

/// Folds condition numbers `cs` into `points` (each the result of its poses within
/// every limit: reachable with condition 0 until folded, or the first orientation's
/// failure), `cs[k]` of a pose of point `owner[k]` (in orientation order): a point's
/// condition is the worst of its poses'; a point with one that is not finite is
/// singular, also one whose failure came after it, whose violations (in `deferred`)
/// are then not tallied.
pub(super) fn fold_conditions(
    points: &mut [PointResult],
    owner: &[usize],
    cs: &[f64],
    deferred: Vec<(usize, Vec<Violation>)>,
    tally: &mut Tally,
) {
    let mut singular = vec![false; points.len()];
    for (&i, &c) in owner.iter().zip(cs) {
        if singular[i] {
            continue;
        }
        if !c.is_finite() {
            singular[i] = true;
            points[i] = conditioned(c);
        } else if points[i].reachable {
            points[i].condition = points[i].condition.max(c);
        }
    }
    for (i, violations) in deferred {
        if !singular[i] {
            tally.add(&violations);
        }
    }
}

/// The result of a pose within every limit with condition number `c`: singular when
/// it is not finite (or could not be computed: NaN).
pub(super) fn conditioned(c: f64) -> PointResult {
    if c.is_finite() {
        PointResult {
            reachable: true,
            status: PointStatus::Reachable,
            condition: c,
            binding: None,
        }
    } else {
        PointResult::unreachable(PointStatus::Singular, "singular".into())
    }
}

pub(crate) fn evaluate<M: Mechanism<P, A>, const P: usize, const A: usize>(
    m: &M,
    x: &SVector<f64, P>,
    v: &mut Vec<Violation>,
) -> PointResult {
    judge(m, x, m.inverse(x), v)
}

/// Points per violated limit, each point counted once per limit it violates.
#[derive(Default)]
pub(super) struct Tally(std::collections::HashMap<String, usize>);

impl Tally {
    pub(super) fn add(&mut self, v: &[Violation]) {
        for (i, x) in v.iter().enumerate() {
            // A limit listed twice at one point (two orientations) counts once.
            if v[..i].iter().any(|y| y.limit == x.limit) {
                continue;
            }
            match self.0.get_mut(x.limit.as_str()) {
                Some(n) => *n += 1,
                None => {
                    self.0.insert(x.limit.to_string(), 1);
                }
            }
        }
    }

    pub(super) fn merge(&mut self, other: Tally) {
        for (k, n) in other.0 {
            *self.0.entry(k).or_default() += n;
        }
    }

    pub(super) fn sorted(self) -> Vec<(String, usize)> {
        let mut v: Vec<(String, usize)> = self.0.into_iter().collect();
        v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::limits::{LimitKind, Side};
    use crate::units::Quantity;

    /// The fold of a chunk's condition numbers: the worst of a point's poses; singular
    /// at one that is not finite (NaN: it failed), also when a limit failure came
    /// after it, whose violations are then not tallied; a failure after finite ones
    /// stays and is tallied.
    #[test]
    fn conditions_fold_as_point_by_point() {
        let limits = PointResult::unreachable(PointStatus::Limits, "strut 1".into());
        let mut points = vec![
            conditioned(0.0),
            conditioned(0.0),
            limits.clone(),
            limits.clone(),
            conditioned(0.0),
            limits.clone(),
        ];
        let owner = [0, 0, 1, 1, 2, 3, 4, 4];
        let cs = [
            2.0,
            3.0,
            2.0,
            f64::INFINITY,
            f64::INFINITY,
            1.5,
            f64::NAN,
            2.0,
        ];
        let v = |name: &str| {
            vec![Violation::new(
                name.to_string(),
                LimitKind::ActuatorPosition,
                Side::Max,
                Quantity::Length,
                2.0,
                1.0,
            )]
        };
        let deferred = vec![(2, v("a")), (3, v("b"))];
        let mut tally = Tally::default();
        tally.add(&v("c"));
        fold_conditions(&mut points, &owner, &cs, deferred, &mut tally);
        // Equal, NaN conditions included.
        let same = |a: &PointResult, b: &PointResult| {
            assert_eq!(
                (a.reachable, a.status, &a.binding, a.condition.to_bits()),
                (b.reachable, b.status, &b.binding, b.condition.to_bits())
            )
        };
        same(&points[0], &conditioned(3.0));
        let singular = PointResult::unreachable(PointStatus::Singular, "singular".into());
        for i in [1, 2, 4] {
            same(&points[i], &singular);
        }
        same(&points[3], &limits);
        same(&points[5], &limits);
        assert_eq!(
            tally.sorted(),
            vec![("b".to_string(), 1), ("c".to_string(), 1)]
        );
        // And as `judge` decides one pose: a finite condition is reachable.
        assert!(conditioned(1.2).reachable && !conditioned(f64::NAN).reachable);
    }
}
