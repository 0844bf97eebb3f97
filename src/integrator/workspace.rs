//! Reusable buffers for one integrator and one Lagrangian: after construction, a step
//! allocates nothing (unless the Lagrangian's own derivative code does).

use super::GalerkinIntegrator;
use crate::basis::Basis;
use crate::curve::GalerkinCurveRef;
use crate::error::{GviError, Result};
use crate::lagrangian::Lagrangian;
use crate::linalg::Lu;
use crate::quadrature::Quadrature;

/// Work buffers for [`GalerkinIntegrator::step`]; create with
/// [`GalerkinIntegrator::workspace`]. It also remembers the previous step's Galerkin curve,
/// from which the next initial guess is extrapolated.
#[derive(Debug, Clone)]
pub struct Workspace {
    pub(crate) d: usize,
    pub(crate) n: usize,
    /// The step size h of the integrator that made the workspace.
    pub(crate) h: f64,
    /// Present for separable Lagrangians L = ½vᵀMv − V(q).
    pub(crate) separable: Option<Separable>,
    /// The Newton unknowns: increments ΔQ_i = Q_i − u_i q_k, row i (n×D; ΔQ_0 = 0).
    pub(crate) coeffs: Vec<f64>,
    /// q_k, the start of the current step's curve (D).
    pub(crate) base: Vec<f64>,
    /// Low-order parts of the compensated state (q_k + base_err, p_k + p_err), zero unless
    /// the step is taken by `step_compensated`.
    pub(crate) base_err: Vec<f64>,
    pub(crate) p_err: Vec<f64>,
    /// Whether the curve values last evaluated came from `cand` (else `coeffs`).
    pub(crate) curve_from_cand: bool,
    /// Absolute coefficients Q_i of the last completed step (n×D), the public meaning.
    pub(crate) abs: Vec<f64>,
    /// Total impulse h Σ_j b_j L_q(c_j) of the last solved step (D).
    pub(crate) impulse: Vec<f64>,
    /// Its low-order part (the impulse is hi + lo to about twice the working precision).
    pub(crate) impulse_lo: Vec<f64>,
    /// Low-order part of ΔQ_{n−1} accumulated by the Newton corrections.
    pub(crate) last_lo: Vec<f64>,
    /// Previous step's increments and whether they are valid.
    pub(crate) prev: Vec<f64>,
    pub(crate) has_prev: bool,
    /// The last guess competition's winner, its residual, and the steps since it was held.
    pub(crate) guess_winner: Option<super::InitialGuess>,
    pub(crate) guess_reference: f64,
    pub(crate) guess_age: usize,
    /// The stage residual of the coefficients in `coeffs` is already in the workspace (norm).
    pub(crate) residual_ready: Option<f64>,

    /// Force evaluations spent by the RK4 predictor guess in the current step.
    pub(crate) guess_force_evaluations: usize,
    /// Evaluate the curve's velocities at the nodes also for separable Lagrangians.
    pub(crate) need_velocities: bool,
    /// A caller-supplied start for the next step's Newton iteration (absolute coefficients,
    /// n×D) and whether it is pending; see [`Workspace::warm_start`].
    pub(crate) warm: Vec<f64>,
    pub(crate) has_warm: bool,
    /// Candidate guess and the best one so far.
    pub(crate) cand: Vec<f64>,
    pub(crate) best: Vec<f64>,
    /// Curve values and velocities at the quadrature nodes (m×D).
    pub(crate) qj: Vec<f64>,
    pub(crate) vj: Vec<f64>,
    /// L_q and L_v at the quadrature nodes (m×D).
    pub(crate) lq: Vec<f64>,
    pub(crate) lv: Vec<f64>,
    /// L_qq at every node (m×D×D) and the weighted basis table of one Gram product (n×m).
    pub(crate) hall: Vec<f64>,
    /// The system's matrix-free force-Jacobian products replace `hall` in Newton–Krylov's
    /// products (large N-body systems, [`MATRIX_FREE_MIN_DIM`]).
    pub(crate) matrix_free: bool,
    /// `hall` is not at the iterate of the last freeze (which formed only diagonal blocks).
    pub(crate) hall_stale: bool,
    /// Diagonal b×b blocks of the node force Jacobians (m·D·b), when the system provides them
    /// and the frozen-Hessian preconditioner uses only those; empty otherwise.
    pub(crate) hblocks: Vec<f64>,
    pub(crate) gram: Vec<f64>,
    /// One (n−1)×(n−1) block of the Newton matrix.
    pub(crate) block: Vec<f64>,
    /// Second derivatives at one node (D×D each).
    /// Non-separable Lagrangians: L_qq, L_qv, L_vv at every node (m × 3 × D²) and four
    /// D-vectors of scratch, for matrix-free Jacobian products; empty otherwise.
    pub(crate) node_hessians: Vec<f64>,
    pub(crate) jvp_scratch: Vec<f64>,
    pub(crate) hqq: Vec<f64>,
    pub(crate) hqv: Vec<f64>,
    pub(crate) hvv: Vec<f64>,
    /// ∂S/∂Q_a for every a (n×D).
    pub(crate) grad: Vec<f64>,
    /// Weighted forces h b_j L_q(c_j) (m×D).
    pub(crate) scaled: Vec<f64>,
    /// M (Q_b − u_b q_k) for the separable residual (n×D).
    pub(crate) mq: Vec<f64>,
    /// Newton matrix, its factorisation, right-hand side and scratch.
    pub(crate) jac: Vec<f64>,
    pub(crate) lu: Lu,
    /// Whether `lu` factorises a Newton matrix of the initial-value step (reusable).
    pub(crate) lu_valid: bool,
    pub(crate) rhs: Vec<f64>,
    pub(crate) scratch: Vec<f64>,
    /// RK4 predictor: substeps, states at substep ends ((S+1)×2D), stages (4×2D), stage input.
    pub(crate) rk_substeps: usize,
    pub(crate) rk_states: Vec<f64>,
    pub(crate) rk_k: Vec<f64>,
    pub(crate) rk_tmp: Vec<f64>,
    /// Scratch for fitting values to coefficients (n each).
    pub(crate) fit_col: Vec<f64>,
    pub(crate) fit_scratch: Vec<f64>,
    /// A velocity (D) and a small D×D solver for inverse Legendre transforms.
    pub(crate) vel: Vec<f64>,
    pub(crate) small: Lu,
    pub(crate) small_rhs: Vec<f64>,
    /// Double-double accumulators, one pair per coordinate (D each).
    pub(crate) dd_hi: Vec<f64>,
    pub(crate) dd_lo: Vec<f64>,
    pub(crate) small_scratch: Vec<f64>,
    /// Buffers of the Kronecker solver (separable Lagrangians whose tables have a Schur form).
    pub(crate) kron: Option<super::kronecker::KroneckerWork>,
    /// Buffers of the Newton–Krylov solver (present with `kron`).
    pub(crate) krylov: Option<super::krylov::KrylovWork>,
    /// `StageSolver::Auto`'s current rung (1 frozen Hessian, 2 Newton–Krylov; the fixed-point
    /// iteration, rung 0, is never faster than the frozen Hessian in the scaling study and is
    /// left to an explicit choice)
    /// and the solves left before it tries the rung below again.
    pub(crate) auto_level: usize,
    pub(crate) auto_holdoff: usize,
    /// Frozen-Hessian failures of `Auto` in the recent solves, and solves since the last one.
    pub(crate) auto_recent: usize,
    pub(crate) auto_calm: usize,
}

/// The constant kinetic part of a separable Lagrangian.
#[derive(Debug, Clone)]
pub(crate) struct Separable {
    /// M, row-major D×D.
    pub mass: Vec<f64>,
    /// Factorised M, for v = M⁻¹p.
    pub mass_lu: Lu,
    /// (K_ab / h) M for equations a = 0…n−2 and unknowns b = 1…n−1: ((n−1)D)².
    pub kinetic_jacobian: Vec<f64>,
    /// (K_{n−1,b} / h) M for the last row block against every unknown b = 0…n−1: D×(nD),
    /// the kinetic part of ∂S/∂ΔQ_{n−1} for its compensated evaluation, stored by rows as its
    /// nonzero entries only (for a diagonal M, as in N-body, one in D): the values …
    pub kinetic_last: Vec<f64>,
    /// … their columns in 0…nD …
    pub kinetic_last_index: Vec<usize>,
    /// … and where row r starts (D + 1 offsets). Skipping the zeros leaves the compensated
    /// sums bit for bit as they were (a zero product adds exactly nothing).
    pub kinetic_last_start: Vec<usize>,
    /// M's diagonal when M is diagonal.
    pub mass_diagonal: Option<Vec<f64>>,
}

/// Configuration dimension from which Newton–Krylov uses a system's matrix-free force-Jacobian
/// products (N-body: pairwise, O(N²) per node) instead of the node Jacobians (O(D²) memory and
/// work per node). Below it the stored Jacobians are cheaper: one pairwise product costs about
/// as much as forming a node's Jacobian, and GMRES makes several per Newton iteration.
pub const MATRIX_FREE_MIN_DIM: usize = 192;

impl Separable {
    /// x ← M⁻¹ x: a division when M is diagonal (bit for bit what the LU solve of a diagonal
    /// matrix gives, without its O(D²) loops), else the LU solve.
    pub fn solve_mass(&self, x: &mut [f64], scratch: &mut [f64]) {
        match &self.mass_diagonal {
            Some(m) => x.iter_mut().zip(m).for_each(|(v, m)| *v /= m),
            None => self.mass_lu.solve_in_place(x, scratch),
        }
    }
}

impl Workspace {
    pub(crate) fn new<B: Basis, Q: Quadrature, L: Lagrangian>(
        gvi: &GalerkinIntegrator<B, Q>,
        lagrangian: &L,
    ) -> Result<Self> {
        let t = gvi.tables();
        let d = lagrangian.dim();
        if d == 0 {
            return Err(GviError::DimensionMismatch {
                what: "configuration space of the Lagrangian (must be ≥ 1)".into(),
                expected: 1,
                got: 0,
            });
        }
        let (n, m) = (t.n, t.m);
        let nu = (n - 1) * d;
        let separable = match lagrangian.mass_matrix() {
            None => None,
            Some(mass) => {
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
                let mass_lu =
                    Lu::factor(flat.clone(), d).map_err(|_| GviError::InvalidParameter {
                        name: "mass matrix".into(),
                        value: f64::NAN,
                        reason: "singular".into(),
                    })?;
                let h = gvi.step_size();
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
                Some(Separable {
                    mass_diagonal: diagonal.then(|| (0..d).map(|r| flat[r * d + r]).collect()),
                    kinetic_last: kl,
                    kinetic_last_index: kl_index,
                    kinetic_last_start: kl_start,
                    mass: flat,
                    mass_lu,
                    kinetic_jacobian: kj,
                })
            }
        };
        let kron = match (&t.kron, &separable) {
            (Some(kt), Some(sep)) => super::kronecker::KroneckerWork::new(
                kt,
                d,
                &sep.mass,
                lagrangian.coordinate_blocks(),
            ),
            _ => None,
        };
        // Probe with empty slices: a system without the optional kernels answers `false`.
        let matrix_free = d >= MATRIX_FREE_MIN_DIM
            && kron.is_some()
            && lagrangian.force_jacobian_products_at_points(&[], &[], &mut []);
        let hblocks = match (&kron, lagrangian.coordinate_blocks()) {
            (Some(kw), Some(b))
                if kw.block() == b
                    && b < d
                    && lagrangian.force_jacobian_diagonal_blocks_at_points(&[], &mut []) =>
            {
                vec![0.0; m * d * b]
            }
            _ => Vec::new(),
        };
        // Non-separable: the matrix-free Jacobian products keep node Hessians.
        let general = separable.is_none();
        Ok(Workspace {
            matrix_free,
            hall_stale: true,
            hblocks,
            d,
            n,
            h: gvi.step_size(),
            separable,
            coeffs: vec![0.0; n * d],
            base: vec![0.0; d],
            base_err: vec![0.0; d],
            p_err: vec![0.0; d],
            curve_from_cand: false,
            abs: vec![0.0; n * d],
            impulse: vec![0.0; d],
            impulse_lo: vec![0.0; d],
            last_lo: vec![0.0; d],
            prev: vec![0.0; n * d],
            has_prev: false,
            guess_winner: None,
            guess_reference: 0.0,
            guess_age: 0,
            residual_ready: None,
            guess_force_evaluations: 0,
            need_velocities: false,
            warm: vec![0.0; n * d],
            has_warm: false,
            cand: vec![0.0; n * d],
            best: vec![0.0; n * d],
            qj: vec![0.0; m * d],
            vj: vec![0.0; m * d],
            lq: vec![0.0; m * d],
            lv: vec![0.0; m * d],
            hall: vec![0.0; m * d * d],
            gram: vec![0.0; n * m],
            block: vec![0.0; n * n],
            node_hessians: if general {
                vec![0.0; 3 * m * d * d]
            } else {
                Vec::new()
            },
            jvp_scratch: if general {
                vec![0.0; 4 * d]
            } else {
                Vec::new()
            },
            hqq: vec![0.0; d * d],
            hqv: vec![0.0; d * d],
            hvv: vec![0.0; d * d],
            grad: vec![0.0; n * d],
            mq: vec![0.0; n * d],
            scaled: vec![0.0; m * d],
            jac: vec![0.0; nu * nu],
            lu: Lu::with_capacity(nu),
            lu_valid: false,
            rhs: vec![0.0; nu],
            scratch: vec![0.0; nu],
            rk_substeps: gvi.options().predictor_substeps.unwrap_or(n.max(8)),
            rk_states: vec![
                0.0;
                (gvi.options().predictor_substeps.unwrap_or(n.max(8)) + 1) * 2 * d
            ],
            rk_k: vec![0.0; 8 * d],
            rk_tmp: vec![0.0; 2 * d],
            fit_col: vec![0.0; n],
            fit_scratch: vec![0.0; n],
            vel: vec![0.0; d],
            small: Lu::with_capacity(d),
            small_rhs: vec![0.0; d],
            dd_hi: vec![0.0; d],
            dd_lo: vec![0.0; d],
            small_scratch: vec![0.0; d],
            krylov: kron
                .is_some()
                .then(|| super::krylov::KrylovWork::new(n - 1, m, d)),
            kron,
            auto_level: 1,
            auto_holdoff: 0,
            auto_recent: 0,
            auto_calm: 0,
        })
    }

    /// The Galerkin coefficients of the last completed step (n×D, row i = Q_i).
    pub fn coefficients(&self) -> &[f64] {
        &self.abs
    }

    /// The Galerkin curve of the last completed step, starting at time 0 (a workspace does not
    /// know the time of its step: set it with [`GalerkinCurveRef::starting_at`]). All zeros
    /// before the first step.
    pub fn curve(&self) -> GalerkinCurveRef<'_> {
        GalerkinCurveRef::from_parts(&self.abs, self.n, self.d, self.h, 0.0)
    }

    /// Forget the previous step's curve (the next guess will not extrapolate) and any pending
    /// warm start.
    pub fn reset(&mut self) {
        self.has_prev = false;
        self.has_warm = false;
        self.residual_ready = None;
        self.lu_valid = false;
    }

    /// Start the next step's Newton iteration from the given Galerkin coefficients (n×D, row
    /// i = Q_i, in this integrator's basis) instead of choosing among the built-in guesses —
    /// e.g. a curve solved at a lower n and refitted, when an error estimate re-solves the
    /// same step at a higher n. The first row is replaced by the step's q_k. Used by one step
    /// only; if Newton fails from it, the built-in guesses are tried as usual.
    ///
    /// Errors: wrong length or non-finite entries.
    pub fn warm_start(&mut self, coefficients: &[f64]) -> Result<()> {
        crate::error::ensure_len(
            "warm-start coefficients",
            self.n * self.d,
            coefficients.len(),
        )?;
        crate::error::ensure_finite("warm-start coefficients", coefficients)?;
        self.warm.copy_from_slice(coefficients);
        self.has_warm = true;
        Ok(())
    }

    /// Dimension D.
    pub fn dim(&self) -> usize {
        self.d
    }

    /// Whether Newton–Krylov takes the system's matrix-free force-Jacobian products (D at
    /// least [`MATRIX_FREE_MIN_DIM`] and a system that provides them, e.g. N-body from 64
    /// bodies in 3D) instead of forming the node Jacobians.
    pub fn uses_matrix_free_products(&self) -> bool {
        self.matrix_free
    }
}
