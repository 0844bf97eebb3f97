//! `gvi run SCENE`.

use super::values;
use super::write_output;
use crate::error::LabError;
use crate::output::{AtomicFile, Plan};
use crate::run::stream::stream_scene;
use crate::run::{RunOptions, RunSummary, run_scene};
use crate::scene::{BuiltScene, BuiltSystem, Overrides, Scene};
use clap::{Args, ValueEnum};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    Csv,
    Json,
}

#[derive(Debug, Args)]
pub struct SceneArgs {
    /// Built-in scene name (see `gvi scenes`) or path to a TOML scene file.
    pub scene: String,
    /// Basis: chebyshev (default), legendre, hermite, fourier, or enriched (polynomials plus
    /// sin/cos of --omega; n = degree + 1 + 2·harmonics·frequencies).
    #[arg(long)]
    pub basis: Option<String>,
    /// Enrichment frequency ω of the enriched basis (finite, > 0), or several separated by
    /// commas (--omega 50,20: sin/cos of each in the space).
    #[arg(long, allow_hyphen_values = true, value_delimiter = ',', value_parser = values::number)]
    pub omega: Option<Vec<f64>>,
    /// Number of harmonics of the enriched basis (default 1).
    #[arg(long)]
    pub harmonics: Option<usize>,
    /// Quadrature: gauss-legendre (default), gauss-lobatto, clenshaw-curtis or
    /// trapezoid.
    #[arg(long)]
    pub quadrature: Option<String>,
    /// Number of basis functions n.
    #[arg(long)]
    pub n: Option<usize>,
    /// Number of quadrature points (default: the rule's default for n; 2n Gauss points).
    #[arg(long)]
    pub quad_points: Option<usize>,
    /// Use the economical number of quadrature points (⌈3n/2⌉ for Gauss–Legendre: the
    /// paper's accuracy with 25 % fewer force evaluations) unless --quad-points is given.
    #[arg(long)]
    pub economical: bool,
    /// Step size h.
    #[arg(long, allow_hyphen_values = true)]
    pub h: Option<f64>,
    /// Stage solver: auto (default; the velocity form where it applies, exact for --tol runs),
    /// modal, exact, kronecker, newton-krylov or fixed-point. Every solver gives the same map to
    /// round-off; they differ in cost (docs/solvers.md).
    #[arg(long)]
    pub solver: Option<String>,
    /// Number of steps.
    #[arg(long)]
    pub steps: Option<usize>,
    /// Rigid-body scenes: the Lie group chart, exp (default) or cayley.
    #[arg(long)]
    pub retraction: Option<String>,
    /// Initial position, comma-separated (e.g. 0.4,0).
    #[arg(long, allow_hyphen_values = true, value_delimiter = ',', value_parser = values::number)]
    pub q0: Option<Vec<f64>>,
    /// Initial momentum, comma-separated.
    #[arg(long, allow_hyphen_values = true, value_delimiter = ',', value_parser = values::number)]
    pub p0: Option<Vec<f64>>,
}

/// `gvi run`: the scene and method, and what only a run uses (tolerance, outputs).
#[derive(Debug, Args)]
pub struct RunArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Tolerance on the max position error: choose n per step (adds the CSV columns `n`,
    /// `indicator` and `estimate`; with --plot also writes STEM-n.svg).
    #[arg(long, allow_hyphen_values = true)]
    pub tol: Option<f64>,
    /// Error control of a --tol run: embedded (default; every step also solved at the next n,
    /// whose difference fills the CSV column `estimate`, empty otherwise), indicator, or
    /// calibrated (experimental).
    #[arg(long, requires = "tol")]
    pub control: Option<String>,
    /// Values of n a --tol run may use, comma-separated, increasing (default 4,6,…,64).
    #[arg(long, requires = "tol", value_delimiter = ',', value_parser = values::basis_count)]
    pub ladder: Option<Vec<usize>>,
    /// With --tol: choose one h for the run (same horizon h·steps) from the tolerance and the
    /// system's time scale by short pilot runs; the choice is reported.
    #[arg(long, requires = "tol")]
    pub auto_h: bool,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Csv)]
    pub format: Format,
    /// Output file (default: stdout when it is a pipe or a file; to a terminal only the
    /// summary is printed, with a hint).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Also write an SVG chart of the run (orbit for 2-D systems, q(t) otherwise; N-body: one
    /// orbit per body, xy projection, and for the solar system a zoom on the inner planets
    /// written next to it as `<stem>-inner.svg`).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Make the sanity warnings errors (exit status 1): a relative energy or position error
    /// above 1e-2, an unresolved close encounter. The table is still written.
    #[arg(long)]
    pub strict: bool,
    /// A Poincaré time transformation (docs/guide/time-transformations.md): fixed fictitious
    /// steps h (= the physical step at the initial state) whose physical length follows the
    /// monitor g: sundman (|q|^alpha for kepler, a smooth minimum of the pair distances^alpha for nbody),
    /// radius, min-distance, softmin-distance or product-distance. Rows are in physical time
    /// (columns step, s, t, dt, ...); --plot charts the physical step against t.
    #[arg(long)]
    pub time_transform: Option<String>,
    /// The monitor's exponent alpha (default 1.5).
    #[arg(long, allow_hyphen_values = true)]
    pub alpha: Option<f64>,
    /// The energy level E0 of the time transformation (default: the initial state's energy,
    /// the only level on which the fictitious time reparametrises the physical motion).
    #[arg(long, allow_hyphen_values = true)]
    pub energy_level: Option<f64>,
    /// Time-transformed runs: the physical end time, located on t(s) (--steps caps the
    /// fictitious steps; reaching the cap first is an error).
    #[arg(long, allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Time-transformed runs: rows at t0 + k*EVERY in physical time, each located on the
    /// Galerkin curve as a zero of t(s) - t0 - k*EVERY, instead of at the step ends.
    #[arg(long, allow_hyphen_values = true)]
    pub every: Option<f64>,
}

impl SceneArgs {
    /// The method and initial-state flags as [`Overrides`] (parsed, not yet checked against
    /// the system: [`Scene::build`] does that).
    pub fn overrides(&self) -> Result<Overrides, LabError> {
        Ok(Overrides {
            basis: self.basis.as_deref().map(str::parse).transpose()?,
            quadrature: self.quadrature.as_deref().map(str::parse).transpose()?,
            n: self.n,
            quad_points: self.quad_points,
            economical: self.economical,
            h: self.h,
            solver: self.solver.as_deref().map(str::parse).transpose()?,
            steps: self.steps,
            retraction: self.retraction.as_deref().map(str::parse).transpose()?,
            q0: self.q0.clone(),
            p0: self.p0.clone(),
            omega: self.omega.clone(),
            harmonics: self.harmonics,
            ..Overrides::default()
        })
    }
}

impl RunArgs {
    /// The scene flags and the tolerance flags of `gvi run` as [`Overrides`].
    pub fn overrides(&self) -> Result<Overrides, LabError> {
        let mut o = self.scene.overrides()?;
        o.tol = self.tol;
        o.control = self.control.as_deref().map(str::parse).transpose()?;
        o.auto_h = self.auto_h;
        o.ladder = self.ladder.clone();
        o.time_transform = self.time_transform.as_deref().map(str::parse).transpose()?;
        o.time_alpha = self.alpha;
        o.time_energy = self.energy_level;
        o.t_end = self.t_end;
        o.every = self.every;
        Ok(o)
    }
}

/// Refuse the time-transformation flags on a scene without a time transformation (they
/// would be ignored), and `--tol` with one (its steps are fixed in fictitious time).
fn refuse_unused_time_flags(args: &RunArgs, scene: &BuiltScene) -> Result<(), LabError> {
    let transformed = scene.method.time_transform.is_some();
    if !transformed {
        for (flag, given) in [
            ("--alpha", args.alpha.is_some()),
            ("--energy-level", args.energy_level.is_some()),
            ("--t-end", args.t_end.is_some()),
            ("--every", args.every.is_some()),
        ] {
            if given {
                return Err(ignored(
                    flag,
                    format!(
                        "{} has no time transformation; give --time-transform MONITOR (or \
                         [method.time_transform] in the scene) for {flag} to mean something",
                        scene.name
                    ),
                ));
            }
        }
    } else if args.tol.is_some() {
        return Err(ignored(
            "--tol",
            "a time-transformed run takes fixed fictitious steps at a fixed n; --tol would \
             be ignored"
                .into(),
        ));
    }
    Ok(())
}

/// `gvi run` of a scene with a time transformation: rows in physical time, the chart of the
/// physical step (crate::run::time_transform).
fn run_time_transformed(
    args: &RunArgs,
    scene: &BuiltScene,
    started: std::time::Instant,
) -> Result<(), LabError> {
    let mut plan = Plan::new();
    if let Some(o) = &args.output {
        plan.output("--output", o);
    }
    if let Some(p) = &args.plot {
        plan.chart("--plot", p);
    }
    plan.scene(&args.scene.scene).check()?;
    refuse_if_too_big(scene, args)?;
    let to_terminal = args.output.is_none() && std::io::stdout().is_terminal();
    let result = crate::run::time_transform::run_time_transformed(scene, args.plot.is_some())?;
    if !to_terminal {
        let text = match args.format {
            Format::Csv => result.to_csv()?,
            Format::Json => result.to_json()?,
        };
        write_output(args.output.as_deref(), &text)?;
    }
    if let (Some(path), Some(chart)) = (&args.plot, &result.chart) {
        chart
            .save_svg(path)
            .map_err(|e| LabError::Plot(e.to_string()))?;
        eprintln!("chart written to {}", path.display());
    }
    eprintln!(
        "{}; whole command: {:.3} s (wall clock)",
        result.summary,
        started.elapsed().as_secs_f64()
    );
    if to_terminal {
        eprintln!("{TERMINAL_HINT}");
    }
    if let Some(e) = result.failure {
        return Err(e);
    }
    let rel = result.summary.max_relative_energy_error;
    if args.strict && rel > crate::run::SANITY_THRESHOLD {
        return Err(LabError::Untrustworthy(format!(
            "relative energy error {rel:.3e} above {:e}",
            crate::run::SANITY_THRESHOLD
        )));
    }
    Ok(())
}

/// Load the scene named on the command line, apply the flag overrides and build it (once);
/// flags the built scene would ignore are refused ([`refuse_unused_scene_flags`]).
pub fn load_scene(a: &SceneArgs) -> Result<BuiltScene, LabError> {
    let scene = Scene::load(&a.scene)?
        .with_overrides(&a.overrides()?)
        .build()?;
    refuse_unused_scene_flags(a, &scene)?;
    refuse_time_transform(&scene.method)?;
    Ok(scene)
}

/// Refuse a time-transformed method in the commands that run the method's integrator in
/// physical time (checks, studies, sections, ensembles, reports): they would ignore
/// `[method.time_transform]` and step with h as a physical step. Only `gvi run` runs it.
pub fn refuse_time_transform(method: &galerkin_vi::method::MethodSpec) -> Result<(), LabError> {
    if method.time_transform.is_some() {
        return Err(galerkin_vi::GviError::Unsupported(
            "the scene's method has a time transformation ([method.time_transform]), which \
             only `gvi run` runs; this command would step in physical time and ignore it"
                .into(),
        )
        .into());
    }
    Ok(())
}

fn ignored(flag: &str, reason: String) -> LabError {
    LabError::InvalidArgument {
        name: flag.to_string(),
        reason,
    }
}

/// Refuse the scene flags a built scene would ignore: `--retraction` outside the rigid-body
/// scenes (only the Lie group integrator has a chart), `--solver` on them (that integrator has
/// no stage solver to choose).
pub fn refuse_unused_scene_flags(a: &SceneArgs, scene: &BuiltScene) -> Result<(), LabError> {
    let rigid = matches!(scene.system, BuiltSystem::RigidBody(_));
    if a.retraction.is_some() && !rigid {
        return Err(ignored(
            "--retraction",
            format!(
                "{} is not a rigid-body scene; only those (rigid-body, heavy-top, pendulum-3d, \
                 type = \"rigid-body\" | \"heavy-top\") run on SO(3) with a retraction",
                scene.name
            ),
        ));
    }
    if a.solver.is_some() && rigid {
        return Err(ignored(
            "--solver",
            format!(
                "{} is a rigid-body scene, run by the Lie group integrator, which has no stage \
                 solver to choose",
                scene.name
            ),
        ));
    }
    Ok(())
}

/// Refuse the method flags a `--tol` run would ignore: n is chosen per step from the ladder,
/// each rung with its quadrature's default points, so `--n`, `--quad-points` and
/// `--economical` have no effect.
fn refuse_fixed_n_flags_with_tol(args: &RunArgs) -> Result<(), LabError> {
    if args.tol.is_none() {
        return Ok(());
    }
    let a = &args.scene;
    for (flag, given) in [
        ("--n", a.n.is_some()),
        ("--quad-points", a.quad_points.is_some()),
        ("--economical", a.economical),
    ] {
        if given {
            return Err(ignored(
                flag,
                format!(
                    "with --tol, n is chosen per step from the ladder (--ladder), each rung \
                     with its quadrature's default points; {flag} would be ignored"
                ),
            ));
        }
    }
    Ok(())
}

/// In-memory runs whose estimated memory exceeds this are refused up front (streamed runs
/// hold one row at a time and have no such limit).
const MEMORY_LIMIT_BYTES: f64 = crate::memory::LIMIT_BYTES;

/// `<stem><suffix>.svg` next to `path`.
fn sibling(path: &Path, suffix: &str, fallback: &str) -> PathBuf {
    let stem = path
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(fallback);
    path.with_file_name(format!("{stem}{suffix}.svg"))
}

pub fn run(args: RunArgs) -> Result<(), LabError> {
    let started = std::time::Instant::now();
    refuse_fixed_n_flags_with_tol(&args)?;
    let scene = Scene::load(&args.scene.scene)?
        .with_overrides(&args.overrides()?)
        .build()?;
    refuse_unused_scene_flags(&args.scene, &scene)?;
    refuse_unused_time_flags(&args, &scene)?;
    if scene.method.time_transform.is_some() {
        return run_time_transformed(&args, &scene, started);
    }
    // Every output is checked before any work: usable, distinct, and not the scene file.
    let mut outputs: Vec<(&str, PathBuf)> = Vec::new();
    if let Some(o) = &args.output {
        outputs.push(("--output", o.clone()));
    }
    if let Some(p) = &args.plot {
        outputs.push(("--plot", p.clone()));
        if matches!(&scene.system, BuiltSystem::Euclidean(s) if s.as_nbody().is_some()) {
            outputs.push(("the inner-bodies chart", sibling(p, "-inner", "orbits")));
        }
        // Checked before the run, so from the method: a run that chooses n per step draws it.
        if scene.method.chooses_n() {
            outputs.push(("the n chart", sibling(p, "-n", "run")));
        }
    }
    let mut plan = Plan::new();
    for (role, path) in &outputs {
        if *role == "--output" {
            plan.output(*role, path);
        } else {
            plan.chart(*role, path);
        }
    }
    plan.scene(&args.scene.scene).check()?;
    // Without --output, a table bound for a terminal (hundreds of rows, up to hundreds of
    // columns) is not printed: the summary on stderr and a hint take its place.
    let to_terminal = args.output.is_none() && std::io::stdout().is_terminal();

    // Rigid bodies run on SO(3) by their own integrator (galerkin_vi::lie), in memory.
    let on_so3 = matches!(scene.system, BuiltSystem::RigidBody(_));
    // A run that chooses n per step keeps its trajectory (the library does not stream it).
    let streamed =
        args.plot.is_none() && args.format == Format::Csv && !scene.method.chooses_n() && !on_so3;
    let samples = RunOptions::default().curve_samples_per_step;
    let (mut summary, failure) = if streamed {
        // The first Ctrl-C stops the stream after the step in progress; the rows are kept.
        let _sigint = crate::interrupt::catch();
        let outcome = match &args.output {
            Some(path) => {
                let mut file = AtomicFile::create(path)?;
                let outcome = stream_scene(&scene, samples, &mut file)?;
                // Committed even when the run stopped early: the rows before a failure are kept.
                file.commit()?;
                outcome
            }
            None if to_terminal => stream_scene(&scene, samples, &mut std::io::sink())?,
            None => {
                let mut out = std::io::BufWriter::new(std::io::stdout().lock());
                stream_scene(&scene, samples, &mut out)?
            }
        };
        (outcome.summary, outcome.failure)
    } else {
        refuse_if_too_big(&scene, &args)?;
        run_in_memory(&scene, &args, to_terminal)?
    };
    summary.command_seconds = Some(started.elapsed().as_secs_f64());
    eprintln!("{summary}");
    if to_terminal {
        eprintln!("{TERMINAL_HINT}");
    }
    if let Some(LabError::Interrupted { step, .. }) = failure {
        let kept = match &args.output {
            Some(path) => format!(
                "the rows of steps 0…{} are written to {}",
                step.saturating_sub(1),
                path.display()
            ),
            None if to_terminal => "no table was written (stdout is a terminal)".to_string(),
            None => format!(
                "the rows of steps 0…{} went to stdout",
                step.saturating_sub(1)
            ),
        };
        return Err(LabError::Interrupted { step, kept });
    }
    if let Some(e) = failure {
        return Err(e);
    }
    if args.strict && !summary.warnings.is_empty() {
        return Err(LabError::Untrustworthy(summary.warnings.join("; ")));
    }
    Ok(())
}

/// Refuse an in-memory run (chart, JSON or --tol) whose estimated memory is absurd.
fn refuse_if_too_big(scene: &BuiltScene, args: &RunArgs) -> Result<(), LabError> {
    // A tolerance-driven run may use the largest n of its ladder.
    let (per_step, estimate) = crate::run::in_memory_bytes(scene, args.format == Format::Json);
    if estimate > MEMORY_LIMIT_BYTES {
        return Err(LabError::MemoryTooHigh {
            steps: scene.method.steps,
            bytes_per_step: per_step,
            estimate,
            limit: MEMORY_LIMIT_BYTES,
        });
    }
    Ok(())
}

/// Printed after the summary when the table was not printed because stdout is a terminal.
pub const TERMINAL_HINT: &str = "table not printed: stdout is a terminal; write it with \
     --output FILE (.csv, or .json with --format json) or pipe it (gvi run ... | less)";

fn run_in_memory(
    scene: &BuiltScene,
    args: &RunArgs,
    to_terminal: bool,
) -> Result<(RunSummary, Option<LabError>), LabError> {
    let options = RunOptions {
        chart: args.plot.is_some(),
        ..RunOptions::default()
    };
    let result = run_scene(scene, options)?;
    if !to_terminal {
        let text = match args.format {
            Format::Csv => result.to_csv()?,
            Format::Json => result.to_json()?,
        };
        write_output(args.output.as_deref(), &text)?;
    }
    let plot = |chart: &crate::plot::Chart, path: &Path, what: &str| {
        chart
            .save_svg(path)
            .map_err(|e| LabError::Plot(e.to_string()))
            .map(|_| eprintln!("{what} written to {}", path.display()))
    };
    if let (Some(path), Some(chart)) = (&args.plot, &result.chart) {
        plot(chart, path, "chart")?;
        if let Some(inner) = &result.inner_chart {
            plot(
                inner,
                &sibling(path, "-inner", "orbits"),
                "inner-bodies chart",
            )?;
        }
        if let Some(nc) = &result.n_chart {
            plot(nc, &sibling(path, "-n", "run"), "n-against-time chart")?;
        }
    }
    Ok((result.summary, result.failure))
}
