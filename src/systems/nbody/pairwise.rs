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

/// |d|² summed from zero in coordinate order (the run-time loop's bits).
#[inline]
fn squared_norm<const K: usize>(d: &[f64; K]) -> f64 {
    let mut r2 = 0.0;
    for x in d {
        r2 += x * x;
    }
    r2
}
