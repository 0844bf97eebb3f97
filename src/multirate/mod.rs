//! A multirate Galerkin variational integrator for N-body systems with a few fast bodies:
//! the slow bodies' curves are polynomials over a macro step H, each fast body's curve is
//! piecewise polynomial over R micro steps h = H/R, and the coupling between them is
//! integrated on the micro steps' Gauss nodes in both bodies' equations.
//!
//! # Why
//!
//! On the J2000 solar system the single-rate spectral step is held at h ≈ 11 d by Mercury
//! (88-day period, e = 0.21): without Mercury the other nine bodies reach a position error of
//! 1e-9 over 10 000 days at h = 33.3 d in a third of the time (docs/solvers.md, issue 35's
//! report). A multirate step lets every body take the step its own motion needs.
//!
//! # The discrete action
//!
//! With the slow bodies S (masses m_s) and the fast bodies F, write the potential as
//! V = V_SS(q_S) + V_F(q_S, q_F), V_SS the pairs among slow bodies and V_F every pair with a
//! fast body. Over a macro step [t_k, t_k + H] the slow curve is
//! q_S(τH) = q_S,k + H Σ_{a<n−1} c_a I_a(τ) (the velocity form of the polynomial Galerkin
//! step: Legendre modes of the velocity, I_a their integrals, `crate::integrator`'s velocity
//! form), and the fast curve on micro step r is q_F(t_r + σh) = x_r + h Σ_a c^r_a I_a(σ) with
//! the knots x_{r+1} = x_r + h c^r_0. The discrete Lagrangian is the extremum over the
//! internal unknowns (the slow modes, the fast modes and knots) of
//!
//! S = H Σ_j b_j \[½ q̇_Sᵀ M_S q̇_S − V_SS(q_S)\](c_j)
//!   + Σ_r h Σ_i β_i \[½ q̇_Fᵀ M_F q̇_F − V_F(q_S, q_F)\](t_r + γ_i h),
//!
//! (c_j, b_j) the m-point Gauss rule of the macro step and (γ_i, β_i) the m_F-point rule of a
//! micro step. Stationarity gives, for every slow mode b (with ψ_0 = I_0 − 1, ψ_b = I_b),
//!
//! M_S c_b + H Σ_j b_j ψ_b(c_j) f_SS,j + H Σ_{r,i} (β_i/R) ψ_b((r + γ_i)/R) f_S←F,ri = δ_b0 p_S,k,
//!
//! and for every micro step r and fast mode b
//!
//! M_F c^r_b + h Σ_i β_i ψ_b(γ_i) f_F,ri = δ_b0 p^r,  p^{r+1} = p^r + h Σ_i β_i f_F,ri,
//!
//! with f = −∇V, p^0 = p_F,k, and the step ends q_S,k+1 = q_S,k + H c_0,
//! p_S,k+1 = p_S,k + H Σ_j b_j f_SS,j + h Σ_{r,i} β_i f_S←F,ri, q_F,k+1 = x_R, p_F,k+1 = p^R.
//! For R = 1 and the same rule for both it is the single-rate velocity-form step.
//!
//! # What it preserves
//!
//! It is the discrete Euler–Lagrange map of a discrete Lagrangian (a Galerkin variational
//! integrator over a piecewise-polynomial space), hence symplectic. Each pair's potential is
//! integrated by one rule in the equations of both its bodies, and each rule's term is
//! invariant under translations and rotations, so the discrete Noether theorem gives exact
//! conservation of the total linear and angular momentum (to round-off and the stage solve's
//! tolerance). The tests check both with a negative control: the same step with the fast
//! bodies' pull on the slow ones weighted equally at the micro nodes (a different rule in the
//! two bodies' equations) conserves neither.
//!
//! # The stage solve
//!
//! Picard's iteration on all the unknowns at once (each correction −F/m from one iterate's
//! forces, the fast micro steps' momenta chained from that iterate), run by the crate's one
//! Newton driver ([`crate::newton::drive`]). Guesses continue the previous step's curves.

mod coupling;
mod solve;
mod tables;
#[cfg(test)]
mod tests;

use crate::baselines::OneStepMethod;
use crate::error::{GviError, Result};
use crate::newton::{Termination, drive};
use crate::systems::NBody;
use coupling::LANES;
use solve::StageIteration;
use tables::{ModeTables, modes_at};

/// The largest number of basis functions (slow or fast) accepted.
pub const MAX_MULTIRATE_N: usize = 40;

/// The largest number of micro steps per macro step accepted.
pub const MAX_MICRO_STEPS: usize = 64;

/// Iteration cap of the stage equations' Picard iteration.
const MAX_ITERATIONS: usize = 80;

/// The Picard iteration ends when a correction is at most this relative to the modes, or
/// its contraction estimate says the remaining error is (θ below [`ESTIMATE_BELOW`]).
const TOLERANCE: f64 = 1e-16;

/// See [`TOLERANCE`].
const ESTIMATE_BELOW: f64 = 0.5;

/// Converged at the round-off floor when corrections stop shrinking below this (relative).
const FLOOR: f64 = 1e-14;

/// The numbers that define a multirate step besides H: the slow bodies' n basis functions and
/// m Gauss points, the number R of micro steps, and the fast bodies' n_F and m_F.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MultirateShape {
    /// Basis functions of the slow curves (n ≥ 2: degree n − 1).
    pub n: usize,
    /// Gauss–Legendre points of the macro rule (at least n − 1, so that the kinetic term is
    /// exact).
    pub points: usize,
    /// Micro steps R per macro step (1 ≤ R ≤ [`MAX_MICRO_STEPS`]).
    pub micro_steps: usize,
    /// Basis functions of the fast curves on each micro step.
    pub fast_n: usize,
    /// Gauss–Legendre points of a micro step's rule (at least `fast_n` − 1).
    pub fast_points: usize,
}

impl MultirateShape {
    /// n basis functions and n − 1 Gauss points (Gauss collocation, the studies' fastest rule
    /// at 1e-9) for both, and R micro steps.
    pub fn collocation(n: usize, micro_steps: usize) -> Self {
        let points = n.saturating_sub(1).max(1);
        MultirateShape {
            n,
            points,
            micro_steps,
            fast_n: n,
            fast_points: points,
        }
    }

    fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: String| {
            Err(GviError::InvalidInput {
                name: name.into(),
                reason,
            })
        };
        for (name, n) in [("n", self.n), ("fast n", self.fast_n)] {
            if !(2..=MAX_MULTIRATE_N).contains(&n) {
                return bad(name, format!("{n}; need 2 ≤ n ≤ {MAX_MULTIRATE_N}"));
            }
        }
        for (name, n, points) in [
            ("points", self.n, self.points),
            ("fast points", self.fast_n, self.fast_points),
        ] {
            if points + 1 < n || points > 2 * MAX_MULTIRATE_N {
                return bad(
                    name,
                    format!(
                        "{points} Gauss points for n = {n}: the kinetic term needs at least n − 1 \
                         (and at most {})",
                        2 * MAX_MULTIRATE_N
                    ),
                );
            }
        }
        if !(1..=MAX_MICRO_STEPS).contains(&self.micro_steps) {
            return bad(
                "micro steps",
                format!("{}; need 1 ≤ R ≤ {MAX_MICRO_STEPS}", self.micro_steps),
            );
        }
        Ok(())
    }
}

/// The multirate Galerkin variational integrator (see the [module](self)): the slow bodies on
/// macro steps of H, the fast ones on R micro steps each, for an [`NBody`] system in its own
/// coordinates (q body-major, p = m v).
///
/// ```
/// use galerkin_vi::baselines::OneStepMethod;
/// use galerkin_vi::multirate::{MultirateGalerkin, MultirateShape};
/// use galerkin_vi::systems::NBody;
///
/// // A star, an inner planet on a short orbit (body 1, fast) and an outer one.
/// let nb = NBody::new(vec![1.0, 1e-4, 1e-3], 1.0, 2)?;
/// let q = [0.0, 0.0, 0.3, 0.0, 0.0, 2.0];
/// let p = [0.0, 0.0, 0.0, 1e-4 * (1.0f64 / 0.3).sqrt(), -1e-3 * (0.5f64).sqrt(), 0.0];
/// let shape = MultirateShape::collocation(8, 4);
/// let mut m = MultirateGalerkin::new(&nb, &[1], shape, 0.5)?;
/// let (mut q1, mut p1) = ([0.0; 6], [0.0; 6]);
/// m.step(0.0, &q, &p, &mut q1, &mut p1)?;
/// // The total momentum is conserved exactly (to round-off).
/// let total = |p: &[f64], c: usize| p[c] + p[2 + c] + p[4 + c];
/// assert!((total(&p1, 0) - total(&p, 0)).abs() < 1e-18);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct MultirateGalerkin {
    dim: usize,
    g: f64,
    masses: Vec<f64>,
    slow: Vec<usize>,
    fast: Vec<usize>,
    /// The slow bodies alone: their mutual forces.
    slow_system: NBody,
    shape: MultirateShape,
    h: f64,
    macro_rule: ModeTables,
    micro_rule: ModeTables,
    /// The slow modes at the micro nodes, τ = (r + γ_i)/R: ι and ψ transposed (k rows of the
    /// padded node count, zero on the padding).
    iota_micro_t: Vec<f64>,
    psi_micro_t: Vec<f64>,
    /// β_i / R at each micro node (zero on the padding).
    weights_micro: Vec<f64>,
    /// The masses of the slow and fast bodies.
    slow_masses: Vec<f64>,
    fast_masses: Vec<f64>,
    /// Each slow and fast coordinate's mass.
    slow_mass: Vec<f64>,
    fast_mass: Vec<f64>,
    state: State,
    /// The largest |c| of the last sweep: the scale of the fast micro steps' own tests.
    scale_hint: f64,
    evaluations: usize,
    iterations: usize,
    /// The coupling integrated by one rule in both bodies' equations (the method); `false`
    /// weights the slow bodies' side equally, the tests' negative control.
    consistent: bool,
}

/// The unknowns and work buffers of a step (no allocation per step).
#[derive(Debug, Clone)]
struct State {
    qs: Vec<f64>,
    ps: Vec<f64>,
    qf: Vec<f64>,
    pf: Vec<f64>,
    /// Slow modes (k×D_S) and fast modes (R×k_F×D_F), and the previous step's.
    cs: Vec<f64>,
    cf: Vec<f64>,
    cs_prev: Vec<f64>,
    cf_prev: Vec<f64>,
    has_prev: bool,
    /// The slow bodies' projections (k×D_S).
    ds: Vec<f64>,
    /// The slow curve at the macro nodes (m×D_S) and its forces (weighted: H b_j f).
    xs: Vec<f64>,
    gs: Vec<f64>,
    /// The micro nodes of all micro steps (each padded to whole vectors of [`LANES`]), and of
    /// one.
    stride: usize,
    step_stride: usize,
    /// The slow curve at the micro nodes and the fast bodies' pull on it, by coordinate
    /// (D_S rows of `stride`).
    xs_micro: Vec<f64>,
    gs_micro: Vec<f64>,
    /// The fast curve at the micro nodes and its forces, by coordinate (D_F rows).
    xf: Vec<f64>,
    gf: Vec<f64>,

    /// The fast knot and momentum as a sweep goes through the micro steps (x_R, p^R at its
    /// end).
    knot: Vec<f64>,
    momentum: Vec<f64>,
    /// The slow momentum increment of the last evaluation (D_S).
    dps: Vec<f64>,
    /// The last correction's size (0 before the first).
    last: f64,
}

/// Column `c` of body `b` in a block of bodies of `dim` coordinates.
fn gather(from: &[f64], bodies: &[usize], dim: usize, to: &mut [f64]) {
    for (i, &b) in bodies.iter().enumerate() {
        to[i * dim..(i + 1) * dim].copy_from_slice(&from[b * dim..(b + 1) * dim]);
    }
}

fn scatter(from: &[f64], bodies: &[usize], dim: usize, to: &mut [f64]) {
    for (i, &b) in bodies.iter().enumerate() {
        to[b * dim..(b + 1) * dim].copy_from_slice(&from[i * dim..(i + 1) * dim]);
    }
}

impl MultirateGalerkin {
    /// The integrator for `system` with the bodies `fast` on micro steps (at least one, not
    /// all, each listed once), the numbers of `shape` and the macro step `h` > 0.
    ///
    /// Errors: [`GviError::InvalidStepSize`] for h not finite and positive,
    /// [`GviError::InvalidInput`] for a bad body list or shape.
    pub fn new(system: &NBody, fast: &[usize], shape: MultirateShape, h: f64) -> Result<Self> {
        if !(h.is_finite() && h > 0.0) {
            return Err(GviError::InvalidStepSize { h });
        }
        shape.validate()?;
        let nb = system.bodies();
        let bad = |reason: String| {
            Err(GviError::InvalidInput {
                name: "fast bodies".into(),
                reason,
            })
        };
        if fast.is_empty() || fast.len() >= nb {
            return bad(format!(
                "{} fast bodies of {nb}: need at least one fast and one slow body",
                fast.len()
            ));
        }
        if let Some(&b) = fast.iter().find(|&&b| b >= nb) {
            return bad(format!("body {b} does not exist ({nb} bodies)"));
        }
        let mut sorted = fast.to_vec();
        sorted.sort_unstable();
        if sorted.windows(2).any(|w| w[0] == w[1]) {
            return bad(format!("{fast:?} lists a body twice"));
        }
        let slow: Vec<usize> = (0..nb).filter(|b| !sorted.contains(b)).collect();
        let (dim, masses) = (system.body_dim(), system.masses().to_vec());
        let slow_masses: Vec<f64> = slow.iter().map(|&b| masses[b]).collect();
        let fast_masses: Vec<f64> = sorted.iter().map(|&b| masses[b]).collect();
        let slow_system = NBody::new(slow_masses.clone(), system.g(), dim)?;
        let macro_rule = ModeTables::new(shape.n, shape.points)?;
        let micro_rule = ModeTables::new(shape.fast_n, shape.fast_points)?;
        let r = shape.micro_steps;
        // The micro nodes in macro time, each micro step's padded to whole vectors (the
        // padding repeats its last node, with weight zero).
        let mf = micro_rule.m();
        let step_stride = mf.div_ceil(LANES) * LANES;
        let stride = r * step_stride;
        let taus: Vec<f64> = (0..stride)
            .map(|i| (i / step_stride, (i % step_stride).min(mf - 1)))
            .map(|(step, j)| (step as f64 + micro_rule.nodes[j]) / r as f64)
            .collect();
        let (iota_micro, psi_micro) = modes_at(&taus, macro_rule.k);
        let weights_micro: Vec<f64> = (0..stride)
            .map(|i| {
                let j = i % step_stride;
                if j < mf {
                    micro_rule.weights[j] / r as f64
                } else {
                    0.0
                }
            })
            .collect();
        let transpose = |table: &[f64]| {
            let mut t = vec![0.0; macro_rule.k * stride];
            for (j, row) in table.chunks_exact(macro_rule.k).enumerate() {
                for (a, &x) in row.iter().enumerate() {
                    t[a * stride + j] = x;
                }
            }
            t
        };
        let (iota_micro_t, mut psi_micro_t) = (transpose(&iota_micro), transpose(&psi_micro));
        // The padding contributes nothing to the projections.
        for row in psi_micro_t.chunks_exact_mut(stride) {
            for (x, &w) in row.iter_mut().zip(&weights_micro) {
                if w == 0.0 {
                    *x = 0.0;
                }
            }
        }
        let coordinate_masses = |bodies: &[usize]| {
            bodies
                .iter()
                .flat_map(|&b| std::iter::repeat_n(masses[b], dim))
                .collect()
        };
        let (ds, df) = (slow.len() * dim, sorted.len() * dim);
        let (k, kf, m) = (macro_rule.k, micro_rule.k, macro_rule.m());
        let state = State {
            qs: vec![0.0; ds],
            ps: vec![0.0; ds],
            qf: vec![0.0; df],
            pf: vec![0.0; df],
            cs: vec![0.0; k * ds],
            cf: vec![0.0; r * kf * df],
            cs_prev: vec![0.0; k * ds],
            cf_prev: vec![0.0; r * kf * df],
            has_prev: false,
            ds: vec![0.0; k * ds],
            xs: vec![0.0; m * ds],
            gs: vec![0.0; m * ds],
            stride,
            step_stride,
            xs_micro: vec![0.0; ds * stride],
            gs_micro: vec![0.0; ds * stride],
            xf: vec![0.0; df * stride],
            gf: vec![0.0; df * stride],
            knot: vec![0.0; df],
            momentum: vec![0.0; df],
            dps: vec![0.0; ds],
            last: 0.0,
        };
        Ok(MultirateGalerkin {
            dim,
            g: system.g(),
            slow_mass: coordinate_masses(&slow),
            fast_mass: coordinate_masses(&sorted),
            masses,
            slow,
            fast: sorted,
            slow_system,
            shape,
            h,
            macro_rule,
            micro_rule,
            iota_micro_t,
            psi_micro_t,
            weights_micro,
            slow_masses,
            fast_masses,
            state,
            scale_hint: 0.0,
            evaluations: 0,
            iterations: 0,
            consistent: true,
        })
    }

    /// The body with the shortest osculating period about the heaviest body at the state
    /// (q, p) (body-major, p = m v): the natural fast body of a planetary system (Mercury on
    /// J2000). `None` without a bound two-body orbit about it, or for mismatched lengths.
    pub fn shortest_period_body(system: &NBody, q: &[f64], p: &[f64]) -> Option<usize> {
        let (dim, masses) = (system.body_dim(), system.masses());
        if q.len() != masses.len() * dim || p.len() != q.len() {
            return None;
        }
        let star = (0..masses.len()).max_by(|&a, &b| masses[a].total_cmp(&masses[b]))?;
        fn at(x: &[f64], b: usize, dim: usize) -> &[f64] {
            &x[b * dim..(b + 1) * dim]
        }
        (0..masses.len())
            .filter(|&b| b != star)
            .filter_map(|b| {
                let mu = system.g() * (masses[star] + masses[b]);
                let r: f64 = at(q, b, dim)
                    .iter()
                    .zip(at(q, star, dim))
                    .map(|(x, y)| (x - y) * (x - y))
                    .sum::<f64>()
                    .sqrt();
                let v2: f64 = at(p, b, dim)
                    .iter()
                    .zip(at(p, star, dim))
                    .map(|(x, y)| (x / masses[b] - y / masses[star]).powi(2))
                    .sum();
                // Vis-viva: 1/a = 2/r − v²/μ; the period 2π √(a³/μ) orders like a.
                let inverse_a = 2.0 / r - v2 / mu;
                (inverse_a > 0.0 && inverse_a.is_finite())
                    .then(|| (b, (1.0 / inverse_a).powi(3) / mu))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(b, _)| b)
    }

    /// The numbers of the step.
    pub fn shape(&self) -> MultirateShape {
        self.shape
    }

    /// The fast bodies (ascending).
    pub fn fast_bodies(&self) -> &[usize] {
        &self.fast
    }

    /// Picard iterations of the stage equations so far.
    pub fn iterations(&self) -> usize {
        self.iterations
    }
}

impl OneStepMethod for MultirateGalerkin {
    fn name(&self) -> String {
        let s = self.shape;
        format!(
            "multirate galerkin (n = {}, m = {}, H = {}, R = {}, fast {:?})",
            s.n, s.points, self.h, s.micro_steps, self.fast
        )
    }

    fn step_size(&self) -> f64 {
        self.h
    }

    /// Quadrature points at which forces were evaluated: m + R·m_F per Picard iteration.
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
        let (dim, nb) = (self.dim, self.masses.len());
        crate::error::ensure_step_state(nb * dim, q, p, q_next, p_next)?;
        let st = &mut self.state;
        gather(q, &self.slow, dim, &mut st.qs);
        gather(p, &self.slow, dim, &mut st.ps);
        gather(q, &self.fast, dim, &mut st.qf);
        gather(p, &self.fast, dim, &mut st.pf);
        self.guess();
        // (The driver reads the residual before the first correction; the first correction
        // is the first measure of it.)
        self.state.last = 0.0;
        let step = (t / self.h).round().max(0.0) as usize;
        let first = Termination::new(MAX_ITERATIONS, TOLERANCE, None, 0.0, 1.0);
        let outcome = drive(&mut StageIteration { m: self }, &first);
        let st = &mut self.state;
        if let Err(f) = outcome {
            st.has_prev = false;
            return Err(GviError::NewtonFailure {
                step,
                t,
                residual: f.residual,
                iterations: f.iterations,
                reason: format!("multirate Galerkin: {}", f.reason),
            });
        }
        // The step's end from the converged modes and the last evaluation's forces (one
        // correction earlier, within the tolerance).
        let (ds, df) = (st.qs.len(), st.qf.len());
        let r = self.shape.micro_steps;
        let h = self.h / r as f64;
        for (i, ((x, p), (&q0, &p0))) in st
            .xs
            .iter_mut()
            .zip(st.gs.iter_mut())
            .zip(st.qs.iter().zip(&st.ps))
            .take(ds)
            .enumerate()
        {
            // (The node buffers are free once the iteration has ended.)
            *x = q0 + self.h * st.cs[i];
            *p = p0 + st.dps[i];
        }
        scatter(&st.xs[..ds], &self.slow, dim, q_next);
        scatter(&st.gs[..ds], &self.slow, dim, p_next);
        // x_R from the corrected modes; p^R from the last sweep's forces.
        let kf = self.micro_rule.k;
        let x = &mut st.knot;
        x.copy_from_slice(&st.qf);
        for step_r in 0..r {
            let c0 = &st.cf[step_r * kf * df..step_r * kf * df + df];
            x.iter_mut().zip(c0).for_each(|(x, v)| *x += h * v);
        }
        scatter(x, &self.fast, dim, q_next);
        scatter(&st.momentum, &self.fast, dim, p_next);
        st.cs_prev.copy_from_slice(&st.cs);
        st.cf_prev.copy_from_slice(&st.cf);
        st.has_prev = true;
        if q_next.iter().chain(p_next.iter()).any(|v| !v.is_finite()) {
            st.has_prev = false;
            return Err(GviError::NewtonFailure {
                step,
                t,
                residual: f64::NAN,
                iterations: 0,
                reason: "multirate Galerkin: non-finite state".into(),
            });
        }
        Ok(())
    }
}
