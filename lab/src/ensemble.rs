//! Ensembles: many runs of one scene from Gaussian perturbations of its initial state, in
//! parallel over cores (`gvi ensemble`).
//!
//! Member i starts at (q₀ + σ ξ_q, p₀ + σ ξ_p) with ξ standard normal, drawn from a
//! [`StdRng`] seeded by [`member_seed`]`(seed, i)`: every member's draw depends only on the
//! ensemble seed and its index, never on which thread runs it, so an ensemble is reproducible
//! bit for bit whatever the number of threads. Each member is integrated step by step with the
//! exact step Jacobian ([`GalerkinIntegrator::step_jacobian_in`]), which gives at once
//!
//! - the final state, the maximum relative energy error max_k |E_k − E_0| / (T₀ + |V₀|) (the
//!   scale of `gvi run`, [`crate::energy`], at the member's own start; |E₀| for a system
//!   without a constant mass matrix) and the
//!   maximum error max_k |J_k − J_0| of every momentum map of the system's symmetries
//!   (discrete Noether: conserved to round-off at step ends), and
//! - a largest-Lyapunov-exponent estimate from the tangent map Φ_k = J_{k−1} ⋯ J_0: with
//!   M_0 = I / ‖I‖_F, M_{k+1} = J_k M_k, renormalised M ← M / ‖M‖_F every
//!   [`RENORMALISE_EVERY`] steps (so that ‖Φ‖ never overflows), the estimate is
//!   λ = (Σ ln ‖M‖_F at each renormalisation + ln ‖M_final‖_F) / T = ln(‖Φ_N‖_F / ‖I‖_F) / T.
//!   For a map conjugate to a rotation (a symplectic integrator of the harmonic oscillator)
//!   ‖Φ_N‖_F stays bounded, so λ = O(1/T); for a chaotic orbit it tends to the largest
//!   exponent.
//!
//! ```
//! use galerkin_vi_lab::ensemble::{EnsembleOptions, run_ensemble};
//! use galerkin_vi_lab::scene::Scene;
//!
//! let mut scene = Scene::load("harmonic")?;
//! scene.method.n = 8;
//! scene.method.h = 1.0;
//! scene.method.steps = 20;
//! let options = EnsembleOptions { count: 4, sigma: 1e-3, seed: 7, ..Default::default() };
//! let ensemble = run_ensemble(&scene.build()?, &options, None)?;
//! assert_eq!(ensemble.members.len(), 4);
//! assert!(ensemble.members.iter().all(|m| m.max_relative_energy_error < 1e-10));
//! # Ok::<(), galerkin_vi_lab::error::LabError>(())
//! ```

use crate::distance::nan_max;
use crate::error::{LabError, Result};
use crate::scene::BuiltScene;
use galerkin_vi::GalerkinIntegrator;
use galerkin_vi::Lagrangian;
use galerkin_vi::basis::Basis;
use galerkin_vi::geometry::NamedMomentumMap;
use galerkin_vi::quadrature::Quadrature;
use galerkin_vi::systems::System;
use indicatif::ProgressBar;
use nalgebra::DMatrix;
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rayon::prelude::*;
use std::fmt::Write as _;

/// Steps between two renormalisations of the tangent map. ‖J_k‖ ≤ e^{λ_max h} per step, so
/// ten steps keep ‖M‖ far from overflow for any physical λ h < 70.
pub const RENORMALISE_EVERY: usize = 10;

/// Largest ensemble accepted (members are held in memory with their results).
pub const MAX_MEMBERS: usize = 10_000_000;

/// What an ensemble is: how many members, the perturbation size and the seed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnsembleOptions {
    /// Number of members (≥ 1).
    pub count: usize,
    /// Standard deviation σ of the Gaussian perturbation of every component of q and p
    /// (absolute, ≥ 0; 0 gives identical members).
    pub sigma: f64,
    /// Ensemble seed.
    pub seed: u64,
}

impl Default for EnsembleOptions {
    fn default() -> Self {
        EnsembleOptions {
            count: 16,
            sigma: 1e-6,
            seed: 0,
        }
    }
}

impl EnsembleOptions {
    /// Check the count and σ (a typed error naming the flag).
    pub fn validate(&self) -> Result<()> {
        if self.count == 0 || self.count > MAX_MEMBERS {
            return Err(LabError::InvalidArgument {
                name: "--count".into(),
                reason: format!(
                    "{} members: an ensemble needs 1 ≤ count ≤ {MAX_MEMBERS}",
                    self.count
                ),
            });
        }
        if !(self.sigma.is_finite() && self.sigma >= 0.0) {
            return Err(LabError::InvalidArgument {
                name: "--perturb".into(),
                reason: format!(
                    "σ = {}: the perturbation's standard deviation must be finite and ≥ 0",
                    self.sigma
                ),
            });
        }
        Ok(())
    }
}

/// The memory an ensemble of `count` members in dimension `d` with `momenta` momentum maps
/// needs, estimated before it runs: every member's initial state and result (final state,
/// errors, failure) and the CSV text of its row (about 25 bytes per number, written twice: the
/// output and the one-thread comparison), checked against [`crate::memory::LIMIT_BYTES`].
pub fn ensure_memory(count: usize, d: usize, momenta: usize) -> Result<()> {
    let state = (16 * d + 2 * 24) as f64;
    let numbers = (2 * d + 6 + momenta) as f64;
    let per_member = 2.0 * state + 8.0 * momenta as f64 + 128.0 + 2.0 * 25.0 * numbers;
    crate::memory::ensure_fits(
        format!("an ensemble of {count} members"),
        per_member * count as f64,
        "the members' rows are held until written; fewer --count",
    )
}

/// One member's initial state.
#[derive(Debug, Clone, PartialEq)]
pub struct Member {
    /// Index in the ensemble.
    pub member: usize,
    /// The seed of its perturbation ([`member_seed`]).
    pub seed: u64,
    /// Initial position.
    pub q0: Vec<f64>,
    /// Initial momentum.
    pub p0: Vec<f64>,
    /// Euclidean norm of the perturbation (δq, δp).
    pub perturbation_norm: f64,
}

/// SplitMix64's finaliser: a bijective mixing of 64 bits (Steele, Lea & Flood 2014).
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The seed of member `member` of an ensemble seeded by `seed`: a hash of both, so members'
/// streams are unrelated and each depends only on (seed, member).
pub fn member_seed(seed: u64, member: usize) -> u64 {
    splitmix64(seed ^ splitmix64(member as u64))
}

/// One standard normal deviate by the Box–Muller transform (two uniforms give
/// √(−2 ln u₁) cos 2πu₂); u₁ ∈ (0, 1] so the logarithm is finite. Written out rather than
/// taken from `rand_distr` to keep the dependency list short.
fn standard_normal(rng: &mut StdRng) -> f64 {
    let u1 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// The members' initial states: (q0, p0) plus σ times standard normal deviates.
pub fn perturbed_members(q0: &[f64], p0: &[f64], options: &EnsembleOptions) -> Result<Vec<Member>> {
    options.validate()?;
    galerkin_vi::error::ensure_finite("initial position q0", q0)?;
    galerkin_vi::error::ensure_finite("initial momentum p0", p0)?;
    Ok((0..options.count)
        .map(|i| {
            let seed = member_seed(options.seed, i);
            let mut rng = StdRng::seed_from_u64(seed);
            let mut norm2 = 0.0;
            let mut perturb = |x: &[f64]| -> Vec<f64> {
                x.iter()
                    .map(|&v| {
                        let d = options.sigma * standard_normal(&mut rng);
                        norm2 += d * d;
                        v + d
                    })
                    .collect()
            };
            let q = perturb(q0);
            let p = perturb(p0);
            Member {
                member: i,
                seed,
                q0: q,
                p0: p,
                perturbation_norm: norm2.sqrt(),
            }
        })
        .collect())
}

/// What one member's run measured.
#[derive(Debug, Clone, PartialEq)]
pub struct MemberResult {
    /// Index in the ensemble.
    pub member: usize,
    /// The seed of its perturbation.
    pub seed: u64,
    /// Norm of its initial perturbation.
    pub perturbation_norm: f64,
    /// Steps completed (the requested number unless the run failed).
    pub steps_completed: usize,
    /// Final position.
    pub q: Vec<f64>,
    /// Final momentum.
    pub p: Vec<f64>,
    /// max_k |E_k − E_0| over [`energy_scale`](Self::energy_scale) (NaN when the system has
    /// no energy invariant or the scale is 0).
    pub max_relative_energy_error: f64,
    /// The scale of the relative energy error and how it was taken (T₀ + |V₀| at the member's
    /// start, or |E₀|: [`crate::energy`]); `None` without an energy invariant.
    pub energy_scale: Option<(&'static str, f64)>,
    /// max_k |J_k − J_0| for each momentum map of the system's symmetries.
    pub momentum_errors: Vec<f64>,
    /// Largest-Lyapunov-exponent estimate ln(‖Φ_N‖_F / ‖I‖_F) / T.
    pub lyapunov: f64,
    /// The error that stopped the run early, if any.
    pub failure: Option<String>,
}

/// Integrate one member for `steps` steps, measuring invariants and the tangent map.
/// A Newton failure is recorded in [`MemberResult::failure`] with the figures of the steps
/// before it; invalid input (a wrong dimension) is an `Err`.
pub fn run_member<S: System, B: Basis, Q: Quadrature>(
    gvi: &GalerkinIntegrator<B, Q>,
    system: &S,
    symmetries: &[NamedMomentumMap],
    member: &Member,
    steps: usize,
) -> Result<MemberResult> {
    let d = system.dim();
    galerkin_vi::error::ensure_len("initial position q0", d, member.q0.len())?;
    galerkin_vi::error::ensure_len("initial momentum p0", d, member.p0.len())?;
    let mut ws = gvi.workspace(system)?;
    let energy_index = system.invariant_names().iter().position(|n| *n == "energy");
    let mut inv = vec![0.0; system.invariant_names().len()];
    let mut xi = vec![0.0; d];
    let momentum = |map: &NamedMomentumMap, q: &[f64], p: &[f64], xi: &mut [f64]| {
        map.map.generator(q, xi);
        p.iter().zip(xi.iter()).map(|(a, b)| a * b).sum::<f64>()
    };
    let (mut q, mut p) = (member.q0.clone(), member.p0.clone());
    system.invariants(&q, &p, &mut inv);
    let e0 = energy_index.map(|i| inv[i]);
    let energy_scale = e0.map(|e0| crate::energy::energy_scale(system, &q, &p, e0));
    let j0: Vec<f64> = symmetries
        .iter()
        .map(|s| momentum(s, &q, &p, &mut xi))
        .collect();
    let mut energy_error = 0.0f64;
    let mut momentum_errors = vec![0.0f64; symmetries.len()];
    let d2 = 2 * d;
    let mut tangent = DMatrix::<f64>::identity(d2, d2) / (d2 as f64).sqrt();
    let mut product = DMatrix::<f64>::zeros(d2, d2);
    // Everything the step loop touches is allocated here: the loop allocates nothing
    // (`the_member_step_loop_allocates_nothing` in lab/tests/ensemble.rs).
    let mut tws = gvi.tangent_workspace(system)?;
    let mut jac = DMatrix::<f64>::zeros(d2, d2);
    let (mut q_next, mut p_next) = (vec![0.0; d], vec![0.0; d]);
    let mut log_growth = 0.0;
    // A start that overflows (σ = 1e300) has no meaningful errors: a failure, not zeros.
    let start_values = q.iter().chain(&p).chain(&inv).chain(&j0);
    let mut failure = start_values.clone().any(|x| !x.is_finite()).then(|| {
        let bad = start_values
            .copied()
            .find(|x| !x.is_finite())
            .unwrap_or(f64::NAN);
        format!("the perturbed initial state or its invariants are not finite ({bad})")
    });
    let mut completed = 0;
    let steps = if failure.is_some() {
        energy_error = f64::NAN;
        momentum_errors.fill(f64::NAN);
        0
    } else {
        steps
    };
    for k in 0..steps {
        let next = (&mut q_next[..], &mut p_next[..]);
        if let Err(e) = gvi.step_jacobian_into(system, &mut ws, &mut tws, &q, &p, next, &mut jac, k)
        {
            failure = Some(e.to_string());
            break;
        }
        product.gemm(1.0, &jac, &tangent, 0.0);
        std::mem::swap(&mut tangent, &mut product);
        std::mem::swap(&mut q, &mut q_next);
        std::mem::swap(&mut p, &mut p_next);
        completed = k + 1;
        if completed % RENORMALISE_EVERY == 0 {
            let s = tangent.norm();
            log_growth += s.ln();
            tangent /= s;
        }
        system.invariants(&q, &p, &mut inv);
        if let (Some(i), Some(e0)) = (energy_index, e0) {
            energy_error = nan_max(energy_error, (inv[i] - e0).abs());
        }
        for ((err, s), j0) in momentum_errors.iter_mut().zip(symmetries).zip(&j0) {
            *err = nan_max(*err, (momentum(s, &q, &p, &mut xi) - j0).abs());
        }
    }
    let time = completed as f64 * gvi.step_size();
    let lyapunov = if completed == 0 {
        f64::NAN
    } else {
        (log_growth + tangent.norm().ln()) / time
    };
    let max_relative_energy_error = match energy_scale {
        Some((_, scale)) => crate::energy::relative_energy_error(energy_error, scale),
        None => f64::NAN,
    };
    Ok(MemberResult {
        member: member.member,
        seed: member.seed,
        perturbation_norm: member.perturbation_norm,
        steps_completed: completed,
        q,
        p,
        max_relative_energy_error,
        energy_scale,
        momentum_errors,
        lyapunov,
        failure,
    })
}

/// Mean, standard deviation (n − 1), minimum and maximum of one quantity over the members
/// that completed their run.
#[derive(Debug, Clone, PartialEq)]
pub struct Statistic {
    /// The quantity (a CSV column name).
    pub quantity: String,
    /// Members counted (finite values of completed runs).
    pub count: usize,
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation (0 for one member, NaN for none).
    pub std: f64,
    /// Minimum.
    pub min: f64,
    /// Maximum.
    pub max: f64,
}

impl Statistic {
    /// The statistics of `values` (non-finite values are left out).
    pub fn of(quantity: &str, values: impl IntoIterator<Item = f64>) -> Statistic {
        let v: Vec<f64> = values.into_iter().filter(|x| x.is_finite()).collect();
        let n = v.len();
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = match n {
            0 => f64::NAN,
            1 => 0.0,
            _ => v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64,
        };
        // With no finite value every statistic is NaN (not ±∞ from an empty fold).
        let extreme = |f: fn(f64, f64) -> f64| v.iter().copied().reduce(f).unwrap_or(f64::NAN);
        Statistic {
            quantity: quantity.to_string(),
            count: n,
            mean,
            std: var.sqrt(),
            min: extreme(f64::min),
            max: extreme(f64::max),
        }
    }
}

/// An ensemble's results: one [`MemberResult`] per member, in member order.
#[derive(Debug, Clone, PartialEq)]
pub struct Ensemble {
    /// System name.
    pub system: String,
    /// Method description.
    pub method: String,
    /// Steps per member.
    pub steps: usize,
    /// Step size.
    pub h: f64,
    /// Configuration dimension D.
    pub dim: usize,
    /// Names of the 2D state components, coordinates then momenta
    /// ([`crate::names::state_columns`]: `q0, …, p0, …`, or an expression Lagrangian's own
    /// `theta, …, p_theta, …`).
    pub state_names: Vec<String>,
    /// Names of the momentum maps, in the order of [`MemberResult::momentum_errors`].
    pub momentum_names: Vec<String>,
    /// The members' results.
    pub members: Vec<MemberResult>,
}

impl Ensemble {
    /// The CSV header: member, seed, perturbation norm, steps completed, final q and p, the
    /// invariant errors and the Lyapunov estimate.
    pub fn columns(&self) -> Vec<String> {
        let mut c: Vec<String> = ["member", "seed", "perturbation_norm", "steps_completed"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        c.extend(self.state_names.iter().cloned());
        c.push("max_rel_energy_error".into());
        c.extend(self.momentum_names.iter().map(|n| format!("max_{n}_error")));
        c.push("lyapunov".into());
        c
    }

    /// One row per member (final q and p at full precision, as [`crate::table::number`]
    /// writes them: the file is reproducible byte for byte from the seed, and reads back bit
    /// for bit; the NaN errors of a failed member are written `NaN`).
    pub fn to_csv(&self) -> String {
        let mut out = self.columns().join(",");
        out.push('\n');
        for m in &self.members {
            let _ = write!(
                out,
                "{},{},{},{}",
                m.member,
                m.seed,
                crate::table::number(m.perturbation_norm),
                m.steps_completed
            );
            for x in
                m.q.iter()
                    .chain(&m.p)
                    .chain(std::iter::once(&m.max_relative_energy_error))
                    .chain(&m.momentum_errors)
                    .chain(std::iter::once(&m.lyapunov))
            {
                // A failed member's errors are a visible NaN, not an empty cell.
                match x.is_nan() {
                    true => out.push_str(",NaN"),
                    false => {
                        let _ = write!(out, ",{}", crate::table::number(*x));
                    }
                }
            }
            out.push('\n');
        }
        out
    }

    /// The members whose run completed.
    pub fn completed(&self) -> impl Iterator<Item = &MemberResult> {
        self.members.iter().filter(|m| m.failure.is_none())
    }

    /// Statistics of the invariant errors and of the Lyapunov estimates over the completed
    /// members.
    pub fn summary(&self) -> Vec<Statistic> {
        let mut s = vec![Statistic::of(
            "max_rel_energy_error",
            self.completed().map(|m| m.max_relative_energy_error),
        )];
        for (i, name) in self.momentum_names.iter().enumerate() {
            s.push(Statistic::of(
                &format!("max_{name}_error"),
                self.completed().map(|m| m.momentum_errors[i]),
            ));
        }
        s.push(Statistic::of(
            "lyapunov",
            self.completed().map(|m| m.lyapunov),
        ));
        s
    }

    /// [`summary`](Self::summary) as CSV (quantity, count, mean, std, min, max).
    pub fn summary_csv(&self) -> String {
        let mut out = String::from("quantity,count,mean,std,min,max\n");
        for s in self.summary() {
            let _ = writeln!(
                out,
                "{},{},{:e},{:e},{:e},{:e}",
                s.quantity, s.count, s.mean, s.std, s.min, s.max
            );
        }
        out
    }
}

impl std::fmt::Display for Ensemble {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let failed = self.members.len() - self.completed().count();
        writeln!(
            f,
            "{}: {}, {} members × {} steps (T = {}), {failed} failed",
            self.system,
            self.method,
            self.members.len(),
            self.steps,
            self.steps as f64 * self.h
        )?;
        writeln!(
            f,
            "  {:<28} {:>10} {:>10} {:>10} {:>10}",
            "quantity", "mean", "std", "min", "max"
        )?;
        for s in self.summary() {
            writeln!(
                f,
                "  {:<28} {:>10.3e} {:>10.3e} {:>10.3e} {:>10.3e}",
                s.quantity, s.mean, s.std, s.min, s.max
            )?;
        }
        // Say what the relative energy error is relative to (all members share the label
        // unless a member's T₀ + |V₀| is not a positive number).
        if let Some((label, _)) = self.members.iter().find_map(|m| m.energy_scale) {
            writeln!(
                f,
                "  max_rel_energy_error = max_k |E_k − E_0| / ({label} at each member's start)"
            )?;
        }
        writeln!(f, "  {}", lyapunov_note(self.steps as f64 * self.h))?;
        if let Some(m) = self.members.iter().find(|m| m.failure.is_some()) {
            write!(
                f,
                "  first failure (member {}): {}",
                m.member,
                m.failure.as_deref().unwrap_or("")
            )?;
        }
        Ok(())
    }
}

/// How to read a finite-time Lyapunov estimate over the time span `t`, one line: printed
/// beside the estimates (`gvi ensemble`).
///
/// ```
/// let note = galerkin_vi_lab::ensemble::lyapunov_note(100.0);
/// assert!(note.contains("ln(T)/T = 4.605e-2"), "{note}");
/// ```
pub fn lyapunov_note(t: f64) -> String {
    format!(
        "lyapunov is a finite-time estimate ln(growth of the tangent map)/T at T = {}: for a \
         regular orbit it decays like ln(T)/T = {:.3e}; a positive value means chaos only if it \
         stays constant as T grows (rerun with more --steps)",
        crate::error::fmt_number(t),
        t.ln() / t
    )
}

/// Run every member of an ensemble of `scene` in parallel on the current rayon pool (call it
/// inside [`rayon::ThreadPool::install`] to choose the threads), advancing `progress` by one
/// per member. The results are in member order and do not depend on the number of threads.
pub fn run_ensemble(
    scene: &BuiltScene,
    options: &EnsembleOptions,
    progress: Option<&ProgressBar>,
) -> Result<Ensemble> {
    let members = perturbed_members(&scene.initial.q, &scene.initial.p, options)?;
    run_members(scene, &members, progress)
}

/// Run the given members (e.g. a subset of [`perturbed_members`]) in parallel.
pub fn run_members(
    scene: &BuiltScene,
    members: &[Member],
    progress: Option<&ProgressBar>,
) -> Result<Ensemble> {
    let m = &scene.method;
    m.require_fixed_n("an ensemble (its tangent map is that of one fixed-n method)")?;
    let system = scene.euclidean()?;
    let gvi = m.integrator()?;
    let symmetries = system.symmetries();
    let results = members
        .par_iter()
        .map(|member| {
            let r = run_member(&gvi, system, &symmetries, member, m.steps);
            if let Some(pb) = progress {
                pb.inc(1);
            }
            r
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Ensemble {
        system: system.name().to_string(),
        method: format!(
            "{} basis, n = {}, {}, h = {}",
            gvi.basis().name(),
            gvi.n(),
            gvi.quadrature().name(),
            gvi.step_size()
        ),
        steps: m.steps,
        h: m.h,
        dim: system.dim(),
        state_names: crate::names::state_columns(system),
        momentum_names: symmetries.iter().map(|s| s.name.clone()).collect(),
        members: results,
    })
}
