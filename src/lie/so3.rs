//! The rotation group SO(3), its algebra so(3) ≅ R³ (ξ ↦ ξ̂ with ξ̂y = ξ × y), and the two
//! retractions τ: so(3) → SO(3) the Lie group integrator can use, with their trivialised
//! derivatives.
//!
//! # Conventions
//!
//! For a curve g(t) = g_k τ(ξ(t)) the *left-trivialised* velocity (the body angular velocity of a
//! rigid body) is Ω = g⁻¹ġ = J_r(ξ) ξ̇, and the *right-trivialised* one is ġg⁻¹ = Ad_g J_l(ξ) ξ̇
//! (g_k fixed). For τ = exp, J_r(ξ) = dexp_{−ξ} and J_l(ξ) = dexp_ξ, with
//! dexp_x(y) = Σ_j ad_x^j y / (j + 1)! (Hairer, Lubich & Wanner, *Geometric Numerical
//! Integration*, §III.4, Lemma 4.2: d/dt exp(Ω) = dexp_Ω(Ω̇) exp(Ω)); on so(3)
//!
//! - exp(ξ̂) = I + c₀ ξ̂ + c₁ ξ̂² (Rodrigues),
//! - J_r(ξ) = I − c₁ ξ̂ + c₂ ξ̂², J_l(ξ) = I + c₁ ξ̂ + c₂ ξ̂²,
//!
//! with θ = |ξ|, c₀ = sin θ/θ, c₁ = (1 − cos θ)/θ², c₂ = (θ − sin θ)/θ³. For the Cayley map
//! cay(ξ̂) = (I − ξ̂/2)⁻¹(I + ξ̂/2) = I + 4/(4 + θ²)(ξ̂ + ξ̂²/2),
//! J_r(ξ) = 4/(4 + θ²)(I − ξ̂/2) and J_l(ξ) = 4/(4 + θ²)(I + ξ̂/2) (HLW §IV.8.3). For both,
//! J_l(ξ) = τ(ξ) J_r(ξ) (J_l = Ad_τ(ξ) J_r), which is what makes the discrete spatial momentum
//! exactly conserved (see [`crate::lie`]).
//!
//! The functions are generic over the scalar (num-dual) so the integrator's Newton Jacobian is
//! exact. The c_i are evaluated by their Taylor series in θ² below θ = 1 (no 0/0 and no
//! cancellation in θ − sin θ, and smooth dual parts at ξ = 0), by the closed forms above it.

use num_dual::DualNum;
use serde::{Deserialize, Serialize};

/// A 3 × 3 matrix as rows, generic over the scalar.
pub type Mat3<T> = [[T; 3]; 3];

/// The identity matrix.
pub fn identity<T: DualNum<Primitive = f64> + Copy>() -> Mat3<T> {
    let (o, z) = (T::from(1.0), T::from(0.0));
    [[o, z, z], [z, o, z], [z, z, o]]
}

/// Lift a constant matrix to the scalar T.
pub fn lift<T: DualNum<Primitive = f64> + Copy>(m: &Mat3<f64>) -> Mat3<T> {
    m.map(|r| r.map(T::from))
}

/// The hat map ξ ↦ ξ̂ (ξ̂ y = ξ × y).
pub fn hat<T: DualNum<Primitive = f64> + Copy>(x: &[T; 3]) -> Mat3<T> {
    let z = T::from(0.0);
    [[z, -x[2], x[1]], [x[2], z, -x[0]], [-x[1], x[0], z]]
}

/// The inverse of [`hat`] on the skew part: vee(A) = ((A₃₂ − A₂₃)/2, (A₁₃ − A₃₁)/2, (A₂₁ − A₁₂)/2).
pub fn vee_skew(a: &Mat3<f64>) -> [f64; 3] {
    [
        0.5 * (a[2][1] - a[1][2]),
        0.5 * (a[0][2] - a[2][0]),
        0.5 * (a[1][0] - a[0][1]),
    ]
}

/// Cross product a × b.
pub fn cross<T: DualNum<Primitive = f64> + Copy>(a: &[T; 3], b: &[T; 3]) -> [T; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Dot product.
pub fn dot<T: DualNum<Primitive = f64> + Copy>(a: &[T; 3], b: &[T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Matrix product A B.
pub fn mul<T: DualNum<Primitive = f64> + Copy>(a: &Mat3<T>, b: &Mat3<T>) -> Mat3<T> {
    let mut c = [[T::from(0.0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    c
}

/// Matrix–vector product A x.
pub fn mul_vec<T: DualNum<Primitive = f64> + Copy>(a: &Mat3<T>, x: &[T; 3]) -> [T; 3] {
    [
        a[0][0] * x[0] + a[0][1] * x[1] + a[0][2] * x[2],
        a[1][0] * x[0] + a[1][1] * x[1] + a[1][2] * x[2],
        a[2][0] * x[0] + a[2][1] * x[1] + a[2][2] * x[2],
    ]
}

/// Transposed product Aᵀ x.
pub fn mul_tr_vec<T: DualNum<Primitive = f64> + Copy>(a: &Mat3<T>, x: &[T; 3]) -> [T; 3] {
    [
        a[0][0] * x[0] + a[1][0] * x[1] + a[2][0] * x[2],
        a[0][1] * x[0] + a[1][1] * x[1] + a[2][1] * x[2],
        a[0][2] * x[0] + a[1][2] * x[1] + a[2][2] * x[2],
    ]
}

/// Transpose.
pub fn transpose<T: Copy>(a: &Mat3<T>) -> Mat3<T> {
    [
        [a[0][0], a[1][0], a[2][0]],
        [a[0][1], a[1][1], a[2][1]],
        [a[0][2], a[1][2], a[2][2]],
    ]
}

/// ‖RᵀR − I‖_F: the distance of R from the orthogonal matrices (first order).
pub fn orthogonality_defect(r: &Mat3<f64>) -> f64 {
    let rtr = mul(&transpose(r), r);
    let mut s = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let d = rtr[i][j] - if i == j { 1.0 } else { 0.0 };
            s += d * d;
        }
    }
    s.sqrt()
}

/// Frobenius norm of A − B.
pub fn distance(a: &Mat3<f64>, b: &Mat3<f64>) -> f64 {
    let mut s = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            s += (a[i][j] - b[i][j]).powi(2);
        }
    }
    s.sqrt()
}

/// Rotation by angle `a` about coordinate axis `axis` (0, 1, 2).
pub fn axis_rotation(axis: usize, a: f64) -> Mat3<f64> {
    let (s, c) = a.sin_cos();
    let mut r = identity::<f64>();
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    r[i][i] = c;
    r[j][j] = c;
    r[i][j] = -s;
    r[j][i] = s;
    r
}

/// Σ_k (−s)^k / (2k + offset)!, for s = θ² < 1 (terms to 1/21!: below 2e-20).
fn series<T: DualNum<Primitive = f64> + Copy>(s: T, offset: u32) -> T {
    // 1/(2k+offset)! for k = 0..=9.
    let mut coef = [0.0f64; 10];
    let mut f = 1.0;
    for m in 1..=offset {
        f *= m as f64;
    }
    coef[0] = 1.0 / f;
    for k in 1..10 {
        let a = (2 * k as u32 + offset - 1) as f64;
        let b = (2 * k as u32 + offset) as f64;
        coef[k] = -coef[k - 1] / (a * b);
    }
    // Horner in s.
    let mut acc = T::from(coef[9]);
    for k in (0..9).rev() {
        acc = acc * s + coef[k];
    }
    acc
}

/// (c₀, c₁, c₂) = (sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³) at s = θ².
pub fn exp_coefficients<T: DualNum<Primitive = f64> + Copy>(s: T) -> (T, T, T) {
    if s.re() < 1.0 {
        (series(s, 1), series(s, 2), series(s, 3))
    } else {
        let th = s.sqrt();
        let sn = th.sin();
        let half = (th * 0.5).sin();
        (sn / th, half * half * 2.0 / s, (th - sn) / (s * th))
    }
}

/// I + a ξ̂ + b ξ̂² (the common form of exp, J_r, J_l).
fn quadratic<T: DualNum<Primitive = f64> + Copy>(x: &[T; 3], a: T, b: T) -> Mat3<T> {
    let k = hat(x);
    let k2 = mul(&k, &k);
    let mut m = identity::<T>();
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] += a * k[i][j] + b * k2[i][j];
        }
    }
    m
}

/// The map from the algebra to the group used to build curves g(t) = g_k τ(ξ(t)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Retraction {
    /// The exponential map (Rodrigues' formula): the natural chart of Hall & Leok.
    #[default]
    Exp,
    /// The Cayley map: rational, cheaper, covers rotations by less than π.
    Cayley,
}

impl Retraction {
    /// The name used in scene files.
    pub fn as_str(self) -> &'static str {
        match self {
            Retraction::Exp => "exp",
            Retraction::Cayley => "cayley",
        }
    }

    /// τ(ξ) as a rotation matrix.
    pub fn map<T: DualNum<Primitive = f64> + Copy>(self, x: &[T; 3]) -> Mat3<T> {
        let s = dot(x, x);
        match self {
            Retraction::Exp => {
                let (c0, c1, _) = exp_coefficients(s);
                quadratic(x, c0, c1)
            }
            Retraction::Cayley => {
                let f = (s + 4.0).recip() * 4.0;
                quadratic(x, f, f * 0.5)
            }
        }
    }

    /// J_r(ξ): Ω = J_r(ξ) ξ̇ is the left-trivialised velocity of τ(ξ(t)).
    pub fn right_jacobian<T: DualNum<Primitive = f64> + Copy>(self, x: &[T; 3]) -> Mat3<T> {
        let s = dot(x, x);
        match self {
            Retraction::Exp => {
                let (_, c1, c2) = exp_coefficients(s);
                quadratic(x, -c1, c2)
            }
            Retraction::Cayley => {
                let f = (s + 4.0).recip() * 4.0;
                scaled_linear(x, f, f * -0.5)
            }
        }
    }

    /// J_l(ξ) = τ(ξ) J_r(ξ): the right-trivialised velocity of τ(ξ(t)) is J_l(ξ) ξ̇.
    pub fn left_jacobian<T: DualNum<Primitive = f64> + Copy>(self, x: &[T; 3]) -> Mat3<T> {
        let s = dot(x, x);
        match self {
            Retraction::Exp => {
                let (_, c1, c2) = exp_coefficients(s);
                quadratic(x, c1, c2)
            }
            Retraction::Cayley => {
                let f = (s + 4.0).recip() * 4.0;
                scaled_linear(x, f, f * 0.5)
            }
        }
    }

    /// The inverse τ⁻¹(R) (principal branch): log for exp (rotation angle in [0, π)),
    /// 2 vee(R − Rᵀ)/(1 + tr R) for Cayley (rotation angle below π). Used for initial guesses.
    pub fn inverse(self, r: &Mat3<f64>) -> [f64; 3] {
        let w = vee_skew(r); // sin θ · axis
        let tr = r[0][0] + r[1][1] + r[2][2];
        match self {
            Retraction::Exp => {
                let sin = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
                let cos = 0.5 * (tr - 1.0);
                let th = sin.atan2(cos);
                let f = if sin < 1e-8 {
                    1.0 + th * th / 6.0
                } else {
                    th / sin
                };
                w.map(|v| v * f)
            }
            Retraction::Cayley => w.map(|v| 4.0 * v / (1.0 + tr)),
        }
    }
}

/// f (I + g ξ̂) written as a matrix.
fn scaled_linear<T: DualNum<Primitive = f64> + Copy>(x: &[T; 3], f: T, g: T) -> Mat3<T> {
    let k = hat(x);
    let mut m = [[T::from(0.0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 } else { 0.0 };
            m[i][j] = f * id + g * k[i][j];
        }
    }
    m
}

impl std::fmt::Display for Retraction {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Retraction {
    type Err = crate::GviError;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "exp" => Ok(Retraction::Exp),
            "cayley" => Ok(Retraction::Cayley),
            other => Err(crate::GviError::InvalidInput {
                name: "retraction".into(),
                reason: format!("unknown retraction '{other}' (expected exp or cayley)"),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn max_diff(a: &Mat3<f64>, b: &Mat3<f64>) -> f64 {
        let mut m: f64 = 0.0;
        for i in 0..3 {
            for j in 0..3 {
                m = m.max((a[i][j] - b[i][j]).abs());
            }
        }
        m
    }

    /// Ω = J_r ξ̇ and ġg⁻¹ = J_l ξ̇, checked against central differences of τ(ξ + t ξ̇).
    #[test]
    fn trivialised_derivatives_match_finite_differences() {
        for tau in [Retraction::Exp, Retraction::Cayley] {
            for x in [[0.3, -0.2, 0.5], [1.2, 0.7, -1.9], [1e-3, 2e-4, -5e-4]] {
                let v = [0.4, 0.9, -0.3];
                let e = 1e-6;
                let xp = [x[0] + e * v[0], x[1] + e * v[1], x[2] + e * v[2]];
                let xm = [x[0] - e * v[0], x[1] - e * v[1], x[2] - e * v[2]];
                let (rp, rm, r) = (tau.map(&xp), tau.map(&xm), tau.map(&x));
                let mut d = [[0.0; 3]; 3];
                for i in 0..3 {
                    for j in 0..3 {
                        d[i][j] = (rp[i][j] - rm[i][j]) / (2.0 * e);
                    }
                }
                let body = mul(&transpose(&r), &d);
                let spatial = mul(&d, &transpose(&r));
                let om = mul_vec(&tau.right_jacobian(&x), &v);
                let sp = mul_vec(&tau.left_jacobian(&x), &v);
                assert!(max_diff(&body, &hat(&om)) < 1e-8, "{tau} J_r at {x:?}");
                assert!(max_diff(&spatial, &hat(&sp)) < 1e-8, "{tau} J_l at {x:?}");
                assert!(orthogonality_defect(&r) < 1e-15);
                let back = tau.inverse(&r);
                for i in 0..3 {
                    assert!((back[i] - x[i]).abs() < 1e-13, "{tau} inverse");
                }
            }
        }
    }

    #[test]
    fn series_and_closed_forms_agree_at_the_switch() {
        // The series just below θ = 1 against the closed forms at θ = 1 (slopes ≤ 1/6 in s).
        let s = 1.0f64 - 1e-12;
        let below = exp_coefficients(s);
        let above = exp_coefficients(1.0f64);
        assert!((below.0 - above.0).abs() < 1e-15 + 2e-13);
        assert!((below.1 - above.1).abs() < 1e-15 + 1e-13);
        assert!((below.2 - above.2).abs() < 1e-15 + 1e-13);
        let (s1, c1) = 1.0f64.sin_cos();
        assert!((above.0 - s1).abs() < 1e-16);
        assert!((above.1 - (1.0 - c1)).abs() < 1e-16);
        assert!((above.2 - (1.0 - s1)).abs() < 1e-16);
    }
}
