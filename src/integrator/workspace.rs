//! Reusable state of one integrator and one Lagrangian: after construction, a step
//! allocates nothing (unless the Lagrangian's own derivative code does).
//!
//! A [`Workspace`] is made of named parts, each in its own file with its fields documented:
//! - the constant kinetic part of a separable Lagrangian ([`super::separable`]);
//! - [`StageScratch`]: the curve and the Lagrangian's derivatives at the quadrature nodes,
//!   the action gradient (overwritten by every evaluation);
//! - [`Iterate`]: the Newton iterate in increments, its compensation terms and the impulse;
//! - [`NewtonSystem`]: the Newton matrix, its factorisation and the structured solvers'
//!   buffers;
//! - [`GuessState`]: what the next step's initial guesses need (the previous curve in
//!   increments, a warm start, the predictor);
//! - the last completed step's curve, a [`GalerkinCurve`] ([`Workspace::curve`]).
//!
//! The per-(basis, quadrature, h) tables stay in the [`GalerkinIntegrator`]: one integrator
//! serves any number of workspaces.

use super::GalerkinIntegrator;
use super::guess::GuessState;
use super::iterate::Iterate;
use super::newton_system::NewtonSystem;
use super::separable::Separable;
use super::stage_scratch::StageScratch;
use super::velocity::VelocityState;
use crate::basis::Basis;
use crate::curve::{GalerkinCurve, GalerkinCurveRef};
use crate::error::{GviError, Result};
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;

/// Work buffers for [`GalerkinIntegrator::step`]; create with
/// [`GalerkinIntegrator::workspace`]. It also remembers the previous step's Galerkin curve,
/// from which the next initial guess is extrapolated.
#[derive(Debug, Clone)]
pub struct Workspace {
    /// What the workspace was made for: a step with another integrator is refused.
    pub(crate) made_for: MadeFor,
    /// Configuration dimension D.
    pub(crate) d: usize,
    /// Number of basis functions n.
    pub(crate) n: usize,
    /// Present for separable Lagrangians L = ½vᵀMv − V(q).
    pub(crate) separable: Option<Separable>,
    /// The system's matrix-free force-Jacobian products replace the node Jacobians in
    /// Newton–Krylov's products (large N-body systems, [`MATRIX_FREE_MIN_DIM`]).
    pub(crate) matrix_free: bool,
    /// Evaluate the curve's velocities at the nodes also for separable Lagrangians (for the
    /// value of the action).
    pub(crate) need_velocities: bool,
    /// Node values and derivatives of the stage equations.
    pub(crate) stage: StageScratch,
    /// The Newton iterate, its compensation terms and the impulse.
    pub(crate) iterate: Iterate,
    /// The Newton matrix and the linear solves.
    pub(crate) system: NewtonSystem,
    /// The initial guesses' state.
    pub(crate) guess: GuessState,
    /// The last completed step's curve (absolute coefficients Q_i, the public meaning).
    pub(crate) last: GalerkinCurve,
    /// The velocity form's iterate and linear solve (separable Lagrangians with a polynomial
    /// basis and a rule exact for the kinetic term).
    pub(crate) velocity: Option<VelocityState>,
    /// What `StageSolver::Auto` learnt from the recent steps.
    pub(crate) auto: super::auto::AutoState,
}

/// The integrator a workspace was made for (basis and its n, quadrature family and points,
/// h) and the dimension of its Lagrangian: its tables are laid out for exactly these.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MadeFor {
    pub basis: &'static str,
    pub n: usize,
    pub quadrature: String,
    pub m: usize,
    pub h: f64,
    pub d: usize,
}

impl MadeFor {
    pub(crate) fn of<B: Basis, Q: Quadrature>(gvi: &GalerkinIntegrator<B, Q>, d: usize) -> Self {
        MadeFor {
            basis: gvi.basis().name(),
            n: gvi.n(),
            quadrature: gvi.rule().family.clone(),
            m: gvi.rule().len(),
            h: gvi.step_size(),
            d,
        }
    }

    /// Whether a step of `gvi` may use this workspace (no allocation).
    pub(crate) fn matches<B: Basis, Q: Quadrature>(&self, gvi: &GalerkinIntegrator<B, Q>) -> bool {
        self.basis == gvi.basis().name()
            && self.n == gvi.n()
            && self.m == gvi.rule().len()
            && self.h.to_bits() == gvi.step_size().to_bits()
            && self.quadrature == gvi.rule().family
    }
}

impl std::fmt::Display for MadeFor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} basis n = {}, {} with {} points, h = {}, D = {}",
            self.basis, self.n, self.quadrature, self.m, self.h, self.d
        )
    }
}

/// Configuration dimension from which Newton–Krylov uses a system's matrix-free force-Jacobian
/// products (N-body: pairwise, O(N²) per node) instead of the node Jacobians (O(D²) memory and
/// work per node). Below it the stored Jacobians are cheaper: one pairwise product costs about
/// as much as forming a node's Jacobian, and GMRES makes several per Newton iteration.
pub const MATRIX_FREE_MIN_DIM: usize = 192;

impl Workspace {
    pub(crate) fn new<B: Basis, Q: Quadrature, L: Lagrangian>(
        gvi: &GalerkinIntegrator<B, Q>,
        lagrangian: &L,
    ) -> Result<Self> {
        let t = gvi.tables();
        let d = lagrangian.dim();
        if d == 0 {
            return Err(GviError::DimensionMismatch {
                what: "configuration space of the Lagrangian (must be ≥ 1)".into(),
                expected: 1,
                got: 0,
            });
        }
        let (n, m, h) = (t.n, t.m, gvi.step_size());
        // A time-dependent or forced system takes the general path with the node times
        // (node_model.rs): the structured solvers rest on a time-independent L_q(q) alone.
        let (timed, forced) = (!lagrangian.is_autonomous(), lagrangian.is_forced());
        let separable = match lagrangian.mass_matrix() {
            Some(mass) if !timed && !forced => Some(Separable::new(&mass, t, d, h)?),
            _ => None,
        };
        // The buffers only: the Schur form is built by the first solve that needs it.
        let kron = match &separable {
            Some(sep) => super::kronecker::KroneckerWork::new(
                n - 1,
                d,
                sep.mass(),
                lagrangian.coordinate_blocks(),
                m,
                gvi.options().structured.self_block_rate,
            ),
            _ => None,
        };
        // Probe with empty slices: a system without the optional kernels answers `false`.
        let matrix_free = d >= MATRIX_FREE_MIN_DIM
            && kron.is_some()
            && lagrangian.force_jacobian_products_at_points(&[], &[], &mut []);
        let block_entries = match (&kron, lagrangian.coordinate_blocks()) {
            (Some(kw), Some(b))
                if kw.block() == b
                    && b < d
                    && lagrangian.force_jacobian_diagonal_blocks_at_points(&[], &mut []) =>
            {
                m * d * b
            }
            _ => 0,
        };
        // Non-separable: the matrix-free Jacobian products keep node Hessians.
        let general = separable.is_none();
        let krylov = kron
            .is_some()
            .then(|| super::krylov::KrylovWork::new(n - 1, m, d));
        let substeps = gvi.options().predictor_substeps.unwrap_or(n.max(8));
        let velocity = match (&t.velocity, &separable) {
            (Some(vt), Some(sep)) => {
                let rate = gvi.options().structured.velocity_self_block_rate;
                VelocityState::new(vt, d, sep, lagrangian.coordinate_blocks(), rate)
            }
            _ => None,
        };
        let mut stage = StageScratch::new(n, m, d, general, block_entries);
        stage.set_time_dependence(timed, forced);
        Ok(Workspace {
            made_for: MadeFor::of(gvi, d),
            d,
            n,
            separable,
            matrix_free,
            need_velocities: false,
            stage,
            iterate: Iterate::new(n, d),
            system: NewtonSystem::new(n, d, kron, krylov),
            guess: GuessState::new(n, d, substeps),
            last: GalerkinCurve::with_capacity(n, d, h),
            velocity,
            auto: Default::default(),
        })
    }

    /// The Galerkin coefficients of the last completed step (n×D, row i = Q_i).
    pub fn coefficients(&self) -> &[f64] {
        self.last.coefficients()
    }

    /// The Galerkin curve of the last completed step, starting at time 0 (a workspace does not
    /// know the time of its step: set it with [`GalerkinCurveRef::starting_at`]). All zeros
    /// before the first step.
    pub fn curve(&self) -> GalerkinCurveRef<'_> {
        self.last.as_ref()
    }

    /// Forget the previous step's curve (the next guess will not extrapolate) and any pending
    /// warm start.
    pub fn reset(&mut self) {
        self.guess.forget();
        self.iterate.set_ready_residual(None);
        self.system.invalidate();
        if let Some(v) = self.velocity.as_mut() {
            v.forget_previous();
        }
    }

    /// Copy another workspace of the same integrator and dimension into this one (a
    /// [`Stepper`](super::Stepper) checkpoint's restore).
    pub(crate) fn restore_from(&mut self, saved: &Workspace) {
        self.clone_from(saved);
    }

    /// Forget everything a previous run left: the guesses' history, a pending warm start,
    /// the ready residual, the reusable factorisation and `Auto`'s memory.
    pub(crate) fn start_afresh(&mut self) {
        self.reset();
        self.auto = Default::default();
    }

    /// Start the next step's Newton iteration from the given Galerkin coefficients (n×D, row
    /// i = Q_i, in this integrator's basis) instead of choosing among the built-in guesses —
    /// e.g. a curve solved at a lower n and refitted, when an error estimate re-solves the
    /// same step at a higher n. The first row is replaced by the step's q_k. Used by one step
    /// only; if Newton fails from it, the built-in guesses are tried as usual.
    ///
    /// Errors: wrong length or non-finite entries.
    pub fn warm_start(&mut self, coefficients: &[f64]) -> Result<()> {
        crate::error::ensure_len(
            "warm-start coefficients",
            self.n * self.d,
            coefficients.len(),
        )?;
        crate::error::ensure_finite("warm-start coefficients", coefficients)?;
        self.guess.set_warm_start(coefficients);
        Ok(())
    }

    /// Set the start time t_k of the next step. Non-autonomous and forced systems are
    /// evaluated at the node times t_k + c_j h; [`GalerkinIntegrator::step`] advances the time
    /// by h after each step, and a [`Stepper`](super::Stepper) sets it itself. Autonomous,
    /// unforced systems ignore it.
    ///
    /// Errors: a non-finite t.
    pub fn set_time(&mut self, t: f64) -> Result<()> {
        crate::error::ensure_finite("step start time t_k", &[t])?;
        self.stage.set_step_start(t, 0.0, &[]);
        Ok(())
    }

    /// The start time t_k of the next step (see [`set_time`](Self::set_time)).
    pub fn time(&self) -> f64 {
        self.stage.step_start()
    }

    /// Dimension D.
    pub fn dim(&self) -> usize {
        self.d
    }

    /// Whether Newton–Krylov takes the system's matrix-free force-Jacobian products (D at
    /// least [`MATRIX_FREE_MIN_DIM`] and a system that provides them, e.g. N-body from 64
    /// bodies in 3D) instead of forming the node Jacobians.
    pub fn uses_matrix_free_products(&self) -> bool {
        self.matrix_free
    }
}
