//! Non-conservative forces f(t, q, v) and the forced system of the discrete
//! Lagrange–d'Alembert principle.
//!
//! Marsden & West's forced discrete Euler–Lagrange equations add the discrete forces
//! F_d^± to the discrete Legendre transforms: p_k = −D₁L_d − F_d⁻ and
//! p_{k+1} = D₂L_d + F_d⁺. In Galerkin form the discrete virtual work of a step is
//! h Σ_j b_j f(c_j)·δq(c_j) with δq = Σ_i δQ_i φ_i, so F_d enters each stage row i as
//! h Σ_j b_j f(c_j) φ_i(c_j) — exactly where L_q does. The integrator therefore adds f to
//! L_q at every node; the momentum update and the Newton matrix (with ∂f/∂q and ∂f/∂v) follow.

use crate::error::{GviError, Result};
use crate::lagrangian::Lagrangian;
use crate::systems::NBody;
use nalgebra::DMatrix;
use num_dual::{Dual64, DualNum};

/// A non-conservative generalised force f(t, q, v) (a covector on the configuration space),
/// written once and generic over the scalar; its Jacobians come from automatic
/// differentiation unless overridden.
///
/// ```
/// use galerkin_vi::{DualNum, ExternalForce};
///
/// /// Harmonic driving γ cos(ωt) on the first coordinate.
/// struct Drive { gamma: f64, omega: f64 }
/// impl ExternalForce for Drive {
///     fn dim(&self) -> usize { 1 }
///     fn force<T: DualNum<Primitive = f64> + Copy>(&self, t: T, _q: &[T], _v: &[T], f: &mut [T]) {
///         f[0] = (t * self.omega).cos() * self.gamma;
///     }
/// }
/// let mut f = [0.0];
/// Drive { gamma: 0.5, omega: 1.2 }.evaluate(0.0, &[0.0], &[0.0], &mut f);
/// assert_eq!(f[0], 0.5);
/// ```
pub trait ExternalForce {
    /// Dimension D of the configuration space.
    fn dim(&self) -> usize;

    /// f(t, q, v) into `f` (D values), generic over the scalar.
    fn force<T: DualNum<Primitive = f64> + Copy>(&self, t: T, q: &[T], v: &[T], f: &mut [T]);

    /// f(t, q, v) in `f64`.
    fn evaluate(&self, t: f64, q: &[f64], v: &[f64], f: &mut [f64]) {
        self.force(t, q, v, f)
    }

    /// ∂f/∂q and ∂f/∂v, row-major D×D. Default: forward-mode AD, 2D force evaluations.
    fn jacobian(&self, t: f64, q: &[f64], v: &[f64], fq: &mut [f64], fv: &mut [f64]) {
        let d = self.dim();
        let zero = Dual64::from_re(0.0);
        let (mut qs, mut vs, mut fs) = ([zero; 16], [zero; 16], [zero; 16]);
        let mut heap: (Vec<Dual64>, Vec<Dual64>, Vec<Dual64>);
        let (qd, vd, fd): (&mut [Dual64], &mut [Dual64], &mut [Dual64]) = if d <= 16 {
            (&mut qs[..d], &mut vs[..d], &mut fs[..d])
        } else {
            heap = (vec![zero; d], vec![zero; d], vec![zero; d]);
            (&mut heap.0, &mut heap.1, &mut heap.2)
        };
        for (x, &y) in qd.iter_mut().zip(q) {
            *x = Dual64::from_re(y);
        }
        for (x, &y) in vd.iter_mut().zip(v) {
            *x = Dual64::from_re(y);
        }
        let td = Dual64::from_re(t);
        for s in 0..2 * d {
            let seed = |x: &mut [Dual64], e: f64| x[s % d].eps = e;
            if s < d {
                seed(qd, 1.0);
            } else {
                seed(vd, 1.0);
            }
            self.force(td, qd, vd, fd);
            let out = if s < d { &mut *fq } else { &mut *fv };
            for (r, f) in fd.iter().enumerate() {
                out[r * d + s % d] = f.eps;
            }
            if s < d {
                seed(qd, 0.0);
            } else {
                seed(vd, 0.0);
            }
        }
    }
}

/// A Lagrangian with a non-conservative force: the system of the discrete
/// Lagrange–d'Alembert principle. Every part of the Lagrangian (hand-written derivatives,
/// time dependence) is kept; the integrator adds f where L_q enters the stage equations.
///
/// ```
/// use galerkin_vi::{Forced, GalerkinIntegrator, LinearDamping, Lagrangian};
/// use galerkin_vi::systems::HarmonicOscillator;
///
/// let damped = Forced::new(HarmonicOscillator::new(1.0, 1.0)?, LinearDamping::uniform(1, 0.1)?)?;
/// let gvi = GalerkinIntegrator::spectral(10, 1.0)?;
/// let traj = gvi.integrate(&damped, 0.0, &[1.0], &[0.0], 50).map_err(|f| f.error)?;
/// // x'' + 0.1 x' + x = 0: the amplitude decays as e^{−t/20}.
/// let e = |k: usize| 0.5 * (traj.q[k][0].powi(2) + traj.p[k][0].powi(2));
/// assert!(e(50) < 0.1 * e(0));
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Forced<L, F> {
    lagrangian: L,
    force: F,
}

impl<L: Lagrangian, F: ExternalForce> Forced<L, F> {
    /// The Lagrangian L with the force f acting.
    ///
    /// Errors: [`GviError::DimensionMismatch`] when f's dimension is not L's.
    pub fn new(lagrangian: L, force: F) -> Result<Self> {
        if force.dim() != lagrangian.dim() {
            return Err(GviError::DimensionMismatch {
                what: "external force (its dimension must be the Lagrangian's)".into(),
                expected: lagrangian.dim(),
                got: force.dim(),
            });
        }
        Ok(Forced { lagrangian, force })
    }

    /// The Lagrangian.
    pub fn lagrangian(&self) -> &L {
        &self.lagrangian
    }

    /// The force.
    pub fn force(&self) -> &F {
        &self.force
    }
}

impl<L: Lagrangian, F: ExternalForce> Lagrangian for Forced<L, F> {
    fn dim(&self) -> usize {
        self.lagrangian.dim()
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        self.lagrangian.lagrangian(q, v)
    }
    fn value(&self, q: &[f64], v: &[f64]) -> f64 {
        self.lagrangian.value(q, v)
    }
    fn gradient(&self, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        self.lagrangian.gradient(q, v, lq, lv)
    }
    fn hessian(&self, q: &[f64], v: &[f64], lqq: &mut [f64], lqv: &mut [f64], lvv: &mut [f64]) {
        self.lagrangian.hessian(q, v, lqq, lqv, lvv)
    }
    fn mass_matrix(&self) -> Option<DMatrix<f64>> {
        self.lagrangian.mass_matrix()
    }
    fn force(&self, q: &[f64], out: &mut [f64]) {
        self.lagrangian.force(q, out)
    }
    fn force_jacobian(&self, q: &[f64], out: &mut [f64]) {
        self.lagrangian.force_jacobian(q, out)
    }
    fn legendre_transform(&self, q: &[f64], v: &[f64], p: &mut [f64]) {
        self.lagrangian.legendre_transform(q, v, p)
    }
    fn energy(&self, q: &[f64], v: &[f64]) -> f64 {
        self.lagrangian.energy(q, v)
    }
    fn is_autonomous(&self) -> bool {
        self.lagrangian.is_autonomous()
    }
    fn value_at(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        self.lagrangian.value_at(t, q, v)
    }
    fn gradient_at(&self, t: f64, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        self.lagrangian.gradient_at(t, q, v, lq, lv)
    }
    fn hessian_at(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        lqq: &mut [f64],
        lqv: &mut [f64],
        lvv: &mut [f64],
    ) {
        self.lagrangian.hessian_at(t, q, v, lqq, lqv, lvv)
    }
    fn time_derivative(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        self.lagrangian.time_derivative(t, q, v)
    }
    fn legendre_transform_at(&self, t: f64, q: &[f64], v: &[f64], p: &mut [f64]) {
        self.lagrangian.legendre_transform_at(t, q, v, p)
    }
    fn energy_at(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        self.lagrangian.energy_at(t, q, v)
    }
    fn is_forced(&self) -> bool {
        true
    }
    fn external_force(&self, t: f64, q: &[f64], v: &[f64], f: &mut [f64]) {
        self.force.evaluate(t, q, v, f)
    }
    fn external_force_jacobian(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        fq: &mut [f64],
        fv: &mut [f64],
    ) {
        self.force.jacobian(t, q, v, fq, fv)
    }
}

/// Linear (Rayleigh) damping f = −C v with a constant symmetric positive semi-definite C:
/// the energy decays at the rate vᵀ C v.
#[derive(Debug, Clone)]
pub struct LinearDamping {
    d: usize,
    /// C, row-major D×D.
    c: Vec<f64>,
}

impl LinearDamping {
    /// C = γ I on D coordinates.
    ///
    /// Errors: γ negative or not finite; D = 0.
    pub fn uniform(d: usize, gamma: f64) -> Result<Self> {
        Self::diagonal(&vec![gamma; d])
    }

    /// C = diag(γ_1, …, γ_D).
    ///
    /// Errors: any γ negative or not finite; no coefficients.
    pub fn diagonal(gammas: &[f64]) -> Result<Self> {
        let d = gammas.len();
        let mut c = vec![0.0; d * d];
        for (r, &g) in gammas.iter().enumerate() {
            c[r * d + r] = g;
        }
        Self::matrix(d, c)
    }

    /// A full damping matrix C (row-major D×D), symmetric with non-negative diagonal.
    ///
    /// Errors: wrong length, non-finite entries, an asymmetric C or a negative diagonal entry.
    pub fn matrix(d: usize, c: Vec<f64>) -> Result<Self> {
        if d == 0 {
            return Err(GviError::DimensionMismatch {
                what: "damping coefficients (at least one)".into(),
                expected: 1,
                got: 0,
            });
        }
        crate::error::ensure_len("damping matrix C (D×D entries)", d * d, c.len())?;
        crate::error::ensure_finite("damping matrix C", &c)?;
        for r in 0..d {
            if c[r * d + r] < 0.0 {
                return Err(GviError::InvalidParameter {
                    name: format!("damping coefficient C[{r}][{r}]"),
                    value: c[r * d + r],
                    reason: "damping must dissipate: C's diagonal is ≥ 0".into(),
                });
            }
            for s in 0..r {
                let (a, b) = (c[r * d + s], c[s * d + r]);
                if (a - b).abs() > 1e-14 * (a.abs() + b.abs()) {
                    return Err(GviError::InvalidParameter {
                        name: format!("damping matrix C[{r}][{s}]"),
                        value: a,
                        reason: format!("C must be symmetric; C[{s}][{r}] = {b}"),
                    });
                }
            }
        }
        Ok(LinearDamping { d, c })
    }
}

impl ExternalForce for LinearDamping {
    fn dim(&self) -> usize {
        self.d
    }
    fn force<T: DualNum<Primitive = f64> + Copy>(&self, _t: T, _q: &[T], v: &[T], f: &mut [T]) {
        let d = self.d;
        for (r, out) in f.iter_mut().enumerate() {
            let mut s = T::from(0.0);
            for (c, &vc) in self.c[r * d..(r + 1) * d].iter().zip(v) {
                s -= vc * *c;
            }
            *out = s;
        }
    }
    fn jacobian(&self, _t: f64, _q: &[f64], _v: &[f64], fq: &mut [f64], fv: &mut [f64]) {
        fq.iter_mut().for_each(|x| *x = 0.0);
        for (o, c) in fv.iter_mut().zip(&self.c) {
            *o = -c;
        }
    }
}

/// Stokes drag on the bodies of an N-body system: f_i = −m_i (v_i − w_i) / τ_i, with a
/// damping time τ_i per body and an optional velocity w_i of the medium (gas drag in a
/// protoplanetary disc, as REBOUNDx's `stokes_drag`). A body with τ_i = ∞ feels no drag.
#[derive(Debug, Clone)]
pub struct StokesDrag {
    body_dim: usize,
    /// m_i / τ_i per body.
    rate: Vec<f64>,
    /// The medium's velocity per coordinate (zero by default).
    medium: Vec<f64>,
}

impl StokesDrag {
    /// Drag with damping times `tau` (one per body, > 0, ∞ for none) on `system`'s bodies in
    /// a medium at rest.
    ///
    /// Errors: a count that is not the system's, a τ that is not positive, NaN.
    pub fn new(system: &NBody, tau: &[f64]) -> Result<Self> {
        crate::error::ensure_len("drag times τ (one per body)", system.bodies(), tau.len())?;
        let mut rate = Vec::with_capacity(tau.len());
        for (i, (&t, &m)) in tau.iter().zip(system.masses()).enumerate() {
            if t.is_nan() || t <= 0.0 {
                return Err(GviError::InvalidParameter {
                    name: format!("drag time τ of body {i}"),
                    value: t,
                    reason: "τ must be positive (∞ for no drag)".into(),
                });
            }
            rate.push(m / t);
        }
        let medium = vec![0.0; system.bodies() * system.body_dim()];
        Ok(StokesDrag {
            body_dim: system.body_dim(),
            rate,
            medium,
        })
    }

    /// The same drag in a medium moving with velocity `w` (D values, one block per body).
    ///
    /// Errors: wrong length or non-finite values.
    pub fn with_medium_velocity(mut self, w: &[f64]) -> Result<Self> {
        crate::error::ensure_len("medium velocity w", self.medium.len(), w.len())?;
        crate::error::ensure_finite("medium velocity w", w)?;
        self.medium.copy_from_slice(w);
        Ok(self)
    }
}

impl ExternalForce for StokesDrag {
    fn dim(&self) -> usize {
        self.medium.len()
    }
    fn force<T: DualNum<Primitive = f64> + Copy>(&self, _t: T, _q: &[T], v: &[T], f: &mut [T]) {
        for (i, &k) in self.rate.iter().enumerate() {
            for c in i * self.body_dim..(i + 1) * self.body_dim {
                f[c] = (v[c] - self.medium[c]) * (-k);
            }
        }
    }
    fn jacobian(&self, _t: f64, _q: &[f64], _v: &[f64], fq: &mut [f64], fv: &mut [f64]) {
        let d = self.medium.len();
        fq.iter_mut().for_each(|x| *x = 0.0);
        fv.iter_mut().for_each(|x| *x = 0.0);
        for (i, &k) in self.rate.iter().enumerate() {
            for c in i * self.body_dim..(i + 1) * self.body_dim {
                fv[c * d + c] = -k;
            }
        }
    }
}
