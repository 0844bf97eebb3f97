//! DOP853 (Hairer's explicit Runge–Kutta 8(5,3) of Dormand & Prince with adaptive steps), from
//! the `differential-equations` crate, as an external peer (cargo feature `dop853`, on by
//! default).
//!
//! Its dense output is only about fourth order between step ends, so states are never
//! interpolated: each call of [`OneStepMethod::step`] integrates the canonical equations from t
//! to t + h (h the *sample interval*) as its own initial-value problem, ending exactly at the
//! sample time, and the next interval starts with the last accepted step size of this one.

use super::{CanonicalParts, OneStepMethod};
use crate::error::{GviError, Result};
use crate::lagrangian::Lagrangian;
use differential_equations::prelude::{ExplicitRungeKutta, IVP, ODE};

/// The canonical equations y = (q, p), ẏ = (M⁻¹p, f(q)) for the external solver.
struct Canonical<'a, L: Lagrangian> {
    lagrangian: &'a L,
    parts: &'a CanonicalParts,
}

impl<L: Lagrangian> ODE<f64, Vec<f64>> for Canonical<'_, L> {
    fn diff(&self, _t: f64, y: &Vec<f64>, dydt: &mut Vec<f64>) {
        let d = self.parts.d;
        let (q, p) = y.split_at(d);
        let (dq, dp) = dydt.split_at_mut(d);
        self.parts.velocity(p, dq);
        self.lagrangian.force(q, dp);
    }
}

/// DOP853 with rtol = atol = `tolerance`, stopped exactly at every multiple of the sample
/// interval h.
///
/// ```
/// use galerkin_vi::baselines::{Dop853Baseline, OneStepMethod};
/// use galerkin_vi::systems::HarmonicOscillator;
///
/// let ho = HarmonicOscillator::unit();
/// let mut m = Dop853Baseline::new(&ho, 1.0, 1e-12)?;
/// let (mut q, mut p) = ([0.0], [0.0]);
/// m.step(0.0, &[1.0], &[0.0], &mut q, &mut p)?;
/// assert!((q[0] - 1.0f64.cos()).abs() < 1e-10);
/// assert!(m.force_evaluations() > 0);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
pub struct Dop853Baseline<'a, L: Lagrangian> {
    lagrangian: &'a L,
    h: f64,
    tolerance: f64,
    parts: CanonicalParts,
    last_step: Option<f64>,
    evaluations: usize,
    steps: usize,
    y0: Vec<f64>,
}

impl<'a, L: Lagrangian> Dop853Baseline<'a, L> {
    /// DOP853 at tolerance `tolerance` (rtol = atol, in [1e-16, 1)) with output interval h.
    pub fn new(lagrangian: &'a L, h: f64, tolerance: f64) -> Result<Self> {
        if !(tolerance.is_finite() && (1e-16..1.0).contains(&tolerance)) {
            return Err(GviError::InvalidParameter {
                name: "DOP853 tolerance".into(),
                value: tolerance,
                reason: "need 1e-16 ≤ tolerance < 1".into(),
            });
        }
        let parts = CanonicalParts::new(lagrangian, h)?;
        let d = parts.d;
        Ok(Dop853Baseline {
            lagrangian,
            h,
            tolerance,
            parts,
            last_step: None,
            evaluations: 0,
            steps: 0,
            y0: vec![0.0; 2 * d],
        })
    }

    /// Accepted plus rejected adaptive steps so far.
    pub fn adaptive_steps(&self) -> usize {
        self.steps
    }
}

impl<L: Lagrangian> OneStepMethod for Dop853Baseline<'_, L> {
    fn name(&self) -> String {
        format!(
            "dop853 (tol = {:e}, output every {})",
            self.tolerance, self.h
        )
    }

    fn step_size(&self) -> f64 {
        self.h
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
        self.parts.check(q, p, q_next, p_next)?;
        let d = self.parts.d;
        self.y0[..d].copy_from_slice(q);
        self.y0[d..].copy_from_slice(p);
        let ode = Canonical {
            lagrangian: self.lagrangian,
            parts: &self.parts,
        };
        let mut method = ExplicitRungeKutta::dop853()
            .rtol(self.tolerance)
            .atol(self.tolerance)
            .max_steps(10_000_000);
        if let Some(h0) = self.last_step {
            method = method.h0(h0.min(self.h));
        }
        let solution = IVP::ode(&ode, t, t + self.h, self.y0.clone())
            .method(method)
            .solve()
            .map_err(|e| GviError::Unsupported(format!("DOP853 failed at t = {t}: {e:?}")))?;
        self.evaluations += solution.evals.function;
        self.steps += solution.steps.accepted + solution.steps.rejected;
        let n = solution.t.len();
        let (Some(t_end), Some(y_end)) = (solution.t.last(), solution.y.last()) else {
            return Err(GviError::Unsupported(format!(
                "DOP853 returned no state at t = {t}"
            )));
        };
        if (t_end - (t + self.h)).abs() > 1e-12 * (1.0 + t_end.abs()) {
            return Err(GviError::Unsupported(format!(
                "DOP853 stopped at t = {t_end} instead of {}",
                t + self.h
            )));
        }
        if n >= 3 {
            // The last interval may be shortened to hit the sample time: use the one before.
            self.last_step = Some(solution.t[n - 2] - solution.t[n - 3]);
        }
        q_next.copy_from_slice(&y_end[..d]);
        p_next.copy_from_slice(&y_end[d..]);
        Ok(())
    }
}
