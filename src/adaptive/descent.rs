//! How far a tolerance-driven run steps down the ladder after an accepted step: one rung per
//! factor [`DOWN`] by which the embedded estimate lies below the budget, at most
//! [`MAX_DOWN`]. Shared by the embedded control ([`super::embedded`]) and the ladder's cost
//! comparison ([`super::ladder::Ladder::next_rung`]); it sits apart from both so that neither
//! imports the other.

/// Step down one rung per factor DOWN that the estimate lies below the budget (at most
/// [`MAX_DOWN`]), unless staying is predicted cheaper
/// ([`Ladder::next_rung`](super::ladder::Ladder::next_rung)).
const DOWN: f64 = 0.05;
/// At most this many rungs down from one step to the next.
const MAX_DOWN: usize = 5;

/// How many rungs to step down after an estimate `e`: one per factor [`DOWN`] below the
/// budget, at most [`MAX_DOWN`].
pub(super) fn rungs_down(e: f64, budget: f64) -> usize {
    let mut k = 0;
    let mut level = DOWN * budget;
    while e < level && k < MAX_DOWN {
        k += 1;
        level *= DOWN;
    }
    k
}
