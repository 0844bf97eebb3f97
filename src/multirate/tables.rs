//! The velocity-form tables of the multirate step: Legendre modes of the velocity at the Gauss
//! nodes of the macro and micro rules (the tables of the single-rate velocity form, built
//! here for two rules and for the slow modes at the micro nodes).

use crate::error::Result;
use crate::integrator::velocity::legendre_modes;
use crate::quadrature::QuadratureKind;

/// The tables of one rule for k = n − 1 velocity modes (row-major, m nodes).
#[derive(Debug, Clone)]
pub(super) struct ModeTables {
    /// k = n − 1 modes.
    pub k: usize,
    /// Nodes c_j in [0, 1].
    pub nodes: Vec<f64>,
    /// Weights b_j (summing to 1).
    pub weights: Vec<f64>,
    /// ι_ja = I_a(c_j), m×k (column 0: c_j on the 2⁻⁵³ grid, so that ψ_j0 is exact).
    pub iota: Vec<f64>,
    /// ψ_jb: ι_jb for b ≥ 1, ι_j0 − 1 for b = 0.
    pub psi: Vec<f64>,
    /// The extrapolation of the velocity to the next step, k×k: the previous step's
    /// q̇(τ + 1) projected on the modes (exact for polynomials: the rule integrates degree
    /// 2k − 2).
    pub extrapolate: Vec<f64>,
}

/// ι and ψ of k modes at the times `taus` (in units of the step), row-major.
pub(super) fn modes_at(taus: &[f64], k: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut iota, mut values) = (vec![0.0; taus.len() * k], vec![0.0; k]);
    for (row, &tau) in iota.chunks_exact_mut(k).zip(taus) {
        legendre_modes(tau, &mut values, row);
        // On the 2⁻⁵³ grid, so that ι_j0 − 1 is exact (as the single-rate tables).
        row[0] = (tau * 2f64.powi(53)).round() / 2f64.powi(53);
    }
    let mut psi = iota.clone();
    for row in psi.chunks_exact_mut(k) {
        row[0] -= 1.0;
    }
    (iota, psi)
}

impl ModeTables {
    /// n basis functions (k = n − 1 velocity modes) and m Gauss–Legendre points.
    pub(super) fn new(n: usize, points: usize) -> Result<Self> {
        let rule = QuadratureKind::GaussLegendre.build(points)?;
        let k = n - 1;
        let (iota, psi) = modes_at(&rule.nodes, k);
        let (mut now, mut next, mut scratch) = (vec![0.0; k], vec![0.0; k], vec![0.0; k]);
        let mut extrapolate = vec![0.0; k * k];
        for (&c, &w) in rule.nodes.iter().zip(&rule.weights) {
            legendre_modes(c, &mut now, &mut scratch);
            legendre_modes(1.0 + c, &mut next, &mut scratch);
            for b in 0..k {
                for a in 0..k {
                    extrapolate[b * k + a] += w * now[b] * next[a];
                }
            }
        }
        Ok(ModeTables {
            k,
            nodes: rule.nodes,
            weights: rule.weights,
            iota,
            psi,
            extrapolate,
        })
    }

    /// Number of nodes m.
    pub(super) fn m(&self) -> usize {
        self.nodes.len()
    }
}
