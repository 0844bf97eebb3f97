//! Accuracy of N-body runs against an independent high-accuracy reference of the same
//! Newtonian point-mass model: what `gvi nbody-report SCENE` writes.
//!
//! The reference is Gauss collocation ([`GaussCollocationBaseline`]) with s = 6 stages (order 12),
//! fixed-point iteration and compensated summation, at a step h/K that divides the Galerkin
//! step (K chosen so that the shortest two-body orbital period of the initial state spans at
//! least 256 reference steps); a second reference at step h/(2K) estimates its error
//! ([`NBodyReport::reference_uncertainty`]).
//!
//! Measured (`gvi nbody-report solar-system`: n = 25, h = 100 days, 100 steps = 27.4 years;
//! reference s = 6, h/220 ≈ 0.45 days, half-step cross-check 4.2e-13 AU): the largest position
//! error is Mercury's, 2.7e-4 AU (its 88-day orbit is shorter than the step), then Venus
//! 8.2e-9, Earth–Moon 9.8e-10, Mars 8.6e-11, the Sun 4.5e-11 AU, and 3e-13 … 3e-12 AU for
//! Jupiter … Pluto; relative energy error 1.6e-10 (over T₀ + |V₀|, [`crate::energy`]); linear
//! and angular momenta conserved to
//! round-off (|ΔJ| ≤ 4 ε √k × scale). Mercury's perihelion longitude drifts from the
//! reference's by up to 1.0e-3 rad (206″) over the run, while the reference (physical,
//! Newtonian planetary perturbations) advances 7.3e-4 rad: the spurious precession is of the
//! size of the physical one, not "almost none". At n = 15 Mercury's error is 0.35 AU (the
//! orbit is lost; its perihelion is off by 1.2 rad); at n = 32 it is 1.8e-6 AU with a
//! perihelion difference of 6.7e-6 rad (1.4″) — there the paper's "almost no precession"
//! holds. The crate's tests assert the bound 1e-3 AU at n = 25 (about 4× the measured value)
//! and that the errors fall from n = 15 to n = 25.
//!
//! `outer-solar-system` (HLW data, n = 25, h = 1825 days, 100 steps = 500 years): Jupiter
//! 5.1e-9 AU, Saturn 9.1e-10, Uranus 7.9e-11, Neptune 2.7e-11, Pluto 3.4e-11; relative energy
//! error 4.5e-15. Linear momentum is conserved to 2e-15 of Σ|pᵢ| (pairwise forces cancel
//! exactly), angular momentum to 1.5e-12 of Σ|qᵢ||pᵢ|: with h = 1825 the stage equations'
//! round-off floor (residual ≈ 1e-18, ε times the Sun's kinetic terms) sets the drift.

mod charts;
mod elements;

use crate::names::unit_suffix;
pub use charts::{ORBIT_SAMPLES_PER_STEP, orbit_charts};
pub use elements::{longitude_of_perihelion, wrap};

use crate::error::LabError;
use crate::error::Result;
use crate::plot::{Chart, Series};
use crate::scene::{BuiltScene, Scene};
use galerkin_vi::baselines::{GaussCollocationBaseline, OneStepMethod};
use galerkin_vi::systems::{NBody, System};
use std::time::Instant;

/// Reference settings for [`nbody_report`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReportOptions {
    /// Gauss collocation stages of the reference (order 2s). Default 6.
    pub stages: usize,
    /// Reference steps per Galerkin step (`None`: automatic, see the module docs).
    pub substeps: Option<usize>,
    /// Also compute the half-step reference to estimate the reference's error. Default true.
    pub cross_check: bool,
}

impl Default for ReportOptions {
    fn default() -> Self {
        ReportOptions {
            stages: 6,
            substeps: None,
            cross_check: true,
        }
    }
}

/// Drift of Mercury's perihelion: the longitude of perihelion ϖ of its osculating orbit about
/// the Sun (μ = G(m_Sun + m_Mercury)), see [`longitude_of_perihelion`].
#[derive(Debug, Clone, PartialEq)]
pub struct PerihelionDrift {
    /// ϖ at every step end of the Galerkin run (radians).
    pub galerkin: Vec<f64>,
    /// ϖ of the reference at the same times.
    pub reference: Vec<f64>,
    /// max_k |ϖ_galerkin(t_k) − ϖ_ref(t_k)| (radians): the integrator's spurious precession.
    pub max_difference: f64,
    /// ϖ_galerkin(t_end) − ϖ_galerkin(0) (radians).
    pub galerkin_advance: f64,
    /// ϖ_ref(t_end) − ϖ_ref(0) (radians): the physical (Newtonian, planetary) precession.
    pub reference_advance: f64,
}

/// The report: per-body position errors at every step end against the reference, errors of
/// the invariants, and Mercury's perihelion drift when the scene has bodies named `Sun` and
/// `Mercury`.
#[derive(Debug)]
pub struct NBodyReport {
    /// The scene run (with any overrides).
    pub scene: Scene,
    /// Body names.
    pub body_names: Vec<String>,
    /// Times t_k of the step ends.
    pub times: Vec<f64>,
    /// Euclidean position error of each body at each step end: `[k][body]`.
    pub position_errors: Vec<Vec<f64>>,
    /// Names of the invariants (`energy`, linear and angular momentum components).
    pub invariant_names: Vec<String>,
    /// Errors of the invariants at each step end, `[k][i]`: relative energy error
    /// |E_k − E_0| / (T₀ + |V₀|) for `energy` (the scale of `gvi run`, [`crate::energy`]),
    /// absolute |J_k − J_0| for the momenta.
    pub invariant_errors: Vec<Vec<f64>>,
    /// Scale of each invariant for relative statements: T₀ + |V₀| for the energy
    /// ([`NBodyReport::energy_scale_label`] says how it was taken), Σᵢ |pᵢ| for the linear
    /// and Σᵢ |qᵢ| |pᵢ| for the angular momentum components.
    pub invariant_scales: Vec<f64>,
    /// How the energy's scale was taken (`T₀ + |V₀|`, or `|E₀|` if that is not positive).
    pub energy_scale_label: String,
    /// Max over step ends of the position difference between the reference and the half-step
    /// reference (`None` without the cross-check).
    pub reference_uncertainty: Option<f64>,
    /// Description of the reference method.
    pub reference: String,
    /// Mercury's perihelion drift, when the scene has `Sun` and `Mercury`.
    pub mercury: Option<PerihelionDrift>,
    /// Mean Newton iterations per Galerkin step.
    pub newton_iterations_per_step: f64,
    /// Wall-clock seconds of the Galerkin run and of the reference(s).
    pub seconds: (f64, f64),
    /// The orbit chart and the inner-bodies chart of the Galerkin run.
    pub orbit_charts: (Chart, Option<Chart>),
}

/// The files [`NBodyReport::write_to`] writes for the scene named `scene`:
/// `<stem>-errors.csv`, `-summary.txt`, `-errors.svg`, `-orbits.svg` and (when the report has
/// an inner chart) `-orbits-inner.svg`, where the stem is the name with `/`, `\\` and spaces
/// replaced by `_`.
pub fn file_names(scene: &str) -> [String; 5] {
    let stem = scene.replace(['/', '\\', ' '], "_");
    [
        "-errors.csv",
        "-summary.txt",
        "-errors.svg",
        "-orbits.svg",
        "-orbits-inner.svg",
    ]
    .map(|suffix| format!("{stem}{suffix}"))
}

/// The memory [`nbody_report`] needs, estimated before it runs: per step end, the Galerkin
/// trajectory, the reference positions and momenta (and the cross-check's positions), the
/// per-body errors, the invariant errors and the time, checked against
/// [`crate::memory::LIMIT_BYTES`].
pub fn ensure_memory(scene: &BuiltScene, options: &ReportOptions) -> Result<()> {
    let system = scene.euclidean()?;
    let d = scene.initial.q.len();
    let bodies = system.as_nbody().map_or(1, |nb| nb.bodies());
    let invariants = system.invariant_names().len();
    let vector = (8 * d + 24) as f64;
    let reference = vector * if options.cross_check { 3.0 } else { 2.0 };
    let per_step = crate::memory::trajectory_bytes_per_step(scene.method.n, d)
        + reference
        + (8 * (bodies + invariants + 1) + 48) as f64;
    let steps = scene.method.steps;
    crate::memory::ensure_fits(
        format!("the N-body report of {steps} steps"),
        per_step * (steps as f64 + 1.0),
        "the report keeps the run and its reference; fewer --steps",
    )
}

/// Run an N-body scene with its Galerkin method and compare it with a Gauss-collocation
/// reference of the same model (module docs). A Galerkin solver failure is an error.
pub fn nbody_report(scene: &BuiltScene, options: ReportOptions) -> Result<NBodyReport> {
    let system = scene
        .euclidean()?
        .as_nbody()
        .ok_or_else(|| LabError::Scene {
            source_name: scene.name.clone(),
            reason: "the N-body report needs an N-body scene (type = \"nbody\")".into(),
        })?;
    // The initial state was checked against the system when the scene was built.
    let m = &scene.method;
    let init = &scene.initial;
    let gvi = m.integrator()?;
    let start = Instant::now();
    let traj = gvi
        .integrate(system, init.t0, &init.q, &init.p, m.steps)
        .map_err(|f| f.error)?;
    let t_gal = start.elapsed().as_secs_f64();

    let k = options
        .substeps
        .unwrap_or_else(|| auto_substeps(system, &init.q, &init.p, m.h));
    let start = Instant::now();
    let mut gauss = GaussCollocationBaseline::new(system, options.stages, m.h / k as f64)?;
    let (rq, rp) = gauss.integrate_compensated(&init.q, &init.p, m.steps * k, k)?;
    let reference_uncertainty = if options.cross_check {
        let mut fine = GaussCollocationBaseline::new(system, options.stages, m.h / (2 * k) as f64)?;
        let (fq, _) = fine.integrate_compensated(&init.q, &init.p, m.steps * 2 * k, 2 * k)?;
        Some(
            rq.iter()
                .zip(&fq)
                .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
                .fold(0.0, crate::distance::nan_max),
        )
    } else {
        None
    };
    let t_ref = start.elapsed().as_secs_f64();

    let names = system.body_names().unwrap_or_default();
    let nb = system.bodies();
    let dim = system.body_dim();
    let position_errors: Vec<Vec<f64>> = (0..traj.q.len())
        .map(|s| {
            (0..nb)
                .map(|b| {
                    let blk = b * dim..(b + 1) * dim;
                    traj.q[s][blk.clone()]
                        .iter()
                        .zip(&rq[s][blk])
                        .map(|(x, y)| (x - y) * (x - y))
                        .sum::<f64>()
                        .sqrt()
                })
                .collect()
        })
        .collect();
    let inv_names: Vec<String> = system
        .invariant_names()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let ni = inv_names.len();
    let mut inv0 = vec![0.0; ni];
    system.invariants(&init.q, &init.p, &mut inv0);
    let mut invariant_scales = momentum_scales(system, &init.q, &init.p);
    // The energy's scale is every run's T₀ + |V₀| (|E₀| vanishes for a parabolic encounter).
    let (energy_scale_label, energy_scale) =
        crate::energy::energy_scale(system, &init.q, &init.p, inv0[0]);
    invariant_scales[0] = energy_scale;
    let mut inv = vec![0.0; ni];
    let invariant_errors = (0..traj.q.len())
        .map(|s| {
            system.invariants(&traj.q[s], &traj.p[s], &mut inv);
            (0..ni)
                .map(|i| {
                    let e = (inv[i] - inv0[i]).abs();
                    if i == 0 {
                        crate::energy::relative_energy_error(e, energy_scale)
                    } else {
                        e
                    }
                })
                .collect()
        })
        .collect();
    let mercury = perihelion_drift(system, &traj.q, &traj.p, &rq, &rp);
    let orbit_charts = orbit_charts(&names, &scene.name, scene.units(), &traj)?;
    Ok(NBodyReport {
        scene: scene.scene(),
        body_names: names,
        times: (0..traj.q.len()).map(|s| traj.time(s)).collect(),
        position_errors,
        invariant_names: inv_names,
        invariant_errors,
        invariant_scales,
        energy_scale_label: energy_scale_label.to_string(),
        reference_uncertainty,
        reference: gauss.name(),
        mercury,
        newton_iterations_per_step: traj.newton_iterations() as f64 / m.steps.max(1) as f64,
        seconds: (t_gal, t_ref),
        orbit_charts,
    })
}

/// Reference steps per Galerkin step: the shortest two-body period 2π√(r³/G(mᵢ+mⱼ)) of the
/// initial state over 256, divided into h.
fn auto_substeps(system: &NBody, q: &[f64], p: &[f64], h: f64) -> usize {
    match system.shortest_time_scale(q, p) {
        Some(shortest) => ((h * 256.0 / shortest).ceil() as usize).clamp(1, 100_000),
        None => 64,
    }
}

/// Scales for the invariants: |E_0| for the energy (replaced by T₀ + |V₀| in
/// [`nbody_report`]), Σᵢ |pᵢ| for every linear-momentum
/// component and Σᵢ |qᵢ| |pᵢ| for every angular-momentum component (the size of the terms
/// whose round-off the components accumulate).
fn momentum_scales(system: &NBody, q: &[f64], p: &[f64]) -> Vec<f64> {
    let names = system.invariant_names();
    let k = system.body_dim();
    let mut inv = vec![0.0; names.len()];
    system.invariants(q, p, &mut inv);
    let norm = |x: &[f64]| x.iter().map(|y| y * y).sum::<f64>().sqrt();
    let (mut linear, mut angular) = (0.0, 0.0);
    for b in 0..system.bodies() {
        let (qb, pb) = (&q[b * k..(b + 1) * k], &p[b * k..(b + 1) * k]);
        linear += norm(pb);
        angular += norm(qb) * norm(pb);
    }
    let mut out = vec![angular; names.len()];
    out[0] = inv[0].abs();
    out[1..=k].iter_mut().for_each(|x| *x = linear);
    out
}

fn perihelion_at(system: &NBody, sun: usize, mer: usize, q: &[f64], p: &[f64]) -> Option<f64> {
    let k = system.body_dim();
    let ms = system.masses();
    let mut r = [0.0; 3];
    let mut v = [0.0; 3];
    for c in 0..k {
        r[c] = q[mer * k + c] - q[sun * k + c];
        v[c] = p[mer * k + c] / ms[mer] - p[sun * k + c] / ms[sun];
    }
    longitude_of_perihelion(r, v, system.g() * (ms[sun] + ms[mer]))
}

fn perihelion_drift(
    system: &NBody,
    gq: &[Vec<f64>],
    gp: &[Vec<f64>],
    rq: &[Vec<f64>],
    rp: &[Vec<f64>],
) -> Option<PerihelionDrift> {
    let (sun, mer) = (system.body_index("Sun")?, system.body_index("Mercury")?);
    let mut galerkin = Vec::with_capacity(gq.len());
    let mut reference = Vec::with_capacity(gq.len());
    for s in 0..gq.len().min(rq.len()) {
        galerkin.push(perihelion_at(system, sun, mer, &gq[s], &gp[s])?);
        reference.push(perihelion_at(system, sun, mer, &rq[s], &rp[s])?);
    }
    let max_difference = galerkin
        .iter()
        .zip(&reference)
        .map(|(a, b)| wrap(a - b).abs())
        .fold(0.0, crate::distance::nan_max);
    let advance = |w: &[f64]| wrap(w[w.len() - 1] - w[0]);
    Some(PerihelionDrift {
        galerkin_advance: advance(&galerkin),
        reference_advance: advance(&reference),
        galerkin,
        reference,
        max_difference,
    })
}

impl NBodyReport {
    /// Max over step ends of each body's position error: (name, error).
    pub fn max_position_errors(&self) -> Vec<(String, f64)> {
        self.body_names
            .iter()
            .enumerate()
            .map(|(b, n)| {
                let e = self
                    .position_errors
                    .iter()
                    .map(|r| r[b])
                    .fold(0.0, crate::distance::nan_max);
                (n.clone(), e)
            })
            .collect()
    }

    /// Max over step ends of each invariant's error (see [`NBodyReport::invariant_errors`]).
    pub fn max_invariant_errors(&self) -> Vec<(String, f64)> {
        self.invariant_names
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let e = self
                    .invariant_errors
                    .iter()
                    .map(|r| r[i])
                    .fold(0.0, crate::distance::nan_max);
                (n.clone(), e)
            })
            .collect()
    }

    /// The per-step table as CSV: `step,t,err_<body>…,<invariant>_error…` and, with Mercury,
    /// `mercury_varpi_galerkin,mercury_varpi_reference,mercury_varpi_difference` (radians).
    pub fn to_csv(&self) -> Result<String> {
        let mut cols = vec!["step".to_string(), "t".to_string()];
        cols.extend(
            self.body_names
                .iter()
                .map(|n| format!("err_{}", n.replace(' ', "_"))),
        );
        cols.extend(self.invariant_names.iter().map(|n| format!("{n}_error")));
        if self.mercury.is_some() {
            cols.extend(
                ["galerkin", "reference", "difference"].map(|s| format!("mercury_varpi_{s}")),
            );
        }
        let rows = self.times.iter().enumerate().map(|(k, t)| {
            let mut row = vec![k.to_string(), format!("{t:e}")];
            row.extend(self.position_errors[k].iter().map(|x| format!("{x:e}")));
            row.extend(self.invariant_errors[k].iter().map(|x| format!("{x:e}")));
            if let Some(m) = &self.mercury {
                let (a, b) = (m.galerkin[k], m.reference[k]);
                row.extend([a, b, wrap(a - b)].map(|x| format!("{x:e}")));
            }
            row
        });
        crate::table::csv_records(&cols, rows)
    }

    /// Chart of each body's position error against time (log scale; t = 0 is omitted).
    pub fn error_chart(&self) -> Chart {
        let units = &self.scene.units;
        let mut chart = Chart::new(
            format!("{}: position error against the reference", self.scene.name),
            format!("t{}", unit_suffix(units.time.as_deref(), "time")),
            format!(
                "|q_galerkin − q_reference|{}",
                unit_suffix(units.length.as_deref(), "length")
            ),
        )
        .log_y();
        for (b, name) in self.body_names.iter().enumerate() {
            let pts: Vec<(f64, f64)> = self
                .times
                .iter()
                .zip(&self.position_errors)
                .skip(1)
                .map(|(&t, e)| (t, e[b]))
                .collect();
            chart.push(Series::line(name.clone(), pts).with_color(b));
        }
        chart
    }

    /// Write `<name>-errors.csv`, `<name>-errors.svg`, `<name>-orbits.svg` (and
    /// `<name>-orbits-inner.svg` when there is an inner chart) and `<name>-summary.txt` into
    /// `dir`; returns the file names.
    pub fn write_to(&self, dir: &std::path::Path) -> Result<Vec<String>> {
        crate::output::check_output_dir(dir)?;
        let [csv, summary, errors, orbits, inner] = file_names(&self.scene.name);
        let mut files = Vec::new();
        let mut text = |name: String, body: String| -> Result<()> {
            let path = dir.join(&name);
            crate::output::write_file(&path, &body)?;
            files.push(name);
            Ok(())
        };
        text(csv, self.to_csv()?)?;
        text(summary, self.to_string())?;
        let mut charts = vec![(errors, self.error_chart())];
        charts.push((orbits, self.orbit_charts.0.clone()));
        if let Some(chart) = &self.orbit_charts.1 {
            charts.push((inner, chart.clone()));
        }
        for (name, chart) in charts {
            chart
                .save_svg(dir.join(&name))
                .map_err(|e| LabError::Plot(e.to_string()))?;
            files.push(name);
        }
        Ok(files)
    }
}

impl std::fmt::Display for NBodyReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let m = &self.scene.method;
        writeln!(
            f,
            "{}: {} basis n = {}, h = {}, {} steps (t_end = {}); {:.2} Newton iterations/step, {:.2} s",
            self.scene.name,
            m.basis,
            m.n,
            m.h,
            m.steps,
            self.times.last().copied().unwrap_or(0.0),
            self.newton_iterations_per_step,
            self.seconds.0
        )?;
        write!(f, "reference: {} ({:.2} s)", self.reference, self.seconds.1)?;
        match self.reference_uncertainty {
            Some(u) => writeln!(f, "; half-step cross-check differs by {u:.2e}")?,
            None => writeln!(f)?,
        }
        writeln!(f, "max position error per body:")?;
        for (name, e) in self.max_position_errors() {
            writeln!(f, "  {name:<12} {e:.3e}")?;
        }
        writeln!(
            f,
            "max invariant errors (energy relative to {}; momenta absolute / scale):",
            self.energy_scale_label
        )?;
        for (i, (name, e)) in self.max_invariant_errors().into_iter().enumerate() {
            if i == 0 {
                writeln!(
                    f,
                    "  {name:<18} {e:.3e} ({} = {:.3e})",
                    self.energy_scale_label, self.invariant_scales[0]
                )?;
            } else {
                writeln!(
                    f,
                    "  {name:<18} {e:.3e} (scale {:.3e})",
                    self.invariant_scales[i]
                )?;
            }
        }
        if let Some(mp) = &self.mercury {
            writeln!(
                f,
                "Mercury perihelion longitude: Galerkin advance {:.3e} rad, reference advance \
                 {:.3e} rad, max |difference| {:.3e} rad ({:.2} arcsec)",
                mp.galerkin_advance,
                mp.reference_advance,
                mp.max_difference,
                mp.max_difference.to_degrees() * 3600.0
            )?;
        }
        Ok(())
    }
}
