//! The sweep of a work–precision study: which configurations it runs, family by family.

use super::WorkPrecisionConfig;
use crate::studies::peers::{Peer, nbody_of};
use galerkin_vi::baselines::CompositionScheme;
use galerkin_vi::systems::System;

/// The configurations of the sweep, one list per family in sweep order: (peer, steps per
/// sample interval). Fixed-step families are listed from coarse to fine, so that the study can
/// stop refining one once it is converged.
pub(super) fn sweep_plan<S: System + 'static>(
    system: &S,
    config: &WorkPrecisionConfig,
    samples: usize,
) -> Vec<Vec<(Peer, usize)>> {
    // (peer, divisor) in sweep order; fixed-step families stop refining once converged.
    // The paper's quadrature first, so that its rows keep their order in the outputs.
    let mut plan: Vec<Vec<(Peer, usize)>> = Vec::new();
    for &points in &config.quad_points {
        for &basis in &config.bases {
            for &m in &config.galerkin_divisors {
                plan.push(
                    config
                        .ns
                        .iter()
                        .map(|&n| (Peer::Galerkin { basis, n, points }, m))
                        .collect(),
                );
            }
        }
    }
    // The Kepler-adapted integrator on N-body scenes: one family per stage count, over its
    // own step grid (its steps are longer than the polynomial bases').
    if nbody_of(system).is_some() {
        for &s in &config.kepler_stages {
            for &bodies in &config.kepler_bodies {
                plan.push(
                    config
                        .kepler_divisors
                        .iter()
                        .map(|&m| (Peer::KeplerAdapted { s, bodies }, m))
                        .collect(),
                );
            }
        }
    }
    // The multirate integrator on N-body scenes with a dominant mass (a star and planets):
    // one family per number of micro steps and step, over n.
    if let Some(nb) = nbody_of(system) {
        let masses = nb.masses();
        let heaviest = masses.iter().copied().fold(0.0, f64::max);
        let rest: f64 = masses.iter().sum::<f64>() - heaviest;
        if masses.len() > 2 && heaviest >= 10.0 * rest {
            for &r in &config.multirate_micro_steps {
                for &m in &config.multirate_divisors {
                    plan.push(
                        config
                            .multirate_ns
                            .iter()
                            .map(|&n| (Peer::Multirate { n, micro_steps: r }, m))
                            .collect(),
                    );
                }
            }
        }
    }
    let mut fixed = vec![Peer::StormerVerlet, Peer::Rk4];
    fixed.extend(config.gauss_stages.iter().map(|&s| Peer::Gauss { s }));
    fixed.extend(CompositionScheme::ALL.map(|scheme| Peer::Composition { scheme }));
    // The classical peers need L = ½ vᵀ M v − V(q); a non-separable Lagrangian (expression
    // scenes `magnetic`, `double-pendulum`) is swept with the Galerkin families only.
    let mechanical = system.mass_matrix().is_some();
    if !mechanical {
        fixed.clear();
    }
    for peer in fixed {
        plan.push(
            config
                .baseline_divisors
                .iter()
                .filter(|&&m| m.saturating_mul(samples) <= config.max_steps)
                .map(|&m| (peer, m))
                .collect(),
        );
    }
    if cfg!(feature = "dop853") && mechanical {
        plan.push(
            config
                .tolerances
                .iter()
                .map(|&tolerance| (Peer::Dop853 { tolerance }, 1))
                .collect(),
        );
    }
    plan
}
