//! What the initial guesses of the next step need ([`super::guess`]): the previous step's
//! curve in increments (for the extrapolated and linear guesses), a pending warm start, the
//! candidate being scored and the best so far, the memory of the last guess competition, and
//! the RK4 predictor's buffers.
//!
//! The previous curve is kept here as increments ΔP_i from q_{k−1} (not as the absolute
//! coefficients the caller sees, [`Workspace::curve`](super::Workspace::curve)): extrapolating
//! increments keeps the guess free of the rounding of q_k (docs/DESIGN.md §4), and so the
//! guesses are bit for bit what they were before the workspace was split.

use crate::stats::InitialGuess;

/// Initial-guess state carried from step to step, and the guesses' scratch.
#[derive(Debug, Clone)]
pub(crate) struct GuessState {
    /// Previous step's increments ΔP_i (n×D) …
    pub prev: Vec<f64>,
    /// … and whether they are valid.
    pub has_prev: bool,
    /// The last guess competition's winner …
    pub guess_winner: Option<InitialGuess>,
    /// … its residual …
    pub guess_reference: f64,
    /// … and the steps since it was held.
    pub guess_age: usize,
    /// Force evaluations spent by the RK4 predictor guess in the current step.
    pub guess_force_evaluations: usize,
    /// A caller-supplied start for the next step's Newton iteration (absolute coefficients,
    /// n×D) …
    pub warm: Vec<f64>,
    /// … and whether it is pending; see [`Workspace::warm_start`](super::Workspace::warm_start).
    pub has_warm: bool,
    /// The candidate guess (increments, n×D) …
    pub cand: Vec<f64>,
    /// … and the best one so far.
    pub best: Vec<f64>,
    /// RK4 predictor: substeps …
    pub rk_substeps: usize,
    /// … states at substep ends ((S+1)×2D) …
    pub rk_states: Vec<f64>,
    /// … stages (4×2D) …
    pub rk_k: Vec<f64>,
    /// … and stage input (2D).
    pub rk_tmp: Vec<f64>,
    /// Scratch for fitting values to coefficients (n each).
    pub fit_col: Vec<f64>,
    /// See `fit_col`.
    pub fit_scratch: Vec<f64>,
}

impl GuessState {
    /// Buffers for n basis functions, D coordinates and `substeps` RK4 predictor substeps.
    pub(crate) fn new(n: usize, d: usize, substeps: usize) -> Self {
        GuessState {
            prev: vec![0.0; n * d],
            has_prev: false,
            guess_winner: None,
            guess_reference: 0.0,
            guess_age: 0,
            guess_force_evaluations: 0,
            warm: vec![0.0; n * d],
            has_warm: false,
            cand: vec![0.0; n * d],
            best: vec![0.0; n * d],
            rk_substeps: substeps,
            rk_states: vec![0.0; (substeps + 1) * 2 * d],
            rk_k: vec![0.0; 8 * d],
            rk_tmp: vec![0.0; 2 * d],
            fit_col: vec![0.0; n],
            fit_scratch: vec![0.0; n],
        }
    }
}
