//! A fixed-height register panel for the few-column products of a step (k or m ≤ [`PANEL`]
//! rows: the Kepler-like configurations), where loops of run-time length 12 or 13 spend more
//! instructions on their own control than on their multiply–adds.

/// Rows of the panel of [`panel_product`]: a whole column of the result (D ≤ 4 of them) is
/// held in vector registers over the whole sum.
pub(crate) const PANEL: usize = 16;

/// acc[s][i] = Σ_a cols[a][i] x[a][s] for the first `k` columns (each [`PANEL`] long, zero
/// beyond the rows in use) and the k×D right-hand side x (by rows), each sum over a in order
/// from zero — the entries, bit for bit, of the plain i-k-j loop of [`super::gemm`] with
/// β = 0, so callers may switch between the two freely. The fixed length lets the compiler
/// unroll and vectorise along i.
pub(crate) fn panel_product<const D: usize>(
    cols: &[f64],
    x: &[f64],
    k: usize,
) -> [[f64; PANEL]; D] {
    let mut acc = [[0.0f64; PANEL]; D];
    for (col, row) in cols.chunks_exact(PANEL).zip(x.chunks_exact(D)).take(k) {
        let Ok(col) = <&[f64; PANEL]>::try_from(col) else {
            continue;
        };
        for s in 0..D {
            let xs = row[s];
            for (a, &c) in acc[s].iter_mut().zip(col) {
                *a += c * xs;
            }
        }
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panel_product_is_the_plain_loop_bit_for_bit() {
        let (k, m) = (13usize, 11usize);
        let a: Vec<f64> = (0..m * k)
            .map(|i| ((i * 37 % 101) as f64 / 7.0).sin())
            .collect();
        let x: Vec<f64> = (0..k * 2)
            .map(|i| ((i * 13 % 29) as f64 / 3.0).cos())
            .collect();
        let mut cols = vec![0.0; k * PANEL];
        for i in 0..m {
            for c in 0..k {
                cols[c * PANEL + i] = a[i * k + c];
            }
        }
        let acc = panel_product::<2>(&cols, &x, k);
        for i in 0..m {
            for s in 0..2 {
                let mut plain = 0.0;
                for c in 0..k {
                    plain += a[i * k + c] * x[c * 2 + s];
                }
                assert_eq!(acc[s][i].to_bits(), plain.to_bits());
            }
        }
        for s in 0..2 {
            assert!(acc[s][m..].iter().all(|&v| v == 0.0));
        }
    }
}
