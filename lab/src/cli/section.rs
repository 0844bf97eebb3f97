//! `gvi section SCENE`: a Poincaré section or a stroboscopic map, located on the Galerkin
//! curves, for one orbit or a fan of orbits on one energy surface.

use super::run::{SceneArgs, load_scene};
use crate::error::LabError;
use crate::output::Plan;
use crate::section::{Fan, SectionEvent, run_section};
use clap::Args;
use galerkin_vi::events::Direction;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct SectionArgs {
    #[command(flatten)]
    pub run: SceneArgs,
    /// The section g(t, q, p) = 0, an expression over the coordinate names, the momenta
    /// `p_<name>` (p0, p1, … for scenes with coordinates q0, q1, …), `t` and the scene's
    /// parameters, e.g. "x" for the plane x = 0.
    #[arg(long, conflicts_with = "every", required_unless_present = "every")]
    pub event: Option<String>,
    /// Which crossings of --event: rising (g goes from − to +, default), falling or both.
    #[arg(long, default_value = "rising", requires = "event")]
    pub direction: String,
    /// A stroboscopic map instead: the state at t0 + k·PERIOD (e.g. 2π/ω for a drive of
    /// frequency ω; `2*pi/1.2` is accepted).
    #[arg(long, allow_hyphen_values = true, value_parser = super::values::expression_number)]
    pub every: Option<f64>,
    /// Number of orbits (default 1: the scene's initial state).
    #[arg(long, default_value_t = 1)]
    pub orbits: usize,
    /// Spread the orbits' NAME over [A, B]: NAME=A:B, NAME a coordinate or `p_<name>`.
    #[arg(long, allow_hyphen_values = true)]
    pub vary: Option<String>,
    /// The energy of every orbit, reached by solving for --solve.
    #[arg(long, allow_hyphen_values = true, requires = "solve")]
    pub energy: Option<f64>,
    /// The component solved for --energy (its sign taken from the scene's state).
    #[arg(long, requires = "energy")]
    pub solve: Option<String>,
    /// The chart's axes: two components, A,B (default: the last coordinate and its momentum).
    #[arg(long, value_delimiter = ',')]
    pub axes: Option<Vec<String>>,
    /// Write the section points (CSV: orbit, t, q, p) here instead of stdout.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Write the chart (SVG) here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

fn parse_vary(text: &str) -> Result<(String, f64, f64), LabError> {
    let bad = |reason: &str| LabError::InvalidArgument {
        name: "--vary".into(),
        reason: format!("{reason} (expected NAME=A:B, e.g. y=-0.4:0.6), got `{text}`"),
    };
    let (name, range) = text.split_once('=').ok_or_else(|| bad("no `=`"))?;
    let (a, b) = range
        .split_once(':')
        .ok_or_else(|| bad("no `:` in the range"))?;
    let num = |s: &str| {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad("the range ends must be finite numbers"))
    };
    Ok((name.trim().to_string(), num(a)?, num(b)?))
}

pub fn run_section_command(args: SectionArgs) -> Result<(), LabError> {
    Plan::new()
        .output_opt("--output", args.output.as_deref())
        .chart_opt("--plot", args.plot.as_deref())
        .scene(&args.run.scene)
        .check()?;
    if args.orbits == 0 || args.orbits > 10_000 {
        return Err(LabError::InvalidArgument {
            name: "--orbits".into(),
            reason: format!("need 1 ≤ orbits ≤ 10000, got {}", args.orbits),
        });
    }
    if args.orbits > 1 && args.vary.is_none() {
        return Err(LabError::InvalidArgument {
            name: "--orbits".into(),
            reason: "several orbits need --vary to spread their initial states".into(),
        });
    }
    let scene = load_scene(&args.run)?;
    let event = match (&args.event, args.every) {
        (Some(g), None) => {
            let direction = match args.direction.as_str() {
                "rising" => Direction::Rising,
                "falling" => Direction::Falling,
                "both" => Direction::Either,
                other => {
                    return Err(LabError::InvalidArgument {
                        name: "--direction".into(),
                        reason: format!("rising, falling or both, not `{other}`"),
                    });
                }
            };
            SectionEvent::Expression(g.clone(), direction)
        }
        (None, Some(period)) => SectionEvent::Every(period),
        _ => {
            return Err(LabError::InvalidArgument {
                name: "--event/--every".into(),
                reason: "give exactly one".into(),
            });
        }
    };
    let fan = Fan {
        orbits: args.orbits,
        vary: args.vary.as_deref().map(parse_vary).transpose()?,
        energy: args.energy,
        solve: args.solve.clone(),
    };
    // Memory: a point per crossing; a crossing per curve sample at most.
    let d = scene.initial.q.len();
    let samples = galerkin_vi::events::EventOptions::default().samples_per_step;
    crate::memory::ensure_fits(
        format!(
            "the section of {} orbits × {} steps",
            args.orbits, scene.method.steps
        ),
        (args.orbits * scene.method.steps * samples) as f64 * (16.0 * d as f64 + 48.0),
        "fewer --steps or --orbits",
    )?;
    let section = run_section(&scene, &event, &fan)?;
    super::write_output(args.output.as_deref(), &section.to_csv()?)?;
    if let Some(path) = &args.plot {
        let d = section.names.len() / 2;
        let axes = match &args.axes {
            Some(a) if a.len() == 2 => (a[0].clone(), a[1].clone()),
            Some(_) => {
                return Err(LabError::InvalidArgument {
                    name: "--axes".into(),
                    reason: "two components, A,B".into(),
                });
            }
            None => (
                section.names[d - 1].clone(),
                section.names[2 * d - 1].clone(),
            ),
        };
        let title = match &event {
            SectionEvent::Expression(g, _) => format!("{}: section {g} = 0", scene.name),
            SectionEvent::Every(p) => format!("{}: stroboscopic map, period {p:.6}", scene.name),
        };
        section
            .chart(&title, (&axes.0, &axes.1))?
            .save_svg(path)
            .map_err(|e| LabError::Plot(e.to_string()))?;
    }
    let summary = format!(
        "{}: {} section points from {} orbits over t ∈ [{}, {}]\n",
        scene.name,
        section.points.len(),
        section.starts.len(),
        scene.initial.t0,
        scene.initial.t0 + scene.method.h * scene.method.steps as f64
    );
    eprint!("{summary}");
    for note in &section.notes {
        eprintln!("  note: {note}");
    }
    if section.failed {
        return Err(LabError::InvalidArgument {
            name: "orbits".into(),
            reason: "some orbits failed (their points up to the failure are written; see the \
                     notes above)"
                .into(),
        });
    }
    Ok(())
}
