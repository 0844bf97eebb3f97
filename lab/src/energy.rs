//! The scale of every relative energy error the lab reports (`gvi run`, `gvi ensemble`,
//! `gvi stability`, `gvi nbody-report`): T₀ + |V₀|, the kinetic energy plus the magnitude of
//! the potential at the start, so that all of them measure the same thing.
//!
//! |E₀| is the obvious scale and the wrong one: it vanishes where the kinetic and potential
//! energies cancel (a parabolic orbit, E₀ = 0 to round-off), and a run that conserves the
//! energy to 1e-15 of its terms then reports a relative error of order one (1.5 measured for
//! a parabolic Kepler orbit over |E₀|). T₀ + |V₀| ≥ |E₀| always, equals it when V ≥ 0 (the
//! harmonic oscillator), and is the size of the terms whose round-off the energy carries.

use galerkin_vi::systems::System;

/// Label of the scale T₀ + |V₀|.
pub const KINETIC_PLUS_POTENTIAL: &str = "T₀ + |V₀|";

/// Label of the fallback scale |E₀|.
pub const INITIAL_ENERGY: &str = "|E₀|";

/// The scale of a relative energy error from the start's kinetic energy T₀ and potential V₀
/// (E₀ = T₀ + V₀): (label, T₀ + |V₀|), or (`|E₀|`, |e0|) if T₀ + |V₀| is not a positive
/// finite number.
pub fn energy_scale_of_parts(kinetic: f64, potential: f64, e0: f64) -> (&'static str, f64) {
    let scale = kinetic.abs() + potential.abs();
    if scale.is_finite() && scale > 0.0 {
        (KINETIC_PLUS_POTENTIAL, scale)
    } else {
        (INITIAL_ENERGY, e0.abs())
    }
}

/// The scale of a run's relative energy error from its start (q0, p0) with energy e0:
/// T₀ + |V₀| ([`energy_scale_of_parts`]) with T₀ = ½ p₀ᵀ M⁻¹ p₀ and V₀ = T₀ − L(q₀, v₀),
/// v₀ = M⁻¹p₀, for a system with a constant mass matrix M; |E₀| otherwise (the kinetic and
/// potential parts of a general Lagrangian are not defined). Returns the label and value.
pub fn energy_scale<S: System>(system: &S, q0: &[f64], p0: &[f64], e0: f64) -> (&'static str, f64) {
    let fallback = (INITIAL_ENERGY, e0.abs());
    let Some(mass) = system.mass_matrix() else {
        return fallback;
    };
    let p = nalgebra::DVector::from_column_slice(p0);
    let Some(v) = mass.lu().solve(&p) else {
        return fallback;
    };
    let kinetic = 0.5 * p.dot(&v);
    let potential = kinetic - system.value(q0, v.as_slice());
    energy_scale_of_parts(kinetic, potential, e0)
}

/// |ΔE| over `scale`, NaN where the scale is 0 (no relative error can be given).
pub fn relative_energy_error(absolute: f64, scale: f64) -> f64 {
    if scale > 0.0 {
        absolute / scale
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use galerkin_vi::systems::{HarmonicOscillator, Kepler};

    /// A parabolic Kepler orbit (E₀ = 0): the scale is T₀ + |V₀| = 1 + 1 = 2, where |E₀|
    /// (the negative control) is 0. For the harmonic oscillator (V ≥ 0) the two agree.
    #[test]
    fn the_scale_does_not_vanish_with_the_energy() {
        let kepler = Kepler::new(1.0).unwrap();
        let (q, p) = ([1.0, 0.0], [0.0, 2f64.sqrt()]);
        let mut e = [0.0; 2];
        kepler.invariants(&q, &p, &mut e);
        assert!(e[0].abs() < 1e-15, "{e:?}");
        let (label, scale) = energy_scale(&kepler, &q, &p, e[0]);
        assert_eq!(label, KINETIC_PLUS_POTENTIAL);
        assert!((scale - 2.0).abs() < 1e-15, "{scale}");
        assert!(relative_energy_error(1e-16, scale) < 1e-15);
        assert!(relative_energy_error(1e-16, e[0].abs()).is_nan() || 1e-16 / e[0].abs() > 0.1);
        let oscillator = HarmonicOscillator::new(1.0, 1.0).unwrap();
        let (q, p) = ([0.6], [0.8]);
        let mut e = [0.0; 1];
        oscillator.invariants(&q, &p, &mut e);
        let (_, scale) = energy_scale(&oscillator, &q, &p, e[0]);
        assert!((scale - e[0]).abs() < 1e-15, "{scale} vs {}", e[0]);
        assert_eq!(energy_scale_of_parts(0.0, 0.0, 0.0), (INITIAL_ENERGY, 0.0));
    }
}
