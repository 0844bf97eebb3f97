//! The pairwise sums of the N-body potential's gradient and of its Hessian's diagonal blocks
//! with the body dimension K ∈ {2, 3} a constant: the two evaluations a step of the velocity
//! form makes at every quadrature node (the forces at every iteration, the blocks once per
//! frozen Hessian).
//!
//! With K known the separation, the pair's factors and the K updates of each body are
//! straight-line code on registers (issue 35's profile of the outer solar system: 1.3 k
//! instructions per node for 15 pairs through the run-time loops over K). Every entry sees
//! the operations of the run-time loops in the same order — body i's running sums are held in
//! registers while j runs, as they were added to in memory — so the results are the same bits.

use std::cell::RefCell;

use crate::by_coordinate::ByCoordinate;
use crate::scratch::with_scratch;

/// ∇V(q) into `out` (N·K): for every pair i < j with d = qᵢ − qⱼ, r² = |d|² and
/// f = G mᵢ mⱼ / r³, out_i += f d and out_j −= f d.
pub(super) fn gradient<const K: usize>(g: f64, masses: &[f64], q: &[f64], out: &mut [f64]) {
    out.iter_mut().for_each(|x| *x = 0.0);
    let nb = masses.len().min(q.len() / K).min(out.len() / K);
    for i in 0..nb {
        let qi: [f64; K] = std::array::from_fn(|c| q[i * K + c]);
        let mut oi: [f64; K] = std::array::from_fn(|c| out[i * K + c]);
        let gmi = g * masses[i];
        for j in i + 1..nb {
            let qj = &q[j * K..j * K + K];
            let d: [f64; K] = std::array::from_fn(|c| qi[c] - qj[c]);
            let r2 = squared_norm(&d);
            let f = gmi * masses[j] / (r2 * r2.sqrt());
            let oj = &mut out[j * K..j * K + K];
            for c in 0..K {
                oi[c] += f * d[c];
                oj[c] -= f * d[c];
            }
        }
        out[i * K..i * K + K].copy_from_slice(&oi);
    }
}

/// Quadrature nodes per lane group of [`gradient_at_points`]: one AVX-512 vector of doubles,
/// two AVX2 vectors.
const LANES: usize = 8;

thread_local! {
    /// The transposed positions and gradients of [`gradient_at_points`] (2·D rows of
    /// [`LANES`]): grown on a thread's first call, reused after (no allocation per step).
    static LANE_SCRATCH: RefCell<Vec<[f64; LANES]>> = const { RefCell::new(Vec::new()) };
}

/// ∇V at every point of `q` (points of D = N·K coordinates, one after another) into `out`,
/// the nodes in groups of [`LANES`] side by side: each group is transposed so that a
/// coordinate's values at the group's nodes are one vector, and for each pair the
/// separations, square roots, divisions and updates of all of them run as vector operations,
/// where [`gradient`] takes one node at a time (issue 35's profile of the outer solar system:
/// the pairwise gradient was 34 % of the run, 15 pairs at each of 10 nodes per residual).
///
/// The same bits as [`gradient`] at each point: every node's separation, r², factor and
/// updates are the same operations in the same order (body b receives −f d from its pairs
/// (i, b), i < b, in increasing i, then +f d from (b, j) in increasing j, body i's sums held
/// while j runs as in [`gradient`]). A group with fewer than [`LANES`] nodes repeats its
/// last node in the spare lanes and discards them.
pub(super) fn gradient_at_points<const K: usize>(
    g: f64,
    masses: &[f64],
    q: &[f64],
    d: usize,
    out: &mut [f64],
) {
    if d == 0 {
        return;
    }
    // Every row the kernel reads it writes first (each group's transposed nodes and zeroed
    // sums), so the buffer's previous contents do not matter.
    let nodes = (q.len() / d).min(out.len() / d);
    with_scratch(&LANE_SCRATCH, 2 * d, [0.0; LANES], |buf| {
        let load = |first, valid, qt: &mut [[f64; LANES]]| transpose_nodes(q, d, first, valid, qt);
        let store = |first, valid, ot: &[[f64; LANES]]| untranspose_nodes(ot, d, first, valid, out);
        gradient_in_lanes::<K, false>(g, masses, d, nodes, &[], buf, load, store)
    });
}

/// [`gradient_at_points`] for the bodies marked in `active` only: the pairs with at least one
/// active body, so that an active body's gradient is the same bits as the full evaluation's
/// (all its pairs, in the same order) and the rows of the others are left unspecified. The
/// velocity form's fixed-point iteration evaluates this once most bodies have converged
/// (`Lagrangian::force_at_points_on_blocks`): on J2000 the slow inner planets iterate on
/// after the outer ones are done, and a pass with Mercury and the Sun active costs 17 of the
/// 45 pairs.
pub(super) fn gradient_at_points_on<const K: usize>(
    g: f64,
    masses: &[f64],
    q: &[f64],
    d: usize,
    active: &[bool],
    out: &mut [f64],
) {
    if d == 0 {
        return;
    }
    let nodes = (q.len() / d).min(out.len() / d);
    with_scratch(&LANE_SCRATCH, 2 * d, [0.0; LANES], |buf| {
        let load = |first, valid, qt: &mut [[f64; LANES]]| transpose_nodes(q, d, first, valid, qt);
        // The active bodies' rows only: the others' sums are not formed.
        let store = |first: usize, valid: usize, ot: &[[f64; LANES]]| {
            for l in 0..valid {
                let node = &mut out[(first + l) * d..][..d];
                for (b, _) in active.iter().enumerate().filter(|(_, on)| **on) {
                    for r in b * K..((b + 1) * K).min(d) {
                        node[r] = ot[r][l];
                    }
                }
            }
        };
        gradient_in_lanes::<K, true>(g, masses, d, nodes, active, buf, load, store)
    });
}

/// [`gradient_at_points_on`] for points laid out by coordinate ([`ByCoordinate`]): each group
/// of [`LANES`] nodes is a slice of every row, copied as one vector (no transposition), and
/// only the active bodies' rows of `out` are written — of each group's nodes, and of the
/// padding after them where the row has room. The same operations in the same order as
/// [`gradient_at_points`], so the active rows are its bits.
pub(super) fn gradient_by_coordinate_on<const K: usize>(
    g: f64,
    masses: &[f64],
    q: &[f64],
    d: usize,
    layout: ByCoordinate,
    active: &[bool],
    out: &mut [f64],
) {
    let (nodes, stride) = (layout.nodes, layout.stride);
    if d == 0 || nodes == 0 {
        return;
    }
    let load = |first: usize, valid: usize, qt: &mut [[f64; LANES]]| {
        for (r, row) in qt.iter_mut().enumerate() {
            let src = &q[r * stride + first..(r + 1) * stride];
            *row = match src.first_chunk::<LANES>() {
                Some(lanes) => *lanes,
                None => std::array::from_fn(|l| src[l.min(valid - 1)]),
            };
        }
    };
    let store = |first: usize, valid: usize, ot: &[[f64; LANES]]| {
        for (b, _) in active.iter().enumerate().filter(|(_, on)| **on) {
            for r in b * K..((b + 1) * K).min(d) {
                let dst = &mut out[r * stride + first..(r + 1) * stride];
                match dst.first_chunk_mut::<LANES>() {
                    Some(lanes) => *lanes = ot[r],
                    None => dst[..valid].copy_from_slice(&ot[r][..valid]),
                }
            }
        }
    };
    with_scratch(&LANE_SCRATCH, 2 * d, [0.0; LANES], |buf| {
        gradient_in_lanes::<K, true>(g, masses, d, nodes, active, buf, load, store)
    });
}

/// The kernel of [`gradient_at_points`] and its variants on its scratch (2·D rows): for each
/// group of [`LANES`] nodes from `first` (`valid` of them), `load` fills the positions' rows,
/// the pairs run in lanes, and `store` takes the gradient's rows. `MASKED`: only the pairs
/// with a body marked in `active`, and only the active bodies' rows zeroed and summed (the
/// others' rows hold anything, and `store` writes the active ones only).
#[allow(clippy::too_many_arguments)]
fn gradient_in_lanes<const K: usize, const MASKED: bool>(
    g: f64,
    masses: &[f64],
    d: usize,
    nodes: usize,
    active: &[bool],
    scratch: &mut [[f64; LANES]],
    mut load: impl FnMut(usize, usize, &mut [[f64; LANES]]),
    mut store: impl FnMut(usize, usize, &[[f64; LANES]]),
) {
    let is_active = |b: usize| !MASKED || active.get(b).copied().unwrap_or(false);
    let nb = masses.len().min(d / K);
    let (qt, ot) = scratch.split_at_mut(d);
    for first in (0..nodes).step_by(LANES) {
        let valid = (nodes - first).min(LANES);
        load(first, valid, qt);
        for (b, rows) in ot.chunks_exact_mut(K).enumerate().take(nb) {
            if is_active(b) {
                rows.iter_mut().for_each(|row| *row = [0.0; LANES]);
            }
        }
        // Past the last active body no pair has one (all pairs when not masked).
        let last = if MASKED {
            (0..nb).rev().find(|&b| is_active(b)).map_or(0, |b| b + 1)
        } else {
            nb
        };
        for i in 0..last {
            let qi: [[f64; LANES]; K] = std::array::from_fn(|c| qt[i * K + c]);
            let mut acc: [[f64; LANES]; K] = std::array::from_fn(|c| ot[i * K + c]);
            let gmi = g * masses[i];
            let i_active = is_active(i);
            for j in i + 1..nb {
                let j_active = is_active(j);
                if !i_active && !j_active {
                    continue;
                }
                let (sep, r2) = separation(&qi, &qt[j * K..(j + 1) * K]);
                let gm = gmi * masses[j];
                let f: [f64; LANES] = std::array::from_fn(|l| gm / (r2[l] * r2[l].sqrt()));
                for (c, row) in sep.iter().enumerate() {
                    let x: [f64; LANES] = std::array::from_fn(|l| f[l] * row[l]);
                    for l in 0..LANES {
                        acc[c][l] += x[l];
                    }
                    if j_active {
                        let oj = &mut ot[j * K + c];
                        for l in 0..LANES {
                            oj[l] -= x[l];
                        }
                    }
                }
            }
            if i_active {
                ot[i * K..i * K + K].copy_from_slice(&acc);
            }
        }
        store(first, valid, ot);
    }
}

thread_local! {
    /// The transposed positions and Hessian blocks of [`hessian_blocks_at_points`] (D + N·K·K
    /// rows of [`LANES`]): grown on a thread's first call, reused after.
    static BLOCK_SCRATCH: RefCell<Vec<[f64; LANES]>> = const { RefCell::new(Vec::new()) };
}

/// [`hessian_diagonal_blocks`] at every point of `q` (points of D = N·K coordinates) into
/// `out` (N·K·K per point), the nodes in groups of [`LANES`] side by side as in
/// [`gradient_at_points`]: the same operations in the same order at each node, so the same
/// bits as node by node. Measured: a J2000 run with the frozen-Hessian solver
/// (`gvi run solar-system --n 12 --h 12.5 --steps 800 --solver kronecker`) 0.142 → 0.138 s;
/// J2000 at n = 14 with a fast body's exact self-block factorised once per step (issue 35,
/// not kept) 3.2 → 2.4 ms for the blocks.
pub(super) fn hessian_blocks_at_points<const K: usize>(
    g: f64,
    masses: &[f64],
    q: &[f64],
    d: usize,
    out: &mut [f64],
) {
    let nb = masses.len().min(d / K);
    if d == 0 || nb == 0 {
        return;
    }
    let per_point = nb * K * K;
    with_scratch(&BLOCK_SCRATCH, d + per_point, [0.0; LANES], |buf| {
        let nodes = (q.len() / d).min(out.len() / per_point);
        let (qt, ht) = buf.split_at_mut(d);
        for first in (0..nodes).step_by(LANES) {
            let valid = (nodes - first).min(LANES);
            transpose_nodes(q, d, first, valid, qt);
            ht.iter_mut().for_each(|row| *row = [0.0; LANES]);
            for i in 0..nb {
                let qi: [[f64; LANES]; K] = std::array::from_fn(|c| qt[i * K + c]);
                let base = i * K * K;
                let mut bi: [[[f64; LANES]; K]; K] =
                    std::array::from_fn(|r| std::array::from_fn(|c| ht[base + r * K + c]));
                let gmi = g * masses[i];
                for j in i + 1..nb {
                    let (sep, r2) = separation(&qi, &qt[j * K..(j + 1) * K]);
                    let gm = gmi * masses[j];
                    let a: [f64; LANES] = std::array::from_fn(|l| gm / (r2[l] * r2[l].sqrt()));
                    let b: [f64; LANES] = std::array::from_fn(|l| 3.0 * a[l] / r2[l]);
                    for r in 0..K {
                        for c in 0..K {
                            let bj = &mut ht[j * K * K + r * K + c];
                            for l in 0..LANES {
                                let e = -b[l] * sep[r][l] * sep[c][l];
                                let e = if r == c { e + a[l] } else { e };
                                bi[r][c][l] += e;
                                bj[l] += e;
                            }
                        }
                    }
                }
                for r in 0..K {
                    for c in 0..K {
                        ht[base + r * K + c] = bi[r][c];
                    }
                }
            }
            untranspose_nodes(ht, per_point, first, valid, out);
        }
    });
}

/// The diagonal K×K blocks of ∇²V(q), body after body, into `out` (N·K·K): every pair adds
/// B = a I − b d dᵀ (a = G mᵢ mⱼ / r³, b = 3a / r²) to the blocks of both bodies.
pub(super) fn hessian_diagonal_blocks<const K: usize>(
    g: f64,
    masses: &[f64],
    q: &[f64],
    out: &mut [f64],
) {
    out.iter_mut().for_each(|x| *x = 0.0);
    let nb = masses.len().min(q.len() / K).min(out.len() / (K * K));
    for i in 0..nb {
        let qi: [f64; K] = std::array::from_fn(|c| q[i * K + c]);
        let base = i * K * K;
        let mut bi: [[f64; K]; K] =
            std::array::from_fn(|r| std::array::from_fn(|s| out[base + r * K + s]));
        let gmi = g * masses[i];
        for j in i + 1..nb {
            let qj = &q[j * K..j * K + K];
            let d: [f64; K] = std::array::from_fn(|c| qi[c] - qj[c]);
            let r2 = squared_norm(&d);
            let a = gmi * masses[j] / (r2 * r2.sqrt());
            let b = 3.0 * a / r2;
            let bj = &mut out[j * K * K..(j + 1) * K * K];
            for r in 0..K {
                for s in 0..K {
                    let e = -b * d[r] * d[s];
                    let e = if r == s { e + a } else { e };
                    bi[r][s] += e;
                    bj[r * K + s] += e;
                }
            }
        }
        for (r, row) in bi.iter().enumerate() {
            out[base + r * K..base + r * K + K].copy_from_slice(row);
        }
    }
}

/// qt[x][l] = coordinate x of node first + l of `q` (nodes of `d` coordinates), the last
/// valid node again in the spare lanes.
#[inline(always)]
fn transpose_nodes(q: &[f64], d: usize, first: usize, valid: usize, qt: &mut [[f64; LANES]]) {
    for l in 0..LANES {
        let node = &q[(first + l.min(valid - 1)) * d..][..d];
        for (row, &v) in qt.iter_mut().zip(node) {
            row[l] = v;
        }
    }
}

/// Rows of `width` values of `out` for the `valid` nodes from `first`, from the lanes of `t`.
#[inline(always)]
fn untranspose_nodes(
    t: &[[f64; LANES]],
    width: usize,
    first: usize,
    valid: usize,
    out: &mut [f64],
) {
    for l in 0..valid {
        let node = &mut out[(first + l) * width..][..width];
        for (o, row) in node.iter_mut().zip(t.iter()) {
            *o = row[l];
        }
    }
}

/// The separation qᵢ − qⱼ of two bodies at each lane's node (`qj`: body j's K rows of the
/// transposed positions) and |qᵢ − qⱼ|² summed from zero in coordinate order (the bits of
/// [`squared_norm`]).
#[inline(always)]
fn separation<const K: usize>(
    qi: &[[f64; LANES]; K],
    qj: &[[f64; LANES]],
) -> ([[f64; LANES]; K], [f64; LANES]) {
    let sep: [[f64; LANES]; K] =
        std::array::from_fn(|c| std::array::from_fn(|l| qi[c][l] - qj[c][l]));
    let mut r2 = [0.0f64; LANES];
    for row in &sep {
        for (r, x) in r2.iter_mut().zip(row) {
            *r += x * x;
        }
    }
    (sep, r2)
}

/// |d|² summed from zero in coordinate order (the run-time loop's bits).
#[inline]
fn squared_norm<const K: usize>(d: &[f64; K]) -> f64 {
    let mut r2 = 0.0;
    for x in d {
        r2 += x * x;
    }
    r2
}
