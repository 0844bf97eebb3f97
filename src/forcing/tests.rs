//! Forced and time-dependent motions: exact solutions, geometric convergence in n, the
//! energy and momentum balances (each with a negative control), and typed refusals.

use super::*;
use crate::DualNum;
use crate::geometry::{Rotation, finite_difference_jacobian, relative_symplecticity_defect};
use crate::integrator::GalerkinIntegrator;
use crate::systems::{HarmonicOscillator, Kepler};

/// x'' + 2ζ x' + x = 0 from (1, 0): the underdamped exact solution.
fn damped_exact(zeta: f64, t: f64) -> f64 {
    let wd = (1.0 - zeta * zeta).sqrt();
    (-zeta * t).exp() * ((wd * t).cos() + zeta / wd * (wd * t).sin())
}

fn damped(zeta: f64) -> Forced<HarmonicOscillator, LinearDamping> {
    Forced::new(
        HarmonicOscillator::new(1.0, 1.0).unwrap(),
        LinearDamping::uniform(1, 2.0 * zeta).unwrap(),
    )
    .unwrap()
}

/// Least-squares slope of log10(err) against n.
fn log_slope(ns: &[usize], errs: &[f64]) -> f64 {
    let x: Vec<f64> = ns.iter().map(|&n| n as f64).collect();
    let y: Vec<f64> = errs.iter().map(|e| e.log10()).collect();
    let (mx, my) = (
        x.iter().sum::<f64>() / x.len() as f64,
        y.iter().sum::<f64>() / y.len() as f64,
    );
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

#[test]
fn damped_oscillator_converges_geometrically_in_n() {
    let (zeta, h, steps) = (0.1, 1.0, 20);
    let sys = damped(zeta);
    let ns = [4, 5, 6, 7, 8, 9, 10];
    let mut errs = Vec::new();
    for &n in &ns {
        let gvi = GalerkinIntegrator::spectral(n, h).unwrap();
        let traj = gvi.integrate(&sys, 0.0, &[1.0], &[0.0], steps).unwrap();
        let err = (0..=steps)
            .map(|k| (traj.q[k][0] - damped_exact(zeta, k as f64 * h)).abs())
            .fold(0.0, f64::max);
        errs.push(err);
    }
    // Measured: 1.7e-5, 7.0e-8, 1.8e-10, 3.1e-13, then round-off (7e-16) from n = 8: about
    // 2.6 decades per basis function before the floor.
    let slope = log_slope(&ns[..4], &errs[..4]);
    assert!(slope < -2.0, "errors {errs:?}, slope {slope}");
    assert!(errs[4..].iter().all(|&e| e < 1e-14), "{errs:?}");
}

#[test]
fn damped_oscillator_energy_balance_holds_and_unforced_bookkeeping_fails_it() {
    let sys = damped(0.1);
    let gvi = GalerkinIntegrator::spectral(14, 1.0).unwrap();
    let traj = gvi.integrate(&sys, 0.0, &[1.0], &[0.0], 30).unwrap();
    let balance = energy_balance(&sys, &traj).unwrap();
    assert!(balance.max_change() > 0.4);
    assert!(balance.max_defect() < 1e-13, "{}", balance.max_defect());
    // Negative control: the same energies without the work of the force.
    let plain = energy_balance(sys.lagrangian(), &traj).unwrap();
    assert!(plain.max_defect() > 0.4, "{}", plain.max_defect());
}

/// L = v²/2 − q²/2 + γ q cos ωt: the driven oscillator as a time-dependent Lagrangian.
struct DrivenLagrangian {
    gamma: f64,
    omega: f64,
}
impl NonAutonomousLagrangian for DrivenLagrangian {
    fn dim(&self) -> usize {
        1
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, t: T, q: &[T], v: &[T]) -> T {
        (v[0] * v[0] - q[0] * q[0]) * 0.5 + q[0] * (t * self.omega).cos() * self.gamma
    }
}

/// The same drive as a Lagrange–d'Alembert force f = γ cos ωt.
struct Drive {
    gamma: f64,
    omega: f64,
}
impl ExternalForce for Drive {
    fn dim(&self) -> usize {
        1
    }
    fn force<T: DualNum<Primitive = f64> + Copy>(&self, t: T, _q: &[T], _v: &[T], f: &mut [T]) {
        f[0] = (t * self.omega).cos() * self.gamma;
    }
}

#[test]
fn a_drive_as_time_dependent_lagrangian_or_as_force_gives_the_exact_motion() {
    let (gamma, omega) = (0.5, 1.2);
    let a = gamma / (1.0 - omega * omega);
    let exact = |t: f64| (1.0 - a) * t.cos() + a * (omega * t).cos();
    let timed = NonAutonomous(DrivenLagrangian { gamma, omega });
    let forced = Forced::new(
        HarmonicOscillator::new(1.0, 1.0).unwrap(),
        Drive { gamma, omega },
    )
    .unwrap();
    let gvi = GalerkinIntegrator::spectral(14, 0.5).unwrap();
    let (t0, steps) = (3.0, 40);
    // Start at t0 = 3 so that a missing time offset would show.
    let velocity = |t: f64| -(1.0 - a) * t.sin() - a * omega * (omega * t).sin();
    let (q0, p0) = (exact(t0), velocity(t0));
    let x = gvi.integrate(&timed, t0, &[q0], &[p0], steps).unwrap();
    let y = gvi.integrate(&forced, t0, &[q0], &[p0], steps).unwrap();
    let mut worst: f64 = 0.0;
    for k in 0..=steps {
        let t = t0 + 0.5 * k as f64;
        assert!((x.q[k][0] - y.q[k][0]).abs() < 1e-13, "k = {k}");
        worst = worst.max((x.q[k][0] - exact(t)).abs());
    }
    assert!(worst < 1e-12, "{worst}");
    // Energy of the time-dependent form changes by −∫∂L/∂t; of the forced form by the work.
    let bx = energy_balance(&timed, &x).unwrap();
    let by = energy_balance(&forced, &y).unwrap();
    assert!(bx.max_change() > 0.1 && by.max_change() > 0.1);
    assert!(bx.max_defect() < 1e-12 && by.max_defect() < 1e-12);
}

#[test]
fn time_dependent_steps_are_symplectic_and_damped_ones_are_not() {
    let timed = NonAutonomous(DrivenLagrangian {
        gamma: 0.5,
        omega: 1.2,
    });
    let sys = damped(0.1);
    let gvi = GalerkinIntegrator::spectral(12, 0.5).unwrap();
    type StepMap<'a> = &'a dyn Fn(&[f64], &[f64]) -> (Vec<f64>, Vec<f64>);
    let defect = |lag: StepMap| {
        relative_symplecticity_defect(&finite_difference_jacobian(lag, &[0.7], &[0.2], 1e-5))
    };
    let step_timed = |q: &[f64], p: &[f64]| {
        let mut ws = gvi.workspace(&timed).unwrap();
        ws.set_time(2.0).unwrap();
        let (mut q1, mut p1) = (vec![0.0], vec![0.0]);
        gvi.step(&timed, &mut ws, q, p, &mut q1, &mut p1).unwrap();
        (q1, p1)
    };
    let step_damped = |q: &[f64], p: &[f64]| {
        let mut ws = gvi.workspace(&sys).unwrap();
        let (mut q1, mut p1) = (vec![0.0], vec![0.0]);
        gvi.step(&sys, &mut ws, q, p, &mut q1, &mut p1).unwrap();
        (q1, p1)
    };
    let (a, b) = (defect(&step_timed), defect(&step_damped));
    assert!(a < 1e-8, "{a}");
    // det = e^{−2ζh} for the exact damped flow: a defect of order 2ζh = 0.1.
    assert!(b > 0.05, "{b}");
}

#[test]
fn kepler_with_drag_balances_angular_momentum_and_decays() {
    let kepler = Kepler::new(1.0).unwrap();
    let drag = Forced::new(kepler, LinearDamping::uniform(2, 1e-3).unwrap()).unwrap();
    let (q0, p0) = ([1.0, 0.0], [0.0, 1.0]);
    let gvi = GalerkinIntegrator::spectral(14, 0.5).unwrap();
    let traj = gvi.integrate(&drag, 0.0, &q0, &p0, 400).unwrap();
    let rot = Rotation::planar(2, 1, 0, 1).unwrap();
    let balance = momentum_balance(&drag, &rot, &traj).unwrap();
    assert!(balance.max_change() > 0.1);
    assert!(balance.max_defect() < 1e-12, "{}", balance.max_defect());
    // Negative control: Noether's conservation law, as if there were no drag.
    let unforced = momentum_balance(drag.lagrangian(), &rot, &traj).unwrap();
    assert!(unforced.max_defect() > 0.1);
    // The orbit decays: the radius shrinks.
    let r = |k: usize| traj.q[k][0].hypot(traj.q[k][1]);
    assert!(r(400) < 0.95 * r(0), "{}", r(400));
}

#[test]
fn forced_and_time_dependent_systems_are_refused_where_autonomy_is_assumed() {
    let sys = damped(0.1);
    let gvi = GalerkinIntegrator::spectral(8, 0.5).unwrap();
    let err = gvi.tangent_workspace(&sys).unwrap_err();
    assert!(err.to_string().contains("is forced"), "{err}");
    let timed = NonAutonomous(DrivenLagrangian {
        gamma: 0.5,
        omega: 1.2,
    });
    let err = gvi.tangent_workspace(&timed).unwrap_err();
    assert!(err.to_string().contains("depends on time"), "{err}");
    // Negative control: the unforced oscillator is accepted.
    assert!(gvi.tangent_workspace(sys.lagrangian()).is_ok());
}

#[test]
fn bad_forces_are_typed_errors() {
    let ho = HarmonicOscillator::new(1.0, 1.0).unwrap();
    assert!(Forced::new(ho, LinearDamping::uniform(2, 0.1).unwrap()).is_err());
    assert!(LinearDamping::uniform(1, -0.1).is_err());
    assert!(LinearDamping::uniform(1, f64::NAN).is_err());
    assert!(LinearDamping::uniform(0, 0.1).is_err());
    assert!(LinearDamping::matrix(2, vec![1.0, 0.5, 0.4, 1.0]).is_err());
    assert!(LinearDamping::matrix(2, vec![1.0, 0.5]).is_err());
    let nbody = crate::systems::NBody::new(vec![1.0, 1e-3], 1.0, 2).unwrap();
    assert!(StokesDrag::new(&nbody, &[1.0]).is_err());
    assert!(StokesDrag::new(&nbody, &[f64::INFINITY, 0.0]).is_err());
    assert!(StokesDrag::new(&nbody, &[f64::INFINITY, 100.0]).is_ok());
    let mut ws = GalerkinIntegrator::spectral(6, 0.5)
        .unwrap()
        .workspace(&ho)
        .unwrap();
    assert!(ws.set_time(f64::NAN).is_err());
}

#[test]
fn force_jacobians_from_ad_match_the_hand_written_ones() {
    let nbody = crate::systems::NBody::new(vec![1.0, 1e-3, 2e-3], 1.0, 2).unwrap();
    let drag = StokesDrag::new(&nbody, &[f64::INFINITY, 50.0, 80.0])
        .unwrap()
        .with_medium_velocity(&[0.0, 0.0, 0.1, -0.2, 0.0, 0.3])
        .unwrap();
    /// The same drag through the default (AD) Jacobian.
    struct Ad<'a>(&'a StokesDrag);
    impl ExternalForce for Ad<'_> {
        fn dim(&self) -> usize {
            self.0.dim()
        }
        fn force<T: DualNum<Primitive = f64> + Copy>(&self, t: T, q: &[T], v: &[T], f: &mut [T]) {
            self.0.force(t, q, v, f)
        }
    }
    let q = [0.1, 0.2, 1.0, 0.0, -1.5, 0.3];
    let v = [0.0, 0.1, 0.0, 1.0, 0.2, -0.7];
    let (mut a, mut b, mut c, mut e) = ([0.0; 36], [0.0; 36], [0.0; 36], [0.0; 36]);
    drag.jacobian(0.0, &q, &v, &mut a, &mut b);
    Ad(&drag).jacobian(0.0, &q, &v, &mut c, &mut e);
    assert_eq!(a, c);
    assert_eq!(b, e);
    assert!(b[2 * 6 + 2] < 0.0 && b[0] == 0.0);
}

/// x'' = −δx' + x − x³ + γ cos ωt by classical RK4 on (x, v): an independent reference.
fn duffing_rk4(x0: f64, v0: f64, t_end: f64, steps: usize, out_every: usize) -> Vec<(f64, f64)> {
    let (delta, gamma, omega) = (0.3, 0.5, 1.2);
    let f = |t: f64, x: f64, v: f64| (v, -delta * v + x - x * x * x + gamma * (omega * t).cos());
    let dt = t_end / steps as f64;
    let (mut x, mut v) = (x0, v0);
    let mut out = vec![(x, v)];
    for k in 0..steps {
        let t = k as f64 * dt;
        let (a1, b1) = f(t, x, v);
        let (a2, b2) = f(t + dt / 2.0, x + dt / 2.0 * a1, v + dt / 2.0 * b1);
        let (a3, b3) = f(t + dt / 2.0, x + dt / 2.0 * a2, v + dt / 2.0 * b2);
        let (a4, b4) = f(t + dt, x + dt * a3, v + dt * b3);
        x += dt / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
        v += dt / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
        if (k + 1) % out_every == 0 {
            out.push((x, v));
        }
    }
    out
}

#[test]
fn forced_duffing_agrees_with_an_independent_integration_over_t_100() {
    let duffing = Forced::new(
        NonAutonomous(DrivenDuffing),
        LinearDamping::uniform(1, 0.3).unwrap(),
    )
    .unwrap();
    // h = 0.5, 200 steps; the reference RK4 with dt = 1/8000.
    let gvi = GalerkinIntegrator::spectral(16, 0.5).unwrap();
    let traj = gvi.integrate(&duffing, 0.0, &[1.0], &[0.0], 200).unwrap();
    let reference = duffing_rk4(1.0, 0.0, 100.0, 800_000, 4000);
    let worst = |k_end: usize| {
        (0..=k_end)
            .map(|k| (traj.q[k][0] - reference[k].0).abs())
            .fold(0.0, f64::max)
    };
    // The motion is chaotic: differences grow like e^{λt} with λ ≈ 0.23 (measured: from
    // 2.5e-14 at t = 10 to 2.7e-5 at t = 100, the same for n = 12, 16, 20 and h = 0.25; two
    // RK4 runs at dt = 1/2000 and 1/8000 differ by 6.4e-5 at t = 100). So agreement to
    // round-off holds over t ≤ 10 and to the amplified round-off over t ≤ 100.
    assert!(worst(20) < 1e-12, "t ≤ 10: {:e}", worst(20));
    assert!(worst(200) < 3e-4, "t ≤ 100: {:e}", worst(200));
    // Negative control: without the drive the motion is another one entirely.
    let undriven = Forced::new(
        crate::systems::expression::ExpressionLagrangian::parse(
            "x_dot^2/2 + x^2/2 - x^4/4",
            &["x"],
            &[],
        )
        .unwrap(),
        LinearDamping::uniform(1, 0.3).unwrap(),
    )
    .unwrap();
    let other = gvi.integrate(&undriven, 0.0, &[1.0], &[0.0], 200).unwrap();
    assert!((other.q[200][0] - reference[200].0).abs() > 0.1);
}

/// The Duffing drive as a time-dependent Lagrangian: L = v²/2 + x²/2 − x⁴/4 + γ x cos ωt.
struct DrivenDuffing;
impl NonAutonomousLagrangian for DrivenDuffing {
    fn dim(&self) -> usize {
        1
    }
    fn lagrangian<T: DualNum<Primitive = f64> + Copy>(&self, t: T, q: &[T], v: &[T]) -> T {
        v[0] * v[0] * 0.5 + q[0] * q[0] * 0.5 - q[0].powi(4) * 0.25 + q[0] * (t * 1.2).cos() * 0.5
    }
}

#[test]
fn stokes_drag_on_a_planet_balances_the_total_momentum_and_shrinks_its_orbit() {
    use crate::geometry::Translation;
    use crate::systems::NBody;
    // Sun and a planet on a circular orbit; the planet alone feels gas drag with τ = 200.
    let nbody = NBody::new(vec![1.0, 1e-3], 1.0, 2).unwrap();
    let drag = StokesDrag::new(&nbody, &[f64::INFINITY, 200.0]).unwrap();
    let system = Forced::new(nbody.clone(), drag).unwrap();
    let v = (1.0f64 + 1e-3).sqrt();
    let q0 = [0.0, 0.0, 1.0, 0.0];
    let p0 = [0.0, -1e-3 * v / 1.0, 0.0, 1e-3 * v];
    let gvi = GalerkinIntegrator::spectral(14, 0.5).unwrap();
    let traj = gvi.integrate(&system, 0.0, &q0, &p0, 200).unwrap();
    // Total momentum along y: changed by the drag's impulse only (measured: defect 3.6e-19
    // on a change of 5.0e-6, 0.5 % of the planet's momentum).
    let py = Translation::axis(2, 2, 1).unwrap();
    let balance = momentum_balance(&system, &py, &traj).unwrap();
    assert!(balance.max_change() > 1e-6, "{}", balance.max_change());
    assert!(balance.max_defect() < 1e-16, "{}", balance.max_defect());
    // Negative control: conservation of the total momentum, as without drag.
    let plain = momentum_balance(&nbody, &py, &traj).unwrap();
    assert!(plain.max_defect() > 1e-6, "{}", plain.max_defect());
    // The planet spirals in.
    let r = |k: usize| {
        let q = &traj.q[k];
        (q[2] - q[0]).hypot(q[3] - q[1])
    };
    assert!(r(200) < 0.9 * r(0), "{}", r(200));
}

#[test]
fn kepler_with_drag_agrees_with_an_independent_integration() {
    // q'' = −q/|q|³ − γ q' from a circular start, γ = 1e-3, T = 200 (the orbit decays by 18 %
    // in angular momentum): the Galerkin run against RK4 with dt = 1/2000 on (q, q').
    let gamma = 1e-3;
    let system = Forced::new(
        Kepler::new(1.0).unwrap(),
        LinearDamping::uniform(2, gamma).unwrap(),
    )
    .unwrap();
    let gvi = GalerkinIntegrator::spectral(14, 0.5).unwrap();
    let traj = gvi
        .integrate(&system, 0.0, &[1.0, 0.0], &[0.0, 1.0], 400)
        .unwrap();
    let f = |y: [f64; 4]| {
        let r3 = (y[0] * y[0] + y[1] * y[1]).powf(1.5);
        [
            y[2],
            y[3],
            -y[0] / r3 - gamma * y[2],
            -y[1] / r3 - gamma * y[3],
        ]
    };
    let (dt, per) = (1.0 / 2000.0, 1000);
    let mut y = [1.0, 0.0, 0.0, 1.0];
    let mut worst = 0.0f64;
    for k in 1..=400 {
        for _ in 0..per {
            let add = |a: [f64; 4], b: [f64; 4], s: f64| std::array::from_fn(|i| a[i] + s * b[i]);
            let k1 = f(y);
            let k2 = f(add(y, k1, dt / 2.0));
            let k3 = f(add(y, k2, dt / 2.0));
            let k4 = f(add(y, k3, dt));
            y = std::array::from_fn(|i| {
                y[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
        }
        worst = worst
            .max((traj.q[k][0] - y[0]).abs())
            .max((traj.q[k][1] - y[1]).abs());
    }
    // Measured 4.6e-12 over the 400 step ends.
    assert!(worst < 1e-10, "{worst:e}");
}
