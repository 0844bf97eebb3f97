//! The Galerkin curve of one step (docs/DESIGN.md §2; paper §2.2): the polynomial (or other
//! basis) curve q(t) = Σ_i Q_i φ_i(τ), t = t_k + τh, τ ∈ [0, 1], whose coefficients Q_i the
//! step's stage equations determine. Its ends are the step's states, Q_0 = q_k and
//! Q_{n−1} = q_{k+1} (the basis is boundary-adapted), and between them it is the method's dense
//! output: q(t) and q̇(t) = (1/h) Σ_i Q_i φ_i'(τ) at any t of the step.
//!
//! Two forms, one meaning:
//! - [`GalerkinCurve`] owns its coefficients (n×D, row i = Q_i, absolute, not increments);
//!   it is what a caller keeps. [`GalerkinCurve::set`] overwrites it from another curve of at
//!   most the capacity it was built with, without allocating (the adaptive ladder keeps the
//!   last accepted curve this way).
//! - [`GalerkinCurveRef`] borrows them: what [`Workspace::curve`](crate::integrator::Workspace::curve)
//!   and [`Trajectory::curve`](crate::trajectory::Trajectory::curve) hand out, free of
//!   allocation inside step loops.
//!
//! A curve does not carry its basis: evaluation takes one ([`GalerkinCurveRef::state_into`]),
//! because the basis belongs to the integrator that made the curve, and a trajectory rebuilds
//! it from its kind and n. The discrete action of a curve and its discrete Legendre transforms
//! are computed by the integrator ([`GalerkinIntegrator::discrete_action`](crate::integrator::GalerkinIntegrator::discrete_action),
//! [`GalerkinIntegrator::discrete_legendre_transforms`](crate::integrator::GalerkinIntegrator::discrete_legendre_transforms)),
//! which owns the quadrature tables. Guide: docs/guide/paper-objects.md.

use crate::basis::Basis;
use crate::error::{GviError, Result, ensure_finite, ensure_len};

/// A borrowed Galerkin curve: n×D absolute coefficients Q_i (row-major, row i = Q_i), the
/// step size h and the start time t_k.
///
/// ```
/// use galerkin_vi::prelude::*;
///
/// // Integrate Kepler and evaluate the third step's curve in the middle of the step.
/// let kepler = Kepler::new(1.0)?;
/// let (q0, p0) = Kepler::paper_initial_state();
/// let gvi = GalerkinIntegrator::spectral(16, 2.0)?;
/// let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, 5)?;
/// let curve = traj.curve(2)?;
/// assert_eq!((curve.n(), curve.dim()), (16, 2));
/// let (q, v) = curve.state_at(gvi.basis(), curve.start_time() + 1.0)?;
/// // The same point as the trajectory's dense output, and the curve ends at q_3.
/// assert_eq!(q, traj.position_at(5.0)?);
/// assert_eq!(curve.end(), &traj.q[3][..]);
/// // Angular momentum along the curve (q × q̇, unit mass) is close to the orbit's.
/// let l = q[0] * v[1] - q[1] * v[0];
/// assert!((l - (q0[0] * p0[1] - q0[1] * p0[0])).abs() < 1e-3);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GalerkinCurveRef<'a> {
    coefficients: &'a [f64],
    n: usize,
    dim: usize,
    h: f64,
    t0: f64,
}

/// An owned Galerkin curve (see [`GalerkinCurveRef`] for the meaning of its parts).
#[derive(Debug, Clone, PartialEq)]
pub struct GalerkinCurve {
    coefficients: Vec<f64>,
    n: usize,
    dim: usize,
    h: f64,
    t0: f64,
}

impl<'a> GalerkinCurveRef<'a> {
    /// A curve from n×D absolute coefficients (row i = Q_i), step size h and start time t_k.
    ///
    /// Errors: n < 2 or D = 0, a coefficient count other than n·D, non-finite coefficients,
    /// h not finite and positive, or t_k not finite.
    pub fn new(coefficients: &'a [f64], n: usize, dim: usize, h: f64, t0: f64) -> Result<Self> {
        if n < 2 || dim == 0 {
            return Err(GviError::InvalidParameter {
                name: "Galerkin curve size (n, D)".into(),
                value: n.min(dim) as f64,
                reason: "a curve needs n ≥ 2 basis functions and D ≥ 1 coordinates".into(),
            });
        }
        ensure_len("Galerkin curve coefficients", n * dim, coefficients.len())?;
        ensure_finite("Galerkin curve coefficients", coefficients)?;
        if !(h.is_finite() && h > 0.0) {
            return Err(GviError::InvalidStepSize { h });
        }
        if !t0.is_finite() {
            return Err(GviError::NonFinite {
                what: "Galerkin curve start time".into(),
                value: t0,
            });
        }
        Ok(Self::from_parts(coefficients, n, dim, h, t0))
    }

    /// Without checks, for the library's own buffers (their sizes hold by construction).
    pub(crate) fn from_parts(
        coefficients: &'a [f64],
        n: usize,
        dim: usize,
        h: f64,
        t0: f64,
    ) -> Self {
        debug_assert_eq!(coefficients.len(), n * dim);
        GalerkinCurveRef {
            coefficients,
            n,
            dim,
            h,
            t0,
        }
    }

    /// The same curve starting at time `t0` (a workspace does not know the time of its step).
    pub fn starting_at(self, t0: f64) -> Self {
        GalerkinCurveRef { t0, ..self }
    }

    /// The coefficients Q_i, n×D row-major (row i = Q_i).
    pub fn coefficients(&self) -> &'a [f64] {
        self.coefficients
    }

    /// Coefficient Q_i (D values).
    pub fn coefficient(&self, i: usize) -> &'a [f64] {
        &self.coefficients[i * self.dim..(i + 1) * self.dim]
    }

    /// Number of basis functions n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Configuration dimension D.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Step size h.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// Start time t_k.
    pub fn start_time(&self) -> f64 {
        self.t0
    }

    /// End time t_k + h.
    pub fn end_time(&self) -> f64 {
        self.t0 + self.h
    }

    /// q(t_k) = Q_0, the step's start q_k.
    pub fn start(&self) -> &'a [f64] {
        self.coefficient(0)
    }

    /// q(t_k + h) = Q_{n−1}, the step's end q_{k+1}.
    pub fn end(&self) -> &'a [f64] {
        self.coefficient(self.n - 1)
    }

    /// q(τ) and q̇(τ) at the local time τ = (t − t_k)/h into `q` and `v` (D each), with the
    /// basis values φ_i(τ), φ_i'(τ) written to `phi` and `dphi` (n each): no allocation.
    /// `basis` must be the curve's (n functions); τ outside [0, 1] continues the curve.
    pub fn state_into<B: Basis + ?Sized>(
        &self,
        basis: &B,
        tau: f64,
        phi: &mut [f64],
        dphi: &mut [f64],
        q: &mut [f64],
        v: &mut [f64],
    ) {
        let (n, d) = (self.n, self.dim);
        basis.eval(tau, &mut phi[..n], &mut dphi[..n]);
        q[..d].iter_mut().for_each(|x| *x = 0.0);
        v[..d].iter_mut().for_each(|x| *x = 0.0);
        let c = self.coefficients;
        for i in 0..n {
            for r in 0..d {
                q[r] += phi[i] * c[i * d + r];
                v[r] += dphi[i] * c[i * d + r] / self.h;
            }
        }
    }

    /// q(t) and q̇(t) at a time t of the step (allocates the results).
    ///
    /// Errors: a basis whose size is not the curve's n, or t outside [t_k, t_k + h] (beyond
    /// a round-off margin).
    pub fn state_at<B: Basis + ?Sized>(&self, basis: &B, t: f64) -> Result<(Vec<f64>, Vec<f64>)> {
        ensure_len("basis size of the Galerkin curve", self.n, basis.len())?;
        let tol = 1e-12 * self.h.max(self.t0.abs() + self.h);
        if !t.is_finite() || t < self.t0 - tol || t > self.end_time() + tol {
            return Err(GviError::InvalidInput {
                name: "t".into(),
                reason: format!(
                    "{t} is outside the curve's step [{}, {}]",
                    self.t0,
                    self.end_time()
                ),
            });
        }
        let tau = ((t - self.t0) / self.h).clamp(0.0, 1.0);
        let (mut phi, mut dphi) = (vec![0.0; self.n], vec![0.0; self.n]);
        let (mut q, mut v) = (vec![0.0; self.dim], vec![0.0; self.dim]);
        self.state_into(basis, tau, &mut phi, &mut dphi, &mut q, &mut v);
        Ok((q, v))
    }

    /// An owned copy.
    pub fn to_curve(&self) -> GalerkinCurve {
        GalerkinCurve {
            coefficients: self.coefficients.to_vec(),
            n: self.n,
            dim: self.dim,
            h: self.h,
            t0: self.t0,
        }
    }
}

impl GalerkinCurve {
    /// A curve from n×D absolute coefficients (row i = Q_i), step size h and start time t_k;
    /// errors as [`GalerkinCurveRef::new`].
    pub fn new(coefficients: Vec<f64>, n: usize, dim: usize, h: f64, t0: f64) -> Result<Self> {
        GalerkinCurveRef::new(&coefficients, n, dim, h, t0)?;
        Ok(GalerkinCurve {
            coefficients,
            n,
            dim,
            h,
            t0,
        })
    }

    /// An all-zero curve with room for up to `max_n` × `dim` coefficients, to be filled by
    /// [`set`](Self::set) (it starts with n = max_n).
    pub fn with_capacity(max_n: usize, dim: usize, h: f64) -> Self {
        GalerkinCurve {
            coefficients: vec![0.0; max_n * dim],
            n: max_n,
            dim,
            h,
            t0: 0.0,
        }
    }

    /// Overwrite with `other` (any n and D): allocates only if it has more coefficients than
    /// this curve has ever held.
    pub fn set(&mut self, other: GalerkinCurveRef<'_>) {
        self.coefficients.clear();
        self.coefficients.extend_from_slice(other.coefficients);
        (self.n, self.dim, self.h, self.t0) = (other.n, other.dim, other.h, other.t0);
    }

    /// The borrowed view, for evaluation.
    pub fn as_ref(&self) -> GalerkinCurveRef<'_> {
        GalerkinCurveRef::from_parts(&self.coefficients, self.n, self.dim, self.h, self.t0)
    }

    /// The coefficients Q_i, n×D row-major.
    pub fn coefficients(&self) -> &[f64] {
        &self.coefficients
    }

    /// The coefficients, writable (n×D; the curve's size stays).
    pub fn coefficients_mut(&mut self) -> &mut [f64] {
        &mut self.coefficients
    }

    /// Number of basis functions n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Configuration dimension D.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Step size h.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// Start time t_k.
    pub fn start_time(&self) -> f64 {
        self.t0
    }

    /// q(t) and q̇(t) at a time t of the step; see [`GalerkinCurveRef::state_at`].
    pub fn state_at<B: Basis + ?Sized>(&self, basis: &B, t: f64) -> Result<(Vec<f64>, Vec<f64>)> {
        self.as_ref().state_at(basis, t)
    }
}

impl<'a> From<&'a GalerkinCurve> for GalerkinCurveRef<'a> {
    fn from(c: &'a GalerkinCurve) -> Self {
        c.as_ref()
    }
}
