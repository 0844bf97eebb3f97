//! Newton's method for the stationary points of the discrete action ([`super::action`]) in the
//! orthogonal complement of the symmetry directions.
//!
//! The action is invariant under the time shift (and, for N bodies, translations and
//! rotations), so its Hessian is singular at a solution along the generators of these
//! symmetries. Each Newton step is taken in their orthogonal complement: the generators at the
//! current iterate are orthonormalised (dependent ones dropped — for a rigidly rotating orbit
//! the time shift and the rotation coincide), the Hessian is projected onto the complement, and
//! the step is the minimum-norm solution over its eigenvalues above a relative cut-off (which
//! also absorbs degeneracies no symmetry explains, such as the family of elliptic homographic
//! orbits through Lagrange's circular one).

pub use super::action::PeriodCondition;
use super::action::{Evaluation, Tables, default_nodes, evaluate};
use super::curve::{FourierCurve, basis_len};
use crate::error::{GviError, Result, ensure_finite};
use crate::lagrangian::Lagrangian;
use crate::newton::{ConvergedBy, Correction, NewtonFailure, NewtonIteration, Termination, drive};
use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// A continuous symmetry of the action, whose generator is removed from every Newton step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Symmetry {
    /// Time shift t ↦ t + s (every autonomous Lagrangian).
    TimeShift,
    /// Translation of every body along `axis` (N bodies of dimension `body_dim`).
    Translation {
        /// Coordinate axis.
        axis: usize,
        /// Dimension of each body.
        body_dim: usize,
    },
    /// Rotation of every body in the (i, j) coordinate plane.
    Rotation {
        /// First axis of the plane.
        i: usize,
        /// Second axis of the plane.
        j: usize,
        /// Dimension of each body.
        body_dim: usize,
    },
}

impl Symmetry {
    /// The symmetries of the N-body problem in `body_dim` dimensions (with the time shift).
    pub fn nbody(body_dim: usize) -> Vec<Symmetry> {
        let mut out = vec![Symmetry::TimeShift];
        for axis in 0..body_dim {
            out.push(Symmetry::Translation { axis, body_dim });
        }
        let planes: &[(usize, usize)] = if body_dim == 2 {
            &[(0, 1)]
        } else {
            &[(1, 2), (2, 0), (0, 1)]
        };
        for &(i, j) in planes {
            out.push(Symmetry::Rotation { i, j, body_dim });
        }
        out
    }

    /// The generator at the coefficients `c` (length (2K+1)·components).
    fn generator(&self, curve: &FourierCurve, out: &mut [f64]) {
        let nc = curve.layout.components();
        let c = &curve.coefficients;
        out.iter_mut().for_each(|x| *x = 0.0);
        match *self {
            Symmetry::TimeShift => {
                // d/dθ of the curve: (a_k, b_k) ↦ 2πk (b_k, −a_k).
                for k in 1..=curve.modes {
                    let w = std::f64::consts::TAU * k as f64;
                    for comp in 0..nc {
                        let (ia, ib) = ((2 * k - 1) * nc + comp, 2 * k * nc + comp);
                        out[ia] = w * c[ib];
                        out[ib] = -w * c[ia];
                    }
                }
            }
            Symmetry::Translation { axis, body_dim } => {
                for comp in (0..nc).filter(|comp| comp % body_dim == axis) {
                    out[comp] = 1.0;
                }
            }
            Symmetry::Rotation { i, j, body_dim } => {
                for body in 0..nc / body_dim {
                    let (ci, cj) = (body * body_dim + i, body * body_dim + j);
                    for m in 0..basis_len(curve.modes) {
                        out[m * nc + ci] = -c[m * nc + cj];
                        out[m * nc + cj] = c[m * nc + ci];
                    }
                }
            }
        }
    }
}

/// Settings of the periodic Newton solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodicOptions {
    /// Trapezoid nodes M over one period; `None`: 4(K + 1), at least 32, rounded up to a
    /// multiple of the number of bodies of a choreography.
    pub nodes: Option<usize>,
    /// Stop when the residual (max-norm of the gradient) is at most this.
    pub tolerance: f64,
    /// Newton iteration limit.
    pub max_iterations: usize,
    /// Eigenvalues of the projected Hessian below this fraction of the largest are treated
    /// as zero (the minimum-norm step).
    pub eigen_cutoff: f64,
    /// Largest step as a fraction of the coefficient norm (longer steps are scaled down; a
    /// safeguard for crude guesses, inactive near the solution).
    pub max_step: f64,
    /// Reject a solution whose last two modes exceed this fraction of the largest mode
    /// ([`GviError::PeriodicUnderResolved`]); `None`: accept any.
    pub tail_tolerance: Option<f64>,
    /// Reject a stationary point whose energy varies along the curve by more than this
    /// (relative to max(1, |E|)): a stationary point of the discrete action through a
    /// collision, not an orbit ([`GviError::PeriodicNotConverged`]); `None`: accept any.
    pub energy_spread_tolerance: Option<f64>,
}

impl Default for PeriodicOptions {
    fn default() -> Self {
        PeriodicOptions {
            nodes: None,
            tolerance: 1e-11,
            max_iterations: 40,
            eigen_cutoff: 1e-10,
            max_step: 0.5,
            tail_tolerance: None,
            energy_spread_tolerance: Some(1e-6),
        }
    }
}

/// A stationary point of the discrete action.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicSolution {
    /// The curve (its period is the found period).
    pub curve: FourierCurve,
    /// The discrete action S over one period.
    pub action: f64,
    /// Mean energy over the nodes.
    pub energy: f64,
    /// Max − min of the energy over the nodes (zero for an exact orbit).
    pub energy_spread: f64,
    /// Final residual: max-norm of the gradient of F in the complement of the symmetry
    /// directions.
    pub residual: f64,
    /// Residual before each Newton step and at the end.
    pub residual_history: Vec<f64>,
    /// Newton iterations taken.
    pub iterations: usize,
    /// Trapezoid nodes M.
    pub nodes: usize,
    /// Size of the last two modes relative to the largest mode.
    pub tail: f64,
}

fn max_norm(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m: f64, v| {
        if v.is_nan() || m.is_nan() {
            f64::NAN
        } else {
            m.max(v.abs())
        }
    })
}

/// Orthonormal basis of the span of the symmetry generators (length `nu` each; the period
/// component is zero), dependent generators dropped.
fn symmetry_basis(curve: &FourierCurve, symmetries: &[Symmetry], nu: usize) -> Vec<Vec<f64>> {
    let p = curve.coefficients.len();
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let mut g = vec![0.0; p];
    for sym in symmetries {
        sym.generator(curve, &mut g);
        let mut z = vec![0.0; nu];
        z[..p].copy_from_slice(&g);
        let norm0 = z.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm0 == 0.0 || !norm0.is_finite() {
            continue;
        }
        // Modified Gram–Schmidt, twice for stability.
        for _ in 0..2 {
            for b in &basis {
                let dot: f64 = b.iter().zip(&z).map(|(x, y)| x * y).sum();
                z.iter_mut().zip(b).for_each(|(x, y)| *x -= dot * y);
            }
        }
        let norm = z.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm > 1e-8 * norm0 {
            z.iter_mut().for_each(|x| *x /= norm);
            basis.push(z);
        }
    }
    basis
}

/// Find a stationary point of the discrete action from the guess `curve`.
///
/// `symmetries` lists the continuous symmetries whose generators are removed from every step.
/// Errors: [`GviError::PeriodicNotConverged`] (naming the residual) when the iteration
/// diverges, meets a non-finite value or reaches the limit; [`GviError::PeriodicUnderResolved`]
/// when [`PeriodicOptions::tail_tolerance`] is set and the last modes are too large;
/// [`GviError::NonFinite`] for a non-finite guess.
pub fn solve<L: Lagrangian>(
    lag: &L,
    guess: FourierCurve,
    condition: PeriodCondition,
    symmetries: &[Symmetry],
    options: &PeriodicOptions,
) -> Result<PeriodicSolution> {
    crate::forcing::ensure_conservative(lag, "the periodic-orbit solver")?;
    let curve = guess;
    crate::error::ensure_len("configuration dimension", lag.dim(), curve.layout.dim())?;
    ensure_finite("periodic guess", &curve.coefficients)?;
    ensure_finite("period", &[curve.period])?;
    if let PeriodCondition::Energy(e) = condition {
        ensure_finite("energy", &[e])?;
    }
    let nodes = options
        .nodes
        .unwrap_or_else(|| default_nodes(&curve.layout, curve.modes));
    if nodes < 2 * curve.modes + 1 {
        return Err(GviError::InvalidInput {
            name: "nodes".into(),
            reason: format!(
                "{nodes} trapezoid nodes cannot resolve K = {} modes (need at least 2K + 1)",
                curve.modes
            ),
        });
    }
    let tables = Tables::new(&curve.layout, curve.modes, nodes);
    let p = curve.coefficients.len();
    let energy_unknown = matches!(condition, PeriodCondition::Energy(_));
    let mut problem = PeriodicNewton {
        lag,
        curve,
        tables: &tables,
        nodes,
        condition,
        symmetries,
        options,
        p,
        nu: p + usize::from(energy_unknown),
        energy_unknown,
        eval: None,
        zbasis: Vec::new(),
        residual: f64::NAN,
        history: Vec::new(),
        tail: f64::NAN,
        failure: None,
    };
    let termination = problem.termination();
    match drive(&mut problem, &termination) {
        Ok((_, iterations)) => {
            let Some(eval) = problem.eval else {
                unreachable!("the driver converges only after a residual evaluation")
            };
            Ok(PeriodicSolution {
                action: eval.action,
                energy: eval.energy,
                energy_spread: eval.energy_spread,
                residual: problem.residual,
                residual_history: problem.history,
                iterations,
                nodes,
                tail: problem.tail,
                curve: problem.curve,
            })
        }
        // The problem's own failures carry their error; the driver's own is the iteration
        // limit (its non-finite tests are preceded by the problem's, which name the cause).
        // The limit's message names the limit, as before the driver.
        Err(f) => Err(problem.failure.take().unwrap_or_else(|| {
            let reason = if f.iterations >= options.max_iterations {
                format!("iteration limit {} reached", options.max_iterations)
            } else {
                f.reason
            };
            not_converged(f.residual, f.iterations, reason)
        })),
    }
}

/// [`GviError::PeriodicNotConverged`] with the residual, the iterations and the reason.
fn not_converged(residual: f64, iterations: usize, reason: String) -> GviError {
    GviError::PeriodicNotConverged {
        residual,
        iterations,
        reason,
    }
}

/// One periodic solve as a [`NewtonIteration`] run by the crate's Newton driver
/// ([`crate::newton::drive`]): the residual is the projected gradient of the discrete action,
/// the linear solve the minimum-norm step in the complement of the symmetry directions
/// ([`newton_step`]), safeguarded for crude guesses.
///
/// Convergence is on the residual alone (`residual_tolerance`): the correction tests are off,
/// because near a degenerate stationary point (a family of orbits, the cut-off eigenvalues)
/// a small step says nothing about the gradient. The failures the solver names itself — a
/// non-finite action, divergence of the residual, a missing or zero Hessian, the solution's
/// tail and energy checks — are kept in `failure` with their [`GviError`] and surface as a
/// [`NewtonFailure`] to stop the driver.
struct PeriodicNewton<'a, L: Lagrangian> {
    lag: &'a L,
    curve: FourierCurve,
    tables: &'a Tables,
    nodes: usize,
    condition: PeriodCondition,
    symmetries: &'a [Symmetry],
    options: &'a PeriodicOptions,
    /// Coefficients, and unknowns (the coefficients and, at prescribed energy, the period).
    p: usize,
    nu: usize,
    energy_unknown: bool,
    /// The evaluation at the current iterate (its Hessian is taken by the step).
    eval: Option<Evaluation>,
    /// Orthonormal basis of the symmetry generators at the current iterate.
    zbasis: Vec<Vec<f64>>,
    /// The current residual, and the residual of every iterate so far.
    residual: f64,
    history: Vec<f64>,
    /// Size of the last two modes of the solution (set by `finish`).
    tail: f64,
    /// The failure in the solver's own terms, when the problem (not the driver) found it.
    failure: Option<GviError>,
}

impl<L: Lagrangian> PeriodicNewton<'_, L> {
    /// Converged when the residual is at most [`PeriodicOptions::tolerance`]; no test on the
    /// corrections (tolerance and floor 0, no estimate; a zero step is reported as the
    /// smallest positive size, see `correct`) and no divergence test on them (the residual's
    /// is in `correct`).
    fn termination(&self) -> Termination {
        Termination {
            residual_tolerance: Some(self.options.tolerance),
            ..Termination::new(self.options.max_iterations, 0.0, None, 0.0, f64::INFINITY)
        }
    }

    /// Record a failure of the solve and stop the driver with it.
    fn fail(&mut self, error: GviError) -> NewtonFailure {
        let failure = match &error {
            GviError::PeriodicNotConverged {
                residual,
                iterations,
                reason,
            } => NewtonFailure {
                residual: *residual,
                iterations: *iterations,
                reason: reason.clone(),
            },
            other => NewtonFailure {
                residual: self.residual,
                iterations: self.history.len().saturating_sub(1),
                reason: other.to_string(),
            },
        };
        self.failure = Some(error);
        failure
    }
}

impl<L: Lagrangian> NewtonIteration for PeriodicNewton<'_, L> {
    fn residual(&mut self, iteration: usize) -> f64 {
        let eval = evaluate(
            self.lag,
            &self.curve,
            self.tables,
            self.nodes,
            self.condition,
            true,
        );
        // The residual is the gradient with its components along the symmetry generators
        // removed (the phase conditions' Lagrange multipliers): rotations and translations
        // leave the discrete action exactly invariant, but the trapezoid rule is invariant
        // only under time shifts by multiples of T/M, so the gradient keeps an aliasing-size
        // component along the time shift that no step in the complement can (or should) remove.
        self.zbasis = symmetry_basis(&self.curve, self.symmetries, self.nu);
        let mut projected = eval.gradient.clone();
        for z in &self.zbasis {
            let dot: f64 = z.iter().zip(&projected).map(|(a, b)| a * b).sum();
            projected.iter_mut().zip(z).for_each(|(x, y)| *x -= dot * y);
        }
        let residual = max_norm(&projected);
        self.residual = residual;
        self.history.push(residual);
        let finite = residual.is_finite() && eval.action.is_finite();
        self.eval = Some(eval);
        if !finite {
            self.fail(not_converged(
                residual,
                iteration,
                "non-finite action or gradient (a collision or a singular curve)".into(),
            ));
            return f64::NAN;
        }
        residual
    }

    fn correct(&mut self, iteration: usize) -> Result<(Correction, Termination), NewtonFailure> {
        let residual = self.residual;
        // The residual's divergence test (the driver's tests are on the corrections).
        if self.history.len() > 3 && residual > 1e6 * self.history[0] {
            return Err(self.fail(not_converged(residual, iteration, "diverged".into())));
        }
        let Some(h) = self.eval.as_mut().and_then(|eval| eval.hessian.take()) else {
            return Err(self.fail(not_converged(residual, iteration, "no Hessian".into())));
        };
        let step = self
            .eval
            .as_ref()
            .and_then(|eval| newton_step(h, &eval.gradient, &self.zbasis, self.options));
        let Some(mut step) = step else {
            return Err(self.fail(not_converged(
                residual,
                iteration,
                "the projected Hessian is zero or non-finite".into(),
            )));
        };
        // Safeguards for crude guesses: bounded relative step, positive period.
        let (p, curve) = (self.p, &mut self.curve);
        let cnorm = curve.coefficients.iter().map(|x| x * x).sum::<f64>().sqrt();
        let snorm = step[..p].iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut scale: f64 = 1.0;
        if cnorm > 0.0 && snorm > self.options.max_step * cnorm {
            scale = self.options.max_step * cnorm / snorm;
        }
        if self.energy_unknown {
            let dt = step[p];
            if dt.abs() > 0.5 * curve.period {
                scale = scale.min(0.5 * curve.period / dt.abs());
            }
        }
        step.iter_mut().for_each(|x| *x *= scale);
        curve
            .coefficients
            .iter_mut()
            .zip(&step[..p])
            .for_each(|(c, s)| *c += s);
        if self.energy_unknown {
            curve.period += step[p];
        }
        // The sizes are reported for the driver's bookkeeping only (its correction tests are
        // off). A zero step — the gradient in the cut-off eigenspaces — is not convergence
        // here: it is reported as the smallest positive size, so the iteration goes on to the
        // residual test, as it did before the driver.
        let correction = Correction {
            size: max_norm(&step).max(f64::MIN_POSITIVE),
            scale: max_norm(&curve.coefficients).max(f64::MIN_POSITIVE),
        };
        if !(correction.size.is_finite() && correction.scale.is_finite()) {
            return Err(self.fail(not_converged(
                residual,
                iteration + 1,
                "non-finite Newton step".into(),
            )));
        }
        Ok((correction, self.termination()))
    }

    /// The solution's own checks: its tail ([`PeriodicOptions::tail_tolerance`]) and the
    /// energy along it ([`PeriodicOptions::energy_spread_tolerance`]).
    fn finish(&mut self, _: ConvergedBy) -> Result<(), NewtonFailure> {
        let Some(eval) = self.eval.as_ref() else {
            unreachable!("the driver converges only after a residual evaluation")
        };
        let (residual, iterations) = (self.residual, self.history.len() - 1);
        let spread = eval.energy_spread / eval.energy.abs().max(1.0);
        self.tail = tail_size(&self.curve);
        if let Some(tol) = self.options.tail_tolerance
            && self.tail > tol
        {
            return Err(self.fail(GviError::PeriodicUnderResolved {
                modes: self.curve.modes,
                tail: self.tail,
                tolerance: tol,
            }));
        }
        if let Some(tol) = self.options.energy_spread_tolerance
            && (spread > tol || spread.is_nan())
        {
            return Err(self.fail(not_converged(
                residual,
                iterations,
                format!(
                    "a stationary point of the discrete action that is not an orbit: the \
                     energy varies by {spread:.2e} (relative) along it, above {tol:.0e} — a \
                     collision or far too few modes"
                ),
            )));
        }
        Ok(())
    }
}

/// The minimum-norm Newton step H δ = −g in the orthogonal complement of the symmetry basis.
fn newton_step(
    h: DMatrix<f64>,
    g: &[f64],
    symmetry: &[Vec<f64>],
    options: &PeriodicOptions,
) -> Option<Vec<f64>> {
    let nu = g.len();
    // P = I − Z Zᵀ; Hp = P H P (symmetrised).
    let mut proj = DMatrix::<f64>::identity(nu, nu);
    for z in symmetry {
        let zv = DVector::from_column_slice(z);
        proj -= &zv * zv.transpose();
    }
    let hs = (&h + h.transpose()) * 0.5;
    let hp = &proj * hs * &proj;
    let gp = &proj * DVector::from_column_slice(g);
    if hp.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let eig = SymmetricEigen::new(hp);
    let lmax = eig.eigenvalues.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if lmax == 0.0 || !lmax.is_finite() {
        return None;
    }
    let mut step = DVector::<f64>::zeros(nu);
    for (i, &lam) in eig.eigenvalues.iter().enumerate() {
        if lam.abs() <= options.eigen_cutoff * lmax {
            continue;
        }
        let vcol = eig.eigenvectors.column(i);
        let coef = vcol.dot(&gp) / lam;
        step -= vcol * coef;
    }
    let step = &proj * step;
    Some(step.iter().copied().collect())
}

/// Size of the last two modes relative to the largest mode k ≥ 1.
pub fn tail_size(curve: &FourierCurve) -> f64 {
    let k = curve.modes;
    let largest = (1..=k).map(|m| curve.mode_size(m)).fold(0.0, f64::max);
    if largest == 0.0 {
        return 0.0;
    }
    let last = if k >= 2 {
        curve.mode_size(k).max(curve.mode_size(k - 1))
    } else {
        curve.mode_size(k)
    };
    last / largest
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::periodic::curve::Layout;
    use crate::systems::HarmonicOscillator;

    #[test]
    fn harmonic_oscillator_period_from_energy() {
        // L = v²/2 − q²/2: every orbit has period 2π; energy ½ gives amplitude 1.
        let ho = HarmonicOscillator::new(1.0, 1.0).unwrap();
        let mut c = FourierCurve::zeros(4, Layout::Orbit { dim: 1 }, 5.0).unwrap();
        c.set_mode(1, &[0.7], &[0.1]).unwrap();
        c.set_mode(2, &[0.05], &[0.0]).unwrap();
        let sol = solve(
            &ho,
            c,
            PeriodCondition::Energy(0.5),
            &[Symmetry::TimeShift],
            &PeriodicOptions::default(),
        )
        .unwrap();
        assert!((sol.curve.period - std::f64::consts::TAU).abs() < 1e-12);
        let c = &sol.curve.coefficients;
        assert!((c[1].hypot(c[2]) - 1.0).abs() < 1e-12);
    }
}
