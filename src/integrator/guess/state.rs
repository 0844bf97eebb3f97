//! What the initial guesses of the next step need ([`super::guess`]): the previous step's
//! curve in increments (for the extrapolated and linear guesses), a pending warm start, the
//! candidate being scored and the best so far, the memory of the last guess competition, and
//! the RK4 predictor's buffers.
//!
//! The previous curve is kept here as increments ΔP_i from q_{k−1} (not as the absolute
//! coefficients the caller sees, [`Workspace::curve`](crate::integrator::Workspace::curve)): extrapolating
//! increments keeps the guess free of the rounding of q_k (docs/DESIGN.md §4), and so the
//! guesses are bit for bit what they were before the workspace was split.
//!
//! Its fields are private to the guess module: the rest of the step sees the candidate curve
//! and the memory through the methods below, so that the flags (`has_prev`, `has_warm`) and the
//! buffers they describe cannot drift apart.

use crate::stats::InitialGuess;

/// Initial-guess state carried from step to step, and the guesses' scratch.
#[derive(Debug, Clone)]
pub(crate) struct GuessState {
    /// Previous step's increments ΔP_i (n×D) …
    pub(super) prev: Vec<f64>,
    /// … and whether they are valid.
    pub(super) has_prev: bool,
    /// The last guess competition's winner …
    pub(super) guess_winner: Option<InitialGuess>,
    /// … its residual …
    pub(super) guess_reference: f64,
    /// … and the steps since it was held.
    pub(super) guess_age: usize,
    /// Force evaluations spent by the RK4 predictor guess in the current step.
    pub(super) guess_force_evaluations: usize,
    /// A caller-supplied start for the next step's Newton iteration (absolute coefficients,
    /// n×D) …
    pub(super) warm: Vec<f64>,
    /// … and whether it is pending; see [`Workspace::warm_start`](crate::integrator::Workspace::warm_start).
    pub(super) has_warm: bool,
    /// The candidate guess (increments, n×D) …
    pub(super) cand: Vec<f64>,
    /// … and the best one so far.
    pub(super) best: Vec<f64>,
    /// RK4 predictor: substeps …
    pub(super) rk_substeps: usize,
    /// … states at substep ends ((S+1)×2D) …
    pub(super) rk_states: Vec<f64>,
    /// … stages (4×2D) …
    pub(super) rk_k: Vec<f64>,
    /// … and stage input (2D).
    pub(super) rk_tmp: Vec<f64>,
    /// Scratch for fitting values to coefficients (n each).
    pub(super) fit_col: Vec<f64>,
    /// See `fit_col`.
    pub(super) fit_scratch: Vec<f64>,
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

    /// The candidate guess, increments ΔQ_i from q_k (n×D): the last guess made.
    pub(crate) fn candidate(&self) -> &[f64] {
        &self.cand
    }

    /// Remember a solved step's increments ΔQ (n×D) for the next step's guesses.
    pub(crate) fn remember(&mut self, increments: &[f64]) {
        self.prev.copy_from_slice(increments);
        self.has_prev = true;
    }

    /// Forget the previous step's curve (after a failed step, or on request).
    pub(crate) fn forget_previous(&mut self) {
        self.has_prev = false;
    }

    /// Forget the previous curve and any pending warm start.
    pub(crate) fn forget(&mut self) {
        self.has_prev = false;
        self.has_warm = false;
    }

    /// Start the next step from these absolute coefficients (n×D, checked by the caller).
    pub(crate) fn set_warm_start(&mut self, coefficients: &[f64]) {
        self.warm.copy_from_slice(coefficients);
        self.has_warm = true;
    }

    /// Whether a warm start is pending for the next step.
    pub(crate) fn warm_start_pending(&self) -> bool {
        self.has_warm
    }

    /// The RK4 predictor's force evaluations since the last call (counted into the step's
    /// gradient evaluations), and reset the count.
    pub(crate) fn take_force_evaluations(&mut self) -> usize {
        std::mem::take(&mut self.guess_force_evaluations)
    }
}
