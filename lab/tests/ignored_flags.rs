//! Nothing lost, round 2 (issue 32, class 5): a flag that would be ignored is refused with a
//! clear error naming it, before any work. Each refusal has a negative control: the flag in
//! the setting where it is used is accepted.

use crate::common::robust;
use robust::*;

fn ok(args: &[&str]) {
    let o = gvi(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
}

#[test]
fn retraction_only_on_rigid_bodies_and_solver_not_on_them() {
    let o = gvi(&["run", "kepler", "--steps", "3", "--retraction", "cayley"]);
    fails_with(&o, "--retraction");
    fails_with(&o, "not a rigid-body scene");
    let o = gvi(&["check", "kepler", "--steps", "3", "--retraction", "cayley"]);
    fails_with(&o, "--retraction");
    ok(&[
        "run",
        "rigid-body",
        "--steps",
        "3",
        "--retraction",
        "cayley",
    ]);

    let o = gvi(&["run", "rigid-body", "--steps", "3", "--solver", "modal"]);
    fails_with(&o, "--solver");
    fails_with(&o, "Lie group integrator");
    ok(&["run", "kepler", "--steps", "3", "--solver", "modal"]);
}

#[test]
fn fixed_n_flags_are_refused_with_tol() {
    for extra in [
        &["--n", "12"][..],
        &["--economical"][..],
        &["--quad-points", "64"][..],
    ] {
        let mut args = vec!["run", "kepler", "--steps", "3", "--tol", "1e-6"];
        args.extend_from_slice(extra);
        let o = gvi(&args);
        fails_with(&o, extra[0]);
        fails_with(&o, "with --tol");
        // Negative control: the same flag without --tol is used.
        let mut args = vec!["run", "kepler", "--steps", "3"];
        args.extend_from_slice(extra);
        ok(&args);
    }
    ok(&["run", "kepler", "--steps", "3", "--tol", "1e-6"]);
}

#[test]
fn work_precision_repeats_and_write_reference_flags() {
    let dir = scratch("wp-flags");
    let o = gvi(&["work-precision", "kepler", "--quick", "--repeats", "0"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--repeats"), "{}", stderr(&o));
    let reference = dir.join("ref.csv");
    for extra in [
        &["--ns", "8"][..],
        &["--bases", "legendre"][..],
        &["--repeats", "2"][..],
        &["--divisors", "2"][..],
        &["--quadratures", "paper"][..],
        &["--out", "x"][..],
    ] {
        let mut args = vec![
            "work-precision",
            "kepler",
            "--quick",
            "--write-reference",
            s(&reference),
        ];
        args.extend_from_slice(extra);
        let o = gvi(&args);
        fails_with(&o, extra[0]);
        fails_with(&o, "runs no sweep");
        assert!(!reference.exists());
    }
    // Negative control: --write-reference alone writes the reference.
    ok(&[
        "work-precision",
        "kepler",
        "--quick",
        "--write-reference",
        s(&reference),
    ]);
    assert!(reference.is_file());
}

#[test]
fn charts_must_be_named_svg() {
    let dir = scratch("svg-ext");
    for name in ["x.png", "x.pdf", "chart"] {
        let path = dir.join(name);
        let o = gvi(&["run", "kepler", "--steps", "3", "--plot", s(&path)]);
        fails_with(&o, "extension .svg");
        assert!(!path.exists());
        let o = gvi(&["periodic", "figure-eight", "--plot", s(&path)]);
        fails_with(&o, "extension .svg");
    }
    // Negative control: .svg (any case) is written.
    let path = dir.join("x.SVG");
    ok(&["run", "kepler", "--steps", "3", "--plot", s(&path)]);
    assert!(std::fs::read_to_string(&path).unwrap().contains("<svg"));
}
