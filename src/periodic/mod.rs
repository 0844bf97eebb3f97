//! Periodic Galerkin: a whole period as one element with the Fourier basis.
//!
//! A periodic orbit is a stationary point of the action over one period among closed curves
//! q(t) = a₀ + Σ_{k=1..K} (a_k cos 2πkt/T + b_k sin 2πkt/T) ([`curve`]). The action is
//! integrated by the trapezoid rule, spectrally accurate for periodic integrands, and made
//! stationary by Newton's method with the exact Hessian (automatic differentiation through
//! [`Lagrangian::hessian`](crate::Lagrangian::hessian), the analytic pairwise Hessian for N bodies), at fixed period or
//! with the period unknown and the energy prescribed ([`action`], [`newton`]). The symmetry directions are
//! removed from every step. An N-body choreography has one unknown curve,
//! q_{i+1}(t) = q_i(t + T/N). The stability of the orbit found comes from the monodromy
//! matrix, the product of the step Jacobians of a time-stepping run over one period
//! ([`floquet`]). docs/guide/periodic-orbits.md has the mathematics and measured results.
//!
//! ```
//! use galerkin_vi::periodic::{self, FourierCurve, Layout, PeriodCondition, Symmetry};
//! use galerkin_vi::systems::NBody;
//! // The figure-eight from a lemniscate guess, energy from Simó's initial data.
//! let nb = NBody::new(vec![1.0; 3], 1.0, 2)?;
//! let layout = Layout::Choreography { bodies: 3, body_dim: 2 };
//! let mut guess = FourierCurve::zeros(30, layout, 6.0)?;
//! guess.set_mode(1, &[0.0, 0.0], &[1.0, 0.0])?;
//! guess.set_mode(2, &[0.0, 0.0], &[0.0, 0.35])?;
//! let sol = periodic::solve(&nb, guess, PeriodCondition::Energy(-1.287_141_991_8),
//!     &Symmetry::nbody(2), &Default::default())?;
//! assert!((sol.curve.period - 6.3259).abs() < 1e-3);
//! # Ok::<(), galerkin_vi::GviError>(())
//! ```

pub mod action;
pub mod curve;
pub mod floquet;
pub mod newton;
pub mod spec;

pub use action::{action_and_energy, default_nodes, equation_residual};
pub use curve::{FourierCurve, Layout};
pub use floquet::{Floquet, monodromy};
pub use newton::{PeriodCondition, PeriodicOptions, PeriodicSolution, Symmetry, solve};
pub use spec::{ConditionKind, CurveKind, GuessMode, PeriodicSpec};
