//! Unit tests: the hand-written derivatives against automatic differentiation, the clock,
//! and the typed errors of bad input.

use super::*;
use crate::GviError;
use crate::ad;
use crate::prelude::*;

/// The Pythagorean three-body problem (Burrau): masses 3, 4, 5 at rest, G = 1.
pub(crate) fn pythagorean() -> (NBody, Vec<f64>, Vec<f64>) {
    let nb = NBody::new(vec![3.0, 4.0, 5.0], 1.0, 2).unwrap();
    (nb, vec![1.0, 3.0, -2.0, -1.0, 1.0, -1.0], vec![0.0; 6])
}

/// Compare L̃'s hand-written gradient and Hessian with AD of its generic value.
fn check_derivatives<S: Lagrangian, M: Monitor>(tt: &TimeTransformed<S, M>, q: &[f64], v: &[f64]) {
    let d = tt.dim();
    let (mut lq, mut lv) = (vec![0.0; d], vec![0.0; d]);
    tt.gradient(q, v, &mut lq, &mut lv);
    let (mut aq, mut av) = (vec![0.0; d], vec![0.0; d]);
    ad::gradient_blocks(|y| tt.lagrangian(&y[..d], &y[d..]), q, v, &mut aq, &mut av);
    let scale = aq.iter().chain(&av).fold(1e-300f64, |m, x| m.max(x.abs()));
    for r in 0..d {
        assert!(
            (lq[r] - aq[r]).abs() <= 1e-12 * scale,
            "L_q[{r}]: {} vs {}",
            lq[r],
            aq[r]
        );
        assert!((lv[r] - av[r]).abs() <= 1e-12 * scale, "L_v[{r}]");
    }
    let dd = d * d;
    let (mut qq, mut qv, mut vv) = (vec![0.0; dd], vec![0.0; dd], vec![0.0; dd]);
    tt.hessian(q, v, &mut qq, &mut qv, &mut vv);
    let (mut aqq, mut aqv, mut avv) = (vec![0.0; dd], vec![0.0; dd], vec![0.0; dd]);
    ad::hessian_blocks(
        |y| tt.lagrangian(&y[..d], &y[d..]),
        (q, v),
        &mut aqq,
        &mut aqv,
        &mut avv,
    );
    let scale = aqq
        .iter()
        .chain(&aqv)
        .chain(&avv)
        .fold(1e-300f64, |m, x| m.max(x.abs()));
    for i in 0..dd {
        assert!(
            (qq[i] - aqq[i]).abs() <= 1e-11 * scale,
            "L_qq[{i}]: {} vs {}",
            qq[i],
            aqq[i]
        );
        assert!(
            (qv[i] - aqv[i]).abs() <= 1e-11 * scale,
            "L_qv[{i}]: {} vs {}",
            qv[i],
            aqv[i]
        );
        assert!((vv[i] - avv[i]).abs() <= 1e-11 * scale, "L_vv[{i}]");
    }
    // The value, the Legendre transform and the energy against their definitions.
    assert!((tt.value(q, v) - tt.lagrangian(q, v)).abs() <= 1e-13 * tt.value(q, v).abs().max(1.0));
    let mut p = vec![0.0; d];
    tt.legendre_transform(q, v, &mut p);
    assert_eq!(p, lv);
    let e = lv.iter().zip(v).map(|(a, b)| a * b).sum::<f64>() - tt.value(q, v);
    assert!((tt.energy(q, v) - e).abs() <= 1e-12 * e.abs().max(1.0));
    assert!(
        (tt.energy(q, v) - tt.transformed_hamiltonian(q, &p)).abs() <= 1e-12 * e.abs().max(1.0)
    );
}

#[test]
fn hand_written_derivatives_match_ad() {
    let kepler = Kepler::new(1.3).unwrap();
    for alpha in [1.0, 1.5, 2.0, -0.5] {
        let m = CentralDistance::new(alpha).unwrap();
        let tt = TimeTransformed::new(kepler, m, &[0.4, 0.1], &[0.2, 1.9], None).unwrap();
        check_derivatives(&tt, &[-0.3, 1.2], &[0.7, -0.4]);
        check_derivatives(&tt, &[2.0, -0.7], &[0.1, 0.3]);
    }
    let (nb, q0, p0) = pythagorean();
    for combine in [Combine::Min, Combine::Softmin, Combine::Product] {
        let m = PairDistances::new(3, 2, 1.5, combine).unwrap();
        let tt = TimeTransformed::new(nb.clone(), m, &q0, &p0, Some(-20.0)).unwrap();
        check_derivatives(
            &tt,
            &[1.1, 2.9, -1.8, -1.2, 0.9, -0.7],
            &[0.3, -0.2, 0.1, 0.5, -0.4, 0.2],
        );
    }
    // 3-D bodies.
    let nb3 = NBody::new(vec![1.0, 2.0, 0.5], 1.0, 3).unwrap();
    let q = [1.0, 0.2, -0.1, -0.5, 0.4, 0.3, 0.2, -0.9, 0.6];
    let v = [0.1, -0.3, 0.2, 0.0, 0.4, -0.1, 0.3, 0.2, -0.2];
    for combine in [Combine::Min, Combine::Softmin, Combine::Product] {
        let m = PairDistances::new(3, 3, 1.0, combine).unwrap();
        let tt = TimeTransformed::new(nb3.clone(), m, &q, &v, None).unwrap();
        check_derivatives(&tt, &q, &v);
    }
}

#[test]
fn potential_energy_is_minus_the_lagrangian_at_rest() {
    let (nb, q, _) = pythagorean();
    let kepler = Kepler::new(1.3).unwrap();
    for (v, l) in [
        (nb.potential_energy(&q), nb.value(&q, &[0.0; 6])),
        (
            kepler.potential_energy(&[0.4, 0.3]),
            kepler.value(&[0.4, 0.3], &[0.0; 2]),
        ),
    ] {
        assert_eq!(v, Some(-l));
    }
    let any = crate::systems::AnySystem::NBody(nb.clone());
    assert_eq!(any.potential_energy(&q), nb.potential_energy(&q));
    assert_eq!(
        crate::systems::AnySystem::Harmonic(HarmonicOscillator::unit()).potential_energy(&[1.0]),
        Some(0.5)
    );
}

#[test]
fn monitor_derivatives_match_ad() {
    let q = [1.1, 2.9, -1.8, -1.2, 0.9, -0.7];
    for combine in [Combine::Min, Combine::Softmin, Combine::Product] {
        let m = PairDistances::new(3, 2, 1.5, combine).unwrap();
        let (mut g, mut h) = ([0.0; 6], [0.0; 36]);
        let value = m.hessian(&q, &mut g, &mut h);
        let (mut ag, mut ah) = ([0.0; 6], [0.0; 36]);
        let ad_value = ad::hessian(|y| m.value(y), &q, &mut ag, &mut ah);
        assert!((value - ad_value).abs() < 1e-13 * value);
        assert!((m.value_f64(&q) - value).abs() < 1e-13 * value);
        let mut g1 = [0.0; 6];
        assert!((m.gradient(&q, &mut g1) - value).abs() < 1e-13 * value);
        for i in 0..6 {
            assert!(
                (g[i] - ag[i]).abs() < 1e-12 * value.max(1.0),
                "{combine:?} grad {i}"
            );
            assert!((g1[i] - ag[i]).abs() < 1e-12 * value.max(1.0));
        }
        for i in 0..36 {
            assert!(
                (h[i] - ah[i]).abs() < 1e-11 * value.max(1.0),
                "{combine:?} hess {i}"
            );
        }
    }
    // Min is the closest pair's distance: bodies 1 and 2 here.
    let m = PairDistances::new(3, 2, 1.0, Combine::Min).unwrap();
    let r12 = ((1.1f64 - 0.9).powi(2) + (2.9f64 + 0.7).powi(2)).sqrt();
    let r23 = ((-1.8f64 - 0.9).powi(2) + (-1.2f64 + 0.7).powi(2)).sqrt();
    let r13 = ((1.1f64 + 1.8).powi(2) + (2.9f64 + 1.2).powi(2)).sqrt();
    assert_eq!(m.value_f64(&q), r12.min(r23).min(r13));
    // The smooth minimum is below the minimum and within (pairs)^(1/β) of it.
    let s = PairDistances::new(3, 2, 1.0, Combine::Softmin).unwrap();
    let min = r12.min(r23).min(r13);
    assert!(s.value_f64(&q) < min && s.value_f64(&q) > min * 3f64.powf(-1.0 / SOFTMIN_BETA));
}

#[test]
fn the_clock_integrates_the_monitor_along_the_curve() {
    // A circular Kepler orbit with g = r^{3/2}: g is constant (1 after normalisation), so
    // t(s) = s to round-off, at the step ends and inside the steps.
    let kepler = Kepler::new(1.0).unwrap();
    let m = CentralDistance::new(1.5).unwrap();
    let (q0, p0) = ([2.0, 0.0], [0.0, 0.5f64.sqrt()]);
    let tt = TimeTransformed::new(kepler, m, &q0, &p0, None).unwrap();
    let gvi = GalerkinIntegrator::spectral(10, 0.7).unwrap();
    let mut stepper = tt.stepper(&gvi, 3.0, &q0, &p0).unwrap();
    for _ in 0..20 {
        stepper.step().unwrap();
        assert!((stepper.time() - 3.0 - stepper.fictitious_time()).abs() < 1e-12);
        assert!((stepper.last_step() - 0.7).abs() < 1e-12);
        let mid = stepper.time_on_curve(0.37);
        assert!((mid - stepper.previous_time() - 0.37 * 0.7).abs() < 1e-12);
        // τ = 1 is the step's end: the same increment, bit for bit.
        assert_eq!(
            stepper.time_on_curve(1.0),
            stepper.previous_time() + stepper.last_step()
        );
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = ([0.4, 0.0], [0.0, 2.0]);
    let radius = CentralDistance::new(1.5).unwrap();
    // The monitor is zero at q0 (r = 0): not positive.
    let e = TimeTransformed::new(kepler, radius, &[0.0, 0.0], &p0, Some(-0.5)).unwrap_err();
    assert!(
        matches!(&e, GviError::InvalidParameter { name, value, .. } if name.contains("monitor") && *value == 0.0),
        "{e}"
    );
    // Not finite: r^{-1} at r = 0.
    let inverse = CentralDistance::new(-1.0).unwrap();
    let e = TimeTransformed::new(kepler, inverse, &[0.0, 0.0], &p0, Some(-0.5)).unwrap_err();
    assert!(
        matches!(&e, GviError::InvalidParameter { value, .. } if value.is_infinite()),
        "{e}"
    );
    // E₀ not finite.
    for bad in [f64::NAN, f64::INFINITY] {
        let e = TimeTransformed::new(kepler, radius, &q0, &p0, Some(bad)).unwrap_err();
        assert!(
            matches!(&e, GviError::InvalidParameter { name, .. } if name.contains("E0")),
            "{e}"
        );
    }
    // α not finite.
    assert!(matches!(
        CentralDistance::new(f64::NAN),
        Err(GviError::InvalidParameter { .. })
    ));
    assert!(PairDistances::new(1, 2, 1.0, Combine::Min).is_err());
    assert!(PairDistances::new(3, 4, 1.0, Combine::Min).is_err());
    // A state of the wrong length, a non-finite state, a monitor of another dimension.
    assert!(TimeTransformed::new(kepler, radius, &[0.4], &p0, None).is_err());
    assert!(TimeTransformed::new(kepler, radius, &[f64::NAN, 0.0], &p0, None).is_err());
    let pairs = PairDistances::new(3, 2, 1.0, Combine::Min).unwrap();
    assert!(matches!(
        TimeTransformed::new(kepler, pairs, &q0, &p0, None),
        Err(GviError::DimensionMismatch { .. })
    ));
    // Two coincident bodies: the pair monitor is zero.
    let (nb, mut q, p) = pythagorean();
    q[2] = 1.0;
    q[3] = 3.0;
    let e = TimeTransformed::new(nb, pairs, &q, &p, None).unwrap_err();
    assert!(matches!(e, GviError::InvalidParameter { .. }), "{e}");
    // A non-separable or forced system.
    let damped = crate::Forced::new(
        HarmonicOscillator::unit(),
        crate::LinearDamping::uniform(1, 0.1).unwrap(),
    )
    .unwrap();
    let one = CentralDistance::new(0.0).unwrap();
    assert!(matches!(
        TimeTransformed::new(damped, one, &[1.0], &[0.0], None),
        Err(GviError::Unsupported(_))
    ));
    // The spec: unknown monitor names, non-finite fields, a monitor that does not fit.
    assert!("warp".parse::<MonitorKind>().is_err());
    let mut spec = TimeTransformSpec::new(MonitorKind::Radius);
    let nbody = crate::systems::AnySystem::NBody(pythagorean().0);
    assert!(matches!(
        spec.monitor_for(&nbody),
        Err(GviError::Unsupported(_))
    ));
    spec.energy = Some(f64::NAN);
    assert!(spec.validate().is_err());
    spec.energy = None;
    spec.every = Some(0.0);
    assert!(spec.validate().is_err());
}

#[test]
fn run_options_are_checked() {
    let kepler = Kepler::new(1.0).unwrap();
    let (q0, p0) = ([0.4, 0.0], [0.0, 2.0]);
    let tt =
        TimeTransformed::new(kepler, CentralDistance::new(1.5).unwrap(), &q0, &p0, None).unwrap();
    let gvi = GalerkinIntegrator::spectral(8, 0.1).unwrap();
    let run = |o: &TimeTransformOptions| {
        integrate_time_transformed(&gvi, &tt, 0.0, &q0, &p0, &mut [], o).map(|_| ())
    };
    let base = TimeTransformOptions::default();
    for bad in [
        TimeTransformOptions {
            t_end: Some(-1.0),
            ..base.clone()
        },
        TimeTransformOptions {
            t_end: Some(f64::NAN),
            ..base.clone()
        },
        TimeTransformOptions {
            every: Some(0.0),
            ..base.clone()
        },
        TimeTransformOptions {
            max_steps: 0,
            ..base.clone()
        },
    ] {
        let e = run(&bad).unwrap_err();
        assert!(e.partial.is_none(), "{e}");
    }
    // Too few steps for t_end: an error that keeps the run.
    let short = TimeTransformOptions {
        t_end: Some(100.0),
        max_steps: 5,
        ..base.clone()
    };
    let e = run(&short).unwrap_err();
    assert!(matches!(e.error, GviError::InvalidStepCount { .. }));
    assert_eq!(e.partial.map(|p| p.steps()), Some(5));
    // An event that maps the state is refused.
    let mut events = [
        crate::events::Event::new("x", |_t: f64, q: &[f64], _p: &[f64]| q[0])
            .apply(|_t, _q, p| p[0] = -p[0]),
    ];
    let e = integrate_time_transformed(&gvi, &tt, 0.0, &q0, &p0, &mut events, &base).unwrap_err();
    assert!(matches!(e.error, GviError::Unsupported(_)));
}
