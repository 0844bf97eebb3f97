//! Ensembles (`gvi ensemble`): reproducibility from the seed, independence of the thread
//! count, the zero perturbation, the Lyapunov estimate (positive for a chaotic scene, O(1/T)
//! for the harmonic oscillator as the negative control), conservation of the invariants, and
//! typed errors for bad input.

use galerkin_vi_lab::ensemble::{EnsembleOptions, perturbed_members, run_ensemble};
use galerkin_vi_lab::error::LabError;
use galerkin_vi_lab::scene::{BuiltScene, Scene};
use std::process::Command;

fn scene(name: &str, n: usize, h: f64, steps: usize) -> BuiltScene {
    let mut s = Scene::load(name).unwrap();
    s.method.n = n;
    s.method.h = h;
    s.method.steps = steps;
    s.build().unwrap()
}

fn options(count: usize, sigma: f64, seed: u64) -> EnsembleOptions {
    EnsembleOptions { count, sigma, seed }
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

#[test]
fn same_seed_same_bytes_other_seed_other_members() {
    let s = scene("kepler", 12, 0.5, 20);
    let a = run_ensemble(&s, &options(6, 1e-3, 42), None)
        .unwrap()
        .to_csv();
    let b = run_ensemble(&s, &options(6, 1e-3, 42), None)
        .unwrap()
        .to_csv();
    assert_eq!(a, b, "same seed must give the same CSV bytes");
    let c = run_ensemble(&s, &options(6, 1e-3, 43), None)
        .unwrap()
        .to_csv();
    assert_ne!(a, c, "another seed must give other members");
    // Every row differs, not just one: the members' streams are unrelated.
    for (ra, rc) in a.lines().zip(c.lines()).skip(1) {
        assert_ne!(ra, rc);
    }
}

#[test]
fn results_do_not_depend_on_the_number_of_threads() {
    let s = scene("henon-heiles", 12, 1.0, 30);
    let o = options(5, 1e-3, 9);
    let one = in_pool(1, || run_ensemble(&s, &o, None).unwrap().to_csv());
    let two = in_pool(2, || run_ensemble(&s, &o, None).unwrap().to_csv());
    assert_eq!(one, two);
}

#[test]
fn perturbations_are_standard_normal_times_sigma() {
    // 4000 members × 4 components: the sample standard deviation of the perturbations is σ
    // within 4 standard errors (σ/√(2N) for N normal deviates) and the mean 0 within 4σ/√N.
    let (sigma, count) = (0.25, 4000);
    let q0 = [1.0, -2.0];
    let p0 = [0.5, 3.0];
    let members = perturbed_members(&q0, &p0, &options(count, sigma, 1)).unwrap();
    let deltas: Vec<f64> = members
        .iter()
        .flat_map(|m| {
            let dq = m.q0.iter().zip(&q0).map(|(a, b)| a - b);
            let dp = m.p0.iter().zip(&p0).map(|(a, b)| a - b);
            dq.chain(dp).collect::<Vec<_>>()
        })
        .collect();
    let n = deltas.len() as f64;
    let mean = deltas.iter().sum::<f64>() / n;
    let std = (deltas.iter().map(|d| (d - mean) * (d - mean)).sum::<f64>() / (n - 1.0)).sqrt();
    assert!(mean.abs() < 4.0 * sigma / n.sqrt(), "mean {mean}");
    assert!(
        (std - sigma).abs() < 4.0 * sigma / (2.0 * n).sqrt(),
        "std {std} vs σ = {sigma}"
    );
    // The reported norm is the norm of the perturbation.
    let m = &members[17];
    let norm =
        m.q0.iter()
            .zip(&q0)
            .chain(m.p0.iter().zip(&p0))
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
    assert!((norm - m.perturbation_norm).abs() <= 1e-15);
}

#[test]
fn statistics_of_values() {
    use galerkin_vi_lab::ensemble::Statistic;
    let s = Statistic::of("x", [1.0, 2.0, f64::NAN, 3.0, 6.0]);
    assert_eq!((s.count, s.mean, s.min, s.max), (4, 3.0, 1.0, 6.0));
    assert!((s.std - (14.0f64 / 3.0).sqrt()).abs() < 1e-15);
    let empty = Statistic::of("y", [f64::NAN]);
    assert_eq!(empty.count, 0);
    assert!(empty.mean.is_nan() && empty.min.is_nan() && empty.max.is_nan());
}

#[test]
fn zero_perturbation_gives_identical_members() {
    let s = scene("kepler", 12, 0.5, 20);
    let e = run_ensemble(&s, &options(4, 0.0, 5), None).unwrap();
    let first = &e.members[0];
    assert_eq!(first.perturbation_norm, 0.0);
    for m in &e.members[1..] {
        assert_eq!(m.q, first.q);
        assert_eq!(m.p, first.p);
        assert_eq!(m.lyapunov.to_bits(), first.lyapunov.to_bits());
        assert_eq!(m.momentum_errors, first.momentum_errors);
    }
    // Negative control: a nonzero σ separates them.
    let e = run_ensemble(&s, &options(4, 1e-6, 5), None).unwrap();
    assert_ne!(e.members[0].q, e.members[1].q);
}

/// The CSV names the final state as the runs do: Kepler `q0, q1, p0, p1`, an expression
/// Lagrangian its own coordinates and `p_<name>`; the numbers read back bit for bit.
#[test]
fn ensemble_columns_use_the_scenes_names() {
    let e = run_ensemble(&scene("kepler", 12, 0.5, 4), &options(2, 1e-3, 5), None).unwrap();
    let header = e.to_csv().lines().next().unwrap().to_string();
    assert!(header.contains(",q0,q1,p0,p1,"), "{header}");
    let e = run_ensemble(
        &scene("henon-heiles", 8, 0.5, 4),
        &options(2, 1e-3, 5),
        None,
    )
    .unwrap();
    let csv = e.to_csv();
    let header = csv.lines().next().unwrap();
    assert!(header.contains(",x,y,p_x,p_y,"), "{header}");
    let row: Vec<f64> = csv
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|c| c.parse().unwrap())
        .collect();
    let m = &e.members[0];
    assert_eq!(row[4].to_bits(), m.q[0].to_bits());
    assert_eq!(row[7].to_bits(), m.p[1].to_bits());
}

#[test]
fn invariants_are_conserved_in_every_member() {
    // Kepler, n = 12, h = 0.5, 40 steps: the angular momentum (discrete Noether) to round-off,
    // the energy to the method's error (measured ≤ 3e-8 relative).
    let s = scene("kepler", 12, 0.5, 40);
    let e = run_ensemble(&s, &options(6, 1e-3, 3), None).unwrap();
    assert_eq!(e.momentum_names, ["angular_momentum"]);
    for m in &e.members {
        assert_eq!(m.steps_completed, 40);
        assert!(m.momentum_errors[0] < 1e-13, "{:?}", m.momentum_errors);
        assert!(
            m.max_relative_energy_error < 1e-6,
            "{}",
            m.max_relative_energy_error
        );
    }
    let summary = e.summary();
    let names: Vec<&str> = summary.iter().map(|s| s.quantity.as_str()).collect();
    assert_eq!(
        names,
        [
            "max_rel_energy_error",
            "max_angular_momentum_error",
            "lyapunov"
        ]
    );
    for st in &summary {
        assert_eq!(st.count, 6);
        assert!(st.min <= st.mean && st.mean <= st.max && st.std >= 0.0);
    }
}

/// For a regular (non-chaotic) orbit the tangent map grows at most linearly in time (shear
/// along the invariant tori), so ln(‖Φ_N‖/‖I‖)/T ≤ ln(1 + c T)/T; for the harmonic oscillator
/// the discrete map is conjugate to a rotation and ‖Φ_N‖ stays bounded, so the estimate is
/// O(1/T).
#[test]
fn lyapunov_estimate_positive_for_chaos_and_near_zero_for_the_oscillator() {
    // Chaotic: the double pendulum released from rest at (1.5, 0.5) rad, T = 400 (measured
    // λ ≈ 0.058–0.075 over four members).
    let s = scene("double-pendulum", 16, 0.5, 800);
    let t = 400.0;
    let chaos = run_ensemble(&s, &options(4, 1e-6, 1), None).unwrap();
    // Negative control: the harmonic oscillator, same horizon.
    // Measured λ ≈ 1e-13: the estimate is round-off.
    let s = scene("harmonic", 10, 0.5, 800);
    let osc = run_ensemble(&s, &options(4, 1e-3, 1), None).unwrap();
    for m in &osc.members {
        assert!(
            m.lyapunov.abs() < 1.0 / t,
            "oscillator: λ = {} above 1/T",
            m.lyapunov
        );
    }
    // Exponential growth beats the linear growth of regular motion with any constant up to
    // T itself: ln(‖Φ‖/‖I‖) > ln(T · T).
    for m in &chaos.members {
        assert_eq!(m.steps_completed, 800);
        assert!(
            m.lyapunov > 2.0 * f64::ln(t) / t,
            "double pendulum: λ = {} not above 2 ln(T)/T = {}",
            m.lyapunov,
            2.0 * f64::ln(t) / t
        );
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let s = scene("kepler", 12, 0.5, 5);
    let cases = [
        (options(0, 1e-3, 0), "--count"),
        (options(3, -1.0, 0), "--perturb"),
        (options(3, f64::NAN, 0), "--perturb"),
        (options(3, f64::INFINITY, 0), "--perturb"),
    ];
    for (o, flag) in cases {
        match run_ensemble(&s, &o, None) {
            Err(LabError::InvalidArgument { name, .. }) => assert_eq!(name, flag),
            other => panic!("{o:?}: expected InvalidArgument({flag}), got {other:?}"),
        }
    }
    // Rigid bodies (SO(3)) have no ensemble: a typed error, not a panic.
    let s = Scene::load("rigid-body").unwrap().build().unwrap();
    assert!(matches!(
        run_ensemble(&s, &options(2, 0.0, 0), None),
        Err(LabError::Core(_))
    ));
}

#[test]
fn the_command_writes_csv_and_summary_and_reports_throughput() {
    let dir = std::env::temp_dir().join(format!("gvi-ensemble-{}", std::process::id()));
    let csv = dir.join("kepler.csv");
    let out = Command::new(env!("CARGO_BIN_EXE_gvi"))
        .args(["ensemble", "kepler", "--count", "4", "--perturb", "1e-4"])
        .args(["--steps", "10", "--n", "10", "--h", "0.5", "--threads", "2"])
        .arg("--output")
        .arg(&csv)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("speed-up"), "{stderr}");
    assert!(stderr.contains("one-thread results identical"), "{stderr}");
    // How to read the Lyapunov estimate of an integrable system, at this run's T = 5.
    assert!(
        stderr.contains("lyapunov is a finite-time estimate")
            && stderr.contains("ln(T)/T = 3.219e-1"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 5);
    let summary = std::fs::read_to_string(dir.join("kepler-summary.csv")).unwrap();
    assert!(summary.starts_with("quantity,count,mean,std,min,max\n"));
    assert!(summary.contains("\nlyapunov,4,"));
    std::fs::remove_dir_all(&dir).ok();

    for (args, flag) in [
        (["--count", "0", "--perturb", "1e-3"], "--count"),
        (["--count", "3", "--perturb", "-1"], "--perturb"),
        (["--count", "3", "--perturb", "nan"], "--perturb"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_gvi"))
            .args(["ensemble", "kepler"])
            .args(args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(stderr.contains(flag), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn the_member_step_loop_allocates_nothing() {
    use crate::common::counting::allocations;
    use galerkin_vi::systems::System;
    use galerkin_vi_lab::ensemble::run_member;
    let s = scene("kepler", 8, 0.5, 1);
    let system = s.euclidean().unwrap();
    let gvi = s.method.integrator().unwrap();
    let symmetries = system.symmetries();
    let member = perturbed_members(&s.initial.q, &s.initial.p, &options(1, 0.0, 0))
        .unwrap()
        .remove(0);
    // Everything run_member allocates is allocated before its loop: the count does not grow
    // with the number of steps (step, step Jacobian, tangent product, invariants).
    let in_member = |steps: usize| {
        let before = allocations();
        let r = run_member(&gvi, system, &symmetries, &member, steps).unwrap();
        assert!(r.failure.is_none());
        allocations() - before
    };
    // The integrator builds its stage pencils' Schur forms when a solve first needs them
    // (here the step Jacobian's), once for every member that shares it: the first member
    // pays for those few tables, and no member's count grows with its steps.
    let first = in_member(10);
    let (short, long) = (in_member(10), in_member(60));
    assert_eq!(
        short, long,
        "allocations: {short} for 10 steps, {long} for 60"
    );
    assert!(
        first >= short && first - short <= 16,
        "the first member's one-time tables: {first} against {short} allocations"
    );
    // Negative control: the owning step_jacobian_in allocates on every step.
    let owning = |steps: usize| {
        let mut ws = gvi.workspace(system).unwrap();
        let (mut q, mut p) = (member.q0.clone(), member.p0.clone());
        let before = allocations();
        for k in 0..steps {
            let sj = gvi.step_jacobian_in(system, &mut ws, &q, &p, k).unwrap();
            q = sj.q_next;
            p = sj.p_next;
        }
        allocations() - before
    };
    let (short, long) = (owning(10), owning(60));
    assert!(long > short, "control: {short} for 10 steps, {long} for 60");
}
