//! The velocity form's residual on the active blocks' columns only, while the fixed-point
//! iteration has frozen some blocks ([`super::freeze`]).

use super::VelocityTables;
use super::momentum::MomentumRow;
use crate::basis::Basis;
use crate::integrator::{GalerkinIntegrator, Workspace};
use crate::lagrangian::Lagrangian;
use crate::linalg::{Strided, gemm};
use crate::quadrature::Quadrature;

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// [`Self::velocity_residual_general`] on the active blocks' columns only, while the
    /// fixed-point iteration has frozen some blocks ([`super::freeze`]): the curve, the forces
    /// (`Lagrangian::force_at_points_on_blocks`), the projections and the rows of those
    /// columns, the others left as they were. The same operations on each active entry as
    /// the unmasked residual, run by run (a run of columns [a, b) is one strided product);
    /// kept apart from it so that the unmasked residual keeps its flat loops.
    pub(super) fn velocity_residual_on_blocks<L: Lagrangian>(
        &self,
        lag: &L,
        ws: &mut Workspace,
        vt: &VelocityTables,
        p_k: &[f64],
        momentum: MomentumRow,
    ) -> f64 {
        let t = self.tables();
        let (m, k, d, h) = (t.m, vt.k, ws.d, self.step_size());
        let (Some(vs), Some(sep)) = (ws.velocity.as_mut(), ws.separable.as_ref()) else {
            return f64::NAN;
        };
        let (Some(freeze), Some(tiled)) = (vs.freeze.as_ref(), vs.mass_tiled.as_deref()) else {
            return f64::NAN;
        };
        let runs = freeze.runs();
        let rk = Strided::rows(0, k);
        // Columns a … b − 1 of a row-major matrix of D columns.
        let columns = |a: usize| Strided {
            offset: a,
            row_stride: d,
            col_stride: 1,
        };
        // q_j = q_k + (δq_k + h ι_j0 c_0,lo + h Σ_a ι_ja c_a): the small parts first.
        let (origin, origin_lo) = (ws.iterate.origin(), ws.iterate.origin_lo());
        for (j, row) in ws.stage.qj.chunks_exact_mut(d).enumerate() {
            let w = h * vt.iota[j * k];
            for &(a, b) in runs {
                for ((x, &e), &lo) in row[a..b]
                    .iter_mut()
                    .zip(&origin_lo[a..b])
                    .zip(&vs.c0_lo[a..b])
                {
                    *x = e + w * lo;
                }
            }
        }
        for (a, b) in product_runs(runs) {
            let v = columns(a);
            gemm(
                m,
                k,
                b - a,
                h,
                &vt.iota,
                rk,
                &vs.c,
                v,
                1.0,
                &mut ws.stage.qj,
                v,
            );
        }
        for row in ws.stage.qj.chunks_exact_mut(d) {
            for &(a, b) in runs {
                for (x, o) in row[a..b].iter_mut().zip(&origin[a..b]) {
                    *x += o;
                }
            }
        }
        lag.force_at_points_on_blocks(&ws.stage.qj, freeze.active(), &mut ws.stage.lq);
        // h b_j f_j, then Σ_j ψ_jb (h b_j f_j).
        for (j, (s, f)) in ws
            .stage
            .scaled
            .chunks_exact_mut(d)
            .zip(ws.stage.lq.chunks_exact(d))
            .enumerate()
        {
            let w = t.weights[j] * h;
            for &(a, b) in runs {
                for (s, &f) in s[a..b].iter_mut().zip(&f[a..b]) {
                    *s = w * f;
                }
            }
        }
        for (a, b) in product_runs(runs) {
            let v = columns(a);
            let psi_t = Strided::transposed(k);
            gemm(
                k,
                m,
                b - a,
                1.0,
                &vt.psi,
                psi_t,
                &ws.stage.scaled,
                v,
                0.0,
                &mut vs.delta,
                v,
            );
        }
        let (stage, momentum_lo) = (&mut ws.stage, ws.iterate.momentum_lo());
        self.momentum_rows(vt, sep, vs, stage, (p_k, momentum_lo), runs, momentum);
        close_rows_on(runs, tiled, &vs.c, &mut vs.delta, &ws.stage.dd_hi, d)
    }
}

/// The runs of columns for the masked products, a run of 5–7 columns cut into 4 and the
/// rest: `gemm` keeps ≤ 4 columns in registers and takes ≥ 8 as vectors, but 5–7 through its
/// generic loop (the Sun and Mercury of J2000 are 6 columns).
fn product_runs(runs: &[(usize, usize)]) -> impl Iterator<Item = (usize, usize)> + '_ {
    runs.iter().flat_map(|&(a, b)| {
        let cut = if (5..8).contains(&(b - a)) { a + 4 } else { b };
        [(a, cut), (cut, b)].into_iter().filter(|(x, y)| x < y)
    })
}

/// [`close_rows`] on the active columns `runs` only, for a diagonal M (`tiled`, as there;
/// freezing blocks needs one): −F into `delta` (row 0 from `row0`), returns max |F| over
/// those columns (∞ if an entry is not finite).
fn close_rows_on(
    runs: &[(usize, usize)],
    tiled: &[f64],
    c: &[f64],
    delta: &mut [f64],
    row0: &[f64],
    d: usize,
) -> f64 {
    let size = |v: f64| if v.is_nan() { f64::INFINITY } else { v.abs() };
    let mut max = 0.0f64;
    for (row, ((x, c), m)) in delta
        .chunks_exact_mut(d)
        .zip(c.chunks_exact(d))
        .zip(tiled.chunks_exact(d))
        .enumerate()
    {
        for &(a, b) in runs {
            for r in a..b {
                x[r] = if row == 0 {
                    -row0[r]
                } else {
                    -(m[r] * c[r] + x[r])
                };
                max = max.max(size(x[r]));
            }
        }
    }
    max
}
