//! Exact solution of the planar Kepler problem `q̈ = −μ q/|q|³` for bound (elliptic) orbits.
//!
//! The relative coordinate obeys `L = |q̇|²/2 + μ/|q|`, so `p = q̇`. [`KeplerOrbit`] converts a
//! state `(q, q̇)` at an epoch into orbital elements and evaluates the exact state at any time
//! by solving Kepler's equation with [`solve_kepler_equation`].

use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// `2π − TAU` (the part of 2π not representable in `TAU`), for careful angle reduction.
const TAU_LO: f64 = 2.449_293_598_294_706_4e-16;

/// Reasons why a state cannot be turned into an elliptic [`KeplerOrbit`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OrbitError {
    /// Specific energy `|v|²/2 − μ/|q|` is non-negative (parabolic or hyperbolic motion).
    #[error("orbit is not bound: specific energy {energy} >= 0")]
    NotBound {
        /// The specific orbital energy.
        energy: f64,
    },
    /// Zero angular momentum (radial orbit) or `|q| = 0`.
    #[error("degenerate orbit: zero angular momentum or zero radius")]
    Degenerate,
    /// An input was NaN or infinite (or the elements overflowed).
    #[error("non-finite input")]
    NonFinite,
    /// The gravitational parameter must be strictly positive.
    #[error("gravitational parameter mu must be positive")]
    NonPositiveMu,
}

/// `E − sin E` without cancellation for small `|E|`.
fn e_minus_sin(x: f64) -> f64 {
    if x.abs() >= 1.0 {
        return x - x.sin();
    }
    // x³/3! − x⁵/5! + …; terms shrink by ≥ 20× so 12 terms reach well below machine precision.
    let (x2, mut sum) = (x * x, 0.0);
    let mut term = x * x2 / 6.0;
    for k in 0..12 {
        sum += term;
        let j = f64::from(2 * k + 4);
        term *= -x2 / (j * (j + 1.0));
    }
    sum
}

/// `E − e sin E`, accurate also for `e → 1`, `E → 0`.
fn mean_from_eccentric(x: f64, e: f64) -> f64 {
    (1.0 - e) * x + e * e_minus_sin(x)
}

/// Splits `x` into `(k, r)` with `x ≈ 2πk + r`, `|r| ≲ π`, using a two-term `2π`.
fn reduce_angle(x: f64, x_lo: f64) -> (f64, f64) {
    let k = ((x + x_lo) / TAU).round();
    let r = (-k).mul_add(TAU, x) + (x_lo - k * TAU_LO);
    (k, r)
}

/// Solve Kepler's equation `E − e sin E = M` for `0 ≤ e < 1` and any finite real `M`.
///
/// `M` is reduced to `[−π, π]`, then a bracketed Newton iteration (bisection whenever a Newton
/// step leaves the bracket `[M − e, M + e]`) started at `M + 0.85 e sign(sin M)` converges to full
/// double precision in a bounded number of iterations. The `2πk` removed is added back.
/// Returns NaN (never panics) for non-finite input or `e ∉ [0, 1)`.
///
/// ```
/// use galerkin_vi::systems::kepler_orbit::solve_kepler_equation;
/// let e = solve_kepler_equation(1.0, 0.5);
/// assert!((e - 0.5 * e.sin() - 1.0).abs() < 1e-15);
/// ```
pub fn solve_kepler_equation(mean_anomaly: f64, e: f64) -> f64 {
    if !mean_anomaly.is_finite() || !(0.0..1.0).contains(&e) {
        return f64::NAN;
    }
    let (k, m) = reduce_angle(mean_anomaly, 0.0);
    k.mul_add(TAU, solve_reduced(m, e) + k * TAU_LO)
}

fn solve_reduced(m: f64, e: f64) -> f64 {
    if e == 0.0 || m == 0.0 {
        return m;
    }
    // f(E) = E − e sin E − m is increasing, f(m − e) ≤ 0 ≤ f(m + e).
    let (mut lo, mut hi) = (m - e, m + e);
    let mut x = (m + 0.85 * e * m.sin().signum()).clamp(lo, hi);
    for _ in 0..100 {
        let f = mean_from_eccentric(x, e) - m;
        if f == 0.0 {
            return x;
        }
        (lo, hi) = if f < 0.0 { (x, hi) } else { (lo, x) };
        let s = (0.5 * x).sin();
        let df = (1.0 - e) + 2.0 * e * s * s; // 1 − e cos E, cancellation-free
        let mut next = x - f / df;
        if (next - x).abs() <= 2.0 * f64::EPSILON * next.abs() {
            return next;
        }
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
            if next == lo || next == hi {
                return next;
            }
        }
        x = next;
    }
    x
}

/// An elliptic Kepler orbit `q̈ = −μ q/|q|³` in the plane, described by its elements.
///
/// Position in the perifocal frame is `a(cos E − e, s√(1−e²) sin E)` with `s = sense`, rotated
/// by `argument_of_periapsis`; the mean anomaly is `M(t) = M₀ + n (t − epoch)`.
///
/// ```
/// use galerkin_vi::systems::kepler_orbit::KeplerOrbit;
/// // a = 1, e = 0.6, periapsis on the +x axis at t = 0, period 2π.
/// let orbit = KeplerOrbit::from_state(1.0, [0.4, 0.0], [0.0, 2.0], 0.0)?;
/// assert!((orbit.semi_major_axis - 1.0).abs() < 1e-14);
/// assert!((orbit.eccentricity - 0.6).abs() < 1e-14);
/// assert!((orbit.period() - 2.0 * std::f64::consts::PI).abs() < 1e-13);
/// let (q, v) = orbit.state_at(std::f64::consts::PI); // apoapsis
/// assert!((q[0] + 1.6).abs() < 1e-14 && q[1].abs() < 1e-14);
/// assert!((v[1] + 0.5).abs() < 1e-14);
/// # Ok::<(), galerkin_vi::systems::kepler_orbit::OrbitError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KeplerOrbit {
    /// Gravitational parameter `μ > 0`.
    pub mu: f64,
    /// Semi-major axis `a = −μ/(2 energy)`.
    pub semi_major_axis: f64,
    /// Eccentricity `0 ≤ e < 1`.
    pub eccentricity: f64,
    /// Angle of periapsis from the +x axis (for circular orbits: chosen to reproduce the state).
    pub argument_of_periapsis: f64,
    /// Mean anomaly at `epoch`, in `(−π, π]`.
    pub mean_anomaly_at_epoch: f64,
    /// Mean motion `n = √(μ/a³)`.
    pub mean_motion: f64,
    /// `+1` counter-clockwise, `−1` clockwise.
    pub sense: f64,
    /// Reference time of `mean_anomaly_at_epoch`.
    pub epoch: f64,
}

impl KeplerOrbit {
    /// Orbital elements from a state `(q, q̇)` at time `epoch`.
    ///
    /// Errors, checked in this order: [`OrbitError::NonFinite`], [`OrbitError::NonPositiveMu`],
    /// [`OrbitError::Degenerate`] for `q = 0`, [`OrbitError::NotBound`] for energy ≥ 0, and
    /// [`OrbitError::Degenerate`] for (numerically) zero angular momentum.
    pub fn from_state(mu: f64, q: [f64; 2], v: [f64; 2], epoch: f64) -> Result<Self, OrbitError> {
        let all_finite = |xs: &[f64]| xs.iter().all(|x| x.is_finite());
        if !all_finite(&[mu, q[0], q[1], v[0], v[1], epoch]) {
            return Err(OrbitError::NonFinite);
        }
        if mu <= 0.0 {
            return Err(OrbitError::NonPositiveMu);
        }
        let r = q[0].hypot(q[1]);
        if r == 0.0 {
            return Err(OrbitError::Degenerate);
        }
        let v2 = v[0] * v[0] + v[1] * v[1];
        let energy = 0.5 * v2 - mu / r;
        if !energy.is_finite() {
            return Err(OrbitError::NonFinite);
        }
        if energy >= 0.0 {
            return Err(OrbitError::NotBound { energy });
        }
        let h = q[0] * v[1] - q[1] * v[0];
        if h.abs() <= 4.0 * f64::EPSILON * r * v2.sqrt() {
            return Err(OrbitError::Degenerate);
        }
        let a = -0.5 * mu / energy;
        // e cos E = 1 − r/a = r v²/μ − 1,  e sin E = (q·v)/√(μa).
        let e_cos = r * v2 / mu - 1.0;
        let e_sin = (q[0] * v[0] + q[1] * v[1]) / (mu * a).sqrt();
        let e = e_cos.hypot(e_sin);
        if e >= 1.0 {
            return Err(OrbitError::Degenerate);
        }
        let ecc_anomaly = e_sin.atan2(e_cos);
        let mut orbit = Self {
            mu,
            semi_major_axis: a,
            eccentricity: e,
            argument_of_periapsis: 0.0,
            mean_anomaly_at_epoch: mean_from_eccentric(ecc_anomaly, e),
            mean_motion: (mu / a).sqrt() / a,
            sense: h.signum(),
            epoch,
        };
        // Periapsis direction such that the perifocal position rotates onto q exactly.
        let (p, _) = orbit.perifocal(ecc_anomaly);
        let w = q[1].atan2(q[0]) - p[1].atan2(p[0]);
        orbit.argument_of_periapsis = w - TAU * (w / TAU).round(); // exact when |w| ≤ π
        match all_finite(&[a, e, orbit.mean_anomaly_at_epoch, orbit.mean_motion]) {
            true => Ok(orbit),
            false => Err(OrbitError::NonFinite),
        }
    }

    /// Position and velocity in the perifocal frame at eccentric anomaly `ecc`.
    fn perifocal(&self, ecc: f64) -> ([f64; 2], [f64; 2]) {
        let (a, e, s) = (self.semi_major_axis, self.eccentricity, self.sense);
        let one_m_e = 1.0 - e;
        let beta = (one_m_e * (1.0 + e)).sqrt();
        let (sin_e, cos_e) = ecc.sin_cos();
        let half = (0.5 * ecc).sin();
        let one_m_cos = 2.0 * half * half;
        let denom = one_m_e + e * one_m_cos; // 1 − e cos E
        let an = a * self.mean_motion;
        (
            [a * (one_m_e - one_m_cos), s * a * beta * sin_e],
            [-an * sin_e / denom, s * an * beta * cos_e / denom],
        )
    }

    /// Mean anomaly at time `t`, reduced to about `[−π, π]` (product and `2π` carried in
    /// extended precision, so accuracy is limited only by the representation of `t − epoch`).
    pub fn mean_anomaly_at(&self, t: f64) -> f64 {
        let dt = t - self.epoch;
        let p = self.mean_motion * dt;
        let p_err = self.mean_motion.mul_add(dt, -p);
        reduce_angle(p, p_err + self.mean_anomaly_at_epoch).1
    }

    /// Exact position and velocity at time `t` (NaN for non-finite `t`).
    pub fn state_at(&self, t: f64) -> ([f64; 2], [f64; 2]) {
        let ecc = solve_kepler_equation(self.mean_anomaly_at(t), self.eccentricity);
        let (p, u) = self.perifocal(ecc);
        let (sw, cw) = self.argument_of_periapsis.sin_cos();
        let rot = |x: [f64; 2]| [cw * x[0] - sw * x[1], sw * x[0] + cw * x[1]];
        (rot(p), rot(u))
    }

    /// Orbital period `2π/n`.
    pub fn period(&self) -> f64 {
        TAU / self.mean_motion
    }

    /// Specific energy `−μ/(2a)`.
    pub fn energy(&self) -> f64 {
        -0.5 * self.mu / self.semi_major_axis
    }

    /// Signed angular momentum `q_x v_y − q_y v_x = sense·√(μ a (1 − e²))`.
    pub fn angular_momentum(&self) -> f64 {
        let e = self.eccentricity;
        self.sense * (self.mu * self.semi_major_axis * (1.0 - e) * (1.0 + e)).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{RngExt, SeedableRng};
    use std::f64::consts::PI;

    fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
        (a[0] - b[0]).hypot(a[1] - b[1])
    }
    fn norm(a: [f64; 2]) -> f64 {
        a[0].hypot(a[1])
    }
    fn invariants(mu: f64, q: [f64; 2], v: [f64; 2]) -> (f64, f64, f64) {
        let (t, u) = (0.5 * (v[0] * v[0] + v[1] * v[1]), mu / norm(q));
        (t - u, t + u, q[0] * v[1] - q[1] * v[0])
    }

    /// Test states `(mu, q, v, epoch)`: special cases plus random bound states.
    fn states() -> Vec<(f64, [f64; 2], [f64; 2], f64)> {
        let mut out = vec![
            (1.0, [0.4, 0.0], [0.0, 2.0], 0.0),
            (1.0, [1.0, 0.0], [0.0, 1.0], 0.0), // circular ccw
            (2.0, [0.0, 3.0], [(2.0f64 / 3.0).sqrt(), 0.0], -7.5), // circular cw
            (1.0, [0.6, -0.8], [0.8 * (1.0 + 1e-12), 0.6], 3.0), // near circular
            (1.0, [0.01, 0.0], [0.0, -(1.99f64 / 0.01).sqrt()], 0.0), // e = 0.99 periapsis, cw
            (1.0, [-1.99, 0.0], [0.0, (0.01f64 / 1.99).sqrt()], 1e3), // e = 0.99 apoapsis
        ];
        let mut rng = StdRng::seed_from_u64(0x9E37_79B9_7F4A_7C15);
        let mut i = 0;
        while out.len() < 300 {
            i += 1;
            let mu = 0.2 + 5.0 * rng.random::<f64>();
            let (r, th) = (0.3 + 3.0 * rng.random::<f64>(), TAU * rng.random::<f64>());
            let speed = (0.02 + 0.97 * rng.random::<f64>()) * (2.0 * mu / r).sqrt();
            let dir =
                th + (0.05 + 0.9 * rng.random::<f64>()) * PI * if i % 2 == 0 { 1.0 } else { -1.0 };
            let epoch = 200.0 * (rng.random::<f64>() - 0.5);
            let (q, v) = (
                [r * th.cos(), r * th.sin()],
                [speed * dir.cos(), speed * dir.sin()],
            );
            // Keep e ≤ 0.99: beyond that, f64 rounding of e alone limits accuracy (~ε/(1−e)).
            if KeplerOrbit::from_state(mu, q, v, epoch).is_ok_and(|o| o.eccentricity <= 0.99) {
                out.push((mu, q, v, epoch));
            }
        }
        out
    }

    #[test]
    fn kepler_equation_reference_values() {
        // Meeus, Astronomical Algorithms, Ex. 30.a: e = 0.1, M = 5° → E = 5.554589°.
        let meeus = solve_kepler_equation(5f64.to_radians(), 0.1).to_degrees();
        assert!((meeus - 5.554_589).abs() < 1e-6);
        // 40-digit references (mpmath findroot).
        let refs = [
            (0.5, 0.1, 0.552_479_986_906_570_3),
            (1.0, 0.5, 1.498_701_133_517_848_3),
            (2.0, 0.9, 2.522_365_434_000_245),
            (0.01, 0.99, 0.342_270_316_491_775_1),
            (3.0, 0.99, 3.070_410_669_117_501_7),
            (-7.0, 0.3, -7.246_290_562_569_086),
        ];
        for (m, e, want) in refs {
            assert!((solve_kepler_equation(m, e) - want).abs() < 4e-16 * want.abs().max(1.0));
        }
        // Independent bisection on the unreduced equation.
        for &e in &[0.0, 0.3, 0.7, 0.99] {
            for i in -40..=40 {
                let m = 0.37 * f64::from(i);
                let (mut lo, mut hi) = (m - e - 1e-9, m + e + 1e-9);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    (lo, hi) = if mid - e * mid.sin() < m {
                        (mid, hi)
                    } else {
                        (lo, mid)
                    };
                }
                let got = solve_kepler_equation(m, e);
                let cond = 1.0 / (1.0 - e * got.cos());
                assert!(
                    (got - lo).abs() <= 2e-15 * m.abs().max(1.0) * cond,
                    "{m} {e}"
                );
            }
        }
        assert!(solve_kepler_equation(f64::NAN, 0.1).is_nan());
        assert!(solve_kepler_equation(1.0, 1.0).is_nan());
        assert!(solve_kepler_equation(f64::INFINITY, 0.5).is_nan());
    }

    #[test]
    fn kepler_equation_residual_grid() {
        let mut worst = 0.0f64;
        let es = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.99];
        for e in es {
            for im in 0..=4000 {
                let m = -20.0 + 0.01 * f64::from(im);
                let big_e = solve_kepler_equation(m, e);
                let res = (big_e - e * big_e.sin() - m).abs() / m.abs().max(1.0);
                worst = worst.max(res);
                assert!(res <= 1e-15, "e={e} M={m} residual={res}");
            }
        }
        eprintln!("worst scaled Kepler residual {worst:e}");
    }

    #[test]
    fn normalisation_case_closed_form() {
        let orbit = KeplerOrbit::from_state(1.0, [0.4, 0.0], [0.0, 2.0], 0.0).unwrap();
        assert!((orbit.period() - TAU).abs() < 1e-14);
        assert!(orbit.argument_of_periapsis.abs() < 1e-15 && orbit.sense == 1.0);
        let (e, b) = (0.6, 0.8);
        let mut worst = 0.0f64;
        for i in -500..=500 {
            let t = 0.1 * f64::from(i) + 0.013;
            let ecc = solve_kepler_equation(t, e);
            let d = 1.0 - e * ecc.cos();
            let q = [ecc.cos() - e, b * ecc.sin()];
            let v = [-ecc.sin() / d, b * ecc.cos() / d];
            let (qs, vs) = orbit.state_at(t);
            worst = worst.max(dist(q, qs)).max(dist(v, vs));
        }
        eprintln!("normalisation case worst deviation {worst:e}");
        assert!(worst < 1e-13);
    }

    #[test]
    fn reproduction_invariants_ode_periodicity() {
        let [mut rep, mut de, mut dh, mut fd, mut per] = [0.0f64; 5];
        for (mu, q0, v0, epoch) in states() {
            let orbit = KeplerOrbit::from_state(mu, q0, v0, epoch).unwrap();
            let (e0, scale, h0) = invariants(mu, q0, v0);
            let (q1, v1) = orbit.state_at(epoch);
            rep = rep
                .max(dist(q0, q1) / norm(q0))
                .max(dist(v0, v1) / norm(v0));
            assert_eq!(orbit.sense, h0.signum());
            approx::assert_relative_eq!(orbit.angular_momentum(), h0, max_relative = 1e-14);
            let p = orbit.period();
            assert!((orbit.energy() - e0).abs() < 1e-14 * scale);
            for k in 0..25 {
                let t = epoch + p * (0.37 * f64::from(k) - 3.0);
                let (q, v) = orbit.state_at(t);
                let (en, _, h) = invariants(mu, q, v);
                de = de.max((en - e0).abs() / scale);
                dh = dh.max((h - h0).abs() / h0.abs());
                // Central differences: dq/dt = v and dv/dt = −μ q/|q|³ (O(dt²) accurate).
                let dt = 1e-4 * p;
                let (qp, vp) = orbit.state_at(t + dt);
                let (qm, vm) = orbit.state_at(t - dt);
                let r3 = norm(q).powi(3);
                let acc = [-mu * q[0] / r3, -mu * q[1] / r3];
                let fd_a = [(vp[0] - vm[0]) / (2.0 * dt), (vp[1] - vm[1]) / (2.0 * dt)];
                let fd_v = [(qp[0] - qm[0]) / (2.0 * dt), (qp[1] - qm[1]) / (2.0 * dt)];
                let tol = (dt / orbit.period()).powi(2) * 1e2 / (1.0 - orbit.eccentricity).powi(3);
                fd = fd
                    .max(dist(acc, fd_a) / norm(acc) / tol)
                    .max(dist(v, fd_v) / norm(v) / tol);
                let (qn, vn) = orbit.state_at(t + p);
                per = per.max(dist(q, qn) / norm(q)).max(dist(v, vn) / norm(v));
            }
        }
        eprintln!("reproduction {rep:e} energy {de:e} ang mom {dh:e} fd/tol {fd:e} period {per:e}");
        assert!(rep < 1e-14 && de < 1e-13 && dh < 1e-13 && fd < 1.0 && per < 1e-11);
    }

    #[test]
    fn large_times() {
        let orbit = KeplerOrbit::from_state(1.0, [0.4, 0.0], [0.0, 2.0], 0.0).unwrap();
        // n = 1 exactly, so M(t) = t; check against the 2π-periodic closed form at t = 2π·10⁶ + s.
        let t = 1e6 * TAU;
        let (q, v) = orbit.state_at(t);
        // t − 2π·10⁶ evaluated exactly (to rounding of the small result).
        let s = -(1e6f64).mul_add(TAU, -t) - 1e6 * TAU_LO;
        let (qr, vr) = orbit.state_at(s);
        assert!(dist(q, qr) < 1e-14 && dist(v, vr) < 1e-14);
        for t in [1e7, 3.3e8, -4.1e9] {
            let (q, v) = orbit.state_at(t);
            let (en, _, h) = invariants(1.0, q, v);
            assert!((en + 0.5).abs() < 1e-14 && (h - 0.8).abs() < 1e-14);
        }
    }

    #[test]
    fn error_cases() {
        use OrbitError::*;
        let (x, y, nan, inf) = ([1.0, 0.0], [0.0, 1.0], f64::NAN, f64::INFINITY);
        let cases = [
            (1.0, x, [0.0, 2.0], 0.0, NotBound { energy: 1.0 }), // hyperbolic
            (2.0, x, [0.0, 2.0], 0.0, NotBound { energy: 0.0 }), // parabolic
            (1.0, [1.0, 1.0], [0.3, 0.3], 0.0, Degenerate),      // radial
            (1.0, x, [0.0, 0.0], 0.0, Degenerate),               // at rest
            (1.0, [0.0, 0.0], y, 0.0, Degenerate),               // r = 0
            (1.0, [nan, 0.0], y, 0.0, NonFinite),
            (1.0, x, y, inf, NonFinite),
            (nan, x, y, 0.0, NonFinite),
            (0.0, x, y, 0.0, NonPositiveMu),
            (-1.0, x, y, 0.0, NonPositiveMu),
        ];
        for (mu, q, v, epoch, err) in cases {
            assert_eq!(KeplerOrbit::from_state(mu, q, v, epoch), Err(err));
        }
        let orbit = KeplerOrbit::from_state(1.0, x, y, 0.0).unwrap();
        assert!(orbit.state_at(nan).0[0].is_nan() && orbit.state_at(inf).1[1].is_nan());
    }
}
