//! The exact Kepler flow in universal variables, with its tangent map.
//!
//! One body in the two-body problem `r̈ = −μ r/|r|³` (`μ > 0`) is carried from `(r0, v0)` over a
//! time `t` of either sign, on elliptic, parabolic and hyperbolic orbits alike. This is the drift
//! of the interaction-picture integrator of the [parent module](super), made once per planet and
//! stage, so it works on `[f64; 3]`, allocates nothing and warm-starts its solve.
//!
//! # Universal variables (Danby, *Fundamentals of Celestial Mechanics*, 2nd ed., §6.9)
//!
//! With `r0 = |r0|`, `η0 = r0·v0`, `β = 2μ/r0 − |v0|²` (−2 × the energy) and the universal
//! anomaly `X` defined by `dt/dX = |r|`, the functions
//!
//! ```text
//! G_k(X, β) = Σ_{j≥0} (−β)^j X^{k+2j}/(k+2j)! = X^k c_k(βX²),   c_k(z) = 1/k! − z c_{k+2}(z)
//! ```
//!
//! (`c_k` the Stumpff functions) give Kepler's equation, the radius and the Lagrange coefficients
//!
//! ```text
//! t = r0 G1 + η0 G2 + μ G3,                   r = |r(t)| = r0 G0 + η0 G1 + μ G2 = dt/dX,
//! f = 1 − μ G2/r0,   g = t − μ G3,            ḟ = −μ G1/(r r0),   ġ = 1 − μ G2/r,
//! r(t) = f r0 + g v0,                         v(t) = ḟ r0 + ġ v0.
//! ```
//!
//! The derivatives `∂G_k/∂X = G_{k−1}` (`∂G0/∂X = −β G1`) and
//! `∂G_k/∂β = −½ (X G_{k+1} − k G_{k+2})` give Newton-type solves and the tangent map.
//!
//! # Tangent map (the variational equations of WHFast: Rein & Tamayo 2015, 2016)
//!
//! At fixed `t`, a variation `(δr0, δv0)` changes `δr0n = r0·δr0/r0`, `δη = δr0·v0 + r0·δv0`,
//! `δβ = −2μ δr0n/r0² − 2 v0·δv0`; Kepler's equation then fixes
//! `δX = −(δr0n G1 + δη G2 + (r0 ∂βG1 + η0 ∂βG2 + μ ∂βG3) δβ)/r`, so that
//! `δG_k = (∂G_k/∂X) δX + (∂G_k/∂β) δβ`, `δr = δr0n G0 + r0 δG0 + δη G1 + η0 δG1 + μ δG2`, and
//! the product rule on `f r0 + g v0`, `ḟ r0 + ġ v0` gives `(δr(t), δv(t))`.
//!
//! The inverse map is the tangent of the time-reversed drift, from `(r(t), v(t))` over `−t`:
//! its anomaly is `−X`, `G_k(−X, β) = (−1)^k G_k(X, β)` and `β` is unchanged (energy is
//! conserved), so it needs no second Kepler solve.

use std::f64::consts::TAU;

use super::stumpff::{beta_derivatives, g_functions};

/// The solve has converged when the correction is at most this relative to `X`.
const X_TOL: f64 = 1e-15;

/// A correction that no longer shrinks while below this (relative to `X`) is round-off.
const X_FLOOR: f64 = 1e-10;

/// Iteration cap of the Kepler solve.
const MAX_ITERATIONS: u32 = 50;

/// Why a drift failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DriftError {
    /// An input (μ, a component of the state, the time or the anomaly guess) is NaN or infinite,
    /// or the end state overflowed.
    #[error("non-finite input to or result of a Kepler drift")]
    NonFinite,
    /// The gravitational parameter μ is zero or negative.
    #[error("Kepler drift needs a positive gravitational parameter mu")]
    NonPositiveMu,
    /// The drift starts at the attracting centre (`r0 = 0`), or a radial orbit reaches it.
    #[error("Kepler drift starts at or reaches zero radius")]
    ZeroRadius,
    /// Kepler's equation was not solved within the iteration cap.
    #[error("Kepler solver did not converge over t = {time} (residual {residual})")]
    NoConvergence {
        /// The drift's time.
        time: f64,
        /// The last residual of Kepler's equation, in time units.
        residual: f64,
    },
}

/// One body's Kepler drift over time t, keeping what the tangent map needs.
///
/// [`KeplerDrift::new`] solves Kepler's equation once; [`position`](KeplerDrift::position) and
/// [`velocity`](KeplerDrift::velocity) give the end state, [`push_forward`](KeplerDrift::push_forward)
/// and [`pull_back`](KeplerDrift::pull_back) the tangent map and its inverse.
#[derive(Debug, Clone, Copy)]
pub struct KeplerDrift {
    /// The drift from its start `(r0, v0)` over `t`.
    forward: Leg,
    /// End position `r(t)`.
    r1: [f64; 3],
    /// End velocity `v(t)`.
    v1: [f64; 3],
    /// `η1 = r(t)·v(t)`.
    eta1: f64,
    /// Universal anomaly `X` of the whole drift (not reduced by periods).
    x: f64,
    /// Kepler-solve iterations (G-function evaluations) taken.
    #[cfg(test)]
    iterations: u32,
}

/// One direction of a drift, seen from its start: what the tangent map needs.
#[derive(Debug, Clone, Copy)]
struct Leg {
    mu: f64,
    beta: f64,
    /// `G0, G1, G2` at the leg's anomaly.
    gs: [f64; 3],
    /// `∂G0/∂β … ∂G3/∂β`.
    dgs: [f64; 4],
    /// Start position, velocity, `η = r·v`.
    ra: [f64; 3],
    va: [f64; 3],
    eta_a: f64,
    /// Start and end radius, and their reciprocals.
    ra_n: f64,
    rb_n: f64,
    inv_ra: f64,
    inv_rb: f64,
    /// Lagrange coefficients `f, g, ḟ, ġ`.
    fg: [f64; 4],
}

impl Leg {
    /// The same drift run backwards, from its end over `−t` with anomaly `−X`:
    /// `G_k → (−1)^k G_k`, `(f, g, ḟ, ġ) → (ġ, −g, −ḟ, f)`.
    fn reversed(&self, rb: [f64; 3], vb: [f64; 3], eta_b: f64) -> Leg {
        let [g0, g1, g2] = self.gs;
        let [b0, b1, b2, b3] = self.dgs;
        let [f, g, fd, gd] = self.fg;
        Leg {
            gs: [g0, -g1, g2],
            dgs: [b0, -b1, b2, -b3],
            ra: rb,
            va: vb,
            eta_a: eta_b,
            ra_n: self.rb_n,
            rb_n: self.ra_n,
            inv_ra: self.inv_rb,
            inv_rb: self.inv_ra,
            fg: [gd, -g, -fd, f],
            ..*self
        }
    }

    /// `Dφ(ra, va)·(δr, δv)`: the differentiated Kepler equation for `δX`, then the product
    /// rule on `r = f ra + g va`, `v = ḟ ra + ġ va` (module docs).
    fn tangent(&self, dr: [f64; 3], dv: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        let (mu, beta, ra, va, eta_a) = (self.mu, self.beta, self.ra, self.va, self.eta_a);
        let (ra_n, inv_ra, inv_rb) = (self.ra_n, self.inv_ra, self.inv_rb);
        let [g0, g1, g2] = self.gs;
        let [b0, b1, b2, b3] = self.dgs;
        let [f, g, fd, gd] = self.fg;
        let d_ra = dot(ra, dr) * inv_ra;
        let d_eta = dot(dr, va) + dot(ra, dv);
        let d_beta = -2.0 * (mu * d_ra * inv_ra * inv_ra + dot(va, dv));
        let t_beta = ra_n * b1 + eta_a * b2 + mu * b3; // ∂t/∂β at fixed X
        let dx = -(d_ra * g1 + d_eta * g2 + t_beta * d_beta) * inv_rb;
        let dg0 = -beta * g1 * dx + b0 * d_beta;
        let dg1 = g0 * dx + b1 * d_beta;
        let dg2 = g1 * dx + b2 * d_beta;
        let dg3 = g2 * dx + b3 * d_beta;
        let d_rb = d_ra * g0 + ra_n * dg0 + d_eta * g1 + eta_a * dg1 + mu * dg2;
        let (d_ln_ra, d_ln_rb) = (d_ra * inv_ra, d_rb * inv_rb);
        let df = -mu * (dg2 - g2 * d_ln_ra) * inv_ra;
        let dg = -mu * dg3;
        let dfd = -mu * (dg1 - g1 * (d_ln_rb + d_ln_ra)) * (inv_rb * inv_ra);
        let dgd = -mu * (dg2 - g2 * d_ln_rb) * inv_rb;
        let mut out_r = [0.0; 3];
        let mut out_v = [0.0; 3];
        for i in 0..3 {
            out_r[i] = f * dr[i] + g * dv[i] + df * ra[i] + dg * va[i];
            out_v[i] = fd * dr[i] + gd * dv[i] + dfd * ra[i] + dgd * va[i];
        }
        (out_r, out_v)
    }
}

impl KeplerDrift {
    /// Exact flow of r̈ = −μ r/|r|³ over time t (any sign, elliptic, parabolic or hyperbolic)
    /// from (r0, v0).
    ///
    /// `anomaly_guess` is a previous universal anomaly `X` for (nearly) the same drift, e.g.
    /// [`anomaly`](Self::anomaly) of the last one; `None` uses a cold starter (a Taylor series in
    /// `t` for short drifts, otherwise Danby's `E ≈ M + 0.85 e` on the ellipse, its hyperbolic
    /// analogue, or Barker's equation near a parabola). Elliptic drifts longer than a period are
    /// first reduced by whole periods. Kepler's equation `F(X) = 0` is solved to full double
    /// precision by Laguerre–Conway iteration (Conway 1986), Halley's method near the root
    /// (`F' = r`, `F'' = η0 G0 + ζ0 G1`, `ζ0 = μ − β r0`), safeguarded by bisection on the
    /// bracket that `F' > 0` keeps. A guess within about 1e-7 (relative) of the solution takes one
    /// G-function evaluation (on drifts shorter than a period).
    ///
    /// # Errors
    /// [`DriftError::NonFinite`] for a NaN or infinite input (including the guess) or an
    /// overflowing end state, [`DriftError::NonPositiveMu`] for `μ ≤ 0`,
    /// [`DriftError::ZeroRadius`] for `r0 = 0` and [`DriftError::NoConvergence`] if the solve
    /// fails (e.g. a hyperbolic drift so long that its `cosh` overflows).
    pub fn new(
        mu: f64,
        r0: [f64; 3],
        v0: [f64; 3],
        t: f64,
        anomaly_guess: Option<f64>,
    ) -> Result<Self, DriftError> {
        let finite = r0.iter().chain(&v0).all(|c| c.is_finite());
        if !(finite && mu.is_finite() && t.is_finite() && anomaly_guess.is_none_or(f64::is_finite))
        {
            return Err(DriftError::NonFinite);
        }
        if mu <= 0.0 {
            return Err(DriftError::NonPositiveMu);
        }
        let (r0_sq, v0_sq) = (dot(r0, r0), dot(v0, v0));
        if !(r0_sq.is_finite() && v0_sq.is_finite()) {
            return Err(DriftError::NonFinite);
        }
        if r0_sq == 0.0 {
            return Err(DriftError::ZeroRadius);
        }
        let r0n = r0_sq.sqrt();
        let inv_r0 = 1.0 / r0n;
        let eta0 = dot(r0, v0);
        let beta = 2.0 * mu * inv_r0 - v0_sq;
        let conic = Conic {
            mu,
            r0n,
            eta0,
            beta,
            zeta0: mu - beta * r0n,
        };

        // Elliptic: over a period P = 2πμ/β^{3/2} the anomaly grows by X_P = 2π/√β. Drop whole
        // periods from drifts longer than one; then |t| < P bounds |X| < X_P (with a margin).
        // This bound (or the hyperbolic one) keeps the solve's bisection fallback short.
        let (mut t_red, mut x_shift, mut x_max) = (t, 0.0, f64::INFINITY);
        if beta > 0.0 {
            let x_period = TAU / beta.sqrt();
            let period = x_period * mu / beta;
            if t.abs() >= period {
                let n = (t / period).trunc();
                t_red = (-n).mul_add(period, t);
                x_shift = n * x_period;
            }
            x_max = 1.01 * x_period;
        } else if beta < 0.0 {
            // exp(√−β |X|/2) overflows beyond √−β |X| ≈ 1419: no solvable drift goes further.
            x_max = 1420.0 / (-beta).sqrt();
        }
        let x0 = match anomaly_guess.map(|guess| guess - x_shift) {
            Some(guess) if guess * t_red > 0.0 && guess.abs() < x_max => guess,
            _ => conic.starter(t_red),
        };
        let sol = conic.solve(t_red, x0, x_max)?;

        // End state from the reduced drift (G0, G1, G2 are periodic in X; g = t − μ G3 is too).
        let [g0, g1, g2, g3, g4, g5] = sol.gs;
        let (r1n, inv_r1) = (sol.r, 1.0 / sol.r);
        let f_m1 = -mu * g2 * inv_r0;
        let g = t_red - mu * g3;
        let fd = -mu * g1 * (inv_r1 * inv_r0);
        let gd_m1 = -mu * g2 * inv_r1;
        let mut r1 = [0.0; 3];
        let mut v1 = [0.0; 3];
        for i in 0..3 {
            r1[i] = r0[i] + (f_m1 * r0[i] + g * v0[i]);
            v1[i] = v0[i] + (fd * r0[i] + gd_m1 * v0[i]);
        }
        if !r1.iter().chain(&v1).all(|c| c.is_finite()) {
            return Err(DriftError::NonFinite);
        }
        if r1n <= 0.0 {
            return Err(DriftError::ZeroRadius);
        }

        // The whole anomaly X = X' + h for the tangent map: G3, G4, G5 grow secularly,
        // G_{k+2} = (X^k/k! − G_k)/β, so G3 += h/β, G4 += h(2X' + h)/(2β),
        // G5 += (h(X² + X X' + X'²)/6 − h/β)/β (no cancellation: h is a whole period or more).
        let (xr, h) = (sol.x, x_shift);
        let x = xr + h;
        let gs = if h == 0.0 {
            sol.gs
        } else {
            [
                g0,
                g1,
                g2,
                g3 + h / beta,
                g4 + h * (2.0 * xr + h) / (2.0 * beta),
                g5 + (h * (x * x + x * xr + xr * xr) / 6.0 - h / beta) / beta,
            ]
        };
        let forward = Leg {
            mu,
            beta,
            gs: [gs[0], gs[1], gs[2]],
            dgs: beta_derivatives(beta, x, &gs),
            ra: r0,
            va: v0,
            eta_a: eta0,
            ra_n: r0n,
            rb_n: r1n,
            inv_ra: inv_r0,
            inv_rb: inv_r1,
            fg: [1.0 + f_m1, g, fd, 1.0 + gd_m1],
        };
        Ok(KeplerDrift {
            forward,
            r1,
            v1,
            eta1: dot(r1, v1),
            x,
            #[cfg(test)]
            iterations: sol.iterations,
        })
    }

    /// The end position `r(t)`.
    pub fn position(&self) -> [f64; 3] {
        self.r1
    }

    /// The end velocity `v(t)`.
    pub fn velocity(&self) -> [f64; 3] {
        self.v1
    }

    /// The universal anomaly X of the solution (for warm starts).
    pub fn anomaly(&self) -> f64 {
        self.x
    }

    /// Dφ_t(r0, v0)·(δr0, δv0): push a tangent vector at the start to the end.
    pub fn push_forward(&self, dr: [f64; 3], dv: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        self.forward.tangent(dr, dv)
    }

    /// Dφ_{−t}(r1, v1)·(δr1, δv1) = (Dφ_t(r0, v0))⁻¹·(δr1, δv1): pull a tangent vector at the
    /// end back to the start.
    ///
    /// This is the tangent of the time-reversed drift from the end state, whose anomaly is `−X`
    /// with the same `β` (module docs): no new Kepler solve.
    pub fn pull_back(&self, dr: [f64; 3], dv: [f64; 3]) -> ([f64; 3], [f64; 3]) {
        self.forward
            .reversed(self.r1, self.v1, self.eta1)
            .tangent(dr, dv)
    }

    /// Kepler-solve iterations (G-function evaluations) the drift took.
    #[cfg(test)]
    pub(crate) fn iterations(&self) -> u32 {
        self.iterations
    }
}

/// Kepler's equation `F(X) = r0 G1 + η0 G2 + μ G3 − t = 0` of one start state.
struct Conic {
    mu: f64,
    r0n: f64,
    eta0: f64,
    beta: f64,
    /// `ζ0 = μ − β r0`, so that `F'' = dr/dX = η0 G0 + ζ0 G1`.
    zeta0: f64,
}

/// A solution of Kepler's equation: anomaly, `G0 … G5` there, radius `r = F'(X)`.
struct Solved {
    x: f64,
    gs: [f64; 6],
    r: f64,
    #[cfg(test)]
    iterations: u32,
}

impl Conic {
    /// A cold start for `F(X) = 0`.
    ///
    /// Short drifts: the Taylor series `X ≈ t/r0 − η0 t²/(2 r0³)` (`dX/dt = 1/r`). Otherwise the
    /// conic's anomaly: on an ellipse (`n = β^{3/2}/μ`, `e cos E0 = ζ0/μ`, `e sin E0 = η0 √β/μ`)
    /// Danby's starter `E ≈ M + 0.85 e sign(sin M)` for `M = E0 − e sin E0 + n t`, and
    /// `X = (E − E0)/√β`; on a hyperbola (`e cosh H0 = ζ0/μ`, `e sinh H0 = η0 √(−β)/μ`)
    /// `H ≈ asinh(N/e)` for `N = e sinh H0 − H0 + n t`; near a parabola (`|β| r0/μ < 1e-5`,
    /// where `M0` would cancel) Barker's equation `D + D³/3 = M` solved exactly (`D = tan(ν/2)`,
    /// `q = h²/(2μ)`, `η = D √(2μq)`, `dt = √(2q³/μ) (1 + D²) dD`, `X = √(2q/μ) (D − D0)`).
    fn starter(&self, t: f64) -> f64 {
        let (mu, r0n, eta0, beta, zeta0) = (self.mu, self.r0n, self.eta0, self.beta, self.zeta0);
        let tr = t / r0n;
        let second = 0.5 * tr * eta0 / r0n;
        let series = tr * (1.0 - second);
        let v0_sq = 2.0 * mu / r0n - beta;
        if tr * tr * (mu / r0n + v0_sq.abs()) <= 1e-2 && second.abs() <= 0.1 {
            return series;
        }
        let conic = if (beta * r0n / mu).abs() < 1e-5 {
            let q = 0.5 * (r0n * r0n * v0_sq - eta0 * eta0) / mu;
            let k = (2.0 * q / mu).sqrt();
            let d0 = eta0 / (mu * k);
            let m = d0 + d0 * d0 * d0 / 3.0 + t / (q * k);
            let w = (1.5 * m.abs() + (1.0 + 2.25 * m * m).sqrt()).cbrt();
            k * (m.signum() * (w - 1.0 / w) - d0)
        } else if beta > 0.0 {
            let s = beta.sqrt();
            let (ec, es) = (zeta0 / mu, eta0 * s / mu);
            let e0 = es.atan2(ec);
            let m = e0 - es + s * beta / mu * t;
            let e = m + 0.85 * ec.hypot(es) * m.sin().signum();
            (e - e0) / s
        } else {
            let s = (-beta).sqrt();
            let (ec, es) = (zeta0 / mu, eta0 * s / mu);
            let q = es / ec; // tanh H0
            let h0 = q.atanh();
            let ecc = (ec * ((1.0 - q) * (1.0 + q)).sqrt()).max(1.0);
            let n = es - h0 - s * beta / mu * t;
            ((n / ecc).asinh() - h0) / s
        };
        if conic.is_finite() && conic * t > 0.0 {
            conic
        } else {
            series
        }
    }

    /// Solves `F(X) = t` from `x`, keeping the bracket `lo < X < hi` that `F' = r > 0`,
    /// `F(0) = −t` and `|X| < x_max` give; a Laguerre step leaving it (or a non-finite one) is
    /// a bisection.
    #[cfg_attr(not(test), allow(unused_variables))]
    fn solve(&self, t: f64, mut x: f64, x_max: f64) -> Result<Solved, DriftError> {
        let (mu, r0n, eta0, beta, zeta0) = (self.mu, self.r0n, self.eta0, self.beta, self.zeta0);
        if t == 0.0 {
            let gs = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
            #[rustfmt::skip]
            return Ok(Solved { x: 0.0, gs, r: r0n, #[cfg(test)] iterations: 0 });
        }
        let (mut lo, mut hi) = if t > 0.0 { (0.0, x_max) } else { (-x_max, 0.0) };
        if !(x > lo && x < hi) {
            x = 0.5 * (lo + hi);
            if !x.is_finite() {
                x = t / r0n;
            }
        }
        let (mut last_step, mut residual) = (f64::INFINITY, f64::NAN);
        for iteration in 1..=MAX_ITERATIONS {
            let gs = g_functions(beta, x);
            let f = r0n * gs[1] + eta0 * gs[2] + mu * gs[3] - t;
            let fp = r0n * gs[0] + eta0 * gs[1] + mu * gs[2];
            if !(f.is_finite() && fp.is_finite()) {
                // cosh/sinh overflowed far out on a hyperbola: the root lies nearer to 0.
                (lo, hi) = if x > 0.0 {
                    (lo, hi.min(x))
                } else {
                    (lo.max(x), hi)
                };
                (x, last_step) = (0.5 * (lo + hi), f64::INFINITY);
                if !x.is_finite() {
                    break;
                }
                continue;
            }
            residual = f;
            (lo, hi) = if f < 0.0 {
                (lo.max(x), hi)
            } else {
                (lo, hi.min(x))
            };
            // Laguerre–Conway with n = 5: dX = −5F/(F' + √|16F'² − 20 F F''|); near the root
            // (|F F''| ≪ F'²) it is Halley's dX = −2F F'/(2F'² − F F''), without the root.
            let fpp = eta0 * gs[0] + zeta0 * gs[1];
            let (ff, fp2) = (f * fpp, fp * fp);
            let halley = 64.0 * ff.abs() <= fp2;
            let dx = if halley {
                -2.0 * f * fp / (2.0 * fp2 - ff)
            } else {
                -5.0 * f / (fp + (16.0 * fp2 - 20.0 * ff).abs().sqrt())
            };
            let step = dx.abs();
            // F's own round-off: below it a correction is noise.
            let noise = 4.0
                * f64::EPSILON
                * (t.abs() + (r0n * gs[1]).abs() + (eta0 * gs[2]).abs() + (mu * gs[3]).abs());
            // A small Halley step is the last: it leaves an error ≈ K dX³ with
            // K = (F''/F')²/4 − F'''/(6F'), F''' = ζ0 G0 − β η0 G1, and the second-order Taylor
            // update of the G's below leaves O((dX/X)³, (√|β| dX)³).
            let last = halley && dx * dx * (1.0 / (x * x)).max(beta.abs()) <= 1e-12 && {
                let fppp = zeta0 * gs[0] - beta * eta0 * gs[1];
                let k = 0.25 * (fpp / fp).powi(2) - fppp / (6.0 * fp);
                (k * dx * dx * dx).abs() <= 1e-16 * x.abs()
            };
            let converged = last
                || step <= X_TOL * x.abs()
                || f.abs() <= noise
                || (step >= last_step && step <= X_FLOOR * x.abs());
            if converged && dx.is_finite() {
                // Move the G's to X + dX by Taylor's series to second order
                // (∂G0/∂X = −β G1, ∂G_k/∂X = G_{k−1}).
                let [g0, g1, g2, g3, g4, g5] = gs;
                let h = 0.5 * dx * dx;
                let gs = [
                    g0 - beta * (g1 * dx + g0 * h),
                    g1 + g0 * dx - beta * g1 * h,
                    g2 + g1 * dx + g0 * h,
                    g3 + g2 * dx + g1 * h,
                    g4 + g3 * dx + g2 * h,
                    g5 + g4 * dx + g3 * h,
                ];
                let r = r0n * gs[0] + eta0 * gs[1] + mu * gs[2];
                #[rustfmt::skip]
                return Ok(Solved { x: x + dx, gs, r, #[cfg(test)] iterations: iteration });
            }
            let next = x + dx;
            if next > lo && next < hi {
                (x, last_step) = (next, step);
            } else {
                (x, last_step) = (0.5 * (lo + hi), f64::INFINITY);
                if !x.is_finite() {
                    break;
                }
            }
        }
        Err(DriftError::NoConvergence { time: t, residual })
    }
}

/// `a·b`.
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
#[path = "drift_tests.rs"]
mod tests;
