//! Forward-mode automatic differentiation helpers (num-dual) without per-call allocation.
//!
//! A Lagrangian is written once, generic over the scalar `T: DualNum<Primitive = f64>`. Its
//! gradient comes from 2D evaluations with first-order duals ([`Dual64`]) and its Hessian from
//! (2D)(2D+1)/2 evaluations with hyper-dual numbers ([`HyperDual64`]), each seeded along a
//! pair of coordinate directions. The dual-number argument vectors live in thread-local scratch
//! buffers, so after the first call on a thread no heap allocation happens — which keeps the
//! integrator's step loop allocation-free even on the AD path.
//!
//! Second derivatives are needed by Newton's method at every quadrature node; for large
//! systems they dominate the cost, which is why [`Lagrangian`](crate::Lagrangian) lets a system
//! override them and why the N-body system supplies analytic pairwise Hessians. The guide's
//! speed page (docs/guide/speed.md) measures the AD path against hand-written derivatives.

use num_dual::{Dual64, HyperDual64};
use std::cell::RefCell;

use crate::scratch::with_scratch;

thread_local! {
    static DUAL_SCRATCH: RefCell<Vec<Dual64>> = const { RefCell::new(Vec::new()) };
    static HYPER_SCRATCH: RefCell<Vec<HyperDual64>> = const { RefCell::new(Vec::new()) };
}

/// Gradient of `f` at `x` by forward-mode AD: `grad[i] = ∂f/∂x_i`. Returns f(x).
pub fn gradient(f: impl Fn(&[Dual64]) -> Dual64, x: &[f64], grad: &mut [f64]) -> f64 {
    let n = x.len();
    with_scratch(&DUAL_SCRATCH, n, Dual64::from_re(0.0), |xs| {
        for (xi, &x0) in xs.iter_mut().zip(x) {
            *xi = Dual64::from_re(x0);
        }
        let mut value = 0.0;
        if n == 0 {
            return f(xs).re;
        }
        for i in 0..n {
            xs[i].eps = 1.0;
            let y = f(xs);
            xs[i].eps = 0.0;
            grad[i] = y.eps;
            value = y.re;
        }
        value
    })
}

/// Gradient and Hessian of `f` at `x` by hyper-dual numbers: `hess` is row-major n×n.
/// Returns f(x).
pub fn hessian(
    f: impl Fn(&[HyperDual64]) -> HyperDual64,
    x: &[f64],
    grad: &mut [f64],
    hess: &mut [f64],
) -> f64 {
    let n = x.len();
    with_scratch(&HYPER_SCRATCH, n, HyperDual64::from_re(0.0), |xs| {
        for (xi, &x0) in xs.iter_mut().zip(x) {
            *xi = HyperDual64::from_re(x0);
        }
        if n == 0 {
            return f(xs).re;
        }
        let mut value = 0.0;
        for i in 0..n {
            for j in i..n {
                xs[i].eps1 = 1.0;
                xs[j].eps2 = 1.0;
                let y = f(xs);
                xs[i].eps1 = 0.0;
                xs[j].eps2 = 0.0;
                hess[i * n + j] = y.eps1eps2;
                hess[j * n + i] = y.eps1eps2;
                if i == j {
                    grad[i] = y.eps1;
                }
                value = y.re;
            }
        }
        value
    })
}

/// L_q and L_v of `f(y)` with y = (q, v): the gradient split into its two D-blocks. Stack
/// scratch up to D = 32, so a step allocates nothing.
pub fn gradient_blocks(
    f: impl Fn(&[Dual64]) -> Dual64,
    q: &[f64],
    v: &[f64],
    lq: &mut [f64],
    lv: &mut [f64],
) {
    let d = q.len();
    let (mut xs, mut gs) = ([0.0; 64], [0.0; 64]);
    let mut heap: (Vec<f64>, Vec<f64>);
    let (x, g): (&mut [f64], &mut [f64]) = if 2 * d <= xs.len() {
        (&mut xs[..2 * d], &mut gs[..2 * d])
    } else {
        heap = (vec![0.0; 2 * d], vec![0.0; 2 * d]);
        (&mut heap.0, &mut heap.1)
    };
    x[..d].copy_from_slice(q);
    x[d..].copy_from_slice(v);
    gradient(f, x, g);
    lq.copy_from_slice(&g[..d]);
    lv.copy_from_slice(&g[d..]);
}

/// L_qq, L_qv (entry (r, s) = ∂²f/∂q_r∂v_s) and L_vv of `f(y)` with y = (q, v), each row-major
/// D×D. Stack scratch up to D = 16; above it the scratch is allocated per call.
pub fn hessian_blocks(
    f: impl Fn(&[HyperDual64]) -> HyperDual64,
    (q, v): (&[f64], &[f64]),
    lqq: &mut [f64],
    lqv: &mut [f64],
    lvv: &mut [f64],
) {
    let d = q.len();
    let n = 2 * d;
    let (mut xs, mut gs, mut hs) = ([0.0; 32], [0.0; 32], [0.0; 32 * 32]);
    let mut heap: (Vec<f64>, Vec<f64>, Vec<f64>);
    let (x, g, h): (&mut [f64], &mut [f64], &mut [f64]) = if n <= 32 {
        (&mut xs[..n], &mut gs[..n], &mut hs[..n * n])
    } else {
        heap = (vec![0.0; n], vec![0.0; n], vec![0.0; n * n]);
        (&mut heap.0, &mut heap.1, &mut heap.2)
    };
    x[..d].copy_from_slice(q);
    x[d..].copy_from_slice(v);
    hessian(f, x, g, h);
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
    use num_dual::DualNum;

    fn rosen<T: DualNum<Primitive = f64> + Copy>(x: &[T]) -> T {
        let a = T::from(1.0) - x[0];
        let b = x[1] - x[0] * x[0];
        a * a + b * b * 100.0 + (x[2] * x[0]).sin()
    }

    #[test]
    fn gradient_and_hessian_match_closed_form() {
        let x = [0.3, -0.7, 1.1];
        let mut g = [0.0; 3];
        let v = gradient(rosen, &x, &mut g);
        let mut g2 = [0.0; 3];
        let mut h = [0.0; 9];
        let v2 = hessian(rosen, &x, &mut g2, &mut h);
        let (x0, x1, x2) = (x[0], x[1], x[2]);
        let c = (x2 * x0).cos();
        let s = (x2 * x0).sin();
        let exact_g = [
            -2.0 * (1.0 - x0) - 400.0 * x0 * (x1 - x0 * x0) + x2 * c,
            200.0 * (x1 - x0 * x0),
            x0 * c,
        ];
        let exact_h00 = 2.0 - 400.0 * (x1 - 3.0 * x0 * x0) - x2 * x2 * s;
        let exact_h02 = c - x0 * x2 * s;
        assert!((v - v2).abs() < 1e-15);
        for i in 0..3 {
            assert!((g[i] - exact_g[i]).abs() < 1e-12, "{i}");
            assert!((g2[i] - exact_g[i]).abs() < 1e-12, "{i}");
        }
        assert!((h[0] - exact_h00).abs() < 1e-10);
        assert!((h[2] - exact_h02).abs() < 1e-12);
        assert!((h[6] - exact_h02).abs() < 1e-12);
        assert!((h[4] - 200.0).abs() < 1e-12);
        assert!((h[1] + 400.0 * x0).abs() < 1e-12);
    }
}
