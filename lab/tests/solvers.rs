//! The stage-solver layer: every solver gives the exact-Newton map to the round-off of the
//! stage equations, across bases and systems; its maps are symplectic and conserve the
//! Noether momenta; failures keep the step, residual and partial trajectory; and no solver
//! allocates per step. Each geometric property has a negative control (RK4, or the same
//! solver stopped at a loose tolerance), so the tests can fail.

use galerkin_vi::baselines::{OneStepMethod, Rk4};
use galerkin_vi::geometry::{
    MomentumMap, Rotation, Translation, finite_difference_jacobian, relative_symplecticity_defect,
};
use galerkin_vi::integrator::StageSolver;
use galerkin_vi::prelude::*;
use galerkin_vi_lab::scene::{InitialState, Scene};
use nalgebra::DMatrix;

use crate::common::counting::allocations;
use crate::common::distance;
use crate::common::systems;
use distance::final_state_distance;
use systems::{Coupled, Magnetic};

/// The structured solvers and `Auto`, each compared with `Exact`.
const SOLVERS: [StageSolver; 5] = [
    StageSolver::Modal,
    StageSolver::Kronecker,
    StageSolver::NewtonKrylov,
    StageSolver::FixedPoint,
    StageSolver::Auto,
];

fn with_solver(
    basis: BasisKind,
    n: usize,
    h: f64,
    solver: StageSolver,
) -> GalerkinIntegrator<AnyBasis, QuadratureRule> {
    let gvi = GalerkinIntegrator::from_kinds(basis, n, QuadratureKind::default(), None, h).unwrap();
    let options = NewtonOptions {
        solver,
        ..*gvi.options()
    };
    gvi.with_options(options)
}

/// [`with_solver`] with the fast-body self-block threshold `rate`
/// (`StructuredOptions::self_block_rate`; `f64::MAX`: none).
fn with_solver_rate(
    basis: BasisKind,
    n: usize,
    h: f64,
    solver: StageSolver,
    rate: f64,
) -> GalerkinIntegrator<AnyBasis, QuadratureRule> {
    let gvi = with_solver(basis, n, h, solver);
    let mut options = *gvi.options();
    options.structured.self_block_rate = rate;
    gvi.with_options(options)
}

/// A built-in N-body scene: the system, its initial state and the scene's step.
pub(crate) fn scene_nbody(name: &str) -> (NBody, InitialState, f64) {
    let scene = Scene::load(name).unwrap();
    let built = scene.build().unwrap();
    let nbody = built.euclidean().unwrap().as_nbody().unwrap().clone();
    (nbody, built.initial, scene.method.h)
}

/// Allocations in `steps` steps after a first one that warms the workspace up.
pub(crate) fn allocations_per_run<L: Lagrangian>(
    gvi: &GalerkinIntegrator<AnyBasis, QuadratureRule>,
    lag: &L,
    init: &InitialState,
    steps: usize,
) -> usize {
    let mut ws = gvi.workspace(lag).unwrap();
    let d = init.q.len();
    let (mut q, mut p) = (init.q.clone(), init.p.clone());
    let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
    gvi.step(lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
    let before = allocations();
    for _ in 0..steps {
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
        gvi.step(lag, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
    }
    allocations() - before
}

struct Case<'a, L: Lagrangian> {
    name: &'a str,
    lag: &'a L,
    q0: &'a [f64],
    p0: &'a [f64],
    n: usize,
    h: f64,
    steps: usize,
}

/// Every solver against exact Newton on one system, for every basis; returns the largest
/// relative distance of the final states.
fn agreement<L: Lagrangian>(c: &Case<'_, L>, bases: &[BasisKind]) -> f64 {
    let mut worst = 0.0f64;
    for &basis in bases {
        let exact = with_solver(basis, c.n, c.h, StageSolver::Exact)
            .integrate(c.lag, 0.0, c.q0, c.p0, c.steps)
            .unwrap();
        for solver in SOLVERS {
            let traj = with_solver(basis, c.n, c.h, solver)
                .integrate(c.lag, 0.0, c.q0, c.p0, c.steps)
                .unwrap();
            let dist = final_state_distance(&exact, &traj);
            let inner: usize = traj.stats.iter().map(|s| s.inner_iterations).sum();
            if solver == StageSolver::NewtonKrylov {
                assert!(
                    inner > 0,
                    "{}: Newton–Krylov ran no GMRES iteration",
                    c.name
                );
            }
            println!(
                "{} {basis} {solver}: relative distance {dist:.2e}, {:.2} iterations/step, {} inner",
                c.name,
                traj.newton_iterations() as f64 / c.steps as f64,
                inner
            );
            worst = worst.max(dist);
        }
    }
    worst
}

/// The map is the same to the round-off of the stage equations. Measured (test profile):
/// Kepler 50 steps ≤ 2e-13 relative, coupled ≤ 1e-14, outer solar system (20 steps of
/// 1825 d) ≤ 4e-13. The bound 1e-10 is what the bases themselves are held to in
/// `tests/bases.rs` (the stage solutions differ by the Newton tolerance, ~1e-16 relative
/// per step, and the flow carries it along); the negative control shows a solver stopped
/// at a loose tolerance breaks it.
#[test]
fn every_solver_gives_the_exact_newton_map_across_bases_and_systems() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let bound = 1e-10;
    let k = Case {
        name: "kepler",
        lag: &kepler,
        q0: &q0,
        p0: &p0,
        n: 16,
        h: 1.0,
        steps: 50,
    };
    let w = agreement(&k, &BasisKind::ALL);
    assert!(w <= bound, "kepler: {w:e}");
    let c = Case {
        name: "coupled",
        lag: &Coupled,
        q0: &[0.5, -0.3],
        p0: &[0.2, 0.4],
        n: 12,
        h: 0.5,
        steps: 50,
    };
    let w = agreement(&c, &BasisKind::ALL);
    assert!(w <= bound, "coupled: {w:e}");
    let (nbody, init, h) = scene_nbody("outer-solar-system");
    let o = Case {
        name: "outer solar system",
        lag: &nbody,
        q0: &init.q,
        p0: &init.p,
        n: 12,
        h,
        steps: 20,
    };
    let w = agreement(&o, &[BasisKind::Chebyshev, BasisKind::Legendre]);
    assert!(w <= bound, "outer solar system: {w:e}");
}

/// Negative control for the agreement bound: the frozen-Hessian solver stopped at a loose
/// tolerance (1e-6 of the increments) is measurably another map.
#[test]
fn agreement_bound_catches_a_loosely_solved_map() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    let exact = with_solver(BasisKind::Chebyshev, 16, 1.0, StageSolver::Exact)
        .integrate(&kepler, 0.0, &q0, &p0, 50)
        .unwrap();
    let base = with_solver(BasisKind::Chebyshev, 16, 1.0, StageSolver::Kronecker);
    let loose = NewtonOptions {
        tolerance: 1e-6,
        floor_tolerance: 1e-6,
        ..*base.options()
    };
    let traj = base
        .with_options(loose)
        .integrate(&kepler, 0.0, &q0, &p0, 50)
        .unwrap();
    let dist = final_state_distance(&exact, &traj);
    println!("loose Kronecker: relative distance {dist:.2e}");
    assert!(dist > 1e-9, "the loose solve should differ: {dist:e}");
}

/// A non-separable Lagrangian has no Kronecker structure: every solver choice runs the exact
/// solver, bit for bit.
#[test]
fn non_separable_lagrangians_use_the_exact_solver() {
    let runs: Vec<Trajectory> = StageSolver::ALL
        .iter()
        .map(|&s| {
            with_solver(BasisKind::Chebyshev, 10, 0.3, s)
                .integrate(&Magnetic, 0.0, &[0.5, 0.1], &[0.0, 0.4], 20)
                .unwrap()
        })
        .collect();
    for t in &runs[1..] {
        assert_eq!(t.q, runs[0].q);
        assert_eq!(t.p, runs[0].p);
        assert_eq!(t.stats.iter().map(|s| s.inner_iterations).sum::<usize>(), 0);
    }
}

/// The map each solver actually computes is symplectic: the relative defect of its
/// finite-difference Jacobian (truncation ≈ ε²|f‴| ≈ 1e-10, solve noise / ε ≈ 1e-11) stays
/// below 1e-8, for every solver, on Kepler and on the coupled system. Negative control: RK4
/// at the same h (defect ≈ 1e-3) fails the same bound.
#[test]
fn every_solver_computes_a_symplectic_map() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = Kepler::paper_initial_state();
    for solver in StageSolver::ALL {
        let gvi = with_solver(BasisKind::Chebyshev, 16, 1.0, solver);
        let step = |q: &[f64], p: &[f64]| {
            let t = gvi.integrate(&kepler, 0.0, q, p, 1).unwrap();
            (t.q[1].clone(), t.p[1].clone())
        };
        let d = relative_symplecticity_defect(&finite_difference_jacobian(step, &q0, &p0, 1e-5));
        let gc = with_solver(BasisKind::Legendre, 12, 0.5, solver);
        let step = |q: &[f64], p: &[f64]| {
            let t = gc.integrate(&Coupled, 0.0, q, p, 1).unwrap();
            (t.q[1].clone(), t.p[1].clone())
        };
        let dc = relative_symplecticity_defect(&finite_difference_jacobian(
            step,
            &[0.5, -0.3],
            &[0.2, 0.4],
            1e-5,
        ));
        println!("{solver}: Kepler defect {d:.2e}, coupled {dc:.2e}");
        assert!(d <= 1e-8 && dc <= 1e-8, "{solver}: {d:e}, {dc:e}");
    }
    let step = |q: &[f64], p: &[f64]| {
        let (mut qn, mut pn) = (vec![0.0; 2], vec![0.0; 2]);
        let mut rk4 = Rk4::new(&kepler, 1.0).unwrap();
        rk4.step(0.0, q, p, &mut qn, &mut pn).unwrap();
        (qn, pn)
    };
    let d = relative_symplecticity_defect(&finite_difference_jacobian(step, &q0, &p0, 1e-5));
    println!("RK4: defect {d:.2e}");
    assert!(d > 1e-8, "RK4 should fail: {d:e}");
}

/// Discrete Noether theorem with every solver: the outer solar system's total linear and
/// angular momentum (translation and rotation invariance) over 100 steps of 1825 d stay
/// within C·ε·√N·S with C = 1000 and S the momenta's round-off scale (the bound of `tests/geometry.rs`). Negative control:
/// the same solver stopped at 1e-8 of the increments drifts past it. Measured: 2.5e-18 to
/// 3.3e-18 for the four solvers against a bound of 1.2e-16; loosely solved, 4.4e-12.
#[test]
fn every_solver_conserves_the_noether_momenta() {
    let (nbody, init, h) = scene_nbody("outer-solar-system");
    let (q0, p0) = (&init.q, &init.p);
    let steps = 100;
    let maps: Vec<(&str, Box<dyn MomentumMap>)> = vec![
        ("P_x", Box::new(Translation::axis(3, 6, 0).unwrap())),
        ("P_z", Box::new(Translation::axis(3, 6, 2).unwrap())),
        ("L_xy", Box::new(Rotation::planar(3, 6, 0, 1).unwrap())),
        ("L_yz", Box::new(Rotation::planar(3, 6, 1, 2).unwrap())),
    ];
    // The round-off scale of the momenta: Σ|p| (linear) and Σ|q||p| (angular), since the
    // totals themselves are near zero in the barycentric frame.
    let scale = p0.iter().map(|x| x.abs()).sum::<f64>().max(
        q0.iter()
            .zip(p0.iter())
            .map(|(q, p)| (q * p).abs())
            .sum::<f64>(),
    );
    let bound = 1000.0 * f64::EPSILON * (steps as f64).sqrt() * scale;
    let drift = |opts: Option<NewtonOptions>, solver| {
        let mut gvi = with_solver(BasisKind::Chebyshev, 12, h, solver);
        if let Some(o) = opts {
            gvi = gvi.with_options(NewtonOptions { solver, ..o });
        }
        let traj = gvi.integrate(&nbody, 0.0, q0, p0, steps).unwrap();
        maps.iter()
            .map(|(_, m)| {
                let j0 = m.value(q0, p0);
                (0..=steps)
                    .map(|k| (m.value(&traj.q[k], &traj.p[k]) - j0).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max)
    };
    for solver in StageSolver::ALL {
        let d = drift(None, solver);
        println!("{solver}: momentum drift {d:.2e} (bound {bound:.2e})");
        assert!(d <= bound, "{solver}: {d:e} > {bound:e}");
    }
    let loose = NewtonOptions {
        tolerance: 1e-8,
        floor_tolerance: 1e-8,
        ..NewtonOptions::default()
    };
    let d = drift(Some(loose), StageSolver::Kronecker);
    println!("loose Kronecker: momentum drift {d:.2e}");
    assert!(d > bound, "the loose solve should drift: {d:e}");
}

/// A particle pulled into a wall at q = 1 (V = 2√(1 − q), force 1/√(1 − q) towards it, and no
/// real force beyond it): every curve that reaches the wall has non-finite forces, so the step
/// that gets there fails whatever the solver and guess.
struct Wall;
impl Mechanical for Wall {
    fn degrees_of_freedom(&self) -> usize {
        1
    }
    fn mass(&self) -> DMatrix<f64> {
        DMatrix::identity(1, 1)
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        (T::from(1.0) - q[0]).sqrt() * 2.0
    }
}

/// A failing step names the step and residual and keeps the trajectory, whatever the
/// solver. (The pendulum case of `tests/errors.rs` is not used: at h = 10 the structured
/// solvers find another root of its stage equations where exact Newton finds none.)
#[test]
fn every_solver_reports_failures_with_the_partial_trajectory() {
    for solver in StageSolver::ALL {
        let gvi = with_solver(BasisKind::Chebyshev, 6, 0.25, solver);
        let failure = gvi.integrate(&Wall, 0.0, &[0.0], &[0.5], 40).unwrap_err();
        match &failure.error {
            GviError::NewtonFailure { step, .. } => {
                assert!(*step >= 1, "{solver}: failed at step {step}");
                let partial = failure.partial.as_ref().expect("partial trajectory");
                assert_eq!(partial.steps(), *step, "{solver}");
                assert!(partial.q.iter().all(|q| q[0] < 1.0), "{solver}");
                println!("{solver}: failed at step {step}: {}", failure.error);
            }
            other => panic!("{solver}: expected a Newton failure, got {other:?}"),
        }
        let msg = failure.to_string();
        assert!(msg.contains("step") && msg.contains("residual"), "{msg}");
    }
}

/// No solver allocates inside the step loop (after the workspace is built).
#[test]
fn no_solver_allocates_per_step() {
    let (nbody, init, h) = scene_nbody("outer-solar-system");
    for solver in StageSolver::ALL {
        let gvi = with_solver(BasisKind::Chebyshev, 12, h, solver);
        let n = allocations_per_run(&gvi, &nbody, &init, 10);
        assert_eq!(n, 0, "{solver}: {n} allocations in 10 steps");
    }
}

/// Large N-body systems take pairwise force-Jacobian products (no 3N×3N node Jacobians) in
/// Newton–Krylov: a 64-body ring (D = 192) does, the 10-body system does not, and the
/// matrix-free map is the Kronecker solver's to round-off (measured 3.6e-15 relative at
/// n = 8 over 3 steps; bound 1e-10, as above).
#[test]
fn matrix_free_products_give_the_same_map() {
    use galerkin_vi_lab::ring::{RingConfig, planetesimal_ring};
    let config = RingConfig::with_bodies(64);
    let (ring, init) = planetesimal_ring(&config).unwrap();
    let h = config.step();
    let krylov = with_solver(BasisKind::Chebyshev, 8, h, StageSolver::NewtonKrylov);
    assert!(krylov.workspace(&ring).unwrap().uses_matrix_free_products());
    let (ten, _, _) = scene_nbody("solar-system");
    assert!(!krylov.workspace(&ten).unwrap().uses_matrix_free_products());
    let a = krylov.integrate(&ring, 0.0, &init.q, &init.p, 3).unwrap();
    let b = with_solver(BasisKind::Chebyshev, 8, h, StageSolver::Kronecker)
        .integrate(&ring, 0.0, &init.q, &init.p, 3)
        .unwrap();
    let inner: usize = a.stats.iter().map(|s| s.inner_iterations).sum();
    let dist = final_state_distance(&a, &b);
    println!(
        "64-body ring: matrix-free Newton–Krylov vs Kronecker {dist:.2e}, {inner} GMRES iterations"
    );
    assert!(inner > 0);
    assert!(dist < 1e-10, "{dist:e}");
}

/// The paper's 10-body run (J2000, n = 25, h = 100 d; 20 of its 100 steps): Mercury turns
/// through more than an orbit per step, the velocity form's frozen Hessian stalls, and with
/// (n − 1)·D = 720 unknowns there is no dense matrix to continue with, so those steps go to the
/// nodal solvers. The explicit `modal` tries every step; `auto` hands the next 32 steps over
/// after two failures, so it tries fewer (measured 20 and 2 fallbacks, with the nodal frozen
/// iteration and its fast-body self-blocks taking the steps). Both give the Newton–Krylov
/// map: measured 7.1e-14 relative for both, bound 1e-10 (the run's round-off floor is
/// ~1e-10 AU).
#[test]
fn steps_the_velocity_form_cannot_solve_go_to_the_nodal_solvers() {
    let (nbody, init, _) = scene_nbody("solar-system");
    let run = |solver| {
        with_solver(BasisKind::Chebyshev, 25, 100.0, solver)
            .integrate(&nbody, init.t0, &init.q, &init.p, 20)
            .unwrap()
    };
    let reference = run(StageSolver::NewtonKrylov);
    let fallbacks = |t: &Trajectory| t.stats.iter().map(|s| s.fallbacks).sum::<usize>();
    let (modal, auto) = (run(StageSolver::Modal), run(StageSolver::Auto));
    let (dm, da) = (
        final_state_distance(&reference, &modal),
        final_state_distance(&reference, &auto),
    );
    println!(
        "paper 10-body, 20 steps: modal {} fallbacks ({dm:.1e}), auto {} ({da:.1e})",
        fallbacks(&modal),
        fallbacks(&auto)
    );
    assert!(fallbacks(&modal) >= 2);
    assert!(fallbacks(&auto) < fallbacks(&modal));
    assert!(dm <= 1e-10 && da <= 1e-10, "{dm:e} {da:e}");
}

/// The fast bodies' exact self-blocks (`StructuredOptions::self_block_rate`): at the paper's
/// h = 100 d Mercury ((h ω)² ≈ 50) and Venus (≈ 8) turn through a large angle per step, the
/// frozen mean Hessian leaves out most of their Jacobian, and the frozen iteration stalls and
/// falls back to exact Newton. With their time-varying self-blocks in the preconditioner it
/// contracts. Negative control: the same solver with the self-blocks off. Both give the
/// exact-Newton map (bound 1e-10, as above). Measured (n = 16, 10 steps): with the self-blocks no step
/// falls back (9.5 iterations per step, 1.7e-14 from exact Newton); without, all 10 do (3.0e-14).
#[test]
fn exact_self_blocks_of_the_fast_bodies_make_the_frozen_iteration_contract() {
    let (nbody, init, _) = scene_nbody("solar-system");
    let steps = 10;
    let run = |solver, rate| {
        with_solver_rate(BasisKind::Chebyshev, 16, 100.0, solver, rate)
            .integrate(&nbody, init.t0, &init.q, &init.p, steps)
            .unwrap()
    };
    let default_rate = NewtonOptions::default().structured.self_block_rate;
    let reference = run(StageSolver::Exact, default_rate);
    let fallbacks = |t: &Trajectory| t.stats.iter().map(|s| s.fallbacks).sum::<usize>();
    let per_step = |t: &Trajectory| t.newton_iterations() as f64 / steps as f64;
    let with = run(StageSolver::Kronecker, default_rate);
    let without = run(StageSolver::Kronecker, f64::MAX);
    let (dw, dn) = (
        final_state_distance(&reference, &with),
        final_state_distance(&reference, &without),
    );
    println!(
        "solar system n = 16, h = 100 d: self-blocks {} fallbacks, {:.2} it/step ({dw:.1e}); \
         frozen mean only {} fallbacks, {:.2} it/step ({dn:.1e})",
        fallbacks(&with),
        per_step(&with),
        fallbacks(&without),
        per_step(&without),
    );
    assert_eq!(fallbacks(&with), 0);
    assert!(fallbacks(&without) >= steps / 2);
    assert!(dw <= 1e-10 && dn <= 1e-10, "{dw:e} {dn:e}");
    // The self-blocks are assembled and factorised in the workspace's buffers: no allocation
    // per step.
    let gvi = with_solver(BasisKind::Chebyshev, 16, 100.0, StageSolver::Kronecker);
    assert_eq!(allocations_per_run(&gvi, &nbody, &init, 5), 0);
}

/// More fast bodies than self-block buffers: a 32-body ring at four times its usual step
/// (half the innermost period, so the inner bodies have (h ω)² up to π² ≈ 10) gives the
/// frozen iteration more bodies above the threshold than it keeps exact self-blocks for (it
/// takes the fastest eight). The map is still Newton–Krylov's (the matrix-free exact-Newton
/// directions) to round-off: bound 1e-10 as above. Measured: 13–15 bodies above the
/// threshold at the freezes, 10.7 iterations per step, no fallback, 5.6e-14 from
/// Newton–Krylov.
#[test]
fn the_fastest_bodies_get_the_self_blocks_when_there_are_many() {
    use galerkin_vi_lab::ring::{RingConfig, planetesimal_ring};
    let config = RingConfig::with_bodies(32);
    let (ring, init) = planetesimal_ring(&config).unwrap();
    let h = 4.0 * config.step();
    let steps = 3;
    let run = |solver, rate| {
        with_solver_rate(BasisKind::Chebyshev, 10, h, solver, rate)
            .integrate(&ring, 0.0, &init.q, &init.p, steps)
            .unwrap()
    };
    let rate = NewtonOptions::default().structured.self_block_rate;
    let reference = run(StageSolver::NewtonKrylov, f64::MAX);
    let frozen = run(StageSolver::Kronecker, rate);
    let fallbacks: usize = frozen.stats.iter().map(|s| s.fallbacks).sum();
    let dist = final_state_distance(&reference, &frozen);
    println!(
        "32-body ring, h = {h:.3}: kronecker with self-blocks {:.2} it/step, {fallbacks} \
         fallbacks, {dist:.1e} from Newton–Krylov",
        frozen.newton_iterations() as f64 / steps as f64
    );
    assert!(dist <= 1e-10, "{dist:e}");
}

/// The velocity form's exact self-blocks (`StructuredOptions::velocity_self_block_rate`): on the
/// outer solar system at h = 912.5 d (Chebyshev n = 10, 15 points: issue 35's fastest
/// configuration at 1e-9) Jupiter turns through 76° per step, and the frozen mean Hessian
/// misses most of how its block varies over the step. With its time-varying self-block in the
/// preconditioner the `modal` iteration needs fewer residual evaluations. Negative control: the
/// same solver with the self-blocks off. Both give the exact-Newton map to round-off (bound
/// 1e-10, as above). Measured (20 steps): 1 765 against 2 530 force evaluations (0.70), both
/// 5.3e-14 from exact Newton; no allocation per step. The fixed-point start
/// (`velocity_fixed_point_handover`) is off here: with it the steps of this configuration
/// never reach the frozen Hessian.
#[test]
fn velocity_form_self_blocks_of_the_fast_bodies_cut_the_iterations() {
    let (nbody, init, _) = scene_nbody("outer-solar-system");
    let steps = 20;
    let integrator = |solver, rate: f64| {
        let gvi = GalerkinIntegrator::from_kinds(
            BasisKind::Chebyshev,
            10,
            QuadratureKind::default(),
            Some(15),
            912.5,
        )
        .unwrap();
        let mut options = NewtonOptions {
            solver,
            ..*gvi.options()
        };
        options.structured.velocity_self_block_rate = rate;
        options.structured.velocity_fixed_point_handover = 0.0;
        gvi.with_options(options)
    };
    let run = |solver, rate| {
        integrator(solver, rate)
            .integrate(&nbody, init.t0, &init.q, &init.p, steps)
            .unwrap()
    };
    let rate = NewtonOptions::default().structured.velocity_self_block_rate;
    let reference = run(StageSolver::Exact, rate);
    let with = run(StageSolver::Modal, rate);
    let without = run(StageSolver::Modal, f64::MAX);
    let evaluations = |t: &Trajectory| {
        t.stats
            .iter()
            .map(|s| s.gradient_evaluations)
            .sum::<usize>()
    };
    let (dw, dn) = (
        final_state_distance(&reference, &with),
        final_state_distance(&reference, &without),
    );
    println!(
        "outer solar system n = 10, h = 912.5 d: self-blocks {} force evaluations ({dw:.1e}); \
         frozen mean only {} ({dn:.1e})",
        evaluations(&with),
        evaluations(&without),
    );
    assert!(
        (evaluations(&with) as f64) < 0.8 * evaluations(&without) as f64,
        "{} {}",
        evaluations(&with),
        evaluations(&without)
    );
    assert!(dw <= 1e-10 && dn <= 1e-10, "{dw:e} {dn:e}");
    let gvi = integrator(StageSolver::Auto, rate);
    assert_eq!(allocations_per_run(&gvi, &nbody, &init, 5), 0);
}
