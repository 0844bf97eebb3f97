//! [`InnerKeplerGalerkin`]: the Kepler-adapted step with only the innermost planets on their
//! Kepler orbits, solved the way the velocity form solves a polynomial step (the method is
//! described on the type).

mod iteration;
#[cfg(test)]
mod tests;

use super::jacobi::{Jacobi, add, scale};
use super::stages::termination;
use super::{
    KeplerDrift, MAX_KEPLER_ADAPTED_STAGES, extrapolation_table, load_points, same_bits,
    store_points, warm_drift,
};
use crate::baselines::{OneStepMethod, gauss_tableau};
use crate::error::{GviError, Result};
use crate::integrator::velocity::BlockFreeze;
use crate::newton::drive;
use crate::systems::NBody;
use iteration::SlotIteration;

/// Gauss collocation with the innermost k planets on their exact Kepler orbits (order 2s):
/// [`KeplerAdaptedGalerkin::with_kepler_bodies`](super::KeplerAdaptedGalerkin::with_kepler_bodies)
/// with the bodies 1 … k, solved slot by slot with converged slots frozen and the forces in
/// vector lanes.
///
/// # Coordinates
///
/// Take Jacobi coordinates of the first k + 1 bodies only: their centre of mass C (mass
/// η_k = m₀ + … + m_k), the Jacobi positions r′₁ … r′_k (masses m′ᵢ), and leave the bodies
/// k + 1 … N − 1 Cartesian. The kinetic energy stays diagonal,
/// T = |P_C|²/2η_k + Σ_{i≤k} |p′ᵢ|²/2m′ᵢ + Σ_{b>k} |p_b|²/2m_b, and the Kepler terms of the
/// planets 1 … k are the full Jacobi splitting's (the same r′ᵢ, m′ᵢ and μᵢ = G ηᵢ: a Jacobi
/// coordinate depends only on the bodies inside it). These coordinates are a linear function of
/// the full Jacobi coordinates in which r′₁ … r′_k enter only as themselves
/// (C = R − Σ_{l>k} m_l r′_l/η_l and x_b = R + (1 − m_b/η_b) r′_b − Σ_{l>b} m_l r′_l/η_l for
/// b > k), and a Runge–Kutta method commutes with linear changes of the variables it treats
/// polynomially: the step is the map of `with_kepler_bodies(1 … k)` (the same discrete
/// Lagrangian, so the same variational statement, symplecticity and angular momentum), up to
/// the stage equations' tolerance and round-off.
///
/// # The stage equations
///
/// The polynomial slots (C and the bodies b > k) obey q̈ = f(q)/m: s-stage Gauss collocation
/// in its second-order form, the positions the only unknowns,
///
/// Q_j = q_k + h c_j v_k + h² Σ_l (A²)_jl f(Q_l)/m,
/// q_{k+1} = q_k + h v_k + h² Σ_l (bᵀA)_l f(Q_l)/m,  p_{k+1} = p_k + h Σ_l b_l f(Q_l),
///
/// which is what the velocity form computes with the collocation rule (n − 1 Gauss points for
/// n basis functions). The Kepler slots are in the interaction picture of
/// [`KeplerAdaptedGalerkin`](super::KeplerAdaptedGalerkin): stage values
/// Z_j = z_k + h Σ_l a_jl F_l with F the pulled-back kick of the perturbation
/// ∂H_R/∂r′ᵢ = ∂V/∂r′ᵢ + m′ᵢμᵢ r′ᵢ/|r′ᵢ|³ at the drifted positions.
///
/// # Why it is fast
///
/// Picard's iteration converges for each slot at its own rate, about (hωᵢ)² per iteration for
/// a polynomial one and O(ε h²ω²) for a Kepler one, so the converged slots are frozen as in the
/// velocity form (`crate::integrator::velocity` freeze): the forces are evaluated, in vector
/// lanes over the stages, for the pairs with an active body only, and a last correction of
/// every slot confirms the frozen ones. With the fastest planet on its exact orbit the step
/// can be set by the slower ones (J2000: Mercury's 88-day orbit no longer sets h; measured in
/// docs/solvers.md).
///
/// # Example
///
/// ```
/// use galerkin_vi::baselines::OneStepMethod;
/// use galerkin_vi::kepler_adapted::{InnerKeplerGalerkin, KeplerAdaptedGalerkin};
/// use galerkin_vi::systems::NBody;
///
/// // A star, a fast inner planet and a slow outer one.
/// let nb = NBody::new(vec![1.0, 1e-5, 1e-3], 1.0, 2)?;
/// let (q, p) = (
///    [0.0, 0.0, 0.4, 0.0, -2.0, 0.0],
///    [0.0, 1e-5 / 0.4f64.sqrt() - 1e-3 / 2f64.sqrt(), 0.0, -1e-5 / 0.4f64.sqrt(), 0.0, 1e-3 / 2f64.sqrt()],
/// );
/// let mut fast = InnerKeplerGalerkin::new(&nb, 6, 0.5, 1)?;
/// let mut reference = KeplerAdaptedGalerkin::with_kepler_bodies(&nb, 6, 0.5, &[1])?;
/// let (mut q1, mut p1, mut q2, mut p2) = ([0.0; 6], [0.0; 6], [0.0; 6], [0.0; 6]);
/// fast.step(0.0, &q, &p, &mut q1, &mut p1)?;
/// reference.step(0.0, &q, &p, &mut q2, &mut p2)?;
/// // The same map, up to round-off.
/// assert!(q1.iter().zip(&q2).all(|(a, b)| (a - b).abs() < 1e-14));
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone)]
pub struct InnerKeplerGalerkin {
    system: NBody,
    /// The Jacobi chain of bodies 0 … k.
    prefix: Jacobi,
    /// k, the number of Kepler-adapted planets.
    kepler: usize,
    /// Body dimension (2 or 3).
    dim: usize,
    h: f64,
    s: usize,
    c: Vec<f64>,
    b: Vec<f64>,
    /// a_jl, row-major s×s.
    a: Vec<f64>,
    /// (A²)_lj, the transpose of the positions' stage matrix of the second-order form
    /// (row-major s×s: row l holds column l of A², so that a slot's stage positions are
    /// updated a row at a time over the stages).
    a2t: Vec<f64>,
    /// (bᵀA)_l: the end position's weights.
    ba: Vec<f64>,
    /// The polynomial slots' stage guesses: row j holds the Lagrange basis over the nodes 0,
    /// c_1, …, c_s of the last step evaluated at 1 + c_j (s × (s + 1)).
    extrapolate: Vec<f64>,
    /// The slots' masses: η_k, m′₁ … m′_k, m_{k+1} … m_{N−1}.
    mass: Vec<f64>,
    slots: Slots,
    freeze: BlockFreeze,
    /// Freeze converged slots (always, except in the tests' comparison with the unfrozen
    /// iteration).
    freezing: bool,
    evaluations: usize,
    masked_evaluations: usize,
    iterations: usize,
}

/// The stage equations' unknowns and work buffers. Slot b of stage j is at index j·N + b.
#[derive(Debug, Clone)]
struct Slots {
    /// N, the number of slots (= bodies).
    n: usize,
    /// The slots' positions and momenta at the step's start.
    q0: Vec<[f64; 3]>,
    p0: Vec<[f64; 3]>,
    /// The chain's stage positions: Q_j of slot 0, the interaction-picture position of a
    /// Kepler slot (the slots after the chain have theirs in `x`).
    q: Vec<[f64; 3]>,
    /// A Kepler slot's interaction-picture stage momenta (unused for the others).
    zp: Vec<[f64; 3]>,
    /// A Kepler slot's right-hand side for its positions (unused for the others).
    fq: Vec<[f64; 3]>,
    /// The force on slot 0; a Kepler slot's right-hand side for its momenta (the slots after
    /// the chain have theirs, negated, in `gradient`).
    f: Vec<[f64; 3]>,
    /// A Kepler slot's drift at each stage (its position and the pull-back of its kicks).
    drifts: Vec<Option<KeplerDrift>>,
    /// Universal anomalies of the last stage and full-step drifts (warm starts; NaN before).
    anomaly: Vec<f64>,
    full_anomaly: Vec<f64>,
    /// The last step's start and stage positions, for the polynomial slots' guesses (valid
    /// when `has_previous`): slot 0's at entries l = 0 … s, the others' by coordinate (row
    /// r = b·K + c holds s + 1 values, the start first).
    previous: Vec<[f64; 3]>,
    previous_rows: Vec<f64>,
    has_previous: bool,
    /// Cartesian positions and the potential's gradient at the stages by coordinate: row
    /// b·K + c holds coordinate c of body b at the s stages. For a body after the chain these
    /// are its slot's stage positions Q_j, the unknowns themselves.
    x: Vec<f64>,
    gradient: Vec<f64>,
    /// The Cartesian bodies whose gradient an iteration needs.
    need: Vec<bool>,
    /// The chain's positions and gradients at one stage (k + 1 entries each).
    chain: Vec<[f64; 3]>,
    chain_out: Vec<[f64; 3]>,
    /// Each slot's position scale this step (the convergence test's).
    scale: Vec<f64>,
    /// Cartesian state in and out.
    r: Vec<[f64; 3]>,
    p: Vec<[f64; 3]>,
    /// The last step's output as returned (valid when `has_last`: `q0`, `p0` then hold the
    /// slot state it was rounded from).
    last_q: Vec<f64>,
    last_p: Vec<f64>,
    has_last: bool,
}

impl InnerKeplerGalerkin {
    /// The integrator with `stages` Gauss stages (1 ≤ s ≤ [`MAX_KEPLER_ADAPTED_STAGES`]), step
    /// `h` > 0 and the bodies 1 … `kepler` of `system` (1 ≤ k ≤ N − 1; body 0 the central
    /// mass, the bodies ordered from the inside out as Jacobi coordinates need) on their exact
    /// Kepler orbits.
    pub fn new(system: &NBody, stages: usize, h: f64, kepler: usize) -> Result<Self> {
        if !(1..=MAX_KEPLER_ADAPTED_STAGES).contains(&stages) {
            return Err(GviError::InvalidInput {
                name: "Kepler-adapted stages".into(),
                reason: format!("s = {stages}; need 1 ≤ s ≤ {MAX_KEPLER_ADAPTED_STAGES}"),
            });
        }
        let (c, b, a) = gauss_tableau(stages)?;
        Self::from_tableau(system, c, b, a, h, kepler)
    }

    /// The step with the Runge–Kutta tableau (c, b, A) (A row-major): Gauss for
    /// [`new`](Self::new); other tableaux serve as the property tests' negative controls.
    fn from_tableau(
        system: &NBody,
        c: Vec<f64>,
        b: Vec<f64>,
        a: Vec<f64>,
        h: f64,
        kepler: usize,
    ) -> Result<Self> {
        if !(h.is_finite() && h > 0.0) {
            return Err(GviError::InvalidStepSize { h });
        }
        let nb = system.bodies();
        if nb < 2 || !(1..nb).contains(&kepler) {
            return Err(GviError::InvalidInput {
                name: "Kepler bodies".into(),
                reason: format!(
                    "k = {kepler} innermost planets of {nb} bodies; need 1 ≤ k ≤ N − 1 (body 0 \
                     is the central mass)"
                ),
            });
        }
        let s = c.len();
        let a2t = (0..s * s)
            .map(|lj| {
                let (l, j) = (lj / s, lj % s);
                (0..s).map(|m| a[j * s + m] * a[m * s + l]).sum()
            })
            .collect();
        let ba = (0..s)
            .map(|l| (0..s).map(|j| b[j] * a[j * s + l]).sum())
            .collect();
        let extrapolate = extrapolation_table(&c);
        let masses = system.masses();
        let prefix = Jacobi::new(&masses[..=kepler], system.g());
        let mass = (0..nb)
            .map(|i| {
                if i <= kepler {
                    prefix.jacobi_mass(i)
                } else {
                    masses[i]
                }
            })
            .collect();
        let freeze = BlockFreeze::new(nb, 1).ok_or_else(|| GviError::InvalidInput {
            name: "bodies".into(),
            reason: "need a central body and at least one more".into(),
        })?;
        let dim = system.body_dim();
        let three = vec![[0.0; 3]; nb];
        let staged = vec![[0.0; 3]; s * nb];
        Ok(InnerKeplerGalerkin {
            system: system.clone(),
            prefix,
            kepler,
            dim,
            h,
            s,
            c,
            b,
            a,
            a2t,
            ba,
            extrapolate,
            mass,
            slots: Slots {
                n: nb,
                q0: three.clone(),
                p0: three.clone(),
                q: staged.clone(),
                zp: staged.clone(),
                fq: staged.clone(),
                f: staged,
                drifts: vec![None; s * nb],
                anomaly: vec![f64::NAN; s * nb],
                full_anomaly: vec![f64::NAN; nb],
                previous: vec![[0.0; 3]; s + 1],
                previous_rows: vec![0.0; nb * dim * (s + 1)],
                has_previous: false,
                x: vec![0.0; nb * dim * s],
                gradient: vec![0.0; nb * dim * s],
                need: vec![true; nb],
                chain: vec![[0.0; 3]; kepler + 1],
                chain_out: vec![[0.0; 3]; kepler + 1],
                scale: vec![1.0; nb],
                r: three.clone(),
                p: three,
                last_q: vec![0.0; nb * dim],
                last_p: vec![0.0; nb * dim],
                has_last: false,
            },
            freeze,
            freezing: true,
            evaluations: 0,
            masked_evaluations: 0,
            iterations: 0,
        })
    }

    /// Number of stages s (the order is 2s).
    pub fn stages(&self) -> usize {
        self.s
    }

    /// The number k of innermost planets on their Kepler orbits.
    pub fn kepler_bodies(&self) -> usize {
        self.kepler
    }

    /// Fixed-point iterations of the stage equations so far.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// Stage force evaluations so far on a subset of the bodies (the frozen ones left out);
    /// [`force_evaluations`](OneStepMethod::force_evaluations) counts those of every body.
    pub fn partial_force_evaluations(&self) -> usize {
        self.masked_evaluations
    }

    /// Whether slot `b` is on a Kepler orbit.
    fn is_kepler(&self, b: usize) -> bool {
        (1..=self.kepler).contains(&b)
    }

    /// Cartesian → slots: the chain's Jacobi coordinates, the other bodies as they are.
    fn load_slots(&mut self) {
        let k = self.kepler;
        let st = &mut self.slots;
        self.prefix
            .positions_to_jacobi(&st.r[..=k], &mut st.q0[..=k]);
        self.prefix
            .covector_to_jacobi(&st.p[..=k], &mut st.p0[..=k]);
        for b in k + 1..st.n {
            st.q0[b] = st.r[b];
            st.p0[b] = st.p[b];
        }
    }

    /// Slots → Cartesian.
    fn store_slots(&mut self) {
        let k = self.kepler;
        let st = &mut self.slots;
        self.prefix
            .positions_from_jacobi(&st.q0[..=k], &mut st.r[..=k]);
        self.prefix
            .covector_from_jacobi(&st.p0[..=k], &mut st.p[..=k]);
        for b in k + 1..st.n {
            st.r[b] = st.q0[b];
            st.p[b] = st.p0[b];
        }
    }

    /// The stage guesses: a Kepler slot's start (its interaction-picture state changes by
    /// O(ε) over the step); a polynomial slot's last collocation polynomial continued to this
    /// step's stage times, or its free flight on a new start.
    fn guess(&mut self) {
        let (s, h, n) = (self.s, self.h, self.slots.n);
        // The convergence test's position scales: a slot's own size, but never below the
        // innermost Kepler orbit's (the chain's centre of mass sits near the origin, and its
        // error matters on the planets' scale).
        let inner = norm_max(self.slots.q0[1]);
        for b in 0..n {
            self.slots.scale[b] = norm_max(self.slots.q0[b]).max(inner);
        }
        let (k, dim) = (self.kepler, self.dim);
        let st = &mut self.slots;
        for j in 0..s {
            for b in 1..=k {
                st.q[j * n + b] = st.q0[b];
                st.zp[j * n + b] = st.p0[b];
            }
            let e = &self.extrapolate[j * (s + 1)..(j + 1) * (s + 1)];
            st.q[j * n] = if st.has_previous {
                let mut q = [0.0; 3];
                for (l, &e) in e.iter().enumerate() {
                    q = add(q, scale(e, st.previous[l]));
                }
                q
            } else {
                add(st.q0[0], scale(self.c[j] * h / self.mass[0], st.p0[0]))
            };
        }
        for b in k + 1..n {
            for c in 0..dim {
                let r = b * dim + c;
                let row = &mut st.x[r * s..(r + 1) * s];
                if st.has_previous {
                    let previous = &st.previous_rows[r * (s + 1)..(r + 1) * (s + 1)];
                    for (j, x) in row.iter_mut().enumerate() {
                        let e = &self.extrapolate[j * (s + 1)..(j + 1) * (s + 1)];
                        *x = e.iter().zip(previous).map(|(e, q)| e * q).sum();
                    }
                } else {
                    let (q0, v) = (st.q0[b][c], st.p0[b][c] / self.mass[b]);
                    for (x, &cj) in row.iter_mut().zip(&self.c) {
                        *x = q0 + cj * h * v;
                    }
                }
            }
        }
    }

    /// The step in slot coordinates: `q0`, `p0` hold the start on entry and the end on return.
    fn advance(&mut self, t: f64) -> Result<()> {
        let (s, h, n) = (self.s, self.h, self.slots.n);
        self.guess();
        let step = (t / h).round().max(0.0) as usize;
        let fail = |residual: f64, iterations: usize, reason: String| GviError::NewtonFailure {
            step,
            t,
            residual,
            iterations,
            reason: format!("inner Kepler-adapted Galerkin (s = {s}): {reason}"),
        };
        self.freeze.start(self.freezing);
        let mut solve = SlotIteration {
            m: self,
            last: 0.0,
            confirmation: false,
        };
        drive(&mut solve, &termination(0)).map_err(|f| fail(f.residual, f.iterations, f.reason))?;
        let (k, dim) = (self.kepler, self.dim);
        let st = &mut self.slots;
        st.previous[0] = st.q0[0];
        for j in 0..s {
            st.previous[j + 1] = st.q[j * n];
        }
        st.has_previous = true;
        // The polynomial slots: p_{k+1} = p_k + h Σ b_l f_l and
        // q_{k+1} = q_k + h v_k + h² Σ (bᵀA)_l f_l/m, with f = −∇V after the chain.
        let (mut dp, mut dq) = ([0.0; 3], [0.0; 3]);
        for l in 0..s {
            let f = st.f[l * n];
            dp = add(dp, scale(h * self.b[l], f));
            dq = add(dq, scale(h * h * self.ba[l] / self.mass[0], f));
        }
        let v = scale(h / self.mass[0], st.p0[0]);
        st.q0[0] = add(st.q0[0], add(v, dq));
        st.p0[0] = add(st.p0[0], dp);
        for b in k + 1..n {
            let m = self.mass[b];
            for c in 0..dim {
                let r = b * dim + c;
                let g = &st.gradient[r * s..(r + 1) * s];
                let (mut dp, mut dq) = (0.0, 0.0);
                for l in 0..s {
                    dp -= h * self.b[l] * g[l];
                    dq -= h * h * self.ba[l] / m * g[l];
                }
                let previous = &mut st.previous_rows[r * (s + 1)..(r + 1) * (s + 1)];
                previous[0] = st.q0[b][c];
                previous[1..].copy_from_slice(&st.x[r * s..(r + 1) * s]);
                st.q0[b][c] += h / m * st.p0[b][c] + dq;
                st.p0[b][c] += dp;
            }
        }
        for b in 1..=k {
            let m = self.mass[b];
            let st = &mut self.slots;
            // z_{k+1} = z_k + h Σ b_l F_l, then the Kepler flow over the whole step.
            let (mut dq, mut dp) = ([0.0; 3], [0.0; 3]);
            for l in 0..s {
                let w = h * self.b[l];
                dq = add(dq, scale(w, st.fq[l * n + b]));
                dp = add(dp, scale(w, st.f[l * n + b]));
            }
            let (q1, p1) = (add(st.q0[b], dq), add(st.p0[b], dp));
            let drift = warm_drift(self.prefix.mu(b), m, q1, p1, h, &mut st.full_anomaly[b])
                .map_err(|e| fail(f64::NAN, 0, format!("Kepler drift of body {b}: {e}")))?;
            st.q0[b] = drift.position();
            st.p0[b] = scale(m, drift.velocity());
        }
        Ok(())
    }
}

impl OneStepMethod for InnerKeplerGalerkin {
    fn name(&self) -> String {
        format!(
            "inner kepler-adapted galerkin (s = {}, k = {}, h = {})",
            self.s, self.kepler, self.h
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
        let (k, nb) = (self.dim, self.slots.n);
        crate::error::ensure_step_state(nb * k, q, p, q_next, p_next)?;
        // A step that starts where the last one ended continues from the slot state that step
        // computed (the rounded Cartesian state converted back every step adds a rounding
        // error per step: `KeplerAdaptedGalerkin::step`).
        let st = &self.slots;
        let continues = st.has_last && same_bits(&st.last_q, q) && same_bits(&st.last_p, p);
        if !continues {
            let st = &mut self.slots;
            load_points(k, q, p, &mut st.r, &mut st.p);
            st.has_previous = false;
            self.load_slots();
        }
        self.slots.has_last = false;
        self.advance(t)?;
        self.store_slots();
        let st = &mut self.slots;
        store_points(k, &st.r, &st.p, q_next, p_next);
        st.last_q.copy_from_slice(q_next);
        st.last_p.copy_from_slice(p_next);
        st.has_last = true;
        if q_next.iter().chain(p_next.iter()).any(|x| !x.is_finite()) {
            st.has_last = false;
            return Err(GviError::NewtonFailure {
                step: (t / self.h).round().max(0.0) as usize,
                t,
                residual: f64::NAN,
                iterations: 0,
                reason: "inner Kepler-adapted Galerkin: non-finite state".into(),
            });
        }
        Ok(())
    }
}

/// max |xᵢ| (at least the smallest positive normal).
fn norm_max(x: [f64; 3]) -> f64 {
    x.iter().fold(f64::MIN_POSITIVE, |m, v| m.max(v.abs()))
}
