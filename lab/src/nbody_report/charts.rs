//! Orbit charts of N-body runs: one series per body, xy projection of the Galerkin curves.

use crate::error::Result;
use crate::names::unit_suffix;
use crate::plot::{Chart, Series};
use crate::scene::Units;
use galerkin_vi::trajectory::Trajectory;

/// Samples per step along the Galerkin curves in orbit charts (dense enough to draw Mercury's
/// 88-day orbit inside a 100-day step smoothly).
pub const ORBIT_SAMPLES_PER_STEP: usize = 64;

/// The orbit chart of an N-body trajectory (xy projection, one colour per body: the Galerkin
/// curves sampled [`ORBIT_SAMPLES_PER_STEP`] times per step as lines, the step ends as
/// markers of the same colour) and, when at least three bodies' orbits stay within a tenth
/// of the largest orbit's extent, a zoomed chart of those inner bodies.
///
/// `names` gives the bodies in the trajectory's (body-major) order; the body dimension is
/// `traj.dim / names.len()`. The axes are labelled `x` and `y` with the scene's length unit
/// (`x (AU)`), or `(length units)` when the scene gives none.
pub fn orbit_charts(
    names: &[String],
    title: &str,
    units: &Units,
    traj: &Trajectory,
) -> Result<(Chart, Option<Chart>)> {
    let nb = names.len().max(1);
    let k = (traj.dim / nb).max(1);
    let mut curves: Vec<Vec<(f64, f64)>> = vec![Vec::new(); nb];
    let mut extent = vec![0.0f64; nb];
    for t in crate::run::chart_times(traj, ORBIT_SAMPLES_PER_STEP) {
        let q = traj.position_at(t)?;
        for b in 0..nb {
            let (x, y) = (q[b * k], if k > 1 { q[b * k + 1] } else { 0.0 });
            extent[b] = extent[b].max(x.hypot(y));
            curves[b].push((x, y));
        }
    }
    let ends: Vec<Vec<(f64, f64)>> = (0..nb)
        .map(|b| {
            crate::run::chart_indices(traj.q.len())
                .into_iter()
                .map(|i| &traj.q[i])
                .map(|q| (q[b * k], if k > 1 { q[b * k + 1] } else { 0.0 }))
                .collect()
        })
        .collect();
    let length = unit_suffix(units.length.as_deref(), "length");
    let build = |bodies: &[usize], title: String| {
        let mut chart = Chart::new(title, format!("x{length}"), format!("y{length}"))
            .equal_aspect()
            .size(900, 900);
        for &b in bodies {
            chart.push(Series::line(names[b].clone(), curves[b].clone()).with_color(b));
            chart.push(Series::markers("", ends[b].clone()).with_color(b));
        }
        chart
    };
    let all: Vec<usize> = (0..nb).collect();
    let chart = build(&all, format!("{title} (xy projection; dots: step ends)"));
    let largest = extent.iter().cloned().fold(0.0, f64::max);
    let inner: Vec<usize> = (0..nb).filter(|&b| extent[b] < 0.1 * largest).collect();
    let inner_chart = (inner.len() >= 3).then(|| build(&inner, format!("{title} — inner bodies")));
    Ok((chart, inner_chart))
}

#[cfg(test)]
mod tests {
    use crate::run::{RunOptions, run_scene};
    use crate::scene::Scene;

    /// The orbit charts' axes carry the scene's length unit: AU for the solar system (its
    /// `[units]`), "length units" for a scene without units (two-body, G = 1).
    #[test]
    fn orbit_axes_carry_the_scenes_length_unit() {
        let chart = |name: &str| {
            let mut scene = Scene::load(name).unwrap();
            scene.method.steps = 2;
            scene.method.n = 12;
            let options = RunOptions {
                chart: true,
                curve_samples_per_step: 0,
            };
            let run = run_scene(&scene.build().unwrap(), options).unwrap();
            run.chart.unwrap()
        };
        let solar = chart("solar-system");
        assert_eq!(
            (solar.x_label.as_str(), solar.y_label.as_str()),
            ("x (AU)", "y (AU)")
        );
        let two = chart("two-body");
        assert_eq!(two.x_label, "x (length units)");
        assert_eq!(two.y_label, "y (length units)");
    }
}
