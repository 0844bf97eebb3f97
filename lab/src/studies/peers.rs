//! Running the Galerkin method and the classical baselines the same way, sampled on a common
//! grid t_k = t₀ + k·Δ (the work–precision and stability studies).

use crate::error::LabError;
use crate::error::Result;
use crate::scene::InitialState;
use galerkin_vi::baselines::{
    Composition, CompositionScheme, GalerkinMethod, GaussCollocationBaseline, OneStepMethod, Rk4,
    StaticKernel, StormerVerlet,
};
use galerkin_vi::basis::BasisKind;
use galerkin_vi::integrator::GalerkinIntegrator;
use galerkin_vi::kepler_adapted::{InnerKeplerGalerkin, KeplerAdaptedGalerkin};
use galerkin_vi::multirate::{MultirateGalerkin, MultirateShape};
use galerkin_vi::quadrature::QuadratureKind;
use galerkin_vi::systems::{AnySystem, NBody, System};
use serde::Serialize;

/// How many Gauss–Legendre points a Galerkin step uses: the paper's 2n, the economical
/// ⌈3n/2⌉ ([`QuadratureKind::economical_points`]: 25 % fewer force evaluations per step), or
/// the compact n ([`QuadratureKind::compact_points`]: for small h·ω).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum QuadPoints {
    /// The paper's rule: 2n points ([`QuadratureKind::default_points`]).
    Paper,
    /// ⌈3n/2⌉ points ([`QuadratureKind::economical_points`]).
    Economical,
    /// n points ([`QuadratureKind::compact_points`]).
    Compact,
    /// n − 1 points ([`QuadratureKind::collocation_points`]): Gauss collocation.
    Collocation,
}

impl QuadPoints {
    /// Every choice, paper first.
    pub const ALL: [QuadPoints; 4] = [
        QuadPoints::Paper,
        QuadPoints::Economical,
        QuadPoints::Compact,
        QuadPoints::Collocation,
    ];

    /// The name on the command line (`paper`, `economical`, `compact`, `collocation`).
    pub fn as_str(self) -> &'static str {
        match self {
            QuadPoints::Paper => "paper",
            QuadPoints::Economical => "economical",
            QuadPoints::Compact => "compact",
            QuadPoints::Collocation => "collocation",
        }
    }

    /// The suffix of the method family (`""`, `-econ`, `-compact`, `-colloc`).
    pub fn family_suffix(self) -> &'static str {
        match self {
            QuadPoints::Paper => "",
            QuadPoints::Economical => "-econ",
            QuadPoints::Compact => "-compact",
            QuadPoints::Collocation => "-colloc",
        }
    }

    /// The number of points of the default quadrature (Gauss–Legendre) for n basis functions.
    pub fn points(self, n: usize) -> usize {
        let rule = QuadratureKind::default();
        match self {
            QuadPoints::Paper => rule.default_points(n),
            QuadPoints::Economical => rule.economical_points(n),
            QuadPoints::Compact => rule.compact_points(n),
            QuadPoints::Collocation => rule.collocation_points(n),
        }
    }
}

impl std::fmt::Display for QuadPoints {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Which bodies the Kepler-adapted integrator puts on their exact Kepler orbits.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum KeplerBodies {
    /// Every planet (`KeplerAdaptedGalerkin::new`; families `galerkin-kepler-S`).
    All,
    /// Only the body with the shortest orbit about the heaviest one, the others' curves
    /// polynomial (`KeplerAdaptedGalerkin::with_kepler_bodies`, solved by
    /// `InnerKeplerGalerkin` when that body is body 1, the innermost in Jacobi order; families
    /// `galerkin-kepler-S-fast`).
    Fastest,
}

impl KeplerBodies {
    /// Its name on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            KeplerBodies::All => "all",
            KeplerBodies::Fastest => "fastest",
        }
    }
}

impl std::str::FromStr for KeplerBodies {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        [KeplerBodies::All, KeplerBodies::Fastest]
            .into_iter()
            .find(|k| k.as_str() == s.trim())
            .ok_or_else(|| format!("unknown Kepler bodies '{s}' (expected all or fastest)"))
    }
}

impl std::str::FromStr for QuadPoints {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        QuadPoints::ALL
            .into_iter()
            .find(|q| q.as_str() == s.trim())
            .ok_or_else(|| {
                format!(
                    "unknown quadrature point count '{s}' (expected paper, economical, compact or collocation)"
                )
            })
    }
}

/// A method that can be run on the sampling grid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "method")]
pub enum Peer {
    /// The Galerkin integrator with `n` functions of `basis`, the default quadrature
    /// (Gauss–Legendre) with `points` points, step Δ/`divisor`.
    Galerkin {
        /// Basis.
        basis: BasisKind,
        /// Number of basis functions.
        n: usize,
        /// Number of quadrature points: the paper's, the economical or the compact one.
        points: QuadPoints,
    },
    /// Störmer–Verlet.
    StormerVerlet,
    /// Classical RK4.
    Rk4,
    /// s-stage Gauss–Legendre collocation.
    Gauss {
        /// Stages.
        s: usize,
    },
    /// Symplectic composition of Störmer–Verlet.
    Composition {
        /// Which one.
        scheme: CompositionScheme,
    },
    /// The Kepler-adapted Galerkin integrator (Gauss collocation with `s` stages in the
    /// interaction picture of the Jacobi Wisdom–Holman splitting): N-body scenes only.
    KeplerAdapted {
        /// Stages (order 2s).
        s: usize,
        /// Which bodies move on their exact Kepler orbits.
        bodies: KeplerBodies,
    },
    /// The multirate Galerkin integrator: the body with the shortest orbit on `micro_steps`
    /// micro steps per step, every body with n basis functions and n − 1 Gauss points (Gauss
    /// collocation): N-body scenes with a dominant mass only.
    Multirate {
        /// Number of basis functions.
        n: usize,
        /// Micro steps R per step.
        micro_steps: usize,
    },
    /// DOP853 (adaptive) with rtol = atol = tolerance, stopped at every sample time.
    Dop853 {
        /// Tolerance.
        tolerance: f64,
    },
}

impl Peer {
    /// The method family, e.g. `galerkin-chebyshev`, `galerkin-legendre-econ` (economical
    /// quadrature), `galerkin-hermite-compact` (n points), `gauss-2`, `dop853`.
    pub fn family(&self) -> String {
        match self {
            Peer::Galerkin { basis, points, .. } => {
                format!("galerkin-{basis}{}", points.family_suffix())
            }
            Peer::StormerVerlet => "stormer-verlet".into(),
            Peer::Rk4 => "rk4".into(),
            Peer::Gauss { s } => format!("gauss-{s}"),
            Peer::KeplerAdapted {
                s,
                bodies: KeplerBodies::All,
            } => format!("galerkin-kepler-{s}"),
            Peer::KeplerAdapted {
                s,
                bodies: KeplerBodies::Fastest,
            } => format!("galerkin-kepler-{s}-fast"),
            Peer::Multirate { micro_steps, .. } => format!("galerkin-multirate-{micro_steps}"),
            Peer::Composition { scheme } => scheme.as_str().into(),
            Peer::Dop853 { .. } => "dop853".into(),
        }
    }

    /// Whether the step is fixed (and divides the sample interval).
    pub fn fixed_step(&self) -> bool {
        !matches!(self, Peer::Dop853 { .. })
    }
}

/// States at the sample times and the cost of getting them.
#[derive(Debug, Clone)]
pub struct SampledRun {
    /// q at t₀ + kΔ, k = 0 … (samples completed).
    pub q: Vec<Vec<f64>>,
    /// p at the same times.
    pub p: Vec<Vec<f64>>,
    /// Force evaluations.
    pub force_evaluations: usize,
    /// The error that stopped the run early, if any.
    pub failure: Option<String>,
}

/// Run `peer` from `initial` for `samples` sample intervals of length `interval`, with
/// `divisor` fixed steps per interval (ignored by DOP853).
///
/// DOP853 runs on the concrete system inside an [`AnySystem`] (Kepler, N-body; the scenes'
/// type), as a user of the crate would write it, rather than through the enum's dispatch in
/// every force evaluation (which cost it 10–15 % on Kepler).
pub fn run_peer<S: System + 'static>(
    system: &S,
    initial: &InitialState,
    peer: Peer,
    interval: f64,
    divisor: usize,
    samples: usize,
) -> Result<SampledRun> {
    if divisor == 0 || !(interval.is_finite() && interval > 0.0) {
        return Err(LabError::InvalidArgument {
            name: "sampling".into(),
            reason: format!("interval {interval} with {divisor} steps per interval"),
        });
    }
    let h = interval / divisor as f64;
    Ok(match peer {
        Peer::Galerkin { basis, n, points } => {
            let gvi = GalerkinIntegrator::from_kinds(
                basis,
                n,
                QuadratureKind::default(),
                Some(points.points(n)),
                h,
            )?;
            let mut m = GalerkinMethod::new(&gvi, system)?;
            sampled(&mut m, initial, divisor, samples)
        }
        Peer::StormerVerlet => {
            let mut m = StormerVerlet::new(system, h)?;
            sampled_fixed(&mut m, initial, divisor, samples)
        }
        Peer::Rk4 => sampled_fixed(&mut Rk4::new(system, h)?, initial, divisor, samples),
        Peer::Gauss { s } => sampled_fixed(
            &mut GaussCollocationBaseline::new(system, s, h)?,
            initial,
            divisor,
            samples,
        ),
        Peer::Composition { scheme } => sampled_fixed(
            &mut Composition::new(system, scheme, h)?,
            initial,
            divisor,
            samples,
        ),
        Peer::KeplerAdapted { s, bodies } => {
            let nbody = nbody_of(system).ok_or_else(|| LabError::InvalidArgument {
                name: "peer".into(),
                reason: "the Kepler-adapted integrator needs an N-body scene".into(),
            })?;
            match bodies {
                KeplerBodies::All => {
                    let mut method = KeplerAdaptedGalerkin::new(nbody, s, h)?;
                    sampled(&mut method, initial, divisor, samples)
                }
                // The innermost body: the same map solved slot by slot with the converged
                // bodies frozen (`InnerKeplerGalerkin`).
                KeplerBodies::Fastest => match shortest_period_body(nbody, initial)? {
                    1 => {
                        let mut method = InnerKeplerGalerkin::new(nbody, s, h, 1)?;
                        sampled(&mut method, initial, divisor, samples)
                    }
                    fast => {
                        let mut method =
                            KeplerAdaptedGalerkin::with_kepler_bodies(nbody, s, h, &[fast])?;
                        sampled(&mut method, initial, divisor, samples)
                    }
                },
            }
        }
        Peer::Multirate { n, micro_steps } => {
            let nbody = nbody_of(system).ok_or_else(|| LabError::InvalidArgument {
                name: "peer".into(),
                reason: "the multirate integrator needs an N-body scene".into(),
            })?;
            let fast = shortest_period_body(nbody, initial)?;
            let shape = MultirateShape::collocation(n, micro_steps);
            sampled(
                &mut MultirateGalerkin::new(nbody, &[fast], shape, h)?,
                initial,
                divisor,
                samples,
            )
        }
        Peer::Dop853 { tolerance } => {
            let any = system as &dyn std::any::Any;
            match any.downcast_ref::<AnySystem>() {
                Some(AnySystem::Kepler(s)) => dop853(s, initial, interval, tolerance, samples)?,
                Some(AnySystem::NBody(s)) => dop853(s, initial, interval, tolerance, samples)?,
                _ => dop853(system, initial, interval, tolerance, samples)?,
            }
        }
    })
}

/// The N-body system inside `system`, if it is one (directly or as a scene's [`AnySystem`]).
pub fn nbody_of<S: System + 'static>(system: &S) -> Option<&NBody> {
    let any = system as &dyn std::any::Any;
    match any.downcast_ref::<AnySystem>() {
        Some(AnySystem::NBody(nb)) => Some(nb),
        _ => any.downcast_ref::<NBody>(),
    }
}

#[cfg(feature = "dop853")]
fn dop853<S: System>(
    system: &S,
    initial: &InitialState,
    interval: f64,
    tolerance: f64,
    samples: usize,
) -> Result<SampledRun> {
    let mut m = crate::dop853::Dop853Baseline::new(system, interval, tolerance)?;
    Ok(sampled(&mut m, initial, 1, samples))
}

#[cfg(not(feature = "dop853"))]
fn dop853<S: System>(
    _system: &S,
    _initial: &InitialState,
    _interval: f64,
    _tolerance: f64,
    _samples: usize,
) -> Result<SampledRun> {
    Err(
        crate::error::GviError::Unsupported("DOP853 needs the cargo feature `dop853`".into())
            .into(),
    )
}

/// The body with the shortest orbit about the heaviest one (the multirate integrator's fast
/// body, the Kepler-adapted integrator's `fastest`).
fn shortest_period_body(nbody: &NBody, initial: &InitialState) -> Result<usize> {
    MultirateGalerkin::shortest_period_body(nbody, &initial.q, &initial.p).ok_or_else(|| {
        LabError::InvalidArgument {
            name: "peer".into(),
            reason: "no bound orbit about the heaviest body".into(),
        }
    })
}

/// The generic loop (monomorphised per method, so timings compare like with like): `samples`
/// sample intervals of `divisor` steps of `m` from `initial`, the state at every sample
/// (for methods built outside [`Peer`], e.g. by the lab's examples).
pub fn sampled<M: OneStepMethod>(
    m: &mut M,
    initial: &InitialState,
    divisor: usize,
    samples: usize,
) -> SampledRun {
    let h = m.step_size();
    let d = initial.q.len();
    let mut run = SampledRun {
        q: Vec::with_capacity(samples + 1),
        p: Vec::with_capacity(samples + 1),
        force_evaluations: 0,
        failure: None,
    };
    run.q.push(initial.q.clone());
    run.p.push(initial.p.clone());
    let (mut q, mut p) = (initial.q.clone(), initial.p.clone());
    let (mut qn, mut pn) = (vec![0.0; d], vec![0.0; d]);
    'outer: for k in 0..samples {
        for j in 0..divisor {
            let t = initial.t0 + (k * divisor + j) as f64 * h;
            if let Err(e) = m.step(t, &q, &p, &mut qn, &mut pn) {
                run.failure = Some(e.to_string());
                break 'outer;
            }
            std::mem::swap(&mut q, &mut qn);
            std::mem::swap(&mut p, &mut pn);
        }
        if q.iter().chain(&p).any(|x| !x.is_finite()) {
            run.failure = Some(format!("non-finite state at sample {}", k + 1));
            break;
        }
        run.q.push(q.clone());
        run.p.push(p.clone());
    }
    run.force_evaluations = m.force_evaluations();
    run
}

/// A fixed-step baseline on the sampling grid: for the dimensions of the built-in scenes
/// (D = 1, 2, 4, 6, 18, 30) the fixed-size kernel on `[f64; D]` states (the same arithmetic
/// as [`OneStepMethod::step`]), otherwise the generic loop.
pub(crate) fn sampled_fixed<M: StaticKernel>(
    m: &mut M,
    initial: &InitialState,
    divisor: usize,
    samples: usize,
) -> SampledRun {
    let d = initial.q.len();
    if initial.p.len() != d || m.dim() != d {
        // The generic loop reports the mismatch.
        return sampled(m, initial, divisor, samples);
    }
    match d {
        1 => sampled_static::<M, 1>(m, initial, divisor, samples),
        2 => sampled_static::<M, 2>(m, initial, divisor, samples),
        4 => sampled_static::<M, 4>(m, initial, divisor, samples),
        6 => sampled_static::<M, 6>(m, initial, divisor, samples),
        18 => sampled_static::<M, 18>(m, initial, divisor, samples),
        30 => sampled_static::<M, 30>(m, initial, divisor, samples),
        _ => sampled(m, initial, divisor, samples),
    }
}

/// [`sampled`] with `[f64; D]` states (the caller has checked the lengths).
fn sampled_static<M: StaticKernel, const D: usize>(
    m: &mut M,
    initial: &InitialState,
    divisor: usize,
    samples: usize,
) -> SampledRun {
    let mut run = SampledRun {
        q: Vec::with_capacity(samples + 1),
        p: Vec::with_capacity(samples + 1),
        force_evaluations: 0,
        failure: None,
    };
    run.q.push(initial.q.clone());
    run.p.push(initial.p.clone());
    let (mut q, mut p) = ([0.0; D], [0.0; D]);
    q.copy_from_slice(&initial.q);
    p.copy_from_slice(&initial.p);
    let h = m.step_size();
    let mut fsal = None;
    'outer: for k in 0..samples {
        for j in 0..divisor {
            let t = initial.t0 + (k * divisor + j) as f64 * h;
            if let Err(e) = m.advance(t, &mut q, &mut p, &mut fsal) {
                run.failure = Some(e.to_string());
                break 'outer;
            }
        }
        if q.iter().chain(&p).any(|x| !x.is_finite()) {
            run.failure = Some(format!("non-finite state at sample {}", k + 1));
            break;
        }
        run.q.push(q.to_vec());
        run.p.push(p.to_vec());
    }
    run.force_evaluations = m.force_evaluations();
    run
}
