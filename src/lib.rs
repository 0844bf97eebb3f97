//! # galerkin-vi
//!
//! Galerkin variational integrators with pluggable bases and quadratures, and the *spectral
//! variational integrators* of Hall & Leok as the default pairing (Chebyshev–Lagrange basis,
//! 2n-point Gauss–Legendre quadrature, convergence by raising n at a fixed large step h).
//!
//! A Lagrangian is written once, generic over the scalar; derivatives come from forward-mode
//! automatic differentiation unless a system supplies hand-written ones.
//!
//! ```
//! use galerkin_vi::prelude::*;
//!
//! let kepler = Kepler::new(1.0)?;
//! let (q0, p0) = Kepler::paper_initial_state();
//! let gvi = GalerkinIntegrator::spectral(32, 2.0)?;     // n = 32, h = 2
//! let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, 100)?;
//! let exact = kepler.exact_solution(0.0, &q0, &p0)?.expect("bound orbit");
//! let err = (0..=100)
//!     .map(|k| {
//!         let (q, qe) = (&traj.q[k], exact.position(traj.time(k)));
//!         (q[0] - qe[0]).abs().max((q[1] - qe[1]).abs())
//!     })
//!     .fold(0.0, galerkin_vi::reduce::nan_max); // a NaN stays visible (f64::max drops it)
//! assert!(err < 1e-5); // measured 4.4e-6 (README)
//! # Ok::<(), galerkin_vi::GviError>(())
//! ```

#![warn(missing_docs)]
// Numerical kernels index several arrays with the same loop variable, as the formulas do.
#![allow(clippy::needless_range_loop)]

pub mod ad;
pub mod adaptive;
pub mod baselines;
pub mod basis;
mod by_coordinate;
pub mod curve;
pub mod error;
pub mod events;
pub mod forcing;
pub mod geometry;
pub mod integrator;
pub mod kepler_adapted;
pub mod lagrangian;
pub mod lie;
pub mod linalg;
pub mod method;
pub mod multirate;
pub mod newton;
pub mod periodic;
pub mod quadrature;
pub mod reduce;
pub mod refinement;
mod scratch;
pub mod solve;
pub mod stats;
pub mod symmetries;
pub mod systems;
pub mod time_transform;
pub mod trajectory;

pub use error::{GviError, Result};
pub use forcing::{
    ExternalForce, Forced, LinearDamping, NonAutonomous, NonAutonomousLagrangian, StokesDrag,
};
pub use integrator::{GalerkinIntegrator, IntegrationFailure, NewtonOptions, StepJacobian};
pub use lagrangian::{Lagrangian, Mechanical};
pub use num_dual::DualNum;
pub use solve::{Solution, SolveFailure, solve, solve_until};
pub use trajectory::Trajectory;

/// The names most programs need.
pub mod prelude {
    pub use crate::baselines::{OneStepMethod, Rk4, StormerVerlet};
    pub use crate::basis::{AnyBasis, Basis, BasisKind, ChebyshevLagrange};
    pub use crate::geometry::{MomentumMap, Rotation, Translation, symplecticity_defect};
    pub use crate::integrator::{GalerkinIntegrator, InitialGuess, NewtonOptions, StageSolver};
    pub use crate::lagrangian::{Lagrangian, Mechanical};
    pub use crate::method::{InitialState, MethodSpec};
    pub use crate::quadrature::{GaussLegendre, Quadrature, QuadratureKind, QuadratureRule};
    pub use crate::solve::{Solution, SolveFailure, solve};
    pub use crate::systems::{HarmonicOscillator, Kepler, NBody, Pendulum, System};
    pub use crate::trajectory::Trajectory;
    pub use crate::{DualNum, GviError};
}
