//! `gvi run` without a chart, JSON or `--tol` streams its CSV: peak heap memory is flat in the
//! number of steps. Measured with the counting global allocator (the test thread's own peak
//! heap bytes, not a timer), against the in-memory run as the negative control, whose peak
//! grows linearly with the steps.

use crate::common::counting::peak_during;
use galerkin_vi_lab::run::stream::stream_scene;
use galerkin_vi_lab::run::{RunOptions, run_scene};
use galerkin_vi_lab::scene::Scene;

fn harmonic(steps: usize) -> Scene {
    let mut scene = Scene::load("harmonic").unwrap();
    scene.method.n = 4;
    scene.method.h = 0.1;
    scene.method.steps = steps;
    scene
}

/// Streamed into a sink: peak memory for 10^4 and 10^6 steps.
#[test]
fn streamed_run_memory_is_flat_in_the_number_of_steps() {
    let mut peaks = Vec::new();
    for steps in [10_000, 1_000_000] {
        let scene = harmonic(steps);
        let mut rows = 0usize;
        let peak = peak_during(|| {
            let mut sink = CountingSink(&mut rows);
            let outcome = stream_scene(&scene.build().unwrap(), 0, &mut sink).unwrap();
            assert!(outcome.failure.is_none());
            assert_eq!(outcome.summary.steps, steps);
        });
        assert_eq!(rows, steps + 2, "header and steps + 1 rows");
        peaks.push(peak);
    }
    eprintln!(
        "streamed peak heap: 1e4 steps {} B, 1e6 steps {} B",
        peaks[0], peaks[1]
    );
    // Flat: 100 times the steps, at most a few kilobytes more (allocator noise), and far
    // below the 100 MB bound for 10^6 steps.
    assert!(peaks[1] < peaks[0] + 64 * 1024, "{peaks:?}");
    assert!(peaks[1] < 100 << 20, "{peaks:?}");
}

/// Negative control: the in-memory run holds the whole trajectory.
#[test]
fn in_memory_run_memory_grows_with_the_steps() {
    let mut peaks = Vec::new();
    for steps in [1_000, 10_000] {
        let scene = harmonic(steps);
        peaks.push(peak_during(|| {
            let r = run_scene(&scene.build().unwrap(), RunOptions::default()).unwrap();
            assert_eq!(r.rows.len(), steps + 1);
        }));
    }
    eprintln!(
        "in-memory peak heap: 1e3 steps {} B, 1e4 steps {} B",
        peaks[0], peaks[1]
    );
    let per_step = (peaks[1] - peaks[0]) as f64 / 9_000.0;
    assert!(per_step > 200.0, "{peaks:?}: {per_step} B per step");
}

/// Counts lines written, keeps nothing.
struct CountingSink<'a>(&'a mut usize);

impl std::io::Write for CountingSink<'_> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        *self.0 += buf.iter().filter(|&&b| b == b'\n').count();
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// The streamed table and summary are the in-memory run's, byte for byte and figure for figure.
#[test]
fn streamed_and_in_memory_runs_agree() {
    for name in ["kepler", "harmonic", "two-body", "double-pendulum"] {
        let mut scene = Scene::load(name).unwrap();
        scene.method.steps = 20;
        let mut out = Vec::new();
        let streamed = stream_scene(&scene.build().unwrap(), 16, &mut out).unwrap();
        let memory = run_scene(&scene.build().unwrap(), RunOptions::default()).unwrap();
        assert_eq!(
            String::from_utf8(out).unwrap(),
            memory.to_csv().unwrap(),
            "{name}"
        );
        let (a, b) = (&streamed.summary, &memory.summary);
        assert_eq!(a.steps, b.steps);
        assert_eq!(a.max_position_error, b.max_position_error, "{name}");
        assert_eq!(a.invariant_errors, b.invariant_errors, "{name}");
        assert_eq!(a.force_evaluations, b.force_evaluations, "{name}");
        match (a.max_curve_error, b.max_curve_error) {
            (Some(x), Some(y)) => {
                assert!((x - y).abs() <= 1e-12 * y.max(1e-300), "{name}: {x} {y}")
            }
            (x, y) => assert_eq!(x, y, "{name}"),
        }
    }
}

/// The cells of a run's CSV (step as an integer, NaN as an empty cell).
fn read_back(csv: &str) -> Vec<Vec<f64>> {
    csv.lines()
        .skip(1)
        .map(|line| {
            line.split(',')
                .map(|cell| match cell {
                    "" => f64::NAN,
                    c => c.parse::<f64>().unwrap_or_else(|_| panic!("cell {c:?}")),
                })
                .collect()
        })
        .collect()
}

/// A run's CSV reads back bit for bit, streamed and in memory, with awkward values in it
/// (1/3, −0, 1e-300, 1e150 and their products), and numbers read plainly where that reads
/// well (`0.4`, not `4e-1`).
#[test]
fn the_csv_reads_back_bit_for_bit() {
    let mut cases = Vec::new();
    for (q, p) in [
        (1.0 / 3.0, -0.0),
        (1e150, 1e-300),
        (-2.0 / 3.0 * 1e-200, 7.0e15 + 0.5),
    ] {
        let mut scene = harmonic(12);
        scene.method.n = 8;
        scene.method.h = 0.7;
        scene.initial.q = vec![q];
        scene.initial.p = vec![p];
        cases.push(scene);
    }
    let mut kepler = Scene::load("kepler").unwrap();
    kepler.method.steps = 10;
    cases.push(kepler);
    for scene in cases {
        let built = scene.build().unwrap();
        let memory = run_scene(&built, RunOptions::default()).unwrap();
        let csv = memory.to_csv().unwrap();
        let mut out = Vec::new();
        stream_scene(&built, 16, &mut out).unwrap();
        assert_eq!(String::from_utf8(out).unwrap(), csv);
        let cells = read_back(&csv);
        assert_eq!(cells.len(), memory.rows.len());
        for (row, back) in memory.rows.iter().zip(&cells) {
            assert_eq!(row.len(), back.len());
            for (x, y) in row.iter().zip(back) {
                assert!(
                    x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()),
                    "{x:e} read back as {y:e}\n{csv}"
                );
            }
        }
        // The initial state's cells are as written in the scene, −0 included.
        let first: Vec<&str> = csv.lines().nth(1).unwrap().split(',').collect();
        assert_eq!(first[0], "0");
        assert_eq!(first[1], "0");
        if built.name == "kepler" {
            assert_eq!(&first[2..6], ["0.4", "0", "0", "2"]);
        }
    }
}
