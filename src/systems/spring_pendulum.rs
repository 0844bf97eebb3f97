//! The stiff spring pendulum: a unit point mass on a stiff linear spring of rest length l and
//! frequency ω = √(k/m), under gravity g, in the plane — a multiscale problem whose fast
//! frequency depends on the state.
//!
//! In Cartesian coordinates q = (x, y) (y up, pivot at the origin), r = |q|,
//!
//! L = ½ |q̇|² − ½ ω² (r − l)² − g y.
//!
//! The spring's radial oscillation is fast (ω ≫ √(g/l)); the swing of the pendulum is slow.
//! The radial stiffness is not ω² but the curvature of the effective potential
//! ½ω²(r − l)² + ℓ²/(2r²) in r at fixed angular momentum ℓ = r²φ̇, ω² + 3ℓ²/r⁴: the
//! centrifugal term raises the fast frequency to
//!
//! ω_fast ≈ √(ω² + 3φ̇²)
//!
//! (gravity's radial component is linear in r and adds no stiffness). A swinging pendulum sweeps
//! ω_fast between ω (at the turning points) and √(ω² + 3φ̇_max²) (at the bottom); a rotating one
//! runs at a frequency above ω throughout. Oscillatory systems whose high frequency varies with
//! the state in this way are the subject of Hairer, Lubich & Wanner, *Geometric Numerical
//! Integration* (2nd ed.), ch. XIV; this is the test case of docs/guide/enriched-bases.md for
//! where an enrichment with the fixed frequency ω stops helping.

use super::{System, positive};
use crate::error::Result;
use crate::lagrangian::Mechanical;
use nalgebra::DMatrix;
use num_dual::DualNum;

/// The planar stiff spring pendulum (unit mass, D = 2): spring frequency ω, rest length l,
/// gravity g.
///
/// ```
/// use galerkin_vi::systems::{SpringPendulum, System};
/// let sp = SpringPendulum::new(50.0, 1.0, 1.0).unwrap();
/// // Hanging at rest, stretched by g/ω²: the spring's oscillatory energy is 0.
/// let (q, p) = sp.initial_state(0.0, 0.0);
/// let mut inv = [0.0; 3];
/// sp.invariants(&q, &p, &mut inv);
/// assert!(inv[1].abs() < 1e-15 && (inv[2] - 50.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringPendulum {
    omega: f64,
    length: f64,
    gravity: f64,
}

impl SpringPendulum {
    /// Spring frequency ω > 0, rest length l > 0, gravity g > 0.
    ///
    /// Errors: [`GviError::InvalidParameter`](crate::GviError::InvalidParameter) naming the
    /// parameter that is not finite and positive.
    pub fn new(omega: f64, length: f64, gravity: f64) -> Result<Self> {
        Ok(SpringPendulum {
            omega: positive("omega", omega)?,
            length: positive("length", length)?,
            gravity: positive("gravity", gravity)?,
        })
    }

    /// The spring frequency ω = √(k/m) at rest (the fast frequency of a pendulum at rest).
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// Hanging straight down at the stretched rest length r* = l + g/ω², with the spring
    /// stretched further by `stretch` and angular velocity `spin` (φ̇ at the bottom, radians
    /// per unit time): q = (0, −(r* + stretch)), p = ((r* + stretch)·spin, 0). The spring's
    /// oscillatory energy is then ½ω²·stretch²; `spin` sets the swing (it rotates over the top
    /// for spin above about 2√(g/l)) and with it how far ω_fast departs from ω.
    pub fn initial_state(&self, stretch: f64, spin: f64) -> (Vec<f64>, Vec<f64>) {
        let r = self.length + self.gravity / (self.omega * self.omega) + stretch;
        (vec![0.0, -r], vec![r * spin, 0.0])
    }

    /// The quasi-static fast frequency √(ω² + 3φ̇²) at (q, p) (module docs).
    pub fn fast_frequency(&self, q: &[f64], p: &[f64]) -> f64 {
        let r2 = q[0] * q[0] + q[1] * q[1];
        let spin = (q[0] * p[1] - q[1] * p[0]) / r2;
        (self.omega * self.omega + 3.0 * spin * spin).sqrt()
    }
}

impl Mechanical for SpringPendulum {
    fn degrees_of_freedom(&self) -> usize {
        2
    }
    fn mass(&self) -> DMatrix<f64> {
        DMatrix::identity(2, 2)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
        let e = r - self.length;
        e * e * (0.5 * self.omega * self.omega) + q[1] * self.gravity
    }
    /// ∇V = ω² (r − l) q/r + g e_y.
    fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
        let r = q[0].hypot(q[1]);
        let s = self.omega * self.omega * (1.0 - self.length / r);
        out[0] = s * q[0];
        out[1] = s * q[1] + self.gravity;
    }
    /// ∇²V = ω² [(1 − l/r) I + (l/r³) q qᵀ].
    fn potential_hessian(&self, q: &[f64], out: &mut [f64]) {
        let r = q[0].hypot(q[1]);
        let w2 = self.omega * self.omega;
        let (diag, outer) = (w2 * (1.0 - self.length / r), w2 * self.length / (r * r * r));
        out[0] = diag + outer * q[0] * q[0];
        out[1] = outer * q[0] * q[1];
        out[2] = out[1];
        out[3] = diag + outer * q[1] * q[1];
    }
}

impl System for SpringPendulum {
    fn name(&self) -> &'static str {
        "spring-pendulum"
    }
    /// The energy H, the spring's oscillatory energy I = ½(p_r² + ω²(r − r*)²) about the
    /// hanging rest length r* = l + g/ω² (p_r = q·p/r), and the fast frequency √(ω² + 3φ̇²).
    fn invariant_names(&self) -> &'static [&'static str] {
        &["energy", "oscillatory_energy", "fast_frequency"]
    }
    fn invariants(&self, q: &[f64], p: &[f64], out: &mut [f64]) {
        let kinetic = 0.5 * (p[0] * p[0] + p[1] * p[1]);
        out[0] = kinetic + self.potential(q);
        let r = q[0].hypot(q[1]);
        let pr = (q[0] * p[0] + q[1] * p[1]) / r;
        let w2 = self.omega * self.omega;
        let e = r - self.length - self.gravity / w2;
        out[1] = 0.5 * (pr * pr + w2 * e * e);
        out[2] = self.fast_frequency(q, p);
    }
    /// The fast period 2π/√(ω² + 3φ̇²).
    fn shortest_time_scale(&self, q: &[f64], p: &[f64]) -> Option<f64> {
        Some(std::f64::consts::TAU / self.fast_frequency(q, p))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_ad_and_the_rest_state() {
        let sp = SpringPendulum::new(50.0, 1.0, 1.0).unwrap();
        for q in [[0.3, -0.9], [-1.2, 0.4], [0.0, -1.03], [0.7, 0.8]] {
            crate::systems::derivative_tests::check_against_ad(&sp, &q);
        }
        // The hanging rest state is an equilibrium: ∇V = 0 there.
        let (q, _) = sp.initial_state(0.0, 0.0);
        let mut g = [0.0; 2];
        sp.potential_gradient(&q, &mut g);
        assert!(g.iter().all(|x| x.abs() < 1e-12), "{g:?}");
        // Spin raises the fast frequency: √(ω² + 3φ̇²) at the bottom.
        let (q, p) = sp.initial_state(0.02, 10.0);
        assert!((sp.fast_frequency(&q, &p) - (2500.0f64 + 300.0).sqrt()).abs() < 1e-12);
        for bad in [0.0, -1.0, f64::NAN] {
            assert!(SpringPendulum::new(bad, 1.0, 1.0).is_err());
            assert!(SpringPendulum::new(50.0, bad, 1.0).is_err());
            assert!(SpringPendulum::new(50.0, 1.0, bad).is_err());
        }
    }
}
