//! `gvi run SCENE`.

use super::{parse_vector, write_output};
use clap::{Args, ValueEnum};
use galerkin_vi::GviError;
use galerkin_vi::run::{RunOptions, run_scene};
use galerkin_vi::scene::Scene;
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Format {
    Csv,
    Json,
}

#[derive(Debug, Args)]
pub struct RunArgs {
    /// Built-in scene name (see `gvi scenes`) or path to a TOML scene file.
    pub scene: String,
    /// Basis: chebyshev (others as they are available).
    #[arg(long)]
    pub basis: Option<String>,
    /// Quadrature: gauss-legendre (others as they are available).
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
    /// Stage solver: auto (default; exact for --tol runs), exact, kronecker, newton-krylov or
    /// fixed-point. Every solver gives the same map to round-off; they differ in cost
    /// (docs/solvers.md).
    #[arg(long)]
    pub solver: Option<String>,
    /// Number of steps.
    #[arg(long)]
    pub steps: Option<usize>,
    /// Initial position, comma-separated (e.g. 0.4,0).
    #[arg(long, allow_hyphen_values = true)]
    pub q0: Option<String>,
    /// Initial momentum, comma-separated.
    #[arg(long, allow_hyphen_values = true)]
    pub p0: Option<String>,
    /// Tolerance on the max position error: choose n per step (adds the CSV columns `n` and
    /// `indicator`; with --plot also writes STEM-n.svg).
    #[arg(long, allow_hyphen_values = true)]
    pub tol: Option<f64>,
    /// Error control of a --tol run: embedded (default; every step also solved at the next n,
    /// CSV column `estimate`), indicator, or calibrated (experimental).
    #[arg(long)]
    pub control: Option<String>,
    /// Values of n a --tol run may use, comma-separated (default 4,6,…,64).
    #[arg(long)]
    pub ladder: Option<String>,
    /// With --tol: choose one h for the run (same horizon h·steps) from the tolerance and the
    /// system's time scale by short pilot runs; the choice is reported.
    #[arg(long)]
    pub auto_h: bool,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Csv)]
    pub format: Format,
    /// Output file (default: stdout).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Also write an SVG chart of the run (orbit for 2-D systems, q(t) otherwise; N-body: one
    /// orbit per body, xy projection, and for the solar system a zoom on the inner planets
    /// written next to it as `<stem>-inner.svg`).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// Load the scene named on the command line and apply the flag overrides.
pub fn load_scene(a: &RunArgs) -> Result<Scene, GviError> {
    let mut scene = Scene::load(&a.scene)?;
    apply_overrides(&mut scene, a)?;
    Ok(scene)
}

/// Apply command-line overrides to a scene.
pub fn apply_overrides(scene: &mut Scene, a: &RunArgs) -> Result<(), GviError> {
    if let Some(b) = &a.basis {
        scene.method.basis = b.parse()?;
    }
    if let Some(q) = &a.quadrature {
        scene.method.quadrature = q.parse()?;
    }
    if let Some(n) = a.n {
        scene.method.n = n;
    }
    if let Some(s) = &a.solver {
        scene.method.solver = s.parse()?;
    }
    if a.quad_points.is_some() {
        scene.method.quad_points = a.quad_points;
    }
    if a.economical && a.quad_points.is_none() {
        scene.method.quad_points = Some(scene.method.quadrature.economical_points(scene.method.n));
    }
    if let Some(h) = a.h {
        scene.method.h = h;
    }
    if let Some(s) = a.steps {
        scene.method.steps = s;
    }
    if let Some(q) = &a.q0 {
        scene.initial.q = parse_vector("--q0", q)?;
    }
    if a.tol.is_some() {
        scene.method.tol = a.tol;
    }
    if let Some(c) = &a.control {
        scene.method.control = Some(c.parse()?);
    }
    if a.auto_h {
        scene.method.auto_h = true;
    }
    if let Some(l) = &a.ladder {
        let values = parse_vector("--ladder", l)?;
        let mut ladder = Vec::with_capacity(values.len());
        for v in values {
            if !(v.is_finite() && v >= 2.0 && v.fract() == 0.0) {
                return Err(GviError::InvalidArgument {
                    name: "--ladder".into(),
                    reason: format!("{v} is not a whole number of basis functions ≥ 2"),
                });
            }
            ladder.push(v as usize);
        }
        scene.method.ladder = Some(ladder);
    }
    if let Some(p) = &a.p0 {
        scene.initial.p = parse_vector("--p0", p)?;
    }
    if a.q0.is_some() || a.p0.is_some() {
        scene.validate()?;
    }
    Ok(())
}

pub fn run(args: RunArgs) -> Result<(), GviError> {
    let scene = load_scene(&args)?;
    let options = RunOptions {
        chart: args.plot.is_some(),
        ..RunOptions::default()
    };
    let result = run_scene(&scene, options)?;
    let text = match args.format {
        Format::Csv => result.to_csv(),
        Format::Json => result.to_json()?,
    };
    write_output(args.output.as_deref(), &text)?;
    if let (Some(path), Some(chart)) = (&args.plot, &result.chart) {
        chart
            .save_svg(path)
            .map_err(|e| GviError::Plot(e.to_string()))?;
        eprintln!("chart written to {}", path.display());
        if let Some(inner) = &result.inner_chart {
            let inner_path = path.with_file_name(format!(
                "{}-inner.svg",
                path.file_stem()
                    .and_then(|s| s.to_str())
                    .unwrap_or("orbits")
            ));
            inner
                .save_svg(&inner_path)
                .map_err(|e| GviError::Plot(e.to_string()))?;
            eprintln!("inner-bodies chart written to {}", inner_path.display());
        }
        if let Some(nc) = &result.n_chart {
            let n_path = path.with_file_name(format!(
                "{}-n.svg",
                path.file_stem().and_then(|s| s.to_str()).unwrap_or("run")
            ));
            nc.save_svg(&n_path)
                .map_err(|e| GviError::Plot(e.to_string()))?;
            eprintln!("n-against-time chart written to {}", n_path.display());
        }
    }
    eprintln!("{}", result.summary);
    match result.failure {
        Some(e) => Err(e),
        None => Ok(()),
    }
}
