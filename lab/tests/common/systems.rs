//! Small test systems shared by the solver, geometry and allocation tests. Include with
//! `#[path = "common/systems.rs"] mod systems;`.
#![allow(dead_code)]

use galerkin_vi::prelude::*;
use nalgebra::DMatrix;

/// Coupled anharmonic 2-DOF system with a non-diagonal constant mass matrix (the Kronecker
/// solver's M-eigenbasis is then not the coordinate basis).
pub struct Coupled;
impl Mechanical for Coupled {
    fn degrees_of_freedom(&self) -> usize {
        2
    }
    fn mass(&self) -> DMatrix<f64> {
        DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 1.0])
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        q[0] * q[0] * 0.5 + q[1] * q[1] * 0.5 + q[0].powi(4) * 0.1 + q[0] * q[1].powi(3) * 0.3
    }
}

/// Charged particle in a uniform magnetic field B = 1 with an anisotropic quadratic potential,
/// written directly as a `Lagrangian` (non-separable: L_qv ≠ 0, so the structured solvers do
/// not apply; AD derivatives).
pub struct Magnetic;
impl Lagrangian for Magnetic {
    fn dim(&self) -> usize {
        2
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        (v[0] * v[0] + v[1] * v[1]) * 0.5 + (q[0] * v[1] - q[1] * v[0]) * 0.5
            - (q[0] * q[0] + q[1] * q[1] * 2.0) * 0.5
    }
}
