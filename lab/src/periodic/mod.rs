//! The periodic-orbit analysis of a scene (`gvi periodic`): solve the scene's `[periodic]`
//! problem with [`galerkin_vi::periodic`], refine in K, compute the Floquet multipliers and run a
//! closing check, and draws its charts.
//!
//! The solver itself (Fourier curves, the action, Newton, Floquet multipliers) is the
//! library's [`galerkin_vi::periodic`], re-exported here; this module adds what a scene needs:
//! the problem layout and symmetries from the scene's bodies, refinement in K with its fitted
//! rate, the closing run over many periods, and the report and charts. The guide's page on
//! periodic orbits (docs/guide/periodic-orbits.md) has the measured results.

mod report;

use crate::error::LabError;
use crate::error::{GviError, Result};
use crate::scene::BuiltScene;
use galerkin_vi::lagrangian::Lagrangian;
pub use galerkin_vi::periodic::*;
use galerkin_vi::systems::System;
use serde::Serialize;

/// What to compute for a scene's periodic orbit.
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicRequest {
    /// The modes K of the main solve (default: the scene's); with several, the largest is
    /// the main solve and the others form the refinement in K.
    pub modes: Vec<usize>,
    /// Newton settings.
    pub options: PeriodicOptions,
    /// Periods of the closing run with the time-stepping integrator (0: skip).
    pub periods: usize,
    /// Compute the monodromy and its multipliers.
    pub floquet: bool,
    /// Samples of the orbit table.
    pub samples: usize,
}

impl Default for PeriodicRequest {
    fn default() -> Self {
        PeriodicRequest {
            modes: Vec::new(),
            options: PeriodicOptions {
                tail_tolerance: Some(1e-6),
                ..PeriodicOptions::default()
            },
            periods: 100,
            floquet: true,
            samples: 200,
        }
    }
}

/// One row of the refinement in K.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RefinementRow {
    /// Modes K.
    pub modes: usize,
    /// Period found.
    pub period: f64,
    /// Action.
    pub action: f64,
    /// Newton residual.
    pub residual: f64,
    /// Max Euler–Lagrange residual along the truncated series.
    pub equation_residual: f64,
    /// |T_K − T_Kmax| (energy condition) or |S_K − S_Kmax| (fixed period).
    pub difference: f64,
}

/// The time-stepping run from the orbit found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Closing {
    /// Periods integrated.
    pub periods: usize,
    /// Steps per period.
    pub steps_per_period: usize,
    /// Basis functions per step.
    pub n: usize,
    /// max-norm |q(1·T) − q(0)| after one period.
    pub position_distance_one_period: f64,
    /// max-norm |q(periods·T) − q(0)|.
    pub position_distance: f64,
    /// max-norm |p(periods·T) − p(0)|.
    pub momentum_distance: f64,
}

/// Everything `gvi periodic` reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PeriodicReport {
    /// Scene name.
    pub scene: String,
    /// Orbit or choreography.
    pub kind: String,
    /// Modes K of the main solve.
    pub modes: usize,
    /// Trapezoid nodes.
    pub nodes: usize,
    /// Period found (or fixed).
    pub period: f64,
    /// The published period, if the scene gives one.
    pub reference_period: Option<f64>,
    /// Mean energy over the nodes.
    pub energy: f64,
    /// Max − min of the energy over the nodes.
    pub energy_spread: f64,
    /// Prescribed energy (energy condition).
    pub target_energy: Option<f64>,
    /// Action over one period.
    pub action: f64,
    /// Newton residual (max-norm of the gradient).
    pub residual: f64,
    /// Newton iterations.
    pub iterations: usize,
    /// Residual before each Newton step and at the end.
    pub residual_history: Vec<f64>,
    /// Max Euler–Lagrange residual along the series.
    pub equation_residual: f64,
    /// Size of the last two modes relative to the largest.
    pub tail: f64,
    /// The invariants of the system at (q0, p0), by name (energy, momenta, angular momentum).
    pub invariants: Vec<(String, f64)>,
    /// Angular momentum at (q0, p0), when the system has one.
    pub angular_momentum: Option<f64>,
    /// Configuration at t = 0.
    pub q0: Vec<f64>,
    /// Momentum at t = 0.
    pub p0: Vec<f64>,
    /// Floquet multipliers [re, im], trivial ones (closest to 1) first.
    pub multipliers: Vec<[f64; 2]>,
    /// Number of multipliers within [`floquet::TRIVIAL_TOLERANCE`] of 1.
    pub trivial_multipliers: usize,
    /// Expected number of trivial multipliers: 2 per continuous symmetry (time shift,
    /// translations, rotations).
    pub expected_trivial_multipliers: usize,
    /// max | |λ| − 1 |.
    pub max_modulus_defect: Option<f64>,
    /// Symplecticity defect of the monodromy.
    pub monodromy_symplecticity_defect: Option<f64>,
    /// The closing run.
    pub closing: Option<Closing>,
    /// The refinement in K (empty without several `--modes`).
    pub refinement: Vec<RefinementRow>,
    /// Geometric fit of the Euler–Lagrange residual against K.
    pub refinement_fit: Option<crate::fit::GeometricFit>,
    /// Orbit samples: times.
    pub t: Vec<f64>,
    /// Orbit samples: configurations.
    pub q: Vec<Vec<f64>>,
    /// Orbit samples: momenta.
    pub p: Vec<Vec<f64>>,
    /// Body dimension for plotting (2 or 3 for N bodies, None otherwise).
    #[serde(skip)]
    pub body_dim: Option<usize>,
    /// Names of the state components for the CSV header and the chart: coordinates, then
    /// momenta ([`crate::names::state_columns`]; `theta, p_theta` for an expression
    /// Lagrangian).
    #[serde(skip)]
    pub state_names: Vec<String>,
}

/// Solve a built scene's periodic problem and analyse the orbit found.
pub fn analyse_scene(scene: &BuiltScene, request: &PeriodicRequest) -> Result<PeriodicReport> {
    analyse(scene.euclidean()?, scene, request)
}

/// The layout, symmetries and body dimension of a scene's periodic problem.
pub fn problem_of(
    scene: &BuiltScene,
    spec: &PeriodicSpec,
) -> Result<(Layout, Vec<Symmetry>, Option<usize>)> {
    let nbody = scene.euclidean()?.as_nbody();
    let (layout, symmetries, body_dim) = match (nbody, spec.kind) {
        (Some(nb), kind) => {
            let layout = if kind == CurveKind::Choreography {
                let m0 = nb.masses()[0];
                if nb.masses().iter().any(|&m| m != m0) {
                    return Err(LabError::InvalidArgument {
                        name: "[periodic] kind".into(),
                        reason: "a choreography needs equal masses".into(),
                    });
                }
                Layout::Choreography {
                    bodies: nb.bodies(),
                    body_dim: nb.body_dim(),
                }
            } else {
                Layout::Orbit {
                    dim: nb.bodies() * nb.body_dim(),
                }
            };
            (layout, Symmetry::nbody(nb.body_dim()), Some(nb.body_dim()))
        }
        (None, CurveKind::Choreography) => {
            return Err(LabError::InvalidArgument {
                name: "[periodic] kind".into(),
                reason: "choreographies need an N-body system".into(),
            });
        }
        (None, CurveKind::Orbit) => (
            Layout::Orbit {
                dim: scene.initial.q.len(),
            },
            vec![Symmetry::TimeShift],
            None,
        ),
    };
    Ok((layout, symmetries, body_dim))
}

/// The largest number of Fourier modes K of a solve (`--modes` and the scene's
/// `[periodic] modes` alike): the solve holds dense tables of (nodes × (2K + 1)) values and a
/// Jacobian of ((2K + 1)·d)² values.
pub const MAX_MODES: usize = 4096;

/// The one range check of a number of Fourier modes, for `--modes` and the scene's
/// `[periodic] modes` alike: 1 ≤ K ≤ [`MAX_MODES`].
pub fn check_modes(k: usize) -> std::result::Result<usize, String> {
    if (1..=MAX_MODES).contains(&k) {
        Ok(k)
    } else {
        Err(format!("K must be an integer in 1..={MAX_MODES}, got {k}"))
    }
}

/// The scene's `[periodic]` values checked as the flags are: `modes` by [`check_modes`],
/// `steps` ≥ 1 and `n` ≥ 2 when given. Errors name the scene key, not a flag.
fn check_spec(scene: &BuiltScene, spec: &PeriodicSpec) -> Result<()> {
    let bad = |key: &str, reason: String| LabError::Scene {
        source_name: scene.name.clone(),
        reason: format!("[periodic] {key}: {reason}"),
    };
    check_modes(spec.modes).map_err(|r| bad("modes", r))?;
    if spec.steps == Some(0) {
        return Err(bad(
            "steps",
            "0 steps per period: need at least 1 (omit the key for the scene's steps)".into(),
        ));
    }
    if let Some(n) = spec.n.filter(|&n| n < 2) {
        return Err(bad(
            "n",
            format!("{n} basis functions: need at least 2 (omit the key for the scene's n)"),
        ));
    }
    Ok(())
}

/// The memory of a periodic analysis at `kmax` modes, estimated before it runs: the solve's
/// basis tables (two of nodes × (2K + 1) values per shift class) and its dense Jacobian with
/// its factorisation (three matrices of ((2K + 1)·components)² values), and the closing run
/// (steps per period × periods, kept whole), checked against [`crate::memory::LIMIT_BYTES`].
fn ensure_memory(
    scene: &BuiltScene,
    spec: &PeriodicSpec,
    layout: &Layout,
    kmax: usize,
    request: &PeriodicRequest,
) -> Result<()> {
    let nb = (2 * kmax + 1) as f64;
    let nodes = spec
        .nodes
        .or(request.options.nodes)
        .unwrap_or_else(|| default_nodes(layout, kmax)) as f64;
    let classes = match *layout {
        Layout::Choreography { bodies, .. } => bodies,
        Layout::Orbit { .. } => 1,
    } as f64;
    let unknowns = nb * layout.components() as f64 + 2.0;
    let solve = 8.0 * (2.0 * classes * nodes * nb + 3.0 * unknowns * unknowns);
    let steps = spec.steps.unwrap_or(scene.method.steps) as f64;
    let n = spec.n.unwrap_or(scene.method.n);
    let closing =
        steps * request.periods as f64 * crate::memory::trajectory_bytes_per_step(n, layout.dim());
    crate::memory::ensure_fits(
        format!(
            "the periodic analysis at K = {kmax} modes with {} closing periods",
            request.periods
        ),
        solve + closing,
        "fewer modes (--modes or the scene's [periodic] modes) or fewer --periods",
    )
}

/// The scene's `[periodic]` table, or a typed error naming the scene.
pub fn spec_of(scene: &BuiltScene) -> Result<&PeriodicSpec> {
    scene.periodic().ok_or_else(|| LabError::Scene {
        source_name: scene.name.clone(),
        reason: "no [periodic] table (periodic data and initial guess); see \
                 docs/guide/periodic-orbits.md"
            .into(),
    })
}

fn energy_index<S: System>(system: &S) -> Option<usize> {
    system.invariant_names().iter().position(|n| *n == "energy")
}

/// [`analyse_scene`] for the scene's own system.
fn analyse<S: System>(
    system: &S,
    scene: &BuiltScene,
    request: &PeriodicRequest,
) -> Result<PeriodicReport> {
    let spec = spec_of(scene)?;
    let (layout, symmetries, body_dim) = problem_of(scene, spec)?;
    check_spec(scene, spec)?;
    let mut modes_list = request.modes.clone();
    if modes_list.is_empty() {
        modes_list.push(spec.modes);
    }
    for &k in &modes_list {
        check_modes(k).map_err(|reason| LabError::InvalidArgument {
            name: "--modes".into(),
            reason,
        })?;
    }
    modes_list.sort_unstable();
    modes_list.dedup();
    let kmax = *modes_list.last().unwrap_or(&spec.modes);
    ensure_memory(scene, spec, &layout, kmax, request)?;
    let mut names = system.invariant_names().iter();
    let mut inv = vec![0.0; system.invariant_names().len()];
    let condition = match spec.condition {
        ConditionKind::Period => PeriodCondition::Fixed,
        ConditionKind::Energy => {
            let e = match spec.energy {
                Some(e) => e,
                None => {
                    // The scene's state was checked against its system when built.
                    system.invariants(&scene.initial.q, &scene.initial.p, &mut inv);
                    let i = energy_index(system).ok_or_else(|| {
                        GviError::Unsupported("this system reports no energy".into())
                    })?;
                    inv[i]
                }
            };
            PeriodCondition::Energy(e)
        }
    };
    let options = PeriodicOptions {
        nodes: spec.nodes.or(request.options.nodes),
        ..request.options
    };
    let guess = spec.guess_curve(layout.clone(), kmax)?;
    let sol = solve(system, guess, condition, &symmetries, &options)?;
    let curve = &sol.curve;
    let period = curve.period;

    // Refinement in K: each smaller K re-solved from the truncated main solution.
    let mut refinement = Vec::new();
    for &k in &modes_list {
        let row_sol = if k == kmax {
            sol.clone()
        } else {
            let opts = PeriodicOptions {
                nodes: None,
                tail_tolerance: None,
                energy_spread_tolerance: None,
                ..options
            };
            solve(system, curve.with_modes(k)?, condition, &symmetries, &opts)?
        };
        refinement.push(RefinementRow {
            modes: k,
            period: row_sol.curve.period,
            action: row_sol.action,
            residual: row_sol.residual,
            equation_residual: equation_residual(system, &row_sol.curve, 512),
            difference: 0.0,
        });
    }
    for row in &mut refinement {
        row.difference = match condition {
            PeriodCondition::Energy(_) => (row.period - period).abs(),
            PeriodCondition::Fixed => (row.action - sol.action).abs(),
        };
    }
    let refinement_fit = if refinement.len() >= 3 {
        let ks: Vec<f64> = refinement.iter().map(|r| r.modes as f64).collect();
        let es: Vec<f64> = refinement.iter().map(|r| r.equation_residual).collect();
        crate::fit::fit_geometric(&ks, &es).ok()
    } else {
        None
    };
    let equation_res = refinement
        .iter()
        .find(|r| r.modes == kmax)
        .map_or(f64::NAN, |r| r.equation_residual);

    // The state at t = 0 and the orbit table.
    let d = system.dim();
    let (mut q0, mut v0, mut a0) = (vec![0.0; d], vec![0.0; d], vec![0.0; d]);
    curve.state_at(0.0, &mut q0, &mut v0, &mut a0);
    let mut p0 = vec![0.0; d];
    system.legendre_transform(&q0, &v0, &mut p0);
    let samples = request.samples.max(2);
    let (mut ts, mut qs, mut ps) = (Vec::new(), Vec::new(), Vec::new());
    let (mut q, mut v, mut p) = (vec![0.0; d], vec![0.0; d], vec![0.0; d]);
    for i in 0..=samples {
        let t = period * i as f64 / samples as f64;
        curve.state_at(t, &mut q, &mut v, &mut a0);
        system.legendre_transform(&q, &v, &mut p);
        ts.push(t);
        qs.push(q.clone());
        ps.push(p.clone());
    }
    system.invariants(&q0, &p0, &mut inv);
    let invariants: Vec<(String, f64)> = names
        .by_ref()
        .zip(&inv)
        .map(|(n, &x)| ((*n).to_string(), x))
        .collect();
    let angular_momentum = invariants
        .iter()
        .find(|(n, _)| n == "angular_momentum" || n == "lz")
        .map(|(_, x)| *x);

    let steps = spec.steps.unwrap_or(scene.method.steps).max(1);
    let mut method = scene.method.clone();
    method.n = spec.n.unwrap_or(method.n);
    let floquet = if request.floquet {
        Some(monodromy(system, &method, &q0, &p0, period, steps)?)
    } else {
        None
    };
    let closing = if request.periods > 0 {
        Some(closing_run(
            system,
            &method,
            &q0,
            &p0,
            period,
            steps,
            request.periods,
        )?)
    } else {
        None
    };
    let kind = match spec.kind {
        CurveKind::Orbit => "orbit",
        CurveKind::Choreography => "choreography",
    };
    Ok(PeriodicReport {
        state_names: crate::names::state_columns(scene.euclidean()?),
        scene: scene.name.clone(),
        kind: kind.into(),
        modes: kmax,
        nodes: sol.nodes,
        period,
        reference_period: spec.reference_period,
        energy: sol.energy,
        energy_spread: sol.energy_spread,
        target_energy: match condition {
            PeriodCondition::Energy(e) => Some(e),
            PeriodCondition::Fixed => None,
        },
        action: sol.action,
        residual: sol.residual,
        iterations: sol.iterations,
        residual_history: sol.residual_history.clone(),
        equation_residual: equation_res,
        tail: sol.tail,
        invariants,
        angular_momentum,
        q0,
        p0,
        multipliers: floquet
            .as_ref()
            .map_or(Vec::new(), |f| f.multipliers.clone()),
        trivial_multipliers: floquet.as_ref().map_or(0, |f| f.trivial),
        expected_trivial_multipliers: 2 * symmetries.len(),
        max_modulus_defect: floquet.as_ref().map(|f| f.max_modulus_defect),
        monodromy_symplecticity_defect: floquet.as_ref().map(|f| f.symplecticity_defect),
        closing,
        refinement,
        refinement_fit,
        t: ts,
        q: qs,
        p: ps,
        body_dim,
    })
}

/// Integrate `periods` periods from (q0, p0) with the scene's method at h = T/steps and
/// measure how far the end state is from the start.
fn closing_run<L: Lagrangian>(
    lag: &L,
    method: &crate::scene::MethodSpec,
    q0: &[f64],
    p0: &[f64],
    period: f64,
    steps: usize,
    periods: usize,
) -> Result<Closing> {
    let gvi = floquet::integrator_for_period(method, period, steps)?;
    let traj = gvi
        .integrate(lag, 0.0, q0, p0, steps * periods)
        .map_err(|f| f.error)?;
    let dist = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, crate::distance::nan_max)
    };
    let last = traj.q.len() - 1;
    Ok(Closing {
        periods,
        steps_per_period: steps,
        n: method.n,
        position_distance_one_period: dist(&traj.q[steps.min(last)], q0),
        position_distance: dist(&traj.q[last], q0),
        momentum_distance: dist(&traj.p[last], p0),
    })
}
