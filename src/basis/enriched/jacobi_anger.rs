//! Chebyshev coefficients of sin(xτ) and cos(xτ) on τ ∈ [0, 1], each to full *relative*
//! accuracy, from the Jacobi–Anger expansion. This is what lets the enriched basis remove the
//! polynomial part of its trigonometric functions without cancellation (see the parent module).
//!
//! With s = 2τ − 1 and z = x/2, xτ = z + zs, so
//! sin(xτ) = sin z · cos(zs) + cos z · sin(zs) and cos(xτ) = cos z · cos(zs) − sin z · sin(zs),
//! and (Jacobi–Anger) cos(zs) = J₀(z) + 2 Σ_{k≥1} (−1)^k J_{2k}(z) T_{2k}(s),
//! sin(zs) = 2 Σ_{k≥0} (−1)^k J_{2k+1}(z) T_{2k+1}(s). Every Chebyshev coefficient is therefore
//! a product of one Bessel value and sin z or cos z: no sums, no cancellation. The Bessel
//! values J_0 … J_N come from their power series for z ≤ 2 and from Miller's backward recurrence
//! (the minimal solution, normalised by J₀ + 2 Σ J_{2k} = 1) above, both relatively accurate
//! for the orders j > z where the coefficients are small.

/// J_0(z) … J_nmax(z) for z > 0.
pub(super) fn bessel_j(z: f64, nmax: usize) -> Vec<f64> {
    let mut out = vec![0.0; nmax + 1];
    if z <= 2.0 {
        // J_j(z) = (z/2)^j / j! · Σ_m (−z²/4)^m / (m! (j + 1)_m); the ratio of consecutive
        // terms is at most 1/(j + 1) in size, so the sum loses at most a digit (j = 0).
        let half = 0.5 * z;
        let q = -half * half;
        let mut lead = 1.0;
        for (j, o) in out.iter_mut().enumerate() {
            if j > 0 {
                lead *= half / j as f64;
            }
            if lead == 0.0 {
                break;
            }
            let (mut term, mut sum) = (1.0, 1.0);
            for m in 1..60 {
                term *= q / (m as f64 * (m + j) as f64);
                sum += term;
                if term.abs() <= 1e-17 * sum.abs() {
                    break;
                }
            }
            *o = lead * sum;
        }
        return out;
    }
    // Miller: start well above both nmax and z, recur J_{k−1} = (2k/z) J_k − J_{k+1} downward.
    let start = 2 * ((nmax.max(z.ceil() as usize) + 40 + (z.sqrt() * 6.0) as usize) / 2);
    let (mut next, mut cur) = (0.0f64, 1e-30f64);
    let mut norm = 2.0 * cur; // start is even: its term of J₀ + 2 Σ J_{2k}.
    for k in (1..=start).rev() {
        let prev = (2.0 * k as f64 / z) * cur - next;
        next = cur;
        cur = prev;
        let j = k - 1;
        if j <= nmax {
            out[j] = cur;
        }
        if j > 0 && j.is_multiple_of(2) {
            norm += 2.0 * cur;
        }
        if cur.abs() > 1e250 {
            // Rescale everything kept so far; the smallest entries underflow harmlessly.
            cur *= 1e-250;
            next *= 1e-250;
            norm *= 1e-250;
            out.iter_mut().for_each(|v| *v *= 1e-250);
        }
    }
    norm += cur; // J₀
    out.iter_mut().for_each(|v| *v /= norm);
    out
}

/// The number of Chebyshev coefficients kept for frequency x and polynomial degree p: past
/// order z = x/2 the Bessel values fall super-exponentially (Debye: like
/// exp(−(2/3) d^{3/2} / √z) at order z + d), and d = 20 + 16 z^{1/3} takes them below 1e-18.
pub(super) fn coefficient_count(x: f64, degree: usize) -> usize {
    let z = 0.5 * x;
    (degree + 2).max(z.ceil() as usize) + 20 + (16.0 * z.cbrt()).ceil() as usize
}

/// Chebyshev coefficients a_0 … a_N of f(xτ) on τ ∈ [0, 1] in T_j(2τ − 1): f = cos when
/// `cosine`, else sin.
pub(super) fn chebyshev_coefficients(x: f64, cosine: bool, count: usize) -> Vec<f64> {
    let z = 0.5 * x;
    let j = bessel_j(z, count);
    let (sz, cz) = z.sin_cos();
    // Even orders come from cos(zs), odd ones from sin(zs).
    let (even, odd) = if cosine { (cz, -sz) } else { (sz, cz) };
    j.iter()
        .enumerate()
        .map(|(k, &jk)| {
            let sign = if (k / 2).is_multiple_of(2) { 1.0 } else { -1.0 };
            let weight = if k == 0 { 1.0 } else { 2.0 };
            let f = if k.is_multiple_of(2) { even } else { odd };
            f * sign * weight * jk
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Σ a_j T_j(s) at s by the three-term recurrence.
    fn sum(a: &[f64], s: f64) -> f64 {
        let (mut t0, mut t1) = (1.0, s);
        let mut total = a[0];
        for &c in &a[1..] {
            total += c * t1;
            (t0, t1) = (t1, 2.0 * s * t1 - t0);
        }
        total
    }

    #[test]
    fn bessel_values_against_known_ones() {
        // Abramowitz & Stegun Table 9.1 and 9.4 (10 significant digits).
        let j = bessel_j(1.0, 3);
        assert!((j[0] - 0.765_197_686_6).abs() < 1e-10);
        assert!((j[1] - 0.440_050_585_7).abs() < 1e-10);
        let j = bessel_j(10.0, 20);
        assert!((j[0] + 0.245_935_764_5).abs() < 1e-10);
        assert!((j[1] - 0.043_472_746_17).abs() < 1e-10);
        // J_20(10) = 1.151336925e-5 (relative accuracy in the decaying range).
        assert!((j[20] / 1.151_336_925e-5 - 1.0).abs() < 1e-8);
        // The two branches meet at z = 2 (relative agreement where the values are tiny).
        let (a, b) = (bessel_j(2.0, 30), bessel_j(2.0 + 1e-12, 30));
        for (k, (x, y)) in a.iter().zip(&b).enumerate() {
            assert!((x / y - 1.0).abs() < 1e-9, "J_{k}(2): {x} vs {y}");
        }
    }

    #[test]
    fn expansions_reproduce_sin_and_cos() {
        for x in [1e-6, 0.3, 2.0, 7.5, 50.0, 160.0] {
            for cosine in [false, true] {
                let a = chebyshev_coefficients(x, cosine, coefficient_count(x, 4));
                for k in 0..=40 {
                    let tau = k as f64 / 40.0;
                    let want = if cosine {
                        (x * tau).cos()
                    } else {
                        (x * tau).sin()
                    };
                    let got = sum(&a, 2.0 * tau - 1.0);
                    assert!(
                        (got - want).abs() < 1e-13,
                        "x = {x}, τ = {tau}: {got} vs {want}"
                    );
                }
            }
        }
    }
}
