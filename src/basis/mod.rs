//! Basis functions on the reference step τ ∈ [0, 1].
//!
//! A [`Basis`] is n functions φ_0 … φ_{n−1} with the *boundary-adapted* contract of docs/DESIGN.md §2:
//! φ_0(0) = 1, φ_0(1) = 0, φ_{n−1}(0) = 0, φ_{n−1}(1) = 1, and every other φ_i vanishes at both
//! ends. A Galerkin curve on one step is q(t_k + τh) = Σ Q_i φ_i(τ), so Q_0 = q(t_k) and
//! Q_{n−1} = q(t_k + h), exactly as with the paper's Lagrange basis (its q¹ and qⁿ).
//!
//! Bases are small values; [`BasisKind`] names them for scene files and the command line and
//! builds an [`AnyBasis`], which implements [`Basis`] by dispatching to the concrete type.
//!
//! The bases: [`ChebyshevLagrange`] (nodal, the paper's spectral basis), [`Legendre`] (modal,
//! integrated Legendre polynomials), [`Hermite`] (end values and derivatives plus interior
//! values) and [`Fourier`] (chord plus sines, not polynomial). The three polynomial bases with
//! the same n span the same space, so with the same quadrature they define the same discrete
//! Lagrangian and the same discrete flow; they differ only in conditioning.
//!
//! # Conditioning at large n
//!
//! Measured on Kepler (e = 0.6, h = 2, 100 steps, Gauss–Legendre 2n; `tests/bases.rs`):
//!
//! | n | Chebyshev error / cond K | Legendre error / cond K | Hermite error / cond K |
//! |---|---|---|---|
//! | 48 | 2.3e-8 / 3.8e4 | 5.6e-10 / 2 | 9.4e-8 / 5.5e8 |
//! | 56 | 3.8e-8 / 6.0e4 | 3.3e-11 / 2 | 1.3e-7 / 1.4e9 |
//! | 64 | 9.1e-9 / 9.0e4 | 8.9e-12 / 2 | 9.3e-7 / 3.3e9 |
//!
//! (cond K: the 2-norm condition number of the stage block of the kinetic matrix,
//! `GalerkinIntegrator::kinetic_condition_number`.) Only the Legendre basis keeps converging:
//! its interior kinetic block is exactly 2·I, so the stage equations are as well conditioned
//! as they can be. The condition number of the nodal Chebyshev–Lagrange kinetic matrix grows
//! like n³ and that of the Hermite one like n⁶ (derivative degrees of freedom, and weights
//! 1/(y(1 − y)) ~ n² at the interior nodes next to the ends); round-off in the stage
//! equations, amplified by that condition number and then by the Kepler flow over 100 steps,
//! sets a floor near 1e-8 (Chebyshev) and 1e-7–1e-6 (Hermite, still rising with n).
//!
//! The collocation matrices used by [`CurveFit`] only affect the initial guesses, not the
//! converged solution. Their condition numbers at n = 8 / 16 / 32 / 64: Chebyshev 1 (nodal),
//! Legendre 12 / 37 / 110 / 310 (Chebyshev–Lobatto nodes), Hermite 120 / 1.3e3 / 1.6e4 /
//! 2.0e5, Fourier 3.7 / 5.5 / 7.9 / 11 (equispaced nodes, where the sine block is the DST-I).

mod chebyshev;
mod enriched;
mod fourier;
mod hermite;
mod legendre;

pub use chebyshev::ChebyshevLagrange;
pub use enriched::Enriched;
pub use fourier::Fourier;
pub use hermite::Hermite;
pub use legendre::Legendre;

use crate::error::{GviError, Result};
use serde::{Deserialize, Serialize};

/// A family of n functions on [0, 1] obeying the boundary-adapted contract.
///
/// A basis written outside the crate is a first-class citizen: it gets the step map, dense
/// output, the tangent map, the discrete action and every study the built-in bases get. A
/// [`Trajectory`](crate::Trajectory) keeps the basis itself (shared, hence `Send + Sync +
/// 'static`) to evaluate its curves, so nothing has to name a built-in kind. The built-in
/// kinds ([`BasisKind`]) are only names for scene files and the command line.
pub trait Basis: std::fmt::Debug + Send + Sync + 'static {
    /// Number of basis functions n.
    fn len(&self) -> usize;

    /// Always false: a valid basis has at least two functions.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Human-readable name, e.g. "chebyshev". A serialised trajectory records it, and a
    /// basis attached to a deserialised trajectory must answer the same name
    /// ([`Trajectory::attach_basis`](crate::Trajectory::attach_basis)).
    fn name(&self) -> &'static str;

    /// Evaluate φ_i(τ) into `values[i]` and dφ_i/dτ into `derivatives[i]`, for all i.
    /// Both slices have length n. τ may lie outside [0, 1] (extrapolation).
    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]);

    /// Degree of the polynomial space spanned, or `None` for a non-polynomial basis.
    fn polynomial_degree(&self) -> Option<usize>;

    /// Points at which [`fit_coefficients`](crate::basis::CurveFit) interpolates a curve to
    /// obtain coefficients (initial guesses, projections). Default: the n Chebyshev–Lobatto
    /// points of [0, 1], which include both ends so the fitted coefficients keep the contract.
    fn interpolation_nodes(&self) -> Vec<f64> {
        chebyshev_lobatto_points(self.len())
    }

    /// The step size h the basis was made for, if its functions depend on it (an
    /// [`Enriched`] basis has frequency ωh in τ), else `None` (the default). The integrator
    /// refuses another h with [`GviError::Mismatch`].
    fn step_size(&self) -> Option<f64> {
        None
    }

    /// Refuse a quadrature rule too weak for this basis, beyond the integrator's own check
    /// (exactness for φ_a'φ_b' of a polynomial basis, an invertible kinetic matrix otherwise).
    /// A non-polynomial basis whose products need a given resolution (an [`Enriched`] basis
    /// at large ωh) says so here. Default: accept.
    ///
    /// Errors: [`GviError::InvalidQuadrature`], naming what the rule lacks.
    fn check_quadrature(&self, rule: &crate::quadrature::QuadratureRule) -> Result<()> {
        let _ = rule;
        Ok(())
    }
}

/// The n Chebyshev–Lobatto points τ_i = (1 − cos(iπ/(n−1)))/2 of [0, 1], increasing.
pub fn chebyshev_lobatto_points(n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![0.5],
        _ => (0..n)
            .map(|i| {
                // sin form is symmetric and exact at the ends and the centre.
                let theta = std::f64::consts::PI * (i as f64) / ((n - 1) as f64);
                let s = (0.5 * theta).sin();
                s * s
            })
            .collect(),
    }
}

/// The bases this crate provides, selectable by value and by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum BasisKind {
    /// Lagrange polynomials at Chebyshev–Lobatto points (the paper's spectral basis).
    #[default]
    Chebyshev,
    /// Modal boundary-adapted (integrated) Legendre polynomials.
    Legendre,
    /// Hermite–Birkhoff: end values and derivatives plus interior nodal values (n ≥ 4).
    Hermite,
    /// Linear end functions plus sines sin(kπτ) (not polynomial).
    Fourier,
    /// Polynomials plus sin(kωhτ), cos(kωhτ) ([`Enriched`]): needs the frequency ω and h,
    /// so it is built by [`build_with`](BasisKind::build_with), not [`build`](BasisKind::build),
    /// and is not in [`ALL`](BasisKind::ALL).
    Enriched,
}

impl BasisKind {
    /// The kinds built from n alone (every kind but [`Enriched`](BasisKind::Enriched)), for
    /// sweeps.
    pub const ALL: [BasisKind; 4] = [
        BasisKind::Chebyshev,
        BasisKind::Legendre,
        BasisKind::Hermite,
        BasisKind::Fourier,
    ];

    /// The name used in scene files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            BasisKind::Chebyshev => "chebyshev",
            BasisKind::Legendre => "legendre",
            BasisKind::Hermite => "hermite",
            BasisKind::Fourier => "fourier",
            BasisKind::Enriched => "enriched",
        }
    }

    /// Whether the basis needs more than n to be built (the enriched basis: ω and h). A
    /// serialised trajectory cannot rebuild such a basis from its name and n, so it records
    /// it as a user's basis, to be attached again
    /// ([`Trajectory::attach_basis`](crate::Trajectory::attach_basis)).
    pub fn is_parametrised(self) -> bool {
        matches!(self, BasisKind::Enriched)
    }

    /// The built-in kind of `basis`, or `None` for a basis written outside the crate. Decided
    /// by the basis's type, not by anything it answers, so a user's basis can never be
    /// mistaken for a built-in one (a serialised trajectory of a built-in basis rebuilds it
    /// by this kind; one of a user's basis needs the basis attached again).
    pub fn of<B: Basis>(basis: &B) -> Option<BasisKind> {
        let any = basis as &dyn std::any::Any;
        if let Some(b) = any.downcast_ref::<AnyBasis>() {
            return Some(b.kind());
        }
        if any.is::<ChebyshevLagrange>() {
            Some(BasisKind::Chebyshev)
        } else if any.is::<Legendre>() {
            Some(BasisKind::Legendre)
        } else if any.is::<Hermite>() {
            Some(BasisKind::Hermite)
        } else if any.is::<Fourier>() {
            Some(BasisKind::Fourier)
        } else if any.is::<Enriched>() {
            Some(BasisKind::Enriched)
        } else {
            None
        }
    }

    /// Build the basis with n functions.
    ///
    /// Errors: the basis's own (n out of range); [`GviError::InvalidInput`] for
    /// [`Enriched`](BasisKind::Enriched), which needs ω and h ([`build_with`](Self::build_with)).
    pub fn build(self, n: usize) -> Result<AnyBasis> {
        Ok(match self {
            BasisKind::Chebyshev => AnyBasis::Chebyshev(ChebyshevLagrange::new(n)?),
            BasisKind::Legendre => AnyBasis::Legendre(Legendre::new(n)?),
            BasisKind::Hermite => AnyBasis::Hermite(Hermite::new(n)?),
            BasisKind::Fourier => AnyBasis::Fourier(Fourier::new(n)?),
            BasisKind::Enriched => {
                return Err(GviError::InvalidInput {
                    name: "basis".into(),
                    reason: "the enriched basis needs a frequency omega and the step size h \
                             (scene: [method] omega = …; command line: --omega)"
                        .into(),
                });
            }
        })
    }

    /// Build the basis with n functions for step size h, with the enrichment frequencies
    /// `omega` (one or several) and number of `harmonics` (default 1) of the enriched basis:
    /// n = p + 1 + 2rK functions for r frequencies, polynomial degree p = n − 1 − 2rK.
    ///
    /// Errors: those of [`build`](Self::build) and [`Enriched::with_frequencies`];
    /// [`GviError::InvalidInput`] named `omega` (or `harmonics`) when given to another basis,
    /// or `omega` missing for the enriched one; [`GviError::InvalidBasisSize`] when n leaves
    /// no room for polynomial degree ≥ 1.
    pub fn build_with(
        self,
        n: usize,
        h: f64,
        omega: Option<&[f64]>,
        harmonics: Option<usize>,
    ) -> Result<AnyBasis> {
        if self != BasisKind::Enriched {
            if let Some((name, _)) = [
                ("omega", omega.is_some()),
                ("harmonics", harmonics.is_some()),
            ]
            .into_iter()
            .find(|(_, given)| *given)
            {
                return Err(GviError::InvalidInput {
                    name: name.into(),
                    reason: format!("only the enriched basis takes {name} (the basis is {self})"),
                });
            }
            return self.build(n);
        }
        let Some(omega) = omega else {
            return self.build(n);
        };
        let k = harmonics.unwrap_or(1);
        // r = 0 (an empty list) is refused by the constructor, with `omega` named.
        let trig = k.saturating_mul(2).saturating_mul(omega.len().max(1));
        if n < trig.saturating_add(2) {
            return Err(GviError::InvalidBasisSize {
                n,
                basis: "enriched".into(),
                reason: format!(
                    "n = p + 1 + 2rK needs n ≥ {} for polynomial degree p ≥ 1 with K = {k} and \
                     r = {} frequencies",
                    trig.saturating_add(2),
                    omega.len()
                ),
            });
        }
        Ok(AnyBasis::Enriched(Enriched::with_frequencies(
            n - 1 - trig,
            k,
            omega,
            h,
        )?))
    }
}

impl std::fmt::Display for BasisKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for BasisKind {
    type Err = GviError;
    fn from_str(s: &str) -> Result<Self> {
        BasisKind::ALL
            .into_iter()
            .chain([BasisKind::Enriched])
            .find(|k| k.as_str().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| GviError::InvalidInput {
                name: "basis".into(),
                reason: format!(
                    "unknown basis '{s}' (expected one of: {}, enriched)",
                    BasisKind::ALL.map(|k| k.as_str()).join(", ")
                ),
            })
    }
}

/// Any of the crate's bases, chosen at run time.
#[derive(Debug, Clone)]
pub enum AnyBasis {
    /// See [`ChebyshevLagrange`].
    Chebyshev(ChebyshevLagrange),
    /// See [`Legendre`].
    Legendre(Legendre),
    /// See [`Hermite`].
    Hermite(Hermite),
    /// See [`Fourier`].
    Fourier(Fourier),
    /// See [`Enriched`].
    Enriched(Enriched),
}

impl AnyBasis {
    /// Which of the crate's bases this is.
    pub fn kind(&self) -> BasisKind {
        match self {
            AnyBasis::Chebyshev(_) => BasisKind::Chebyshev,
            AnyBasis::Legendre(_) => BasisKind::Legendre,
            AnyBasis::Hermite(_) => BasisKind::Hermite,
            AnyBasis::Fourier(_) => BasisKind::Fourier,
            AnyBasis::Enriched(_) => BasisKind::Enriched,
        }
    }
}

macro_rules! dispatch {
    ($self:ident, $b:ident => $e:expr) => {
        match $self {
            AnyBasis::Chebyshev($b) => $e,
            AnyBasis::Legendre($b) => $e,
            AnyBasis::Hermite($b) => $e,
            AnyBasis::Fourier($b) => $e,
            AnyBasis::Enriched($b) => $e,
        }
    };
}

impl Basis for AnyBasis {
    fn len(&self) -> usize {
        dispatch!(self, b => b.len())
    }
    fn name(&self) -> &'static str {
        dispatch!(self, b => b.name())
    }
    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        dispatch!(self, b => b.eval(tau, values, derivatives))
    }
    fn polynomial_degree(&self) -> Option<usize> {
        dispatch!(self, b => b.polynomial_degree())
    }
    fn interpolation_nodes(&self) -> Vec<f64> {
        dispatch!(self, b => b.interpolation_nodes())
    }
    fn step_size(&self) -> Option<f64> {
        dispatch!(self, b => b.step_size())
    }
    fn check_quadrature(&self, rule: &crate::quadrature::QuadratureRule) -> Result<()> {
        dispatch!(self, b => b.check_quadrature(rule))
    }
}

/// Check the common requirement n ≥ `min` for a basis constructor.
pub(crate) fn check_size(basis: &str, n: usize, min: usize, max: usize) -> Result<()> {
    if n < min || n > max {
        return Err(GviError::InvalidBasisSize {
            n,
            basis: basis.to_string(),
            reason: format!("need {min} ≤ n ≤ {max}"),
        });
    }
    Ok(())
}

/// Interpolation of curves by a basis: the coefficients Q_i with Σ Q_i φ_i(x_k) = f(x_k) at the
/// basis's interpolation nodes x_k. For nodal bases this is the identity on nodal values; for
/// modal bases it is a solve with the (precomputed, factorised) collocation matrix, so the
/// coefficients are a true representation of the curve rather than nodal values.
#[derive(Debug, Clone)]
pub struct CurveFit {
    nodes: Vec<f64>,
    lu: crate::linalg::Lu,
    /// The collocation matrix is exactly the identity (a Lagrange basis at its own nodes):
    /// values are coefficients, and the solves are skipped.
    identity: bool,
}

impl CurveFit {
    /// Factorise the collocation matrix A_ki = φ_i(x_k) of `basis`.
    pub fn new<B: Basis + ?Sized>(basis: &B) -> Result<Self> {
        let n = basis.len();
        let nodes = basis.interpolation_nodes();
        ensure_len_nodes(n, nodes.len())?;
        let mut a = vec![0.0; n * n];
        let mut v = vec![0.0; n];
        let mut dv = vec![0.0; n];
        for (k, &x) in nodes.iter().enumerate() {
            basis.eval(x, &mut v, &mut dv);
            a[k * n..(k + 1) * n].copy_from_slice(&v);
        }
        let identity =
            (0..n).all(|k| (0..n).all(|i| a[k * n + i] == if i == k { 1.0 } else { 0.0 }));
        let lu = crate::linalg::Lu::factor(a, n).map_err(|_| GviError::InvalidBasisSize {
            n,
            basis: basis.name().to_string(),
            reason: "collocation matrix at the interpolation nodes is singular".into(),
        })?;
        Ok(CurveFit {
            nodes,
            lu,
            identity,
        })
    }

    /// The interpolation nodes x_k.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Turn values `f` (n × D, row k = f(x_k)) into coefficients in place (row i = Q_i).
    ///
    /// When the collocation matrix is exactly the identity (the Chebyshev–Lagrange basis at
    /// its own nodes) the values are the coefficients and nothing is done: the LU solve of
    /// the identity gives the same bits for finite values (x − 0·y = x, x/1 = x).
    pub fn values_to_coefficients(&self, values: &mut [f64], dim: usize) {
        if !self.identity {
            self.lu.solve_columns_in_place(values, dim);
        }
    }

    /// As [`values_to_coefficients`](CurveFit::values_to_coefficients), with two scratch
    /// vectors of length n (no allocation).
    pub fn values_to_coefficients_with(
        &self,
        values: &mut [f64],
        dim: usize,
        col: &mut [f64],
        scratch: &mut [f64],
    ) {
        if !self.identity {
            self.lu.solve_columns_with(values, dim, col, scratch);
        }
    }
}

fn ensure_len_nodes(n: usize, got: usize) -> Result<()> {
    crate::error::ensure_len("basis interpolation nodes", n, got)
}

#[cfg(test)]
pub(crate) mod contract_tests {
    use super::*;

    /// Check the boundary contract and derivatives against finite differences; returns the
    /// largest finite-difference discrepancy relative to the derivative scale.
    pub fn check_contract<B: Basis>(b: &B) -> f64 {
        let n = b.len();
        let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
        b.eval(0.0, &mut v, &mut d);
        for (i, &x) in v.iter().enumerate() {
            let want = if i == 0 { 1.0 } else { 0.0 };
            assert!((x - want).abs() < 1e-13, "φ_{i}(0) = {x}");
        }
        b.eval(1.0, &mut v, &mut d);
        for (i, &x) in v.iter().enumerate() {
            let want = if i == n - 1 { 1.0 } else { 0.0 };
            assert!((x - want).abs() < 1e-13, "φ_{i}(1) = {x}");
        }
        let mut worst: f64 = 0.0;
        let eps = 1e-6;
        let (mut vp, mut vm, mut tmp) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for k in 0..17 {
            let tau = 0.03 + 0.94 * (k as f64) / 16.0;
            b.eval(tau, &mut v, &mut d);
            b.eval(tau + eps, &mut vp, &mut tmp);
            b.eval(tau - eps, &mut vm, &mut tmp);
            let scale = d.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            for i in 0..n {
                let fd = (vp[i] - vm[i]) / (2.0 * eps);
                worst = worst.max((fd - d[i]).abs() / scale);
            }
        }
        worst
    }
}

#[cfg(test)]
mod kind_tests {
    use super::*;

    #[test]
    fn kinds_round_trip_and_build() {
        for kind in BasisKind::ALL {
            assert_eq!(kind.as_str().parse::<BasisKind>().unwrap(), kind);
            let json = serde_json::to_string(&kind).unwrap();
            assert_eq!(json, format!("\"{}\"", kind.as_str()));
            let b = kind.build(6).unwrap();
            assert_eq!((b.kind(), b.len(), b.name()), (kind, 6, kind.as_str()));
            assert_eq!(BasisKind::of(&b), Some(kind));
            // AnyBasis dispatches eval and the contract holds through it.
            assert!(contract_tests::check_contract(&b) < 1e-6);
        }
        assert!("hermite".parse::<BasisKind>().unwrap().build(3).is_err());
    }

    #[test]
    fn collocation_matrices_are_well_conditioned() {
        // Measured at n = 64: 1, 310, 2.0e5, 11 (see the module docs); guard with ~5× margin.
        for (kind, max) in [
            (BasisKind::Chebyshev, 1.0 + 1e-9),
            (BasisKind::Legendre, 1.5e3),
            (BasisKind::Hermite, 1e6),
            (BasisKind::Fourier, 50.0),
        ] {
            let n = 64;
            let b = kind.build(n).unwrap();
            let mut a = vec![0.0; n * n];
            let (mut v, mut d) = (vec![0.0; n], vec![0.0; n]);
            for (k, &x) in b.interpolation_nodes().iter().enumerate() {
                b.eval(x, &mut v, &mut d);
                a[k * n..(k + 1) * n].copy_from_slice(&v);
            }
            let cond = 1.0 / crate::linalg::reciprocal_condition(&a, n);
            assert!(cond < max, "{kind}: collocation condition number {cond:e}");
        }
        assert!("bessel".parse::<BasisKind>().is_err());
    }
}
