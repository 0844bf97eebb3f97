//! Lie group spectral variational integrators on SO(3) (Hall & Leok, "Lie group spectral
//! variational integrators", Found. Comput. Math. 17 (2017) 199–257), for rigid bodies.
//!
//! # The construction
//!
//! A step of size h from g_k ∈ SO(3) uses curves in the natural chart at g_k,
//! g(t_k + τh) = g_k τ(ξ(τ)), with ξ(τ) = Σ_i Ξ_i φ_i(τ) ∈ so(3) ≅ R³ expanded in any
//! [`Basis`](crate::basis::Basis) and Ξ_0 = 0 (so g(t_k) = g_k); τ is exp (Rodrigues) or the
//! Cayley map ([`Retraction`]). The body velocity along the curve is
//! Ω = g⁻¹ġ = J_r(ξ) ξ̇ with J_r(ξ) = dexp_{−ξ} the left-trivialised derivative of exp
//! (conventions in [`so3`]). The discrete Lagrangian is the quadrature of the left-trivialised
//! Lagrangian ℓ(g, Ω) = ½ Ω·𝕀Ω − V(g) along the extremal curve with g(t_{k+1}) = g_{k+1}:
//!
//! L_d(g_k, g_{k+1}) = ext h Σ_j b_j ℓ(g_k τ(ξ(c_j)), J_r(ξ(c_j)) ξ̇(c_j)).
//!
//! Its left-trivialised derivatives follow from the envelope theorem. Write S(Ξ) for the
//! action, X = Ξ_{n−1} = τ⁻¹(g_k⁻¹g_{k+1}), π = ∂S/∂Ξ_{n−1} and f(g) for the left-trivialised
//! gradient of V. Moving g_{k+1} to g_{k+1}τ(εη) moves X by J_r(X)⁻¹η ε; moving g_k to
//! g_k τ(εη) moves X by −J_l(X)⁻¹η ε and every node g_k τ(ξ_j) by Ad_{τ(ξ_j)⁻¹}η ε. So
//!
//! - μ_{k+1} = D₂L_d = J_r(X)⁻ᵀ π,
//! - μ_k = −D₁L_d = J_l(X)⁻ᵀ π + h Σ_j b_j τ(ξ_j) f(g_k τ(ξ_j)),
//!
//! together with the interior stationarity ∂S/∂Ξ_i = 0 (i = 1 … n − 2): the discrete
//! Euler–Poincaré equations in position–momentum form. Because J_l = τ(X) J_r, the update is
//! μ_{k+1} = τ(X)ᵀ ν with ν = μ_k − h Σ_j b_j τ(ξ_j) f_j, and the spatial momentum changes by the
//! spatial impulse only: g_{k+1}μ_{k+1} = g_kμ_k − h Σ_j b_j g_j f_j. For the free body it is
//! conserved exactly, whatever the Newton tolerance: only round-off in the products remains.
//! The map is the composition of two discrete Legendre transforms of one generating function,
//! hence symplectic on T*SO(3).
//!
//! The Euclidean method (docs/DESIGN.md §2) is the special case of a commutative group.
//!
//! # Modules
//!
//! [`so3`] (hat map, exp/Cayley and their trivialised derivatives), [`body`] (rigid bodies:
//! free body, heavy top), [`integrator`] (the method), [`elliptic`] (Jacobi elliptic
//! functions and the exact free body), [`geometry`] (symplecticity defect in canonical
//! coordinates of T*SO(3)), [`baselines`] (RK4, Lie–Poisson splitting, RATTLE).

pub mod baselines;
pub mod body;
pub mod elliptic;
pub mod geometry;
pub mod integrator;
mod node;

pub mod so3;

pub use body::{FreeRigidBody, HeavyTop, RigidBody};
pub use elliptic::FreeBodyExact;
pub use integrator::{LieGalerkin, LieNewtonOptions, LieState, LieTrajectory};
pub use so3::Retraction;
