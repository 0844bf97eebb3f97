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

mod gauss;
mod lie;
mod periodic_orbits;
mod systems;

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

fn main() -> Res<()> {
    let mut lines = Vec::new();
    systems::kepler_cases(&mut lines)?;
    systems::other_systems(&mut lines)?;
    systems::adaptive_cases(&mut lines)?;
    lie::lie_cases(&mut lines)?;
    periodic_orbits::periodic_cases(&mut lines)?;
    gauss::gauss_cases(&mut lines)?;
    let mut stdout = std::io::stdout().lock();
    for line in &lines {
        writeln!(stdout, "{line}")?;
    }
    Ok(())
}
