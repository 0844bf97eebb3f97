//! Jacobi elliptic functions and the exact motion of the free rigid body.
//!
//! - sn, cn, dn by the descending Landen transformation (the arithmetic–geometric mean;
//!   Abramowitz & Stegun 16.4), after reducing u modulo 4K;
//! - K(m) = π / (2 AGM(1, √(1 − m))) (A&S 17.6);
//! - the incomplete integral F(φ | m) by Carlson's R_F (Carlson, Numer. Algorithms 10 (1995)),
//!   used to find the phase of a given initial condition.
//!
//! [`FreeBodyExact`] is the free rigid body with I₁ < I₂ < I₃ and |μ|² > 2E I₂ (rotation about
//! the axis of largest inertia; Landau & Lifshitz, *Mechanics*, §37):
//! Ω = (a cn u, s b sn u, s c dn u), u = λ t + u₀, s = sign Ω₃(0). The body momentum is exact.
//! The orientation is R(t) = P R_z(φ) R_x(θ) R_z(ψ) (Euler angles with the spatial angular
//! momentum along P e_z): θ and ψ follow from μ(t) exactly, and the precession angle from the
//! quadrature φ(t) = ∫ |μ| (μ₁²/I₁ + μ₂²/I₂)/(μ₁² + μ₂²) dt of a smooth periodic integrand,
//! evaluated by 20-point composite Gauss–Legendre on panels of a 32nd of the period (measured
//! accuracy near round-off; the only non-closed-form part of the reference).

use super::so3::{Mat3, axis_rotation, mul, transpose};
use crate::error::{GviError, Result};
use std::f64::consts::PI;

/// The arithmetic–geometric mean of a and b.
pub fn agm(mut a: f64, mut b: f64) -> f64 {
    for _ in 0..64 {
        let (an, bn) = (0.5 * (a + b), (a * b).sqrt());
        if (an - bn).abs() <= 1e-16 * an {
            return an;
        }
        a = an;
        b = bn;
    }
    a
}

/// The complete elliptic integral of the first kind K(m), 0 ≤ m < 1 (parameter m = k²).
pub fn ellipk(m: f64) -> f64 {
    PI / (2.0 * agm(1.0, (1.0 - m).sqrt()))
}

/// (sn, cn, dn)(u | m) for 0 ≤ m < 1.
pub fn sncndn(u: f64, m: f64) -> (f64, f64, f64) {
    if m < 1e-300 {
        let (s, c) = u.sin_cos();
        return (s, c, 1.0);
    }
    let k4 = 4.0 * ellipk(m);
    let u = u - k4 * (u / k4).round();
    // Descending Landen: a₀ = 1, b₀ = √(1 − m), c₀ = √m.
    let mut a = [0.0f64; 16];
    let mut c = [0.0f64; 16];
    a[0] = 1.0;
    let mut b = (1.0 - m).sqrt();
    c[0] = m.sqrt();
    let mut n = 0;
    while n < 15 && c[n].abs() > 1e-16 {
        a[n + 1] = 0.5 * (a[n] + b);
        c[n + 1] = 0.5 * (a[n] - b);
        b = (a[n] * b).sqrt();
        n += 1;
    }
    let mut phi = (1u64 << n) as f64 * a[n] * u;
    for j in (1..=n).rev() {
        phi = 0.5 * (phi + (c[j] * phi.sin() / a[j]).asin());
    }
    let (s, co) = phi.sin_cos();
    // dn > 0 for m < 1; the A&S form cos φ₀ / cos(φ₁ − φ₀) is 0/0 where cn vanishes.
    (s, co, (1.0 - m * s * s).sqrt())
}

/// Carlson's symmetric integral R_F(x, y, z) by duplication.
pub fn carlson_rf(mut x: f64, mut y: f64, mut z: f64) -> f64 {
    for _ in 0..100 {
        let l = (x * y).sqrt() + (x * z).sqrt() + (y * z).sqrt();
        x = 0.25 * (x + l);
        y = 0.25 * (y + l);
        z = 0.25 * (z + l);
        let mean = (x + y + z) / 3.0;
        let dev = ((x - mean).abs())
            .max((y - mean).abs())
            .max((z - mean).abs())
            / mean;
        if dev < 1e-4 {
            let (dx, dy, dz) = (1.0 - x / mean, 1.0 - y / mean, 1.0 - z / mean);
            let e2 = dx * dy - dz * dz;
            let e3 = dx * dy * dz;
            // Carlson (1995) eq. (2.19), error O(dev⁶) < 1e-24.
            return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0)
                / mean.sqrt();
        }
    }
    f64::NAN
}

/// The incomplete elliptic integral F(φ | m) for any real φ (quasi-periodic: F(φ + π) =
/// F(φ) + 2K).
pub fn ellipf(phi: f64, m: f64) -> f64 {
    let j = (phi / PI).round();
    let r = phi - j * PI; // in [−π/2, π/2]
    let (s, c) = r.sin_cos();
    s * carlson_rf(c * c, 1.0 - m * s * s, 1.0) + 2.0 * j * ellipk(m)
}

/// The exact free rigid body for I₁ < I₂ < I₃ and |μ|² > 2E I₂ (see the module docs).
#[derive(Debug, Clone)]
pub struct FreeBodyExact {
    inertia: [f64; 3],
    amp: [f64; 3],
    sign: f64,
    lambda: f64,
    u0: f64,
    m: f64,
    period: f64,
    momentum: f64,
    frame: Mat3<f64>,
}

impl FreeBodyExact {
    /// The exact solution through (R₀, μ₀), or [`GviError::Unsupported`] outside the case
    /// covered (ordered moments, rotation about the third axis, not a pure spin).
    pub fn new(inertia: [f64; 3], r0: &Mat3<f64>, mu0: &[f64; 3]) -> Result<Self> {
        let [i1, i2, i3] = inertia;
        if !(i1 < i2 && i2 < i3) {
            return Err(GviError::Unsupported(
                "the elliptic-function reference needs I₁ < I₂ < I₃".into(),
            ));
        }
        let m2: f64 = mu0.iter().map(|x| x * x).sum();
        let e2: f64 = (0..3).map(|k| mu0[k] * mu0[k] / inertia[k]).sum();
        if m2 <= e2 * i2 * (1.0 + 1e-12) || mu0[0] * mu0[0] + mu0[1] * mu0[1] == 0.0 {
            return Err(GviError::Unsupported(
                "the elliptic-function reference covers |μ|² > 2E I₂ (rotation about the \
                 third axis), not a pure spin"
                    .into(),
            ));
        }
        let a = ((e2 * i3 - m2) / (i1 * (i3 - i1))).sqrt();
        let b = ((e2 * i3 - m2) / (i2 * (i3 - i2))).sqrt();
        let c = ((m2 - e2 * i1) / (i3 * (i3 - i1))).sqrt();
        let lambda = ((i3 - i2) * (m2 - e2 * i1) / (i1 * i2 * i3)).sqrt();
        let m = (i2 - i1) * (e2 * i3 - m2) / ((i3 - i2) * (m2 - e2 * i1));
        let w = [mu0[0] / i1, mu0[1] / i2, mu0[2] / i3];
        let sign = w[2].signum();
        let phi0 = (sign * w[1] / b).atan2(w[0] / a);
        let u0 = ellipf(phi0, m);
        let period = 4.0 * ellipk(m) / lambda;
        let mut exact = FreeBodyExact {
            inertia,
            amp: [a, b, c],
            sign,
            lambda,
            u0,
            m,
            period,
            momentum: m2.sqrt(),
            frame: [[0.0; 3]; 3],
        };
        let e0 = exact.euler_frame(mu0, 0.0);
        exact.frame = mul(r0, &transpose(&e0));
        Ok(exact)
    }

    /// The period 4K/λ of the body angular velocity.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// The parameter m = k² of the elliptic functions.
    pub fn parameter(&self) -> f64 {
        self.m
    }

    /// Body angular velocity Ω(t).
    pub fn angular_velocity(&self, t: f64) -> [f64; 3] {
        let (sn, cn, dn) = sncndn(self.lambda * t + self.u0, self.m);
        [
            self.amp[0] * cn,
            self.sign * self.amp[1] * sn,
            self.sign * self.amp[2] * dn,
        ]
    }

    /// Body momentum μ(t) = 𝕀Ω(t).
    pub fn body_momentum(&self, t: f64) -> [f64; 3] {
        let w = self.angular_velocity(t);
        [
            w[0] * self.inertia[0],
            w[1] * self.inertia[1],
            w[2] * self.inertia[2],
        ]
    }

    /// dφ/dt of the precession angle.
    fn precession_rate(&self, t: f64) -> f64 {
        let mu = self.body_momentum(t);
        let [i1, i2, _] = self.inertia;
        let perp = mu[0] * mu[0] + mu[1] * mu[1];
        self.momentum * (mu[0] * mu[0] / i1 + mu[1] * mu[1] / i2) / perp
    }

    /// R_z(φ) R_x(θ) R_z(ψ) with θ, ψ from μ.
    fn euler_frame(&self, mu: &[f64; 3], phi: f64) -> Mat3<f64> {
        let theta = (mu[0].hypot(mu[1])).atan2(mu[2]);
        let psi = mu[0].atan2(mu[1]);
        mul(
            &axis_rotation(2, phi),
            &mul(&axis_rotation(0, theta), &axis_rotation(2, psi)),
        )
    }

    /// Orientations R(t) at increasing times `times` (≥ 0), accumulating the precession
    /// angle panel by panel.
    pub fn orientations(&self, times: &[f64]) -> Result<Vec<Mat3<f64>>> {
        let rule = crate::quadrature::QuadratureKind::GaussLegendre.build(20)?;
        let panel = self.period / 32.0;
        let (mut t, mut phi) = (0.0, 0.0);
        let mut out = Vec::with_capacity(times.len());
        for &target in times {
            if target.is_nan() || target < t {
                return Err(GviError::InvalidInput {
                    name: "times".into(),
                    reason: "the reference needs increasing times from 0".into(),
                });
            }
            while t < target {
                let w = (target - t).min(panel);
                phi += w * rule.integrate(|c| self.precession_rate(t + c * w));
                t += w;
            }
            let e = self.euler_frame(&self.body_momentum(target), phi);
            out.push(mul(&self.frame, &e));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn elliptic_identities_and_known_values() {
        assert!((ellipk(0.0) - PI / 2.0).abs() < 1e-15);
        assert!((ellipk(0.5) - 1.854_074_677_301_372).abs() < 1e-14);
        for m in [0.1, 0.5, 0.9, 0.999] {
            let k = ellipk(m);
            let (s, c, d) = sncndn(k, m);
            assert!(
                (s - 1.0).abs() < 1e-13 && c.abs() < 1e-7,
                "m = {m}: {s} {c}"
            );
            assert!((d - (1.0 - m).sqrt()).abs() < 1e-12);
            for u in [0.3, 1.7, -2.9, 40.0] {
                let (s, c, d) = sncndn(u, m);
                assert!((s * s + c * c - 1.0).abs() < 1e-14);
                assert!((d * d + m * s * s - 1.0).abs() < 1e-14);
                let e = 1e-5;
                let (sp, ..) = sncndn(u + e, m);
                let (sm, ..) = sncndn(u - e, m);
                assert!(((sp - sm) / (2.0 * e) - c * d).abs() < 1e-8, "sn' at {u}");
                // F inverts am.
                let phi = s.atan2(c);
                let back = ellipf(phi, m);
                let (s2, c2, _) = sncndn(back, m);
                assert!((s2 - s).abs() < 1e-13 && (c2 - c).abs() < 1e-13);
            }
        }
    }

    #[test]
    fn exact_free_body_solves_euler_and_kinematics() {
        let inertia = [1.0, 2.0, 3.0];
        let r0 = crate::lie::so3::Retraction::Exp.map(&[0.3, -0.4, 0.2]);
        let mu0 = [1.0, 0.4, 3.0];
        let ex = FreeBodyExact::new(inertia, &r0, &mu0).unwrap();
        let m0 = ex.body_momentum(0.0);
        for k in 0..3 {
            assert!((m0[k] - mu0[k]).abs() < 1e-13);
        }
        // Euler's equations by central differences, and Ṙ = R Ω̂.
        let e = 1e-5;
        let times = [0.0, 2.3 - e, 2.3, 2.3 + e];
        let rs = ex.orientations(&times).unwrap();
        assert!(crate::lie::so3::distance(&rs[0], &r0) < 1e-14);
        let w = ex.angular_velocity(2.3);
        let mut rdot = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                rdot[i][j] = (rs[3][i][j] - rs[1][i][j]) / (2.0 * e);
            }
        }
        let want = mul(&rs[2], &crate::lie::so3::hat(&w));
        assert!(crate::lie::so3::distance(&rdot, &want) < 1e-8);
        let (mp, mm) = (ex.body_momentum(2.3 + e), ex.body_momentum(2.3 - e));
        let mu = ex.body_momentum(2.3);
        let c = crate::lie::so3::cross(&mu, &w);
        for k in 0..3 {
            assert!(((mp[k] - mm[k]) / (2.0 * e) - c[k]).abs() < 1e-8);
        }
        assert!(FreeBodyExact::new([2.0, 1.0, 3.0], &r0, &mu0).is_err());
    }
}
