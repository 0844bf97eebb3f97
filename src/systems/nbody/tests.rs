//! Tests of the N-body system: the pairwise Hessian kernels against the formed Hessian, the
//! hand-written derivatives against AD, the symmetries against the invariants, bad parameters.

use super::*;
use crate::symmetries::MomentumMap;

#[test]
fn pairwise_products_and_blocks_match_the_hessian() {
    // Two points of a 4-body 3D system: the matrix-free products agree with the formed
    // Hessian's to round-off (measured ≤ 4e-16 relative; bound 1e-13), the diagonal
    // blocks are its diagonal blocks bit for bit. Negative control: the product at a
    // different point is far off.
    let nb = NBody::new(vec![1.0, 0.5, 2.0, 0.1], 0.7, 3).unwrap();
    let q: Vec<f64> = (0..24)
        .map(|i| ((i * 37 % 11) as f64 - 5.0) * 0.3)
        .collect();
    let x: Vec<f64> = (0..24).map(|i| ((i * 13 % 7) as f64 - 3.0) * 0.1).collect();
    let d = 12;
    let mut hess = vec![0.0; d * d];
    let mut prod = vec![0.0; 24];
    let mut blocks = vec![0.0; 2 * 4 * 9];
    assert!(nb.potential_hessian_products_at_points(&q, &x, &mut prod));
    assert!(nb.potential_hessian_diagonal_blocks_at_points(&q, &mut blocks));
    let mut worst = 0.0f64;
    for j in 0..2 {
        let (qj, xj) = (&q[j * d..(j + 1) * d], &x[j * d..(j + 1) * d]);
        nb.potential_hessian(qj, &mut hess);
        for r in 0..d {
            let y: f64 = (0..d).map(|s| hess[r * d + s] * xj[s]).sum();
            let scale = (0..d).map(|s| (hess[r * d + s] * xj[s]).abs()).sum::<f64>();
            worst = worst.max((y - prod[j * d + r]).abs() / scale.max(1e-300));
        }
        for b in 0..4 {
            for r in 0..3 {
                for c in 0..3 {
                    assert_eq!(
                        blocks[(j * 4 + b) * 9 + r * 3 + c],
                        hess[(b * 3 + r) * d + b * 3 + c]
                    );
                }
            }
        }
    }
    assert!(worst < 1e-13, "{worst:e}");
    let mut other = vec![0.0; 24];
    let shifted: Vec<f64> = q.iter().map(|v| v * 1.1).collect();
    assert!(nb.potential_hessian_products_at_points(&shifted, &x, &mut other));
    let off = other
        .iter()
        .zip(&prod)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(off > 1e-3, "negative control: {off:e}");
}

#[test]
fn derivatives_match_ad_2d_and_3d() {
    let nb = NBody::new(vec![1.0, 0.5, 2.0], 1.3, 2).unwrap();
    crate::systems::derivative_tests::check_against_ad(&nb, &[0.1, 0.2, 1.3, -0.4, -0.7, 0.9]);
    let nb = NBody::new(vec![1.0, 0.5, 2.0, 0.1], 0.7, 3).unwrap();
    crate::systems::derivative_tests::check_against_ad(
        &nb,
        &[
            0.1, 0.2, 0.3, 1.3, -0.4, 0.2, -0.7, 0.9, -0.5, 2.0, 1.0, 1.5,
        ],
    );
}

#[test]
fn symmetries_agree_with_invariants() {
    let nb = NBody::new(vec![1.0, 0.5, 2.0], 1.0, 3).unwrap();
    let q = [0.1, 0.2, 0.3, 1.3, -0.4, 0.2, -0.7, 0.9, -0.5];
    let p = [0.3, -0.1, 0.2, 0.5, 0.4, -0.6, 0.0, 0.7, 0.1];
    let mut inv = [0.0; 7];
    nb.invariants(&q, &p, &mut inv);
    for m in nb.symmetries() {
        let idx = nb
            .invariant_names()
            .iter()
            .position(|n| *n == m.name)
            .unwrap();
        assert!((m.map.value(&q, &p) - inv[idx]).abs() < 1e-15, "{}", m.name);
    }
}

#[test]
fn invalid_parameters_are_errors() {
    assert!(NBody::new(vec![1.0], 1.0, 4).is_err());
    assert!(NBody::new(vec![], 1.0, 3).is_err());
    assert!(NBody::new(vec![1.0, -1.0], 1.0, 3).is_err());
    assert!(NBody::new(vec![1.0], 0.0, 3).is_err());
    assert!(
        NBody::from_gm(vec![1.0], 2)
            .unwrap()
            .with_names(vec![])
            .is_err()
    );
}

/// The gradient as the run-time loops over the body dimension computed it before the
/// constant-K kernel ([`super::pairwise`]): pair by pair, out_i += f d, out_j −= f d.
fn gradient_by_runtime_loops(nb: &NBody, q: &[f64]) -> Vec<f64> {
    let (k, n) = (nb.body_dim(), nb.bodies());
    let mut out = vec![0.0; n * k];
    let mut d = [0.0; 3];
    for i in 0..n {
        for j in i + 1..n {
            let r2 = nb.separation(q, i, j, &mut d);
            let f = nb.g * nb.masses[i] * nb.masses[j] / (r2 * r2.sqrt());
            for c in 0..k {
                out[i * k + c] += f * d[c];
                out[j * k + c] -= f * d[c];
            }
        }
    }
    out
}

#[test]
fn constant_dimension_gradient_is_the_runtime_loop_bit_for_bit() {
    // 2-D and 3-D, 7 bodies: every entry the same bits. Negative control: the gradient at a
    // perturbed point differs.
    for dim in [2, 3] {
        let nb = NBody::new(vec![1.0, 1e-3, 3e-4, 0.5, 2e-6, 0.1, 7e-5], 2.9e-4, dim).unwrap();
        let q: Vec<f64> = (0..7 * dim)
            .map(|i| ((i * 37 % 23) as f64 - 11.0) * 0.37 + (i as f64).sin())
            .collect();
        let mut fast = vec![0.0; q.len()];
        nb.potential_gradient(&q, &mut fast);
        let reference = gradient_by_runtime_loops(&nb, &q);
        for (a, b) in fast.iter().zip(&reference) {
            assert_eq!(a.to_bits(), b.to_bits(), "dim {dim}");
        }
        let mut moved = q.clone();
        moved[0] += 1e-9;
        assert_ne!(gradient_by_runtime_loops(&nb, &moved), fast);
    }
}

/// Evaluations at many points (`at_points`, the nodes in vector lanes) against the same
/// evaluation point by point (`pointwise`), `width` values per point, bit for bit, in 2D and
/// 3D, for full and partial lane groups (1, 7, 8, 9 and 17 points). Negative control: moving
/// one coordinate of the last point by an ulp changes that point's values and no other's.
fn lanes_match_pointwise(
    width: impl Fn(usize) -> usize,
    at_points: impl Fn(&NBody, &[f64], &mut [f64]),
    pointwise: impl Fn(&NBody, &[f64], &mut [f64]),
) {
    for dim in [2usize, 3] {
        let nb = NBody::new(vec![1.0, 1e-3, 3e-4, 5e-5, 4e-5, 7e-9], 2.9591e-4, dim).unwrap();
        let (d, per) = (6 * dim, width(dim));
        for points in [1usize, 7, 8, 9, 17] {
            let q: Vec<f64> = (0..points * d)
                .map(|i| ((i * 37 % 23) as f64 - 11.0) * 0.7 + (i as f64 * 0.37).sin())
                .collect();
            let mut lanes = vec![f64::NAN; points * per];
            at_points(&nb, &q, &mut lanes);
            let mut one = vec![0.0; per];
            for j in 0..points {
                pointwise(&nb, &q[j * d..(j + 1) * d], &mut one);
                let got = &lanes[j * per..(j + 1) * per];
                assert!(
                    got.iter()
                        .zip(&one)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "dim {dim}, {points} points, point {j}"
                );
            }
            let mut moved = q.clone();
            let last = (points - 1) * d;
            moved[last] = f64::from_bits(moved[last].to_bits() + 1);
            let mut other = vec![0.0; points * per];
            at_points(&nb, &moved, &mut other);
            let split = (points - 1) * per;
            assert_eq!(other[..split], lanes[..split]);
            assert_ne!(other[split..], lanes[split..]);
        }
    }
}

/// The gradient at many points, the nodes in vector lanes, is the point-by-point gradient bit
/// for bit ([`lanes_match_pointwise`]).
#[test]
fn gradient_in_lanes_is_the_pointwise_gradient_bit_for_bit() {
    lanes_match_pointwise(
        |dim| 6 * dim,
        |nb, q, out| nb.potential_gradient_at_points(q, out),
        |nb, q, out| nb.potential_gradient(q, out),
    );
}

/// The Hessian's diagonal blocks at many points, the nodes in vector lanes, are the
/// point-by-point blocks bit for bit ([`lanes_match_pointwise`]).
#[test]
fn hessian_blocks_in_lanes_are_the_pointwise_blocks_bit_for_bit() {
    lanes_match_pointwise(
        |dim| 6 * dim * dim,
        |nb, q, out| assert!(nb.potential_hessian_diagonal_blocks_at_points(q, out)),
        |nb, q, out| nb.potential_hessian_diagonal_blocks(q, out),
    );
}

/// Six bodies in `dim` dimensions at nine scattered points, and their full gradients there:
/// (system, D, points, positions point by point, gradients point by point).
fn six_bodies_at_nine_points(dim: usize) -> (NBody, usize, usize, Vec<f64>, Vec<f64>) {
    let nb = NBody::new(vec![1.0, 1e-3, 3e-4, 5e-5, 4e-5, 7e-9], 2.9591e-4, dim).unwrap();
    let (d, points) = (6 * dim, 9);
    let q: Vec<f64> = (0..points * d)
        .map(|i| ((i * 37 % 23) as f64 - 11.0) * 0.7 + (i as f64 * 0.37).sin())
        .collect();
    let mut full = vec![0.0; points * d];
    nb.potential_gradient_at_points(&q, &mut full);
    (nb, d, points, q, full)
}

/// The gradient on some bodies only (`potential_gradient_at_points_on_blocks`): the active
/// bodies' rows are the full gradient's bit for bit, whichever bodies are active (the Sun
/// alone, the innermost pair, a scattered set). Negative control: an inactive body's row,
/// which misses its pairs with the other inactive bodies, differs from its full gradient.
#[test]
fn gradient_on_active_bodies_is_the_full_gradient_there() {
    for dim in [2usize, 3] {
        let (nb, d, points, q, full) = six_bodies_at_nine_points(dim);
        for active in [
            [true, false, false, false, false, false],
            [true, true, false, false, false, false],
            [false, true, false, true, false, true],
        ] {
            let mut some = vec![f64::NAN; points * d];
            nb.potential_gradient_at_points_on_blocks(&q, &active, &mut some);
            let mut inactive_differs = false;
            for j in 0..points {
                for (b, &on) in active.iter().enumerate() {
                    let rows = j * d + b * dim..j * d + (b + 1) * dim;
                    let same = some[rows.clone()]
                        .iter()
                        .zip(&full[rows])
                        .all(|(x, y)| x.to_bits() == y.to_bits());
                    if on {
                        assert!(same, "dim {dim}, active {active:?}, point {j}, body {b}");
                    } else {
                        inactive_differs |= !same;
                    }
                }
            }
            assert!(inactive_differs, "negative control: {active:?}");
        }
    }
}

/// The gradient on some bodies with the points laid out by coordinate
/// (`potential_gradient_at_points_by_coordinate_on_blocks`), in rows padded to whole vectors
/// and in rows of exactly the points: the active bodies' rows are the full gradient's bit for
/// bit, and the inactive bodies' rows are left as they were.
#[test]
fn gradient_by_coordinate_on_active_bodies_is_the_full_gradient_there() {
    use crate::lagrangian::ByCoordinate;
    for dim in [2usize, 3] {
        let (nb, d, points, q, full) = six_bodies_at_nine_points(dim);
        for stride in [points, 16] {
            let layout = ByCoordinate::new(points, stride);
            let mut qt = vec![0.0; d * stride];
            for r in 0..d {
                for j in 0..stride {
                    qt[r * stride + j] = q[j.min(points - 1) * d + r];
                }
            }
            for active in [
                [true, false, false, false, false, false],
                [true, true, false, false, false, false],
                [false, true, false, true, false, true],
            ] {
                let mut some = vec![f64::NAN; d * stride];
                nb.potential_gradient_at_points_by_coordinate_on_blocks(
                    &qt, layout, &active, &mut some,
                );
                for r in 0..d {
                    for j in 0..points {
                        let x = some[r * stride + j];
                        if active[r / dim] {
                            let y = full[j * d + r];
                            assert_eq!(x.to_bits(), y.to_bits(), "dim {dim}, stride {stride}");
                        } else {
                            assert!(x.is_nan(), "inactive row {r} written");
                        }
                    }
                }
            }
        }
    }
}
