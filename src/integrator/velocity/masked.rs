//! The velocity form's residual on the active blocks only, while the fixed-point iteration has
//! frozen some blocks ([`super::freeze`]), with the curve and the forces laid out by
//! coordinate ([`ByCoordinate`]).
//!
//! Once most blocks have converged (on J2000: everything but Mercury and the Sun, for about
//! seven of a step's ten residuals) a residual's work should scale with the active columns.
//! In the point-by-point layout of the unmasked residual it did not: each masked residual
//! transposed all D coordinates at the m nodes into the force kernel's lanes and back, and
//! its products and passes ran over short strided runs of columns (issue 35's timing: 1.80 µs
//! for a masked residual on 6 of 30 columns against 2.47 µs for all of them). Here the
//! converged blocks' rows stay in place between iterations — filled once from the last
//! unmasked residual's curve — and only the active rows are recomputed: each a contiguous row
//! of the curve at the nodes (the small parts, then Σ_a (h ι_ja) c_a,r over the rows of h ιᵀ),
//! of the forces, and of the residual (its k modes). Every entry sees the operations of the
//! unmasked residual in the same order, so the iteration is the same. (The masked products
//! before summed runs of fewer than eight columns from zero instead; against them the maps
//! are the same bits in 332 of the 344 same-maps cases and within 2.5e-14 in the others:
//! docs/solvers.md.)

use super::VelocityTables;
use super::momentum::{MomentumRow, momentum_row, rounded_momentum_row};
use crate::basis::Basis;
use crate::by_coordinate::ByCoordinate;
use crate::integrator::dd::{dd_acc, two_sum};
use crate::integrator::{GalerkinIntegrator, Workspace};
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;

/// Nodes per vector of the by-coordinate rows: rows are padded to a multiple of this, so that
/// a kernel reads and writes whole vectors.
const LANES: usize = 8;

/// The by-coordinate buffers of the masked residual (owned by the velocity form's state:
/// nothing is allocated per step).
#[derive(Debug, Clone)]
pub(crate) struct MaskedRows {
    /// m nodes in rows padded to a multiple of [`LANES`].
    layout: ByCoordinate,
    /// ιᵀ (k rows of the padded length; row a: ι_ja at the nodes, the last node's value in the
    /// padding, so that the padding lanes hold the curve at the last node).
    iota_t: Vec<f64>,
    /// h ιᵀ for the step size `scaled_for` (the coefficients the product multiplies the modes
    /// by), refreshed when h changes.
    h_iota_t: Vec<f64>,
    scaled_for: f64,
    /// The curve at the nodes by coordinate (D rows).
    q: Vec<f64>,
    /// The forces at the nodes by coordinate (D rows; the active ones written).
    f: Vec<f64>,
    /// The rows of ψ (m of them) padded with zeros to `kstride` modes.
    psi_pad: Vec<f64>,
    /// k rounded up to a multiple of [`LANES`].
    kstride: usize,
    /// −F of each coordinate's k modes (D rows of `kstride`; the active ones written).
    residual: Vec<f64>,
    /// `q` holds every coordinate's curve as of the last residual it was active in (filled
    /// from the unmasked residual's curve on the first masked residual after it).
    current: bool,
    /// The last residual was this one, in `residual`: the correction reads it there.
    holds_residual: bool,
}

impl MaskedRows {
    /// Buffers for the tables `vt` (m nodes, k modes) and D coordinates.
    pub(crate) fn new(vt: &VelocityTables, d: usize) -> Self {
        let k = vt.k.max(1);
        let m = vt.iota.len() / k;
        let stride = m.div_ceil(LANES).max(1) * LANES;
        let mut iota_t = vec![0.0; k * stride];
        for (a, row) in iota_t.chunks_exact_mut(stride).enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = vt.iota[j.min(m.saturating_sub(1)) * k + a];
            }
        }
        let kstride = k.div_ceil(LANES) * LANES;
        let mut psi_pad = vec![0.0; m * kstride];
        for (row, psi) in psi_pad
            .chunks_exact_mut(kstride)
            .zip(vt.psi.chunks_exact(k))
        {
            row[..k].copy_from_slice(psi);
        }
        MaskedRows {
            layout: ByCoordinate::new(m, stride),
            h_iota_t: vec![0.0; iota_t.len()],
            scaled_for: f64::NAN,
            iota_t,
            q: vec![0.0; d * stride],
            f: vec![0.0; d * stride],
            psi_pad,
            kstride,
            residual: vec![0.0; d * kstride],
            current: false,
            holds_residual: false,
        }
    }

    /// An unmasked residual was evaluated: the rows are stale, the correction reads its own.
    pub(crate) fn forget(&mut self) {
        self.current = false;
        self.holds_residual = false;
    }

    /// Whether the last residual was the masked one (its −F is in [`Self::residual`]).
    pub(crate) fn holds_residual(&self) -> bool {
        self.holds_residual
    }

    /// −F of the active coordinates: D rows of [`Self::kstride`] entries, the first k of
    /// them the modes.
    pub(crate) fn residual(&self) -> &[f64] {
        &self.residual
    }

    /// The length of a row of [`Self::residual`].
    pub(crate) fn kstride(&self) -> usize {
        self.kstride
    }
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// [`Self::velocity_residual`] on the active blocks only, while the fixed-point iteration
    /// has frozen some blocks: the curve, the forces
    /// (`Lagrangian::force_at_points_by_coordinate_on_blocks`) and −F of the active
    /// coordinates, row by row (module docs); returns max |F| over them.
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
        let Some(vs) = ws.velocity.as_mut() else {
            return f64::NAN;
        };
        let (Some(sep), Some(freeze), Some(tiled), Some(rows)) = (
            ws.separable.as_ref(),
            vs.freeze.as_ref(),
            vs.mass_tiled.as_deref(),
            vs.masked.as_mut(),
        ) else {
            return f64::NAN;
        };
        let stride = rows.layout.stride;
        if !rows.current {
            // The unmasked residual's curve, transposed once (the padding: the last node).
            for (j, point) in ws.stage.qj.chunks_exact(d).take(m).enumerate() {
                for (x, &v) in rows.q.iter_mut().skip(j).step_by(stride).zip(point) {
                    *x = v;
                }
            }
            for row in rows.q.chunks_exact_mut(stride) {
                let last = row[m - 1];
                row[m..].iter_mut().for_each(|x| *x = last);
            }
            rows.current = true;
        }
        if rows.scaled_for != h {
            for (x, &i) in rows.h_iota_t.iter_mut().zip(&rows.iota_t) {
                *x = h * i;
            }
            rows.scaled_for = h;
        }
        let (origin, origin_lo) = (ws.iterate.origin(), ws.iterate.origin_lo());
        let runs = freeze.runs();
        let chunks = stride / LANES;
        let (iota_t, _) = rows.iota_t.as_chunks::<LANES>();
        let (h_iota_t, _) = rows.h_iota_t.as_chunks::<LANES>();
        for r in runs.iter().flat_map(|&(a, b)| a..b) {
            // q_j = q_k + (δq_k + h ι_j0 c_0,lo + Σ_a (h ι_ja) c_a): the small parts first,
            // then the modes added in order, as the unmasked residual's product adds them,
            // whole vectors of nodes at a time.
            let (row, _) = rows.q[r * stride..(r + 1) * stride].as_chunks_mut::<LANES>();
            let (o, lo, c0) = (origin[r], origin_lo[r], vs.c0_lo[r]);
            let small = |i0: &[f64; LANES]| std::array::from_fn(|l| lo + (h * i0[l]) * c0);
            let modes = |a: usize| vs.c[a * d + r];
            let rows = CurveRow {
                small,
                modes,
                h_iota_t,
                iota_t,
                k,
                o,
            };
            match chunks {
                1 => rows.fill::<1>(row),
                2 => rows.fill::<2>(row),
                3 => rows.fill::<3>(row),
                _ => rows.fill_any(row),
            }
        }
        lag.force_at_points_by_coordinate_on_blocks(
            &rows.q,
            rows.layout,
            freeze.active(),
            &mut rows.f,
        );
        let momentum_lo = ws.iterate.momentum_lo();
        let kstride = rows.kstride;
        let (psi, _) = rows.psi_pad.as_chunks::<LANES>();
        for r in runs.iter().flat_map(|&(a, b)| a..b) {
            // Σ_j ψ_jb (h b_j f_j), summed over j from zero as the unmasked projection.
            let f = &rows.f[r * stride..r * stride + m];
            let (res, _) = rows.residual[r * kstride..(r + 1) * kstride].as_chunks_mut::<LANES>();
            let scaled = |j: usize| (t.weights[j] * h) * f[j];
            match kstride / LANES {
                1 => project_row::<1>(scaled, psi, m, res),
                2 => project_row::<2>(scaled, psi, m, res),
                3 => project_row::<3>(scaled, psi, m, res),
                _ => project_row_any(scaled, psi, m, res),
            }
        }
        // Row 0, the momentum condition (`super::momentum`), of up to eight coordinates side
        // by side; then rows b ≥ 1, M c_b plus the projections.
        let rows0 = MomentumRows0 {
            sep,
            c: &vs.c,
            c0_lo: &vs.c0_lo,
            p_k,
            momentum_lo,
            weights: &t.weights,
            psi: &vt.psi,
            k,
            h,
            forces: &rows.f,
            stride,
        };
        for &(a, b) in runs {
            let mut r0 = a;
            while r0 < b {
                // Eight lanes for five or more coordinates (the spare lanes sum a neighbour's
                // row again and are not stored): one pass of independent chains.
                r0 += match b - r0 {
                    5.. => rows0.fill::<8>(r0, b, momentum, &mut rows.residual, kstride),
                    3 | 4 => rows0.fill::<4>(r0, b, momentum, &mut rows.residual, kstride),
                    2 => rows0.fill::<2>(r0, b, momentum, &mut rows.residual, kstride),
                    _ => rows0.fill::<1>(r0, b, momentum, &mut rows.residual, kstride),
                };
            }
        }
        // Rows b ≥ 1: −(M c_b + projection); then max |F| over each row in vector lanes (its
        // padding holds zeros: ψ is padded with zeros).
        let mut lanes = [0.0f64; LANES];
        for r in runs.iter().flat_map(|&(a, b)| a..b) {
            let row = &mut rows.residual[r * kstride..(r + 1) * kstride];
            let mass = tiled[r];
            for (b, x) in row[..k].iter_mut().enumerate().skip(1) {
                *x = -(mass * vs.c[b * d + r] + *x);
            }
            let (chunks, _) = row.as_chunks::<LANES>();
            for x in chunks {
                lanes = std::array::from_fn(|l| {
                    let v = if x[l].is_nan() {
                        f64::INFINITY
                    } else {
                        x[l].abs()
                    };
                    if v > lanes[l] { v } else { lanes[l] }
                });
            }
        }
        let max = lanes.iter().fold(0.0f64, |a, &b| a.max(b));
        rows.holds_residual = true;
        max
    }
}

/// What one coordinate's row of the curve at the nodes is made of: the small parts
/// δq_k + h ι_j0 c_0,lo (`small`, from a vector of ι_·0), the modes c_a,r (`modes`), the rows
/// of h ιᵀ and ιᵀ (k rows of vectors each) and q_k,r (`o`).
struct CurveRow<'a, S, M> {
    small: S,
    modes: M,
    h_iota_t: &'a [[f64; LANES]],
    iota_t: &'a [[f64; LANES]],
    k: usize,
    o: f64,
}

impl<S: Fn(&[f64; LANES]) -> [f64; LANES], M: Fn(usize) -> f64> CurveRow<'_, S, M> {
    /// The row (`C` vectors): the small parts, then Σ_a (h ι_ja) c_a,r added for a ascending,
    /// as the unmasked residual's product (`gemm`) adds them, then q_k — in registers, one
    /// store.
    #[inline(always)]
    fn fill<const C: usize>(&self, row: &mut [[f64; LANES]]) {
        let mut acc: [[f64; LANES]; C] = std::array::from_fn(|c| (self.small)(&self.iota_t[c]));
        for (a, it) in self.h_iota_t.chunks_exact(C).take(self.k).enumerate() {
            let x = (self.modes)(a);
            for (acc, it) in acc.iter_mut().zip(it) {
                *acc = std::array::from_fn(|l| acc[l] + it[l] * x);
            }
        }
        for (q, acc) in row.iter_mut().zip(&acc) {
            *q = std::array::from_fn(|l| acc[l] + self.o);
        }
    }

    /// [`Self::fill`] for rows of any length (the sums in memory).
    fn fill_any(&self, row: &mut [[f64; LANES]]) {
        let c = row.len();
        for (q, i0) in row.iter_mut().zip(self.iota_t) {
            *q = (self.small)(i0);
        }
        for (a, it) in self.h_iota_t.chunks_exact(c).take(self.k).enumerate() {
            let x = (self.modes)(a);
            for (q, it) in row.iter_mut().zip(it) {
                *q = std::array::from_fn(|l| q[l] + it[l] * x);
            }
        }
        for q in row.iter_mut() {
            *q = std::array::from_fn(|l| q[l] + self.o);
        }
    }
}

/// The projections Σ_j ψ_jb g_j of one coordinate (`scaled(j)` = h b_j f_j; `psi`: the rows
/// of ψ padded to `C` vectors), summed over j from zero, the row's `C` vectors in registers.
#[inline(always)]
fn project_row<const C: usize>(
    scaled: impl Fn(usize) -> f64,
    psi: &[[f64; LANES]],
    m: usize,
    res: &mut [[f64; LANES]],
) {
    let mut acc = [[0.0f64; LANES]; C];
    for (j, p) in psi.chunks_exact(C).take(m).enumerate() {
        let g = scaled(j);
        for (acc, p) in acc.iter_mut().zip(p) {
            *acc = std::array::from_fn(|l| acc[l] + p[l] * g);
        }
    }
    res[..C].copy_from_slice(&acc);
}

/// [`project_row`] for rows of any length (the sums in memory).
fn project_row_any(
    scaled: impl Fn(usize) -> f64,
    psi: &[[f64; LANES]],
    m: usize,
    res: &mut [[f64; LANES]],
) {
    let c = res.len();
    res.iter_mut().for_each(|x| *x = [0.0; LANES]);
    for (j, p) in psi.chunks_exact(c).take(m).enumerate() {
        let g = scaled(j);
        for (x, p) in res.iter_mut().zip(p) {
            *x = std::array::from_fn(|l| x[l] + p[l] * g);
        }
    }
}

/// Row 0 of the masked residual, the momentum condition, from the forces by coordinate: what
/// `MomentumRows` sums from the forces point by point, the same operations in the same order.
struct MomentumRows0<'a> {
    sep: &'a crate::integrator::separable::Separable,
    c: &'a [f64],
    c0_lo: &'a [f64],
    p_k: &'a [f64],
    momentum_lo: &'a [f64],
    weights: &'a [f64],
    psi: &'a [f64],
    k: usize,
    h: f64,
    forces: &'a [f64],
    stride: usize,
}

impl MomentumRows0<'_> {
    /// −F_0 of coordinates r0 … min(r0 + L, `end`) − 1 into entry 0 of their rows of
    /// `residual` (rows of `kstride`, whose entry 0 holds the force terms' projection);
    /// returns how many. Compensated:
    /// (hi, lo) from `momentum_row`, the force terms added in double-double with the L sums
    /// side by side (independent chains hide each other's latency).
    fn fill<const L: usize>(
        &self,
        r0: usize,
        end: usize,
        momentum: MomentumRow,
        residual: &mut [f64],
        kstride: usize,
    ) -> usize {
        // Lane l sums row r0 + l, or the run's last row again where there is none.
        let row = |l: usize| (r0 + l).min(end - 1);
        let row0: [f64; L] = match momentum {
            MomentumRow::Rounded => std::array::from_fn(|l| {
                let r = row(l);
                rounded_momentum_row(self.sep, self.c, self.p_k, residual[r * kstride], r)
            }),
            MomentumRow::Compensated => {
                let mut hi = [0.0f64; L];
                let mut lo = [0.0f64; L];
                let r: [usize; L] = std::array::from_fn(row);
                match self.sep.mass_diagonal() {
                    // `momentum_row`'s operations for a diagonal M, the lanes side by side.
                    Some(diag) => {
                        let m: [f64; L] = std::array::from_fn(|l| diag[r[l]]);
                        for l in 0..L {
                            dd_acc(&mut hi[l], &mut lo[l], m[l], self.c[r[l]]);
                            lo[l] += m[l] * self.c0_lo[r[l]];
                        }
                        for l in 0..L {
                            let (s, e) = two_sum(hi[l], -self.p_k[r[l]]);
                            (hi[l], lo[l]) = (s, lo[l] + (e - self.momentum_lo[r[l]]));
                        }
                    }
                    None => {
                        for l in 0..L {
                            (hi[l], lo[l]) = momentum_row(
                                self.sep,
                                self.c,
                                self.c0_lo,
                                self.p_k,
                                self.momentum_lo,
                                r[l],
                            );
                        }
                    }
                }
                let rows: [usize; L] = std::array::from_fn(|l| r[l] * self.stride);
                for (j, &b) in self.weights.iter().enumerate() {
                    let (w, psi0) = (b * self.h, self.psi[j * self.k]);
                    for l in 0..L {
                        let f = self.forces[rows[l] + j];
                        let g = w * f;
                        dd_acc(&mut hi[l], &mut lo[l], psi0, g);
                        lo[l] += psi0 * w.mul_add(f, -g);
                    }
                }
                std::array::from_fn(|l| hi[l] + lo[l])
            }
        };
        let stored = L.min(end - r0);
        for (l, &x) in row0.iter().enumerate().take(stored) {
            residual[(r0 + l) * kstride] = -x;
        }
        stored
    }
}
