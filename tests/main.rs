//! The library's integration tests, as modules of one test binary: one link instead of one
//! per file, which is most of a fresh `cargo test`'s build time. Run one file's tests with
//! `cargo test --test integration <module>::` (for example `extension::`).

#[path = "common/counting.rs"]
mod counting;
#[path = "common/enriched_checks.rs"]
mod enriched_checks;
#[path = "common/kepler_periapsis.rs"]
mod kepler_periapsis;

mod collocation;
mod counts;
mod dependencies;
mod enriched;
mod enriched_frequencies;
mod expression_proptest;
mod extension;
mod paper_objects;
mod roundoff;
mod timetransform;
mod velocity_form;
