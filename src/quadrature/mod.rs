//! Quadrature rules on [0, 1].
//!
//! The discrete action of one step is S(Q) = h Σ_j b_j L(q(c_j), q̇(c_j)) (paper eq. (1)) with
//! nodes c_j ∈ [0, 1] and weights b_j summing to 1. A [`Quadrature`] produces a
//! [`QuadratureRule`] (nodes, weights and the degree of polynomial exactness);
//! [`QuadratureKind`] names the rules for scene files and the command line.
//!
//! Rules: [`GaussLegendre`] (the default, 2n points for n basis functions, exact to degree
//! 4n − 1, so the kinetic term of a polynomial curve is integrated exactly), [`GaussLobatto`]
//! (includes the end points), [`ClenshawCurtis`] (Chebyshev extrema, nested) and [`Trapezoid`]
//! (spectrally accurate for periodic integrands, used by periodic Galerkin). A rule too weak
//! for the basis, one that cannot integrate the kinetic matrix exactly, is refused with
//! `GviError::QuadratureTooWeak` when the integrator is built.
//!
//! The guide's page on bases and quadratures (docs/guide/bases-and-quadratures.md) compares
//! every basis × quadrature pair on Kepler.

mod clenshaw_curtis;
mod gauss_legendre;
mod gauss_lobatto;
mod trapezoid;

pub use clenshaw_curtis::ClenshawCurtis;
pub use gauss_legendre::GaussLegendre;
pub use gauss_lobatto::GaussLobatto;
pub use trapezoid::Trapezoid;

use crate::error::{GviError, Result};
use serde::{Deserialize, Serialize};

/// A quadrature rule on [0, 1]: a recipe for nodes and weights.
pub trait Quadrature {
    /// Number of points m.
    fn points(&self) -> usize;
    /// Largest degree d such that every polynomial of degree ≤ d is integrated exactly.
    fn degree_of_exactness(&self) -> usize;
    /// Human-readable name.
    fn name(&self) -> String;
    /// Nodes and weights on [0, 1].
    fn rule(&self) -> Result<QuadratureRule>;
}

/// Check `min ≤ points ≤ max` for a rule's constructor (the common validation of every rule).
pub(crate) fn check_points(rule: &str, points: usize, min: usize, max: usize) -> Result<()> {
    if (min..=max).contains(&points) {
        Ok(())
    } else {
        Err(GviError::InvalidQuadrature {
            reason: format!("{rule} needs {min} ≤ points ≤ {max}, got {points}"),
        })
    }
}

/// Nodes c_j ∈ [0, 1] and weights b_j (Σ b_j = 1) with the rule's degree of exactness.
///
/// A rule written outside the crate is built with [`QuadratureRule::new`] and any family
/// name; nothing about it has to be a built-in [`QuadratureKind`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QuadratureRule {
    /// The family's name, e.g. `gauss-legendre` (a built-in [`QuadratureKind`]'s name) or a
    /// user's `gauss-radau`.
    #[serde(alias = "kind")]
    pub family: String,
    /// Nodes in [0, 1], increasing.
    pub nodes: Vec<f64>,
    /// Weights, summing to 1.
    pub weights: Vec<f64>,
    /// Polynomial degree of exactness.
    pub degree: usize,
}

impl QuadratureRule {
    /// A validated rule: the family's name, nodes in [0, 1], weights summing to 1 and the
    /// polynomial degree of exactness.
    ///
    /// Errors: as [`validate`](Self::validate).
    pub fn new(
        family: impl Into<String>,
        nodes: Vec<f64>,
        weights: Vec<f64>,
        degree: usize,
    ) -> Result<Self> {
        let rule = QuadratureRule {
            family: family.into(),
            nodes,
            weights,
            degree,
        };
        rule.validate()?;
        Ok(rule)
    }

    /// Validate: equal lengths, at least one node, nodes in [0, 1], finite weights summing to 1.
    pub fn validate(&self) -> Result<()> {
        let bad = |reason: String| Err(GviError::InvalidQuadrature { reason });
        if self.nodes.is_empty() {
            return bad("the rule has no points".into());
        }
        if self.nodes.len() != self.weights.len() {
            return bad(format!(
                "{} nodes but {} weights",
                self.nodes.len(),
                self.weights.len()
            ));
        }
        if let Some(c) = self
            .nodes
            .iter()
            .find(|c| !c.is_finite() || **c < -1e-14 || **c > 1.0 + 1e-14)
        {
            return bad(format!("node {c} is not in [0, 1]"));
        }
        if let Some(w) = self.weights.iter().find(|w| !w.is_finite()) {
            return bad(format!("weight {w} is not finite"));
        }
        let sum: f64 = self.weights.iter().sum();
        if (sum - 1.0).abs() > 1e-12 {
            return bad(format!("weights sum to {sum}, not 1"));
        }
        Ok(())
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True when the rule has no points (never for a validated rule).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Σ_j b_j f(c_j): the integral of f over [0, 1].
    pub fn integrate(&self, f: impl Fn(f64) -> f64) -> f64 {
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(|(&c, &b)| b * f(c))
            .sum()
    }
}

/// The quadrature families this crate provides.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum QuadratureKind {
    /// Gauss–Legendre: m points, exact to degree 2m − 1 (the paper's choice, m = 2n).
    #[default]
    GaussLegendre,
    /// Gauss–Lobatto: m points including both ends, exact to degree 2m − 3.
    GaussLobatto,
    /// Clenshaw–Curtis: m Chebyshev extrema, exact to degree m − 1 (m for odd m).
    ClenshawCurtis,
    /// Composite trapezoid: m equispaced points, degree 1 (not exact for polynomial bases;
    /// meant for the Fourier basis).
    Trapezoid,
}

impl QuadratureKind {
    /// All kinds, for sweeps.
    pub const ALL: [QuadratureKind; 4] = [
        QuadratureKind::GaussLegendre,
        QuadratureKind::GaussLobatto,
        QuadratureKind::ClenshawCurtis,
        QuadratureKind::Trapezoid,
    ];

    /// The name used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            QuadratureKind::GaussLegendre => "gauss-legendre",
            QuadratureKind::GaussLobatto => "gauss-lobatto",
            QuadratureKind::ClenshawCurtis => "clenshaw-curtis",
            QuadratureKind::Trapezoid => "trapezoid",
        }
    }

    /// The default number of points for n basis functions: the paper's 2n for Gauss–Legendre
    /// (degree 4n − 1); 2n + 1 for Gauss–Lobatto (degree 4n − 1); 4n for Clenshaw–Curtis
    /// (degree 4n − 1); 8n for the trapezoid rule, which is never exact for polynomial bases
    /// (the integrator rejects it for them) and is meant for the Fourier basis.
    pub fn default_points(self, n: usize) -> usize {
        match self {
            QuadratureKind::GaussLegendre => 2 * n,
            QuadratureKind::GaussLobatto => 2 * n + 1,
            QuadratureKind::ClenshawCurtis => 4 * n,
            QuadratureKind::Trapezoid => 8 * n,
        }
    }

    /// The cheapest number of points measured to keep the paper's accuracy: for Gauss–Legendre
    /// ⌈3n/2⌉ (25 % fewer force evaluations than 2n). Measured on Kepler e = 0.6 over T = 200
    /// (`gvi run kepler --n N --h H --quad-points M`): at h = 2 the max error with ⌈3n/2⌉ points
    /// is within 2 % of the 2n error for n = 20 and 32 (7.35e-3 vs 7.18e-3; 4.40e-6 vs 4.41e-6),
    /// while n or n − 1 points (the minimum that keeps the stage matrix invertible) lose up to
    /// 100× (4.2e-4 at n = 32); at h = 0.5 all choices from ⌈3n/2⌉ up sit at the round-off
    /// floor. Other rules: their default.
    pub fn economical_points(self, n: usize) -> usize {
        match self {
            QuadratureKind::GaussLegendre => (3 * n).div_ceil(2),
            other => other.default_points(n),
        }
    }

    /// The compact rule: n points for Gauss–Legendre (degree 2n − 1, still exact for the
    /// kinetic term of n basis functions, degree 2n − 4), one force evaluation per basis
    /// function. Its error constant is larger, by a factor that grows with h·ω, so it is a
    /// point on the work–precision chart rather than a default: on Kepler e = 0.6 over
    /// T = 200 the max error at h = 1/4, n = 10 (Hermite) is 2.0e-10 against 2.2e-10 with
    /// ⌈3n/2⌉ points, in 12 % less time, but 4.3× the 2n error at h = 1/2, n = 12 (3.5e-7)
    /// and 100× at h = 2, n = 32 (4.2e-4). Other rules: their default.
    pub fn compact_points(self, n: usize) -> usize {
        match self {
            QuadratureKind::GaussLegendre => n,
            other => other.default_points(n),
        }
    }

    /// The Gauss collocation rule: n − 1 points for Gauss–Legendre (degree 2n − 3, the least
    /// that is exact for the kinetic term of n basis functions, degree 2n − 4), with which the
    /// Galerkin step of a polynomial space is Gauss collocation with n − 1 stages (order
    /// 2n − 2, as for the n-point rule). Other rules: their default.
    pub fn collocation_points(self, n: usize) -> usize {
        match self {
            QuadratureKind::GaussLegendre => n.saturating_sub(1).max(1),
            other => other.default_points(n),
        }
    }

    /// Build the rule with m points.
    pub fn build(self, points: usize) -> Result<QuadratureRule> {
        match self {
            QuadratureKind::GaussLegendre => GaussLegendre::new(points)?.rule(),
            QuadratureKind::GaussLobatto => GaussLobatto::new(points)?.rule(),
            QuadratureKind::ClenshawCurtis => ClenshawCurtis::new(points)?.rule(),
            QuadratureKind::Trapezoid => Trapezoid::new(points)?.rule(),
        }
    }
}

impl std::fmt::Display for QuadratureKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for QuadratureKind {
    type Err = GviError;
    fn from_str(s: &str) -> Result<Self> {
        QuadratureKind::ALL
            .into_iter()
            .find(|k| k.as_str().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| GviError::InvalidInput {
                name: "quadrature".into(),
                reason: format!(
                    "unknown quadrature '{s}' (expected one of: {})",
                    QuadratureKind::ALL.map(|k| k.as_str()).join(", ")
                ),
            })
    }
}

impl Quadrature for QuadratureRule {
    fn points(&self) -> usize {
        self.nodes.len()
    }
    fn degree_of_exactness(&self) -> usize {
        self.degree
    }
    fn name(&self) -> String {
        format!("{} ({} points)", self.family, self.nodes.len())
    }
    fn rule(&self) -> Result<QuadratureRule> {
        self.validate()?;
        Ok(self.clone())
    }
}

#[cfg(test)]
pub(crate) mod exactness_tests {
    use super::*;

    /// Largest error integrating the monomials τ^k, k = 0..=max_degree.
    pub fn monomial_errors(rule: &QuadratureRule, max_degree: usize) -> Vec<f64> {
        (0..=max_degree)
            .map(|k| {
                let exact = 1.0 / (k as f64 + 1.0);
                (rule.integrate(|t| t.powi(k as i32)) - exact).abs()
            })
            .collect()
    }

    /// Legendre polynomial P_k(x) by the three-term recurrence.
    pub fn legendre(k: usize, x: f64) -> f64 {
        let (mut p0, mut p1) = (1.0, x);
        if k == 0 {
            return p0;
        }
        for j in 1..k {
            let p2 = ((2 * j + 1) as f64 * x * p1 - j as f64 * p0) / (j + 1) as f64;
            p0 = p1;
            p1 = p2;
        }
        p1
    }

    /// Assert exactness to `degree` (on the well-conditioned shifted Legendre polynomials,
    /// whose integrals over [0, 1] are δ_k0) and failure at `degree + 1` (sharpness), tested
    /// on P_a P_b with a + b = degree + 1 (a ≈ b) — for Gauss-type rules P_a² is the polynomial
    /// with the largest quadrature error among those of that degree.
    pub fn assert_sharp_degree(rule: &QuadratureRule) {
        let d = rule.degree;
        for k in 0..=d {
            let exact = if k == 0 { 1.0 } else { 0.0 };
            let got = rule.integrate(|t| legendre(k, 2.0 * t - 1.0));
            assert!(
                (got - exact).abs() < 1e-14,
                "{:?} with {} points: degree {k} error {:e}",
                rule.family,
                rule.len(),
                (got - exact).abs()
            );
        }
        let (a, b) = ((d + 1).div_ceil(2), d.div_ceil(2));
        let exact = if a == b {
            1.0 / (2 * a + 1) as f64
        } else {
            0.0
        };
        let got = rule.integrate(|t| legendre(a, 2.0 * t - 1.0) * legendre(b, 2.0 * t - 1.0));
        let monomial = monomial_errors(rule, d + 1)[d + 1];
        let err = (got - exact).abs().max(monomial);
        assert!(
            err > 1e-12,
            "{:?} with {} points integrates degree {} exactly (error {err:e}): the stated degree {d} is not sharp",
            rule.family,
            rule.len(),
            d + 1
        );
    }
}

#[cfg(test)]
mod kind_tests {
    use super::*;

    #[test]
    fn kinds_round_trip_and_build() {
        for kind in QuadratureKind::ALL {
            assert_eq!(kind.as_str().parse::<QuadratureKind>().unwrap(), kind);
            let json = serde_json::to_string(&kind).unwrap();
            assert_eq!(json, format!("\"{}\"", kind.as_str()));
            for n in [2, 5, 16] {
                let rule = kind.build(kind.default_points(n)).unwrap();
                assert_eq!(rule.family, kind.as_str());
                assert_eq!(rule.len(), kind.default_points(n));
                // Every default except the trapezoid rule is exact for φ_a'φ_b' (degree 2n − 4),
                // with room to spare (degree ≥ 4n − 1).
                if kind != QuadratureKind::Trapezoid {
                    assert!(
                        rule.degree >= 4 * n - 1,
                        "{kind} n = {n}: degree {}",
                        rule.degree
                    );
                }
            }
        }
        assert!("simpson".parse::<QuadratureKind>().is_err());
    }

    /// The compact Gauss–Legendre rule has n points and degree 2n − 1: exact for the kinetic
    /// integrand (degree 2n − 4), so the integrator accepts it for every polynomial basis,
    /// while n − 2 points (degree 2n − 5) are rejected as too weak. Other rules keep their
    /// default.
    #[test]
    fn compact_rule_is_exact_for_the_kinetic_term() {
        use crate::basis::BasisKind;
        use crate::integrator::GalerkinIntegrator;
        let gl = QuadratureKind::GaussLegendre;
        for n in [4, 12, 13, 20] {
            assert_eq!(gl.compact_points(n), n);
            assert_eq!(gl.build(n).unwrap().degree, 2 * n - 1);
            for basis in [
                BasisKind::Chebyshev,
                BasisKind::Legendre,
                BasisKind::Hermite,
            ] {
                assert!(GalerkinIntegrator::from_kinds(basis, n, gl, Some(n), 0.4).is_ok());
                let weak = GalerkinIntegrator::from_kinds(basis, n, gl, Some(n - 2), 0.4);
                assert!(
                    matches!(weak, Err(crate::GviError::QuadratureTooWeak { .. })),
                    "{basis} n = {n}"
                );
            }
        }
        for kind in [QuadratureKind::GaussLobatto, QuadratureKind::ClenshawCurtis] {
            assert_eq!(kind.compact_points(9), kind.default_points(9));
        }
    }
}
