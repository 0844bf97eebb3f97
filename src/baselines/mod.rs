//! Classical baselines behind a common one-step interface, as negative and positive controls
//! for the geometric checks and as peers in the work–precision and stability studies:
//! classical Runge–Kutta 4 (accurate, not symplectic), Störmer–Verlet (second order,
//! symplectic), s-stage Gauss–Legendre collocation (order 2s, symplectic, simplified Newton;
//! with compensated summation it is the high-accuracy reference of the N-body report),
//! Yoshida-6 and Kahan–Li-8
//! compositions of Störmer–Verlet, plus an adapter
//! that puts the Galerkin integrator behind the same interface.
//!
//! The classical methods integrate the canonical equations of a mechanical Lagrangian
//! L = ½ q̇ᵀMq̇ − V(q): q̇ = M⁻¹p, ṗ = −∇V(q) ([`Lagrangian::force`]).

mod composition;
mod gauss_collocation;
mod rk4;
mod verlet;

pub use composition::{Composition, CompositionScheme};
pub(crate) use gauss_collocation::gauss_tableau;
pub use gauss_collocation::{GaussCollocationBaseline, MAX_GAUSS_STAGES};
pub use rk4::Rk4;
pub use verlet::StormerVerlet;

use crate::basis::Basis;
use crate::error::{GviError, Result, ensure_finite, ensure_len};
use crate::integrator::{GalerkinIntegrator, MAX_STEPS, Workspace};
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;
use nalgebra::DMatrix;

/// A one-step method (q_k, p_k) ↦ (q_{k+1}, p_{k+1}) at a fixed step size.
pub trait OneStepMethod {
    /// A label for output, e.g. `rk4 (h = 0.01)`.
    fn name(&self) -> String;
    /// The fixed step size h.
    fn step_size(&self) -> f64;
    /// Advance one step from (q, p) at time t into (q_next, p_next).
    fn step(
        &mut self,
        t: f64,
        q: &[f64],
        p: &[f64],
        q_next: &mut [f64],
        p_next: &mut [f64],
    ) -> Result<()>;
    /// Force (right-hand-side) evaluations so far: ∇V calls for the classical methods, the
    /// Lagrangian's first derivatives per quadrature point for the Galerkin method. The
    /// default, for methods that do not count, is 0.
    fn force_evaluations(&self) -> usize {
        0
    }
}

/// Positions and momenta at every step end, (q_k)_k and (p_k)_k.
pub type States = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// Integrate `steps` steps of `method` from (q0, p0) at t = 0; returns the positions and
/// momenta at every step end (steps + 1 of each, starting with the initial state).
pub fn integrate_one_step<M: OneStepMethod + ?Sized>(
    method: &mut M,
    q0: &[f64],
    p0: &[f64],
    steps: usize,
) -> Result<States> {
    if steps == 0 || steps > MAX_STEPS {
        return Err(GviError::InvalidStepCount {
            steps,
            reason: format!("need 1 ≤ steps ≤ {MAX_STEPS}"),
        });
    }
    ensure_len("initial momentum p0", q0.len(), p0.len())?;
    ensure_finite("initial position q0", q0)?;
    ensure_finite("initial momentum p0", p0)?;
    let h = method.step_size();
    let d = q0.len();
    let cap = steps.min(1 << 20) + 1;
    let (mut qs, mut ps) = (Vec::with_capacity(cap), Vec::with_capacity(cap));
    qs.push(q0.to_vec());
    ps.push(p0.to_vec());
    let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
    for k in 0..steps {
        let (q, p) = (&qs[k], &ps[k]);
        method.step(k as f64 * h, q, p, &mut qn, &mut pn)?;
        qs.push(qn.clone());
        ps.push(pn.clone());
    }
    Ok((qs, ps))
}

/// M⁻¹ in the form that makes v = M⁻¹p cheapest: the identity (Kepler, oscillator, pendulum
/// with unit mass), a diagonal (N bodies), or a dense row-major matrix.
#[derive(Debug, Clone)]
pub enum InverseMass {
    /// M = I.
    Identity,
    /// The diagonal of M⁻¹.
    Diagonal(Vec<f64>),
    /// M⁻¹, row-major D×D.
    Dense(Vec<f64>),
}

/// The pieces of a mechanical Lagrangian the classical methods need: D and M⁻¹. Public so
/// that peers outside the crate (the lab's DOP853 adapter) integrate the same canonical
/// equations with the same arithmetic.
#[derive(Debug, Clone)]
pub struct CanonicalParts {
    /// Dimension D of the configuration space.
    pub d: usize,
    /// M⁻¹ as a matrix.
    pub inverse_mass: DMatrix<f64>,
    /// The same M⁻¹, stored for a cheap matrix–vector product.
    pub inverse: InverseMass,
}

impl CanonicalParts {
    /// D and M⁻¹ of a mechanical Lagrangian; typed errors for h ≤ 0, a non-mechanical
    /// Lagrangian, a mass matrix of the wrong size or a singular one.
    pub fn new<L: Lagrangian>(lag: &L, h: f64) -> Result<Self> {
        if !(h.is_finite() && h > 0.0) {
            return Err(GviError::InvalidStepSize { h });
        }
        // The classical baselines integrate Hamilton's equations of H(q, p) alone: a force or
        // an explicit time would be ignored silently.
        crate::forcing::ensure_conservative(lag, "the classical baselines")?;
        let d = lag.dim();
        let mass = lag.mass_matrix().ok_or_else(|| {
            GviError::Unsupported(
                "the classical baselines need a mechanical Lagrangian ½q̇ᵀMq̇ − V(q)".into(),
            )
        })?;
        if mass.shape() != (d, d) {
            return Err(GviError::DimensionMismatch {
                what: "mass matrix".into(),
                expected: d,
                got: mass.nrows().max(mass.ncols()),
            });
        }
        let inverse_mass = mass
            .try_inverse()
            .filter(|m| m.iter().all(|x| x.is_finite()))
            .ok_or_else(|| GviError::InvalidParameter {
                name: "mass matrix".into(),
                value: f64::NAN,
                reason: "singular".into(),
            })?;
        let off_diagonal_zero =
            (0..d).all(|r| (0..d).all(|s| r == s || inverse_mass[(r, s)] == 0.0));
        let inverse = if !off_diagonal_zero {
            InverseMass::Dense((0..d * d).map(|k| inverse_mass[(k / d, k % d)]).collect())
        } else if (0..d).all(|r| inverse_mass[(r, r)] == 1.0) {
            InverseMass::Identity
        } else {
            InverseMass::Diagonal((0..d).map(|r| inverse_mass[(r, r)]).collect())
        };
        Ok(CanonicalParts {
            d,
            inverse_mass,
            inverse,
        })
    }

    /// v = M⁻¹ p (a copy for M = I, d multiplications for a diagonal M; bit-for-bit the dense
    /// product in both cases, whose other terms are exact zeros).
    #[inline]
    pub fn velocity(&self, p: &[f64], v: &mut [f64]) {
        let d = self.d;
        let (p, v) = (&p[..d], &mut v[..d]);
        match &self.inverse {
            InverseMass::Identity => v.copy_from_slice(p),
            InverseMass::Diagonal(m) => {
                for ((v, p), m) in v.iter_mut().zip(p).zip(m) {
                    *v = m * p;
                }
            }
            InverseMass::Dense(m) => {
                for (v, row) in v.iter_mut().zip(m.chunks_exact(d)) {
                    *v = row.iter().zip(p).map(|(a, b)| a * b).sum();
                }
            }
        }
    }

    /// v = M⁻¹ p for a fixed-size state, with the same arithmetic as
    /// [`velocity`](Self::velocity).
    #[inline(always)]
    pub fn velocity_static<const D: usize>(&self, p: &[f64; D]) -> [f64; D] {
        match &self.inverse {
            InverseMass::Identity => *p,
            InverseMass::Diagonal(m) => std::array::from_fn(|r| m[r] * p[r]),
            InverseMass::Dense(m) => std::array::from_fn(|r| {
                m[r * D..(r + 1) * D]
                    .iter()
                    .zip(p)
                    .map(|(a, b)| a * b)
                    .sum()
            }),
        }
    }

    /// Typed errors unless q, p and the outputs q_next, p_next all have length D.
    pub fn check(&self, q: &[f64], p: &[f64], qn: &[f64], pn: &[f64]) -> Result<()> {
        ensure_len("q", self.d, q.len())?;
        ensure_len("p", self.d, p.len())?;
        ensure_len("q_next", self.d, qn.len())?;
        ensure_len("p_next", self.d, pn.len())?;
        Ok(())
    }
}

/// The force f(q) = −∇V(q) of a fixed-size position.
#[inline(always)]
pub fn force_static<L: Lagrangian, const D: usize>(lagrangian: &L, q: &[f64; D]) -> [f64; D] {
    let mut f = [0.0; D];
    lagrangian.force(q, &mut f);
    f
}

/// The fixed-size-state kernel of a fixed-step baseline: the same step as
/// [`OneStepMethod::step`], bit for bit, on `[f64; D]` positions and momenta updated in place
/// (the study's loop runs it for the dimensions of the built-in scenes). The caller owns the
/// first-same-as-last force: `fsal` holds f(q) when known and receives f at the new q from the
/// methods that end with it.
pub trait StaticKernel: OneStepMethod {
    /// Dimension D the method was built for.
    fn dim(&self) -> usize;
    /// One step from (q, p) at time t, in place.
    fn advance<const D: usize>(
        &mut self,
        t: f64,
        q: &mut [f64; D],
        p: &mut [f64; D],
        fsal: &mut Option<[f64; D]>,
    ) -> Result<()>;
}

/// The Galerkin variational integrator behind the [`OneStepMethod`] interface (owns a
/// workspace, so the next step's initial guess extrapolates the previous curve).
#[derive(Debug)]
pub struct GalerkinMethod<'a, L: Lagrangian, B: Basis, Q: Quadrature> {
    integrator: &'a GalerkinIntegrator<B, Q>,
    lagrangian: &'a L,
    workspace: Workspace,
    evaluations: usize,
    /// Compensation terms of the last returned state, and that state: they are used when the
    /// next call continues from exactly that state (the usual loop), and dropped otherwise.
    q_err: Vec<f64>,
    p_err: Vec<f64>,
    last_q: Vec<f64>,
    last_p: Vec<f64>,
}

impl<'a, L: Lagrangian, B: Basis, Q: Quadrature> GalerkinMethod<'a, L, B, Q> {
    /// Wrap an integrator and a Lagrangian.
    pub fn new(integrator: &'a GalerkinIntegrator<B, Q>, lagrangian: &'a L) -> Result<Self> {
        Ok(GalerkinMethod {
            integrator,
            lagrangian,
            workspace: integrator.workspace(lagrangian)?,
            evaluations: 0,
            q_err: vec![0.0; lagrangian.dim()],
            p_err: vec![0.0; lagrangian.dim()],
            last_q: vec![f64::NAN; lagrangian.dim()],
            last_p: vec![f64::NAN; lagrangian.dim()],
        })
    }
}

impl<L: Lagrangian, B: Basis, Q: Quadrature> OneStepMethod for GalerkinMethod<'_, L, B, Q> {
    fn name(&self) -> String {
        format!(
            "galerkin ({} basis, n = {}, {}, h = {})",
            self.integrator.basis().name(),
            self.integrator.n(),
            self.integrator.quadrature().name(),
            self.integrator.step_size()
        )
    }

    fn step_size(&self) -> f64 {
        self.integrator.step_size()
    }

    fn force_evaluations(&self) -> usize {
        self.evaluations
    }

    fn step(
        &mut self,
        t: f64,
        q: &[f64],
        p: &[f64],
        q_next: &mut [f64],
        p_next: &mut [f64],
    ) -> Result<()> {
        let d = self.lagrangian.dim();
        ensure_len("q", d, q.len())?;
        ensure_len("p", d, p.len())?;
        ensure_len("q_next", d, q_next.len())?;
        ensure_len("p_next", d, p_next.len())?;
        self.workspace.set_time(t)?;
        let result = if self.integrator.options().compensated {
            // Continue the compensated sums only when called with the state returned last.
            if q != self.last_q.as_slice() || p != self.last_p.as_slice() {
                self.q_err.iter_mut().for_each(|x| *x = 0.0);
                self.p_err.iter_mut().for_each(|x| *x = 0.0);
            }
            q_next.copy_from_slice(q);
            p_next.copy_from_slice(p);
            let r = self.integrator.step_compensated(
                self.lagrangian,
                &mut self.workspace,
                q_next,
                &mut self.q_err,
                p_next,
                &mut self.p_err,
            );
            if r.is_ok() {
                self.last_q.copy_from_slice(q_next);
                self.last_p.copy_from_slice(p_next);
            }
            r
        } else {
            self.integrator
                .step(self.lagrangian, &mut self.workspace, q, p, q_next, p_next)
        };
        result
            .map(|stats| self.evaluations += stats.gradient_evaluations)
            .map_err(|f| GviError::NewtonFailure {
                step: (t / self.integrator.step_size()).round().max(0.0) as usize,
                t,
                residual: f.residual,
                iterations: f.iterations,
                reason: f.reason,
            })
    }
}
