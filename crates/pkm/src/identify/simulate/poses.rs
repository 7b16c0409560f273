//! The states of a simulated experiment: the poses of each [`super::Design`].

use nalgebra::SVector;
use rand::Rng;

use super::Experiment;
use crate::error::{Error, Result};
use crate::identify::Identifiable;
use crate::units::Quantity;

/// [`super::Design::Random`]'s `e.states` poses of `truth`, drawn with `rng`; fails when too
/// few draws are within the limits.
pub(super) fn random<M: Identifiable<P, A>, const P: usize, const A: usize>(
    truth: &M,
    e: &Experiment,
    rng: &mut impl Rng,
) -> Result<Vec<SVector<f64, P>>> {
    let mut poses = Vec::with_capacity(e.states);
    let mut draw = RandomPoses::new(truth, e.translation, e.rotation, e.condition_ratio);
    let mut tries = 0;
    while poses.len() < e.states {
        tries += 1;
        if tries > 1000 * e.states.max(1) {
            // Poses refused for their conditioning: how many, and the second
            // remedy.
            let (refused, remedy) = if draw.ill_conditioned > 0 {
                (
                    format!(
                        " ({} more within them refused beyond {} times the home \
                         pose's condition number)",
                        draw.ill_conditioned, e.condition_ratio
                    ),
                    " or raise the condition ratio",
                )
            } else {
                (String::new(), "")
            };
            return Err(Error::InvalidInput {
                what: "simulated experiment".into(),
                message: format!(
                    "found only {} poses within the limits in {} tries{refused}: \
                     reduce the translation/rotation spans{remedy}",
                    poses.len(),
                    tries - 1,
                ),
            });
        }
        if let Some(x) = draw.next(truth, rng) {
            poses.push(x);
        }
    }
    Ok(poses)
}

/// [`super::Design::OneActuator`]'s `e.states` poses of `truth` (zero readings
/// `true_zero`): the zero state, then one more actuator changed by `e.step` per state.
pub(super) fn one_actuator<M: Identifiable<P, A>, const P: usize, const A: usize>(
    truth: &M,
    true_zero: &SVector<f64, A>,
    e: &Experiment,
) -> Result<Vec<SVector<f64, P>>> {
    let mut poses = Vec::with_capacity(e.states);
    let mut dq = SVector::<f64, A>::zeros();
    let mut start = truth.info().home();
    for i in 0..e.states {
        if i > 0 {
            let j = (i - 1) % A;
            let sign = if ((i - 1) / A).is_multiple_of(2) {
                1.0
            } else {
                -1.0
            };
            dq[j] += sign * e.step;
        }
        let f = truth.forward(&(true_zero + dq), &start)?;
        start = f.pose;
        poses.push(f.pose);
    }
    Ok(poses)
}

/// Uniform random poses around home: every driven coordinate within `translation`
/// (lengths, mm) or `rotation` (angles, rad) of its home value; coordinates the
/// mechanism holds (a translational tripod's angles) stay at home. A pose within the
/// limits is kept when its condition number is at most `condition_ratio` times the
/// home pose's (every pose where home's is not finite or cannot be computed).
pub(super) struct RandomPoses<const P: usize> {
    home: SVector<f64, P>,
    span: SVector<f64, P>,
    /// Largest condition number kept (infinite: none computed).
    max_condition: f64,
    /// Poses within the limits refused for their condition number so far.
    pub(super) ill_conditioned: usize,
    violations: Vec<crate::limits::Violation>,
}

impl<const P: usize> RandomPoses<P> {
    pub(super) fn new<M: Identifiable<P, A>, const A: usize>(
        m: &M,
        translation: f64,
        rotation: f64,
        condition_ratio: f64,
    ) -> Self {
        let driven = m.info().driven();
        let span = SVector::<f64, P>::from_fn(|k, _| match m.info().coordinates()[k].quantity {
            _ if !driven.contains(&k) => 0.0,
            Quantity::Length => translation,
            Quantity::Angle => rotation,
        });
        let home = m.info().home();
        let max_condition = if condition_ratio.is_finite() {
            m.condition(&home)
                .ok()
                .filter(|c| c.is_finite())
                .map_or(f64::INFINITY, |c| condition_ratio * c)
        } else {
            f64::INFINITY
        };
        RandomPoses {
            home,
            span,
            max_condition,
            ill_conditioned: 0,
            violations: Vec::new(),
        }
    }

    /// The next draw, if `m` reaches it within every limit.
    pub(super) fn next<M: Identifiable<P, A>, const A: usize>(
        &mut self,
        m: &M,
        rng: &mut impl Rng,
    ) -> Option<SVector<f64, P>> {
        let x = SVector::<f64, P>::from_fn(|k, _| {
            self.home[k] + rng.random_range(-1.0..=1.0) * self.span[k]
        });
        let q = m.inverse(&x).ok()?;
        self.violations.clear();
        m.check_limits(&x, &q, &mut self.violations);
        if !self.violations.is_empty() {
            return None;
        }
        // NaN (a condition that cannot be computed) is refused too.
        if self.max_condition.is_finite()
            && !(m.condition_at(&x, &q).unwrap_or(f64::NAN) <= self.max_condition)
        {
            self.ill_conditioned += 1;
            return None;
        }
        Some(x)
    }
}
