//! Work–precision on the free asymmetric rigid body (the `rigid-body` scene's state,
//! I = (1, 2, 3), horizon four body periods T = 27.6): the Lie group Galerkin method raising n
//! at a quarter-period step, and raising 1/h at n = 4, against the Lie–Poisson splitting
//! (orders 2 and 4), RATTLE (discrete Moser–Veselov) and RK4 on the matrix ODE. The error is
//! the max over the 16 quarter-period instants of ‖R − R_exact‖_F against the elliptic-function
//! reference; the cost is the best of 5 timings of each run, all in this one process. Prints the
//! Markdown table quoted in docs/guide/lie-group.md and writes CSV and SVG charts (work–precision
//! and error against n) to the directory given as the first argument (default `target/lie`).
//!
//! Run: `cargo run --release --example lie_work_precision [-- OUT_DIR]`

use galerkin_vi::GviError;
use galerkin_vi::basis::BasisKind;
use galerkin_vi::lie::so3::{self, Mat3};
use galerkin_vi::lie::*;
use galerkin_vi::quadrature::QuadratureKind;
use galerkin_vi_lab::error::LabError;
use galerkin_vi_lab::fit::fit_geometric_in;
use galerkin_vi_lab::plot::{Chart, Series};
use std::time::Instant;

struct Point {
    method: String,
    param: String,
    error: f64,
    seconds: f64,
}

/// Best of 5 wall-clock timings of `run`, with its last result.
fn timed<T>(mut run: impl FnMut() -> Result<T, GviError>) -> Result<(T, f64), GviError> {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..5 {
        let t = Instant::now();
        let r = run()?;
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    Ok((out.expect("five runs"), best))
}

fn main() -> Result<(), galerkin_vi_lab::error::LabError> {
    let out_dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "target/lie".to_string());
    let inertia = [1.0, 2.0, 3.0];
    let body = FreeRigidBody::new(inertia)?;
    let r0 = Retraction::Exp.map(&[0.3, -0.4, 0.2]);
    let mu0 = [1.0, 0.4, 3.0];
    let exact = FreeBodyExact::new(inertia, &r0, &mu0)?;
    let quarter = exact.period() / 4.0;
    let marks: Vec<f64> = (0..=16).map(|j| j as f64 * quarter).collect();
    let refs = exact.orientations(&marks)?;
    // Error at the quarter-period marks of a run with `per` steps per quarter period.
    let error = |states: &[Mat3<f64>], per: usize| {
        (0..=16)
            .map(|j| so3::distance(&states[j * per], &refs[j]))
            .fold(0.0, f64::max)
    };
    let mut points = Vec::new();
    // Lie Galerkin, n-refinement at h = T/4.
    let mut n_err = Vec::new();
    for n in (4..=18).step_by(2) {
        let gvi = LieGalerkin::from_kinds(
            BasisKind::Legendre,
            n,
            QuadratureKind::GaussLegendre,
            None,
            quarter,
        )?;
        let (traj, s) = timed(|| gvi.integrate(&body, 0.0, &r0, &mu0, 16))?;
        let rs: Vec<Mat3<f64>> = traj.states.iter().map(|x| x.r).collect();
        let e = error(&rs, 1);
        n_err.push((n as f64, e));
        points.push(Point {
            method: "Lie Galerkin, h = T/4".into(),
            param: format!("n = {n}"),
            error: e,
            seconds: s,
        });
    }
    // Lie Galerkin, h-refinement at n = 4 (order 6).
    for per in [1usize, 2, 4, 8, 16] {
        let gvi = LieGalerkin::spectral(4, quarter / per as f64)?;
        let (traj, s) = timed(|| gvi.integrate(&body, 0.0, &r0, &mu0, 16 * per))?;
        let rs: Vec<Mat3<f64>> = traj.states.iter().map(|x| x.r).collect();
        points.push(Point {
            method: "Lie Galerkin, n = 4".into(),
            param: format!("h = T/{}", 4 * per),
            error: error(&rs, per),
            seconds: s,
        });
    }
    // Classical one-step methods at h = (T/4)/per.
    type Stepper<'a> = Box<dyn Fn(&LieState, f64) -> Result<LieState, GviError> + 'a>;
    let classical: Vec<(&str, Stepper, Vec<usize>)> = vec![
        (
            "splitting, order 2",
            Box::new(|s: &LieState, h: f64| Ok(baselines::splitting_step(&inertia, s, h, 2))),
            vec![4, 16, 64, 256, 1024, 4096, 16384],
        ),
        (
            "splitting, order 4",
            Box::new(|s: &LieState, h: f64| Ok(baselines::splitting_step(&inertia, s, h, 4))),
            vec![4, 16, 64, 256, 1024, 4096],
        ),
        (
            "RATTLE (DMV)",
            Box::new(|s: &LieState, h: f64| baselines::rattle_step(&inertia, s, h)),
            vec![4, 16, 64, 256, 1024, 4096, 16384],
        ),
        (
            "RK4 (matrix ODE)",
            Box::new(|s: &LieState, h: f64| Ok(baselines::rk4_step(&body, s, h))),
            vec![4, 16, 64, 256, 1024, 4096],
        ),
    ];
    for (name, step, pers) in &classical {
        for &per in pers {
            let h = quarter / per as f64;
            let (rs, s) = timed(|| {
                let mut st = LieState { r: r0, mu: mu0 };
                let mut rs = Vec::with_capacity(16 * per + 1);
                rs.push(st.r);
                for _ in 0..16 * per {
                    st = step(&st, h)?;
                    rs.push(st.r);
                }
                Ok(rs)
            })?;
            points.push(Point {
                method: name.to_string(),
                param: format!("h = T/{}", 4 * per),
                error: error(&rs, per),
                seconds: s,
            });
        }
    }
    // Table, CSV, charts.
    println!("| method | parameter | max error ‖R − R_exact‖_F | seconds |");
    println!("|---|---|---|---|");
    let mut csv = String::from("method,parameter,error,seconds\n");
    for p in &points {
        println!(
            "| {} | {} | {:.2e} | {:.2e} |",
            p.method, p.param, p.error, p.seconds
        );
        csv.push_str(&format!(
            "{},{},{:e},{:e}\n",
            p.method, p.param, p.error, p.seconds
        ));
    }
    // Cost to reach a tolerance relative to the Lie Galerkin method (same process).
    let cheapest = |m: &str, tol: f64| {
        points
            .iter()
            .filter(|p| p.method == m && p.error <= tol)
            .map(|p| p.seconds)
            .fold(f64::INFINITY, f64::min)
    };
    for tol in [1e-6, 1e-10, 1e-12] {
        let ours = cheapest("Lie Galerkin, h = T/4", tol);
        println!("\ncost to reach {tol:e}, relative to Lie Galerkin at h = T/4:");
        for m in [
            "Lie Galerkin, n = 4",
            "splitting, order 2",
            "splitting, order 4",
            "RATTLE (DMV)",
            "RK4 (matrix ODE)",
        ] {
            let c = cheapest(m, tol);
            if c.is_finite() {
                println!("  {m}: {:.2}x", c / ours);
            } else {
                println!("  {m}: not reached in the sweep");
            }
        }
    }
    let (ns, es): (Vec<f64>, Vec<f64>) = n_err.iter().copied().unzip();
    let fit = fit_geometric_in(&ns, &es, 4.0, 12.0)
        .map_err(|e| GviError::Unsupported(format!("fit: {e}")))?;
    println!(
        "\nfitted rate in n (n = 4 … 12, h = T/4): {:.4} per n\n",
        fit.rate
    );
    std::fs::create_dir_all(&out_dir).map_err(|source| LabError::Io {
        path: out_dir.clone().into(),
        source,
    })?;
    let write = |name: &str, text: &str| {
        let path = std::path::Path::new(&out_dir).join(name);
        std::fs::write(&path, text).map_err(|source| LabError::Io { path, source })
    };
    write("work-precision.csv", &csv)?;
    let mut chart = Chart::new(
        "Free rigid body, 4 periods: work–precision",
        "seconds",
        "max ‖R − R_exact‖_F",
    )
    .log_x()
    .log_y();
    let mut methods: Vec<&str> = points.iter().map(|p| p.method.as_str()).collect();
    methods.dedup();
    for m in methods {
        chart.push(Series::line_markers(
            m,
            points
                .iter()
                .filter(|p| p.method == m)
                .map(|p| (p.seconds, p.error.max(1e-16))),
        ));
    }
    let plot_err = |e: galerkin_vi_lab::plot::PlotError| LabError::Plot(e.to_string());
    write(
        "work-precision.svg",
        &chart.to_svg_string().map_err(plot_err)?,
    )?;
    let mut conv = Chart::new(
        "Free rigid body at h = T/4: spectral convergence",
        "n",
        "max ‖R − R_exact‖_F",
    )
    .log_y();
    conv.push(Series::line_markers(
        "Lie Galerkin (Legendre, exp)",
        n_err.clone(),
    ));
    conv.push(Series::dashed(
        format!("fit C·{:.3}ⁿ", fit.rate),
        ns.iter().map(|&n| (n, fit.constant * fit.rate.powf(n))),
    ));
    write(
        "convergence-n.svg",
        &conv.to_svg_string().map_err(plot_err)?,
    )?;
    eprintln!("CSV and charts written to {out_dir}");
    Ok(())
}
