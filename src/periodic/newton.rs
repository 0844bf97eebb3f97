//! The discrete action of a periodic curve, its exact gradient and Hessian, and Newton's
//! method for its stationary points in the orthogonal complement of the symmetry directions.
//!
//! With θ_j = j/M (j = 0…M−1), A_j = φ(θ_j + s_r), B_j = φ'(θ_j + s_r)/T the basis and its
//! time derivative at the node of coordinate r (shift s_r), the curve is q_j = A_j c, q̇_j = B_j c
//! and the trapezoid rule (spectrally accurate for periodic integrands) gives
//!
//! S(c, T) = (T/M) Σ_j L(q_j, q̇_j),
//! ∂S/∂c = (T/M) Σ_j (A_jᵀ L_q + B_jᵀ L_v),
//! ∂²S/∂c² = (T/M) Σ_j (Aᵀ L_qq A + Aᵀ L_qv B + Bᵀ L_vq A + Bᵀ L_vv B).
//!
//! With the period unknown and the energy E₀ prescribed, the unknowns are (c, T) and the
//! function made stationary is F = S + E₀ T: since q̇ = q'(θ)/T, ∂S/∂T = (1/M) Σ_j (L − L_v·q̇)
//! = −Ē (the mean energy over the nodes), so ∂F/∂T = 0 is exactly the energy condition Ē = E₀
//! and the Newton matrix stays symmetric:
//! ∂²F/∂c∂T = (1/M) Σ_j (Aᵀ L_q − Aᵀ L_qv q̇ − Bᵀ L_vv q̇), ∂²F/∂T² = (1/(MT)) Σ_j q̇ᵀ L_vv q̇.
//!
//! The action is invariant under the time shift (and, for N bodies, translations and
//! rotations), so its Hessian is singular at a solution along the generators of these
//! symmetries. Each Newton step is taken in their orthogonal complement: the generators at the
//! current iterate are orthonormalised (dependent ones dropped — for a rigidly rotating orbit
//! the time shift and the rotation coincide), the Hessian is projected onto the complement, and
//! the step is the minimum-norm solution over its eigenvalues above a relative cut-off (which
//! also absorbs degeneracies no symmetry explains, such as the family of elliptic homographic
//! orbits through Lagrange's circular one).

use super::curve::{FourierCurve, Layout, basis_at, basis_len};
use crate::error::{GviError, Result, ensure_finite};
use crate::lagrangian::Lagrangian;
use nalgebra::{DMatrix, DVector, SymmetricEigen};

/// Fixed period, or unknown period with a prescribed energy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PeriodCondition {
    /// The period is the curve's `period` and stays fixed.
    Fixed,
    /// The period is unknown (the curve's `period` is the guess); the mean energy over the
    /// orbit must equal this value.
    Energy(f64),
}

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

/// The basis at the nodes of every shift class: `phi[class][j * nb + m]`.
struct Tables {
    phi: Vec<Vec<f64>>,
    dphi: Vec<Vec<f64>>,
    class: Vec<usize>,
}

impl Tables {
    fn new(layout: &Layout, modes: usize, nodes: usize) -> Self {
        let nb = basis_len(modes);
        let (shifts, class) = layout.shift_classes();
        let mut phi = Vec::with_capacity(shifts.len());
        let mut dphi = Vec::with_capacity(shifts.len());
        let mut d2 = vec![0.0; nb];
        for &s in &shifts {
            let (mut p, mut dp) = (vec![0.0; nodes * nb], vec![0.0; nodes * nb]);
            for j in 0..nodes {
                let theta = j as f64 / nodes as f64 + s;
                basis_at(
                    theta,
                    modes,
                    &mut p[j * nb..(j + 1) * nb],
                    &mut dp[j * nb..(j + 1) * nb],
                    &mut d2,
                );
            }
            phi.push(p);
            dphi.push(dp);
        }
        Tables { phi, dphi, class }
    }
}

/// Action, gradient and Hessian of F at a curve.
pub(crate) struct Evaluation {
    pub action: f64,
    pub energy: f64,
    pub energy_spread: f64,
    pub gradient: Vec<f64>,
    pub hessian: Option<DMatrix<f64>>,
}

/// Default number of trapezoid nodes for K modes.
pub fn default_nodes(layout: &Layout, modes: usize) -> usize {
    let m = (4 * (modes + 1)).max(32);
    match *layout {
        Layout::Choreography { bodies, .. } => m.div_ceil(bodies) * bodies,
        Layout::Orbit { .. } => m,
    }
}

fn evaluate<L: Lagrangian>(
    lag: &L,
    curve: &FourierCurve,
    tables: &Tables,
    nodes: usize,
    condition: PeriodCondition,
    with_hessian: bool,
) -> Evaluation {
    let layout = &curve.layout;
    let (d, nc, nb) = (layout.dim(), layout.components(), basis_len(curve.modes));
    let p = nb * nc;
    let energy_unknown = matches!(condition, PeriodCondition::Energy(_));
    let nu = p + usize::from(energy_unknown);
    let t = curve.period;
    let mf = nodes as f64;
    let w = t / mf;
    let c = &curve.coefficients;
    let mut grad = vec![0.0; nu];
    let mut hess = if with_hessian {
        Some(DMatrix::<f64>::zeros(nu, nu))
    } else {
        None
    };
    let (mut q, mut v) = (vec![0.0; d], vec![0.0; d]);
    let (mut lq, mut lv) = (vec![0.0; d], vec![0.0; d]);
    let (mut lqq, mut lqv, mut lvv) = (vec![0.0; d * d], vec![0.0; d * d], vec![0.0; d * d]);
    let (mut action, mut esum) = (0.0, 0.0);
    let (mut emin, mut emax) = (f64::INFINITY, f64::NEG_INFINITY);
    for j in 0..nodes {
        for r in 0..d {
            let cls = tables.class[r];
            let a = &tables.phi[cls][j * nb..(j + 1) * nb];
            let b = &tables.dphi[cls][j * nb..(j + 1) * nb];
            let comp = layout.component(r);
            let (mut x, mut dx) = (0.0, 0.0);
            for m in 0..nb {
                x += a[m] * c[m * nc + comp];
                dx += b[m] * c[m * nc + comp];
            }
            q[r] = x;
            v[r] = dx / t;
        }
        let l = lag.value(&q, &v);
        lag.gradient(&q, &v, &mut lq, &mut lv);
        action += w * l;
        let e = lv.iter().zip(&v).map(|(x, y)| x * y).sum::<f64>() - l;
        esum += e;
        emin = emin.min(e);
        emax = emax.max(e);
        for r in 0..d {
            let cls = tables.class[r];
            let a = &tables.phi[cls][j * nb..(j + 1) * nb];
            let b = &tables.dphi[cls][j * nb..(j + 1) * nb];
            let comp = layout.component(r);
            for m in 0..nb {
                grad[m * nc + comp] += w * (a[m] * lq[r] + b[m] / t * lv[r]);
            }
        }
        let Some(h) = hess.as_mut() else { continue };
        lag.hessian(&q, &v, &mut lqq, &mut lqv, &mut lvv);
        for r in 0..d {
            let (cr, cls_r) = (layout.component(r), tables.class[r]);
            let ar = &tables.phi[cls_r][j * nb..(j + 1) * nb];
            let br = &tables.dphi[cls_r][j * nb..(j + 1) * nb];
            for s in 0..d {
                let (x, y, yt, z) = (
                    lqq[r * d + s],
                    lqv[r * d + s],
                    lqv[s * d + r],
                    lvv[r * d + s],
                );
                if x == 0.0 && y == 0.0 && yt == 0.0 && z == 0.0 {
                    continue;
                }
                let (cs, cls_s) = (layout.component(s), tables.class[s]);
                let as_ = &tables.phi[cls_s][j * nb..(j + 1) * nb];
                let bs = &tables.dphi[cls_s][j * nb..(j + 1) * nb];
                for m in 0..nb {
                    // H_(m,r),(n,s) = w (A_r A_s L_qq + A_r B_s L_qv + B_r A_s L_vq + B_r B_s L_vv).
                    let alpha = w * (ar[m] * x + br[m] / t * yt);
                    let beta = w * (ar[m] * y + br[m] / t * z) / t;
                    if alpha == 0.0 && beta == 0.0 {
                        continue;
                    }
                    let row = m * nc + cr;
                    for n in 0..nb {
                        h[(row, n * nc + cs)] += alpha * as_[n] + beta * bs[n];
                    }
                }
            }
        }
        if energy_unknown {
            // ∂²F/∂c∂T and ∂²F/∂T² (module docs).
            let mut vlv = 0.0;
            for r in 0..d {
                let (qv_v, vv_v): (f64, f64) = (0..d)
                    .map(|s| (lqv[r * d + s] * v[s], lvv[r * d + s] * v[s]))
                    .fold((0.0, 0.0), |(x, y), (a, b)| (x + a, y + b));
                vlv += v[r] * vv_v;
                let cls = tables.class[r];
                let a = &tables.phi[cls][j * nb..(j + 1) * nb];
                let b = &tables.dphi[cls][j * nb..(j + 1) * nb];
                let comp = layout.component(r);
                for m in 0..nb {
                    let val = (a[m] * (lq[r] - qv_v) - b[m] / t * vv_v) / mf;
                    h[(m * nc + comp, p)] += val;
                    h[(p, m * nc + comp)] += val;
                }
            }
            h[(p, p)] += vlv / (mf * t);
        }
    }
    let energy = esum / mf;
    if let PeriodCondition::Energy(e0) = condition {
        grad[p] = e0 - energy;
    }
    Evaluation {
        action,
        energy,
        energy_spread: emax - emin,
        gradient: grad,
        hessian: hess,
    }
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
    let mut curve = guess;
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
        return Err(GviError::InvalidArgument {
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
    let nu = p + usize::from(energy_unknown);
    let mut history = Vec::new();
    let fail = |residual: f64, iterations: usize, reason: String| GviError::PeriodicNotConverged {
        residual,
        iterations,
        reason,
    };
    for iteration in 0..=options.max_iterations {
        let eval = evaluate(lag, &curve, &tables, nodes, condition, true);
        // The residual is the gradient with its components along the symmetry generators
        // removed (the phase conditions' Lagrange multipliers): rotations and translations
        // leave the discrete action exactly invariant, but the trapezoid rule is invariant
        // only under time shifts by multiples of T/M, so the gradient keeps an aliasing-size
        // component along the time shift that no step in the complement can (or should) remove.
        let zbasis = symmetry_basis(&curve, symmetries, nu);
        let mut projected = eval.gradient.clone();
        for z in &zbasis {
            let dot: f64 = z.iter().zip(&projected).map(|(a, b)| a * b).sum();
            projected.iter_mut().zip(z).for_each(|(x, y)| *x -= dot * y);
        }
        let residual = max_norm(&projected);
        history.push(residual);
        if !residual.is_finite() || !eval.action.is_finite() {
            return Err(fail(
                residual,
                iteration,
                "non-finite action or gradient (a collision or a singular curve)".into(),
            ));
        }
        if residual <= options.tolerance {
            let tail = tail_size(&curve);
            if let Some(tol) = options.tail_tolerance
                && tail > tol
            {
                return Err(GviError::PeriodicUnderResolved {
                    modes: curve.modes,
                    tail,
                    tolerance: tol,
                });
            }
            let spread = eval.energy_spread / eval.energy.abs().max(1.0);
            if let Some(tol) = options.energy_spread_tolerance
                && (spread > tol || spread.is_nan())
            {
                return Err(fail(
                    residual,
                    iteration,
                    format!(
                        "a stationary point of the discrete action that is not an orbit: the \
                         energy varies by {spread:.2e} (relative) along it, above {tol:.0e} — a \
                         collision or far too few modes"
                    ),
                ));
            }
            return Ok(PeriodicSolution {
                action: eval.action,
                energy: eval.energy,
                energy_spread: eval.energy_spread,
                residual,
                residual_history: history,
                iterations: iteration,
                nodes,
                tail,
                curve,
            });
        }
        if iteration == options.max_iterations {
            return Err(fail(
                residual,
                iteration,
                format!("iteration limit {} reached", options.max_iterations),
            ));
        }
        if history.len() > 3 && residual > 1e6 * history[0] {
            return Err(fail(residual, iteration, "diverged".into()));
        }
        let Some(h) = eval.hessian else {
            return Err(fail(residual, iteration, "no Hessian".into()));
        };
        let step = newton_step(
            h,
            &eval.gradient,
            &symmetry_basis(&curve, symmetries, nu),
            options,
        );
        let Some(mut step) = step else {
            return Err(fail(
                residual,
                iteration,
                "the projected Hessian is zero or non-finite".into(),
            ));
        };
        // Safeguards for crude guesses: bounded relative step, positive period.
        let cnorm = curve.coefficients.iter().map(|x| x * x).sum::<f64>().sqrt();
        let snorm = step[..p].iter().map(|x| x * x).sum::<f64>().sqrt();
        let mut scale: f64 = 1.0;
        if cnorm > 0.0 && snorm > options.max_step * cnorm {
            scale = options.max_step * cnorm / snorm;
        }
        if energy_unknown {
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
        if energy_unknown {
            curve.period += step[p];
        }
    }
    Err(fail(f64::NAN, options.max_iterations, "unreachable".into()))
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

/// Max-norm over `samples` equally spaced times of the Euler–Lagrange residual
/// d/dt L_v − L_q = L_vq q̇ + L_vv q̈ − L_q along the curve: the error of the truncated series
/// as a solution of the equations of motion (phase-independent, needs no reference).
pub fn equation_residual<L: Lagrangian>(lag: &L, curve: &FourierCurve, samples: usize) -> f64 {
    let d = curve.layout.dim();
    let (mut q, mut v, mut a) = (vec![0.0; d], vec![0.0; d], vec![0.0; d]);
    let (mut lq, mut lv) = (vec![0.0; d], vec![0.0; d]);
    let (mut lqq, mut lqv, mut lvv) = (vec![0.0; d * d], vec![0.0; d * d], vec![0.0; d * d]);
    let mut worst: f64 = 0.0;
    for i in 0..samples.max(1) {
        let t = curve.period * i as f64 / samples.max(1) as f64;
        curve.state_at(t, &mut q, &mut v, &mut a);
        lag.gradient(&q, &v, &mut lq, &mut lv);
        lag.hessian(&q, &v, &mut lqq, &mut lqv, &mut lvv);
        for r in 0..d {
            let mut e = -lq[r];
            for s in 0..d {
                e += lqv[s * d + r] * v[s] + lvv[r * d + s] * a[s];
            }
            worst = worst.max(e.abs());
        }
    }
    worst
}

/// The action, mean energy and its spread at a curve (no Newton).
pub fn action_and_energy<L: Lagrangian>(
    lag: &L,
    curve: &FourierCurve,
    nodes: usize,
) -> (f64, f64, f64) {
    let tables = Tables::new(&curve.layout, curve.modes, nodes);
    let e = evaluate(lag, curve, &tables, nodes, PeriodCondition::Fixed, false);
    (e.action, e.energy, e.energy_spread)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::systems::{HarmonicOscillator, NBody};

    /// The exact Hessian and ∂/∂T terms against central differences of the gradient.
    #[test]
    fn hessian_matches_differences_of_the_gradient() {
        let nb = NBody::new(vec![1.0, 1.0, 1.0], 1.0, 2).unwrap();
        let layout = Layout::Choreography {
            bodies: 3,
            body_dim: 2,
        };
        let mut c = FourierCurve::zeros(3, layout, 6.0).unwrap();
        c.set_mode(1, &[0.05, -0.02], &[1.0, 0.03]).unwrap();
        c.set_mode(2, &[0.01, 0.3], &[0.02, 0.01]).unwrap();
        c.set_mode(3, &[0.0, 0.01], &[0.02, 0.0]).unwrap();
        let nodes = 48;
        let tables = Tables::new(&c.layout, c.modes, nodes);
        let cond = PeriodCondition::Energy(-1.3);
        let e = evaluate(&nb, &c, &tables, nodes, cond, true);
        let h = e.hessian.unwrap();
        let nu = e.gradient.len();
        let eps = 1e-6;
        let mut worst: f64 = 0.0;
        for k in 0..nu {
            let (mut cp, mut cm) = (c.clone(), c.clone());
            if k < nu - 1 {
                cp.coefficients[k] += eps;
                cm.coefficients[k] -= eps;
            } else {
                cp.period += eps;
                cm.period -= eps;
            }
            let gp = evaluate(&nb, &cp, &tables, nodes, cond, false).gradient;
            let gm = evaluate(&nb, &cm, &tables, nodes, cond, false).gradient;
            for i in 0..nu {
                let fd = (gp[i] - gm[i]) / (2.0 * eps);
                worst = worst.max((fd - h[(i, k)]).abs());
            }
        }
        // Central differences with ε = 1e-6 carry ~1e-10 relative round-off and ε² truncation.
        let scale = h.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(
            worst < 1e-7 * scale,
            "Hessian vs differences: {worst:.3e} (max entry {scale:.3e})"
        );
        // The action gradient against differences of the action.
        let mut cp = c.clone();
        cp.coefficients[3] += eps;
        let mut cm = c.clone();
        cm.coefficients[3] -= eps;
        let sp = evaluate(&nb, &cp, &tables, nodes, cond, false).action;
        let sm = evaluate(&nb, &cm, &tables, nodes, cond, false).action;
        assert!(((sp - sm) / (2.0 * eps) - e.gradient[3]).abs() < 1e-7);
    }

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
