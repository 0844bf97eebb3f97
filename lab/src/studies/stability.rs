//! `gvi stability`: where each method works, over a grid of step sizes (and, for the Galerkin
//! method, numbers of basis functions).
//!
//! Every Galerkin cell (h, n) runs a fixed number of steps (default 100, so the horizon grows
//! with h) and is classified by the relative energy error max_k |E_k − E₀| / (T₀ + |V₀|) over
//! the run (the scale of `gvi run`, [`crate::energy`]: kinetic plus absolute potential energy
//! at the start, which does not vanish with E₀; |E₀| for a system without a constant mass
//! matrix):
//! - `accurate`: ≤ 10⁻⁶, and (when an exact solution is known) the max-norm position error
//!   at the step ends is ≤ 10⁻⁴·max(1, |q₀|);
//! - `bounded`: at most |E₀| / (T₀ + |V₀|) (the energy did not move by more than itself: a
//!   bound orbit whose energy reaches 0 can escape, and an escaped orbit's error is constant;
//!   1 when E₀ is below 10⁻³ of T₀ + |V₀|, a parabolic orbit) and not growing (the max over
//!   the second half of the run is at most ten times the max over the first half, or below
//!   10⁻³);
//! - `solver failure`: the Newton solve failed (the typed error's message is kept);
//! - `blow-up`: a non-finite state, an energy error above that limit, or a growing one.
//!
//! For the baselines (Störmer–Verlet, RK4, Gauss s = 2, Yoshida-6, Kahan–Li-8) the largest
//! stable h is found by bisection with "bounded" over `baseline_steps` steps as the criterion
//! (doubling from h = 10⁻² to bracket it, then bisecting to a relative width `tolerance`;
//! capped at `h_max`). This assumes one boundary; on non-linear problems it is the first one
//! met from small h.
//!
//! ```
//! use galerkin_vi_lab::scene::Scene;
//! use galerkin_vi_lab::studies::stability::{stability, StabilityConfig};
//! let scene = Scene::load("harmonic").unwrap().build().unwrap();
//! let study = stability(&scene, &StabilityConfig::quick()).unwrap();
//! let verlet = study.baselines.iter().find(|b| b.method == "stormer-verlet").unwrap();
//! assert!((verlet.largest_stable_h - 2.0).abs() < 0.01);
//! ```

use super::peers::{Peer, run_peer};
use super::write_file;
use crate::error::LabError;
use crate::error::Result;
use crate::plot::HeatMap;
use crate::scene::BuiltScene;
use crate::table;
use galerkin_vi::baselines::CompositionScheme;
use galerkin_vi::integrator::GalerkinIntegrator;
use galerkin_vi::systems::System;
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The files [`StabilityStudy::write`] writes into its directory.
pub const FILES: [&str; 4] = [
    "stability.csv",
    "stability_baselines.csv",
    "stability.json",
    "stability.svg",
];

/// The grid and criteria.
#[derive(Debug, Clone, Serialize)]
pub struct StabilityConfig {
    /// Step sizes (the map's columns).
    pub hs: Vec<f64>,
    /// Numbers of basis functions (the map's rows).
    pub ns: Vec<usize>,
    /// Steps per Galerkin cell.
    pub steps: usize,
    /// Steps per baseline stability test.
    pub baseline_steps: usize,
    /// Largest h tried for the baselines.
    pub h_max: f64,
    /// Relative width at which the bisection stops.
    pub tolerance: f64,
}

impl StabilityConfig {
    /// 12 log-spaced h from 0.1 to 100, n = 2, 4, …, 40, 100 steps per cell; baselines over
    /// 2000 steps, h ≤ 1000, bisection to 10⁻³.
    pub fn full() -> Self {
        StabilityConfig {
            hs: (0..12)
                .map(|i| 0.1 * 1000f64.powf(i as f64 / 11.0))
                .collect(),
            ns: (2..=40).step_by(2).collect(),
            steps: 100,
            baseline_steps: 2000,
            h_max: 1000.0,
            tolerance: 1e-3,
        }
    }

    /// A small grid (h = 1, 20; n = 4, 24, 40; 20 steps) for tests.
    pub fn quick() -> Self {
        StabilityConfig {
            hs: vec![1.0, 20.0],
            ns: vec![4, 24, 40],
            steps: 20,
            baseline_steps: 2000,
            h_max: 1000.0,
            tolerance: 1e-3,
        }
    }
}

/// A cell's class.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Class {
    /// Energy (and position, if known) accurate.
    Accurate,
    /// Energy error bounded but not accurate.
    Bounded,
    /// The implicit solve failed.
    SolverFailure,
    /// Non-finite, energy error > 1, or growing.
    BlowUp,
}

impl Class {
    /// All classes in legend order.
    pub const ALL: [Class; 4] = [
        Class::Accurate,
        Class::Bounded,
        Class::SolverFailure,
        Class::BlowUp,
    ];

    /// Label.
    pub fn as_str(self) -> &'static str {
        match self {
            Class::Accurate => "accurate",
            Class::Bounded => "bounded",
            Class::SolverFailure => "solver failure",
            Class::BlowUp => "blow-up",
        }
    }
}

/// One Galerkin cell.
#[derive(Debug, Clone, Serialize)]
pub struct Cell {
    /// Step size.
    pub h: f64,
    /// Basis functions.
    pub n: usize,
    /// Class.
    pub class: Class,
    /// Max relative energy error over the completed steps, over
    /// [`StabilityStudy::energy_scale`].
    pub energy_error: f64,
    /// Max position error at the step ends, if an exact solution is known.
    pub position_error: Option<f64>,
    /// The solver's error message.
    pub message: Option<String>,
}

/// A baseline's largest stable step.
#[derive(Debug, Clone, Serialize)]
pub struct BaselineLimit {
    /// Method family.
    pub method: String,
    /// Largest h found stable (0 if even h = 10⁻² is not).
    pub largest_stable_h: f64,
    /// Smallest h found unstable (∞ if stable up to `h_max`).
    pub smallest_unstable_h: f64,
}

/// The result of a stability study.
#[derive(Debug, Clone, Serialize)]
pub struct StabilityStudy {
    /// Scene name.
    pub scene: String,
    /// The grid and criteria.
    pub config: StabilityConfig,
    /// Cells, row-major over (n, h).
    pub cells: Vec<Cell>,
    /// The baselines' limits.
    pub baselines: Vec<BaselineLimit>,
    /// The scale of the cells' relative energy errors: how it was taken (`T₀ + |V₀|` or
    /// `|E₀|`, [`crate::energy`]) and its value at the scene's initial state; `None` without
    /// an energy invariant.
    pub energy_scale: Option<(String, f64)>,
}

/// Run the stability study.
pub fn stability(scene: &BuiltScene, config: &StabilityConfig) -> Result<StabilityStudy> {
    if config.hs.is_empty() || config.ns.is_empty() || config.steps == 0 {
        return Err(LabError::InvalidArgument {
            name: "stability grid".into(),
            reason: "needs at least one h, one n and one step".into(),
        });
    }
    let total = (config.hs.len() * config.ns.len()) as f64 * config.steps as f64;
    let limit = super::work_precision::MAX_TOTAL_STEPS;
    if total > limit {
        return Err(LabError::CostTooHigh {
            what: format!(
                "the total number of integration steps ({} cells × {} steps per cell; lower \
                 --cell-steps)",
                config.hs.len() * config.ns.len(),
                config.steps
            ),
            estimate: total,
            limit,
        });
    }
    let max_n = config.ns.iter().copied().max().unwrap_or(0);
    super::refuse_memory(config.steps as f64, max_n, scene.initial.q.len())?;
    let system = scene.euclidean()?;
    study_system(system, scene, config)
}

fn study_system<S: System + Sync + 'static>(
    system: &S,
    scene: &BuiltScene,
    config: &StabilityConfig,
) -> Result<StabilityStudy> {
    let grid: Vec<(usize, f64)> = config
        .ns
        .iter()
        .flat_map(|&n| config.hs.iter().map(move |&h| (n, h)))
        .collect();
    let baselines = [
        Peer::StormerVerlet,
        Peer::Rk4,
        Peer::Gauss { s: 2 },
        Peer::Composition {
            scheme: CompositionScheme::Yoshida6,
        },
        Peer::Composition {
            scheme: CompositionScheme::KahanLi8,
        },
    ];
    let pb = crate::progress::bar(grid.len() + baselines.len(), "stability");
    let cells: Vec<Cell> = grid
        .par_iter()
        .map(|&(n, h)| {
            let c = galerkin_cell(system, scene, n, h, config.steps);
            pb.inc(1);
            c
        })
        .collect();
    // The classical baselines need L = ½ vᵀ M v − V(q): none for a non-separable Lagrangian.
    let baselines = match system.mass_matrix() {
        Some(_) => &baselines[..],
        None => &[],
    };
    let limits: Vec<BaselineLimit> = baselines
        .par_iter()
        .map(|&peer| {
            let l = largest_stable_h(system, scene, peer, config);
            pb.inc(1);
            l
        })
        .collect();
    pb.finish_and_clear();
    let init = &scene.initial;
    Ok(StabilityStudy {
        scene: scene.name.clone(),
        config: config.clone(),
        cells,
        baselines: limits,
        energy_scale: energy_reference(system, &init.q, &init.p)
            .map(|(_, label, scale)| (label.to_string(), scale)),
    })
}

/// The position of the `energy` invariant, E₀ and the scale of relative energy errors at
/// (q0, p0) ([`crate::energy::energy_scale`]); `None` without an energy invariant.
fn energy_reference<S: System>(
    system: &S,
    q0: &[f64],
    p0: &[f64],
) -> Option<(usize, &'static str, f64)> {
    let index = system
        .invariant_names()
        .iter()
        .position(|n| *n == "energy")?;
    let mut inv = vec![0.0; system.invariant_names().len()];
    system.invariants(q0, p0, &mut inv);
    let (label, scale) = crate::energy::energy_scale(system, q0, p0, inv[index]);
    Some((index, label, scale))
}

/// What [`classify`] reads off a run's energy.
#[derive(Debug, Clone, Copy)]
struct EnergyProfile {
    /// Max relative energy error over the states (over T₀ + |V₀| at the first state:
    /// [`crate::energy`]).
    worst: f64,
    /// Whether it grows (second half > 10 × first half and above 10⁻³).
    growing: bool,
    /// The largest relative error a bounded run may have: |E₀| / (T₀ + |V₀|), an energy that
    /// moved by more than itself (for a bound orbit, E reached 0: it can escape, and an
    /// escaped orbit keeps a constant, "bounded" error); 1 where E₀ is negligible against
    /// its terms (below 10⁻³ of T₀ + |V₀|: a parabolic orbit, which has no such limit).
    /// With T₀ + |V₀| = |E₀| (V ≥ 0, the oscillator) it is 1 either way.
    limit: f64,
}

/// The [`EnergyProfile`] of a run's states.
fn energy_profile<S: System>(system: &S, q: &[Vec<f64>], p: &[Vec<f64>]) -> EnergyProfile {
    let none = EnergyProfile {
        worst: f64::NAN,
        growing: false,
        limit: 1.0,
    };
    if q.is_empty() {
        return none;
    }
    let Some((index, _, scale)) = energy_reference(system, &q[0], &p[0]) else {
        return none;
    };
    let mut inv = vec![0.0; system.invariant_names().len()];
    system.invariants(&q[0], &p[0], &mut inv);
    let e0 = inv[index];
    // A zero scale (no motion and no potential) leaves the absolute error: still 0 for a
    // run that stays put, and a blow-up still shows.
    let scale = scale.max(1e-300);
    let half = q.len() / 2;
    let (mut first, mut second) = (0.0f64, 0.0f64);
    for k in 0..q.len() {
        system.invariants(&q[k], &p[k], &mut inv);
        let e = (inv[index] - e0).abs() / scale;
        let e = if e.is_finite() { e } else { f64::INFINITY };
        if k <= half {
            first = first.max(e);
        } else {
            second = second.max(e);
        }
    }
    let worst = first.max(second);
    let own = e0.abs() / scale;
    EnergyProfile {
        worst,
        growing: second > 1e-3 && second > 10.0 * first,
        limit: if own >= 1e-3 { own.min(1.0) } else { 1.0 },
    }
}

fn classify(profile: EnergyProfile, position_ok: bool) -> Class {
    let EnergyProfile {
        worst: energy,
        growing,
        limit,
    } = profile;
    if !energy.is_finite() || energy > limit || growing {
        Class::BlowUp
    } else if energy <= 1e-6 && position_ok {
        Class::Accurate
    } else {
        Class::Bounded
    }
}

fn galerkin_cell<S: System>(
    system: &S,
    scene: &BuiltScene,
    n: usize,
    h: f64,
    steps: usize,
) -> Cell {
    let init = &scene.initial;
    let m = &scene.method;
    let mut cell = Cell {
        h,
        n,
        class: Class::SolverFailure,
        energy_error: f64::NAN,
        position_error: None,
        message: None,
    };
    let gvi = match GalerkinIntegrator::from_kinds(m.basis, n, m.quadrature, None, h) {
        Ok(g) => g,
        Err(e) => {
            cell.message = Some(e.to_string());
            return cell;
        }
    };
    let traj = match gvi.integrate(system, init.t0, &init.q, &init.p, steps) {
        Ok(t) => t,
        Err(f) => {
            cell.message = Some(f.error.to_string());
            if let Some(p) = f.partial {
                cell.energy_error = energy_profile(system, &p.q, &p.p).worst;
            }
            return cell;
        }
    };
    let profile = energy_profile(system, &traj.q, &traj.p);
    cell.energy_error = profile.worst;
    if let Ok(Some(exact)) = system.exact_solution(init.t0, &init.q, &init.p) {
        let err = (0..traj.q.len())
            .map(|k| super::max_norm_diff(&traj.q[k], &exact.position(traj.time(k))))
            .fold(0.0, super::nan_max);
        cell.position_error = Some(if err.is_finite() { err } else { f64::INFINITY });
    }
    let scale = init.q.iter().fold(1.0f64, |a, x| a.max(x.abs()));
    let position_ok = cell.position_error.is_none_or(|e| e <= 1e-4 * scale);
    cell.class = classify(profile, position_ok);
    cell
}

/// Whether `peer` keeps a bounded energy over `steps` steps of size h.
pub fn bounded_at<S: System + 'static>(
    system: &S,
    scene: &BuiltScene,
    peer: Peer,
    h: f64,
    steps: usize,
) -> bool {
    match run_peer(system, &scene.initial, peer, h, 1, steps) {
        Ok(run) if run.failure.is_none() => {
            let profile = energy_profile(system, &run.q, &run.p);
            matches!(classify(profile, true), Class::Accurate | Class::Bounded)
        }
        _ => false,
    }
}

fn largest_stable_h<S: System + 'static>(
    system: &S,
    scene: &BuiltScene,
    peer: Peer,
    config: &StabilityConfig,
) -> BaselineLimit {
    let ok = |h: f64| bounded_at(system, scene, peer, h, config.baseline_steps);
    let (mut lo, mut hi) = (0.0, 1e-2);
    while hi <= config.h_max && ok(hi) {
        lo = hi;
        hi *= 2.0;
    }
    if hi > config.h_max {
        hi = f64::INFINITY;
    } else if lo > 0.0 {
        while hi - lo > config.tolerance * hi {
            let mid = 0.5 * (lo + hi);
            if ok(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }
    BaselineLimit {
        method: peer.family(),
        largest_stable_h: lo,
        smallest_unstable_h: hi,
    }
}

impl StabilityStudy {
    /// The cell at (n, h), if on the grid.
    pub fn cell(&self, n: usize, h: f64) -> Option<&Cell> {
        self.cells
            .iter()
            .find(|c| c.n == n && (c.h - h).abs() <= 1e-12 * h)
    }

    /// Number of cells in each class, in [`Class::ALL`] order.
    pub fn counts(&self) -> [usize; 4] {
        Class::ALL.map(|k| self.cells.iter().filter(|c| c.class == k).count())
    }

    /// The heat map over (h, n).
    pub fn heat_map(&self) -> HeatMap {
        let cfg = &self.config;
        let cells = cfg
            .ns
            .iter()
            .map(|&n| {
                cfg.hs
                    .iter()
                    .map(|&h| {
                        self.cell(n, h)
                            .and_then(|c| Class::ALL.iter().position(|&k| k == c.class))
                            .unwrap_or(usize::MAX)
                    })
                    .collect()
            })
            .collect();
        HeatMap {
            title: format!(
                "{}: Galerkin stability map ({} steps per cell)",
                self.scene, cfg.steps
            ),
            x_label: "h (step size)".into(),
            y_label: "n (basis functions)".into(),
            x_values: cfg.hs.clone(),
            y_values: cfg.ns.iter().map(|&n| n as f64).collect(),
            x_log: true,
            cells,
            categories: vec![
                ("accurate".into(), (46, 160, 67)),
                ("bounded".into(), (120, 180, 230)),
                ("solver failure".into(), (240, 160, 40)),
                ("blow-up".into(), (200, 40, 40)),
            ],
        }
    }

    /// CSV of the cells.
    pub fn csv(&self) -> Result<String> {
        /// One CSV line of a cell.
        #[derive(Serialize)]
        struct Row<'a> {
            #[serde(serialize_with = "table::sci")]
            h: f64,
            n: usize,
            class: &'a str,
            #[serde(serialize_with = "table::sci")]
            energy_error: f64,
            #[serde(serialize_with = "table::sci_opt")]
            position_error: Option<f64>,
            #[serde(serialize_with = "table::quoted")]
            message: Option<&'a str>,
        }
        table::csv_text(self.cells.iter().map(|c| Row {
            h: c.h,
            n: c.n,
            class: c.class.as_str(),
            energy_error: c.energy_error,
            position_error: c.position_error,
            message: c.message.as_deref(),
        }))
    }

    /// The baselines' limits as CSV.
    pub fn baselines_csv(&self) -> Result<String> {
        /// One CSV line of a baseline's limits.
        #[derive(Serialize)]
        struct Row<'a> {
            method: &'a str,
            #[serde(serialize_with = "table::sci")]
            largest_stable_h: f64,
            #[serde(serialize_with = "table::sci")]
            smallest_unstable_h: f64,
        }
        table::csv_text(self.baselines.iter().map(|b| Row {
            method: &b.method,
            largest_stable_h: b.largest_stable_h,
            smallest_unstable_h: b.smallest_unstable_h,
        }))
    }

    /// Write `stability.{csv,json,svg}` and `stability_baselines.csv` into `dir`.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let [csv, base, json, svg] = FILES.map(|f| dir.join(f));
        write_file(&csv, &self.csv()?)?;
        write_file(&base, &self.baselines_csv()?)?;
        let text =
            serde_json::to_string_pretty(self).map_err(|e| LabError::Serialize(e.to_string()))?;
        write_file(&json, &text)?;
        self.heat_map()
            .save_svg(&svg)
            .map_err(|e| LabError::Plot(e.to_string()))?;
        Ok(vec![csv, base, json, svg])
    }
}
