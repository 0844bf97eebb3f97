//! Kepler from periapsis and the fictitious period of a time transformation, shared by the
//! library's and the lab's time-transformation tests (the lab includes this file by path).

use std::f64::consts::TAU;

/// Kepler with a = 1, μ = 1 (period 2π) from periapsis at eccentricity e.
pub fn kepler_at_periapsis(e: f64) -> ([f64; 2], [f64; 2]) {
    ([1.0 - e, 0.0], [0.0, ((1.0 + e) / (1.0 - e)).sqrt()])
}

/// The fictitious time of one orbit for g = (r/r_p)^α: ∫ dt/g = ∫ r (r_p/r)^α dE over the
/// eccentric anomaly (dt = r dE for a = μ = 1), by the trapezoid rule (spectral for a
/// periodic integrand).
pub fn fictitious_period(e: f64, alpha: f64) -> f64 {
    let m = 20_000;
    let rp = 1.0 - e;
    (0..m)
        .map(|i| {
            let r = 1.0 - e * (TAU * i as f64 / m as f64).cos();
            r * (rp / r).powf(alpha)
        })
        .sum::<f64>()
        * TAU
        / m as f64
}
