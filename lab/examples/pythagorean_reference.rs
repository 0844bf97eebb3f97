//! The tight DOP853 reference of the Pythagorean problem that docs/guide/time-transformations.md
//! measures agreement against (DOP853 at tol = 1e-15 to each output time t = 0, 0.1, …, 70, as
//! `pythagorean_dop` in lab/tests/timetransform_study.rs), written as CSV `k,t,q0,…,q5` (the
//! positions in scene order, shortest round-trip numbers) for external peers:
//! scripts/rebound/time_transform.py compares REBOUND's IAS15 with it.
//!
//! Run: `cargo run --release -j 1 -p galerkin-vi-lab --example pythagorean_reference -- FILE`

use galerkin_vi::baselines::OneStepMethod;
use galerkin_vi::systems::NBody;
use galerkin_vi_lab::dop853::Dop853Baseline;
use std::io::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: pythagorean_reference FILE")?;
    // Masses 3, 4, 5 at rest at (1, 3), (−2, −1), (1, −1), G = 1: the scene `pythagorean`.
    let nb = NBody::new(vec![3.0, 4.0, 5.0], 1.0, 2)?;
    let (mut q, mut p) = (vec![1.0, 3.0, -2.0, -1.0, 1.0, -1.0], vec![0.0; 6]);
    let (mut qn, mut pn) = (vec![0.0; 6], vec![0.0; 6]);
    let h = 0.1;
    let mut dop = Dop853Baseline::new(&nb, h, 1e-15)?;
    let mut out = std::io::BufWriter::new(std::fs::File::create(&path)?);
    writeln!(out, "k,t,q0,q1,q2,q3,q4,q5")?;
    let row = |out: &mut std::io::BufWriter<std::fs::File>, k: usize, q: &[f64]| {
        let cells: Vec<String> = q.iter().map(|x| format!("{x:e}")).collect();
        writeln!(out, "{k},{:e},{}", k as f64 * h, cells.join(","))
    };
    row(&mut out, 0, &q)?;
    for k in 0..700 {
        dop.step(k as f64 * h, &q, &p, &mut qn, &mut pn)?;
        std::mem::swap(&mut q, &mut qn);
        std::mem::swap(&mut p, &mut pn);
        row(&mut out, k + 1, &q)?;
    }
    out.flush()?;
    eprintln!(
        "DOP853 tol = 1e-15: {} steps, {} force evaluations; written to {path}",
        dop.adaptive_steps(),
        dop.force_evaluations()
    );
    Ok(())
}
