//! Time and forcing in expression Lagrangians: `t` in L(t, q, q̇) and non-conservative forces
//! `force = ["…", …]`, one expression per coordinate (docs/guide/forcing.md).
//!
//! The time is compiled as one more coordinate slot, Q(D), after the coordinates: an
//! expression reads it as `t`, and the evaluations here pass (q, t) together. Autonomous
//! expressions never read the slot, so their tapes and derivatives are unchanged.

use super::ExpressionLagrangian;
use super::eval::{Symbol, Tape};
use super::parse;
use crate::ad;
use crate::error::{Result, ensure_len};
use num_dual::{Dual64, DualNum, HyperDual64};

/// Largest D evaluated with stack buffers (the (q, t, v) vector has 2D + 1 entries).
const STACK_DIM: usize = 16;

/// Run `body` with `(q, t)` and `v` as one buffer: z = [q_0 … q_{D−1}, t, v_0 … v_{D−1}].
fn with_qtv<T: DualNum<Primitive = f64> + Copy, R>(
    q: &[T],
    t: T,
    v: &[T],
    body: impl FnOnce(&[T], &[T]) -> R,
) -> R {
    let d = q.len();
    let zero = T::from(0.0);
    let mut stack = [zero; 2 * STACK_DIM + 1];
    let mut heap;
    let z: &mut [T] = if d <= STACK_DIM {
        &mut stack[..2 * d + 1]
    } else {
        heap = vec![zero; 2 * d + 1];
        &mut heap
    };
    z[..d].copy_from_slice(q);
    z[d] = t;
    z[d + 1..].copy_from_slice(v);
    body(&z[..d + 1], &z[d + 1..])
}

impl ExpressionLagrangian {
    /// The symbols of this system's expressions: coordinates Q(i), velocities V(i), the
    /// parameters, `pi` and `t` = Q(D).
    pub(super) fn symbols_with_time(
        coordinates: &[String],
        parameters: &[(String, f64)],
    ) -> Vec<(String, Symbol)> {
        let d = coordinates.len();
        let mut symbols: Vec<(String, Symbol)> = Vec::with_capacity(2 * d + parameters.len() + 2);
        for (i, c) in coordinates.iter().enumerate() {
            symbols.push((c.clone(), Symbol::Q(i as u32)));
        }
        for (i, c) in coordinates.iter().enumerate() {
            symbols.push((
                format!("{c}{}", super::VELOCITY_SUFFIX),
                Symbol::V(i as u32),
            ));
        }
        for (n, v) in parameters {
            symbols.push((n.clone(), Symbol::Value(*v)));
        }
        symbols.push(("pi".to_string(), Symbol::Value(std::f64::consts::PI)));
        symbols.push(("t".to_string(), Symbol::Q(d as u32)));
        symbols
    }

    /// Add a non-conservative force f(t, q, q̇), one expression per coordinate in the
    /// coordinates, their velocities (`x_dot`), `t` and the parameters; it enters the stage
    /// equations by the discrete Lagrange–d'Alembert principle. The energy is then not an
    /// invariant (use [`crate::forcing::energy_balance`]).
    ///
    /// ```
    /// use galerkin_vi::systems::expression::ExpressionLagrangian;
    /// use galerkin_vi::Lagrangian;
    ///
    /// // Forced Duffing: x'' + δx' − x + x³ = γ cos ωt.
    /// let duffing = ExpressionLagrangian::parse(
    ///     "x_dot^2/2 + x^2/2 - x^4/4", &["x"], &[("delta", 0.3), ("gamma", 0.5), ("omega", 1.2)],
    /// )?
    /// .with_force(&["-delta*x_dot + gamma*cos(omega*t)"])?;
    /// assert!(duffing.is_forced());
    /// let mut f = [0.0];
    /// duffing.external_force(0.0, &[1.0], &[1.0], &mut f);
    /// assert!((f[0] - 0.2).abs() < 1e-15);
    /// # Ok::<(), galerkin_vi::GviError>(())
    /// ```
    ///
    /// Errors: one expression per coordinate is needed; syntax errors and unknown symbols as
    /// for the Lagrangian.
    pub fn with_force(mut self, force: &[&str]) -> Result<Self> {
        ensure_len(
            "force (one expression per coordinate)",
            self.coordinates.len(),
            force.len(),
        )?;
        let symbols = Self::symbols_with_time(&self.coordinates, &self.parameters);
        let mut tapes = Vec::with_capacity(force.len());
        for (i, text) in force.iter().enumerate() {
            let what = || {
                format!(
                    "`force` entry {} of {} (the force on `{}`)",
                    i + 1,
                    force.len(),
                    self.coordinates[i]
                )
            };
            let tape = parse(text).and_then(|e| Tape::compile(&e, text, &symbols));
            tapes.push(tape.map_err(|e| e.within(what()))?);
        }
        self.force = Some(std::sync::Arc::new(ForceTapes {
            texts: force.iter().map(|s| s.to_string()).collect(),
            tapes,
        }));
        // A forced system's classical baselines would ignore f: it is not used as separable.
        self.separable = None;
        Ok(self)
    }

    /// Whether L reads `t`.
    pub fn is_time_dependent(&self) -> bool {
        self.time_dependent
    }

    /// The force expressions, if any.
    pub fn force_expressions(&self) -> Option<&[String]> {
        self.force.as_ref().map(|f| f.texts.as_slice())
    }

    pub(super) fn value_with_time(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        with_qtv(q, t, v, |qt, v| self.tape.eval(qt, v))
    }

    /// L_q, L_v at (t, q, v) and ∂L/∂t, by 2D + 1 dual passes over (q, t, v).
    pub(super) fn gradient_with_time(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        lq: &mut [f64],
        lv: &mut [f64],
    ) -> f64 {
        let d = q.len();
        let mut g = [0.0; 2 * STACK_DIM + 1];
        let mut heap;
        let g: &mut [f64] = if d <= STACK_DIM {
            &mut g[..2 * d + 1]
        } else {
            heap = vec![0.0; 2 * d + 1];
            &mut heap
        };
        with_qtv(q, t, v, |qt, v| {
            let mut x = [0.0; 2 * STACK_DIM + 1];
            let mut xh;
            let x: &mut [f64] = if d <= STACK_DIM {
                &mut x[..2 * d + 1]
            } else {
                xh = vec![0.0; 2 * d + 1];
                &mut xh
            };
            x[..d + 1].copy_from_slice(qt);
            x[d + 1..].copy_from_slice(v);
            ad::gradient(|y| self.tape.eval(&y[..d + 1], &y[d + 1..]), x, g);
        });
        lq.copy_from_slice(&g[..d]);
        lv.copy_from_slice(&g[d + 1..]);
        g[d]
    }

    /// L_qq, L_qv, L_vv at (t, q, v) with t held fixed: hyper-dual passes over (q, v).
    pub(super) fn hessian_with_time(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        [lqq, lqv, lvv]: [&mut [f64]; 3],
    ) {
        let (d, tt) = (q.len(), HyperDual64::from_re(t));
        ad::hessian_blocks(
            |y| with_qtv(&y[..d], tt, &y[d..], |qt, v| self.tape.eval(qt, v)),
            (q, v),
            lqq,
            lqv,
            lvv,
        );
    }

    /// f(t, q, v) from the force expressions (zero without them).
    pub(super) fn force_with_time(&self, t: f64, q: &[f64], v: &[f64], f: &mut [f64]) {
        match &self.force {
            Some(force) => with_qtv(q, t, v, |qt, v| {
                for (out, tape) in f.iter_mut().zip(&force.tapes) {
                    *out = tape.eval(qt, v);
                }
            }),
            None => f.iter_mut().for_each(|x| *x = 0.0),
        }
    }

    /// ∂f/∂q, ∂f/∂v at (t, q, v): one gradient over (q, v) per force component.
    pub(super) fn force_jacobian_with_time(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        fq: &mut [f64],
        fv: &mut [f64],
    ) {
        let d = q.len();
        let Some(force) = &self.force else {
            fq.iter_mut().for_each(|x| *x = 0.0);
            fv.iter_mut().for_each(|x| *x = 0.0);
            return;
        };
        let tt = Dual64::from_re(t);
        for (r, tape) in force.tapes.iter().enumerate() {
            ad::gradient_blocks(
                |y| with_qtv(&y[..d], tt, &y[d..], |qt, v| tape.eval(qt, v)),
                q,
                v,
                &mut fq[r * d..(r + 1) * d],
                &mut fv[r * d..(r + 1) * d],
            );
        }
    }
}

/// The compiled force expressions of an [`ExpressionLagrangian`].
#[derive(Debug)]
pub(super) struct ForceTapes {
    texts: Vec<String>,
    tapes: Vec<Tape>,
}
