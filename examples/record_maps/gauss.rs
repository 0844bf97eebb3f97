//! The Gauss collocation baseline through its three entry points.

use super::*;

/// The state after the first step, at the middle and at the end of a baseline run, and the
/// work counters as text (they change if an iteration takes another path).
fn states_tokens(line: &mut String, (qs, ps): &States) {
    let steps = qs.len() - 1;
    for (name, k) in [("1", 1), ("mid", steps / 2), ("end", steps)] {
        push_vector(line, &format!("q{name}"), &qs[k]);
        push_vector(line, &format!("p{name}"), &ps[k]);
    }
}

/// `steps` steps of [`StaticKernel::advance`] (the fixed-size kernel of the peer studies).
fn gauss_static<L: Lagrangian, const D: usize>(
    g: &mut GaussCollocationBaseline<'_, L>,
    (q0, p0): (&[f64], &[f64]),
    steps: usize,
) -> Res<States> {
    let mut q: [f64; D] = q0.try_into()?;
    let mut p: [f64; D] = p0.try_into()?;
    let (mut qs, mut ps) = (vec![q.to_vec()], vec![p.to_vec()]);
    let mut fsal = None;
    for k in 0..steps {
        g.advance(k as f64 * g.step_size(), &mut q, &mut p, &mut fsal)?;
        qs.push(q.to_vec());
        ps.push(p.to_vec());
    }
    Ok((qs, ps))
}

/// Gauss collocation with s stages through its three entry points: `step` (fixed point, then
/// simplified Newton), `integrate_compensated` (the increments) and the static kernel.
fn gauss_run<L: Lagrangian>(
    out: &mut Vec<String>,
    system: &str,
    lag: &L,
    (s, h, steps): (usize, f64, usize),
    (q0, p0): (&[f64], &[f64]),
) {
    for entry in ["step", "compensated", "static"] {
        let id = format!("gauss/{system}/s{s}/h{h}/s{steps}/{entry}");
        let mut g = match GaussCollocationBaseline::new(lag, s, h) {
            Ok(g) => g,
            Err(e) => {
                out.push(error_line(&id, "construct", &e));
                continue;
            }
        };
        let run: Res<States> = match entry {
            "step" => integrate_one_step(&mut g, q0, p0, steps).map_err(Into::into),
            "compensated" => g
                .integrate_compensated(q0, p0, steps, 1)
                .map_err(Into::into),
            _ => match q0.len() {
                1 => gauss_static::<L, 1>(&mut g, (q0, p0), steps),
                _ => gauss_static::<L, 2>(&mut g, (q0, p0), steps),
            },
        };
        let line = match run {
            Ok(states) => {
                let mut line = format!(
                    "{id} ok evaluations={} iterations={}",
                    g.force_evaluations(),
                    g.iterations()
                );
                states_tokens(&mut line, &states);
                line
            }
            Err(e) => error_line(&id, "integrate", &*e),
        };
        out.push(line);
    }
}

/// The Gauss collocation baseline (src/baselines): Kepler (e = 0.6) at a small step (the
/// fixed-point iteration), at larger ones (simplified Newton near the pericentre; at h = 1 it
/// diverges: a negative control), the oscillator at h = 5 (the fixed point diverges: Newton),
/// the pendulum at a large amplitude.
pub(super) fn gauss_cases(out: &mut Vec<String>) -> Res<()> {
    let kepler = Kepler::new(1.0)?;
    let (q0, p0) = Kepler::paper_initial_state();
    for s in 2..=4 {
        for (h, steps) in [(0.05, 200), (0.25, 80), (0.5, 40), (1.0, 20)] {
            gauss_run(out, "kepler", &kepler, (s, h, steps), (&q0, &p0));
        }
    }
    let ho = HarmonicOscillator::unit();
    for s in [2, 3] {
        gauss_run(out, "harmonic", &ho, (s, 5.0, 20), (&[1.0], &[0.0]));
    }
    let pendulum = Pendulum::unit();
    gauss_run(out, "pendulum", &pendulum, (3, 1.0, 40), (&[2.5], &[0.0]));
    Ok(())
}
