//! The planar Kepler problem in the relative coordinate (paper §5.2.1).

use super::kepler_orbit::KeplerOrbit;
use super::{ExactSolution, System, positive};
use crate::error::{GviError, Result, ensure_len};
use crate::lagrangian::Mechanical;
use nalgebra::DMatrix;
use num_dual::DualNum;

/// Planar Kepler problem L = |q̇|²/2 + μ/|q| (relative coordinate, μ = G(m₁ + m₂)).
///
/// With μ = 1, q(0) = (0.4, 0), p(0) = (0, 2) the orbit has e = 0.6, a = 1, period 2π and
/// starts at periapsis (Hairer–Lubich–Wanner's normalisation; the paper's e = 0.6 run).
///
/// ```
/// use galerkin_vi::systems::{Kepler, System};
/// let kepler = Kepler::new(1.0).unwrap();
/// let mut inv = [0.0; 2];
/// kepler.invariants(&[0.4, 0.0], &[0.0, 2.0], &mut inv);
/// assert!((inv[0] + 0.5).abs() < 1e-15); // energy −1/2
/// assert!((inv[1] - 0.8).abs() < 1e-15); // angular momentum
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kepler {
    mu: f64,
}

impl Kepler {
    /// Gravitational parameter μ > 0.
    pub fn new(mu: f64) -> Result<Self> {
        Ok(Kepler {
            mu: positive("mu", mu)?,
        })
    }

    /// μ.
    pub fn mu(&self) -> f64 {
        self.mu
    }

    /// The e = 0.6 initial state of the paper: (q0, p0).
    pub fn paper_initial_state() -> ([f64; 2], [f64; 2]) {
        ([0.4, 0.0], [0.0, 2.0])
    }
}

impl Mechanical for Kepler {
    fn degrees_of_freedom(&self) -> usize {
        2
    }
    fn mass(&self) -> DMatrix<f64> {
        DMatrix::identity(2, 2)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        -(q[0] * q[0] + q[1] * q[1]).sqrt().recip() * self.mu
    }
    fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
        let r2 = q[0] * q[0] + q[1] * q[1];
        let k = self.mu / (r2 * r2.sqrt());
        out[0] = k * q[0];
        out[1] = k * q[1];
    }
    /// The same arithmetic as [`Self::potential_gradient`], point by point with the two
    /// coordinates fixed, so that the square roots and divisions of several points run side by
    /// side in vector lanes (the same bits: each is correctly rounded in either form). The
    /// default's per-point calls were 10 % of issue 35's fastest Kepler run.
    fn potential_gradient_at_points(&self, q: &[f64], out: &mut [f64]) {
        for (qj, oj) in q.chunks_exact(2).zip(out.chunks_exact_mut(2)) {
            let r2 = qj[0] * qj[0] + qj[1] * qj[1];
            let k = self.mu / (r2 * r2.sqrt());
            oj[0] = k * qj[0];
            oj[1] = k * qj[1];
        }
    }
    fn potential_hessian(&self, q: &[f64], out: &mut [f64]) {
        // ∇²V = μ (I/r³ − 3 q qᵀ/r⁵)
        let r2 = q[0] * q[0] + q[1] * q[1];
        let r3 = r2 * r2.sqrt();
        let a = self.mu / r3;
        let b = 3.0 * a / r2;
        out[0] = a - b * q[0] * q[0];
        out[1] = -b * q[0] * q[1];
        out[2] = out[1];
        out[3] = a - b * q[1] * q[1];
    }
}

impl System for Kepler {
    fn name(&self) -> &'static str {
        "kepler"
    }
    /// The orbital period 2π √(a³/μ) of a bound orbit (a = −μ/(2E)); for an unbound one
    /// the time 2π r/|v| to sweep its current distance.
    fn shortest_time_scale(&self, q: &[f64], p: &[f64]) -> Option<f64> {
        if q.len() != 2 || p.len() != 2 {
            return None;
        }
        let r = q[0].hypot(q[1]);
        let v2 = p[0] * p[0] + p[1] * p[1];
        let energy = 0.5 * v2 - self.mu / r;
        let t = if energy < 0.0 {
            let a = -self.mu / (2.0 * energy);
            std::f64::consts::TAU * (a * a * a / self.mu).sqrt()
        } else {
            std::f64::consts::TAU * r / v2.sqrt()
        };
        (t.is_finite() && t > 0.0).then_some(t)
    }
    fn invariant_names(&self) -> &'static [&'static str] {
        &["energy", "angular_momentum"]
    }
    fn invariants(&self, q: &[f64], p: &[f64], out: &mut [f64]) {
        let r = (q[0] * q[0] + q[1] * q[1]).sqrt();
        out[0] = 0.5 * (p[0] * p[0] + p[1] * p[1]) - self.mu / r;
        out[1] = q[0] * p[1] - q[1] * p[0];
    }
    fn symmetries(&self) -> Vec<crate::symmetries::NamedMomentumMap> {
        // L is invariant under rotations of the plane: angular momentum q × p.
        crate::symmetries::Rotation::planar(2, 1, 0, 1)
            .map(|rot| {
                vec![crate::symmetries::NamedMomentumMap {
                    name: "angular_momentum".into(),
                    map: Box::new(rot),
                }]
            })
            .unwrap_or_default()
    }
    fn exact_solution(&self, t0: f64, q0: &[f64], p0: &[f64]) -> Result<Option<ExactSolution>> {
        ensure_len("q0", 2, q0.len())?;
        ensure_len("p0", 2, p0.len())?;
        let orbit = KeplerOrbit::from_state(self.mu, [q0[0], q0[1]], [p0[0], p0[1]], t0);
        match orbit {
            Ok(orbit) => Ok(Some(ExactSolution::new(move |t| {
                let (q, v) = orbit.state_at(t);
                (q.to_vec(), v.to_vec())
            }))),
            // Unbound or degenerate orbits have no closed form here; that is not an error.
            Err(super::kepler_orbit::OrbitError::NotBound { .. })
            | Err(super::kepler_orbit::OrbitError::Degenerate) => Ok(None),
            Err(e) => {
                // Name the field and the value that broke the orbit's elements.
                let fields = [
                    ("t0", t0),
                    ("q0[0]", q0[0]),
                    ("q0[1]", q0[1]),
                    ("p0[0]", p0[0]),
                    ("p0[1]", p0[1]),
                    ("mu", self.mu),
                ];
                // A non-finite field if there is one; otherwise the one of the most extreme
                // magnitude (p0 = 1e300 overflows the elements, not mu = 1).
                let extremity = |v: f64| if v == 0.0 { 0.0 } else { v.abs().log10().abs() };
                let (name, value) = fields
                    .into_iter()
                    .find(|(_, v)| !v.is_finite())
                    .or_else(|| {
                        fields
                            .into_iter()
                            .max_by(|a, b| extremity(a.1).total_cmp(&extremity(b.1)))
                    })
                    .unwrap_or(("mu", self.mu));
                Err(GviError::InvalidParameter {
                    name: format!("Kepler {name}"),
                    value,
                    reason: format!(
                        "{e} (mu = {:e}, q0 = [{:e}, {:e}], p0 = [{:e}, {:e}], t0 = {:e}: the \
                         orbital elements overflow)",
                        self.mu, q0[0], q0[1], p0[0], p0[1], t0
                    ),
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_ad() {
        let k = Kepler::new(1.3).unwrap();
        for q in [[0.4, 0.0], [-0.3, 1.2], [2.0, -0.7]] {
            crate::systems::derivative_tests::check_against_ad(&k, &q);
        }
    }

    #[test]
    fn exact_solution_matches_closed_form() {
        let k = Kepler::new(1.0).unwrap();
        let (q0, p0) = Kepler::paper_initial_state();
        let ex = k.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
        let e: f64 = 0.6;
        for i in 0..40 {
            let t = 0.5 * i as f64;
            let big_e = super::super::kepler_orbit::solve_kepler_equation(t, e);
            let x = big_e.cos() - e;
            let y = (1.0 - e * e).sqrt() * big_e.sin();
            let q = ex.position(t);
            assert!((q[0] - x).abs() < 1e-13 && (q[1] - y).abs() < 1e-13);
        }
        // Unbound: no exact solution, not an error.
        assert!(
            k.exact_solution(0.0, &[1.0, 0.0], &[0.0, 2.0])
                .unwrap()
                .is_none()
        );
    }
}
