//! Extending the framework: a basis (Bernstein), a quadrature (Gauss–Radau), a stage solver
//! (capped Newton) and a Lagrangian (a charged particle in a non-uniform magnetic field),
//! all written outside the crate, and what the library gives them: the step map, dense
//! output, the tangent map, refinement studies and serialisation.
//!
//! Run: `cargo run --release --example extending`. The tested version of every piece, with
//! its negative controls, is `tests/extension.rs`; the walk-through is
//! docs/guide/extending.md.

use galerkin_vi::basis::{Basis, ChebyshevLagrange};
use galerkin_vi::geometry::relative_symplecticity_defect;
use galerkin_vi::integrator::{StageEquations, StageSolve, StepFailure};
use galerkin_vi::quadrature::{Quadrature, QuadratureRule};
use galerkin_vi::refinement::{
    ErrorMeasure, Problem, RefineBy, fitted_rate, h_refinement, n_refinement,
};
use galerkin_vi::systems::{Kepler, System};
use galerkin_vi::{DualNum, GalerkinIntegrator, GviError, Lagrangian, Result, Trajectory};

/// Bernstein polynomials B_{i,n−1}: already boundary-adapted (B_0(0) = 1, B_{n−1}(1) = 1,
/// every other one zero at both ends).
#[derive(Debug, Clone)]
struct Bernstein {
    n: usize,
}

impl Bernstein {
    fn new(n: usize) -> Result<Self> {
        if n < 2 {
            return Err(GviError::InvalidBasisSize {
                n,
                basis: "bernstein".into(),
                reason: "needs the two end functions".into(),
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
    /// De Casteljau's triangle up to degree p − 1 (derivatives), then degree p (values).
    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        let (p, s) = (self.n - 1, 1.0 - tau);
        let raise = |b: &mut [f64], k: usize| {
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
        for i in 0..=p {
            let left = if i > 0 { values[i - 1] } else { 0.0 };
            let right = if i < p { values[i] } else { 0.0 };
            derivatives[i] = p as f64 * (left - right);
        }
        raise(values, p);
    }
    fn polynomial_degree(&self) -> Option<usize> {
        Some(self.n - 1)
    }
}

/// Left Gauss–Radau: m points on [0, 1] including 0, exact to degree 2m − 2.
#[derive(Debug, Clone, Copy)]
struct GaussRadau {
    m: usize,
}

fn legendre_pair(k: usize, x: f64) -> (f64, f64) {
    let (mut prev, mut cur) = (1.0, x);
    for j in 1..k {
        let next = ((2 * j + 1) as f64 * x * cur - j as f64 * prev) / (j + 1) as f64;
        (prev, cur) = (cur, next);
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
        let (m, mf) = (self.m, self.m as f64);
        if m < 2 {
            return Err(GviError::InvalidQuadrature {
                reason: "this walk-through's Radau rule needs m ≥ 2".into(),
            });
        }
        let (mut nodes, mut weights) = (vec![0.0], vec![1.0 / (mf * mf)]);
        for i in 1..m {
            let mut x = -(2.0 * std::f64::consts::PI * i as f64 / (2.0 * mf - 1.0)).cos();
            for _ in 0..100 {
                let (a, b) = legendre_pair(m, x);
                let dx = (1.0 - x) / mf * (a + b) / (a - b);
                x -= dx;
                if dx.abs() <= 1e-16 {
                    break;
                }
            }
            let a = legendre_pair(m, x).0;
            nodes.push(0.5 * (1.0 + x));
            weights.push(0.5 * (1.0 - x) / (mf * a * mf * a));
        }
        QuadratureRule::new("gauss-radau", nodes, weights, 2 * m - 2)
    }
}

/// Newton with the dense exact Jacobian, its correction capped at `cap` × the unknowns.
#[derive(Debug)]
struct CappedNewton {
    cap: f64,
}

impl StageSolve for CappedNewton {
    fn name(&self) -> &str {
        "capped-newton"
    }
    fn solve(&self, eq: &mut dyn StageEquations) -> std::result::Result<(), StepFailure> {
        let mut previous = f64::INFINITY;
        for it in 0..eq.options().max_iterations {
            let residual = eq.residual();
            if !residual.is_finite() {
                let reason = "non-finite residual".into();
                return Err(StepFailure {
                    residual,
                    iterations: it,
                    reason,
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
        let reason = "iteration limit".into();
        Err(StepFailure {
            residual: eq.residual(),
            iterations: 0,
            reason,
        })
    }
}

/// L = ½|v|² + A(q)·v − V(q), A = ½ b0 (1 + β r²)(−y, x), V = ½ r² + ¼ λ r⁴: not separable,
/// rotation-invariant.
struct Magnetic;

impl Lagrangian for Magnetic {
    fn dim(&self) -> usize {
        2
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        let r2 = q[0] * q[0] + q[1] * q[1];
        let b = (r2 * 0.3 + 1.0) * 0.75;
        (v[0] * v[0] + v[1] * v[1]) * 0.5 + b * (q[0] * v[1] - q[1] * v[0])
            - r2 * 0.5
            - r2 * r2 * 0.125
    }
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

fn main() -> Result<()> {
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    let exact = kepler
        .exact_solution(0.0, &q0, &p0)?
        .ok_or_else(|| GviError::Unsupported("exact Kepler solution".into()))?;

    // 1. The user's basis, rule and solver in the integrator; the same map as Chebyshev's.
    let radau = GaussRadau { m: 12 };
    let bern = GalerkinIntegrator::new(Bernstein::new(12)?, radau, 0.5)?
        .with_stage_solver(CappedNewton { cap: 10.0 });
    let cheb = GalerkinIntegrator::new(ChebyshevLagrange::new(12)?, radau, 0.5)?;
    let tb = bern.integrate(&kepler, 0.0, &q0, &p0, 40)?;
    let tc = cheb.integrate(&kepler, 0.0, &q0, &p0, 40)?;
    let map = (0..=40)
        .map(|k| max_diff(&tb.q[k], &tc.q[k]))
        .fold(0.0, f64::max);
    let dense = [0.25, 3.3, 10.1]
        .iter()
        .map(|&t| Ok(max_diff(&tb.velocity_at(t)?, &tc.velocity_at(t)?)))
        .collect::<Result<Vec<f64>>>()?
        .into_iter()
        .fold(0.0, f64::max);
    let error = max_diff(&tb.position_at(20.0)?, &exact.position(20.0));
    println!("Bernstein n = 12 + Gauss–Radau(12) + capped Newton, Kepler h = 0.5, T = 20:");
    println!("  step ends vs Chebyshev (same rule)   {map:.1e}");
    println!("  dense q̇(t) vs Chebyshev at 0.25, 3.3, 10.1   {dense:.1e}");
    println!("  error vs the exact orbit at T        {error:.1e}");
    let misread = tb.curve(6)?.state_at(&ChebyshevLagrange::new(12)?, 3.3)?.0;
    let wrong = max_diff(&misread, &tc.position_at(3.3)?);
    println!("  (its coefficients read as Chebyshev's: off by {wrong:.1e})");

    // 2. The user's Lagrangian: exact tangent map, symplecticity, Noether momentum.
    let (qm, pm) = ([0.8, 0.1], [0.2, 0.9]);
    let gm = GalerkinIntegrator::new(Bernstein::new(10)?, GaussRadau { m: 10 }, 0.5)?
        .with_stage_solver(CappedNewton { cap: 10.0 });
    let maps = gm.tangent_map(&Magnetic, &qm, &pm, 20)?;
    let defect = relative_symplecticity_defect(&maps[19]);
    let run = gm.integrate(&Magnetic, 0.0, &qm, &pm, 200)?;
    let ang = |k: usize| run.q[k][0] * run.p[k][1] - run.q[k][1] * run.p[k][0];
    let drift = (0..=200)
        .map(|k| (ang(k) - ang(0)).abs())
        .fold(0.0, f64::max);
    println!("Magnetic Lagrangian, Bernstein 10 + Radau(10), h = 0.5:");
    println!("  20-step tangent map, relative symplecticity defect   {defect:.1e}");
    println!("  canonical angular momentum drift over 200 steps      {drift:.1e}");

    // 3. Studies over the user's family.
    let problem = Problem::new(&kepler, 0.0, &q0, &p0, 20.0)?;
    let ns: Vec<usize> = (6..=20).step_by(2).collect();
    let points = n_refinement(
        |n| GalerkinIntegrator::new(Bernstein::new(n)?, GaussRadau { m: n + 1 }, 1.0),
        &ns,
        &problem,
        |t| exact.position(t),
        8,
    )?;
    println!("n-refinement, Bernstein(n) + Radau(n + 1), Kepler h = 1, T = 20:");
    for p in &points {
        println!(
            "  n = {:2}  map error {:.2e}  curve error {:.2e}  {:5} gradient evaluations",
            p.n, p.map_error, p.error, p.gradient_evaluations
        );
    }
    let fit = fitted_rate(&points, RefineBy::N, ErrorMeasure::Map)?;
    println!(
        "  fitted: error ≈ C·{:.3}ⁿ (ρ = {:.2})",
        fit.rate,
        fit.rho().unwrap_or(f64::NAN)
    );
    let period = std::f64::consts::TAU;
    let one_period = Problem::new(&kepler, 0.0, &q0, &p0, period)?;
    let hs: Vec<f64> = [128.0, 192.0, 256.0, 384.0, 512.0]
        .iter()
        .map(|s| period / s)
        .collect();
    for m in [3, 4] {
        let points = h_refinement(
            |h| GalerkinIntegrator::new(Bernstein::new(4)?, GaussRadau { m }, h),
            &hs,
            &one_period,
            |t| exact.position(t),
            4,
        )?;
        let fit = fitted_rate(&points, RefineBy::H, ErrorMeasure::Map)?;
        println!(
            "h-refinement, Bernstein 4 + Radau({m}): order {:.2} (expected min(2(n − 1), 2m − 1) = {})",
            fit.rate,
            6.min(2 * m - 1)
        );
    }

    // 4. Serialisation: JSON records the basis by name; the user's basis must be attached
    // again before dense output.
    let json = serde_json::to_string(&tb).map_err(|e| GviError::Unsupported(e.to_string()))?;
    let mut back: Trajectory =
        serde_json::from_str(&json).map_err(|e| GviError::Unsupported(e.to_string()))?;
    println!("Serialisation (JSON, {} bytes):", json.len());
    let describe = |r: Result<()>| match r {
        Ok(()) => "accepted (unexpected)".to_string(),
        Err(e) => e.to_string(),
    };
    println!(
        "  before attach_basis: {}",
        describe(back.position_at(3.3).map(|_| ()))
    );
    println!(
        "  attaching Chebyshev: {}",
        describe(back.attach_basis(ChebyshevLagrange::new))
    );
    back.attach_basis(Bernstein::new)?;
    let after = max_diff(&back.position_at(3.3)?, &tb.position_at(3.3)?);
    println!("  after attach_basis(Bernstein::new): q(3.3) within {after:.1e} of the original");
    Ok(())
}
