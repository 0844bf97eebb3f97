//! Lagrangians: written once, differentiated automatically.
//!
//! [`Lagrangian`] is the general interface: the value L(q, v) generic over the scalar, with
//! first and second derivatives from forward-mode automatic differentiation unless a system
//! overrides them with hand-written ones. [`Mechanical`] is the separable special case
//! L = ½ vᵀ M v − V(q) with a constant mass matrix; every `Mechanical` is a `Lagrangian` through
//! a blanket implementation, and the integrator exploits the constant kinetic part of the
//! Jacobian (docs/DESIGN.md §2) for it.
//!
//! The integrator needs L_q and L_v at every quadrature node (the stage residual, paper eqs.
//! (3)–(4)) and, for Newton's method, the second derivatives L_qq, L_qv, L_vv. A system may
//! also supply batched kernels (forces and force Jacobians at all nodes at once, and for large
//! N-body systems pairwise Jacobian–vector products, so that no 3N×3N matrix is formed); each has
//! a default built from the per-point derivatives, so a user writes only
//! [`Lagrangian::lagrangian`] and [`Lagrangian::dim`].
//!
//! The README's quickstart writes a double-well Lagrangian in eight lines; the guide's page on
//! expression Lagrangians shows the same without Rust, from text in a scene file.

use crate::ad;
pub use crate::by_coordinate::ByCoordinate;
use nalgebra::DMatrix;
use num_dual::DualNum;

/// A Lagrangian L(q, v) on a configuration space R^D.
///
/// Only [`dim`](Lagrangian::dim) and [`lagrangian`](Lagrangian::lagrangian) are required; the
/// derivatives default to forward-mode automatic differentiation of `lagrangian`.
///
/// ```
/// use galerkin_vi::{Lagrangian, DualNum};
///
/// /// A particle in a double well: L = v²/2 − (q² − 1)²/4.
/// struct DoubleWell;
/// impl Lagrangian for DoubleWell {
///     fn dim(&self) -> usize { 1 }
///     fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
///         let w = q[0] * q[0] - 1.0;
///         v[0] * v[0] * 0.5 - w * w * 0.25
///     }
/// }
/// let (mut lq, mut lv) = ([0.0], [0.0]);
/// DoubleWell.gradient(&[2.0], &[0.5], &mut lq, &mut lv);
/// assert!((lq[0] + 6.0).abs() < 1e-14 && (lv[0] - 0.5).abs() < 1e-14);
/// ```
pub trait Lagrangian {
    /// Dimension D of the configuration space.
    fn dim(&self) -> usize;

    /// The value L(q, v), generic over the scalar so that dual numbers give derivatives.
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T;

    /// L(q, v) in `f64`.
    fn value(&self, q: &[f64], v: &[f64]) -> f64 {
        self.lagrangian(q, v)
    }

    /// The gradients L_q and L_v at (q, v).
    fn gradient(&self, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        let d = self.dim();
        ad::gradient_blocks(|y| self.lagrangian(&y[..d], &y[d..]), q, v, lq, lv);
    }

    /// The second derivatives L_qq, L_qv (entry (r, s) = ∂²L/∂q_r∂v_s) and L_vv, each a
    /// row-major D×D array. The default uses hyper-dual numbers; the scratch space for
    /// D > 16 is allocated per call, so large systems should override this.
    fn hessian(&self, q: &[f64], v: &[f64], lqq: &mut [f64], lqv: &mut [f64], lvv: &mut [f64]) {
        let d = self.dim();
        ad::hessian_blocks(|y| self.lagrangian(&y[..d], &y[d..]), (q, v), lqq, lqv, lvv);
    }

    /// The constant mass matrix M when L = ½ vᵀ M v − V(q). The integrator then precomputes
    /// the kinetic part of the stage Jacobian and calls [`force`](Lagrangian::force) and
    /// [`force_jacobian`](Lagrangian::force_jacobian) instead of the full derivatives.
    fn mass_matrix(&self) -> Option<DMatrix<f64>> {
        None
    }

    /// For separable Lagrangians: the potential V(q) (L = ½ vᵀMv − V(q)), or `None` (the
    /// default). Allocation-free where given, unlike −L(q, 0) through the generic value of a
    /// [`Mechanical`] system (which forms M); the time transformation
    /// ([`crate::time_transform`]) evaluates it at every quadrature node.
    fn potential_energy(&self, q: &[f64]) -> Option<f64> {
        let _ = q;
        None
    }

    /// For separable Lagrangians: the generalised force L_q(q) = −∇V(q).
    fn force(&self, q: &[f64], out: &mut [f64]) {
        let d = self.dim();
        let zeros = vec![0.0; d];
        let mut lv = vec![0.0; d];
        self.gradient(q, &zeros, out, &mut lv);
    }

    /// The size b of the coordinate blocks whose mutual coupling in the force Jacobian is weak
    /// relative to the mass matrix (N-body: b = the body dimension, since the M-scaled
    /// coupling of bodies i and j is √(mᵢ mⱼ)/max(mᵢ, mⱼ) times a body's own term), or
    /// `None`. The structured stage solvers then precondition with the diagonal blocks of the
    /// frozen Hessian only, at O(D b²) instead of O(D³) per step; the map is unchanged.
    fn coordinate_blocks(&self) -> Option<usize> {
        None
    }

    /// [`force`](Lagrangian::force) at many points: row j of `q` (D values) into row j of
    /// `out` — the m quadrature nodes of a step. The default calls `force` point by point;
    /// systems with expensive forces evaluate the points in parallel ([`crate::systems::NBody`]
    /// from 128 bodies).
    fn force_at_points(&self, q: &[f64], out: &mut [f64]) {
        let d = self.dim().max(1);
        for (qj, oj) in q.chunks_exact(d).zip(out.chunks_exact_mut(d)) {
            self.force(qj, oj);
        }
    }

    /// [`force_at_points`](Lagrangian::force_at_points) where only some coordinate blocks'
    /// forces are wanted: `active[i]` marks block i (coordinates i·b … i·b + b − 1, b from
    /// [`coordinate_blocks`](Lagrangian::coordinate_blocks)); rows of the other blocks may be
    /// left holding anything. The velocity form's fixed-point iteration asks for this once
    /// some blocks have converged and the others iterate on (the inner planets of a planetary
    /// system after the outer ones), so a system whose forces on a few blocks cost less than
    /// all of them (an N-body system: the pairs with an active body) overrides it. The active
    /// blocks' forces must be those of `force_at_points`, bit for bit. The default computes
    /// all of them.
    fn force_at_points_on_blocks(&self, q: &[f64], active: &[bool], out: &mut [f64]) {
        let _ = active;
        self.force_at_points(q, out);
    }

    /// [`force_at_points_on_blocks`](Lagrangian::force_at_points_on_blocks) with the points
    /// laid out by coordinate ([`ByCoordinate`]: row r of `q` holds coordinate r at every
    /// point), the forces into the active blocks' rows of `out` (the same layout; the other
    /// rows are left as they were). The velocity form's fixed-point iteration evaluates its
    /// masked residuals this way: the converged bodies' rows stay in place between
    /// iterations and only the active ones are recomputed, so a system whose kernel works on
    /// coordinates side by side (an N-body system: the nodes in vector lanes) reads and
    /// writes them without transposing. The forces must be those of `force_at_points`, bit
    /// for bit. The default transposes the points and calls `force_at_points_on_blocks`.
    fn force_at_points_by_coordinate_on_blocks(
        &self,
        q: &[f64],
        layout: ByCoordinate,
        active: &[bool],
        out: &mut [f64],
    ) {
        let blocks = self.coordinate_blocks().unwrap_or(self.dim().max(1));
        layout.through_points(self.dim(), blocks, q, active, out, |qp, op| {
            self.force_at_points_on_blocks(qp, active, op)
        });
    }

    /// [`force_jacobian`](Lagrangian::force_jacobian) at many points: row j of `q` (D values)
    /// into block j of `out` (D×D values), as [`force_at_points`](Lagrangian::force_at_points).
    fn force_jacobian_at_points(&self, q: &[f64], out: &mut [f64]) {
        let d = self.dim().max(1);
        for (qj, oj) in q.chunks_exact(d).zip(out.chunks_exact_mut(d * d)) {
            self.force_jacobian(qj, oj);
        }
    }

    /// Products of the force Jacobians with vectors at many points, without forming them:
    /// row j of `out` = L_qq(q_j) x_j (rows of `q`, `x` and `out`: D values each). Returns
    /// `false`, touching nothing, when the system does not provide them (the default); the
    /// Newton–Krylov solver then forms the D×D Jacobians at the nodes. [`crate::systems::NBody`]
    /// provides them pairwise, O(N²) per point with no 3N×3N matrix.
    fn force_jacobian_products_at_points(&self, q: &[f64], x: &[f64], out: &mut [f64]) -> bool {
        let _ = (q, x, out);
        false
    }

    /// The diagonal b×b blocks of the force Jacobians at many points, b from
    /// [`coordinate_blocks`](Lagrangian::coordinate_blocks): block c of point j at
    /// `out[(j·D/b + c)·b² ..]`, row-major — all the frozen-Hessian preconditioner uses of
    /// them. Returns `false`, touching nothing, when the system does not provide them (the
    /// default; the full Jacobians are formed instead).
    fn force_jacobian_diagonal_blocks_at_points(&self, q: &[f64], out: &mut [f64]) -> bool {
        let _ = (q, out);
        false
    }

    /// For separable Lagrangians: L_qq(q) = −∇²V(q), row-major D×D.
    fn force_jacobian(&self, q: &[f64], out: &mut [f64]) {
        let d = self.dim();
        let zeros = vec![0.0; d];
        let mut a = vec![0.0; d * d];
        let mut b = vec![0.0; d * d];
        self.hessian(q, &zeros, out, &mut a, &mut b);
    }

    /// The (continuous) Legendre transform p = ∂L/∂v(q, v).
    fn legendre_transform(&self, q: &[f64], v: &[f64], p: &mut [f64]) {
        let mut lq = vec![0.0; self.dim()];
        self.gradient(q, v, &mut lq, p);
    }

    /// The energy E = L_v·v − L of an autonomous Lagrangian.
    fn energy(&self, q: &[f64], v: &[f64]) -> f64 {
        let d = self.dim();
        let mut lq = vec![0.0; d];
        let mut lv = vec![0.0; d];
        self.gradient(q, v, &mut lq, &mut lv);
        lv.iter().zip(v).map(|(a, b)| a * b).sum::<f64>() - self.value(q, v)
    }

    // --- Time dependence and forcing (docs/guide/forcing.md). Every method has a default
    // that describes an autonomous, conservative system at no cost; the integrator asks
    // `is_autonomous` and `is_forced` once per workspace and only then evaluates the `_at`
    // forms at the node times t_k + c_j h. ---

    /// Whether L has no explicit time dependence (the default). A non-autonomous Lagrangian
    /// ([`crate::NonAutonomous`]) answers `false` and overrides the `_at` methods; its
    /// time-free methods then see L at t = 0, and tools that assume autonomy (periodic orbits,
    /// the geometric check's energy invariant) refuse it with a typed error.
    fn is_autonomous(&self) -> bool {
        true
    }

    /// L(t, q, v). Default: [`value`](Lagrangian::value), ignoring t.
    fn value_at(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        let _ = t;
        self.value(q, v)
    }

    /// L_q and L_v at (t, q, v). Default: [`gradient`](Lagrangian::gradient), ignoring t.
    fn gradient_at(&self, t: f64, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        let _ = t;
        self.gradient(q, v, lq, lv)
    }

    /// L_qq, L_qv, L_vv at (t, q, v), as [`hessian`](Lagrangian::hessian). Default: ignoring t.
    fn hessian_at(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        lqq: &mut [f64],
        lqv: &mut [f64],
        lvv: &mut [f64],
    ) {
        let _ = t;
        self.hessian(q, v, lqq, lqv, lvv)
    }

    /// ∂L/∂t at (t, q, v): the rate at which the energy changes along a motion of an
    /// unforced system, dE/dt = −∂L/∂t. Default 0.
    fn time_derivative(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        let _ = (t, q, v);
        0.0
    }

    /// p = ∂L/∂v(t, q, v). Default: [`legendre_transform`](Lagrangian::legendre_transform).
    fn legendre_transform_at(&self, t: f64, q: &[f64], v: &[f64], p: &mut [f64]) {
        let _ = t;
        self.legendre_transform(q, v, p)
    }

    /// E = L_v·v − L at (t, q, v). Default: [`energy`](Lagrangian::energy).
    fn energy_at(&self, t: f64, q: &[f64], v: &[f64]) -> f64 {
        let _ = t;
        self.energy(q, v)
    }

    /// Whether a non-conservative force f(t, q, v) acts ([`crate::Forced`]); default `false`.
    /// The integrator then solves the forced stage equations of the discrete
    /// Lagrange–d'Alembert principle (docs/DESIGN.md §2): f enters wherever L_q does,
    /// weighted by the quadrature, so p_{k+1} = D₂L_d + F_d⁺ and p_k = −D₁L_d − F_d⁻.
    fn is_forced(&self) -> bool {
        false
    }

    /// The force f(t, q, v) into `f` (a covector, D values). Default: zero.
    fn external_force(&self, t: f64, q: &[f64], v: &[f64], f: &mut [f64]) {
        let _ = (t, q, v);
        f.iter_mut().for_each(|x| *x = 0.0);
    }

    /// ∂f/∂q and ∂f/∂v at (t, q, v), row-major D×D (entry (r, s) = ∂f_r/∂q_s, ∂f_r/∂v_s).
    /// Default: zero.
    fn external_force_jacobian(
        &self,
        t: f64,
        q: &[f64],
        v: &[f64],
        fq: &mut [f64],
        fv: &mut [f64],
    ) {
        let _ = (t, q, v);
        fq.iter_mut().for_each(|x| *x = 0.0);
        fv.iter_mut().for_each(|x| *x = 0.0);
    }
}

/// A separable mechanical Lagrangian L = ½ vᵀ M v − V(q) with a constant symmetric
/// positive-definite mass matrix M.
///
/// Implement the potential once, generic over the scalar; its gradient and Hessian come from
/// automatic differentiation unless overridden with hand-written (faster) ones.
///
/// ```
/// use galerkin_vi::{Mechanical, Lagrangian, DualNum};
/// use nalgebra::DMatrix;
///
/// /// Anharmonic oscillator V = q²/2 + q⁴/4.
/// struct Quartic;
/// impl Mechanical for Quartic {
///     fn degrees_of_freedom(&self) -> usize { 1 }
///     fn mass(&self) -> DMatrix<f64> { DMatrix::identity(1, 1) }
///     fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
///         q[0] * q[0] * 0.5 + q[0].powi(4) * 0.25
///     }
/// }
/// let mut f = [0.0];
/// Quartic.force(&[1.0], &mut f);
/// assert!((f[0] + 2.0).abs() < 1e-14);
/// ```
pub trait Mechanical {
    /// Dimension D of the configuration space.
    fn degrees_of_freedom(&self) -> usize;
    /// The constant mass matrix M (D×D, symmetric positive definite).
    fn mass(&self) -> DMatrix<f64>;
    /// The potential V(q), generic over the scalar.
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T;
    /// ∇V(q). Default: automatic differentiation.
    fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
        ad::gradient(|y| self.potential(y), q, out);
    }
    /// See [`Lagrangian::coordinate_blocks`]. Default `None`.
    fn coordinate_blocks(&self) -> Option<usize> {
        None
    }
    /// ∇V at many points (row j of `q` into row j of `out`), for
    /// [`Lagrangian::force_at_points`]. Default: point by point.
    fn potential_gradient_at_points(&self, q: &[f64], out: &mut [f64]) {
        let d = self.degrees_of_freedom().max(1);
        for (qj, oj) in q.chunks_exact(d).zip(out.chunks_exact_mut(d)) {
            self.potential_gradient(qj, oj);
        }
    }
    /// ∇V at many points for the coordinate blocks marked in `active` only, for
    /// [`Lagrangian::force_at_points_on_blocks`] (the same contract: the active blocks' rows
    /// bit for bit those of `potential_gradient_at_points`, the others unspecified). Default:
    /// all of them.
    fn potential_gradient_at_points_on_blocks(&self, q: &[f64], active: &[bool], out: &mut [f64]) {
        let _ = active;
        self.potential_gradient_at_points(q, out);
    }
    /// ∇V at many points laid out by coordinate for the active blocks' rows only, for
    /// [`Lagrangian::force_at_points_by_coordinate_on_blocks`] (the same contract). Default:
    /// the points transposed, through `potential_gradient_at_points_on_blocks`.
    fn potential_gradient_at_points_by_coordinate_on_blocks(
        &self,
        q: &[f64],
        layout: ByCoordinate,
        active: &[bool],
        out: &mut [f64],
    ) {
        let d = self.degrees_of_freedom();
        let blocks = Mechanical::coordinate_blocks(self).unwrap_or(d.max(1));
        layout.through_points(d, blocks, q, active, out, |qp, op| {
            self.potential_gradient_at_points_on_blocks(qp, active, op)
        });
    }
    /// ∇²V at many points (row j of `q` into block j of `out`, D×D each), for
    /// [`Lagrangian::force_jacobian_at_points`]. Default: point by point.
    fn potential_hessian_at_points(&self, q: &[f64], out: &mut [f64]) {
        let d = self.degrees_of_freedom().max(1);
        for (qj, oj) in q.chunks_exact(d).zip(out.chunks_exact_mut(d * d)) {
            self.potential_hessian(qj, oj);
        }
    }
    /// ∇²V(q_j)·x_j at many points without forming the Hessians, for
    /// [`Lagrangian::force_jacobian_products_at_points`]; `false` (the default) when not
    /// provided.
    fn potential_hessian_products_at_points(&self, q: &[f64], x: &[f64], out: &mut [f64]) -> bool {
        let _ = (q, x, out);
        false
    }
    /// The diagonal b×b blocks of ∇²V at many points, for
    /// [`Lagrangian::force_jacobian_diagonal_blocks_at_points`]; `false` (the default) when
    /// not provided.
    fn potential_hessian_diagonal_blocks_at_points(&self, q: &[f64], out: &mut [f64]) -> bool {
        let _ = (q, out);
        false
    }
    /// ∇²V(q), row-major D×D. Default: automatic differentiation.
    fn potential_hessian(&self, q: &[f64], out: &mut [f64]) {
        let d = self.degrees_of_freedom();
        let mut g = [0.0; 64];
        if d <= g.len() {
            ad::hessian(|y| self.potential(y), q, &mut g[..d], out);
        } else {
            let mut g = vec![0.0; d];
            ad::hessian(|y| self.potential(y), q, &mut g, out);
        }
    }
}

impl<S: Mechanical> Lagrangian for S {
    fn dim(&self) -> usize {
        self.degrees_of_freedom()
    }

    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        let m = self.mass();
        let d = self.degrees_of_freedom();
        let mut kinetic = T::from(0.0);
        for r in 0..d {
            for s in 0..d {
                kinetic += v[r] * v[s] * m[(r, s)];
            }
        }
        kinetic * 0.5 - self.potential(q)
    }

    fn gradient(&self, q: &[f64], v: &[f64], lq: &mut [f64], lv: &mut [f64]) {
        self.potential_gradient(q, lq);
        lq.iter_mut().for_each(|x| *x = -*x);
        let m = self.mass();
        for (r, out) in lv.iter_mut().enumerate() {
            *out = (0..v.len()).map(|s| m[(r, s)] * v[s]).sum();
        }
    }

    fn hessian(&self, q: &[f64], _v: &[f64], lqq: &mut [f64], lqv: &mut [f64], lvv: &mut [f64]) {
        let d = self.degrees_of_freedom();
        self.potential_hessian(q, lqq);
        lqq.iter_mut().for_each(|x| *x = -*x);
        lqv.iter_mut().for_each(|x| *x = 0.0);
        let m = self.mass();
        for r in 0..d {
            for s in 0..d {
                lvv[r * d + s] = m[(r, s)];
            }
        }
    }

    fn mass_matrix(&self) -> Option<DMatrix<f64>> {
        Some(self.mass())
    }

    fn potential_energy(&self, q: &[f64]) -> Option<f64> {
        Some(self.potential(q))
    }

    fn force(&self, q: &[f64], out: &mut [f64]) {
        self.potential_gradient(q, out);
        out.iter_mut().for_each(|x| *x = -*x);
    }

    fn force_jacobian(&self, q: &[f64], out: &mut [f64]) {
        self.potential_hessian(q, out);
        out.iter_mut().for_each(|x| *x = -*x);
    }

    fn coordinate_blocks(&self) -> Option<usize> {
        Mechanical::coordinate_blocks(self)
    }

    fn force_at_points(&self, q: &[f64], out: &mut [f64]) {
        self.potential_gradient_at_points(q, out);
        out.iter_mut().for_each(|x| *x = -*x);
    }

    fn force_at_points_on_blocks(&self, q: &[f64], active: &[bool], out: &mut [f64]) {
        self.potential_gradient_at_points_on_blocks(q, active, out);
        out.iter_mut().for_each(|x| *x = -*x);
    }

    fn force_at_points_by_coordinate_on_blocks(
        &self,
        q: &[f64],
        layout: ByCoordinate,
        active: &[bool],
        out: &mut [f64],
    ) {
        self.potential_gradient_at_points_by_coordinate_on_blocks(q, layout, active, out);
        let blocks = Mechanical::coordinate_blocks(self).unwrap_or(self.degrees_of_freedom());
        layout.for_active_rows(self.degrees_of_freedom(), blocks, active, out, |row| {
            row.iter_mut().for_each(|x| *x = -*x)
        });
    }

    fn force_jacobian_at_points(&self, q: &[f64], out: &mut [f64]) {
        self.potential_hessian_at_points(q, out);
        out.iter_mut().for_each(|x| *x = -*x);
    }

    fn force_jacobian_products_at_points(&self, q: &[f64], x: &[f64], out: &mut [f64]) -> bool {
        if !self.potential_hessian_products_at_points(q, x, out) {
            return false;
        }
        out.iter_mut().for_each(|x| *x = -*x);
        true
    }

    fn force_jacobian_diagonal_blocks_at_points(&self, q: &[f64], out: &mut [f64]) -> bool {
        if !self.potential_hessian_diagonal_blocks_at_points(q, out) {
            return false;
        }
        out.iter_mut().for_each(|x| *x = -*x);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-separable Lagrangian: charged particle in a magnetic field plus a potential.
    struct Magnetic;
    impl Lagrangian for Magnetic {
        fn dim(&self) -> usize {
            2
        }
        fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
            (v[0] * v[0] + v[1] * v[1]) * 0.5 + (q[0] * v[1] - q[1] * v[0]) * 0.5
                - (q[0] * q[0] + q[1] * q[1] * 2.0) * 0.5
        }
    }

    #[test]
    fn ad_derivatives_of_a_non_separable_lagrangian() {
        let (q, v) = ([0.3, -0.2], [1.5, 0.7]);
        let (mut lq, mut lv) = ([0.0; 2], [0.0; 2]);
        Magnetic.gradient(&q, &v, &mut lq, &mut lv);
        // L_q = (v1/2 − q0, −v0/2 − 2 q1), L_v = (v0 − q1/2, v1 + q0/2)
        assert!((lq[0] - (0.35 - 0.3)).abs() < 1e-15);
        assert!((lq[1] - (-0.75 + 0.4)).abs() < 1e-15);
        assert!((lv[0] - (1.5 + 0.1)).abs() < 1e-15);
        assert!((lv[1] - (0.7 + 0.15)).abs() < 1e-15);
        let (mut a, mut b, mut c) = ([0.0; 4], [0.0; 4], [0.0; 4]);
        Magnetic.hessian(&q, &v, &mut a, &mut b, &mut c);
        assert_eq!(a, [-1.0, 0.0, 0.0, -2.0]);
        assert_eq!(b, [0.0, 0.5, -0.5, 0.0]);
        assert_eq!(c, [1.0, 0.0, 0.0, 1.0]);
        assert!(Magnetic.mass_matrix().is_none());
        let e = Magnetic.energy(&q, &v);
        let exact = 0.5 * (1.5f64.powi(2) + 0.7f64.powi(2)) + 0.5 * (0.09 + 2.0 * 0.04);
        assert!((e - exact).abs() < 1e-14);
    }
}
