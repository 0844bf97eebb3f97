//! Records the maps of the built-in methods, for the "same maps" regression check.
//!
//! Cases: every built-in basis × quadrature (default points; Gauss–Legendre also with ⌈3n/2⌉
//! and n points) × stage solver on Kepler (e = 0.6); the Chebyshev and the Legendre basis ×
//! every stage solver on the other systems (oscillator, pendulum, Hénon–Heiles, a magnetic and a
//! double-pendulum expression Lagrangian (non-separable), a double well differentiated by AD, the
//! figure-eight three-body choreography and the outer solar system); a few tolerance-driven
//! (adaptive n) runs; Lie group runs on SO(3); periodic orbits (`periodic::solve`: the
//! figure-eight at prescribed energy and at fixed period, the oscillator and the pendulum, and
//! negative controls); the Gauss collocation baseline (s = 2 … 4, its three entry points). A
//! combination that fails (e.g. the trapezoid rule with a polynomial basis) records its error
//! message.
//!
//! One line per case: its id, then `ok` and `name[index]=value|bits` tokens — the state after
//! the first step (`q1`, `p1`: the one-step map itself) and at the end (`q`, `p`), a few
//! Galerkin coefficients of the first, middle and last step, dense output q(t) and q̇(t) at
//! three interior times (`x@j`, `v@j`), each value as `{:e}` with 17 significant digits and its
//! `f64::to_bits` in hex — or `error` and the message. Tokens without `|` (the n of each
//! adaptive step) are compared as text.
//!
//! The output is plain text and deterministic. `scripts/same-maps.sh [BASE_COMMIT]` runs this
//! example at a base commit and in the current checkout and compares the two recordings with
//! `scripts/compare-maps.py` (bit-identical, or within 1e-14 relative). It uses only the
//! stable public API, so that the same file builds at the base commit.
//!
//! Run: `cargo run --release --example record_maps -p galerkin-vi > maps.txt`

use galerkin_vi::adaptive::{AdaptiveOptions, integrate_adaptive};
use galerkin_vi::baselines::{
    GaussCollocationBaseline, OneStepMethod, States, StaticKernel, integrate_one_step,
};
use galerkin_vi::basis::BasisKind;
use galerkin_vi::integrator::StageSolver;
use galerkin_vi::lie::so3::{Mat3, Retraction};
use galerkin_vi::lie::{FreeRigidBody, HeavyTop, LieGalerkin, LieTrajectory, RigidBody};
use galerkin_vi::periodic::{
    self, FourierCurve, Layout, PeriodCondition, PeriodicOptions, PeriodicSolution, Symmetry,
};
use galerkin_vi::quadrature::QuadratureKind;
use galerkin_vi::systems::{ExpressionLagrangian, HarmonicOscillator, Kepler, NBody, Pendulum};
use galerkin_vi::{DualNum, GalerkinIntegrator, Lagrangian, NewtonOptions, Trajectory};
use std::error::Error;
use std::fmt::Write as _;
use std::io::Write as _;

type Res<T> = Result<T, Box<dyn Error>>;

/// Appends ` name[i]=value|bits` for each value (index labels from `labels`).
fn push_values(line: &mut String, name: &str, labels: &[String], values: &[f64]) {
    for (label, v) in labels.iter().zip(values) {
        let _ = write!(line, " {name}[{label}]={v:.16e}|{:016x}", v.to_bits());
    }
}

fn push_vector(line: &mut String, name: &str, values: &[f64]) {
    let labels: Vec<String> = (0..values.len()).map(|i| i.to_string()).collect();
    push_values(line, name, &labels, values);
}

/// One line of text: newlines in error messages would break the format.
fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn error_line(id: &str, stage: &str, e: &dyn std::fmt::Display) -> String {
    format!("{id} error {stage}: {}", one_line(&e.to_string()))
}

/// Three interior times, inside steps ⌊s/5⌋, ⌊s/2⌋ and ⌊4s/5⌋ at τ = 0.3, 0.61, 0.87.
fn dense_times(t0: f64, h: f64, steps: usize) -> [f64; 3] {
    let at = |k: usize, tau: f64| t0 + (k as f64 + tau) * h;
    [
        at(steps / 5, 0.3),
        at(steps / 2, 0.61),
        at((4 * steps) / 5, 0.87),
    ]
}

/// The recorded values of a Euclidean trajectory.
fn trajectory_tokens(line: &mut String, traj: &Trajectory, t0: f64, h: f64) -> Res<()> {
    let steps = traj.q.len() - 1;
    // The one-step map from the initial state (no propagation of round-off differences over
    // the run), then the final state.
    push_vector(line, "q1", &traj.q[1]);
    push_vector(line, "p1", &traj.p[1]);
    push_vector(line, "q", &traj.q[steps]);
    push_vector(line, "p", &traj.p[steps]);
    // A few Galerkin coefficients of the first, the middle and the last step: the first three
    // and the last three of the n×D row-major array.
    for k in [0, steps / 2, steps - 1] {
        let c = &traj.coefficients[k];
        let mut idx: Vec<usize> = (0..c.len().min(3)).collect();
        idx.extend(c.len().saturating_sub(3).max(idx.len())..c.len());
        let labels: Vec<String> = idx.iter().map(|i| format!("{k},{i}")).collect();
        let values: Vec<f64> = idx.iter().map(|&i| c[i]).collect();
        push_values(line, "coef", &labels, &values);
    }
    for (j, t) in dense_times(t0, h, steps).into_iter().enumerate() {
        push_vector(line, &format!("x@{j}"), &traj.position_at(t)?);
        push_vector(line, &format!("v@{j}"), &traj.velocity_at(t)?);
    }
    Ok(())
}

/// A run of the fixed-n integrator.
struct Run<'a> {
    system: &'a str,
    basis: BasisKind,
    n: usize,
    quadrature: QuadratureKind,
    /// Quadrature points (`None`: the kind's default for n).
    points: Option<usize>,
    h: f64,
    steps: usize,
}

impl Run<'_> {
    fn id(&self, solver: StageSolver) -> String {
        let points = self
            .points
            .map_or_else(|| "default".to_string(), |m| m.to_string());
        format!(
            "{}/{}/n{}/{}:{}/h{}/s{}/{}",
            self.system,
            self.basis.as_str(),
            self.n,
            self.quadrature.as_str(),
            points,
            self.h,
            self.steps,
            solver.as_str()
        )
    }

    /// Runs every stage solver; one line each.
    fn record<L: Lagrangian>(&self, out: &mut Vec<String>, sys: &L, q0: &[f64], p0: &[f64]) {
        for solver in StageSolver::ALL {
            out.push(self.line(solver, sys, q0, p0));
        }
    }

    fn line<L: Lagrangian>(&self, solver: StageSolver, sys: &L, q0: &[f64], p0: &[f64]) -> String {
        let id = self.id(solver);
        let gvi = match GalerkinIntegrator::from_kinds(
            self.basis,
            self.n,
            self.quadrature,
            self.points,
            self.h,
        ) {
            Ok(g) => g.with_options(NewtonOptions {
                solver,
                ..NewtonOptions::default()
            }),
            Err(e) => return error_line(&id, "construct", &e),
        };
        let t0 = 0.0;
        let traj = match gvi.integrate(sys, t0, q0, p0, self.steps) {
            Ok(t) => t,
            Err(e) => return error_line(&id, "integrate", &e),
        };
        let mut line = format!("{id} ok");
        match trajectory_tokens(&mut line, &traj, t0, self.h) {
            Ok(()) => line,
            Err(e) => error_line(&id, "dense output", &*e),
        }
    }
}

/// A particle in a double well, L = v²/2 − (q² − 1)²/4, with derivatives from AD only.
struct DoubleWell;

impl Lagrangian for DoubleWell {
    fn dim(&self) -> usize {
        1
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T], v: &[T]) -> T {
        let w = q[0] * q[0] - 1.0;
        v[0] * v[0] * 0.5 - w * w * 0.25
    }
}

fn kepler_cases(out: &mut Vec<String>) -> Res<()> {
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    // Every basis × every quadrature (default points; Gauss–Legendre also with the economical
    // ⌈3n/2⌉ and the compact n points) × every solver.
    let (n, h, steps): (usize, f64, usize) = (12, 1.0, 30);
    for basis in BasisKind::ALL {
        for quadrature in [
            QuadratureKind::GaussLegendre,
            QuadratureKind::GaussLobatto,
            QuadratureKind::ClenshawCurtis,
            QuadratureKind::Trapezoid,
        ] {
            let mut points = vec![None];
            if quadrature == QuadratureKind::GaussLegendre {
                points.push(Some((3 * n).div_ceil(2)));
                // The compact rule (n points) is too weak for the Fourier basis: its map is
                // ill-posed there (the solvers converge to different solutions).
                if basis != BasisKind::Fourier {
                    points.push(Some(n));
                }
            }
            for points in points {
                let run = Run {
                    system: "kepler",
                    basis,
                    n,
                    quadrature,
                    points,
                    h,
                    steps,
                };
                run.record(out, &kepler, &q0, &p0);
            }
        }
    }
    // A second (n, h) with the default rule.
    for basis in BasisKind::ALL {
        let run = Run {
            system: "kepler",
            basis,
            n: 16,
            quadrature: QuadratureKind::GaussLegendre,
            points: None,
            h: 0.5,
            steps: 40,
        };
        run.record(out, &kepler, &q0, &p0);
    }
    Ok(())
}

/// The Chebyshev and the Legendre basis, 2n Gauss–Legendre points, every solver.
fn record_system<L: Lagrangian>(
    out: &mut Vec<String>,
    system: &str,
    sys: &L,
    (q0, p0): (&[f64], &[f64]),
    n: usize,
    h: f64,
    steps: usize,
) {
    for basis in [BasisKind::Chebyshev, BasisKind::Legendre] {
        let run = Run {
            system,
            basis,
            n,
            quadrature: QuadratureKind::GaussLegendre,
            points: None,
            h,
            steps,
        };
        run.record(out, sys, q0, p0);
    }
}

/// The outer solar system of Hairer, Lubich & Wanner §I.2.4 (scenes/outer-solar-system.toml)
/// without Pluto: Sun (with the inner planets), Jupiter, Saturn, Uranus, Neptune; AU, days,
/// solar masses, barycentric.
fn outer_solar_system() -> Res<(NBody, Vec<f64>, Vec<f64>)> {
    // (mass, position, velocity), heliocentric.
    let bodies: [(f64, [f64; 3], [f64; 3]); 5] = [
        (1.00000597682, [0.0; 3], [0.0; 3]),
        (
            0.000954786104043,
            [-3.5023653, -3.8169847, -1.5507963],
            [0.00565429, -0.00412490, -0.00190589],
        ),
        (
            0.000285583733151,
            [9.0755314, -3.0458353, -1.6483708],
            [0.00168318, 0.00483525, 0.00192462],
        ),
        (
            0.0000437273164546,
            [8.3101420, -16.2901086, -7.2521278],
            [0.00354178, 0.00137102, 0.00055029],
        ),
        (
            0.0000517759138449,
            [11.4707666, -25.7294829, -10.8169456],
            [0.00288930, 0.00114527, 0.00039677],
        ),
    ];
    let masses = bodies.iter().map(|b| b.0).collect();
    let mut q: Vec<f64> = bodies.iter().flat_map(|b| b.1).collect();
    let mut v: Vec<f64> = bodies.iter().flat_map(|b| b.2).collect();
    let nb = NBody::new(masses, 2.95912208286e-4, 3)?;
    nb.to_barycentric(&mut q, &mut v)?;
    let p = nb.momenta(&v);
    Ok((nb, q, p))
}

/// The figure-eight choreography (Chenciner & Montgomery; Simó's data), G = m = 1.
fn figure_eight() -> Res<(NBody, Vec<f64>, Vec<f64>)> {
    let nb = NBody::new(vec![1.0; 3], 1.0, 2)?;
    let q = vec![0.97000436, -0.24308753, -0.97000436, 0.24308753, 0.0, 0.0];
    let v = vec![
        0.466203685,
        0.43236573,
        0.466203685,
        0.43236573,
        -0.93240737,
        -0.86473146,
    ];
    let p = nb.momenta(&v);
    Ok((nb, q, p))
}

fn other_systems(out: &mut Vec<String>) -> Res<()> {
    let ho = HarmonicOscillator::unit();
    record_system(out, "harmonic", &ho, (&[1.0], &[0.0]), 16, 2.0, 30);
    record_system(out, "harmonic", &ho, (&[1.0], &[0.0]), 40, 20.0, 20);
    let pendulum = Pendulum::unit();
    record_system(out, "pendulum", &pendulum, (&[2.5], &[0.0]), 16, 1.0, 40);
    record_system(
        out,
        "double-well-ad",
        &DoubleWell,
        (&[0.0], &[0.75]),
        16,
        1.0,
        40,
    );
    let henon_heiles = ExpressionLagrangian::parse(
        "(x_dot^2 + y_dot^2)/2 - (x^2 + y^2)/2 - lambda*(x^2*y - y^3/3)",
        &["x", "y"],
        &[("lambda", 1.0)],
    )?;
    record_system(
        out,
        "henon-heiles",
        &henon_heiles,
        (&[0.0, 0.1], &[0.35, 0.0]),
        16,
        1.0,
        40,
    );
    // Non-separable (every solver runs exact Newton on them): a charged particle in a magnetic field (x·ẏ terms) and the double
    // pendulum (configuration-dependent mass matrix).
    let magnetic = ExpressionLagrangian::parse(
        "(x_dot^2 + y_dot^2)/2 + B/2*(x*y_dot - y*x_dot)",
        &["x", "y"],
        &[("B", 1.0)],
    )?;
    record_system(
        out,
        "magnetic",
        &magnetic,
        (&[1.5, 0.2], &[-0.1, -0.25]),
        12,
        0.5,
        40,
    );
    let double_pendulum = ExpressionLagrangian::parse(
        "(m1 + m2)*l1^2*th1_dot^2/2 + m2*l2^2*th2_dot^2/2 \
         + m2*l1*l2*th1_dot*th2_dot*cos(th1 - th2) \
         + (m1 + m2)*g*l1*cos(th1) + m2*g*l2*cos(th2)",
        &["th1", "th2"],
        &[
            ("m1", 1.0),
            ("m2", 1.0),
            ("l1", 1.0),
            ("l2", 1.0),
            ("g", 1.0),
        ],
    )?;
    record_system(
        out,
        "double-pendulum",
        &double_pendulum,
        (&[1.5, 0.5], &[0.0, 0.0]),
        16,
        0.5,
        // Chaotic: few steps, so that round-off differences are not amplified beyond reading.
        12,
    );
    let (nb, q, p) = figure_eight()?;
    record_system(out, "figure-eight", &nb, (&q, &p), 16, 0.7907392475, 16);
    let (nb, q, p) = outer_solar_system()?;
    // Small steps (no self-blocks, dense Newton systems) and the paper's large step, where
    // Jupiter is solved with its own self-block and the Newton system has 360 unknowns.
    record_system(out, "outer-solar-system", &nb, (&q, &p), 12, 200.0, 20);
    record_system(out, "outer-solar-system", &nb, (&q, &p), 25, 1825.0, 8);
    Ok(())
}

/// Tolerance-driven n (the n of each step is recorded as text).
fn adaptive_cases(out: &mut Vec<String>) -> Res<()> {
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    let (h, steps, t0) = (1.0, 30, 0.0);
    for (basis, tol) in [(BasisKind::Legendre, 1e-8), (BasisKind::Chebyshev, 1e-10)] {
        for solver in [StageSolver::Exact, StageSolver::Auto] {
            let mut opts = AdaptiveOptions::new(tol, basis, QuadratureKind::GaussLegendre, h);
            opts.solver = solver;
            let id = format!(
                "adaptive/kepler/{}/tol{tol:e}/h{h}/s{steps}/{}",
                basis.as_str(),
                solver.as_str()
            );
            let line = match integrate_adaptive(&kepler, &opts, t0, &q0, &p0, steps) {
                Ok(run) => {
                    let step_n: Vec<String> = run
                        .trajectory
                        .step_n
                        .iter()
                        .map(|n| n.to_string())
                        .collect();
                    let mut line = format!("{id} ok step_n={}", step_n.join(","));
                    match trajectory_tokens(&mut line, &run.trajectory, t0, h) {
                        Ok(()) => line,
                        Err(e) => error_line(&id, "dense output", &*e),
                    }
                }
                Err(e) => error_line(&id, "integrate", &e),
            };
            out.push(line);
        }
    }
    Ok(())
}

fn lie_tokens(line: &mut String, traj: &LieTrajectory) {
    let steps = traj.states.len() - 1;
    for (name, k) in [("mid", steps / 2), ("end", steps)] {
        let s = &traj.states[k];
        let r: Vec<f64> = s.r.iter().flatten().copied().collect();
        push_vector(line, &format!("R_{name}"), &r);
        push_vector(line, &format!("mu_{name}"), &s.mu);
    }
}

fn lie_run<S: RigidBody>(
    out: &mut Vec<String>,
    (system, body): (&str, &S),
    (basis, n, h, steps): (BasisKind, usize, f64, usize),
    retraction: Retraction,
    (r0, mu0): (&Mat3<f64>, &[f64; 3]),
) {
    let id = format!(
        "lie/{system}/{}/n{n}/gauss-legendre:default/h{h}/s{steps}/{}",
        basis.as_str(),
        retraction.as_str()
    );
    let line = match LieGalerkin::from_kinds(basis, n, QuadratureKind::GaussLegendre, None, h) {
        Ok(lie) => match lie
            .with_retraction(retraction)
            .integrate(body, 0.0, r0, mu0, steps)
        {
            Ok(traj) => {
                let mut line = format!("{id} ok");
                lie_tokens(&mut line, &traj);
                line
            }
            Err(e) => error_line(&id, "integrate", &e),
        },
        Err(e) => error_line(&id, "construct", &e),
    };
    out.push(line);
}

/// The Lie group integrator on SO(3): the free rigid body of scenes/rigid-body.toml (a quarter
/// period per step) and the heavy top of scenes/heavy-top.toml.
fn lie_cases(out: &mut Vec<String>) -> Res<()> {
    let free = FreeRigidBody::new([1.0, 2.0, 3.0])?;
    let r0 = Retraction::Exp.map(&[0.3, -0.4, 0.2]);
    let mu0 = [1.0, 0.4, 3.0];
    let quarter = 1.7278907507449373;
    for (basis, retraction) in [
        (BasisKind::Legendre, Retraction::Exp),
        (BasisKind::Chebyshev, Retraction::Exp),
        (BasisKind::Legendre, Retraction::Cayley),
    ] {
        lie_run(
            out,
            ("rigid-body", &free),
            (basis, 16, quarter, 16),
            retraction,
            (&r0, &mu0),
        );
    }
    let top = HeavyTop::new([1.0, 1.0, 0.5], 1.0, 9.81, [0.0, 0.0, 0.5])?;
    let r0 = Retraction::Exp.map(&[0.5, 0.0, 0.0]);
    lie_run(
        out,
        ("heavy-top", &top),
        (BasisKind::Legendre, 12, 0.1, 40),
        Retraction::Exp,
        (&r0, &[0.0, 0.0, 5.0]),
    );
    Ok(())
}

/// The recorded values of a periodic solution: every coefficient, the period, the action, the
/// energy and its spread, the residual history; the iterations and nodes as text.
fn periodic_tokens(line: &mut String, sol: &PeriodicSolution) {
    let _ = write!(line, " iterations={} nodes={}", sol.iterations, sol.nodes);
    push_vector(line, "c", &sol.curve.coefficients);
    let scalars = [
        sol.curve.period,
        sol.action,
        sol.energy,
        sol.energy_spread,
        sol.residual,
        sol.tail,
    ];
    push_vector(line, "T,S,E,spread,res,tail", &scalars);
    push_vector(line, "history", &sol.residual_history);
}

fn periodic_run<L: Lagrangian>(
    out: &mut Vec<String>,
    id: &str,
    lag: &L,
    guess: FourierCurve,
    (condition, symmetries, options): (PeriodCondition, &[Symmetry], &PeriodicOptions),
) {
    let id = format!("periodic/{id}");
    let line = match periodic::solve(lag, guess, condition, symmetries, options) {
        Ok(sol) => {
            let mut line = format!("{id} ok");
            periodic_tokens(&mut line, &sol);
            line
        }
        Err(e) => error_line(&id, "solve", &e),
    };
    out.push(line);
}

/// Periodic orbits by Newton on the discrete action (src/periodic): the figure-eight from the
/// module's lemniscate guess at Simó's energy and, from the solution, at fixed period; the
/// oscillator's and the pendulum's period from the energy; negative controls (a collision
/// curve that is no orbit, no orbit at positive energy, the iteration limit, too few modes).
fn periodic_cases(out: &mut Vec<String>) -> Res<()> {
    let nb = NBody::new(vec![1.0; 3], 1.0, 2)?;
    let layout = Layout::Choreography {
        bodies: 3,
        body_dim: 2,
    };
    let symmetries = Symmetry::nbody(2);
    let defaults = PeriodicOptions::default();
    let energy = PeriodCondition::Energy(-1.287_141_991_8);
    let lemniscate = |modes: usize| -> Res<FourierCurve> {
        let mut guess = FourierCurve::zeros(modes, layout.clone(), 6.0)?;
        guess.set_mode(1, &[0.0, 0.0], &[1.0, 0.0])?;
        guess.set_mode(2, &[0.0, 0.0], &[0.0, 0.35])?;
        Ok(guess)
    };
    for modes in [16, 30] {
        periodic_run(
            out,
            &format!("figure-eight/K{modes}/energy"),
            &nb,
            lemniscate(modes)?,
            (energy, &symmetries, &defaults),
        );
    }
    if let Ok(sol) = periodic::solve(&nb, lemniscate(30)?, energy, &symmetries, &defaults) {
        let mut at_period = sol.curve;
        at_period.period = 6.32591398;
        periodic_run(
            out,
            "figure-eight/K30/fixed-period",
            &nb,
            at_period,
            (PeriodCondition::Fixed, &symmetries, &defaults),
        );
    }
    // Negative controls: a guess through collisions (a stationary point that is no orbit, or
    // a failure), positive energy (no orbit), one iteration, the tail test at K = 6.
    let mut far = FourierCurve::zeros(16, layout.clone(), 6.0)?;
    far.set_mode(1, &[0.0, 0.0], &[1.0, 0.0])?;
    periodic_run(
        out,
        "figure-eight/collision-guess/energy",
        &nb,
        far.clone(),
        (energy, &symmetries, &defaults),
    );
    periodic_run(
        out,
        "figure-eight/collision-guess/positive-energy",
        &nb,
        far,
        (PeriodCondition::Energy(0.5), &symmetries, &defaults),
    );
    let one = PeriodicOptions {
        max_iterations: 1,
        ..defaults
    };
    periodic_run(
        out,
        "figure-eight/K30/one-iteration",
        &nb,
        lemniscate(30)?,
        (energy, &symmetries, &one),
    );
    let tail = PeriodicOptions {
        tail_tolerance: Some(1e-6),
        ..defaults
    };
    periodic_run(
        out,
        "figure-eight/K6/tail-test",
        &nb,
        lemniscate(6)?,
        (energy, &symmetries, &tail),
    );
    // One degree of freedom: the oscillator (period 2π at every energy) and the pendulum at
    // amplitude 2.5 (energy −cos 2.5).
    let ho = HarmonicOscillator::new(1.0, 1.0)?;
    let mut guess = FourierCurve::zeros(4, Layout::Orbit { dim: 1 }, 5.0)?;
    guess.set_mode(1, &[0.7], &[0.1])?;
    guess.set_mode(2, &[0.05], &[0.0])?;
    periodic_run(
        out,
        "harmonic/K4/energy",
        &ho,
        guess,
        (
            PeriodCondition::Energy(0.5),
            &[Symmetry::TimeShift],
            &defaults,
        ),
    );
    let pendulum = Pendulum::unit();
    let mut guess = FourierCurve::zeros(24, Layout::Orbit { dim: 1 }, 9.0)?;
    guess.set_mode(1, &[2.3], &[0.0])?;
    guess.set_mode(3, &[0.15], &[0.0])?;
    periodic_run(
        out,
        "pendulum/K24/energy",
        &pendulum,
        guess,
        (
            PeriodCondition::Energy(-(2.5f64).cos()),
            &[Symmetry::TimeShift],
            &defaults,
        ),
    );
    Ok(())
}

/// The state after the first step, at the middle and at the end of a baseline run, and the
/// work counters as text (they change if an iteration takes another path).
fn states_tokens(line: &mut String, (qs, ps): &States) {
    let steps = qs.len() - 1;
    for (name, k) in [("1", 1), ("mid", steps / 2), ("end", steps)] {
        push_vector(line, &format!("q{name}"), &qs[k]);
        push_vector(line, &format!("p{name}"), &ps[k]);
    }
}

/// `steps` steps of [`StaticKernel::advance`] (the fixed-size kernel of the peer studies).
fn gauss_static<L: Lagrangian, const D: usize>(
    g: &mut GaussCollocationBaseline<'_, L>,
    (q0, p0): (&[f64], &[f64]),
    steps: usize,
) -> Res<States> {
    let mut q: [f64; D] = q0.try_into()?;
    let mut p: [f64; D] = p0.try_into()?;
    let (mut qs, mut ps) = (vec![q.to_vec()], vec![p.to_vec()]);
    let mut fsal = None;
    for k in 0..steps {
        g.advance(k as f64 * g.step_size(), &mut q, &mut p, &mut fsal)?;
        qs.push(q.to_vec());
        ps.push(p.to_vec());
    }
    Ok((qs, ps))
}

/// Gauss collocation with s stages through its three entry points: `step` (fixed point, then
/// simplified Newton), `integrate_compensated` (the increments) and the static kernel.
fn gauss_run<L: Lagrangian>(
    out: &mut Vec<String>,
    system: &str,
    lag: &L,
    (s, h, steps): (usize, f64, usize),
    (q0, p0): (&[f64], &[f64]),
) {
    for entry in ["step", "compensated", "static"] {
        let id = format!("gauss/{system}/s{s}/h{h}/s{steps}/{entry}");
        let mut g = match GaussCollocationBaseline::new(lag, s, h) {
            Ok(g) => g,
            Err(e) => {
                out.push(error_line(&id, "construct", &e));
                continue;
            }
        };
        let run: Res<States> = match entry {
            "step" => integrate_one_step(&mut g, q0, p0, steps).map_err(Into::into),
            "compensated" => g
                .integrate_compensated(q0, p0, steps, 1)
                .map_err(Into::into),
            _ => match q0.len() {
                1 => gauss_static::<L, 1>(&mut g, (q0, p0), steps),
                _ => gauss_static::<L, 2>(&mut g, (q0, p0), steps),
            },
        };
        let line = match run {
            Ok(states) => {
                let mut line = format!(
                    "{id} ok evaluations={} iterations={}",
                    g.force_evaluations(),
                    g.iterations()
                );
                states_tokens(&mut line, &states);
                line
            }
            Err(e) => error_line(&id, "integrate", &*e),
        };
        out.push(line);
    }
}

/// The Gauss collocation baseline (src/baselines): Kepler (e = 0.6) at a small step (the
/// fixed-point iteration), at larger ones (simplified Newton near the pericentre; at h = 1 it
/// diverges: a negative control), the oscillator at h = 5 (the fixed point diverges: Newton),
/// the pendulum at a large amplitude.
fn gauss_cases(out: &mut Vec<String>) -> Res<()> {
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    for s in 2..=4 {
        for (h, steps) in [(0.05, 200), (0.25, 80), (0.5, 40), (1.0, 20)] {
            gauss_run(out, "kepler", &kepler, (s, h, steps), (&q0, &p0));
        }
    }
    let ho = HarmonicOscillator::unit();
    for s in [2, 3] {
        gauss_run(out, "harmonic", &ho, (s, 5.0, 20), (&[1.0], &[0.0]));
    }
    let pendulum = Pendulum::unit();
    gauss_run(out, "pendulum", &pendulum, (3, 1.0, 40), (&[2.5], &[0.0]));
    Ok(())
}

fn main() -> Res<()> {
    let mut lines = Vec::new();
    kepler_cases(&mut lines)?;
    other_systems(&mut lines)?;
    adaptive_cases(&mut lines)?;
    lie_cases(&mut lines)?;
    periodic_cases(&mut lines)?;
    gauss_cases(&mut lines)?;
    let mut stdout = std::io::stdout().lock();
    for line in &lines {
        writeln!(stdout, "{line}")?;
    }
    Ok(())
}
