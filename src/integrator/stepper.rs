//! [`Stepper`]: one integrator, one Lagrangian and the workspace made for them, stepping a
//! state forward one step at a time.
//!
//! [`GalerkinIntegrator::step`] takes a [`Workspace`] as an argument, so a workspace made for
//! one integrator can be handed to another (it is then refused at run time). A stepper owns
//! its workspace and borrows the integrator and the Lagrangian it was made with, so that
//! mismatch cannot be written at all. It also carries the state with its compensation terms
//! (docs/DESIGN.md §4) and the step count, so its steps are exactly those of
//! [`GalerkinIntegrator::integrate`], which is a stepper driven to the end.

use super::{GalerkinIntegrator, StepStats, Workspace};
use crate::basis::Basis;
use crate::curve::GalerkinCurveRef;
use crate::error::{GviError, Result};
use crate::lagrangian::Lagrangian;
use crate::quadrature::Quadrature;

/// Steps of one integrator for one Lagrangian from an initial state, with the workspace made
/// for them.
///
/// ```
/// use galerkin_vi::prelude::*;
///
/// let kepler = Kepler::new(1.0)?;
/// let (q0, p0) = Kepler::paper_initial_state();
/// let gvi = GalerkinIntegrator::spectral(12, 0.5)?;
/// let mut stepper = gvi.stepper(&kepler, 0.0, &q0, &p0)?;
/// while stepper.time() < 2.0 {
///     stepper.step()?;
/// }
/// // The same steps as `integrate`.
/// let traj = gvi.integrate(&kepler, 0.0, &q0, &p0, 4)?;
/// assert_eq!(stepper.position(), &traj.q[4][..]);
/// assert_eq!(stepper.momentum(), &traj.p[4][..]);
/// // The last step's Galerkin curve, at its own time.
/// let (q, _) = stepper.curve().state_at(gvi.basis(), 1.8)?;
/// assert_eq!(q, traj.position_at(1.8)?);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug)]
pub struct Stepper<'a, B: Basis, Q: Quadrature, L: Lagrangian> {
    integrator: &'a GalerkinIntegrator<B, Q>,
    lagrangian: &'a L,
    workspace: Workspace,
    t0: f64,
    steps: usize,
    q: Vec<f64>,
    p: Vec<f64>,
    /// Compensation terms of the running sums q and p (unused when
    /// `NewtonOptions::compensated` is off).
    q_err: Vec<f64>,
    p_err: Vec<f64>,
    /// Buffers of the uncompensated step.
    q_next: Vec<f64>,
    p_next: Vec<f64>,
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// A [`Stepper`] from (q0, p0) at time t0 for `lagrangian`, with its own workspace.
    ///
    /// Errors: wrong lengths or non-finite values of t0, q0, p0; a Lagrangian of dimension 0.
    pub fn stepper<'a, L: Lagrangian>(
        &'a self,
        lagrangian: &'a L,
        t0: f64,
        q0: &[f64],
        p0: &[f64],
    ) -> Result<Stepper<'a, B, Q, L>> {
        if !t0.is_finite() {
            return Err(GviError::NonFinite {
                what: "initial time t0".into(),
                value: t0,
            });
        }
        self.check_state(lagrangian, q0, p0)?;
        let d = lagrangian.dim();
        let workspace = self.workspace(lagrangian)?;
        Ok(Stepper {
            integrator: self,
            lagrangian,
            workspace,
            t0,
            steps: 0,
            q: q0.to_vec(),
            p: p0.to_vec(),
            q_err: vec![0.0; d],
            p_err: vec![0.0; d],
            q_next: vec![0.0; d],
            p_next: vec![0.0; d],
        })
    }
}

impl<B: Basis, Q: Quadrature, L: Lagrangian> Stepper<'_, B, Q, L> {
    /// Take one step (q_k, p_k) ↦ (q_{k+1}, p_{k+1}); allocates nothing.
    ///
    /// Errors: [`GviError::NewtonFailure`] naming the step, its time and the residual; the
    /// state is then unchanged (the last completed step's), so the run so far is kept.
    pub fn step(&mut self) -> Result<StepStats> {
        let gvi = self.integrator;
        // t_k = t0 + k h exactly (not accumulated), for time-dependent and forced systems.
        self.workspace.stage.set_step_start(self.time(), 0.0, &[]);
        let result = if gvi.options().compensated {
            gvi.step_compensated(
                self.lagrangian,
                &mut self.workspace,
                &mut self.q,
                &mut self.q_err,
                &mut self.p,
                &mut self.p_err,
            )
        } else {
            gvi.step(
                self.lagrangian,
                &mut self.workspace,
                &self.q,
                &self.p,
                &mut self.q_next,
                &mut self.p_next,
            )
            .inspect(|_| {
                std::mem::swap(&mut self.q, &mut self.q_next);
                std::mem::swap(&mut self.p, &mut self.p_next);
            })
        };
        match result {
            Ok(stats) => {
                self.steps += 1;
                Ok(stats)
            }
            Err(failure) => Err(GviError::NewtonFailure {
                step: self.steps,
                t: self.time(),
                residual: failure.residual,
                iterations: failure.iterations,
                reason: failure.reason,
            }),
        }
    }

    /// Steps completed.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The time of the current state, t0 + k h.
    pub fn time(&self) -> f64 {
        self.t0 + self.steps as f64 * self.integrator.step_size()
    }

    /// The current position q_k.
    pub fn position(&self) -> &[f64] {
        &self.q
    }

    /// The current momentum p_k.
    pub fn momentum(&self) -> &[f64] {
        &self.p
    }

    /// The last completed step's Galerkin curve, from t_{k−1} to t_k (all zeros before the
    /// first step).
    pub fn curve(&self) -> GalerkinCurveRef<'_> {
        let start = self.t0 + self.steps.saturating_sub(1) as f64 * self.integrator.step_size();
        self.workspace.curve().starting_at(start)
    }

    /// The integrator.
    pub fn integrator(&self) -> &GalerkinIntegrator<B, Q> {
        self.integrator
    }

    /// Start the next step's Newton iteration from the given coefficients (see
    /// [`Workspace::warm_start`]).
    ///
    /// Errors: wrong length or non-finite entries.
    pub fn warm_start(&mut self, coefficients: &[f64]) -> Result<()> {
        self.workspace.warm_start(coefficients)
    }

    /// Forget the previous step's curve (the next initial guess does not extrapolate it).
    pub fn reset_guess(&mut self) {
        self.workspace.reset();
    }

    /// Whether Newton–Krylov takes the system's matrix-free force-Jacobian products (see
    /// [`Workspace::uses_matrix_free_products`]).
    pub fn uses_matrix_free_products(&self) -> bool {
        self.workspace.uses_matrix_free_products()
    }

    /// Save everything the next steps depend on: the state with its compensation terms, the
    /// step count, and the workspace's memory (the last curve, the guesses' history, a
    /// reusable factorisation, `Auto`'s rung). [`restore`](Self::restore) puts it back, and
    /// the steps taken after it are then bit for bit those taken after the checkpoint — e.g.
    /// to step past an event, look, and go back. A checkpoint owns copies of the buffers:
    /// taking and restoring one allocate (the steps themselves still do not).
    pub fn checkpoint(&self) -> Checkpoint {
        Checkpoint {
            t0: self.t0,
            steps: self.steps,
            q: self.q.clone(),
            p: self.p.clone(),
            q_err: self.q_err.clone(),
            p_err: self.p_err.clone(),
            workspace: self.workspace.clone(),
        }
    }

    /// Return to a [`checkpoint`](Self::checkpoint) of a stepper of the same integrator and
    /// dimension.
    ///
    /// Errors: [`GviError::Mismatch`] for a checkpoint of another integrator (basis, n,
    /// quadrature, h) or dimension; the stepper is then unchanged.
    pub fn restore(&mut self, checkpoint: &Checkpoint) -> Result<()> {
        if checkpoint.workspace.made_for != self.workspace.made_for {
            return Err(GviError::Mismatch {
                expected: format!("a checkpoint of {}", self.workspace.made_for),
                got: format!("one of {}", checkpoint.workspace.made_for),
            });
        }
        self.t0 = checkpoint.t0;
        self.steps = checkpoint.steps;
        self.q.copy_from_slice(&checkpoint.q);
        self.p.copy_from_slice(&checkpoint.p);
        self.q_err.copy_from_slice(&checkpoint.q_err);
        self.p_err.copy_from_slice(&checkpoint.p_err);
        self.workspace.restore_from(&checkpoint.workspace);
        Ok(())
    }

    /// Start again from (q, p) at time t: the step count is zero, the compensation terms are
    /// cleared and the guesses forget the previous curve, so the steps are those of a new
    /// stepper from that state (the workspace is reused).
    ///
    /// Errors: wrong lengths or non-finite values; the stepper is then unchanged.
    pub fn set_state(&mut self, t: f64, q: &[f64], p: &[f64]) -> Result<()> {
        if !t.is_finite() {
            return Err(GviError::NonFinite {
                what: "time t".into(),
                value: t,
            });
        }
        self.integrator.check_state(self.lagrangian, q, p)?;
        self.t0 = t;
        self.steps = 0;
        self.q.copy_from_slice(q);
        self.p.copy_from_slice(p);
        self.q_err.iter_mut().for_each(|x| *x = 0.0);
        self.p_err.iter_mut().for_each(|x| *x = 0.0);
        self.workspace.start_afresh();
        Ok(())
    }

    /// The current time and state (t_k, q_k, p_k), taking the stepper.
    pub fn into_state(self) -> (f64, Vec<f64>, Vec<f64>) {
        (self.time(), self.q, self.p)
    }
}

/// A saved [`Stepper`] state: see [`Stepper::checkpoint`] and [`Stepper::restore`].
#[derive(Debug, Clone)]
pub struct Checkpoint {
    t0: f64,
    steps: usize,
    q: Vec<f64>,
    p: Vec<f64>,
    q_err: Vec<f64>,
    p_err: Vec<f64>,
    workspace: Workspace,
}

impl Checkpoint {
    /// Steps completed at the checkpoint.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Position q_k at the checkpoint.
    pub fn position(&self) -> &[f64] {
        &self.q
    }

    /// Momentum p_k at the checkpoint.
    pub fn momentum(&self) -> &[f64] {
        &self.p
    }
}

#[cfg(test)]
mod tests {
    use crate::prelude::*;

    /// A workspace made for h = 0.5 and handed to an h = 1.0 integrator is refused with the
    /// reason (it used to fail with "iteration limit reached" under `exact`, or to step right
    /// while the curve reported h = 0.5 under `auto`). Negative control: the same workspace
    /// with its own integrator steps.
    #[test]
    fn a_workspace_is_refused_by_another_integrator() {
        let kepler = Kepler::new(1.0).unwrap();
        let (q0, p0) = Kepler::paper_initial_state();
        let (mut q1, mut p1) = (vec![0.0; 2], vec![0.0; 2]);
        for solver in [StageSolver::Exact, StageSolver::Auto] {
            let options = NewtonOptions {
                solver,
                ..NewtonOptions::default()
            };
            let half = GalerkinIntegrator::spectral(12, 0.5)
                .unwrap()
                .with_options(options);
            let one = GalerkinIntegrator::spectral(12, 1.0)
                .unwrap()
                .with_options(options);
            let mut ws = half.workspace(&kepler).unwrap();
            let err = one
                .step(&kepler, &mut ws, &q0, &p0, &mut q1, &mut p1)
                .unwrap_err();
            assert!(err.reason.contains("made for"), "{solver}: {}", err.reason);
            assert!(err.reason.contains("h = 0.5"), "{}", err.reason);
            assert!(
                half.step(&kepler, &mut ws, &q0, &p0, &mut q1, &mut p1)
                    .is_ok()
            );
            // Wrong output lengths are refused, not a panic.
            let mut short = vec![0.0; 1];
            assert!(
                half.step(&kepler, &mut ws, &q0, &p0, &mut short, &mut p1)
                    .is_err()
            );
        }
    }

    /// The stepper's steps are `integrate`'s, bit for bit, compensated or not.
    #[test]
    fn the_stepper_takes_integrates_steps() {
        let kepler = Kepler::new(1.0).unwrap();
        let (q0, p0) = Kepler::paper_initial_state();
        for compensated in [true, false] {
            let options = NewtonOptions {
                compensated,
                ..NewtonOptions::default()
            };
            let gvi = GalerkinIntegrator::spectral(10, 0.5)
                .unwrap()
                .with_options(options);
            let traj = gvi.integrate(&kepler, 1.0, &q0, &p0, 7).unwrap();
            let mut stepper = gvi.stepper(&kepler, 1.0, &q0, &p0).unwrap();
            for k in 1..=7 {
                stepper.step().unwrap();
                assert_eq!(stepper.position(), &traj.q[k][..]);
                assert_eq!(stepper.momentum(), &traj.p[k][..]);
                assert_eq!(
                    stepper.curve().coefficients(),
                    &traj.coefficients[k - 1][..]
                );
            }
            assert_eq!(stepper.time(), traj.end_time());
        }
        let gvi = GalerkinIntegrator::spectral(10, 0.5).unwrap();
        assert!(gvi.stepper(&kepler, f64::NAN, &q0, &p0).is_err());
        assert!(gvi.stepper(&kepler, 0.0, &q0[..1], &p0).is_err());
    }

    /// Steps after a restored checkpoint are bit for bit the steps taken after it, because
    /// the workspace's memory (the guesses' history) comes back too; a stepper re-seeded with
    /// `set_state` takes a fresh stepper's steps. Negative controls: a state alone, without
    /// the guess memory, starts the next step from another guess (the Newton iterations
    /// differ), and a checkpoint of another integrator is refused.
    #[test]
    fn a_restored_checkpoint_replays_the_same_steps() {
        let kepler = Kepler::new(1.0).unwrap();
        let (q0, p0) = Kepler::paper_initial_state();
        for compensated in [true, false] {
            // The extrapolated guess needs the previous curve (without it: the linear one).
            let options = NewtonOptions {
                compensated,
                solver: StageSolver::Exact,
                initial_guess: InitialGuess::Extrapolate,
                ..NewtonOptions::default()
            };
            let gvi = GalerkinIntegrator::spectral(10, 0.5)
                .unwrap()
                .with_options(options);
            let mut stepper = gvi.stepper(&kepler, 0.0, &q0, &p0).unwrap();
            for _ in 0..3 {
                stepper.step().unwrap();
            }
            let saved = stepper.checkpoint();
            assert_eq!(saved.steps(), 3);
            let mut first = Vec::new();
            for _ in 0..4 {
                let stats = stepper.step().unwrap();
                first.push((
                    stepper.position().to_vec(),
                    stepper.momentum().to_vec(),
                    stats,
                ));
            }
            stepper.restore(&saved).unwrap();
            assert_eq!(stepper.time(), 1.5);
            for (q, p, stats) in &first {
                let again = stepper.step().unwrap();
                assert_eq!(stepper.position(), &q[..]);
                assert_eq!(stepper.momentum(), &p[..]);
                assert_eq!(again.iterations, stats.iterations);
                assert_eq!(again.guess, stats.guess);
            }
            // Re-seeded: a fresh stepper's steps from the checkpoint's state.
            stepper
                .set_state(1.5, saved.position(), saved.momentum())
                .unwrap();
            let mut fresh = gvi
                .stepper(&kepler, 1.5, saved.position(), saved.momentum())
                .unwrap();
            let mut guesses = Vec::new();
            for _ in &first {
                let (a, b) = (stepper.step().unwrap(), fresh.step().unwrap());
                assert_eq!(stepper.position(), fresh.position());
                assert_eq!(stepper.momentum(), fresh.momentum());
                assert_eq!((a.guess, a.iterations), (b.guess, b.iterations));
                guesses.push(a.guess);
            }
            // Negative control: without the memory the first step cannot extrapolate a
            // previous curve, as the restored checkpoint did.
            assert_eq!(first[0].2.guess, InitialGuess::Extrapolate);
            assert_eq!(
                guesses[0],
                InitialGuess::Linear,
                "compensated = {compensated}"
            );
        }
        // A checkpoint of another integrator is refused, the stepper unchanged.
        let other = GalerkinIntegrator::spectral(10, 0.25).unwrap();
        let foreign = other.stepper(&kepler, 0.0, &q0, &p0).unwrap().checkpoint();
        let gvi = GalerkinIntegrator::spectral(10, 0.5).unwrap();
        let mut stepper = gvi.stepper(&kepler, 0.0, &q0, &p0).unwrap();
        stepper.step().unwrap();
        let err = stepper.restore(&foreign).unwrap_err();
        assert!(matches!(err, GviError::Mismatch { .. }), "{err}");
        assert_eq!(stepper.steps(), 1);
        assert!(stepper.set_state(f64::INFINITY, &q0, &p0).is_err());
        assert!(stepper.set_state(0.0, &q0[..1], &p0).is_err());
        assert_eq!(stepper.steps(), 1);
        let (t, q, _) = stepper.into_state();
        assert_eq!((t, q.len()), (0.5, 2));
    }
}
