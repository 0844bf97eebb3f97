//! Continuous symmetries and their Noether momentum maps J(q, p) = p · ξ(q).
//!
//! A one-parameter group of transformations that leaves the Lagrangian invariant has an
//! infinitesimal generator ξ(q); Noether's theorem makes J(q, p) = p · ξ(q) a constant of the
//! exact flow, and the discrete Noether theorem (paper §3.4) makes it a constant of the
//! discrete flow of a variational integrator, to round-off and solver tolerance. Generators:
//! [`Rotation`] (in a coordinate plane, for every body of an N-body system at once) and
//! [`Translation`] (along an axis). Systems list theirs with
//! [`System::symmetries`](crate::systems::System::symmetries); [`crate::geometry`] measures
//! the drift of each over a run.

use crate::error::{GviError, Result};
use std::fmt;

/// A momentum map of a symmetry: its infinitesimal generator ξ(q) on configuration space
/// and the value J(q, p) = p · ξ(q) (by Noether's theorem conserved by the exact flow, and
/// exactly — to round-off and solver tolerance — by the discrete flow of a variational
/// integrator, when the Lagrangian is invariant).
pub trait MomentumMap {
    /// The generator ξ(q) into `xi` (same length as q).
    fn generator(&self, q: &[f64], xi: &mut [f64]);

    /// J(q, p) = p · ξ(q).
    fn value(&self, q: &[f64], p: &[f64]) -> f64 {
        let mut xi = vec![0.0; q.len()];
        self.generator(q, &mut xi);
        p.iter().zip(&xi).map(|(a, b)| a * b).sum()
    }
}

/// Simultaneous rotation in the (i, j) coordinate plane of every body, when the
/// configuration is a stack of point masses of dimension `dim_per_body` each:
/// ξ(q) has components ξ_i = −q_j, ξ_j = q_i for every body, so
/// J = Σ_bodies (q_i p_j − q_j p_i) (the angular momentum about the origin in that plane).
///
/// ```
/// use galerkin_vi::geometry::{MomentumMap, Rotation};
///
/// // Planar Kepler problem: one body in 2-D, rotation in the (x, y) plane.
/// let rot = Rotation::planar(2, 1, 0, 1)?;
/// assert!((rot.value(&[0.4, 0.0], &[0.0, 2.0]) - 0.8).abs() < 1e-15);
/// // Two bodies in 2-D: the total angular momentum.
/// let rot2 = Rotation::planar(2, 2, 0, 1)?;
/// let j = rot2.value(&[1.0, 0.0, -1.0, 0.0], &[0.0, 1.0, 0.0, -1.0]);
/// assert!((j - 2.0).abs() < 1e-15);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rotation {
    /// First axis of the rotation plane (within one body).
    pub i: usize,
    /// Second axis of the rotation plane.
    pub j: usize,
    /// Coordinates per body.
    pub dim_per_body: usize,
    /// Number of bodies.
    pub bodies: usize,
}

impl Rotation {
    /// Rotation in the (i, j) plane of every one of `bodies` point masses in `dim_per_body`
    /// dimensions (configuration q = (x_1, …, x_bodies), D = dim_per_body · bodies).
    pub fn planar(dim_per_body: usize, bodies: usize, i: usize, j: usize) -> Result<Self> {
        if i == j || i >= dim_per_body || j >= dim_per_body || bodies == 0 {
            return Err(GviError::InvalidInput {
                name: "rotation plane".into(),
                reason: format!(
                    "need distinct axes i = {i}, j = {j} below the body dimension \
                     {dim_per_body} and at least one body (got {bodies})"
                ),
            });
        }
        Ok(Rotation {
            i,
            j,
            dim_per_body,
            bodies,
        })
    }

    /// Configuration dimension D this rotation acts on.
    pub fn dim(&self) -> usize {
        self.dim_per_body * self.bodies
    }
}

impl MomentumMap for Rotation {
    fn generator(&self, q: &[f64], xi: &mut [f64]) {
        xi.iter_mut().for_each(|x| *x = 0.0);
        let d = self.dim_per_body.max(1);
        for b in 0..self.bodies {
            let (ii, jj) = (b * d + self.i, b * d + self.j);
            if jj < q.len().min(xi.len()) && ii < q.len().min(xi.len()) {
                xi[ii] = -q[jj];
                xi[jj] = q[ii];
            }
        }
    }
}

/// A constant generator ξ(q) = `direction` (a translation symmetry); J = p · direction.
#[derive(Debug, Clone, PartialEq)]
pub struct Translation {
    /// The direction in configuration space (length D).
    pub direction: Vec<f64>,
}

impl Translation {
    /// Translation along `direction` (any vector of length D).
    pub fn new(direction: Vec<f64>) -> Self {
        Translation { direction }
    }

    /// Translation of every one of `bodies` point masses of dimension `dim_per_body` along
    /// axis `axis`: J is the total linear momentum along that axis.
    pub fn axis(dim_per_body: usize, bodies: usize, axis: usize) -> Result<Self> {
        if axis >= dim_per_body || bodies == 0 {
            return Err(GviError::InvalidInput {
                name: "translation axis".into(),
                reason: format!(
                    "axis {axis} is not below the body dimension {dim_per_body}, or no bodies"
                ),
            });
        }
        let mut direction = vec![0.0; dim_per_body * bodies];
        for b in 0..bodies {
            direction[b * dim_per_body + axis] = 1.0;
        }
        Ok(Translation { direction })
    }
}

impl MomentumMap for Translation {
    fn generator(&self, _q: &[f64], xi: &mut [f64]) {
        for (k, x) in xi.iter_mut().enumerate() {
            *x = self.direction.get(k).copied().unwrap_or(0.0);
        }
    }
}

/// A user-defined generator ξ(q) given by a closure `f(q, xi)`.
///
/// ```
/// use galerkin_vi::geometry::{Generator, MomentumMap};
/// // Rotation of a single planar body written by hand.
/// let g = Generator::new(|q: &[f64], xi: &mut [f64]| {
///     xi[0] = -q[1];
///     xi[1] = q[0];
/// });
/// assert!((g.value(&[1.0, 0.0], &[0.0, 3.0]) - 3.0).abs() < 1e-15);
/// ```
#[derive(Clone)]
pub struct Generator<F> {
    f: F,
}

impl<F: Fn(&[f64], &mut [f64])> Generator<F> {
    /// Wrap a closure that writes ξ(q) into its second argument.
    pub fn new(f: F) -> Self {
        Generator { f }
    }
}

impl<F: Fn(&[f64], &mut [f64])> MomentumMap for Generator<F> {
    fn generator(&self, q: &[f64], xi: &mut [f64]) {
        (self.f)(q, xi)
    }
}

impl<F> std::fmt::Debug for Generator<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Generator")
    }
}

impl<M: MomentumMap + ?Sized> MomentumMap for &M {
    fn generator(&self, q: &[f64], xi: &mut [f64]) {
        (**self).generator(q, xi)
    }
    fn value(&self, q: &[f64], p: &[f64]) -> f64 {
        (**self).value(q, p)
    }
}

impl<M: MomentumMap + ?Sized> MomentumMap for Box<M> {
    fn generator(&self, q: &[f64], xi: &mut [f64]) {
        (**self).generator(q, xi)
    }
    fn value(&self, q: &[f64], p: &[f64]) -> f64 {
        (**self).value(q, p)
    }
}

/// A momentum map with a display name.
pub struct NamedMomentumMap {
    /// Name, e.g. `angular_momentum`.
    pub name: String,
    /// The map.
    pub map: Box<dyn MomentumMap + Send + Sync>,
}

impl fmt::Debug for NamedMomentumMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "NamedMomentumMap({})", self.name)
    }
}
