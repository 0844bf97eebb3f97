//! The inverse Legendre transform of an expression Lagrangian: v from p = ∂L/∂v(t, q, v) by
//! Newton's method, and the regularity check of an initial state.

use super::{ExpressionLagrangian, MIN_RCOND};
use crate::ad;
use crate::error::{ExpressionError, GviError, Result, ensure_finite, ensure_len};
use crate::lagrangian::Lagrangian;
use nalgebra::{DMatrix, DVector};

/// Newton iterations of the inverse Legendre transform before it is declared failed.
const LEGENDRE_ITERATIONS: usize = 50;

/// Halvings of a Newton step before the line search gives up (2⁻⁶⁰ ≈ 1e-18 of the step).
const LEGENDRE_HALVINGS: usize = 60;

impl ExpressionLagrangian {
    /// ∂L/∂v and ∂²L/∂v∂v (row-major) at (t, q, v).
    fn velocity_derivatives(&self, t: f64, q: &[f64], v: &[f64], lv: &mut [f64], lvv: &mut [f64]) {
        let qc: Vec<num_dual::HyperDual64> = q.iter().chain([&t]).map(|&x| x.into()).collect();
        ad::hessian(|y| self.tape.eval(&qc, y), v, lv, lvv);
    }

    /// A NaN or infinite L, ∂L/∂v or ∂²L/∂v² at (q, v) is a [`GviError::NonFinite`] naming
    /// the state (a singularity of L there), not a singular velocity Hessian.
    fn ensure_finite_at(
        &self,
        t: f64,
        (q, v): (&[f64], &[f64]),
        lv: &[f64],
        lvv: &[f64],
    ) -> Result<()> {
        let l = self.value_with_time(t, q, v);
        let bad = std::iter::once(l)
            .chain(lv.iter().copied())
            .chain(lvv.iter().copied())
            .find(|x| !x.is_finite());
        match bad {
            Some(value) => Err(GviError::NonFinite {
                what: format!(
                    "the Lagrangian or its velocity derivatives at q = {q:?}, v = {v:?} (L is \
                     singular there)"
                ),
                value,
            }),
            None => Ok(()),
        }
    }

    /// The velocity v with ∂L/∂v(q, v) = p (inverse Legendre transform), by damped Newton
    /// iteration from v = 0 (one full step for Lagrangians quadratic in v). Errors: wrong
    /// lengths, non-finite input, a singular velocity Hessian at an iterate
    /// ([`ExpressionError::SingularHessian`]), no convergence ([`ExpressionError::Legendre`],
    /// naming the residual).
    pub fn velocity(&self, q: &[f64], p: &[f64]) -> Result<Vec<f64>> {
        self.velocity_at(0.0, q, p)
    }

    /// [`velocity`](Self::velocity) at time t (for Lagrangians that read `t`).
    pub fn velocity_at(&self, t: f64, q: &[f64], p: &[f64]) -> Result<Vec<f64>> {
        self.velocity_near(t, q, p, &vec![0.0; self.dim()])
    }

    /// [`velocity_at`](Self::velocity_at) started from `start` instead of v = 0: a warm start
    /// from a nearby state's velocity (the previous step's) needs fewer iterations.
    ///
    /// Newton's method is damped: a step is halved until the residual max|p − ∂L/∂v| falls
    /// (by at least 10⁻⁴ of the step fraction), because the full step can overshoot by
    /// orders of magnitude where ∂L/∂v grows fast. For L = cosh(v), p = sinh v, the full
    /// step from v = 0 lands at v = p, where sinh p overflows for p ≳ 710 and, for p = 48,
    /// costs one Newton step per unit of v back down (the 50-iteration budget ran out).
    /// A full step that decreases the residual is always taken first, so where the plain
    /// iteration converged monotonically (every Lagrangian quadratic in v) the iterates are
    /// the same.
    pub fn velocity_near(&self, t: f64, q: &[f64], p: &[f64], start: &[f64]) -> Result<Vec<f64>> {
        let d = self.dim();
        ensure_len("q (number of coordinates)", d, q.len())?;
        ensure_len("p (number of coordinates)", d, p.len())?;
        ensure_len(
            "the starting velocity (number of coordinates)",
            d,
            start.len(),
        )?;
        ensure_finite("q", q)?;
        ensure_finite("p", p)?;
        ensure_finite("the starting velocity", start)?;
        let mut v = start.to_vec();
        let (mut lv, mut lvv) = (vec![0.0; d], vec![0.0; d * d]);
        let (mut trial_lv, mut trial_lvv) = (vec![0.0; d], vec![0.0; d * d]);
        let mut trial = vec![0.0; d];
        let scale = 1.0 + p.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let residual_of = |lv: &[f64]| {
            p.iter()
                .zip(lv)
                .fold(0.0f64, |m, (p, l)| crate::reduce::nan_max(m, (p - l).abs()))
        };
        self.velocity_derivatives(t, q, &v, &mut lv, &mut lvv);
        let mut residual = residual_of(&lv);
        let mut iterations = 0;
        while iterations < LEGENDRE_ITERATIONS {
            if residual <= 4.0 * f64::EPSILON * scale {
                return Ok(v);
            }
            self.ensure_finite_at(t, (q, &v), &lv, &lvv)?;
            let m = DMatrix::from_row_slice(d, d, &lvv);
            let rcond = reciprocal_condition(&m);
            if rcond.is_nan() || rcond <= MIN_RCOND {
                if iterations > 0 {
                    // Singular at an iterate, not at the start: the iteration ran off where
                    // L_vv vanishes (p outside the range of ∂L/∂v, e.g. |p| ≥ 1 for
                    // L = √(1 + ẋ²)). Report the residual, not the iterate's Hessian.
                    break;
                }
                return Err(ExpressionError::SingularHessian {
                    what: "the initial state".into(),
                    q: q.to_vec(),
                    v: v.clone(),
                    rcond,
                }
                .into());
            }
            let r = DVector::from_iterator(d, p.iter().zip(&lv).map(|(p, l)| p - l));
            let Some(dv) = m.lu().solve(&r) else { break };
            iterations += 1;
            // Backtracking on the residual: λ = 1, ½, ¼, … until it decreases.
            let mut lambda = 1.0;
            let mut accepted = None;
            for _ in 0..LEGENDRE_HALVINGS {
                for ((x, v), dv) in trial.iter_mut().zip(&v).zip(dv.iter()) {
                    *x = v + lambda * dv;
                }
                self.velocity_derivatives(t, q, &trial, &mut trial_lv, &mut trial_lvv);
                let r = residual_of(&trial_lv);
                // NaN (overflow of L's derivatives) compares false: halve.
                if r <= (1.0 - 1e-4 * lambda) * residual {
                    accepted = Some(r);
                    break;
                }
                lambda *= 0.5;
            }
            let Some(r) = accepted else {
                // No decrease along the Newton direction: the residual is at its round-off
                // floor (accept it if small) or Newton cannot make progress.
                if residual <= 1e-10 * scale {
                    return Ok(v);
                }
                break;
            };
            std::mem::swap(&mut v, &mut trial);
            std::mem::swap(&mut lv, &mut trial_lv);
            std::mem::swap(&mut lvv, &mut trial_lvv);
            residual = r;
            let step = lambda * dv.amax();
            if step <= 1e-15 * (1.0 + v.iter().fold(0.0f64, |m, x| m.max(x.abs()))) {
                if residual <= 1e-10 * scale {
                    return Ok(v);
                }
                break;
            }
        }
        if residual <= 4.0 * f64::EPSILON * scale {
            return Ok(v);
        }
        Err(ExpressionError::Legendre {
            q: q.to_vec(),
            p: p.to_vec(),
            residual,
            iterations,
        }
        .into())
    }

    /// Check a state before integrating: lengths, finiteness, and that the Lagrangian is
    /// regular there (the velocity Hessian is invertible, so p determines v). Returns v.
    pub fn check_state(&self, q: &[f64], p: &[f64]) -> Result<Vec<f64>> {
        self.check_state_at(0.0, q, p)
    }

    /// [`check_state`](Self::check_state) at time t (for Lagrangians that read `t`).
    pub fn check_state_at(&self, t: f64, q: &[f64], p: &[f64]) -> Result<Vec<f64>> {
        ensure_len("initial q (number of coordinates)", self.dim(), q.len())?;
        ensure_len("initial p (number of coordinates)", self.dim(), p.len())?;
        let v = self.velocity_at(t, q, p)?;
        let d = self.dim();
        let (mut lv, mut lvv) = (vec![0.0; d], vec![0.0; d * d]);
        self.velocity_derivatives(t, q, &v, &mut lv, &mut lvv);
        self.ensure_finite_at(t, (q, &v), &lv, &lvv)?;
        let rcond = reciprocal_condition(&DMatrix::from_row_slice(d, d, &lvv));
        if rcond.is_nan() || rcond <= MIN_RCOND {
            return Err(ExpressionError::SingularHessian {
                what: "the initial state".into(),
                q: q.to_vec(),
                v,
                rcond,
            }
            .into());
        }
        Ok(v)
    }
}

/// min|λ| / max|λ| of the symmetric part of `m`; 0 if not finite or zero.
fn reciprocal_condition(m: &DMatrix<f64>) -> f64 {
    if m.iter().any(|x| !x.is_finite()) {
        return 0.0;
    }
    let sym = (m + m.transpose()) * 0.5;
    let eig = sym.symmetric_eigenvalues();
    let hi = eig.amax();
    if hi == 0.0 {
        return 0.0;
    }
    eig.iter().fold(f64::INFINITY, |m, x| m.min(x.abs())) / hi
}
