//! The Stumpff functions c₀ … c₅ and the universal functions G_k(X, β) = X^k c_k(βX²) of the
//! [Kepler drift](super::drift), with their β-derivatives: evaluated to about 1e-15 relative and
//! without bias (the rounded constants 1/k! that lead their sums are compensated).

/// `|z| = |βX²|` up to which the Stumpff functions come from their power series; above it from
/// the closed (half-angle) forms, whose cancellations (`c3 = (1 − c1)/z`, `c4 = (½ − c2)/z`,
/// `c5 = (⅙ − c3)/z`) then cost at most about two bits.
const Z_SERIES: f64 = 9.0;

/// `[1/(4+2j)!, 1/(5+2j)!]` for `j = 0, 1, …`: the coefficients of the `c4`, `c5` series in
/// `−z`. Truncated after 8 terms for `|z| ≤ 1` and 13 for `|z| ≤ 9`, the first omitted term is
/// below `2⁻⁵⁶ c_k(z)`.
const SERIES: [[f64; 2]; 13] = {
    let mut table = [[0.0; 2]; 13];
    let (mut factorial, mut k) = (24.0, 4.0);
    let mut j = 0;
    while j < 13 {
        // k! is exact in f64 up to 22!, so each entry is one rounding (two beyond).
        table[j][0] = 1.0 / factorial;
        table[j][1] = 1.0 / (factorial * (k + 1.0));
        factorial *= (k + 1.0) * (k + 2.0);
        k += 2.0;
        j += 1;
    }
    table
};

/// `|z|` above which `∂G2/∂β`, `∂G3/∂β` use the forms divided by `β`, free of the
/// `X G4 ≈ 3 G5` cancellation that grows like `z` (many periods); below, the forms in `G4`, `G5`.
const Z_BETA_FORM: f64 = 4.0;

/// `G0 … G5` at `(X, β)`: `G_k = X^k c_k(βX²)`.
pub(super) fn g_functions(beta: f64, x: f64) -> [f64; 6] {
    let x2 = x * x;
    let c = stumpff(beta * x2);
    let (x3, x4) = (x2 * x, x2 * x2);
    let x5 = x4 * x;
    [c[0], x * c[1], x2 * c[2], x3 * c[3], x4 * c[4], x5 * c[5]]
}

/// The Stumpff functions `c0 … c5` at `z`, to about 1e-15 relative (to their scale near the
/// zeros of `c0`, `c1`).
///
/// `|z| ≤ Z_SERIES`: the series for `c4`, `c5`, then `c_k = 1/k! − z c_{k+2}` (stable there).
/// Beyond, closed forms in the half angle `θ/2`, `θ = √|z|`, which keep `c2 = 2 sin²(θ/2)/θ²`
/// accurate where `1 − cos θ` would cancel (cf. Wisdom & Hernandez 2015), then
/// `c_{k+2} = (1/k! − c_k)/z`.
pub(super) fn stumpff(z: f64) -> [f64; 6] {
    let az = z.abs();
    if az <= Z_SERIES {
        // The series' tails (from the second term), then the leading 1/24, 1/120 added with
        // their rounding errors: a rounded constant that leads a sum is the same one-signed
        // relative error at every call (1/6 and 1/24 are 5.6e-17 low), which biased the
        // drift's energy by 3.3e-16 per drift on average, growing linearly into the phase.
        let w = -z;
        let (t4, t5) = if az <= 1.0 {
            // Estrin's scheme in w: a short dependency chain for the hot path.
            let w2 = z * z;
            let w4 = w2 * w2;
            let q = |k: usize| {
                let a = |j: usize| SERIES[j][k];
                (a(1) + a(2) * w + w2 * (a(3) + a(4) * w)) + w4 * (a(5) + a(6) * w + w2 * a(7))
            };
            (q(0), q(1))
        } else {
            SERIES[1..]
                .iter()
                .rev()
                .fold((0.0, 0.0), |(t4, t5), [a4, a5]| (a4 + w * t4, a5 + w * t5))
        };
        let c4 = sum_with_product(SERIES[0][0], INV_24_LO, w, t4);
        let c5 = sum_with_product(SERIES[0][1], INV_120_LO, w, t5);
        let (c3, c2) = (sum_with_product(1.0 / 6.0, INV_6_LO, w, c5), 0.5 - z * c4);
        return [1.0 - z * c2, 1.0 - z * c3, c2, c3, c4, c5];
    }
    let theta = az.sqrt();
    let (c0, c1, c2) = if z > 0.0 {
        let (s, c) = (0.5 * theta).sin_cos();
        (1.0 - 2.0 * s * s, 2.0 * s * c / theta, 2.0 * s * s / az)
    } else {
        let e = (0.5 * theta).exp();
        let (s, c) = (0.5 * (e - 1.0 / e), 0.5 * (e + 1.0 / e));
        (1.0 + 2.0 * s * s, 2.0 * s * c / theta, 2.0 * s * s / az)
    };
    let c3 = (1.0 - c1) / z;
    [
        c0,
        c1,
        c2,
        c3,
        (0.5 - c2) / z,
        sum_with_product(1.0 / 6.0, INV_6_LO, -1.0, c3) / z,
    ]
}

/// `hi + lo + x·y` with one rounding at the end (nearly): the product and the sum `hi + x·y`
/// are split into value and error (fused multiply–add, Knuth's two-sum), and the errors and
/// `lo` are added before the last rounding. For `hi + lo` a constant that `hi` alone rounds.
#[inline(always)]
fn sum_with_product(hi: f64, lo: f64, x: f64, y: f64) -> f64 {
    let p = x * y;
    let p_err = x.mul_add(y, -p);
    let s = hi + p;
    let b = s - hi;
    let s_err = (hi - (s - b)) + (p - b);
    s + (s_err + p_err + lo)
}

/// `1/6 − fl(1/6)`: the part of 1/6 a double does not hold (exact to the digits given).
const INV_6_LO: f64 = 9.25185853854297e-18;
/// `1/24 − fl(1/24)` (= `INV_6_LO`/4).
const INV_24_LO: f64 = 2.3129646346357427e-18;
/// `1/120 − fl(1/120)`.
const INV_120_LO: f64 = 1.1564823173178714e-19;

/// `∂G_k/∂β = −½ (X G_{k+1} − k G_{k+2})` for `k = 0 … 3`.
///
/// For `|βX²| > Z_BETA_FORM` the `k = 2, 3` ones use `G_{k+2} = (X^k/k! − G_k)/β`:
/// `∂G2/∂β = (X G1 − 2 G2)/(2β)`, `∂G3/∂β = (X G2 − 3 G3)/(2β)`, whose terms do not cancel
/// when `X` spans many periods.
pub(super) fn beta_derivatives(beta: f64, x: f64, gs: &[f64; 6]) -> [f64; 4] {
    let [_, g1, g2, g3, g4, g5] = *gs;
    let (b2, b3) = if (beta * x * x).abs() <= Z_BETA_FORM {
        (0.5 * (2.0 * g4 - x * g3), 0.5 * (3.0 * g5 - x * g4))
    } else {
        let d = 0.5 / beta;
        ((x * g1 - 2.0 * g2) * d, (x * g2 - 3.0 * g3) * d)
    };
    [-0.5 * x * g1, 0.5 * (g3 - x * g2), b2, b3]
}

#[cfg(test)]
#[path = "stumpff_tests.rs"]
mod tests;
