//! Each peer of the work–precision study timed exactly as the study runs it
//! (`studies::peers::run_peer`) against a bare, careful use of the same method on the same
//! problem: Kepler e = 0.6 (μ = 1), T = 200 sampled every 2 (100 samples), fixed-step methods
//! at h = 2/64, DOP853 at rtol = atol = 1e-12, 10^-13.5 and 1e-14 (the study's half-decade
//! grid around 1e-9 at T = 200).
//!
//! The bare versions are hand-written static-size loops of the same schemes (`[f64; 2]`
//! positions and momenta, the Kepler force written out, samples stored as `[f64; 4]`); the
//! bare DOP853 is the `differential-equations` crate used directly as a careful user would:
//! `[f64; 4]` state, a hand-written right-hand side, one reused method object, the whole span
//! in one `solve_ode` call, timed twice: with an output handler that stores nothing and no
//! samples at all (an upper bound on what sampling costs the wrapper, which stops exactly at the
//! 100 sample times), and with the same 101 samples from the crate's own evenly spaced output
//! (`EvenSolout`, its dense output: the same problem the study solves).
//!
//! Before criterion's own measurements it prints a table of wrapper/bare ratios of median
//! wall times (`cargo bench -p galerkin-vi-lab --bench peers`). It asserts nothing about time;
//! it does check that wrapper and bare reach the same end state.

use criterion::{Criterion, criterion_group, criterion_main};
use galerkin_vi::baselines::CompositionScheme;
use galerkin_vi::systems::Kepler;
use galerkin_vi_lab::scene::InitialState;
use galerkin_vi_lab::studies::peers::{Peer, SampledRun, run_peer};
use std::hint::black_box;
use std::time::{Duration, Instant};

const INTERVAL: f64 = 2.0;
const SAMPLES: usize = 100;
const DIVISOR: usize = 64;
const H: f64 = INTERVAL / DIVISOR as f64;
const Q0: [f64; 2] = [0.4, 0.0];
const P0: [f64; 2] = [0.0, 2.0];

/// The Kepler problem with μ = 1.
static KEPLER: std::sync::LazyLock<Kepler> =
    std::sync::LazyLock::new(|| Kepler::new(1.0).expect("μ = 1"));

/// Kepler force −μq/|q|³: the system's analytic gradient (`Kepler::potential_gradient`, which
/// is r² = q·q, k = μ/(r² √r²), ∇V = k q), on arrays. Written out here instead
/// (`[-(k q₀), -(k q₁)]` with k = 1/(r²√r²)), LLVM made RK4's four dependent stages 1.4× slower
/// (306 µs against 227 µs), and with the negation as a separate loop 1.7× (382 µs).
#[inline(always)]
fn force(q: [f64; 2]) -> [f64; 2] {
    use galerkin_vi::Mechanical;
    let mut g = [0.0; 2];
    KEPLER.potential_gradient(&q, &mut g);
    [-g[0], -g[1]]
}

/// The bare loops' output: the sample states (q, p).
type Samples = Vec<[f64; 4]>;

/// The sampling loop of the bare versions: `$step` advances `q`, `p` by one step.
macro_rules! sampled_bare {
    (|$q:ident, $p:ident| $step:block) => {{
        let (mut $q, mut $p) = (Q0, P0);
        let mut out: Samples = Vec::with_capacity(SAMPLES + 1);
        out.push([$q[0], $q[1], $p[0], $p[1]]);
        for _ in 0..SAMPLES {
            for _ in 0..DIVISOR {
                $step
            }
            out.push([$q[0], $q[1], $p[0], $p[1]]);
        }
        out
    }};
}

fn bare_rk4() -> Samples {
    #[inline(always)]
    fn rhs(y: [f64; 4]) -> [f64; 4] {
        let f = force([y[0], y[1]]);
        [y[2], y[3], f[0], f[1]]
    }
    #[inline(always)]
    fn axpy(y: &[f64; 4], a: f64, k: &[f64; 4]) -> [f64; 4] {
        std::array::from_fn(|r| y[r] + a * k[r])
    }
    sampled_bare!(|q, p| {
        let y = [q[0], q[1], p[0], p[1]];
        let k1 = rhs(y);
        let k2 = rhs(axpy(&y, 0.5 * H, &k1));
        let k3 = rhs(axpy(&y, 0.5 * H, &k2));
        let k4 = rhs(axpy(&y, H, &k3));
        let y: [f64; 4] =
            std::array::from_fn(|r| y[r] + H / 6.0 * (k1[r] + 2.0 * k2[r] + 2.0 * k3[r] + k4[r]));
        (q, p) = ([y[0], y[1]], [y[2], y[3]]);
    })
}

/// Kick–drift–kick Störmer–Verlet, the end force of one step reused by the next.
fn bare_verlet() -> Samples {
    let mut f = force(Q0);
    sampled_bare!(|q, p| {
        let half = [p[0] + 0.5 * H * f[0], p[1] + 0.5 * H * f[1]];
        q = [q[0] + H * half[0], q[1] + H * half[1]];
        f = force(q);
        p = [half[0] + 0.5 * H * f[0], half[1] + 0.5 * H * f[1]];
    })
}

/// Kick–drift–kick compositions with the end force of one step reused by the next.
fn bare_composition<const S: usize>(gamma: [f64; S]) -> Samples {
    let mut f = force(Q0);
    sampled_bare!(|q, p| {
        let mut kick = 0.5 * gamma[0] * H;
        for k in 0..S {
            for r in 0..2 {
                p[r] += kick * f[r];
            }
            let drift = gamma[k] * H;
            for r in 0..2 {
                q[r] += drift * p[r];
            }
            f = force(q);
            kick = 0.5 * H * (gamma[k] + if k + 1 < S { gamma[k + 1] } else { 0.0 });
        }
        for r in 0..2 {
            p[r] += kick * f[r];
        }
    })
}

fn yoshida6() -> [f64; 7] {
    let mut g = [0.0; 7];
    g.copy_from_slice(&CompositionScheme::Yoshida6.coefficients());
    g
}

/// Two-stage Gauss collocation for q̈ = f(q) with the wrapper's iteration: fixed point
/// Z ← h² A² F(Z) from Z = 0 until the change is at round-off, then forces re-evaluated.
fn bare_gauss2() -> Samples {
    let h = H;
    let s3 = 3f64.sqrt();
    let c = [0.5 - s3 / 6.0, 0.5 + s3 / 6.0];
    let a = [[0.25, 0.25 - s3 / 6.0], [0.25 + s3 / 6.0, 0.25]];
    let b = [0.5, 0.5];
    let mut a2 = [[0.0; 2]; 2];
    let mut ba = [0.0; 2];
    for i in 0..2 {
        for j in 0..2 {
            a2[i][j] = a[i][0] * a[0][j] + a[i][1] * a[1][j];
        }
        ba[i] = b[0] * a[0][i] + b[1] * a[1][i];
    }
    sampled_bare!(|q, p| {
        let v0 = p;
        let mut z = [[0.0; 2]; 2];
        let mut f = [[0.0; 2]; 2];
        let eval = |z: &[[f64; 2]; 2], f: &mut [[f64; 2]; 2]| {
            for i in 0..2 {
                f[i] = force([
                    q[0] + h * c[i] * v0[0] + z[i][0],
                    q[1] + h * c[i] * v0[1] + z[i][1],
                ]);
            }
        };
        let scale = q.iter().fold(1e-300f64, |m, x| m.max(x.abs()));
        let mut previous = f64::INFINITY;
        for it in 0..30 {
            eval(&z, &mut f);
            let mut change = 0.0f64;
            for i in 0..2 {
                for r in 0..2 {
                    let zn = h * h * (a2[i][0] * f[0][r] + a2[i][1] * f[1][r]);
                    change = change.max((zn - z[i][r]).abs());
                    z[i][r] = zn;
                }
            }
            if it >= 2 && change > 0.5 * previous {
                assert!(change <= 1e-14 * scale, "fixed point stalled");
                eval(&z, &mut f);
                break;
            }
            if change <= 1e-15 * scale {
                eval(&z, &mut f);
                break;
            }
            previous = change;
        }
        for r in 0..2 {
            let dq = h * v0[r] + h * h * (ba[0] * f[0][r] + ba[1] * f[1][r]);
            let dp = h * (b[0] * f[0][r] + b[1] * f[1][r]);
            q[r] += dq;
            p[r] += dp;
        }
    })
}

#[cfg(feature = "dop853")]
mod dop {
    use super::*;
    use differential_equations::control::ControlFlag;
    use differential_equations::interpolate::Interpolation;
    use differential_equations::methods::{DormandPrince, ExplicitRungeKutta, Ordinary};
    use differential_equations::ode::{ODE, OrdinaryNumericalMethod, solve_ode};
    use differential_equations::solout::{EvenSolout, Solout};
    use differential_equations::solution::Solution;

    struct KeplerRhs;
    impl ODE<f64, [f64; 4]> for KeplerRhs {
        #[inline]
        fn diff(&self, _t: f64, y: &[f64; 4], dydt: &mut [f64; 4]) {
            let f = force([y[0], y[1]]);
            *dydt = [y[2], y[3], f[0], f[1]];
        }
    }

    /// Stores nothing.
    struct Nothing;
    impl Solout<f64, [f64; 4]> for Nothing {
        #[inline]
        fn solout<I>(
            &mut self,
            _t: f64,
            _t_prev: f64,
            _y: &[f64; 4],
            _y_prev: &[f64; 4],
            _i: &mut I,
            _s: &mut Solution<f64, [f64; 4]>,
        ) -> ControlFlag<f64, [f64; 4]>
        where
            I: Interpolation<f64, [f64; 4]> + ?Sized,
        {
            ControlFlag::Continue
        }
    }

    /// The crate used directly by a careful user: one `[f64; 4]` state, the hand-written
    /// right-hand side, one method object reused for every run (`h0 = 0`: its own initial-step
    /// heuristic each time), the whole span T = 200 in one `solve_ode` call, an output handler
    /// that stores nothing. It samples nothing: only the end state is read.
    pub fn bare_dop853(method: &mut Dop) -> ([f64; 4], usize) {
        method.h0 = 0.0;
        let y = [Q0[0], Q0[1], P0[0], P0[1]];
        let solution = solve_ode(
            method,
            &KeplerRhs,
            0.0,
            INTERVAL * SAMPLES as f64,
            &y,
            &mut Nothing,
        )
        .expect("DOP853 on Kepler");
        (
            *OrdinaryNumericalMethod::<f64, [f64; 4]>::y(method),
            solution.evals.function,
        )
    }

    /// The crate's DOP853 type for a `[f64; 4]` state.
    pub type Dop = ExplicitRungeKutta<Ordinary, DormandPrince, f64, [f64; 4], 8, 12, 16>;

    /// A fresh method object (its step count runs over its whole life, so no step limit).
    pub fn new_dop(tolerance: f64) -> Dop {
        ExplicitRungeKutta::dop853()
            .rtol(tolerance)
            .atol(tolerance)
            .max_steps(usize::MAX)
    }

    /// Tolerances compared: the study's half-decade grid around 1e-9 at T = 200.
    pub const TOLERANCES: [f64; 3] = [1e-12, 3.1622776601683794e-14, 1e-14];

    /// The same careful use sampling the same problem: the 101 states at t = 0, 2, …, 200
    /// from the crate's own output handler for evenly spaced times (`EvenSolout`, DOP853's
    /// seventh-order dense output between step ends: no step is shortened, each sampled step
    /// pays the interpolant's three extra stages). Returns the last sample and the force
    /// evaluations.
    pub fn bare_dop853_sampled(method: &mut Dop) -> ([f64; 4], usize) {
        method.h0 = 0.0;
        let y = [Q0[0], Q0[1], P0[0], P0[1]];
        let t_end = INTERVAL * SAMPLES as f64;
        let mut out = EvenSolout::new(INTERVAL, 0.0, t_end);
        let solution =
            solve_ode(method, &KeplerRhs, 0.0, t_end, &y, &mut out).expect("DOP853 on Kepler");
        assert_eq!(solution.y.len(), SAMPLES + 1, "one state per sample time");
        (solution.y[SAMPLES], solution.evals.function)
    }

    /// Prints wrapper / careful-bare ratios of wall times (interleaved runs: the median of
    /// the per-round ratios, robust to a machine whose load drifts), the wrapper on the study's
    /// own system type (`AnySystem`, as `gvi work-precision` runs it) and on `Kepler`, against
    /// the bare crate with no samples (only the end state) and with the same 101 samples from
    /// its own dense output, with the force evaluations of each, and checks that all reach the
    /// same end state to within the tolerance-level error.
    pub fn compare(kepler: &Kepler, initial: &InitialState) {
        let any = galerkin_vi::systems::AnySystem::Kepler(*kepler);
        eprintln!(
            "\nDOP853: the study's wrapper (100 samples, each exactly at a step end) against the \
             crate used bare over the whole span, without samples (bare) and with the same \
             samples from its dense output (sampled); ratios: median of interleaved rounds"
        );
        eprintln!(
            "{:<10} {:>10} {:>10} {:>10} {:>10} | {:>8} {:>8} {:>8} {:>8} | {:>7} {:>7} {:>9}",
            "tol",
            "wrapper",
            "AnySystem",
            "bare",
            "sampled",
            "w/bare",
            "Any/bare",
            "w/samp",
            "Any/samp",
            "evals/b",
            "evals/s",
            "|Δ end|"
        );
        for tolerance in TOLERANCES {
            let peer = Peer::Dop853 { tolerance };
            let mut method = new_dop(tolerance);
            let mut sampled_method = new_dop(tolerance);
            let run = wrapper(kepler, initial, peer);
            let (end, bare_evals) = bare_dop853(&mut method);
            let (end_sampled, sampled_evals) = bare_dop853_sampled(&mut sampled_method);
            let (q, p) = (&run.q[SAMPLES], &run.p[SAMPLES]);
            let mut diff = 0.0f64;
            for e in [end, end_sampled] {
                for x in [q[0] - e[0], q[1] - e[1], p[0] - e[2], p[1] - e[3]] {
                    diff = diff.max(x.abs());
                }
            }
            assert!(
                diff < 1e-6,
                "DOP853 {tolerance:e}: wrapper and bare differ by {diff:e}"
            );
            let budget = Duration::from_millis(4000);
            let mut direct = || {
                black_box(wrapper(kepler, initial, black_box(peer)));
            };
            let mut study = || {
                let run = run_peer(&any, initial, black_box(peer), INTERVAL, 1, SAMPLES);
                black_box(run.expect("run_peer"));
            };
            let mut bare = || {
                black_box(bare_dop853(&mut method));
            };
            let mut sampled = || {
                black_box(bare_dop853_sampled(&mut sampled_method));
            };
            let (t, r) = interleaved(
                &mut [&mut direct, &mut study, &mut bare, &mut sampled],
                budget,
            );
            eprintln!(
                "{:<10.3e} {:>7.1} µs {:>7.1} µs {:>7.1} µs {:>7.1} µs | {:>7.3}× {:>7.3}× \
                 {:>7.3}× {:>7.3}× | {:>7.3} {:>7.3} {:>9.1e}",
                tolerance,
                t[0] * 1e6,
                t[1] * 1e6,
                t[2] * 1e6,
                t[3] * 1e6,
                r(0, 2),
                r(1, 2),
                r(0, 3),
                r(1, 3),
                run.force_evaluations as f64 / bare_evals as f64,
                run.force_evaluations as f64 / sampled_evals as f64,
                diff
            );
        }
    }

    /// Issue 35's first target, measured as the work–precision study runs both: the fastest
    /// Galerkin configuration at 1e-9 on this problem (Legendre n = 13, h = 0.4, 13 Gauss
    /// points, the study's `galerkin-legendre-compact` row) against DOP853 at 10^-13.5, the
    /// tolerance at which it reaches 1e-9 here, both through `run_peer` on `AnySystem`.
    /// Prints their median times and the median of the per-round ratio (interleaved rounds).
    pub fn fastest_at_1e9(initial: &InitialState) {
        let any = galerkin_vi::systems::AnySystem::Kepler(*KEPLER);
        let galerkin = fastest_galerkin();
        let dop = Peer::Dop853 {
            tolerance: TOLERANCES[1],
        };
        let mut g = || {
            let run = run_peer(&any, initial, black_box(galerkin), INTERVAL, 5, SAMPLES);
            black_box(run.expect("run_peer"));
        };
        let mut d = || {
            let run = run_peer(&any, initial, black_box(dop), INTERVAL, 1, SAMPLES);
            black_box(run.expect("run_peer"));
        };
        let (t, r) = interleaved(&mut [&mut g, &mut d], Duration::from_millis(4000));
        eprintln!(
            "\nKepler T = 200 at 1e-9 (issue 35): Galerkin Legendre n = 13, h = 0.4, 13 points \
             {:.3} ms; DOP853 10^-13.5 {:.3} ms; ratio {:.3}× (median of interleaved rounds)",
            t[0] * 1e3,
            t[1] * 1e3,
            r(0, 1)
        );
    }

    /// Runs the closures in turn, round after round, until `budget` (at least 15 rounds);
    /// returns their median times and the median over rounds of the ratio of two of them
    /// (`ratio(a, b)`: time of a / time of b in the same round).
    fn interleaved(
        runs: &mut [&mut dyn FnMut()],
        budget: Duration,
    ) -> (Vec<f64>, impl Fn(usize, usize) -> f64 + use<>) {
        for f in runs.iter_mut() {
            f();
        }
        let mut rounds: Vec<Vec<f64>> = Vec::new();
        let start = Instant::now();
        while rounds.len() < 15 || (start.elapsed() < budget && rounds.len() < 1001) {
            rounds.push(
                runs.iter_mut()
                    .map(|f| {
                        let t = Instant::now();
                        f();
                        t.elapsed().as_secs_f64()
                    })
                    .collect(),
            );
        }
        fn median(mut v: Vec<f64>) -> f64 {
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        }
        let times = (0..runs.len())
            .map(|k| median(rounds.iter().map(|r| r[k]).collect()))
            .collect();
        (times, move |a: usize, b: usize| {
            median(rounds.iter().map(|r| r[a] / r[b]).collect())
        })
    }
}

fn wrapper(kepler: &Kepler, initial: &InitialState, peer: Peer) -> SampledRun {
    let divisor = if peer.fixed_step() { DIVISOR } else { 1 };
    let run = run_peer(kepler, initial, peer, INTERVAL, divisor, SAMPLES).expect("run_peer");
    assert!(run.failure.is_none(), "{:?}", run.failure);
    run
}

/// The fastest Galerkin configuration at 1e-9 on this problem in the work–precision study:
/// Legendre n = 13, h = 0.4 (five steps per sample), 13 Gauss points.
fn fastest_galerkin() -> Peer {
    Peer::Galerkin {
        basis: galerkin_vi::basis::BasisKind::Legendre,
        n: 13,
        points: galerkin_vi_lab::studies::peers::QuadPoints::Compact,
    }
}

/// A peer: its label, the study's wrapper, and the bare loop.
struct Case {
    label: &'static str,
    peer: Peer,
    bare: fn() -> Samples,
}

fn cases() -> Vec<Case> {
    vec![
        Case {
            label: "stormer-verlet",
            peer: Peer::StormerVerlet,
            bare: bare_verlet,
        },
        Case {
            label: "rk4",
            peer: Peer::Rk4,
            bare: bare_rk4,
        },
        Case {
            label: "gauss-2",
            peer: Peer::Gauss { s: 2 },
            bare: bare_gauss2,
        },
        Case {
            label: "yoshida-6",
            peer: Peer::Composition {
                scheme: CompositionScheme::Yoshida6,
            },
            bare: || bare_composition(yoshida6()),
        },
    ]
}

fn median_time(mut f: impl FnMut(), budget: Duration) -> f64 {
    f();
    let mut times = Vec::new();
    let start = Instant::now();
    while times.len() < 7 || (start.elapsed() < budget && times.len() < 501) {
        let t = Instant::now();
        f();
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn peers(c: &mut Criterion) {
    let kepler = Kepler::new(1.0).expect("μ = 1");
    let initial = InitialState {
        t0: 0.0,
        q: Q0.to_vec(),
        p: P0.to_vec(),
    };
    let cases = cases();
    eprintln!(
        "\nKepler e = 0.6, T = {}, {SAMPLES} samples; fixed steps h = 2/{DIVISOR}",
        INTERVAL * SAMPLES as f64
    );
    eprintln!(
        "{:<16} {:>12} {:>12} {:>8} {:>12}",
        "peer", "wrapper", "bare", "ratio", "|Δ end|"
    );
    for case in &cases {
        let run = wrapper(&kepler, &initial, case.peer);
        let bare = (case.bare)();
        let (q, p) = (&run.q[SAMPLES], &run.p[SAMPLES]);
        let end = bare[SAMPLES];
        let diff = [q[0] - end[0], q[1] - end[1], p[0] - end[2], p[1] - end[3]]
            .iter()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(
            diff < 1e-8,
            "{}: wrapper and bare differ by {diff:e}",
            case.label
        );
        let budget = Duration::from_millis(1500);
        let tw = median_time(
            || {
                black_box(wrapper(&kepler, &initial, black_box(case.peer)));
            },
            budget,
        );
        let tb = median_time(
            || {
                black_box((case.bare)());
            },
            budget,
        );
        eprintln!(
            "{:<16} {:>9.1} µs {:>9.1} µs {:>7.2}× {:>12.1e}",
            case.label,
            tw * 1e6,
            tb * 1e6,
            tw / tb,
            diff
        );
    }
    #[cfg(feature = "dop853")]
    dop::compare(&kepler, &initial);
    #[cfg(feature = "dop853")]
    dop::fastest_at_1e9(&initial);
    let mut group = c.benchmark_group("peers");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    for case in &cases {
        let label = case.label.replace(" (", "-").replace(")", "");
        group.bench_function(format!("{label}/wrapper"), |b| {
            b.iter(|| wrapper(&kepler, &initial, black_box(case.peer)))
        });
        group.bench_function(format!("{label}/bare"), |b| b.iter(|| (case.bare)()));
    }
    group.bench_function("kepler-1e-9/galerkin-legendre-n13-h0.4-m13", |b| {
        b.iter(|| {
            run_peer(
                &kepler,
                &initial,
                black_box(fastest_galerkin()),
                INTERVAL,
                5,
                SAMPLES,
            )
        })
    });
    #[cfg(feature = "dop853")]
    for tolerance in dop::TOLERANCES {
        let peer = Peer::Dop853 { tolerance };
        group.bench_function(format!("dop853-{tolerance:e}/wrapper"), |b| {
            b.iter(|| wrapper(&kepler, &initial, black_box(peer)))
        });
        let mut method = dop::new_dop(tolerance);
        group.bench_function(format!("dop853-{tolerance:e}/bare"), |b| {
            b.iter(|| dop::bare_dop853(&mut method))
        });
        group.bench_function(format!("dop853-{tolerance:e}/bare-sampled"), |b| {
            b.iter(|| dop::bare_dop853_sampled(&mut method))
        });
    }
    group.finish();
}

criterion_group!(benches, peers);
criterion_main!(benches);
