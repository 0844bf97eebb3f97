//! Values at many points laid out by coordinate: the layout of the velocity form's masked
//! residuals ([`crate::Lagrangian::force_at_points_by_coordinate_on_blocks`]).
//!
//! The stage equations keep the curve at the quadrature nodes point by point (m rows of D
//! coordinates). Once most coordinate blocks of the fixed-point iteration have converged, the
//! few that still iterate are better kept coordinate by coordinate: a block's rows are then
//! contiguous, the converged blocks' rows stay where they are between iterations, and a kernel
//! that evaluates the nodes side by side (the N-body forces, eight nodes to a vector) reads
//! and writes whole rows instead of transposing the points on every call.

use std::cell::RefCell;

use crate::scratch::with_scratch;

/// The layout of values at `nodes` points of D coordinates by coordinate: row r, the entries
/// r·`stride` … r·`stride` + `stride` − 1, holds coordinate r at points 0 … `nodes` − 1 and
/// then `stride` − `nodes` entries of padding, which a kernel may read and compute with, and
/// overwrite in the rows it writes (its results there are discarded; the crate fills the
/// padding of the points with copies of the last point).
///
/// A `q` of this layout has at least D·`stride` entries. Implementations index it directly
/// and panic on a shorter slice: a programming error, never a user's data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ByCoordinate {
    /// The number of points.
    pub nodes: usize,
    /// The length of a row (at least `nodes`).
    pub stride: usize,
}

thread_local! {
    /// The points of [`ByCoordinate::through_points`] (2·m·D values): grown on a thread's
    /// first call, reused after (no allocation per step).
    static POINTS: RefCell<Vec<f64>> = const { RefCell::new(Vec::new()) };
}

impl ByCoordinate {
    /// The layout of `nodes` points in rows of `stride` values (`stride` is raised to
    /// `nodes` if smaller).
    pub fn new(nodes: usize, stride: usize) -> Self {
        ByCoordinate {
            nodes,
            stride: stride.max(nodes),
        }
    }

    /// Apply `f` to the `nodes` values of each row of `out` (D = `d` rows) that belongs to a
    /// block marked in `active` (block i: rows i·`block` … i·`block` + `block` − 1).
    pub fn for_active_rows(
        &self,
        d: usize,
        block: usize,
        active: &[bool],
        out: &mut [f64],
        mut f: impl FnMut(&mut [f64]),
    ) {
        let block = block.max(1);
        for (i, _) in active.iter().enumerate().filter(|(_, on)| **on) {
            for r in i * block..((i + 1) * block).min(d) {
                f(&mut out[r * self.stride..r * self.stride + self.nodes]);
            }
        }
    }

    /// Evaluate a point-by-point kernel `eval` (m rows of D values in, the same out) on `q`
    /// of this layout and write the active blocks' rows of its result into `out`: the
    /// default of the by-coordinate evaluations, for systems without a kernel of their own.
    pub(crate) fn through_points(
        &self,
        d: usize,
        block: usize,
        q: &[f64],
        active: &[bool],
        out: &mut [f64],
        eval: impl FnOnce(&[f64], &mut [f64]),
    ) {
        let (m, stride) = (self.nodes, self.stride);
        if m == 0 || d == 0 {
            return;
        }
        with_scratch(&POINTS, 2 * m * d, 0.0, |buf| {
            let (points, values) = buf.split_at_mut(m * d);
            for (r, row) in q.chunks(stride).take(d).enumerate() {
                for (j, &x) in row.iter().take(m).enumerate() {
                    points[j * d + r] = x;
                }
            }
            eval(points, values);
            let block = block.max(1);
            for (i, _) in active.iter().enumerate().filter(|(_, on)| **on) {
                for r in i * block..((i + 1) * block).min(d) {
                    for j in 0..m {
                        out[r * stride + j] = values[j * d + r];
                    }
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn through_points_transposes_in_and_writes_back_only_active_rows() {
        // D = 4 in blocks of 2, 3 points, rows of 4 (one entry of padding).
        let layout = ByCoordinate::new(3, 4);
        let q: Vec<f64> = (0..16).map(f64::from).collect();
        let mut out = vec![-1.0; 16];
        layout.through_points(4, 2, &q, &[false, true], &mut out, |p, o| {
            // Point j's coordinates are q[r·4 + j]; the kernel doubles them.
            assert_eq!(&p[..4], &[0.0, 4.0, 8.0, 12.0]);
            for (o, x) in o.iter_mut().zip(p) {
                *o = 2.0 * x;
            }
        });
        assert_eq!(&out[..8], &[-1.0; 8]);
        assert_eq!(&out[8..], &[16.0, 18.0, 20.0, -1.0, 24.0, 26.0, 28.0, -1.0]);
        let mut rows = 0;
        layout.for_active_rows(4, 2, &[true, false], &mut out, |row| {
            assert_eq!(row.len(), 3);
            rows += 1;
        });
        assert_eq!(rows, 2);
    }
}
