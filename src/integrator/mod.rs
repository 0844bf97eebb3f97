//! The Galerkin variational integrator (docs/DESIGN.md §2; paper §3).
//!
//! [`GalerkinIntegrator`] is built once per (basis, quadrature, h): it tabulates the basis and
//! its derivative at the quadrature nodes, the kinetic matrix K_ab = Σ_j b_j φ_a'(c_j) φ_b'(c_j),
//! the coefficients of constant and linear curves and the extrapolation table used for initial
//! guesses. The Lagrangian is a separate value passed to [`step`](GalerkinIntegrator::step) and
//! [`integrate`](GalerkinIntegrator::integrate), as problem and algorithm are in
//! DifferentialEquations.jl.
//!
//! One step, in position–momentum form: given (q_k, p_k), set Q_0 = q_k and solve
//! p_k + ∂S/∂Q_0 = 0 (the discrete Legendre transform, paper §1.1 and eq. (4)) and ∂S/∂Q_i = 0,
//! i = 1 … n−2 (the internal stage equations, eq. (3)) for Q_1 … Q_{n−1} by Newton's method with the
//! exact Jacobian; then q_{k+1} = Q_{n−1} and p_{k+1} = ∂S/∂Q_{n−1}.
//!
//! # Round-off
//!
//! Round-off sets the floor of a spectral method (docs/DESIGN.md §4), so the step is formulated
//! for it. The Newton unknowns are the increments ΔQ_i = Q_i − u_i q_k (u: the coefficients
//! of the constant curve, Σ u_i φ_i ≡ 1): the curve at the nodes is q_k + Φ ΔQ, its velocity
//! Φ' ΔQ / h, the kinetic residual (1/h) K M ΔQ, and q_{k+1} = q_k + ΔQ_{n−1}, an increment
//! known to full relative accuracy. p_{k+1} = p_k + h Σ_j b_j L_q(c_j), the total impulse.
//! [`integrate`](GalerkinIntegrator::integrate) (and the
//! [`GalerkinMethod`](crate::baselines::GalerkinMethod) adapter) then add the increments with
//! compensated summation ([`step_compensated`](GalerkinIntegrator::step_compensated)), unless
//! [`NewtonOptions::compensated`] is off. The public coefficients
//! ([`Workspace::coefficients`], `Trajectory::coefficients`) stay absolute Q.

mod auto;
mod dd;
mod discrete_action;
mod equations;
mod frozen;
mod guess;
mod iterate;
mod kronecker;
mod krylov;
mod legendre_transform;
mod linear;
mod modal;
mod newton;
mod newton_system;
mod nodal_newton;
mod node_model;
mod options;
mod self_blocks;
mod separable;
mod solver;
mod stage;
mod stage_scratch;
mod stepper;
mod tangent;
pub(crate) mod velocity;
mod workspace;

pub use discrete_action::DiscreteLagrangian;
pub use equations::{Correction, StageEquations, StageSolve};
pub use newton::{
    DenseOptions, InitialGuess, NewtonOptions, StepFailure, StepStats, StructuredOptions,
};
pub use solver::StageSolver;
pub use stepper::{Checkpoint, Stepper};
pub use tangent::{StepJacobian, TangentWorkspace};
pub use workspace::{MATRIX_FREE_MIN_DIM, Workspace};

use std::sync::OnceLock;

use crate::basis::{AnyBasis, Basis, BasisKind, ChebyshevLagrange, CurveFit};
use crate::error::{GviError, Result, ensure_finite, ensure_len};
use crate::lagrangian::Lagrangian;
use crate::quadrature::{GaussLegendre, Quadrature, QuadratureKind, QuadratureRule};
use crate::trajectory::Trajectory;

/// A Galerkin variational integrator for a basis `B` and quadrature `Q` at fixed step h.
///
/// ```
/// use galerkin_vi::prelude::*;
///
/// // The paper's spectral method: Chebyshev–Lagrange, n = 16, 2n Gauss points, h = 2.
/// let gvi = GalerkinIntegrator::spectral(16, 2.0).unwrap();
/// let kepler = Kepler::new(1.0).unwrap();
/// let traj = gvi.integrate(&kepler, 0.0, &[0.4, 0.0], &[0.0, 2.0], 10).unwrap();
/// assert_eq!(traj.steps(), 10);
/// // Dense output along the Galerkin curves.
/// let q = traj.position_at(3.3).unwrap();
/// assert!((q[0] * q[0] + q[1] * q[1]).sqrt() < 1.6 + 1e-6);
/// ```
#[derive(Debug, Clone)]
pub struct GalerkinIntegrator<B: Basis = ChebyshevLagrange, Q: Quadrature = GaussLegendre> {
    /// Shared with the trajectories the integrator makes, which evaluate their curves in it.
    basis: std::sync::Arc<B>,
    quadrature: Q,
    rule: QuadratureRule,
    h: f64,
    options: NewtonOptions,
    tables: Tables,
    /// A user's stage solver, used instead of `options.solver` when set.
    stage_solver: Option<std::sync::Arc<dyn StageSolve>>,
}

/// Precomputed basis tables (row-major).
#[derive(Debug, Clone)]
pub(crate) struct Tables {
    pub n: usize,
    pub m: usize,
    /// φ_i(c_j) at [j*n + i].
    pub phi: Vec<f64>,
    /// dφ_i/dτ(c_j) at [j*n + i].
    pub dphi: Vec<f64>,
    /// Quadrature weights b_j.
    pub weights: Vec<f64>,
    /// K_ab = Σ_j b_j φ_a'(c_j) φ_b'(c_j), n×n.
    pub kinetic: Vec<f64>,
    /// Coefficients of the constant curve 1.
    pub unit: Vec<f64>,
    /// Coefficients of the curve τ.
    pub ramp: Vec<f64>,
    /// dφ_i/dτ at τ = 1.
    pub dphi_end: Vec<f64>,
    /// Extrapolation operator E (n×n): coefficients of the next step's guess are E · Q_prev,
    /// i.e. the previous curve continued to τ ∈ [1, 2] and re-fitted.
    /// `None` when the continuation overflows (very large n): extrapolation is then skipped.
    pub extrapolate: Option<Vec<f64>>,
    /// Interpolation of curve values at the basis's interpolation nodes.
    pub fit: CurveFit,
    /// Chebyshev coefficients of the Galerkin curve from its basis coefficients (n×n):
    /// a = C·Q, with q(τ) ≈ Σ_j a_j T_j(2τ − 1) (exact for polynomial bases).
    pub chebyshev: Vec<f64>,
    /// The Schur form of the stage matrices for the Kronecker solver, built when first asked
    /// for ([`Tables::kron`]).
    kron: OnceLock<Option<kronecker::KroneckerTables>>,
    /// The velocity form of the stage equations (`None` when it is not the same map: the
    /// Fourier basis, or a rule too weak for the kinetic term).
    pub velocity: Option<velocity::VelocityTables>,
}

impl GalerkinIntegrator<ChebyshevLagrange, GaussLegendre> {
    /// The paper's spectral variational integrator: Chebyshev–Lagrange basis with n functions
    /// and Gauss–Legendre quadrature with 2n points, step h.
    pub fn spectral(n: usize, h: f64) -> Result<Self> {
        GalerkinIntegrator::new(ChebyshevLagrange::new(n)?, GaussLegendre::new(2 * n)?, h)
    }
}

impl GalerkinIntegrator<AnyBasis, QuadratureRule> {
    /// An integrator chosen by value: basis kind and n, quadrature kind and points (`None`:
    /// the kind's default for n, 2n Gauss–Legendre points), and step h.
    pub fn from_kinds(
        basis: BasisKind,
        n: usize,
        quadrature: QuadratureKind,
        points: Option<usize>,
        h: f64,
    ) -> Result<Self> {
        let b = basis.build(n)?;
        let q = quadrature.build(points.unwrap_or_else(|| quadrature.default_points(n)))?;
        GalerkinIntegrator::new(b, q, h)
    }
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// Build the integrator: validates h, the quadrature, and that the quadrature is strong
    /// enough for the basis (the kinetic stage matrix must be invertible; for polynomial bases
    /// the rule must integrate φ_a'φ_b', of degree 2n − 4, exactly).
    pub fn new(basis: B, quadrature: Q, h: f64) -> Result<Self> {
        if !(h.is_finite() && h > 0.0) {
            return Err(GviError::InvalidStepSize { h });
        }
        let n = basis.len();
        if n < 2 {
            return Err(GviError::InvalidBasisSize {
                n,
                basis: basis.name().into(),
                reason: "a Galerkin curve needs at least the two end functions".into(),
            });
        }
        if let Some(made_for) = basis.step_size()
            && (made_for - h).abs() > 1e-12 * h
        {
            return Err(GviError::Mismatch {
                expected: format!(
                    "the step size h = {made_for} the {} basis was made for",
                    basis.name()
                ),
                got: format!("h = {h}"),
            });
        }
        let rule = quadrature.rule()?;
        basis.check_quadrature(&rule)?;
        let tables = Tables::build(&basis, &rule)?;
        let integrator = GalerkinIntegrator {
            basis: std::sync::Arc::new(basis),
            quadrature,
            rule,
            h,
            options: NewtonOptions::default(),
            tables,
            stage_solver: None,
        };
        integrator.check_quadrature_strength()?;
        Ok(integrator)
    }

    /// Replace the Newton options.
    pub fn with_options(mut self, options: NewtonOptions) -> Self {
        self.options = options;
        self
    }

    /// Solve the stage equations of every step with a custom [`StageSolve`] instead of the
    /// built-in solver `NewtonOptions::solver` names (see [`StageEquations`] for what it can
    /// use). The discrete Lagrangian's two-point problem keeps the built-in solver.
    pub fn with_stage_solver<S: StageSolve + 'static>(mut self, solver: S) -> Self {
        self.stage_solver = Some(std::sync::Arc::new(solver));
        self
    }

    /// The custom stage solver, if one was set.
    pub fn stage_solver(&self) -> Option<&dyn StageSolve> {
        self.stage_solver.as_deref()
    }

    /// The Newton options.
    pub fn options(&self) -> &NewtonOptions {
        &self.options
    }

    /// The step size h.
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// Number of basis functions n.
    pub fn n(&self) -> usize {
        self.tables.n
    }

    /// The basis.
    pub fn basis(&self) -> &B {
        &self.basis
    }

    /// The quadrature recipe.
    pub fn quadrature(&self) -> &Q {
        &self.quadrature
    }

    /// The quadrature nodes and weights in use.
    pub fn rule(&self) -> &QuadratureRule {
        &self.rule
    }

    pub(crate) fn tables(&self) -> &Tables {
        &self.tables
    }

    /// Interpolation of curve values at the basis's interpolation nodes (values to
    /// coefficients): how a curve known by its values, e.g. another rung's curve or a
    /// predictor, becomes coefficients in this integrator's basis.
    pub fn curve_fit(&self) -> &CurveFit {
        &self.tables.fit
    }

    /// The n×n matrix C of the Chebyshev coefficients of a curve from its basis coefficients,
    /// a = C·Q with q(τ) ≈ Σ_j a_j T_j(2τ − 1) (exact for polynomial bases); row j is mode j.
    pub fn chebyshev_transform(&self) -> &[f64] {
        &self.tables.chebyshev
    }

    /// The kinetic matrix K_ab = Σ_j b_j φ_a'(c_j) φ_b'(c_j) (n×n, row-major, τ-units): the
    /// Jacobian of a free particle's stage equations is K ⊗ M / h.
    pub fn kinetic_matrix(&self) -> &[f64] {
        &self.tables.kinetic
    }

    /// 2-norm condition number of the stage block of the kinetic matrix (rows 0…n−2, columns
    /// 1…n−1), the matrix Newton inverts for a free particle. Large values mean the basis is
    /// ill-conditioned at this n.
    pub fn kinetic_condition_number(&self) -> f64 {
        let block = self.stage_kinetic_block();
        let r = crate::linalg::reciprocal_condition(&block, self.tables.n - 1);
        if r > 0.0 { 1.0 / r } else { f64::INFINITY }
    }

    fn stage_kinetic_block(&self) -> Vec<f64> {
        let n = self.tables.n;
        let k = n - 1;
        let mut block = vec![0.0; k * k];
        for a in 0..k {
            for b in 0..k {
                block[a * k + b] = self.tables.kinetic[a * n + b + 1];
            }
        }
        block
    }

    fn check_quadrature_strength(&self) -> Result<()> {
        let n = self.tables.n;
        let required = match self.basis.polynomial_degree() {
            Some(p) => 2 * p.saturating_sub(1),
            None => 0,
        };
        let block = self.stage_kinetic_block();
        let rcond = crate::linalg::reciprocal_condition(&block, n - 1);
        let too_weak_degree =
            self.basis.polynomial_degree().is_some() && self.rule.degree < required;
        let exact_rule = self.basis.polynomial_degree().is_some() && !too_weak_degree;
        let singular = rcond.is_nan() || rcond < 1e-13;
        if exact_rule && singular {
            // The quadrature is exact for the kinetic integrand: the basis itself is
            // numerically singular at this n, not the rule.
            return Err(GviError::InvalidBasisSize {
                n,
                basis: self.basis.name().into(),
                reason: format!(
                    "the kinetic matrix is numerically singular (reciprocal condition number \
                     {rcond:.3e}) although {} is exact for it: this basis is ill-conditioned \
                     at this n (use a smaller n or the chebyshev basis)",
                    self.quadrature.name()
                ),
            });
        }
        if too_weak_degree || singular {
            return Err(GviError::QuadratureTooWeak {
                quadrature: self.quadrature.name(),
                degree: self.rule.degree,
                basis: self.basis.name().into(),
                n,
                required,
                rcond,
            });
        }
        Ok(())
    }

    /// An empty trajectory of this integrator's curves (its basis, shared), for `capacity`
    /// steps of dimension `dim` from `t0`.
    pub(crate) fn empty_trajectory(&self, t0: f64, dim: usize, capacity: usize) -> Trajectory {
        let basis: crate::trajectory::SharedBasis = self.basis.clone();
        let mut traj = Trajectory::new(
            basis,
            &self.rule.family,
            self.rule.len(),
            self.h,
            t0,
            dim,
            capacity,
        );
        // A parametrised built-in basis (enriched) cannot be rebuilt from its name and n.
        traj.set_user_basis(BasisKind::of(&*self.basis).is_none_or(BasisKind::is_parametrised));
        traj
    }

    /// Validate an initial state for `lagrangian`.
    fn check_state<L: Lagrangian>(&self, lagrangian: &L, q: &[f64], p: &[f64]) -> Result<()> {
        let d = lagrangian.dim();
        ensure_len("initial position q0", d, q.len())?;
        ensure_len("initial momentum p0", d, p.len())?;
        ensure_finite("initial position q0", q)?;
        ensure_finite("initial momentum p0", p)?;
        Ok(())
    }

    /// A fresh workspace for `lagrangian` (allocates; reuse it across steps).
    pub fn workspace<L: Lagrangian>(&self, lagrangian: &L) -> Result<Workspace> {
        Workspace::new(self, lagrangian)
    }

    /// Integrate `steps` steps from (q0, p0) at time t0, keeping every step's Galerkin
    /// coefficients for dense output.
    ///
    /// On a Newton failure the error carries the trajectory computed up to the failing step.
    pub fn integrate<L: Lagrangian>(
        &self,
        lagrangian: &L,
        t0: f64,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
    ) -> std::result::Result<Trajectory, IntegrationFailure> {
        self.integrate_until(lagrangian, t0, q0, p0, steps, &|| false)
    }

    /// [`integrate`](Self::integrate), asking `stop` before every step whether to stop
    /// there: a `true` ends the run with [`GviError::Interrupted`] and the steps before it as
    /// the partial trajectory. This is the one fixed-n step loop: `integrate` is this with a
    /// `stop` that never says yes, and [`crate::solve::solve_until`] runs it with the
    /// caller's, so the two cannot drift apart (an interruptible copy of the loop once
    /// skipped `integrate`'s check of t0).
    pub(crate) fn integrate_until<L: Lagrangian>(
        &self,
        lagrangian: &L,
        t0: f64,
        q0: &[f64],
        p0: &[f64],
        steps: usize,
        stop: &dyn Fn() -> bool,
    ) -> std::result::Result<Trajectory, IntegrationFailure> {
        let fail = |error| IntegrationFailure {
            error,
            partial: None,
        };
        if steps == 0 || steps > MAX_STEPS {
            return Err(fail(GviError::InvalidStepCount {
                steps,
                reason: format!("need 1 ≤ steps ≤ {MAX_STEPS}"),
            }));
        }
        if !t0.is_finite() {
            return Err(fail(GviError::NonFinite {
                what: "initial time t0".into(),
                value: t0,
            }));
        }
        let mut stepper = self.stepper(lagrangian, t0, q0, p0).map_err(fail)?;
        let mut traj = self.empty_trajectory(t0, lagrangian.dim(), steps);
        traj.push_state(q0, p0);
        for k in 0..steps {
            if stop() {
                return Err(IntegrationFailure {
                    error: GviError::Interrupted {
                        step: k,
                        t: stepper.time(),
                    },
                    partial: Some(Box::new(traj)),
                });
            }
            match stepper.step() {
                Ok(stats) => traj.push_step(
                    stepper.curve(),
                    stepper.position(),
                    stepper.momentum(),
                    stats,
                ),
                Err(error) => {
                    return Err(IntegrationFailure {
                        error,
                        partial: Some(Box::new(traj)),
                    });
                }
            }
        }
        Ok(traj)
    }
}

/// The most steps one `integrate` call accepts (a guard against absurd input).
pub const MAX_STEPS: usize = 100_000_000;

/// A failed integration: the error and, for a Newton failure, the trajectory up to the step
/// that failed.
#[derive(Debug)]
pub struct IntegrationFailure {
    /// What went wrong.
    pub error: GviError,
    /// The trajectory computed before the failure (for solver failures).
    pub partial: Option<Box<Trajectory>>,
}

impl std::fmt::Display for IntegrationFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)?;
        if let Some(t) = &self.partial {
            write!(f, " ({} steps completed before it)", t.steps())?;
        }
        Ok(())
    }
}

impl std::error::Error for IntegrationFailure {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

impl From<IntegrationFailure> for GviError {
    fn from(f: IntegrationFailure) -> Self {
        f.error
    }
}

impl From<GviError> for IntegrationFailure {
    fn from(error: GviError) -> Self {
        IntegrationFailure {
            error,
            partial: None,
        }
    }
}

impl Tables {
    fn build<B: Basis + ?Sized>(basis: &B, rule: &QuadratureRule) -> Result<Self> {
        let n = basis.len();
        let m = rule.len();
        let mut phi = vec![0.0; m * n];
        let mut dphi = vec![0.0; m * n];
        for (j, &c) in rule.nodes.iter().enumerate() {
            let (v, d) = (&mut phi[j * n..(j + 1) * n], &mut dphi[j * n..(j + 1) * n]);
            basis.eval(c, v, d);
        }
        let mut kinetic = vec![0.0; n * n];
        for j in 0..m {
            let w = rule.weights[j];
            let row = &dphi[j * n..(j + 1) * n];
            for a in 0..n {
                let wa = w * row[a];
                for b in a..n {
                    kinetic[a * n + b] += wa * row[b];
                }
            }
        }
        // Exactly symmetric (a variational residual needs a symmetric kinetic form).
        for a in 0..n {
            for b in 0..a {
                kinetic[a * n + b] = kinetic[b * n + a];
            }
        }
        snap_to_short_binary(&mut kinetic);
        let fit = CurveFit::new(basis)?;
        let nodes = fit.nodes().to_vec();
        let mut unit = vec![1.0; n];
        fit.values_to_coefficients(&mut unit, 1);
        let mut ramp = nodes.clone();
        fit.values_to_coefficients(&mut ramp, 1);
        let (mut v, mut d1) = (vec![0.0; n], vec![0.0; n]);
        basis.eval(1.0, &mut v, &mut d1);
        // E = A⁻¹ X with X[k][i] = φ_i(1 + x_k): fit the continued curve's values.
        let mut extrapolate = vec![0.0; n * n];
        let mut dv = vec![0.0; n];
        for (k, &x) in nodes.iter().enumerate() {
            basis.eval(1.0 + x, &mut v, &mut dv);
            extrapolate[k * n..(k + 1) * n].copy_from_slice(&v);
        }
        fit.values_to_coefficients(&mut extrapolate, n);
        let extrapolate = extrapolate
            .iter()
            .all(|x| x.is_finite())
            .then_some(extrapolate);
        let all_finite = phi
            .iter()
            .chain(&dphi)
            .chain(&kinetic)
            .all(|x| x.is_finite());
        if !all_finite {
            return Err(GviError::InvalidBasisSize {
                n,
                basis: basis.name().into(),
                reason: "basis tables are not finite at this size".into(),
            });
        }
        let mut tables = Tables {
            n,
            m,
            phi,
            dphi,
            weights: rule.weights.clone(),
            kinetic,
            unit,
            ramp,
            dphi_end: d1,
            extrapolate,
            chebyshev: modal::chebyshev_transform(basis, n),
            fit,
            kron: OnceLock::new(),
            velocity: None,
        };
        tables.velocity = velocity::VelocityTables::build(rule, &tables);
        Ok(tables)
    }

    /// The Schur form of the nodal stage pencil for the Kronecker solver, or `None` when it
    /// could not be computed (the exact solver is then used). Built on the first call: a
    /// run solved in the velocity form by its fixed-point start never needs it, and the two
    /// Schur decompositions (this one and the velocity pencil's) were more than half of
    /// building the integrator (issue 35: 72 µs for Legendre n = 13 with 13 points, 32 µs
    /// without them, against 1.1 ms for the whole Kepler run at 1e-9).
    pub(crate) fn kron(&self) -> Option<&kronecker::KroneckerTables> {
        self.kron
            .get_or_init(|| kronecker::KroneckerTables::build(self))
            .as_ref()
    }
}

/// Entries of the kinetic matrix within a few ulps of a short binary fraction (a multiple of
/// 2⁻¹⁰, zero included) are set to it: the integrated Legendre basis's K is exactly 2·I on its
/// interior block, with ±1 and 0 elsewhere, and the quadrature leaves those entries an ulp or
/// two off. An entry c = 2(1 + η) with |η| ≈ ε makes fl(c·x) round to 2x or to the next
/// double depending on x's last bits, always on the side of η: a state-dependent, one-signed
/// perturbation of the stage equations that is not variational and made the energy of long
/// Kepler runs drift (Legendre n = 24, h = 0.5: ΔE ≈ +1.2e-14 over T = 8000 in 3 of 4
/// realisations; snapped, the signs are mixed). Any symmetric K defines a discrete Lagrangian,
/// so snapping changes the method by O(ε) and keeps it exactly variational.
fn snap_to_short_binary(kinetic: &mut [f64]) {
    let scale = kinetic.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for k in kinetic.iter_mut() {
        let snapped = (*k * 1024.0).round() / 1024.0;
        if (*k - snapped).abs() <= 16.0 * f64::EPSILON * scale.max(1.0) {
            *k = snapped;
        }
    }
}
