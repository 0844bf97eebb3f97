//! The method: everything that chooses how a problem is integrated, as one serialisable value,
//! and [`InitialState`], the problem's initial value.
//!
//! DifferentialEquations.jl and argmin keep the problem (here a [`Lagrangian`](crate::Lagrangian)
//! with its initial state), the method and the solution ([`Trajectory`](crate::Trajectory)) as
//! separate values; [`MethodSpec`] is the method. It names a basis, a quadrature, n, h, the
//! number of steps and the stage solver, or, with `tol`, a tolerance-driven run that chooses n
//! per step ([`crate::adaptive`]). Scene files store it as their `[method]` table, which is why
//! it derives serde; [`MethodSpec::integrator`] builds the fixed-n integrator it names.
//!
//! ```
//! use galerkin_vi::method::MethodSpec;
//! use galerkin_vi::systems::Kepler;
//!
//! let method = MethodSpec::spectral(16, 2.0, 10);
//! let gvi = method.integrator()?;
//! let kepler = Kepler::new(1.0)?;
//! let (q0, p0) = Kepler::paper_initial_state();
//! let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, method.steps)?;
//! assert_eq!(traj.q.len(), 11);
//! # Ok::<(), galerkin_vi::GviError>(())
//! ```

use crate::basis::BasisKind;
use crate::error::{GviError, Result};
use crate::quadrature::QuadratureKind;
use serde::{Deserialize, Serialize};

/// Method settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MethodSpec {
    /// Basis kind.
    #[serde(default)]
    pub basis: BasisKind,
    /// Quadrature kind.
    #[serde(default)]
    pub quadrature: QuadratureKind,
    /// Number of basis functions.
    pub n: usize,
    /// Quadrature points (default: the rule's default for n, 2n for Gauss–Legendre).
    #[serde(default)]
    pub quad_points: Option<usize>,
    /// Step size.
    pub h: f64,
    /// Number of steps.
    pub steps: usize,
    /// Tolerance on the max position error: choose n per step from `ladder` (see
    /// [`crate::adaptive`]); `n` is then ignored.
    #[serde(default)]
    pub tol: Option<f64>,
    /// The values of n a tolerance-driven run chooses from (default
    /// [`crate::adaptive::DEFAULT_LADDER`]).
    #[serde(default)]
    pub ladder: Option<Vec<usize>>,
    /// Error control of a tolerance-driven run (`embedded`, `indicator` or `calibrated`;
    /// default [`crate::adaptive::ErrorControl::Embedded`]).
    #[serde(default)]
    pub control: Option<crate::adaptive::ErrorControl>,
    /// With `tol`: choose one h for the run (spanning the same horizon h · steps) from the
    /// tolerance and the system's time scale by pilot runs ([`crate::adaptive::choose_step`]).
    #[serde(default)]
    pub auto_h: bool,
    /// How each step's stage equations are solved (`auto`, `modal`, `exact`, `kronecker`,
    /// `newton-krylov`, `fixed-point`; default `auto`). Every solver gives the same map to
    /// round-off.
    #[serde(default)]
    pub solver: crate::integrator::StageSolver,
    /// The enrichment frequencies of the `enriched` basis (required by it, refused by the
    /// others): one ω (`omega = 50.0` in a scene) or a set (`omega = [50.0, 20.0]`), n =
    /// p + 1 + 2rK functions, polynomial degree p plus sin(kω_jhτ), cos(kω_jhτ) for each of the
    /// r frequencies ([`Enriched::with_frequencies`](crate::basis::Enriched::with_frequencies)).
    /// A single frequency is written back as a number.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "frequencies::deserialize",
        serialize_with = "frequencies::serialize"
    )]
    pub omega: Option<Vec<f64>>,
    /// The number K of harmonics of the `enriched` basis (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub harmonics: Option<usize>,
    /// Rigid-body scenes: the retraction of the Lie group integrator (`exp` or `cayley`;
    /// default `exp`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retraction: Option<crate::lie::Retraction>,
    /// A Poincaré time transformation (`[method.time_transform]`): fixed fictitious steps of
    /// h with physical steps that follow the monitor ([`crate::time_transform`]). Runs with
    /// it go through [`crate::time_transform::integrate_time_transformed`]; [`crate::solve::solve`]
    /// refuses them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_transform: Option<crate::time_transform::TimeTransformSpec>,
}

impl MethodSpec {
    /// The fixed-n integrator this method names (basis, n, quadrature, points, h and solver).
    pub fn integrator(
        &self,
    ) -> Result<
        crate::integrator::GalerkinIntegrator<
            crate::basis::AnyBasis,
            crate::quadrature::QuadratureRule,
        >,
    > {
        let gvi =
            if self.basis.is_parametrised() || self.omega.is_some() || self.harmonics.is_some() {
                let basis =
                    self.basis
                        .build_with(self.n, self.h, self.omega.as_deref(), self.harmonics)?;
                // The enriched basis needs its products resolved: at least its own Gauss count
                // (unless the points are given, when a weak rule is a typed error).
                let points = match (&basis, self.quad_points) {
                    (_, Some(points)) => points,
                    (crate::basis::AnyBasis::Enriched(b), None) => {
                        self.quadrature.default_points(self.n).max(b.gauss_points())
                    }
                    (_, None) => self.quadrature.default_points(self.n),
                };
                crate::integrator::GalerkinIntegrator::new(
                    basis,
                    self.quadrature.build(points)?,
                    self.h,
                )?
            } else {
                crate::integrator::GalerkinIntegrator::from_kinds(
                    self.basis,
                    self.n,
                    self.quadrature,
                    self.quad_points,
                    self.h,
                )?
            };
        let options = crate::integrator::NewtonOptions {
            solver: self.solver,
            ..*gvi.options()
        };
        Ok(gvi.with_options(options))
    }

    /// Whether n is chosen per step from `ladder` (`tol` given): a tolerance-driven run
    /// ([`crate::adaptive`]). [`crate::solve::solve`] runs either kind; the uses that need one
    /// map for every step ([`crate::solve::solve_streaming`], [`crate::solve::solve_rigid_body`],
    /// [`MethodSpec::require_fixed_n`]) refuse it.
    pub fn chooses_n(&self) -> bool {
        self.tol.is_some()
    }

    /// The quadrature points of the fixed-n integrator this method names: `quad_points`, or
    /// the quadrature's default for n (what [`integrator`](Self::integrator) builds).
    pub fn quadrature_points(&self) -> usize {
        self.quad_points
            .unwrap_or_else(|| self.quadrature.default_points(self.n))
    }

    /// The largest n a run of this method may use: the top of the ladder (default
    /// [`crate::adaptive::DEFAULT_LADDER`]) when n is chosen per step, else `n`. For memory
    /// estimates before a run.
    pub fn largest_n(&self) -> usize {
        if !self.chooses_n() {
            return self.n;
        }
        self.ladder
            .as_ref()
            .and_then(|l| l.iter().max().copied())
            .unwrap_or_else(|| {
                crate::adaptive::DEFAULT_LADDER
                    .iter()
                    .copied()
                    .max()
                    .unwrap_or(0)
            })
    }

    /// Check the settings that need no integrator: h is finite and positive, and `auto_h`
    /// (which chooses h from the tolerance) has `tol`. The integrator checks the rest (n, the
    /// quadrature) when it is built.
    ///
    /// Errors: [`GviError::InvalidStepSize`]; [`GviError::InvalidInput`] named `auto_h`, or
    /// `tol` with the enriched basis (which needs a fixed n).
    pub fn validate(&self) -> Result<()> {
        if !(self.h.is_finite() && self.h > 0.0) {
            return Err(GviError::InvalidStepSize { h: self.h });
        }
        if self.auto_h && self.tol.is_none() {
            return Err(GviError::InvalidInput {
                name: "auto_h".into(),
                reason: "choosing h needs a tolerance (tol)".into(),
            });
        }
        // The tolerance-driven ladder and the Lie group integrator build bases from n alone.
        if self.tol.is_some() && (self.basis.is_parametrised() || self.omega.is_some()) {
            return Err(GviError::InvalidInput {
                name: "tol".into(),
                reason: "a tolerance-driven run chooses n per step from bases built from n \
                         alone; the enriched basis (omega) needs a fixed n"
                    .into(),
            });
        }
        Ok(())
    }

    /// The settings of the tolerance-driven run this method names (`None` without `tol`):
    /// its tolerance, basis, quadrature (at each rung's default points; `quad_points` is for
    /// fixed n), h, ladder and control. The stage solver is the method's unless that is `auto`,
    /// in which case it stays the controller's `exact` (its costs were tuned with it, see
    /// [`AdaptiveOptions::solver`](crate::adaptive::AdaptiveOptions::solver)).
    pub fn adaptive_options(&self) -> Option<crate::adaptive::AdaptiveOptions> {
        let tol = self.tol?;
        let mut opts =
            crate::adaptive::AdaptiveOptions::new(tol, self.basis, self.quadrature, self.h);
        if let Some(ladder) = &self.ladder {
            opts.ladder = ladder.clone();
        }
        if let Some(control) = self.control {
            opts.control = control;
        }
        if self.solver != crate::integrator::StageSolver::Auto {
            opts.solver = self.solver;
        }
        Some(opts)
    }

    /// Refuse a tolerance-driven method for a use that needs one map for every step (a
    /// tangent map, an ensemble, a streamed run, the Lie group integrator); `purpose` names
    /// that use in the error.
    ///
    /// Errors: those of [`validate`](Self::validate); [`GviError::Unsupported`] when n is
    /// chosen per step ([`chooses_n`](Self::chooses_n)).
    ///
    /// ```
    /// use galerkin_vi::method::MethodSpec;
    /// let mut method = MethodSpec::spectral(16, 1.0, 10);
    /// assert!(method.require_fixed_n("a tangent map").is_ok());
    /// method.tol = Some(1e-8);
    /// let e = method.require_fixed_n("a tangent map").unwrap_err();
    /// assert!(e.to_string().starts_with("a tangent map needs a fixed n"));
    /// ```
    pub fn require_fixed_n(&self, purpose: &str) -> Result<()> {
        self.validate()?;
        match self.tol {
            Some(tol) => Err(GviError::Unsupported(format!(
                "{purpose} needs a fixed n, but tol = {tol:e} chooses n per step; give n \
                 instead of tol"
            ))),
            None => Ok(()),
        }
    }

    /// The Lie group integrator on SO(3) this method names (basis, n, quadrature, points, h
    /// and `retraction`, default exp), for rigid bodies ([`crate::lie`]).
    pub fn lie_integrator(&self) -> Result<crate::lie::LieGalerkin> {
        if self.omega.is_some() || self.harmonics.is_some() {
            return Err(GviError::Unsupported(
                "the Lie group integrator takes no enriched basis (omega, harmonics)".into(),
            ));
        }
        Ok(crate::lie::LieGalerkin::from_kinds(
            self.basis,
            self.n,
            self.quadrature,
            self.quad_points,
            self.h,
        )?
        .with_retraction(self.retraction.unwrap_or_default()))
    }
}

impl MethodSpec {
    /// The paper's spectral method (Chebyshev–Lagrange, 2n Gauss–Legendre points, the `auto`
    /// stage solver) with n basis functions, step h and `steps` steps.
    pub fn spectral(n: usize, h: f64, steps: usize) -> Self {
        MethodSpec {
            basis: BasisKind::default(),
            quadrature: QuadratureKind::default(),
            n,
            quad_points: None,
            h,
            steps,
            tol: None,
            ladder: None,
            control: None,
            auto_h: false,
            solver: Default::default(),
            omega: None,
            harmonics: None,
            retraction: None,
            time_transform: None,
        }
    }
}

/// Serde helpers for a frequency field written as a number or a list of numbers (`omega = 50.0`
/// or `omega = [50.0, 20.0]` in a scene): read as `Option<Vec<f64>>`, a list of one written
/// back as a number so that single-frequency scenes round-trip unchanged. Used by
/// [`MethodSpec::omega`] and by the lab's `fpu` system table, with
/// `#[serde(default, deserialize_with = "…::deserialize", serialize_with = "…::serialize")]`.
pub mod frequencies {
    use serde::de::{self, SeqAccess, Visitor};
    use serde::{Deserializer, Serializer};

    /// Write `Some([ω])` as ω, `Some([ω₁, …])` as a list (skip `None` with
    /// `skip_serializing_if`).
    pub fn serialize<S: Serializer>(
        value: &Option<Vec<f64>>,
        serializer: S,
    ) -> Result<S::Ok, S::Error> {
        match value.as_deref() {
            Some([one]) => serializer.serialize_f64(*one),
            Some(many) => serializer.collect_seq(many),
            None => serializer.serialize_none(),
        }
    }

    struct OneOrMany;

    impl<'de> Visitor<'de> for OneOrMany {
        type Value = Vec<f64>;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("a frequency or a list of frequencies (omega = 50.0 or [50.0, 20.0])")
        }
        fn visit_f64<E: de::Error>(self, v: f64) -> Result<Vec<f64>, E> {
            Ok(vec![v])
        }
        fn visit_i64<E: de::Error>(self, v: i64) -> Result<Vec<f64>, E> {
            Ok(vec![v as f64])
        }
        fn visit_u64<E: de::Error>(self, v: u64) -> Result<Vec<f64>, E> {
            Ok(vec![v as f64])
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<f64>, A::Error> {
            let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(2));
            while let Some(w) = seq.next_element::<f64>()? {
                out.push(w);
            }
            Ok(out)
        }
    }

    /// Read a number or a list of numbers as `Some(list)`.
    pub fn deserialize<'de, D: Deserializer<'de>>(
        deserializer: D,
    ) -> Result<Option<Vec<f64>>, D::Error> {
        deserializer.deserialize_any(OneOrMany).map(Some)
    }
}

/// The problem's initial value: the time t₀ and the phase-space point (q₀, p₀) at which a run
/// starts. Scene files store it as their `[initial]` table, which is why it derives serde; the
/// lengths are checked against the system when a scene is built (the lab's `Scene::build`).
///
/// ```
/// use galerkin_vi::method::InitialState;
/// let init = InitialState { t0: 0.0, q: vec![1.0, 0.0], p: vec![0.0, 1.0] };
/// assert_eq!(init.q.len(), init.p.len());
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialState {
    /// Initial time.
    #[serde(default)]
    pub t0: f64,
    /// Initial position (required unless the system is an N-body system).
    #[serde(default)]
    pub q: Vec<f64>,
    /// Initial momentum (required unless the system is an N-body system).
    #[serde(default)]
    pub p: Vec<f64>,
}
