//! Kepler over every basis × quadrature × solver, the other systems, and tolerance-driven runs.

use super::*;

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

pub(super) fn kepler_cases(out: &mut Vec<String>) -> Res<()> {
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

pub(super) fn other_systems(out: &mut Vec<String>) -> Res<()> {
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
pub(super) fn adaptive_cases(out: &mut Vec<String>) -> Res<()> {
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
