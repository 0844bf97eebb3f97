//! Recognising the separable mechanical form L = ½ vᵀ M v + U(q) in an expression, so that
//! expression Lagrangians like Hénon–Heiles get the integrator's separable path (constant
//! kinetic part of the stage Jacobian, force evaluations only) and the classical baselines,
//! exactly as a [`Mechanical`](crate::Mechanical) system written in Rust.
//!
//! The test is structural, not numerical: L is split into its additive terms (through `+`,
//! `−` and unary minus); every term must depend on q only, or be a homogeneous quadratic in v
//! with constant coefficients. The mass matrix is the Hessian of the kinetic terms (constant by
//! construction) and must be symmetric positive definite; otherwise the general path is used.

use super::eval::{Symbol, Tape};
use super::parse::{BinOp, Expr, Func};

/// The separable split: the mass matrix M (row-major) and the compiled U(q) = L − ½ vᵀ M v.
#[derive(Debug, Clone)]
pub(crate) struct Separable {
    pub mass: Vec<f64>,
    pub potential: Tape,
}

/// Degree in v of a term free of q: `Some(k)` if homogeneous of degree k with constant
/// coefficients, `None` otherwise (or if it reads q).
fn degree(e: &Expr, class: &impl Fn(&str) -> Option<Symbol>) -> Option<u32> {
    match e {
        Expr::Num(_) => Some(0),
        Expr::Sym { name, .. } => match class(name)? {
            Symbol::Value(_) => Some(0),
            Symbol::V(_) => Some(1),
            Symbol::Q(_) => None,
        },
        Expr::Neg(a) => degree(a, class),
        Expr::Bin(op, a, b) => {
            let (da, db) = (degree(a, class)?, degree(b, class)?);
            match op {
                BinOp::Add | BinOp::Sub => (da == db).then_some(da),
                BinOp::Mul => Some(da + db),
                BinOp::Div => (db == 0).then_some(da),
                BinOp::Pow => match (da, b.as_ref()) {
                    (0, _) if db == 0 => Some(0),
                    (_, Expr::Num(k)) if k.fract() == 0.0 && *k >= 0.0 && *k <= 8.0 => {
                        Some(da * *k as u32)
                    }
                    _ => None,
                },
            }
        }
        Expr::Call(f, args) => {
            let ds: Option<Vec<u32>> = args.iter().map(|a| degree(a, class)).collect();
            let ds = ds?;
            match (f, ds.as_slice(), args.as_slice()) {
                (_, ds, _) if ds.iter().all(|&d| d == 0) => Some(0),
                (Func::Pow, [d, 0], [_, Expr::Num(k)])
                    if k.fract() == 0.0 && *k >= 0.0 && *k <= 8.0 =>
                {
                    Some(d * *k as u32)
                }
                _ => None,
            }
        }
    }
}

/// Whether `e` reads any velocity.
fn reads_velocity(e: &Expr, class: &impl Fn(&str) -> Option<Symbol>) -> bool {
    let mut found = false;
    e.for_each_symbol(&mut |name, _| {
        if matches!(class(name), Some(Symbol::V(_))) {
            found = true;
        }
    });
    found
}

/// The additive terms of `e` with their signs.
fn terms<'a>(e: &'a Expr, positive: bool, out: &mut Vec<(bool, &'a Expr)>) {
    match e {
        Expr::Bin(BinOp::Add, a, b) => {
            terms(a, positive, out);
            terms(b, positive, out);
        }
        Expr::Bin(BinOp::Sub, a, b) => {
            terms(a, positive, out);
            terms(b, !positive, out);
        }
        Expr::Neg(a) => terms(a, !positive, out),
        _ => out.push((positive, e)),
    }
}

/// A balanced sum of signed terms (balanced so that compiling it recurses only log-deep).
fn sum(terms: &[(bool, &Expr)]) -> Expr {
    match terms {
        [] => Expr::Num(0.0),
        [(true, e)] => (*e).clone(),
        [(false, e)] => Expr::Neg(Box::new((*e).clone())),
        _ => {
            let (a, b) = terms.split_at(terms.len() / 2);
            Expr::Bin(BinOp::Add, Box::new(sum(a)), Box::new(sum(b)))
        }
    }
}

/// The separable split of `expr`, if it has one with a positive-definite mass matrix.
pub(crate) fn split(
    expr: &Expr,
    text: &str,
    symbols: &[(String, Symbol)],
    d: usize,
) -> Option<Separable> {
    let class = |name: &str| symbols.iter().find(|(n, _)| n == name).map(|(_, s)| *s);
    let mut all = Vec::new();
    terms(expr, true, &mut all);
    let (mut kinetic, mut potential) = (Vec::new(), Vec::new());
    for (sign, term) in all {
        if !reads_velocity(term, &class) {
            potential.push((sign, term));
        } else if degree(term, &class) == Some(2) {
            kinetic.push((sign, term));
        } else {
            return None;
        }
    }
    let kinetic_tape = Tape::compile(&sum(&kinetic), text, symbols).ok()?;
    let potential = Tape::compile(&sum(&potential), text, symbols).ok()?;
    // M = ∂²T/∂v² (T quadratic: the Hessian at v = 0 is exact and constant).
    let zeros = vec![0.0; d];
    let (mut g, mut mass) = (vec![0.0; d], vec![0.0; d * d]);
    let q0: Vec<num_dual::HyperDual64> = zeros.iter().map(|&x| x.into()).collect();
    crate::ad::hessian(|v| kinetic_tape.eval(&q0, v), &zeros, &mut g, &mut mass);
    let m = nalgebra::DMatrix::from_row_slice(d, d, &mass);
    let symmetric = (0..d).all(|r| (0..d).all(|s| m[(r, s)] == m[(s, r)]));
    (symmetric && m.iter().all(|x| x.is_finite()) && m.cholesky().is_some())
        .then_some(Separable { mass, potential })
}
