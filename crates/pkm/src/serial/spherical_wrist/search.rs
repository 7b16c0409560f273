//! The branch-and-bound toward the solution nearest given joint values, shared by the
//! closed forms.

use nalgebra::Vector6;

/// The joint values whose nearest solution [`super::SphericalWrist::solve`] is asked for:
/// nearest in `|wrap(q) - near|^2`, where `wrap` shifts the joints marked `wrapped` by
/// whole turns to within half a turn of `near` (as [`crate::serial::arm::SerialArm`] ranks its
/// solutions).
pub(in crate::serial) struct Nearest<'a> {
    pub near: &'a Vector6<f64>,
    pub wrapped: [bool; 6],
}

/// The branch-and-bound of [`super::SphericalWrist::solve`] toward [`Nearest`]: each branch
/// (shoulder, then elbow, then wrist flip) is tried nearest first, and one whose
/// joints known so far are already farther than a whole solution found is skipped.
///
/// The squared distance of a solution is a sum of one term per joint, each
/// nonnegative, so a partial sum never exceeds the whole (rounding to nearest is
/// monotone). A branch is skipped only when its partial sum exceeds the best whole
/// sum by more than 1e-9 relative: far beyond the few ulps by which sums of the same
/// terms in another order (the caller's ranking) can differ, so a skipped solution is
/// strictly farther than one kept and never the nearest, nor tied with it.
pub(in crate::serial) struct Search<'a> {
    nearest: Option<&'a Nearest<'a>>,
    best: f64,
}

impl<'a> Search<'a> {
    pub(in crate::serial) fn new(nearest: Option<&'a Nearest<'a>>) -> Self {
        Search {
            nearest,
            best: f64::INFINITY,
        }
    }

    /// Joint `i`'s term `(wrap(q) - near_i)^2`; 0 without [`Nearest`].
    pub(in crate::serial) fn term(&self, i: usize, q: f64) -> f64 {
        use std::f64::consts::TAU;
        let Some(n) = self.nearest else {
            return 0.0;
        };
        let near = n.near[i];
        // `SerialArm::wrap`'s operations, so the same wrapped value.
        let w = if n.wrapped[i] {
            q - TAU * crate::rotation::whole_turns(q - near)
        } else {
            q
        };
        (w - near) * (w - near)
    }

    /// Whether a branch whose joints so far sum to `partial` cannot hold the nearest.
    pub(in crate::serial) fn beyond(&self, partial: f64) -> bool {
        partial > self.best * (1.0 + 1e-9)
    }

    /// A whole solution at squared distance `whole` was found.
    pub(in crate::serial) fn found(&mut self, whole: f64) {
        if whole < self.best {
            self.best = whole;
        }
    }

    /// The indices of a subproblem's two solutions `qs` of joint `i` (one when they are
    /// equal), nearer first with [`Nearest`], else in order.
    pub(in crate::serial) fn order(&self, i: usize, qs: &[f64; 2]) -> impl Iterator<Item = usize> {
        let order = if qs[1] == qs[0] {
            [Some(0), None]
        } else if self.nearest.is_some() && self.term(i, qs[1]) < self.term(i, qs[0]) {
            [Some(1), Some(0)]
        } else {
            [Some(0), Some(1)]
        };
        order.into_iter().flatten()
    }
}
