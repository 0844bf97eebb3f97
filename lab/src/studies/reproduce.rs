//! `gvi reproduce`: every numerical experiment of Hall & Leok except the solar system
//! (§5.1 harmonic oscillator, §5.2.1 Kepler), as SVG charts like the paper's figures plus
//! `summary.md`, a table of the paper's stated rates beside the measured ones.

use super::{max_norm_diff, write_file};
use crate::error::LabError;
use crate::error::{GviError, Result};
use crate::fit::{fit_algebraic, fit_geometric, fit_geometric_in};
use crate::plot::{Chart, Series};
use galerkin_vi::integrator::GalerkinIntegrator;
use galerkin_vi::systems::{ExactSolution, HarmonicOscillator, Kepler, System};
use galerkin_vi::trajectory::Trajectory;
use rayon::prelude::*;
use serde::Serialize;
use std::path::Path;

/// Size of the reproduction: the paper's, or a reduced one for tests.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Size {
    /// The paper's ranges (minutes on 2 cores).
    Full,
    /// Fewer points per sweep (seconds).
    Quick,
}

/// One row of `summary.md`.
#[derive(Debug, Clone, Serialize)]
pub struct SummaryRow {
    /// Figure(s) of the paper.
    pub figure: String,
    /// The quantity.
    pub quantity: String,
    /// What the paper states.
    pub paper: String,
    /// The measured rate or order.
    pub measured: f64,
    /// How the measured value is expressed ("K" or "order").
    pub kind: String,
    /// Fit window and residual.
    pub detail: String,
}

/// All rows plus the files written.
#[derive(Debug, Clone, Serialize)]
pub struct Reproduction {
    /// Summary rows.
    pub rows: Vec<SummaryRow>,
    /// Files written (relative to the output directory).
    pub files: Vec<String>,
}

struct Errors {
    n: usize,
    h: f64,
    map: f64,
    curve: f64,
    inv_ends: Vec<f64>,
    inv_curve: Vec<f64>,
}

/// Errors of one run: step ends and along the curves, for position and every invariant.
fn run_errors<S: System>(
    sys: &S,
    exact: &ExactSolution,
    q0: &[f64],
    p0: &[f64],
    n: usize,
    h: f64,
    steps: usize,
) -> Result<(Errors, Trajectory)> {
    let gvi = GalerkinIntegrator::spectral(n, h)?;
    let traj = gvi.integrate(sys, 0.0, q0, p0, steps)?;
    let k = sys.invariant_names().len();
    let (mut i0, mut i) = (vec![0.0; k], vec![0.0; k]);
    sys.invariants(q0, p0, &mut i0);
    let mut e = Errors {
        n,
        h,
        map: 0.0,
        curve: 0.0,
        inv_ends: vec![0.0; k],
        inv_curve: vec![0.0; k],
    };
    for s in 0..traj.q.len() {
        e.map = e
            .map
            .max(max_norm_diff(&traj.q[s], &exact.position(traj.time(s))));
        sys.invariants(&traj.q[s], &traj.p[s], &mut i);
        for c in 0..k {
            e.inv_ends[c] = e.inv_ends[c].max((i[c] - i0[c]).abs());
        }
    }
    let mut p = vec![0.0; sys.dim()];
    for t in traj.sample_times(24) {
        let (q, v) = traj.state_on_curve(t)?;
        e.curve = e.curve.max(max_norm_diff(&q, &exact.position(t)));
        sys.legendre_transform(&q, &v, &mut p);
        sys.invariants(&q, &p, &mut i);
        for c in 0..k {
            e.inv_curve[c] = e.inv_curve[c].max((i[c] - i0[c]).abs());
        }
    }
    Ok((e, traj))
}

fn save(chart: &Chart, dir: &Path, name: &str, files: &mut Vec<String>) -> Result<()> {
    chart
        .save_svg(dir.join(name))
        .map_err(|e| LabError::Plot(e.to_string()))?;
    files.push(name.to_string());
    Ok(())
}

fn pts(es: &[Errors], f: impl Fn(&Errors) -> f64, by_h: bool) -> Vec<(f64, f64)> {
    es.iter()
        .map(|e| (if by_h { e.h } else { e.n as f64 }, f(e)))
        .collect()
}

fn geometric_row(
    figure: &str,
    quantity: &str,
    paper: &str,
    es: &[Errors],
    f: impl Fn(&Errors) -> f64,
    window: Option<(f64, f64)>,
) -> SummaryRow {
    let x: Vec<f64> = es.iter().map(|e| e.n as f64).collect();
    let y: Vec<f64> = es.iter().map(f).collect();
    let fit = match window {
        Some((lo, hi)) => fit_geometric_in(&x, &y, lo, hi),
        None => fit_geometric(&x, &y),
    };
    match fit {
        Ok(g) => SummaryRow {
            figure: figure.into(),
            quantity: quantity.into(),
            paper: paper.into(),
            measured: g.rate,
            kind: "K".into(),
            detail: format!(
                "n ∈ [{}, {}], {} points, residual {:.3} decades",
                g.window.0, g.window.1, g.points_used, g.residual
            ),
        },
        Err(e) => SummaryRow {
            figure: figure.into(),
            quantity: quantity.into(),
            paper: paper.into(),
            measured: f64::NAN,
            kind: "K".into(),
            detail: format!("no fit: {e}"),
        },
    }
}

/// Run every experiment and write charts, `summary.md` and `summary.json` into `dir`.
pub fn reproduce(dir: &Path, size: Size) -> Result<Reproduction> {
    let mut files = Vec::new();
    let mut rows = Vec::new();
    let quick = size == Size::Quick;

    // §5.1 harmonic oscillator, h = 20, 100 steps (Figures 2–4).
    let ho = HarmonicOscillator::unit();
    let ho_exact = ho
        .exact_solution(0.0, &[1.0], &[0.0])?
        .ok_or_else(|| GviError::Unsupported("harmonic oscillator exact solution".into()))?;
    let ho_ns: Vec<usize> = if quick {
        (12..=32).step_by(4).collect()
    } else {
        (8..=48).step_by(2).collect()
    };
    let ho_errs: Vec<Errors> = ho_ns
        .par_iter()
        .map(|&n| run_errors(&ho, &ho_exact, &[1.0], &[0.0], n, 20.0, 100).map(|r| r.0))
        .collect::<Result<_>>()?;
    let mut c = Chart::new(
        "Harmonic oscillator, h = 20, 100 steps (paper Figs. 2–3)",
        "n",
        "max error",
    )
    .log_y();
    c.push(Series::line_markers(
        "position, step ends",
        pts(&ho_errs, |e| e.map, false),
    ));
    c.push(Series::line_markers(
        "position, Galerkin curves",
        pts(&ho_errs, |e| e.curve, false),
    ));
    c.push(Series::line_markers(
        "energy, step ends",
        pts(&ho_errs, |e| e.inv_ends[0], false),
    ));
    save(&c, dir, "fig02-03-harmonic-n-refinement.svg", &mut files)?;
    rows.push(geometric_row(
        "2",
        "harmonic oscillator position (h = 20)",
        "geometric",
        &ho_errs,
        |e| e.map,
        None,
    ));
    rows.push(geometric_row(
        "3",
        "harmonic oscillator energy (h = 20)",
        "geometric",
        &ho_errs,
        |e| e.inv_ends[0],
        None,
    ));
    let (_, traj) = run_errors(
        &ho,
        &ho_exact,
        &[1.0],
        &[0.0],
        14,
        20.0,
        if quick { 100 } else { 1000 },
    )?;
    let energy: Vec<(f64, f64)> = (0..traj.q.len())
        .map(|k| {
            let mut e = [0.0];
            ho.invariants(&traj.q[k], &traj.p[k], &mut e);
            (traj.time(k), (e[0] - 0.5).abs())
        })
        .collect();
    let mut c = Chart::new(
        "Harmonic oscillator energy error, n = 14, h = 20 (paper Fig. 4)",
        "t",
        "|E(t) − E(0)|",
    )
    .log_y();
    c.push(Series::line("energy error at step ends", energy));
    save(&c, dir, "fig04-harmonic-energy-time.svg", &mut files)?;

    // §5.2.1 Kepler e = 0.6, h = 2, 100 steps (Figures 5–7).
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    let kex = kepler
        .exact_solution(0.0, &q0, &p0)?
        .ok_or_else(|| GviError::Unsupported("Kepler exact solution".into()))?;
    let k_ns: Vec<usize> = if quick {
        (12..=36).step_by(4).collect()
    } else {
        (6..=48).step_by(2).collect()
    };
    // n too small for h = 2 can fail to converge (n = 4 does): those points are left out.
    let k_errs: Vec<Errors> = k_ns
        .par_iter()
        .filter_map(|&n| {
            run_errors(&kepler, &kex, &q0, &p0, n, 2.0, 100)
                .ok()
                .map(|r| r.0)
        })
        .collect();
    let mut c = Chart::new(
        "Kepler e = 0.6, h = 2, 100 steps (paper Fig. 5)",
        "n",
        "max position error",
    )
    .log_y();
    c.push(Series::line_markers(
        "one-step map",
        pts(&k_errs, |e| e.map, false),
    ));
    c.push(Series::line_markers(
        "Galerkin curves",
        pts(&k_errs, |e| e.curve, false),
    ));
    save(&c, dir, "fig05-kepler-n-refinement.svg", &mut files)?;
    let mut c = Chart::new(
        "Kepler energy and angular momentum errors (paper Figs. 6–7)",
        "n",
        "max error",
    )
    .log_y();
    c.push(Series::line_markers(
        "energy, Galerkin curves",
        pts(&k_errs, |e| e.inv_curve[0], false),
    ));
    c.push(Series::line_markers(
        "energy, step ends",
        pts(&k_errs, |e| e.inv_ends[0], false),
    ));
    c.push(Series::line_markers(
        "angular momentum, Galerkin curves",
        pts(&k_errs, |e| e.inv_curve[1], false),
    ));
    c.push(Series::line_markers(
        "angular momentum, step ends",
        pts(&k_errs, |e| e.inv_ends[1], false),
    ));
    save(&c, dir, "fig06-07-kepler-invariants-n.svg", &mut files)?;
    let tail = if quick { (28.0, 36.0) } else { (34.0, 48.0) };
    rows.push(geometric_row(
        "5",
        "Kepler one-step map",
        "0.56",
        &k_errs,
        |e| e.map,
        None,
    ));
    rows.push(geometric_row(
        "5",
        "Kepler Galerkin curves (large n)",
        "0.74",
        &k_errs,
        |e| e.curve,
        Some(tail),
    ));
    rows.push(geometric_row(
        "6",
        "Kepler energy along the curves (large n)",
        "0.74",
        &k_errs,
        |e| e.inv_curve[0],
        Some(tail),
    ));
    rows.push(geometric_row(
        "7",
        "Kepler angular momentum along the curves (large n)",
        "0.74",
        &k_errs,
        |e| e.inv_curve[1],
        Some(tail),
    ));

    // h-refinement over 10 steps (Figures 8–10).
    let mut c8 = Chart::new(
        "Kepler h-refinement, 10 steps (paper Fig. 8)",
        "h",
        "max position error",
    )
    .log_x()
    .log_y();
    let mut c9 = Chart::new(
        "Kepler h-refinement: energy (paper Fig. 9)",
        "h",
        "max energy error",
    )
    .log_x()
    .log_y();
    let mut c10 = Chart::new(
        "Kepler h-refinement: angular momentum (paper Fig. 10)",
        "h",
        "max error",
    )
    .log_x()
    .log_y();
    let hs: Vec<f64> = (0..if quick { 8 } else { 14 })
        .map(|i| 0.4 * 0.75f64.powi(i))
        .collect();
    for n in [2usize, 3, 4, 5, 6] {
        let es: Vec<Errors> = hs
            .par_iter()
            .filter_map(|&h| {
                run_errors(&kepler, &kex, &q0, &p0, n, h, 10)
                    .ok()
                    .map(|r| r.0)
            })
            .collect();
        c8.push(Series::line_markers(
            format!("n = {n}"),
            pts(&es, |e| e.map, true),
        ));
        c9.push(Series::line_markers(
            format!("n = {n}"),
            pts(&es, |e| e.inv_ends[0], true),
        ));
        c10.push(Series::line_markers(
            format!("n = {n}"),
            pts(&es, |e| e.inv_curve[1], true),
        ));
        let x: Vec<f64> = es.iter().map(|e| e.h).collect();
        let y: Vec<f64> = es.iter().map(|e| e.map).collect();
        let row = match fit_algebraic(&x, &y) {
            Ok(a) => SummaryRow {
                figure: "8".into(),
                quantity: format!("Kepler h-refinement over 10 steps, n = {n}"),
                paper: format!(
                    "2⌈n/2⌉ = {} (paper's n); theory 2n − 1 = {} here",
                    2 * n.div_ceil(2),
                    2 * n - 1
                ),
                measured: a.order,
                kind: "order".into(),
                detail: format!(
                    "h ∈ [{:.2e}, {:.2e}], {} points, residual {:.3}",
                    a.window.0, a.window.1, a.points_used, a.residual
                ),
            },
            Err(e) => SummaryRow {
                figure: "8".into(),
                quantity: format!("Kepler h-refinement, n = {n}"),
                paper: format!("2⌈n/2⌉ = {}", 2 * n.div_ceil(2)),
                measured: f64::NAN,
                kind: "order".into(),
                detail: format!("no fit: {e}"),
            },
        };
        rows.push(row);
    }
    save(&c8, dir, "fig08-kepler-h-refinement.svg", &mut files)?;
    save(&c9, dir, "fig09-kepler-h-energy.svg", &mut files)?;
    save(&c10, dir, "fig10-kepler-h-angular-momentum.svg", &mut files)?;

    // Energy and angular momentum over time (Figures 11–12): n = 24, h = 2.
    let steps = if quick { 200 } else { 2000 };
    let (_, traj) = run_errors(&kepler, &kex, &q0, &p0, 24, 2.0, steps)?;
    let (mut en, mut am) = (Vec::new(), Vec::new());
    for k in 0..traj.q.len() {
        let mut i = [0.0; 2];
        kepler.invariants(&traj.q[k], &traj.p[k], &mut i);
        en.push((traj.time(k), (i[0] + 0.5).abs()));
        am.push((traj.time(k), (i[1] - 0.8).abs()));
    }
    let mut c = Chart::new(
        format!("Kepler energy error over time, n = 24, h = 2, {steps} steps (paper Fig. 11)"),
        "t",
        "|E − E₀|",
    )
    .log_y();
    c.push(Series::line("energy error at step ends", en));
    save(&c, dir, "fig11-kepler-energy-time.svg", &mut files)?;
    let mut c = Chart::new(
        "Kepler angular momentum error over time, n = 24, h = 2 (paper Fig. 12)",
        "t",
        "|L − L₀|",
    )
    .log_y();
    c.push(Series::line("angular momentum error at step ends", am));
    save(
        &c,
        dir,
        "fig12-kepler-angular-momentum-time.svg",
        &mut files,
    )?;

    let rep = Reproduction { rows, files };
    write_file(&dir.join("summary.md"), &rep.markdown())?;
    let json =
        serde_json::to_string_pretty(&rep).map_err(|e| LabError::Serialize(e.to_string()))?;
    write_file(&dir.join("summary.json"), &json)?;
    Ok(rep)
}

impl Reproduction {
    /// The summary table in Markdown.
    pub fn markdown(&self) -> String {
        let mut s = String::from(
            "# Hall & Leok, reproduced\n\nGenerated by `gvi reproduce`. K: fitted geometric rate \
             (error ≈ C·Kⁿ); order: fitted algebraic order in h over 10 steps.\n\n",
        );
        s.push_str(&crate::table::markdown(
            &["figure", "quantity", "paper", "measured", "fit"],
            self.rows.iter().map(|r| {
                [
                    r.figure.to_string(),
                    r.quantity.to_string(),
                    r.paper.to_string(),
                    format!("{} {:.3}", r.kind, r.measured),
                    r.detail.to_string(),
                ]
            }),
        ));
        s.push_str("\nCharts:\n\n");
        for f in &self.files {
            s.push_str(&format!("- [{f}]({f})\n"));
        }
        s
    }
}
