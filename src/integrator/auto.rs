//! [`StageSolver::Auto`](super::StageSolver::Auto): the one policy that chooses, step by step,
//! the form of the stage equations and the linear solve inside Newton's iteration.
//!
//! The choices, in the order a step meets them:
//!
//! 1. **The velocity form** ([`super::velocity`]) where it is the same map (separable
//!    Lagrangians, polynomial bases, a rule exact for the kinetic term), with its frozen
//!    Hessian, or with its dense exact matrix for the steps that follow two stalls of the
//!    frozen one ([`AutoState::velocity_dense`]). A step it gives up goes to the nodal solvers;
//!    after two such steps within [`CALM`] solves, the next [`HOLDOFF`] steps go there directly
//!    ([`AutoState::velocity_gives_up`]).
//! 2. **The nodal equations**: dense exact Newton up to a Newton-system size (n − 1)·D of
//!    [`DENSE_SIZE`]; above it the frozen-Hessian Kronecker solve, or Newton–Krylov for the
//!    [`HOLDOFF`] solves after the frozen Hessian stalled twice within [`CALM`] solves
//!    ([`AutoState::krylov`]).
//!
//! The three memories are the same rule ([`Escalation`]): two failures of the cheaper solve
//! within [`CALM`] solves, then the more robust one for the next [`HOLDOFF`] solves, after
//! which the cheaper one is tried again. An occasional hard step (Kepler's periapsis) changes
//! nothing; a run whose steps are all hard (the paper's 10-body run at h = 100 d) stops paying
//! for a solve that fails.

use super::{GalerkinIntegrator, StageSolver, Workspace};
use crate::basis::Basis;
use crate::quadrature::Quadrature;

/// Solves without a failure after which an [`Escalation`] forgets the earlier failure.
pub(crate) const CALM: usize = 8;

/// Solves for which an [`Escalation`] keeps the robust solve before the cheaper one is tried
/// again. On 20 steps of the paper's 10-body run the explicit `modal` solver tries the
/// velocity form and fails 22 times, `auto` 4.
pub(crate) const HOLDOFF: usize = 32;

/// Newton-system size (n − 1)·D up to which `Auto` takes the dense exact solver. Measured on
/// Kepler (D = 2, h = 1, 200 steps): exact Newton is the fastest at n = 16 (size 30), the
/// structured solvers and exact are within noise at n = 32 (size 62), and the frozen-Hessian
/// solver is 1.8× faster at n = 64 (size 126); N-body scenes (D ≥ 18) are always above. The
/// velocity form continues densely up to the same size when its frozen Hessian stalls.
pub(crate) const DENSE_SIZE: usize = 64;

/// The memory of one escalation: two failures within [`CALM`] solves start a hold-off of
/// [`HOLDOFF`] solves.
///
/// What counts as a solve is the caller's: the nodal equations count every solve when it
/// starts ([`calm_solve`](Self::calm_solve) then, [`failure`](Self::failure) if its frozen
/// Hessian stalls); the velocity form counts a solve when it ends.
#[derive(Debug, Clone, Default)]
pub(crate) struct Escalation {
    /// Failures within the recent solves …
    recent: usize,
    /// … and solves since the last failure.
    calm: usize,
    /// Solves left in the hold-off.
    holdoff: usize,
}

impl Escalation {
    /// A solve without a failure (so far).
    pub(crate) fn calm_solve(&mut self) {
        self.calm += 1;
        if self.calm > CALM {
            self.recent = 0;
        }
    }

    /// A failure; true when it starts a hold-off (the second within [`CALM`] solves).
    pub(crate) fn failure(&mut self) -> bool {
        self.calm = 0;
        self.recent += 1;
        if self.recent >= 2 {
            self.recent = 0;
            self.holdoff = HOLDOFF;
            return true;
        }
        false
    }

    /// Whether this solve is in a hold-off (counts it).
    pub(crate) fn holding(&mut self) -> bool {
        if self.holdoff > 0 {
            self.holdoff -= 1;
            return true;
        }
        false
    }
}

/// `Auto`'s state in a workspace: what the recent steps taught it.
#[derive(Debug, Clone, Default)]
pub(crate) struct AutoState {
    /// The nodal frozen Hessian stalled: start with Newton–Krylov.
    pub krylov: Escalation,
    /// The velocity form gave steps up: send steps to the nodal solvers directly.
    pub velocity_gives_up: Escalation,
    /// The velocity form's frozen Hessian stalled into its dense matrix: start with it.
    pub velocity_dense: Escalation,
    /// The velocity form's fixed-point iterations handed over to the frozen Hessian: start
    /// with it.
    pub velocity_frozen: Escalation,
}

impl<B: Basis, Q: Quadrature> GalerkinIntegrator<B, Q> {
    /// The nodal solver `solver` names for one solve, with `Auto` (and the nodal fallback of
    /// `Modal`) resolved for this workspace; counts the solve in `Auto`'s memory.
    pub(super) fn resolve_solver(&self, ws: &mut Workspace, solver: StageSolver) -> StageSolver {
        match solver {
            StageSolver::Auto | StageSolver::Modal => {
                let krylov = ws.auto.krylov.holding();
                ws.auto.krylov.calm_solve();
                if !ws.system.structured() || (ws.n - 1) * ws.d <= DENSE_SIZE {
                    StageSolver::Exact
                } else if krylov {
                    StageSolver::NewtonKrylov
                } else {
                    StageSolver::Kronecker
                }
            }
            s => s,
        }
    }

    /// Whether this step is solved in the velocity form: where it exists and is the same map,
    /// for `Modal` always, for `Auto` unless the velocity form is in a hold-off (counts it).
    pub(super) fn velocity_form_applies(&self, ws: &mut Workspace) -> bool {
        let solver = self.options().solver;
        ws.velocity.is_some()
            && self.tables().velocity.is_some()
            && self.stage_solver.is_none()
            && !ws.guess.warm_start_pending()
            && match solver {
                StageSolver::Modal => true,
                StageSolver::Auto => !ws.auto.velocity_gives_up.holding(),
                _ => false,
            }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two failures within CALM solves start a hold-off of HOLDOFF solves; failures further
    /// apart do not (negative control).
    #[test]
    fn two_close_failures_start_a_holdoff() {
        let mut e = Escalation::default();
        assert!(!e.failure());
        for _ in 0..=CALM {
            e.calm_solve();
        }
        assert!(!e.failure(), "failures CALM + 1 solves apart are forgotten");
        e.calm_solve();
        assert!(e.failure());
        let held = (0..2 * HOLDOFF).filter(|_| e.holding()).count();
        assert_eq!(held, HOLDOFF);
    }
}
