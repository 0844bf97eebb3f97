//! The velocity form's fixed-point iteration with its converged bodies frozen
//! (`StructuredOptions::velocity_freeze_converged_blocks`): the same map, fewer forces.

use galerkin_vi::integrator::StageSolver;
use galerkin_vi::prelude::*;

use crate::common::distance::final_state_distance;
use crate::solvers::{allocations_per_run, scene_nbody};

/// The fixed-point iteration's converged blocks frozen
/// (`StructuredOptions::velocity_freeze_converged_blocks`): on J2000 at h = 20 d (Legendre
/// n = 12, 12 Gauss points: the study's frontier at 1e-9) the outer planets converge in 2–4
/// corrections and Mercury in about 10, so most corrections evaluate the forces on a few
/// bodies only. Both runs give the exact-Newton map to round-off (bound 1e-10, as every solver
/// in `solvers.rs`; its negative control is
/// `solvers::agreement_bound_catches_a_loosely_solved_map`). Measured (25 steps): frozen 5.1e-16 and unfrozen 6.2e-17 from exact Newton; 3.7 full and 7.0 partial force
/// evaluations per node and step against 10.4 full; no allocation per step.
#[test]
fn freezing_converged_bodies_keeps_the_map_and_skips_their_forces() {
    let (nbody, init, _) = scene_nbody("solar-system");
    let steps = 25;
    let integrator = |solver, freeze: bool| {
        let gvi = GalerkinIntegrator::from_kinds(
            BasisKind::Legendre,
            12,
            QuadratureKind::default(),
            Some(12),
            20.0,
        )
        .unwrap();
        let mut options = NewtonOptions {
            solver,
            ..*gvi.options()
        };
        options.structured.velocity_freeze_converged_blocks = freeze;
        gvi.with_options(options)
    };
    let run = |solver, freeze| {
        integrator(solver, freeze)
            .integrate(&nbody, init.t0, &init.q, &init.p, steps)
            .unwrap()
    };
    let reference = run(StageSolver::Exact, false);
    let frozen = run(StageSolver::Auto, true);
    let plain = run(StageSolver::Auto, false);
    let sum = |t: &Trajectory, f: fn(&galerkin_vi::stats::StepStats) -> usize| {
        t.stats.iter().map(f).sum::<usize>()
    };
    let full = |t: &Trajectory| sum(t, |s| s.gradient_evaluations) as f64 / (12 * steps) as f64;
    let partial = sum(&frozen, |s| s.partial_gradient_evaluations);
    let (df, dp) = (
        final_state_distance(&reference, &frozen),
        final_state_distance(&reference, &plain),
    );
    println!(
        "J2000 n = 12, h = 20 d: frozen {:.1} full + {:.1} partial evaluations per node and \
         step ({df:.1e}); unfrozen {:.1} ({dp:.1e})",
        full(&frozen),
        partial as f64 / (12 * steps) as f64,
        full(&plain),
    );
    assert_eq!(sum(&plain, |s| s.partial_gradient_evaluations), 0);
    assert!(partial > 0);
    assert!(
        full(&frozen) < 0.6 * full(&plain),
        "{} {}",
        full(&frozen),
        full(&plain)
    );
    assert!(df <= 1e-10 && dp <= 1e-10, "{df:e} {dp:e}");
    assert_eq!(
        allocations_per_run(&integrator(StageSolver::Auto, true), &nbody, &init, 5),
        0
    );
}

/// A user's system with coordinate blocks and its own batched forces, but no kernel for the
/// points laid out by coordinate (`Lagrangian::force_at_points_by_coordinate_on_blocks`): the
/// masked residuals go through the trait's default (the points transposed into its own
/// scratch), and the map is the built-in system's, bit for bit — the forces of the active
/// blocks are the same numbers either way. No allocation per step.
#[test]
fn a_system_without_a_by_coordinate_kernel_gets_the_same_frozen_map() {
    /// J2000's N-body system through `Mechanical`'s point-by-point kernels only.
    struct PointsOnly(NBody);
    impl Mechanical for PointsOnly {
        fn degrees_of_freedom(&self) -> usize {
            self.0.degrees_of_freedom()
        }
        fn mass(&self) -> nalgebra::DMatrix<f64> {
            Mechanical::mass(&self.0)
        }
        fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
            self.0.potential(q)
        }
        fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
            self.0.potential_gradient(q, out)
        }
        fn coordinate_blocks(&self) -> Option<usize> {
            Mechanical::coordinate_blocks(&self.0)
        }
        fn potential_gradient_at_points(&self, q: &[f64], out: &mut [f64]) {
            self.0.potential_gradient_at_points(q, out)
        }
        fn potential_gradient_at_points_on_blocks(
            &self,
            q: &[f64],
            active: &[bool],
            out: &mut [f64],
        ) {
            self.0
                .potential_gradient_at_points_on_blocks(q, active, out)
        }
        fn potential_hessian(&self, q: &[f64], out: &mut [f64]) {
            self.0.potential_hessian(q, out)
        }
    }
    let (nbody, init, _) = scene_nbody("solar-system");
    let gvi = GalerkinIntegrator::from_kinds(
        BasisKind::Legendre,
        9,
        QuadratureKind::default(),
        Some(8),
        100.0 / 9.0,
    )
    .unwrap();
    let steps = 40;
    let built_in = gvi
        .integrate(&nbody, init.t0, &init.q, &init.p, steps)
        .unwrap();
    let user = PointsOnly(nbody.clone());
    let theirs = gvi
        .integrate(&user, init.t0, &init.q, &init.p, steps)
        .unwrap();
    let partial: usize = theirs
        .stats
        .iter()
        .map(|s| s.partial_gradient_evaluations)
        .sum();
    assert!(partial > 0, "the masked residuals ran");
    let bits = |t: &Trajectory| {
        let (q, p) = (t.q.last().unwrap(), t.p.last().unwrap());
        q.iter().chain(p).map(|x| x.to_bits()).collect::<Vec<_>>()
    };
    assert_eq!(bits(&built_in), bits(&theirs));
    assert_eq!(allocations_per_run(&gvi, &user, &init, 5), 0);
}
