//! Converged coordinate blocks frozen inside the velocity form's fixed-point iteration.
//!
//! The fixed-point iteration c ← c + M⁻¹(−F(c)) is Picard's iteration on the stage equations.
//! With a diagonal mass matrix each coordinate block (a body of an N-body system:
//! `Lagrangian::coordinate_blocks`) is corrected from its own rows of F, and the blocks
//! converge at their own rates: about (h ω_i)² per iteration for a body of frequency ω_i.
//! Traced on J2000 at h = 20 d (Legendre n = 12), the outer planets' corrections reach the
//! tolerance after 2–4 iterations, Venus and Earth after 5–6, Mercury after 9–10, while each
//! iteration evaluated all 45 pairs at every node and corrected all 30 coordinates.
//!
//! So each block is tested as the whole iteration is (its correction at most the tolerance
//! times the iterate's scale, or the contraction estimate θ/(1 − θ)·|δ_i| below it), and a
//! block that passes stops being iterated: the residual, the forces
//! (`Lagrangian::force_at_points_on_blocks`) and the correction are evaluated on the active
//! blocks' columns only. A frozen block is not exactly converged where the blocks are coupled:
//! the others' later corrections move its residual by the coupling (a planet's with the
//! Sun's later corrections, at full strength: up to 2.5e-15 of the modes on J2000). So the
//! iteration never ends on a masked correction: once every block is frozen, one correction of
//! all of them follows, and the executor decides on it with the usual tests (and a round-off
//! floor, the slowest block having frozen at its own); if that one does not pass, the step
//! continues without freezing. That confirmation is also the step's finishing pass. The map is
//! therefore the one the unfrozen iteration converges to, within its tolerance.

/// Where a step's fixed-point iteration is in freezing its converged blocks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// Blocks that pass the test stop being iterated.
    Freezing,
    /// Every block was frozen: the next correction is of all of them, and ends freezing.
    Confirming,
    /// No freezing (switched off, not applicable, or after the confirmation).
    Off,
}

/// The per-block convergence state of one step (owned by the velocity form's workspace: no
/// allocation per step).
#[derive(Debug, Clone)]
pub(crate) struct BlockFreeze {
    /// Coordinates per block.
    block: usize,
    /// D, the number of coordinates.
    dim: usize,
    /// Which blocks are iterated.
    active: Vec<bool>,
    /// The active blocks as runs of columns [a, b) (merged where adjacent).
    runs: Vec<(usize, usize)>,
    /// Each block's largest |δ| and |c| in the last correction.
    block_delta: Vec<f64>,
    block_scale: Vec<f64>,
    /// Each column's largest |δ| and |c| over the modes (scratch of [`correct_on_blocks`]).
    column_delta: Vec<f64>,
    column_scale: Vec<f64>,
    /// Each block's largest |δ| in the correction before (∞ before the first).
    previous: Vec<f64>,
    /// The largest |c| over the frozen blocks (which no longer change).
    frozen_scale: f64,
    phase: Phase,
}

impl BlockFreeze {
    /// State for D coordinates in blocks of `block`; `None` for fewer than two blocks.
    pub(crate) fn new(dim: usize, block: usize) -> Option<Self> {
        if block == 0 || !dim.is_multiple_of(block) || dim / block < 2 {
            return None;
        }
        let blocks = dim / block;
        Some(BlockFreeze {
            block,
            dim,
            active: vec![true; blocks],
            runs: Vec::with_capacity(blocks),
            block_delta: vec![0.0; blocks],
            block_scale: vec![0.0; blocks],
            column_delta: vec![0.0; dim],
            column_scale: vec![0.0; dim],
            previous: vec![f64::INFINITY; blocks],
            frozen_scale: 0.0,
            phase: Phase::Off,
        })
    }

    /// A new step: every block active, freezing on (`enabled`) or off.
    pub(crate) fn start(&mut self, enabled: bool) {
        self.activate_all();
        self.previous.iter_mut().for_each(|x| *x = f64::INFINITY);
        self.phase = if enabled { Phase::Freezing } else { Phase::Off };
    }

    fn activate_all(&mut self) {
        self.active.iter_mut().for_each(|x| *x = true);
        self.runs.clear();
        self.runs.push((0, self.dim));
        self.frozen_scale = 0.0;
    }

    /// Whether the residual and correction are evaluated on some blocks only.
    pub(crate) fn masked(&self) -> bool {
        self.phase == Phase::Freezing && self.runs.first() != Some(&(0, self.dim))
    }

    /// Whether the corrections are tested block by block (freezing, or its confirmation).
    pub(crate) fn freezing(&self) -> bool {
        self.phase != Phase::Off
    }

    /// The active blocks (`Lagrangian::force_at_points_on_blocks`).
    pub(crate) fn active(&self) -> &[bool] {
        &self.active
    }

    /// The active columns as runs [a, b).
    pub(crate) fn runs(&self) -> &[(usize, usize)] {
        &self.runs
    }

    /// Stop freezing for the rest of the step (the iteration left the fixed point, or the
    /// confirmation did not pass).
    pub(crate) fn stop(&mut self) {
        if self.phase != Phase::Off {
            self.activate_all();
            self.phase = Phase::Off;
        }
    }

    /// The correction just applied was the confirmation of all blocks: freezing ends.
    pub(crate) fn confirmed(&mut self) -> bool {
        if self.phase == Phase::Confirming {
            self.phase = Phase::Off;
            return true;
        }
        false
    }

    /// The largest |c| over all blocks, from the active blocks' `active_scale`.
    pub(crate) fn scale(&self, active_scale: f64) -> f64 {
        active_scale.max(self.frozen_scale)
    }

    /// After a correction of the active blocks with their maxima in `block_delta` and
    /// `block_scale` ([`correct_on_blocks`]): freeze each block that passes the iteration's
    /// test at `tolerance` × `scale` (|δ_i| ≤ tol, or θ_i < `estimate_below` and θ_i/(1 − θ_i)
    /// |δ_i| ≤ tol, θ_i = |δ_i| / |δ_i|_previous). Once none is left active, the next
    /// correction is of all of them (the confirmation). Returns whether some block is frozen
    /// now, so that the executor must not end the iteration on this correction.
    pub(crate) fn update(&mut self, tolerance: f64, scale: f64, estimate_below: f64) -> bool {
        let tol = tolerance * scale;
        let was_full = !self.masked();
        let mut changed = false;
        for (i, active) in self.active.iter_mut().enumerate() {
            if !*active {
                continue;
            }
            let (delta, previous) = (self.block_delta[i], self.previous[i]);
            self.previous[i] = delta;
            let theta = if previous.is_finite() && previous > 0.0 {
                delta / previous
            } else {
                f64::INFINITY
            };
            let converged =
                delta <= tol || (theta < estimate_below && theta / (1.0 - theta) * delta <= tol);
            if converged {
                *active = false;
                self.frozen_scale = self.frozen_scale.max(self.block_scale[i]);
                changed = true;
            }
        }
        if !changed {
            return self.masked();
        }
        if self.active.iter().all(|a| !a) {
            // All at once from a correction of all of them: that correction is the
            // confirmation, and the executor's own test decides on it.
            self.activate_all();
            self.phase = if was_full {
                Phase::Off
            } else {
                Phase::Confirming
            };
            return !was_full;
        }
        self.runs.clear();
        let block = self.block;
        for (i, _) in self.active.iter().enumerate().filter(|(_, a)| **a) {
            let (a, b) = (i * block, (i + 1) * block);
            match self.runs.last_mut() {
                Some(run) if run.1 == a => run.1 = b,
                _ => self.runs.push((a, b)),
            }
        }
        true
    }

    /// Block `block`'s largest |δ| and |c| in the last correction, for an iteration that
    /// corrects its blocks itself rather than through [`correct_on_blocks`] (the inner
    /// Kepler-adapted step's bodies, `crate::kepler_adapted::InnerKeplerGalerkin`).
    pub(crate) fn record(&mut self, block: usize, delta: f64, scale: f64) {
        self.block_delta[block] = delta;
        self.block_scale[block] = scale;
    }

    /// The active columns and the maxima's buffers, for [`correct_on_blocks`].
    pub(crate) fn maxima_mut(&mut self) -> BlockMaxima<'_> {
        BlockMaxima {
            runs: &self.runs,
            block: self.block,
            block_delta: &mut self.block_delta,
            block_scale: &mut self.block_scale,
            column_delta: &mut self.column_delta,
            column_scale: &mut self.column_scale,
        }
    }
}

/// The active columns of a [`BlockFreeze`] and where [`correct_on_blocks`] leaves each
/// block's largest |δ| and |c|.
pub(crate) struct BlockMaxima<'a> {
    runs: &'a [(usize, usize)],
    block: usize,
    block_delta: &'a mut [f64],
    block_scale: &'a mut [f64],
    column_delta: &'a mut [f64],
    column_scale: &'a mut [f64],
}

impl BlockMaxima<'_> {
    /// Each active block's largest |δ| and |c| from its columns' maxima; returns the largest
    /// over the active blocks.
    fn fold(self) -> (f64, f64) {
        let (mut size, mut scale) = (0.0f64, 0.0f64);
        let fold = |v: &[f64]| v.iter().fold(0.0f64, |acc, &x| acc.max(x));
        for &(a, b) in self.runs {
            for i in a / self.block..b / self.block {
                let cols = i * self.block..(i + 1) * self.block;
                self.block_delta[i] = fold(&self.column_delta[cols.clone()]);
                self.block_scale[i] = fold(&self.column_scale[cols]);
                size = size.max(self.block_delta[i]);
                scale = scale.max(self.block_scale[i]);
            }
        }
        (size, scale)
    }
}

/// The fixed-point correction on the active columns of the k×D iterate: δ = −F/m (`divide`;
/// M = I leaves δ = −F, `tiled` the diagonal of M repeated for every mode), c ← c + δ with
/// row 0 compensated (TwoSum into `c0_lo`, as the unmasked correction), and each active
/// block's largest |δ| and |c| into the maxima's block buffers. Returns the largest |δ| and
/// |c| over the active columns.
///
/// The rows b ≥ 1 run over each run of active columns as one contiguous loop, the maxima
/// kept per column (vectorised), and reduced to the blocks at the end: with the blocks'
/// maxima inside the loop (three coordinates each) it was 9 % of a J2000 run.
pub(crate) fn correct_on_blocks(
    c: &mut [f64],
    c0_lo: &mut [f64],
    delta: &mut [f64],
    tiled: &[f64],
    divide: bool,
    d: usize,
    maxima: BlockMaxima<'_>,
) -> (f64, f64) {
    use crate::integrator::dd::two_sum;
    let runs = maxima.runs;
    let (column_delta, column_scale) = (&mut *maxima.column_delta, &mut *maxima.column_scale);
    let step = |x: f64, m: f64| if divide { x / m } else { x };
    // Row 0, compensated: the columns' maxima start here.
    for &(a, b) in runs {
        for r in a..b {
            let v = step(delta[r], tiled[r]);
            delta[r] = v;
            let (s, e) = two_sum(c[r], v);
            c[r] = s;
            c0_lo[r] += e;
            column_delta[r] = v.abs();
            column_scale[r] = s.abs();
        }
    }
    for ((c, x), m) in c
        .chunks_exact_mut(d)
        .zip(delta.chunks_exact_mut(d))
        .zip(tiled.chunks_exact(d))
        .skip(1)
    {
        for &(a, b) in runs {
            let columns = c[a..b]
                .iter_mut()
                .zip(&mut x[a..b])
                .zip(&m[a..b])
                .zip(column_delta[a..b].iter_mut().zip(&mut column_scale[a..b]));
            for (((c, x), &m), (cd, cs)) in columns {
                let v = step(*x, m);
                *x = v;
                *c += v;
                // Comparisons rather than `f64::max`, whose NaN rule costs a compare and a
                // blend per entry: a NaN here fails the iteration through its residual anyway.
                let (av, ac) = (v.abs(), c.abs());
                *cd = if av > *cd { av } else { *cd };
                *cs = if ac > *cs { ac } else { *cs };
            }
        }
    }
    maxima.fold()
}

/// [`correct_on_blocks`] from −F laid out by coordinate, as the masked residual leaves it
/// ([`super::masked`]: `residual` holds D rows of `kstride` entries, the first k of them the
/// modes, the active rows written): the same
/// operations on each entry, a coordinate's k modes in one contiguous row.
#[allow(clippy::too_many_arguments)]
pub(crate) fn correct_on_rows(
    c: &mut [f64],
    c0_lo: &mut [f64],
    residual: &[f64],
    (k, kstride): (usize, usize),
    tiled: &[f64],
    divide: bool,
    d: usize,
    maxima: BlockMaxima<'_>,
) -> (f64, f64) {
    use crate::integrator::dd::two_sum;
    let runs = maxima.runs;
    let (column_delta, column_scale) = (&mut *maxima.column_delta, &mut *maxima.column_scale);
    const LANES: usize = 8;
    for r in runs.iter().flat_map(|&(a, b)| a..b) {
        // The row's modes divided by m_r in vector lanes (its padding too), then applied
        // one by one: row 0 compensated, rows b ≥ 1 into their strided entries.
        let m = tiled[r];
        let (chunks, _) = residual[r * kstride..(r + 1) * kstride].as_chunks::<LANES>();
        let (mut cd, mut cs) = (0.0f64, 0.0f64);
        for (ch, x) in chunks.iter().enumerate() {
            let v: [f64; LANES] = std::array::from_fn(|l| if divide { x[l] / m } else { x[l] });
            for (l, &v) in v.iter().enumerate() {
                let b = ch * LANES + l;
                if b >= k {
                    break;
                }
                let av = v.abs();
                if b == 0 {
                    let (s, e) = two_sum(c[r], v);
                    c[r] = s;
                    c0_lo[r] += e;
                    (cd, cs) = (av, s.abs());
                    continue;
                }
                let y = &mut c[b * d + r];
                *y += v;
                let ac = y.abs();
                cd = if av > cd { av } else { cd };
                cs = if ac > cs { ac } else { cs };
            }
        }
        column_delta[r] = cd;
        column_scale[r] = cs;
    }
    maxima.fold()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_freeze_one_by_one_then_all_are_confirmed() {
        let mut f = BlockFreeze::new(6, 2).expect("three blocks");
        f.start(true);
        assert!(!f.masked() && f.freezing());
        // Block 1 passes the tolerance: blocks 0 and 2 stay, as two runs.
        f.block_delta.copy_from_slice(&[1e-3, 1e-20, 1e-3]);
        f.block_scale.copy_from_slice(&[1.0, 2.0, 1.0]);
        assert!(f.update(1e-16, 1.0, 0.5));
        assert!(f.masked());
        assert_eq!(f.runs(), &[(0, 2), (4, 6)]);
        assert_eq!(f.active(), &[true, false, true]);
        assert_eq!(f.scale(1.0), 2.0);
        // Block 0 by its contraction estimate (θ = 1e-14: 1e-17·θ/(1 − θ) ≪ 1e-16), block 2
        // not (θ = 0.9).
        f.block_delta[0] = 1e-17;
        f.block_delta[2] = 9e-4;
        assert!(f.update(1e-16, 1.0, 0.5));
        assert_eq!(f.runs(), &[(4, 6)]);
        // The last block freezes: every block is active again for the confirmation, whose
        // correction may end the iteration.
        f.block_delta[2] = 0.0;
        assert!(f.update(1e-16, 1.0, 0.5));
        assert!(!f.masked() && f.freezing());
        assert_eq!(f.runs(), &[(0, 6)]);
        assert!(f.confirmed());
        assert!(!f.freezing() && !f.confirmed());
    }

    #[test]
    fn blocks_converging_together_leave_the_decision_to_the_executor() {
        let mut f = BlockFreeze::new(4, 2).expect("two blocks");
        f.start(true);
        f.block_delta.copy_from_slice(&[1e-20, 0.0]);
        assert!(!f.update(1e-16, 1.0, 0.5));
        assert!(!f.masked() && !f.freezing());
    }

    #[test]
    fn a_single_block_or_a_ragged_split_is_not_frozen() {
        assert!(BlockFreeze::new(3, 3).is_none());
        assert!(BlockFreeze::new(7, 3).is_none());
        assert!(BlockFreeze::new(6, 0).is_none());
    }

    #[test]
    fn the_masked_correction_is_the_unmasked_one_on_its_columns() {
        // k = 2 modes, D = 4 in blocks of 2; only block 1 active.
        let mut c = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        let mut lo = vec![0.0; 4];
        let mut delta = vec![-2.0, -2.0, -0.5, 1.0, 4.0, 4.0, 2.0, -6.0];
        let tiled = vec![2.0, 2.0, 0.5, 0.5, 2.0, 2.0, 0.5, 0.5];
        let (mut bd, mut bs) = (vec![9.0; 2], vec![9.0; 2]);
        let (mut cd, mut cs) = (vec![0.0; 4], vec![0.0; 4]);
        let maxima = BlockMaxima {
            runs: &[(2, 4)],
            block: 2,
            block_delta: &mut bd,
            block_scale: &mut bs,
            column_delta: &mut cd,
            column_scale: &mut cs,
        };
        let (size, scale) = correct_on_blocks(&mut c, &mut lo, &mut delta, &tiled, true, 4, maxima);
        assert_eq!(c, vec![1.0, 2.0, 2.0, 6.0, 5.0, 6.0, 11.0, -4.0]);
        assert_eq!((size, scale), (12.0, 11.0));
        // Block 0 untouched (its stale maxima too), block 1's maxima fresh.
        assert_eq!((bd, bs), (vec![9.0, 12.0], vec![9.0, 11.0]));
    }
}
