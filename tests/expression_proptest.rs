//! Property tests of the expression language: random expression trees print to text that
//! parses back to the same tree; random trees compile and evaluate (values, gradients,
//! Hessians) without panicking; random text never makes the parser panic.

use galerkin_vi::Lagrangian;
use galerkin_vi::systems::ExpressionLagrangian;
use galerkin_vi::systems::expression::{BinOp, Expr, Func, parse};
use proptest::prelude::*;

const NAMES: [&str; 6] = ["x", "y", "x_dot", "y_dot", "k", "pi"];

fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        (0u32..20).prop_map(f64::from),
        (0.0f64..10.0),
        (-300i32..300).prop_map(|e| 10f64.powi(e)),
        Just(0.1),
        Just(1.5e-7),
    ]
}

fn expr() -> impl Strategy<Value = Expr> {
    let leaf = prop_oneof![
        number().prop_map(Expr::Num),
        (0..NAMES.len()).prop_map(|i| Expr::Sym {
            name: NAMES[i].to_string(),
            at: 0,
        }),
    ];
    leaf.prop_recursive(6, 64, 2, |inner| {
        let ops = [BinOp::Add, BinOp::Sub, BinOp::Mul, BinOp::Div, BinOp::Pow];
        prop_oneof![
            inner.clone().prop_map(|a| Expr::Neg(Box::new(a))),
            (0..ops.len(), inner.clone(), inner.clone()).prop_map(move |(o, a, b)| Expr::Bin(
                ops[o],
                Box::new(a),
                Box::new(b)
            )),
            (0..Func::ALL.len(), inner.clone(), inner).prop_map(|(f, a, b)| {
                let func = Func::ALL[f];
                let args = if func.arity() == 2 {
                    vec![a, b]
                } else {
                    vec![a]
                };
                Expr::Call(func, args)
            }),
        ]
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn printing_round_trips(e in expr()) {
        let text = e.to_string();
        let back = parse(&text).map_err(|err| TestCaseError::fail(format!("{text}: {err}")))?;
        prop_assert_eq!(&back, &e, "{}", text);
        prop_assert_eq!(back.to_string(), text);
    }

    #[test]
    fn random_trees_compile_and_evaluate_without_panicking(
        e in expr(),
        q in prop::array::uniform2(-3.0f64..3.0),
        v in prop::array::uniform2(-3.0f64..3.0),
    ) {
        // Make sure both velocities occur, so that most trees are accepted.
        let text = format!("{e} + x_dot^2 + y_dot^2");
        let l = ExpressionLagrangian::parse(&text, &["x", "y"], &[("k", 0.7)])
            .map_err(|err| TestCaseError::fail(format!("{text}: {err}")))?;
        let value = l.value(&q, &v);
        // The tape agrees with a direct recursive evaluation of the tree (NaN with NaN).
        let direct = eval(&e, &q, &v) + v[0] * v[0] + v[1] * v[1];
        prop_assert!(
            value == direct
                || (value.is_nan() && direct.is_nan())
                || approx::relative_eq!(value, direct, epsilon = 1e-12, max_relative = 1e-12),
            "{}: tape {} vs tree {}", text, value, direct
        );
        let (mut lq, mut lv) = ([0.0; 2], [0.0; 2]);
        l.gradient(&q, &v, &mut lq, &mut lv);
        let (mut a, mut b, mut c) = ([0.0; 4], [0.0; 4], [0.0; 4]);
        l.hessian(&q, &v, &mut a, &mut b, &mut c);
        let _ = l.check_state(&q, &v);
    }

    #[test]
    fn random_text_never_panics(text in "[xy_dotk0-9.eE+*/^()\\-, \nsincoqrtpwah2]{0,40}") {
        let _ = parse(&text);
        let _ = ExpressionLagrangian::parse(&text, &["x", "y"], &[("k", 1.0)]);
    }

    #[test]
    fn arbitrary_unicode_never_panics(text in "\\PC{0,30}") {
        let _ = parse(&text);
        let _ = ExpressionLagrangian::parse(&text, &["x"], &[]);
    }
}

/// Whether the subtree reads no coordinate or velocity (the tape folds it to a number).
fn constant(e: &Expr) -> bool {
    let mut c = true;
    e.for_each_symbol(&mut |name, _| c &= matches!(name, "k" | "pi"));
    c
}

/// a^b as the tape computes it: a constant exponent picks the square, square root or integer
/// power (the rounding differs from `powf`, and sin(y^14) amplifies that), a variable one is
/// num-dual's `powd` (in f64, `powf`).
fn power(a: f64, b: f64, constant_exponent: bool) -> f64 {
    if !constant_exponent {
        a.powf(b)
    } else if b == 1.0 {
        a
    } else if b == 0.0 {
        1.0
    } else if b == 2.0 {
        a * a
    } else if b == 0.5 {
        a.sqrt()
    } else if b.fract() == 0.0 && b.abs() <= 64.0 {
        a.powi(b as i32)
    } else {
        a.powf(b)
    }
}

/// A direct recursive evaluation of the tree in f64 (the reference for the compiled tape),
/// with the tape's choice of power function.
fn eval(e: &Expr, q: &[f64; 2], v: &[f64; 2]) -> f64 {
    match e {
        Expr::Num(x) => *x,
        Expr::Sym { name, .. } => match name.as_str() {
            "x" => q[0],
            "y" => q[1],
            "x_dot" => v[0],
            "y_dot" => v[1],
            "k" => 0.7,
            _ => std::f64::consts::PI,
        },
        Expr::Neg(a) => -eval(a, q, v),
        Expr::Bin(op, a, b) => {
            let constant_exponent = constant(b);
            let (a, b) = (eval(a, q, v), eval(b, q, v));
            match op {
                BinOp::Add => a + b,
                BinOp::Sub => a - b,
                BinOp::Mul => a * b,
                BinOp::Div => a / b,
                BinOp::Pow => power(a, b, constant_exponent),
            }
        }
        Expr::Call(f, args) => {
            let a = eval(&args[0], q, v);
            match f {
                Func::Sin => a.sin(),
                Func::Cos => a.cos(),
                Func::Tan => a.tan(),
                Func::Exp => a.exp(),
                Func::Log => a.ln(),
                Func::Sqrt => a.sqrt(),
                Func::Abs => a.abs(),
                Func::Sinh => a.sinh(),
                Func::Cosh => a.cosh(),
                Func::Tanh => a.tanh(),
                Func::Pow => power(a, eval(&args[1], q, v), constant(&args[1])),
                Func::Atan2 => a.atan2(eval(&args[1], q, v)),
            }
        }
    }
}
