//! Derivatives of an expression Lagrangian in one pass over the tape: dual vectors carry the
//! whole gradient (or gradient and Hessian) of L(q, v) at once, so the tape is interpreted
//! once instead of 2D (gradient) or D(2D + 1) (Hessian) times. Same values as the scalar
//! passes to round-off (tested against them); for D > 4 the scalar passes are used.

use super::ExpressionLagrangian;
use crate::ad;
use nalgebra::{Const, U1};
use num_dual::{Dual2SVec64, DualSVec64};

impl ExpressionLagrangian {
    pub(super) fn gradient_fixed<const N: usize>(
        &self,
        q: &[f64],
        v: &[f64],
        lq: &mut [f64],
        lv: &mut [f64],
    ) {
        let d = N / 2;
        let mut x = [DualSVec64::<N>::from_re(0.0); N];
        for i in 0..d {
            x[i] = DualSVec64::<N>::from_re(q[i]).derivative(i);
            x[d + i] = DualSVec64::<N>::from_re(v[i]).derivative(d + i);
        }
        let y = self.tape.eval(&x[..d], &x[d..]);
        let g = y.eps.unwrap_generic(Const::<N>, U1);
        for i in 0..d {
            lq[i] = g[i];
            lv[i] = g[d + i];
        }
    }

    pub(super) fn hessian_fixed<const N: usize>(
        &self,
        q: &[f64],
        v: &[f64],
        lqq: &mut [f64],
        lqv: &mut [f64],
        lvv: &mut [f64],
    ) {
        let d = N / 2;
        let mut x = [Dual2SVec64::<N>::from_re(0.0); N];
        for i in 0..d {
            x[i] = Dual2SVec64::<N>::from_re(q[i]).derivative(i);
            x[d + i] = Dual2SVec64::<N>::from_re(v[i]).derivative(d + i);
        }
        let y = self.tape.eval(&x[..d], &x[d..]);
        let h = y.v2.unwrap_generic(Const::<N>, Const::<N>);
        for r in 0..d {
            for s in 0..d {
                lqq[r * d + s] = h[(r, s)];
                lqv[r * d + s] = h[(r, d + s)];
                lvv[r * d + s] = h[(d + r, d + s)];
            }
        }
    }
}

/// The gradient by 2D scalar dual passes (the trait's default, for large D).
pub(super) fn gradient_by_passes(
    l: &ExpressionLagrangian,
    q: &[f64],
    v: &[f64],
    lq: &mut [f64],
    lv: &mut [f64],
) {
    let d = q.len();
    let x: Vec<f64> = q.iter().chain(v).copied().collect();
    let mut g = vec![0.0; 2 * d];
    ad::gradient(|y| l.tape.eval(&y[..d], &y[d..]), &x, &mut g);
    lq.copy_from_slice(&g[..d]);
    lv.copy_from_slice(&g[d..]);
}

/// The Hessian blocks by hyper-dual passes (the trait's default, for large D).
pub(super) fn hessian_by_passes(
    l: &ExpressionLagrangian,
    q: &[f64],
    v: &[f64],
    lqq: &mut [f64],
    lqv: &mut [f64],
    lvv: &mut [f64],
) {
    let d = q.len();
    let n = 2 * d;
    let x: Vec<f64> = q.iter().chain(v).copied().collect();
    let (mut g, mut h) = (vec![0.0; n], vec![0.0; n * n]);
    ad::hessian(|y| l.tape.eval(&y[..d], &y[d..]), &x, &mut g, &mut h);
    for r in 0..d {
        for s in 0..d {
            lqq[r * d + s] = h[r * n + s];
            lqv[r * d + s] = h[r * n + d + s];
            lvv[r * d + s] = h[(d + r) * n + d + s];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Lagrangian;

    #[test]
    fn one_pass_derivatives_match_scalar_passes() {
        for (text, coords) in [
            ("x_dot^2/2 + x*x_dot*sin(x) - cosh(x)", &["x"][..]),
            (
                "th1_dot^2 + th2_dot^2/2 + th1_dot*th2_dot*cos(th1 - th2) + 2*cos(th1) + cos(th2)",
                &["th1", "th2"][..],
            ),
            (
                "(a_dot^2 + b_dot^2 + c_dot^2)/2 + a*b_dot - exp(-c)*c_dot*a_dot + atan2(b, 1 + a^2)",
                &["a", "b", "c"][..],
            ),
            (
                "(a_dot^2 + b_dot^2 + c_dot^2 + e_dot^2)/2 - a*b*c*e + sqrt(1 + a_dot^2)*e",
                &["a", "b", "c", "e"][..],
            ),
        ] {
            let l = ExpressionLagrangian::parse(text, coords, &[]).unwrap();
            let d = l.dim();
            let q: Vec<f64> = (0..d).map(|i| 0.3 + 0.2 * i as f64).collect();
            let v: Vec<f64> = (0..d).map(|i| -0.5 + 0.4 * i as f64).collect();
            let (mut a, mut b, mut c, mut e) =
                (vec![0.0; d], vec![0.0; d], vec![0.0; d], vec![0.0; d]);
            l.gradient(&q, &v, &mut a, &mut b);
            gradient_by_passes(&l, &q, &v, &mut c, &mut e);
            let close = |x: &[f64], y: &[f64]| {
                x.iter()
                    .zip(y)
                    .all(|(x, y)| (x - y).abs() <= 1e-14 * (1.0 + y.abs()))
            };
            assert!(close(&a, &c) && close(&b, &e), "{text}");
            let z = || vec![0.0; d * d];
            let (mut h1, mut h2, mut h3) = (z(), z(), z());
            let (mut k1, mut k2, mut k3) = (z(), z(), z());
            l.hessian(&q, &v, &mut h1, &mut h2, &mut h3);
            hessian_by_passes(&l, &q, &v, &mut k1, &mut k2, &mut k3);
            assert!(
                close(&h1, &k1) && close(&h2, &k2) && close(&h3, &k3),
                "{text}"
            );
        }
    }
}
