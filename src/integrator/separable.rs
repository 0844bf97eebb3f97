//! The constant kinetic part of a separable Lagrangian L = ½ vᵀMv − V(q) (docs/DESIGN.md §2):
//! the mass matrix M, its factorisation for v = M⁻¹p, and the kinetic blocks (K_ab / h) M of
//! the stage equations, which for such Lagrangians do not change from step to step.
//!
//! Built once per (integrator, Lagrangian) by [`Workspace`](super::Workspace); the stage
//! residual, the Newton matrix and the Legendre-transform rows read it. A Lagrangian without
//! a mass matrix (non-separable) has none, and its kinetic terms are evaluated at the nodes
//! like the rest of L.

use super::Tables;
use crate::error::{GviError, Result};
use crate::linalg::Lu;
use nalgebra::DMatrix;

/// The constant kinetic part of a separable Lagrangian.
#[derive(Debug, Clone)]
pub(crate) struct Separable {
    /// M, row-major D×D.
    mass: Vec<f64>,
    /// Factorised M, for v = M⁻¹p.
    mass_lu: Lu,
    /// (K_ab / h) M for equations a = 0…n−2 and unknowns b = 1…n−1: ((n−1)D)².
    kinetic_jacobian: Vec<f64>,
    /// (K_{n−1,b} / h) M for the last row block against every unknown b = 0…n−1: D×(nD),
    /// the kinetic part of ∂S/∂ΔQ_{n−1} for its compensated evaluation, stored by rows as its
    /// nonzero entries only (for a diagonal M, as in N-body, one in D): the values …
    kinetic_last: Vec<f64>,
    /// … their columns in 0…nD …
    kinetic_last_index: Vec<usize>,
    /// … and where row r starts (D + 1 offsets). Skipping the zeros leaves the compensated
    /// sums bit for bit as they were (a zero product adds exactly nothing).
    kinetic_last_start: Vec<usize>,
    /// M's diagonal when M is diagonal.
    mass_diagonal: Option<Vec<f64>>,
    /// M = I: [`Separable::solve_mass`] has nothing to do.
    unit_mass: bool,
}

impl Separable {
    /// The kinetic part for mass matrix `mass` (D×D) with the tables `t` at step size h.
    ///
    /// Errors: a mass matrix of the wrong size, non-finite or singular.
    pub(crate) fn new(mass: &DMatrix<f64>, t: &Tables, d: usize, h: f64) -> Result<Self> {
        let n = t.n;
        let nu = (n - 1) * d;
        if mass.nrows() != d || mass.ncols() != d {
            return Err(GviError::DimensionMismatch {
                what: "mass matrix".into(),
                expected: d,
                got: mass.nrows().max(mass.ncols()),
            });
        }
        let mut flat = vec![0.0; d * d];
        for r in 0..d {
            for s in 0..d {
                flat[r * d + s] = mass[(r, s)];
            }
        }
        crate::error::ensure_finite("mass matrix", &flat)?;
        let mass_lu = Lu::factor(flat.clone(), d).map_err(|_| GviError::InvalidParameter {
            name: "mass matrix".into(),
            value: f64::NAN,
            reason: "singular".into(),
        })?;
        let mut kj = vec![0.0; nu * nu];
        for a in 0..n - 1 {
            for b in 1..n {
                let kab = t.kinetic[a * n + b] / h;
                for r in 0..d {
                    for s in 0..d {
                        kj[(a * d + r) * nu + (b - 1) * d + s] = kab * flat[r * d + s];
                    }
                }
            }
        }
        let (mut kl, mut kl_index, mut kl_start) = (Vec::new(), Vec::new(), vec![0]);
        for r in 0..d {
            for b in 0..n {
                let kab = t.kinetic[(n - 1) * n + b] / h;
                for s in 0..d {
                    let value = kab * flat[r * d + s];
                    if value != 0.0 {
                        kl.push(value);
                        kl_index.push(b * d + s);
                    }
                }
            }
            kl_start.push(kl.len());
        }
        let diagonal = (0..d).all(|r| (0..d).all(|s| r == s || flat[r * d + s] == 0.0));
        let unit_mass = diagonal && (0..d).all(|r| flat[r * d + r] == 1.0);
        Ok(Separable {
            unit_mass,
            mass_diagonal: diagonal.then(|| (0..d).map(|r| flat[r * d + r]).collect()),
            kinetic_last: kl,
            kinetic_last_index: kl_index,
            kinetic_last_start: kl_start,
            mass: flat,
            mass_lu,
            kinetic_jacobian: kj,
        })
    }

    /// M, row-major D×D.
    pub(crate) fn mass(&self) -> &[f64] {
        &self.mass
    }

    /// M's diagonal when M is diagonal (N-body), else `None`.
    pub(crate) fn mass_diagonal(&self) -> Option<&[f64]> {
        self.mass_diagonal.as_deref()
    }

    /// (M x)_r for the first D entries of `x`: M's diagonal entry times x_r when M is
    /// diagonal, else row r of M times x summed in order.
    pub(crate) fn mass_row_times(&self, r: usize, x: &[f64]) -> f64 {
        match &self.mass_diagonal {
            Some(diag) => diag[r] * x[r],
            None => {
                let d = self.mass_lu.dim();
                (0..d).map(|s| self.mass[r * d + s] * x[s]).sum()
            }
        }
    }

    /// The kinetic blocks (K_ab / h) M of the initial-value Newton matrix: ((n−1)D)².
    pub(crate) fn kinetic_jacobian(&self) -> &[f64] {
        &self.kinetic_jacobian
    }

    /// Row r of the last row block's kinetic part (K_{n−1,b} / h) M, as its nonzero entries
    /// and their columns in 0…nD.
    pub(crate) fn kinetic_last_row(&self, r: usize) -> (&[f64], &[usize]) {
        let row = self.kinetic_last_start[r]..self.kinetic_last_start[r + 1];
        (
            &self.kinetic_last[row.clone()],
            &self.kinetic_last_index[row],
        )
    }

    /// x ← M⁻¹ x: a division when M is diagonal (bit for bit what the LU solve of a diagonal
    /// matrix gives, without its O(D²) loops), nothing when M = I (x/1 = x, the same bits:
    /// in Kepler's fastest run the divisions by one inside the RK4 predictor were 4–5 % of
    /// the time), else the LU solve.
    pub(crate) fn solve_mass(&self, x: &mut [f64], scratch: &mut [f64]) {
        if self.unit_mass {
            return;
        }
        match &self.mass_diagonal {
            Some(m) => x.iter_mut().zip(m).for_each(|(v, m)| *v /= m),
            None => self.mass_lu.solve_in_place(x, scratch),
        }
    }
}
