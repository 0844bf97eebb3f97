//! Expression Lagrangians (`type = "lagrangian"`): the acceptance run of the non-separable
//! magnetic scene against its exact circle, agreement with the same Lagrangians written in
//! Rust, the separable form recognised, the built-in scenes through the library, and every
//! input error through the CLI (typed, non-zero exit, a message, never a panic).

use crate::common::cli;
use cli::gvi;
use galerkin_vi::prelude::*;
use galerkin_vi::systems::ExpressionLagrangian;
use galerkin_vi::systems::expression::ExpressionError;
use galerkin_vi_lab::run::{RunOptions, run_scene};
use galerkin_vi_lab::scene::Scene;

/// The exact motion of the `magnetic` scene, derived here independently of the scene's
/// `exact` strings: ẍ = B ẏ, ÿ = −B ẋ from L = |q̇|²/2 + (B/2)(x ẏ − y ẋ); from q = (1.5, 0.2)
/// with q̇ = (0, −1) and B = 1 the particle runs clockwise round the unit circle about
/// (0.5, 0.2).
fn magnetic_circle(t: f64) -> [f64; 2] {
    [0.5 + t.cos(), 0.2 - t.sin()]
}

fn max_error_against_circle(n: usize, h: f64, steps: usize) -> f64 {
    let mut scene = Scene::load("magnetic").unwrap();
    let system = match &scene.system {
        galerkin_vi_lab::scene::SystemSpec::Lagrangian(spec) => spec.build().unwrap(),
        other => panic!("{other:?}"),
    };
    scene.method.n = n;
    let gvi = GalerkinIntegrator::spectral(n, h).unwrap();
    let traj = gvi
        .integrate(&system, 0.0, &scene.initial.q, &scene.initial.p, steps)
        .unwrap();
    (0..=steps)
        .map(|k| {
            let e = magnetic_circle(traj.time(k));
            (traj.q[k][0] - e[0]).abs().max((traj.q[k][1] - e[1]).abs())
        })
        .fold(0.0, f64::max)
}

#[test]
fn magnetic_scene_matches_its_exact_circle_to_1e9_over_t50() {
    // Acceptance: n = 12, h = 0.5, T = 50. Measured 1.9e-15 (round-off).
    let err = max_error_against_circle(12, 0.5, 100);
    assert!(err < 1e-9, "max position error {err:e}");
    // Control: the test can fail. n = 4 is a cubic per step, error ~h⁴ per step: far above.
    let coarse = max_error_against_circle(4, 0.5, 100);
    assert!(coarse > 1e-6, "n = 4 should miss 1e-9 (got {coarse:e})");
    // The run path uses the scene's own exact solution (through p = ∂L/∂v at t0) and agrees.
    let run = run_scene(
        &Scene::load("magnetic").unwrap().build().unwrap(),
        RunOptions::default(),
    )
    .unwrap();
    let e = run.summary.max_position_error.expect("exact solution used");
    assert!(e < 1e-9, "{e:e}");
    let curve = run.summary.max_curve_error.expect("curve error");
    assert!(curve < 1e-9, "{curve:e}");
    // Energy from the Legendre transform: E = |q̇|²/2 = 1/2, conserved to round-off.
    let (_, energy_error) = &run.summary.invariant_errors[0];
    assert!(*energy_error < 1e-13, "{energy_error:e}");
    let e0 = run.rows[0][run.columns.iter().position(|c| c == "energy").unwrap()];
    assert!((e0 - 0.5).abs() < 1e-15, "{e0}");
}

/// The double pendulum written in Rust, as in the scene (all parameters 1).
struct DoublePendulum;
impl Lagrangian for DoublePendulum {
    fn dim(&self) -> usize {
        2
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        v[0] * v[0]
            + v[1] * v[1] * 0.5
            + v[0] * v[1] * (q[0] - q[1]).cos()
            + q[0].cos() * 2.0
            + q[1].cos()
    }
}

fn double_pendulum_expression() -> ExpressionLagrangian {
    let scene = Scene::load("double-pendulum").unwrap();
    match &scene.system {
        galerkin_vi_lab::scene::SystemSpec::Lagrangian(spec) => spec.build().unwrap(),
        other => panic!("{other:?}"),
    }
}

#[test]
fn double_pendulum_expression_agrees_with_rust() {
    let expr = double_pendulum_expression();
    assert!(!expr.is_separable());
    let (q, v) = ([1.2, -0.4], [0.3, 0.9]);
    let rel = |a: f64, b: f64| (a - b).abs() / (1.0 + b.abs());
    assert!(rel(expr.value(&q, &v), DoublePendulum.value(&q, &v)) < 1e-15);
    let (mut a, mut b, mut c, mut d) = ([0.0; 2], [0.0; 2], [0.0; 2], [0.0; 2]);
    expr.gradient(&q, &v, &mut a, &mut b);
    DoublePendulum.gradient(&q, &v, &mut c, &mut d);
    for i in 0..2 {
        assert!(rel(a[i], c[i]) < 1e-14 && rel(b[i], d[i]) < 1e-14);
    }
    let mut h1 = [[0.0; 4]; 3];
    let mut h2 = [[0.0; 4]; 3];
    {
        let [x, y, z] = &mut h1;
        expr.hessian(&q, &v, x, y, z);
        let [x, y, z] = &mut h2;
        DoublePendulum.hessian(&q, &v, x, y, z);
    }
    for k in 0..3 {
        for i in 0..4 {
            assert!(rel(h1[k][i], h2[k][i]) < 1e-14, "{k} {i}");
        }
    }
    // Same map: trajectories agree to round-off over 40 steps of the scene's method.
    let gvi = GalerkinIntegrator::spectral(16, 0.5).unwrap();
    let (q0, p0) = ([1.5, 0.5], [0.0, 0.0]);
    let t1 = gvi.integrate(&expr, 0.0, &q0, &p0, 40).unwrap();
    let t2 = gvi.integrate(&DoublePendulum, 0.0, &q0, &p0, 40).unwrap();
    let diff = (0..2)
        .map(|i| (t1.q[40][i] - t2.q[40][i]).abs())
        .fold(0.0, f64::max);
    assert!(diff < 1e-9, "{diff:e}");
    // Energy from the Legendre transform: released from rest, E = −V = −3cos 1.5 − cos 0.5.
    let mut e = [0.0];
    expr.invariants(&q0, &p0, &mut e);
    let exact = -2.0 * 1.5f64.cos() - 0.5f64.cos();
    assert!((e[0] - exact).abs() < 1e-15, "{} vs {exact}", e[0]);
}

/// Hénon–Heiles written in Rust as a `Mechanical` system.
struct HenonHeiles;
impl Mechanical for HenonHeiles {
    fn degrees_of_freedom(&self) -> usize {
        2
    }
    fn mass(&self) -> nalgebra::DMatrix<f64> {
        nalgebra::DMatrix::identity(2, 2)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        let (x, y) = (q[0], q[1]);
        (x * x + y * y) * 0.5 + x * x * y - y * y * y / 3.0
    }
}

#[test]
fn henon_heiles_is_recognised_as_separable_and_matches_rust() {
    let scene = Scene::load("henon-heiles").unwrap();
    let expr = match &scene.system {
        galerkin_vi_lab::scene::SystemSpec::Lagrangian(spec) => spec.build().unwrap(),
        other => panic!("{other:?}"),
    };
    assert!(expr.is_separable());
    assert_eq!(
        expr.mass_matrix().unwrap(),
        nalgebra::DMatrix::identity(2, 2)
    );
    let q = [0.3, -0.2];
    let (mut f1, mut f2) = ([0.0; 2], [0.0; 2]);
    expr.force(&q, &mut f1);
    Lagrangian::force(&HenonHeiles, &q, &mut f2);
    assert!((f1[0] - f2[0]).abs() < 1e-15 && (f1[1] - f2[1]).abs() < 1e-15);
    let gvi = scene.method.integrator().unwrap();
    let t1 = gvi
        .integrate(&expr, 0.0, &scene.initial.q, &scene.initial.p, 50)
        .unwrap();
    let t2 = gvi
        .integrate(&HenonHeiles, 0.0, &scene.initial.q, &scene.initial.p, 50)
        .unwrap();
    for i in 0..2 {
        assert!((t1.q[50][i] - t2.q[50][i]).abs() < 1e-12);
    }
    // Control: a non-separable expression is not claimed separable.
    let gyro = ExpressionLagrangian::parse(
        "(x_dot^2 + y_dot^2)/2 + x*y_dot - (x^2 + y^2)/2",
        &["x", "y"],
        &[],
    )
    .unwrap();
    assert!(!gyro.is_separable() && gyro.mass_matrix().is_none());
    // Nor one with a velocity-dependent mass, or a kinetic term of another degree.
    for l in ["x^2*x_dot^2/2 - x^2", "x_dot^4/4 + x_dot^2/2 - x^2/2"] {
        let e = ExpressionLagrangian::parse(l, &["x"], &[]).unwrap();
        assert!(!e.is_separable(), "{l}");
    }
}

#[test]
fn every_expression_scene_runs() {
    for name in ["henon-heiles", "double-pendulum", "magnetic"] {
        let mut scene = Scene::load(name).unwrap();
        assert!(scene.source.contains(','), "{name} cites a source");
        scene.method.steps = 10;
        let run = run_scene(&scene.build().unwrap(), RunOptions::default()).unwrap();
        assert!(run.failure.is_none(), "{name}");
        assert_eq!(run.rows.len(), 11);
        let (_, de) = &run.summary.invariant_errors[0];
        assert!(*de < 1e-9, "{name}: energy error {de:e}");
    }
}

#[test]
fn library_errors_are_typed() {
    let bad =
        |l: &str, c: &[&str], p: &[(&str, f64)]| ExpressionLagrangian::parse(l, c, p).expect_err(l);
    assert!(matches!(
        bad("x_dot^2 +* x", &["x"], &[]),
        GviError::Expression(ExpressionError::Syntax { .. })
    ));
    match bad("x_dot^2/2 - k*x^2", &["x"], &[("m", 1.0)]) {
        GviError::Expression(ExpressionError::UnknownSymbol { name, known, .. }) => {
            assert_eq!(name, "k");
            assert_eq!(known, ["x", "x_dot", "m", "pi", "t"]);
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        bad("x_dot^2/2 - y^2", &["x", "y"], &[]),
        GviError::Expression(ExpressionError::MissingVelocity { coordinate }) if coordinate == "y"
    ));
    assert!(matches!(
        bad("x_dot^2/2 - k*x^2", &["x"], &[("k", f64::NAN)]),
        GviError::Expression(ExpressionError::NonFiniteParameter { .. })
    ));
    assert!(matches!(
        bad("x_dot^2", &["x", "x"], &[]),
        GviError::Expression(ExpressionError::InvalidName { .. })
    ));
    assert!(matches!(
        bad("sin_dot^2", &["sin"], &[]),
        GviError::Expression(ExpressionError::InvalidName { .. })
    ));
    assert!(matches!(
        bad("foo(x_dot)", &["x"], &[]),
        GviError::Expression(ExpressionError::UnknownFunction { .. })
    ));
    // Not regular: L = (x_dot + y_dot)^2/2 has a rank-one velocity Hessian everywhere.
    let degenerate =
        ExpressionLagrangian::parse("(x_dot + y_dot)^2/2 - x^2 - y^2", &["x", "y"], &[]).unwrap();
    assert!(matches!(
        degenerate.check_state(&[0.1, 0.2], &[0.0, 0.0]),
        Err(GviError::Expression(
            ExpressionError::SingularHessian { .. }
        ))
    ));
    assert!(matches!(
        degenerate.check_state(&[0.1], &[0.0, 0.0]),
        Err(GviError::DimensionMismatch {
            expected: 2,
            got: 1,
            ..
        })
    ));
    // Regular away from q = 0 only: L = x²ẋ²/2 is singular at x = 0.
    let l = ExpressionLagrangian::parse("x^2*x_dot^2/2 - x^2/2", &["x"], &[]).unwrap();
    assert!(l.check_state(&[0.5], &[0.1]).is_ok());
    assert!(l.check_state(&[0.0], &[0.1]).is_err());
}

fn scene_file(dir: &std::path::Path, name: &str, system: &str, q: &str, p: &str) -> String {
    let path = dir.join(format!("{name}.toml"));
    let text = format!(
        "[system]\ntype = \"lagrangian\"\n{system}\n[initial]\nq = {q}\np = {p}\n\
         [method]\nn = 8\nh = 0.5\nsteps = 4\n"
    );
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

fn assert_clean_failure(args: &[&str], needles: &[&str]) {
    let (code, _, err) = gvi(args);
    assert_ne!(code, 0, "{args:?} should fail");
    for needle in needles {
        assert!(
            err.contains(needle),
            "{args:?}: stderr lacks {needle:?}:\n{err}"
        );
    }
    assert!(!err.contains("panicked"), "{args:?} panicked:\n{err}");
}

#[test]
fn cli_reports_expression_errors_without_panicking() {
    let dir = std::env::temp_dir().join(format!("gvi-expression-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let xy = "coordinates = [\"x\", \"y\"]";
    // A syntax error on the second line of a multi-line Lagrangian (TOML drops the newline
    // right after `"""`): line and column within the string, and a caret under the spot.
    let f = scene_file(
        &dir,
        "syntax",
        &format!("{xy}\nlagrangian = \"\"\"\n(x_dot^2 + y_dot^2)/2\n  - (x^2 + * y^2)/2\"\"\""),
        "[0.1, 0.0]",
        "[0.0, 0.3]",
    );
    assert_clean_failure(
        &["run", &f],
        &[
            "syntax error at line 2, column 12",
            "  - (x^2 + * y^2)/2\n           ^",
        ],
    );
    // An unknown symbol, listing the known ones.
    let f = scene_file(
        &dir,
        "unknown",
        &format!(
            "{xy}\nparameters = {{ k = 2.0 }}\nlagrangian = \"(x_dot^2 + y_dot^2)/2 - kk*x^2\""
        ),
        "[0.1, 0.0]",
        "[0.0, 0.3]",
    );
    assert_clean_failure(
        &["check", &f],
        &[
            "unknown symbol `kk`",
            "known symbols: x, y, x_dot, y_dot, k, pi",
        ],
    );
    // A coordinate whose velocity never occurs.
    let f = scene_file(
        &dir,
        "novel",
        &format!("{xy}\nlagrangian = \"x_dot^2/2 - x^2/2 - y^2\""),
        "[0.1, 0.0]",
        "[0.0, 0.3]",
    );
    assert_clean_failure(&["run", &f], &["coordinate `y` has no velocity"]);
    // A non-finite parameter (TOML has nan and inf literals).
    let f = scene_file(
        &dir,
        "nan",
        &format!(
            "{xy}\nparameters = {{ k = nan }}\nlagrangian = \"(x_dot^2 + y_dot^2)/2 - k*x^2\""
        ),
        "[0.1, 0.0]",
        "[0.0, 0.3]",
    );
    assert_clean_failure(&["run", &f], &["parameter `k` = NaN is not finite"]);
    // Not regular at the initial state.
    let f = scene_file(
        &dir,
        "singular",
        &format!("{xy}\nlagrangian = \"(x_dot + y_dot)^2/2 - (x^2 + y^2)/2\""),
        "[0.1, 0.0]",
        "[0.0, 0.3]",
    );
    assert_clean_failure(&["run", &f], &["not regular", "singular"]);
    // Wrong lengths of q and p.
    let ok = format!("{xy}\nlagrangian = \"(x_dot^2 + y_dot^2)/2 - (x^2 + y^2)/2\"");
    let f = scene_file(&dir, "shortq", &ok, "[0.1]", "[0.0, 0.3]");
    assert_clean_failure(&["run", &f], &["dimension mismatch", "expected 2, got 1"]);
    let f = scene_file(&dir, "longp", &ok, "[0.1, 0.0]", "[0.0, 0.3, 1.0]");
    assert_clean_failure(
        &["refine", &f, "--vary", "n", "--range", "4:8:2"],
        &["expected 2, got 3"],
    );
    // Overrides of the state are checked too.
    assert_clean_failure(
        &["run", "magnetic", "--p0", "1,2,3"],
        &["expected 2, got 3"],
    );
    assert_clean_failure(
        &["run", "henon-heiles", "--q0", "0.1"],
        &["expected 2, got 1"],
    );
    // An unknown key in [system] is still a scene error.
    let f = scene_file(
        &dir,
        "typo",
        &format!("{ok}\nparameter = {{ k = 1 }}"),
        "[0.1, 0.0]",
        "[0.0, 0.3]",
    );
    assert_clean_failure(&["run", &f], &["unknown field `parameter`"]);
    // The same file with valid content runs.
    let f = scene_file(&dir, "fine", &ok, "[0.1, 0.0]", "[0.0, 0.3]");
    let (code, out, err) = gvi(&["run", &f]);
    assert_eq!(code, 0, "{err}");
    assert!(out.lines().count() == 6, "{out}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A bad `exact` (or `force`) formula is an error naming that key and entry, not one blamed on
/// line 1 of the Lagrangian. The docs once showed `exact = ["...", "..."]` as a placeholder;
/// copied, it failed with `expression Lagrangian: syntax error at line 1`.
#[test]
fn a_bad_exact_or_force_formula_names_its_key() {
    let dir = std::env::temp_dir().join(format!("gvi-expression-exact-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let oscillator = "coordinates = [\"x\", \"y\"]\n\
                      lagrangian = \"(x_dot^2 + y_dot^2)/2 - (x^2 + y^2)/2\"";
    let placeholder = scene_file(
        &dir,
        "placeholder",
        &format!("{oscillator}\nexact = [\"...\", \"...\"]"),
        "[1.0, 0.0]",
        "[0.0, 0.5]",
    );
    assert_clean_failure(
        &["run", &placeholder],
        &["`exact` entry 1 of 2 (q(t) of `x`)", "syntax error"],
    );
    let (_, _, err) = gvi(&["run", &placeholder]);
    assert!(!err.contains("expression Lagrangian"), "{err}");
    let unknown = scene_file(
        &dir,
        "unknown",
        &format!("{oscillator}\nexact = [\"cos(t)\", \"s*sin(t)\"]"),
        "[1.0, 0.0]",
        "[0.0, 0.5]",
    );
    assert_clean_failure(
        &["run", &unknown],
        &["`exact` entry 2 of 2 (q(t) of `y`)", "unknown symbol `s`"],
    );
    let force = scene_file(
        &dir,
        "force",
        &format!("{oscillator}\nforce = [\"0\", \"-x_dott\"]"),
        "[1.0, 0.0]",
        "[0.0, 0.5]",
    );
    assert_clean_failure(
        &["run", &force],
        &[
            "`force` entry 2 of 2 (the force on `y`)",
            "unknown symbol `x_dott`",
        ],
    );
    // Negative control: an error in the Lagrangian itself still says so.
    let lagrangian = scene_file(
        &dir,
        "lagrangian",
        "coordinates = [\"x\"]\nlagrangian = \"x_dot^2/2 - (x^2\"",
        "[1.0]",
        "[0.0]",
    );
    assert_clean_failure(
        &["run", &lagrangian],
        &["expression Lagrangian: syntax error"],
    );
    // The real formula runs and is used: errors against it are reported.
    let real = scene_file(
        &dir,
        "real",
        &format!("{oscillator}\nexact = [\"cos(t)\", \"0.5*sin(t)\"]"),
        "[1.0, 0.0]",
        "[0.0, 0.5]",
    );
    let (code, _, err) = gvi(&["run", &real, "--output", "/dev/null"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("max position error at step ends"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The user's coordinate names label the CSV header, the JSON columns and the chart axes
/// (`theta`, `p_theta`); a scene without `name` and `description` gets a chart title without
/// a dangling dash.
#[test]
fn the_users_coordinate_names_label_every_output() {
    let dir = std::env::temp_dir().join(format!("gvi-expression-names-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = scene_file(
        &dir,
        "swing",
        "coordinates = [\"theta\"]\nlagrangian = \"theta_dot^2/2 + cos(theta)\"",
        "[1.0]",
        "[0.0]",
    );
    let csv = dir.join("swing.csv");
    let svg = dir.join("swing.svg");
    let json = dir.join("swing.json");
    let csv_s = csv.to_string_lossy().into_owned();
    let svg_s = svg.to_string_lossy().into_owned();
    let json_s = json.to_string_lossy().into_owned();
    // Streamed (no chart), in memory with a chart, and JSON.
    for args in [
        vec!["run", &f, "--output", &csv_s],
        vec!["run", &f, "--output", &csv_s, "--plot", &svg_s],
    ] {
        let (code, _, err) = gvi(&args);
        assert_eq!(code, 0, "{err}");
        let text = std::fs::read_to_string(&csv).unwrap();
        let header = text.lines().next().unwrap();
        assert_eq!(header, "step,t,theta,p_theta,energy", "{args:?}");
    }
    let (code, _, err) = gvi(&["run", &f, "--format", "json", "--output", &json_s]);
    assert_eq!(code, 0, "{err}");
    let value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(
        value["columns"],
        serde_json::json!(["step", "t", "theta", "p_theta", "energy"])
    );
    let chart = std::fs::read_to_string(&svg).unwrap();
    assert!(chart.contains(">\ntheta\n</text>"), "no theta axis label");
    assert!(!chart.contains(">\nq\n</text>"), "a q axis label is left");
    // The title is the scene's origin alone, no "—".
    assert!(!chart.contains(" —"), "dangling dash in the title");
    // Negative control: with a description the title is `name — description`.
    let described = dir.join("described.toml");
    let text = std::fs::read_to_string(&f).unwrap();
    std::fs::write(
        &described,
        format!("name = \"swing\"\ndescription = \"a pendulum\"\n{text}"),
    )
    .unwrap();
    let (code, _, err) = gvi(&[
        "run",
        &described.to_string_lossy(),
        "--output",
        &csv_s,
        "--plot",
        &svg_s,
    ]);
    assert_eq!(code, 0, "{err}");
    let chart = std::fs::read_to_string(&svg).unwrap();
    assert!(chart.contains("swing — a pendulum"), "title");
    // Built-in scenes keep their documented numbered columns (scripts and the Python tests
    // read q0, p1 of kepler.csv); the Kepler chart's axes are x and y.
    let (code, out, err) = gvi(&["run", "kepler", "--steps", "3"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("step,t,q0,q1,p0,p1,"), "{out}");
    let kepler_svg = dir.join("kepler.svg");
    let kepler_svg_s = kepler_svg.to_string_lossy().into_owned();
    let (code, _, err) = gvi(&[
        "run",
        "kepler",
        "--steps",
        "3",
        "--output",
        "/dev/null",
        "--plot",
        &kepler_svg_s,
    ]);
    assert_eq!(code, 0, "{err}");
    let chart = std::fs::read_to_string(&kepler_svg).unwrap();
    assert!(chart.contains(">\nx\n</text>") && chart.contains(">\ny\n</text>"));
    std::fs::remove_dir_all(&dir).ok();
}
