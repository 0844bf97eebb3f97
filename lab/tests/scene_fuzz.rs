//! Fuzzing the scene parser and the run through it: randomly mutated shipped scenes
//! (scenes/*.toml: numbers replaced by extreme values, lines deleted or duplicated, keys
//! renamed, characters overwritten) must never panic, and a run that reports success must
//! have written only finite numbers. A fixed budget of cases keeps it a CI test of seconds.

use galerkin_vi_lab::run::stream::stream_scene;
use galerkin_vi_lab::run::{RunOptions, run_scene};
use galerkin_vi_lab::scene::{BUILTIN_SCENES, Scene, SystemSpec};
use proptest::prelude::*;

const VALUES: [&str; 14] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "-inf",
    "1e-308",
    "1e300",
    "4294967297",
    "0.5",
    "2",
    "-0.0",
    "18446744073709551615",
];
const KEYS: [&str; 10] = [
    "mass",
    "gm",
    "mu",
    "n",
    "h",
    "steps",
    "q",
    "dim",
    "tol",
    "quad_points",
];

/// Byte ranges of the numbers in a TOML text (outside comments).
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    let mut comment = false;
    while i < b.len() {
        match b[i] {
            b'\n' => comment = false,
            b'#' => comment = true,
            c if !comment && (c.is_ascii_digit() || c == b'-') => {
                let start = i;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b"-+.".contains(&b[i])) {
                    i += 1;
                }
                spans.push((start, i));
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    spans
}

fn mutate(text: &str, kind: u8, pick: usize, value: usize) -> String {
    let lines: Vec<&str> = text.lines().collect();
    match kind {
        0 => {
            let spans = number_spans(text);
            let (a, b) = spans[pick % spans.len()];
            format!(
                "{}{}{}",
                &text[..a],
                VALUES[value % VALUES.len()],
                &text[b..]
            )
        }
        1 => {
            let mut l = lines.clone();
            l.remove(pick % lines.len());
            l.join("\n")
        }
        2 => {
            let mut l = lines.clone();
            let i = pick % lines.len();
            l.insert(i, lines[i]);
            l.join("\n")
        }
        3 => {
            let keyed: Vec<usize> = (0..lines.len())
                .filter(|&i| lines[i].contains(" = ") && !lines[i].starts_with('#'))
                .collect();
            let i = keyed[pick % keyed.len()];
            let rest = lines[i].split_once(" = ").map_or("", |(_, r)| r);
            let mut l: Vec<String> = lines.iter().map(|s| s.to_string()).collect();
            l[i] = format!("{} = {rest}", KEYS[value % KEYS.len()]);
            l.join("\n")
        }
        _ => {
            let mut bytes = text.as_bytes().to_vec();
            let i = pick % bytes.len();
            bytes[i] = b"=[]\"0.-e,x\n#"[value % 12];
            String::from_utf8_lossy(&bytes).into_owned()
        }
    }
}

/// Keep each case cheap: few steps, small n, no tolerance-driven n.
fn cap(scene: &mut Scene) {
    // N-body scenes get their state from the bodies when built: count those coordinates.
    let big = scene.initial.q.len() > 12
        || matches!(&scene.system, SystemSpec::NBody { dim, bodies, .. } if dim.saturating_mul(bodies.len()) > 12);
    let m = &mut scene.method;
    m.steps = m.steps.min(if big { 2 } else { 6 });
    m.n = m.n.min(12);
    m.quad_points = m.quad_points.map(|p| p.min(32));
    m.tol = None;
    m.auto_h = false;
}

fn finite_csv(text: &str) -> bool {
    text.lines()
        .skip(1)
        .flat_map(|l| l.split(','))
        .all(|c| c.is_empty() || c.parse::<f64>().is_ok_and(f64::is_finite))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 160, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn mutated_scenes_never_panic_nor_succeed_with_non_finite_output(
        scene in 0..BUILTIN_SCENES.len(),
        kind in 0u8..5,
        pick in 0usize..10_000,
        value in 0usize..1000,
    ) {
        let text = mutate(BUILTIN_SCENES[scene].1, kind, pick, value);
        let Ok(mut parsed) = Scene::from_toml_str("fuzz", &text) else {
            return Ok(());
        };
        cap(&mut parsed);
        let Ok(parsed) = parsed.build() else {
            return Ok(());
        };
        let mut out = Vec::new();
        if let Ok(outcome) = stream_scene(&parsed, 4, &mut out) {
            let csv = String::from_utf8(out).unwrap();
            if outcome.failure.is_none() {
                prop_assert!(finite_csv(&csv), "streamed success with non-finite output:\n{text}\n{csv}");
                for (name, e) in &outcome.summary.invariant_errors {
                    prop_assert!(e.is_finite(), "{name} error {e}\n{text}");
                }
            }
        }
        let options = RunOptions { curve_samples_per_step: 4, chart: false };
        if let Ok(result) = run_scene(&parsed, options) && result.failure.is_none() {
            prop_assert!(finite_csv(&result.to_csv().unwrap()), "success with non-finite output:\n{text}");
            prop_assert!(result.summary.max_position_error.is_none_or(f64::is_finite));
        }
    }
}
