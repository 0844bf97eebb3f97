//! Matrix-free Newton–Krylov for the stage equations: GMRES on the exact Newton matrix,
//! right-preconditioned by the Kronecker solve of the frozen-Hessian matrix
//! ([`super::kronecker`]).
//!
//! The Newton matrix is never formed. A product J x costs the kinetic part (1/h)(K_s ⊗ M) x,
//! applied as K_s (M x) (O(n²D + nD²)), and the potential part h Σ_j b_j φ(c_j) ⊗ H_j x(c_j):
//! the increment's curve at the nodes (O(mnD)), one force-Jacobian product per node
//! (O(D²) from the node Hessians, which for N-body are the pairwise blocks) and the
//! projection back (O(mnD)); row block 0 is then combined into the Legendre-transform row
//! as [`GalerkinIntegrator::jacobian`](super::GalerkinIntegrator) does. GMRES converges in
//! few iterations when the force Jacobian varies little over the step (the preconditioned
//! matrix is then close to the identity) and in more as the variation grows; either way a
//! Newton iteration costs O(iterations · (mnD + mD²)) instead of an O((nD)³) factorisation.

use super::kronecker::{KroneckerTables, KroneckerWork};
use super::{Tables, Workspace};
use crate::linalg::{Strided, gemm};

/// Largest Krylov subspace per Newton iteration (no restarts: an unconverged solve is an
/// inexact Newton step, and the outer iteration continues from it).
pub(crate) const KRYLOV_DIM: usize = 40;
/// Relative residual at which GMRES stops (the forcing term of the inexact Newton method):
/// small enough that the outer iteration stays quadratic down to the round-off floor in
/// three or four iterations.
pub(crate) const FORCING: f64 = 1e-5;

/// Buffers of the Newton–Krylov solver (allocated once per workspace).
#[derive(Debug, Clone)]
pub(crate) struct KrylovWork {
    size: usize,
    /// Arnoldi basis, (KRYLOV_DIM + 1) × size.
    basis: Vec<f64>,
    /// Hessenberg matrix, (KRYLOV_DIM + 1) × KRYLOV_DIM, row-major.
    hess: Vec<f64>,
    cs: Vec<f64>,
    sn: Vec<f64>,
    g: Vec<f64>,
    y: Vec<f64>,
    w: Vec<f64>,
    tmp: Vec<f64>,
    /// M x per block (k×D), the increment at the nodes and the weighted products there (m×D).
    mx: Vec<f64>,
    node: Vec<f64>,
    node_force: Vec<f64>,
}

impl KrylovWork {
    /// y = J x with this workspace's buffers.
    pub(crate) fn product(&mut self, op: &Operator<'_>, x: &[f64], y: &mut [f64]) {
        op.apply(x, y, &mut self.mx, &mut self.node, &mut self.node_force);
    }

    pub(crate) fn new(k: usize, m: usize, d: usize) -> Self {
        let size = k * d;
        KrylovWork {
            size,
            basis: vec![0.0; (KRYLOV_DIM + 1) * size],
            hess: vec![0.0; (KRYLOV_DIM + 1) * KRYLOV_DIM],
            cs: vec![0.0; KRYLOV_DIM],
            sn: vec![0.0; KRYLOV_DIM],
            g: vec![0.0; KRYLOV_DIM + 1],
            y: vec![0.0; KRYLOV_DIM],
            w: vec![0.0; size],
            tmp: vec![0.0; size],
            mx: vec![0.0; size],
            node: vec![0.0; m * d],
            node_force: vec![0.0; m * d],
        }
    }
}

/// What a product J x needs besides the vectors.
pub(crate) struct Operator<'a> {
    pub t: &'a Tables,
    pub h: f64,
    pub d: usize,
    pub mass: &'a [f64],
    /// M's diagonal when M is diagonal (N-body), for an O(D) product.
    pub mass_diagonal: Option<&'a [f64]>,
    /// Force Jacobians L_qq at the nodes (m × D × D), unless `products` is given.
    pub hall: &'a [f64],
    /// The system's matrix-free products (L_qq(q_j) x_j at every node j, `false` if not
    /// provided) and the nodes q_j they are taken at; used instead of `hall` when set.
    pub products: Option<Products<'a>>,
}

/// y_j = L_qq(q_j) x_j at every node j (q, x, y), `false` when the system has no such kernel.
pub(crate) type ProductKernel<'a> = &'a dyn Fn(&[f64], &[f64], &mut [f64]) -> bool;

/// A system's matrix-free force-Jacobian products at the nodes.
#[derive(Clone, Copy)]
pub(crate) struct Products<'a> {
    pub apply: ProductKernel<'a>,
    pub nodes: &'a [f64],
}

impl Operator<'_> {
    /// y = J x for the initial-value step (x: unknown blocks 1…n−1, y: rows 0…n−2 with row
    /// block 0 the Legendre-transform row).
    fn apply(&self, x: &[f64], y: &mut [f64], mx: &mut [f64], node: &mut [f64], nf: &mut [f64]) {
        let t = self.t;
        let (n, m, d, h) = (t.n, t.m, self.d, self.h);
        let k = n - 1;
        let rd = Strided::rows(0, d);
        // Kinetic part (1/h) K_s (M x).
        match self.mass_diagonal {
            Some(diag) => {
                for (xb, mb) in x.chunks_exact(d).zip(mx.chunks_exact_mut(d)) {
                    for ((m, &a), &b) in mb.iter_mut().zip(diag).zip(xb) {
                        *m = a * b;
                    }
                }
            }
            None => {
                for (xb, mb) in x.chunks_exact(d).zip(mx.chunks_exact_mut(d)) {
                    for r in 0..d {
                        let row = &self.mass[r * d..(r + 1) * d];
                        mb[r] = row.iter().zip(xb).map(|(a, b)| a * b).sum();
                    }
                }
            }
        }
        let ks = Strided {
            offset: 1,
            row_stride: n,
            col_stride: 1,
        };
        gemm(k, k, d, 1.0 / h, &t.kinetic, ks, mx, rd, 0.0, y, rd);
        // Potential part Σ_j h b_j φ_a(c_j) H_j x(c_j).
        let phi_u = Strided {
            offset: 1,
            row_stride: n,
            col_stride: 1,
        };
        gemm(m, k, d, 1.0, &t.phi, phi_u, x, rd, 0.0, node, rd);
        let dd = d * d;
        let pairwise = self
            .products
            .is_some_and(|p| (p.apply)(p.nodes, &node[..m * d], &mut nf[..m * d]));
        if pairwise {
            for (j, row) in nf[..m * d].chunks_exact_mut(d).enumerate() {
                let w = h * t.weights[j];
                row.iter_mut().for_each(|y| *y *= w);
            }
        } else {
            // H_j is a force Jacobian of a separable Lagrangian, −∇²V: symmetric, so H_j x_j
            // is the row (w x_j)ᵀ H_j, summed over H_j's contiguous rows in registers (as D dot
            // products their serial sums bound the loop by latency: 21 % of the 10-body run).
            for j in 0..m {
                let w = h * t.weights[j];
                let (x1, rh) = (Strided::rows(j * d, d), Strided::rows(j * dd, d));
                gemm(1, d, d, w, node, x1, self.hall, rh, 0.0, nf, x1);
            }
        }
        let phi_t = Strided::transposed(n);
        gemm(k, m, d, 1.0, &t.phi, phi_t, nf, rd, 1.0, y, rd);
        // Row block 0 += Σ_{a ≥ 1} u_a (row block a).
        let (first, rest) = y.split_at_mut(d);
        for (a, block) in rest.chunks_exact(d).enumerate() {
            let u = t.unit[a + 1];
            if u != 0.0 {
                for (f, b) in first.iter_mut().zip(block) {
                    *f += u * b;
                }
            }
        }
    }
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// Solve J x = rhs (in place) by right-preconditioned GMRES from x = 0, to a relative
/// residual of [`FORCING`] or [`KRYLOV_DIM`] iterations. Returns the iterations.
pub(crate) fn gmres(
    op: &Operator<'_>,
    kt: &KroneckerTables,
    kw: &mut KroneckerWork,
    kv: &mut KrylovWork,
    rhs: &mut [f64],
) -> usize {
    let size = kv.size;
    let beta = norm(rhs);
    if beta == 0.0 || !beta.is_finite() {
        return 0;
    }
    let KrylovWork {
        basis,
        hess,
        cs,
        sn,
        g,
        y,
        w,
        tmp,
        mx,
        node,
        node_force,
        ..
    } = kv;
    for (v, r) in basis[..size].iter_mut().zip(rhs.iter()) {
        *v = r / beta;
    }
    g.iter_mut().for_each(|x| *x = 0.0);
    g[0] = beta;
    let kd = KRYLOV_DIM;
    let mut steps = 0;
    for i in 0..kd {
        tmp.copy_from_slice(&basis[i * size..(i + 1) * size]);
        kw.solve(kt, op.h, tmp);
        op.apply(tmp, w, mx, node, node_force);
        // Modified Gram–Schmidt.
        for j in 0..=i {
            let vj = &basis[j * size..(j + 1) * size];
            let hij: f64 = vj.iter().zip(w.iter()).map(|(a, b)| a * b).sum();
            hess[j * kd + i] = hij;
            for (x, v) in w.iter_mut().zip(vj) {
                *x -= hij * v;
            }
        }
        let hn = norm(w);
        hess[(i + 1) * kd + i] = hn;
        if hn > 0.0 {
            for (v, x) in basis[(i + 1) * size..(i + 2) * size]
                .iter_mut()
                .zip(w.iter())
            {
                *v = x / hn;
            }
        }
        // Previous Givens rotations on the new column, then a new one.
        for j in 0..i {
            let (a, b) = (hess[j * kd + i], hess[(j + 1) * kd + i]);
            hess[j * kd + i] = cs[j] * a + sn[j] * b;
            hess[(j + 1) * kd + i] = -sn[j] * a + cs[j] * b;
        }
        let (a, b) = (hess[i * kd + i], hess[(i + 1) * kd + i]);
        let r = a.hypot(b);
        (cs[i], sn[i]) = if r == 0.0 { (1.0, 0.0) } else { (a / r, b / r) };
        hess[i * kd + i] = r;
        hess[(i + 1) * kd + i] = 0.0;
        g[i + 1] = -sn[i] * g[i];
        g[i] *= cs[i];
        steps = i + 1;
        if g[i + 1].abs() <= FORCING * beta || hn == 0.0 || !g[i + 1].is_finite() {
            break;
        }
    }
    // y = H⁻¹ g (upper triangular), x = P⁻¹ (V y).
    for i in (0..steps).rev() {
        let mut s = g[i];
        for j in i + 1..steps {
            s -= hess[i * kd + j] * y[j];
        }
        let hii = hess[i * kd + i];
        y[i] = if hii != 0.0 { s / hii } else { 0.0 };
    }
    rhs.iter_mut().for_each(|x| *x = 0.0);
    for (j, &yj) in y[..steps].iter().enumerate() {
        for (x, v) in rhs.iter_mut().zip(&basis[j * size..(j + 1) * size]) {
            *x += yj * v;
        }
    }
    kw.solve(kt, op.h, rhs);
    steps
}

/// The workspace parts an [`Operator`] borrows.
pub(crate) struct Operands<'a> {
    pub mass: &'a [f64],
    pub mass_diagonal: Option<&'a [f64]>,
    pub hall: &'a [f64],
    /// The curve at the nodes, when the products are matrix-free (`Workspace::matrix_free`).
    pub matrix_free_nodes: Option<&'a [f64]>,
}

impl<'a> Operands<'a> {
    /// The operator J x of a step of size h, with the system's matrix-free products `apply`
    /// used when the workspace chose them.
    pub(crate) fn operator(
        self,
        t: &'a Tables,
        h: f64,
        d: usize,
        apply: ProductKernel<'a>,
    ) -> Operator<'a> {
        Operator {
            t,
            h,
            d,
            mass: self.mass,
            mass_diagonal: self.mass_diagonal,
            hall: self.hall,
            products: self
                .matrix_free_nodes
                .map(|nodes| Products { apply, nodes }),
        }
    }
}

impl Workspace {
    /// The Newton–Krylov buffers, if this workspace has them.
    pub(crate) fn krylov_parts(
        &mut self,
    ) -> Option<(
        &mut KroneckerWork,
        &mut KrylovWork,
        Operands<'_>,
        &mut [f64],
    )> {
        let sep = self.separable.as_ref()?;
        let (kw, kv, rhs) = self.system.krylov_mut()?;
        let operands = Operands {
            mass: sep.mass(),
            mass_diagonal: sep.mass_diagonal(),
            hall: &self.stage.hall,
            matrix_free_nodes: self.matrix_free.then_some(&self.stage.qj[..]),
        };
        Some((kw, kv, operands, rhs))
    }
}
