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
use crate::error::Result;
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
    /// Rigid-body scenes: the retraction of the Lie group integrator (`exp` or `cayley`;
    /// default `exp`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retraction: Option<crate::lie::Retraction>,
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
        let gvi = crate::integrator::GalerkinIntegrator::from_kinds(
            self.basis,
            self.n,
            self.quadrature,
            self.quad_points,
            self.h,
        )?;
        let options = crate::integrator::NewtonOptions {
            solver: self.solver,
            ..*gvi.options()
        };
        Ok(gvi.with_options(options))
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
            retraction: None,
        }
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
