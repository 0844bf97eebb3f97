//! A Galerkin variational integrator for planetary systems whose approximation space is
//! adapted to Kepler motion: Gauss collocation in the *interaction picture* of the
//! Wisdom–Holman splitting (Antoñana, Makazaga & Murua, arXiv:2511.03655; the paper's
//! "enriched" approximation spaces, §4, for near-Keplerian motion).
//!
//! # The method
//!
//! In Jacobi coordinates (Wisdom & Holman 1991, with the Kepler masses of REBOUND's WHFast)
//! the N-body Hamiltonian splits as H = H_K + H_I: one Kepler problem per planet (flow φᴷ_t, exact, [`KeplerDrift`]) and an interaction H_I(r′)
//! of the order of the planet-to-star mass ratio ε. Over a step [t_k, t_k + h] write the
//! state as y(t) = φᴷ_{t−t_k}(z(t)). Since φᴷ is symplectic this change of variables is
//! canonical, and z obeys Hamilton's equations of the time-dependent Hamiltonian
//!
//! H̃(z, τ) = H_I(φᴷ_τ(z)),  ż = J∇H̃ = (Dφᴷ_τ(z))⁻¹ J∇H_I(φᴷ_τ(z)),   (1)
//!
//! whose right-hand side is O(ε) and varies on the planets' orbital periods. One step applies
//! s-stage Gauss–Legendre collocation to (1) from z(t_k) = y_k and then the exact Kepler flow:
//! y_{k+1} = φᴷ_h(z_{k+1}).
//!
//! # Which variational integrator it is
//!
//! s-stage Gauss collocation of a Hamiltonian system is the Galerkin discretisation of
//! Hamilton's phase-space principle δ∫(p·q̇ − H̃) dt = 0 with curves that are polynomials of
//! degree s and the s-point Gauss–Legendre rule for the action (the Galerkin type-II discrete
//! Hamiltonian of Leok & Zhang, *IMA J. Numer. Anal.* 31 (2011); Hairer, Lubich & Wanner,
//! *Geometric Numerical Integration*, §VI.6). The canonical change of variables leaves the
//! phase-space action unchanged up to boundary terms, so in the physical variables the method
//! is the same Galerkin principle for H over the approximation space
//!
//! { t ↦ φᴷ_{t−t_k}(P(t)) : P a polynomial of degree s },
//!
//! Kepler orbits whose elements vary polynomially: for ε = 0 the space contains the exact
//! solution, and the error constant carries the factor ε. Hence the step map is symplectic
//! (a composition of the symplectic Galerkin map and the exact Kepler flow), and it conserves
//! the total angular momentum exactly (up to the stage solve and round-off): H̃ is invariant
//! under rotations (H_I is and φᴷ commutes with them), so Σ r′ᵢ × p′ᵢ is a quadratic
//! invariant of (1), which Gauss collocation conserves; φᴷ conserves each body's angular
//! momentum; the Jacobi transform conserves the total. The total linear momentum is the
//! centre of mass's, which drifts freely and exactly.
//!
//! # Some bodies only
//!
//! [`KeplerAdaptedGalerkin::with_kepler_bodies`] puts only the listed planets on their
//! exact Kepler flows: H = Σ_{i∈K} H_K,i + H_R, and (1) becomes the interaction picture of
//! that partial flow, the unlisted planets' Kepler terms part of H_R and their curves
//! polynomials in the physical variables. The statement above holds with K in place of every
//! planet; no planet listed is s-stage Gauss collocation of H.
//!
//! # Cost
//!
//! Each evaluation of (1) at the s stages makes one Kepler drift per planet and stage (warm
//! started from the previous iterate's universal anomaly), one pairwise force sum per stage
//! and one tangent pull-back per planet and stage. The stage equations are solved by
//! fixed-point iteration: its contraction is O(ε h²ω²), so it converges in a few iterations.

pub mod drift;
mod inner;
#[cfg(test)]
mod j2000_fixture;
mod jacobi;
mod stages;
mod stumpff;
#[cfg(test)]
mod tests;

pub use drift::{DriftError, KeplerDrift};
pub use inner::InnerKeplerGalerkin;

use crate::baselines::{OneStepMethod, gauss_tableau};
use crate::error::{GviError, Result};
use crate::newton::drive;
use crate::systems::NBody;
use jacobi::{Jacobi, add, scale};
use stages::{StageIteration, termination};

/// The largest number of stages accepted.
pub const MAX_KEPLER_ADAPTED_STAGES: usize = 16;

/// The contraction below which the estimate θ/(1 − θ)·|δ| of the remaining error ends the
/// iteration.
const ESTIMATE_BELOW: f64 = 0.05;

/// Iteration cap of the stage equations' fixed-point iteration.
const MAX_ITERATIONS: usize = 40;

/// Converged at the round-off floor once the stage increment stops shrinking below this
/// (relative to each planet's Jacobi position and momentum).
const FLOOR: f64 = 1e-14;

/// The Kepler drift of a body of Jacobi mass `m` from position `q` and momentum `p` over
/// time `t`, warm-started from `anomaly` (the universal anomaly of the same body's last drift
/// of this kind, NaN before the first), which it updates.
fn warm_drift(
    mu: f64,
    m: f64,
    q: [f64; 3],
    p: [f64; 3],
    t: f64,
    anomaly: &mut f64,
) -> std::result::Result<KeplerDrift, DriftError> {
    let guess = anomaly.is_finite().then_some(*anomaly);
    let drift = KeplerDrift::new(mu, q, scale(1.0 / m, p), t, guess)?;
    *anomaly = drift.anomaly();
    Ok(drift)
}

/// The stage guesses' extrapolation table of Gauss nodes `c`: row j holds the Lagrange basis
/// over the nodes 0, c_1, …, c_s evaluated at 1 + c_j (s × (s + 1)), so that the last step's
/// start and stage values give this step's stage values on the same polynomial.
fn extrapolation_table(c: &[f64]) -> Vec<f64> {
    let nodes: Vec<f64> = std::iter::once(0.0).chain(c.iter().copied()).collect();
    c.iter()
        .flat_map(|&cj| {
            let x = 1.0 + cj;
            let nodes = &nodes;
            (0..nodes.len()).map(move |l| {
                (0..nodes.len())
                    .filter(|&m| m != l)
                    .map(|m| (x - nodes[m]) / (nodes[l] - nodes[m]))
                    .product::<f64>()
            })
        })
        .collect()
}

/// The Cartesian state `q`, `p` (N bodies of `k` ≤ 3 coordinates, body-major) into points of
/// three (zero-padded).
fn load_points(k: usize, q: &[f64], p: &[f64], r: &mut [[f64; 3]], pr: &mut [[f64; 3]]) {
    for (b, (rb, pb)) in r.iter_mut().zip(pr.iter_mut()).enumerate() {
        *rb = [0.0; 3];
        *pb = [0.0; 3];
        rb[..k].copy_from_slice(&q[b * k..b * k + k]);
        pb[..k].copy_from_slice(&p[b * k..b * k + k]);
    }
}

/// [`load_points`] reversed.
fn store_points(k: usize, r: &[[f64; 3]], pr: &[[f64; 3]], q: &mut [f64], p: &mut [f64]) {
    for (b, (rb, pb)) in r.iter().zip(pr).enumerate() {
        q[b * k..b * k + k].copy_from_slice(&rb[..k]);
        p[b * k..b * k + k].copy_from_slice(&pb[..k]);
    }
}

/// Whether two slices hold the same bits (a step starting where the last one ended).
fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// The Kepler-adapted Galerkin integrator: s-stage Gauss collocation in the interaction
/// picture of the Jacobi Wisdom–Holman splitting (order 2s; see the [module](self) for the
/// method and its variational statement).
///
/// It integrates an [`NBody`] system (2 or 3 dimensions) in its own coordinates — q
/// body-major, p = m v — and fits systems with one dominant mass, body 0 (a star and its
/// planets): the error constant is proportional to the planets' mass ratio.
///
/// ```
/// use galerkin_vi::baselines::OneStepMethod;
/// use galerkin_vi::kepler_adapted::KeplerAdaptedGalerkin;
/// use galerkin_vi::systems::NBody;
///
/// // A star and a planet on a circular relative orbit of radius 1: μ = G(m₀ + m₁), relative
/// // speed √μ, momenta ±m′√μ with the reduced mass m′ = m₀m₁/(m₀ + m₁).
/// let (m0, m1) = (1.0, 1e-3);
/// let nb = NBody::new(vec![m0, m1], 1.0, 2)?;
/// let mu: f64 = m0 + m1;
/// let pr = m0 * m1 / mu * mu.sqrt();
/// let (q, p) = ([0.0, 0.0, 1.0, 0.0], [0.0, -pr, 0.0, pr]);
/// let mut m = KeplerAdaptedGalerkin::new(&nb, 4, 0.5)?;
/// let (mut q1, mut p1) = ([0.0; 4], [0.0; 4]);
/// m.step(0.0, &q, &p, &mut q1, &mut p1)?;
/// // Two bodies are one Kepler problem in Jacobi coordinates: the step is exact.
/// let x = q1[2] - q1[0];
/// assert!((x - (0.5 * mu.sqrt()).cos()).abs() < 1e-14);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct KeplerAdaptedGalerkin {
    jacobi: Jacobi,
    dim: usize,
    h: f64,
    s: usize,
    c: Vec<f64>,
    b: Vec<f64>,
    /// a_ij, row-major s×s.
    a: Vec<f64>,
    /// The stage guesses of the polynomial bodies: row j holds the Lagrange basis over the
    /// nodes 0, c_1, …, c_s of the last step evaluated at 1 + c_j (s × (s + 1)).
    extrapolate: Vec<f64>,
    stages: StageState,
    evaluations: usize,
    iterations: usize,
    /// Continue from the last step's Jacobi state when a step starts where it ended (always,
    /// except in the tests' negative control).
    continue_jacobi: bool,
    /// Which Jacobi bodies move on their exact Kepler flow (entry 0, the centre of mass,
    /// unused); the others' curves are polynomials ([`KeplerAdaptedGalerkin::with_kepler_bodies`]).
    kepler: Vec<bool>,
}

/// The stage equations' unknowns and work buffers: planet i of stage j at index j·n + i
/// (n = N − 1 planets, Jacobi bodies 1 … N−1).
#[derive(Debug, Clone)]
struct StageState {
    n: usize,
    /// z_k: the Jacobi positions and momenta at the step's start (entry 0 the centre of mass).
    rj: Vec<[f64; 3]>,
    pj: Vec<[f64; 3]>,
    /// Stage values Z_j (positions, momenta).
    zq: Vec<[f64; 3]>,
    zp: Vec<[f64; 3]>,
    /// Right-hand side of (1) at the stage values.
    fq: Vec<[f64; 3]>,
    fp: Vec<[f64; 3]>,
    /// Universal anomalies of the last stage drifts (warm starts); NaN before the first.
    anomaly: Vec<f64>,
    /// Universal anomalies of the last full-step drifts.
    full_anomaly: Vec<f64>,
    /// The last step's z_k and stage values (entries l·n + i, l = 0 … s), for the polynomial
    /// bodies' next stage guesses; valid when `has_previous`.
    previous_q: Vec<[f64; 3]>,
    previous_p: Vec<[f64; 3]>,
    has_previous: bool,
    /// One stage's drifts, its Jacobi positions, Cartesian scratch and gradients.
    drifts: Vec<KeplerDrift>,
    positions: Vec<[f64; 3]>,
    cartesian: Vec<[f64; 3]>,
    cartesian_gradient: Vec<[f64; 3]>,
    gradient: Vec<[f64; 3]>,
    /// Cartesian state in and out.
    r: Vec<[f64; 3]>,
    p: Vec<[f64; 3]>,
    /// The last step's output, as returned (valid when `has_last`; `rj`, `pj` then still hold
    /// the Jacobi state it was rounded from).
    last_q: Vec<f64>,
    last_p: Vec<f64>,
    has_last: bool,
}

impl KeplerAdaptedGalerkin {
    /// The integrator with `stages` Gauss stages (1 ≤ s ≤ [`MAX_KEPLER_ADAPTED_STAGES`]) and
    /// step `h` > 0 for `system` (at least two bodies; body 0 the central mass).
    pub fn new(system: &NBody, stages: usize, h: f64) -> Result<Self> {
        if !(1..=MAX_KEPLER_ADAPTED_STAGES).contains(&stages) {
            return Err(GviError::InvalidInput {
                name: "Kepler-adapted stages".into(),
                reason: format!("s = {stages}; need 1 ≤ s ≤ {MAX_KEPLER_ADAPTED_STAGES}"),
            });
        }
        let (c, b, a) = gauss_tableau(stages)?;
        let all: Vec<usize> = (1..system.bodies()).collect();
        Self::from_tableau(system, c, b, a, h, &all)
    }

    /// The integrator adapted to the Kepler motion of the listed bodies only (indices
    /// 1 … N − 1 of `system`'s bodies, in any order): each listed body's Jacobi Kepler problem
    /// is solved exactly, as in [`new`](Self::new), and every other body's curve is a
    /// polynomial, as in plain Gauss collocation. `bodies` = 1 … N − 1 is [`new`](Self::new);
    /// an empty list is s-stage Gauss collocation of the whole system (in Jacobi coordinates,
    /// which a Runge–Kutta method does not notice: it commutes with linear changes of
    /// variables).
    ///
    /// The splitting is H = Σ_{i∈K} H_K,i + H_R with H_R the rest (the unlisted bodies'
    /// Kepler terms included), and the step is Gauss collocation of H_R in the interaction
    /// picture of the listed bodies' Kepler flows: the same variational statement as the
    /// [module](self)'s over the space of curves whose listed bodies follow Kepler orbits with
    /// polynomially varying elements, so the map is symplectic and conserves the angular
    /// momentum. Its use: a fast planet on its exact orbit (Mercury in the J2000 scene, where
    /// a polynomial curve needs steps a third of the slow planets' and Picard iterations that
    /// contract by (hω)² per step; docs/solvers.md, issue 35), the others on the polynomial
    /// step.
    pub fn with_kepler_bodies(
        system: &NBody,
        stages: usize,
        h: f64,
        bodies: &[usize],
    ) -> Result<Self> {
        let mut m = Self::new(system, stages, h)?;
        let nb = system.bodies();
        if let Some(&bad) = bodies.iter().find(|&&b| b == 0 || b >= nb) {
            return Err(GviError::InvalidInput {
                name: "Kepler bodies".into(),
                reason: format!(
                    "body {bad}: the Kepler-adapted bodies are 1 … {} (body 0 is the central \
                     mass)",
                    nb - 1
                ),
            });
        }
        m.kepler = (0..nb).map(|b| bodies.contains(&b)).collect();
        Ok(m)
    }

    /// The interaction-picture step with the Runge–Kutta tableau (c, b, A) (A row-major):
    /// Gauss for [`new`](Self::new); other tableaux serve as the property tests' negative
    /// controls.
    fn from_tableau(
        system: &NBody,
        c: Vec<f64>,
        b: Vec<f64>,
        a: Vec<f64>,
        h: f64,
        kepler_bodies: &[usize],
    ) -> Result<Self> {
        let stages = c.len();
        if !(h.is_finite() && h > 0.0) {
            return Err(GviError::InvalidStepSize { h });
        }
        let nb = system.bodies();
        if nb < 2 {
            return Err(GviError::InvalidInput {
                name: "bodies".into(),
                reason: "the Kepler-adapted integrator needs a central body and at least one \
                         more"
                    .into(),
            });
        }
        let n = nb - 1;
        let three = vec![[0.0; 3]; nb];
        let stage_values = vec![[0.0; 3]; stages * n];
        let extrapolate = extrapolation_table(&c);
        Ok(KeplerAdaptedGalerkin {
            jacobi: Jacobi::new(system.masses(), system.g()),
            dim: system.body_dim(),
            h,
            s: stages,
            c,
            b,
            a,
            extrapolate,
            stages: StageState {
                n,
                rj: three.clone(),
                pj: three.clone(),
                zq: stage_values.clone(),
                zp: stage_values.clone(),
                fq: stage_values.clone(),
                fp: stage_values,
                anomaly: vec![f64::NAN; stages * n],
                full_anomaly: vec![f64::NAN; n],
                previous_q: vec![[0.0; 3]; (stages + 1) * n],
                previous_p: vec![[0.0; 3]; (stages + 1) * n],
                has_previous: false,
                drifts: Vec::with_capacity(n),
                positions: three.clone(),
                cartesian: three.clone(),
                cartesian_gradient: three.clone(),
                gradient: three.clone(),
                r: three.clone(),
                p: three,
                last_q: vec![0.0; nb * system.body_dim()],
                last_p: vec![0.0; nb * system.body_dim()],
                has_last: false,
            },
            evaluations: 0,
            iterations: 0,
            continue_jacobi: true,
            kepler: (0..nb).map(|b| kepler_bodies.contains(&b)).collect(),
        })
    }

    /// Number of stages s (the order is 2s).
    pub fn stages(&self) -> usize {
        self.s
    }

    /// Fixed-point iterations of the stage equations so far (each one evaluation of (1) at
    /// every stage).
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// The step in Jacobi coordinates: `stages.rj`, `stages.pj` hold z_k on entry and
    /// y_{k+1} on return.
    fn advance_jacobi(&mut self, t: f64) -> Result<()> {
        let (s, h) = (self.s, self.h);
        let n = self.stages.n;
        let st = &mut self.stages;
        for j in 0..s {
            for i in 0..n {
                let (body, k) = (i + 1, j * n + i);
                if self.kepler[body] || !st.has_previous {
                    // In the interaction picture a Kepler body's state changes by O(ε) over
                    // the step: its start is the guess.
                    st.zq[k] = st.rj[body];
                    st.zp[k] = st.pj[body];
                    continue;
                }
                // A polynomial body: the last step's collocation polynomial (through its
                // z_k and stage values) continued to this step's stage times.
                let row = &self.extrapolate[j * (s + 1)..(j + 1) * (s + 1)];
                let (mut q, mut p) = ([0.0; 3], [0.0; 3]);
                for (l, &e) in row.iter().enumerate() {
                    q = add(q, scale(e, st.previous_q[l * n + i]));
                    p = add(p, scale(e, st.previous_p[l * n + i]));
                }
                st.zq[k] = q;
                st.zp[k] = p;
            }
        }
        let step = (t / h).round().max(0.0) as usize;
        let fail = |residual: f64, iterations: usize, reason: String| GviError::NewtonFailure {
            step,
            t,
            residual,
            iterations,
            reason: format!("Kepler-adapted Galerkin (s = {s}): {reason}"),
        };
        let mut solve = StageIteration { m: self, last: 0.0 };
        let first = termination(0);
        drive(&mut solve, &first).map_err(|f| fail(f.residual, f.iterations, f.reason))?;
        let st = &mut self.stages;
        // The polynomial bodies' next guesses start from this step's z_k and stage values.
        for i in 0..n {
            st.previous_q[i] = st.rj[i + 1];
            st.previous_p[i] = st.pj[i + 1];
        }
        st.previous_q[n..].copy_from_slice(&st.zq);
        st.previous_p[n..].copy_from_slice(&st.zp);
        st.has_previous = true;
        // z_{k+1} = z_k + h Σ b_j F_j, then the Kepler flow over the whole step.
        for i in 0..n {
            let body = i + 1;
            let (mut dq, mut dp) = ([0.0; 3], [0.0; 3]);
            for j in 0..s {
                let w = h * self.b[j];
                dq = add(dq, scale(w, st.fq[j * n + i]));
                dp = add(dp, scale(w, st.fp[j * n + i]));
            }
            let m = self.jacobi.jacobi_mass(body);
            let (q1, p1) = (add(st.rj[body], dq), add(st.pj[body], dp));
            if !self.kepler[body] {
                st.rj[body] = q1;
                st.pj[body] = p1;
                continue;
            }
            let drift = warm_drift(self.jacobi.mu(body), m, q1, p1, h, &mut st.full_anomaly[i])
                .map_err(|e| fail(f64::NAN, 0, format!("Kepler drift of body {body}: {e}")))?;
            st.rj[body] = drift.position();
            st.pj[body] = scale(m, drift.velocity());
        }
        // The centre of mass drifts freely.
        let total = self.jacobi.jacobi_mass(0);
        st.rj[0] = add(st.rj[0], scale(h / total, st.pj[0]));
        Ok(())
    }
}

impl OneStepMethod for KeplerAdaptedGalerkin {
    fn name(&self) -> String {
        format!("kepler-adapted galerkin (s = {}, h = {})", self.s, self.h)
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
        let (k, nb) = (self.dim, self.jacobi.bodies());
        crate::error::ensure_step_state(nb * k, q, p, q_next, p_next)?;
        let st = &mut self.stages;
        load_points(k, q, p, &mut st.r, &mut st.p);
        // A step that starts where the last one ended continues from the Jacobi state that
        // step computed: converting the rounded Cartesian state back every step adds a
        // rounding error per step that accumulates (J2000, s = 8, h = 16.7 d: Mercury's
        // error 0.7–1.8e-9 AU depending on a 1e-15 change of the start, Mars's 3.4e-10,
        // against 8.0–9.1e-11 and 6.5e-12 continuing; docs/guide/kepler-adapted.md).
        // (`rj`, `pj` still hold that state: only a step writes them.)
        let continues = self.continue_jacobi
            && st.has_last
            && same_bits(&st.last_q, q)
            && same_bits(&st.last_p, p);
        if !continues {
            // A new start: no last step to continue the polynomial bodies' curves from.
            st.has_previous = false;
            self.jacobi.positions_to_jacobi(&st.r, &mut st.rj);
            self.jacobi.covector_to_jacobi(&st.p, &mut st.pj);
        }
        st.has_last = false;
        self.advance_jacobi(t)?;
        let st = &mut self.stages;
        self.jacobi.positions_from_jacobi(&st.rj, &mut st.r);
        self.jacobi.covector_from_jacobi(&st.pj, &mut st.p);
        store_points(k, &st.r, &st.p, q_next, p_next);
        let st = &mut self.stages;
        st.last_q.copy_from_slice(q_next);
        st.last_p.copy_from_slice(p_next);
        st.has_last = true;
        if q_next.iter().chain(p_next.iter()).any(|x| !x.is_finite()) {
            return Err(GviError::NewtonFailure {
                step: (t / self.h).round().max(0.0) as usize,
                t,
                residual: f64::NAN,
                iterations: 0,
                reason: "Kepler-adapted Galerkin: non-finite state".into(),
            });
        }
        Ok(())
    }
}
