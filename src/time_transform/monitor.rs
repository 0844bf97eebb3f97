//! Monitors: the positive function g(q) = dt/ds of a Poincaré time transformation.
//!
//! A [`Monitor`] is written once, generic over the scalar (as [`crate::Mechanical::potential`]
//! is), with its gradient and Hessian from automatic differentiation unless it supplies
//! hand-written ones. The built-in ones are hand-written: [`CentralDistance`] (g = |q|^α, the
//! Sundman-type choices of the Kepler problem) and [`PairDistances`] (N-body: the smallest
//! pair distance, the product of the pair distances, or a smooth minimum, to a power).
//! [`TimeTransformed`](super::TimeTransformed) divides g by its value at the initial state,
//! so the fictitious step Δs is the physical step there.

use crate::ad;
use crate::error::{GviError, Result};
use num_dual::DualNum;
use serde::{Deserialize, Serialize};

/// A positive monitor function g(q), the rate dt/ds of physical time per fictitious time.
///
/// Only [`value`](Monitor::value) is required; [`gradient`](Monitor::gradient) and
/// [`hessian`](Monitor::hessian) default to automatic differentiation of it (which allocates
/// nothing after its first call: the scratch is per thread).
///
/// ```
/// use galerkin_vi::time_transform::Monitor;
/// use galerkin_vi::DualNum;
///
/// /// g = 1 + x², a user's monitor.
/// struct Soft;
/// impl Monitor for Soft {
///     fn name(&self) -> String { "1 + x^2".into() }
///     fn value<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
///         q[0] * q[0] + 1.0
///     }
/// }
/// let mut grad = [0.0, 0.0];
/// let g = Soft.gradient(&[2.0, 7.0], &mut grad);
/// assert_eq!((g, grad), (5.0, [4.0, 0.0]));
/// ```
pub trait Monitor {
    /// A short description for output, e.g. `r^1.5`.
    fn name(&self) -> String;

    /// g(q), generic over the scalar so that dual numbers give its derivatives.
    fn value<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T;

    /// The configuration dimension the monitor is made for, if it has one (checked against
    /// the system's). Default `None`: any.
    fn dim(&self) -> Option<usize> {
        None
    }

    /// g(q) in `f64`.
    fn value_f64(&self, q: &[f64]) -> f64 {
        self.value(q)
    }

    /// ∇g(q) into `grad` (D values); returns g(q). Default: automatic differentiation.
    fn gradient(&self, q: &[f64], grad: &mut [f64]) -> f64 {
        ad::gradient(|y| self.value(y), q, grad)
    }

    /// ∇g(q) into `grad` and ∇²g(q) into `hess` (row-major D×D); returns g(q). Default:
    /// automatic differentiation (hyper-dual numbers).
    fn hessian(&self, q: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        ad::hessian(|y| self.value(y), q, grad, hess)
    }
}

/// g = |q|^α: for the Kepler problem in the relative coordinate, Sundman's family. α = 1
/// makes s proportional to the eccentric anomaly, α = 2 to the true anomaly, α = 3/2 is the
/// "intermediate anomaly" between them; for e → 1 all three keep the number of steps per
/// orbit bounded where a fixed physical step needs O((1 − e)^{−3/2}) of them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CentralDistance {
    alpha: f64,
}

impl CentralDistance {
    /// g = |q|^α with α finite.
    ///
    /// Errors: α not finite.
    pub fn new(alpha: f64) -> Result<Self> {
        finite_exponent(alpha)?;
        Ok(CentralDistance { alpha })
    }

    /// The exponent α.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }
}

fn finite_exponent(alpha: f64) -> Result<()> {
    if alpha.is_finite() {
        Ok(())
    } else {
        Err(GviError::InvalidParameter {
            name: "time-transform exponent alpha".into(),
            value: alpha,
            reason: "must be finite".into(),
        })
    }
}

impl Monitor for CentralDistance {
    fn name(&self) -> String {
        format!("r^{}", self.alpha)
    }

    fn value<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        let mut r2 = T::from(0.0);
        for &x in q {
            r2 += x * x;
        }
        r2.powf(0.5 * self.alpha)
    }

    fn gradient(&self, q: &[f64], grad: &mut [f64]) -> f64 {
        let r2: f64 = q.iter().map(|x| x * x).sum();
        let g = r2.powf(0.5 * self.alpha);
        // ∇g = α r^{α−2} q
        let k = self.alpha * g / r2;
        grad.iter_mut().zip(q).for_each(|(o, x)| *o = k * x);
        g
    }

    fn hessian(&self, q: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        let d = q.len();
        let r2: f64 = q.iter().map(|x| x * x).sum();
        let g = r2.powf(0.5 * self.alpha);
        let a = self.alpha * g / r2;
        // ∇²g = α r^{α−2} I + α(α−2) r^{α−4} q qᵀ
        let b = a * (self.alpha - 2.0) / r2;
        for r in 0..d {
            grad[r] = a * q[r];
            for c in 0..d {
                hess[r * d + c] = b * q[r] * q[c] + if r == c { a } else { 0.0 };
            }
        }
        g
    }
}

/// How [`PairDistances`] combines the distances r_ij of the N(N − 1)/2 pairs of bodies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Combine {
    /// g = (min r_ij)^α. Only piecewise smooth: where the closest pair changes, g has a
    /// kink, the time-transformed Lagrangian is not C², and a step across it converges at a
    /// lower order (it is still a variational step of that Lagrangian).
    #[default]
    Min,
    /// g = (Σ_{i<j} r_ij^{−β})^{−α/β} with β = [`SOFTMIN_BETA`]: a smooth minimum, within a
    /// factor (N(N − 1)/2)^{−α/β} of (min r_ij)^α, and C^∞ away from collisions.
    Softmin,
    /// g = Π_{i<j} r_ij^α: smooth, but an escaping body makes it grow with its distance, so
    /// the steps of the remaining bodies grow with it.
    Product,
}

/// The β of [`Combine::Softmin`]: large enough that the closest pair dominates the sum
/// (a pair twice as far contributes 2^{−β}), small enough that g stays well scaled.
pub const SOFTMIN_BETA: f64 = 8.0;

impl Combine {
    /// The name used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            Combine::Min => "min",
            Combine::Softmin => "softmin",
            Combine::Product => "product",
        }
    }
}

/// An N-body monitor from the pair distances r_ij = |x_i − x_j| of a body-major
/// configuration (x₀, y₀, (z₀,) x₁, …): [`Combine::Min`], [`Combine::Softmin`] or
/// [`Combine::Product`], to the power α. Invariant under translations and rotations, so the
/// time-transformed Lagrangian keeps the N-body Noether momenta.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairDistances {
    bodies: usize,
    body_dim: usize,
    alpha: f64,
    combine: Combine,
}

impl PairDistances {
    /// A monitor of `bodies` ≥ 2 bodies of dimension `body_dim` ∈ {1, 2, 3} with exponent α.
    ///
    /// Errors: fewer than two bodies, `body_dim` not 1, 2 or 3, α not finite.
    pub fn new(bodies: usize, body_dim: usize, alpha: f64, combine: Combine) -> Result<Self> {
        finite_exponent(alpha)?;
        if bodies < 2 || !(1..=3).contains(&body_dim) {
            return Err(GviError::InvalidInput {
                name: "pair-distance monitor".into(),
                reason: format!(
                    "needs at least two bodies of dimension 1, 2 or 3, got {bodies} of \
                     dimension {body_dim}"
                ),
            });
        }
        Ok(PairDistances {
            bodies,
            body_dim,
            alpha,
            combine,
        })
    }

    /// The exponent α.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// How the distances are combined.
    pub fn combine(&self) -> Combine {
        self.combine
    }

    /// The closest pair (i, j) and its squared distance.
    fn closest(&self, q: &[f64]) -> (usize, usize, f64) {
        let k = self.body_dim;
        let mut best = (0, 1, f64::INFINITY);
        for i in 0..self.bodies {
            for j in i + 1..self.bodies {
                let r2: f64 = (0..k).map(|c| (q[i * k + c] - q[j * k + c]).powi(2)).sum();
                if r2 < best.2 {
                    best = (i, j, r2);
                }
            }
        }
        best
    }

    /// φ(r²) of one pair and its derivatives with respect to r² (the pair's term in the
    /// inner sum S = Σ φ): Min and Product use log r, Softmin r^{−β}.
    fn pair_term(&self, r2: f64) -> (f64, f64, f64) {
        match self.combine {
            // φ = ½ log r², φ' = 1/(2r²), φ'' = −1/(2r⁴)
            Combine::Min | Combine::Product => (0.5 * r2.ln(), 0.5 / r2, -0.5 / (r2 * r2)),
            Combine::Softmin => {
                let e = -0.5 * SOFTMIN_BETA;
                let v = r2.powf(e);
                (v, e * v / r2, e * (e - 1.0) * v / (r2 * r2))
            }
        }
    }

    /// g = F(S) and F', F'' from the inner sum S.
    fn outer(&self, s: f64) -> (f64, f64, f64) {
        match self.combine {
            // g = exp(α S), S = Σ log r (one pair for Min)
            Combine::Min | Combine::Product => {
                let g = (self.alpha * s).exp();
                (g, self.alpha * g, self.alpha * self.alpha * g)
            }
            Combine::Softmin => {
                let e = -self.alpha / SOFTMIN_BETA;
                let g = s.powf(e);
                (g, e * g / s, e * (e - 1.0) * g / (s * s))
            }
        }
    }

    /// Visit the pairs that enter S: all of them, or for Min only the closest.
    fn for_pairs(&self, q: &[f64], mut visit: impl FnMut(usize, usize)) {
        if self.combine == Combine::Min {
            let (i, j, _) = self.closest(q);
            visit(i, j);
            return;
        }
        for i in 0..self.bodies {
            for j in i + 1..self.bodies {
                visit(i, j);
            }
        }
    }
}

impl Monitor for PairDistances {
    fn name(&self) -> String {
        format!("{} pair distance^{}", self.combine.as_str(), self.alpha)
    }

    fn dim(&self) -> Option<usize> {
        Some(self.bodies * self.body_dim)
    }

    fn value<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        let k = self.body_dim;
        let r2 = |i: usize, j: usize| {
            let mut s = T::from(0.0);
            for c in 0..k {
                let dx = q[i * k + c] - q[j * k + c];
                s += dx * dx;
            }
            s
        };
        match self.combine {
            Combine::Min => {
                // The closest pair by the real parts (no allocation), then g in T.
                let mut best = (0, 1, f64::INFINITY);
                self.for_pairs_generic(|i, j| {
                    let d2 = r2(i, j).re();
                    if d2 < best.2 {
                        best = (i, j, d2);
                    }
                });
                r2(best.0, best.1).powf(0.5 * self.alpha)
            }
            Combine::Product => {
                let mut s = T::from(0.0);
                self.for_pairs_generic(|i, j| s += r2(i, j).ln() * 0.5);
                (s * self.alpha).exp()
            }
            Combine::Softmin => {
                let mut s = T::from(0.0);
                self.for_pairs_generic(|i, j| s += r2(i, j).powf(-0.5 * SOFTMIN_BETA));
                s.powf(-self.alpha / SOFTMIN_BETA)
            }
        }
    }

    fn value_f64(&self, q: &[f64]) -> f64 {
        let k = self.body_dim;
        let mut s = 0.0;
        self.for_pairs(q, |i, j| {
            let r2: f64 = (0..k).map(|c| (q[i * k + c] - q[j * k + c]).powi(2)).sum();
            s += self.pair_term(r2).0;
        });
        self.outer(s).0
    }

    fn gradient(&self, q: &[f64], grad: &mut [f64]) -> f64 {
        let k = self.body_dim;
        grad.iter_mut().for_each(|x| *x = 0.0);
        // ∇S = Σ_pairs 2 φ'(r²) δ on body i, minus on body j (δ = x_i − x_j).
        let mut s = 0.0;
        self.for_pairs(q, |i, j| {
            let mut r2 = 0.0;
            for c in 0..k {
                r2 += (q[i * k + c] - q[j * k + c]).powi(2);
            }
            let (phi, dphi, _) = self.pair_term(r2);
            s += phi;
            for c in 0..k {
                let gc = 2.0 * dphi * (q[i * k + c] - q[j * k + c]);
                grad[i * k + c] += gc;
                grad[j * k + c] -= gc;
            }
        });
        let (g, f1, _) = self.outer(s);
        grad.iter_mut().for_each(|x| *x *= f1);
        g
    }

    fn hessian(&self, q: &[f64], grad: &mut [f64], hess: &mut [f64]) -> f64 {
        let (k, d) = (self.body_dim, q.len());
        grad.iter_mut().for_each(|x| *x = 0.0);
        hess.iter_mut().for_each(|x| *x = 0.0);
        // ∇S into grad, ∇²S into hess: per pair, with A = 4 φ'' δδᵀ + 2 φ' I, the blocks
        // (i, i) and (j, j) get +A, (i, j) and (j, i) get −A.
        let mut s = 0.0;
        self.for_pairs(q, |i, j| {
            let mut delta = [0.0; 3];
            let mut r2 = 0.0;
            for c in 0..k {
                delta[c] = q[i * k + c] - q[j * k + c];
                r2 += delta[c] * delta[c];
            }
            let (phi, dphi, ddphi) = self.pair_term(r2);
            s += phi;
            for a in 0..k {
                grad[i * k + a] += 2.0 * dphi * delta[a];
                grad[j * k + a] -= 2.0 * dphi * delta[a];
                for b in 0..k {
                    let entry =
                        4.0 * ddphi * delta[a] * delta[b] + if a == b { 2.0 * dphi } else { 0.0 };
                    hess[(i * k + a) * d + i * k + b] += entry;
                    hess[(j * k + a) * d + j * k + b] += entry;
                    hess[(i * k + a) * d + j * k + b] -= entry;
                    hess[(j * k + a) * d + i * k + b] -= entry;
                }
            }
        });
        // g = F(S): ∇²g = F'' ∇S ∇Sᵀ + F' ∇²S, ∇g = F' ∇S.
        let (g, f1, f2) = self.outer(s);
        for r in 0..d {
            for c in 0..d {
                hess[r * d + c] = f2 * grad[r] * grad[c] + f1 * hess[r * d + c];
            }
        }
        grad.iter_mut().for_each(|x| *x *= f1);
        g
    }
}

impl PairDistances {
    /// All pairs (the generic value's loop; Min picks its pair itself).
    fn for_pairs_generic(&self, mut visit: impl FnMut(usize, usize)) {
        for i in 0..self.bodies {
            for j in i + 1..self.bodies {
                visit(i, j);
            }
        }
    }
}
