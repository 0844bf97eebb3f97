//! The stage equations in the Legendre modes of the velocity: the same one-step map as the
//! nodal equations of paper eqs. (3)–(4), written in the representation where the kinetic
//! matrix is the identity.
//!
//! For a polynomial space (every built-in basis but Fourier) the Galerkin curve of a step is
//!
//! q(τh) = q_k + h Σ_{a<n−1} c_a I_a(τ),   q̇(τh) = Σ_a c_a P̃_a(τ),   I_a(τ) = ∫_0^τ P̃_a,
//!
//! with P̃_a = √(2a+1) P_a(2τ − 1) the Legendre polynomials orthonormal on [0, 1] and the
//! unknowns c_a (D-vectors, velocity units). The test functions vanishing at τ = 1 are
//! ψ_0 = τ − 1 = I_0 − 1 and ψ_b = I_b (b ≥ 1, which vanish at both ends). For a separable
//! Lagrangian L = ½ vᵀMv − V(q), a quadrature exact to degree 2n − 4 (the kinetic integrand;
//! m ≥ n − 1 Gauss points) makes Σ_j b_j P̃_a(c_j) P̃_b(c_j) = δ_ab, and the stage equations
//! (the discrete Legendre transform p_k = −D₁L_d, eq. (4), combined with the internal stage
//! equations, eq. (3)) become
//!
//! F_b(c) = M c_b + h Σ_j b_j ψ_b(c_j) f(q(c_j)) − δ_b0 p_k = 0,   f = L_q = −∇V,
//!
//! with q_{k+1} = q_k + h c_0 and p_{k+1} = p_k + h Σ_j b_j f_j. There is no kinetic sum at
//! all — the term whose cancellation the nodal residual has to sum in double-double — and the
//! Newton matrix J = I ⊗ M + h² Σ_j b_j ψ(c_j) I(c_j)ᵀ ⊗ H_j is the mass matrix plus an
//! O(h²) term, so a factorisation stays good for many steps and the frozen-Hessian form
//! I ⊗ M + h² C ⊗ H̄ has the Kronecker structure of `kronecker.rs` with
//! C = Σ_j b_j ψ(c_j) I(c_j)ᵀ.
//!
//! It is the nodal map, not an approximation of it: the space, the quadrature and the test
//! space are the same, only their bases differ. The tables below are built only when that
//! can be checked — the rule integrates the kinetic term exactly and the basis reproduces
//! every I_a — and the converged modes are converted to the basis's coefficients for dense
//! output and the next step.
//!
//! Exactly variational in floating point too: the curve at node j uses the table entries
//! ι_ja ≈ I_a(c_j) and the test functions use the same numbers (ψ_jb = ι_jb for b ≥ 1,
//! ψ_j0 = ι_j0 − 1 computed exactly, ι_j0 = c_j being kept on the 2⁻⁵³ grid), so the
//! equations are the exact stationarity conditions of the discrete Lagrangian
//! h[½ Σ_a c_aᵀMc_a − Σ_j b_j V(q_k + h Σ_a ι_ja c_a)] that these tables define.

mod equations;
mod freeze;
mod masked;
mod momentum;
mod solve;
mod state;

pub(crate) use freeze::BlockFreeze;
pub(crate) use solve::FIXED_POINT_HANDOVER;
pub(crate) use state::VelocityState;

use std::sync::OnceLock;

use crate::integrator::Tables;
use crate::integrator::kronecker::KroneckerTables;
use crate::linalg::{PANEL, panel_product};
use crate::quadrature::QuadratureRule;

/// The largest deviation from the identity of the quadrature's Gram matrix of the velocity
/// modes, and from I_a of the basis's interpolant, accepted as "the same map" (the table
/// entries themselves carry rounding errors of a few ulps times n).
const REPRODUCTION_TOLERANCE: f64 = 1e-11;

/// The (basis, quadrature, n)-dependent tables of the velocity form (k = n − 1 modes, m
/// nodes; row-major).
#[derive(Debug, Clone)]
pub(crate) struct VelocityTables {
    /// k = n − 1, the number of velocity modes.
    pub k: usize,
    /// ι_ja = I_a(c_j), m×k (column 0: c_j on the 2⁻⁵³ grid).
    pub iota: Vec<f64>,
    /// ψ_jb, m×k: ι_jb for b ≥ 1, ι_j0 − 1 (exact) for b = 0.
    pub psi: Vec<f64>,
    /// The columns of ι padded to [`PANEL`] nodes (k×PANEL) when m ≤ PANEL, else empty: the
    /// curve at the nodes as one register panel (`velocity_residual`, D ≤ 4).
    pub iota_cols: Vec<f64>,
    /// The rows of ψ padded to [`PANEL`] modes (m×PANEL) when k ≤ PANEL, else empty: the
    /// projections as one register panel.
    pub psi_rows: Vec<f64>,
    /// Extrapolation of the velocity to the next step, k×k: c_next = E c (the previous
    /// step's q̇(τ + 1) projected on the modes, exact for polynomials).
    pub extrapolate: Vec<f64>,
    /// The columns of E, of B (`to_basis`) and of F A⁻¹ (`from_values`) padded to [`PANEL`] rows
    /// (empty when there are more rows): the guess and the step's end as register panels
    /// ([`panel_times`]).
    pub extrapolate_cols: Vec<f64>,
    /// See [`extrapolate_cols`](Self::extrapolate_cols).
    pub to_basis_cols: Vec<f64>,
    /// See [`extrapolate_cols`](Self::extrapolate_cols).
    pub from_values_cols: Vec<f64>,
    /// The basis coefficients of the curve: ΔQ_i = h Σ_a B_ia c_a, n×k (row 0 is zero and
    /// row n − 1 is (1, 0, …, 0), both set exactly).
    pub to_basis: Vec<f64>,
    /// The modes of a curve given by its increments from q_k at the basis's interpolation
    /// nodes (n×D values V): c = (1/h) F A⁻¹ V, k×n, with F the modes of a curve given by its
    /// coefficients ΔQ (c = (1/h) F ΔQ) and A the collocation matrix of the fit (ΔQ = A⁻¹ V):
    /// the RK4 predictor's curve without its n×n solve per coordinate (issue 35: the solves
    /// were 5 % of Kepler's fastest run).
    pub from_values: Vec<f64>,
    /// C = Σ_j b_j ψ(c_j) I(c_j)ᵀ, k×k: the pencil of the frozen Newton matrix.
    pencil: Vec<f64>,
    /// The Schur form of C for the frozen-Hessian solve, built when first asked for
    /// ([`VelocityTables::kron`]).
    kron: OnceLock<Option<KroneckerTables>>,
}

/// P̃_a(τ) for a < len and I_a(τ) for a < len − 1 (with I_0 = τ), from the Legendre
/// recurrence at x = 2τ − 1.
pub(crate) fn legendre_modes(tau: f64, values: &mut [f64], integrals: &mut [f64]) {
    let len = values.len();
    let x = 2.0 * tau - 1.0;
    // P_0 … P_{len−1}
    let (mut p0, mut p1) = (1.0, x);
    let mut p = vec![0.0; len + 1];
    p[0] = 1.0;
    if len > 0 {
        p[1] = x;
    }
    for a in 1..len {
        let next = ((2 * a + 1) as f64 * x * p1 - a as f64 * p0) / (a + 1) as f64;
        p[a + 1] = next;
        (p0, p1) = (p1, next);
    }
    for a in 0..len {
        values[a] = ((2 * a + 1) as f64).sqrt() * p[a];
    }
    for a in 0..integrals.len() {
        integrals[a] = if a == 0 {
            tau
        } else {
            // ∫_0^τ √(2a+1) P_a(2s − 1) ds = (P_{a+1}(x) − P_{a−1}(x)) / (2√(2a+1)).
            (p[a + 1] - p[a - 1]) / (2.0 * ((2 * a + 1) as f64).sqrt())
        };
    }
}

/// The columns of the rows×inner matrix `a` (by rows), each padded to [`PANEL`] entries, for
/// [`panel_times`]; empty when rows > [`PANEL`].
fn panel_columns(a: &[f64], rows: usize, inner: usize) -> Vec<f64> {
    if rows > PANEL {
        return Vec::new();
    }
    let mut cols = vec![0.0; inner * PANEL];
    for i in 0..rows {
        for c in 0..inner {
            cols[c * PANEL + i] = a[i * inner + c];
        }
    }
    cols
}

/// out = α A x for the rows×inner matrix A given as `cols` ([`panel_columns`]) and x (inner×D,
/// by rows) as one register panel, when A has one and D ≤ 4; returns false otherwise (the
/// caller takes `gemm`). Each entry is α times its sum over the inner index in order from
/// zero: `gemm`'s few-column loop with β = 0, bit for bit (up to the sign of an exactly zero
/// entry). Measured (issue 35, callgrind, Kepler n = 13, 500 steps): the 1 121 small products
/// of the guesses and the step's end took 2.35 M instructions through `gemm`, about 2 k each
/// for 300 multiply–adds.
pub(super) fn panel_times(
    cols: &[f64],
    x: &[f64],
    inner: usize,
    rows: usize,
    d: usize,
    alpha: f64,
    out: &mut [f64],
) -> bool {
    fn write<const D: usize>(acc: [[f64; PANEL]; D], rows: usize, alpha: f64, out: &mut [f64]) {
        for (i, row) in out.chunks_exact_mut(D).take(rows).enumerate() {
            for (s, y) in row.iter_mut().enumerate() {
                *y = alpha * acc[s][i];
            }
        }
    }
    if cols.len() != inner * PANEL || rows > PANEL || x.len() < inner * d || out.len() < rows * d {
        return false;
    }
    match d {
        1 => write::<1>(panel_product::<1>(cols, x, inner), rows, alpha, out),
        2 => write::<2>(panel_product::<2>(cols, x, inner), rows, alpha, out),
        3 => write::<3>(panel_product::<3>(cols, x, inner), rows, alpha, out),
        4 => write::<4>(panel_product::<4>(cols, x, inner), rows, alpha, out),
        _ => return false,
    }
    true
}

impl VelocityTables {
    /// Build the tables, or `None` when the velocity form is not the nodal map for this
    /// basis and rule: a rule too weak for the kinetic term, a basis that does not reproduce
    /// the polynomials of degree n − 1 (Fourier), or tables that are not finite.
    pub(crate) fn build(rule: &QuadratureRule, t: &Tables) -> Option<Self> {
        let (n, m) = (t.n, t.m);
        if n < 2 || m == 0 {
            return None;
        }
        let k = n - 1;
        let (mut pt, mut it) = (vec![0.0; m * k], vec![0.0; m * k]);
        for (j, &c) in rule.nodes.iter().enumerate() {
            legendre_modes(c, &mut pt[j * k..(j + 1) * k], &mut it[j * k..(j + 1) * k]);
            // Node on the 2⁻⁵³ grid so that ι_j0 − 1 is exact (Sterbenz above ½, the grid
            // below).
            let snapped = (c * 2f64.powi(53)).round() / 2f64.powi(53);
            it[j * k] = snapped;
        }
        // The rule must integrate the kinetic term exactly: the modes' Gram matrix is I.
        for a in 0..k {
            for b in 0..k {
                let g: f64 = (0..m)
                    .map(|j| rule.weights[j] * pt[j * k + a] * pt[j * k + b])
                    .sum();
                let target = if a == b { 1.0 } else { 0.0 };
                if (g - target).abs() > REPRODUCTION_TOLERANCE || !g.is_finite() {
                    return None;
                }
            }
        }
        // B: the basis coefficients of I_a, fitted at the basis's interpolation nodes …
        let nodes = t.fit.nodes();
        let mut to_basis = vec![0.0; n * k];
        let mut v = vec![0.0; k];
        for (i, &x) in nodes.iter().enumerate() {
            legendre_modes(x, &mut vec![0.0; k], &mut v);
            to_basis[i * k..(i + 1) * k].copy_from_slice(&v);
        }
        t.fit.values_to_coefficients(&mut to_basis, k);
        // … which must reproduce I_a and P̃_a at the quadrature nodes (a polynomial basis).
        for j in 0..m {
            for a in 0..k {
                let (mut value, mut slope) = (0.0, 0.0);
                for i in 0..n {
                    value += t.phi[j * n + i] * to_basis[i * k + a];
                    slope += t.dphi[j * n + i] * to_basis[i * k + a];
                }
                let exact = if a == 0 { rule.nodes[j] } else { it[j * k + a] };
                let ok = (value - exact).abs() <= REPRODUCTION_TOLERANCE
                    && (slope - pt[j * k + a]).abs() <= 1e3 * REPRODUCTION_TOLERANCE;
                if !ok {
                    return None;
                }
            }
        }
        // The curve starts at q_k and ends at q_k + h c_0 (Q_0 and Q_{n−1} are its end
        // values in every built-in basis): checked, then set exactly.
        for a in 0..k {
            let end = if a == 0 { 1.0 } else { 0.0 };
            if to_basis[a].abs() > REPRODUCTION_TOLERANCE
                || (to_basis[(n - 1) * k + a] - end).abs() > REPRODUCTION_TOLERANCE
            {
                return None;
            }
            to_basis[a] = 0.0;
            to_basis[(n - 1) * k + a] = end;
        }
        let mut psi = it.clone();
        for j in 0..m {
            psi[j * k] = it[j * k] - 1.0;
        }
        // C_ba = Σ_j b_j ψ_jb ι_ja, the pencil of the frozen Newton matrix I ⊗ M + h² C ⊗ H̄.
        let mut c = vec![0.0; k * k];
        for j in 0..m {
            let w = rule.weights[j];
            for b in 0..k {
                for a in 0..k {
                    c[b * k + a] += w * psi[j * k + b] * it[j * k + a];
                }
            }
        }
        // E_ba = Σ_j b_j P̃_b(c_j) P̃_a(c_j + 1).
        let mut extrapolate = vec![0.0; k * k];
        let mut shifted = vec![0.0; k];
        for j in 0..m {
            legendre_modes(1.0 + rule.nodes[j], &mut shifted, &mut []);
            for b in 0..k {
                for a in 0..k {
                    extrapolate[b * k + a] += rule.weights[j] * pt[j * k + b] * shifted[a];
                }
            }
        }
        // F_bi = Σ_j b_j P̃_b(c_j) φ_i'(c_j): c = (1/h) F ΔQ.
        let mut from_basis = vec![0.0; k * n];
        for j in 0..m {
            for b in 0..k {
                let wp = rule.weights[j] * pt[j * k + b];
                for i in 0..n {
                    from_basis[b * n + i] += wp * t.dphi[j * n + i];
                }
            }
        }
        // F A⁻¹: the fit's inverse, A⁻¹ = the coefficients of the identity's columns.
        let mut inverse = vec![0.0; n * n];
        for i in 0..n {
            inverse[i * n + i] = 1.0;
        }
        t.fit.values_to_coefficients(&mut inverse, n);
        let mut from_values = vec![0.0; k * n];
        for b in 0..k {
            for l in 0..n {
                let f = from_basis[b * n + l];
                for i in 0..n {
                    from_values[b * n + i] += f * inverse[l * n + i];
                }
            }
        }
        let finite = [&it, &psi, &extrapolate, &to_basis, &from_values]
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite()));
        if !finite {
            return None;
        }
        let mut iota_cols = Vec::new();
        if m <= PANEL {
            iota_cols = vec![0.0; k * PANEL];
            for j in 0..m {
                for a in 0..k {
                    iota_cols[a * PANEL + j] = it[j * k + a];
                }
            }
        }
        let mut psi_rows = Vec::new();
        if k <= PANEL {
            psi_rows = vec![0.0; m * PANEL];
            for j in 0..m {
                psi_rows[j * PANEL..j * PANEL + k].copy_from_slice(&psi[j * k..(j + 1) * k]);
            }
        }
        Some(VelocityTables {
            k,
            iota_cols,
            psi_rows,
            extrapolate_cols: panel_columns(&extrapolate, k, k),
            to_basis_cols: panel_columns(&to_basis, n, k),
            from_values_cols: panel_columns(&from_values, k, n),
            pencil: c,
            kron: OnceLock::new(),
            iota: it,
            psi,
            extrapolate,
            to_basis,
            from_values,
        })
    }

    /// The Schur form of the pencil C for the frozen-Hessian solve, or `None` when it could
    /// not be computed (the velocity form then hands such steps to the nodal solvers). Built
    /// on the first call, when a step first needs the frozen Hessian: runs that the
    /// fixed-point start solves throughout never do.
    pub(crate) fn kron(&self) -> Option<&KroneckerTables> {
        let k = self.k;
        let schur = || {
            let mut identity = vec![0.0; k * k];
            identity.iter_mut().step_by(k + 1).for_each(|x| *x = 1.0);
            KroneckerTables::from_pencil(&self.pencil, &identity, k)
        };
        self.kron.get_or_init(schur).as_ref()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::{Strided, gemm};

    /// `panel_times` gives `gemm`'s bits (β = 0) for every D it takes and both shapes of the
    /// step (fewer and more rows than inner terms), and declines what it cannot take.
    #[test]
    fn panel_times_is_gemm_bit_for_bit() {
        for (rows, inner) in [(12usize, 12usize), (13, 12), (12, 13), (1, 16)] {
            let a: Vec<f64> = (0..rows * inner)
                .map(|i| ((i * 37 % 101) as f64 / 7.0).sin())
                .collect();
            let cols = panel_columns(&a, rows, inner);
            for d in 1..=4 {
                let x: Vec<f64> = (0..inner * d)
                    .map(|i| ((i * 13 % 29) as f64 / 3.0).cos())
                    .collect();
                for alpha in [1.0, 0.4, 1.0 / 0.4] {
                    let mut panel = vec![f64::NAN; rows * d];
                    assert!(panel_times(&cols, &x, inner, rows, d, alpha, &mut panel));
                    let mut plain = vec![0.0; rows * d];
                    let (ra, rd) = (Strided::rows(0, inner), Strided::rows(0, d));
                    gemm(rows, inner, d, alpha, &a, ra, &x, rd, 0.0, &mut plain, rd);
                    for (p, g) in panel.iter().zip(&plain) {
                        assert!(p.to_bits() == g.to_bits() || (*p == 0.0 && *g == 0.0));
                    }
                }
            }
            let mut out = vec![0.0; rows * 5];
            let x = vec![1.0; inner * 5];
            assert!(!panel_times(&cols, &x, inner, rows, 5, 1.0, &mut out));
        }
        assert!(panel_columns(&[0.0; 17], 17, 1).is_empty());
        assert!(!panel_times(&[], &[1.0], 1, 1, 1, 1.0, &mut [0.0]));
    }
}
