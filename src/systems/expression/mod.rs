//! Lagrangians written as expressions: any system without recompiling.
//!
//! A scene file (or a program) gives the coordinates, the parameters and L(q, q̇) as text;
//! velocities are the coordinate names with `_dot` appended. The text is parsed once
//! ([`parse`]) and compiled to a [`Tape`] (constants folded, common subexpressions shared),
//! which is evaluated generically over the scalar, so the integrator's derivatives are exact
//! (forward-mode dual numbers, as for Lagrangians written in Rust), with no string handling
//! per call. Non-separable Lagrangians (magnetic terms x·ẏ, velocity-dependent kinetic
//! energy) are fine: the energy is reported from the Legendre transform E = p·v − L with
//! v solved from p = ∂L/∂v by Newton's method. See docs/guide/expression-lagrangians.md.
//!
//! ```
//! use galerkin_vi::systems::expression::ExpressionLagrangian;
//! use galerkin_vi::{GalerkinIntegrator, Lagrangian};
//! use galerkin_vi::systems::System;
//!
//! // Hénon–Heiles.
//! let hh = ExpressionLagrangian::parse(
//!     "(x_dot^2 + y_dot^2)/2 - (x^2 + y^2)/2 - lambda*(x^2*y - y^3/3)",
//!     &["x", "y"],
//!     &[("lambda", 1.0)],
//! )?;
//! let (q0, p0) = ([0.0, 0.1], [0.35, 0.0]);
//! let traj = GalerkinIntegrator::spectral(12, 0.5)?.integrate(&hh, 0.0, &q0, &p0, 20)?;
//! let (mut e0, mut e1) = ([0.0], [0.0]);
//! hh.invariants(&q0, &p0, &mut e0);
//! hh.invariants(&traj.q[20], &traj.p[20], &mut e1);
//! assert!((e1[0] - e0[0]).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod eval;
mod legendre;
mod parse;
mod separable;
mod spec;
mod time_force;
mod vectorised;

pub use crate::error::{ExpressionError, Position};
pub(crate) use eval::Symbol;
pub use eval::Tape;
pub use parse::{BinOp, Expr, Func, MAX_DEPTH, parse};
pub use spec::{ExpressionInvariants, LagrangianSpec};

use super::{ExactSolution, System};
use crate::ad;
use crate::error::{GviError, Result, ensure_len};
use crate::lagrangian::Lagrangian;
use nalgebra::DMatrix;
use num_dual::{Dual64, DualNum};
use std::sync::Arc;

/// The smallest reciprocal condition number of ∂²L/∂v∂v accepted as regular (a few hundred
/// ulps: below it, solving for v loses every digit).
const MIN_RCOND: f64 = 1e-13;

/// The suffix that turns a coordinate name into its velocity's name.
pub const VELOCITY_SUFFIX: &str = "_dot";

/// A Lagrangian L(q, q̇) given as an expression over named coordinates, their velocities
/// (`name_dot`) and named parameters; see the [module documentation](self).
#[derive(Debug, Clone)]
pub struct ExpressionLagrangian {
    text: String,
    expr: Expr,
    tape: Tape,
    coordinates: Vec<String>,
    parameters: Vec<(String, f64)>,
    energy: bool,
    exact: Option<Arc<ExactTapes>>,
    separable: Option<separable::Separable>,
    /// L reads `t` (compiled as the coordinate slot D).
    time_dependent: bool,
    /// Non-conservative force expressions ([`ExpressionLagrangian::with_force`]).
    force: Option<Arc<time_force::ForceTapes>>,
}

/// q(t) as compiled expressions in `t`, with the Lagrangian to form p = ∂L/∂v(q, q̇).
#[derive(Debug)]
struct ExactTapes {
    q: Vec<Tape>,
    lagrangian: Tape,
}

fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

fn invalid(name: &str, reason: &str) -> GviError {
    ExpressionError::InvalidName {
        name: name.to_string(),
        reason: reason.to_string(),
    }
    .into()
}

impl ExpressionLagrangian {
    /// Parse and compile `lagrangian` over `coordinates` (velocities `x_dot` for a coordinate
    /// `x`) with the given parameters; `pi` is predefined. Errors: a syntax error (with line,
    /// column and caret), an unknown symbol (listing the known ones), a coordinate whose
    /// velocity does not occur, a non-finite parameter, an unusable or repeated name.
    pub fn parse(
        lagrangian: &str,
        coordinates: &[&str],
        parameters: &[(&str, f64)],
    ) -> Result<Self> {
        if coordinates.is_empty() {
            return Err(invalid("coordinates", "at least one coordinate is needed"));
        }
        let mut symbols: Vec<(String, Symbol)> = Vec::new();
        let taken = |name: &str, symbols: &[(String, Symbol)]| -> Result<()> {
            if !is_identifier(name) {
                return Err(invalid(
                    name,
                    "not a name (letters, digits and _, not first a digit)",
                ));
            }
            if Func::from_name(name).is_some() || name == "pi" || name == "t" {
                return Err(invalid(name, "reserved (a function name, pi or t)"));
            }
            if symbols.iter().any(|(n, _)| n == name) {
                return Err(invalid(name, "defined twice"));
            }
            Ok(())
        };
        for (i, &c) in coordinates.iter().enumerate() {
            if c.ends_with(VELOCITY_SUFFIX) {
                return Err(invalid(c, "a coordinate name cannot end in _dot"));
            }
            taken(c, &symbols)?;
            symbols.push((c.to_string(), Symbol::Q(i as u32)));
        }
        for (i, &c) in coordinates.iter().enumerate() {
            symbols.push((format!("{c}{VELOCITY_SUFFIX}"), Symbol::V(i as u32)));
        }
        for &(name, value) in parameters {
            taken(name, &symbols)?;
            if !value.is_finite() {
                return Err(ExpressionError::NonFiniteParameter {
                    name: name.to_string(),
                    value,
                }
                .into());
            }
            symbols.push((name.to_string(), Symbol::Value(value)));
        }
        symbols.push(("pi".to_string(), Symbol::Value(std::f64::consts::PI)));
        // `t`: the slot after the coordinates (time_force.rs).
        symbols.push(("t".to_string(), Symbol::Q(coordinates.len() as u32)));
        let expr = parse(lagrangian)?;
        let tape = Tape::compile(&expr, lagrangian, &symbols)?;
        let time_dependent = tape.reads_q(coordinates.len());
        for (i, c) in coordinates.iter().enumerate() {
            if !tape.reads_v(i) {
                return Err(ExpressionError::MissingVelocity {
                    coordinate: c.to_string(),
                }
                .into());
            }
        }
        let separable = if time_dependent {
            None
        } else {
            separable::split(&expr, lagrangian, &symbols, coordinates.len())
        };
        Ok(ExpressionLagrangian {
            separable,
            time_dependent,
            force: None,
            text: lagrangian.to_string(),
            expr,
            tape,
            coordinates: coordinates.iter().map(|c| c.to_string()).collect(),
            parameters: parameters
                .iter()
                .map(|&(n, v)| (n.to_string(), v))
                .collect(),
            energy: true,
            exact: None,
        })
    }

    /// Report the energy as an invariant (default true); turn off for Lagrangians whose
    /// Legendre transform is expensive or not wanted in output.
    pub fn with_energy(mut self, energy: bool) -> Self {
        self.energy = energy;
        self
    }

    /// A closed-form solution q(t), one expression in `t` (and the parameters) per coordinate.
    /// Velocities come from dual numbers in t and momenta from p = ∂L/∂v, so the solution is
    /// used for the initial state it passes through (see [`System::exact_solution`]).
    pub fn with_exact_solution(mut self, q_of_t: &[&str]) -> Result<Self> {
        ensure_len(
            "exact solution (one expression per coordinate)",
            self.dim(),
            q_of_t.len(),
        )?;
        let mut symbols: Vec<(String, Symbol)> = vec![("t".to_string(), Symbol::Q(0))];
        for (n, v) in &self.parameters {
            symbols.push((n.clone(), Symbol::Value(*v)));
        }
        symbols.push(("pi".to_string(), Symbol::Value(std::f64::consts::PI)));
        let mut q = Vec::with_capacity(q_of_t.len());
        for (i, text) in q_of_t.iter().enumerate() {
            let what = || {
                format!(
                    "`exact` entry {} of {} (q(t) of `{}`)",
                    i + 1,
                    q_of_t.len(),
                    self.coordinates[i]
                )
            };
            let tape = parse(text).and_then(|e| Tape::compile(&e, text, &symbols));
            q.push(tape.map_err(|e| e.within(what()))?);
        }
        self.exact = Some(Arc::new(ExactTapes {
            q,
            lagrangian: self.tape.clone(),
        }));
        Ok(self)
    }

    /// The expression as parsed.
    pub fn expression(&self) -> &Expr {
        &self.expr
    }

    /// The source text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The compiled tape.
    pub fn tape(&self) -> &Tape {
        &self.tape
    }

    /// Coordinate names.
    pub fn coordinates(&self) -> &[String] {
        &self.coordinates
    }

    /// The named parameters and their values.
    pub fn parameters(&self) -> &[(String, f64)] {
        &self.parameters
    }

    /// Whether L was recognised as separable, ½ vᵀ M v + U(q) with a constant
    /// positive-definite M (then [`Lagrangian::mass_matrix`] is `Some` and the integrator and
    /// the classical baselines use the force −∇V = ∇U).
    pub fn is_separable(&self) -> bool {
        self.separable.is_some()
    }
}

impl Lagrangian for ExpressionLagrangian {
    fn dim(&self) -> usize {
        self.coordinates.len()
    }

    #[inline]
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        self.tape.eval(q, v)
    }

    /// One tape pass with first-order dual vectors of size 2D for D ≤ 4 (the default makes
    /// 2D passes with scalar duals).
    fn gradient(&self, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        match self.dim() {
            1 => self.gradient_fixed::<2>(q, v, lq, lv),
            2 => self.gradient_fixed::<4>(q, v, lq, lv),
            3 => self.gradient_fixed::<6>(q, v, lq, lv),
            4 => self.gradient_fixed::<8>(q, v, lq, lv),
            _ => vectorised::gradient_by_passes(self, q, v, lq, lv),
        }
    }

    /// One tape pass with second-order dual vectors (value, gradient and Hessian together)
    /// for D ≤ 4; the default makes D(2D + 1) passes with hyper-dual numbers.
    fn hessian(&self, q: &[f64], v: &[f64], lqq: &mut [f64], lqv: &mut [f64], lvv: &mut [f64]) {
        match self.dim() {
            1 => self.hessian_fixed::<2>(q, v, lqq, lqv, lvv),
            2 => self.hessian_fixed::<4>(q, v, lqq, lqv, lvv),
            3 => self.hessian_fixed::<6>(q, v, lqq, lqv, lvv),
            4 => self.hessian_fixed::<8>(q, v, lqq, lqv, lvv),
            _ => vectorised::hessian_by_passes(self, q, v, lqq, lqv, lvv),
        }
    }

    fn mass_matrix(&self) -> Option<DMatrix<f64>> {
        let d = self.dim();
        self.separable
            .as_ref()
            .map(|s| DMatrix::from_row_slice(d, d, &s.mass))
    }

    /// ∇U(q) for a separable L (no allocation up to D = 64); otherwise ∂L/∂q at v = 0.
    fn force(&self, q: &[f64], out: &mut [f64]) {
        let d = self.dim();
        match &self.separable {
            Some(s) => {
                ad::gradient(|y| s.potential.eval(y, &[]), q, out);
            }
            None => {
                let (zeros, mut lv) = (vec![0.0; d], vec![0.0; d]);
                self.gradient(q, &zeros, out, &mut lv);
            }
        }
    }

    /// ∇²U(q) for a separable L (no allocation up to D = 64); otherwise ∂²L/∂q² at v = 0.
    fn force_jacobian(&self, q: &[f64], out: &mut [f64]) {
        let d = self.dim();
        match &self.separable {
            Some(s) if d <= 64 => {
                let mut g = [0.0; 64];
                ad::hessian(|y| s.potential.eval(y, &[]), q, &mut g[..d], out);
            }
            Some(s) => {
                let mut g = vec![0.0; d];
                ad::hessian(|y| s.potential.eval(y, &[]), q, &mut g, out);
            }
            None => {
                let zeros = vec![0.0; d];
                let (mut a, mut b) = (vec![0.0; d * d], vec![0.0; d * d]);
                self.hessian(q, &zeros, out, &mut a, &mut b);
            }
        }
    }

    // Time and forcing (time_force.rs): autonomous expressions keep the fast paths above.

    fn is_autonomous(&self) -> bool {
        !self.time_dependent
    }

    fn value_at(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        self.value_with_time(t, q, v)
    }

    fn gradient_at(&self, t: f64, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        if self.time_dependent {
            self.gradient_with_time(t, q, v, lq, lv);
        } else {
            self.gradient(q, v, lq, lv);
        }
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
        if self.time_dependent {
            self.hessian_with_time(t, q, v, [lqq, lqv, lvv]);
        } else {
            self.hessian(q, v, lqq, lqv, lvv);
        }
    }

    fn time_derivative(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        if !self.time_dependent {
            return 0.0;
        }
        let d = self.dim();
        let (mut lq, mut lv) = (vec![0.0; d], vec![0.0; d]);
        self.gradient_with_time(t, q, v, &mut lq, &mut lv)
    }

    fn legendre_transform_at(&self, t: f64, q: &[f64], v: &[f64], p: &mut [f64]) {
        let mut lq = vec![0.0; self.dim()];
        self.gradient_at(t, q, v, &mut lq, p);
    }

    fn energy_at(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        let d = self.dim();
        let (mut lq, mut lv) = (vec![0.0; d], vec![0.0; d]);
        self.gradient_at(t, q, v, &mut lq, &mut lv);
        lv.iter().zip(v).map(|(a, b)| a * b).sum::<f64>() - self.value_at(t, q, v)
    }

    fn is_forced(&self) -> bool {
        self.force.is_some()
    }

    fn external_force(&self, t: f64, q: &[f64], v: &[f64], f: &mut [f64]) {
        self.force_with_time(t, q, v, f)
    }

    fn external_force_jacobian(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        fq: &mut [f64],
        fv: &mut [f64],
    ) {
        self.force_jacobian_with_time(t, q, v, fq, fv)
    }
}

impl System for ExpressionLagrangian {
    fn name(&self) -> &'static str {
        "lagrangian"
    }

    /// `energy` unless switched off, or L reads `t`, or a force acts (then the energy
    /// balance replaces it: [`crate::forcing::energy_balance`]).
    fn invariant_names(&self) -> &'static [&'static str] {
        if self.energy && !self.time_dependent && self.force.is_none() {
            &["energy"]
        } else {
            &[]
        }
    }

    /// The energy E = p·v − L(q, v), v from the inverse Legendre transform (NaN if that
    /// fails at this state).
    fn invariants(&self, q: &[f64], p: &[f64], out: &mut [f64]) {
        if let Some(e) = out.first_mut() {
            *e = match self.velocity(q, p) {
                Ok(v) => p.iter().zip(&v).map(|(p, v)| p * v).sum::<f64>() - self.value(q, &v),
                Err(_) => f64::NAN,
            };
        }
    }

    /// 2π/ω with ω² = ρ(M⁻¹K) + ρ(M⁻¹G)² from the linearisation at (q, v): M = L_vv, the
    /// stiffness K = −L_qq and the gyroscopic part G = L_qv − L_vq (for a charged particle,
    /// ρ(M⁻¹G) is the cyclotron frequency). `None` when the motion has no time scale there.
    fn shortest_time_scale(&self, q: &[f64], p: &[f64]) -> Option<f64> {
        let v = self.velocity(q, p).ok()?;
        let d = self.dim();
        let (mut lqq, mut lqv, mut lvv) = (vec![0.0; d * d], vec![0.0; d * d], vec![0.0; d * d]);
        self.hessian(q, &v, &mut lqq, &mut lqv, &mut lvv);
        let m_inv = DMatrix::from_row_slice(d, d, &lvv).try_inverse()?;
        let k = -DMatrix::from_row_slice(d, d, &lqq);
        let b = DMatrix::from_row_slice(d, d, &lqv);
        let g = &b - b.transpose();
        let rho = |a: DMatrix<f64>| {
            a.complex_eigenvalues()
                .iter()
                .fold(0.0f64, |m, z| m.max(z.norm()))
        };
        let omega = (rho(&m_inv * k) + rho(&m_inv * g).powi(2)).sqrt();
        (omega.is_finite() && omega > 0.0).then(|| std::f64::consts::TAU / omega)
    }

    /// The scene's closed-form q(t), when it passes through (q0, p0) at t0 (to 1e-9
    /// relative); `Ok(None)` otherwise or when none was given.
    fn exact_solution(&self, t0: f64, q0: &[f64], p0: &[f64]) -> Result<Option<ExactSolution>> {
        let Some(exact) = self.exact.clone() else {
            return Ok(None);
        };
        let state = move |t: f64| exact_state(&exact, t);
        let (q, p) = state(t0);
        let close = |a: &[f64], b: &[f64]| {
            a.len() == b.len()
                && a.iter()
                    .zip(b)
                    .all(|(x, y)| (x - y).abs() <= 1e-9 * (1.0 + y.abs()))
        };
        if !(close(&q, q0) && close(&p, p0)) {
            return Ok(None);
        }
        Ok(Some(ExactSolution::new(state)))
    }
}

/// (q(t), p(t)) from the exact-solution tapes: q̇ by a dual number in t, p = ∂L/∂v(q, q̇).
fn exact_state(exact: &ExactTapes, t: f64) -> (Vec<f64>, Vec<f64>) {
    let tt = [Dual64::from(t).derivative()];
    let (q, v): (Vec<f64>, Vec<f64>) = exact
        .q
        .iter()
        .map(|tape| {
            let x = tape.eval(&tt, &[]);
            (x.re, x.eps)
        })
        .unzip();
    // p = ∂L/∂v at (q, t, v): the time sits in the slot after the coordinates.
    let d = q.len();
    let x: Vec<f64> = q.iter().chain([&t]).chain(&v).copied().collect();
    let mut g = vec![0.0; 2 * d + 1];
    ad::gradient(
        |y| exact.lagrangian.eval(&y[..d + 1], &y[d + 1..]),
        &x,
        &mut g,
    );
    (q, g[d + 1..].to_vec())
}

#[cfg(test)]
mod tests;
