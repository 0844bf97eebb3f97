//! Tests of the Kepler drift against independent references (orbital elements with Kepler's
//! and Barker's equations, mpmath tables, finite differences). Measured values are in comments.

use super::*;
use std::f64::consts::PI;

type State = ([f64; 3], [f64; 3]);

/// An orbit by its elements: μ, pericentre distance q, eccentricity e, inclination, node,
/// argument of pericentre, and the mean anomaly at t = 0 (for e = 1: Barker's D = tan(ν/2)).
#[derive(Clone, Copy, Debug)]
struct Orbit {
    mu: f64,
    q: f64,
    e: f64,
    angles: [f64; 3],
    m0: f64,
}

const fn orbit(mu: f64, q: f64, e: f64, m0: f64) -> Orbit {
    Orbit {
        mu,
        q,
        e,
        angles: [0.3, 1.1, -0.7],
        m0,
    }
}

impl Orbit {
    /// Mean motion (ellipse/hyperbola) or √(μ/(2q³)) (parabola).
    fn n(&self) -> f64 {
        let a = self.q / (1.0 - self.e).abs();
        if self.e == 1.0 {
            (self.mu / (2.0 * self.q.powi(3))).sqrt()
        } else {
            (self.mu / a.powi(3)).sqrt()
        }
    }

    fn period(&self) -> f64 {
        2.0 * PI / self.n()
    }

    /// The state at time t, by the elements alone (no universal variables, no Stumpff series).
    fn state(&self, t: f64) -> State {
        let (q, e, n) = (self.q, self.e, self.n());
        let m = self.m0 + n * t;
        let (x, y, vx, vy);
        if e < 1.0 {
            let a = q / (1.0 - e);
            let b = a * (1.0 - e * e).sqrt();
            let m = m - 2.0 * PI * (m / (2.0 * PI)).round();
            let mut ea = m + 0.85 * e * m.sin().signum();
            for _ in 0..100 {
                let d = (ea - e * ea.sin() - m) / (1.0 - e * ea.cos());
                ea -= d;
                if d.abs() < 1e-16 {
                    break;
                }
            }
            let den = 1.0 - e * ea.cos();
            (x, y) = (a * (ea.cos() - e), b * ea.sin());
            (vx, vy) = (-a * n * ea.sin() / den, b * n * ea.cos() / den);
        } else if e > 1.0 {
            let a = q / (e - 1.0);
            let b = a * (e * e - 1.0).sqrt();
            let mut h = m.signum() * (2.0 * m.abs() / e + 1.8).ln();
            for _ in 0..200 {
                let d = (e * h.sinh() - h - m) / (e * h.cosh() - 1.0);
                h -= d;
                if d.abs() < 1e-16 * h.abs().max(1.0) {
                    break;
                }
            }
            let den = e * h.cosh() - 1.0;
            (x, y) = (a * (e - h.cosh()), b * h.sinh());
            (vx, vy) = (-a * n * h.sinh() / den, b * n * h.cosh() / den);
        } else {
            // Barker: D + D³/3 = M, D = w − 1/w with w³ = 3M/2 + √(1 + 9M²/4), then Newton.
            let w = (1.5 * m.abs() + (1.0 + 2.25 * m * m).sqrt()).cbrt();
            let mut d = m.signum() * (w - 1.0 / w);
            d -= (d + d * d * d / 3.0 - m) / (1.0 + d * d);
            let dd = n / (1.0 + d * d);
            (x, y) = (q * (1.0 - d * d), 2.0 * q * d);
            (vx, vy) = (-2.0 * q * d * dd, 2.0 * q * dd);
        }
        (self.rotate([x, y, 0.0]), self.rotate([vx, vy, 0.0]))
    }

    /// Rz(node) Rx(inclination) Rz(argument of pericentre).
    fn rotate(&self, p: [f64; 3]) -> [f64; 3] {
        let [i, node, peri] = self.angles;
        let (s, c) = peri.sin_cos();
        let p = [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
        let (s, c) = i.sin_cos();
        let p = [p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]];
        let (s, c) = node.sin_cos();
        [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]]
    }

    fn drift(&self, t: f64) -> KeplerDrift {
        let (r0, v0) = self.state(0.0);
        KeplerDrift::new(self.mu, r0, v0, t, None).unwrap()
    }
}

const MERCURY_MU: f64 = 2.959e-4;
/// e = 0.6, e = 0.05 (Mercury-like a), e = 0.206 (Mercury), hyperbolic e = 1.5, parabola,
/// near-parabolic e = 1 ∓ 1e-3.
const ORBITS: [Orbit; 7] = [
    orbit(1.0, 0.4, 0.6, 0.4),
    orbit(MERCURY_MU, 0.387 * 0.95, 0.05, 2.0),
    orbit(MERCURY_MU, 0.387 * 0.794, 0.206, -1.0),
    orbit(1.0, 0.7, 1.5, -0.5),
    orbit(1.0, 0.5, 1.0, -1.2),
    orbit(1.0, 0.5, 0.999, -0.01),
    orbit(1.0, 0.5, 1.001, -0.3),
];

/// Times for an orbit: a fraction of the local time scale, tiny, negative, several periods.
fn times(o: &Orbit) -> Vec<f64> {
    let scale = (o.q.powi(3) / o.mu).sqrt();
    let mut ts = vec![0.9 * scale, -2.3 * scale, 1e-9 * scale, 7.7 * scale];
    if o.e < 1.0 {
        ts.extend([7.3 * o.period(), -3.6 * o.period()]);
    } else {
        ts.extend([300.0 * scale, -40.0 * scale]);
    }
    ts
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// max_i |a_i − b_i| / |b|.
fn rel(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).abs()).fold(0.0, f64::max) / norm(b)
}

#[test]
fn end_state_matches_orbital_elements_and_barker() {
    let mut worst = 0.0_f64;
    for o in &ORBITS {
        for t in times(o) {
            let d = o.drift(t);
            let (r, v) = o.state(t);
            let err = rel(d.position(), r).max(rel(d.velocity(), v));
            worst = worst.max(err);
        }
    }
    eprintln!("worst relative error against the elements: {worst:.1e}");
    assert!(worst < 1e-12, "{worst:e}");
}

#[test]
fn energy_and_angular_momentum_are_conserved() {
    let (mut de, mut dh, mut dh_plain) = (0.0_f64, 0.0_f64, 0.0_f64);
    for o in &ORBITS {
        let (r0, v0) = o.state(0.0);
        let energy = |r: [f64; 3], v: [f64; 3]| 0.5 * dot(v, v) - o.mu / norm(r);
        let scale = 0.5 * dot(v0, v0) + o.mu / norm(r0);
        let h0 = cross(r0, v0);
        for t in times(o) {
            let d = o.drift(t);
            let (r, v) = (d.position(), d.velocity());
            de = de.max((energy(r, v) - energy(r0, v0)).abs() / scale);
            // Relative to |r||v|, the size of the terms of r × v (far out on a hyperbola r ∥ v
            // and |h| ≪ |r||v|); relative to |h| itself it is at most 6e-14 (e = 1.5, r/r0 ≈ 300).
            let size = norm(r) * norm(v) / norm(h0);
            dh = dh.max(rel(cross(r, v), h0) / size.max(1.0));
            dh_plain = dh_plain.max(rel(cross(r, v), h0));
        }
    }
    eprintln!(
        "energy {de:.1e} (of |v²/2| + μ/r), angular momentum {dh:.1e} (of |r||v|; {dh_plain:.1e} of |h|)"
    );
    assert!(
        de < 1e-14 && dh < 1e-14,
        "energy {de:e}, angular momentum {dh:e}"
    );
}

#[test]
fn drifting_back_returns_to_the_start() {
    let (mut worst, mut worst_plain, mut short) = (0.0_f64, 0.0_f64, 0.0_f64);
    for o in &ORBITS {
        let (r0, v0) = o.state(0.0);
        for t in times(o) {
            let d = o.drift(t);
            let back = KeplerDrift::new(o.mu, d.position(), d.velocity(), -t, None).unwrap();
            let err = rel(back.position(), r0).max(rel(back.velocity(), v0));
            // The end state's rounding comes back amplified by |Dφ₋ₜ| (scaled): 1 for short
            // drifts, up to 1e3 over many periods or far out on a hyperbola.
            let sc = scales(&d, (r0, v0));
            let cond = max_abs(&matrix(|dr, dv| d.pull_back(dr, dv), sc[1], sc[0])).max(1.0);
            (worst, worst_plain) = (worst.max(err / cond), worst_plain.max(err));
            if t.abs() <= 3.0 * (o.q.powi(3) / o.mu).sqrt() {
                short = short.max(err);
            }
            let anomaly = (back.anomaly() + d.anomaly()).abs() / d.anomaly().abs().max(1e-300);
            assert!(anomaly < 1e-12, "anomaly {anomaly:e}");
        }
    }
    eprintln!(
        "round trip: {worst:.1e} × condition number; plain {worst_plain:.1e}, short {short:.1e}"
    );
    assert!(worst < 2e-14 && short < 1e-14, "{worst:e} {short:e}");
}

/// The tangent matrix in units of the start's |r0|, |v0| (inputs) and the end's (outputs),
/// column k from `map` applied to the k-th unit vector.
fn matrix(
    map: impl Fn([f64; 3], [f64; 3]) -> State,
    (l0, s0): (f64, f64),
    (l1, s1): (f64, f64),
) -> [[f64; 6]; 6] {
    let mut m = [[0.0; 6]; 6];
    for k in 0..6 {
        let (mut dr, mut dv) = ([0.0; 3], [0.0; 3]);
        if k < 3 {
            dr[k] = l0
        } else {
            dv[k - 3] = s0
        }
        let (a, b) = map(dr, dv);
        for i in 0..3 {
            m[i][k] = a[i] / l1;
            m[i + 3][k] = b[i] / s1;
        }
    }
    m
}

/// Central differences of the drift from (r, v) over t, steps h and h/2 of the scales
/// combined by Richardson extrapolation (error O(h⁴) + O(ε/h)).
fn finite_differences(mu: f64, (r, v): State, t: f64, scales: [(f64, f64); 2]) -> [[f64; 6]; 6] {
    let flow = |dr: [f64; 3], dv: [f64; 3], s: f64| {
        let add = |a: [f64; 3], b: [f64; 3]| [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]];
        let d = KeplerDrift::new(mu, add(r, dr), add(v, dv), t, None).unwrap();
        (d.position(), d.velocity())
    };
    let central = |dr, dv, h: f64| {
        let ((rp, vp), (rm, vm)) = (flow(dr, dv, h), flow(dr, dv, -h));
        let diff = |p: [f64; 3], m: [f64; 3]| [0, 1, 2].map(|i| (p[i] - m[i]) / (2.0 * h));
        [diff(rp, rm), diff(vp, vm)]
    };
    let h = FD_STEP;
    matrix(
        |dr, dv| {
            let (coarse, fine) = (central(dr, dv, h), central(dr, dv, 0.5 * h));
            let extrapolate = |k: usize| [0, 1, 2].map(|i| (4.0 * fine[k][i] - coarse[k][i]) / 3.0);
            (extrapolate(0), extrapolate(1))
        },
        scales[0],
        scales[1],
    )
}

/// Finite-difference step, relative to |r0| and |v0|.
const FD_STEP: f64 = 2e-5;

fn max_abs(m: &[[f64; 6]; 6]) -> f64 {
    m.iter().flatten().fold(0.0, |a: f64, b| a.max(b.abs()))
}

fn max_diff(a: &[[f64; 6]; 6], b: &[[f64; 6]; 6]) -> f64 {
    let mut d = 0.0_f64;
    for i in 0..6 {
        for k in 0..6 {
            d = d.max((a[i][k] - b[i][k]).abs());
        }
    }
    d
}

/// Orbits and times for the tangent tests: incl. hyperbolic, parabolic and many periods.
fn tangent_cases() -> Vec<(Orbit, f64)> {
    let mut cases = Vec::new();
    for o in &ORBITS {
        let scale = (o.q.powi(3) / o.mu).sqrt();
        cases.push((*o, 0.9 * scale));
        cases.push((*o, -2.3 * scale));
        if o.e < 0.99 {
            cases.push((*o, 20.4 * o.period()));
        }
    }
    cases.push((ORBITS[3], 60.0));
    cases
}

fn scales(d: &KeplerDrift, (r0, v0): State) -> [(f64, f64); 2] {
    [
        (norm(r0), norm(v0)),
        (norm(d.position()), norm(d.velocity())),
    ]
}

#[test]
fn push_forward_matches_finite_differences() {
    let mut worst = 0.0_f64;
    for (o, t) in tangent_cases() {
        let start = o.state(0.0);
        let d = o.drift(t);
        let sc = scales(&d, start);
        let m = matrix(|dr, dv| d.push_forward(dr, dv), sc[0], sc[1]);
        let fd = finite_differences(o.mu, start, t, sc);
        let err = max_diff(&m, &fd) / max_abs(&m);
        worst = worst.max(err);
    }
    eprintln!("push_forward against central differences: {worst:.1e}");
    assert!(worst < 1e-9, "{worst:e}");
}

#[test]
fn pull_back_inverts_push_forward_and_matches_the_backward_drift() {
    let (mut inverse, mut inverse_scaled, mut inverse_short) = (0.0_f64, 0.0_f64, 0.0_f64);
    let mut inverse_hyperbolic = 0.0_f64;
    let mut fd_err = 0.0_f64;
    for (o, t) in tangent_cases() {
        let start = o.state(0.0);
        let d = o.drift(t);
        let sc = scales(&d, start);
        let round = matrix(
            |dr, dv| {
                let (a, b) = d.push_forward(dr, dv);
                d.pull_back(a, b)
            },
            sc[0],
            sc[0],
        );
        let mut identity = [[0.0; 6]; 6];
        (0..6).for_each(|i| identity[i][i] = 1.0);
        let pull = matrix(|dr, dv| d.pull_back(dr, dv), sc[1], sc[0]);
        let push = matrix(|dr, dv| d.push_forward(dr, dv), sc[0], sc[1]);
        // Rounding in the pushed vector comes back amplified by |M⁻¹|: normalise by |M||M⁻¹|.
        let cond = max_abs(&push) * max_abs(&pull);
        let err = max_diff(&round, &identity);
        inverse = inverse.max(err);
        if o.e > 1.0 {
            inverse_hyperbolic = inverse_hyperbolic.max(err / cond);
        } else {
            inverse_scaled = inverse_scaled.max(err / cond);
        }
        if cond < 30.0 {
            inverse_short = inverse_short.max(err);
        }
        let fd = finite_differences(o.mu, (d.position(), d.velocity()), -t, [sc[1], sc[0]]);
        fd_err = fd_err.max(max_diff(&pull, &fd) / max_abs(&pull));
    }
    eprintln!(
        "pull_back ∘ push_forward − I: {inverse_short:.1e} where |M||M⁻¹| < 30, {inverse:.1e} in \
         all; × |M||M⁻¹|: {inverse_scaled:.1e} (e ≤ 1), {inverse_hyperbolic:.1e} (e = 1.5); \
         pull_back against FD {fd_err:.1e}"
    );
    // Far out on the hyperbola (e = 1.5, t = 60, r/r0 ≈ 40) the reversed leg’s Kepler terms
    // cancel: 8.8e-14 × |M||M⁻¹| there (measured), 7.9e-16 × |M||M⁻¹| on the others.
    assert!(inverse_short < 1e-13, "{inverse_short:e}");
    assert!(
        inverse_scaled < 2e-15 && inverse_hyperbolic < 5e-13,
        "{inverse:e}"
    );
    // The backward drift from far out is itself noisy: 1e-9 there, ≤ 4.4e-10 elsewhere.
    assert!(fd_err < 1e-8, "{fd_err:e}");
}

#[test]
fn tangent_map_is_symplectic() {
    let mut worst = 0.0_f64;
    for (o, t) in tangent_cases() {
        let start = o.state(0.0);
        let d = o.drift(t);
        // Same length and speed scales at both ends keep the form: M̃ᵀ Ω M̃ = Ω.
        let sc = scales(&d, start)[0];
        let m = matrix(|dr, dv| d.push_forward(dr, dv), sc, sc);
        let mut defect = 0.0_f64;
        for i in 0..6 {
            for k in 0..6 {
                // (MᵀΩM)_ik = Σ_j M_ji (ΩM)_jk, ΩM = [M_v; −M_r].
                let s: f64 = (0..3)
                    .map(|j| m[j][i] * m[j + 3][k] - m[j + 3][i] * m[j][k])
                    .sum();
                let omega = if k == i + 3 {
                    1.0
                } else if i == k + 3 {
                    -1.0
                } else {
                    0.0
                };
                defect = defect.max((s - omega).abs());
            }
        }
        worst = worst.max(defect / max_abs(&m).powi(2));
    }
    eprintln!("symplecticity defect ‖MᵀΩM − Ω‖/‖M‖²: {worst:.1e}");
    assert!(worst < 1e-13, "{worst:e}");
}

#[test]
fn negative_control_tangent_without_beta_terms_fails_the_difference_test() {
    let o = ORBITS[0];
    let start = o.state(0.0);
    let d = o.drift(0.9);
    let mut wrong = d.forward;
    wrong.dgs = [0.0; 4];
    let sc = scales(&d, start);
    let m = matrix(|dr, dv| wrong.tangent(dr, dv), sc[0], sc[1]);
    let err = max_diff(&m, &finite_differences(o.mu, start, 0.9, sc)) / max_abs(&m);
    eprintln!("tangent without ∂/∂β terms against FD: {err:.1e}");
    assert!(err > 1e-3, "{err:e}");
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let (r, v) = ([1.0, 0.2, 0.0], [0.1, 1.0, 0.3]);
    let new = |mu, r, v, t, g| KeplerDrift::new(mu, r, v, t, g).map(|d| d.position());
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(new(bad, r, v, 1.0, None), Err(DriftError::NonFinite));
        assert_eq!(
            new(1.0, [1.0, bad, 0.0], v, 1.0, None),
            Err(DriftError::NonFinite)
        );
        assert_eq!(
            new(1.0, r, [0.0, 0.0, bad], 1.0, None),
            Err(DriftError::NonFinite)
        );
        assert_eq!(new(1.0, r, v, bad, None), Err(DriftError::NonFinite));
        assert_eq!(new(1.0, r, v, 1.0, Some(bad)), Err(DriftError::NonFinite));
    }
    assert_eq!(
        new(1e300, r, [1e300; 3], 1.0, None),
        Err(DriftError::NonFinite)
    );
    assert_eq!(new(0.0, r, v, 1.0, None), Err(DriftError::NonPositiveMu));
    assert_eq!(new(-1.0, r, v, 1.0, None), Err(DriftError::NonPositiveMu));
    assert_eq!(
        new(1.0, [0.0; 3], v, 1.0, None),
        Err(DriftError::ZeroRadius)
    );
    // A hyperbolic drift whose cosh overflows cannot be solved: an error, no panic.
    let far = new(1.0, r, [3.0, 0.0, 0.0], 1e308, None);
    assert!(
        matches!(
            far,
            Err(DriftError::NoConvergence { .. } | DriftError::NonFinite)
        ),
        "{far:?}"
    );
    // t = 0 is the identity; a wrong-signed guess is ignored.
    let d = KeplerDrift::new(1.0, r, v, 0.0, None).unwrap();
    assert_eq!((d.position(), d.velocity(), d.anomaly()), (r, v, 0.0));
    assert!(KeplerDrift::new(1.0, r, v, 1.0, Some(-5.0)).is_ok());
}

#[test]
fn warm_start_from_the_solution_takes_at_most_two_iterations() {
    // (exact X, X (1 + 1e-7) within a period, X (1 + 1e-7) over several periods)
    let mut worst = (0, 0, 0);
    for o in &ORBITS {
        let (r0, v0) = o.state(0.0);
        for t in times(o) {
            let cold = o.drift(t);
            let x = cold.anomaly();
            let exact = KeplerDrift::new(o.mu, r0, v0, t, Some(x)).unwrap();
            let near = KeplerDrift::new(o.mu, r0, v0, t, Some(x * (1.0 + 1e-7))).unwrap();
            let moved =
                rel(exact.position(), cold.position()).max(rel(exact.velocity(), cold.velocity()));
            assert!(moved < 4e-15, "{moved:e}");
            worst.0 = worst.0.max(exact.iterations());
            if o.e < 1.0 && t.abs() >= o.period() {
                // Reduced by whole periods: the guess is relatively worse for the remainder.
                worst.2 = worst.2.max(near.iterations());
            } else {
                worst.1 = worst.1.max(near.iterations());
            }
        }
    }
    eprintln!(
        "iterations warm-started at X: {}; at X (1 + 1e-7): {}, {} (many periods)",
        worst.0, worst.1, worst.2
    );
    assert!(worst.0 <= 1 && worst.1 <= 1 && worst.2 <= 2, "{worst:?}");
}

#[test]
fn cold_starts_converge_on_random_orbits() {
    const SPAN: f64 = 30.0;
    // Ellipses (e < 0.999), hyperbolas (e ≤ 5), parabolas and e = 1 ± 1e-3, random orientation
    // and phase, |t| up to 30 time scales (√(q³/μ)).
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut uniform = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut most, mut total, mut worst, mut most_bad) = (0, 0, 0.0_f64, 0);
    let count = 4000;
    for k in 0..count {
        let e = match k % 4 {
            0 => 0.999 * uniform(),
            1 => 1.01 + 4.0 * uniform(),
            2 => 1.0,
            _ => 1.0 + 1e-3 * (2.0 * uniform() - 1.0),
        };
        let mut o = orbit(1.0, 0.1 + uniform(), e, 6.0 * uniform() - 3.0);
        o.angles = [uniform() * PI, uniform() * 6.0, uniform() * 6.0];
        let t = (2.0 * uniform() - 1.0) * SPAN * (o.q.powi(3) / o.mu).sqrt() * uniform().powi(3);
        let d = o.drift(t);
        let (r0, v0) = o.state(0.0);
        // A poor warm start: X off by up to ±50% (hundreds of periods on long drifts).
        let guess = d.anomaly() * (0.5 + uniform());
        let bad = KeplerDrift::new(o.mu, r0, v0, t, Some(guess)).unwrap();
        most_bad = most_bad.max(bad.iterations());
        let (r, v) = o.state(t);
        worst = worst.max(rel(d.position(), r).max(rel(d.velocity(), v)));
        most = most.max(d.iterations());
        total += d.iterations();
    }
    let mean = f64::from(total) / f64::from(count);
    eprintln!(
        "cold starts: at most {most} iterations, mean {mean:.2}; error {worst:.1e}; \
         guess off by up to 50%: at most {most_bad} iterations"
    );
    assert!(
        most <= 8 && most_bad <= 12 && worst < 1e-12,
        "{most}, {most_bad}, {worst:e}"
    );
}
