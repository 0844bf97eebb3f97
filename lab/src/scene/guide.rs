//! The scene files of the guide are real: every `toml` block of docs/guide/scenes.md and of
//! docs/guide/expression-lagrangians.md is loaded through the scene parser and built, and
//! every built-in scene is listed in docs/guide/scenes.md.

use super::{Scene, SystemSpec};
use galerkin_vi::systems::System;

const SCENES_GUIDE: &str = include_str!("../../../docs/guide/scenes.md");
const EXPRESSIONS_GUIDE: &str = include_str!("../../../docs/guide/expression-lagrangians.md");

/// The ```toml blocks of a Markdown text, with the line each starts on.
fn toml_blocks(markdown: &str) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in markdown.lines().enumerate() {
        match (&mut current, line.trim()) {
            (None, "```toml") => current = Some((i + 1, String::new())),
            (Some(_), "```") => blocks.extend(current.take()),
            (Some((_, text)), l) => {
                text.push_str(l);
                text.push('\n');
            }
            (None, _) => {}
        }
    }
    assert!(current.is_none(), "an unterminated ```toml block");
    blocks
}

/// Load and build every block; an expression scene with `exact` must pass through its
/// initial state (otherwise runs drop the formula and report no error).
fn check_guide(name: &str, markdown: &str) -> usize {
    let blocks = toml_blocks(markdown);
    for (line, text) in &blocks {
        let origin = format!("{name}, the block at line {line}");
        let scene = Scene::from_toml_str(&origin, text)
            .unwrap_or_else(|e| panic!("{origin} does not parse: {e}"));
        let built = scene
            .build()
            .unwrap_or_else(|e| panic!("{origin} does not build: {e}"));
        if let SystemSpec::Lagrangian(spec) = &scene.system
            && spec.exact.is_some()
        {
            let system = built.euclidean().unwrap();
            let init = &built.initial;
            let exact = system.exact_solution(init.t0, &init.q, &init.p).unwrap();
            assert!(
                exact.is_some(),
                "{origin}: `exact` does not pass through the initial state"
            );
        }
    }
    blocks.len()
}

#[test]
fn scenes_guide_examples_load() {
    let n = check_guide("docs/guide/scenes.md", SCENES_GUIDE);
    // One example per system type and the variants (tol, gm, forced, time-dependent,
    // periodic): a page that lost its blocks would pass the loop vacuously.
    assert!(n >= 14, "only {n} toml blocks in docs/guide/scenes.md");
    let types = [
        "harmonic",
        "kepler",
        "pendulum",
        "nbody",
        "lagrangian",
        "rigid-body",
        "heavy-top",
    ];
    for t in types {
        assert!(
            SCENES_GUIDE.contains(&format!("type = \"{t}\"")),
            "docs/guide/scenes.md has no example of type = \"{t}\""
        );
    }
    for key in [
        "exact = [",
        "force = [",
        "[periodic]",
        "[units]",
        "tol = ",
        "gm = ",
    ] {
        assert!(SCENES_GUIDE.contains(key), "no example with {key}");
    }
    let n = check_guide("docs/guide/expression-lagrangians.md", EXPRESSIONS_GUIDE);
    assert!(
        n >= 2,
        "only {n} toml blocks in docs/guide/expression-lagrangians.md"
    );
}

/// Negative control of the block check: a broken block is refused, with the block's line.
#[test]
fn a_broken_guide_block_is_caught() {
    let page = "text\n```toml\n[system]\ntype = \"kepler\"\n```\n";
    assert_eq!(
        toml_blocks(page),
        [(2, "[system]\ntype = \"kepler\"\n".to_string())]
    );
    let caught = std::panic::catch_unwind(|| check_guide("page", page));
    assert!(caught.is_err());
}

#[test]
fn every_builtin_scene_is_in_the_scenes_guide() {
    for name in Scene::builtin_names() {
        assert!(
            SCENES_GUIDE.contains(&format!("| `{name}` |")),
            "built-in scene {name} is missing from the table of docs/guide/scenes.md"
        );
    }
}
