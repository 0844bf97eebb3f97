//! Events of N-body systems: close encounters located on the Galerkin curves.

use super::Event;
use crate::error::{GviError, Result};

/// An N-body close encounter: the smallest separation of two bodies falls below `r_min`
/// somewhere on a step's curve (not only at its ends); the run stops there. The pair is
/// [`NBody::closest_pair`](crate::systems::NBody::closest_pair) of the crossing's q.
///
/// Errors: `r_min` not finite and positive; fewer than two bodies.
pub fn close_encounter(nbody: &crate::systems::NBody, r_min: f64) -> Result<Event<'_>> {
    if !(r_min.is_finite() && r_min > 0.0) {
        return Err(GviError::InvalidParameter {
            name: "close-encounter distance".into(),
            value: r_min,
            reason: "must be finite and positive".into(),
        });
    }
    if nbody.bodies() < 2 {
        return Err(GviError::InvalidInput {
            name: "close encounter".into(),
            reason: "needs at least two bodies".into(),
        });
    }
    let g = move |_t: f64, q: &[f64], _p: &[f64]| {
        nbody
            .closest_pair(q)
            .map_or(f64::INFINITY, |(_, _, r)| r - r_min)
    };
    Ok(Event::new(format!("close encounter below {r_min}"), g)
        .falling()
        .stop())
}
