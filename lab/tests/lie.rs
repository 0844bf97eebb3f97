//! Lie group spectral variational integrators on SO(3) (`galerkin_vi::lie`): invariants over
//! 10⁴ steps, spectral convergence at a quarter period against the elliptic-function solution,
//! h-order per n, symplecticity in trivialised coordinates, the heavy top, scenes and errors.
//! Each geometric property has a negative control: classical RK4 on the matrix ODE.

use galerkin_vi::basis::BasisKind;
use galerkin_vi::lie::so3::{self, Mat3};
use galerkin_vi::lie::*;
use galerkin_vi::quadrature::QuadratureKind;
use galerkin_vi_lab::error::LabError;
use galerkin_vi_lab::fit::{fit_algebraic_in, fit_geometric_in};

const INERTIA: [f64; 3] = [1.0, 2.0, 3.0];

/// The `rigid-body` scene's initial state: R₀ = exp(q̂), μ₀ (|μ|² = 10.16 > 2E I₂ = 8.64).
fn scene_state() -> (Mat3<f64>, [f64; 3]) {
    (Retraction::Exp.map(&[0.3, -0.4, 0.2]), [1.0, 0.4, 3.0])
}

fn max_orientation_error(traj: &LieTrajectory, ex: &FreeBodyExact) -> f64 {
    let times: Vec<f64> = (0..traj.states.len()).map(|k| k as f64 * traj.h).collect();
    let refs = ex.orientations(&times).unwrap();
    traj.states
        .iter()
        .zip(&refs)
        .map(|(s, r)| so3::distance(&s.r, r))
        .fold(0.0, f64::max)
}

fn max_abs_diff(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).fold(0.0f64, |m, i| m.max((a[i] - b[i]).abs()))
}

/// Orthogonality, spatial angular momentum and energy over 10⁴ steps (n = 3, h = 0.4; order 4,
/// energy error 2.1e-5 from the first steps on). Measured: ‖RᵀR − I‖ ≤ 3.6e-14, |ΔL| ≤ 4.8e-14
/// (a random walk, ~ε|L|√k). RK4 at the same h: ‖RᵀR − I‖ = 1.4, |ΔL| = 0.28, energy error
/// growing from 3.3e-3 (100 steps) to 0.25.
#[test]
fn invariants_over_ten_thousand_steps_with_rk4_control() {
    let body = FreeRigidBody::new(INERTIA).unwrap();
    let (r0, mu0) = scene_state();
    let (h, steps) = (0.4, 10_000);
    let traj = LieGalerkin::spectral(3, h)
        .unwrap()
        .integrate(&body, 0.0, &r0, &mu0, steps)
        .unwrap();
    let s0 = traj.states[0];
    let (e0, l0) = (body.energy(&s0.r, &s0.mu), s0.spatial_momentum());
    let lnorm = so3::dot(&l0, &l0).sqrt();
    let mut rk = s0;
    let (mut gal_e_early, mut gal_e, mut rk_e_early, mut rk_e) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let (mut rk_orth, mut rk_l) = (0.0f64, 0.0f64);
    let (mut gal_orth, mut gal_l) = (0.0f64, 0.0f64);
    for (k, s) in traj.states.iter().enumerate() {
        let orth = so3::orthogonality_defect(&s.r);
        assert!(orth <= 1e-12, "step {k}: ‖RᵀR − I‖ = {orth:e}");
        // Spatial momentum: conserved exactly by the map; round-off walks like ε|L|√k.
        let dl = max_abs_diff(&s.spatial_momentum(), &l0);
        gal_l = gal_l.max(dl);
        gal_orth = gal_orth.max(orth);
        let bound = 4.0 * f64::EPSILON * lnorm * (k.max(1) as f64).sqrt();
        assert!(dl <= bound, "step {k}: |ΔL| = {dl:e} > {bound:e}");
        let de = (body.energy(&s.r, &s.mu) - e0).abs();
        gal_e = gal_e.max(de);
        if k > 0 {
            rk = baselines::rk4_step(&body, &rk, h);
        }
        let rde = (body.energy(&rk.r, &rk.mu) - e0).abs();
        rk_e = rk_e.max(rde);
        if k <= 100 {
            gal_e_early = gal_e;
            rk_e_early = rk_e;
        }
        rk_orth = rk_orth.max(so3::orthogonality_defect(&rk.r));
        rk_l = rk_l.max(max_abs_diff(&rk.spatial_momentum(), &l0));
    }
    eprintln!(
        "10^4 steps: ‖RᵀR − I‖ {gal_orth:.3e}, |ΔL| {gal_l:.3e}, energy {gal_e:.3e} (first 100: {gal_e_early:.3e}); RK4 energy {rk_e:.3e} \
         (first 100: {rk_e_early:.3e}), ‖RᵀR − I‖ {rk_orth:.3e}, |ΔL| {rk_l:.3e}"
    );
    // Energy: bounded (no growth after the first 100 steps), at the method's truncation level.
    assert!(
        gal_e <= 1.01 * gal_e_early && gal_e < 1e-4,
        "{gal_e:e} vs {gal_e_early:e}"
    );
    // Controls: RK4 leaves SO(3), loses L and drifts in energy.
    assert!(rk_orth > 0.1, "RK4 ‖RᵀR − I‖ = {rk_orth:e}");
    assert!(rk_l > 1e-2, "RK4 |ΔL| = {rk_l:e}");
    assert!(
        rk_e > 20.0 * rk_e_early,
        "RK4 energy {rk_e:e} vs {rk_e_early:e}"
    );
}

/// Spectral convergence at h = a quarter of the body period (8 steps, two periods): fitted
/// rate over n = 4 … 12 measured 0.039 per n (errors 3.0e-2 at n = 4, 1.5e-13 at n = 12), and
/// 1e-12 reached (2.0e-14 at n = 16). Chebyshev and Legendre give the same map; the Cayley
/// chart also converges geometrically (more slowly: 2.4e-6 at n = 10, 1.5e-12 at n = 16).
#[test]
fn spectral_convergence_at_a_quarter_period() {
    let body = FreeRigidBody::new(INERTIA).unwrap();
    let (r0, mu0) = scene_state();
    let ex = FreeBodyExact::new(INERTIA, &r0, &mu0).unwrap();
    let h = ex.period() / 4.0;
    let ns = [4usize, 6, 8, 10, 12];
    let mut errs = Vec::new();
    for &n in &ns {
        let gvi = LieGalerkin::from_kinds(
            BasisKind::Legendre,
            n,
            QuadratureKind::GaussLegendre,
            None,
            h,
        )
        .unwrap();
        let traj = gvi.integrate(&body, 0.0, &r0, &mu0, 8).unwrap();
        errs.push(max_orientation_error(&traj, &ex));
    }
    let nf: Vec<f64> = ns.iter().map(|&n| n as f64).collect();
    let fit = fit_geometric_in(&nf, &errs, 4.0, 12.0).unwrap();
    eprintln!(
        "quarter period h = {h}: errors {errs:?}, fitted rate {:.4}",
        fit.rate
    );
    assert!(fit.rate < 0.06, "rate {} ({errs:?})", fit.rate);
    for w in errs.windows(2) {
        assert!(w[1] < 0.05 * w[0], "not geometric: {errs:?}");
    }
    let run = |kind: BasisKind, n: usize, tau: Retraction| {
        let gvi = LieGalerkin::from_kinds(kind, n, QuadratureKind::GaussLegendre, None, h)
            .unwrap()
            .with_retraction(tau);
        gvi.integrate(&body, 0.0, &r0, &mu0, 8).unwrap()
    };
    let leg = run(BasisKind::Legendre, 16, Retraction::Exp);
    let cheb = run(BasisKind::Chebyshev, 16, Retraction::Exp);
    let e16 = max_orientation_error(&leg, &ex);
    assert!(e16 <= 1e-12, "n = 16: {e16:e}");
    for (a, b) in leg.states.iter().zip(&cheb.states) {
        assert!(so3::distance(&a.r, &b.r) < 1e-12, "bases disagree");
    }
    let cay10 = max_orientation_error(&run(BasisKind::Legendre, 10, Retraction::Cayley), &ex);
    let cay16 = max_orientation_error(&run(BasisKind::Legendre, 16, Retraction::Cayley), &ex);
    eprintln!("n = 16: exp {e16:.2e}; Cayley n = 10 {cay10:.2e}, n = 16 {cay16:.2e}");
    assert!(
        cay10 < 1e-5 && cay16 < 1e-11 && cay16 < 1e-5 * cay10,
        "{cay10:e} {cay16:e}"
    );
}

/// Order in h at fixed n: 2(n − 1), measured 1.98, 3.99, 6.01 for n = 2, 3, 4 (h = 0.4 … 0.1,
/// T = 3.2), as for Gauss-type Galerkin methods on vector spaces.
#[test]
fn h_order_per_n() {
    let body = FreeRigidBody::new(INERTIA).unwrap();
    let (r0, mu0) = scene_state();
    let ex = FreeBodyExact::new(INERTIA, &r0, &mu0).unwrap();
    let hs = [0.4f64, 0.2, 0.1];
    for n in [2usize, 3, 4] {
        let errs: Vec<f64> = hs
            .iter()
            .map(|&h| {
                let steps = (3.2 / h).round() as usize;
                let traj = LieGalerkin::spectral(n, h)
                    .unwrap()
                    .integrate(&body, 0.0, &r0, &mu0, steps)
                    .unwrap();
                max_orientation_error(&traj, &ex)
            })
            .collect();
        let fit = fit_algebraic_in(&hs, &errs, 0.1, 0.4).unwrap();
        let want = 2.0 * (n as f64 - 1.0);
        eprintln!("n = {n}: errors {errs:?}, order {:.3}", fit.order);
        assert!(
            (fit.order - want).abs() < 0.25,
            "n = {n}: order {} ({errs:?})",
            fit.order
        );
    }
}

/// The one-step map in canonical coordinates of T*SO(3) near (R_k, μ_k): ζ with R = R_k exp(ζ̂)
/// and π = J_r(ζ)ᵀμ (the cotangent lift of the chart); the same chart around the image.
/// Central differences (δ = 1e-5) give the 6 × 6 Jacobian M; ‖MᵀJM − J‖ measured 7e-11 and 2.7e-10 for
/// the Lie Galerkin map (h = 0.4, n = 5; h = T/4, n = 12) and 2.9e-3 for RK4 at h = 0.4.
#[test]
fn symplectic_in_trivialised_coordinates_with_rk4_control() {
    let body = FreeRigidBody::new(INERTIA).unwrap();
    let (r0, mu0) = scene_state();
    let ex = FreeBodyExact::new(INERTIA, &r0, &mu0).unwrap();
    let state = LieState { r: r0, mu: mu0 };
    for (n, h) in [(5usize, 0.4), (12, ex.period() / 4.0)] {
        let gvi = LieGalerkin::spectral(n, h).unwrap();
        let d = geometry::symplecticity_defect(|s| gvi.step(&body, s), &state, 1e-5).unwrap();
        eprintln!("symplecticity defect n = {n}, h = {h:.4}: {d:.2e}");
        assert!(d < 1e-8, "Lie Galerkin n = {n}, h = {h}: defect {d:e}");
    }
    let d_rk4 =
        geometry::symplecticity_defect(|s| Ok(baselines::rk4_step(&body, s, 0.4)), &state, 1e-5)
            .unwrap();
    eprintln!("symplecticity defect RK4 h = 0.4: {d_rk4:.2e}");
    assert!(d_rk4 > 1e-5, "RK4 defect {d_rk4:e}");
}

/// The Lagrange top (I₁ = I₂, centre of mass on the axis): the vertical spatial momentum lz is
/// conserved to round-off (the spatial impulse of gravity is horizontal), the spin μ₃ too
/// (discrete Noether for the body symmetry), the energy error stays bounded over 2000 steps.
/// RK4 at the same step loses lz and drifts in energy.
#[test]
fn heavy_top_invariants_with_rk4_control() {
    let top = HeavyTop::new([1.0, 1.0, 0.5], 1.0, 9.81, [0.0, 0.0, 0.5]).unwrap();
    let r0 = Retraction::Exp.map(&[0.5, 0.0, 0.0]);
    let mu0 = [0.0, 0.0, 5.0];
    let (h, steps) = (0.1, 2000);
    let traj = LieGalerkin::spectral(4, h)
        .unwrap()
        .integrate(&top, 0.0, &r0, &mu0, steps)
        .unwrap();
    let lz0 = traj.states[0].spatial_momentum()[2];
    let e0 = top.energy(&r0, &mu0);
    let (mut de_early, mut de) = (0.0f64, 0.0f64);
    let mut rk = traj.states[0];
    let (mut rk_lz, mut rk_e_early, mut rk_e) = (0.0f64, 0.0f64, 0.0f64);
    for (k, s) in traj.states.iter().enumerate() {
        let dlz = (s.spatial_momentum()[2] - lz0).abs();
        assert!(dlz < 1e-12, "step {k}: Δlz = {dlz:e}");
        assert!((s.mu[2] - mu0[2]).abs() < 1e-12, "step {k}: Δμ₃");
        assert!(so3::orthogonality_defect(&s.r) < 1e-13);
        de = de.max((top.energy(&s.r, &s.mu) - e0).abs());
        if k > 0 {
            // Five RK4 substeps per step: more work than the Galerkin step, still a drift.
            for _ in 0..5 {
                rk = baselines::rk4_step(&top, &rk, h / 5.0);
            }
        }
        rk_lz = rk_lz.max((rk.spatial_momentum()[2] - lz0).abs());
        rk_e = rk_e.max((top.energy(&rk.r, &rk.mu) - e0).abs());
        if k <= 200 {
            de_early = de;
            rk_e_early = rk_e;
        }
    }
    assert!(
        de < 1e-5 && de <= 1.5 * de_early,
        "energy {de:e} vs {de_early:e}"
    );
    eprintln!(
        "heavy top: energy {de:e} (first 200 steps {de_early:e}); RK4 Δlz {rk_lz:e}, energy {rk_e:e} (first 200 steps {rk_e_early:e})"
    );
    assert!(rk_lz > 1e-6, "RK4 Δlz = {rk_lz:e}");
    assert!(
        rk_e > 5.0 * rk_e_early,
        "RK4 energy {rk_e:e} vs {rk_e_early:e}"
    );
}

/// The scene reaches 1e-12 from the run layer (what `gvi run rigid-body` prints), and its CSV
/// has the documented columns.
#[test]
fn rigid_body_scene_reaches_1e_12() {
    use galerkin_vi_lab::run::{RunOptions, run_scene};
    use galerkin_vi_lab::scene::Scene;
    let scene = Scene::load("rigid-body").unwrap();
    let result = run_scene(&scene.build().unwrap(), RunOptions::default()).unwrap();
    let err = result.summary.max_position_error.unwrap();
    assert!(err <= 1e-12, "orientation error {err:e}");
    let csv = result.to_csv().unwrap();
    let header = csv.lines().next().unwrap();
    for col in ["r00", "r12", "r22", "mu0", "w2", "lx", "ly", "lz", "energy"] {
        assert!(
            header.split(',').any(|c| c == col),
            "missing {col} in {header}"
        );
    }
    let top = run_scene(
        &Scene::load("heavy-top").unwrap().build().unwrap(),
        RunOptions::default(),
    )
    .unwrap();
    assert!(top.summary.max_position_error.is_none());
    let (name, lz) = &top.summary.invariant_errors[1];
    assert_eq!(name, "vertical angular momentum lz");
    assert!(*lz < 1e-12, "heavy-top |Δlz| {lz:e}");
}

#[test]
fn bad_input_is_a_typed_error() {
    use galerkin_vi::GviError;
    let body = FreeRigidBody::new(INERTIA).unwrap();
    let gvi = LieGalerkin::spectral(6, 0.5).unwrap();
    let (r0, mu0) = scene_state();
    let mut skewed = r0;
    skewed[0][0] += 1e-6;
    assert!(matches!(
        gvi.integrate(&body, 0.0, &skewed, &mu0, 5),
        Err(GviError::InvalidInput { .. })
    ));
    assert!(
        gvi.integrate(&body, 0.0, &r0, &[f64::NAN, 0.0, 0.0], 5)
            .is_err()
    );
    assert!(matches!(
        gvi.integrate(&body, 0.0, &r0, &mu0, 0),
        Err(GviError::InvalidStepCount { .. })
    ));
    assert!(matches!(
        LieGalerkin::spectral(6, -1.0),
        Err(GviError::InvalidStepSize { .. })
    ));
    assert!(matches!(
        LieGalerkin::from_kinds(
            BasisKind::Chebyshev,
            8,
            QuadratureKind::GaussLegendre,
            Some(3),
            0.5
        ),
        Err(GviError::InvalidQuadrature { .. })
    ));
    assert!(FreeBodyExact::new([3.0, 2.0, 1.0], &r0, &mu0).is_err());
    // A step far beyond the chart's reach fails with a typed Newton error, not a panic.
    let wild = LieGalerkin::spectral(4, 40.0).unwrap();
    match wild.integrate(&body, 0.0, &r0, &[30.0, 20.0, 10.0], 3) {
        Ok(_) | Err(GviError::NewtonFailure { .. }) => {}
        Err(e) => panic!("unexpected error {e}"),
    }
    use galerkin_vi_lab::scene::Scene;
    let bad = "[system]\ntype = \"rigid-body\"\ninertia = [1, 2, 3]\n[initial]\nq = [0, 0]\n\
               p = [1, 0, 3]\n[method]\nn = 6\nh = 0.5\nsteps = 2\n";
    // A wrong length is refused when the scene is built, before any run.
    let scene = Scene::from_toml_str("t", bad).unwrap();
    assert!(matches!(
        scene.build(),
        Err(LabError::Core(GviError::DimensionMismatch { .. }))
    ));
}

/// `gvi run` on the rigid-body scenes writes the SO(3) table (a plain CSV run, which for the
/// Euclidean scenes is streamed, must still reach the Lie group integrator).
#[test]
fn gvi_run_writes_the_rigid_body_tables() {
    let dir = std::env::temp_dir().join(format!("gvi-lie-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for scene in ["rigid-body", "heavy-top"] {
        let out = dir.join(format!("{scene}.csv"));
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_gvi"))
            .args(["run", scene, "--output"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            status.status.success(),
            "{scene}: {}",
            String::from_utf8_lossy(&status.stderr)
        );
        let text = std::fs::read_to_string(&out).unwrap();
        let header = text.lines().next().unwrap_or_default();
        assert!(
            header.contains("r00") && header.contains("lz") && header.contains("energy"),
            "{header}"
        );
        assert!(text.lines().count() > 2);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
