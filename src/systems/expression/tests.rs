use super::*;

fn magnetic() -> ExpressionLagrangian {
    ExpressionLagrangian::parse(
        "(x_dot^2 + y_dot^2)/2 + B/2*(x*y_dot - y*x_dot)",
        &["x", "y"],
        &[("B", 2.0)],
    )
    .unwrap()
}

#[test]
fn inverse_legendre_transform_recovers_the_velocity() {
    // Double pendulum: the mass matrix depends on q; p = M(q) v, so v = M(q)⁻¹ p.
    let l = ExpressionLagrangian::parse(
        "th1_dot^2 + th2_dot^2/2 + th1_dot*th2_dot*cos(th1 - th2) + 2*cos(th1) + cos(th2)",
        &["th1", "th2"],
        &[],
    )
    .unwrap();
    let (q, v) = ([0.7, -0.3], [1.1, -0.4]);
    let mut p = [0.0; 2];
    l.legendre_transform(&q, &v, &mut p);
    let back = l.velocity(&q, &p).unwrap();
    for i in 0..2 {
        assert!((back[i] - v[i]).abs() < 1e-14, "{back:?}");
    }
    // A Lagrangian not quadratic in v: L = cosh(v) − x²/2 (p = sinh v), Newton iterates.
    let l = ExpressionLagrangian::parse("cosh(x_dot) - x^2/2", &["x"], &[]).unwrap();
    let v = l.velocity(&[0.2], &[1.5f64.sinh()]).unwrap();
    assert!((v[0] - 1.5).abs() < 1e-14, "{v:?}");
}

#[test]
fn magnetic_time_scale_is_the_cyclotron_period_and_exact_solution_checks_the_state() {
    let l = magnetic();
    // ω = B = 2 (no potential): τ = 2π/2.
    let tau = l.shortest_time_scale(&[0.3, 0.1], &[0.2, -0.5]).unwrap();
    assert!((tau - std::f64::consts::PI).abs() < 1e-12, "{tau}");
    // Circle of radius 1 about the origin, clockwise at frequency B: q = (cos 2t, −sin 2t),
    // q̇(0) = (0, −2), p(0) = (ẋ − B y/2, ẏ + B x/2) = (0, −1).
    let l = l.with_exact_solution(&["cos(B*t)", "-sin(B*t)"]).unwrap();
    let exact = l.exact_solution(0.0, &[1.0, 0.0], &[0.0, -1.0]).unwrap();
    let (q, p) = exact.expect("passes through the state").state(0.25);
    assert!((q[0] - 0.5f64.cos()).abs() < 1e-15 && (q[1] + 0.5f64.sin()).abs() < 1e-15);
    let v = [-2.0 * 0.5f64.sin(), -2.0 * 0.5f64.cos()];
    assert!((p[0] - (v[0] - q[1])).abs() < 1e-15 && (p[1] - (v[1] + q[0])).abs() < 1e-15);
    // Another initial state: the formula does not apply.
    assert!(
        l.exact_solution(0.0, &[1.0, 0.1], &[0.0, -1.0])
            .unwrap()
            .is_none()
    );
    assert!(l.clone().with_exact_solution(&["cos(t)"]).is_err());
    assert!(l.with_exact_solution(&["cos(t)", "sin(x)"]).is_err());
}

#[test]
fn energy_invariant_can_be_switched_off() {
    let l = magnetic().with_energy(false);
    assert!(l.invariant_names().is_empty());
    let mut out: [f64; 0] = [];
    l.invariants(&[0.0, 0.0], &[0.0, 0.0], &mut out);
}

#[test]
fn positions_count_characters_and_keep_tabs() {
    let p = Position::locate("a +\n\tθ + $", 10);
    assert_eq!((p.line, p.column), (2, 6));
    assert_eq!(p.to_string(), "\tθ + $\n\t    ^");
    let end = Position::locate("x +", 99);
    assert_eq!((end.line, end.column), (1, 4));
}

/// The parser (kept here so that parse.rs stays a readable size).
mod parse_tests {
    use super::*;

    fn round_trip(s: &str) -> String {
        parse(s).unwrap().to_string()
    }

    #[test]
    fn precedence_and_associativity() {
        assert_eq!(round_trip("a - b - c"), "a-b-c");
        assert_eq!(round_trip("a - (b - c)"), "a-(b-c)");
        assert_eq!(round_trip("a ^ b ^ c"), "a^b^c");
        assert_eq!(round_trip("(a ^ b) ^ c"), "(a^b)^c");
        assert_eq!(round_trip("-a^2"), "-a^2");
        assert_eq!(round_trip("(-a)^2"), "(-a)^2");
        assert_eq!(round_trip("2^-1"), "2^(-1)");
        assert_eq!(round_trip("a*-b"), "a*-b");
        assert_eq!(round_trip("--a"), "-(-a)");
        assert_eq!(round_trip("a/(b*c)"), "a/(b*c)");
        assert_eq!(round_trip("1.5e-3*atan2(y, x)"), "0.0015*atan2(y, x)");
        assert!(parse("-a^2").unwrap() == parse("-(a^2)").unwrap());
    }

    #[test]
    fn syntax_errors_point_at_the_spot() {
        let e = parse("x +\n  (y * )").unwrap_err();
        match &e {
            ExpressionError::Syntax { at, .. } => assert_eq!((at.line, at.column), (2, 8)),
            other => panic!("{other:?}"),
        }
        let text = e.to_string();
        assert!(text.ends_with("\n  (y * )\n       ^"), "{text}");
        for bad in [
            "", "x +", "(x", "x)", "sin(x", "sin x", "1e", "x $ y", "pow(x)", "x y", "1..2",
        ] {
            assert!(parse(bad).is_err(), "{bad}");
        }
        let deep = "(".repeat(10_000) + "x" + &")".repeat(10_000);
        assert!(parse(&deep).is_err());
        let long = vec!["x"; 10_000].join("+");
        assert!(parse(&long).is_err());
    }

    #[test]
    fn the_deepest_accepted_tree_is_handled_on_a_small_stack() {
        // 999 terms: depth 998, just inside MAX_DEPTH; compiled, evaluated, printed and
        // dropped on a 2 MiB thread (the test harness's default).
        let text = (0..999)
            .map(|i| format!("x_dot^2*{i}"))
            .collect::<Vec<_>>()
            .join(" + ");
        let handle = std::thread::Builder::new()
            .stack_size(2 << 20)
            .spawn(move || {
                let l = crate::systems::ExpressionLagrangian::parse(&text, &["x"], &[]).unwrap();
                let printed = l.expression().to_string();
                let again = parse(&printed).unwrap();
                let mut lvv = [0.0];
                crate::Lagrangian::hessian(&l, &[0.1], &[0.2], &mut [0.0], &mut [0.0], &mut lvv);
                (again == *l.expression(), lvv[0])
            })
            .unwrap();
        let (same, lvv) = handle.join().unwrap();
        assert!(same);
        assert_eq!(lvv, 2.0 * (0..999).sum::<i32>() as f64);
    }
}

/// x'' + δx' − x + x³ = γ cos ωt, written in Rust.
struct RustDuffing;
impl crate::forcing::NonAutonomousLagrangian for RustDuffing {
    fn dim(&self) -> usize {
        1
    }
    fn lagrangian<T: num_dual::DualNum<Primitive = f64> + Copy>(
        &self,
        t: T,
        q: &[T],
        v: &[T],
    ) -> T {
        // The drive as a time-dependent potential term x γ cos ωt; the damping is a force.
        v[0] * v[0] * 0.5 + q[0] * q[0] * 0.5 - q[0].powi(4) * 0.25 + q[0] * (t * 1.2).cos() * 0.5
    }
}

#[test]
fn forced_duffing_from_expressions_matches_the_rust_system() {
    use crate::forcing::{Forced, LinearDamping, NonAutonomous};
    let params = [("delta", 0.3), ("gamma", 0.5), ("omega", 1.2)];
    // The drive as a force in one, as a time-dependent Lagrangian in the other.
    let as_force = ExpressionLagrangian::parse("x_dot^2/2 + x^2/2 - x^4/4", &["x"], &params)
        .unwrap()
        .with_force(&["-delta*x_dot + gamma*cos(omega*t)"])
        .unwrap();
    let as_time = ExpressionLagrangian::parse(
        "x_dot^2/2 + x^2/2 - x^4/4 + x*gamma*cos(omega*t)",
        &["x"],
        &params,
    )
    .unwrap()
    .with_force(&["-delta*x_dot"])
    .unwrap();
    assert!(as_force.is_autonomous() && as_force.is_forced());
    assert!(!as_time.is_autonomous() && as_time.is_time_dependent());
    assert!(as_force.invariant_names().is_empty() && !as_force.is_separable());
    let rust = Forced::new(
        NonAutonomous(RustDuffing),
        LinearDamping::uniform(1, 0.3).unwrap(),
    )
    .unwrap();
    let gvi = crate::GalerkinIntegrator::spectral(12, 0.5).unwrap();
    let run = |l: &dyn Fn() -> crate::Trajectory| l();
    let a = run(&|| gvi.integrate(&as_force, 1.0, &[1.0], &[0.0], 60).unwrap());
    let b = run(&|| gvi.integrate(&as_time, 1.0, &[1.0], &[0.0], 60).unwrap());
    let c = run(&|| gvi.integrate(&rust, 1.0, &[1.0], &[0.0], 60).unwrap());
    for k in 0..=60 {
        assert!((a.q[k][0] - c.q[k][0]).abs() < 1e-12, "k = {k}");
        assert!((b.q[k][0] - c.q[k][0]).abs() < 1e-12, "k = {k}");
    }
    // ∂L/∂t of the expression agrees with the Rust one's.
    let (t, q, v) = (0.7, [0.4], [0.2]);
    let lt = as_time.time_derivative(t, &q, &v);
    assert!((lt - rust.time_derivative(t, &q, &v)).abs() < 1e-15);
    assert!((lt - (-0.4 * 0.5 * 1.2 * (1.2f64 * 0.7).sin())).abs() < 1e-15);
}

#[test]
fn a_force_of_the_wrong_length_or_unknown_symbol_is_refused() {
    let l = ExpressionLagrangian::parse("x_dot^2/2 - x^2/2", &["x"], &[]).unwrap();
    assert!(l.clone().with_force(&["0", "1"]).is_err());
    let err = l.clone().with_force(&["-k*x_dot"]).unwrap_err();
    assert!(err.to_string().contains('k'), "{err}");
    // `t` is a symbol, not a name a parameter may take.
    assert!(ExpressionLagrangian::parse("x_dot^2/2", &["x"], &[("t", 1.0)]).is_err());
    // Negative control: an autonomous L is not time-dependent.
    assert!(l.is_autonomous() && !l.is_forced());
}

/// L = cosh(ẋ) has p = sinh ẋ: the inverse Legendre transform must give v = asinh p for large
/// p. Newton from v = 0 steps to v = p, where sinh p is enormous (and overflows beyond 710),
/// so the iteration is damped. Negative control: the undamped iteration from 0 with the same
/// 50-iteration budget needs all but one of them at p = 48, fails at p = 50 and overflows at
/// p = 1e3.
#[test]
fn inverse_legendre_of_cosh_recovers_asinh_p_for_large_momenta() {
    let l = ExpressionLagrangian::parse("cosh(x_dot) - x^2/2", &["x"], &[]).unwrap();
    for p in [48.0, 50.0, 1e3, 1e6, -1e6] {
        let v = l.velocity(&[0.2], &[p]).unwrap()[0];
        let exact = f64::asinh(p);
        assert!(
            (v - exact).abs() <= 1e-14 * exact.abs(),
            "p = {p}: {v} vs {exact}"
        );
    }
    // A warm start from a nearby velocity gives the same v.
    let v = l.velocity_near(0.0, &[0.2], &[1e3], &[7.5]).unwrap()[0];
    assert!((v - 1e3f64.asinh()).abs() <= 1e-14 * 1e3f64.asinh(), "{v}");
    // The undamped iteration (what velocity did before): Some(iterations) if it reaches
    // asinh p to 1e-14 within 50 iterations.
    let undamped = |p: f64| {
        let mut v = 0.0f64;
        for k in 1..=50 {
            v += (p - v.sinh()) / v.cosh();
            if (v - p.asinh()).abs() <= 1e-14 * p.asinh() {
                return Some(k);
            }
        }
        None
    };
    assert!(
        undamped(48.0).is_some_and(|k| k >= 45),
        "{:?}",
        undamped(48.0)
    );
    assert_eq!(undamped(50.0), None);
    assert_eq!(undamped(1e3), None);
    // A momentum no velocity has (L = √(1 + ẋ²) has |p| = |ẋ|/√(1 + ẋ²) < 1) is a typed
    // error naming the residual, not a panic or a wrong v.
    let bounded = ExpressionLagrangian::parse("sqrt(1 + x_dot^2)", &["x"], &[]).unwrap();
    let err = bounded.velocity(&[0.0], &[2.0]).unwrap_err().to_string();
    assert!(err.contains("residual max|p − ∂L/∂v|"), "{err}");
}
