//! The four extensions written outside the crate, with its public API only: a basis
//! (Bernstein), a quadrature (left Gauss–Radau), a stage solver (Newton with a capped step)
//! and a non-separable Lagrangian (a charged particle in a non-uniform magnetic field).
//! `examples/extending/main.rs` walks through them; `tests/extension.rs` includes this same
//! file and tests every facility of the library with them.

use galerkin_vi::basis::Basis;
use galerkin_vi::integrator::{StageEquations, StageSolve, StepFailure};
use galerkin_vi::quadrature::{Quadrature, QuadratureRule};
use galerkin_vi::{DualNum, GviError, Lagrangian, Result};

// ---------------------------------------------------------------------------------------
// A basis: Bernstein polynomials.
// ---------------------------------------------------------------------------------------

/// The Bernstein polynomials B_{i,p}(τ) = C(p, i) τⁱ (1 − τ)^{p−i}, i = 0 … p, p = n − 1.
/// They already obey the boundary-adapted contract: B_{0,p}(0) = 1, B_{p,p}(1) = 1, and every
/// other one vanishes at both ends. Their coefficients are the control points of the curve
/// (not its values anywhere but at the ends).
#[derive(Debug, Clone)]
pub struct Bernstein {
    n: usize,
}

impl Bernstein {
    /// n Bernstein polynomials of degree n − 1 (n ≥ 2).
    pub fn new(n: usize) -> Result<Self> {
        if n < 2 {
            return Err(GviError::InvalidBasisSize {
                n,
                basis: "bernstein".into(),
                reason: "a Galerkin curve needs at least the two end functions".into(),
            });
        }
        Ok(Bernstein { n })
    }
}

impl Basis for Bernstein {
    fn len(&self) -> usize {
        self.n
    }
    fn name(&self) -> &'static str {
        "bernstein"
    }
    /// De Casteljau's triangle: raise the degree one at a time,
    /// B_{i,k} = (1 − τ) B_{i,k−1} + τ B_{i−1,k−1} (convex combinations on [0, 1], so
    /// stable), stopping at degree p − 1 for the derivatives
    /// B'_{i,p} = p (B_{i−1,p−1} − B_{i,p−1}), then one more step for the values.
    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        let p = self.n - 1;
        let s = 1.0 - tau;
        let raise = |b: &mut [f64], k: usize| {
            // b[0..k] holds degree k − 1; afterwards b[0..=k] holds degree k.
            b[k] = tau * b[k - 1];
            for i in (1..k).rev() {
                b[i] = s * b[i] + tau * b[i - 1];
            }
            b[0] *= s;
        };
        values[0] = 1.0;
        for k in 1..p {
            raise(values, k);
        }
        let pf = p as f64;
        for i in 0..=p {
            let left = if i > 0 { values[i - 1] } else { 0.0 };
            let right = if i < p { values[i] } else { 0.0 };
            derivatives[i] = pf * (left - right);
        }
        raise(values, p);
    }
    fn polynomial_degree(&self) -> Option<usize> {
        Some(self.n - 1)
    }
    // interpolation_nodes: the default Chebyshev–Lobatto points.
}

// ---------------------------------------------------------------------------------------
// A quadrature: left Gauss–Radau.
// ---------------------------------------------------------------------------------------

/// Left Gauss–Radau on [0, 1]: m points including τ = 0, exact to degree 2m − 2. On [−1, 1]
/// the nodes are −1 and the m − 1 roots of (P_{m−1}(x) + P_m(x))/(1 + x); the weights are
/// 2/m² at −1 and (1 − x)/(m P_{m−1}(x))² elsewhere.
#[derive(Debug, Clone, Copy)]
pub struct GaussRadau {
    /// Number of points.
    pub m: usize,
}

impl GaussRadau {
    /// The m-point rule (1 ≤ m ≤ 500).
    pub fn new(m: usize) -> Result<Self> {
        if !(1..=500).contains(&m) {
            return Err(GviError::InvalidQuadrature {
                reason: format!("gauss-radau needs 1 ≤ points ≤ 500, got {m}"),
            });
        }
        Ok(GaussRadau { m })
    }
}

/// (P_{k−1}(x), P_k(x)) by the three-term recurrence.
pub fn legendre_pair(k: usize, x: f64) -> (f64, f64) {
    let (mut prev, mut cur) = (1.0, x);
    if k == 0 {
        return (0.0, 1.0);
    }
    for j in 1..k {
        let next = ((2 * j + 1) as f64 * x * cur - j as f64 * prev) / (j + 1) as f64;
        prev = cur;
        cur = next;
    }
    (prev, cur)
}

impl Quadrature for GaussRadau {
    fn points(&self) -> usize {
        self.m
    }
    fn degree_of_exactness(&self) -> usize {
        2 * self.m - 2
    }
    fn name(&self) -> String {
        format!("gauss-radau({})", self.m)
    }
    fn rule(&self) -> Result<QuadratureRule> {
        let m = self.m;
        let mf = m as f64;
        let mut x = vec![-1.0; m];
        let mut w = vec![2.0 / (mf * mf); m];
        for i in 1..m {
            // Start at the Chebyshev–Gauss–Radau point, then the Newton-type update of von
            // Winckel's `lgrnodes` for the roots of f = P_{m−1} + P_m other than −1:
            // x ← x − ((1 − x)/m) f / (P_{m−1} − P_m). Exactness is checked in the tests.
            let mut xi = -(2.0 * std::f64::consts::PI * i as f64 / (2.0 * mf - 1.0)).cos();
            for _ in 0..100 {
                let (pm1, pm) = legendre_pair(m, xi);
                let dx = (1.0 - xi) / mf * (pm1 + pm) / (pm1 - pm);
                xi -= dx;
                if dx.abs() <= 1e-16 {
                    break;
                }
            }
            let (pm1, _) = legendre_pair(m, xi);
            x[i] = xi;
            w[i] = (1.0 - xi) / (mf * pm1 * mf * pm1);
        }
        let mut nodes: Vec<(f64, f64)> = x
            .iter()
            .zip(&w)
            .map(|(&x, &w)| (0.5 * (1.0 + x), 0.5 * w))
            .collect();
        nodes.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Σ w = 2 holds to a few ulps; the rule's validation allows 1e-12.
        QuadratureRule::new(
            "gauss-radau",
            nodes.iter().map(|p| p.0).collect(),
            nodes.iter().map(|p| p.1).collect(),
            2 * m - 2,
        )
    }
}

// ---------------------------------------------------------------------------------------
// A stage solver: Newton with a capped step.
// ---------------------------------------------------------------------------------------

/// Newton's method on the stage equations with the dense exact Jacobian, its correction
/// capped at `cap` times the size of the unknowns (a crude trust region that only acts far
/// from the solution), stopping when the correction is below ε of the unknowns or stops
/// shrinking at the round-off floor.
#[derive(Debug)]
pub struct CappedNewton {
    /// The largest correction, relative to the unknowns.
    pub cap: f64,
}

impl StageSolve for CappedNewton {
    fn name(&self) -> &str {
        "capped-newton"
    }
    fn solve(&self, eq: &mut dyn StageEquations) -> std::result::Result<(), StepFailure> {
        let max_iterations = eq.options().max_iterations;
        let mut previous = f64::INFINITY;
        for it in 0..max_iterations {
            let residual = eq.residual();
            if !residual.is_finite() {
                return Err(StepFailure {
                    residual,
                    iterations: it,
                    reason: "non-finite residual".into(),
                });
            }
            eq.solve_exact()?;
            let scale = eq.iterate().iter().fold(1.0f64, |m, x| m.max(x.abs()));
            let size = eq.correction().iter().fold(0.0f64, |m, x| m.max(x.abs()));
            if size > self.cap * scale {
                let shrink = self.cap * scale / size;
                eq.correction().iter_mut().for_each(|x| *x *= shrink);
            }
            let step = eq.apply_correction();
            if step.size <= 1e-15 * step.scale
                || (step.size <= 1e-12 * step.scale && step.size >= previous)
            {
                return Ok(());
            }
            previous = step.size;
        }
        Err(StepFailure {
            residual: eq.residual(),
            iterations: max_iterations,
            reason: "iteration limit".into(),
        })
    }
}

// ---------------------------------------------------------------------------------------
// A Lagrangian: a charged particle in a non-uniform magnetic field.
// ---------------------------------------------------------------------------------------

/// L = ½|v|² + A(q)·v − V(q) in the plane with A = ½ b(r) (−y, x), b(r) = b0 (1 + β r²)
/// (a field growing away from the centre) and V = ½ r² + ¼ λ r⁴. Not separable (L_qv ≠ 0);
/// invariant under rotations, so the canonical angular momentum x p_y − y p_x is a Noether
/// quantity; the energy ½|v|² + V is conserved by the flow (the field does no work).
#[derive(Debug, Clone, Copy)]
pub struct Magnetic {
    /// Field strength at the centre.
    pub b0: f64,
    /// Its growth with r².
    pub beta: f64,
    /// The quartic part of the potential.
    pub lambda: f64,
}

/// The field of the example and the tests.
pub const MAGNETIC: Magnetic = Magnetic {
    b0: 1.5,
    beta: 0.3,
    lambda: 0.5,
};

impl Magnetic {
    /// A(q).
    pub fn vector_potential(&self, q: &[f64]) -> [f64; 2] {
        let b = 0.5 * self.b0 * (1.0 + self.beta * (q[0] * q[0] + q[1] * q[1]));
        [-b * q[1], b * q[0]]
    }
    /// The energy ½|p − A(q)|² + V(q).
    pub fn energy(&self, q: &[f64], p: &[f64]) -> f64 {
        let a = self.vector_potential(q);
        let (vx, vy) = (p[0] - a[0], p[1] - a[1]);
        let r2 = q[0] * q[0] + q[1] * q[1];
        0.5 * (vx * vx + vy * vy) + 0.5 * r2 + 0.25 * self.lambda * r2 * r2
    }
}

impl Lagrangian for Magnetic {
    fn dim(&self) -> usize {
        2
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        let r2 = q[0] * q[0] + q[1] * q[1];
        let b = (r2 * self.beta + 1.0) * (0.5 * self.b0);
        let kinetic = (v[0] * v[0] + v[1] * v[1]) * 0.5;
        let coupling = b * (q[0] * v[1] - q[1] * v[0]);
        let potential = r2 * 0.5 + r2 * r2 * (0.25 * self.lambda);
        kinetic + coupling - potential
    }
}
