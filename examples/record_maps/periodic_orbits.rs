//! Periodic orbits (`periodic::solve`) and their negative controls.

use super::*;

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
pub(super) fn periodic_cases(out: &mut Vec<String>) -> Res<()> {
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
