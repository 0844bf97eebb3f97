//! The simple pendulum L = m l² θ̇²/2 + m g l cos θ.

use super::{System, positive};
use crate::error::Result;
use crate::lagrangian::Mechanical;
use nalgebra::DMatrix;
use num_dual::DualNum;

/// Planar pendulum of length l, point mass m, gravity g; θ = 0 hangs down.
///
/// ```
/// use galerkin_vi::systems::{Pendulum, System};
/// let pend = Pendulum::new(1.0, 9.81, 1.0).unwrap();
/// let mut e = [0.0];
/// pend.invariants(&[0.0], &[0.0], &mut e);
/// assert!((e[0] + 9.81).abs() < 1e-12); // bottom of the well: −m g l
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pendulum {
    length: f64,
    gravity: f64,
    mass: f64,
}

impl Pendulum {
    /// Length l > 0, gravity g > 0, mass m > 0.
    pub fn new(length: f64, gravity: f64, mass: f64) -> Result<Self> {
        Ok(Pendulum {
            length: positive("length", length)?,
            gravity: positive("gravity", gravity)?,
            mass: positive("mass", mass)?,
        })
    }

    /// l = g = m = 1 (small-oscillation period 2π).
    pub fn unit() -> Self {
        Pendulum {
            length: 1.0,
            gravity: 1.0,
            mass: 1.0,
        }
    }
}

impl Mechanical for Pendulum {
    fn degrees_of_freedom(&self) -> usize {
        1
    }
    fn mass(&self) -> DMatrix<f64> {
        DMatrix::from_element(1, 1, self.mass * self.length * self.length)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        -q[0].cos() * (self.mass * self.gravity * self.length)
    }
    fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
        out[0] = self.mass * self.gravity * self.length * q[0].sin();
    }
    fn potential_hessian(&self, q: &[f64], out: &mut [f64]) {
        out[0] = self.mass * self.gravity * self.length * q[0].cos();
    }
}

impl System for Pendulum {
    fn name(&self) -> &'static str {
        "pendulum"
    }
    /// The small-amplitude period 2π √(l/g) (larger amplitudes swing more slowly).
    fn shortest_time_scale(&self, _q: &[f64], _p: &[f64]) -> Option<f64> {
        Some(std::f64::consts::TAU * (self.length / self.gravity).sqrt())
    }
    fn invariant_names(&self) -> &'static [&'static str] {
        &["energy"]
    }
    fn invariants(&self, q: &[f64], p: &[f64], out: &mut [f64]) {
        let inertia = self.mass * self.length * self.length;
        out[0] = 0.5 * p[0] * p[0] / inertia - self.mass * self.gravity * self.length * q[0].cos();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_ad() {
        let p = Pendulum::new(1.5, 9.81, 0.7).unwrap();
        for q in [0.0, 0.4, 2.9, -1.3] {
            crate::systems::derivative_tests::check_against_ad(&p, &[q]);
        }
        assert!(Pendulum::new(-1.0, 1.0, 1.0).is_err());
    }
}
