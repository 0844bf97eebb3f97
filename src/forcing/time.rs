//! Non-autonomous Lagrangians L(t, q, v).
//!
//! The discrete action of a step over [t_k, t_k + h] evaluates L at the quadrature times:
//! S_d = h Σ_j b_j L(t_k + c_j h, q(c_j h), q̇(c_j h)) (paper eq. (1) with t explicit). The
//! stage equations and the discrete Legendre transforms keep their form; only the node values
//! carry the time. Energy is no longer conserved: along a motion dE/dt = −∂L/∂t, which
//! [`crate::forcing::energy_balance`] integrates along the Galerkin curve.

use crate::ad;
use crate::lagrangian::Lagrangian;
use num_dual::DualNum;

/// A Lagrangian L(t, q, v) with explicit time dependence, written once and generic over the
/// scalar (t included), as [`Lagrangian::lagrangian`] is. Wrap it in [`NonAutonomous`] to
/// integrate it; its derivatives come from automatic differentiation.
///
/// ```
/// use galerkin_vi::{DualNum, GalerkinIntegrator, Lagrangian, NonAutonomous, NonAutonomousLagrangian};
///
/// /// A parametrically driven oscillator: L = v²/2 − (1 + ε cos t) q²/2.
/// struct Mathieu { eps: f64 }
/// impl NonAutonomousLagrangian for Mathieu {
///     fn dim(&self) -> usize { 1 }
///     fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, t: T, q: &[T], v: &[T]) -> T {
///         v[0] * v[0] * 0.5 - (t.cos() * self.eps + 1.0) * q[0] * q[0] * 0.5
///     }
/// }
/// let system = NonAutonomous(Mathieu { eps: 0.1 });
/// assert!(!system.is_autonomous());
/// let gvi = GalerkinIntegrator::spectral(10, 0.5)?;
/// let traj = gvi.integrate(&system, 0.0, &[1.0], &[0.0], 20).map_err(|f| f.error)?;
/// assert!(traj.q[20][0].is_finite());
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
pub trait NonAutonomousLagrangian {
    /// Dimension D of the configuration space.
    fn dim(&self) -> usize;
    /// L(t, q, v), generic over the scalar so that dual numbers give derivatives.
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, t: T, q: &[T], v: &[T]) -> T;
}

/// A [`NonAutonomousLagrangian`] as a [`Lagrangian`] the integrator steps: its `_at` methods
/// evaluate at the given time; its time-free methods see t = 0 (tools that assume autonomy
/// ask [`Lagrangian::is_autonomous`] and refuse it).
#[derive(Debug, Clone)]
pub struct NonAutonomous<L>(pub L);

/// Largest D whose AD scratch lives on the stack (2D + 1 inputs).
const STACK_DIM: usize = 15;

impl<L: NonAutonomousLagrangian> NonAutonomous<L> {
    /// The wrapped Lagrangian.
    pub fn inner(&self) -> &L {
        &self.0
    }

    /// Gradient in (q, v, t) of L: `g` has 2D + 1 entries, t last.
    fn full_gradient(&self, t: f64, q: &[f64], v: &[f64], g: &mut [f64]) {
        let d = self.0.dim();
        let mut stack = [0.0; 2 * STACK_DIM + 1];
        let mut heap;
        let x: &mut [f64] = if d <= STACK_DIM {
            &mut stack[..2 * d + 1]
        } else {
            heap = vec![0.0; 2 * d + 1];
            &mut heap
        };
        x[..d].copy_from_slice(q);
        x[d..2 * d].copy_from_slice(v);
        x[2 * d] = t;
        ad::gradient(|y| self.0.lagrangian(y[2 * d], &y[..d], &y[d..2 * d]), x, g);
    }
}

impl<L: NonAutonomousLagrangian> Lagrangian for NonAutonomous<L> {
    fn dim(&self) -> usize {
        self.0.dim()
    }

    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        self.0.lagrangian(T::from(0.0), q, v)
    }

    fn is_autonomous(&self) -> bool {
        false
    }

    fn value_at(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        self.0.lagrangian(t, q, v)
    }

    fn gradient_at(&self, t: f64, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        // t is a constant of the differentiation: a plain dual with zero derivative.
        let (d, t) = (self.0.dim(), num_dual::Dual64::from_re(t));
        ad::gradient_blocks(|y| self.0.lagrangian(t, &y[..d], &y[d..]), q, v, lq, lv);
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
        let (d, t) = (self.0.dim(), num_dual::HyperDual64::from_re(t));
        ad::hessian_blocks(
            |y| self.0.lagrangian(t, &y[..d], &y[d..]),
            (q, v),
            lqq,
            lqv,
            lvv,
        );
    }

    fn time_derivative(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        let d = self.0.dim();
        let mut g = vec![0.0; 2 * d + 1];
        self.full_gradient(t, q, v, &mut g);
        g[2 * d]
    }

    fn legendre_transform_at(&self, t: f64, q: &[f64], v: &[f64], p: &mut [f64]) {
        let mut lq = vec![0.0; self.0.dim()];
        self.gradient_at(t, q, v, &mut lq, p);
    }

    fn energy_at(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        let d = self.0.dim();
        let (mut lq, mut lv) = (vec![0.0; d], vec![0.0; d]);
        self.gradient_at(t, q, v, &mut lq, &mut lv);
        lv.iter().zip(v).map(|(a, b)| a * b).sum::<f64>() - self.value_at(t, q, v)
    }
}
