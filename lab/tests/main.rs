//! The lab's integration and command-line tests, as modules of one test binary: one link
//! instead of one per file. Run one file's tests with
//! `cargo test -p galerkin-vi-lab --test integration <module>::` (for example `streaming::`).

mod common;

mod adaptive;
mod adaptive_embedded;
mod allocation;
mod baselines;
mod bases;
mod compare_refinement;
mod custom_solver;
mod enriched;
mod ensemble;
mod errors;
mod expression;
mod expression_allocation;
mod external;
mod freezing;
mod geometry;
mod ignored_flags;
mod interruption;
mod lie;
mod memory_limits;
mod messages;
mod nbody;
mod output_paths;
mod output_safety;
mod paper_core;
mod periodic;
mod robustness;
mod scaling;
mod scene_fuzz;
mod sections;
mod silent_nonsense;
mod solvers;
mod stability;
mod stdout_errors;
mod streaming;
mod studies;
mod timetransform;
#[cfg(feature = "dop853")]
mod timetransform_study;
mod work_precision;
