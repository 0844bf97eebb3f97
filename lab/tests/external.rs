//! External work–precision rows (`gvi work-precision --external`, e.g. REBOUND's IAS15 and
//! WHFast from `scripts/rebound/work_precision.py`): merging into the table, the Pareto front,
//! the fastest table and the chart; typed errors naming the file and line, with nothing
//! written; and the up-front refusal of absurd horizons.

use crate::common::cli;
use cli::gvi;
use galerkin_vi_lab::error::LabError;
use galerkin_vi_lab::scene::Scene;
use galerkin_vi_lab::studies::work_precision::{
    MAX_SAMPLES, MAX_TOTAL_STEPS, WorkPrecisionConfig, read_external, read_external_csv,
    reference_csv, work_precision,
};
use std::path::{Path, PathBuf};

/// Real REBOUND rows (Kepler, T = 200), committed so that CI needs no Python.
fn sample() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/rebound_sample.csv")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gvi-external-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn sample_rows_merge_into_table_front_and_chart() {
    let rows = read_external_csv(&sample()).unwrap();
    assert_eq!(rows.len(), 4);
    assert!(rows.iter().all(|p| p.external && p.failure.is_none()));
    assert_eq!(rows[0].method, "rebound-ias15");
    assert_eq!(rows[0].parameters, "epsilon = 0.01");
    assert_eq!(rows[0].tolerance, Some(0.01));
    assert_eq!(rows[3].h, Some(0.25));
    assert_eq!(rows[3].force_evaluations, 800);

    let mut scene = Scene::load("kepler").unwrap();
    scene.method.steps = 3;
    let mut study = work_precision(&scene.build().unwrap(), &WorkPrecisionConfig::quick()).unwrap();
    let internal = study.points.len();
    // Synthetic internal times (slower than every external row), so that the front is
    // determined by the committed numbers alone: WHFast at dt = 0.25 (1.6e-13 in 7.7e-4 s) is
    // on it, IAS15 at epsilon = 0.01 (2.2e-2 in 3.4e-3 s, slower and less accurate than
    // WHFast at dt = 2) is not.
    for p in &mut study.points {
        p.seconds = 1.0;
    }
    study.merge_external("rebound_sample.csv", rows);
    assert_eq!(study.points.len(), internal + 4);
    assert_eq!(study.points.iter().filter(|p| p.external).count(), 4);
    let find = |params: &str| {
        study
            .points
            .iter()
            .find(|p| p.external && p.parameters == params)
            .unwrap()
    };
    assert!(find("dt = 0.25").pareto);
    assert!(find("dt = 2").pareto);
    assert!(!find("epsilon = 0.01").pareto);
    assert!(!find("epsilon = 1e-12").pareto);
    // The front is non-dominated over all points, internal and external.
    for a in study.pareto_front() {
        for b in study.points.iter().filter(|p| p.failure.is_none()) {
            assert!(!(b.seconds < a.seconds && b.error < a.error));
        }
    }
    // The fastest table, CSV, Markdown and chart show the rows as external.
    assert!(study.fastest.iter().any(|f| f.method == "rebound-whfast"
        && f.target == 1e-9
        && f.best.as_ref().is_some_and(|b| b.0 == "dt = 2")));
    let csv = study.csv().unwrap();
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .ends_with("pareto,failure,external")
    );
    assert_eq!(
        csv.lines()
            .filter(|l| l.starts_with("rebound-") && l.ends_with(",true"))
            .count(),
        4
    );
    assert!(study.summary().contains("rebound-whfast (external)"));
    assert!(study.summary().contains("rebound_sample.csv"));
    let svg = study.chart().to_svg_string().unwrap();
    assert!(svg.contains("rebound-ias15 (external)"));
    // The study's own CSV reads back as external rows.
    let dir = scratch("roundtrip");
    let files = study.write(&dir).unwrap();
    let back = read_external_csv(&files[0]).unwrap();
    assert_eq!(back.len(), study.points.len());
    let json = std::fs::read_to_string(&files[1]).unwrap();
    assert!(json.contains("\"external\": true") && json.contains("rebound_sample.csv"));
    std::fs::remove_dir_all(&dir).unwrap();
}

fn expect_csv_error(text: &str, line: usize, needle: &str) {
    let dir = scratch(&format!("bad{line}-{}", needle.len()));
    let path = dir.join("bad.csv");
    std::fs::write(&path, text).unwrap();
    match read_external_csv(&path) {
        Err(e @ LabError::ExternalCsv { .. }) => {
            let msg = e.to_string();
            if let LabError::ExternalCsv {
                path: p, line: l, ..
            } = &e
            {
                assert_eq!(p, &path);
                assert_eq!(*l, line, "{msg}");
            }
            assert!(
                msg.contains(&format!("bad.csv:{line}:")) && msg.contains(needle),
                "{msg}"
            );
        }
        other => panic!("expected ExternalCsv at line {line}, got {other:?}"),
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

const HEADER: &str =
    "method,parameters,h,n,tolerance,error,seconds,force_evaluations,pareto,failure";

#[test]
fn malformed_files_are_typed_errors_naming_file_and_line() {
    let missing = Path::new("/nonexistent/dir/rebound.csv");
    match read_external_csv(missing) {
        Err(e @ LabError::ExternalFile { .. }) => assert!(e.to_string().contains("rebound.csv")),
        other => panic!("expected ExternalFile, got {other:?}"),
    }
    let row = "rebound-whfast,\"dt = 2, safe\",2.0,,,3.5e-11,6.7e-4,100,false,";
    // A good file with a comma inside a quoted field parses.
    let dir = scratch("good");
    std::fs::write(dir.join("ok.csv"), format!("{HEADER}\n{row}\n")).unwrap();
    let ok = read_external_csv(&dir.join("ok.csv")).unwrap();
    assert_eq!(ok[0].parameters, "dt = 2, safe");
    std::fs::remove_dir_all(&dir).unwrap();

    expect_csv_error(
        &format!("{}\n{row}\n", HEADER.replace("seconds", "time")),
        1,
        "unknown column 'time'",
    );
    expect_csv_error(
        &format!("# comment\n{}\n{row}\n", HEADER.replace(",failure", "")),
        2,
        "missing column 'failure'",
    );
    expect_csv_error(
        &format!("{HEADER}\n{row}\n{}\n", row.replace("6.7e-4", "6.7e-4x")),
        3,
        "seconds: malformed number",
    );
    expect_csv_error(
        &format!("{HEADER}\n\n{row}\n{}\n", row.replace("3.5e-11", "NaN")),
        4,
        "error: non-finite",
    );
    expect_csv_error(
        &format!("{HEADER}\n{}\n", row.replace("2.0,", "inf,")),
        2,
        "h: non-finite",
    );
    expect_csv_error(&format!("{HEADER}\n{row},extra\n"), 2, "11 fields");
    expect_csv_error(
        &format!(
            "{HEADER}\n{}\n",
            row.replace("\"dt = 2, safe\"", "\"dt = 2")
        ),
        2,
        "unterminated",
    );
    expect_csv_error(
        &format!("{HEADER}\n{}\n", row.replace(",100,", ",-3,")),
        2,
        "force_evaluations",
    );
}

#[test]
fn cli_writes_nothing_when_an_external_file_is_bad() {
    let dir = scratch("cli");
    let bad = dir.join("bad.csv");
    std::fs::write(
        &bad,
        format!("{HEADER}\nrebound-ias15,\"epsilon = 1e-9\",,,1e-9,1e-13,oops,0,false,\n"),
    )
    .unwrap();
    let out = dir.join("out");
    let sample = sample();
    let (code, _, err) = gvi(&[
        "work-precision",
        "kepler",
        "--quick",
        "--horizon",
        "4",
        "--external",
        sample.to_str().unwrap(),
        "--external",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(
        err.contains("bad.csv:2: seconds: malformed number"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        !out.exists(),
        "output written despite the bad external file"
    );
    let (code, _, err) = gvi(&[
        "work-precision",
        "kepler",
        "--external",
        dir.join("absent.csv").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("absent.csv"), "{err}");
    assert!(!out.exists());
    // And a good run merges: the CSV has the four external rows.
    let (code, _, err) = gvi(&[
        "work-precision",
        "kepler",
        "--quick",
        "--horizon",
        "4",
        "--external",
        sample.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let csv = std::fs::read_to_string(out.join("work_precision.csv")).unwrap();
    assert_eq!(csv.matches("rebound-").count(), 4);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn absurd_horizons_are_refused_up_front_with_the_estimate() {
    let scene = Scene::load("kepler").unwrap();
    let mut config = WorkPrecisionConfig::full();
    config.horizon = Some(1e300);
    let start = std::time::Instant::now();
    match work_precision(&scene.build().unwrap(), &config) {
        Err(
            e @ LabError::CostTooHigh {
                estimate, limit, ..
            },
        ) => {
            assert_eq!(limit, MAX_SAMPLES);
            assert_eq!(estimate, 5e299);
            assert!(e.to_string().contains("5.000e299"), "{e}");
        }
        other => panic!("expected CostTooHigh, got {other:?}"),
    }
    assert!(matches!(
        reference_csv(&scene.build().unwrap(), &config),
        Err(LabError::CostTooHigh { .. })
    ));
    // Few enough samples, too many steps: 10⁶ samples × (4 bases × 19 n × (1+2+4+8)) × 5
    // repeats of Galerkin steps alone.
    config.horizon = Some(2e6);
    match work_precision(&scene.build().unwrap(), &config) {
        Err(LabError::CostTooHigh {
            estimate, limit, ..
        }) => {
            assert_eq!(limit, MAX_TOTAL_STEPS);
            assert!(estimate >= 1e6 * 4.0 * 19.0 * 15.0 * 5.0, "{estimate:e}");
        }
        other => panic!("expected CostTooHigh, got {other:?}"),
    }
    assert!(start.elapsed().as_secs_f64() < 5.0);
    let (code, _, err) = gvi(&["work-precision", "kepler", "--horizon", "1e300"]);
    assert_ne!(code, 0);
    assert!(
        err.contains("refusing the sweep") && err.contains("5.000e299"),
        "{err}"
    );
}

#[test]
fn reference_file_samples_the_study_grid() {
    let scene = Scene::load("kepler").unwrap();
    let mut config = WorkPrecisionConfig::quick();
    config.horizon = Some(20.0);
    let r = reference_csv(&scene.build().unwrap(), &config).unwrap();
    assert_eq!(r.t.len(), 11);
    assert_eq!(r.t[10], 20.0);
    assert!((r.q[0][0] - 0.4).abs() < 1e-15 && r.q[0][1].abs() < 1e-15);
    let csv = r.csv().unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("k,t,q0,q1"));
    let last: Vec<f64> = lines
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(last[0], 10.0);
    assert_eq!(last[2], r.q[10][0]);
}

/// A study's own CSV with a failed row (a run that failed before it was timed: `NaN` seconds,
/// `inf` error) reads back: the failed row is skipped with a note, the others are kept, and
/// `gvi work-precision --external` prints the note and merges the rest.
#[test]
fn failed_rows_of_a_study_csv_are_skipped_with_a_note() {
    let mut scene = Scene::load("kepler").unwrap();
    scene.method.steps = 3;
    let mut study = work_precision(&scene.build().unwrap(), &WorkPrecisionConfig::quick()).unwrap();
    let mut failed = study.points[0].clone();
    failed.method = "dop853".into();
    failed.parameters = "tol = 1e-300".into();
    failed.seconds = f64::NAN;
    failed.error = f64::INFINITY;
    failed.failure = Some("DOP853 tolerance: need 1e-16 ≤ tolerance < 1".into());
    study.points.push(failed);
    let dir = scratch("failed-rows");
    let files = study.write(&dir).unwrap();
    let csv = std::fs::read_to_string(&files[0]).unwrap();
    let failed_line = csv
        .lines()
        .position(|l| l.contains("tol = 1e-300"))
        .unwrap()
        + 1;
    assert!(csv.lines().nth(failed_line - 1).unwrap().contains(",NaN,"));
    let rows = read_external(&files[0]).unwrap();
    assert_eq!(rows.points.len(), study.points.len() - 1);
    assert!(rows.points.iter().all(|p| p.seconds.is_finite()));
    assert_eq!(rows.skipped.len(), 1);
    let skipped = &rows.skipped[0];
    assert_eq!(skipped.line, failed_line);
    assert_eq!(skipped.method, "dop853");
    assert_eq!(skipped.parameters, "tol = 1e-300");
    assert!(skipped.failure.contains("tolerance"));
    assert!(
        skipped
            .to_string()
            .contains("skipped the failed row dop853")
    );
    assert_eq!(
        read_external_csv(&files[0]).unwrap().len(),
        rows.points.len()
    );
    // A failed row with a malformed (not merely non-finite) time is still a typed error.
    let bad = dir.join("bad.csv");
    std::fs::write(
        &bad,
        format!("{HEADER}\ndop853,\"tol = 1e-300\",,,1e-300,inf,oops,0,false,\"failed\"\n"),
    )
    .unwrap();
    assert!(matches!(
        read_external(&bad),
        Err(LabError::ExternalCsv { line: 2, .. })
    ));
    // The CLI prints the note and merges the rest.
    let out = dir.join("out");
    let (code, _, err) = gvi(&[
        "work-precision",
        "kepler",
        "--quick",
        "--horizon",
        "4",
        "--external",
        files[0].to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("note: ") && err.contains("skipped the failed row dop853 (tol = 1e-300)"),
        "{err}"
    );
    let merged = std::fs::read_to_string(out.join("work_precision.csv")).unwrap();
    assert!(!merged.contains("tol = 1e-300"));
    assert_eq!(
        merged.lines().filter(|l| l.ends_with(",true")).count(),
        rows.points.len()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
