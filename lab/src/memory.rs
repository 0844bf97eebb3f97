//! Memory estimated before the work, and the one limit every command holds it to.
//!
//! A command that keeps a whole run (or many) in memory estimates the bytes up front from its
//! sizes (steps, n, dimension, members, modes) and refuses work above [`LIMIT_BYTES`] with the
//! estimate in the message ([`ensure_fits`]), before it computes anything. Streamed output
//! (`gvi run` writing CSV) holds one row at a time and needs no estimate.

use crate::error::{LabError, Result};

/// The memory limit of every command's estimate: 4 GB.
pub const LIMIT_BYTES: f64 = 4e9;

/// Bytes of one stored state with its Galerkin step, in dimension `d` with `n` basis functions
/// per coordinate: q and p, the step's coefficients, the step statistics and the vector headers
/// ([`galerkin_vi::Trajectory`]).
pub fn trajectory_bytes_per_step(n: usize, d: usize) -> f64 {
    (8 * (n * d + 2 * d) + 3 * 24 + 64) as f64
}

/// Refuse `what` (e.g. "the check of 10⁸ steps") when `estimate` bytes exceed [`LIMIT_BYTES`]
/// (a NaN or infinite estimate too); `hint` says what to shrink.
pub fn ensure_fits(what: impl Into<String>, estimate: f64, hint: &str) -> Result<()> {
    if estimate <= LIMIT_BYTES {
        return Ok(());
    }
    Err(LabError::MemoryEstimate {
        what: what.into(),
        estimate,
        limit: LIMIT_BYTES,
        hint: hint.to_string(),
    })
}
